"""The speed-against-error report (`marchlab.accuracy`, ``marchlab bench accuracy``)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from cli_helpers import run_cli

from marchlab import accuracy as A, accuracy_report as R, accuracy_truth as T


def row(setting, ms, surface, off_band=0, normal=0.1, backend="numpy", precision="float64",
        scene="s"):
    zeros = {f.name: 0.0 for f in dataclasses.fields(A.Row)
             if f.type in ("float", float)}
    zeros.update(misclassified=0, off_band=off_band, notes=[])
    zeros.update(scene=scene, backend=backend, precision=precision, setting=setting, ms=ms,
                 surface_p99=surface, normal_p99_deg=normal)
    return A.Row(**zeros)


def test_pareto_keeps_exactly_the_rows_nothing_beats_on_both_time_and_error():
    rows = [row("a", 10, 1e-3), row("b", 20, 1e-4), row("c", 30, 1e-3), row("d", 5, 1e-2),
            row("e", 20, 1e-3)]
    assert [r.setting for r in A.pareto(rows)] == ["d", "a", "b"]


def test_recommend_picks_the_fastest_setting_within_tolerance_on_every_scene():
    rows = [row("fast but wrong", 1, 5e-3, scene="x"), row("fast but wrong", 1, 1e-4, scene="y"),
            row("good", 4, 9e-4, scene="x"), row("good", 4, 9e-4, scene="y"),
            row("slow", 9, 1e-5, scene="x"), row("slow", 9, 1e-5, scene="y")]
    assert A.recommend(rows)[("numpy", "float64")] == "good"
    # a misclassified pixel off the silhouette band disqualifies a setting too
    rows[2] = row("good", 4, 9e-4, off_band=1, scene="x")
    assert A.recommend(rows)[("numpy", "float64")] == "slow"


def test_a_normal_error_the_truth_cannot_resolve_does_not_rule_a_setting_out():
    rows = [row("good", 4, 9e-4, normal=0.8), row("slow", 9, 1e-5, normal=0.1)]
    assert A.recommend(rows)[("numpy", "float64")] == "slow"      # 0.8° > 0.5°
    rows[0].within_truth = ("normal_p99_deg",)                      # ... but within the truth's
    assert A.recommend(rows)[("numpy", "float64")] == "good"


def test_measured_errors_of_the_reference_stay_within_its_contract():
    """NumPy float64 at epsilon 1e-3 against the exact truth: every hit point is within
    epsilon of the surface (the march stops where |sdf| < epsilon, and these SDFs are exact),
    and relaxed marching keeps that while taking at least 25% fewer steps; the cone pre-pass
    with relaxed marching keeps it too while taking at least 40% fewer (its own evaluations
    counted: 47% measured at this size)."""
    scenes = A.analytic_scenes()
    grid = {k: v for k, v in A.settings_grid().items()
            if k in ("plain, eps 0.001", "auto, eps 0.001", "cone + auto, eps 0.001")}
    rows = A.sweep(scenes, size=(48, 36), repeat=1, grid=grid, pairs=[("numpy", "float64")])
    assert len(rows) == 6
    for r in rows:
        assert r.surface_max < 1e-3, r
        assert r.color_max <= 1 and not r.notes
    saved = A.steps_saved(rows, "auto, eps 0.001", "plain, eps 0.001")
    assert min(saved.values()) >= 0.25, saved
    saved = A.steps_saved(rows, "cone + auto, eps 0.001", "plain, eps 0.001")
    assert min(saved.values()) >= 0.40, saved


def test_the_markdown_table_escapes_the_pipes_of_its_titles():
    text = R.table([row("plain", 1.5, 1e-3)])
    header, rule, line = text.splitlines()
    assert header.count(" | ") == rule.count(" | ") == line.count(" | ")


# --- Scenes only the Embree truth can trace ----------------------------------------------------

needs_embree = pytest.mark.skipif(A.embree_problem() is not None,
                                  reason=str(A.embree_problem()))

# A hit point rendered in float32 lies a few float32 units in the last place from where the
# float64 SDF would put it; at |p| < 16 that is under 16 * 8 * 2^-23 ~ 1.5e-5.
FLOAT32_SLACK = 1.5e-5


def test_within_truth_marks_a_statistic_only_where_the_truths_own_error_covers_its_pixels():
    own = np.full(1000, 1.0)
    error = np.full(1000, 0.5)
    error[:5] = 2.0                  # 0.5% of the pixels beyond the truth's own error
    marked = T.within_truth({"depth": error, "normal": error}, {"depth": own, "normal": own})
    assert set(marked) == {"depth_p99", "normal_p99_deg"}
    error[:20] = 2.0                 # 2%: the p99 is the renderer's now
    assert T.within_truth({"depth": error, "normal": error},
                          {"depth": own, "normal": own}) == ()
    # everything within: every statistic; a truth without error of its own: none
    small = np.full(1000, 0.5)
    assert set(T.within_truth({"depth": small, "normal": small},
                              {"depth": own, "normal": own})) == {
        "depth_mean", "depth_p99", "depth_max", "normal_p99_deg", "normal_max_deg"}
    zero = np.zeros(1000)
    assert T.within_truth({"depth": zero, "normal": zero}, {"depth": zero, "normal": zero}) == ()


def test_written_out_repeats_have_the_repeats_surface():
    # The repetition scene: a limited 5x5 grid of capsules and an infinite row of spheres.
    # Written out as copies, the union has the same sign everywhere (each copy lies inside
    # its cell) and, near the surface, the same distance to 1e-12.
    from reference_cpu.scene_sdf import build_scene_sdf
    scene = A.sweep_scenes()["repetition"]
    written = T.truth_scene(scene)
    rng = np.random.default_rng(6)
    points = rng.uniform((-60, -0.5, -6), (60, 2.0, 4), size=(200_000, 3))
    near = rng.uniform((-60, 0.0, -4.5), (60, 1.0, -3.5), size=(100_000, 3))  # the row
    points = np.concatenate([points, near])
    repeated = build_scene_sdf(scene.objects, np.float64)(points)[0]
    copies = build_scene_sdf(written.objects, np.float64)(points)[0]
    np.testing.assert_array_equal(np.sign(copies), np.sign(repeated))
    close = np.abs(repeated) < 0.1
    assert close.sum() > 1000
    np.testing.assert_allclose(copies[close], repeated[close], rtol=0, atol=1e-12)


def test_a_repeated_shape_reaching_out_of_its_cell_is_refused_in_one_line():
    from scene_model.builder import Scene, sphere
    from scene_model.errors import MarchlabError
    scene = Scene(objects=(sphere(0.8).repeat((1.0, 0.0, 0.0), (2, 0, 0)),))
    with pytest.raises(MarchlabError, match="reaches out of its cell") as err:
        T.truth_scene(scene)
    assert "\n" not in str(err.value)


@needs_embree
@pytest.mark.parametrize("name", ["classroom", "boxes"])
def test_embree_truths_own_depth_error_is_its_actual_error_within_1_percent(name):
    # Traced by Embree (icospheres, exact boxes and floor), an analytic scene shows how far
    # the Embree truth really is off. Its own depth error, one Newton step along the ray from
    # its hit to the SDF's zero, is exact on planes and first order on spheres: never short
    # of the actual error (1e-6 relative), and over it by the second-order term, a fraction
    # of gap / radius (the icospheres' gap is under 1% of their radius here). Its own normal
    # error is the actual one, which stays far under the facets' tilt.
    scene = A.analytic_scenes()[name]
    embree = T.scene_truth(scene, 64, 48, resolution=32, method="embree")
    exact = T.scene_truth(scene, 64, 48)
    core = (embree.truth.hit & exact.truth.hit
            & ~A.dilate(A.boundary(exact.truth.object_id.astype(np.int64)), 1))
    actual = np.abs(embree.truth.depth[core] - exact.truth.depth[core])
    own = embree.depth_error[core]
    assert actual.max() > 1e-3                      # the truth is really off, measurably
    assert np.all(actual <= own * (1 + 1e-6) + 1e-12)
    assert np.all(own <= actual * (1 + 1e-2) + 1e-12)
    normal = T.angle_deg(embree.normal[core], exact.normal[core])
    assert np.all(normal <= embree.normal_error_deg[core] + 1e-6)
    assert np.percentile(normal, 99) < 0.2
    if name == "classroom":                          # its spheres fill many pixels
        assert np.percentile(embree.facet_error_deg[core], 99) > 1.0


@needs_embree
def test_a_render_finer_than_its_truth_has_its_errors_marked():
    # A sphere filling the view, rendered at epsilon 1e-6, against a coarse icosphere (gap
    # about 0.02): every hit lies within the truth's own depth error of the truth's hit, so
    # the truth cannot tell its error from 0 and marks it; the exact truth marks nothing,
    # and finds the render over 100 times closer than the coarse truth's own p99 error.
    from scene_model.builder import Camera, RenderSettings, Scene, sphere
    scene = Scene(camera=Camera(position=(0, 0, 3), look_at=(0, 0, 0), fov=40),
                  render=RenderSettings(epsilon=1e-6, max_steps=1000), objects=(sphere(1.0),))
    size = (32, 24)
    gold = A.gold_render(scene, *size)
    coarse = T.scene_truth(scene, *size, resolution=4, method="embree")
    exact = T.scene_truth(scene, *size)
    assert coarse.truth.error_terms["tessellation"] > 1e-2
    row, _ = A.measure("sphere", scene, coarse, gold, "numpy", "float64", "plain", {}, size, 1)
    assert {"depth_mean", "depth_p99", "depth_max", "normal_p99_deg"} <= set(row.within_truth)
    assert row.off_band == 0
    row, _ = A.measure("sphere", scene, exact, gold, "numpy", "float64", "plain", {}, size, 1)
    assert row.within_truth == ()
    assert row.depth_p99 < coarse.errors()["depth_p99"] / 100


@needs_embree
def test_pixels_the_truths_silhouette_may_have_moved_are_excused_and_marked():
    # The same sphere against a coarser icosphere (gap 0.066): its silhouette lies up to
    # about 3 pixels inside the sphere's at 128x96, so some pixels the render hits lie
    # beyond the 1-pixel band; the band widened by the stated bound in pixels takes them
    # in, and the count is marked as excused only by that widening.
    from scene_model.builder import Camera, RenderSettings, Scene, sphere
    scene = Scene(camera=Camera(position=(0, 0, 3), look_at=(0, 0, 0), fov=40),
                  render=RenderSettings(epsilon=1e-6, max_steps=1000), objects=(sphere(1.0),))
    size = (128, 96)
    coarse = T.scene_truth(scene, *size, resolution=2, method="embree")
    row, hit = A.measure("sphere", scene, coarse, A.gold_render(scene, *size), "numpy",
                         "float64", "plain", {}, size, 1)
    one_pixel_band = A.dilate(A.boundary(coarse.truth.hit.astype(np.int64)), 1)
    assert ((hit != coarse.truth.hit) & ~one_pixel_band).sum() > 0
    assert coarse.band_px >= 3
    assert row.off_band == 0 and "off_band" in row.within_truth


@needs_embree
def test_embree_scenes_keep_hits_within_epsilon_and_the_report_names_their_truths_error(
        tmp_path):
    """csg (marching cubes) and lights (icosphere, marching cubes, exact floor) at 48x36
    against a 16-cell Embree truth: plain and auto sphere tracing at epsilon 1e-3 keep every
    hit point within epsilon of the surface (the SDF needs no truth), misclassify no pixel off
    the silhouette band widened by the truth's bound, and auto saves at least 25% of the
    steps without changing the hit mask. The report puts the truth's own error next to every
    row and only writes the plots it shows."""
    scenes = {k: v for k, v in A.sweep_scenes().items() if k in ("csg", "lights")}
    grid = {k: v for k, v in A.settings_grid().items()
            if k in ("plain, eps 0.001", "auto, eps 0.001")}
    truths = {}
    rows = A.sweep(scenes, size=(48, 36), repeat=1, grid=grid,
                   pairs=[("numpy", "float64"), ("numpy", "float32")], truths=truths,
                   resolution=16)
    assert len(rows) == 8 and set(truths) == {"csg", "lights"}
    for r in rows:
        assert r.truth == "embree 16"
        slack = FLOAT32_SLACK if r.precision == "float32" else 0.0
        assert r.surface_max <= 1e-3 + slack, r
        assert r.off_band == 0, r
        if r.setting.startswith("auto"):
            assert r.hit_changed == 0, r
    saved = A.steps_saved(rows, "auto, eps 0.001", "plain, eps 0.001")
    assert min(saved.values()) >= 0.25, saved
    for ref in truths.values():
        assert ref.band_px >= 1                     # a 16-cell grid is off by pixels

    report = tmp_path / "report.md"
    written = R.write_report(rows, report, tmp_path / "images", "cmd", (48, 36), 1,
                             truths=truths)
    text = report.read_text()
    for name, ref in truths.items():
        bound = R.format_number(ref.truth.error_bound)
        assert f"| {name} | embree | 16 | {bound} = " in text
        own = ref.errors()
        cell = (f"embree 16 ({R.format_number(own['depth_p99'])}, "
                f"{R.format_number(own['normal_p99_deg'])}°)")
        lines = [line for line in text.splitlines() if line.startswith(f"| {name} | numpy |")]
        assert lines and all(cell in line for line in lines)
    images = sorted(p.name for p in (tmp_path / "images").iterdir())
    assert images == ["speed-vs-error-csg.png"] == sorted(
        p.name for p in written if p.suffix == ".png")
    assert "images/speed-vs-error-csg.png" in text and "speed-vs-error-lights" not in text


def test_bench_accuracy_says_which_scenes_it_left_out_without_embree(tmp_path, capsys,
                                                                       monkeypatch):
    monkeypatch.setattr(R, "embree_problem", lambda: "the Embree truth needs embreex")
    report = tmp_path / "report.md"
    code, _, err = run_cli(capsys, "bench", "accuracy", "--quick", "--size", "16x12",
                           "--repeat", "1", "-o", report)
    assert code == 0, err
    assert "left out csg: the Embree truth needs embreex" in err
    text = report.read_text()
    assert "Left out: `csg` (the Embree truth needs embreex)" in text
    assert "| csg |" not in text


def test_bench_accuracy_quick_writes_the_report_and_its_plot(tmp_path, capsys):
    report = tmp_path / "out" / "report.md"
    code, _, err = run_cli(capsys, "bench", "accuracy", "--quick", "--size", "32x24",
                           "--repeat", "1", "-o", report)
    assert code == 0, err
    text = report.read_text()
    assert "## Recommended settings" in text and "classroom" in text
    plot = tmp_path / "out" / "images" / "speed-vs-error-classroom.png"
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    if A.embree_problem() is None:      # the quick run takes one scene of each truth
        assert "## The truth of each scene" in text and "`csg` (embree 32)" in text
        assert (tmp_path / "out" / "images" / "speed-vs-error-csg.png").is_file()


@pytest.mark.parametrize("args, message", [
    (["-o", "report.txt"], "report.txt: the report is Markdown"),
    (["--repeat", "0"], "expected a positive integer"),
])
def test_bench_accuracy_refuses_bad_options_in_one_line(tmp_path, monkeypatch, capsys, args,
                                                        message):
    monkeypatch.chdir(tmp_path)
    code, _, err = run_cli(capsys, "bench", "accuracy", "--quick", *args)
    assert code == 2
    assert message in err and len(err.strip().splitlines()) == 1
    assert not list(tmp_path.iterdir())
