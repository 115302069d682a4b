"""The restricted expression language of problem files (Optimica-like), parsed into CasADi SX.

Problem files declare objectives and constraints as strings, e.g.::

    objective = "final_time + w * integral(tau1^2 + tau2^2 + tau3^2)"
    constraints = ["abs(qd1) <= 1.0", "x(final_time) == 0.3", "-0.5 <= xd <= 0.5"]

The text is parsed with :func:`ast.parse` (``mode="eval"``) and the tree is walked over
a whitelist of node kinds (numbers, names, ``+ - * /``, ``^``/``**`` for powers, unary
``-``/``+``, calls of the functions in :data:`FUNCTIONS`, the comparisons ``<=``, ``>=``,
``==``). Nothing is ever evaluated as Python code. ``^`` is rewritten to ``**`` before
parsing, so it binds like a power (``a + b^2`` is ``a + (b^2)``). The language reference
is ``docs/problem_language.md``; :mod:`gtmodel.modeling.ocp.declare` declares the parsed
objective and constraints on an :class:`~gtmodel.modeling.Optimization`.

Every error is a :class:`~gtmodel.errors.ProblemError` whose message has the form
``<origin>: field '<key>': <what> at column <c>: '<token>'`` (columns count characters
from 1; newlines in the text count as one character), followed by the text and a caret.
"""

from __future__ import annotations

import ast
import math
import re
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass
from typing import Any

import casadi as ca

from gtmodel.errors import GtModelError, InputError, ProblemError
from gtmodel.modeling.ocp.suggestions import close_names

__all__ = [
    "FUNCTIONS",
    "TIME_POINTS",
    "Objective",
    "ParsedConstraint",
    "parse_expression",
    "parse_objective",
    "parse_constraint",
]


_Fn = Callable[..., ca.SX]
#: Whitelisted functions: name -> (minimum, maximum number of arguments (None: any), CasADi function).
_FUNCS: dict[str, tuple[int, int | None, _Fn]] = {
    "abs": (1, 1, ca.fabs),
    "sqrt": (1, 1, ca.sqrt),
    "exp": (1, 1, ca.exp),
    "log": (1, 1, ca.log),
    "sin": (1, 1, ca.sin),
    "cos": (1, 1, ca.cos),
    "tan": (1, 1, ca.tan),
    "asin": (1, 1, ca.asin),
    "acos": (1, 1, ca.acos),
    "atan": (1, 1, ca.atan),
    "atan2": (2, 2, ca.atan2),
    "sinh": (1, 1, ca.sinh),
    "cosh": (1, 1, ca.cosh),
    "tanh": (1, 1, ca.tanh),
    "min": (2, None, ca.fmin),
    "max": (2, None, ca.fmax),
}
#: Names of the functions callable in expressions (``integral`` only in objectives).
FUNCTIONS: tuple[str, ...] = (*_FUNCS, "integral")
#: Time-point names: ``v(final_time)`` / ``v(start_time)`` evaluates variable ``v`` there.
TIME_POINTS: dict[str, str] = {"start_time": "start", "final_time": "final"}
_CONSTANTS = {"pi": math.pi}
_ALWAYS_STATIC = frozenset(TIME_POINTS)
_OPS: dict[type, str] = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**"}
_CMP: dict[type, str] = {ast.LtE: "<=", ast.GtE: ">=", ast.Eq: "=="}
_FORBIDDEN: dict[type, str] = {
    ast.Attribute: "attribute access is not allowed",
    ast.Subscript: "indexing is not allowed; use the scalar names",
    ast.BoolOp: "boolean operators are not allowed; write one constraint per condition",
    ast.Lambda: "lambda is not allowed",
    ast.IfExp: "conditional expressions are not allowed",
    ast.NamedExpr: "assignment is not allowed",
    ast.JoinedStr: "strings are not allowed",
    ast.Starred: "unpacking is not allowed",
    ast.Tuple: "tuples are not allowed",
    ast.List: "lists are not allowed",
}
_TOKEN_RE = re.compile(r"[A-Za-z_]\w*|\d+\.?\d*(?:[eE][-+]?\d+)?|\.\d+|\*\*|<=|>=|==|!=|\S")


