"""The teacher's version (lessons/solutions.py): a solution for every exercise, each passing
its self-check, and notebooks written with the exercises solved whose cells define them."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat", reason="the lessons extra is not installed")

LESSONS = Path(__file__).resolve().parents[2] / "lessons"
spec = importlib.util.spec_from_file_location("solutions", LESSONS / "solutions.py")
solutions = importlib.util.module_from_spec(spec)
spec.loader.exec_module(solutions)


def exercises() -> dict[str, str]:
    """Every exercise template in the lessons: function name -> lesson file."""
    found = {}
    for path in sorted(LESSONS.glob("*.ipynb")):
        for cell in nbformat.read(path, as_version=4).cells:
            if cell.cell_type == "code" and "NotImplementedError" in cell.source:
                for name in re.findall(r"^def (\w+)\(", cell.source, re.M):
                    found[name] = path.name
    return found


def test_every_exercise_has_a_solution_and_every_solution_an_exercise():
    assert set(exercises()) == set(solutions.SOLUTIONS)
    assert len(solutions.SOLUTIONS) >= 14


@pytest.mark.parametrize("name", sorted(solutions.SOLUTIONS))
def test_each_solution_passes_its_self_check(name):
    import marchlab.check
    result = getattr(marchlab.check, name)(solutions.SOLUTIONS[name])
    assert result.passed, str(result)


def test_solved_notebooks_define_each_solution_in_place_of_its_template(tmp_path):
    import marchlab.check
    written = solutions.solved_notebooks(tmp_path)
    assert [p.name for p in written] == sorted(p.name for p in LESSONS.glob("*.ipynb"))
    solved = {}
    for path in written:
        for cell in nbformat.read(path, as_version=4).cells:
            if cell.cell_type != "code" or not re.search(r"^def \w+\(", cell.source, re.M):
                continue
            assert "NotImplementedError" not in cell.source
            # Only the cell's function definitions (the rest draws or checks), in a namespace
            # that has just what a lesson's first cell imports for them.
            blocks = [block for block in re.findall(r"^def .*?(?=^\S|\Z)", cell.source,
                                                    re.M | re.S)
                      if block[4:].split("(")[0] in solutions.SOLUTIONS]
            namespace = {}
            exec("import math\nimport numpy as np\n" + "".join(blocks), namespace)
            solved.update({name: namespace[name] for name in solutions.SOLUTIONS
                           if name in namespace})
    assert set(solved) == set(solutions.SOLUTIONS)
    for name, function in solved.items():
        assert getattr(marchlab.check, name)(function).passed, name


@pytest.mark.parametrize("name, lesson", sorted(exercises().items()))
def test_no_cell_shows_an_exercises_answer_before_the_exercise(name, lesson):
    cells = nbformat.read(LESSONS / lesson, as_version=4).cells
    exercise = next(i for i, cell in enumerate(cells) if cell.cell_type == "code"
                    and re.search(rf"^def {name}\(", cell.source, re.M))
    for cell in cells[:exercise]:
        if cell.cell_type == "code" and "show_source(" in cell.source:
            shown = re.findall(r"show_source\(([^)]*)\)", cell.source, re.S)
            assert not any(re.search(rf"\b{name}\b", text) for text in shown), (name, shown)
