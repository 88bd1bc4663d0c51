# The README's two commands, for a fresh Debian machine:
#   make demo   set up .venv, install marchlab, render the classroom scene to out/classroom.png
#   make test   set up .venv with the test extras and run the whole suite
# and the documentation site:
#   make docs   run every lesson and build the site into docs/_build/html (warnings are errors)
# System packages the backends need are installed with apt when missing (root or sudo).

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin

# Mesa's EGL and software OpenGL (llvmpipe) for the headless GPU backend; Debian's PoCL
# (with the ICD loader) for the OpenCL backend: the PoCL wheel from PyPI cannot build
# kernels on some CPUs ("unknown target CPU 'generic'"), Debian's can.
SYSTEM_PACKAGES := libegl1 libegl-mesa0 libgl1-mesa-dri pocl-opencl-icd ocl-icd-libopencl1

.PHONY: demo test docs system-packages clean

demo: $(VENV)/.installed
	$(BIN)/marchlab render classroom -o out/classroom.png

# lint-imports checks the four floors (pyproject.toml, [tool.importlinter]) before the suite.
# The backends named here must run: a test that would skip for one fails instead, naming it
# (tests/required_backends.py). Without their drivers: make test MARCHLAB_REQUIRE_BACKENDS=
MARCHLAB_REQUIRE_BACKENDS := gpu,opencl

test: $(VENV)/.installed-test
	$(BIN)/lint-imports
	MARCHLAB_REQUIRE_BACKENDS=$(MARCHLAB_REQUIRE_BACKENDS) $(BIN)/python -m pytest

# The test environment holds the docs extra and everything the lessons import, which the
# site executes (sphinx-build -D nb_execution_mode=off skips that, as tests/test_docs_site.py does).
docs: $(VENV)/.installed-test
	$(BIN)/python -m sphinx -W --keep-going -b html docs docs/_build/html

system-packages:
	@if ! command -v dpkg-query >/dev/null; then \
	  echo "not a Debian system: install by hand if missing: $(SYSTEM_PACKAGES)"; exit 0; fi; \
	missing=""; \
	for pkg in $(SYSTEM_PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$pkg 2>/dev/null | grep -q "ok installed" || missing="$$missing $$pkg"; \
	done; \
	if [ -n "$$missing" ]; then \
	  sudo=""; [ "$$(id -u)" = 0 ] || sudo=sudo; \
	  echo "installing system packages:$$missing"; \
	  $$sudo apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $$sudo apt-get install -y -qq --no-install-recommends $$missing; \
	fi

$(BIN)/python:
	@$(PYTHON) -c 'import sys; sys.exit(sys.version_info < (3, 11))' || \
	  { echo "marchlab needs Python >= 3.11; set PYTHON=python3.11 or newer"; exit 1; }
	@$(PYTHON) -c 'import ensurepip' 2>/dev/null || $(MAKE) --no-print-directory system-packages SYSTEM_PACKAGES=python3-venv
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip

$(VENV)/.installed: pyproject.toml | $(BIN)/python system-packages
	$(BIN)/python -m pip install -q -e '.[all]'
	touch $@

$(VENV)/.installed-test: pyproject.toml | $(BIN)/python system-packages
	$(BIN)/python -m pip install -q -e '.[all,dev]'
	touch $@

clean:
	rm -rf $(VENV) out build *.egg-info .pytest_cache .hypothesis
