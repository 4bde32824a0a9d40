# The two set-up commands of the README:
#   make demo   - the main job: the paper's study on the simulated beam
#   make test   - C tests under sanitizers, then the Python test suite
# Both create .venv and install pihyst into it on first use.
PYTHON ?= python3
VENV = .venv
BIN = $(VENV)/bin

.PHONY: demo test test-slow install ctest lint pytest bench clean
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

pytest: install
	$(BIN)/python -m pytest
	$(BIN)/python -m pytest -q --doctest-modules src/pihyst --ignore=src/pihyst/__main__.py -p no:cacheprovider

test: ctest lint pytest

# the tests marked slow (measured data sets, simulated-beam accuracy, worker processes)
test-slow: install
	$(BIN)/python -m pytest -m slow

bench: install
	for b in benchmarks/bench_*.py; do $(BIN)/python $$b || exit 1; done

clean:
	rm -rf $(VENV) build out src/*.egg-info src/pihyst/_core.c src/pihyst/*.so
	$(MAKE) -C csrc clean
