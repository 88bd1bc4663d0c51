"""The C-like subset the building blocks are written in, as a small syntax tree.

The generator's one-ray program (``glsl/*.glsl`` and what `gpu_shader.generate` writes) keeps
to a subset of C that GLSL and OpenCL C share: declarations (``precise vec3 p = ...``),
assignments (``s.radiance = ...``, ``step++``), ``if``/``else``, ``for`` with ``break`` and
``continue``, ``return``, ``?:``, calls, swizzles, ``P[...]``, casts ``(real)(x)`` and
``#define``. `gpu_shader.subset_reader.parse` reads such a program into the nodes below,
`format_program` writes a tree back as text, and `gpu_shader.vectorise` rewrites the tree of
the one-ray program into its packet form, so the packet program is derived, never copied.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field, fields
from functools import cache

BASE_TYPES = {"real", "vec2", "vec3", "vec4", "int", "uint", "bool", "void"}


class SubsetError(ValueError):
    """Source outside the subset: says what and where (line of the source read)."""


# --- The tree ---------------------------------------------------------------------------------

@dataclass(eq=False, kw_only=True)
class Node:
    line: int = 0                          # where it starts in the source read
    macro: tuple | None = None             # (name, arguments) of the macro call it expands


@dataclass(eq=False)
class Name(Node):
    name: str


@dataclass(eq=False)
class Number(Node):
    text: str                              # as written: "1.0", "0u", "0xFFFFFFu", "1e-3"


@dataclass(eq=False)
class Unary(Node):
    op: str
    operand: Node


@dataclass(eq=False)
class Binary(Node):
    op: str
    left: Node
    right: Node


@dataclass(eq=False)
class Ternary(Node):
    condition: Node
    then: Node
    other: Node


@dataclass(eq=False)
class Call(Node):
    function: str
    arguments: list


@dataclass(eq=False)
class Cast(Node):
    type: str
    operand: Node


@dataclass(eq=False)
class Member(Node):
    base: Node
    field: str


@dataclass(eq=False)
class Index(Node):
    base: Node
    index: Node


@dataclass(eq=False, kw_only=True)
class Statement(Node):
    comment: str = ""                      # a "// ..." after it on its line


@dataclass(eq=False)
class Declare(Statement):
    type: str
    name: str
    value: Node | None = None
    precise: bool = False


@dataclass(eq=False)
class Assign(Statement):
    target: Node
    op: str                                # "=", "+=", ..., or "++", "--" (value None)
    value: Node | None = None


@dataclass(eq=False)
class Block(Statement):
    statements: list = field(default_factory=list)


@dataclass(eq=False)
class If(Statement):
    condition: Node
    then: Block
    other: Block | None = None


@dataclass(eq=False)
class For(Statement):
    init: Statement | None
    condition: Node | None
    step: Statement | None
    body: Block


@dataclass(eq=False)
class Break(Statement):
    pass


@dataclass(eq=False)
class Continue(Statement):
    pass


@dataclass(eq=False)
class Return(Statement):
    value: Node | None = None


@dataclass(eq=False)
class Comment(Statement):
    text: str = ""                         # the whole line, "// ..."


@dataclass(eq=False)
class Blank(Statement):
    pass


@dataclass(eq=False)
class Function(Node):
    type: str
    name: str
    parameters: list                       # [(type, name), ...]
    body: Block


@dataclass(eq=False)
class Define(Node):
    name: str
    parameters: list | None                # None for an object-like macro
    body: str
    text: str                              # the line as written


@dataclass(eq=False)
class Program(Node):
    items: list                            # Function, Define, Comment, Blank in source order

    def functions(self) -> dict:
        return {item.name: item for item in self.items if isinstance(item, Function)}

    def defines(self) -> dict:
        return {item.name: item for item in self.items if isinstance(item, Define)}


@cache
def _field_names(kind: type) -> tuple:
    return tuple(f.name for f in fields(kind) if f.name not in ("line", "macro", "comment"))


def children(node: Node):
    """The nodes directly below ``node``, in source order."""
    for name in _field_names(type(node)):
        value = getattr(node, name)
        if isinstance(value, Node):
            yield value
        elif isinstance(value, list):
            for item in value:
                if isinstance(item, Node):
                    yield item


def target_root(target: Node) -> Node:
    """The variable an assignment writes to: ``s`` in ``s.radiance = ...``."""
    while isinstance(target, Member):
        target = target.base
    return target


def walk(node: Node):
    """``node`` and every node below it, depth first, in source order (and the arguments
    of the macro call a node expands, after it)."""
    yield node
    for child in children(node):
        yield from walk(child)
    if node.macro is not None:
        for argument in node.macro[1]:
            yield from walk(argument)


# --- Writing ------------------------------------------------------------------------------

# Binary operators by C precedence, loosest first; `?:` binds looser than all of them.
BINARY = {"||": 2, "&&": 3, "|": 4, "^": 5, "&": 6, "==": 7, "!=": 7, "<": 8, ">": 8, "<=": 8,
          ">=": 8, "<<": 9, ">>": 9, "+": 10, "-": 10, "*": 11, "/": 11, "%": 11}
TERNARY, UNARY, POSTFIX = 1, 12, 13


def format_expression(node: Node) -> str:
    return _format(node)[0]


def _format(node: Node) -> tuple:
    """(text, precedence) of an expression; parentheses only where C needs them, and
    around mixed logical or bitwise operators, where a reader would want them."""
    if node.macro is not None:
        name, arguments = node.macro
        return f"{name}({', '.join(format_expression(a) for a in arguments)})", POSTFIX
    if isinstance(node, Name):
        return node.name, POSTFIX
    if isinstance(node, Number):
        return node.text, POSTFIX
    if isinstance(node, Call):
        arguments = ', '.join(format_expression(a) for a in node.arguments)
        return f"{node.function}({arguments})", POSTFIX
    if isinstance(node, Member):
        return f"{_operand(node.base, POSTFIX)}.{node.field}", POSTFIX
    if isinstance(node, Index):
        return f"{_operand(node.base, POSTFIX)}[{format_expression(node.index)}]", POSTFIX
    if isinstance(node, Cast):
        return f"({node.type})({format_expression(node.operand)})", UNARY
    if isinstance(node, Unary):
        inner = node.operand
        text = _operand(inner, UNARY)
        if isinstance(inner, Unary) and inner.op in "-+" and node.op in "-+":
            text = f"({text})"                     # "- -x" would read as "--x"
        return f"{node.op}{text}", UNARY
    if isinstance(node, Binary):
        p = BINARY[node.op]
        left = _operand(node.left, p, _unclear(node.op, node.left))
        right = _operand(node.right, p + 1, _unclear(node.op, node.right))
        return f"{left} {node.op} {right}", p
    if isinstance(node, Ternary):
        condition = _operand(node.condition, TERNARY + 1)
        then, other = (_operand(n, TERNARY + 1, isinstance(n, Binary) and n.macro is None
                                and BINARY[n.op] <= BINARY["<"]) for n in (node.then, node.other))
        return f"{condition} ? {then} : {other}", TERNARY
    raise SubsetError(f"not an expression: {type(node).__name__}")


def _operand(node: Node, least: int, force: bool = False) -> str:
    text, precedence = _format(node)
    return f"({text})" if precedence < least or force else text


def _unclear(op: str, child: Node) -> bool:
    """Whether ``child`` of an ``op`` node gets parentheses for the reader's sake."""
    if not isinstance(child, Binary) or child.macro is not None or child.op == op:
        return False
    logical, bitwise = {"&&", "||"}, {"&", "|", "^", "<<", ">>"}
    comparisons = {"==", "!=", "<", ">", "<=", ">="}
    return ((op in logical and child.op in logical) or op in bitwise or child.op in bitwise
            or (op in ("==", "!=") and child.op in comparisons))


