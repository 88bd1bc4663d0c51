"""The packet form of a one-ray program, derived from it: whole-function vectorisation.

`gpu_shader.varying` finds which values differ from ray to ray. Here each function of the
one-ray program is rewritten for LANES rays at once, as ISPC runs an SPMD program on SIMD
units (Pharr and Mark, "ispc: A SPMD compiler for high-performance CPU programming", InPar
2012) and as Karrenberg and Hack's whole-function vectorisation does in a compiler (CGO
2011): a varying value becomes a vector with one lane per ray (glsl/packet.cl), a uniform
one stays scalar, and control flow that varies becomes masks:

- ``if (c)`` with a varying ``c``: a mask ``then1 = c`` of the lanes that take it (and
  ``else1`` of the others); inside, a variable declared outside is assigned only in its lanes,
  ``x = then1 ? new : x``; a branch with real work is skipped when no lane takes it;
- a loop that rays leave at different times: a mask ``looping1`` of the lanes still in it,
  and the loop runs while any lane is; ``break`` takes lanes out of it, ``continue`` out of
  the rest of the iteration (``iteration1``);
- ``return`` under varying control: the value goes into ``ret`` in the returning lanes,
  which leave every mask (``active`` holds the lanes still running the function);
- a function whose loops rays leave at different times, or that calls one, takes the mask
  ``live`` of the lanes its caller wants, so that no other lane is marched.

Each lane computes exactly the one-ray program's operations in the same order, so the two
programs agree to the bit (tests/opencl/test_packet_*.py). `vectorise` returns the rewritten
tree; `gpu_shader.subset.format_program` writes it.
"""

from __future__ import annotations

import re

from .packet_expressions import ALL_LANES, ExpressionLowering, literal, packet_type, zero
from .subset import (Assign, Binary, Blank, Block, Break, Call, Comment, Continue, Declare, Define,
                     For, Function, If, Index, Name, Node, Number, Program, Return, Unary,
                     target_root, walk)
from .varying import Analysis, reachable


def vectorise(program: Program, structs: dict, roots: dict, live_roots=()) -> tuple:
    """The packet form of ``program`` and its analysis.

    Parameters
    ----------
    program : subset.Program
        The one-ray program (defines and functions).
    structs : dict
        Struct name -> ((type, field), ...); every field becomes one value per lane.
    roots, live_roots
        As `gpu_shader.varying.Analysis`: how the packet program's own code calls in.

    Returns
    -------
    packet_program : subset.Program
    analysis : gpu_shader.varying.Analysis
    """
    analysis = Analysis(program, structs, roots, live_roots)
    gathered = _gathered_macros(program, analysis)
    called = reachable(program, roots)
    items, comments = [], []          # a function's leading comments go where it goes
    for item in program.items:
        if isinstance(item, Comment):
            comments.append(item)
            continue
        if isinstance(item, Function) and item.name not in called:
            comments = []             # the packet entry never reaches it: leave it out
            continue
        items += comments
        comments = []
        if isinstance(item, Function):
            items.append(_FunctionLowering(analysis, item, gathered).run())
        elif isinstance(item, Define) and item.name in gathered:
            body = re.sub(r"^[PU]\[(.*)\]$", r"gather(\1)", item.body)
            items.append(Define(item.name, item.parameters, body, f"#define {item.name}("
                                f"{', '.join(item.parameters)}) {body}"))
        else:
            items.append(item)
    return Program(items + comments), analysis



def _gathered_macros(program: Program, analysis: Analysis) -> set:
    """Function-like macros reading a parameter row (``MATERIAL(id, row)``) whose every use
    has a varying row, so that their packet form can read ``gather(...)``."""
    uses: dict = {}
    for function in program.functions().values():
        for node in walk(function.body):
            if isinstance(node, Index) and node.macro is not None:
                simple = all(isinstance(a, (Name, Number)) for a in node.macro[1])
                uses.setdefault(node.macro[0], []).append(
                    simple and analysis.type_of(node.index)[1])
    return {name for name, varying in uses.items() if all(varying)}


