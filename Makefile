# The two quick-start commands of the README live here:
#   make run    set up .venv and run the main job
#   make test   set up .venv (and the system packages the tests need) and run the whole test suite
# Everything else is a building block of those two.

PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin

.PHONY: run test setup system-deps ros2-interfaces learn bench clean

run: setup
	$(BIN)/simatch run msl_5v5 --events all

test: setup system-deps ros2-interfaces learn
	$(BIN)/python -m pytest

bench: setup
	$(BIN)/simatch bench

setup: $(VENV)/.installed

# setup.py and the C encoder too: a changed extension is rebuilt by the next make
$(VENV)/.installed: pyproject.toml setup.py src/simatch/msgs/_cdr_accel.c
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[test,ros2]'
	touch $@

# simatch_msgs and tf2_msgs as ROS 2 interface packages, built into .venv with the ros2 extra's rosidl tools
# (cmake and the C compiler of the system; a few minutes the first time, nothing when up to date)
ros2-interfaces: $(VENV)/.ros2-interfaces

$(VENV)/.ros2-interfaces: $(VENV)/.installed $(wildcard src/simatch/msgs/simatch_msgs/msg/*.msg)
	$(BIN)/simatch ros2 --build-interfaces
	touch $@

# The learning extra (docs/learning.md), for the tests, not for `make run`: torch's CPU build first (2.13.0 lies on
# the development machines' disk; an unpinned torch would pull a CUDA build of several GB), then the extra.
learn: $(VENV)/.learn

$(VENV)/.learn: $(VENV)/.installed
	$(BIN)/pip install --quiet 'torch==2.13.0'
	$(BIN)/pip install --quiet -e '.[test,learn]'
	touch $@

system-deps:
	scripts/install-system-deps.sh

clean:
	rm -rf $(VENV) build src/*.egg-info .pytest_cache
