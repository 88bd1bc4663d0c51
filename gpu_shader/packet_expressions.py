"""How an expression of the one-ray program reads in its packet form (`gpu_shader.vectorise`).

A uniform expression (`gpu_shader.varying`) is written as it was. A varying one computes
the same operations lane by lane, spelled for OpenCL vectors:

- reals, integers and booleans become packets, with OpenCL's own operators; a boolean is a
  mask (-1 where true, 0 where false), so ``c ? a : b`` picks lane by lane;
- vectors become vec3p (three packets), their arithmetic and builtins calls of the
  overloads of glsl/packet.cl: ``p - a`` is ``sub(p, a)``, ``vec3(x, y, z)`` ``pack3(x, y,
  z)``; a uniform operand stays scalar where packet.cl has an overload for it, else is
  widened (``splat3``);
- conversions are OpenCL's ``convert_`` functions, ``pow`` is ``power`` (glsl/packet.cl
  says why), and a row of the parameters read with a varying index, ``U[24 + 4 * id]``, is a
  gather, one load per lane.
"""

from __future__ import annotations

import re
from functools import cache
from itertools import combinations

from .library import glsl_file
from .subset import (Assign, Binary, Call, Cast, Declare, Function, Index, Member, Name, Node,
                     Number, SubsetError, Ternary, Unary, format_expression, target_root, walk)
from .varying import COMPARISONS, VECTORS, Analysis, widest

PACKET_TYPES = {"real": "packet", "int": "ipacket", "uint": "upacket", "bool": "ipacket",
                "vec2": "vec2p", "vec3": "vec3p", "vec4": "vec4p"}
CONVERT = {"real": "convert_packet", "int": "convert_ipacket", "uint": "convert_upacket"}
OPERATORS = {"+": "add", "-": "sub", "*": "mul", "/": "div"}
# OpenCL builtins that take a scalar where a vector goes, at these argument positions.
SCALAR_ARGUMENTS = {"min": {1}, "max": {1}, "fmin": {1}, "fmax": {1}, "clamp": {1, 2},
                    "mix": {2}, "step": {0}, "smoothstep": {0, 1}}
# PoCL's pow over 8 or 16 doubles is wrong in some lanes: glsl/packet.cl, `power`.
RENAMED = {"pow": "power"}
SWIZZLE = {"r": "x", "g": "y", "b": "z", "a": "w"}
ALL_LANES = Cast("ipacket", Number("-1"))


@cache
def packet_overloads() -> dict:
    """Function name -> the argument types glsl/packet.cl defines it for."""
    found: dict = {}
    for m in re.finditer(r"^\w+\s+(?:OVERLOAD\s+)?(\w+)\(([^)]*)\)", glsl_file("packet.cl"),
                         re.M):
        types = tuple(p.split()[0] for p in m.group(2).split(",") if p.strip())
        found.setdefault(m.group(1), set()).add(types)
    return found


def packet_type(type_: str, varying: bool) -> str:
    return PACKET_TYPES.get(type_, type_) if varying else type_


def zero(type_: str) -> Node:
    """A zero of the packet type ``type_`` (a struct's or vector's is ``{0}``)."""
    if type_ in ("ipacket", "upacket"):
        return Number("0")
    return Number("0.0") if type_ == "packet" else Name("{0}")


def literal(node: Node) -> bool:
    """A number, or minus a number."""
    return isinstance(node, Number) or isinstance(node, Unary) and isinstance(node.operand, Number)