class _FunctionLowering(ExpressionLowering):
    """Rewrites one function into its packet form (see the module docstring)."""

    # --- the function ----------------------------------------------------------------------

    def run(self) -> Function:
        info, function = self.info, self.function
        parameters = [(packet_type(p.type, p.varying), p.name) for p in info.parameters]
        head = self.hoist_gathers()
        live = None
        if info.needs_live:
            parameters.append(("ipacket", self.fresh("live", numbered=False)))
            live = Name("live")
        self.result_type = packet_type(function.type, info.returns_varying)
        if info.divergent_returns:
            self.ret = self.fresh("ret", numbered=False)
            active = self.fresh("active", numbered=False)
            head += [Declare(self.result_type, self.ret, zero(self.result_type),
                             comment="// what each lane returns"),
                     Declare("ipacket", active, live or ALL_LANES,
                             comment="// the lanes that have not returned yet")]
            self.masks.append(("function", active, None))
        elif live is not None:
            self.masks.append(("function", "live", None))
        body = head + self.statements(function.body.statements)
        if info.divergent_returns and not isinstance(body[-1], Return):
            body.append(Return(Name(self.ret)))
        return Function(self.result_type, function.name, parameters, Block(body),
                        line=function.line)

    # --- statements ------------------------------------------------------------------------

    def statements(self, statements: list) -> list:
        out = []
        for k, statement in enumerate(statements):
            out += self.statement(statement)
            if isinstance(statement, (Break, Continue, Return)):
                break                            # the rest of the block is unreachable
            rest = statements[k + 1:]
            if statement in self.a.divergent and isinstance(statement, If) \
                    and _leaves(statement) and self.heavy(rest):
                return out + self.unless_every_lane_left(rest)
        return out

    def heavy(self, statements: list) -> bool:
        """Whether ``statements`` call a function of the program or loop: work worth an
        any() to skip when no lane is left."""
        return any(isinstance(n, For) or isinstance(n, Call) and n.function in self.a.functions
                   for s in statements for n in walk(s))

    def unless_every_lane_left(self, rest: list) -> list:
        """After a branch that some lanes left by (break, return), the ``rest`` of the block,
        skipped when no lane is left: the march and shading of a bounce that every ray
        of the packet has ended."""
        kind, mask, _ = self.masks[-1]
        left = Unary("!", Call("any", [Name(mask)]))
        if kind == "loop":
            stop = If(left, Block([Break()]), comment="// no lane is left in the loop")
            return [stop] + self.statements(rest)
        if kind == "function":
            stop = If(left, Block([Return(Name(self.ret))]), comment="// every lane has returned")
            return [stop] + self.statements(rest)
        return [If(Call("any", [Name(mask)]), Block(self.statements(rest)))]

    def block(self, block: Block) -> Block:
        return Block(self.statements(block.statements), comment=block.comment)

    def diverging(self, regions: list) -> bool:
        return any(node in self.a.divergent for node, _ in regions)

    def statement(self, node) -> list:
        if isinstance(node, Declare):
            variable = self.a.declared[node]
            type_ = packet_type(node.type, variable.varying)
            if node.value is None:
                value = zero(type_) if variable.varying else None
            elif variable.varying and node.type in ("real", "int", "uint") and literal(node.value):
                value = node.value               # OpenCL widens it to every lane
            else:
                value = self.coerced(node.value, node.type, variable.varying)
            return [Declare(type_, node.name, value, node.precise, comment=node.comment)]
        if isinstance(node, Assign):
            return [self.assignment(node)]
        if isinstance(node, Block):
            return [self.block(node)]
        if isinstance(node, If):
            return self.if_statement(node)
        if isinstance(node, For):
            return self.for_statement(node)
        if isinstance(node, (Break, Continue)):
            return self.loop_exit(node)
        if isinstance(node, Return):
            return self.return_statement(node)
        return [node]                            # comments, blank lines

    def masked(self, node: Assign) -> bool:
        """Whether an assignment here reaches only some of the lanes that share the
        variable: those of the current mask."""
        variable = self.a.resolved[target_root(node.target)]
        return self.diverging(self.regions[variable.depth:])

    def assignment(self, node: Assign) -> Assign:
        varying = self.a.resolved[target_root(node.target)].varying
        type_, _ = self.a.type_of(node.target)
        target, _, _ = self.expression(node.target)
        if node.value is None and not varying:
            return Assign(target, node.op, comment=node.comment)
        value = node.value
        if node.op != "=":
            one = Number("1")
            value = Binary(node.op[0], node.target, one if value is None else value,
                           line=node.line)
        masked = self.masked(node)
        if not masked and type_ in ("real", "int", "uint") and literal(value):
            return Assign(target, "=", value, comment=node.comment)   # widened to every lane
        value = self.coerced(value, type_, varying)
        if masked:
            value = self.select(Name(self.mask()), value, target, type_)
        return Assign(target, "=", value, comment=node.comment)

    def if_statement(self, node: If) -> list:
        condition, _, _ = self.expression(node.condition)
        if node not in self.a.divergent:
            then = self.branch(node, "then", node.then)
            other = self.branch(node, "else", node.other) if node.other else None
            return [If(condition, Block(then), other and Block(other), comment=node.comment)]
        outer = self.mask()
        taken = self.to_mask(condition, self.a.type_of(node.condition)[0])
        leaving = self.only_leaves(node)
        if leaving is not None:
            return leaving(taken)
        then, out = self.fresh("then"), []
        out.append(Declare("ipacket", then, _and(outer, taken),
                           comment=node.comment or "// the lanes that take the if"))
        if node.other is not None:
            other = self.fresh("else" + then[len("then"):], numbered=False)
            out.append(Declare("ipacket", other, _and(outer, Unary("~", Name(then))),
                               comment="// the lanes that take the else"))
        for mask, part, block in ((then, "then", node.then), (node.other and other, "else",
                                                              node.other)):
            if block is None:
                continue
            self.masks.append(("if", mask, None))
            statements = self.branch(node, part, block)
            self.masks.pop()
            out += self.guarded(mask, statements)
        return out

    def only_leaves(self, node: If):
        """For ``if (c) break;`` (or continue) where the loop's mask is the current one: a
        function writing ``looping = looping & ~(c)``, the lanes leaving without a mask of
        their own (as a hand-written packet loop would); None for any other if."""
        statements = [s for s in node.then.statements if not isinstance(s, (Comment, Blank))]
        if node.other is not None or len(statements) != 1 or \
                not isinstance(statements[0], (Break, Continue)):
            return None
        kind = "loop" if isinstance(statements[0], Break) else "body"
        if not self.masks or self.masks[-1][0] != kind:
            return None
        mask = self.masks[-1][1]
        word = "break" if kind == "loop" else "continue"
        comment = (statements[0].comment or node.comment
                   or f"// {word}: these lanes leave the "
                      f"{'loop' if kind == 'loop' else 'iteration'}")
        return lambda taken: [Assign(Name(mask), "=", _and(mask, Unary("~", taken)),
                                     comment=comment)]

    def guarded(self, mask: str, statements: list) -> list:
        """A masked branch: skipped when no lane takes it if it calls a function of the
        program or loops, kept in its own block if it declares, else inline (a few selects
        cost less than the test)."""
        if self.heavy(statements):
            return [If(Call("any", [Name(mask)]), Block(statements))]
        if any(isinstance(n, Declare) for s in statements for n in walk(s)):
            return [Block(statements)]
        return statements

    def branch(self, node: Node, part: str, block: Block) -> list:
        self.regions.append((node, part))
        statements = self.statements(block.statements)
        self.regions.pop()
        return statements

    def for_statement(self, node: For) -> list:
        inside = (node, "loop")
        if node not in self.a.divergent:
            self.regions.append(inside)
            init = node.init and self.statement(node.init)[0]
            condition = node.condition and self.expression(node.condition)[0]
            body = self.block(node.body)
            step = node.step and self.statement(node.step)[0]
            self.regions.pop()
            return [For(init, condition, step, body, comment=node.comment)]
        looping = self.fresh("looping")
        out = [Declare("ipacket", looping, self.mask_node(),
                       comment="// the lanes still in the loop")]
        if isinstance(node.init, Declare):
            self.regions.append(inside)
        init = node.init and self.statement(node.init)[0]
        if not isinstance(node.init, Declare):
            self.regions.append(inside)
        body, kept = [], []
        if node in self.a.counters:
            before, init, kept = self.counting(node, init, looping)
            out, body = before + out, kept[:1]
        self.masks.append(("loop", looping, node))
        header = Call("any", [Name(looping)])
        if node.condition is not None:
            condition, type_, varies = self.expression(node.condition)
            if varies:
                body += [Assign(Name(looping), "=", _and(looping, self.to_mask(condition, type_)),
                                comment="// the lanes whose loop condition holds"),
                         If(Unary("!", header), Block([Break()]))]
                header = None
            else:
                header = Binary("&&", condition, header)
        if any(isinstance(n, Continue) for n in _own_statements(node.body)):
            iteration = self.fresh("iteration" + looping[len("looping"):], numbered=False)
            body.append(Declare("ipacket", iteration, Name(looping),
                                comment="// the lanes going through this iteration"))
            self.masks.append(("body", iteration, node))
        body += self.statements(node.body.statements)
        if self.masks[-1][0] == "body":
            self.masks.pop()
        step = None
        if node.step is not None:
            step = self.statement(node.step)[0]
            if self.masked(node.step):
                body.append(step)                # per lane, at the end of the iteration
                step = None
        self.masks.pop()
        self.regions.pop()
        return out + [For(init, header, step, Block(body), comment=node.comment)] + kept[1:]

    def counting(self, node: For, init: Assign, looping: str) -> tuple:
        """A loop that counts with a variable read after it (``step`` of the march): every
        lane starts the count (``init``), a uniform copy counts in the loop, and each lane
        keeps the count it had when it left (Karrenberg and Hack's result vectors).

        Returns the statements before the loop, the loop's own init, and the two that keep
        each lane's count: at the top of the loop body, and after the loop."""
        lanes, count = self.a.counters[node]
        self.fresh(count.name, numbered=False)
        uniform = self.convert(Name(count.name), lanes.type, False, lanes.type, True)
        keep = lambda comment: Assign(Name(lanes.name), "=", self.select(  # noqa: E731
            Name(looping), uniform, Name(lanes.name), lanes.type), comment=comment)
        return ([init, Declare(count.type, count.name)],
                Assign(Name(count.name), "=", self.expression(node.init.value)[0]),
                [keep(f"// each lane's {lanes.name}: the loop's, while in it"),
                 keep("// the lanes that the loop's condition let out")])

    def loop_exit(self, node) -> list:
        loops = [i for i, (kind, _, _) in enumerate(self.masks) if kind == "loop"]
        loop = next((n for n, part in reversed(self.regions) if part == "loop"), None)
        if loop not in self.a.divergent:
            return [node]
        start = loops[-1]
        if isinstance(node, Continue):
            start = next(i for i, (kind, _, n) in enumerate(self.masks)
                         if kind == "body" and n is loop)
        word = "break" if isinstance(node, Break) else "continue"
        return self.leave(start, node.comment or f"// {word}: these lanes leave the "
                          + ("loop" if word == "break" else "iteration"))

    def leave(self, start: int, comment: str) -> list:
        """Take the current mask's lanes out of the masks from ``start`` on (outermost
        first, so that the current mask is read before it is cleared)."""
        leaving = self.mask()
        out = []
        for kind, mask, _ in self.masks[start:]:
            if kind == "if" and mask == leaving:
                continue                         # the branch ends here
            out.append(Assign(Name(mask), "=", _and(mask, Unary("~", Name(leaving)))))
        if out:
            out[0].comment = comment
        return out

    def return_statement(self, node: Return) -> list:
        value = None
        if node.value is not None:
            value = self.coerced(node.value, self.function.type, self.info.returns_varying)
        if not self.info.divergent_returns:
            return [Return(value, comment=node.comment)]
        ret = Name(self.ret)
        if not self.diverging(self.regions):
            value = self.select(Name(self.mask()), value, ret, self.function.type)
            return [Return(value, comment=node.comment)]
        out = [Assign(ret, "=", self.select(Name(self.mask()), value, ret, self.function.type),
                      comment=node.comment or "// return: these lanes are done")]
        return out + self.leave(0, "")


def _and(mask, node: Node) -> Node:
    """``mask & node``, or ``node`` where there is no mask (every lane)."""
    return node if mask is None else Binary("&", Name(mask), node)


def _leaves(node: If) -> bool:
    """Whether lanes may leave by ``node``: a return in it, or a break or continue of the
    loop around it."""
    blocks = [node.then] + ([node.other] if node.other is not None else [])
    return any(isinstance(n, Return) for n in walk(node)) or any(
        isinstance(n, (Break, Continue)) for b in blocks for n in _own_statements(b))


def _own_statements(block: Block):
    """The statements of a loop body that belong to that loop (not to a nested loop)."""
    for statement in block.statements:
        yield statement
        if isinstance(statement, If):
            yield from _own_statements(statement.then)
            if statement.other is not None:
                yield from _own_statements(statement.other)
        elif isinstance(statement, Block):
            yield from _own_statements(statement)
