# meicp — two commands on a fresh Debian bookworm machine (as root):
#   make demo    the main job on a shipped default
#   make test    the serial suite, then the 2-rank suite
SHELL := /bin/bash
PY := .venv/bin/python
export OMPI_ALLOW_RUN_AS_ROOT := 1
export OMPI_ALLOW_RUN_AS_ROOT_CONFIRM := 1
# keep BLAS single-threaded: the ranks are the parallelism (2 cores)
export OMP_NUM_THREADS := 1
export OPENBLAS_NUM_THREADS := 1
MPIRUN := mpirun -n 2 --oversubscribe
PYTEST_MPI := $(MPIRUN) $(PY) -m mpi4py -m pytest --with-mpi --timeout=120 --timeout-method=thread -p no:cacheprovider --color=no

.PHONY: setup demo test test-serial test-mpi bench clean

setup:
	@bash scripts/setup.sh

demo: setup
	@bash scripts/demo.sh

test: setup
	@$(MAKE) --no-print-directory test-serial
	@$(MAKE) --no-print-directory test-mpi

# pytest exits 5 when it collects nothing: that is a failure here, as it should be
test-serial:
	timeout 1200 $(PY) -m pytest -q --timeout=300 -p no:cacheprovider -m "not mpi" tests

test-mpi:
	timeout 600 $(PYTEST_MPI) -q -m mpi tests

# benchmarks are not tests: `make bench` (quick, < 10 min, into build/benchmarks/) or
# `make bench MODE=full` (the committed figures of docs/benchmarks.md, into docs/benchmarks/)
MODE ?= quick
bench: setup
	@bash scripts/bench.sh $(MODE)

clean:
	rm -rf .venv build src/*.egg-info .pytest_cache
