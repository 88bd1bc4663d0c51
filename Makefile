# The README's two commands, for a fresh Debian machine:
#   make demo   set up .venv, install marchlab, render the classroom scene to out/classroom.png
#   make test   set up .venv with the test extras and run the whole suite
# and the lessons:
#   make lessons   set up .venv and open the lessons in JupyterLab (on 127.0.0.1 only)
# and the documentation site:
#   make docs   run every lesson and build the site into docs/_build/html (warnings are errors)
#   make speed-vs-error   rerun the speed-against-error benchmark (minutes) into the docs:
#               docs/speed-vs-error.md and its plots (plain `marchlab bench accuracy` writes out/)
# System packages the backends need are installed with apt when missing (root or sudo); where
# they cannot be (no root or sudo, no apt, no network) set-up goes on without them, says so in
# one line, and marchlab renders with the NumPy reference (`marchlab doctor` says the rest).

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin

# Mesa's EGL and software OpenGL (llvmpipe) for the headless GPU backend; Debian's PoCL
# (with the ICD loader) for the OpenCL backend: the PoCL wheel from PyPI cannot build
# kernels on some CPUs ("unknown target CPU 'generic'"), Debian's can.
# Xvfb, a display in memory, for the tests of the `marchlab view` window (pytest-xvfb starts it).
# Chromium, which Playwright drives (no browser download) for the notebook view's browser test.
SYSTEM_PACKAGES := libegl1 libegl-mesa0 libgl1-mesa-dri pocl-opencl-icd ocl-icd-libopencl1 xvfb chromium

.PHONY: demo test lessons docs speed-vs-error system-packages clean

# The first line says which backends render here and why the others cannot; the NumPy
# reference renders the demo everywhere.
demo: $(VENV)/.installed
	@$(BIN)/marchlab doctor --brief
	$(BIN)/marchlab render classroom -o out/classroom.png

# lint-imports checks the four floors (pyproject.toml, [tool.importlinter]) before the suite.
# The backends named here must run: a test that would skip for one fails instead, naming it
# (tests/required_backends.py). Without their drivers: make test MARCHLAB_REQUIRE_BACKENDS=
MARCHLAB_REQUIRE_BACKENDS := gpu,opencl,raster,embree
# The `marchlab view` window's tests (tests/view) must run too: imgui-bundle, and Xvfb started
# by pytest-xvfb. Without a display: make test MARCHLAB_REQUIRE_VIEW=
MARCHLAB_REQUIRE_VIEW := 1
# The notebook view's browser test (tests/browser) must run too: Chromium, Playwright, Voila.
MARCHLAB_REQUIRE_BROWSER := 1

test: $(VENV)/.installed-test
	@$(BIN)/marchlab doctor --brief
	$(BIN)/lint-imports
	MARCHLAB_REQUIRE_BACKENDS=$(MARCHLAB_REQUIRE_BACKENDS) MARCHLAB_REQUIRE_VIEW=$(MARCHLAB_REQUIRE_VIEW) \
	  MARCHLAB_REQUIRE_BROWSER=$(MARCHLAB_REQUIRE_BROWSER) $(BIN)/python -m pytest

# JupyterLab (in the lessons extra) serves this machine only; as root it must be told it may.
lessons: $(VENV)/.installed
	$(BIN)/jupyter lab --ip=127.0.0.1 --ServerApp.root_dir=lessons \
	  $$([ "$$(id -u)" = 0 ] && echo --allow-root)

# The test environment holds the docs extra and everything the lessons import, which the
# site executes (sphinx-build -D nb_execution_mode=off skips that, as tests/test_docs_site.py does).
docs: $(VENV)/.installed-test
	$(BIN)/python -m sphinx -W --keep-going -b html docs docs/_build/html

# The documentation's copy of the speed-against-error report is regenerated only on purpose,
# here: `marchlab bench accuracy` on its own writes into out/ and never over tracked files.
speed-vs-error: $(VENV)/.installed
	$(BIN)/marchlab bench accuracy -o docs/speed-vs-error.md --images docs/images

# Never stops the build: a package that cannot be installed is named, with the reason, in one
# line. sudo is used where it needs no password, or can ask for one on this terminal.
system-packages:
	@if ! command -v dpkg-query >/dev/null; then \
	  echo "marchlab: not a Debian system: install by hand if missing: $(SYSTEM_PACKAGES)"; exit 0; fi; \
	missing=""; \
	for pkg in $(SYSTEM_PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$pkg 2>/dev/null | grep -q "ok installed" || missing="$$missing $$pkg"; \
	done; \
	[ -n "$$missing" ] || exit 0; \
	sudo=""; \
	if [ "$$(id -u)" != 0 ]; then \
	  if ! command -v sudo >/dev/null; then why="not root, and no sudo"; \
	  elif [ -t 0 ] || sudo -n true 2>/dev/null; then sudo=sudo; \
	  else why="not root, and sudo wants a password with no terminal to type it"; fi; \
	  [ -n "$$sudo" ] || { echo "marchlab: cannot install$$missing ($$why): going on without them"; exit 0; }; \
	fi; \
	if ! command -v apt-get >/dev/null; then \
	  echo "marchlab: cannot install$$missing (no apt-get): going on without them"; exit 0; fi; \
	echo "installing system packages:$$missing"; \
	log=$$(mktemp); \
	if $$sudo apt-get update -qq >$$log 2>&1 && \
	  $$sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $$missing >>$$log 2>&1; \
	then rm -f $$log; \
	else echo "marchlab: could not install$$missing ($$(grep -v '^[[:space:]]*$$' $$log | tail -n 1)): going on without them"; rm -f $$log; fi

$(BIN)/python:
	@$(PYTHON) -c 'import sys; sys.exit(sys.version_info < (3, 11))' || \
	  { echo "marchlab needs Python >= 3.11; set PYTHON=python3.11 or newer"; exit 1; }
	@$(PYTHON) -c 'import ensurepip' 2>/dev/null || $(MAKE) --no-print-directory system-packages SYSTEM_PACKAGES=python3-venv
	@if $(PYTHON) -c 'import ensurepip' 2>/dev/null; then $(PYTHON) -m venv $(VENV); \
	elif $(PYTHON) -m pip --version >/dev/null 2>&1; then \
	  echo "marchlab: $(PYTHON) has no ensurepip (python3-venv): $(VENV) gets pip from $(PYTHON)'s own"; \
	  $(PYTHON) -m venv --without-pip $(VENV) && $(PYTHON) -m pip --python $(BIN)/python install -q pip; \
	else echo "marchlab: $(PYTHON) can make no virtual environment (no ensurepip, no pip): install python3-venv, or set PYTHON= to a Python 3.11+ that has it"; exit 1; fi
	$(BIN)/python -m pip install -q --upgrade pip

$(VENV)/.installed: pyproject.toml | $(BIN)/python system-packages
	$(BIN)/python -m pip install -q -e '.[all]'
	touch $@

$(VENV)/.installed-test: pyproject.toml | $(BIN)/python system-packages
	$(BIN)/python -m pip install -q -e '.[all,dev]'
	touch $@

clean:
	rm -rf $(VENV) out build *.egg-info .pytest_cache .hypothesis
