"""``marchlab doctor``: which backends and optional extras work on this machine, one line each,
and for each one that does not, why not and the command that fixes it.

A backend works when `marchlab.render.backend_problem` says so (it makes an OpenGL context or
an OpenCL device, as a render would); the line then names the device it computes on. A backend
that cannot run gets its own reason and a fix: the pip extra when its Python package is missing,
else the Debian packages `make system-packages` installs (the Makefile's ``SYSTEM_PACKAGES``;
tests/test_doctor.py keeps the two lists equal). ``--brief`` says all of it in one line, as
``make demo`` prints before rendering with the NumPy reference.
"""

from __future__ import annotations

import importlib
import importlib.metadata
import importlib.util
import platform
import sys
from dataclasses import dataclass

from scene_model.errors import MarchlabError

from .render import BACKENDS, backend_problem

# The Debian packages (apt) and the Python modules (pip extra of the same name) each backend
# needs beyond NumPy.
APT_PACKAGES = {"gpu": ("libegl1", "libegl-mesa0", "libgl1-mesa-dri"),
                "opencl": ("pocl-opencl-icd", "ocl-icd-libopencl1"),
                "view": ("xvfb",),    # a display in memory: headless `marchlab view`, its tests
                "lessons": ("chromium",)}   # the notebook view's browser test (Playwright)
PYTHON_MODULES = {"gpu": ("moderngl",), "opencl": ("pyopencl",)}
# Backends that need what another backend or an extra brings: the raster pipeline draws with
# the gpu backend's OpenGL, the embree backend casts with the embree extra's embreex.
SAME_NEEDS = {"raster": "gpu", "embree": "embree"}
PYTHON_MODULES["embree"] = ("embreex",)


@dataclass(frozen=True)
class Extra:
    """An optional extra of pyproject.toml: what it is for and the modules it brings,
    as ``{module: distribution}``."""
    purpose: str
    modules: dict[str, str]


EXTRAS = {
    "embree": Extra("independent ground truth: marchlab truth --method embree",
                    {"embreex": "embreex", "skimage": "scikit-image"}),
    "lessons": Extra("the notebooks in lessons/ and make docs",
                     {"nbclient": "nbclient", "nbformat": "nbformat", "ipykernel": "ipykernel",
                      "ipywidgets": "ipywidgets", "matplotlib": "matplotlib"}),
}


STATES = {"backend": ("works", "unavailable"), "extra": ("installed", "missing")}


@dataclass(frozen=True)
class Finding:
    """One line of the report: a backend or an extra, whether it works, and if not, the fix."""
    kind: str           # "backend" or "extra"
    name: str
    works: bool
    detail: str         # the device it uses, or what is missing and why
    fix: str = ""

    @property
    def label(self) -> str:
        return f"{self.kind} {self.name}"

    def line(self, width: int) -> str:
        """``label  state: detail -- fix: FIX`` on one line, the labels padded to ``width``."""
        state = STATES[self.kind][0 if self.works else 1]
        fix = f" -- fix: {self.fix}" if self.fix else ""
        return f"{self.label:<{width}}  {state}: {one_line(self.detail + fix)}"


def one_line(text: str) -> str:
    """``text`` with every run of whitespace (newlines included) made one space."""
    return " ".join(text.split())


def backend_finding(name: str) -> Finding:
    """Whether backend ``name`` renders here: on which device, or why not and how to fix it."""
    try:
        problem = backend_problem(name)
    except Exception as err:     # a driver failing in a way the backend does not expect:
        problem = f"{type(err).__name__}: {err}"     # saying so is the doctor's whole job
    if problem is None:
        return Finding("backend", name, True, device_of(name))
    needs = SAME_NEEDS.get(name, name)
    missing = [m for m in PYTHON_MODULES.get(needs, ()) if importlib.util.find_spec(m) is None]
    if missing:
        fix = f"pip install 'marchlab[{needs}]' (or make demo)"
    elif needs in APT_PACKAGES:
        fix = (f"sudo apt-get install {' '.join(APT_PACKAGES[needs])} "
               "(or make system-packages as root)")
    else:
        fix = ""
    return Finding("backend", name, False, problem, fix)


def device_of(name: str) -> str:
    """The device a working backend computes on, as its module names it."""
    if name == "numpy":
        import numpy
        return f"NumPy {numpy.__version__} on the CPU ({platform.machine() or 'unknown'})"
    module = importlib.import_module(BACKENDS[name].module)
    if not hasattr(module, "device_name"):
        return BACKENDS[name].description
    try:
        return module.device_name()
    except MarchlabError as err:       # it passed its check a moment ago: say what it says now
        return f"device unknown ({err})"


def extra_finding(name: str) -> Finding:
    """Whether the extra ``name`` is installed (Python finds its modules), with their versions."""
    extra = EXTRAS[name]
    missing, versions = [], []
    for module, distribution in extra.modules.items():
        if importlib.util.find_spec(module) is None:
            missing.append(distribution)
            continue
        try:
            versions.append(f"{distribution} {importlib.metadata.version(distribution)}")
        except importlib.metadata.PackageNotFoundError:
            versions.append(distribution)
    if missing:
        return Finding("extra", name, False, f"{', '.join(missing)} not installed "
                       f"({extra.purpose})", f"pip install 'marchlab[{name}]'")
    return Finding("extra", name, True, f"{', '.join(versions)} ({extra.purpose})")


def findings() -> list[Finding]:
    """Every backend of `marchlab.render.BACKENDS`, then every extra of `EXTRAS`."""
    return [backend_finding(name) for name in BACKENDS] + [extra_finding(n) for n in EXTRAS]


def report() -> list[str]:
    """The lines ``marchlab doctor`` prints: where it runs, then one line per finding."""
    from . import __version__
    found = findings()
    width = max(len(f.label) for f in found)
    head = (f"marchlab {__version__} on Python {platform.python_version()}, "
            f"{platform.system()} {platform.machine()}")
    return [head] + [f.line(width) for f in found]


def brief() -> str:
    """One line: the backends that render here and why the others do not."""
    found = [backend_finding(name) for name in BACKENDS]
    works = ", ".join(f.name for f in found if f.works)
    broken = [f for f in found if not f.works]
    if not broken:
        return f"marchlab: backends that render here: {works}"
    why = "; ".join(f"{f.name} ({f.detail})" for f in broken)
    return one_line(f"marchlab: backends that render here: {works}; unavailable: {why}; "
                    "`marchlab doctor` says how to fix them")


def cmd_doctor(args) -> int:
    """``marchlab doctor``: the report (or ``--brief``, one line); exit 0 once it is said."""
    lines = [brief()] if args.brief else report()
    print("\n".join(lines))
    sys.stdout.flush()
    return 0


def add_parser(commands) -> None:
    """Add ``marchlab doctor`` to the CLI's subcommands (``commands`` from add_subparsers)."""
    p = commands.add_parser("doctor", help="say which backends and extras work here, and how "
                                           "to fix the ones that do not")
    p.add_argument("--brief", action="store_true",
                   help="one line: the backends that render here and why the others do not")
    p.set_defaults(func=cmd_doctor)
