"""Hypothesis strategies for hostile input: every bundled scene with one field mutated, and
every option of every subcommand given a value nobody should type. Each draws a
`fuzz_runner.Case`; tests/test_fuzz_inputs.py and benchmarks/fuzz_inputs.py run them.

Scene files are mutated in the tree `marchlab show` prints (every field, defaults included)
and written back as TOML by a small emitter of our own, so that a value can be spelt as a user
might spell it (``-0``, ``+inf``, ``1e400``, an integer of 400 digits), a key can be written
twice, and nesting can go deeper than any TOML library would write. Options are found in
`marchlab.cli.build_parser`, so an option added later is fuzzed without a change here.
"""

from __future__ import annotations

import argparse
import copy
import functools
import json
import re
import tomllib

from hypothesis import strategies as st

from fuzz_runner import Case
from marchlab.cli import build_parser
from marchlab.render import backend_problem
from scene_model.errors import format_path
from scene_model.scenefile import POLYMORPHIC, bundled_scene_names, load_scene, scene_to_toml

# --- Values, as TOML text -------------------------------------------------------------------

EXTREME_NUMBERS = ("0", "-0", "0.0", "-0.0", "+0.0", "5e-324", "1e-300", "1e-12", "-1",
                   "-1e-300", "1e12", "1e100", "3.5e38", "1e308", "-1e308",
                   "1.7976931348623157e308")
NON_FINITE = ("nan", "+nan", "-nan", "inf", "+inf", "-inf", "1e400", "-1e400")
HUGE_INTEGERS = ("2147483648", "-2147483649", "4294967296", "9223372036854775807",
                 "9223372036854775808", "-9223372036854775809", "1" + "0" * 30,
                 "0x7fffffffffffffff", "1" + "0" * 400)
STRINGS = ('"50"', '"1e308"', '"nan"', '""', '"sphere"', "'literal'", '"two\\nlines"',
           '"\\u0000"', '"ünïcödé ✓"', '"' + "x" * 100_000 + '"', '"""multi\nline"""')
WRONG_TYPES = ("true", "false", "1979-05-27T07:32:00Z", "1979-05-27", "07:32:00", "{}", "[]",
               '{ type = "sphere", radius = 1.0 }', "[[1.0, 2.0], [3.0, 4.0]]", '["a", 1]',
               "[true, false, true]", "[1, 2, 3]", "[0.5, 0.5]", "[0.5, 0.5, 0.5, 0.5]")
DEPTHS = (63, 64, 65, 200, 1000, 10_000)
# The header form grows as depth squared: 500 levels are 2.3 MB, which tomllib alone reads in
# about a second (1,000 levels, 9 MB, take it 6 s: a time limit, not a scene).
HEADER_DEPTHS = (63, 64, 65, 200, 500)


def deep_value(depth: int, table: bool) -> str:
    """An array (or inline table) nested ``depth`` levels around one number."""
    return ("{a = " * depth + "1" + "}" * depth) if table else ("[" * depth + "0.5" + "]" * depth)


def sphere_fields(material: str | None) -> list[str]:
    return ['type = "sphere"', "radius = 0.1"] + ([f"material = {json.dumps(material)}"]
                                                  if material else [])


def deep_union_inline(depth: int, material: str | None = None) -> str:
    """A union of a sphere (of ``material``) and a union of ..., ``depth`` levels, as one
    inline table."""
    sphere = "{" + ", ".join(sphere_fields(material)) + "}"
    return ('{type = "union", children = [' + sphere + ", ") * depth + sphere + "]}" * depth


def deep_union_headers(depth: int, material: str | None = None) -> str:
    """The same union written with ``[[objects.children...]]`` headers, one per level."""
    lines, table = ["[[objects]]", 'type = "union"'], "objects"
    for _ in range(depth):
        table += ".children"
        lines += [f"[[{table}]]", *sphere_fields(material), f"[[{table}]]", 'type = "union"']
    lines += [f"[[{table}.children]]", *sphere_fields(material)]
    return "\n".join(lines) + "\n"


