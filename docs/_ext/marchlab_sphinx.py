"""The parts of the marchlab site that are generated from the code at build time.

So that the site cannot drift from what it documents, nothing here is copied by hand:

- ``marchlab-cli``: the command-line reference, read from `marchlab.cli.build_parser`, and
  ``marchlab-api``: one section per module of a package, each an ``automodule``, found by
  walking the package so that a new module appears on its own (both in reference_pages.py);
- ``marchlab-toctree``: a toctree whose entries marked ``(optional)`` may name pages that do
  not exist yet (the lessons, pages other people are still writing): they are left out
  without a warning, and picked up as soon as they exist;
- the field reference of ``scene-format.md`` is replaced, as the page is read, by what
  `marchlab.docgen` writes from the scene model now;
- the lessons (``lessons/*.ipynb`` at the top of the repository) are copied into
  ``docs/lessons/`` (generated, ignored by git) before Sphinx looks for its sources.

Docstrings are plain-text maths (``|d|``, ``|J|``), not reStructuredText substitutions, so
`escape_bars` escapes their bars before autodoc parses them.
"""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

from docutils.statemachine import StringList
from sphinx.directives.other import TocTree
from sphinx.util import docname_join, logging
from sphinx.util.matching import patfilter

from reference_pages import ApiReference, CliReference, depend_on_packages

logger = logging.getLogger(__name__)

ROOT = Path(__file__).resolve().parent.parent.parent
LESSONS = ROOT / "lessons"
OPTIONAL = "(optional)"


# --- a toctree with optional entries ---------------------------------------------------------

class OptionalTocTree(TocTree):
    """``marchlab-toctree``: a toctree in which an entry ending in ``(optional)`` is left out,
    silently, while no page matches it (a page or glob pattern other people add later)."""

    def parse_content(self, toctree) -> None:
        here = self.env.current_document.docname
        kept = []
        for entry in self.content:
            if entry.rstrip().endswith(OPTIONAL):
                entry = entry.rstrip()[:-len(OPTIONAL)].strip()
                if not patfilter(self.env.found_docs - {here}, docname_join(here, entry)):
                    continue
            kept.append(entry)
        self.content = StringList(kept, source=self.content.source(0) if self.content else "")
        self.env.marchlab_optional_toctrees = getattr(self.env, "marchlab_optional_toctrees",
                                                      set()) | {here}
        super().parse_content(toctree)


def outdated_toctrees(app, env, added, changed, removed):
    """A page added or removed may be an optional entry: re-read the pages that have some."""
    if added or removed:
        return sorted(getattr(env, "marchlab_optional_toctrees", set()) & env.found_docs)
    return []


def purge_toctrees(app, env, docname):
    getattr(env, "marchlab_optional_toctrees", set()).discard(docname)


def merge_toctrees(app, env, docnames, other):
    env.marchlab_optional_toctrees = (getattr(env, "marchlab_optional_toctrees", set())
                                      | getattr(other, "marchlab_optional_toctrees", set()))


# --- pages read from elsewhere ------------------------------------------------------------------

def copy_lessons(app, config) -> None:
    """Mirror the lessons into docs/lessons/ before Sphinx looks for its sources.

    Top-level notebooks become pages; files beside them (images, data) are copied so that the
    notebooks find them at the same relative paths. Files are rewritten only when they
    changed, so an unchanged lesson is not read (nor executed) again. Notebooks in
    subfolders and Markdown files are not copied: they are not lessons.
    """
    target = Path(app.srcdir) / "lessons"
    wanted = {}
    if LESSONS.is_dir():
        for path in LESSONS.rglob("*"):
            relative = path.relative_to(LESSONS)
            if (not path.is_file() or any(part.startswith(".") or part == "__pycache__"
                                          for part in relative.parts)
                    or path.suffix in (".md", ".rst")
                    or (path.suffix == ".ipynb" and len(relative.parts) > 1)):
                continue
            wanted[relative] = path
    for relative, source in wanted.items():
        destination = target / relative
        if destination.is_file() and destination.read_bytes() == source.read_bytes():
            continue
        destination.parent.mkdir(parents=True, exist_ok=True)
        # A private temporary name: `make docs` and the test build may copy at the same time.
        temporary = destination.with_name(f".{destination.name}.{os.getpid()}.tmp")
        shutil.copyfile(source, temporary)
        temporary.replace(destination)
    if target.is_dir():
        for path in sorted(target.rglob("*"), reverse=True):
            relative = path.relative_to(target)
            if path.is_file() and relative not in wanted:
                path.unlink()
            elif path.is_dir() and not any(path.iterdir()):
                path.rmdir()


def read_source(app, docname, source) -> None:
    """Fill in what a page takes from the code as Sphinx reads it."""
    if docname == "scene-format":
        from marchlab import docgen
        current = docgen.updated(source[0])
        if current != source[0]:
            logger.info("docs/scene-format.md: its field reference is out of date (run "
                        "python -m marchlab.docgen); the site shows the current one")
        source[0] = current
        depend_on_packages(app.env)
    elif docname.startswith("lessons/"):
        # A lesson's output depends on the toolkit: execute it again when the code changes.
        depend_on_packages(app.env)


def check_cross_references(app, env, node, contnode):
    """Turn a broken ``{py:...}`` reference on a written page into a warning (-W: an error).

    Docstrings name many things informally and stay lenient; the pages that explain the
    maths promise links to the functions that implement it, so there a reference that names
    nothing is a mistake.
    """
    if node.get("refdomain") == "py" and not node.get("refdoc", "").startswith("api/"):
        logger.warning("cross-reference to %s %r names nothing", node.get("reftype"),
                       node.get("reftarget"), location=node)
    return None


# --- docstrings ----------------------------------------------------------------------------------

INLINE = re.compile(r"(``.+?``|`[^`]+`)")


def escape_bars(app, what, name, obj, options, lines) -> None:
    """Escape ``|`` outside literals: |x| in a docstring is an absolute value, not a
    reStructuredText substitution. Literal blocks (after ``::``) are left alone."""
    literal_indent = None
    for i, line in enumerate(lines):
        indent = len(line) - len(line.lstrip())
        if literal_indent is not None:
            if not line.strip() or indent > literal_indent:
                continue
            literal_indent = None
        if "|" in line:
            lines[i] = "".join(part if INLINE.fullmatch(part) else part.replace("|", "\\|")
                               for part in INLINE.split(line))
        if line.rstrip().endswith("::"):
            literal_indent = indent


def setup(app):
    app.add_directive("marchlab-cli", CliReference)
    app.add_directive("marchlab-api", ApiReference)
    app.add_directive("marchlab-toctree", OptionalTocTree)
    app.connect("config-inited", copy_lessons)
    app.connect("source-read", read_source)
    app.connect("env-get-outdated", outdated_toctrees)
    app.connect("env-purge-doc", purge_toctrees)
    app.connect("env-merge-info", merge_toctrees)
    app.connect("missing-reference", check_cross_references, priority=900)
    app.connect("autodoc-process-docstring", escape_bars, priority=600)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
