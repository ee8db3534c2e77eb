# comove_dolfinx: set-up and main jobs.
#   make demo   install what is missing, then run the main job (the beam scene)
#   make test   install what is missing, then run the test suite (serial and 2 MPI ranks)
#   make bench  run the speed/accuracy benchmarks (writes results/bench/)
# Debian 12: the FEniCSx stack comes from Debian's packages and serves /usr/bin/python3 only,
# so the virtual environment is made from that interpreter with --system-site-packages.

SYSPY   := /usr/bin/python3
VENV    := .venv
PY      := $(VENV)/bin/python
SUDO    := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
APT_PKGS := python3-dolfinx-real python3-gmsh python3-matplotlib python3-pytest python3-venv \
            python3-pip python3-setuptools python3-wheel python3-tqdm python3-meshio python3-h5py \
            openmpi-bin libopenblas0
NP      ?= 2
# mpirun as root and on machines with fewer cores than ranks
export OMPI_ALLOW_RUN_AS_ROOT := 1
export OMPI_ALLOW_RUN_AS_ROOT_CONFIRM := 1
export OMPI_MCA_rmaps_base_oversubscribe := 1
export OPENBLAS_NUM_THREADS := 1
export MPLBACKEND := Agg
MPIRUN  := mpirun -n $(NP)

.PHONY: all system venv demo test test-serial test-mpi bench clean

all: demo

# Installs the Debian packages that are missing (apt-get as root, sudo otherwise).
system:
	@missing=""; for p in $(APT_PKGS); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages:$$missing"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing; \
	fi

# The venv and the editable install; never pulls numpy, gmsh, mpi4py, petsc4py or FEniCS from PyPI.
$(VENV)/.installed: pyproject.toml | system
	$(SYSPY) -m venv --system-site-packages $(VENV)
	$(PY) -m pip install -q --no-deps --no-build-isolation -e .
	$(PY) -c "import comove_dolfinx; comove_dolfinx.check_platform()"
	touch $@

venv: system $(VENV)/.installed

demo: venv
	$(VENV)/bin/comove run beam --out results/beam

test: venv
	$(PY) -m pytest -q tests
	$(MPIRUN) $(PY) -m pytest -q -p no:cacheprovider -m mpi tests

bench: venv
	$(PY) -m comove_dolfinx.bench all --out results/bench

clean:
	rm -rf $(VENV) results .pytest_cache
