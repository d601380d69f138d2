# Two commands set everything up on a fresh machine (Python 3.11, pip, make):
#   make run   -- every scenario (with both state models) and a noise sweep, reports into
#                 results/ (report.html)
#   make test  -- ruff + pytest (installs Debian's chromium for the browser tests if missing)
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
DEVSTAMP := $(VENV)/.installed-dev
BENCHSTAMP := $(VENV)/.installed-bench

.PHONY: run test docs bench safety lint clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# Every install takes the versions pinned in requirements.lock (docs/howto/development.md, "Pinned installs").
LOCK   := requirements.lock

$(STAMP): pyproject.toml $(LOCK) | $(BIN)/python
	$(BIN)/pip install --quiet -c $(LOCK) -e ".[dask]"
	touch $@

$(DEVSTAMP): pyproject.toml $(LOCK) | $(BIN)/python
	$(BIN)/pip install --quiet -c $(LOCK) -e ".[dev,dask]"
	touch $@ $(STAMP)

run: $(STAMP)
	$(BIN)/sse-cosim batch scenarios/ --out results/
	$(BIN)/sse-cosim sweep --file sweeps/noise.toml --out results/sweep/ --summaries-only
	$(BIN)/sse-cosim sweep --file sweeps/motion/every_scenario.toml \
		--out results/motion/every_scenario/ --summaries-only
	$(BIN)/sse-cosim report results/ --out results/

$(BENCHSTAMP): pyproject.toml $(LOCK) | $(BIN)/python
	$(BIN)/pip install --quiet -c $(LOCK) -e ".[dask,bench]"
	touch $@ $(STAMP)

# The browser tests drive Debian's chromium (playwright never downloads a browser).
# The first pytest spreads the test files over every core (pytest-xdist; a file's tests stay
# in one process, so its module fixtures run once).
# The second pytest runs the compiled kernels against their NumPy references again with
# NumPy's AVX-512 code (SIMD sin, cos, arctan2 that may differ from libm in the last bit) and
# numba's host CPU features switched off, as on a machine with neither (the `kernels` marker;
# about 20 s, a minute the first time while numba compiles for the generic CPU).
test: $(DEVSTAMP)
	command -v chromium >/dev/null || (apt-get update && apt-get install -y chromium chromium-driver)
	$(BIN)/ruff check .
	$(BIN)/python -m pytest -q -n auto --dist loadfile
	NPY_DISABLE_CPU_FEATURES="X86_V4 AVX512_ICL AVX512_SPR" NUMBA_CPU_NAME=generic $(BIN)/python -m pytest -q -m kernels

# The documentation site (docs/, mkdocs.yml) into site/; --strict: a broken link or a stale
# reference fails. The tests build it too and open it in Chromium (tests/reporting/test_docs_site.py).
docs: $(DEVSTAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict

bench: $(BENCHSTAMP)
	$(BIN)/sse-cosim bench --out results/

# The safety campaign (sweeps/safety.toml; measured on two cores: S1-S3 about 31 minutes, the
# town 44, the junction 109, the crowd 92, about 4.7 hours in all; `make bench` projects it):
# results/safety/ and results/safety.md; exit status 4 if a safety target is missed.
safety: $(STAMP)
	$(BIN)/sse-cosim safety --out results/safety

clean:
	rm -rf $(VENV) sumo_net/build