@dataclass
class Objective:
    """An objective split into its Mayer and Lagrange parts (``mayer + integral(lagrange)``).

    Parameters
    ----------
    mayer : casadi.SX
        Scalar evaluated at the final time; point-evaluated variables ``v(final_time)``
        appear as the symbol ``v`` itself (as :meth:`Optimization.set_objective` expects).
    lagrange : casadi.SX
        Scalar integrand over ``[start_time, final_time]``; ``0`` without ``integral()``.
    text : str
        The source text.
    """

    mayer: ca.SX
    lagrange: ca.SX
    text: str = ""


@dataclass
class ParsedConstraint:
    """A parsed constraint ``lb <= expr <= ub``.

    Parameters
    ----------
    expr : casadi.SX
        Scalar expression; point-evaluated variables ``v(final_time)`` appear as ``v``.
    lb, ub : float
        Bounds (``-inf``/``inf`` when absent; equal for ``==``).
    at : str or None
        ``None`` for a path constraint, ``"start"`` or ``"final"`` for a point constraint,
        ``"timed"`` for a constraint on timed variables and integrals (``expr`` holds
        their symbols).
    text : str
        The source text.
    name : str
        Label for messages (the field key, or the text when no key was given).
    """

    expr: ca.SX
    lb: float
    ub: float
    at: str | None
    text: str
    name: str = ""


#: Callbacks of timed variables and integrals: ``timed(expr, time)`` with ``time`` a
#: static SX (or ``"start"``/``"final"``) and ``integral(expr)``, each returning a symbol
#: (:meth:`Optimization.timed`, :meth:`Optimization.integral`).
Specials = tuple[Callable[[ca.SX, Any], ca.SX], Callable[[ca.SX], ca.SX]]


