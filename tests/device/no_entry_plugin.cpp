// A shared object without the entry symbol: the host must say it is not a hattr plugin.
extern "C" __attribute__((visibility("default"))) int some_other_library_function() { return 42; }
