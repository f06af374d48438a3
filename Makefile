# The two quick-start commands: `make run` and `make test`. Both build .venv from this repo's own files.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
# The app needs only racer-tui; the tests also need the dev tools and the car extra
# (OpenVINO and TensorFlow, which prove a car export loads as the car loads it).
APP_STAMP := $(VENV)/.installed-app
STAMP := $(VENV)/.installed-test

.PHONY: run test lint bench clean

$(APP_STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e .
	touch $(APP_STAMP)

# Byte-compiled as pip installs (not --no-compile, though that halves the install): where
# PYTHONDONTWRITEBYTECODE is set no import writes a .pyc, and every process of the tests
# would compile torch and the rest again (5 s more a process).
$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e ".[dev,car]"
	touch $(STAMP)

# racer-tui's own modules byte-compiled as pip compiles what it installs (an editable
# install compiles nothing): where PYTHONDONTWRITEBYTECODE is set, every process would
# compile them again, 0.3 s of each start that imports the trainer, the app and the league.
# Only what changed is compiled again (0.1 s when nothing has).
SOURCES := racer_tui sim league tracks benchmarks tests
COMPILE := $(BIN)/python -m compileall -q $(SOURCES)

run: $(APP_STAMP)
	$(COMPILE)
	$(BIN)/racer-tui $(ARGS)

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy
	$(BIN)/lint-imports --no-cache

# Three workers on CI's two cores: a worker often waits (on a child process, a server on
# loopback, an app's timer), and a third keeps the cores busy meanwhile (the whole suite in
# 585 s instead of 684 on this machine's two).
# loadgroup: tests marked with one xdist_group run in one worker (TensorFlow's tests, so
# only one worker spends 15 s importing it).
test: lint
	$(COMPILE)
	$(BIN)/pytest -n 3 --dist loadgroup -q

bench: $(APP_STAMP)
	$(BIN)/python -m benchmarks.sim.simulator

clean:
	rm -rf $(VENV) .mypy_cache .ruff_cache .pytest_cache .import_linter_cache .grimp_cache
