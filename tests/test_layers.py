"""The four floors (README, "What is where"): each package imports only from the floors below.

The contract itself is in pyproject.toml ([tool.importlinter]) and `lint-imports` checks it
statically; these tests check it the way a user meets it, by what an import actually loads.
"""

import importlib
import pkgutil
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("scene_model", "physics", "reference_cpu", "gpu_shader", "marchlab")


def loaded_by(code: str, prefixes: tuple[str, ...]) -> list[str]:
    """The modules starting with one of ``prefixes`` loaded by ``code`` in a fresh interpreter."""
    probe = (f"{code}\nimport sys\n"
             f"print(sorted(m for m in sys.modules if m.startswith({prefixes!r})))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         check=True, cwd=ROOT)
    return eval(out.stdout.strip().splitlines()[-1])


def every_module(package: str) -> str:
    """``import`` lines for every module of ``package``, subpackages included."""
    path = importlib.import_module(package).__path__
    names = [package] + [info.name for info in pkgutil.walk_packages(path, f"{package}.")]
    return "\n".join(f"import {name}" for name in names)


def test_import_linter_keeps_the_layer_and_acyclic_contracts():
    lint = shutil.which("lint-imports", path=str(Path(sys.executable).parent))
    assert lint, "lint-imports is missing: `make test` installs it (the dev extra)"
    run = subprocess.run([lint], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stdout[-3000:]
    assert "2 kept, 0 broken" in run.stdout


def test_importing_physics_loads_no_front_door_renderer_or_moderngl():
    loaded = loaded_by("import physics", ("marchlab", "gpu_shader", "reference_cpu", "moderngl"))
    assert loaded == []


def test_every_module_of_reference_cpu_loads_no_gpu_shader_opencl_or_front_door():
    loaded = loaded_by(every_module("reference_cpu"),
                       ("gpu_shader", "pyopencl", "moderngl", "marchlab", "physics"))
    assert loaded == []


def test_every_module_of_the_model_loads_no_engine_and_no_front_door():
    loaded = loaded_by(every_module("scene_model"),
                       ("physics", "reference_cpu", "gpu_shader", "marchlab"))
    assert loaded == []


@pytest.mark.parametrize("package", PACKAGES)
def test_every_package_says_what_lives_in_it(package):
    docstring = __import__(package).__doc__
    assert docstring and len(docstring.strip().splitlines()) >= 2
