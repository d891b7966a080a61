# One-step environment, tests and demo. `make env` is idempotent: with nothing changed it is a
# no-op of a few seconds. Everything runs with ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST.
SHELL := /bin/bash
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
VPY := $(VENV)/bin/python
IFACES := $(wildcard icub_interfaces/srv/*.srv icub_interfaces/msg/*.msg icub_interfaces/action/*.action) icub_interfaces/CMakeLists.txt icub_interfaces/package.xml
# tf2_msgs (TFMessage for /tf): the wheels lack it; built from interfaces/tf2_msgs only where missing.
IFACES += $(wildcard interfaces/tf2_msgs/msg/*.msg interfaces/tf2_msgs/CMakeLists.txt interfaces/tf2_msgs/package.xml)
TF2_MSGS = $$(test -e $(VENV)/share/ament_index/resource_index/packages/tf2_msgs || echo interfaces/tf2_msgs)
PKG := setup.py setup.cfg package.xml $(wildcard config/*.yaml)
export ROS_AUTOMATIC_DISCOVERY_RANGE := LOCALHOST

.PHONY: env test test-fast lint demo demo-learned demo-tabletop bench paper clean lock

env: $(VENV)/.deps-stamp install/.build-stamp

$(VPY):
	$(PYTHON) -m venv $(VENV)
	$(VPY) -m pip install -q --upgrade "pip>=24" "setuptools<80" wheel

$(VENV)/.deps-stamp: requirements/lock.txt | $(VPY)
	$(VPY) -m pip install -q --disable-pip-version-check -r requirements/lock.txt 2> >(grep -v "^WARNING: Location" >&2)
	$(VPY) scripts/fix_wheel_cmake.py
	touch $@

install/.build-stamp: $(VENV)/.deps-stamp $(IFACES) $(PKG)
	source $(VENV)/bin/activate && export CMAKE_PREFIX_PATH="$$VIRTUAL_ENV" AMENT_PREFIX_PATH="$$VIRTUAL_ENV" && \
	  colcon --log-base log build --symlink-install --base-paths . icub_interfaces $(TF2_MSGS) \
	    --event-handlers console_direct- --cmake-args -DPython3_EXECUTABLE=$(abspath $(VPY)) -DBUILD_TESTING=OFF
	touch $@

lock:
	$(VPY) scripts/lock_requirements.py

lint: env
	scripts/env.sh ruff check icub_pmp icub_sim_bridge test $(wildcard bench) scripts

test: env
	scripts/env.sh scripts/run_tests.sh

# the inner loop: the same lint and suite without the modules marked slow (CI runs make test)
test-fast: env
	scripts/env.sh scripts/run_tests.sh -m "not slow"

demo: env
	scripts/env.sh scripts/demo.sh $(DEMO_ARGS)

# PMP on the learned body vs the URDF in the simulator (LEARNED_ARGS="--model FILE" etc.)
demo-learned: env
	scripts/env.sh python -m icub_pmp.demo.learned_reach $(LEARNED_ARGS)

# the tabletop task of issue 19 (two arms, hand-over, emulated grasp): bags/tabletop-<time>/
demo-tabletop: env
	OPENBLAS_NUM_THREADS=1 scripts/env.sh python -m icub_pmp.demo.tabletop $(TABLETOP_ARGS)

# every benchmark's --quick run, one after the other, then BENCHMARKS.md rewritten
bench: env
	scripts/env.sh python bench/run_all.py

# the papers' results side by side: paper/<timestamp>/report.md (PAPER_ARGS=--quick for CI)
paper: env
	scripts/env.sh python -m icub_pmp.paper $(PAPER_ARGS)

clean:
	rm -rf build install log
