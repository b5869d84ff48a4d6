# hattr: the two commands a newcomer needs are `make demo` and `make test`.
# Each installs the Debian packages it needs (scripts/install-deps), then builds.

PRESET ?= release
JOBS ?= $(shell nproc)
# The release suite runs two tests to a core: many wait (real-time loops, leases, child
# processes) rather than compute; those that time loops are RUN_SERIAL and still run alone. The
# sanitizer suites compute, and run one to a core (docs/architecture.md).
TEST_JOBS ?= $(shell echo $$(( 2 * $(JOBS) )))
BUILD := build/$(PRESET)
# Warnings are errors in CI (CI=true), warnings elsewhere.
export HATTR_WERROR := $(if $(filter true 1,$(CI)),ON,OFF)

.PHONY: all deps build test demo sanitize asan tsan bench fuzz package package-check nounity clean help

all: build

help:
	@echo "make demo      install deps, build, run the main job (hattr demo)"
	@echo "make test      install deps, build, run every test (ctest)"
	@echo "make sanitize  the C++ tests again under address+undefined sanitizers, and those that start"
	@echo "               threads or processes under the thread sanitizer (make asan, make tsan)"
	@echo "make bench     build and run the benchmarks"
	@echo "make fuzz      build the libFuzzer targets and fuzz the profile, study and world readers for 60 s each"
	@echo "make package   build the Debian packages into build/package/packages (docs/install.md)"
	@echo "make nounity   build every C++ file alone, without unity batches (checks each includes what it uses)"
	@echo "make package-check  the packages installed, run and purged on a fresh debootstrap root (as root)"

deps:
	@scripts/install-deps

build: deps
	cmake --preset $(PRESET) >/dev/null
	cmake --build --preset $(PRESET) -j $(JOBS)

test: build
	scripts/run-ctest $(BUILD) --preset $(PRESET) -j $(TEST_JOBS)

demo: build
	$(BUILD)/apps/hattr/hattr demo --out demo-out

# Address + undefined-behaviour sanitizers over every C++ test (the doc, browser and Python tests
# only drive the release programs: they are not in this preset).
asan: deps
	cmake --preset asan >/dev/null
	cmake --build --preset asan -j $(JOBS)
	scripts/run-ctest build/asan --preset asan -j $(JOBS)

# The thread sanitizer where it finds bugs: the programs whose tests start threads or processes
# (ctest label "threads", tests/CMakeLists.txt), built and run alone.
tsan: deps
	cmake --preset tsan >/dev/null
	cmake --build --preset tsan -j $(JOBS) --target hattr_threaded_tests
	scripts/run-ctest build/tsan --preset tsan -j $(JOBS) -L threads

sanitize: asan tsan

bench: build
	scripts/run-benchmarks $(BUILD)

fuzz: deps
	cmake --preset fuzz >/dev/null
	cmake --build --preset fuzz -j $(JOBS)
	mkdir -p build/fuzz/corpus build/fuzz/corpus-study build/fuzz/corpus-world
	build/fuzz/fuzz/fuzz_profile_csv -max_total_time=60 -max_len=4096 build/fuzz/corpus fuzz/seeds
	build/fuzz/fuzz/fuzz_study_file -max_total_time=60 -max_len=4096 build/fuzz/corpus-study fuzz/seeds-study
	build/fuzz/fuzz/fuzz_world_file -max_total_time=60 -max_len=4096 build/fuzz/corpus-world fuzz/seeds-world

# Every C++ file of the library, the apps and the tests compiled alone (HATTR_UNITY_BUILD=OFF),
# at -O0 without debug info: a file that leans on a batch-mate's include fails here. A build
# check only (nothing runs); the compiler cache keeps it cheap after the first (docs/architecture.md).
nounity: deps
	cmake --preset nounity >/dev/null
	cmake --build --preset nounity -j $(JOBS)

# The Debian packages (cmake/HattrPackaging.cmake): a release build for the prefix /usr, without
# the tests (the compiler cache reuses the release build's objects), packed by CPack.
package: deps
	cmake --preset package >/dev/null
	cmake --build --preset package -j $(JOBS)
	rm -rf build/package/packages
	cd build/package && cpack -G DEB

# The packages on a clean Debian 12 root (scripts/check-debian-packages): installed with apt-get,
# the demo, Python and the studio run from the installed files, then purged.
package-check: package
	scripts/check-debian-packages build/package/packages

clean:
	rm -rf build demo-out
