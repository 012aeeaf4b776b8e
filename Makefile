# Thin wrapper over CMake. `make demo` and `make test` install missing dependencies first.
BUILD ?= build
PYTHON ?= python3
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=

.PHONY: all deps build test test-c test-python test-reduced demo bench clean

all: build

deps:
	@scripts/install-deps.sh

build: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DSOFTHAP_BUILD_TESTS=ON \
	  -DSOFTHAP_BUILD_EXAMPLES=ON -DSOFTHAP_BUILD_BENCH=ON $(CMAKE_FLAGS) > /dev/null
	cmake --build $(BUILD) -j $(JOBS)

test: build
	$(MAKE) --no-print-directory test-c test-python

test-c:
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

test-python:
	SOFTHAP_LIBRARY=$(abspath $(BUILD))/libsofthap.so $(PYTHON) -m pytest -q tests/python

# The library without CHOLMOD and without libccd: both must build and pass their tests.
test-reduced: deps
	$(MAKE) --no-print-directory build test-c BUILD=build-no-cholmod CMAKE_FLAGS="-DSOFTHAP_WITH_CHOLMOD=OFF -DSOFTHAP_BUILD_EXAMPLES=OFF -DSOFTHAP_BUILD_BENCH=OFF"
	$(MAKE) --no-print-directory build test-c BUILD=build-no-ccd CMAKE_FLAGS="-DSOFTHAP_WITH_CCD=OFF -DSOFTHAP_BUILD_EXAMPLES=OFF -DSOFTHAP_BUILD_BENCH=OFF"

demo: build
	$(BUILD)/examples/liver_sag

bench: build
	$(BUILD)/bench/softhap_bench

clean:
	rm -rf build build-no-cholmod build-no-ccd