class _Parser:
    """Walks the whitelisted AST of one text; ``mode`` selects what the context allows."""

    def __init__(
        self, text: Any, names: Mapping[str, Any], static: Collection[str] | None, origin: str, key: str,
        specials: Specials | None = None,
    ) -> None:
        self.origin, self.key = str(origin), str(key)
        self.specials = specials
        self.timed_mode = False  # second pass of a constraint: time points and integrals as symbols
        self.needs_timed = False  # first pass found what only timed variables / integrals can express
        self.point_ats: set[str] = set()
        if not isinstance(text, str):
            raise self.fail(f"expected an expression string, got {type(text).__name__}")
        self.text = text.replace("\r", " ").replace("\n", " ").replace("\t", " ")
        self.names = _table(names)
        if static is None:
            static = [n for n, v in self.names.items() if not ca.symvar(v)]
        self.static = frozenset(static) | _ALWAYS_STATIC
        self.mode = "expression"
        self.at: str | None = None
        self.at_node: ast.AST | None = None
        self.bare: list[ast.Name] = []  # time-varying names used without a time point
        self.inside: list[str] = []  # enclosing calls, for messages
        stripped = self.text.lstrip()
        self.lead = len(self.text) - len(stripped)
        self.carets = [i for i, c in enumerate(stripped) if c == "^"]
        self.source = stripped.replace("^", "**")

    # ------------------------------------------------------------------ positions and errors
    def _orig(self, j: int) -> int:
        """Character index in the transformed source -> index in the original text."""
        return self.lead + j - sum(1 for k, p in enumerate(self.carets) if p + k + 1 <= j)

    def _char(self, byte_col: int) -> int:
        return len(self.source.encode()[:byte_col].decode("utf-8", errors="ignore"))

    def span(self, node: ast.AST) -> tuple[int, int]:
        """Original ``[start, end)`` character indices of a node."""
        a = self._orig(self._char(node.col_offset))  # type: ignore[attr-defined]
        end = getattr(node, "end_col_offset", None)
        b = self._orig(self._char(end) - 1) + 1 if end is not None else a + 1
        return a, max(b, a + 1)

    def op_span(self, left: ast.AST, right: ast.AST) -> tuple[int, int]:
        """Span of the operator between two operands (parentheses skipped)."""
        a, b = self.span(left)[1], self.span(right)[0]
        seg = self.text[a:b]
        m = re.search(r"[^\s()]+", seg)
        return (a + m.start(), a + m.end()) if m else (a, b)

    def fail(self, what: str, where: ast.AST | tuple[int, int] | None = None, hint: str = "") -> ProblemError:
        """Build the error ``<origin>: field '<key>': <what> at column <c>: '<token>'``."""
        prefix = (f"{self.origin}: " if self.origin else "") + (f"field '{self.key}': " if self.key else "")
        if where is None:
            return ProblemError(prefix + what + (f"; {hint}" if hint else ""))
        a, b = self.span(where) if isinstance(where, ast.AST) else where
        msg = f"{prefix}{what} at column {a + 1}: '{self.text[a:b]}'" + (f"; {hint}" if hint else "")
        return ProblemError(f"{msg}\n    {self.text}\n    {' ' * a}^")

    # ------------------------------------------------------------------ parsing
    def tree(self) -> ast.expr:
        if not self.source.strip():
            raise self.fail("empty expression")
        try:
            return ast.parse(self.source, mode="eval").body
        except SyntaxError as exc:
            off = exc.offset or 0
            j = off - 1 if (exc.lineno or 1) == 1 and 1 <= off <= len(self.source) else len(self.source)
            a = self._orig(j) if j < len(self.source) else len(self.text)
            m = _TOKEN_RE.match(self.text, a) or _TOKEN_RE.search(self.text, a)
            if m is None:
                end = len(self.text)
                raise self.fail("syntax error (unexpected end of expression)", (end, end)) from None
            what = f"syntax error ({exc.msg})"
            hint = "use == for equality" if m.group() == "=" else ""
            raise self.fail(what, (m.start(), m.end()), hint) from None

    def ev(self, node: ast.AST) -> ca.SX:
        """Evaluate a node to a scalar SX."""
        if isinstance(node, ast.Constant):
            v = node.value
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                what = "string constants are not allowed" if isinstance(v, (str, bytes)) else (
                    f"constant of type {type(v).__name__} is not allowed")
                raise self.fail(what, node)
            if not math.isfinite(float(v)):
                raise self.fail("number is not finite", node)
            return ca.SX(float(v))
        if isinstance(node, ast.Name):
            return self.name(node)
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            x = self.ev(node.operand)
            return -x if isinstance(node.op, ast.USub) else x
        if isinstance(node, ast.BinOp):
            if type(node.op) not in _OPS:
                raise self.fail("operator is not allowed (use + - * / ^)", self.op_span(node.left, node.right))
            a, b = self.ev(node.left), self.ev(node.right)
            if isinstance(node.op, ast.Div) and b.is_constant() and float(ca.DM(b)) == 0.0:
                raise self.fail("division by zero", node.right)
            if isinstance(node.op, ast.Add):
                return a + b
            if isinstance(node.op, ast.Sub):
                return a - b
            if isinstance(node.op, ast.Mult):
                return a * b
            return a / b if isinstance(node.op, ast.Div) else a**b
        if isinstance(node, ast.Call):
            return self.call(node)
        if isinstance(node, ast.Compare):
            if self.mode == "constraint":
                raise self.fail("a comparison is only allowed at the top of a constraint", node)
            raise self.fail("comparisons are only allowed in constraints", node)
        if isinstance(node, ast.UnaryOp):
            raise self.fail("unary operator is not allowed (use -)", node)
        for kind, what in _FORBIDDEN.items():
            if isinstance(node, kind):
                raise self.fail(what, node)
        raise self.fail(f"{type(node).__name__.lower()} is not allowed", node)

    def name(self, node: ast.Name) -> ca.SX:
        n = node.id
        if n in self.names:
            val = self.names[n]
        elif n in _CONSTANTS:
            return ca.SX(_CONSTANTS[n])
        else:
            raise self.undefined(node, "name")
        if val.numel() != 1:
            raise self.fail(f"'{n}' has {val.numel()} elements, only scalars are allowed", node,
                            "use the scalar names of its elements")
        if n not in self.static:
            if self.mode == "mayer":
                hint = "use final_time" if n == "time" else f"write {n}(final_time) for its final value"
                raise self.fail(f"'{n}' varies in time and is outside integral()", node, hint)
            if self.mode == "factor":
                raise self.fail("a factor of integral() must be constant in time (numbers, parameters, "
                                "final_time)", node)
            if self.mode == "when":
                raise self.fail("the time of a time point must be constant (numbers, parameters, start_time, "
                                "final_time)", node)
            if self.mode != "integrand":
                self.bare.append(node)
        return val

    def undefined(self, node: ast.AST, what: str) -> ProblemError:
        n = node.id if isinstance(node, ast.Name) else "?"
        close = close_names(n, set(self.names) | set(FUNCTIONS) | set(_CONSTANTS))
        hint = ("did you mean " + ", ".join(f"'{c}'" for c in close) + "?") if close else (
            "known names: " + ", ".join(sorted(self.names)[:30]) + ("..." if len(self.names) > 30 else ""))
        return self.fail(f"undefined {what}", node, hint)

    def call(self, node: ast.Call) -> ca.SX:
        f = node.func
        if not isinstance(f, ast.Name):
            raise self.fail("only named functions can be called", f)
        if node.keywords:
            raise self.fail("keyword arguments are not allowed", node.keywords[0].value)
        if f.id == "integral":
            if self.specials is not None and self.mode == "constraint":
                return self.constraint_integral(node, f)
            raise self.integral_misplaced(f)
        if f.id in _FUNCS:
            lo, hi, fn = _FUNCS[f.id]
            n = len(node.args)
            if n < lo or (hi is not None and n > hi):
                want = f"{lo}" if lo == hi else f"at least {lo}"
                raise self.fail(f"{f.id}() takes {want} argument{'s' if lo != 1 else ''}, got {n}", node)
            self.inside.append(f.id)
            try:
                args = [self.ev(a) for a in node.args]
            finally:
                self.inside.pop()
            out = args[0]
            if hi is None:
                for a in args[1:]:
                    out = fn(out, a)
                return out
            return fn(*args)
        if f.id in self.names:
            return self.time_point(node, f)
        point = len(node.args) == 1 and (self.specials is not None or (
            isinstance(node.args[0], ast.Name) and node.args[0].id in TIME_POINTS))
        raise self.undefined(f, "name" if point else "function")

    def constraint_integral(self, node: ast.Call, f: ast.Name) -> ca.SX:
        """``integral(f)`` in a constraint: a symbol of the integral (isoperimetric constraint)."""
        if len(node.args) != 1 or node.keywords:
            raise self.fail(f"integral() takes 1 argument, got {len(node.args)}", node)
        if self.inside:
            raise self.fail(f"integral() inside {self.inside[-1]}() is not allowed in a constraint", f)
        integrand = self.scalar(node.args[0], "integrand")
        self.needs_timed = True
        if not self.timed_mode:
            return ca.SX(0)
        return self.special(lambda: self.specials[1](integrand), node)  # type: ignore[index]

    def special(self, fn: Callable[[], ca.SX], node: ast.AST) -> ca.SX:
        """Call a timed-variable/integral callback, its error placed at ``node``."""
        try:
            return fn()
        except GtModelError as exc:
            raise self.fail(str(exc).split("\n")[0], node) from None

    def integral_misplaced(self, f: ast.Name) -> ProblemError:
        if self.mode in ("mayer", "factor") and self.inside:
            return self.fail(
                f"integral() inside {self.inside[-1]}() is not allowed", f,
                "integral() must be a term of the objective, optionally times a constant or parameter")
        if self.mode in ("mayer", "factor"):
            return self.fail("integral() must be a term of the objective, optionally multiplied or "
                             "divided by a constant or parameter", f)
        if self.mode == "integrand":
            return self.fail("nested integral() is not allowed", f)
        where = "the objective" if self.specials is None else "the objective and constraints"
        return self.fail(f"integral() is only allowed in {where}", f)

    def time_point(self, node: ast.Call, f: ast.Name) -> ca.SX:
        n = f.id
        if len(node.args) != 1 or node.keywords:
            raise self.fail(f"a time point takes one time, as {n}(final_time) or {n}(2.5)", node)
        arg = node.args[0]
        named = isinstance(arg, ast.Name) and arg.id in TIME_POINTS
        if not named and self.specials is None:
            raise self.fail(f"a variable can only be evaluated at final_time or start_time, as "
                            f"{n}(final_time)", node)
        if n in self.static or n == "time":
            raise self.fail(f"'{n}' does not vary in time, write it without a time point", node,
                            "use final_time / start_time" if n == "time" else "")
        if self.mode in ("expression", "integrand", "factor", "when"):
            where = {"expression": "in this expression", "integrand": "inside integral()",
                     "factor": "in a factor of integral()", "when": "in the time of a time point"}[self.mode]
            raise self.fail(f"time-point evaluation is not allowed {where}", node)
        val = self.names[n]
        if val.numel() != 1:
            raise self.fail(f"'{n}' has {val.numel()} elements, only scalars are allowed", f,
                            "use the scalar names of its elements")
        when: Any = TIME_POINTS[arg.id] if named else self.scalar(arg, "when")
        if self.specials is not None and (self.timed_mode or (self.mode == "mayer" and when != "final")):
            return self.special(lambda: self.specials[0](val, when), node)  # type: ignore[index]
        at = when if named else "timed"
        if self.mode == "mayer" and at != "final":
            raise self.fail("the objective can evaluate variables at final_time only", node)
        if self.specials is not None:
            self.point_ats.add(at)
            self.needs_timed = self.needs_timed or at == "timed" or len(self.point_ats) > 1
            if self.needs_timed:
                return val
        if self.at is not None and self.at != at:
            a = self.span(self.at_node)[0] + 1 if self.at_node is not None else 0
            raise self.fail(f"mixes start_time and final_time (first time point at column {a})", node,
                            "write one constraint per time point")
        self.at, self.at_node = at, node
        return val

    def guarded(self, fn: Callable[[], Any]) -> Any:
        """Run ``fn``, turning Python's recursion limit into a ProblemError."""
        try:
            return fn()
        except RecursionError:
            raise self.fail("expression is too deeply nested") from None

    def scalar(self, node: ast.AST, mode: str) -> ca.SX:
        saved, self.mode = self.mode, mode
        try:
            out = self.ev(node)
        finally:
            self.mode = saved
        if out.numel() != 1:  # unreachable while every name is scalar; kept for safety
            raise self.fail(f"expression has {out.numel()} elements, expected a scalar", node)
        return out

    # ------------------------------------------------------------------ objective split
    def split(self, node: ast.AST) -> tuple[ca.SX, ca.SX]:
        """``(mayer, lagrange)`` of an objective term; integral() only along + - * / chains."""
        if not _has_integral(node):
            return self.scalar(node, "mayer"), ca.SX(0)
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            m, l = self.split(node.operand)
            return (-m, -l) if isinstance(node.op, ast.USub) else (m, l)
        if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub)):
            (m1, l1), (m2, l2) = self.split(node.left), self.split(node.right)
            return (m1 + m2, l1 + l2) if isinstance(node.op, ast.Add) else (m1 - m2, l1 - l2)
        if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Mult, ast.Div)):
            li, ri = _has_integral(node.left), _has_integral(node.right)
            if li and ri:
                raise self.fail("a product or ratio of integral() terms is not allowed",
                                self.op_span(node.left, node.right))
            if ri and isinstance(node.op, ast.Div):
                raise self.fail("integral() in a denominator is not allowed", node.right)
            term, factor = (node.left, node.right) if li else (node.right, node.left)
            c = self.scalar(factor, "factor")
            m, l = self.split(term)
            return (m * c, l * c) if isinstance(node.op, ast.Mult) else (m / c, l / c)
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "integral":
            if len(node.args) != 1 or node.keywords:
                raise self.fail(f"integral() takes 1 argument, got {len(node.args)}", node)
            return ca.SX(0), self.scalar(node.args[0], "integrand")
        return self.scalar(node, "mayer"), ca.SX(0)  # raises at the misplaced integral()


