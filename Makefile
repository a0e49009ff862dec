# tribopipe — the two commands a newcomer needs are `make demo` and `make test`.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
BASE   := $(VENV)/.installed-base
TEST_STAMP := $(VENV)/.installed-test

.PHONY: install demo test lint bench bench-scale example clean

# `make demo` needs only the package and its base dependencies; `make test` adds the test
# extras (pytest, hypothesis, ruff, mujoco, playwright, frictionless), which the demo never uses.
# The installs go through uv, from PyPI. uv is the one on the PATH when there is one; else pip
# fetches it once per user into ~/.cache/tribopipe/uv (a 17.6 MB wheel: seconds of download),
# where a later clone finds it, as pip and uv keep their own caches there. uv makes the venv
# with pip seeded (without ensurepip's 3 s), installs from its cache without asking the index
# when every wheel is there (--offline; else it asks), and resolves and links the wheels several
# times faster than pip; the package's editable install is built by uv_build (pyproject.toml)
# in a fraction of a second. Where uv cannot be had or fails (offline with only pip's cache, a
# system Python that refuses pip installs, an unusual platform), `python -m venv` and pip do the
# same install. Neither compiles every module at install: Python compiles only what a command
# imports.
UV_CACHE := $(or $(XDG_CACHE_HOME),$(HOME)/.cache)/tribopipe/uv
UV := $(or $(shell command -v uv 2>/dev/null),$(UV_CACHE)/bin/uv)
PIP_INSTALL := $(PY) -m pip install --quiet --disable-pip-version-check --no-compile
UV_INSTALL := "$(UV)" pip install --quiet --python $(PY)

$(BASE): pyproject.toml
	@echo "installing tribopipe and its base dependencies into $(VENV) (once)"
	@if ! test -x "$(UV)" && mkdir -p "$(dir $(UV_CACHE))" 2>/dev/null && \
	    tmp=$$(mktemp -d "$(UV_CACHE).XXXXXX" 2>/dev/null); then \
	  $(PYTHON) -m pip install --quiet --disable-pip-version-check --target "$$tmp" uv \
	    >/dev/null 2>&1 && mv -T "$$tmp" "$(UV_CACHE)" 2>/dev/null; rm -rf "$$tmp"; fi
	@if ! test -x $(PY); then \
	  if test -x "$(UV)" && "$(UV)" venv --quiet --seed --allow-existing --python $(PYTHON) $(VENV); \
	  then :; else $(PYTHON) -m venv $(VENV); fi; fi
	@if test -x "$(UV)" && { $(UV_INSTALL) --offline -e . 2>/dev/null || $(UV_INSTALL) -e .; }; \
	then :; else $(PIP_INSTALL) -e .; fi
	@touch $(BASE)

$(TEST_STAMP): $(BASE)
	@echo "installing the test extras into $(VENV) (once)"
	@if test -x "$(UV)" && { $(UV_INSTALL) --offline -e ".[test]" 2>/dev/null || \
	    $(UV_INSTALL) -e ".[test]"; }; then :; else $(PIP_INSTALL) -e ".[test]"; fi
	@touch $(TEST_STAMP)

install: $(BASE)

# The demo: 48 synthetic exports (raw/example/) reduced into their own folder and map,
# processed/demo/; every row is flagged `synthetic`, so it is never published as a lab's.
# scripts/demo.py prints and runs five tribopipe commands (batch, map table, export
# abaqus, plot pairs, report) in one Python process: the libraries are imported once.
DEMO := processed/demo

demo: install
	$(PY) scripts/demo.py
	@echo ""
	@echo "Done. Outputs in $(DEMO)/ (synthetic data, flagged as such in the map):"
	@echo "  friction_map.parquet     the friction map (one row per run)"
	@echo "  runs.csv, failures.csv   the campaign's runs and failures"
	@echo "  friction_map_groups.md   group table with repeat statistics"
	@echo "  friction.inp             ABAQUS *FRICTION tables"
	@echo "  plots/traces, plots/pairs  trace and pressure plots (PNG)"
	@echo "  report.html              the campaign report (open it in a browser)"
	@echo ""
	@echo "Next: put tribopipe on your PATH (in this shell) with"
	@echo "  source $(VENV)/bin/activate"
	@echo "then try, from this folder:  tribopipe map show"
	@echo "Commands run here without --map read $(DEMO)/friction_map.parquet: batch named it in ./.tribopipe-map."

test: $(TEST_STAMP)
	$(PY) -m pytest

lint: $(TEST_STAMP)
	$(VENV)/bin/ruff check src tests bench scripts
	$(VENV)/bin/mypy

bench: install
	$(PY) bench/bench_campaign.py

bench-scale: install
	$(PY) bench/bench_scale.py

example: install
	$(PY) scripts/make_example_campaign.py

clean:
	rm -rf $(VENV) processed/*
