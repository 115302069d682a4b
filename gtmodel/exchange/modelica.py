"""Modelica source in: a ``.mo`` file becomes a gtmodel :class:`~gtmodel.modeling.Model` through pymoca.

pymoca (PyPI ``pymoca``, the optional extra ``modelica``) parses the file, flattens the
class (inheritance, modifications, connectors and ``connect`` with flow variables, arrays)
and translates it to CasADi (``pymoca.backends.casadi``): parameters, states, algebraic
variables, inputs, outputs and residual equations as MX expressions. This module checks the
file for the constructs the translation drops or changes without a word (pymoca 0.12 turns
a ``when`` clause or an ``algorithm`` section into *no* equations, ignores the condition of a
conditional component) and rejects them with the file, line and construct; then it rebuilds
the model as a gtmodel ``Model`` (SX), which simulates, linearises, optimises and exports as
an FMU like any other.

Supported subset (docs/fmu.md has the table): ``model``/``block``/``package`` classes,
``parameter``/``constant``/``input``/``output`` Real variables with ``start``, ``min``,
``max``, ``unit`` and comments, ``der()``, equations (also ``if``-expressions and ``for``
equations, of one or several equations, as pymoca expands them), ``initial equation``, ``extends``, modifications,
connectors with ``flow`` and ``connect``, arrays of Reals (``each`` on them), the built-in math functions.
``function`` classes with an ``algorithm`` (pymoca translates them; a function nested in a
model gets a dotted name CasADi 3.8 refuses, so declare it at the top level of the file).
Also, checked on pymoca 0.12 (:mod:`gtmodel.exchange.modelica_checks` says what it does with each):
short classes without a prefix or dimensions (``type Voltage = Real(unit = "V", min = 0);``
with its attributes kept, ``connector PositivePin = Pin;``, ``model M = Base(k = 5);``),
``final`` in the class loaded (its value kept; nothing modifies that class), a class
redeclaration (``replaceable model C = A; C a;`` and ``redeclare model C = B``), ``inner``
alone, ``protected``/``public``, Boolean and Integer parameters in equations.
Rejected: ``when``, ``algorithm`` outside functions, ``pre``/``edge``/``change``/``reinit``/``sample``/
``initial()``/``terminal()``, ``delay``, ``discrete`` variables, external functions,
``assert()``/``terminate()`` (pymoca 0.12 fails on them without a line); and what pymoca 0.12
reads as something else without a word (:data:`~gtmodel.exchange.modelica_checks.MISREAD`): a
short class with a prefix (``connector RealIn = input Real;``, the prefix dropped) or with array
dimensions (``type Vec = Real[3];``, a scalar), a conditional component (``Resistor r if useR;``,
the condition ignored), ``final`` in a class other than the one loaded (an override from outside
wins silently), a component redeclaration (``redeclare B a``, both classes merged), ``outer``
(not bound to its ``inner``), ``enumeration`` types, and Boolean or Integer variables that are
not parameters (read as continuous Reals, without events), reduction expressions
(``sum(x[i]^2 for i in 1:3)``: write ``sum(x.^2)``). Each error names the file, the line,
the construct, what pymoca does and what to write instead.
"""

from __future__ import annotations

import importlib
import keyword
import re
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError, ModelError
from gtmodel.exchange import msl, robot_library
from gtmodel.exchange.modelica_checks import class_spans, find_misread
from gtmodel.exchange.msl import code_only as _code_only
from gtmodel.modeling import Model

__all__ = ["load_modelica", "UNSUPPORTED"]

#: Constructs rejected (pymoca drops or changes them): what, and a regex finding its line.
UNSUPPORTED = {
    "when-clause": r"\bwhen\b",
    "algorithm section": r"\balgorithm\b",
    "pre()": r"\bpre\s*\(",
    "edge()": r"\bedge\s*\(",
    "change()": r"\bchange\s*\(",
    "reinit()": r"\breinit\s*\(",
    "sample()": r"\bsample\s*\(",
    "initial()": r"\binitial\s*\(\s*\)",
    "terminal()": r"\bterminal\s*\(",
    "delay()": r"\bdelay\s*\(",
    "discrete variable": r"\bdiscrete\b",
    "external function": r"\bexternal\b",
    "assert()": r"\bassert\s*\(",
    "terminate()": r"\bterminate\s*\(",
}


def _pymoca() -> tuple[Any, Any]:
    try:
        parser = importlib.import_module("pymoca.parser")
        generator = importlib.import_module("pymoca.backends.casadi.generator")
    except ImportError as exc:
        raise InputError(f"Modelica import needs pymoca: pip install 'gtmodel[modelica]' (or pip install pymoca) ({exc})") from None
    op_map = getattr(generator, "OP_MAP", {})
    if op_map.get("/") == "__div__" and not hasattr(ca.MX, "__div__"):
        # pymoca 0.12 divides by MX.__div__, which CasADi 3.8's MX no longer has: every "/" of an equation
        # failed ("'MX' object has no attribute '__div__'"); Python 3's name of the same operation
        op_map["/"] = "__truediv__"
    return parser, generator


