# cablesim: `make run` runs the main job on the shipped default case, `make test` runs the tests.
# Both create .venv and install the package (with its test extras) first if needed.

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
CLI    := $(VENV)/bin/cablesim
STAMP  := $(VENV)/.installed

.PHONY: install run test bench clean

$(STAMP): pyproject.toml
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	@touch $(STAMP)

install: $(STAMP)

run: $(STAMP)
	$(CLI) sweep configs/paper-example.yaml

test: $(STAMP)
	$(PY) -m pytest -q

bench: $(STAMP)
	$(PY) benchmarks/bench_dynamics.py
	$(PY) benchmarks/bench_sweep.py

clean:
	rm -rf runs/*/ .pytest_cache .hypothesis
