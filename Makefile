# The two set-up commands of the README's Quick start. Both create .venv when it is missing.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python

.PHONY: run test test-fast lint docs clean

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip

# catenet is installed editable: its bytecode is compiled here once, so that every start
# reads it (Python writes none itself where PYTHONDONTWRITEBYTECODE is set).
$(VENV)/.installed: pyproject.toml | $(PY)
	$(PY) -m pip install --quiet -e .
	$(PY) -m compileall -q catenet
	touch $@

$(VENV)/.installed-test: pyproject.toml | $(PY)
	$(PY) -m pip install --quiet -e ".[test]"
	$(PY) -m compileall -q catenet
	touch $@ $(VENV)/.installed

run: $(VENV)/.installed
	$(VENV)/bin/catenet run

test: $(VENV)/.installed-test
	$(PY) -m pytest -n 2 --dist loadfile -q --durations=15

# The development loop: the suite without the tests marked slow (large nets, long runs).
test-fast: $(VENV)/.installed-test
	$(PY) -m pytest -n 2 --dist loadfile -q -m "not slow"

# ruff, and mypy on the package's type hints ([tool.mypy] in pyproject.toml: the kernels
# aside, whose types Numba checks).
lint: $(VENV)/.installed-test
	$(PY) -m pip install --quiet ruff mypy
	$(VENV)/bin/ruff check catenet tests benchmarks docs/hooks
	$(VENV)/bin/mypy

# The documentation site, from docs/ and mkdocs.yml, into site/ (open site/index.html).
$(VENV)/.installed-docs: pyproject.toml | $(PY)
	$(PY) -m pip install --quiet -e ".[docs]"
	touch $@ $(VENV)/.installed

docs: $(VENV)/.installed-docs
	$(PY) -m mkdocs build --strict -d site

clean:
	rm -rf $(VENV) out site .pytest_cache