def format_program(program: Program) -> str:
    lines = []
    for item in program.items:
        if isinstance(item, Function):
            head = f"{item.type} {item.name}("
            parameters = [f"{t} {n}" for t, n in item.parameters]
            for k, parameter in enumerate(parameters):
                text = parameter + (")" if k == len(parameters) - 1 else ",")
                if head.endswith(("(", ",")) and len(head) + 1 + len(text) > WIDTH:
                    lines.append(head)
                    head = " " * (len(item.type) + len(item.name) + 2)
                head += ("" if head.endswith("(") or not head.strip() else " ") + text
            lines.append(head + (")" if not parameters else ""))
            lines += _block_lines(item.body, 0)
        elif isinstance(item, Define):
            lines.append(item.text)
        elif isinstance(item, Comment):
            lines.append(item.text)
        elif isinstance(item, Blank):
            lines.append("")
    return "\n".join(lines) + "\n"


def _block_lines(block: Block, depth: int, head: str = "") -> list:
    """``head {`` (its comment after the brace), the statements one level in, ``}``."""
    pad = "    " * depth
    opening = f"{pad}{head}{{" if head else f"{pad}{{"
    lines = _with_comment(opening, block.comment)
    if len(lines) == 2:                  # no room after the brace: the comment goes inside
        lines = [opening, f"{pad}    {block.comment}"]
    for statement in block.statements:
        lines += _statement_lines(statement, depth + 1)
    return lines + [f"{pad}}}"]


