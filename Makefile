# tribopipe — the two commands a newcomer needs are `make demo` and `make test`.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: install demo test lint bench example clean

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
	$(VENV)/bin/tribopipe report configs/example.toml -o processed/report.html
	@echo "Outputs are in processed/: friction_map.parquet, friction_map_groups.md, friction.inp, report.html, plots/"

test: install
	$(PY) -m pytest

lint: install
	$(VENV)/bin/ruff check src tests bench scripts

bench: install
	$(PY) bench/bench_campaign.py

example: install
	$(PY) scripts/make_example_campaign.py

clean:
	rm -rf $(VENV) processed/*
