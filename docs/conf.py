"""Sphinx configuration of the marchlab site (`make docs`).

Pages are MyST Markdown (they read as plain Markdown on GitHub too); the lessons are notebooks
rendered by myst-nb; the API reference is autodoc over numpydoc docstrings (napoleon). What is
generated from the code at build time lives in _ext/marchlab_sphinx.py.
"""

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS.parent))          # marchlab, reference_cpu, physics, gpu_shader
sys.path.insert(0, str(DOCS / "_ext"))

import marchlab  # noqa: E402

project = "marchlab"
author = "the marchlab authors"
copyright = "marchlab authors, MIT licence"
release = version = marchlab.__version__

extensions = [
    "myst_nb",                  # Markdown pages and notebooks (includes myst_parser)
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",      # numpydoc-style docstrings
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",   # MathJax served from the site itself: formulas render offline
    "sphinx.ext.viewcode",      # [source] links: the code behind every formula
    "marchlab_sphinx",          # the generated parts (CLI, API, scene fields, lessons)
]

exclude_patterns = ["_build", "_ext", "**/.ipynb_checkpoints", "Thumbs.db", ".DS_Store"]

# --- MyST ---------------------------------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 4        # links such as performance.md#physics-cpu work as on GitHub

# --- notebooks (the lessons) --------------------------------------------------------------------
# `make docs` runs every lesson so the site shows what the current code prints and draws; the
# test build passes -D nb_execution_mode=off (the lessons have tests of their own).
nb_execution_mode = "force"
nb_execution_timeout = 600      # seconds per cell; the NumPy reference renders in seconds
nb_execution_show_tb = True     # a failing lesson prints its traceback in the build log
nb_execution_allow_errors = False
# No widget JavaScript from a CDN (require.js, the widget manager): a saved widget shows the
# picture it leaves in its output instead (marchlab.widgets.View's first frame).
nb_ipywidgets_js = {}
nb_mime_priority_overrides = [(builder, "application/vnd.jupyter.widget-view+json", None)
                              for builder in ("html", "dirhtml", "singlehtml")]

# --- API reference ------------------------------------------------------------------------------
autodoc_member_order = "bysource"   # the order a student reads the module in
autodoc_preserve_defaults = True    # show `dtype=np.float64`, not its repr
autodoc_typehints = "description"  # short signatures; the types go into the parameter list
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
default_role = "py:obj"             # `name` in a docstring links to it where it can

# Command lines and option names are text, not typography: keep "--set" from becoming "–set".
smartquotes = False

# --- HTML ---------------------------------------------------------------------------------------
html_theme = "furo"
html_title = f"marchlab {release}"
html_static_path = []