def _check_constructs(path: Path, text: str, loaded: str | None = None) -> None:
    """Refuse the constructs pymoca drops (:data:`UNSUPPORTED`) or misreads (:data:`~gtmodel.exchange.modelica_checks.MISREAD`).

    ``loaded`` is the class being translated (``final`` is accepted in it only; None: nowhere).
    The error names the file, the first line of such a construct, and the construct.
    """
    code = _code_only(text)
    functions = [(a, b) for kind, _, a, b in class_spans(code) if kind == "function"]
    hits = []
    for what, pattern in UNSUPPORTED.items():
        for m in re.finditer(pattern, code):
            if what == "algorithm section" and any(a <= m.start() < b for a, b in functions):
                continue  # a function's algorithm: pymoca translates it
            hits.append((code.count("\n", 0, m.start()) + 1, what, "pymoca would drop it; see the supported subset in docs/fmu.md"))
            break
    hits += find_misread(code, loaded)
    if hits:
        line, what, why = min(hits)
        raise InputError(f"{path}:{line}: unsupported Modelica construct: {what} ({why})")


def _numeric(value: Any, subs: tuple[list[ca.MX], list[float]], what: str, path: Path) -> np.ndarray:
    """A start/parameter value: a number, or an MX expression of parameters evaluated at their values."""
    if isinstance(value, ca.MX):
        f = ca.Function("v", subs[0], [value], {"allow_free": True}) if subs[0] else ca.Function("v", [], [value], {"allow_free": True})
        if f.has_free():
            raise ModelError(f"{path}: {what} depends on {f.free_mx()}, not on parameters only")
        return np.array(f(*subs[1]) if subs[0] else f(), dtype=float).reshape(-1)
    return np.asarray(value, dtype=float).reshape(-1)


