"""The model's own initial conditions in an :class:`~gtmodel.modeling.Optimization`.

A start declared ``fixed=True`` (a component modifier's start value: ``Mass(s=3)``) and an
initial equation (:meth:`gtmodel.modeling.Model.initial_equation`) are initial conditions
of an optimisation as they are of a simulation (Modelica Language Specification 3.6,
section 8.6; Optimica, Akesson (2008), where the model's initialisation is part of the
problem). Which starts are fixed and what each condition says are those of
:mod:`gtmodel.modeling.structure.initialization` (the simulate side):
:func:`~gtmodel.modeling.structure.scalarize` reads them, by scalar name (``"mass.s"``,
``"T[0]"``), and :func:`~gtmodel.modeling.structure.initialization.condition_residuals`
writes each as ``v - value`` in the model's variables.

The problem's own start constraints take precedence, variable by variable: a start point
constraint whose element is exactly one scalar variable (``x(start_time) == 0``, a
``[boundary.start]`` entry, ``add_point_constraint(x, at="start", ...)``) replaces that
variable's fixed start when the start satisfies it (the same value, or within its bounds:
an inequality frees the initial value within them), and is a conflict otherwise
(:class:`InitialConditionConflict`, naming the variable and the constraint). Starts with
``fixed=False`` are guesses: they seed the initial guess (the transcriptions' default
guess is the start values), nothing more.

A fixed start of an algebraic variable (``mass.s`` where index reduction kept the damper's
``s_rel`` as the state) is written in the states where the model's algebraic equations
give the variable affinely without the inputs (the connection equations), so it holds on
the initial state exactly rather than on collocation's extrapolation of the first element.
"""

from __future__ import annotations

import logging
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import ModelError
from gtmodel.modeling.ocp.terms import Constraint
from gtmodel.modeling.structure import scalarize
from gtmodel.modeling.structure.initialization import condition_residuals

__all__ = ["InitialConditionConflict", "fixed_starts", "model_initial_conditions"]

_log = logging.getLogger("gtmodel")


class InitialConditionConflict(ModelError):
    """A fixed start of the model and a different start constraint of the problem on one variable.

    Parameters
    ----------
    message : str
        The message (naming the variable, its fixed start and the constraint).
    variable : str
        The scalar variable's name (``"mass.s"``).
    constraint : str
        The name of the problem's constraint (a problem file's field, e.g. ``"boundary.start.mass_s"``).
    """

    def __init__(self, message: str, variable: str, constraint: str) -> None:
        super().__init__(message)
        self.variable = variable
        self.constraint = constraint


def _own_start_bounds(opt: Any, syms: dict[str, ca.SX]) -> dict[str, list[tuple[str, float, float]]]:
    """The problem's start constraints on single scalar variables: name -> [(constraint, lb, ub), ...]."""
    by_sym = {s.element_hash(): name for name, s in syms.items()}
    timed: dict[int, str] = {}
    for v in opt.timed_variables:
        if v.time == "start" and v.expr.is_symbolic() and v.expr.element_hash() in by_sym:
            timed[v.symbol.element_hash()] = by_sym[v.expr.element_hash()]
    out: dict[str, list[tuple[str, float, float]]] = {}
    for c in opt.declared_point_constraints:
        if c.at not in ("start", "timed"):
            continue
        for i in range(int(c.expr.numel())):
            e = c.expr[i]
            if not e.is_symbolic():
                continue
            name = (by_sym if c.at == "start" else timed).get(e.element_hash())
            if name is not None:
                out.setdefault(name, []).append((c.name, float(c.lb[i]), float(c.ub[i])))
    return out


def fixed_starts(opt: Any) -> dict[str, float]:
    """The model's fixed starts that are initial conditions of the problem, by scalar name.

    Parameters
    ----------
    opt : Optimization
        The problem (its model and the start constraints declared so far).

    Returns
    -------
    dict of str to float
        Scalar variable name -> its fixed start, for the fixed starts that no declared
        start constraint on that variable replaces.

    Raises
    ------
    InitialConditionConflict
        If a fixed start violates the problem's own start constraint on that variable.
    """
    return {name: value for name, (value, _) in _kept(opt, scalarize(opt.model)).items()}


