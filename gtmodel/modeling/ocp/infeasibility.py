"""The likely culprit of a solve that ended without a solution, named in its message.

IPOPT's ``Infeasible_Problem_Detected`` (or a run out of iterations) says that no point was
found, not which declared constraint stands in the way. :func:`likely_culprit` looks at the
solver's last iterate, the trajectory a failed result carries (``last_iterate``):

- a free final time sitting at one of its bounds: at the upper bound, the minimum time is
  likely above it (``final_time at its upper bound 0.3 s at the last iterate: the minimum
  time may be above it``); at the lower bound, the solver found the constraints violated
  least at the shortest time allowed, so a longer one does not help and the rest is named;
- otherwise (and after a lower bound) the declared constraint rows with the largest violation
  at the last iterate, by name (path constraints at the result's samples, point constraints
  at the start and final time, the state and input bounds), each with its excess and where
  it is largest;
- the bounded states and inputs held at a bound over most of the horizon
  (:func:`held_bounds`): a bound met everywhere is never a violated row, yet it is what
  stops a motion whose voltage may not change sign;
- and an input that has (almost) no effect on the states over much of the horizon
  (:func:`inert_inputs`): saturated inside the model (a ``Limiter``'s input beyond its
  corner), it leaves the NLP singular there, whatever the solver's step. A servo whose
  torque command passed a ``Limiter`` (smoothing 1e-3) ended ``Error_In_Step_Computation``
  with every constraint met (4e-14) and IPOPT's Hessian regularisation at 1e15.

:func:`with_culprit` appends that to a failed result's message (the result's, hence
``summary.json``'s and the command line's), and leaves a solution's message alone.
"""

from __future__ import annotations

import logging
import re
from typing import Any

import casadi as ca
import numpy as np

__all__ = ["likely_culprit", "with_culprit", "inert_inputs", "held_bounds", "AT_BOUND_RTOL", "VIOLATION_TOL", "TOP_ROWS",
           "INERT_RATIO", "INERT_FRACTION", "HELD_RTOL", "HELD_FRACTION"]

_log = logging.getLogger("gtmodel")

#: A final time within this relative distance of a bound is "at" it.
AT_BOUND_RTOL = 1e-6
#: Violations (relative to ``max(1, |bound|)``) below this are not reported.
VIOLATION_TOL = 1e-6
#: Constraint rows named at most.
TOP_ROWS = 3
#: An input is inert at a sample where its effect on the state derivatives is below this fraction of its largest (the
#: servo's torque command hovered at 0.503-0.509 N m, 3 to 9 smoothing widths past its Limiter's corner at 0.5 N m:
#: effect 1e-4 to 7e-2 of its largest, each further gain in torque below 1e-4 N m, IPOPT's steps there all
#: regularisation). An input that enters a model linearly (a voltage, a torque) has one effect everywhere.
INERT_RATIO = 0.1
#: ... and named when it is inert at more than this fraction of the samples.
INERT_FRACTION = 0.2
#: A bounded state or input within this fraction of its bounds' span (of ``max(1, |bound|)`` for a one-sided bound) of a
#: bound is "at" it ...
HELD_RTOL = 1e-4
#: ... and named as held when it is at a bound at least this fraction of the samples.
HELD_FRACTION = 0.5


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
        # the solver's infeasibility is smallest at the shortest time allowed: a longer one does not remove it, so the
        # constraints (named after this) stand in the way, not the final time (a double integrator with its input held
        # to [-1, -0.5] V ended here; naming the lower bound sent the user to the one knob that could not help)
        return (f"final_time at its lower bound {lo:g} s at the last iterate: a longer time does not meet the "
                "constraints, so look at those named")
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


def inert_inputs(result: Any, optimization: Any = None) -> list[tuple[str, float]]:
    """The inputs with (almost) no effect on the states over much of a result's horizon.

    The effect of input ``j`` at a sample is the norm of column ``j`` of ``d xdot / d u`` (through
    the algebraic equations: ``f_u - f_z g_z^-1 g_u``), each state row divided by the largest of
    its row over the samples (so that a state's units do not weigh). An input whose effect is below
    :data:`INERT_RATIO` of its largest at more than :data:`INERT_FRACTION` of the samples is
    inert: there the NLP's Hessian is singular in it (any value does the same), which interior-point
    solvers regularise without end.

    Parameters
    ----------
    result : OptimizationResult
        A result with a trajectory (``t``, ``states``, ``algebraics``, ``inputs``) and its ``dae``.
    optimization : Optimization, optional
        The problem it solved: its parameter values under the result's own.

    Returns
    -------
    list of tuple
        ``(input name, fraction of the samples where it is inert)``, largest fraction first; empty
        when every input acts (or the result has no inputs).
    """
    dae = result.dae
    t = np.asarray(result.t, dtype=float).reshape(-1)
    n = t.size
    if dae is None or not dae.nu or not dae.nx or n == 0:
        return []
    x = _stacked(result.states, dae.x_vars, n, dae.nx)
    z = _stacked(result.algebraics, dae.z_vars, n, dae.nz)
    u = _stacked(result.inputs, dae.u_vars, n, dae.nu)
    given = {**dict(getattr(optimization, "parameters", None) or {}), **dict(result.parameters or {})}
    p = np.asarray(dae.parameter_vector(given), dtype=float).reshape(-1)
    f, g = dae.ode_expr, dae.alg_expr
    parts = [ca.jacobian(f, dae.u)]
    if dae.nz:
        parts += [ca.jacobian(f, dae.z), ca.jacobian(g, dae.z), ca.jacobian(g, dae.u)]
    jac = ca.Function("effect", [dae.t, dae.x, dae.z, dae.u, dae.p], parts)
    effect = np.zeros((n, dae.nx, dae.nu))
    for k in range(n):
        out = [np.array(m, dtype=float) for m in jac.call([t[k], x[k], z[k], u[k], p])]
        if not all(np.all(np.isfinite(m)) for m in out):
            return []
        effect[k] = out[0] if not dae.nz else out[0] - out[1] @ np.linalg.lstsq(out[2], out[3], rcond=None)[0]
    scale = np.abs(effect).max(axis=(0, 2))  # each state's largest response to any input
    scaled = np.abs(effect) / np.where(scale > 0, scale, 1.0)[None, :, None]
    norm = np.linalg.norm(scaled, axis=1)  # (n, nu)
    found = []
    for name, sl in dae.u_vars.items():
        col = norm[:, sl].max(axis=1)
        if col.max() <= 0:
            continue  # acts nowhere: the model's own matter, not a saturation
        share = float(np.mean(col < INERT_RATIO * col.max()))
        if share > INERT_FRACTION:
            found.append((name, share))
    return sorted(found, key=lambda item: -item[1])