# --- A TOML emitter that writes what it is given --------------------------------------------

class Raw(str):
    """TOML text written as it is (a spelling no emitter would choose)."""


class Twice:
    """A key written a second time in its table: a duplicated key."""

    def __init__(self, name: str):
        self.name = name


def toml_key(key) -> str:
    name = key.name if isinstance(key, Twice) else key
    if re.fullmatch(r"[A-Za-z0-9_-]+", name):
        return name
    return json.dumps(name, ensure_ascii=False).replace("\x7f", "\\u007f")


def toml_value(value) -> str:
    if isinstance(value, Raw):
        return str(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)          # 1e+16, -0.0, inf and nan are TOML spellings too
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False).replace("\x7f", "\\u007f")
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{toml_key(k)} = {toml_value(v)}" for k, v in value.items()) + "}"
    return value.isoformat()        # dates and times


def toml_document(tree: dict, tail: str = "") -> str:
    """``tree`` as TOML, each top-level key on a line of its own (tables inline), then
    ``tail`` (text with headers of its own, which must come last)."""
    return "".join(f"{toml_key(k)} = {toml_value(v)}\n" for k, v in tree.items()) + tail


# --- Where to mutate ----------------------------------------------------------------------

@functools.cache
def scene_tree(name: str) -> dict:
    """The bundled scene ``name`` as `marchlab show` prints it: every field, defaults too."""
    return tomllib.loads(scene_to_toml(load_scene(name)))


def paths(tree, prefix=()):
    """Every path in a parsed TOML tree, parents before children."""
    items = tree.items() if isinstance(tree, dict) else enumerate(tree)
    for key, value in items:
        yield prefix + (key,)
        if isinstance(value, (dict, list)):
            yield from paths(value, prefix + (key,))


def get(tree, path):
    for step in path:
        tree = tree[step]
    return tree


def is_number_list(value) -> bool:
    return isinstance(value, list) and bool(value) and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)


def fields(tree) -> list[tuple]:
    """Paths of every field (a key of a table) and of every number in an array of numbers."""
    return [p for p in paths(tree) if isinstance(p[-1], str)
            or is_number_list(get(tree, p[:-1]))]


def tables(tree) -> list[tuple]:
    return [()] + [p for p in paths(tree) if isinstance(get(tree, p), dict)]


def keys(tree) -> set[str]:
    return {p[-1] for p in paths(tree) if isinstance(p[-1], str)}


def kinds() -> list[str]:
    """Every ``type`` a scene file may name (shapes, lights, backgrounds)."""
    return sorted({kind for find in POLYMORPHIC.values() for kind in find()})


# --- Scene-file mutations: each returns (TOML text, the mutation in words) ----------------

def replace_with(pool):
    """Set one field (or every number of a vector) to a value from ``pool``."""
    def mutate(draw, tree):
        path = draw(st.sampled_from(fields(tree)))
        value = Raw(draw(st.sampled_from(pool)))
        parent, target = get(tree, path[:-1]), get(tree, path)
        if is_number_list(target) and draw(st.booleans()):
            parent[path[-1]] = [value] * len(target)
            return toml_document(tree), f"{format_path(path)} = [{value}, ...]"
        parent[path[-1]] = value
        return toml_document(tree), f"{format_path(path)} = {value[:40]}"
    return mutate


def empty_list(draw, tree):
    path = draw(st.sampled_from(fields(tree)))
    get(tree, path[:-1])[path[-1]] = []
    return toml_document(tree), f"{format_path(path)} = []"


def long_list(draw, tree):
    """An array made long: a table repeated 32 times, a number up to 100,000 times."""
    path = draw(st.sampled_from(fields(tree)))
    target = get(tree, path)
    items = target if isinstance(target, list) and target else [target]
    count = draw(st.sampled_from((32,) if isinstance(items[0], dict) else (4, 1000, 100_000)))
    get(tree, path[:-1])[path[-1]] = (items * count)[:max(count, len(items))]
    return toml_document(tree), f"{format_path(path)} = [{count} items]"


