"""Reading the C-like subset of the building blocks into its syntax tree (`gpu_shader.subset`).

`parse` reads a one-ray program (``#define`` lines, comments and functions) as C would, with
two steps of the preprocessor done here: ``#if``/``#else``/``#endif`` are decided from the
``#define NAME <integer>`` lines above them, and a function-like macro such as
``MATERIAL(id, row)`` is expanded where it is called (its parameters parenthesised in its
body, as C style asks), the node it becomes remembering the call so that it can be written
back as written. Own-line comments become `Comment` statements and a comment after a
statement on its line stays with it. A construct outside the subset (``while``, arrays, a
call as a statement) is a `SubsetError` naming it and its line.
"""

from __future__ import annotations

import copy
import re
from dataclasses import dataclass, fields

from .subset import (BASE_TYPES, BINARY, Assign, Binary, Blank, Block, Break, Call, Cast,
                     Comment, Continue, Declare, Define, For, Function, If, Index, Member, Name,
                     Node, Number, Program, Return, SubsetError, Ternary, Unary)

_TOKEN = re.compile(r"""
    (?P<comment>//[^\n]*)
  | (?P<directive>^[ \t]*\#[^\n]*)
  | (?P<number>0[xX][0-9a-fA-F]+[uU]?|(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?[uUfF]?)
  | (?P<name>[A-Za-z_]\w*)
  | (?P<op>\+\+|--|[-+*/|&]=|&&|\|\||==|!=|<=|>=|<<|>>|[-+*/%<>=!~&|^?:;,.(){}\[\]])
  | (?P<space>\s+)
  | (?P<other>.)
""", re.M | re.X)

ASSIGNMENTS = {"=", "+=", "-=", "*=", "/=", "|=", "&="}


@dataclass
class Token:
    kind: str                              # a group name of _TOKEN: "name", "op", ...
    text: str
    line: int


def tokenize(source: str) -> list:
    """The tokens of ``source``, comments and ``#`` lines included, blanks left out."""
    tokens, line = [], 1
    for m in _TOKEN.finditer(source):
        kind, text = m.lastgroup, m.group()
        if kind == "other":
            raise SubsetError(f"line {line}: unexpected character {text!r}")
        if kind != "space":
            tokens.append(Token(kind, text.strip() if kind == "directive" else text, line))
        line += text.count("\n")
    return tokens


def preprocess(source: str) -> str:
    """Decide ``#if NAME`` / ``#ifdef`` / ``#ifndef`` / ``#else`` / ``#endif`` from the object-like
    ``#define`` lines met so far, keeping the lines of the branches taken."""
    values: dict = {}
    taking, lines = [], []
    for text in source.split("\n"):
        words = text.split()
        directive = words[0] if words and words[0].startswith("#") else ""
        live = all(taking)
        if directive in ("#if", "#ifdef", "#ifndef"):
            name = words[1] if len(words) > 1 else ""
            if not live:                   # inside a branch not taken: not taken either
                taking.append(False)
            elif directive == "#if":
                value = values.get(name, name)
                if not re.fullmatch(r"\d+", value):
                    raise SubsetError(f"#if {name}: only a defined integer can be tested")
                taking.append(int(value) != 0)
            else:
                taking.append((name in values) == (directive == "#ifdef"))
            continue
        if directive in ("#else", "#endif"):
            if not taking:
                raise SubsetError(f"{directive} without #if")
            if directive == "#else":
                taking[-1] = not taking[-1]
            else:
                taking.pop()
            continue
        if not live:
            continue
        if directive == "#define" and len(words) >= 2 and "(" not in words[1]:
            values[words[1]] = " ".join(words[2:])
        lines.append(text)
    if taking:
        raise SubsetError("#if without #endif")
    return "\n".join(lines)


def parse(source: str, struct_names=()) -> Program:
    """The program ``source`` (defines, comments and functions) as a tree.

    ``struct_names`` are the struct types it may use besides `BASE_TYPES`.
    """
    return _Parser(preprocess(source), BASE_TYPES | set(struct_names)).program()


def parse_expression(text: str, struct_names=()) -> Node:
    """One expression, e.g. the body of ``#define EPSILON P[5].x``."""
    parser = _Parser(text, BASE_TYPES | set(struct_names))
    node = parser.expression()
    parser.expect_end()
    return node


