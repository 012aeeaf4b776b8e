# Thin wrapper over CMake. `make demo` and `make test` install missing dependencies first.
BUILD ?= build
PYTHON ?= python3
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=

.PHONY: all deps build test test-c test-python test-reduced demo palpation haptic-loop tsan bench report report-deps haptic-report press-report clean

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
	@mkdir -p frames
	$(BUILD)/examples/haptic_loop > frames/haptic_loop.csv

# A sphere tool presses into the liver on a table, slides and lifts off (~5 s): CSV of the tool
# force on stdout, a summary on stderr.
palpation: build
	$(BUILD)/examples/palpation

# A fixed-timestep haptic host (~9 s): a simulated hand on a device thread at 1 kHz, then at
# 10 kHz, renders the liver through a haptic context while a sim thread steps the full model at
# 60 Hz. The force trace (CSV) goes to frames/haptic_loop.csv, deadline lateness and step times
# to the terminal.
haptic-loop: build
	@mkdir -p frames
	$(BUILD)/examples/haptic_loop > frames/haptic_loop.csv

# ThreadSanitizer build (build-tsan) of the haptic test: its haptic thread beside the sim thread,
# with fewer haptic steps than the default 1e5 (TSan slows the steps down). Any report fails.
# OMP_THREAD_LIMIT=1 keeps CHOLMOD's OpenMP regions on the calling thread: libgomp is not built
# with TSan, so its barriers are invisible to it and every parallel region would be reported.
TSAN_BUILD ?= build-tsan
TSAN_HAPTIC_STEPS ?= 20000
tsan: deps
	cmake -S . -B $(TSAN_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSOFTHAP_TSAN=ON \
	  -DSOFTHAP_BUILD_TESTS=ON -DSOFTHAP_BUILD_EXAMPLES=OFF -DSOFTHAP_BUILD_BENCH=OFF $(CMAKE_FLAGS) > /dev/null
	cmake --build $(TSAN_BUILD) -j $(JOBS) --target test_haptic
	TSAN_OPTIONS="halt_on_error=1 $(TSAN_OPTIONS)" OMP_THREAD_LIMIT=1 SOFTHAP_HAPTIC_STEPS=$(TSAN_HAPTIC_STEPS) \
	  $(TSAN_BUILD)/tests/test_haptic

bench: build
	$(BUILD)/bench/softhap_bench

# Error against run time (bench/accuracy.c, a few minutes on 2 cores): JSON lines, then tables and
# PNG plots in report/. matplotlib is needed only here and installed on demand. One OpenMP thread
# per worker process: the accuracy bench runs two of them.
report: build report-deps
	@mkdir -p report
	OMP_NUM_THREADS=1 $(BUILD)/bench/softhap_bench accuracy > report/accuracy.jsonl
	$(PYTHON) scripts/report.py report/accuracy.jsonl report/

# matplotlib for the reports, installed on demand.
report-deps:
	@$(PYTHON) -c "import matplotlib" 2>/dev/null || $(PYTHON) -m pip install -q matplotlib </dev/null || \
	  $(PYTHON) -m pip install -q --break-system-packages matplotlib </dev/null

# Haptic step cost against buffer size, force error against buffer radius and force smoothness
# (bench/haptic.c, about 2 minutes on 2 cores): JSON lines, then report/haptic.md and PNG plots.
# --rt runs the haptic thread SCHED_FIFO where allowed, so that its tails are the step's own.
haptic-report: build report-deps
	@mkdir -p report
	OMP_NUM_THREADS=1 $(BUILD)/bench/softhap_bench haptic --rt > report/haptic_cost.jsonl
	OMP_NUM_THREADS=1 $(BUILD)/bench/softhap_bench haptic-error > report/haptic_error.jsonl
	OMP_NUM_THREADS=1 $(BUILD)/bench/softhap_bench haptic-force --csv report/haptic_force.csv > report/haptic_force.jsonl
	$(PYTHON) scripts/haptic_report.py report/

# A sphere and a probe pressed 1.5 cm into liver2 with a 1 kHz haptic context (about 20 s): the
# full model's and the rendered force against the tool's travel, in report/press_*.png.
press-report: build report-deps
	@mkdir -p report
	PYTHONPATH=bindings/python SOFTHAP_LIBRARY=$(abspath $(BUILD))/libsofthap.so $(PYTHON) scripts/press_probe.py \
	  liver2.msh 0.21 0.01 --friction 0.5 --plot report/press_liver2_sphere_10mm.png
	PYTHONPATH=bindings/python SOFTHAP_LIBRARY=$(abspath $(BUILD))/libsofthap.so $(PYTHON) scripts/press_probe.py \
	  liver2.msh 0.21 0.003 --stiffness 1e4 --friction 0.5 --plot report/press_liver2_probe_3mm.png

clean:
	rm -rf build build-no-cholmod build-no-ccd build-tsan
