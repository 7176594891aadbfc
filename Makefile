# Two commands do all the set-up on a fresh machine with Python >= 3.11 and make:
#   make run    -> engineering estimate for a human red blood cell in a 4 um capillary
#   make test   -> the whole default test suite (doctests included)
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV   := .venv
BIN    := $(VENV)/bin

.PHONY: run test test-portable validation validation-report benchmark docs clean

$(BIN)/vesicle-tube: pyproject.toml
	$(PYTHON) -c 'import sys; sys.exit(sys.version_info < (3, 11) and "Python >= 3.11 is required")'
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $@

run: $(BIN)/vesicle-tube
	$(BIN)/vesicle-tube estimate

# -n 2: the suite runs on both cores of the reference machine (pytest-xdist)
test: $(BIN)/vesicle-tube
	$(BIN)/python -m pytest -q -n 2

# The tests marked `numerics` again on another code path, as on another CPU: numba compiled for a
# generic x86-64 (in its own cache), OpenBLAS on its Sandybridge kernels (AVX without FMA) and
# numpy without its AVX-512 loops (its SIMD log and exp differ); names a CPU or build lacks are
# ignored. Each tolerance must hold there too (CI runs this).
test-portable: $(BIN)/vesicle-tube
	NUMBA_CPU_NAME=generic NUMBA_CACHE_DIR=build/numba-generic OPENBLAS_CORETYPE=Sandybridge \
	NPY_DISABLE_CPU_FEATURES="X86_V4 AVX512_ICL AVX512_SPR" \
	    $(BIN)/python -m pytest -n 2 -m 'numerics and (not slow or ci)'

validation: $(BIN)/vesicle-tube
	$(BIN)/python -m pytest -q -n 2 -m slow

# docs/validation.md from docs/validation.md.in: the tests that record (fixture `report`) write
# the values they assert, then tests/validation_report.py fills the template. SLOW=1 also runs
# the slow recording tests and stores their records in docs/data/validation_records_slow.json;
# without it those committed records are used.
RECORDS := build/validation-records
validation-report: $(BIN)/vesicle-tube
	rm -rf $(RECORDS)
	VALIDATION_RECORDS=$(RECORDS) $(BIN)/python -m pytest -q -n 2 \
	    -m '$(if $(SLOW),record,record and (not slow or ci))'
	$(BIN)/python tests/validation_report.py render --records $(RECORDS) $(if $(SLOW),--update-slow)

benchmark: $(BIN)/vesicle-tube
	$(BIN)/python tests/benchmarks/run_benchmarks.py
	$(BIN)/python tests/benchmarks/bench_vesicle.py
	$(BIN)/python tests/benchmarks/bench_solution_map.py
	$(BIN)/python tests/benchmarks/bench_check.py
	$(BIN)/python tests/benchmarks/bench_infer.py
	$(BIN)/python tests/benchmarks/bench_map_build.py

# The HTML reference in build/docs/html: the pages of docs/ and the API of the three packages
# (Sphinx; warnings are errors; the docstrings' >>> examples run as doctests in `make test`).
# Sphinx, MyST-Parser and MathJax (served with the pages) are installed on first use.
docs: $(BIN)/vesicle-tube
	$(BIN)/python -c 'import importlib, sphinx, myst_parser; importlib.import_module("sphinx-mathjax-offline")' 2>/dev/null || $(BIN)/python -m pip install --quiet -e '.[docs]'
	$(BIN)/sphinx-build -W --keep-going -b html docs build/docs/html

clean:
	rm -rf $(VENV) build *.egg-info

# The wheel as users install it: built from a copy of the tree, installed into a fresh venv
# outside the checkout (dependencies from PyPI, pinned to .venv's versions), README.md's commands
# run there and from the source, exit codes, JSON and written files compared (tests/test_wheel.py).
.PHONY: test-wheel
test-wheel: $(BIN)/vesicle-tube
	$(BIN)/python -m pytest -q -s -m slow tests/test_wheel.py