def missing_key(draw, tree):
    path = draw(st.sampled_from(list(paths(tree))))
    del get(tree, path[:-1])[path[-1]]
    return toml_document(tree), f"{format_path(path)} deleted"


def unknown_key(draw, tree):
    path = draw(st.sampled_from(tables(tree)))
    table = get(tree, path)
    near = [k + "s" for k in table] + [k.upper() for k in table] + [k.replace("_", "-")
                                                                    for k in table]
    key = draw(st.one_of(st.sampled_from(near + ["", "__class__", "type ", "ünï"]),
                         st.text(max_size=12)))
    if key in table:
        key += "_"
    table[key] = draw(st.sampled_from((1.0, "x", True, [1.0])))
    return toml_document(tree), f"{format_path(path + (key,))} added"


def duplicated_key(draw, tree):
    path = draw(st.sampled_from([p for p in tables(tree) if get(tree, p)]))
    table = get(tree, path)
    key = draw(st.sampled_from(sorted(table)))
    table[Twice(key)] = Raw(draw(st.sampled_from(("1.0", "0.5", '"x"', "[1.0, 2.0, 3.0]"))))
    return toml_document(tree), f"{format_path(path + (key,))} written twice"


def deep_nesting(draw, tree):
    path = draw(st.sampled_from(fields(tree)))
    depth, table = draw(st.sampled_from(DEPTHS)), draw(st.booleans())
    get(tree, path[:-1])[path[-1]] = Raw(deep_value(depth, table))
    return toml_document(tree), (f"{format_path(path)} = {depth} nested "
                                 f"{'tables' if table else 'arrays'}")


def deep_csg(draw, tree):
    """An object that is a union nested hundreds of levels deep, inline or with headers."""
    objects = tree.setdefault("objects", [])
    material = next(iter(tree.get("materials", {})), None)
    if draw(st.booleans()):
        depth = draw(st.sampled_from(DEPTHS))
        objects.append(Raw(deep_union_inline(depth, material)))
        return toml_document(tree), f"objects[{len(objects) - 1}] = union {depth} deep (inline)"
    depth = draw(st.sampled_from(HEADER_DEPTHS))
    del tree["objects"]
    tail = "".join(f"[[objects]]\n{toml_document(o)}" for o in objects)
    return (toml_document(tree, tail + deep_union_headers(depth, material)),
            f"objects[{len(objects)}] = union {depth} deep ([[objects.children]] headers)")


def wrong_object_type(draw, tree):
    typed = [p for p in tables(tree) if "type" in get(tree, p)]
    path = draw(st.sampled_from(typed))
    table = get(tree, path)
    kind = draw(st.sampled_from([k for k in kinds() if k != table["type"]]
                                + ["", "Sphere", "sphere ", "none"]))
    table["type"] = kind
    return toml_document(tree), f"{format_path(path + ('type',))} = {kind!r}"


SCENE_MUTATIONS = {
    "extreme number": replace_with(EXTREME_NUMBERS),
    "NaN or inf": replace_with(NON_FINITE),
    "huge integer": replace_with(HUGE_INTEGERS),
    "string": replace_with(STRINGS),
    "wrong type": replace_with(WRONG_TYPES),
    "empty list": empty_list,
    "long list": long_list,
    "missing key": missing_key,
    "unknown key": unknown_key,
    "duplicated key": duplicated_key,
    "deep nesting": deep_nesting,
    "deep CSG": deep_csg,
    "wrong object type": wrong_object_type,
}


@functools.cache
def available_backends() -> tuple[str, ...]:
    """The accelerated backends that run here (a refusal for a missing one names no field)."""
    return tuple(b for b in ("gpu", "opencl") if backend_problem(b) is None)


