"""Which values of a one-ray program differ from ray to ray: the analysis behind packets.

In a packet program one work-item runs LANES rays (`gpu_shader.vectorise`). A value the same
for every ray (a parameter, a loop counter that every ray shares) stays a scalar; a value
that may differ (a point on the ray, a distance) becomes a vector with one lane per ray. This
is the divergence analysis of whole-function vectorisation (Karrenberg and Hack,
"Whole-function vectorization", CGO 2011, section 4), done on the syntax tree by fixpoint:

- the roots' parameters vary as they are declared to (``trace(origin, direction)``: both);
- a function's parameter varies if some call passes it a varying value; its result varies if
  a returned value varies, or if it returns under control flow that varies;
- a variable varies if a varying value is assigned to it, or if it is assigned where only
  some of the rays that share its scope get there: inside an ``if`` whose condition varies,
  or a loop that rays leave at different times, between its declaration and the assignment;
- a struct value always varies (its fields are packets); ``#define`` names, which read the
  parameter block at fixed rows, never do;
- an ``if`` or loop *diverges* if its condition varies, and a loop also if a ``break``,
  ``continue`` or ``return`` inside it sits under a diverging ``if``.

A function that holds a diverging loop, or calls one that does, takes the mask of the rays
still wanted (``live``), so that rays no caller wants are never marched.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .subset import (Assign, Binary, Block, Break, Call, Cast, Continue, Declare, For, Function,
                     If, Index, Member, Name, Node, Number, Program, Return, SubsetError,
                     Ternary, Unary, target_root, walk)
from .subset_reader import parse_expression

VECTORS = {"vec2": 2, "vec3": 3, "vec4": 4}
# Scalar types by how a C-like language widens them in arithmetic.
RANK = {"bool": 0, "int": 1, "uint": 2, "real": 3, "vec2": 4, "vec3": 5, "vec4": 6}
COMPARISONS = {"==", "!=", "<", ">", "<=", ">="}
# Builtins whose result has the type of their widest argument, and those giving a real.
COMPONENTWISE = {"sqrt", "abs", "fabs", "floor", "ceil", "exp", "exp2", "log", "log2", "sin",
                 "cos", "tan", "asin", "acos", "atan", "atan2", "sign", "fract", "pow", "min",
                 "max", "clamp", "mix", "step", "smoothstep", "fmod", "round", "trunc",
                 "normalize", "reflect", "cross", "fmin", "fmax"}
REAL_RESULT = {"dot", "length", "distance"}
CONVERSIONS = {"int": "int", "uint": "uint", "real": "real", "bool": "bool", "float": "real"}
CONSTANTS = {"INFINITY": "real", "true": "bool", "false": "bool"}
BUFFERS = {"P", "U"}                     # the parameter block: rows of vec4


@dataclass(eq=False)
class Variable:
    """A local or a parameter: its scalar type, how many control regions enclose its
    declaration, and whether it varies."""
    name: str
    type: str
    depth: int
    varying: bool = False


@dataclass(eq=False)
class FunctionInfo:
    function: Function
    parameters: list
    returns_varying: bool = False
    divergent_returns: bool = False      # some rays return before others
    needs_live: bool = False
    calls: set = field(default_factory=set)


class Analysis:
    """The varying values and diverging control flow of ``program``.

    Parameters
    ----------
    program : subset.Program
    structs : dict
        Struct name -> ((type, field), ...), as `gpu_shader.dialects.STRUCTS`.
    roots : dict
        Function name -> one bool per parameter: whether it varies where the packet program
        calls it (``{"trace": (True, True)}``).
    live_roots : set
        Roots that take a ``live`` mask whatever they hold.
    """

    def __init__(self, program: Program, structs: dict, roots: dict, live_roots=()):
        self.structs = structs
        self.defines = {name: d for name, d in program.defines().items()
                        if d.parameters is None}
        self._define_types: dict = {}
        self.functions = {}
        for name, function in program.functions().items():
            flags = roots.get(name, (False,) * len(function.parameters))
            if len(flags) != len(function.parameters):
                raise SubsetError(f"{name}: {len(function.parameters)} parameters, "
                                  f"{len(flags)} given as roots")
            parameters = [Variable(n, t, 0, bool(v) or t in structs)
                          for (t, n), v in zip(function.parameters, flags)]
            self.functions[name] = FunctionInfo(function, parameters,
                                                returns_varying=function.type in structs)
        self.declared: dict = {}             # Declare node -> Variable
        self.resolved: dict = {}             # Name node -> Variable
        self.divergent: set = set()          # diverging If and For nodes
        self.counters: dict = {}             # For -> (its counter, the counter's copy inside)
        self.changed = True
        while self.changed:
            self.changed = False
            for info in self.functions.values():
                scope = {v.name: v for v in info.parameters}
                _Walk(self, info).block(info.function.body, [scope], [])
        for name, info in self.functions.items():
            info.needs_live = name in live_roots or any(
                n in self.divergent for n in walk(info.function.body) if isinstance(n, For))
        growing = True
        while growing:                       # callers of functions that need `live` need it
            growing = False
            for info in self.functions.values():
                if not info.needs_live and any(self.functions[c].needs_live for c in info.calls):
                    info.needs_live = growing = True

    def mark(self, holder, attribute: str, value: bool = True):
        """Set a flag that only ever goes from False to True, noting the change."""
        if value and not getattr(holder, attribute):
            setattr(holder, attribute, True)
            self.changed = True

    def diverge(self, node: Node):
        if node not in self.divergent:
            self.divergent.add(node)
            self.changed = True

    # --- types -------------------------------------------------------------------------

    def type_of(self, node: Node) -> tuple:
        """(scalar type, varies?) of an expression whose names are resolved."""
        if isinstance(node, Number):
            text = node.text.lower()
            if text.endswith("u"):
                return "uint", False
            hexadecimal = text.startswith("0x")
            real = not hexadecimal and ("." in text or "e" in text or text.endswith("f"))
            return ("real" if real else "int"), False
        if isinstance(node, Name):
            if node in self.resolved:
                variable = self.resolved[node]
                return variable.type, variable.varying
            if node.name in CONSTANTS:
                return CONSTANTS[node.name], False
            return self.define_type(node), False
        if isinstance(node, Unary):
            type_, varying = self.type_of(node.operand)
            return ("bool" if node.op == "!" else type_), varying
        if isinstance(node, Binary):
            (a, va), (b, vb) = self.type_of(node.left), self.type_of(node.right)
            if node.op in COMPARISONS or node.op in ("&&", "||"):
                return "bool", va or vb
            if node.op in ("+", "-", "*", "/"):
                return widest(a, b), va or vb
            return a, va or vb
        if isinstance(node, Ternary):
            (_, vc), (a, va), (b, vb) = (self.type_of(n) for n in
                                         (node.condition, node.then, node.other))
            return (a if a in self.structs or a == b else widest(a, b)), vc or va or vb
        if isinstance(node, Cast):
            return CONVERSIONS.get(node.type, node.type), self.type_of(node.operand)[1]
        if isinstance(node, Member):
            base, varying = self.type_of(node.base)
            if base in self.structs:
                return self.field_type(base, node.field, node), True
            if base in VECTORS and len(node.field) <= 4:
                return ("real" if len(node.field) == 1 else f"vec{len(node.field)}"), varying
            raise SubsetError(f"line {node.line}: {base} has no member {node.field!r}")
        if isinstance(node, Index):
            if not (isinstance(node.base, Name) and node.base.name in BUFFERS):
                raise SubsetError(f"line {node.line}: only the parameter rows P[...] and "
                                  "U[...] can be indexed")
            return "vec4", self.type_of(node.index)[1]
        if isinstance(node, Call):
            return self.call_type(node)
        raise SubsetError(f"line {node.line}: not an expression")

    def call_type(self, node: Call) -> tuple:
        arguments = [self.type_of(a) for a in node.arguments]
        varying = any(v for _, v in arguments)
        name = node.function
        if name in self.functions:
            info = self.functions[name]
            if len(arguments) != len(info.parameters):
                raise SubsetError(f"line {node.line}: {name} takes {len(info.parameters)} "
                                  f"arguments, not {len(arguments)}")
            for parameter, (_, argument_varies) in zip(info.parameters, arguments):
                self.mark(parameter, "varying", argument_varies)
            return info.function.type, info.returns_varying
        if name in VECTORS:
            return name, varying
        if name in CONVERSIONS:
            return CONVERSIONS[name], varying
        if name in REAL_RESULT:
            return "real", varying
        if name in COMPONENTWISE:
            type_ = "bool"
            for argument, _ in arguments:
                type_ = widest(type_, argument)
            return type_, varying
        raise SubsetError(f"line {node.line}: unknown function {name!r}")

    def field_type(self, struct: str, name: str, node: Node) -> str:
        for type_, field_ in self.structs[struct]:
            if field_ == name:
                return type_
        raise SubsetError(f"line {node.line}: {struct} has no field {name!r}")

    def define_type(self, node: Name) -> str:
        """The type of a ``#define`` name, from its body (``P[5].x`` is a real)."""
        name = node.name
        if name not in self._define_types:
            if name not in self.defines:
                raise SubsetError(f"line {node.line}: unknown name {name!r}")
            body = parse_expression(self.defines[name].body, self.structs)
            self._define_types[name] = self.type_of(body)[0]
        return self._define_types[name]