def _kept(opt: Any, system: Any) -> dict[str, tuple[float, str]]:
    """The fixed starts not replaced by a declared start constraint, as initialisation conditions."""
    if not system.fixed_start:
        return {}
    own = _own_start_bounds(opt, dict(zip(system.var_names, system.var_syms)))
    keep: dict[str, tuple[float, str]] = {}
    for name, value in system.fixed_start.items():
        stated = own.get(name, [])
        for cname, lb, ub in stated:
            tol = 1e-9 * max(1.0, abs(value))
            if not lb - tol <= value <= ub + tol:
                what = f"== {lb:.12g}" if lb == ub else f"in [{lb:.12g}, {ub:.12g}]"
                raise InitialConditionConflict(
                    f"initial condition of {name!r}: the model's fixed start {name} = {value:.12g} contradicts the "
                    f"problem's start constraint {cname!r} ({name} {what} at the start time); give the problem's value "
                    f"as the model's start, or declare the start a guess ({{\"start\": {value:.12g}, \"fixed\": False}}), "
                    "or remove the constraint",
                    name, cname,
                )
        if stated:
            _log.debug("fixed start of %s = %g: the problem's start constraint %s takes its place", name, value, stated[0][0])
        else:
            keep[name] = (value, "fixed start")
    return keep


def model_initial_conditions(opt: Any) -> list[Constraint]:
    """Start point constraints from the model's fixed starts and initial equations.

    Parameters
    ----------
    opt : Optimization
        The problem (its model and the start constraints declared so far).

    Returns
    -------
    list of Constraint
        One ``at="start"`` constraint ``v - value == 0`` per fixed start that the problem
        does not constrain itself (named ``"fixed start of <name>"``, :func:`fixed_starts`),
        and one per scalar initial equation (named ``"initial equation <label>"``).

    Raises
    ------
    InitialConditionConflict
        If a fixed start violates the problem's own start constraint on that variable.
    ModelError
        If a fixed start names no variable of the model.
    """
    system = scalarize(opt.model)
    keep = _kept(opt, system)
    out = []
    if keep:
        res, labels = condition_residuals(system, keep)
        res = _in_states(opt, res, [n for n, k in zip(system.var_names, system.var_kinds) if k == "algebraic" and n in keep])
        for r, name, label in zip(res, keep, labels):
            out.append(Constraint(f"fixed start of {name}", r, np.zeros(1), np.zeros(1), "start"))
            _log.debug("optimisation of %s: initial condition %s", system.name, label)
    for r, label in zip(system.init_res, system.init_names):
        out.append(Constraint(f"initial equation {label}", r, np.zeros(1), np.zeros(1), "start"))
    return out


def _in_states(opt: Any, res: list[ca.SX], algebraic: list[str]) -> list[ca.SX]:
    """The residuals with algebraic variables written in the states where the model's equations give them.

    A transcription has no algebraic variables at the start time itself (collocation
    extrapolates them from the first element), so a fixed start of an algebraic variable
    (``mass.s`` made a dummy derivative by index reduction) would hold only to the mesh's
    accuracy. Algebraic equations that fix one unknown algebraic variable each, affinely
    and without the inputs (the alias chains of connections: ``flange.s = mass.s + L/2``,
    ``s_rel = s_b - s_a``), are solved for it one after the other, and the residuals
    written in the states and parameters: the condition then holds on the initial state
    exactly. Algebraic variables in loops or nonlinear equations stay as they are.
    """
    if not algebraic:
        return res
    dae = opt.flat()
    z, g = dae.z, dae.alg_expr
    ne = int(g.numel())
    cols: list[set[int]] = [set() for _ in range(ne)]
    rows, colidx = ca.jacobian(g, z).sparsity().get_triplet()
    for r, c in zip(rows, colidx):
        cols[r].add(c)
    known: dict[int, ca.SX] = {}
    used: set[int] = set()
    progress = True
    while progress:
        progress = False
        for k in range(ne):
            left = [j for j in cols[k] if j not in known]
            if k in used or len(left) != 1:
                continue
            j = left[0]
            e = ca.substitute(g[k], ca.vertcat(*[z[i] for i in known]), ca.vertcat(*known.values())) if known else g[k]
            slope = ca.jacobian(e, z[j])
            if ca.depends_on(e, dae.u) or ca.depends_on(slope, z[j]) or slope.is_zero():
                continue
            known[j] = ca.simplify(z[j] - e / slope)
            used.add(k)
            progress = True
    if not known:
        return res
    zs, exprs = ca.vertcat(*[z[i] for i in known]), ca.vertcat(*known.values())
    return [ca.substitute(r, zs, exprs) for r in res]