class _Parser:
    def __init__(self, source: str, types: set, macros: dict | None = None):
        tokens = tokenize(source)
        self.code = [t for t in tokens if t.kind != "comment"]
        # Comments by the index of the code token they come before.
        self.comments: dict = {}
        k = 0
        for t in tokens:
            if t.kind == "comment":
                self.comments.setdefault(k, []).append(t)
            else:
                k += 1
        self.i, self.types, self.macros = 0, types, dict(macros or {})
        self.last_line = 0                 # the line of the last code token read

    # -- tokens
    def peek(self, ahead: int = 0) -> Token:
        k = self.i + ahead
        return self.code[k] if k < len(self.code) else Token("end", "", self.last_line)

    def next(self) -> Token:
        token = self.peek()
        self.i += 1
        self.last_line = token.line
        return token

    def accept(self, text: str) -> bool:
        if self.peek().text == text and self.peek().kind != "end":
            self.next()
            return True
        return False

    def expect(self, text: str) -> Token:
        if not self.accept(text):
            raise self.error(f"expected {text!r}")
        return self.code[self.i - 1]

    def expect_end(self):
        if self.peek().kind != "end":
            raise self.error("unexpected text after the expression")

    def error(self, what: str) -> SubsetError:
        token = self.peek()
        return SubsetError(f"line {token.line}: {what}, found {token.text or 'the end'!r}")

    def name(self) -> str:
        if self.peek().kind != "name":
            raise self.error("expected a name")
        return self.next().text

    def comments_here(self) -> list:
        """The comment tokens before the next code token."""
        return self.comments.pop(self.i, [])

    # -- the program
    def program(self) -> Program:
        items, line = [], 0
        while True:
            for comment in self.comments_here():
                if comment.line > line + 1 and items:
                    items.append(Blank())
                items.append(Comment(text=comment.text))
                line = comment.line
            if self.peek().kind == "end":
                return Program(items)
            if self.peek().line > line + 1 and items:
                items.append(Blank())
            items.append(self.directive() if self.peek().kind == "directive" else self.function())
            line = self.last_line

    def directive(self) -> Node:
        token = self.next()
        m = re.match(r"#\s*define\s+(\w+)(\(([^)]*)\))?\s*(.*)$", token.text)
        if not m:
            raise SubsetError(f"line {token.line}: only #define is in the subset: {token.text}")
        parameters = [p.strip() for p in m.group(3).split(",")] if m.group(2) else None
        define = Define(m.group(1), parameters, m.group(4), token.text, line=token.line)
        if parameters is not None:
            body = _Parser(m.group(4), self.types, self.macros).expression()
            self.macros[define.name] = (parameters, body)
        return define

    def function(self) -> Function:
        line = self.peek().line
        type_, name = self.type_name(), self.name()
        self.expect("(")
        parameters = []
        while not self.accept(")"):
            if parameters:
                self.expect(",")
            parameters.append((self.type_name(), self.name()))
        return Function(type_, name, parameters, self.block(), line=line)

    def type_name(self) -> str:
        if self.peek().text not in self.types:
            raise self.error("expected a type")
        return self.next().text

    # -- statements
    def block(self) -> Block:
        block = Block(line=self.expect("{").line)
        self.statements(block, "}")
        return block

    def statements(self, block: Block, end: str):
        """Statements up to ``end``, with their comments and blank lines."""
        line = self.last_line
        while True:
            for comment in self.comments_here():
                if comment.line == self.last_line and block.statements and comment.line == line:
                    block.statements[-1].comment = comment.text
                elif comment.line == self.last_line and not block.statements:
                    block.comment = comment.text       # after the opening brace
                else:
                    if comment.line > line + 1 and block.statements:
                        block.statements.append(Blank())
                    block.statements.append(Comment(text=comment.text))
                line = comment.line
            if self.accept(end):
                return
            if self.peek().kind == "end":
                raise self.error(f"expected {end!r}")
            if block.statements and self.peek().line > line + 1:
                block.statements.append(Blank())
            block.statements.extend(self.statement())
            line = self.last_line

    def statement(self) -> list:
        token = self.peek()
        keyword = token.text
        if keyword == "{":
            return [self.block()]
        if keyword == "if":
            self.next()
            self.expect("(")
            condition = self.expression()
            self.expect(")")
            then = self.body()
            other = self.body() if self.accept("else") else None
            return [If(condition, then, other, line=token.line, comment=then.comment)]
        if keyword == "for":
            self.next()
            self.expect("(")
            init = None if self.peek().text == ";" else self.simple_statement()[0]
            self.expect(";")
            condition = None if self.peek().text == ";" else self.expression()
            self.expect(";")
            step = None if self.peek().text == ")" else self.simple_statement()[0]
            self.expect(")")
            body = self.body()
            return [For(init, condition, step, body, line=token.line, comment=body.comment)]
        if keyword in ("break", "continue", "return"):
            self.next()
            value = None
            if keyword == "return" and self.peek().text != ";":
                value = self.expression()
            self.expect(";")
            kind = {"break": Break, "continue": Continue, "return": Return}[keyword]
            return [kind(value, line=token.line) if value else kind(line=token.line)]
        if keyword in ("while", "do", "switch", "goto"):
            raise self.error(f"{keyword} is not in the subset (use for, if)")
        statements = self.simple_statement()
        self.expect(";")
        return statements

    def body(self) -> Block:
        """The body of an if or for: a block, or one statement (kept as a block)."""
        if self.peek().text == "{":
            return self.block()
        line = self.peek().line
        return Block(self.statement(), line=line)

    def simple_statement(self) -> list:
        """Declarations (one per name) or one assignment, without the final ``;``."""
        line = self.peek().line
        precise = self.accept("precise")
        if self.peek().text in self.types and self.peek(1).kind == "name":
            type_, declared = self.type_name(), []
            while True:
                name = self.name()
                if self.peek().text == "[":
                    raise self.error("arrays are not in the subset")
                value = self.expression() if self.accept("=") else None
                declared.append(Declare(type_, name, value, precise, line=line))
                if not self.accept(","):
                    return declared
        target = self.postfix()
        op = self.next().text
        if op in ("++", "--"):
            return [Assign(target, op, line=line)]
        if op not in ASSIGNMENTS:
            raise SubsetError(f"line {line}: a statement must declare or assign (found {op!r})")
        return [Assign(target, op, self.expression(), line=line)]

    # -- expressions
    def expression(self) -> Node:
        line = self.peek().line
        condition = self.binary(BINARY["||"])
        if not self.accept("?"):
            return condition
        then = self.expression()
        self.expect(":")
        return Ternary(condition, then, self.expression(), line=line)

    def binary(self, least: int) -> Node:
        left = self.unary()
        while self.peek().kind == "op" and BINARY.get(self.peek().text, 0) >= least:
            op = self.next().text
            left = Binary(op, left, self.binary(BINARY[op] + 1), line=left.line)
        return left

    def unary(self) -> Node:
        token = self.peek()
        if token.kind == "op" and token.text in ("-", "!", "~", "+"):
            self.next()
            return Unary(token.text, self.unary(), line=token.line)
        if token.text == "(" and self.peek(1).text in self.types and self.peek(2).text == ")":
            self.next()
            type_ = self.next().text
            self.next()
            return Cast(type_, self.unary(), line=token.line)
        return self.postfix()

    def postfix(self) -> Node:
        node = self.primary()
        while True:
            if self.peek().text == "(" and isinstance(node, Name):
                self.next()
                arguments = []
                while not self.accept(")"):
                    if arguments:
                        self.expect(",")
                    arguments.append(self.expression())
                node = self.call(node, arguments)
            elif self.accept("["):
                node = Index(node, self.expression(), line=node.line)
                self.expect("]")
            elif self.accept("."):
                node = Member(node, self.name(), line=node.line)
            else:
                return node

    def call(self, name: Name, arguments: list) -> Node:
        if name.name not in self.macros:
            return Call(name.name, arguments, line=name.line)
        parameters, body = self.macros[name.name]
        if len(arguments) != len(parameters):
            raise SubsetError(f"line {name.line}: {name.name} takes {len(parameters)} arguments")
        expanded = _substitute(body, dict(zip(parameters, arguments)))
        expanded.macro = (name.name, arguments)
        return expanded

    def primary(self) -> Node:
        token = self.next()
        if token.kind == "number":
            return Number(token.text, line=token.line)
        if token.kind == "name":
            return Name(token.text, line=token.line)
        if token.text == "(":
            node = self.expression()
            self.expect(")")
            return node
        self.i -= 1
        raise self.error("expected an expression")


def _substitute(node: Node, values: dict) -> Node:
    """A copy of the macro body ``node`` with its parameters replaced by ``values``."""
    if isinstance(node, Name) and node.name in values:
        return copy.deepcopy(values[node.name])
    node = copy.copy(node)
    for f in fields(node):
        value = getattr(node, f.name)
        if isinstance(value, Node):
            setattr(node, f.name, _substitute(value, values))
        elif isinstance(value, list):
            setattr(node, f.name, [_substitute(v, values) if isinstance(v, Node) else v
                                   for v in value])
    return node