def _has_integral(node: ast.AST) -> bool:
    return any(
        isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id == "integral"
        for n in ast.walk(node)
    )


def _table(names: Mapping[str, Any]) -> dict[str, ca.SX]:
    if not isinstance(names, Mapping):
        raise InputError(f"names must be a mapping of str to casadi.SX or float, got {type(names).__name__}")
    out = {}
    for k, v in names.items():
        if not isinstance(k, str) or not k.isidentifier():
            raise InputError(f"names: key {k!r} is not an identifier")
        try:
            out[k] = v if isinstance(v, ca.SX) else ca.SX(float(v) if isinstance(v, (int, float)) else ca.DM(v))
        except Exception as exc:  # noqa: BLE001 - casadi raises NotImplementedError/TypeError
            raise InputError(f"names[{k!r}]: cannot convert {type(v).__name__} to casadi.SX") from exc
    return out


def _const(e: ca.SX) -> float | None:
    return float(ca.DM(ca.evalf(e))) if not ca.symvar(e) else None


def parse_expression(
    text: str, names: Mapping[str, Any], origin: str = "", key: str = "", static: Collection[str] | None = None
) -> ca.SX:
    """Parse a scalar expression (no comparison, no ``integral()``, no time points).

    Parameters
    ----------
    text : str
        Expression, e.g. ``"sqrt(xd^2 + yd^2 + zd^2)"``.
    names : mapping of str to casadi.SX or float
        Name table; every value must be scalar where it is used.
    origin : str, optional
        File path (or other origin) for messages.
    key : str, optional
        Field key for messages, e.g. ``"constraints[2]"``.
    static : collection of str, optional
        Names constant in time (parameters); default the names whose value has no
        symbols. ``final_time`` and ``start_time`` are always static.

    Returns
    -------
    casadi.SX
        Scalar (1x1) expression.

    Raises
    ------
    ProblemError
        On syntax errors, forbidden constructs, undefined names or non-scalar names.
    InputError
        If ``names`` is not a mapping of identifiers to SX-convertible values.
    """
    p = _Parser(text, names, static, origin, key)
    return p.guarded(lambda: p.scalar(p.tree(), "expression"))


