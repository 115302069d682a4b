"""The MPC step's memory beyond its warm start: the offset-free input-disturbance estimate and the reset.

With :attr:`~gtmodel.control.mpc.MPCController.disturbance_gain` the memory of the generated
step (:mod:`gtmodel.codegen.loop_step`) holds, after the blocked inputs ``w``, the estimate
``d (nu)``, the last measured state ``(nx)``, the last ``u_last (nu)`` and a flag (1 once a
step ran). The estimate is updated each period from the one-period prediction error of the
last measured state, ``d += gain (B'B + eps I)^{-1} B' (x - F(x_prev, u_act + d))``
(``B = dF/du`` there; Pannocchia & Rawlings, AIChE J. 49 (2003), the input-disturbance
model; Maeder, Borrelli & Morari, Automatica 45 (2009)). With
:attr:`~gtmodel.control.mpc.MPCController.constraint_backoff` the memory holds the same (the estimate
zero without a gain), and the constraint rows are tightened by the one-period prediction error of the
constrained quantities (:func:`row_backoff`). The functions take the controller ``c`` (an
:class:`~gtmodel.control.mpc.MPCController`) as their first argument.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from gtmodel.control.bounds import aimed, bound_size
from gtmodel.control.mpc_nlp import between_rows, period_states
from gtmodel.control.reference import period_index
from gtmodel.control.state_limits import BACKOFF_GAIN, envelope
from gtmodel.control.tracking import saturate

__all__ = ["BACKOFF_CAP", "disturbance_estimate", "first_stage_rows", "memory_estimates", "memory_extra", "memory_layout", "memory_predict", "memory_reset", "row_backoff",
           "backoff_error", "backoff_rows", "tightened_rows"]

#: With the reference given, :func:`row_backoff` tightens a row by at most the larger of the plan's own room to the bound
#: there and this fraction of the bound's size (the model error a plan's margin is chosen for: a load 20 % heavier,
#: docs/model_in_the_loop.md). A larger back-off excludes the plan itself, the rows turn infeasible and their penalty
#: steers: a vertical ball screw's error envelope, swollen by the loop's own swing to 48 % of the current's scale, cut
#: its rows to a third of the bound (tracking RMS 0.74 of the feedforward's, the current 17.7 % beyond; capped, 0.16
#: and 10.8 %).
BACKOFF_CAP = 0.2


def memory_layout(c: Any) -> dict[str, int]:
    """The estimator's part of the step's memory after the warm start, in order, by name and length.

    Parameters
    ----------
    c : MPCController
        The controller.

    Returns
    -------
    dict of str to int
        Empty without :attr:`~gtmodel.control.mpc.MPCController.estimates`; else ``d`` (``nu``), ``x`` (``nx``, the last
        measured state), ``u`` (``nu``, the last ``u_last``), with the back-off ``error`` (``nx``, the envelope of the
        one-period prediction errors, :func:`row_backoff`), and ``ran`` (1, a flag: 1 once a step ran).
    """
    if not c.estimates:
        return {}
    backoff = bool(c.constraint_backoff and c.constraints is not None)
    return {"d": c.nu, "x": c.nx, "u": c.nu, **({"error": c.nx} if backoff else {}), "ran": 1}


def memory_extra(c: Any, d: Any, x: Any, u: Any, ran: Any, error: Any = None) -> Any:
    """The estimator's part of the memory from its pieces (:func:`memory_layout`), NumPy rows or CasADi columns.

    Parameters
    ----------
    c : MPCController
        The controller.
    d, x, u, ran : numpy.ndarray or casadi.MX
        The estimate, the last measured state, the last input and the flag: ``(n,)`` vectors, or ``(2, n)`` ranges
        (NumPy, stacked by columns), or CasADi columns.
    error : numpy.ndarray or casadi.MX, optional
        The prediction errors' envelope (zeros of ``x``'s shape when None), used only with the back-off.

    Returns
    -------
    numpy.ndarray or casadi.MX
        The pieces joined (an empty array without :attr:`~gtmodel.control.mpc.MPCController.estimates`).
    """
    layout = memory_layout(c)
    if not layout:
        return np.zeros(0)
    symbolic = isinstance(x, (ca.MX, ca.SX))
    zero = (ca.DM.zeros(c.nx) if symbolic else np.zeros_like(np.asarray(x, dtype=float))) if error is None else error
    parts = [d, x, u] + ([zero] if "error" in layout else []) + [ran]
    if symbolic:
        return ca.vertcat(*parts)
    arrays = [np.asarray(v, dtype=float) for v in parts]
    return np.hstack(arrays) if arrays[1].ndim == 2 else np.concatenate([np.atleast_1d(v) for v in arrays])


def _estimator_memory(c: Any, u_last: ca.MX, mem: ca.MX) -> tuple[ca.MX, ca.MX, ca.MX, ca.MX]:
    """The estimate ``d``, the last measured state, the input that acted over the last period and the flag, from the memory."""
    nx, nu, nw = c.nx, c.nu, c.nw
    d, x_prev, u_prev, ran = mem[nw:nw + nu], mem[nw + nu:nw + nu + nx], mem[nw + nu + nx:nw + 2 * nu + nx], mem[-1]
    # the input that acted over the last period: the one computed then (u_last now) without a delay, with a
    # one-period delay the one computed a period earlier (u_last then, kept in the memory)
    return d, x_prev, (u_last if c.delay == 0 else u_prev), ran


def memory_predict(c: Any) -> ca.Function:
    """The state the memory predicts for now (:meth:`~gtmodel.control.mpc.MPCController.memory_predict`).

    Parameters
    ----------
    c : MPCController
        A controller with a non-zero ``disturbance_gain``.

    Returns
    -------
    casadi.Function
        ``predict(u_last (nu,1), w (n_memory,1)) -> x (nx,1)``: ``c.step`` from the last measured state
        with the input that acted over the last period plus the estimate.
    """
    u_last, mem = ca.MX.sym("u_last", c.nu), ca.MX.sym("w", c.n_memory)
    d, x_prev, u_act, _ = _estimator_memory(c, u_last, mem)
    return ca.Function("predict", [u_last, mem], [c.step(x_prev, u_act + d)], ["u_last", "w"], ["x"])


def disturbance_estimate(c: Any, x: ca.MX, u_last: ca.MX, mem: ca.MX) -> ca.MX:
    """The input-disturbance estimate of this period (see the module docstring) from the memory ``mem``.

    Parameters
    ----------
    c : MPCController
        A controller with a non-zero ``disturbance_gain``.
    x : casadi.MX
        ``(nx, 1)`` the measured state.
    u_last : casadi.MX
        ``(nu, 1)`` the step's ``u_last``.
    mem : casadi.MX
        ``(n_memory, 1)`` the step's memory.

    Returns
    -------
    casadi.MX
        ``(nu, 1)`` the updated estimate ``d`` (unchanged before the first step ran: the memory
        holds no measured state then).
    """
    d, x_prev, u_act, ran = _estimator_memory(c, u_last, mem)
    xs, us = ca.MX.sym("x", c.nx), ca.MX.sym("u", c.nu)
    B = ca.Function("B", [xs, us], [ca.jacobian(c.step(xs, us), us)])(x_prev, u_act + d)
    btb = ca.mtimes(B.T, B)
    eps = 1e-9 * (ca.trace(btb) / c.nu + 1e-300)
    gain = ca.solve(btb + eps * ca.DM.eye(c.nu), B.T)  # (B'B + eps I)^{-1} B': least squares of the state error
    innovation = x - memory_predict(c)(u_last, mem)  # the measurement less the state the memory predicts
    return ca.if_else(ran > 0.5, d + c.disturbance_gain * ca.mtimes(gain, innovation), d)


def memory_reset(c: Any) -> ca.Function:
    """The step's memory reset to the reference's at the current period (:meth:`~gtmodel.control.mpc.MPCController.memory_reset`).

    Parameters
    ----------
    c : MPCController
        The controller.

    Returns
    -------
    casadi.Function
        ``reset(t (1,1), x (nx,1)) -> (u_last (nu,1), w (n_memory,1))``.
    """
    t, x = ca.MX.sym("t"), ca.MX.sym("x", c.nx)
    n, nu, b = c.length, c.nu, c.horizon // c.blocks
    values = ca.MX(ca.DM(c.u_ref.reshape(-1)))

    def u_star(k: Any) -> ca.MX:
        return saturate(ca.vertcat(*[values[nu * ca.fmin(k, n - 1) + i] for i in range(nu)]), c.u_lb, c.u_ub)

    u_last = u_star(period_index(t, c.t0, c.dt, n - 1))
    k = period_index(t + c.delay * c.dt, c.t0, c.dt, n - 1)
    w = ca.vertcat(*[u_star(k + s * b) for s in range(c.blocks)])
    if c.estimates:
        w = ca.vertcat(w, memory_extra(c, ca.DM.zeros(nu), x, u_last, 0.0))
    return ca.Function("reset", [t, x], [u_last, w], ["t", "x"], ["u_last", "w"])


def first_stage_rows(cons: Any, substeps: ca.Function, between: int) -> ca.Function:
    """The constrained quantities over an MPC's first period with the model's parameters free (its a-priori margin).

    Parameters
    ----------
    cons : MPCConstraints
        The MPC's constraints.
    substeps : casadi.Function
        ``S(x, u, p) -> (nx, s)`` the prediction's states after each substep (:func:`gtmodel.control.problem.substep_states`).
    between : int
        The states inside the period that carry rows (:func:`~gtmodel.control.mpc_nlp.between_rows`; 0: the end only).

    Returns
    -------
    casadi.Function
        ``rows_p(x, u, p) -> c ((between + 1) m, 1)``: ``cons.function`` at each of those states and the period's end, in
        :func:`row_backoff`'s order (for :func:`~gtmodel.control.state_limits.parameter_margin`).
    """
    nx, nu = cons.function.size1_in(0), cons.function.size1_in(1)
    x, u, p = ca.SX.sym("x", nx), ca.SX.sym("u", nu), ca.SX.sym("p", substeps.size1_in(2))
    states = substeps(x, u, p)
    points = list(range(between)) + [int(states.size2()) - 1]
    return ca.Function("rows_p", [x, u, p], [ca.vertcat(*[cons.function(states[:, m], u) for m in points])], ["x", "u", "p"], ["c"])


def row_backoff(c: Any, x: ca.MX, x_start: ca.MX, w: ca.MX, u_last: ca.MX, mem: ca.MX, x_ref: Any = None, u_ref: Any = None,
                margin: Any = None) -> tuple[ca.MX, ca.MX]:
    """The lower bounds of the constraint rows: each declared bound tightened by the prediction's observed error.

    The one-period prediction error of the state, ``x - F(x_prev, u_act + d)`` (the memory's prediction,
    :func:`memory_predict`), is kept in the memory as its envelope ``e`` (:func:`~gtmodel.control.state_limits.envelope`:
    a larger error at once, a smaller one approached slowly; zero before a step ran), and taken to recur, each
    period's share of it :data:`~gtmodel.control.state_limits.BACKOFF_GAIN` smaller than the last's: the horizon is
    predicted from its start under the warm start's inputs as the model predicts it and with ``e`` added over the
    input delay's period and ``0.7^j e`` after period ``j``, at every point that carries rows (the substeps inside
    get their fraction of the period's share). The loop measures again each period, so an error does not add up over
    the whole horizon (a speed's error, carried undiminished through 20 periods, reached the current rows many times
    over and drove a belt drive 6 % beyond its current limit), yet a persistent push towards a bound still shows. Where
    the disturbed prediction of a constrained quantity lies nearer a bound than the model's, the row is tightened by
    the difference ``Delta c``:
    the lower bound by ``max(-Delta c, 0)``, the upper by ``max(Delta c, 0)``, each from the bound the controller
    aims at, :data:`~gtmodel.control.bounds.TARGET_MARGIN` inside the declared one (:func:`~gtmodel.control.bounds.aimed`;
    a bound is never loosened), scaled as the rows are (:mod:`gtmodel.control.mpc_constraints`); with the reference given,
    never tightened by more than the larger of the plan's own distance to the bound at that stage and :data:`BACKOFF_CAP`
    of the bound's size (nor by less than the aim's margin). The back-off of robust MPC (Mayne,
    Seron & Rakovic, Automatica 41 (2005)) from the error measured in the loop rather than a bound assumed: a
    flexible joint's plant 20 % heavier than its model drew 8.47 A under rows at 8 A, the prediction
    under-estimating the current by 0.36 A per period (issue 65).

    Parameters
    ----------
    c : MPCController
        A controller with constraint rows and the estimator's memory.
    x : casadi.MX
        ``(nx, 1)`` the measured state.
    x_start : casadi.MX
        ``(nx, 1)`` the horizon's first state (``x``, or with an input delay its prediction one period on).
    w : casadi.MX
        ``(nu * blocks, 1)`` the warm start (the inputs the rows are linearised at).
    u_last : casadi.MX
        ``(nu, 1)`` the step's ``u_last``.
    mem : casadi.MX
        ``(n_memory, 1)`` the step's memory.
    x_ref, u_ref : list of list of casadi.MX, optional
        The horizon's reference window (:meth:`~gtmodel.control.mpc.MPCController._window`: ``H`` rows of ``nx`` states
        at the periods' ends and of ``nu`` inputs), for the cap; default None: no cap.
    margin : casadi.MX, optional
        ``((between + 1) m, 1)`` the first period's a-priori errors of the constrained quantities
        (:attr:`~gtmodel.control.mpc.MPCController.margin`, :func:`first_stage_rows`' order): each of its rows is tightened
        by at least them (within the cap); default None: none.

    Returns
    -------
    lbg : casadi.MX
        ``(constraint_rows, 1)`` the rows' lower bounds (``>= 0``), in the NLP's order (per constrained stage the
        rows inside its period then its end, each in the order of the constraints' sides).
    error : casadi.MX
        ``(nx, 1)`` the errors' envelope, for the memory.
    """
    error = backoff_error(c, x, u_last, mem)
    cols = (lambda rows: None if rows is None else [ca.vertcat(*r) for r in rows])
    return tightened_rows(c, x_start, w, error, cols(x_ref), cols(u_ref), margin), error


def backoff_error(c: Any, x: ca.MX, u_last: ca.MX, mem: ca.MX) -> ca.MX:
    """``(nx, 1)`` the envelope of the one-period prediction error after this period's measurement (:func:`row_backoff`).

    Parameters
    ----------
    c : MPCController
        A controller with the estimator's memory.
    x : casadi.MX
        ``(nx, 1)`` the measured state.
    u_last : casadi.MX
        ``(nu, 1)`` the step's ``u_last``.
    mem : casadi.MX
        ``(n_memory, 1)`` the step's memory.

    Returns
    -------
    casadi.MX
        ``(nx, 1)``: the memory's envelope updated by ``x - F(x_prev, u_act + d)`` (less the filter's noise band);
        the memory's own before a step ran.
    """
    _, _, _, ran = _estimator_memory(c, u_last, mem)
    start = c.nw + 2 * c.nu + c.nx  # the envelope's place (memory_layout)
    kept = mem[start:start + c.nx]
    measured = x - memory_predict(c)(u_last, mem)
    if c.state_filter is not None:  # the innovation less the sensors' noise band
        measured = c.state_filter.model_error(measured)
    return ca.if_else(ran > 0.5, envelope(kept, measured, c.plausible_ranges(c.u_lb, c.u_ub)[0]), kept)


def backoff_rows(c: Any, with_margin: bool) -> tuple[Any, int]:
    """The back-off for :func:`~gtmodel.control.mpc_nlp.single_shooting_rti`: the rows' lower bounds from the rows its
    linearisation predicts under the warm start (one prediction, the disturbed one, besides the step's).

    Parameters
    ----------
    c : MPCController
        A controller with constraint rows and the estimator's memory (``solver = "sqpmethod"``).
    with_margin : bool
        Whether the inputs ``e`` carry the first period's a-priori margin after the envelope.

    Returns
    -------
    rows : callable
        ``rows(nominal, w, p, e) -> lbg``: :func:`tightened_rows` at the parameters ``p``
        (:meth:`~gtmodel.control.mpc.MPCController.parameters`' layout: the horizon's first state, then its reference
        window), ``e`` = the envelope ``(nx,)`` then the margin.
    n_e : int
        The size of ``e``.
    """
    nx, nu, H = c.nx, c.nu, c.horizon
    n_margin = (between_rows(c) + 1) * c.constraints.size if with_margin else 0

    def rows(nominal: Any, w: Any, p: Any, e: Any) -> Any:
        x_ref = [p[nx + j * nx:nx + (j + 1) * nx] for j in range(H)]
        u_ref = [p[nx + H * nx + j * nu:nx + H * nx + (j + 1) * nu] for j in range(H)]
        return tightened_rows(c, p[:nx], w[:c.nw], e[:nx], x_ref, u_ref, e[nx:] if n_margin else None, nominal)

    return rows, nx + n_margin


def tightened_rows(c: Any, x_start: Any, w: Any, error: Any, x_ref: Any = None, u_ref: Any = None, margin: Any = None,
                   nominal: Any = None) -> Any:
    """The rows' lower bounds of :func:`row_backoff` from the error envelope ``error``.

    Parameters
    ----------
    c : MPCController
        A controller with constraint rows.
    x_start : casadi.MX
        ``(nx, 1)`` the horizon's first state.
    w : casadi.MX
        ``(nu * blocks, 1)`` the warm start.
    error : casadi.MX
        ``(nx, 1)`` the envelope of the one-period prediction error.
    x_ref, u_ref : list of casadi.MX, optional
        ``H`` columns ``(nx, 1)`` / ``(nu, 1)``: the horizon's reference window, for the cap; default None: no cap.
    margin : casadi.MX, optional
        ``((between + 1) m, 1)`` the first period's a-priori errors (:func:`row_backoff`).
    nominal : casadi.MX, optional
        ``(constraint_rows, 1)`` the rows at the model's prediction under ``w`` in the NLP's order (the step's
        linearisation has them: :func:`~gtmodel.control.mpc_nlp.single_shooting_rti`); default None: predicted here.

    Returns
    -------
    casadi.MX
        ``(constraint_rows, 1)`` the rows' lower bounds (``>= 0``).
    """
    cons = c.constraints
    b, stages = c.horizon // c.blocks, set(cons.stages(c.horizon))
    inner, ns = between_rows(c), len(cons.sides)
    aim = [aimed(float(lo), float(hi)) for lo, hi in zip(cons.lb, cons.ub)]  # each side TARGET_MARGIN inside the declared
    aim_raw = [(aim[i][0] - float(cons.lb[i])) if s > 0 else (float(cons.ub[i]) - aim[i][1]) for i, s in cons.sides]
    scale = ca.DM([float(cons.scale[i]) for i, _ in cons.sides])
    aim_margin = ca.DM(aim_raw) / scale
    cap = ca.DM([max(BACKOFF_CAP * bound_size(float(cons.lb[i] if s > 0 else cons.ub[i]), float(cons.lb[i]), float(cons.ub[i])), m)
                 for (i, s), m in zip(cons.sides, aim_raw)]) / scale
    first = [None] * (inner + 1) if margin is None else [margin[q * cons.size:(q + 1) * cons.size] for q in range(inner + 1)]
    count = [0]

    def tightening(xa: Any, xb: Any, u: Any, j: int, prior: Any = None) -> Any:
        k = count[0]
        count[0] += 1
        rows_a = cons.rows(xa, u) if nominal is None else nominal[k * ns:(k + 1) * ns]
        held = ca.fmax(rows_a - cons.rows(xb, u), 0)  # the disturbed prediction's approach to the bound, scaled
        if prior is not None:
            held = ca.fmax(held, ca.vertcat(*[prior[i] for i, _ in cons.sides]) / scale)
        out = held + aim_margin
        if x_ref is None:
            return out
        # never tightened past the plan's own room there nor BACKOFF_CAP of the bound, whichever is larger
        room = cons.rows(x_ref[j], u_ref[min(j + 1, c.horizon - 1)])
        return ca.fmin(out, ca.fmax(room, cap))

    nominal_x, disturbed, share, out = x_start, x_start + c.delay * error, 1.0, []
    for j in range(c.horizon):  # the error recurs, each period's share of it BACKOFF_GAIN smaller than the last's
        u = w[(j // b) * c.nu:(j // b + 1) * c.nu]
        if j + 1 in stages:
            end_b, inside_b = period_states(c, disturbed, u)
            end_a, inside_a = period_states(c, nominal_x, u) if nominal is None else (None, [None] * len(inside_b))
            prior = first if j == 0 else [None] * (inner + 1)  # the a-priori margin: the first period's rows
            out += [tightening(xa, xb + share * (m + 1) / (inner + 1) * error, u, j, prior[m]) for m, (xa, xb) in enumerate(zip(inside_a, inside_b))]
            nominal_x, disturbed = end_a, end_b + share * error
            u_row = w[(min(j + 1, c.horizon - 1) // b) * c.nu:(min(j + 1, c.horizon - 1) // b + 1) * c.nu]
            out.append(tightening(nominal_x, disturbed, u_row, j, prior[inner]))
        else:
            nominal_x = c.step(nominal_x, u) if nominal is None else None
            disturbed = c.step(disturbed, u) + share * error
        share *= 1 - BACKOFF_GAIN
    return ca.vertcat(*out)


#: The estimates :func:`memory_estimates` reports: the memory's part, what it is, and the names it goes by.
ESTIMATES = {"d": ("input disturbance", "u_names"), "error": ("prediction error envelope", "x_names")}


def memory_estimates(c: Any, t: np.ndarray, memories: np.ndarray) -> list[dict[str, Any]]:
    """The estimator's figures along a closed loop, read from the step's memory after each period (the check's report).

    Parameters
    ----------
    c : MPCController or Any
        The controller; anything without the estimator's memory (:func:`memory_layout`) gives none.
    t : numpy.ndarray
        ``(n,)`` the periods' times [s].
    memories : numpy.ndarray
        ``(n, n_memory)`` the step's memory after each period (``<prefix>_memory.w``).

    Returns
    -------
    list of dict
        Per input of the disturbance estimate ``d`` (with a gain) and per state of the back-off's error envelope: ``kind``
        (:data:`ESTIMATES`), ``name``, ``largest`` (the value of the largest magnitude, the input's or state's unit),
        ``time`` [s] of it, ``last``, and ``relative``: ``|largest|`` over the input's range (its bounds' span) or the
        state's scale (:meth:`~gtmodel.control.mpc.MPCController.plausible_ranges`). Empty without an estimator.

    Raises
    ------
    ValueError
        ``memories`` not ``(len(t), n_memory)``.
    """
    if not isinstance(getattr(c, "disturbance_gain", None), float) or not memory_layout(c):
        return []
    m = np.asarray(memories, dtype=float)
    if m.ndim != 2 or m.shape != (np.size(t), c.n_memory):
        raise ValueError(f"memories: expected ({np.size(t)}, {c.n_memory}), got {m.shape}")
    span = np.asarray(c.u_ub, dtype=float) - np.asarray(c.u_lb, dtype=float)
    scales = {"d": np.where(np.isfinite(span), span, c.plausible_ranges(c.u_lb, c.u_ub)[1]),
              "error": c.plausible_ranges(c.u_lb, c.u_ub)[0]}
    out, start = [], c.nw
    for key, n in memory_layout(c).items():
        if key in ESTIMATES and (key != "d" or c.disturbance_gain):  # without a gain the estimate stays 0
            kind, names = ESTIMATES[key]
            block = m[:, start:start + n]
            for i, name in enumerate(getattr(c, names)):
                k = int(np.argmax(np.abs(block[:, i])))
                out.append({"kind": kind, "name": name, "largest": float(block[k, i]), "time": float(np.asarray(t)[k]),
                            "last": float(block[-1, i]), "relative": float(abs(block[k, i]) / scales[key][i])})
        start += n
    return out