def file_commands(has_bodies: bool) -> list[tuple[str, ...]]:
    """The commands a mutated ``scene.toml`` is given to, each small and quick."""
    render = ("render", "scene.toml", "-o", "out.npz", "--size", "8x6")
    commands = [render, render, render[:3] + ("out.png", "--size", "8x6", "--aov", "depth"),
                render + ("--precision", "float32"),
                ("show", "scene.toml"), ("shader", "scene.toml"),
                ("shader", "scene.toml", "--dialect", "opencl-packets", "--precision", "float64"),
                ("truth", "scene.toml", "-o", "truth.npz", "--size", "8x6")]
    commands += [render + ("--backend", backend) for backend in available_backends()]
    if available_backends():
        commands.append(("compare", "scene.toml", "--a", "numpy", "--b", available_backends()[0],
                         "--size", "16x12"))
    if has_bodies:
        commands.append(("simulate", "scene.toml", "-o", "out.gif", "--csv", "out.csv",
                         "--seconds", "0.05", "--fps", "20", "--size", "8x6",
                         "--backend", "numpy"))
    return commands


@st.composite
def scene_cases(draw, kind: str, scenes=None, time_limit: float = 10.0) -> Case:
    """A bundled scene (one of ``scenes``, default all) with one mutation of ``kind``, given
    to one of `file_commands`."""
    name = draw(st.sampled_from(sorted(scenes or bundled_scene_names())))
    tree = copy.deepcopy(scene_tree(name))
    text, what = SCENE_MUTATIONS[kind](draw, tree)
    argv = draw(st.sampled_from(file_commands("bodies" in scene_tree(name))))
    # A refusal names the field: some key of the scene (as an error message quotes it), or
    # the line of a TOML syntax error.
    names = {format_path((key,)) for key in keys(scene_tree(name)) | keys(tree)}
    names = tuple(sorted(names | {"line", "[[bodies]]"}))
    return Case(kind, argv, f"{name}: {what}", names, "scene.toml", text,
                time_limit=time_limit)


# --- Command-line mutations ---------------------------------------------------------------

# A valid, small and quick command line per subcommand, which one mutation then spoils.
BASE = {
    "render": ("render", "classroom", "-o", "out.npz", "--size", "8x6"),
    "show": ("show", "classroom"),
    "shader": ("shader", "classroom"),
    "compare": ("compare", "classroom", "--a", "numpy", "--b", "numpy", "--size", "16x12"),
    "simulate": ("simulate", "bounce", "-o", "out.gif", "--seconds", "0.05", "--fps", "20",
                 "--size", "8x6", "--backend", "numpy"),
    "animate": ("animate", "classroom", "-o", "out.gif", "--seconds", "0.05", "--fps", "20",
                "--size", "8x6", "--backend", "numpy"),
    "truth": ("truth", "classroom", "-o", "truth.npz", "--size", "8x6"),
    "bench accuracy": ("bench", "accuracy", "--quick", "-o", "report.md", "--size", "160x120",
                       "--repeat", "3"),
    "scenes": ("scenes",),
    "doctor": ("doctor",),
    "view": ("view", "classroom", "--frames", "1", "--size", "8x6"),
}
# Subcommands whose valid runs take longer than a case may: only values no reading can
# accept are tried on them, and each must be refused before the work starts, within
# REFUSAL_TIME_LIMIT (their base command line above takes ten times as long to run; their
# valid runs have tests of their own: tests/test_accuracy.py, tests/view).
ONLY_REFUSALS = ("bench accuracy", "view")     # view: a valid run opens a window
REFUSAL_TIME_LIMIT = 5.0

# Option values, ordinary (a careful user might type them) and bad (nobody should).
SIZES = (("8x6", "1x1", "3x2", "8X6", "16x1", "16384x1"),
         ("0x0", "0x6", "8x0", "-8x6", "8x-6", "1x16385", "16385x16385", "8x6x2", "8", "x", "",
          "8.5x6", "1e3x2", "axb", "9223372036854775808x1", "10000x10000", "16384x16384"))
