# twistslam developer entry points. `make test` and `make demo` set up everything they need.
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
PIP := $(VENV)/bin/pip
TORCH_VERSION := 2.13.0
# pip's CMake 4 refuses Debian's old config files without this policy floor.
export CMAKE_POLICY_VERSION_MINIMUM := 3.5
export CMAKE_BUILD_PARALLEL_LEVEL ?= 2
# The same C++ compiler name for the Python extension and the C++ test builds (scikit-build-core
# calls it g++, a bare CMake c++): ccache keys on the name, so with one name the test build's
# copies of the core libraries come out of the cache instead of being compiled twice. make's
# default CXX is g++; a CXX set in the environment wins.
export CXX

# Debian packages the C++ core builds against (libpcl-dev with its recommends: VTK, MPI).
APT_PACKAGES := build-essential ccache libeigen3-dev libceres-dev libopencv-dev libpcl-dev libgtest-dev libdeflate-dev
# python files too: the editable redirect install freezes the list of modules at install time
CPP_SOURCES := $(shell find cpp cmake -type f) $(shell find python -name "*.py") CMakeLists.txt pyproject.toml
CPP_TEST_BUILD := build/cpp-tests
REFERENCE_EVALUATORS := trackeval==1.3.0 eval-ab-3d-mot==2.3.0 pure-ab-3d-mot==2.2.0 association-quality-clavia==0.3.2 munkres==3.0.0

.PHONY: setup apt build test test-cpp test-sanitizers test-python demo clean help
help:
	@echo "make setup   - apt packages, .venv, torch==$(TORCH_VERSION) (CPU), editable install"
	@echo "make test    - set up if needed, then C++ (ctest; also under ASan/UBSan) and Python (pytest) tests"
	@echo "make demo    - simulate (once), run SLAM, evaluate: demo_out/"

setup: apt .stamp-venv .stamp-build

apt:
	@missing=$$(for p in $(APT_PACKAGES); do dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q "install ok installed" || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages: $$missing"; \
	  SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -q --install-recommends $$missing; \
	fi

# torch first, pinned, so that nothing later pulls a multi-GB CUDA build.
.stamp-venv: pyproject.toml
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PIP) install -q "torch==$(TORCH_VERSION)"
	$(PIP) install -q scikit-build-core "pybind11>=2.12" "cmake>=3.22" ninja numpy
	$(PIP) install -q --no-build-isolation -e ".[dev,models,viz]"
	@# independent reference implementations the evaluator's tests compare against (TrackEval's
	@# HOTA, AB3DMOT's evaluator for sAMOTA / the devkit rules); --no-deps: their pins would
	@# downgrade numpy and pull opencv / pycocotools, none of which the tested code paths need
	$(PIP) install -q --no-deps $(REFERENCE_EVALUATORS)
	@touch $@ .stamp-build

# Rebuild the extension when C++ changes (incremental: build/{wheel_tag} is kept). flock: two
# builds started at once (parallel work in one checkout) would corrupt the shared build tree.
BUILD_LOCK := flock build/.build.lock
.stamp-build: $(CPP_SOURCES) | .stamp-venv
	@mkdir -p build
	$(BUILD_LOCK) $(PIP) install -q --no-build-isolation --no-deps -e .
	@touch $@

build: apt .stamp-venv .stamp-build

test: build test-cpp test-sanitizers test-python

test-cpp: apt .stamp-venv
	$(VENV)/bin/cmake -S . -B $(CPP_TEST_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release \
	  -DTWISTSLAM_BUILD_TESTS=ON -DTWISTSLAM_BUILD_PYTHON=OFF -DCMAKE_MAKE_PROGRAM=$(abspath $(VENV)/bin/ninja) > /dev/null
	@mkdir -p build
	$(BUILD_LOCK) $(VENV)/bin/cmake --build $(CPP_TEST_BUILD)
	cd $(CPP_TEST_BUILD) && $(abspath $(VENV)/bin/ctest) --output-on-failure

# The C++ tests once more as a Debug build (assertions on) under AddressSanitizer and
# UndefinedBehaviorSanitizer: any out-of-bounds access, leak, overflowing float-to-int
# conversion or Eigen assertion fails its test (-O1: the Eigen-heavy tests stay quick; -g1: line
# tables are all the sanitizers' stack traces need, and full -g made problem_builder.cpp take 124 s
# instead of 53 s to compile, 2026-12-06). Its own
# build folder and lock leave the Release test build untouched.
SANITIZE_BUILD := build/cpp-tests-sanitize
SANITIZE_FLAGS := -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer
test-sanitizers: apt .stamp-venv
	$(VENV)/bin/cmake -S . -B $(SANITIZE_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Debug \
	  -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g1" -DCMAKE_C_FLAGS_DEBUG="-O1 -g1" \
	  -DCMAKE_CXX_FLAGS="$(SANITIZE_FLAGS)" -DCMAKE_EXE_LINKER_FLAGS="$(SANITIZE_FLAGS)" \
	  -DTWISTSLAM_BUILD_TESTS=ON -DTWISTSLAM_BUILD_PYTHON=OFF -DCMAKE_MAKE_PROGRAM=$(abspath $(VENV)/bin/ninja) > /dev/null
	@mkdir -p build
	flock build/.sanitize.lock $(VENV)/bin/cmake --build $(SANITIZE_BUILD)
	cd $(SANITIZE_BUILD) && UBSAN_OPTIONS=print_stacktrace=1 $(abspath $(VENV)/bin/ctest) --output-on-failure \
	  --parallel $(CMAKE_BUILD_PARALLEL_LEVEL)

# Both cores, one test file per worker at a time (loadfile: a module's fixtures are built once):
# 293 -> 190 s on this 2-core machine (2026-12-06; the slowest files first, conftest.py; with the
# demo's simulated sequence cached, which a clean clone's notebook test simulates first: 228-268 s);
# the ten slowest tests are listed.
PYTEST_WORKERS ?= 2
test-python: build
	$(PY) -m pytest tests/python -q -n $(PYTEST_WORKERS) --dist loadfile --durations=10

clean:
	rm -rf build .stamp-venv .stamp-build

# The simulator's default urban sequence, generated once into .cache/sim, then SLAM + eval.
demo: build
	$(PY) -m twistslam.demo --out demo_out --cache .cache/sim
