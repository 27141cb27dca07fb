# The two set-up commands of the README's Quick start. Both create .venv when it is missing.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python

.PHONY: run test test-fast lint docs clean constraints

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip

# catenet is installed editable: its bytecode is compiled here once, so that every start
# reads it (Python writes none itself where PYTHONDONTWRITEBYTECODE is set).
$(VENV)/.installed: pyproject.toml constraints.txt | $(PY)
	$(PY) -m pip install --quiet -c constraints.txt -e .
	$(PY) -m compileall -q catenet
	touch $@

$(VENV)/.installed-test: pyproject.toml constraints.txt | $(PY)
	$(PY) -m pip install --quiet -c constraints.txt -e ".[test]"
	$(PY) -m compileall -q catenet
	touch $@ $(VENV)/.installed

run: $(VENV)/.installed
	$(VENV)/bin/catenet run

# The whole suite, then its verdicts on degenerate models (tests marked roundoff) once
# more with every node moved by 1e-12 of the net's size and two threads
# (tests/conftest.py): a verdict that hangs on round-off fails here, not on a user's machine.
# pytest keeps its rewritten test modules as bytecode only where Python may write some:
# PYTHONDONTWRITEBYTECODE= lets it, so that later pytest processes (the second tier, a
# second run) read them instead of rewriting 300 modules' asserts (collection 19 s
# against 6 s, per worker).
test: $(VENV)/.installed-test
	PYTHONDONTWRITEBYTECODE= $(PY) -m pytest -n 2 --dist loadfile --no-loadscope-reorder -q --durations=15
	CATENET_ROUNDOFF=1 PYTHONDONTWRITEBYTECODE= $(PY) -m pytest -n 2 --dist loadfile --no-loadscope-reorder -q -m roundoff -p no:cacheprovider

# The development loop: the suite without the tests marked slow (large nets, long runs).
test-fast: $(VENV)/.installed-test
	PYTHONDONTWRITEBYTECODE= $(PY) -m pytest -n 2 --dist loadfile --no-loadscope-reorder -q -m "not slow"

# ruff, and mypy on the package's type hints ([tool.mypy] in pyproject.toml: the kernels
# aside, whose types Numba checks).
lint: $(VENV)/.installed-test
	$(PY) -m pip install --quiet ruff mypy
	$(VENV)/bin/ruff check catenet tests benchmarks docs/hooks
	$(VENV)/bin/mypy

# The documentation site, from docs/ and mkdocs.yml, into site/ (open site/index.html).
$(VENV)/.installed-docs: pyproject.toml constraints.txt | $(PY)
	$(PY) -m pip install --quiet -c constraints.txt -e ".[docs]"
	touch $@ $(VENV)/.installed

docs: $(VENV)/.installed-docs
	$(PY) -m mkdocs build --strict -d site

# constraints.txt from the environment the suite just passed in (keep it current)
constraints: $(VENV)/.installed-test
	{ sed -n '1,3p' constraints.txt; $(PY) -m pip freeze --exclude-editable | grep -v -e '^ruff==' -e '^mypy' -e '^pathspec==' -e '^#' -e '^ast_serialize' -e '^librt'; } > constraints.txt.new
	mv constraints.txt.new constraints.txt

clean:
	rm -rf $(VENV) out site .pytest_cache
