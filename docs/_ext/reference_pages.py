"""The reference pages generated from the code: the command line and the API.

``marchlab-cli`` reads `marchlab.cli.build_parser`; ``marchlab-api PACKAGE`` walks a package
and writes an ``automodule`` section per module. Both write MyST Markdown and parse it in
place, so the result is ordinary page content (headings in the table of contents, links).
Registered by marchlab_sphinx.py.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
from pathlib import Path

from docutils import nodes
from docutils.parsers.rst import directives
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective

ROOT = Path(__file__).resolve().parent.parent.parent
PACKAGES = ("scene_model", "physics", "reference_cpu", "gpu_shader", "marchlab")


# --- generated Markdown, parsed in place ------------------------------------------------------

def parse_markdown(directive: SphinxDirective, text: str) -> list[nodes.Node]:
    """Parse MyST Markdown written by a directive, headings included, and return its nodes.

    The text must start with a heading: MyST attaches each new section straight to the page
    as it meets it, so text before the first heading would come back after the sections.
    """
    holder = nodes.section()
    holder.document = directive.state.document
    directive.state.nested_parse(StringList(text.splitlines(), source=directive.get_source_info()[0]),
                                 directive.content_offset, holder, match_titles=True)
    return holder.children


def depend_on_packages(env) -> None:
    """Re-read the current page whenever a module of the toolkit changes."""
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            env.note_dependency(str(path))


def cell(text: str) -> str:
    """Text safe inside a Markdown table cell."""
    return " ".join(text.split()).replace("|", "\\|").replace("<", "&lt;")


# --- the command-line reference --------------------------------------------------------------

def subcommands(parser: argparse.ArgumentParser) -> list[tuple[str, str, argparse.ArgumentParser]]:
    """(name, one-line help, parser) of every subcommand, in the order the parser defines them."""
    out = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {a.dest: a.help or "" for a in action._choices_actions}
            out += [(name, helps.get(name, ""), sub) for name, sub in action.choices.items()]
    return out


def usage(parser: argparse.ArgumentParser, width: int = 90) -> str:
    """The usage line(s) of ``parser`` at a fixed width (not the terminal's)."""
    formatter = parser.formatter_class(prog=parser.prog, width=width)
    formatter.add_usage(parser.usage, parser._actions, parser._mutually_exclusive_groups)
    return formatter.format_help().strip()


def help_texts(parser: argparse.ArgumentParser) -> dict[str, str]:
    """Help of each option string across all subcommands, for options given help only once
    (``--set`` is explained under ``render`` and means the same everywhere)."""
    out = {}
    for _, _, sub in subcommands(parser):
        for action in sub._actions:
            for option in action.option_strings:
                if action.help and option not in out:
                    out[option] = sub._get_formatter()._expand_help(action)
    return out


def argument_rows(parser: argparse.ArgumentParser, shared: dict[str, str]) -> list[str]:
    """A Markdown table of the arguments of ``parser``, help option excluded."""
    formatter = parser._get_formatter()
    rows = ["| argument | value | default | meaning |", "| --- | --- | --- | --- |"]
    for action in parser._actions:
        if isinstance(action, (argparse._HelpAction, argparse._SubParsersAction)):
            continue
        if action.choices is not None:
            value = " \\| ".join(f"`{c}`" for c in action.choices)
        elif action.nargs == 0:
            value = "(flag)"
        elif action.option_strings:
            value = f"`{action.metavar or action.dest.upper()}`"
        else:
            value = ""
        if action.nargs in ("+", "*") and value:
            value += " ..."
        if not action.option_strings:
            name = f"`{action.metavar or action.dest}`"
            default = "required" if action.required else "-"
        else:
            name = ", ".join(f"`{s}`" for s in action.option_strings)
            if action.default in (None, [], False) or action.default is argparse.SUPPRESS:
                default = "-"
            elif isinstance(action.default, tuple) and action.metavar == "WxH":
                default = f"`{'x'.join(map(str, action.default))}`"
            else:
                default = f"`{action.default}`"
        if action.help:
            meaning = formatter._expand_help(action)
        else:
            meaning = next((shared[s] for s in action.option_strings if s in shared), "")
        rows.append(f"| {name} | {value} | {default} | {cell(meaning)} |")
    return rows


def cli_overview(parser: argparse.ArgumentParser) -> str:
    """Markdown: the command's usage and a table of its subcommands."""
    lines = ["## Commands", "", "```text", usage(parser), "```", "",
             "| command | what it does |", "| --- | --- |"]
    lines += [f"| [`{parser.prog} {name}`](#cli-{name}) | {cell(text)} |"
              for name, text, _ in subcommands(parser)]
    return "\n".join(lines)


def cli_sections(parser: argparse.ArgumentParser) -> str:
    """Markdown: one section per subcommand, with its usage and a table of its arguments."""
    shared = help_texts(parser)
    lines = []
    for name, text, sub in subcommands(parser):
        lines += [f"(cli-{name})=", f"## `{parser.prog} {name}`", ""]
        if text:
            lines += [text[:1].upper() + text[1:] + ".", ""]
        if sub.description:
            lines += [sub.description, ""]
        lines += ["```text", usage(sub), "```", ""]
        if len(sub._actions) > 1:
            lines += argument_rows(sub, shared) + [""]
    return "\n".join(lines)


class CliReference(SphinxDirective):
    """``marchlab-cli``: the reference of the ``marchlab`` command, from its argparse parser."""

    def run(self):
        from marchlab import cli
        depend_on_packages(self.env)
        parser = cli.build_parser()
        return parse_markdown(self, cli_overview(parser) + "\n\n" + cli_sections(parser))


# --- the API reference -----------------------------------------------------------------------

def modules_of(package: str, first: list[str], exclude: list[str]) -> list[str]:
    """Every module of ``package`` (recursively): those named in ``first`` in that order, then
    the others alphabetically."""
    root = importlib.import_module(package)
    found = [package]
    if hasattr(root, "__path__"):
        found += [m.name for m in pkgutil.walk_packages(root.__path__, prefix=f"{package}.")]
    found = [m for m in found if m.rsplit(".", 1)[-1] not in exclude and m not in exclude]
    ordered = [f"{package}.{name}" for name in first if f"{package}.{name}" in found]
    return ordered + sorted(m for m in found if m not in ordered and m != package)


def is_package(module: str) -> bool:
    return hasattr(importlib.import_module(module), "__path__")


def api_markdown(package: str, first: list[str], exclude: list[str]) -> str:
    """Markdown: the package's own docstring, then a section per module with its members.

    A name is documented in the module that defines it, never where it is re-exported (a
    package's ``__init__``, `scene_model.builder`): documenting it twice would make every short
    reference to it ambiguous. So a package shows only its docstring, and ``__all__`` is
    ignored in favour of what each module defines. The package comes first, as a section like
    its modules (see `parse_markdown`).
    """
    lines = []
    for module in [package] + modules_of(package, first, exclude):
        lines += [f"## `{module}`", "", "```{eval-rst}", f".. automodule:: {module}"]
        if not is_package(module):
            lines += ["   :members:", "   :ignore-module-all:"]
        lines += ["```", ""]
    return "\n".join(lines)


class ApiReference(SphinxDirective):
    """``marchlab-api PACKAGE``: every module of PACKAGE, documented by autodoc.

    Options: ``:first:`` module names (without the package) to put first, in reading order;
    ``:exclude:`` module names to leave out.
    """

    required_arguments = 1
    option_spec = {"first": directives.unchanged, "exclude": directives.unchanged}

    def run(self):
        package = self.arguments[0]
        first = self.options.get("first", "").split()
        exclude = self.options.get("exclude", "").split()
        return parse_markdown(self, api_markdown(package, first, exclude))