class ExpressionLowering:
    """Lowers the expressions of one function (`gpu_shader.vectorise` its statements)."""

    def __init__(self, analysis: Analysis, function: Function, gathered: set):
        self.a, self.function, self.gathered = analysis, function, gathered
        self.info = analysis.functions[function.name]
        self.regions: list = []          # (node, part) as in the analysis: what encloses us
        self.masks: list = []            # (kind, mask name, For node) from the outermost
        self.count = 0
        self.taken = {n.name for n in walk(function) if isinstance(n, Name)}
        self.taken |= {n.name for n in walk(function) if isinstance(n, Declare)}
        self.taken |= {name for _, name in function.parameters}
        self.hoisted: dict = {}          # index text -> name of the row read once

    def fresh(self, stem: str, numbered: bool = True) -> str:
        """A name the function does not use: ``then3``, ``looping4``, ``ret``..."""
        if numbered:
            self.count += 1
        name = f"{stem}{self.count}" if numbered else stem
        if name in self.taken:
            raise SubsetError(f"{self.function.name} uses the name {name!r}, which its packet "
                              "form needs for a mask or result")
        self.taken.add(name)
        return name

    def error(self, node: Node, what: str) -> SubsetError:
        return SubsetError(f"{self.function.name}, line {node.line}: {what}")

    def mask(self):
        """The current mask's name (None: every lane the function was called for)."""
        return self.masks[-1][1] if self.masks else None

    def mask_node(self) -> Node:
        return Name(self.mask()) if self.mask() else ALL_LANES

    def hoist_gathers(self) -> list:
        """Read once, at the top, each parameter row that the function gathers more than
        once with the same index (``MATERIAL(id, 1)`` in shade_phong): a gather is a load
        per lane. Only indices made of parameters it never assigns qualify."""
        assigned = set()
        for node in walk(self.function.body):
            if isinstance(node, Assign):
                assigned.add(target_root(node.target).name)
        parameters = {name for _, name in self.function.parameters} - assigned
        reads: dict = {}
        for node in walk(self.function.body):
            if isinstance(node, Index) and self.a.type_of(node.index)[1]:
                inner = list(walk(node.index))
                if all(isinstance(n, Number) or (isinstance(n, Name) and n.name in parameters)
                       or isinstance(n, Binary) for n in inner):
                    reads.setdefault(format_expression(node.index), []).append(node)
        lines = []
        for text, nodes in reads.items():
            if len(nodes) < 2:
                continue
            macro = nodes[0].macro
            stem = (macro[0].lower() + "_" + "_".join(format_expression(a) for a in macro[1])
                    if macro else "row")
            name = self.fresh(re.sub(r"\W+", "_", stem), numbered=macro is None)
            value, _, _ = self.gather(nodes[0])
            lines.append(Declare("vec4p", name, value, comment="// one gather for every use"))
            self.hoisted[text] = name
        return lines

    def select(self, mask: Node, a: Node, b: Node, type_: str) -> Node:
        """Lane by lane, ``a`` where ``mask`` is set and ``b`` elsewhere."""
        if type_ in ("real", "int", "uint", "bool"):
            return Ternary(mask, a, b)
        return Call("choose", [mask, a, b])

    def to_mask(self, node: Node, type_: str) -> Node:
        return node if type_ == "bool" else Binary("!=", node, Number("0"))

    def coerced(self, node: Node, type_: str, varying: bool) -> Node:
        """``node`` lowered and turned into a ``type_`` that varies as asked."""
        lowered, have, varies = self.expression(node)
        return self.convert(lowered, have, varies, type_, varying)

    def convert(self, node: Node, have: str, varies: bool, want: str, varying: bool) -> Node:
        if not varying or (varies and have == want) or want in self.a.structs:
            return node
        if have in VECTORS and have != want:
            raise SubsetError(f"{self.function.name}: cannot turn a {have} into a {want}")
        if varies:
            if want == "bool":
                return self.to_mask(node, have)
            if have == "bool":                       # a mask's -1 is C's true, 1
                node, have = Unary("-", node), "int"
            if want in VECTORS:
                return Call(f"splat{VECTORS[want]}", [self.convert(node, have, True, "real", True)])
            return Call(CONVERT[want], [node])
        if want == "bool":
            if isinstance(node, Name) and node.name in ("true", "false"):
                return Cast("ipacket", Number("-1" if node.name == "true" else "0"))
            return Ternary(node, Cast("ipacket", Number("-1")), Cast("ipacket", Number("0")))
        if want in VECTORS:
            if have != want:
                node = Call(want, [node])
            return Call(f"splat{VECTORS[want]}", [node])
        if have != want:
            node = Cast(want, node)
        return Cast(PACKET_TYPES[want], node)

    def expression(self, node: Node) -> tuple:
        """(lowered node, scalar type, varies?)."""
        type_, varies = self.a.type_of(node)
        lowered = self.lower(node, type_, varies)
        if node.macro is not None and not varies:     # written as the macro call it was
            lowered.macro = (node.macro[0], [self.expression(a)[0] for a in node.macro[1]])
        return lowered, type_, varies

    def lower(self, node: Node, type_: str, varies: bool) -> Node:
        if isinstance(node, Name):
            variable = self.a.resolved.get(node)       # a loop's own copy of its counter
            return Name(variable.name) if variable and variable.name != node.name else node
        if isinstance(node, Number):
            return node
        if isinstance(node, Unary):
            operand, _, _ = self.expression(node.operand)
            if varies and type_ in VECTORS and node.op == "-":
                return Call("neg", [operand])
            return Unary(node.op, operand)
        if isinstance(node, Binary):
            return self.binary(node, type_, varies)
        if isinstance(node, Ternary):
            condition, ctype, cvaries = self.expression(node.condition)
            then = self.coerced(node.then, type_, varies)
            other = self.coerced(node.other, type_, varies)
            if not cvaries:
                return Ternary(condition, then, other)
            return self.select(self.to_mask(condition, ctype), then, other, type_)
        if isinstance(node, Cast):
            return self.convert_call(node, [node.operand], node.type, type_, varies)
        if isinstance(node, Member):
            return self.member(node, varies)
        if isinstance(node, Index):
            if not varies:
                return Index(node.base, self.expression(node.index)[0])
            return self.gather(node)[0]
        if isinstance(node, Call):
            return self.call(node, type_, varies)
        raise self.error(node, f"cannot vectorise {type(node).__name__}")

    def binary(self, node: Binary, type_: str, varies: bool) -> Node:
        (left, a, va), (right, b, vb) = self.expression(node.left), self.expression(node.right)
        op = node.op
        if varies and type_ in VECTORS:
            if op not in OPERATORS:
                raise self.error(node, f"cannot vectorise {op!r} on vectors")
            return self.overloaded(OPERATORS[op], [(left, a, va), (right, b, vb)], node)
        if varies and op in ("&&", "||"):
            left, right = (self.to_mask(x, t) if v else x for x, t, v in
                           ((left, a, va), (right, b, vb)))
        elif varies and (op in OPERATORS or op in COMPARISONS):
            target = widest(a, b)
            left = self.convert(left, a, va, target, va) if va or a == "bool" else left
            right = self.convert(right, b, vb, target, vb) if vb or b == "bool" else right
            if a == "bool" and not va:
                left = self.convert(left, a, False, "bool", True)
            if b == "bool" and not vb:
                right = self.convert(right, b, False, "bool", True)
        return Binary(op, left, right)

    def member(self, node: Member, varies: bool) -> Node:
        base, type_, base_varies = self.expression(node.base)
        if type_ in self.a.structs or not base_varies:
            return Member(base, node.field)
        swizzle = "".join(SWIZZLE.get(c, c) for c in node.field)
        if swizzle == "xyzw"[:VECTORS[type_]]:
            return base
        if type_ == "vec4" and swizzle == "xyz":
            return Member(base, "xyz")                   # a vec4p is (xyz, w)
        parts = [Member(Member(base, "xyz"), c) if type_ == "vec4" and c != "w"
                 else Member(base, c) for c in swizzle]
        if len(parts) > 3:
            raise self.error(node, f"cannot vectorise the swizzle .{node.field}")
        return parts[0] if len(parts) == 1 else Call(f"pack{len(parts)}", parts)

    def gather(self, node: Index) -> tuple:
        """Row ``node.index`` of the parameters in each lane (a load per lane)."""
        text = format_expression(node.index)
        if text in self.hoisted:
            return Name(self.hoisted[text]), "vec4", True
        index = self.coerced(node.index, "int", True)
        macro = node.macro
        if macro is not None and macro[0] in self.gathered:
            call = Call("gather", [index])
            call.macro = (macro[0], [self.expression(a)[0] for a in macro[1]])
            return call, "vec4", True
        return Call("gather", [index]), "vec4", True

    def call(self, node: Call, type_: str, varies: bool) -> Node:
        name = node.function
        if name in self.a.functions:
            info = self.a.functions[name]
            arguments = [self.coerced(a, p.type, p.varying)
                         for a, p in zip(node.arguments, info.parameters)]
            if info.needs_live:
                arguments.append(self.mask_node())
            return Call(name, arguments)
        lowered = [self.expression(a) for a in node.arguments]
        if not varies:
            return Call(name, [x for x, _, _ in lowered])
        if name in VECTORS:
            return self.constructor(name, lowered, node)
        if name in ("int", "uint", "real", "bool", "float"):
            return self.convert_call(node, node.arguments, name, type_, varies)
        if type_ in VECTORS or any(t in VECTORS for _, t, _ in lowered):
            return self.overloaded(name, lowered, node)
        keep = SCALAR_ARGUMENTS.get(name, set()) if type_ == "real" else set()
        arguments = [x if (k in keep and not v) else self.convert(x, t, v, type_, True)
                     for k, (x, t, v) in enumerate(lowered)]
        return Call(RENAMED.get(name, name), arguments)

    def constructor(self, name: str, lowered: list, node: Node) -> Node:
        """``vec3(x, y, z)``, ``vec4(v, w)``, ``vec3(x)`` over packets: pack2/3/4, splat."""
        if len(lowered) == 1:
            return self.convert(*lowered[0], name, True)
        sizes = [VECTORS.get(t, 1) for _, t, _ in lowered]
        parts = [self.convert(x, t, v, "vec3" if t == "vec3" else "real", True)
                 for x, t, v in lowered]
        if name == "vec4" and sizes == [1, 1, 1, 1]:
            return Call("pack4", [Call("pack3", parts[:3]), parts[3]])
        if sizes == [1] * VECTORS[name] or (name == "vec4" and sizes == [3, 1]):
            return Call(f"pack{VECTORS[name]}", parts)
        raise self.error(node, f"cannot vectorise {name}() of parts of sizes {sizes}")

    def convert_call(self, node: Node, operands: list, name: str, type_: str,
                     varies: bool) -> Node:
        operand, have, operand_varies = self.expression(operands[0])
        if not varies:
            return Cast(name, operand) if isinstance(node, Cast) else Call(name, [operand])
        return self.convert(operand, have, operand_varies, type_, True)

    def overloaded(self, name: str, lowered: list, node: Node) -> Node:
        """A call of a glsl/packet.cl function over vectors (``add``, ``dot``, ...): its
        arguments as they are if packet.cl has that overload, else with the fewest uniform
        arguments turned into packets that make one it has."""
        known = packet_overloads().get(name, set())
        uniform = [k for k, (_, _, v) in enumerate(lowered) if not v]
        for count in range(len(uniform) + 1):
            for widened in combinations(uniform, count):
                kinds = tuple(packet_type(t, v or k in widened)
                              for k, (_, t, v) in enumerate(lowered))
                if kinds in known:
                    return Call(name, [self.convert(x, t, v, t, True) if k in widened else x
                                       for k, (x, t, v) in enumerate(lowered)])
        kinds = ", ".join(packet_type(t, v) for _, t, v in lowered)
        raise self.error(node, f"glsl/packet.cl has no {name}({kinds}); add that overload")


