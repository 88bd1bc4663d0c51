"""Render every bundled scene and equivalence case with this tree and an earlier revision, and
say which buffers differ by even one bit.

    python benchmarks/frames_against.py REV [--backends numpy,gpu,opencl,opencl-one-ray]

A refactoring (moving modules, generating the same program another way) must not change a
frame. REV is checked out into a temporary git worktree; each tree renders, in a process of
its own with this interpreter, every bundled scene at 96x72 and every feature case of
tests/equivalence/cases.py at 64x48, on each backend in each of its precisions, with path
labels, and the buffers (colour, depth, normal, steps, object id, hit, path) are compared
bit for bit. "opencl-one-ray" is the opencl backend's one-ray program. Prints one line per
buffer that differs, then a summary; exits 1 if any differs.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BUFFERS = ("color", "depth", "normal", "steps", "object_id", "hit", "path")

# Run with the tree under test first on sys.path: writes one .npz per (case, backend,
# precision) into the folder argv[1]. It copes with the layouts of earlier revisions
# (rendered_scene and the OpenCL runner have moved; path labels were always on).
PROBE = """
import importlib, inspect, sys
import numpy as np
sys.path.insert(0, "tests")
import marchlab
from marchlab.render import BACKENDS
from equivalence import cases
out, wanted = sys.argv[1], sys.argv[2].split(",")
for place in ("marchlab.bodies", "scene_model.scene"):   # an earlier layout first
    try:
        rendered_scene = importlib.import_module(place).rendered_scene
        break
    except (ImportError, AttributeError):
        pass
labels = "path_labels" in inspect.signature(marchlab.render).parameters
extra = {"path_labels": True} if labels else {}
opencl = importlib.import_module(BACKENDS["opencl"].module)
scenes = {"scene-" + n: (marchlab.load_scene(n), 96, 72) for n in marchlab.bundled_scene_names(meshes=False)}
scenes.update({"case-" + n: (s, 64, 48) for n, s in cases.feature_cases().items()})
for key, (scene, w, h) in scenes.items():
    for backend in wanted:
        name = "opencl" if backend == "opencl-one-ray" else backend
        for precision in BACKENDS[name].precisions:
            if backend == "opencl-one-ray":
                f = opencl.render(rendered_scene(scene), w, h, precision, packets=False, **extra)
            else:
                f = marchlab.render(scene, w, h, backend=backend, precision=precision, **extra)
            np.savez(f"{out}/{key}--{backend}-{precision}.npz",
                     **{b: getattr(f, b) for b in %r})
""" % (BUFFERS,)


def render_tree(tree: Path, folder: Path, backends: str) -> None:
    folder.mkdir()
    subprocess.run([sys.executable, "-c", PROBE, str(folder), backends], cwd=tree, check=True,
                   env=dict(os.environ, PYTHONPATH=str(tree)))


def differing(old: Path, new: Path) -> tuple[int, list[str]]:
    """How many files both trees wrote, and a line per buffer that differs."""
    compared, lines = 0, []
    for a in sorted(old.glob("*.npz")):
        b = new / a.name
        if not b.exists():
            lines.append(f"{a.stem}: only in the earlier revision")
            continue
        compared += 1
        x, y = np.load(a), np.load(b)
        for buffer in BUFFERS:
            u, v = np.ascontiguousarray(x[buffer]), np.ascontiguousarray(y[buffer])
            if u.dtype != v.dtype or u.shape != v.shape or u.tobytes() != v.tobytes():
                count = int(np.count_nonzero(u != v)) if u.shape == v.shape else u.size
                lines.append(f"{a.stem} {buffer}: {count} values differ")
    return compared, lines


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("revision", help="the earlier revision (commit, tag, branch)")
    parser.add_argument("--backends", default="numpy,gpu,opencl,opencl-one-ray")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        scratch = Path(scratch)
        old = scratch / "old"
        subprocess.run(["git", "worktree", "add", "--detach", "-q", str(old), args.revision],
                       cwd=ROOT, check=True)
        try:
            render_tree(old, scratch / "old-frames", args.backends)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(old)], cwd=ROOT,
                           check=True)
        render_tree(ROOT, scratch / "new-frames", args.backends)
        compared, lines = differing(scratch / "old-frames", scratch / "new-frames")
    print("\n".join(lines))
    print(f"{compared} frames compared against {args.revision}, "
          f"{len(lines)} buffers differ")
    return 1 if lines else 0


if __name__ == "__main__":
    sys.exit(main())