def held_bounds(result: Any, optimization: Any) -> list[tuple[str, str, float, float]]:
    """The bounded states and inputs that sit at a bound over most of a result's horizon.

    A failed solve whose last iterate holds a variable at its bound almost everywhere is being
    stopped by that bound (a motor whose voltage may not be positive cannot turn its load
    forwards, however long it is given); the variable bound itself is met, so the violated rows
    name only its consequences (the final position missed).

    Parameters
    ----------
    result : OptimizationResult
        A result with a trajectory (``t``, ``states``, ``inputs``) and its ``dae``.
    optimization : Optimization
        The problem it solved (its bounds).

    Returns
    -------
    list of tuple
        ``(name, "lower" or "upper", bound, fraction of the samples at it)`` for each bounded state
        or input element within :data:`HELD_RTOL` of a bound at no fewer than :data:`HELD_FRACTION`
        of the samples, largest fraction first; empty when none is (or there is no trajectory).
    """
    dae = result.dae
    t = np.asarray(result.t, dtype=float).reshape(-1)
    n = t.size
    if dae is None or n == 0:
        return []
    found = []
    for kind, variables, values in (("x", dae.x_vars, result.states), ("u", dae.u_vars, result.inputs)):
        lb, ub = (np.asarray(v, dtype=float) for v in optimization.bounds_vectors(dae, kind))
        for name, sl in variables.items():
            if name not in values:
                continue
            vals = np.asarray(values[name], dtype=float).reshape(n, -1)
            for j, (lo, hi) in enumerate(zip(lb[sl], ub[sl])):
                span = hi - lo if np.isfinite(hi - lo) else np.nan
                label = name if vals.shape[1] == 1 else f"{name}[{j}]"
                for side, bound in (("lower", lo), ("upper", hi)):
                    if not np.isfinite(bound):
                        continue
                    tol = HELD_RTOL * (span if np.isfinite(span) and span > 0 else max(1.0, abs(bound)))
                    share = float(np.mean(np.abs(vals[:, j] - bound) <= tol))
                    if share >= HELD_FRACTION:
                        found.append((label, side, float(bound), share))
    return sorted(found, key=lambda item: -item[3])


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
        :data:`VIOLATION_TOL`), and/or ``"bounds held over most of the horizon ('u' at its upper
        bound -0.5 at 100 % of the samples): ..."`` (:func:`held_bounds`; after the upper bound of
        the final time too), and/or ``"an input with almost no effect on the states over much of the
        horizon ('u' at 60 % of the samples; ...)"`` (:func:`inert_inputs`); or ``""``.
    """
    at_bound = _final_time_at_bound(result, optimization)
    # at the upper bound the horizon is what the solver ran out of: a longer one, or looser held bounds (a bang-bang
    # input at its limits, or a voltage allowed no sign), are the remedies; the rows missed say nothing more then
    diagnoses = (held_bounds,) if "upper bound" in at_bound else (_rows, inert_inputs, held_bounds)
    rows, inert, held = [], [], []
    for diagnose in diagnoses:
        try:
            found = diagnose(result, optimization)
        except (RuntimeError, ValueError, KeyError, AttributeError, TypeError, np.linalg.LinAlgError) as exc:
            _log.debug("no diagnosis of the failed solve by %s: %s", diagnose.__name__, exc)  # never hides the failure
            continue
        if diagnose is _rows:
            rows = found
        elif diagnose is inert_inputs:
            inert = found
        else:
            held = found
    said = [at_bound] if at_bound else []
    if rows:
        worst = "; ".join(f"{name} by {excess:.3g} at t = {t:.4g} s" for _, name, excess, t in rows[:TOP_ROWS])
        said.append(f"the largest violations at the last iterate: {worst}")
    if held:
        names = ", ".join(f"'{name}' at its {side} bound {bound:g} at {100 * share:.0f} % of the samples"
                          for name, side, bound, share in held[:TOP_ROWS])
        said.append(f"bounds held over most of the horizon ({names}): the motion may need more than they allow "
                    "(loosen them in [bounds])")
    if inert:
        names = ", ".join(f"'{name}' at {100 * share:.0f} % of the samples" for name, share in inert)
        said.append(f"an input with almost no effect on the states over much of the horizon ({names}; below {INERT_RATIO:g} "
                    "of its largest effect): saturated inside the model (a Limiter on it?), where a larger input buys "
                    "almost nothing and the NLP is nearly singular; bound the input within the saturation in [bounds]")
    return "; ".join(said)

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
