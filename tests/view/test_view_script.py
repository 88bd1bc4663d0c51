"""A ``marchlab view --script`` file is read into one action per frame, and a bad one is
refused in one line naming the file, the action and the problem."""

import pytest

from marchlab.view_script import read_script
from scene_model.errors import MarchlabError


def _script(tmp_path, text):
    path = tmp_path / "moves.toml"
    path.write_text(text)
    return path


def test_a_drag_is_spread_over_its_frames_in_equal_steps(tmp_path):
    actions = read_script(_script(tmp_path, """
[[action]]
drag = "left"
from = [100, 100]
to = [140, 80]
frames = 4
"""))
    assert [a.verb for a in actions] == ["drag"] * 4
    assert actions[0].arguments["first"] and actions[-1].arguments["last"]
    steps = [(a.arguments["to"][0] - a.arguments["from"][0],
              a.arguments["to"][1] - a.arguments["from"][1]) for a in actions]
    assert steps == [(10.0, -5.0)] * 4


def test_every_verb_reads(tmp_path):
    actions = read_script(_script(tmp_path, """
[[action]]
scroll = -1.5
[[action]]
keys = "wq"
seconds = 0.25
shift = true
[[action]]
set = "render.epsilon"
value = 0.01
[[action]]
click = [3, 4]
[[action]]
overlay = "steps"
[[action]]
add = "torus"
[[action]]
delete = true
[[action]]
undo = true
[[action]]
redo = true
[[action]]
physics = "kick"
[[action]]
wait = 3
[[action]]
screenshot = "a.png"
[[action]]
save = "b.toml"
[[action]]
turntable = "spin.gif"
frames = 12
"""))
    verbs = [a.verb for a in actions]
    assert verbs == ["scroll", "keys", "set", "click", "overlay", "add", "delete", "undo",
                     "redo", "physics", "wait", "wait", "wait", "screenshot", "save",
                     "turntable"]
    assert actions[1].arguments == {"keys": "WQ", "seconds": 0.25, "fast": True}
    assert actions[-1].arguments == {"path": "spin.gif", "frames": 12}


@pytest.mark.parametrize("text, problem", [
    ('[[action]]\njump = 1', "names 0 verbs: an action names exactly one of"),
    ('[[action]]\nscroll = 1\nwait = 2', "names 2 verbs (scroll, wait)"),
    ('[[action]]\ndrag = "left"\nfrom = [1, 2]', "drag: to: expected [x, y]"),
    ('[[action]]\ndrag = "thumb"\nfrom = [1, 2]\nto = [3, 4]', "button 'thumb'"),
    ('[[action]]\ndrag = "left"\nfrom = [1, 2]\nto = [3, 4]\nspeed = 2', "unknown key 'speed'"),
    ('[[action]]\ndrag = "left"\nfrom = [1, 2]\nto = [3, 4]\nshift = 1', "shift: write true"),
    ('[[action]]\nkeys = "WX"', "is not a string of WSDAEQ"),
    ('[[action]]\nkeys = "W"\nseconds = -1', "seconds must be in (0, 60]"),
    ('[[action]]\nset = "render.epsilon"', "needs a field path"),
    ('[[action]]\noverlay = "xray"', "'xray' is not one of color"),
    ('[[action]]\nadd = "teapot"', "'teapot' is not a kind of node"),
    ('[[action]]\nwait = 1.5', "wait: expected a whole number"),
    ('[[action]]\nscreenshot = "a.jpg"', "a screenshot is a .png"),
    ('[[action]]\nsave = "a.json"', "must end in .toml"),
    ('[[action]]\ndelete = 1', "write delete = true"),
    ('[[action]]\nturntable = "spin.avi"', "a recording is an .mp4 or a .gif"),
    ('[[action]]\nturntable = "spin.gif"\nframes = 1', "frames: expected a whole number from 2"),
    ('[scene]\nx = 1', "unknown table 'scene'"),
    ('[[action]\n', "not a TOML script"),
])
def test_a_bad_script_is_refused_in_one_line_naming_file_and_action(tmp_path, text, problem):
    path = _script(tmp_path, text)
    with pytest.raises(MarchlabError) as caught:
        read_script(path)
    message = str(caught.value)
    assert message.startswith(str(path)) and problem in message
    assert "\n" not in message
    if "[[action]]\n" in text and "unknown table" not in problem and "TOML" not in problem:
        assert ": action 1: " in message


def test_a_missing_script_is_one_line(tmp_path):
    with pytest.raises(MarchlabError, match="cannot read the script: No such file"):
        read_script(tmp_path / "absent.toml")
