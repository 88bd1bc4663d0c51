"""Strip the outputs from lesson notebooks, in place, so that they are stored clean.

    python lessons/strip.py                      # every lessons/*.ipynb
    python lessons/strip.py lessons/01_sdf_sphere_tracing.ipynb
    python lessons/strip.py --check              # list the notebooks that are not clean

Stripping removes every code cell's outputs and execution count, the per-cell metadata Jupyter
adds while running (timings, collapsed or scrolled outputs) and the saved widget state. The
cells, their ids and the kernel specification stay. A notebook that is already clean is not
rewritten. With ``--check`` nothing is written and the exit status is 1 if any notebook needs
stripping.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import nbformat

LESSONS = Path(__file__).resolve().parent
RUN_METADATA = ("execution", "collapsed", "scrolled")    # per-cell keys written by a run


def strip(notebook: nbformat.NotebookNode) -> bool:
    """Remove outputs, execution counts and run metadata; True if anything was removed."""
    changed = notebook.metadata.pop("widgets", None) is not None
    for cell in notebook.cells:
        for key in RUN_METADATA:
            changed |= cell.metadata.pop(key, None) is not None
        if cell.cell_type == "code":
            changed |= bool(cell.outputs) or cell.execution_count is not None
            cell.outputs = []
            cell.execution_count = None
    return changed


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("notebooks", nargs="*", type=Path,
                        help="notebooks to strip (default: every lessons/*.ipynb)")
    parser.add_argument("--check", action="store_true",
                        help="only report notebooks that need stripping (exit status 1)")
    args = parser.parse_args(argv)
    dirty = []
    for path in args.notebooks or sorted(LESSONS.glob("*.ipynb")):
        notebook = nbformat.read(path, as_version=4)
        if strip(notebook):
            dirty.append(path)
            if not args.check:
                nbformat.write(notebook, path)
    verb = "needs stripping" if args.check else "stripped"
    for path in dirty:
        print(f"{path}: {verb}")
    return 1 if args.check and dirty else 0


if __name__ == "__main__":
    sys.exit(main())
