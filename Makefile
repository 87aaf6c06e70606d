# Two commands do all set-up on a fresh machine:
#   make demo   runs the main job on the bundled data
#   make test   runs the linters (ruff, import-linter, mypy) and the test suite
# Each creates the virtual environment in .venv when it is missing.

PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
# Each target installs only the extras it needs (see pyproject.toml):
#   demo: fast (numba) and viz (matplotlib);  test and lint: also test (pytest, linters,
#   selenium), gym (the environment's tests need Gymnasium), pddl (unified-planning and LPG
#   for the baselines' tests), physics (MuJoCo and imageio for the physics tests; rendering
#   needs an OpenGL library such as Debian's libosmesa6) and team (SciPy for the team engine);  bench: also bench (the
#   peers: networkx, nano-astar, pathplanning).
# The dask, ray and parquet extras are not installed: the tests that need them skip with the
# reason (CI installs dask and parquet and requires them, see .ci/run).
STAMP := $(VENV)/.installed-stamp
DEMO_STAMP := $(VENV)/.demo-stamp
BENCH_STAMP := $(VENV)/.bench-stamp
MAKE_VENV = test -x $(PY) || { $(PYTHON) -m venv $(VENV) && $(PY) -m pip install --quiet --upgrade pip; }

.PHONY: demo test test-slow bench lint clean

$(STAMP): pyproject.toml
	$(MAKE_VENV)
	$(PY) -m pip install --quiet -e '.[fast,viz,test,gym,pddl,physics]'
	touch $(STAMP)

$(DEMO_STAMP): pyproject.toml
	$(MAKE_VENV)
	$(PY) -m pip install --quiet -e '.[fast,viz]'
	touch $(DEMO_STAMP)

$(BENCH_STAMP): $(STAMP)
	$(PY) -m pip install --quiet -e '.[fast,viz,test,gym,pddl,physics,bench]'
	touch $(BENCH_STAMP)

# The main job: the replacement-vs-replanning study on the bundled mazes, then
# its Markdown report with figures (results/report/report.md).
demo: $(DEMO_STAMP)
	$(VENV)/bin/selfrepair experiment paper --db results/paper.sqlite
	$(VENV)/bin/selfrepair report results/paper.sqlite -o results/report

# Lint: style (ruff), the architecture's import rules (import-linter contracts in
# pyproject.toml) and types (mypy --strict on the library).
lint: $(STAMP)
	$(VENV)/bin/ruff check src tests benchmarks examples
	$(VENV)/bin/lint-imports
	$(VENV)/bin/mypy

# pytest exits 5 when it collected no test: that must fail, not pass silently.
test: lint
	$(PY) -m pytest; status=$$?; \
	if [ $$status -eq 5 ]; then echo "pytest collected no tests" >&2; exit 1; fi; \
	exit $$status

test-slow: $(STAMP)
	$(PY) -m pytest -m slow

bench: $(BENCH_STAMP)
	$(PY) benchmarks/planner.py
	$(PY) benchmarks/dstar_lite.py
	$(PY) benchmarks/repair_latency.py
	$(PY) benchmarks/tablegen.py
	$(PY) benchmarks/gym_env.py
	$(PY) benchmarks/sweeps.py
	$(PY) benchmarks/startup.py
	$(PY) benchmarks/mazegen.py
	$(PY) benchmarks/memory.py
	$(PY) benchmarks/missions.py
	$(PY) benchmarks/diagnosis.py --jobs 2

clean:
	rm -rf $(VENV) build dist .pytest_cache .ruff_cache .hypothesis
