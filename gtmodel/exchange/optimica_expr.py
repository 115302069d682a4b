"""Optimica expressions (objective, integrand, constraints, attribute values) parsed into CasADi SX.

:class:`ExprParser` is a restricted recursive-descent parser over the tokens of
:func:`gtmodel.exchange.optimica_syntax.tokenize`: numbers, names, ``der()``, a whitelist of
functions, arithmetic and Optimica's timed variables ``x(finalTime)``. Nothing is evaluated
as Python; every error is an :class:`~gtmodel.exchange.optimica_syntax.OptimicaError` naming
the file, the line and the construct.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import casadi as ca

from gtmodel.exchange.optimica_syntax import MAX_DEPTH, OptimicaError, Token, _Cursor

__all__ = ["ExprParser", "FUNCTIONS"]

_FUNCS: dict[str, tuple[int, Callable[..., Any]]] = {
    "abs": (1, ca.fabs), "sqrt": (1, ca.sqrt), "exp": (1, ca.exp), "log": (1, ca.log), "log10": (1, ca.log10),
    "sin": (1, ca.sin), "cos": (1, ca.cos), "tan": (1, ca.tan), "asin": (1, ca.asin), "acos": (1, ca.acos),
    "atan": (1, ca.atan), "atan2": (2, ca.atan2), "sinh": (1, ca.sinh), "cosh": (1, ca.cosh), "tanh": (1, ca.tanh),
    "min": (2, ca.fmin), "max": (2, ca.fmax), "sum": (1, ca.sum1),
}
_REL = {"<=": "<=", ">=": ">=", "=": "="}
#: The functions an Optimica expression may call (besides ``der``).
FUNCTIONS: tuple[str, ...] = tuple(sorted(_FUNCS))


class ExprParser:
    """A restricted recursive-descent parser of Optimica expressions into CasADi SX.

    Grammar (Modelica's, a subset): numbers, names (dotted, with constant 1-based subscripts
    ``x[2]``), ``time``, ``der(x)``, the functions of ``_FUNCS``, ``+ - * / ^`` (and the
    element-wise ``.* ./ .^``), unary ``-``/``+``, parentheses, and the timed variable
    ``v(t)`` of a variable ``v`` at ``t`` = ``startTime``, ``finalTime`` or a number (the
    ``timed`` callback gives its symbol). Nothing is evaluated as Python.

    Parameters
    ----------
    path : pathlib.Path
        The file (for messages).
    names : dict of str to casadi.SX
        Model names (dotted, as written) -> symbol or expression; ``time``, ``startTime``,
        ``finalTime`` included by the caller.
    derivative : callable
        ``derivative(name, token) -> SX``: ``der(name)``.
    timed : callable or None
        ``timed(expr, at, token) -> SX`` with ``at`` ``"start"``, ``"final"`` or a float;
        ``None`` refuses timed variables (an integrand).
    """

    def __init__(self, path: Path, names: dict[str, ca.SX], derivative: Callable[[str, Token], ca.SX],
                 timed: Callable[[ca.SX, Any, Token], ca.SX] | None) -> None:
        self.path, self.names, self.derivative, self.timed = path, names, derivative, timed
        self.toks: list[Token] = []
        self.i = 0
        self.depth = 0
        self.times: set[Any] = set()

    def _fail(self, tok: Token | None, what: str) -> OptimicaError:
        line = tok.line if tok is not None else (self.toks[-1].line if self.toks else 0)
        return OptimicaError(f"{self.path}:{line}: {what}")

    def parse(self, toks: list[Token]) -> ca.SX:
        """The SX of an expression given as tokens.

        Parameters
        ----------
        toks : list of Token
            The expression.

        Returns
        -------
        casadi.SX
            A column (a scalar, or an array variable's elements).

        Raises
        ------
        OptimicaError
            A construct outside the grammar, an unknown name or function, nesting deeper
            than :data:`MAX_DEPTH` (naming the line).
        """
        self.toks, self.i, self.times = toks, 0, set()
        if not toks:
            raise self._fail(None, "empty expression")
        e = self._sum()
        if self.i < len(toks):
            raise self._fail(toks[self.i], f"unexpected {toks[self.i].text!r} in an expression")
        return e

    def relation(self, toks: list[Token]) -> tuple[ca.SX, str, ca.SX]:
        """``lhs op rhs`` of a constraint, ``op`` one of ``<=``, ``>=``, ``=``.

        Parameters
        ----------
        toks : list of Token
            The statement.

        Returns
        -------
        tuple
            ``(lhs, op, rhs)``.

        Raises
        ------
        OptimicaError
            No relation, ``<``/``>`` (strict), ``==``/``<>``, or a malformed side.
        """
        ops = [k for k, t in enumerate(toks) if t.kind == "op" and t.text in ("<=", ">=", "=", "<", ">", "==", "<>")]
        if len(ops) != 1 or toks[ops[0]].text not in _REL:
            tok = toks[ops[1]] if len(ops) > 1 else toks[ops[0]] if ops else toks[0]
            raise self._fail(tok, "unsupported constraint: write one relation lhs <= rhs, lhs >= rhs or lhs = rhs")
        k = ops[0]
        if k == 0 or k == len(toks) - 1:
            raise self._fail(toks[k], "constraint with an empty side")
        lhs = self.parse(toks[:k])
        times = set(self.times)
        rhs = self.parse(toks[k + 1:])
        self.times |= times
        return lhs, toks[k].text, rhs

    # grammar ----------------------------------------------------------------------------
    def _peek(self) -> Token | None:
        return self.toks[self.i] if self.i < len(self.toks) else None

    def _take(self, text: str) -> Token:
        t = self._peek()
        if t is None or t.text != text:
            raise self._fail(t, f"expected {text!r}" + (f", got {t.text!r}" if t else " at the end of the expression"))
        self.i += 1
        return t

    def _nest(self) -> None:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise self._fail(self._peek(), f"expression nested deeper than {MAX_DEPTH} levels")

    def _sum(self) -> ca.SX:
        self._nest()
        t = self._peek()
        sign = 1.0
        if t is not None and t.text in ("-", "+"):
            self.i += 1
            sign = -1.0 if t.text == "-" else 1.0
        e = sign * self._product()
        while (t := self._peek()) is not None and t.text in ("+", "-", ".+", ".-"):
            self.i += 1
            r = self._product()
            e = self._combine(e, r, t, lambda a, b, s=t.text.strip("."): a + b if s == "+" else a - b)
        self.depth -= 1
        return e

    def _product(self) -> ca.SX:
        e = self._power()
        while (t := self._peek()) is not None and t.text in ("*", "/", ".*", "./"):
            self.i += 1
            r = self._power()
            if t.text == "*" and e.numel() > 1 and r.numel() > 1:
                raise self._fail(t, "unsupported construct: '*' of two arrays (matrix product); use '.*' for element-wise")
            e = self._combine(e, r, t, lambda a, b, s=t.text.strip("."): a * b if s == "*" else a / b)
        return e

    def _power(self) -> ca.SX:
        e = self._primary()
        t = self._peek()
        if t is not None and t.text in ("^", ".^"):
            self.i += 1
            u = self._peek()
            if u is not None and u.text in ("-", "+"):  # 2^-1
                self.i += 1
                r = (-1.0 if u.text == "-" else 1.0) * self._primary()
            else:
                r = self._primary()
            e = self._combine(e, r, t, lambda a, b: a ** b)
        return e

    def _combine(self, a: ca.SX, b: ca.SX, tok: Token, op: Callable[[ca.SX, ca.SX], ca.SX]) -> ca.SX:
        if a.numel() != b.numel() and 1 not in (a.numel(), b.numel()):
            raise self._fail(tok, f"sizes {a.numel()} and {b.numel()} do not match for {tok.text!r}")
        return op(a, b)

    def _primary(self) -> ca.SX:
        t = self._peek()
        if t is None:
            raise self._fail(None, "expression ends too early")
        if t.kind == "number":
            self.i += 1
            return ca.SX(float(t.text))
        if t.text == "(":
            self.i += 1
            self._nest()
            e = self._sum()
            self.depth -= 1
            self._take(")")
            return e
        if t.text == "{":  # an array constructor {e1, e2, ...} (one dimension)
            self.i += 1
            self._nest()
            items = [self._sum()]
            while (c := self._peek()) is not None and c.text == ",":
                self.i += 1
                items.append(self._sum())
            self.depth -= 1
            self._take("}")
            if any(e.numel() != 1 for e in items):
                raise self._fail(t, "unsupported construct: an array constructor of arrays (one dimension only)")
            return ca.vertcat(*items)
        if t.kind != "ident":
            raise self._fail(t, f"unsupported construct in an expression: {t.text!r}")
        if t.text in ("if", "not", "and", "or", "true", "false", "initial", "terminal", "pre", "edge", "sample", "delay"):
            raise self._fail(t, f"unsupported construct in an Optimica expression: {t.text!r}")
        name = self._dotted()
        nxt = self._peek()
        if nxt is not None and nxt.text == "(":
            return self._call(t, name)
        e = self._lookup(t, name)
        nxt = self._peek()
        if nxt is not None and nxt.text == "(":  # an element's timed variable: q[2](finalTime)
            close = _Cursor(self.path, self.toks).closing(self.i)
            args = self.toks[self.i + 1:close]
            self.i = close + 1
            return self._timed_value(t, name, e, [args])
        return e

    def _dotted(self) -> str:
        name = self.toks[self.i].text
        self.i += 1
        while (t := self._peek()) is not None and t.text == "." and self.i + 1 < len(self.toks) \
                and self.toks[self.i + 1].kind == "ident":
            name += "." + self.toks[self.i + 1].text
            self.i += 2
        return name

    def _lookup(self, tok: Token, name: str) -> ca.SX:
        t = self._peek()
        if t is not None and t.text == "[":  # x[2] (1-based), one constant index
            self.i += 1
            idx = self._take_int()
            self._take("]")
            name = f"{name}[{idx - 1}]" if f"{name}[{idx - 1}]" in self.names else name
            if name in self.names and self.names[name].numel() > 1:
                e = self.names[name]
                if not 1 <= idx <= e.numel():
                    raise self._fail(tok, f"index {idx} out of range 1..{e.numel()} of {name}")
                return e[idx - 1]
        if name not in self.names:
            raise self._fail(tok, f"unknown name {name!r} in an expression")
        return self.names[name]

    def _take_int(self) -> int:
        t = self._peek()
        if t is None or t.kind != "number" or not t.text.isdigit():
            raise self._fail(t, "unsupported construct: an index must be a positive integer constant")
        self.i += 1
        return int(t.text)

    def _call(self, tok: Token, name: str) -> ca.SX:
        open_ = self.i
        close = _Cursor(self.path, self.toks).closing(open_)
        args, k, depth = [], open_ + 1, 0
        start = k
        while k <= close:
            s = self.toks[k].text
            depth += s in "([{" and self.toks[k].kind == "op"
            depth -= s in ")]}" and self.toks[k].kind == "op" and k != close
            if (s == "," and depth == 0) or k == close:
                args.append(self.toks[start:k])
                start = k + 1
            k += 1
        if name == "der":
            if len(args) != 1 or len(args[0]) != 1 or args[0][0].kind != "ident":
                raise self._fail(tok, "unsupported construct: der() of anything but one state name")
            self.i = close + 1
            return self.derivative(args[0][0].text, tok)
        if name in self.names:  # a timed variable v(t)
            self.i = close + 1
            return self._timed_value(tok, name, self.names[name], args)
        if name not in _FUNCS:
            raise self._fail(tok, f"unsupported function {name!r} (supported: der, {', '.join(sorted(_FUNCS))})")
        nargs, fn = _FUNCS[name]
        if len(args) != nargs or any(not a for a in args):
            raise self._fail(tok, f"{name}() takes {nargs} argument{'s' if nargs > 1 else ''}")
        saved = (self.toks, self.i)
        values = []
        for a in args:
            sub = ExprParser(self.path, self.names, self.derivative, self.timed)
            sub.depth = self.depth + 1
            values.append(sub.parse(a))
            self.times |= sub.times
        self.toks, self.i = saved[0], close + 1
        return fn(*values)

    def _timed_value(self, tok: Token, name: str, e: ca.SX, args: list[list[Token]]) -> ca.SX:
        """The timed variable ``name(t)`` of the elements ``e`` (the ``timed`` callback's symbols)."""
        if self.timed is None:
            raise self._fail(tok, f"a timed variable {name}(...) is not allowed here (an integrand is over the whole horizon)")
        if len(args) != 1 or not args[0]:
            raise self._fail(tok, f"timed variable {name}(...) needs one time")
        at = self._time_point(args[0])
        self.times.add(at)
        return ca.vertcat(*[self.timed(e[j], at, tok) for j in range(e.numel())])

    def _time_point(self, toks: list[Token]) -> Any:
        if len(toks) == 1 and toks[0].text in ("finalTime", "startTime"):
            return "final" if toks[0].text == "finalTime" else "start"
        sign = -1.0 if toks[0].text == "-" else 1.0
        body = toks[1:] if toks[0].text in ("-", "+") else toks
        if len(body) == 1 and body[0].kind == "number":
            return sign * float(body[0].text)
        raise self._fail(toks[0], "unsupported construct: the time of a timed variable must be startTime, finalTime or a number")
