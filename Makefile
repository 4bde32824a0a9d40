# The two set-up commands of the README:
#   make demo   - the main job: the paper's study on the simulated beam
#   make test   - C tests under sanitizers, then the Python test suite
# Both create .venv and install pihyst into it on first use.
PYTHON ?= python3
VENV = .venv
BIN = $(VENV)/bin

.PHONY: demo test test-slow install ctest lint pytest bench clean
$(BIN)/pihyst: pyproject.toml setup.py $(wildcard csrc/*.c csrc/*.h src/pihyst/*.pyx)
	@echo "== first run: creating $(VENV) and installing pihyst with its dependencies (1-3 min)"
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --progress-bar off -e ".[test]" | grep -E "^(Collecting|Building|Successfully|ERROR)" || true
	@test -x $(BIN)/pihyst || { echo "pip install failed: run $(BIN)/pip install -e '.[test]'"; exit 1; }
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
