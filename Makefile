# The two set-up commands of the README:
#   make demo   - the main job: the paper's study on the simulated beam
#   make test   - C tests under sanitizers, ruff, mypy, then the Python test suite
#   make docs   - the documentation site (Sphinx) in docs/_build/html, warnings as errors
# Both create .venv and install pihyst into it on first use.
PYTHON ?= python3
VENV = .venv
BIN = $(VENV)/bin

.PHONY: demo test test-slow install ctest lint typecheck pytest docs bench clean
$(BIN)/pihyst: pyproject.toml setup.py $(wildcard csrc/*.c csrc/*.h src/pihyst/*.pyx)
	@echo "make: installing pihyst and its dependencies into $(VENV) (first time only, a few minutes: pip's progress follows)"
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --progress-bar on -e ".[test]"
	@echo "make: pihyst is installed in $(VENV)"
	touch $@

install: $(BIN)/pihyst

demo: install
	$(BIN)/pihyst demo --out out/demo

ctest:
	$(MAKE) -C csrc test

lint: install
	$(BIN)/ruff check src tests benchmarks

# mypy on the package (configuration: pyproject.toml [tool.mypy]); stubtest checks the
# stubs of the compiled extensions against the extensions themselves
typecheck: install
	$(BIN)/mypy
	$(BIN)/python -m mypy.stubtest --allowlist tests/stubtest_allowlist.txt \
		pihyst._core pihyst._boucwen_core pihyst.io._fastcsv

pytest: install
	$(BIN)/python -m pytest
	$(BIN)/python -m pytest -q --doctest-modules src/pihyst --ignore=src/pihyst/__main__.py -p no:cacheprovider

test: ctest lint typecheck pytest

# the tests marked slow (measured data sets, simulated-beam accuracy, worker processes)
test-slow: install
	$(BIN)/python -m pytest -m slow

# the docs extra of pyproject.toml, installed into the venv on first use (read from the
# file, so that no rebuild of the extension is needed)
DOCS_REQUIREMENTS = $(BIN)/python -c "import sys; \
	toml = __import__('tomllib' if sys.version_info >= (3, 11) else 'tomli'); \
	print(' '.join(toml.load(open('pyproject.toml', 'rb'))['project']['optional-dependencies']['docs']))"
$(VENV)/.docs-installed: $(BIN)/pihyst pyproject.toml
	@echo "make: installing the docs extra (Sphinx, MyST, numpydoc) into $(VENV)"
	$(BIN)/pip install --quiet $$($(DOCS_REQUIREMENTS))
	touch $@

# the site: docs/ and the README as pages, the API reference from the docstrings
docs: $(VENV)/.docs-installed
	$(BIN)/python -m sphinx -W --keep-going -q -b html docs docs/_build/html
	@echo "make: the documentation site is in docs/_build/html/index.html"

bench: install
	for b in benchmarks/bench_*.py; do $(BIN)/python $$b || exit 1; done

clean:
	rm -rf $(VENV) build out docs/_build docs/api/generated src/*.egg-info src/pihyst/_core.c src/pihyst/*.so
	$(MAKE) -C csrc clean