NUMBERS = (("0.05", "0.5", "1", "20", "240"),
           ("0", "-0", "-1", "1e-300", "5e-324", "1e308", "1e309", "nan", "inf", "-inf", "abc",
            "", "1e6", "1e9", "0x10"))
INTEGERS = (("1", "2", "3", "16"),
            ("0", "-1", "abc", "", "1.5", "1e3", "0x10", "1000000000", "9223372036854775808",
             "1" + "0" * 30))
CHOICES_BAD = ("", "NUMPY", "numpy ", "cuda", "float16", "none", "-")
SCENE_ARGUMENTS = (("classroom", "csg", "lights", "primitives", "repetition", "bounce"),
                   ("nonexistent", "nonexistent.toml", "a_folder", "a_folder/", "a_file",
                    "empty.toml", "binary.toml", "not_toml.toml", "", "-", "a_file/x.toml",
                    "x" * 300, "classroom.toml"))
FOLDERS = (("saved", "deep/er/saved", "a_folder"), ("a_file", "a_file/sub", "", "x" * 300))
GENERIC = (("1", "out"), ("", "-1", "0", "nan", "1e308", "x" * 1000, "a_folder", "a_file"))
UNKNOWN = ("--bogus", "--bogus=1", "-x", "extra", "--", "--size=8x6=1")


def output_paths(suffix: str) -> tuple[tuple[str, ...], tuple[str, ...]]:
    ordinary = (f"out{suffix}", f"deep/er/out{suffix}", f"ünï{suffix}", f"OUT{suffix.upper()}")
    bad = ("a_folder", "a_folder/", f"a_file/out{suffix}", "out.jpg", "out", "", ".",
           "x" * 300 + suffix, "a_file")
    return ordinary, bad


def subcommands() -> dict[str, argparse.ArgumentParser]:
    """Every subcommand's parser, ``bench accuracy`` included, from `build_parser`."""
    found = {}

    def walk(parser, prefix):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    walk(sub, prefix + (name,))
                return
        found[" ".join(prefix)] = parser
    walk(build_parser(), ())
    return found


def options(command: str) -> dict[str, argparse.Action]:
    """The options and positionals of ``command`` by their flag (or dest), help left out."""
    return {(a.option_strings[-1] if a.option_strings else a.dest): a
            for a in subcommands()[command]._actions if not isinstance(a, argparse._HelpAction)}


def value_pool(command: str, action: argparse.Action) -> tuple[str, tuple, tuple]:
    """(row of the outcome table, ordinary values, bad values) for an option's value."""
    kind = getattr(action.type, "__name__", "") if action.type else ""
    if action.dest == "scene":
        return "scene argument", *SCENE_ARGUMENTS
    if action.dest == "set":
        return "--set field", (), ()              # drawn by set_values
    if action.choices:
        return "choice", tuple(action.choices), CHOICES_BAD
    if kind == "parse_size":
        return "size", *SIZES
    if kind == "positive_number":
        if action.dest == "seconds":        # 20 s of animation is 400 real frames: long, not
            return "number", NUMBERS[0][:3], NUMBERS[1]     # a hang; keep the ordinary ones short
        return "number", *NUMBERS
    if kind == "parse" or action.type is int:
        return "integer", *INTEGERS
    if action.dest in ("save", "images"):
        return "output folder", *FOLDERS
    if action.dest in ("output", "csv"):
        base = BASE[command]
        flag = action.option_strings[-1]
        given = base[base.index(flag) + 1] if flag in base else {"csv": "x.csv"}.get(
            action.dest, "x.out")
        return "output path", *output_paths("." + given.rsplit(".", 1)[-1])
    return "other value", *GENERIC