WIDTH = 100                              # characters a line of written code may take


def _with_comment(text: str, comment: str) -> list:
    """The line ``text`` and its comment: after it where the line has room, else above."""
    if not comment:
        return [text]
    if len(text) + 2 + len(comment) <= WIDTH:
        return [f"{text}  {comment}"]
    return [f"{' ' * (len(text) - len(text.lstrip()))}{comment}", text]


def _wrapped(prefix: str, node: Node, suffix: str) -> list:
    """``prefix``, the expression ``node`` and ``suffix`` as lines of at most `WIDTH`
    characters where a call's arguments allow, continued under its opening parenthesis."""
    text = prefix + format_expression(node) + suffix
    if len(text) <= WIDTH or not isinstance(node, Call) or node.macro is not None:
        return [text]
    head = f"{prefix}{node.function}("
    lines, current = [], head
    for k, argument in enumerate(node.arguments):
        end = ")" + suffix if k == len(node.arguments) - 1 else ","
        piece = format_expression(argument) + end
        space = "" if current.endswith("(") or not current.strip() else " "
        if len(current) + len(space) + len(piece) <= WIDTH:
            current += space + piece
            continue
        if current != head:
            lines.append(current)
            current, space = " " * len(head), ""
        if len(current) + len(piece) <= WIDTH:
            current += piece
            continue
        more = _wrapped(current + space, argument, end)
        lines += more[:-1]
        current = more[-1]
    return lines + [current]


def format_statement(statement: Statement) -> str:
    """A simple statement without its ``;`` (declaration, assignment, return), as in a for
    header."""
    if isinstance(statement, Declare):
        value = f" = {format_expression(statement.value)}" if statement.value is not None else ""
        return f"{'precise ' if statement.precise else ''}{statement.type} {statement.name}{value}"
    if isinstance(statement, Assign):
        target = format_expression(statement.target)
        if statement.value is None:
            return f"{target}{statement.op}"
        return f"{target} {statement.op} {format_expression(statement.value)}"
    if isinstance(statement, Return):
        value = statement.value
        return "return" if value is None else f"return {format_expression(value)}"
    raise SubsetError(f"not a simple statement: {type(statement).__name__}")


def _statement_lines(statement: Statement, depth: int) -> list:
    pad = "    " * depth
    if isinstance(statement, (Declare, Assign, Return)) and statement.value is not None:
        text = format_statement(statement)
        value = format_expression(statement.value)
        lines = _wrapped(pad + text[:len(text) - len(value)], statement.value, ";")
        if len(lines) > 1 and statement.comment:
            return [pad + statement.comment] + lines
        return _with_comment(lines[0], statement.comment) + lines[1:]
    if isinstance(statement, (Declare, Assign)):
        return _with_comment(f"{pad}{format_statement(statement)};", statement.comment)
    if isinstance(statement, Comment):
        return [f"{pad}{statement.text}"]
    if isinstance(statement, Blank):
        return [""]
    if isinstance(statement, Block):
        return _block_lines(statement, depth)
    if isinstance(statement, (Break, Continue)):
        word = "break" if isinstance(statement, Break) else "continue"
        return _with_comment(f"{pad}{word};", statement.comment)
    if isinstance(statement, Return):
        value = f" {format_expression(statement.value)}" if statement.value is not None else ""
        return _with_comment(f"{pad}return{value};", statement.comment)
    if isinstance(statement, If):
        block = copy.copy(statement.then)
        block.comment = statement.comment
        lines = _block_lines(block, depth, f"if ({format_expression(statement.condition)}) ")
        other = statement.other
        if other is None:
            return lines
        nested = other.statements[0] if len(other.statements) == 1 else None
        if isinstance(nested, If) and not other.comment and not nested.comment:
            nested = _statement_lines(nested, depth)        # } else if (...) {
            return lines[:-1] + [f"{pad}}} else {nested[0].lstrip()}"] + nested[1:]
        rest = _block_lines(other, depth, "else ")
        return lines[:-1] + [f"{pad}}} {rest[0].lstrip()}"] + rest[1:]
    if isinstance(statement, For):
        parts = [format_statement(statement.init) if statement.init else "",
                 format_expression(statement.condition) if statement.condition else "",
                 format_statement(statement.step) if statement.step else ""]
        block = copy.copy(statement.body)
        block.comment = statement.comment
        return _block_lines(block, depth, f"for ({'; '.join(parts).strip()}) ")
    raise SubsetError(f"not a statement: {type(statement).__name__}")
