# corrlap quick start:  make demo   |   make test
BUILD ?= build
BUILD_TYPE ?= Release
JOBS ?= $(shell nproc)
FUZZ_SECONDS ?= 30
CMAKE_FLAGS ?=
# Relative paths in the compiler cache, so that clones at other paths (CI) reuse it.
export CCACHE_BASEDIR ?= $(CURDIR)

.PHONY: all deps configure build demo test test-stress test-static bench install clean format check-format fuzz

all: build

deps:
	@bash scripts/install_deps.sh

$(BUILD)/build.ninja:
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) $(CMAKE_FLAGS)

configure: deps $(BUILD)/build.ninja

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
	  -DCORRLAP_BUILD_APPS=OFF -DCORRLAP_BUILD_BENCH=OFF $(CMAKE_FLAGS)
	cmake --build $(BUILD)-static -j $(JOBS) --target corrlap_core corrlap_surface corrlap_io corrlap_estimators \
	  corrlap_discretizations corrlap_backends corrlap_problems
	cd $(BUILD)-static && ctest -R install_and_consume --no-tests=error --output-on-failure

bench: build
	bash bench/run_all.sh $(BUILD)

install: build
	cmake --install $(BUILD)

# libFuzzer targets of every reader and parser (clang-14), FUZZ_SECONDS each (default 30).
fuzz: deps
	FUZZ_SECONDS=$(FUZZ_SECONDS) bash scripts/fuzz.sh $(BUILD)-fuzz

format:
	bash scripts/check_format.sh --fix

check-format:
	bash scripts/check_format.sh

clean:
	rm -rf $(BUILD) $(BUILD)-static
