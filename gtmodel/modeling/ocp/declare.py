"""Problem-file objectives and constraints declared on an :class:`~gtmodel.modeling.Optimization`.

:func:`optimization_names` builds the name table of an optimisation (model variables,
outputs, times, numeric parameters, element names); :func:`apply_to` parses an objective
and constraints with the expression language of :mod:`gtmodel.modeling.ocp.expressions`
and declares them on the optimisation (point constraints, path constraints, objective),
every error naming the problem-file field.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import casadi as ca

from gtmodel.errors import GtModelError, InputError, ProblemError
from gtmodel.modeling.ocp.expressions import FUNCTIONS, Objective, ParsedConstraint, _table, parse_constraint, parse_objective
from gtmodel.modeling.ocp.optimization import Optimization

__all__ = ["optimization_names", "apply_to"]

_log = logging.getLogger("gtmodel")


def optimization_names(
    optimization: Optimization,
    parameters: Mapping[str, float] | None = None,
    elements: Mapping[str, Sequence[str]] | None = None,
    origin: str = "",
) -> dict[str, ca.SX]:
    """Name table of an optimisation: model variables, outputs, times, numeric parameters.

    Parameters
    ----------
    optimization : Optimization
        The problem; its model's parameters, states, algebraics, inputs and outputs are
        entered under their declared names, plus ``time``, ``final_time`` and
        ``start_time`` (a number).
    parameters : mapping of str to float, optional
        Numeric names, e.g. a problem file's ``[parameters]`` table.
    elements : mapping of str to sequence of str, optional
        Scalar names for the elements of vector variables or outputs, e.g.
        ``{"tau": ["tau1", "tau2", "tau3"]}``.
    origin : str, optional
        File path for messages.

    Returns
    -------
    dict of str to casadi.SX
        Name -> scalar or vector expression.

    Raises
    ------
    ProblemError
        If a parameter or element name clashes with another name, a parameter is not a
        finite number, or an element list does not match the vector's size.
    """
    model = optimization.model
    out: dict[str, ca.SX] = {}
    for kind in ("parameter", "state", "algebraic", "input"):
        out.update(model.variables(kind))
    out.update(model.outputs)
    out.update(time=model.time, final_time=optimization.final_time, start_time=ca.SX(optimization.start_time))
    pre = f"{origin}: " if origin else ""
    for vec, scalars in (elements or {}).items():
        if vec not in out or out[vec].numel() != len(scalars):
            size = out[vec].numel() if vec in out else "no"
            raise ProblemError(f"{pre}elements of {vec!r}: {len(scalars)} names for {size} elements")
        for i, s in enumerate(scalars):
            if s in out or not s.isidentifier():
                raise ProblemError(f"{pre}element name {s!r} of {vec!r} is not a new identifier")
            out[s] = out[vec][i]
    for name, value in (parameters or {}).items():
        if name in out or not name.isidentifier() or name in FUNCTIONS:
            raise ProblemError(f"{pre}field 'parameters.{name}': name clashes with a model name or function")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ProblemError(f"{pre}field 'parameters.{name}': expected a finite number, got {value!r}")
        out[name] = ca.SX(float(value))
    return out


def apply_to(
    optimization: Optimization,
    objective: str | None = None,
    constraints: Sequence[str] = (),
    names: Mapping[str, Any] | None = None,
    parameters: Mapping[str, float] | None = None,
    origin: str = "",
    prefix: str = "",
    sense: str | None = None,
    objective_key: str = "objective",
) -> tuple[Objective | None, list[ParsedConstraint]]:
    """Parse an objective and constraints and declare them on an optimisation.

    Point constraints are added with :meth:`Optimization.add_point_constraint` (which
    evaluates model variables at the time point), constraints on variables at fixed
    times ``x(2.5)``, at several time points or on ``integral()`` with
    :meth:`Optimization.add_constraint` (over :meth:`Optimization.timed` and
    :meth:`Optimization.integral` symbols), path constraints with
    :meth:`Optimization.add_path_constraint`, the objective with
    :meth:`Optimization.set_objective` (replacing both terms).

    Parameters
    ----------
    optimization : Optimization
        The problem to extend.
    objective : str, optional
        Objective text; the objective is left unchanged when omitted.
    constraints : sequence of str, optional
        Constraint texts; the ``i``-th is reported as field ``constraints[i]``.
    names : mapping of str to casadi.SX or float, optional
        Name table; default :func:`optimization_names` ``(optimization, parameters)``.
        Names whose value does not depend on time, states, algebraics or inputs are
        static (may appear in the Mayer term and as factors of ``integral()``).
    parameters : mapping of str to float, optional
        Numeric names, used only when ``names`` is omitted.
    origin : str, optional
        File path for messages.
    prefix : str, optional
        Prefix of field keys in messages, e.g. ``"optimization."``.
    sense : {"minimize", "maximize"}, optional
        Whether the objective is minimised or maximised; default unchanged (minimised).
    objective_key : str, optional
        Field key of the objective in messages (after ``prefix``); default ``"objective"``.

    Returns
    -------
    tuple
        ``(objective, constraints)``: the parsed :class:`Objective` (or ``None``) and
        the list of :class:`ParsedConstraint`.

    Raises
    ------
    ProblemError
        On any error of the texts, or if the optimisation rejects a declaration (e.g. a
        name table entry with symbols foreign to the model); the message names the field.
    """
    if isinstance(constraints, str):
        raise InputError("constraints must be a sequence of strings, not one string")
    specials = (_timed_callback(optimization), optimization.integral)
    table = _table(optimization_names(optimization, parameters, origin=origin) if names is None else names)
    model = optimization.model
    varying = [model.time] + [
        ca.vec(s) for k in ("state", "algebraic", "input") for s in model.variables(k).values()
    ]
    states = list(model.variables("state").values())
    varying += [ca.vec(model.der(s)) for s in states]
    tv = ca.vertcat(*varying)
    static = [n for n, v in table.items() if not ca.depends_on(v, tv)]
    pre = f"{origin}: " if origin else ""

    def declare(key: str, fn: Callable[[], None]) -> None:
        try:
            fn()
        except GtModelError as exc:
            raise ProblemError(f"{pre}field '{key}': {exc}") from exc

    parsed_obj = None
    if objective is not None:
        key = f"{prefix}{objective_key}"
        parsed_obj = parse_objective(objective, table, origin, key, static, specials)
        declare(key, lambda: optimization.set_objective(mayer=parsed_obj.mayer, lagrange=parsed_obj.lagrange, sense=sense))
        _log.debug("objective %r: mayer %s, lagrange %s", objective, parsed_obj.mayer, parsed_obj.lagrange)
    parsed = []
    for i, text in enumerate(constraints):
        key = f"{prefix}constraints[{i}]"
        c = parse_constraint(text, table, origin, key, static, specials)
        if c.at is None:
            declare(key, lambda c=c: optimization.add_path_constraint(c.expr, c.lb, c.ub, name=c.name))
        elif c.at == "timed":
            declare(key, lambda c=c: optimization.add_constraint(c.expr, c.lb, c.ub, name=c.name))
        else:
            declare(key, lambda c=c: optimization.add_point_constraint(c.expr, c.at, c.lb, c.ub, name=c.name))
        _log.debug("constraint %s %r: %g <= %s <= %g at %s", key, text, c.lb, c.expr, c.ub, c.at or "path")
        parsed.append(c)
    return parsed_obj, parsed


def _timed_callback(optimization: Optimization) -> Callable[[ca.SX, Any], ca.SX]:
    """``timed(expr, time)`` of the parser: the time a number, ``"start"``/``"final"`` or static SX."""

    def timed(expr: ca.SX, time: Any) -> ca.SX:
        if isinstance(time, ca.SX):
            if not optimization.free_final_time:
                time = ca.substitute(time, optimization.final_time, ca.SX(optimization.final_time_value))
            if any(not ca.is_equal(s, optimization.final_time) for s in ca.symvar(time)):
                raise ProblemError("the time of a time point must be a number (start_time, final_time, "
                                   "numbers and [parameters] names)")
            if not ca.symvar(time):
                time = float(ca.DM(ca.evalf(time)))
        return optimization.timed(expr, time)  # a free final time: a fixed fraction of the horizon

    return timed
