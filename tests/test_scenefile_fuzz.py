"""Any TOML document either loads as a scene or is refused with a SceneError: never a crash.

Bundled scenes are mutated at random: a value anywhere in the tree is replaced by a value of
another TOML type (or an out-of-range number), a key is added or deleted. The loader must turn
each case into a Scene or into one SceneError line, because the CLI shows a traceback for
anything else.
"""

import copy
import math
import tomllib

from hypothesis import given, settings
from hypothesis import strategies as st

import marchlab
from scene_model.errors import SceneError
from scene_model.scenefile import scene_from_dict, scene_path

SCENES = {name: tomllib.loads(scene_path(name).read_text())
          for name in marchlab.bundled_scene_names()}

toml_scalars = st.one_of(
    st.integers(-10**6, 10**6), st.floats(allow_nan=True, allow_infinity=True),
    st.booleans(), st.text(max_size=8), st.sampled_from(["sphere", "point", "sky", "union"]))
toml_values = st.recursive(
    toml_scalars,
    lambda inner: st.one_of(st.lists(inner, max_size=4),
                            st.dictionaries(st.text(max_size=6), inner, max_size=3)),
    max_leaves=6)


def locations(tree, path=()):
    """Every (container, key) pair in a parsed TOML tree."""
    items = tree.items() if isinstance(tree, dict) else enumerate(tree)
    for key, value in items:
        yield tree, key
        if isinstance(value, (dict, list)):
            yield from locations(value, path + (key,))


@settings(max_examples=300)
@given(scene=st.sampled_from(sorted(SCENES)), data=st.data())
def test_a_mutated_scene_loads_or_fails_with_a_scene_error(scene, data):
    tree = copy.deepcopy(SCENES[scene])
    places = list(locations(tree))
    for _ in range(data.draw(st.integers(1, 3))):
        container, key = data.draw(st.sampled_from(places))
        action = data.draw(st.sampled_from(["replace", "delete", "add"]))
        if action == "replace" or isinstance(container, list):
            container[key] = data.draw(toml_values)
        elif action == "delete":
            del container[key]
        else:
            container[data.draw(st.text(max_size=8))] = data.draw(toml_values)
        places = list(locations(tree))
        if not places:
            break
    try:
        loaded = scene_from_dict(tree)
    except SceneError as err:
        assert "\n" not in str(err)
    else:
        assert isinstance(loaded, marchlab.Scene)
        for light in loaded.lights:
            assert all(math.isfinite(c) for c in light.color)
