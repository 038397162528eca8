# The two quick-start commands of the README live here:
#   make run    set up .venv with what running needs and run the main job
#   make test   add the test extras (and the system packages the tests need) and run the whole test suite
# Everything else is a building block of those two.

# The interpreter: any supported Python (3.11, 3.12, 3.13), e.g. `make test PYTHON=python3.12`. The default
# python3 sets up .venv; another one a venv of its own, .venv-py312 (so the two never mix).
PYTHON ?= python3
# an interpreter's version (X.Y), empty if it does not run
pyversion = $(shell $(1) -c 'import sys; print("%d.%d" % sys.version_info[:2])' 2>/dev/null)
PYV    := $(call pyversion,$(PYTHON))
PY     := $(subst .,,$(PYV))
VENV   ?= $(if $(filter python3,$(PYTHON)),.venv,.venv-py$(PY))
BIN    := $(VENV)/bin

# The lock files (PEP 751, written by `make lock`): the exact versions and hashes the set-ups install, one pair
# per supported Python; pyproject.toml keeps the loose ranges for those who embed simatch (docs/install.md).
LOCK_RUN  := locks/pylock.run-py$(PY).toml
LOCK_TEST := locks/pylock.test-py$(PY).toml
# the pip that installs them (pip installs from pylock.toml since 25.1; scripts/lock.py writes with the same one)
PIP := pip==26.3
# the interpreters `make lock` locks for (with pyenv: PYENV_VERSION=3.11.7:3.12.1:3.13.0 make lock)
LOCK_PYTHONS ?= python3.11 python3.12 python3.13

# The extras of pyproject.toml that the test set-up installs on top of the run set-up. The one place to
# name them: a part whose tests need an extra adds it here (learn: docs/learning.md; ros2: docs/ros.md).
TEST_EXTRAS := test,learn,ros2

.PHONY: run test setup setup-run system-deps ros2-interfaces other-python bench clean lock

run: setup-run
	$(BIN)/simatch run msl_5v5 --events all

test: setup system-deps ros2-interfaces other-python
	$(BIN)/python -m pytest

bench: setup-run
	$(BIN)/simatch bench

# setup-run: the project alone (what `simatch` needs to run); setup: that and the test extras (development)
setup-run: $(VENV)/.installed-run
setup: $(VENV)/.installed-test

# The locked packages, then the project itself without dependencies (the lock has them) and without build
# isolation (the locked setuptools builds the C extensions). setup.py and every C source and header are
# prerequisites too: a changed extension is rebuilt by the next make.
C_SOURCES := $(wildcard src/simatch/*/_*.c src/simatch/*/_*.h)
$(VENV)/.installed-run: $(wildcard $(LOCK_RUN)) pyproject.toml setup.py $(C_SOURCES)
	$(CHECK_LOCK)
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet $(PIP)
	$(BIN)/pip install --quiet -r $(LOCK_RUN)
	$(BIN)/pip install --quiet --no-deps --no-build-isolation -e .
	touch $@

# again after a new run set-up or a change of the test lock (its extras: TEST_EXTRAS, written by `make lock`)
$(VENV)/.installed-test: $(VENV)/.installed-run $(wildcard $(LOCK_TEST)) Makefile
	$(CHECK_LOCK)
	$(BIN)/pip install --quiet -r $(LOCK_TEST)
	touch $@

# a clear error for an interpreter that does not run or has no lock here (an unsupported Python)
CHECK_LOCK = @test -n "$(PY)" || { echo "make: the interpreter $(PYTHON) does not run here (with pyenv: \
	PYENV_VERSION=3.12.1 make ... PYTHON=python3.12)" >&2; exit 1; }; \
	test -f $(LOCK_TEST) || { echo "make: Python $(PYV) is not supported (no lock in locks/): \
	the supported Pythons are 3.11, 3.12 and 3.13" >&2; exit 1; }

# writes locks/ anew for every supported Python from pyproject.toml's ranges (docs/install.md)
lock:
	for py in $(LOCK_PYTHONS); do $(PYTHON) scripts/lock.py --python $$py --extras $(TEST_EXTRAS) || exit 1; done

# simatch_msgs and tf2_msgs as ROS 2 interface packages, built into .venv with the ros2 extra's rosidl tools
# (cmake and the C compiler of the system; a few minutes the first time, nothing when up to date)
ros2-interfaces: $(VENV)/.ros2-interfaces

$(VENV)/.ros2-interfaces: $(VENV)/.installed-test $(wildcard src/simatch/msgs/simatch_msgs/msg/*.msg)
	$(BIN)/simatch ros2 --build-interfaces
	touch $@

system-deps:
	scripts/install-system-deps.sh

# Another supported Python of this machine (on PATH or pyenv's: scripts/other-python.sh), set up to run simatch
# (its run lock, in a venv of its own), for the tests that verify a recording made under one Python under
# another (tests/record/test_divergence.py finds the checkout's venvs). None here: those tests are skipped.
OTHER_PYTHON ?= $(shell scripts/other-python.sh $(PYV))

OTHER_VENV = .venv-py$(subst .,,$(call pyversion,$(OTHER_PYTHON)))

other-python:
	$(if $(OTHER_PYTHON),$(MAKE) setup-run PYTHON=$(OTHER_PYTHON) VENV=$(OTHER_VENV),@echo "make: no other \
	supported Python here: the tests across Python versions will be skipped")

clean:
	rm -rf $(VENV) build src/*.egg-info .pytest_cache
