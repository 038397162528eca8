# The two quick-start commands of the README live here:
#   make run    set up .venv with what running needs and run the main job
#   make test   add the test extras (and the system packages the tests need) and run the whole test suite
# Everything else is a building block of those two.

PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin

# The extras of pyproject.toml that the test set-up installs on top of the run set-up. The one place to
# name them: a part whose tests need an extra adds it here (learn: docs/learning.md; ros2: docs/ros.md).
TEST_EXTRAS := test,learn,ros2
# Pinned packages installed before those extras: torch's CPU build for the learn extra (2.13.0 lies on the
# development machines' disk; an unpinned torch would pull a CUDA build of several GB).
TEST_PREINSTALL := torch==2.13.0

.PHONY: run test setup setup-run system-deps ros2-interfaces bench clean

run: setup-run
	$(BIN)/simatch run msl_5v5 --events all

test: setup system-deps ros2-interfaces
	$(BIN)/python -m pytest

bench: setup-run
	$(BIN)/simatch bench

# setup-run: the project alone (what `simatch` needs to run); setup: that and the test extras (development)
setup-run: $(VENV)/.installed-run
setup: $(VENV)/.installed-test

# setup.py and the C extensions too: a changed extension is rebuilt by the next make
C_SOURCES := $(wildcard src/simatch/*/_*.c src/simatch/*/_*.h)
$(VENV)/.installed-run: pyproject.toml setup.py $(C_SOURCES)
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e .
	touch $@

# again after a new run set-up (it reinstalls the project) or a change of the lists above
$(VENV)/.installed-test: $(VENV)/.installed-run Makefile
	$(if $(TEST_PREINSTALL),$(BIN)/pip install --quiet $(TEST_PREINSTALL))
	$(BIN)/pip install --quiet -e '.[$(TEST_EXTRAS)]'
	touch $@

# simatch_msgs and tf2_msgs as ROS 2 interface packages, built into .venv with the ros2 extra's rosidl tools
# (cmake and the C compiler of the system; a few minutes the first time, nothing when up to date)
ros2-interfaces: $(VENV)/.ros2-interfaces

$(VENV)/.ros2-interfaces: $(VENV)/.installed-test $(wildcard src/simatch/msgs/simatch_msgs/msg/*.msg)
	$(BIN)/simatch ros2 --build-interfaces
	touch $@

system-deps:
	scripts/install-system-deps.sh

clean:
	rm -rf $(VENV) build src/*.egg-info .pytest_cache
