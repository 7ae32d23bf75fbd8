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
# The tests run in parallel (pytest-xdist): JOBS processes, "auto" = one per core, each on one
# thread, and each test file whole in one process (its shared fixtures run once). `make test JOBS=0`
# runs them in this process, on the threads the environment gives.
JOBS ?= auto
ifeq ($(JOBS),0)
PYTEST_JOBS :=
else
PYTEST_JOBS := OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1
PYTEST_JOBS_ARGS := -n $(JOBS) --dist loadfile
endif

test: $(STAMP)
	$(PYTEST_JOBS) $(BIN)/python -m pytest -m "not slow" $(PYTEST_JOBS_ARGS) $(PYTEST_ARGS)

test-slow: $(STAMP)
	$(PYTEST_JOBS) $(BIN)/python -m pytest -m slow $(PYTEST_JOBS_ARGS) $(PYTEST_ARGS)

test-all: $(STAMP)
	$(PYTEST_JOBS) $(BIN)/python -m pytest $(PYTEST_JOBS_ARGS) $(PYTEST_ARGS)

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
