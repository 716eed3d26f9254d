# Two commands on a fresh machine with Python 3.11 and pip: `make demo` and `make test`.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test test-slow test-heavy bench screenshot docs clean

$(PY):
	$(PYTHON) -m venv $(VENV)

# Re-install (and rebuild the compiled kernels) when the package metadata or a kernel changes.
$(STAMP): pyproject.toml setup.py Makefile $(wildcard cspace/geometry/_kernels/*.pyx) | $(PY)
	$(PY) -m pip install --upgrade pip
	$(PY) -m pip install -e '.[dev,peers,bench]'
	touch $(STAMP)

demo: $(STAMP)
	$(PY) examples/convex_sum.py
	$(PY) examples/view_convex.py --out out/convex_demo.html
	$(VENV)/bin/cspace view scenes/window.toml -o out/window.html
	$(VENV)/bin/cspace plan scenes/comb.toml --seed 1 --time 5 --explain --fcl-check \
		-o out/comb_path.txt --html out/comb_plan.html --result out/comb_result.json

# Needs Chromium (Debian: apt-get install -y chromium); rewrites the README pictures.
screenshot: $(STAMP)
	$(PY) examples/view_convex.py --out out/convex_demo.html --screenshot docs/convex_demo.png
	$(PY) examples/decide_scenes.py --out out --screenshot docs

# The default suite in TEST_WORKERS processes (pytest-xdist), then the tests marked `last` in
# one process of their own: they leave Dask's threads and spawn's resource tracker behind,
# which a worker's later fork tests would see.
TEST_WORKERS ?= 2

test: $(STAMP)
	$(PY) -m pytest -n $(TEST_WORKERS) -m "not slow and not last"
	$(PY) -m pytest -m "last and not slow"

test-slow: $(STAMP)
	$(PY) -m pytest -m "slow and not heavy"

test-heavy: $(STAMP)
	$(PY) -m pytest -m heavy

bench: $(STAMP)
	$(PY) benchmarks/bench_cvms.py
	$(PY) benchmarks/bench_superset.py
	$(PY) benchmarks/bench_minkowski.py
	$(PY) benchmarks/bench_queries.py
	$(PY) benchmarks/bench_hard_cases.py
	$(PY) benchmarks/bench_cold_start.py
	$(PY) benchmarks/bench_speed_error.py

# The documentation site (Sphinx, warnings are errors) into docs/_build/html.
docs: $(STAMP)
	$(PY) -m pip install -e '.[docs]'
	$(PY) -m sphinx -E -W --keep-going -b html docs docs/_build/html
	@echo "open docs/_build/html/index.html"

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache
