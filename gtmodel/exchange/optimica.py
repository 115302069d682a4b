"""Optimica source in: an ``optimization`` class of a ``.mop`` file as a gtmodel :class:`~gtmodel.modeling.Optimization`.

JModelica.org (Akesson 2008; Akesson et al. 2010) solved Optimica problems: a class
``optimization NAME (objective = ..., objectiveIntegrand = ..., startTime = ...,
finalTime(free = true, min = ..., max = ..., initialGuess = ...))`` that declares or
instantiates Modelica models, with a ``constraint`` section. :func:`load_optimica` reads one:
:func:`~gtmodel.exchange.optimica_syntax.split_optimica` takes the Optimica parts out with a
tokenizer, the rest (the class as a ``model``) goes through the Modelica import of
:mod:`gtmodel.exchange.modelica` (pymoca, its construct checks), and the Optimica parts are
declared on an :class:`~gtmodel.modeling.Optimization` through expressions parsed by a
restricted parser (:class:`~gtmodel.exchange.optimica_expr.ExprParser`, never ``eval``).

The mapping (docs/optimica.md has the table):

* ``objective`` -> the Mayer term (timed variables ``x(finalTime)``, ``finalTime``,
  parameters); ``objectiveIntegrand`` -> the Lagrange term; Optimica minimises.
* ``startTime`` -> ``start_time``; ``finalTime = T`` fixed, or ``finalTime(free = true,
  min, max, initialGuess)`` free (a missing ``min`` is ``startTime + 1e-6`` s, a missing
  ``max`` :data:`FREE_FINAL_TIME_MAX` s, as JModelica.org left them open).
* ``constraint``: a relation without timed variables is a path constraint; one with timed
  variables ``v(startTime)``, ``v(finalTime)``, ``v(t)`` (t a number) a point constraint.
* ``parameter Real p(free = true, min, max, initialGuess)`` -> a free parameter;
  ``initialGuess`` of a variable -> its initial guess; inputs' ``min``/``max`` -> bounds.
* ``start``/``fixed``: a state's start with ``fixed = true`` is an initial condition, a
  start with ``fixed = false`` (Modelica's default for states) a guess; with
  ``state_start_values_fixed`` (JModelica.org's compiler option) every state's start is an
  initial condition.

Everything else of Optimica (``startTime(free = true)``, ``static``, ``for`` in a constraint
section, ``if``/``and``/``or`` in its expressions, ``free`` on a non-parameter, strict ``<``/``>``)
is refused with the file, line and construct.
"""

from __future__ import annotations

import logging
import re
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import GtModelError, InputError
from gtmodel.exchange import msl, robot_library
from gtmodel.exchange.msl import code_only
from gtmodel.exchange.modelica import _check_constructs, _name, _numeric, _pymoca, _to_model, _truthy
from gtmodel.exchange.optimica_expr import ExprParser
from gtmodel.exchange.optimica_syntax import MAX_BYTES, Modifier, OptimicaError, Token, split_optimica, tokenize
from gtmodel.modeling import Model, Optimization

__all__ = ["load_optimica", "OptimicaError", "FREE_FINAL_TIME_MAX"]

_log = logging.getLogger("gtmodel")

#: Upper bound of a free final time whose ``finalTime`` gives no ``max``, s.
FREE_FINAL_TIME_MAX = 1.0e4
_IDENT_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_CLASS_DECL_RE = re.compile(r"\b(?:model|block|package|connector|record|function|class|type)\s+([A-Za-z_][A-Za-z0-9_]*)")
#: Most sibling ``.mo`` files looked at for classes the ``.mop`` file does not declare.
MAX_SIBLINGS = 50


def load_optimica(path: str | Path, class_name: str, *, state_start_values_fixed: bool = False) -> Optimization:
    """Load an Optimica ``optimization`` class as a gtmodel optimal control problem.

    Parameters
    ----------
    path : str or pathlib.Path
        The ``.mop`` (or ``.mo``) file; models it uses are declared in it or in ``.mo``
        files in the same folder (read only when the file alone does not translate, and
        only those declaring a class name the file uses).
    class_name : str
        The ``optimization`` class, dotted inside packages (``"Examples.MinTime"``).
    state_start_values_fixed : bool, optional
        JModelica.org's compiler option of that name: every state's ``start`` is an initial
        condition, as if declared ``fixed = true`` (default False: Modelica's semantics,
        a state's start is a guess unless ``fixed = true``).

    Returns
    -------
    Optimization
        The problem on the model of the class (its ``model.source`` the file); attribute
        ``optimica`` holds ``{"file", "class", "constraints"}`` (the constraint texts).

    Raises
    ------
    OptimicaError
        An :class:`~gtmodel.errors.InputError` naming the file, line and construct: a missing
        or hostile file, a syntax error, an unknown class, name or function, or a construct
        outside the supported subset (the module docstring).
    """
    path = Path(path)
    if not path.is_file():
        raise OptimicaError(f"{path}: no such Optimica file")
    if path.stat().st_size > MAX_BYTES:
        raise OptimicaError(f"{path}: file too large ({path.stat().st_size} bytes; at most {MAX_BYTES} are read)")
    text = path.read_text(encoding="utf-8", errors="replace")
    oc = split_optimica(path, text, class_name)
    model, mo = _model(path, oc.model_text, oc.name)
    states = model.variables("state")
    fixed = {_name(v.symbol.name()) for v in mo.states if _truthy(v.fixed)}
    if mo.initial_equations:  # _to_model wrote the fixed starts as initial equations already
        fixed_now = set(states) - fixed if state_start_values_fixed else set()
    else:
        fixed_now = set(states) if state_start_values_fixed else fixed
    for name in sorted(fixed_now):  # Modelica's fixed = true (or the compiler option): the start is an initial condition
        var = model._vars[name]
        var.fixed = np.ones(var.size, dtype=bool)
    return _declare(path, oc, model)


def _model(path: Path, text: str, class_name: str) -> tuple[Model, Any]:
    """The class as a gtmodel model through pymoca (with ``.mo`` files beside ``path`` if it needs them)."""
    parser, generator = _pymoca()
    text = _msl_prepared(path, text)
    ast = _parse(parser, path, text)
    _constructs(path, text)
    with_msl = msl.uses_msl(code_only(text))  # the library under the MSL's class paths (gtmodel.exchange.msl)
    if with_msl:
        msl.extend(parser, ast)
    input_texts = [text]
    if robot_library.uses_robots(code_only(text)):  # the shipped Gantry-Tau robots (gtmodel.exchange.robot_library)
        robot_library.extend(parser, ast)
        input_texts.append(robot_library.ROBOT_SOURCE.read_text(encoding="utf-8"))
    try:
        mo = generator.generate(ast, class_name)
    except Exception as first:  # noqa: BLE001 - pymoca raises many types; retried with the sibling .mo files
        used = set(_IDENT_RE.findall(text))
        siblings = []
        for other in sorted(p for p in path.parent.glob("*.mo") if p != path)[:MAX_SIBLINGS]:
            if other.stat().st_size > MAX_BYTES:
                continue  # not read: a class the file needs from it stays unknown (the error names the class)
            other_text = other.read_text(encoding="utf-8", errors="replace")
            if used & set(_CLASS_DECL_RE.findall(other_text)):  # only the files declaring a name the .mop uses
                siblings.append((other, other_text))
        if not siblings:
            raise _translation_error(path, class_name, first) from None
        for other, other_text in siblings:
            split_check(other, other_text)
            other_text = _msl_prepared(other, other_text)
            _constructs(other, other_text)
            ast.extend(_parse(parser, other, other_text))
            input_texts.append(other_text)
            if not with_msl and msl.uses_msl(code_only(other_text)):
                with_msl = True
                msl.extend(parser, ast)
        try:
            mo = generator.generate(ast, class_name)
        except Exception as exc:  # noqa: BLE001
            raise _translation_error(path, class_name, exc) from None
    if getattr(mo, "delay_states", None):
        raise OptimicaError(f"{path}: unsupported Modelica construct: delay() in class {class_name!r}")
    _numeric_bounds(path, mo)
    _component_inputs(mo, input_texts)
    try:
        return _to_model(path, ast, mo, class_name), mo
    except InputError as exc:
        raise OptimicaError(str(exc)) from None


_INPUT_DECL_RE = re.compile(r"\binput\s+[A-Za-z_][\w.]*\s*(?:\[[^\]]*\]\s*)?([A-Za-z_]\w*)")


def _component_inputs(mo: Any, texts: list[str]) -> None:
    """Inputs of components left unbound (``robot.tau``) made inputs of the problem, as JModelica.org read them (in place).

    pymoca drops the ``input`` prefix of a component's variables (MLS 9.1.1: only top-level
    inputs are inputs); an Optimica problem on a component (the thesis' ``opt_robot`` bounds
    ``robot.tau``) has them as its inputs. A component variable whose name is declared
    ``input`` in the classes read becomes an input when the model lacks exactly as many
    equations as these variables have elements (connected inputs have their equations; then
    nothing moves and the model's own count error stands).
    """
    declared = {m.group(1) for t in texts for m in _INPUT_DECL_RE.finditer(code_only(t))}
    cands = [v for v in mo.alg_states if "." in v.symbol.name() and v.symbol.name().rsplit(".", 1)[1] in declared]
    if not cands:
        return
    unknowns = sum(v.symbol.numel() for v in [*mo.states, *mo.alg_states])
    equations = sum(e.numel() for e in mo.equations)
    if unknowns - equations != sum(v.symbol.numel() for v in cands):
        return
    mo.alg_states = [v for v in mo.alg_states if all(v is not c for c in cands)]
    mo.inputs = [*mo.inputs, *cands]
    _log.debug("component inputs read as the problem's inputs: %s", ", ".join(v.symbol.name() for v in cands))


def _msl_prepared(path: Path, text: str) -> str:
    """:func:`gtmodel.exchange.msl.prepare` (MSL class paths checked, its connectors read) as an :class:`OptimicaError`."""
    try:
        return msl.prepare(path, text)
    except InputError as exc:
        raise OptimicaError(str(exc)) from None


def _numeric_bounds(path: Path, mo: Any) -> None:
    """``min``/``max`` written with parameters (``min = -a_max``) evaluated at the parameters' values (in place)."""
    syms, vals = [], []
    for p in mo.parameters:
        value = p.value if p.value is not None else p.start
        try:
            vals.append(_numeric(value, (syms, vals), f"parameter {p.symbol.name()}", path))
        except GtModelError as exc:
            raise OptimicaError(str(exc)) from None
        syms.append(p.symbol)
    for v in [*mo.states, *mo.alg_states, *mo.inputs]:
        for attr in ("min", "max"):
            b = getattr(v, attr)
            if isinstance(b, ca.MX):
                try:
                    setattr(v, attr, float(_numeric(b, (syms, vals), f"{attr} of {v.symbol.name()}", path)[0]))
                except GtModelError as exc:
                    raise OptimicaError(str(exc)) from None


def split_check(path: Path, text: str) -> None:
    """Refuse hostile input in a sibling ``.mo`` file (its tokens checked as the ``.mop`` file's)."""
    tokenize(path, text)


def _constructs(path: Path, text: str) -> None:
    """The Modelica import's refusals (:data:`gtmodel.exchange.modelica.UNSUPPORTED`) as an :class:`OptimicaError`."""
    try:
        _check_constructs(path, text)
    except InputError as exc:
        raise OptimicaError(str(exc)) from None


def _parse(parser: Any, path: Path, text: str) -> Any:
    try:
        ast = parser.parse(text)
    except RecursionError:
        raise OptimicaError(f"{path}: nesting too deep for the Modelica parser") from None
    except Exception as exc:  # noqa: BLE001 - pymoca's ModelicaSyntaxError and others
        msg = str(exc)
        m = re.search(r"line (\d+)", msg)
        msg = re.sub(r" *\(input, line \d+\)", "", msg)
        raise OptimicaError(f"{path}:{m.group(1) if m else '?'}: Modelica syntax error: {msg}") from None
    if ast is None:
        raise OptimicaError(f"{path}: Modelica syntax error: the parser returned nothing")
    return ast


def _translation_error(path: Path, class_name: str, exc: BaseException) -> OptimicaError:
    lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
    msg = lines[-1] if lines else type(exc).__name__
    return OptimicaError(f"{path}: pymoca cannot translate class {class_name!r} (the optimization class as a model): {msg}")


class _Declarer:
    """Declares the Optimica parts of one class on an Optimization (the state of one load)."""

    def __init__(self, path: Path, oc: Any, model: Model) -> None:
        self.path, self.oc, self.model = path, oc, model
        self.names: dict[str, ca.SX] = {"time": model.time}
        modelica = {_name(n): n for n in _modelica_names(model)}
        for kind in ("parameter", "state", "algebraic", "input"):
            for name, sym in model.variables(kind).items():
                self.names[modelica.get(name, name)] = sym
        self.params = {modelica.get(n, n): s for n, s in model.variables("parameter").items()}
        params = model.variables("parameter")  # their values as declared (no flattening: the model may be of higher index)
        self.p_values = np.concatenate([np.ravel(model._vars[n].start) for n in params]) if params else np.zeros(0)
        self.opt: Optimization | None = None

    def fail(self, line: int, what: str) -> OptimicaError:
        return OptimicaError(f"{self.path}:{line}: {what}")

    def constant(self, toks: list[Token], what: str) -> float:
        """A number or an expression of the model's parameters (at their values), e.g. ``min = 2 * L``."""
        value = self.constant_array(toks, what)
        if value.size != 1:
            raise self.fail(toks[0].line, f"{what} must be a scalar")
        return float(value[0])

    def constant_array(self, toks: list[Token], what: str) -> np.ndarray:
        """A constant as :meth:`constant`, or an array of them (``initialGuess = {1, 2, 3}``), flattened."""
        p = ExprParser(self.path, {**self.params}, lambda n, t: self._no_der(t), None)
        e = p.parse(toks)
        dae_p = ca.vertcat(*[ca.vec(s) for s in self.model.variables("parameter").values()])
        try:
            value = np.ravel(np.asarray(ca.DM(ca.evalf(ca.substitute(e, dae_p, ca.DM(self.p_values)) if dae_p.numel() else e)),
                                        dtype=float))
        except RuntimeError:
            raise self.fail(toks[0].line, f"{what} must be a constant expression of parameters") from None
        if not np.all(np.isfinite(value)):
            raise self.fail(toks[0].line, f"{what} is not finite")
        return value

    def _no_der(self, tok: Token) -> ca.SX:
        raise self.fail(tok.line, "der() is not allowed in a constant")

    def flag(self, mod: Modifier, what: str) -> bool:
        v = mod.value or []
        if len(v) != 1 or v[0].text not in ("true", "false"):
            raise self.fail(mod.line, f"{what} must be true or false")
        return v[0].text == "true"

    def parser(self, timed: bool) -> ExprParser:
        opt = self.opt
        assert opt is not None
        names = {**self.names, "finalTime": opt.final_time, "startTime": ca.SX(opt.start_time)}
        states = self.model.variables("state")

        def der(name: str, tok: Token) -> ca.SX:
            sym = self.names.get(name)
            key = next((k for k, s in states.items() if sym is not None and s.shape == sym.shape and ca.is_equal(s, sym)), None)
            if key is None:
                raise self.fail(tok.line, f"der({name}): {name!r} is not a state of the model")
            return self.model.der(states[key])

        def at(expr: ca.SX, when: Any, tok: Token) -> ca.SX:
            try:
                return opt.timed(expr, when)
            except GtModelError as exc:
                raise self.fail(tok.line, str(exc)) from None

        return ExprParser(self.path, names, der, at if timed else None)

    def varying(self) -> ca.SX:
        m = self.model
        parts = [m.time] + [ca.vec(s) for k in ("state", "algebraic", "input") for s in m.variables(k).values()]
        parts += [ca.vec(m.der(s)) for s in m.variables("state").values()]
        return ca.vertcat(*parts)


def _modelica_names(model: Model) -> list[str]:
    """The Modelica names of the model's variables (``lambda``, where gtmodel has ``lambda_``)."""
    out = []
    for kind in ("parameter", "state", "algebraic", "input"):
        for name in model.variables(kind):
            out.append(".".join(p[:-1] if p.endswith("_") and p[:-1].isidentifier() and _name(p[:-1]) == p else p
                                for p in name.split(".")))
    return out


def _declare(path: Path, oc: Any, model: Model) -> Optimization:
    d = _Declarer(path, oc, model)
    h = oc.header
    t0 = d.constant(h["startTime"].value, "startTime") if "startTime" in h and h["startTime"].value else 0.0
    if "startTime" in h and h["startTime"].subs:
        raise d.fail(h["startTime"].line, "unsupported construct: startTime(...) attributes (a free start time); "
                                          "give startTime = value")
    kw = _final_time(d, h.get("finalTime"), t0)
    try:
        opt = Optimization(model, start_time=t0, **kw)
    except GtModelError as exc:
        raise d.fail(oc.line, f"optimization {oc.name}: {exc}") from None
    d.opt = opt
    if "objective" in h:
        _objective(d, h["objective"])
    if "objectiveIntegrand" in h:
        mod = h["objectiveIntegrand"]
        if not mod.value:
            raise d.fail(mod.line, "objectiveIntegrand needs = expression")
        e = d.parser(timed=False).parse(mod.value)
        if e.numel() != 1:
            raise d.fail(mod.line, "objectiveIntegrand must be a scalar")
        opt.set_objective(lagrange=e)
    texts = []
    for stmt in oc.constraints:
        _constraint(d, stmt)
        texts.append(" ".join(t.text for t in stmt))
    for owner, mod in oc.attributes.items():
        _attributes(d, owner, mod)
    opt.optimica = {"file": str(path), "class": oc.name, "constraints": texts}  # type: ignore[attr-defined]
    _log.debug("%s: %s: %d constraints, %d free parameters", path, oc.name, len(texts), len(opt.free_parameters))
    return opt


def _final_time(d: _Declarer, mod: Modifier | None, t0: float) -> dict[str, Any]:
    """The final-time arguments of :class:`Optimization` from ``finalTime = T`` or ``finalTime(free, min, max, initialGuess)``."""
    if mod is None:
        return {"final_time": t0 + 1.0}  # Optimica's default finalTime is 1
    for key in mod.subs:
        if key not in ("free", "min", "max", "initialGuess", "start"):
            raise d.fail(mod.subs[key].line, f"unsupported finalTime attribute {key!r} (supported: free, min, max, initialGuess)")
    free = d.flag(mod.subs["free"], "finalTime(free)") if "free" in mod.subs else False
    value = d.constant(mod.value, "finalTime") if mod.value else None
    guess_mod = mod.subs.get("initialGuess") or mod.subs.get("start")
    guess = d.constant(guess_mod.value, "finalTime initialGuess") if guess_mod and guess_mod.value else None
    if not free:
        if value is None:
            value = guess if guess is not None else 1.0
        return {"final_time": value}
    lo = d.constant(mod.subs["min"].value, "finalTime min") if "min" in mod.subs else None
    hi = d.constant(mod.subs["max"].value, "finalTime max") if "max" in mod.subs else None
    g = guess if guess is not None else value if value is not None else 1.0
    lo = t0 + 1e-6 if lo is None else lo
    hi = max(FREE_FINAL_TIME_MAX, g) if hi is None else hi
    if not (t0 < lo <= hi):
        raise d.fail(mod.line, f"finalTime: min ({lo:g}) and max ({hi:g}) must satisfy startTime ({t0:g}) < min <= max")
    return {"final_time": g, "free_final_time": True, "final_time_guess": g, "final_time_bounds": (lo, hi)}


def _objective(d: _Declarer, mod: Modifier) -> None:
    opt = d.opt
    assert opt is not None
    if not mod.value:
        raise d.fail(mod.line, "objective needs = expression")
    e = d.parser(timed=True).parse(mod.value)
    if e.numel() != 1:
        raise d.fail(mod.line, "objective must be a scalar")
    if ca.depends_on(e, d.varying()):
        raise d.fail(mod.line, "objective: a model variable without a time; write it as a timed variable, "
                               "e.g. cost(finalTime)")
    opt.set_objective(mayer=e)