def parse_objective(
    text: str, names: Mapping[str, Any], origin: str = "", key: str = "objective",
    static: Collection[str] | None = None, specials: Specials | None = None,
) -> Objective:
    """Parse an objective and split it into Mayer and Lagrange parts.

    ``a + w*integral(f) - integral(g)/c`` gives ``mayer = a`` and
    ``lagrange = w*f - g/c``. ``integral()`` may appear only along chains of ``+ - * /``
    from the top, multiplied or divided by factors constant in time (numbers, static
    names, ``final_time``). Outside ``integral()`` time-varying names must be written
    ``v(final_time)``; with ``specials``, also ``v(start_time)`` or ``v(t)`` at a fixed
    time ``t`` (timed variables in the Mayer term).

    Parameters
    ----------
    text : str
        Objective, e.g. ``"final_time + w * integral(tau1^2 + tau2^2)"``.
    names : mapping of str to casadi.SX or float
        Name table (see :func:`parse_expression`).
    origin : str, optional
        File path for messages.
    key : str, optional
        Field key for messages; default ``"objective"``.
    static : collection of str, optional
        Names constant in time (see :func:`parse_expression`).
    specials : tuple of callable, optional
        ``(timed, integral)`` callbacks (e.g. :meth:`Optimization.timed` and
        :meth:`Optimization.integral`); without them only ``v(final_time)`` is accepted.

    Returns
    -------
    Objective
        Mayer term and Lagrange integrand (both scalar SX).

    Raises
    ------
    ProblemError
        On any error of the text (see :func:`parse_expression`), a misplaced
        ``integral()``, a comparison, or a variable outside ``integral()`` without
        ``(final_time)``.
    InputError
        If ``names`` is malformed.
    """
    p = _Parser(text, names, static, origin, key, specials)
    tree = p.guarded(p.tree)
    if isinstance(tree, ast.Compare):
        raise p.fail("the objective is an expression to minimise, not a comparison", tree)
    mayer, lagrange = p.guarded(lambda: p.split(tree))
    return Objective(mayer=mayer, lagrange=lagrange, text=text)


