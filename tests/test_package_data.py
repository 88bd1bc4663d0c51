"""A wheel of marchlab carries every file its packages read at run time: the shaders and their
templates (gpu_shader/glsl and its pipeline/ and raster/ folders) and the bundled scenes and
models. The editable install of `make` reads them from the checkout, so a glob missing in
pyproject.toml's [tool.setuptools.package-data] would show only in a built wheel; this checks
the globs against the files instead (`pip wheel .` then lists the same 53 shader files)."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DATA_SUFFIXES = {".glsl", ".frag", ".vert", ".comp", ".cl", ".toml", ".obj", ".mtl"}


@pytest.mark.parametrize("package", ["gpu_shader", "scene_model"])
def test_package_data_globs_cover_every_data_file(package):
    globs = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"][
        "package-data"][package]
    covered = {path for pattern in globs for path in (ROOT / package).glob(pattern)}
    data = {path for path in (ROOT / package).rglob("*")
            if path.suffix in DATA_SUFFIXES and "__pycache__" not in path.parts}
    assert data, package
    assert sorted(str(p.relative_to(ROOT)) for p in data - covered) == []
