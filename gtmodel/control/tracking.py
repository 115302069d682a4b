"""A trajectory-tracking controller for any model: feedforward plus time-varying LQR.

From an optimal motion ``x*(t), u*(t)`` of a model (e.g. an ``optimal_control`` result) and
the model's explicit ODE (:func:`gtmodel.modeling.explicit_ode`), :func:`tracking_controller`
builds the controller of the loop with period ``dt`` (the 4 ms loop by default):

* the reference sampled at ``t_k = t_0 + k dt``: ``x*_k`` (linear interpolation of the given
  samples), ``u*_k`` the given input's mean over ``[t_k, t_k + dt]``, the period it is held
  (:func:`~gtmodel.control.reference.period_means`);
* the discretised linearisation along it: ``A_k = d step / d x``, ``B_k = d step / d u`` at
  ``(x*_k, u*_k)``, the Jacobians (CasADi AD) of the model's fixed step
  (:meth:`~gtmodel.modeling.ExplicitODE.step`, the same one the generated C integrates); where the
  reference rests (its start, its settling, the held end), the linearisation whose LQR gain is stable
  within :data:`~gtmodel.defaults.REST_NEIGHBOURHOOD` of the states' ranges around the rest point
  (:func:`~gtmodel.control.lqr.rest_linearization`: the rest point's own unless its gain fails there);
* the time-varying LQR gains from the backward discrete Riccati recursion
  (Anderson & Moore, Optimal Control: Linear Quadratic Methods, sec. 2.4)
  ``P_N = Q_f``, ``K_k = (R + B_k' P_{k+1} B_k)^{-1} B_k' P_{k+1} A_k``,
  ``P_k = Q + A_k' P_{k+1} (A_k - B_k K_k)``;
* the law ``u = sat(u*_k - K_k (x - x*_k))``, saturated at the input bounds (and, with
  declared state bounds, first projected so that the bounded states stay within them over
  the period it acts: :mod:`gtmodel.control.state_limits`); after the
  reference ends, its final state is held: the input that holds it (least squares
  ``f(x*_end, u) = 0``, e.g. zero voltage for a motor at rest) and the stationary LQR gain
  there (before the start, the first sample).

:meth:`TrackingController.function` is ONE CasADi Function of the step interface shared
by the loop controllers (:mod:`gtmodel.codegen.loop_step`): ``control(t, x, u_last) -> (u,
ok)``, the tables (references and gains) constant inside it, indexed by the period
``k = floor((t - t_0) / dt)`` (the first sample before the start, the held end after it);
:func:`gtmodel.codegen.loop_step.generate_loop_step` writes it as C. The LQR designs, and the gain at a rest point
designed for its neighbourhood (a friction's slope at rest is not a damping the loop keeps), are
:mod:`gtmodel.control.lqr`'s.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import casadi as ca
import numpy as np
import scipy.linalg

from gtmodel.defaults import LOOP_PERIOD_S, NOISE_GAIN_LIMIT
from gtmodel.errors import InputError
from gtmodel.control.lqr import RestLinearization, dlqr, rest_groups, rest_linearization, riccati_gains
from gtmodel.control.problem import substep_states, tracking_problem, weight_matrix
from gtmodel.control.state_filter import StateFilter
from gtmodel.control.state_limits import StateLimits, envelope, parameter_margin, state_limits
from gtmodel.control.reference import INDEX_EPS, MEMORY_LIMIT, SampledReference, hold_input, period_index, start_input
from gtmodel.modeling import ExplicitODE

__all__ = ["TrackingController", "tracking_controller", "limit_noise_gain", "weight_matrix", "saturate", "INDEX_EPS"]


def saturate(u: Any, lb: Any, ub: Any) -> Any:
    """``min(max(u, lb), ub)`` element-wise (NumPy arrays or CasADi expressions; infinite bounds bound nothing).

    Parameters
    ----------
    u : array_like or casadi.MX or casadi.SX
        Input, ``(nu,)`` or ``(nu, 1)``.
    lb, ub : array_like or casadi.MX or casadi.SX or casadi.DM
        ``(nu,)`` bounds (CasADi expressions with a CasADi ``u``).

    Returns
    -------
    same type as ``u``
        The saturated input.
    """
    if isinstance(u, (ca.MX, ca.SX)):
        lo, hi = (b if isinstance(b, (ca.MX, ca.SX, ca.DM)) else ca.DM(np.asarray(b, float)) for b in (lb, ub))
        return ca.fmin(ca.fmax(u, lo), hi)
    return np.minimum(np.maximum(np.asarray(u, dtype=float), lb), ub)


@dataclass
class TrackingController(SampledReference):
    """Feedforward plus time-varying LQR along a reference, sampled at the loop period.

    Parameters
    ----------
    dt : float
        Loop period [s].
    t0 : float
        Time of the first sample [s].
    x_ref : numpy.ndarray
        ``(N, nx)`` reference states ``x*_k`` at ``t_0 + k dt``.
    u_ref : numpy.ndarray
        ``(N, nu)`` feedforward ``u*_k``.
    K : numpy.ndarray
        ``(N, nu, nx)`` gains of ``u = u*_k - K_k (x - x*_k)``.
    u_lb, u_ub : numpy.ndarray
        ``(nu,)`` input bounds of the saturation (``-inf``/``inf``: none).
    x_names, u_names : list of str
        Scalar names of states and inputs.
    Q, R, Qf : numpy.ndarray
        The weights the gains were computed with.
    x_hold : numpy.ndarray
        ``(nx,)`` the state held after the reference ends: its last given sample ``x*_end``
        (at the reference's end time, which the period grid need not hit).
    u_hold : numpy.ndarray
        ``(nu,)`` the input that holds it (least squares ``f(x*_end, u) = 0``), saturated.
    K_hold : numpy.ndarray
        ``(nu, nx)`` the stationary LQR gain at ``(x*_end, u_hold)`` (``K_{N-1}`` if the
        pair is not stabilisable there).
    delay : int, optional
        Input delay [periods] the law compensates: 0 (default) or 1. With 1, the input
        computed at ``t_k`` acts from ``t_{k+1}``: the law predicts the state then,
        ``x^_{k+1} = F(x, u_last)`` (:attr:`predict`, the input acting now being the last
        one), and applies ``u = sat(u*_{k+1} - K_{k+1} (x^_{k+1} - x*_{k+1}))``.
    predict : casadi.Function, optional
        ``predict(x (nx,1), u (nu,1)) -> x_next``: the model's fixed step over one period
        (the one linearised), needed when ``delay`` is 1, with ``state_limits`` or a ``state_filter``
        (:func:`tracking_controller` always sets it).
    integral_states : tuple of int, optional
        Indices of the states with integral action (default none): the integrator state
        ``xi (ni,)``, ``xi_{k+1} = xi_k + dt (x - x*_k)[integral_states]``, is the step's
        inner memory, and the law is ``u = sat(u*_k - K_k (x - x*_k) - Ki_k xi_k)``; the
        integration stops while the input saturates (conditional integration, against
        wind-up).
    Ki : numpy.ndarray, optional
        ``(N, nu, ni)`` integral gains (with ``integral_states``).
    Ki_hold : numpy.ndarray, optional
        ``(nu, ni)`` the integral gain after the reference ends.
    Qi : numpy.ndarray, optional
        ``(ni, ni)`` the integrator states' weight the gains were computed with.
    u_start : numpy.ndarray or None, optional
        ``(nu,)`` the input acting before the first step arrives (:attr:`u_initial`):
        :func:`~gtmodel.control.reference.start_input`, the input that holds a start at rest;
        None: ``u*_0``.
    lead : int, optional
        Periods at rest the reference starts with before the plan (the input delay's:
        :func:`~gtmodel.control.reference.delayed_start`; default 0).
    gain_scale : numpy.ndarray or None, optional
        ``(N + 1, nu)`` the factors (<= 1) :func:`limit_noise_gain` scaled each period's gain rows by (the last row:
        the held end's); None: the Riccati gains as computed.
    state_limits : StateLimits or None, optional
        The declared state bounds the law holds over the period its input acts
        (:class:`~gtmodel.control.state_limits.StateLimits`: the input projected so that the bounded states after
        each substep stay within them, then saturated; the integrator holds while the projection or the
        saturation changes the input); None: the input bounds alone. With it the step's memory also holds the last
        measured state, the input that acted since, the errors' envelope and a flag (:attr:`n_memory`): each period the
        model's one-period prediction error is measured, kept as the errors' envelope
        (:func:`~gtmodel.control.state_limits.envelope`) and the rows are tightened by it (the back-off of
        :meth:`~gtmodel.control.state_limits.StateLimits.project`).
    state_filter : StateFilter or None, optional
        The filter of the measurement in front of the law (:mod:`gtmodel.control.state_filter`: the extended Kalman
        filter of :attr:`predict`); the loop step (:func:`~gtmodel.codegen.loop_step.tracking_step`) runs it before
        :meth:`function` and keeps its memory after the law's own; None (default): the measurement as it is.
    margin : numpy.ndarray or None, optional
        ``(N, m)`` with :attr:`state_limits`, each row's a-priori error per period
        (:func:`~gtmodel.control.state_limits.parameter_margin`: the model's parameters
        :data:`~gtmodel.control.state_filter.PARAMETER_ERROR` off, faded as the loop measures its error), held off
        beside the measured back-off; after the end none. None: none.
    rest : RestLinearization or None, optional
        The linearisation the held end's gain was designed on (:func:`~gtmodel.control.lqr.rest_linearization`: the
        end's own, or a neighbour's where the end's own gain is unstable a little away from it); None: not recorded.
    """

    K: np.ndarray
    u_lb: np.ndarray
    u_ub: np.ndarray
    x_names: list[str]
    u_names: list[str]
    Q: np.ndarray
    R: np.ndarray
    Qf: np.ndarray
    x_hold: np.ndarray
    u_hold: np.ndarray
    K_hold: np.ndarray
    delay: int = 0
    predict: Any = None
    integral_states: tuple[int, ...] = ()
    Ki: np.ndarray | None = None
    Ki_hold: np.ndarray | None = None
    Qi: np.ndarray | None = None
    u_start: np.ndarray | None = None
    lead: int = 0
    gain_scale: np.ndarray | None = None
    state_limits: StateLimits | None = None
    state_filter: StateFilter | None = field(default=None, repr=False)
    rest: RestLinearization | None = field(default=None, repr=False)
    margin: np.ndarray | None = field(default=None, repr=False)

    @property
    def ni(self) -> int:
        """Number of integrator states (0: no integral action)."""
        return len(self.integral_states)

    @property
    def n_memory(self) -> int:
        """Length of the step's memory ``w``: the integrator states, and with :attr:`state_limits` the last measured
        state ``(nx)``, the last ``u_last (nu)``, the prediction errors' envelope ``(nx)`` and a flag (1 once a step ran)."""
        return self.ni + (2 * self.nx + self.nu + 1 if self.state_limits is not None else 0)

    @property
    def memory_initial(self) -> np.ndarray:
        """``(n_memory,)`` the step's first memory: zero integrator states (and the reference's first state, :attr:`u_initial`, flag 0)."""
        return np.r_[np.zeros(self.ni), (np.r_[self.x_ref[0], self.u_initial, np.zeros(self.nx), 0.0] if self.state_limits is not None else np.zeros(0))]

    @property
    def u_initial(self) -> np.ndarray:
        """``(nu,)`` the input before the first step: :attr:`u_start` (default ``u*_0``) saturated."""
        return saturate(self.u_ref[0] if self.u_start is None else self.u_start, self.u_lb, self.u_ub)

    def function(self, filtered: bool = False) -> ca.Function:
        """The controller as ONE CasADi Function of the loop-step interface.

        Parameters
        ----------
        filtered : bool, optional
            With a memory (:attr:`n_memory`), a last input ``x_hat (nx,1)``, the filtered state (:attr:`state_filter`):
            the law acts on it and the memory keeps it as the last state, while the back-off's error is measured from
            ``x``, the measurement itself (the filter's innovation, less the sensors' noise band:
            :meth:`~gtmodel.control.state_filter.StateFilter.model_error`); default False: ``x`` for all. Without a memory
            the filtered state is simply given as ``x``.

        Returns
        -------
        casadi.Function
            ``control(t (1,1), x (nx,1), u_last (nu,1)) -> (u (nu,1), ok (1,1))``, with
            a memory (integral action, :attr:`state_limits`) ``control(t, x, u_last, w (n_memory,1)[, x_hat]) -> (u, w_next, ok)``
            (``w`` the integrator states, see :attr:`integral_states`, then the last measured state, input and flag):
            ``k = floor((t - t_0) / dt)`` clamped to ``0 .. N`` (a NaN ``t`` gives
            ``ok = 0``), ``u = sat(u*_k - K_k (x - x*_k))``, where row ``N`` (after the
            reference ends) holds the final state: :attr:`x_hold`, :attr:`u_hold`,
            :attr:`K_hold`; ``ok`` is 1 when ``u`` is
            finite. ``u_last`` is not used by this law without a delay (the interface is
            shared with the MPC, whose warm start it is); with :attr:`delay` 1 it is the
            input acting until the new one arrives: ``x`` is replaced by
            ``predict(x, u_last)`` and ``t`` by ``t + dt``. The tables are constants of the
            graph, indexed parametrically (the generated C looks them up; no heap).
        """
        n, nx, nu, ni, nm = self.length, self.nx, self.nu, self.ni, self.n_memory
        t, x, u_last, mem = ca.MX.sym("t"), ca.MX.sym("x", nx), ca.MX.sym("u_last", nu), ca.MX.sym("w", nm)
        extra = [ca.MX.sym("x_hat", nx)] if filtered and nm else []
        t_in, x_in, w = t, x, mem[:ni]
        x = x_kept = extra[0] if extra else x  # the state the law acts on (and the memory keeps)
        if self.delay:
            t, x = t + self.dt, self.predict(x, u_last)  # the state when this input starts to act
        k = period_index(t, self.t0, self.dt, n)  # a NaN time reads sample 0; ok is then 0 below
        margin = self.margin if self.state_limits is not None and self.margin is not None else None
        rows = [self.x_ref, self.u_ref, self.K.reshape(n, nu * nx)] + ([self.Ki.reshape(n, nu * ni)] if ni else [])
        hold = [self.x_hold, self.u_hold, self.K_hold.reshape(-1)] + ([self.Ki_hold.reshape(-1)] if ni else [])
        if margin is not None:  # the rows' a-priori errors, last in each row (none after the end)
            rows, hold = rows + [margin], hold + [np.zeros(margin.shape[1])]
        table = np.vstack([np.hstack(rows),  # row k: x*_k, u*_k, K_k (row-major)[, Ki_k]
                           np.hstack(hold)])  # row N: hold the end
        width = table.shape[1]
        values = ca.MX(ca.DM(table.reshape(-1)))
        base = width * k
        xs = ca.vertcat(*[values[base + j] for j in range(nx)])
        us = ca.vertcat(*[values[base + nx + j] for j in range(nu)])
        gain = ca.vertcat(*[ca.horzcat(*[values[base + nx + nu + i * nx + j] for j in range(nx)]) for i in range(nu)])
        free = us - ca.mtimes(gain, x - xs)
        if ni:
            off = base + nx + nu + nu * nx
            gain_i = ca.vertcat(*[ca.horzcat(*[values[off + i * ni + j] for j in range(ni)]) for i in range(nu)])
            free = free - ca.mtimes(gain_i, w)
        if self.state_limits is None:
            u, kept = saturate(free, self.u_lb, self.u_ub), ca.MX(0, 1)
        else:  # the declared state bounds over the period the input acts, the rows backed off by the measured error
            x_prev, u_prev, last, ran = mem[ni:ni + nx], mem[ni + nx:ni + nx + nu], mem[ni + nx + nu:nm - 1], mem[nm - 1]
            error = x_in - self.predict(x_prev, u_last if self.delay == 0 else u_prev)
            if extra:  # the innovation less the sensors' noise
                error = self.state_filter.model_error(error)
            error = ca.if_else(ran > 0.5, envelope(last, error, self.plausible_ranges(self.u_lb, self.u_ub)[0]), last)
            margin_k = None if margin is None else ca.vertcat(*[values[base + width - margin.shape[1] + r] for r in range(margin.shape[1])])
            u = self.state_limits.project(x, free, self.u_lb, self.u_ub, error=error, delay=self.delay, margin=margin_k)
            kept = ca.vertcat(x_kept, u_last, error, 1.0)  # this state, the input acting now, the envelope, for the next period
        total = ca.sum1(ca.fabs(u)) + ca.fabs(t) + ca.sum1(ca.fabs(x))
        if not nm:
            ok = total < math.inf  # 0 for NaN or infinite entries
            return ca.Function("control", [t_in, x_in, u_last], [u, ok], ["t", "x", "u_last"], ["u", "ok"])
        error = ca.vertcat(*[x[i] - xs[i] for i in self.integral_states])
        unsaturated = ca.sum1(ca.fabs(u - free)) == 0  # conditional integration: hold xi while the input saturates (or is limited)
        w_next = ca.vertcat(ca.if_else(unsaturated, w + self.dt * error, w) if ni else ca.MX(0, 1), kept)
        ok = (total + ca.sum1(ca.fabs(w_next))) < math.inf
        return ca.Function("control", [t_in, x_in, u_last, mem, *extra], [u, w_next, ok], ["t", "x", "u_last", "w"] + ["x_hat"] * len(extra),
                           ["u", "w_next", "ok"])

    def limits(self) -> dict[str, np.ndarray]:
        """The plausible ranges the generated step checks its measurement and its memory against
        (:mod:`gtmodel.codegen.loop_step`: a measurement outside is rejected, a memory outside is reset).

        Returns
        -------
        dict
            ``"x"`` ``(2, nx)``: the reference's range widened by :data:`~gtmodel.control.reference.MEASUREMENT_LIMIT`
            state scales (:func:`~gtmodel.control.reference.reference_scales`); ``"u_last"`` ``(2, nu)``: the input
            bounds (where infinite, the reference's range widened by ``MEASUREMENT_LIMIT`` input scales);
            ``"memory"`` ``(2, n_memory)``: the integrator states within ``MEMORY_LIMIT`` scales of their states times the
            reference's duration (at least 1 s; :data:`~gtmodel.control.reference.MEMORY_LIMIT`), and with
            :attr:`state_limits` the last state as ``"x"``, the last input as ``"u_last"``, the flag in ``[0, 1]``.
        """
        x_scale, _, x, u = self.plausible_ranges(self.u_lb, self.u_ub)
        xi = MEMORY_LIMIT * x_scale[list(self.integral_states)] * max(self.dt * self.length, 1.0)
        memory = np.vstack([-xi, xi])
        if self.state_limits is not None:  # the last state and input as the measurement's and u_last's, the flag in [0, 1]
            memory = np.hstack([memory, x, u, np.vstack([x[0] - x[1], x[1] - x[0]]), np.array([[0.0], [1.0]])])  # the envelope within a span
        return {"x": x, "u_last": u, "memory": memory}

    def memory_reset(self) -> ca.Function:
        """The step's memory reset to the reference's at the current period (what ``_init`` sets at the first).

        Returns
        -------
        casadi.Function
            ``reset(t (1,1), x (nx,1)) -> (u_last (nu,1)[, w (n_memory,1)])``: ``u_last = u*_k`` saturated
            (``k = floor((t - t_0) / dt)`` clamped to ``0 .. N``, row ``N`` the held end's :attr:`u_hold`), and
            with :attr:`integral_states` zero integrator states, with :attr:`state_limits` ``x`` as the last state,
            ``u_last`` as the last input and the flag 0 (the interface of
            :meth:`gtmodel.control.mpc.MPCController.memory_reset`).
        """
        t, x = ca.MX.sym("t"), ca.MX.sym("x", self.nx)
        nu = self.nu
        values = ca.MX(ca.DM(np.vstack([self.u_ref, self.u_hold]).reshape(-1)))
        k = period_index(t, self.t0, self.dt, self.length)
        u_last = saturate(ca.vertcat(*[values[nu * k + i] for i in range(nu)]), self.u_lb, self.u_ub)
        if not self.n_memory:
            return ca.Function("reset", [t, x], [u_last], ["t", "x"], ["u_last"])
        w = ca.vertcat(ca.DM.zeros(self.ni), *((x, u_last, ca.DM.zeros(self.nx), 0.0) if self.state_limits is not None else ()))
        return ca.Function("reset", [t, x], [u_last, w], ["t", "x"], ["u_last", "w"])

    def __call__(self, t: float, x: Any, u_last: Any = None, w: Any = None) -> np.ndarray:
        """The control law evaluated from Python (the same Function): ``u (nu,)`` at time ``t`` [s], state ``x (nx,)``.

        Parameters
        ----------
        t : float
            Time [s].
        x : array_like
            ``(nx,)`` measured state.
        u_last : array_like, optional
            ``(nu,)`` the input acting now (used with :attr:`delay` 1; default :attr:`u_initial`).
        w : array_like, optional
            ``(n_memory,)`` the step's memory (the integrator states, and with :attr:`state_limits` the last state,
            input and flag; default :attr:`memory_initial`).

        Returns
        -------
        numpy.ndarray
            ``(nu,)`` the saturated input.
        """
        args = [t, np.asarray(x, dtype=float), self.u_initial if u_last is None else np.asarray(u_last, dtype=float)]
        if self.n_memory:
            args.append(self.memory_initial if w is None else np.asarray(w, dtype=float))
        u = self.function()(*args)[0]
        return np.asarray(u).reshape(-1)


def tracking_controller(
    ode: ExplicitODE,
    t: Any,
    x_ref: Any,
    u_ref: Any,
    dt: float = LOOP_PERIOD_S,
    Q: Any = None,
    R: Any = None,
    Qf: Any = None,
    u_lb: Any = None,
    u_ub: Any = None,
    p: Any = None,
    method: str = "rk4",
    substeps: int = 1,
    time_varying: bool = True,
    delay: int = 0,
    integral_weights: Mapping[str, float] | None = None,
    state_bounds: Mapping[str, tuple[float, float]] | None = None,
) -> TrackingController:
    """Feedforward and time-varying LQR along a reference motion of a model.

    Parameters
    ----------
    ode : ExplicitODE
        The model (:func:`gtmodel.modeling.explicit_ode`).
    t : array_like
        ``(M,)`` increasing reference times [s] (e.g. an optimal control result's mesh).
    x_ref : array_like
        ``(M, nx)`` reference states in the order of ``ode.x_names``.
    u_ref : array_like
        ``(M, nu)`` reference inputs in the order of ``ode.u_names``.
    dt : float, optional
        Loop period [s] (default :data:`gtmodel.defaults.LOOP_PERIOD_S`).
    Q : array_like, optional
        State weight: ``(nx,)`` diagonal or ``(nx, nx)``; default Bryson's rule,
        ``1 / s_i^2`` with ``s_i`` the range of state ``i`` along the reference (at least
        ``1e-3 (1 + max|x_i|)``).
    R : array_like, optional
        Input weight, ``(nu,)`` or ``(nu, nu)`` positive definite; default ``1 / s_j^2``
        with ``s_j`` half the bound range (finite bounds) or the reference's range.
    Qf : array_like, optional
        Terminal weight; default the stationary Riccati solution at the held end
        (:attr:`TrackingController.x_hold`, ``u_hold``) if it exists, else ``Q``.
    u_lb, u_ub : array_like, optional
        ``(nu,)`` saturation bounds; default the model's declared input bounds.
    p : array_like, optional
        ``(np,)`` model parameters; default ``ode.p_default``.
    method : {"rk4", "implicit_euler", "radau2"}, optional
        The fixed step whose Jacobians are the ``A_k``, ``B_k``.
    substeps : int, optional
        Its steps within one period.
    time_varying : bool, optional
        True (default): the gains ``K_k`` of the backward Riccati recursion along the
        reference. False: one time-invariant LQR gain for every sample, :func:`~gtmodel.control.lqr.dlqr` of the
        linearisation at the held end (``x*_end``, the input that holds it), i.e.
        :attr:`TrackingController.K_hold`.
    delay : {0, 1}, optional
        Input delay [periods] the law compensates by predicting the state one period ahead
        with the same fixed step (see :attr:`TrackingController.delay`; default 0).
    integral_weights : mapping of str to float, optional
        Integral action on the named states (``ode.x_names``), each with its weight ``> 0``
        on the integrator state ``xi_i = sum dt (x_i - x*_i)`` (default none; see
        :attr:`TrackingController.integral_states`). The gains ``[K_k, Ki_k]`` are the
        LQR's of the model augmented with the integrators, ``xi_{k+1} = xi_k + dt C (x_k -
        x*_k)`` (as ``control.dlqr(..., integral_action=dt C)``), with the weight
        ``blkdiag(Q, Qi)``; after the end, the augmented stationary LQR (Franklin, Powell &
        Workman, Digital Control of Dynamic Systems, 3rd ed., sec. 8.5).
    state_bounds : mapping of str to (float, float), optional
        Declared state bounds ``(lb, ub)`` by state name the law holds over the period its input acts
        (:attr:`TrackingController.state_limits`, :func:`~gtmodel.control.state_limits.state_limits`: the same
        fixed step, ``method`` and ``substeps``, at every substep); names that are not states are ignored; default
        none.

    Returns
    -------
    TrackingController

    Raises
    ------
    InputError
        Shapes or values out of range, times not increasing, a reference shorter than
        one period, ``R`` not positive definite; ``time_varying=False`` at an end where the
        linearisation is not stabilisable; an integral weight of a state the model does not
        have, or not a finite number > 0.
    """
    if isinstance(delay, bool) or delay not in (0, 1):
        raise InputError(f"delay: expected 0 or 1 period of input delay to compensate, got {delay!r}")
    prob = tracking_problem(ode, t, x_ref, u_ref, dt, Q=Q, R=R, u_lb=u_lb, u_ub=u_ub, p=p, min_samples=2, delay=delay)
    xs, us, lb, ub, pv, Qm, Rm = prob.x_ref, prob.u_ref, prob.u_lb, prob.u_ub, prob.p, prob.Q, prob.R
    n = xs.shape[0]
    prob.check_step(method, substeps, "the tracking controller's step")
    step = prob.step(method, substeps)
    xsym, usym, psym = ca.SX.sym("x", ode.nx), ca.SX.sym("u", ode.nu), ca.SX.sym("p", ode.np)
    xn = step.call([xsym, usym, psym])[0]
    ab = ca.Function("AB", [xsym, usym, psym], [ca.jacobian(xn, xsym), ca.jacobian(xn, usym)])
    Aa, Bb = ab.map(n)(xs.T, us.T, np.tile(pv.reshape(-1, 1), (1, n)))
    A = np.asarray(Aa).reshape(ode.nx, n, ode.nx).transpose(1, 0, 2)  # [A_0 A_1 ...] side by side
    B = np.asarray(Bb).reshape(ode.nx, n, ode.nu).transpose(1, 0, 2)
    # after the end: the input that holds the final state (least squares f(x*_N, u) = 0) and the stationary gain there
    x_hold = prob.x_given[-1]
    u_hold = saturate(hold_input(ode.f, x_hold, prob.u_given[-1], pv), lb, ub)
    idx, Qi = _integral(integral_weights, list(ode.x_names))
    if idx:  # the model augmented with the integrators of the selected states' errors
        C = np.eye(ode.nx)[list(idx)]
        ni = len(idx)
        A = np.stack([np.block([[a, np.zeros((ode.nx, ni))], [dt * C, np.eye(ni)]]) for a in A])
        B = np.concatenate([B, np.zeros((n, ni, ode.nu))], axis=1)
        Qm = scipy.linalg.block_diag(Qm, Qi)

    def jacobians(x: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        a, b = (np.asarray(v) for v in ab(x, u, pv))
        if idx:
            a = np.block([[a, np.zeros((ode.nx, ni))], [dt * C, np.eye(ni)]])
            b = np.vstack([b, np.zeros((ni, ode.nu))])
        return a, b

    # at rest, the linearisation whose gain holds the rest point's neighbourhood (gtmodel.control.lqr)
    names = list(ode.x_names)
    hold = rest_linearization(lambda x: jacobians(x, u_hold), x_hold, prob.x_scale, Qm, Rm, delay, names)
    Ah, Bh = hold.A, hold.B
    for a, stop in rest_groups(xs, prob.x_scale):
        last = stop if stop == n else stop - 1  # the run's last sample starts the motion unless it ends the reference
        design = rest_linearization(lambda x, u=us[a]: jacobians(x, u), xs[a], prob.x_scale, Qm, Rm, delay, names)
        A[a:last], B[a:last] = design.A, design.B
    try:
        K_hold, P_hold = dlqr(Ah, Bh, Qm, Rm)
    except InputError as exc:
        if not time_varying:
            raise InputError(f"time_varying: a time-invariant LQR needs a stabilisable linearisation at the held end ({exc})") from None
        K_hold, P_hold = None, Qm
    Qfm = prob.terminal_weight(Qf, P_hold)
    Qfm = scipy.linalg.block_diag(Qfm, Qi) if idx and Qf is not None else Qfm
    K = riccati_gains(A, B, Qm, Rm, Qfm)[0] if time_varying else np.tile(K_hold, (n, 1, 1))
    K_hold = K[-1] if K_hold is None else K_hold
    nx = ode.nx
    integral = dict(integral_states=idx, Ki=K[:, :, nx:], Ki_hold=K_hold[:, nx:], Qi=Qi) if idx else {}
    held = None if not state_bounds else state_limits(substep_states(ode, dt, method, substeps), list(ode.x_names), state_bounds, pv, lb, ub, us, xs)
    margin = None if held is None else parameter_margin(held.rows_p, step, xs, us, pv, delay, prob.lead)
    return TrackingController(state_limits=held, delay=int(delay), predict=prob.prediction(method, substeps, "predict"), dt=float(dt), t0=prob.t0, x_ref=xs, u_ref=us, K=K[:, :, :nx],
                              u_lb=lb.copy(), u_ub=ub.copy(), x_names=list(ode.x_names), u_names=list(ode.u_names), Q=Qm[:nx, :nx], R=Rm,
                              Qf=Qfm[:nx, :nx], x_hold=x_hold.copy(), u_hold=np.asarray(u_hold, dtype=float).reshape(-1),
                              K_hold=K_hold[:, :nx], u_start=start_input(ode.f, prob.x_given[0], us[0], pv), lead=prob.lead,
                              rest=hold, margin=margin, **integral)


def limit_noise_gain(c: TrackingController, sigma: Any, fraction: float = NOISE_GAIN_LIMIT) -> TrackingController:
    """The law with each period's gain rows scaled down to a bounded response to the measurement noise.

    Where the reference passes a point whose linearisation leaves a weighted state barely movable by
    the input (a load held at rest by a regularised Coulomb friction, or inside a smoothed backlash),
    the Riccati gain tends to ``(B^T P B)^-1 B^T P A``, which no input weight lowers: a held-out gear
    drive's TV-LQR turned a 1.2 mrad error of its load position into about 1800 V of a 30 V input at
    rest and cycled at the bounds (ratio 3.3 to its feedforward). The rule: an input's one-sigma response
    to independent state errors of standard deviation ``sigma``, ``s_k,i = sqrt(sum_j (K_k,ij sigma_j)^2)``,
    is at most ``fraction`` of the input's half range; a row above it is scaled by
    ``fraction (u_ub - u_lb)_i / (2 s_k,i)`` (its integral gains with it). The noise then moves each input
    by at most that fraction of its range, as a sensor-limited bandwidth would; rows below it, as on
    every other drive of the family measured, are untouched. The scaled law is no longer the LQR
    optimum there: the closed-loop check judges it.

    Parameters
    ----------
    c : TrackingController
        The law (:func:`tracking_controller`).
    sigma : array_like
        ``(nx,)`` the measurement noise's standard deviation per state (state units, >= 0; the measurement
        filter's, :attr:`~gtmodel.control.state_filter.StateFilter.sigma`).
    fraction : float, optional
        The largest one-sigma response over the half range, > 0 (default :data:`gtmodel.defaults.NOISE_GAIN_LIMIT`).

    Returns
    -------
    TrackingController
        With the scaled ``K``, ``K_hold`` (and ``Ki``, ``Ki_hold``) and :attr:`TrackingController.gain_scale`;
        ``c`` itself where no row is above the limit or an input has no finite range.

    Raises
    ------
    InputError
        ``sigma`` of another length than the states or negative or not finite; ``fraction`` not a finite number > 0.
    """
    sig = np.asarray(sigma, dtype=float).reshape(-1)
    if sig.size != c.nx or not np.all(np.isfinite(sig)) or np.any(sig < 0):
        raise InputError(f"sigma: expected {c.nx} finite standard deviations >= 0, got {np.asarray(sigma).tolist()!r}")
    if isinstance(fraction, bool) or not isinstance(fraction, (int, float)) or not math.isfinite(fraction) or fraction <= 0:
        raise InputError(f"fraction: expected a finite number > 0, got {fraction!r}")
    half = (np.asarray(c.u_ub, dtype=float) - np.asarray(c.u_lb, dtype=float)) / 2
    if not np.all(np.isfinite(half)) or not np.any(sig > 0):
        return c
    K = np.concatenate([c.K, c.K_hold[None]])  # (N + 1, nu, nx)
    response = np.sqrt(np.sum((K * sig) ** 2, axis=2))
    scale = np.minimum(1.0, fraction * half / np.maximum(response, 1e-300))
    if np.all(scale == 1.0):
        return c
    integral = {} if c.Ki is None else {"Ki": c.Ki * scale[:-1, :, None], "Ki_hold": c.Ki_hold * scale[-1][:, None]}
    return replace(c, K=c.K * scale[:-1, :, None], K_hold=c.K_hold * scale[-1][:, None], gain_scale=scale, **integral)


def _integral(weights: Mapping[str, float] | None, names: list[str]) -> tuple[tuple[int, ...], np.ndarray | None]:
    """The integrated states' indices (in the model's order) and their weight ``Qi``, from weights by name."""
    if not weights:
        return (), None
    if not isinstance(weights, Mapping):
        raise InputError(f"integral_weights: expected a mapping of state names to weights, got {type(weights).__name__}")
    for name, value in weights.items():
        if name not in names:
            raise InputError(f"integral_weights: {name!r} is not a state of the model ({', '.join(names)})")
        if not (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value > 0):
            raise InputError(f"integral_weights[{name!r}]: expected a finite weight > 0, got {value!r}")
    idx = tuple(i for i, name in enumerate(names) if name in weights)
    return idx, np.diag([float(weights[names[i]]) for i in idx])
