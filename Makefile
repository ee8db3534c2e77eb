# comove_dolfinx: set-up and main jobs.
#   make demo   install what is missing, then run the main job (the beam scene)
#   make test   install what is missing, then run the test suite (serial and 2 MPI ranks)
#   make study  speed against accuracy across methods (results/study/); make stability, make cost
#   make docs   the documentation site (docs/_build/html; Debian 12 with its packages)
#
# Where dolfinx comes from (DOLFINX=auto|apt|pip; docs/install.md):
#   apt   Debian's packages: Debian 12 has dolfinx 0.5.2, Debian 13 has 0.9. They serve
#         /usr/bin/python3 only, so the venv is made from it with --system-site-packages.
#   pip   the PyPI wheel dolfinx-solver-real (the current release, 0.11, with PETSc, MUMPS and MPICH
#         from PyPI) in a venv of its own (no system site packages: nothing of Debian's FEniCSx
#         stack mixes in); needs Python >= 3.12.
#   auto  apt on Debian 12 and 13, pip anywhere else.
# A venv remembers its source; use VENV=... for a second one (CI tests 0.11 in .venv-pip).

SYSPY   := /usr/bin/python3
VENV    ?= .venv
PY      := $(VENV)/bin/python
SUDO    := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
DOLFINX ?= auto
OS_ID   := $(shell . /etc/os-release 2>/dev/null; echo "$$ID$$VERSION_ID")
ifeq ($(DOLFINX),auto)
SOURCE  := $(if $(filter debian12 debian13,$(OS_ID)),apt,pip)
else
SOURCE  := $(DOLFINX)
endif
ifeq ($(filter apt pip,$(SOURCE)),)
$(error DOLFINX=$(DOLFINX): use apt, pip or auto)
endif

APT_PKGS := python3-dolfinx-real python3-gmsh python3-matplotlib python3-scipy python3-pytest python3-pytest-xdist \
            python3-venv python3-pip python3-setuptools python3-wheel python3-tqdm python3-meshio \
            python3-h5py openmpi-bin libopenblas0 paraview python3-paraview xvfb xauth
# the pip path compiles forms with the system's C compiler; PyPI's gmsh needs a few X/GL libraries
PIP_APT_PKGS := gcc libc6-dev libglu1-mesa libxcursor1 libxft2 libxinerama1
PIP_PKGS := "dolfinx-solver-real==0.11.*" gmsh matplotlib scipy tqdm pytest pytest-xdist meshio h5py
# the first Python >= 3.12 among python3.13, python3.12, pyenv's versions and python3
PIP_PYTHON ?= $(shell for p in python3.13 python3.12 \
    $$(ls -d $${PYENV_ROOT:-$$HOME/.pyenv}/versions/3.1[2-9]*/bin/python3 2>/dev/null | sort -rV) python3; do \
    $$p -c 'import sys; sys.exit(sys.version_info < (3, 12))' 2>/dev/null && { command -v $$p; break; }; done)

NP      ?= 2
# pytest-xdist workers for the serial suite: one per core, at most 4 (each holds a dolfinx and may
# start a 2-rank run); JOBS=0 runs it in one process. Most of a cold run is the C compiler building
# the generated forms, which the workers share through the JIT cache.
JOBS    ?= $(shell n=$$(nproc 2>/dev/null || echo 1); [ $$n -gt 4 ] && n=4; echo $$n)
# mpirun as root and with more ranks than cores (Open MPI 4 and 5); MPICH's mpiexec needs neither
export OMPI_ALLOW_RUN_AS_ROOT := 1
export OMPI_ALLOW_RUN_AS_ROOT_CONFIRM := 1
export OMPI_MCA_rmaps_base_oversubscribe := 1
export PRTE_MCA_rmaps_default_mapping_policy := :oversubscribe
# one thread per process (OpenBLAS, and the OpenMP runtime that Debian's PETSc links): ranks, not
# threads, share the cores (docs/parallel.md)
export OPENBLAS_NUM_THREADS := 1
export OMP_NUM_THREADS := 1
export MPLBACKEND := Agg
ifeq ($(SOURCE),pip)
MPIRUN  := $(VENV)/bin/mpiexec -n $(NP)
else
MPIRUN  := mpirun -n $(NP)
endif
STAMP   := $(VENV)/.installed-$(SOURCE)

.PHONY: all system venv demo test test-serial test-mpi study stability cost docs docs-site clean

all: demo

# $(call apt_missing,PACKAGES): a shell command that installs those of the Debian PACKAGES that are
# missing (apt-get as root, sudo otherwise)
define apt_missing
missing=""; for p in $(1); do \
  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
