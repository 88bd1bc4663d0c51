"""Time this tree against an earlier revision, side by side in one run.

    python benchmarks/bench_against.py REV [--scene classroom] [--size 640x480]
                                           [--backends gpu,opencl] [--rounds 4] [--repeat 7]

A change that should not cost speed (a refactoring, a generator that writes the same program
another way) is checked here. REV is checked out into a temporary git worktree; each round
times both trees in fresh processes, alternating which goes first, so a slow spell of this
shared machine falls on both. Each process renders the scene at every precision of each
backend, the whole scene and its primary rays alone (depth shading, no shadows or mirrors),
once untimed (compiling) and then ``--repeat`` times. The table (Markdown, for
docs/performance.md) gives the median over the rounds of each process's median, in ms, and
the ratio new / old. Both trees run with this interpreter and its packages.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# Run in a fresh process with the tree under test first on sys.path: median ms per
# (backend, precision, workload), as one JSON line.
PROBE = """
import dataclasses, json, statistics, sys, time
import marchlab
scene_name, width, height, backends, repeat = sys.argv[1:6]
width, height, repeat = int(width), int(height), int(repeat)
scene = marchlab.load_scene(scene_name)
primary = dataclasses.replace(scene, render=dataclasses.replace(
    scene.render, shading="depth", shadows="none", reflection_depth=0))
out = {}
for backend in backends.split(","):
    for precision in marchlab.BACKENDS[backend].precisions:
        for workload, s in (("full", scene), ("primary", primary)):
            marchlab.render(s, width, height, backend=backend, precision=precision)
            times = []
            for _ in range(repeat):
                start = time.perf_counter()
                marchlab.render(s, width, height, backend=backend, precision=precision)
                times.append(time.perf_counter() - start)
            out[f"{backend}|{precision}|{workload}"] = 1e3 * statistics.median(times)
print(json.dumps(out))
"""


def time_tree(tree: Path, args) -> dict[str, float]:
    """One process's medians for the code in ``tree``."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    run = subprocess.run([sys.executable, "-c", PROBE, args.scene, str(args.width),
                          str(args.height), args.backends, str(args.repeat)],
                         capture_output=True, text=True, env=env, cwd=tree, check=True)
    return json.loads(run.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("revision", help="the earlier revision (commit, tag, branch)")
    parser.add_argument("--scene", default="classroom")
    parser.add_argument("--size", default="640x480")
    parser.add_argument("--backends", default="gpu,opencl")
    parser.add_argument("--rounds", type=int, default=4)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    args.width, args.height = map(int, args.size.split("x"))
    with tempfile.TemporaryDirectory() as scratch:
        old = Path(scratch) / "old"
        subprocess.run(["git", "worktree", "add", "--detach", "-q", str(old), args.revision],
                       cwd=ROOT, check=True)
        try:
            samples: dict[str, dict[str, list[float]]] = {"old": {}, "new": {}}
            for round_ in range(args.rounds):
                order = [("old", old), ("new", ROOT)]
                for name, tree in order if round_ % 2 == 0 else order[::-1]:
                    for key, ms in time_tree(tree, args).items():
                        samples[name].setdefault(key, []).append(ms)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(old)], cwd=ROOT,
                           check=True)
    print(f"`python benchmarks/bench_against.py {' '.join(sys.argv[1:])}`: {args.scene} at "
          f"{args.size}, median of {args.rounds} rounds of {args.repeat} renders (ms)\n")
    print(f"| backend | precision | workload | {args.revision} | this tree | new / old |")
    print("| --- | --- | --- | ---: | ---: | ---: |")
    for key, old_ms in samples["old"].items():
        backend, precision, workload = key.split("|")
        before = statistics.median(old_ms)
        after = statistics.median(samples["new"][key])
        print(f"| {backend} | {precision} | {workload} | {before:.1f} | {after:.1f} | "
              f"{after / before:.2f} |")


if __name__ == "__main__":
    main()
