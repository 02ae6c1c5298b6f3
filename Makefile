# tumble_ros workspace: `make run` runs the main job, `make test` runs the tests.
# `make setup` (a prerequisite of both) is idempotent and cheap when nothing changed:
#   1. .venv from python3 -m venv, then requirements.txt installed by uv   (only when it changed)
#   2. at once, on both cores: the venv's bytecode compiled (after 1), and
#      colcon build --symlink-install of tumble_ros_interfaces (and vendor/tf2_msgs) and tumble_ros
#      (only when a package file that matters for the build changed)
# The environment logic (venv + install/setup.bash) lives in scripts/env.sh.

SHELL := /bin/bash
.SHELLFLAGS := -eo pipefail -c
.DEFAULT_GOAL := help
.DELETE_ON_ERROR:

PYTHON ?= python3
VENV := .venv
ENV := scripts/env.sh
# vendor/tf2_msgs: TFMessage of /tf (the PyPI wheels have no tf2_msgs; docs/ros.md "TF"), built
# beside tumble_ros_interfaces (colcon builds the two at once), left out where the venv has one.
# Named here: vendor/COLCON_IGNORE hides it from a crawl (a ROS workspace has the real one).
TF2_MSGS := $(if $(wildcard $(VENV)/share/tf2_msgs/package.xml),,vendor/tf2_msgs)
COLCON_PACKAGES := tumble_ros_interfaces $(TF2_MSGS) tumble_ros
COLCON_ARGS ?=
# CMake's generator for the interface package: Ninja where installed, else CMake's default.
CMAKE_GENERATOR ?= $(if $(shell command -v ninja 2>/dev/null),Ninja)
PYTEST_ARGS ?=
CONFIG ?=

STAMPS := .stamps
# Inside the venv: deleting .venv also forgets that requirements were installed.
VENV_STAMP := $(VENV)/.requirements.stamp
BUILD_STAMP := $(STAMPS)/colcon-build
BYTECODE_STAMP := $(VENV)/.bytecode.stamp

