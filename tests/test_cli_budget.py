"""Every long job estimates its work first and is refused beyond its budget (`marchlab.budget`).

The refusal is one line on stderr, exit code 2, no file written and no work started, and it
says how to go ahead anyway (``--allow-large``; ``allow_large=True`` from Python). The
limits are lowered with monkeypatch where a test needs a job just over or under one, so
that nothing large is ever computed here.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from cli_helpers import assert_one_line_error, run_cli

import marchlab
import marchlab.budget as budget
import marchlab.simulation as simulation
from marchlab.budget import BudgetError, count, ray_steps, rays_per_pixel
from scene_model.camera import MAX_PIXELS, check_image_size
from scene_model.scenefile import load_scene

SIZE = "32x24"


def refuse_work(monkeypatch):
    """Make rendering and stepping fail loudly: a refused job must not have started."""
    def started(*args, **kwargs):
        raise AssertionError("the job started before it was refused")
    monkeypatch.setattr("reference_cpu.render.Tracer.trace", started)
    monkeypatch.setattr("physics.World.step", started)


# --- Rendering ----------------------------------------------------------------------------

def test_a_render_over_the_pixel_budget_is_refused_naming_allow_large(tmp_path, capsys,
                                                                      monkeypatch):
    refuse_work(monkeypatch)
    out = tmp_path / "big.png"
    code, _, err = run_cli(capsys, "render", "classroom", "--size", "10000x10000", "-o", out)
    assert_one_line_error(code, err)
    assert f"10000x10000 is 100,000,000 pixels, more than the limit of {MAX_PIXELS:,}" in err
    assert err.rstrip().endswith("add --allow-large to go ahead")
    assert list(tmp_path.iterdir()) == []


def test_a_render_over_the_ray_step_budget_is_refused_naming_allow_large(tmp_path, capsys,
                                                                         monkeypatch):
    """repetition at 640x480 with 100,000 steps: 640 x 480 x 1e5 x 2 rays = 6.14e10 > 5e10."""
    refuse_work(monkeypatch)
    code, _, err = run_cli(capsys, "render", "repetition", "--set", "render.max_steps=100000",
                           "-o", tmp_path / "r.png")
    assert_one_line_error(code, err)
    assert ("rendering 640x480 pixels x 100,000 steps x 2 rays: 6.14e+10 ray steps at worst is "
            "more than the limit of 5.00e+10; add --allow-large to go ahead") in err
    assert list(tmp_path.iterdir()) == []


def test_allow_large_lifts_the_render_budget(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(budget, "MAX_RAY_STEPS", 1000)
    out = tmp_path / "x.png"
    code, _, err = run_cli(capsys, "render", "classroom", "--size", "4x3", "-o", out)
    assert_one_line_error(code, err)
    assert "--allow-large" in err and not out.exists()
    code, stdout, _ = run_cli(capsys, "render", "classroom", "--size", "4x3", "-o", out,
                              "--allow-large")
    assert code == 0 and out.is_file() and str(out) in stdout


def test_render_from_python_has_the_same_budget_lifted_by_a_keyword(monkeypatch):
    scene = load_scene("classroom")
    monkeypatch.setattr(budget, "MAX_RAY_STEPS", 1000)
    with pytest.raises(BudgetError, match="pass allow_large=True to go ahead"):
        marchlab.render(scene, 4, 3)
    frame = marchlab.render(scene, 4, 3, allow_large=True)
    assert frame.color.shape == (3, 4, 3)


def test_check_image_size_refuses_more_than_max_pixels_unless_allowed():
    side = int(MAX_PIXELS ** 0.5) + 1                      # side x side > MAX_PIXELS
    with pytest.raises(marchlab.MarchlabError, match="allow_large=True"):
        check_image_size(side, side)
    check_image_size(side, side, allow_large=True)         # only checks: allocates nothing
    check_image_size(7680, 4320)                           # 8K UHD fits


def test_ray_steps_count_the_primary_ray_its_bounces_and_their_shadow_rays():
    # classroom: one mirror bounce, hard shadows, two lights: (1 + 1) x (1 + 2) rays.
    classroom = load_scene("classroom")
    assert rays_per_pixel(classroom) == 6
    assert ray_steps(classroom, 640, 480) == 640 * 480 * 256 * 6
    no_shadows = load_scene("classroom", ["render.shadows=none"])
    assert rays_per_pixel(no_shadows) == 2
    assert ray_steps(no_shadows, 4, 3, frames=10) == 10 * 4 * 3 * 256 * 2


def test_counts_in_messages_stay_short_even_beyond_a_float():
    assert count(9_999_999) == "9,999,999"
    assert count(61_440_000_000) == "6.14e+10"
    assert count(10 ** 400) == "1.00e+400"


def test_compare_refuses_two_frames_over_the_budget_before_rendering(capsys, monkeypatch):
    refuse_work(monkeypatch)
    monkeypatch.setattr(budget, "MAX_RAY_STEPS", ray_steps(load_scene("classroom"), 32, 24))
    code, _, err = run_cli(capsys, "compare", "classroom", "--a", "numpy", "--b", "numpy",
                           "--size", SIZE)
    assert_one_line_error(code, err)
    assert "x 2 frames" in err and "--allow-large" in err


# --- Simulations and animations ----------------------------------------------------------

@pytest.mark.parametrize("argv, message", [
    (("--fps", "1e9", "--seconds", "0.01"),
     "the animation: 1.00e+07 frames is more than the limit of 10,000; add --allow-large"),
    (("--seconds", "1e9"),
     "the animation: 3.00e+10 frames is more than the limit of 10,000; add --allow-large"),
    (("--seconds", "1e5", "--fps", "0.01"),
     "stepping 6 bodies 2.39e+07 times: 1.43e+08 body steps is more than the limit of "
     "5,000,000; add --allow-large"),
    (("--seconds", "1e308", "--fps", "1e308"),
     "1e+308 s at 1e+308 frames per second is more frames than can be counted"),
], ids=["fps_1e9", "seconds_1e9", "physics_steps", "beyond_a_float"])
def test_a_simulation_over_the_budget_is_refused_before_stepping(tmp_path, capsys, monkeypatch,
                                                                 argv, message):
    refuse_work(monkeypatch)
    code, _, err = run_cli(capsys, "simulate", "bounce", *argv, "--size", SIZE,
                           "-o", tmp_path / "x.gif", "--csv", tmp_path / "x.csv")
    assert_one_line_error(code, err)
    assert message in err, err
    assert list(tmp_path.iterdir()) == []


def test_an_animation_whose_frames_would_not_fit_in_memory_is_refused(tmp_path, capsys,
                                                                      monkeypatch):
    refuse_work(monkeypatch)
    monkeypatch.setattr(budget, "MAX_ANIMATION_BYTES", 4 * 32 * 24 * 8)     # four frames
    code, _, err = run_cli(capsys, "simulate", "bounce", "--seconds", "0.5", "--fps", "10",
                           "--size", SIZE, "-o", tmp_path / "x.gif")
    assert_one_line_error(code, err)
    assert "keeping 5 frames of 32x24 until they are encoded: 30,720 bytes" in err


def test_simulate_scene_from_python_refuses_a_plan_over_the_budget_unless_allowed(monkeypatch):
    scene = load_scene("bounce")
    plan = simulation.frame_plan(scene.physics.dt, fps=10, seconds=0.5)      # 5 frames, 96 steps
    monkeypatch.setattr(budget, "MAX_BODY_STEPS", plan.steps * len(scene.bodies) - 1)
    with pytest.raises(BudgetError, match=r"body steps .* pass allow_large=True"):
        simulation.simulate_scene(scene, plan)
    trajectory = simulation.simulate_scene(scene, plan, allow_large=True)
    assert len(trajectory.times) == plan.frames


# --- Benchmarks ----------------------------------------------------------------------------

def test_bench_accuracy_over_the_budget_is_refused_before_it_starts(tmp_path, capsys,
                                                                   monkeypatch):
    import marchlab.accuracy_report as report
    monkeypatch.setattr(report, "run", lambda *a, **k: pytest.fail("the benchmark started"))
    code, _, err = run_cli(capsys, "bench", "accuracy", "--size", "1280x960", "--repeat", "9",
                           "-o", tmp_path / "r.md")
    assert_one_line_error(code, err)
    assert re.search(r"--size 1280x960 --repeat 9: the benchmark \([\d,]+ configurations x "
                     r"10 renders\): "
                     r"[\d.e+]+ ray steps at worst is more than the limit of 1.00e\+12; "
                     r"add --allow-large to go ahead", err), err
    assert list(tmp_path.iterdir()) == []


# --- The documentation states the limits the code applies ----------------------------------

def test_the_limits_in_the_command_line_reference_are_the_budget():
    text = (Path(__file__).parents[1] / "docs" / "cli.md").read_text()
    assert f"{MAX_PIXELS:,} pixels" in text
    assert f"{budget.MAX_RAY_STEPS:.0e} ray steps".replace("e+", "e") in text
    assert f"{budget.MAX_FRAMES:,} frames" in text
    assert f"{budget.MAX_BODY_STEPS:,} body steps" in text
    assert f"{budget.MAX_BENCH_RAY_STEPS:.0e} ray steps".replace("e+", "e") in text
    assert f"{budget.MAX_ANIMATION_BYTES // 2**30} GiB" in text


# --- The Embree ground truth ----------------------------------------------------------------

def test_an_embree_truth_over_the_meshing_budget_is_refused_before_meshing(tmp_path, capsys,
                                                                           monkeypatch):
    """primitives has 7 parts to mesh besides its floor: 7 x 512^3 = 9.4e8 cells, over a
    limit lowered to 1e8; at 256 a side, 7 x 256^3 = 1.2e8 is still over, 128 is under."""
    monkeypatch.setattr(budget, "MAX_MESH_CELLS", 100_000_000)
    monkeypatch.setattr("reference_cpu.truth.mesh.part_mesh", lambda *a, **k: pytest.fail(
        "meshing started before the job was refused"))
    out = tmp_path / "t.npz"
    code, _, err = run_cli(capsys, "truth", "primitives", "--method", "embree",
                           "--resolution", "512", "-o", out)
    assert_one_line_error(code, err)
    assert ("--resolution 512: meshing 7 parts at 512 cells a side: 9.39e+08 marching-cubes "
            "cells at worst is more than the limit of 1.00e+08; add --allow-large") in err, err
    assert not out.exists()
    with pytest.raises(BudgetError, match=r"7 parts at 256 .* pass allow_large=True"):
        budget.check_truth(load_scene("primitives"), 256)
    budget.check_truth(load_scene("primitives"), 128)


def test_an_embree_truth_reports_progress_part_by_part_and_ends_at_its_total():
    pytest.importorskip("embreex")
    from reference_cpu.truth import ground_truth
    calls = []
    ground_truth(load_scene("csg"), 8, 6, method="embree", resolution=8,
                 progress=lambda done, total: calls.append((done, total)))
    parts = 5                                   # the floor and four shapes
    assert calls == [(k, parts + 1) for k in range(1, parts + 2)]
