# The two commands of the README: `make demo` (the main job) and `make test`.
# Both create ./.venv and install the project into it on first use.
PYTHON ?= python3
VENV   ?= .venv
PY      = $(VENV)/bin/python
WORLD  ?= energy
PLANNER ?= papf

# numba's kernels compiled into its cache: the planners named after -c (every other one with
# --others), the tracker's with --tracker
WARM_UP = import sys; from nodes.planner.registry import PLANNERS, make_planner; \
	from nodes.tracker.core import Tracker, TrackerParams; a = sys.argv[1:]; \
	[make_planner(n).warm_up() for n in PLANNERS if (n in a) != ('--others' in a)]; \
	'--tracker' in a and Tracker(TrackerParams()).warm_up()

.PHONY: demo test test-quick test-slow lint coverage setup bytecode clean docs docs-check
setup: $(VENV)/.installed

# Bytecode of our packages, compiled where it is stale: where PYTHONDONTWRITEBYTECODE is set
# (this machine sets it) no import writes any, and each of the hundreds of Python processes a
# run or the tests start would compile every module it imports from source again
# (docs/performance.md "The test suite's time"); the dependencies' is compiled at install.
PACKAGES = common nodes papf schemas worlds bench
bytecode: setup
	@$(PY) -m compileall -q -j 0 $(PACKAGES) > /dev/null

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet uv   # uv installs the rest, faster than pip (docs/performance.md, setup rows)
	$(PY) -m uv pip install --quiet --compile-bytecode --python $(PY) -e '.[dev,fast]'
	@echo "compiling the numba kernels once (cached; the first run would do it otherwise), on 2 cores"
	$(PY) -c "$(WARM_UP)" papf --tracker & warm=$$!; \
	$(PY) -c "$(WARM_UP)" papf --others && wait $$warm
	touch $@

VIEW   ?=
PORT   ?=
PORT_RANGE ?=
# PORT=7500: the embedded router's port; PORT_RANGE=7500-7510: every port the stack listens
# on inside it (router and nodes; docs/robot.md "Ports and firewalls") — papf run's options
DEMO_PORTS = $(if $(PORT),--port $(PORT)) $(if $(PORT_RANGE),--port-range $(PORT_RANGE))
demo: bytecode   # VIEW=1: at the wall clock's pace, with a live Foxglove view on ws://127.0.0.1:8765
	@echo "papf run --world $(WORLD) --planner $(PLANNER): the whole stack, as separate processes"
ifeq ($(VIEW),)
	@echo "watch it live: make demo VIEW=1, then open ws://127.0.0.1:8765 in Foxglove with the layout docs/foxglove-layout.json"
	$(VENV)/bin/papf run --world $(WORLD) --planner $(PLANNER) $(DEMO_PORTS)
else
	@echo "watch it live: open ws://127.0.0.1:8765 in Foxglove (layout: docs/foxglove-layout.json);"
	@echo "  or in another terminal: .venv/bin/papf topic list | topic echo planner/status | topic hz scan"
	$(VENV)/bin/papf run --world $(WORLD) --planner $(PLANNER) --realtime --view $(DEMO_PORTS)
endif

# The tests on parallel workers (pytest-xdist; each worker its own ports and runtime dir,
# tests/conftest.py). `make test`: every tier in one pytest run, the README's test command and
# CI's: one run leaves no second tail of idle workers and collects once (docs/performance.md
# "One pytest run for every tier"). `make test-quick` leaves the slow tier (marker `slow`,
# long end-to-end cases) out, for the loop while working; `make test-slow` runs it alone.
TEST_WORKERS ?= 4
PYTEST = $(PY) -m pytest -n $(TEST_WORKERS) --dist worksteal
test: bytecode
	$(PYTEST)

test-quick: bytecode
	$(PYTEST) -m "not slow"

test-slow: bytecode
	$(PYTEST) -m slow

lint: setup
	$(VENV)/bin/ruff check .

coverage: setup   # in-process coverage of the unit and pub/sub tiers (node processes not traced)
	$(VENV)/bin/coverage run -m pytest -q -m "not e2e"
	$(VENV)/bin/coverage report

docs: setup        # regenerate the tables and numbers of README.md and docs/ from docs/data/*.csv
	$(PY) -m papf.doctools.tables render

docs-check: setup  # fail when a table or number in README.md or docs/ differs from its CSV
	$(PY) -m papf.doctools.tables check

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache build *.egg-info