def widest(a: str, b: str) -> str:
    """The type of ``a op b`` in arithmetic: the vector one, else the wider scalar."""
    return a if RANK.get(a, 9) >= RANK.get(b, 9) else b


class _Walk:
    """One pass over a function body: resolves names, marks what varies and diverges."""

    def __init__(self, analysis: Analysis, info: FunctionInfo):
        self.a, self.info = analysis, info

    def expression(self, node: Node, scopes: list) -> tuple:
        for inner in walk(node):
            if isinstance(inner, Name):
                for scope in reversed(scopes):
                    if inner.name in scope:
                        self.a.resolved[inner] = scope[inner.name]
                        break
            elif isinstance(inner, Call) and inner.function in self.a.functions:
                self.info.calls.add(inner.function)
        return self.a.type_of(node)

    def diverging(self, regions: list) -> bool:
        return any(node in self.a.divergent for node, _ in regions)

    def counter(self, node: For, scopes: list):
        """The variable that ``node`` counts with, if it is declared outside the loop, set by
        the loop's init and step alone, to values the same in every lane (``for (step = 1;
        ...; step++)``); None otherwise."""
        init, step = node.init, node.step
        if not (isinstance(init, Assign) and init.op == "=" and isinstance(init.target, Name)
                and isinstance(step, Assign) and isinstance(step.target, Name)
                and step.target.name == init.target.name and step.op in ("++", "--", "+=", "-=")):
            return None
        name = init.target.name
        if any(isinstance(n, Assign) and target_root(n.target).name == name
               for n in walk(node.body)):
            return None
        values = [init.value] + ([step.value] if step.value is not None else [])
        if any(self.expression(v, scopes)[1] for v in values):
            return None
        return next((scope[name] for scope in reversed(scopes) if name in scope), None)

    def block(self, block: Block, scopes: list, regions: list):
        scopes = scopes + [{}]
        for statement in block.statements:
            self.statement(statement, scopes, regions)

    def statement(self, node, scopes: list, regions: list):
        a = self.a
        if isinstance(node, Declare):
            variable = a.declared.get(node)
            if variable is None:
                variable = a.declared[node] = Variable(node.name, node.type, len(regions),
                                                       node.type in a.structs)
            if node.value is not None:
                a.mark(variable, "varying", self.expression(node.value, scopes)[1])
            scopes[-1][node.name] = variable
        elif isinstance(node, Assign):
            varies = self.expression(node.value, scopes)[1] if node.value is not None else False
            self.expression(node.target, scopes)
            root = target_root(node.target)
            if not isinstance(root, Name) or root not in a.resolved:
                raise SubsetError(f"line {node.line}: {self.info.function.name} assigns to "
                                  "something that is not a local or a parameter")
            variable = a.resolved[root]
            a.mark(variable, "varying", varies or self.diverging(regions[variable.depth:]))
        elif isinstance(node, Block):
            self.block(node, scopes, regions)
        elif isinstance(node, If):
            if self.expression(node.condition, scopes)[1]:
                a.diverge(node)
            self.block(node.then, scopes, regions + [(node, "then")])
            if node.other is not None:
                self.block(node.other, scopes, regions + [(node, "else")])
        elif isinstance(node, For):
            scopes = scopes + [{}]
            inside = regions + [(node, "loop")]
            if isinstance(node.init, Declare):      # its variable lives and dies with the loop
                self.statement(node.init, scopes, inside)
            elif node.init is not None:
                self.statement(node.init, scopes, regions)
            counter = self.counter(node, scopes)
            if counter is not None and node in a.divergent:
                # Inside the loop every lane still in it has the same count: a uniform copy
                # counts, and each lane keeps the count it left with (Karrenberg and Hack's
                # "result vectors" of loop live values, section 5).
                if node not in a.counters:
                    a.counters[node] = (counter, Variable(f"{counter.name}_loop", counter.type,
                                                          len(inside)))
                a.mark(counter, "varying")
                scopes[-1][counter.name] = a.counters[node][1]
            if node.condition is not None and self.expression(node.condition, scopes)[1]:
                a.diverge(node)
            self.block(node.body, scopes, inside)
            if node.step is not None:
                self.statement(node.step, scopes, inside)
        elif isinstance(node, (Break, Continue)):
            k = max((i for i, (n, _) in enumerate(regions) if isinstance(n, For)), default=None)
            if k is None:
                raise SubsetError(f"line {node.line}: {type(node).__name__.lower()} outside a loop")
            if self.diverging(regions[k + 1:]):
                a.diverge(regions[k][0])
        elif isinstance(node, Return):
            info = self.info
            if node.value is not None:
                a.mark(info, "returns_varying", self.expression(node.value, scopes)[1])
            if self.diverging(regions):
                a.mark(info, "returns_varying")
                a.mark(info, "divergent_returns")
                for region, _ in regions:
                    if isinstance(region, For):
                        a.diverge(region)


def reachable(program: Program, roots) -> set:
    """The functions of ``program`` that the ``roots`` call, directly or through others.

    A one-ray program may hold a function nothing calls (a library block the scene did not
    need after all); its packet form would be derived from no call at all, so it is left out.
    """
    functions = program.functions()
    found, todo = set(), [name for name in roots if name in functions]
    while todo:
        name = todo.pop()
        if name not in found:
            found.add(name)
            todo += [node.function for node in walk(functions[name].body)
                     if isinstance(node, Call) and node.function in functions]
    return found
