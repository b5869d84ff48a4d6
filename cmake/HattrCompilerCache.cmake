# The compiler cache: Debian's ccache, when installed (scripts/install-deps installs it), compiles
# every C++ file unless the caller named a launcher or turned it off (-DHATTR_CCACHE=OFF).
#
# Paths are hashed relative to the source folder (base_dir) and without the build folder
# (hash_dir=false, which -g would otherwise add), so a fresh clone in another folder, as CI's,
# reuses the objects a build of the same sources made before it on this machine
# (docs/architecture.md, "Build and CI in proportion"). Qt Test adds the test's absolute source
# and build folders as definitions (QT_TESTCASE_SOURCEDIR/BUILDDIR) that only QFINDTESTDATA
# reads, which hattr's tests do not use: they are left out of the hash (ignore_options).
option(HATTR_CCACHE "Compile through ccache when it is installed" ON)
if(HATTR_CCACHE AND NOT CMAKE_CXX_COMPILER_LAUNCHER)
  find_program(HATTR_CCACHE_PROGRAM ccache)
  if(HATTR_CCACHE_PROGRAM)
    set(CMAKE_CXX_COMPILER_LAUNCHER
      ${CMAKE_COMMAND} -E env CCACHE_BASEDIR=${PROJECT_SOURCE_DIR} CCACHE_NOHASHDIR=true
      "CCACHE_IGNOREOPTIONS=-DQT_TESTCASE_SOURCEDIR=* -DQT_TESTCASE_BUILDDIR=*"
      ${HATTR_CCACHE_PROGRAM})
    message(STATUS "hattr: compiling through ${HATTR_CCACHE_PROGRAM}")
  endif()
endif()