@st.composite
def set_values(draw, scene: str) -> tuple[str, str]:
    """A ``--set FIELD=VALUE`` for ``scene``: any field or vector component, a hostile value."""
    tree = scene_tree(scene)
    field = draw(st.one_of(
        st.sampled_from([format_path(p) for p in fields(tree)]),
        st.sampled_from(["render.bogus", "objects[99].radius", "camera.position[5]",
                         "render..x", "objects[0]", "", "render.max_steps=", "1abc"])))
    value = draw(st.one_of(
        st.sampled_from(EXTREME_NUMBERS + NON_FINITE + HUGE_INTEGERS + WRONG_TYPES),
        st.sampled_from(STRINGS[:6] + ("toon", "", "=")),
        st.builds(deep_value, st.sampled_from(DEPTHS), st.booleans())))
    return field, value


def target_names(flag: str, value: str) -> tuple[str, ...]:
    """What a refusal of ``flag value`` may name: the option, or the value as typed (a folder
    with or without its trailing slash; "''" for nothing)."""
    return (flag, value, value.rstrip("/") or value) if value else (flag, "''")


@st.composite
def option_cases(draw, command: str, option: str, time_limit: float = 10.0) -> Case:
    """The base command line of ``command`` with ``option`` spoilt (or ``option`` is
    "unknown option": an option or argument it does not have)."""
    argv = list(BASE[command])
    only_bad = command in ONLY_REFUSALS
    case = functools.partial(Case, must_refuse=only_bad,
                             time_limit=min(time_limit, REFUSAL_TIME_LIMIT) if only_bad
                             else time_limit)
    if option == "unknown option":
        token = draw(st.sampled_from([t for t in UNKNOWN if not (only_bad and t == "--")]))
        return case("unknown option", tuple(argv + [token]), f"{command} {token}",
                    (token, token.split("=")[0], "unrecognized"))
    action = options(command)[option]
    row, ordinary, bad = value_pool(command, action)
    values = st.sampled_from(bad) if only_bad or not ordinary else st.sampled_from(
        ordinary + bad)
    if not action.option_strings:                          # the scene argument
        value = draw(values)
        argv[len(command.split())] = value
        return case(row, tuple(argv), f"{command} {value[:40]!r}",
                    (value, value.rstrip("/") or value, "scene") if value else ())
    flag = option
    at = next((i for i, arg in enumerate(argv) if arg in action.option_strings), None)
    spoil = draw(st.sampled_from(
        ["value", "missing", "twice", "no value"] if action.nargs != 0 and not only_bad
        else ["value", "no value"] if action.nargs != 0 else ["flag"]))
    if action.nargs == 0:                                  # a flag: toggle it
        if at is None:
            argv.append(flag)
        else:
            del argv[at]
        return case("flag", tuple(argv), f"{command} {'with' if at is None else 'without'} "
                    f"{flag}", (flag,))
    if action.dest == "set":
        field, value = draw(set_values("bounce" if command == "simulate" else argv[1]))
        assignment = f"{field}={value}"
        head = re.split(r"[.\[=]", field)[0] if field else ""
        return case("--set field", tuple(argv + [flag, assignment]),
                    f"{command} --set {assignment[:60]}", tuple(n for n in (field, head, flag) if n))
    if spoil == "missing" and at is not None:
        del argv[at:at + 2]
        return case("missing option", tuple(argv), f"{command} without {flag}", (flag,))
    value = draw(values)
    if spoil == "no value":
        if at is not None:
            del argv[at:at + 2]
        return case("option without value", tuple(argv + [flag]), f"{command} ... {flag}",
                    (flag,))
    if spoil == "twice" or at is None:
        argv += [flag, value]
    else:
        argv[at + 1] = value
    return case(row, tuple(argv), f"{command} {flag} {value[:40]!r}", target_names(flag, value))


def option_targets() -> list[tuple[str, str]]:
    """Every (subcommand, option) pair to fuzz, and each subcommand's unknown options; not
    the flags of `ONLY_REFUSALS` (a flag has no value to refuse)."""
    return [(command, option) for command in BASE
            for option, action in [*options(command).items(), ("unknown option", None)]
            if not (command in ONLY_REFUSALS and action is not None and action.nargs == 0)]