def parse_constraint(
    text: str, names: Mapping[str, Any], origin: str = "", key: str = "", static: Collection[str] | None = None,
    specials: Specials | None = None,
) -> ParsedConstraint:
    """Parse ``e1 <= e2``, ``e1 >= e2``, ``e1 == e2`` or ``lo <= e <= hi`` (also ``>=``).

    A side that is a number (after folding constants and numeric names) becomes a bound:
    ``abs(qd1) <= 1.0`` gives ``expr = abs(qd1)``, ``ub = 1``; otherwise
    ``e1 <= e2`` gives ``expr = e1 - e2``, ``ub = 0``. In ``lo <= e <= hi`` the outer
    parts must be numbers. Calls ``v(final_time)`` / ``v(start_time)`` make it a point
    constraint; then every time-varying name must be evaluated at that same time point.
    With ``specials``, a constraint may also evaluate names at fixed times ``v(2.5)``,
    mix time points (``x(final_time) == x(start_time)``) and contain ``integral(f)``
    (isoperimetric constraints): it is then a constraint on timed variables and integrals
    (``at = "timed"``), its time points and integrals replaced by the callbacks' symbols.

    Parameters
    ----------
    text : str
        Constraint text.
    names : mapping of str to casadi.SX or float
        Name table (see :func:`parse_expression`).
    origin : str, optional
        File path for messages.
    key : str, optional
        Field key for messages, e.g. ``"constraints[2]"``; also the constraint name.
    static : collection of str, optional
        Names constant in time (see :func:`parse_expression`).
    specials : tuple of callable, optional
        ``(timed, integral)`` callbacks (see :func:`parse_objective`).

    Returns
    -------
    ParsedConstraint
        Expression, bounds and time point.

    Raises
    ------
    ProblemError
        On any error of the text, a strict comparison, a missing comparison, bounds in
        the wrong order, a constraint without variables, or mixed time points.
    InputError
        If ``names`` is malformed.
    """
    p = _Parser(text, names, static, origin, key, specials)
    tree = p.guarded(p.tree)
    if not isinstance(tree, ast.Compare):
        p.guarded(lambda: p.scalar(tree, "constraint"))  # a more specific error first, if any
        raise p.fail("a constraint needs a comparison <=, >= or ==", tree)
    operands = [tree.left, *tree.comparators]
    for i, op in enumerate(tree.ops):
        if type(op) not in _CMP:
            where = p.op_span(operands[i], operands[i + 1])
            sym = p.text[where[0]:where[1]]
            what = (f"strict comparison '{sym}' is not allowed, use <= / >=" if isinstance(op, (ast.Lt, ast.Gt))
                    else f"comparison '{sym}' is not allowed, use <=, >= or ==")
            raise p.fail(what, where)
    if len(operands) > 3:
        raise p.fail("at most two comparisons (lo <= e <= hi) are allowed",
                     p.op_span(operands[2], operands[3]))
    vals = p.guarded(lambda: [p.scalar(n, "constraint") for n in operands])
    if p.needs_timed:  # time points other than one of start/final, or integral(): a second pass with symbols
        if p.bare:
            n = p.bare[0]
            raise p.fail(f"'{n.id}' is not evaluated at a time point in a constraint on time points or integrals", n,
                         "use final_time" if n.id == "time" else f"write {n.id}(t) at a time t, or make it a separate path constraint")
        p = _Parser(text, names, static, origin, key, specials)
        p.timed_mode = True
        tree = p.guarded(p.tree)
        operands = [tree.left, *tree.comparators]  # type: ignore[attr-defined]
        vals = p.guarded(lambda: [p.scalar(n, "constraint") for n in operands])
        p.at = "timed"
    consts = [_const(v) for v in vals]
    inf = math.inf
    if len(operands) == 3:
        kinds = {type(o) for o in tree.ops}
        if len(kinds) != 1 or ast.Eq in kinds:
            raise p.fail("a double comparison must be lo <= e <= hi or hi >= e >= lo",
                         p.op_span(operands[1], operands[2]))
        for i in (0, 2):
            if consts[i] is None:
                raise p.fail("the outer parts of a double comparison must be numbers", operands[i],
                             "write two constraints")
        lo, hi = (consts[0], consts[2]) if ast.LtE in kinds else (consts[2], consts[0])
        expr, node = vals[1], operands[1]
    else:
        (a, b), (ca_, cb) = vals, consts
        op = type(tree.ops[0])
        if op is ast.GtE:
            a, b, ca_, cb = b, a, cb, ca_
        if ca_ is not None and cb is not None:
            raise p.fail("the constraint contains no variables", tree)
        if cb is not None:
            expr, lo, hi = a, (cb if op is ast.Eq else -inf), cb
        elif ca_ is not None:
            expr, lo, hi = b, ca_, (ca_ if op is ast.Eq else inf)
        else:
            expr, lo, hi = a - b, (0.0 if op is ast.Eq else -inf), 0.0
        node = tree
    if _const(expr) is not None:
        raise p.fail("the constrained expression contains no variables", node)
    assert lo is not None and hi is not None
    if lo > hi:
        raise p.fail(f"lower bound {lo:g} exceeds upper bound {hi:g}", tree)
    if p.at is not None and p.bare:
        n = p.bare[0]
        hint = f"use {p.at}_time" if n.id == "time" else (
            f"write {n.id}({p.at}_time), or make it a separate path constraint")
        raise p.fail(f"'{n.id}' is not evaluated at a time point in a point constraint at {p.at}_time", n, hint)
    return ParsedConstraint(expr=expr, lb=float(lo), ub=float(hi), at=p.at, text=text, name=key or text)
