# corrlap quick start:  make demo   |   make test
BUILD ?= build
BUILD_TYPE ?= Release
JOBS ?= $(shell nproc)
FUZZ_SECONDS ?= 30
CMAKE_FLAGS ?=
# Relative paths in the compiler cache, so that clones at other paths (CI) reuse it.
export CCACHE_BASEDIR ?= $(CURDIR)

.PHONY: all deps configure build demo test test-stress test-static bench install clean format check-format fuzz test-sanitize test-tsan

all: build

deps:
	@bash scripts/install_deps.sh

$(BUILD)/build.ninja:
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) $(CMAKE_FLAGS)

# CMAKE_FLAGS given (e.g. CMAKE_FLAGS=-DCORRLAP_WERROR=ON, what CI passes): configure again so that
# they reach an existing build folder too.
configure: deps $(BUILD)/build.ninja
ifneq ($(strip $(CMAKE_FLAGS)),)
	cmake -S . -B $(BUILD) $(CMAKE_FLAGS)
endif

build: configure
	cmake --build $(BUILD) -j $(JOBS)

demo: build
	$(BUILD)/bin/corrlap demo

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) --timeout 1800

test-stress: build
	cd $(BUILD) && ctest --output-on-failure -L stress

# The CMake package with static libraries (BUILD_SHARED_LIBS=OFF): builds only the libraries,
# installs them into a scratch prefix and builds and runs the consumer against them.
test-static: deps
	cmake -S . -B $(BUILD)-static -G Ninja -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) -DBUILD_SHARED_LIBS=OFF \
	  -DCORRLAP_BUILD_APPS=OFF -DCORRLAP_BUILD_BENCH=OFF -DCORRLAP_BUILD_PYTHON=OFF $(CMAKE_FLAGS)
	cmake --build $(BUILD)-static -j $(JOBS) --target corrlap_core corrlap_surface corrlap_io corrlap_estimators corrlap_pipeline \
	  corrlap_discretizations corrlap_backends corrlap_problems corrlap_regularization corrlap_render corrlap_studies
	cd $(BUILD)-static && ctest -R install_and_consume --no-tests=error --output-on-failure

bench: build
	bash bench/run_all.sh $(BUILD)

install: build
	cmake --install $(BUILD)

# Every test built with AddressSanitizer + UndefinedBehaviorSanitizer by clang-14 (own build folder;
# the consumer test is built with the same compiler and flags): the project's clang build and its
# sanitizer run in one. Any report fails the run. SANITIZE_CXX=g++ SANITIZE_CC=gcc for GCC's.
SANITIZE_CXX ?= clang++-14
SANITIZE_CC ?= clang-14
test-sanitize: deps
	cmake -S . -B $(BUILD)-sanitize -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCORRLAP_SANITIZE=ON \
	  -DCMAKE_CXX_COMPILER=$(SANITIZE_CXX) -DCMAKE_C_COMPILER=$(SANITIZE_CC) -DCORRLAP_BUILD_BENCH=OFF $(CMAKE_FLAGS)
	cmake --build $(BUILD)-sanitize -j $(JOBS)
	cd $(BUILD)-sanitize && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --output-on-failure -j $(JOBS) --timeout 3600

# The stress tests under ThreadSanitizer. Debian's TBB is not instrumented: tests/tsan.supp silences
# the reports whose both sides are inside TBB's scheduler, so what is printed is real.
test-tsan: deps
	cmake -S . -B $(BUILD)-tsan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCORRLAP_TSAN=ON \
	  -DCORRLAP_BUILD_BENCH=OFF $(CMAKE_FLAGS)
	cmake --build $(BUILD)-tsan -j $(JOBS) --target corrlap_stress_tests
	TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1 suppressions=$(CURDIR)/tests/tsan.supp" \
	  $(BUILD)-tsan/tests/corrlap_stress_tests

# libFuzzer targets of every reader and parser (clang-14), FUZZ_SECONDS each (default 30), or
# FUZZ_RUNS inputs each from a fixed seed (reproducible; what CI runs).
fuzz: deps
	FUZZ_SECONDS=$(FUZZ_SECONDS) FUZZ_RUNS=$(FUZZ_RUNS) bash scripts/fuzz.sh $(BUILD)-fuzz

format:
	bash scripts/check_format.sh --fix

check-format:
	bash scripts/check_format.sh

clean:
	rm -rf $(BUILD) $(BUILD)-static $(BUILD)-sanitize $(BUILD)-tsan $(BUILD)-fuzz