def _constraint(d: _Declarer, stmt: list[Token]) -> None:
    opt = d.opt
    assert opt is not None
    p = d.parser(timed=True)
    lhs, op, rhs = p.relation(stmt)
    line = stmt[0].line
    name = f"{d.path.name}:{line}"
    if not rhs.is_constant() and lhs.is_constant():  # 1 >= u: u <= 1
        lhs, rhs, op = rhs, lhs, {"<=": ">=", ">=": "<=", "=": "="}[op]
    if rhs.is_constant():
        expr, bound = lhs, np.asarray(ca.DM(rhs), dtype=float).reshape(-1)
    else:
        expr, bound = lhs - rhs, np.zeros(1)
    if expr.is_constant():
        raise d.fail(line, "constraint without a variable")
    if bound.size not in (1, expr.numel()):
        raise d.fail(line, f"constraint sizes {expr.numel()} and {bound.size} do not match")
    bound = np.broadcast_to(bound, (expr.numel(),)).copy()
    lb = bound if op in (">=", "=") else -np.inf
    ub = bound if op in ("<=", "=") else np.inf
    try:
        if not p.times:
            opt.add_path_constraint(expr, lb, ub, name=name)
        elif ca.depends_on(expr, d.varying()):
            raise d.fail(line, "unsupported constraint: timed variables (x(finalTime)) and variables at every time in one "
                               "relation")
        else:
            opt.add_constraint(expr, lb, ub, name=name)
    except OptimicaError:
        raise
    except GtModelError as exc:
        raise d.fail(line, f"constraint: {exc}") from None


def _attributes(d: _Declarer, owner: str, mod: Modifier) -> None:
    """``free``/``initialGuess``/``min``/``max`` of a declaration ``owner``."""
    opt = d.opt
    assert opt is not None
    subs = mod.subs
    free = d.flag(subs["free"], f"{owner}(free)") if "free" in subs else False
    if owner in d.params:
        key = _name(owner)
        arr = {k: d.constant_array(subs[k].value, f"{owner}({k})") for k in ("min", "max", "initialGuess")
               if k in subs and subs[k].value}
        if not free:
            if "initialGuess" in arr:
                _log.info("%s:%d: initialGuess of the fixed parameter %s has no effect", d.path, mod.line, owner)
            return
        declared = np.ravel(np.asarray(d.model._vars[key].start, dtype=float))
        for k, v in arr.items():  # a scalar for every element (Modelica's each), or one value per element
            if v.size not in (1, declared.size):
                raise d.fail(mod.line, f"{owner}({k}): {v.size} values for a parameter of {declared.size} elements")
        lo = np.broadcast_to(arr.get("min", -np.inf), declared.shape).copy()
        hi = np.broadcast_to(arr.get("max", np.inf), declared.shape).copy()
        guess = np.broadcast_to(arr["initialGuess"], declared.shape) if "initialGuess" in arr else np.clip(declared, lo, hi)
        lo, hi, start = (lo[0], hi[0], float(guess[0])) if declared.size == 1 else (lo, hi, np.array(guess, dtype=float))
        try:
            opt.free_parameter(key, lo, hi, start=start)
        except GtModelError as exc:
            raise d.fail(mod.line, f"free parameter {owner}: {exc}") from None
        return
    num = {k: d.constant(subs[k].value, f"{owner}({k})") for k in ("min", "max", "initialGuess")
           if k in subs and subs[k].value}
    if owner not in d.names:
        raise d.fail(mod.line, f"Optimica attribute of {owner!r}: not a variable of the model")
    if free:
        raise d.fail(mod.line, f"unsupported construct: free = true on {owner!r}, which is not a parameter")
    if "initialGuess" in num:
        try:
            opt.set_initial_guess(d.names[owner], num["initialGuess"])
        except GtModelError as exc:
            raise d.fail(mod.line, f"initialGuess of {owner}: {exc}") from None