done; \
if [ -n "$$missing" ]; then \
  echo "installing Debian packages:$$missing"; \
  $(SUDO) apt-get update -qq && \
  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing; \
fi
endef

# Installs the Debian packages that are missing.
system:
	@if ! command -v dpkg-query >/dev/null; then \
	  echo "not a Debian system: make sure a C compiler is installed (the forms are compiled)"; exit 0; fi; \
	$(call apt_missing,$(if $(filter apt,$(SOURCE)),$(APT_PKGS),$(PIP_APT_PKGS)))

# The venv and the editable install. apt: never pulls numpy, gmsh, mpi4py, petsc4py or FEniCS from
# PyPI. pip: everything from PyPI, nothing from the system.
$(VENV)/.installed-apt: pyproject.toml | system
	@if [ -e $(VENV)/.installed-pip ]; then echo "$(VENV) holds the PyPI dolfinx: 'make clean' or choose \
	another VENV=..."; exit 2; fi
	$(SYSPY) -m venv --system-site-packages $(VENV)
	$(PY) -m pip install -q --no-deps --no-build-isolation -e .
	$(PY) -c "import comove_dolfinx; comove_dolfinx.check_platform()"
	touch $@

$(VENV)/.installed-pip: pyproject.toml | system
	@if [ -e $(VENV)/.installed-apt ]; then echo "$(VENV) holds Debian's dolfinx: 'make clean' or choose \
	another VENV=..."; exit 2; fi
	@if [ -z "$(PIP_PYTHON)" ]; then echo "DOLFINX=pip needs Python >= 3.12 (python3.12 or newer on PATH, \
	or PIP_PYTHON=/path/to/python3)"; exit 2; fi
	$(PIP_PYTHON) -m venv $(VENV)
	$(VENV)/bin/pip install -q $(PIP_PKGS)
	$(VENV)/bin/pip install -q --no-deps -e .
	$(PY) -c "import comove_dolfinx; comove_dolfinx.check_platform()"
	touch $@

venv: system $(STAMP)

demo: venv
	$(VENV)/bin/comove run beam --out results/beam --overwrite

test: venv
	@$(PY) -c "import comove_dolfinx, dolfinx; print('testing with dolfinx', dolfinx.__version__, '($(SOURCE))')"
	$(PY) -m pytest -q -n $(JOBS) tests
	$(MPIRUN) $(PY) -m pytest -q -p no:cacheprovider -m mpi tests

# speed against accuracy, where methods break, what an iteration costs (docs/study.md, docs/stability.md,
# docs/performance.md); each writes CSV, PNG and Markdown under results/
study: venv
	$(VENV)/bin/comove study all --out results/study

stability: venv
	$(PY) -m comove_dolfinx.stability all --out results/stability

cost: venv
	$(PY) -m comove_dolfinx.benchmarks dolfinx --out results/cost
	$(PY) -m comove_dolfinx.benchmarks floor --out results/cost
	$(PY) -m comove_dolfinx.benchmarks solvers --out results/cost
	$(PY) -m comove_dolfinx.benchmarks scale --out results/cost
	$(MPIRUN) $(PY) -m comove_dolfinx.benchmarks scale --out results/cost
	$(PY) -m comove_dolfinx.benchmarks slopes --out results/cost

# The documentation site: Sphinx with MyST (the Markdown pages of docs/), autodoc and napoleon (the API
# reference from the numpy-style docstrings), and each demo run once and shown as a page with its
# pictures (jupytext reads the percent scripts; docs/conf.py). Warnings are errors. Built with Debian
# 12's Sphinx 5.3, MyST 0.18 and furo, and jupytext from PyPI into the venv (its other dependencies are
# Debian's); elsewhere it is skipped.
DOCS_APT_PKGS := python3-sphinx python3-myst-parser furo python3-nbformat
DOCS_PIP_PKGS := "jupytext==1.19.*"

docs:
	@if [ "$(OS_ID)" = debian12 ] && [ "$(SOURCE)" = apt ]; then $(MAKE) --no-print-directory docs-site; \
	else echo "make docs: the site is built on Debian 12 with Debian's dolfinx (DOLFINX=apt); skipped on \
	$(OS_ID) with DOLFINX=$(SOURCE)"; fi

docs-site: venv
	@$(call apt_missing,$(DOCS_APT_PKGS))
	@$(PY) -c "import jupytext" 2>/dev/null || $(PY) -m pip install -q $(DOCS_PIP_PKGS)
	$(PY) -m sphinx -W --keep-going -q -b html docs docs/_build/html
	@echo "docs: docs/_build/html/index.html"

clean:
	rm -rf $(VENV) results .pytest_cache docs/_build docs/demos
