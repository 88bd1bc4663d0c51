"""Path labels are bookkeeping for the comparisons: asking for them changes no other buffer.

Every backend computes them only when asked (`marchlab.render(..., path_labels=True)`); the
equivalence suite asks, a student's render and shader do not. A frame without them has
``path`` None.
"""

from __future__ import annotations

import numpy as np
import pytest

from marchlab import load_scene, render

BUFFERS = ("color", "depth", "normal", "steps", "object_id", "hit")
WIDTH, HEIGHT = 48, 36
# A mirror, a checker floor and hard shadows (classroom); spot and soft shadows (lights);
# the steps heat map, whose label counts steps.
SCENES = {"classroom": [], "lights": [], "steps": ["render.shading=steps"]}


def assert_labels_change_nothing_else(plain, labelled):
    assert plain.path is None
    assert labelled.path is not None and labelled.path.dtype == np.uint32
    assert labelled.path.shape == labelled.hit.shape and np.unique(labelled.path).size > 1
    for name in BUFFERS:
        a, b = getattr(plain, name), getattr(labelled, name)
        same_bits = np.array_equal(np.ascontiguousarray(a).view(np.uint8),
                                   np.ascontiguousarray(b).view(np.uint8))
        assert a.dtype == b.dtype and same_bits, name


@pytest.mark.parametrize("precision", ["float64", "float32"])
@pytest.mark.parametrize("name", list(SCENES))
def test_reference_frames_with_and_without_path_labels_agree_to_the_bit(name, precision):
    scene = load_scene(name.replace("steps", "classroom"), SCENES[name])
    assert_labels_change_nothing_else(
        render(scene, WIDTH, HEIGHT, precision=precision),
        render(scene, WIDTH, HEIGHT, precision=precision, path_labels=True))


@pytest.mark.parametrize("name", list(SCENES))
def test_backend_frames_with_and_without_path_labels_agree_to_the_bit(backend, name):
    scene = load_scene(name.replace("steps", "classroom"), SCENES[name])
    assert_labels_change_nothing_else(
        render(scene, WIDTH, HEIGHT, backend=backend),
        render(scene, WIDTH, HEIGHT, backend=backend, path_labels=True))