def load_modelica(path: str | Path, class_name: str | None = None) -> Model:
    """Load a Modelica model from a ``.mo`` file (through pymoca) as a gtmodel model.

    Parameters
    ----------
    path : str or pathlib.Path
        The ``.mo`` file; classes it names under ``Modelica.`` come from the library under the
        MSL's class paths (:mod:`gtmodel.exchange.msl`).
    class_name : str, optional
        The class to translate, dotted inside packages (``"Circuit.RC"``); default the
        last top-level ``model`` of the file (or the only class).

    Returns
    -------
    Model
        Parameters (values, units, descriptions in ``model.exchange_metadata``; a name that
        is a Python keyword gets a trailing ``_``, e.g. ``lambda_``; one of ``quantity =
        "SmoothingWidth"`` a smoothing width, :data:`gtmodel.exchange.msl.SMOOTHING_QUANTITY`), states
        with start values and bounds, algebraic variables, inputs, outputs (the Modelica
        ``output`` variables), equations and initial equations; ``model.source`` is the file.

    Raises
    ------
    InputError
        Naming the file (and line): missing file, pymoca not installed, a syntax error,
        an unsupported construct (:data:`UNSUPPORTED`, and what pymoca misreads:
        :data:`gtmodel.exchange.modelica_checks.MISREAD`), an unknown class, or pymoca's
        translation failing.
    ModelError
        A start or parameter value that is not a function of the parameters.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such Modelica file")
    text = msl.prepare(path, path.read_text(encoding="utf-8", errors="replace"))  # MSL class paths checked (file:line)
    parser, generator = _pymoca()
    try:
        ast = parser.parse(text)
    except Exception as exc:  # noqa: BLE001 - pymoca's ModelicaSyntaxError and others
        msg = str(exc)
        m = re.search(r"line (\d+)", msg)
        where = f"{path}:{m.group(1)}" if m else str(path)
        msg = re.sub(r" *\(input, line \d+\)", "", msg)
        raise InputError(f"{where}: Modelica syntax error: {msg}") from None
    if ast is None:
        raise InputError(f"{path}: Modelica syntax error: the parser returned nothing")
    user = [c for c in ast.classes if c not in ("Real", "Integer", "Boolean", "String", "StateSelect", "Clock")]
    if class_name is None:
        if not user:
            raise InputError(f"{path}: no class in the file")
        top = ast.classes[user[-1]]
        models = [n for n, c in top.classes.items() if c.type in ("model", "block")] if top.type == "package" else []
        class_name = f"{user[-1]}.{models[-1]}" if models else user[-1]
    _check_constructs(path, text, class_name)
    if msl.uses_msl(_code_only(text)):  # the library under the MSL's class paths (gtmodel.exchange.msl)
        msl.extend(parser, ast)
    if robot_library.uses_robots(_code_only(text)):  # the shipped Gantry-Tau robots, as the Optimica loader adds them
        robot_library.extend(parser, ast)
    try:
        mo = generator.generate(ast, class_name)
    except Exception as exc:  # noqa: BLE001 - pymoca raises many types
        lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
        msg = lines[-1] if lines else type(exc).__name__
        if "Function name is not valid" in str(exc):
            msg = "a function declared inside a class gets a dotted name CasADi refuses: declare it at the top level of the file"
        raise InputError(f"{path}: pymoca cannot translate class {class_name!r}: {msg}") from None
    if getattr(mo, "delay_states", None):
        raise InputError(f"{path}: unsupported Modelica construct: delay() in class {class_name!r}")
    return _to_model(path, ast, mo, class_name)


def _comments(ast: Any, class_name: str) -> dict[str, str]:
    """Comments of the symbols of the class (its own, one level), by name."""
    node = ast
    try:
        for part in class_name.split("."):
            node = node.classes[part]
    except (KeyError, AttributeError):
        return {}
    return {name: str(sym.comment) for name, sym in node.symbols.items() if getattr(sym, "comment", "")}


def _name(name: str) -> str:
    """A Modelica name as a gtmodel name: Python keywords get a trailing ``_`` (``lambda_``)."""
    return ".".join(f"{part}_" if keyword.iskeyword(part) else part for part in name.split("."))


def _truthy(value: Any) -> bool:
    try:
        return bool(np.all(np.asarray(value, dtype=float) != 0))
    except (TypeError, ValueError):
        return False


def _unit(v: Any) -> str:
    """The ``unit`` attribute of a pymoca variable ("" when none; pymoca gives parameters none)."""
    unit = getattr(v, "unit", "")
    return unit if isinstance(unit, str) else ""


def _residuals(equations: list[ca.MX]) -> ca.MX:
    """pymoca's residual equations as one column.

    A ``for`` loop of k equations over n indices is one n x k matrix in pymoca's result:
    each is flattened to a column (column-major: the loop's first equation for every index,
    then the second, ...) before they are stacked.
    """
    return ca.vertcat(*[ca.vec(e) for e in equations]) if equations else ca.MX(0, 1)


def _to_model(path: Path, ast: Any, mo: Any, class_name: str) -> Model:
    m = Model(class_name.split(".")[-1])
    m.source = path
    comments = _comments(ast, class_name)
    meta: dict[str, tuple[str, str]] = {}
    mx, sx = [], []  # pymoca's MX symbols and their gtmodel SX replacements
    for c in mo.constants:
        mx.append(c.symbol)
        sx.append(ca.SX(_numeric(c.value, ([], []), f"constant {c.symbol.name()}", path).reshape(c.symbol.shape)))
    p_syms, p_vals = [], []
    for p in mo.parameters:
        name = p.symbol.name()
        value = _numeric(p.value if p.value is not None else p.start, (p_syms, p_vals), f"parameter {name}", path)
        if not np.all(np.isfinite(value)):
            raise InputError(f"{path}: parameter {name} has no value")
        sym = m.parameter(_name(name), value, smoothing=getattr(p, "quantity", "") == msl.SMOOTHING_QUANTITY and value.size == 1)
        mx.append(p.symbol)
        sx.append(sym)
        p_syms.append(p.symbol)
        p_vals.append(value)
        meta[_name(name)] = (_unit(p), comments.get(name, ""))
    start = lambda v: _numeric(v.start, (p_syms, p_vals), f"start of {v.symbol.name()}", path)  # noqa: E731
    bound = lambda v, b: None if not np.all(np.isfinite(np.asarray(b, dtype=float))) else float(b)  # noqa: E731
    for kind, group in (("state", mo.states), ("algebraic", mo.alg_states), ("input", mo.inputs)):
        for v in group:
            name = v.symbol.name()
            n = int(v.symbol.numel())
            kw = dict(shape=n, start=start(v), lb=bound(v, v.min), ub=bound(v, v.max), unit=_unit(v))
            sym = getattr(m, kind)(_name(name), **kw)
            mx.append(v.symbol)
            sx.append(sym)
            meta[_name(name)] = (_unit(v), comments.get(name, ""))
    for d, x in zip(mo.der_states, mo.states):
        mx.append(d.symbol)
        sx.append(m.der(m.variables("state")[_name(x.symbol.name())]))
    mx.append(mo.time)
    sx.append(m.time)
    eq = ca.Function("eq", mx, [_residuals(mo.equations), _residuals(mo.initial_equations)])
    res, init = eq(*sx)
    for i in range(res.numel()):
        m.equation(res[i], 0, name=f"eq{i + 1}")
    for i in range(init.numel()):
        m.initial_equation(init[i], 0, name=f"init{i + 1}")
    if init.numel():  # with initial equations, a state's start counts only when fixed = true (Modelica)
        states = m.variables("state")
        for v in mo.states:
            if _truthy(v.fixed):
                m.initial_equation(states[_name(v.symbol.name())], ca.DM(start(v)), name=f"fixed_{_name(v.symbol.name())}")
    algebraics = m.variables("algebraic")
    for name in mo.outputs:
        out = _name(name if isinstance(name, str) else name.symbol.name())
        if out in algebraics:
            m.output(f"{out}_out" if out in m._vars else out, algebraics[out])
    m.exchange_metadata = meta
    return m
