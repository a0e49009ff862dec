# tribopipe — the two commands a newcomer needs are `make demo` and `make test`.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: install demo test lint bench bench-scale example clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test]"
	touch $(STAMP)

install: $(STAMP)

demo: install
	$(VENV)/bin/tribopipe batch configs/example.toml
	$(VENV)/bin/tribopipe map table --map processed/friction_map.parquet --format markdown -o processed/friction_map_groups.md
	$(VENV)/bin/tribopipe export abaqus --map processed/friction_map.parquet -o processed/friction.inp
	$(VENV)/bin/tribopipe plot pairs --map processed/friction_map.parquet -o processed/plots/pairs
	$(VENV)/bin/tribopipe report configs/example.toml -o processed/report.html
	@echo ""
	@echo "Done. Outputs in processed/:"
	@echo "  friction_map.parquet     the friction map (one row per run)"
	@echo "  runs.csv, failures.csv   the campaign's runs and failures"
	@echo "  friction_map_groups.md   group table with repeat statistics"
	@echo "  friction.inp             ABAQUS *FRICTION tables"
	@echo "  plots/traces, plots/pairs  trace and pressure plots (PNG)"
	@echo "  report.html              the campaign report (open it in a browser)"

test: install
	$(PY) -m pytest

lint: install
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
