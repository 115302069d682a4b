"""Declared state bounds held by a loop law without constraint rows: the input projected onto the admissible set of one period.

A tracking law ``u = sat(u* - K (x - x*))`` knows its input bounds but not the declared state bounds of its plant (a
motor current limit): a held-out ball-screw axis's TV-LQR, its plan at 12 of 15 A and its plant 20 % heavier, drew
100 A (issue 65). :class:`StateLimits` gives the law what an MPC's constraint rows give it, for one period: the
bounded states ``c(u)`` after each substep of the period the input acts over (the prediction's fixed step,
:func:`gtmodel.control.problem.substep_states`, from the state when the input starts to act), linearised in the
input at the law's own ``u0``,

.. math::

    c(u) \\approx c(u_0) + J (u - u_0), \\qquad lb \\le c(u) \\le ub,

and the law's input projected onto these half-spaces one after the other and then onto the input box (the method of
alternating projections; von Neumann 1950, Bauschke & Borwein, SIAM Review 38, 1996). With one input the
projections are intervals and one sweep ends in their intersection when it is not empty (each projection moves
the input towards the next interval without leaving the earlier ones); with several, :data:`SWEEPS` sweeps approach
it. Where the intersection is empty (the state is beyond its bound whatever the input does within one period),
the sweep ends at the last row's side: the input that pulls the state back hardest within its bounds.
A row the input cannot move by :data:`MIN_REACH` of its bound's size within one period is left out (a position,
the speed of a large inertia): this one-period look-ahead cannot hold it, the reference must.

Everything is one CasADi graph (:meth:`StateLimits.project`), generated into the law's C step.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

import casadi as ca
import numpy as np

from gtmodel.control.bounds import aimed
from gtmodel.control.state_filter import PARAMETER_ERROR
from gtmodel.errors import InputError

__all__ = ["SWEEPS", "MIN_REACH", "ORDER", "BACKOFF_GAIN", "MARGIN_ERROR", "StateLimits", "envelope", "parameter_margin", "state_limits"]

#: Sweeps of the alternating projections with more than one input (one input: one sweep is exact).
SWEEPS = 10
#: A row enters the projection when the input's range moves it by at least this fraction of its bound's size in one period.
MIN_REACH = 1e-3
#: Gain per period at which the back-off's error falls towards a smaller or opposite measurement (:func:`envelope`; the
#: MPC's rows, :func:`gtmodel.control.mpc_memory.row_backoff`; the tracking law's, :meth:`StateLimits.project`).
BACKOFF_GAIN = 0.3
#: The rows' order in the projection: by the input's authority over each state within one period along the reference
#: (the median over its samples of ``|dx/du| span(u) / |bound|``), the weakest first. With one input the last
#: projection's row always holds and an earlier one holds where the rows are consistent: where they are not (a
#: motor speed near its limit that one period's voltage barely moves, and the current), the state the input
#: commands directly wins (a belt drive's TV-LQR, its speed row last, drove the current to -43.9 A of 14.2).
ORDER = "authority, weakest first"
#: Each of the model's parameters' relative error the a-priori margin of the first periods assumes
#: (:func:`parameter_margin`): half the filter's :data:`~gtmodel.control.state_filter.PARAMETER_ERROR`, since the margin
#: sums every parameter's change in squares (a drive has 10-20 parameters). With 20 % the margin ate the room a
#: minimum-time plan leaves below its current bound, which the heavier plant needs from the first period (drive0_22's
#: TV-LQR: ratio 0.42 to the feedforward against 0.12 with 10 %); with 10 % the family's first-period excesses are
#: still held (drive0_11: 17.37 A of 18.1 after the first period, 18.34 A without a margin).
MARGIN_ERROR = 0.5 * PARAMETER_ERROR


def envelope(kept: Any, measured: Any, scale: np.ndarray) -> Any:
    """The back-off's error: the envelope of the measured one-period prediction errors (fast attack, slow release).

    A measurement larger than the kept error (in the norm of the errors scaled by the states' scales; the whole
    vector, so that the errors of a current and of the speed whose back-EMF drives it stay together) replaces it at
    once: an error that grows as a mismatched load accelerates is met the period it shows. A smaller one is approached
    at :data:`BACKOFF_GAIN` per period, so that an input swinging each period does not swing the rows with it: a
    back-off that followed each period's error fed a vertical ball screw's MPC its own swing (its voltage between
    2 and 20 V each period, its current 16 % beyond the bound), and a plain low-pass filter lagged the error's growth
    (a flexible joint: 2.1 % over its current limit at the samples).

    Parameters
    ----------
    kept : casadi.MX
        ``(n, 1)`` the error kept from the last period.
    measured : casadi.MX
        ``(n, 1)`` this period's measurement.
    scale : numpy.ndarray
        ``(n,)`` positive scales of the states (:func:`~gtmodel.control.reference.reference_scales`).

    Returns
    -------
    casadi.MX
        ``(n, 1)`` the new kept error.
    """
    weight = ca.DM(1.0 / np.asarray(scale, dtype=float))
    larger = ca.sumsqr(measured * weight) > ca.sumsqr(kept * weight)
    return ca.if_else(larger, measured, kept + BACKOFF_GAIN * (measured - kept))


@dataclass
class StateLimits:
    """The bounded states of one period and their bounds (see the module docstring).

    Parameters
    ----------
    rows : casadi.Function
        ``rows(x (nx,1), u (nu,1)) -> (c (m,1), J (m,nu))``: the bounded states after each substep of one period
        from ``x`` under ``u`` held, and their Jacobian in ``u``.
    lb, ub : numpy.ndarray
        ``(m,)`` each row's bounds (``-inf`` / ``inf``: none).
    names : list of str
        ``(m,)`` ``"<state>@<substep>"`` per row.
    reach : numpy.ndarray
        ``(m,)`` the smallest ``|J_r| * span(u)`` that enters a row (:data:`MIN_REACH` times the bound's size).
    span : numpy.ndarray
        ``(nu,)`` the inputs' ranges (``u_ub - u_lb``; the feedforward's range where a bound is infinite).
    index : numpy.ndarray, optional
        ``(m,)`` each row's state index.
    fraction : numpy.ndarray, optional
        ``(m,)`` each row's substep's share of the period (``(k + 1) / substeps``).
    rows_p : casadi.Function or None, optional
        ``rows_p(x, u, p) -> c``: the rows with the model's parameters free (:func:`parameter_margin`).
    """

    rows: ca.Function
    lb: np.ndarray
    ub: np.ndarray
    names: list[str]
    reach: np.ndarray
    span: np.ndarray
    index: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    fraction: np.ndarray = field(default_factory=lambda: np.zeros(0))
    rows_p: ca.Function | None = field(default=None, repr=False)

    @property
    def n_rows(self) -> int:
        """Number of rows ``m`` (bounded states times substeps)."""
        return int(self.lb.size)

    def project(self, x: Any, u0: Any, u_lb: np.ndarray, u_ub: np.ndarray, error: Any = None, delay: int = 0,
                margin: Any = None) -> Any:
        """The input nearest the law's ``u0`` that keeps the linearised rows within their bounds, then saturated.

        Parameters
        ----------
        x : casadi.MX
            ``(nx, 1)`` the state when the input starts to act.
        u0 : casadi.MX
            ``(nu, 1)`` the law's input.
        u_lb, u_ub : numpy.ndarray
            ``(nu,)`` the input bounds (applied last: the result is always within them).
        error : casadi.MX, optional
            ``(nx, 1)`` the model's one-period prediction error measured in the loop (:func:`envelope`), taken to
            recur: the rows are also predicted from ``x + delay * error`` with each substep's share of it added, and
            each bound is held by the nearer of the two predictions (the back-off; a bound is never loosened).
            None: none.
        delay : int, optional
            Periods between the measurement and ``x`` (the input delay the law compensates: 0 or 1).
        margin : casadi.MX, optional
            ``(m, 1)`` each row's a-priori error, held off either side (:func:`parameter_margin`; the back-off is
            the larger of it and the measured error's); None: none.

        Returns
        -------
        casadi.MX
            ``(nu, 1)``.
        """
        c0, J = self.rows(x, u0)
        c_lo = c_hi = c0
        for e in () if error is None else (error,):
            shifted = self.rows(x + delay * e, u0)[0] + ca.DM(self.fraction) * e[[int(i) for i in self.index]]
            c_lo, c_hi = ca.fmin(c_lo, shifted), ca.fmax(c_hi, shifted)
        if margin is not None:
            c_lo, c_hi = ca.fmin(c_lo, c0 - margin), ca.fmax(c_hi, c0 + margin)
        nu = int(np.size(u_lb))
        u = u0
        for _ in range(1 if nu == 1 else SWEEPS):
            for r in range(self.n_rows):
                a = J[r, :].T
                norm2 = ca.sumsqr(a)
                reach = ca.sqrt(ca.sumsqr(a * ca.DM(self.span))) if nu > 1 else ca.fabs(a[0]) * float(self.span[0])
                move = ca.dot(a, u - u0)
                over = ca.fmax(c_hi[r] + move - float(self.ub[r]), 0) if np.isfinite(self.ub[r]) else 0
                under = ca.fmax(float(self.lb[r]) - c_lo[r] - move, 0) if np.isfinite(self.lb[r]) else 0
                step = ca.if_else(reach >= float(self.reach[r]), (under - over) / ca.fmax(norm2, 1e-300), 0)
                u = u + a * step
            u = ca.fmin(ca.fmax(u, ca.DM(u_lb)), ca.DM(u_ub))
        return u


def state_limits(substeps: ca.Function, x_names: list[str], bounds: Mapping[str, tuple[float, float]], p: np.ndarray,
                 u_lb: np.ndarray, u_ub: np.ndarray, u_ref: np.ndarray, x_ref: np.ndarray | None = None) -> StateLimits | None:
    """The rows of the declared state bounds over one period of a model's fixed step.

    Parameters
    ----------
    substeps : casadi.Function
        ``S(x, u, p) -> (nx, s)`` the states after each substep (:func:`gtmodel.control.problem.substep_states`).
    x_names : list of str
        ``(nx,)`` the state names.
    bounds : mapping of str to (float, float)
        Declared bounds by state name (names that are not states are ignored; both sides infinite: none); the rows
        aim :data:`~gtmodel.control.bounds.TARGET_MARGIN` inside them (:func:`~gtmodel.control.bounds.aimed`).
    p : numpy.ndarray
        ``(np,)`` the model's parameters (the prediction's).
    u_lb, u_ub : numpy.ndarray
        ``(nu,)`` input bounds.
    u_ref : numpy.ndarray
        ``(N, nu)`` the feedforward (the inputs' span where a bound is infinite).
    x_ref : numpy.ndarray, optional
        ``(N, nx)`` the reference's states: where the input's authority over each bounded state is measured (the
        rows' order, :data:`ORDER`); default none (the states' order).

    Returns
    -------
    StateLimits or None
        None when no state has a finite bound.

    Raises
    ------
    InputError
        A bound with ``lb > ub`` or not a number.
    """
    picked = []
    for j, name in enumerate(x_names):
        if name not in bounds:
            continue
        try:
            lo, hi = (float(v) for v in bounds[name])
        except (TypeError, ValueError):
            raise InputError(f"state bounds: {name!r}: expected (lb, ub) numbers, got {bounds[name]!r}") from None
        if not lo <= hi:
            raise InputError(f"state bounds: {name!r}: expected lb <= ub, got [{lo}, {hi}]")
        if np.isfinite(lo) or np.isfinite(hi):
            picked.append((j, name, *aimed(lo, hi)))  # TARGET_MARGIN inside the declared bound
    if not picked:
        return None
    nx, nu = len(x_names), int(np.size(u_lb))
    x, u = ca.SX.sym("x", nx), ca.SX.sym("u", nu)
    states = substeps(x, u, ca.DM(np.asarray(p, dtype=float)))
    s = int(states.size2())
    ref = np.atleast_2d(np.asarray(u_ref, dtype=float))
    span = np.where(np.isfinite(u_ub - u_lb), u_ub - u_lb, np.ptp(ref, axis=0) + 1.0)
    size = {j: max(abs(v) for v in (lo, hi) if np.isfinite(v)) or 1.0 for j, _, lo, hi in picked}
    if x_ref is not None:  # the weakest authority first: the last projection's row holds (one input), the current over a speed
        sens = ca.Function("sens", [x, u], [ca.jacobian(states[:, -1], u)]).map(ref.shape[0])
        gain = np.abs(np.asarray(sens(np.asarray(x_ref, dtype=float).T, ref.T))).reshape(nx, ref.shape[0], nu)
        authority = {j: float(np.median(gain[j] @ span)) / size[j] for j, _, _, _ in picked}
        picked.sort(key=lambda row: authority[row[0]])
    order = [(k, row) for row in picked for k in range(s)]  # a state's rows together, the states in ORDER
    c = ca.vertcat(*[states[j, k] for k, (j, _, _, _) in order])
    rows = ca.Function("state_rows", [x, u], [c, ca.jacobian(c, u)], ["x", "u"], ["c", "J"])
    psym = ca.SX.sym("p", int(np.size(p)))
    free = substeps(x, u, psym)
    rows_p = ca.Function("state_rows_p", [x, u, psym], [ca.vertcat(*[free[j, k] for k, (j, _, _, _) in order])], ["x", "u", "p"], ["c"])
    return StateLimits(rows=rows, lb=np.array([lo for _, (_, _, lo, _) in order]), ub=np.array([hi for _, (_, _, _, hi) in order]),
                       names=[f"{name}@{k + 1}" for k, (_, name, _, _) in order],
                       reach=MIN_REACH * np.array([size[j] for _, (j, _, _, _) in order]), span=np.asarray(span, dtype=float),
                       index=np.array([j for _, (j, _, _, _) in order], dtype=int), fraction=np.array([(k + 1) / s for k, _ in order]),
                       rows_p=rows_p)


def parameter_margin(rows_p: ca.Function, step: ca.Function, x_ref: np.ndarray, u_ref: np.ndarray, p: np.ndarray, delay: int = 0,
                     lead: int = 0, error: float = MARGIN_ERROR) -> np.ndarray:
    """Each row's a-priori error along the reference: what the model's parameters ``error`` off move it, faded as measured.

    Before the loop has measured its model's error (the back-off's envelope, :func:`envelope`, needs a period of the
    plan under way and the input delay's), the rows are held off by an error of the model assumed a priori
    (:data:`MARGIN_ERROR` of each parameter): at period ``k`` of the reference, the
    rows over the period from the state the law predicts for it (with ``delay`` 1, one period from ``x*_{k-1}`` under
    ``u*_{k-1}``; else ``x*_k``) under ``u*_k``, each row's change with each parameter ``error`` off, either way (the
    larger), summed in squares over the parameters (a change, not a derivative: a drive's current row read 260 A of
    sensitivity for a 17.7 A bound from its stiff gear and smoothed friction, 0.37 A as the change), then faded at :data:`BACKOFF_GAIN` per period from the first period whose error the loop has
    measured (``lead + delay`` periods in), as the envelope releases a kept error. A ball-screw axis's TV-LQR (plan at
    0.8 of its 18.1 A, its table 20 % heavier) drew 18.34 A after the plan's first period, its model's prediction
    16.2 A (issue 65's drive family, drive0_11).

    Parameters
    ----------
    rows_p : casadi.Function
        ``rows_p(x, u, p) -> c (m, 1)``: the rows over one period from ``x`` under ``u`` held, the parameters free
        (:attr:`StateLimits.rows_p`; an MPC's first stage, :func:`gtmodel.control.mpc_memory.first_stage_rows`).
    step : casadi.Function
        ``step(x, u, p) -> x_next``: the model's fixed step over one period (the prediction's).
    x_ref : numpy.ndarray
        ``(N, nx)`` the sampled reference.
    u_ref : numpy.ndarray
        ``(N, nu)`` its inputs.
    p : numpy.ndarray
        ``(np,)`` the model's parameters.
    delay : {0, 1}, optional
        The input delay the law compensates.
    lead : int, optional
        Periods at rest before the plan (:func:`~gtmodel.control.reference.delayed_start`).
    error : float, optional
        Each parameter's relative error (default :data:`MARGIN_ERROR`).

    Returns
    -------
    numpy.ndarray
        ``(N, m)`` the rows' margins per period (>= 0).
    """
    x_ref, u_ref, p = (np.asarray(v, dtype=float) for v in (x_ref, u_ref, p))
    n, nx, nu = x_ref.shape[0], x_ref.shape[1], u_ref.shape[1]
    x, u_prev, u, ps = ca.SX.sym("x", nx), ca.SX.sym("u_prev", nu), ca.SX.sym("u", nu), ca.SX.sym("p", p.size)
    start = step(x, u_prev, ps) if delay else x
    start = start[0] if isinstance(start, (list, tuple)) else start
    rows = ca.Function("rows", [x, u_prev, u, ps], [rows_p(start, u, ps)]).map(n)
    before = np.vstack([x_ref[:1], x_ref[:-1]]) if delay else x_ref
    args = (before.T, np.vstack([u_ref[:1], u_ref[:-1]]).T, u_ref.T)
    nominal = np.asarray(rows(*args, np.tile(p[:, None], (1, n))))
    squares = np.zeros_like(nominal)
    for j in np.flatnonzero(p):  # each parameter error off either way, the larger change of each row
        moved = [np.asarray(rows(*args, np.tile((p + sign * error * p[j] * np.eye(p.size)[j])[:, None], (1, n)))) for sign in (-1.0, 1.0)]
        change = np.maximum(*(np.abs(v - nominal) for v in moved))
        squares += np.where(np.isfinite(change), change, 0.0) ** 2
    margin = np.sqrt(squares).T
    fade = (1.0 - BACKOFF_GAIN) ** np.maximum(np.arange(n) - lead - delay, 0)
    return margin * fade[:, None]
