"""Every lesson runs from top to bottom without an error, and is stored clean.

Each notebook in lessons/ is found by glob, so a new lesson is tested without editing this file.
It is executed with nbclient in a kernel that runs this very interpreter (a kernel spec written
to a temporary folder), with a time limit per cell; an exception in any cell fails the test and
shows the cell's traceback. Stored notebooks carry no outputs and no execution counts
(`python lessons/strip.py` removes them), and every lesson has at least one exercise
self-check cell calling ``marchlab.check.``.
"""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat", reason="the lessons extra is not installed")
pytest.importorskip("nbclient", reason="the lessons extra is not installed")
pytest.importorskip("ipykernel", reason="the lessons extra is not installed")

LESSONS = Path(__file__).resolve().parents[2] / "lessons"
NOTEBOOKS = sorted(LESSONS.glob("*.ipynb"))
CELL_TIMEOUT = 300          # seconds for any one cell; a whole lesson takes well under a minute
KERNEL = "marchlab-lessons"


def lesson_id(path: Path) -> str:
    return path.stem


@pytest.fixture(scope="module")
def kernel_specs(tmp_path_factory) -> Path:
    """A folder holding one kernel spec: this interpreter running ipykernel."""
    folder = tmp_path_factory.mktemp("kernels")
    (folder / KERNEL).mkdir()
    spec = {"argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"],
            "display_name": "marchlab lessons (this interpreter)", "language": "python"}
    (folder / KERNEL / "kernel.json").write_text(json.dumps(spec))
    return folder


def test_there_are_lessons():
    assert len(NOTEBOOKS) >= 4, f"expected the lessons in {LESSONS}"


def test_the_lessons_readme_has_a_line_for_every_lesson():
    readme = (LESSONS / "README.md").read_text()
    missing = [p.name for p in sorted(LESSONS.glob("*.ipynb")) if f"| `{p.name}` |" not in readme]
    assert not missing, f"lessons/README.md does not list {missing}"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lesson_id)
def test_lesson_runs_top_to_bottom_without_error(path, kernel_specs):
    from jupyter_client.kernelspec import KernelSpecManager
    from jupyter_client.manager import KernelManager
    from nbclient import NotebookClient

    notebook = nbformat.read(path, as_version=4)
    manager = KernelManager(kernel_name=KERNEL,
                            kernel_spec_manager=KernelSpecManager(kernel_dirs=[str(kernel_specs)]))
    client = NotebookClient(notebook, km=manager, timeout=CELL_TIMEOUT,
                            resources={"metadata": {"path": str(LESSONS)}})
    client.execute()        # raises CellExecutionError, with the cell's traceback, on any error
    errors = [output for cell in notebook.cells if cell.cell_type == "code"
              for output in cell.outputs if output.output_type == "error"]
    assert errors == []


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lesson_id)
def test_lesson_is_stored_without_outputs_or_execution_counts(path):
    notebook = nbformat.read(path, as_version=4)
    nbformat.validate(notebook)
    assert notebook.nbformat == 4
    dirty = [index for index, cell in enumerate(notebook.cells) if cell.cell_type == "code"
             and (cell.outputs or cell.execution_count is not None)]
    assert dirty == [], (f"{path.name}: code cells {dirty} have outputs or execution counts; "
                         f"run `python lessons/strip.py {path.relative_to(LESSONS.parent)}`")


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lesson_id)
def test_lesson_has_an_exercise_self_check_cell(path):
    notebook = nbformat.read(path, as_version=4)
    checks = [cell.source for cell in notebook.cells
              if cell.cell_type == "code" and "marchlab.check." in cell.source]
    assert checks, f"{path.name}: no cell calls marchlab.check.<name>(...)"


def load_strip_tool():
    spec = importlib.util.spec_from_file_location("lesson_strip", LESSONS / "strip.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_strip_removes_outputs_counts_and_widget_state_and_keeps_the_cells(tmp_path):
    strip = load_strip_tool()
    notebook = nbformat.v4.new_notebook()
    notebook.metadata["widgets"] = {"application/vnd.jupyter.widget-state+json": {}}
    ran = nbformat.v4.new_code_cell("print(1)", execution_count=3,
                                    outputs=[nbformat.v4.new_output("stream", text="1\n")])
    ran.metadata["execution"] = {"iopub.status.busy": "2024-01-01T00:00:00Z"}
    notebook.cells = [nbformat.v4.new_markdown_cell("# Title"), ran]
    path = tmp_path / "lesson.ipynb"
    nbformat.write(notebook, path)

    assert strip.main(["--check", str(path)]) == 1           # --check only reports
    assert nbformat.read(path, as_version=4).cells[1].outputs
    assert strip.main([str(path)]) == 0
    stripped = nbformat.read(path, as_version=4)
    assert [c.source for c in stripped.cells] == ["# Title", "print(1)"]
    assert stripped.cells[1].outputs == [] and stripped.cells[1].execution_count is None
    assert "execution" not in stripped.cells[1].metadata and "widgets" not in stripped.metadata
    assert strip.main(["--check", str(path)]) == 0


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lesson_id)
def test_lesson_title_is_in_the_one_style_with_its_number(path):
    title = nbformat.read(path, as_version=4).cells[0].source.splitlines()[0]
    number = int(path.name.split("_")[0])
    assert title.startswith(f"# Lesson {number} — "), title


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lesson_id)
def test_lesson_has_a_live_view_to_try(path):
    cells = nbformat.read(path, as_version=4).cells
    assert any(cell.cell_type == "markdown" and "Try it" in cell.source for cell in cells)
    assert any(cell.cell_type == "code" and "from marchlab.widgets import" in cell.source
               for cell in cells)
