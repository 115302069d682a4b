"""The likely culprit of a solve that ended without a solution, named in its message.

IPOPT's ``Infeasible_Problem_Detected`` (or a run out of iterations) says that no point was
found, not which declared constraint stands in the way. :func:`likely_culprit` looks at the
solver's last iterate, the trajectory a failed result carries (``last_iterate``):

- a free final time sitting at one of its bounds: at the upper bound, the minimum time is
  likely above it (``final_time at its upper bound 0.3 s at the last iterate: the minimum
  time may be above it``); at the lower bound, the bound likely holds the motion back;
- otherwise the declared constraint rows with the largest violation at the last iterate, by
  name (path constraints at the result's samples, point constraints at the start and final
  time, the state and input bounds), each with its excess and where it is largest.

:func:`with_culprit` appends that to a failed result's message (the result's, hence
``summary.json``'s and the command line's), and leaves a solution's message alone.
"""

from __future__ import annotations

import logging
import re
from typing import Any

import casadi as ca
import numpy as np

__all__ = ["likely_culprit", "with_culprit", "AT_BOUND_RTOL", "VIOLATION_TOL", "TOP_ROWS"]

_log = logging.getLogger("gtmodel")

#: A final time within this relative distance of a bound is "at" it.
AT_BOUND_RTOL = 1e-6
#: Violations (relative to ``max(1, |bound|)``) below this are not reported.
VIOLATION_TOL = 1e-6
#: Constraint rows named at most.
TOP_ROWS = 3


def _final_time_at_bound(result: Any, opt: Any) -> str:
    """The free final time at one of its bounds at the last iterate, said in words; ``""`` if not."""
    if not getattr(opt, "free_final_time", False):
        return ""
    tf = float(getattr(result, "final_time", float("nan")))
    lo, hi = (float(v) for v in opt.final_time_bounds)
    if not np.isfinite(tf):
        return ""
    if np.isfinite(hi) and tf >= hi - AT_BOUND_RTOL * max(1.0, abs(hi)):
        return (f"final_time at its upper bound {hi:g} s at the last iterate: the minimum time may be above it "
                "(raise the final time's upper bound)")
    if np.isfinite(lo) and tf <= lo + AT_BOUND_RTOL * max(1.0, abs(lo)):
        return (f"final_time at its lower bound {lo:g} s at the last iterate: the bound may hold the motion back "
                "(lower the final time's lower bound)")
    return ""


def _label(c: Any) -> str:
    """A constraint's name in quotes; an automatic name (``path0``, ``point2``) followed by its expression."""
    if re.fullmatch(r"(path|point)\d+", c.name):
        text = str(c.expr)
        return f"'{c.name}' ({text if len(text) <= 60 else text[:57] + '...'})"
    return f"'{c.name}'"


def _stacked(values: dict[str, Any], variables: dict[str, slice], n: int, width: int) -> np.ndarray:
    """``(n, width)`` samples of a category from a result's dictionary by name (missing names: NaN)."""
    out = np.full((n, width), np.nan)
    for name, sl in variables.items():
        if name in values:
            out[:, sl] = np.asarray(values[name], dtype=float).reshape(n, -1)
    return out


def _rows(result: Any, opt: Any) -> list[tuple[float, str, float, float]]:
    """Every violated row at the last iterate: ``(scaled excess, name, excess, time)``, the worst per row."""
    dae = result.dae
    t = np.asarray(result.t, dtype=float).reshape(-1)
    n = t.size
    if dae is None or n == 0:
        return []
    x = _stacked(result.states, dae.x_vars, n, dae.nx)
    z = _stacked(result.algebraics, dae.z_vars, n, dae.nz)
    u = _stacked(result.inputs, dae.u_vars, n, dae.nu)
    p = np.asarray(dae.parameter_vector({**opt.parameters, **result.parameters}), dtype=float).reshape(-1)
    tf = float(result.final_time)
    specials = [v.symbol for v in opt.special_symbols()]
    symbols = [dae.t, dae.x, dae.z, dae.u, dae.p, opt.final_time]
    out: list[tuple[float, str, float, float]] = []

    def add(name: str, expr: Any, lb: np.ndarray, ub: np.ndarray, idx: np.ndarray) -> None:
        e = ca.vertcat(expr)
        if dae.nx:
            e = ca.substitute(e, dae.xdot, dae.ode_expr)
        if specials and ca.depends_on(e, ca.vertcat(*specials)):
            return  # a timed variable or an integral: not a value at a sample
        f = ca.Function("rows", symbols, [e]).map(idx.size)
        vals = np.array(f(t[idx][None, :], x[idx].T, z[idx].T, u[idx].T, np.tile(p[:, None], (1, idx.size)), tf),
                        dtype=float).reshape(e.numel(), idx.size)
        lb, ub = np.broadcast_to(lb, (e.numel(),)), np.broadcast_to(ub, (e.numel(),))
        for i in range(e.numel()):
            excess = np.maximum(lb[i] - vals[i], vals[i] - ub[i])
            if not np.any(np.isfinite(excess)):
                continue
            k = int(np.nanargmax(excess))
            bound = lb[i] if lb[i] - vals[i, k] >= vals[i, k] - ub[i] else ub[i]
            scaled = float(excess[k]) / max(1.0, abs(float(bound)))
            if scaled > VIOLATION_TOL:
                label = name if e.numel() == 1 else f"{name}[{i}]"
                out.append((scaled, label, float(excess[k]), float(t[idx][k])))

    every, start, final = np.arange(n), np.array([0]), np.array([n - 1])
    for c in opt.path_constraints:
        add(_label(c), c.expr, np.asarray(c.lb, float), np.asarray(c.ub, float), every)
    for c in opt.point_constraints:
        if c.at in ("start", "final"):
            add(f"{_label(c)} at the {c.at} time", c.expr, np.asarray(c.lb, float), np.asarray(c.ub, float), start if c.at == "start" else final)
    for kind, variables in (("x", dae.x_vars), ("u", dae.u_vars)):
        lb, ub = opt.bounds_vectors(dae, kind)
        sym = dae.x if kind == "x" else dae.u
        for name, sl in variables.items():
            if np.any(np.isfinite(lb[sl])) or np.any(np.isfinite(ub[sl])):
                add(f"the bounds of {name}", sym[sl], lb[sl], ub[sl], every)
    return sorted(out, reverse=True)


def likely_culprit(result: Any, optimization: Any) -> str:
    """What most likely stands in the way of a failed solve, read from its last iterate; ``""`` when nothing stands out.

    Parameters
    ----------
    result : OptimizationResult
        A result whose status is not a solution (``last_iterate``): its trajectory is the solver's last iterate.
    optimization : Optimization
        The problem it solved (bounds, constraints and their names).

    Returns
    -------
    str
        ``"final_time at its upper bound 0.3 s at the last iterate: the minimum time may be above
        it (...)"``; or ``"the largest violations at the last iterate: 'name' by 0.012 at t =
        0.21 s; ..."`` (at most :data:`TOP_ROWS` rows, relative violations above
        :data:`VIOLATION_TOL`); or ``""``.
    """
    at_bound = _final_time_at_bound(result, optimization)
    if at_bound:
        return at_bound
    try:
        rows = _rows(result, optimization)
    except (RuntimeError, ValueError, KeyError, AttributeError, TypeError) as exc:  # a diagnosis never hides the failure itself
        _log.debug("no diagnosis of the failed solve: %s", exc)
        return ""
    if not rows:
        return ""
    worst = "; ".join(f"{name} by {excess:.3g} at t = {t:.4g} s" for _, name, excess, t in rows[:TOP_ROWS])
    return f"the largest violations at the last iterate: {worst}"


def with_culprit(message: str, result: Any, optimization: Any) -> str:
    """``message`` with the likely culprit of a failed solve appended (unchanged for a solution).

    Parameters
    ----------
    message : str
        The solver's message.
    result : OptimizationResult
        The result; only a ``last_iterate`` (not a solution) is diagnosed.
    optimization : Optimization
        The problem it solved.

    Returns
    -------
    str
        ``"<message>; likely culprit: <what>"``, or ``message``.
    """
    if not getattr(result, "last_iterate", False):
        return message
    culprit = likely_culprit(result, optimization)
    return f"{message}; likely culprit: {culprit}" if culprit else message
