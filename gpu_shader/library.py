"""The hand-written shader sources, and how a program takes only what its scene needs.

Each ``glsl/*.glsl`` file is a library of building blocks, each function preceded by its
comment. The generator asks for functions by name (``sdf_sphere``, ``op_union``, ...);
`Library.select` returns those and every library function they call, in file order, with
their comments, so a shader holds exactly what its scene uses.

The files in ``glsl/pipeline/`` and the entry points are templates: GLSL with a few Jinja
tags (``{% if fog %}``, ``{% for light in lights %}``, ``{{ first }}``) that `fill_template`
fills in for one scene, so that the generator chooses and numbers but never spells GLSL.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import jinja2

GLSL_DIR = Path(__file__).parent / "glsl"

# A top-level function definition: "type name(" at the start of a line.
_DEFINITION = re.compile(r"^(?:\w+)\s+(\w+)\s*\(", re.M)
_WORD = re.compile(r"\b\w+\b")


@dataclass(frozen=True)
class LibraryFunction:
    """One function of a library file: its name, its text (comment included), who it calls."""
    name: str
    text: str
    calls: frozenset[str]


@dataclass(frozen=True)
class Library:
    """The functions of one building-block file, in file order, and the file's header comment."""
    header: str
    functions: tuple[LibraryFunction, ...]
    file: str = ""                      # where it comes from, "glsl/sdf.glsl"

    def names(self) -> list[str]:
        return [f.name for f in self.functions]

    def select(self, wanted, provided=frozenset()) -> str:
        """Source text of the functions in ``wanted`` and of everything they call.

        Functions named in ``provided`` are left out (the program takes them from
        elsewhere, e.g. the relaxed ``march`` of glsl/relaxed.glsl).
        """
        by_name = {f.name: f for f in self.functions}
        unknown = set(wanted) - set(by_name)
        if unknown:
            raise KeyError(f"not in the library: {', '.join(sorted(unknown))}")
        needed, todo = set(), list(wanted)
        while todo:
            name = todo.pop()
            if name not in needed and name not in provided:
                needed.add(name)
                todo.extend(by_name[name].calls)
        return "\n".join(f.text for f in self.functions if f.name in needed)


@cache
def glsl_file(name: str) -> str:
    """The text of ``glsl/<name>`` (an entry point, the vertex shader, ...), read once."""
    return (GLSL_DIR / name).read_text()


# Tags on lines of their own leave no blank line behind (trim_blocks, lstrip_blocks); a name
# a template uses but the generator did not give is an error, not an empty string.
_TEMPLATES = jinja2.Environment(loader=jinja2.FileSystemLoader(GLSL_DIR), trim_blocks=True,
                                lstrip_blocks=True, keep_trailing_newline=True,
                                undefined=jinja2.StrictUndefined, autoescape=False)


def fill_template(name: str, **context) -> str:
    """The template ``glsl/<name>`` filled in with ``context`` (parsed once, then cached)."""
    return _TEMPLATES.get_template(name).render(**context)


@cache
def load_library(name: str) -> Library:
    """Parse ``glsl/<name>.glsl`` (or, for OpenCL-only blocks, ``glsl/<name>.cl``) into its
    functions."""
    path = GLSL_DIR / f"{name}.glsl"
    if not path.exists():
        path = GLSL_DIR / f"{name}.cl"
    text = path.read_text()
    blocks = _split_blocks(text)
    header, blocks = blocks[0], blocks[1:]
    names = [_DEFINITION.search(b).group(1) for b in blocks]
    functions = []
    for name_, block in zip(names, blocks):
        body = block[block.index("{"):]
        calls = {w for w in _WORD.findall(body) if w in names and w != name_}
        functions.append(LibraryFunction(name_, block, frozenset(calls)))
    return Library(header, tuple(functions), f"{GLSL_DIR.name}/{path.name}")


def _split_blocks(text: str) -> list[str]:
    """The file's header, then one block per function: its leading comment and its body.

    A block ends at a closing brace in column 0; blank lines separate blocks; section
    comments ("// --- ...") between functions are dropped, as they introduce groups that a
    generated shader may include only part of.
    """
    lines = text.splitlines()
    blocks, current, in_body = [], [], False
    for line in lines:
        if not in_body and not line.strip():
            if current:
                blocks.append(current)
                current = []
            continue
        if not in_body and line.startswith("// ---"):
            continue
        current.append(line)
        if _DEFINITION.match(line):
            in_body = True
        elif in_body and line.startswith("}"):
            in_body = False
            blocks.append(current)
            current = []
    if current:
        blocks.append(current)
    header, rest = [], []
    for block in blocks:
        if any(_DEFINITION.match(line) for line in block):
            rest.append(block)
        elif not rest:
            header.append(block)
    # Only the file's first comment block is its header; later free comments are dropped.
    head = "\n".join(header[0]) if header else ""
    return [head] + ["\n".join(b) + "\n" for b in rest]
