# layershell: two commands. `make demo` and `make test` set everything up on a fresh machine.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test test-slow test-all clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e ".[test]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/layershell run examples/cantilever_thick.toml --out results/cantilever_thick
	@echo ""
	@echo "layershell is installed in $(VENV)/. To type 'layershell' in this shell, activate it first:"
	@echo "    source $(VENV)/bin/activate"
	@echo "(or call $(BIN)/layershell directly; 'deactivate' leaves the environment)"

# extra pytest arguments, e.g. `make test-slow PYTEST_ARGS="--time-budget 3600"` (.ci/run)
PYTEST_ARGS ?=

test: $(STAMP)
	$(BIN)/python -m pytest -m "not slow" $(PYTEST_ARGS)

test-slow: $(STAMP)
	$(BIN)/python -m pytest -m slow $(PYTEST_ARGS)

test-all: $(STAMP)
	$(BIN)/python -m pytest

clean:
	rm -rf $(VENV) results build src/*.egg-info

# Distributed runs (MPI + PETSc, docs/distributed.md); not part of `make test`. Needs the system
# packages: `apt-get install python3-petsc4py python3-mpi4py` (petsc4py has no PyPI wheels).
VENV_MPI  := .venv-mpi
PETSC_DIR ?= /usr/lib/petscdir/petsc3.18/x86_64-linux-gnu-real

$(VENV_MPI)/.installed: pyproject.toml
	/usr/bin/python3 -m venv --system-site-packages $(VENV_MPI)
	/usr/bin/python3 -c "import numpy; print('numpy==' + numpy.__version__)" > $(VENV_MPI)/constraints.txt
	PETSC_DIR=$(PETSC_DIR) $(VENV_MPI)/bin/python -m pip install -q -c $(VENV_MPI)/constraints.txt -e ".[test]"
	touch $@

.PHONY: test-mpi
test-mpi: $(STAMP) $(VENV_MPI)/.installed
	PETSC_DIR=$(PETSC_DIR) LAYERSHELL_MPI_PYTHON=$(VENV_MPI)/bin/python $(BIN)/python -m pytest -rs tests/test_petsc.py
