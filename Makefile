# The two set-up commands of the README: `make demo` and `make test`. CI runs `make test`.
PYTHON ?= python3
LLVM ?= /usr/lib/x86_64-linux-gnu/libLLVM.so.19.1
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
export DRJIT_LIBLLVM_PATH ?= $(LLVM)

.PHONY: install install-extras llvm demo test test-exhaustive quick figures benchmark device-check

# The package alone: rendering an image needs neither pytest, Mitsuba nor Ray.
install:
	$(PYTHON) -m pip install -q -e .

# The test extra (Mitsuba, pytest, matplotlib), the Ray extra (the batch tests run on a real local Ray instance
# and a simulated 2-node cluster) and the torch extra (tests/pytorch). torch is pinned first: on this project's
# machines that is the CPU wheel pip finds in /opt/wheels (28 s into a fresh environment, 2 s once there), where
# the extra's range alone may take a newer, multi-GB CUDA build from PyPI.
install-extras:
	$(PYTHON) -m pip install -q "torch==2.13.0"
	$(PYTHON) -m pip install -q -e '.[test,ray,torch]'

# Mitsuba's llvm_ad_rgb variant needs a libLLVM that Dr.Jit can use; Debian 12's libLLVM 15 is not one.
llvm:
	@[ -e $(LLVM) ] || ($(SUDO) apt-get update -qq && $(SUDO) apt-get install -y -qq libllvm19 >/dev/null)

demo: install
	warprt render -o warprt.png

# Two worker processes (pytest-xdist), a test file each at a time: module fixtures stay shared. A worker
# that crashes ends the run with the test it was running named: xdist's replacement worker can wait
# forever under --dist loadfile (pytest-xdist #784, #1378), which CI sees only as its 90-minute timeout.
TEST_WORKERS ?= 2
XDIST := -n $(TEST_WORKERS) --max-worker-restart=0
test: install-extras llvm
	$(PYTHON) -m pytest -q $(XDIST) --dist loadfile -m "not exhaustive"

# The cases make test leaves to others of their kind (tests/marks.py: exhaustive), each minutes long.
test-exhaustive: install-extras llvm
	$(PYTHON) -m pytest -q $(XDIST) --dist loadfile -m exhaustive

# The inner loop: every test not marked slow (pyproject.toml's markers), under a minute on 2 cores.
quick: install-extras llvm
	$(PYTHON) -m pytest -q $(XDIST) -m "not slow"

# The seed's Figures 6-8 and the cost-growth plot, into benchmarks/figures/.
figures: install-extras
	$(PYTHON) -m benchmarks.figures

# The performance report, benchmarks/REPORT.md (26 minutes on 2 cores, quiet; run on a quiet machine).
benchmark: install-extras llvm
	$(PYTHON) -m benchmarks

# The day a GPU is lent: every hash-list image rendered on cuda and held to the CPU's (docs/gpu.md), gradients
# compared, warm 1024x768 frames timed (against Mitsuba cuda_ad_rgb where installed), results in
# benchmarks/results/device.md and a REPORT.md section; without CUDA it says so and succeeds. No install step: a lent machine may be offline.
# DEVICE=cpu: the same script on the CPU, two small scenes (CI's smoke run, so that it does not rot).
DEVICE ?= cuda
device-check:
	$(PYTHON) -m benchmarks.device_check --device $(DEVICE) $(if $(filter cpu,$(DEVICE)),--quick,--out benchmarks/results/device.md --report benchmarks/REPORT.md)
