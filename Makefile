# The two set-up commands of the README:
#   make demo   - the main job: the paper's study on the simulated beam
#   make test   - C tests under sanitizers, ruff, mypy, then the Python test suite
#   make docs   - the documentation site (Sphinx) in docs/_build/html, warnings as errors
# Both create .venv and install pihyst into it on first use. Each long step runs under
# tools/heartbeat.py, which passes its output through and, after 8 s of silence, prints
# a line saying what is running (the file gcc is compiling, the program started).
PYTHON ?= python3
VENV = .venv
BIN = $(VENV)/bin
HEARTBEAT = $(PYTHON) tools/heartbeat.py --
# the measured data sets (not shipped): $PIHYST_DATA, else ../shared/data beside the clone
DATA_SOURCE = $(or $(PIHYST_DATA),$(wildcard ../shared/data))

.PHONY: demo test test-slow test-heavy install ctest lint typecheck pytest docs bench clean data figures screenshot
$(BIN)/pihyst: pyproject.toml setup.py $(wildcard csrc/*.c csrc/*.h src/pihyst/*.pyx)
	@echo "make: installing pihyst and its dependencies into $(VENV) (first time only, a few minutes: pip's progress follows, then the C extensions' build)"
	$(HEARTBEAT) $(PYTHON) -m venv $(VENV)
	$(HEARTBEAT) $(BIN)/pip install --quiet --upgrade pip
	$(HEARTBEAT) $(BIN)/pip install --progress-bar on -e ".[test]"
	@echo "make: pihyst is installed in $(VENV); 'source $(VENV)/bin/activate' puts the pihyst command on your PATH"
	touch $@

install: $(BIN)/pihyst

demo: install
	$(HEARTBEAT) $(BIN)/pihyst demo --out out/demo

ctest:
	$(HEARTBEAT) $(MAKE) -C csrc test

lint: install
	$(BIN)/ruff check src tests benchmarks

# mypy on the package (configuration: pyproject.toml [tool.mypy]); stubtest checks the
# stubs of the compiled extensions against the extensions themselves
typecheck: install
	$(BIN)/mypy
	$(BIN)/python -m mypy.stubtest --allowlist tests/stubtest_allowlist.txt \
		pihyst._core pihyst._boucwen_core pihyst.io._fastcsv pihyst.identify._turning

pytest: install
	$(HEARTBEAT) $(BIN)/python -m pytest
	$(HEARTBEAT) $(BIN)/python -m pytest -q --doctest-modules src/pihyst --ignore=src/pihyst/__main__.py -p no:cacheprovider

test: ctest lint typecheck pytest

# the tests marked slow (measured data sets, simulated-beam accuracy, worker processes)
test-slow: install
	$(HEARTBEAT) $(BIN)/python -m pytest -m slow

# the tests over five minutes each (the steering mirror's one model for all levels)
test-heavy: install
	$(HEARTBEAT) $(BIN)/python -m pytest -m heavy

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

# links each measured data set (its folder, with its LICENSE and SOURCE.md) into data/
data:
	@if [ -z "$(DATA_SOURCE)" ] || [ ! -d "$(DATA_SOURCE)" ]; then \
	    echo "make: no measured data sets: set PIHYST_DATA to the folder that holds them" \
	         "(README, 'Measured data')"; exit 2; fi
	@mkdir -p data
	@for d in "$(DATA_SOURCE)"/*/; do \
	    ln -sfn "$$(cd "$$d" && pwd)" "data/$$(basename "$$d")" && \
	    echo "make: data/$$(basename "$$d") -> $$(cd "$$d" && pwd)"; done

# every figure quoted in README.md and docs/ against the code that produces it
# (docs/figures.toml; the demo's figures from out/demo/metrics.json when it exists)
figures: install
	$(HEARTBEAT) $(BIN)/python tools/check_figures.py --all \
	    $(if $(wildcard out/demo/metrics.json),--demo-metrics out/demo/metrics.json)

# docs/demo-report.png: headless Chromium's screenshot of out/demo/report.html
screenshot: demo
	$(HEARTBEAT) $(BIN)/python tools/screenshot.py out/demo/report.html docs/demo-report.png

clean:
	rm -rf $(VENV) build out docs/_build docs/api/generated src/*.egg-info src/pihyst/_core.c src/pihyst/*.so
	$(MAKE) -C csrc clean