# What colcon's output depends on. Python modules are not listed: with --symlink-install they are
# live. Directories are listed so that adding, renaming or deleting a file in them rebuilds.
BUILD_INPUTS := cmake/tumble_ros_rosidl.cmake \
	$(if $(TF2_MSGS),vendor/tf2_msgs/package.xml vendor/tf2_msgs/CMakeLists.txt vendor/tf2_msgs/msg \
	  $(wildcard vendor/tf2_msgs/msg/*.msg)) \
	tumble_ros_interfaces/package.xml tumble_ros_interfaces/CMakeLists.txt \
	tumble_ros_interfaces/srv tumble_ros_interfaces/msg \
	$(wildcard tumble_ros_interfaces/srv/*.srv tumble_ros_interfaces/msg/*.msg) \
	tumble_ros/package.xml tumble_ros/setup.py tumble_ros/setup.cfg \
	tumble_ros/resource tumble_ros/resource/tumble_ros \
	tumble_ros/config $(wildcard tumble_ros/config/*) \
	tumble_ros/launch $(wildcard tumble_ros/launch/*)

# Rebuild anyway if build/ or install/ was deleted behind make's back.
BUILD_PRESENT := $(and $(wildcard install/setup.bash),$(wildcard build/tumble_ros))

.PHONY: help setup warmup test run figures lock clean clean-recordings distclean FORCE

help:
	@echo 'make run    [CONFIG=...]       run the main job (python -m tumble_ros $$CONFIG)'
	@echo 'make test   [PYTEST_ARGS=...]  run the tests'
	@echo 'make figures [FIGS="fig3 fig9"] reproduce the paper figures into build/figures/'
	@echo '             [FIGURES_OUT=docs/figures]  ... or refresh the published ones (then commit)'
	@echo 'make bench  [BENCH_ARGS=...]   benchmarks: Fig 9 over 2000 yr vs scipy, ensembles (docs/performance.md)'
	@echo 'make setup                     venv + pinned requirements + colcon build (idempotent)'
	@echo 'make warmup                    compile every integration loop now (else: each on first use)'
	@echo 'make lock                      re-pin requirements.txt from requirements.in'
	@echo 'make clean                     remove build/ install/ log/ and stamps (keeps .venv)'
	@echo 'make clean-recordings          remove recordings/ (figure runs, walks: tens to hundreds of MB)'
	@echo 'make distclean                 clean, and remove .venv'

# The venv's bytecode and the colcon build need only the venv: they run at once (make -j here,
# whatever the caller's -j), each announcing itself, beside the loops the target that asked for
# the set-up will use (SETUP_EXTRA, set by run and test below: the loops need only the venv).
# Nothing runs when both are up to date, but SETUP_ALWAYS (test: the warm-up, which also
# recompiles what an edit of a compiled source made stale).
# SETUP_BYTECODE: the venv's bytecode, in the set-up but for run (which compiles it after its job).
SETUP_EXTRA =
SETUP_ALWAYS =
SETUP_BYTECODE = $(BYTECODE_STAMP)
setup:
	@if ! $(MAKE) -q $(BUILD_STAMP) $(SETUP_BYTECODE) 2>/dev/null; then \
		$(MAKE) --no-print-directory -j 3 $(BUILD_STAMP) $(SETUP_BYTECODE) $(SETUP_EXTRA); \
	elif [[ -n '$(SETUP_ALWAYS)' ]]; then \
		$(MAKE) --no-print-directory $(SETUP_ALWAYS); \
	fi
	@# The package's bytecode, refreshed at every make (0.1 s when fresh): the modules are
	@# live (--symlink-install), and where Python is told not to write bytecode
	@# (PYTHONDONTWRITEBYTECODE) every process compiled ~110 of them from source: ~0.2 s of
	@# the Fig 9 main job's start (benchmarks/HISTORY.md).
	@$(ENV) python -m compileall -q -j 0 tumble_ros/tumble_ros

$(VENV_STAMP): requirements.txt
	@# No pip in the venv (ensurepip: ~7 s of CPU before anything else can start): uv, pinned
	@# in the lock, is installed by the system's pip (--python: pip >= 22.3), then the lock by uv.
	@# Without a pip that can, the venv gets its own pip and installs uv with it, as before.
	@test -x $(VENV)/bin/python || { echo '== creating $(VENV)'; $(PYTHON) -m venv --without-pip $(VENV); }
	@# colcon must not crawl the venv (its share/ holds many package.xml files).
	@touch $(VENV)/COLCON_IGNORE
	@echo "== installing requirements.txt ($$(grep -c '==' requirements.txt) pinned packages) with uv"
	@# uv installs the lock: the same wheels from PyPI, looked up and downloaded in parallel
	@# (pip took 26 s, one package at a time; uv ~8 s). The lock is complete (pip freeze of a
	@# full install): no resolution needed (--no-deps), and `uv pip check` says if it ever is not.
	@# No bytecode here: $(BYTECODE_STAMP) compiles it (test, bench, figures: beside the colcon
	@# build; run: after the job, in the background).
	$(PYTHON) -m pip --python $(VENV)/bin/python install --quiet --no-deps --no-compile \
		"$$(grep -m1 '^uv==' requirements.txt)" 2>/dev/null || $(MAKE) --no-print-directory venv-pip
	@# uv reads no pip configuration (a mirror set for pip only: UV_INDEX_URL tells uv): if it
	@# fails, pip installs the lock instead, as before (~26 s).
	$(VENV)/bin/uv pip install --quiet --python $(VENV)/bin/python --link-mode copy --no-deps \
		-r requirements.txt || { echo '== uv failed: installing with pip instead'; \
		$(MAKE) --no-print-directory venv-pip; \
		$(VENV)/bin/python -m pip install --quiet --no-deps --no-compile -r requirements.txt; }
	$(VENV)/bin/uv pip check --quiet --python $(VENV)/bin/python
	touch $@

# The venv's own pip (ensurepip), and uv installed by it: where the system's pip cannot install
# into the venv (no pip, or older than 22.3), or where uv failed.
.PHONY: venv-pip
venv-pip:
	@test -x $(VENV)/bin/pip || $(VENV)/bin/python -m ensurepip --default-pip > /dev/null
	@test -x $(VENV)/bin/uv || $(VENV)/bin/python -m pip install --quiet --no-deps --no-compile \
		"$$(grep -m1 '^uv==' requirements.txt)"

# The bytecode of the venv, compiled on every core, tests of the installed packages left out
# (a third of the sources; nothing imports them). Needed: Python may be told not to write it at
# import (PYTHONDONTWRITEBYTECODE: a run's imports then took 2.8 s instead of 1.0 s).
$(BYTECODE_STAMP): $(VENV_STAMP)
	@echo '== compiling the bytecode of $(VENV)'
	$(VENV)/bin/python -m compileall -q -j 0 -x '/tests?/' $(VENV)/lib
	touch $@

$(BUILD_STAMP): $(VENV_STAMP) $(BUILD_INPUTS) $(if $(BUILD_PRESENT),,FORCE)
	@echo '== colcon build (the interface package: C and Python code generated and compiled)'
	@# CMake's make runs one job a core. Not colcon's default (-j N -l N: no new job while the
	@# load average is above N, so on a busy machine, or beside the bytecode compiling, one job),
	@# nor the jobserver of the make -j above (it built with one job: make said so on stderr).
	@# Ninja where installed (CMAKE_GENERATOR, read by CMake for a new build folder only: one
	@# made by make keeps make): ~10 % less CPU than CMake's recursive make, and one job graph.
	env -u MFLAGS MAKEFLAGS=-j$$(getconf _NPROCESSORS_ONLN) \
		$(if $(CMAKE_GENERATOR),CMAKE_GENERATOR='$(CMAKE_GENERATOR)') \
		$(ENV) --build colcon build --symlink-install \
		--base-paths $(COLCON_PACKAGES) $(COLCON_ARGS)
	@# No warm-up in this step: numba compiles a loop on its first use, once, then loads it
	@# from its cache; run and test compile the loops they use beside this step (SETUP_EXTRA).
	@mkdir -p $(STAMPS)
	touch $@

# Test paths come from pytest.ini (testpaths) unless PYTEST_ARGS names some.
# The tests use every loop: compile them all ahead, in parallel (about a second once cached),
# beside the set-up's bytecode and colcon build (the loops need only the venv).
# PYTEST_WORKERS: pytest-xdist workers (auto: one per core; 0 runs the tests in this process).
# One BLAS thread per worker: the workers already take every core, and OpenBLAS's second thread
# spins between the period search's many small calls (twice the CPU, benchmarks/HISTORY.md).
PYTEST_WORKERS ?= auto
test: SETUP_EXTRA = warmup
test: SETUP_ALWAYS = warmup
test: setup
	OPENBLAS_NUM_THREADS=1 $(ENV) pytest -q -ra --durations=15 -n $(PYTEST_WORKERS) $(PYTEST_ARGS)

# The loops the scenario's run uses compile beside the set-up (the run then loads them).
# The venv's bytecode is not waited for (38 s of CPU for ~6,000 modules, on a fresh machine a
# third of the set-up's CPU; the run imports ~1,000 of them, compiling them from source costs
# it ~2 s): once the job is done, if it is missing, it is compiled in the background, niced
# (log: .venv/.bytecode.log), and a later make finds it done (or compiles what is left).
run: SETUP_EXTRA = warmup-scenario
run: SETUP_BYTECODE =
run: setup
	$(ENV) python -m tumble_ros $(CONFIG)
	@if [[ ! -e $(BYTECODE_STAMP) ]]; then \
		echo '== compiling the bytecode of $(VENV) in the background (log: $(VENV)/.bytecode.log)'; \
		nohup nice -n 19 $(MAKE) --no-print-directory $(BYTECODE_STAMP) \
			> $(VENV)/.bytecode.log 2>&1 < /dev/null & \
	fi

# Optional: compile (or load) every integration loop now, a process a core. The numerical
# core imports no ROS: it needs the venv only, and is imported from the source tree (the same
# files colcon's --symlink-install installs, so the same numba cache).
WARMUP = $(ENV) --build env PYTHONPATH=$(CURDIR)/tumble_ros python -m tumble_ros.cli.warmup
warmup: $(VENV_STAMP)
	$(WARMUP)

# Only what a run of $(CONFIG) uses (the default scenario: the dop853 loop); never fails.
.PHONY: warmup-scenario
warmup-scenario: $(VENV_STAMP)
	@$(WARMUP) --scenario $(CONFIG)

# Untracked by default: a figure run leaves a clean clone clean (docs/figures is the published copy).
FIGURES_OUT ?= build/figures
figures: setup
	$(ENV) python scripts/make_figures.py --out $(FIGURES_OUT) $(FIGS)

# Benchmarks (a few minutes; --quick: seconds): every section in benchmarks/, see docs/performance.md.
.PHONY: bench
BENCH_ARGS ?=
bench: setup
	$(ENV) python benchmarks/run.py $(BENCH_ARGS)

lock:
	scripts/lock.sh

clean:
	rm -rf build install log $(STAMPS)

# What the runs recorded (make figures: recordings/figures/, one MCAP a figure, Fig 9's ~60 MB).
clean-recordings:
	rm -rf recordings

distclean: clean
	rm -rf $(VENV)

FORCE:
