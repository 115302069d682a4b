"""The measurement filtered before a loop controller sees it: an extended Kalman filter on the controller's own model.

A loop controller acts on the state it measures. With sensors' noise that state is off by the noise, and a
controller whose weights make a position error expensive (a drive's position weighted 10^7 times its current)
turns a position noise of a tenth of a millimetre into a jump of its voltage: a ball-screw drive's current went
1.6 A past what its model predicted from the true state (issue 65, docs/model_in_the_loop.md). The step therefore
filters the measurement ``y`` (the measured states, each with its noise's standard deviation ``sigma``) with the
extended Kalman filter of the controller's own fixed step ``F`` (Simon, Optimal State Estimation, Wiley 2006,
sec. 13.2; Pannocchia & Rawlings, AIChE J. 49 (2003), the estimator of offset-free MPC):

- prediction over the last period, with the input that acted then ``u_act`` (the input delay's) plus the
  controller's input-disturbance estimate ``d`` where it keeps one:
  ``x^- = F(x^, u_act + d)``, ``P^- = A P A' + Q``, ``A = dF/dx``, ``B = dF/du`` there;
- the model's error per period ``Q = J_p diag((pi p)^2) J_p' + B diag((rho u_scale)^2) B' + diag((eps x_scale)^2)``:
  each of the model's parameters ``p`` :data:`PARAMETER_ERROR` off (a heavier load, more friction act where the model
  has them, on the load's side as on the motor's), ``J_p = Gamma df/dp`` the right-hand side's sensitivity held over
  the period, ``Gamma = dt (I + A) / 2`` (the trapezoidal rule of the integral of the transition matrix, which the step's
  ``A`` ends: second order in ``dt``, as stable as the step; the step's own ``dF/dp`` through every substep made the
  generated C ten times larger, 1.8 MB of a belt drive's 2 MB filter), an input-side error of :data:`INPUT_ERROR` of
  each input's scale per period, and :data:`STATE_ERROR` of each state's scale (scales of
  :func:`~gtmodel.control.reference.reference_scales`);
- the update with ``R = diag(sigma^2)``: ``L = P^- (P^- + R)^-1``, ``x^ = x^- + L (y - x^-)``,
  ``P = (I - L) P^- (I - L)' + L R L'`` (Joseph's form, equal to ``(I - L) P^-`` for this gain but a sum of two
  covariances in round-off: with ``(I - L) P^-`` a float32 step's ``P`` lost its positive diagonal, and the step
  reset its memory 17 times in 132 periods), symmetrised, its diagonal kept >= 0.

The controller then acts on ``x^``; its own estimators (the MPC's disturbance estimate, the back-off's error envelope)
go on measuring their error from ``y``: the innovation ``y - x^-``, not the filtered correction ``L (y - x^-)``, which
would hide the model's error from them. The filter's memory, after the controller's own, holds
``x^ (nx)``, ``P (nx * nx)``, the last ``u_last (nu)`` and a flag (1 once a step ran): the first step, or one after
a reset, takes ``x^ = y`` and ``P = R``. A state with no noise (``sigma = 0``) is taken as measured; with none
anywhere the filter is not built. The step's memory ranges (:meth:`StateFilter.memory_range`) keep ``x^`` within
the plausible measurement and ``P`` within the squared spans, so a corrupted memory is reset, not used.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError

__all__ = ["INPUT_ERROR", "NOISE_BAND", "PARAMETER_ERROR", "STATE_ERROR", "StateFilter", "measurement_filter", "state_filter"]

#: The model's input-side error per period the filter allows, as a fraction of each input's scale (``rho`` of ``Q``).
INPUT_ERROR = 0.05
#: The model's error per period in each state directly, as a fraction of its scale (``eps`` of ``Q``).
STATE_ERROR = 1e-4
#: The innovation within this many of its state's noise standard deviations is taken as noise, not the model's error
#: (:meth:`StateFilter.model_error`).
NOISE_BAND = 3.0
#: Each of the model's parameters taken as uncertain by this fraction of its value (``pi`` of ``Q``): a load 20 % heavier,
#: the model error a plan's margin and the back-off's cap are chosen for (:data:`~gtmodel.control.mpc_memory.BACKOFF_CAP`).
PARAMETER_ERROR = 0.2


@dataclass(frozen=True)
class StateFilter:
    """The extended Kalman filter a loop step runs on its measurement (see the module docstring).

    Parameters
    ----------
    step : casadi.Function
        ``F(x (nx,1), u (nu,1)) -> x_next``: the controller's own fixed step over one period.
    sigma : numpy.ndarray
        ``(nx,)`` the measurement noise's standard deviation per state (state units, >= 0).
    x_scale, u_scale : numpy.ndarray
        ``(nx,)``, ``(nu,)`` the states' and inputs' scales (> 0) of ``Q``.
    delay : int
        The controller's input delay [periods] (0 or 1): which ``u_last`` acted over the last period.
    disturbance : tuple of int, optional
        ``(start, stop)``: where the controller's own memory holds its input-disturbance estimate ``d`` (added to the
        input of the prediction); default None: none.
    rhs : casadi.Function, optional
        ``f(x, u, p) -> dx/dt``: the model's right-hand side with its parameters free, for ``Q``'s parameter term;
        default None: none.
    p : numpy.ndarray, optional
        ``(np,)`` the parameters ``step`` has (with ``rhs``).
    dt : float, optional
        The period [s] ``step`` spans (with ``rhs``).
    input_error, state_error, parameter_error : float, optional
        ``rho``, ``eps`` and ``pi`` of ``Q`` (default :data:`INPUT_ERROR`, :data:`STATE_ERROR`, :data:`PARAMETER_ERROR`).
    """

    step: ca.Function
    sigma: np.ndarray
    x_scale: np.ndarray
    u_scale: np.ndarray
    delay: int
    disturbance: tuple[int, int] | None = None
    rhs: ca.Function | None = None
    p: np.ndarray | None = None
    dt: float = 0.0
    input_error: float = INPUT_ERROR
    state_error: float = STATE_ERROR
    parameter_error: float = PARAMETER_ERROR

    @property
    def nx(self) -> int:
        """Number of states."""
        return int(self.sigma.size)

    @property
    def nu(self) -> int:
        """Number of inputs."""
        return int(self.u_scale.size)

    @property
    def n_memory(self) -> int:
        """Length of the filter's memory: ``x^ (nx)``, ``P (nx * nx, column-major)``, ``u_last (nu)``, the flag."""
        return self.nx + self.nx * self.nx + self.nu + 1

    def _parts(self, wf: Any) -> tuple[Any, Any, Any, Any]:
        nx, nu = self.nx, self.nu
        return wf[:nx], ca.reshape(wf[nx:nx + nx * nx], nx, nx), wf[nx + nx * nx:nx + nx * nx + nu], wf[-1]

    def _input(self, u_last: Any, wf: Any, inner: Any) -> Any:
        """The input that acted over the last period, plus the controller's disturbance estimate."""
        u_act = u_last if self.delay == 0 else self._parts(wf)[2]
        if self.disturbance is not None:
            u_act = u_act + inner[self.disturbance[0]:self.disturbance[1]]
        return u_act

    def model_error(self, innovation: Any) -> Any:
        """The model's error in an innovation: each state's part beyond :data:`NOISE_BAND` of its noise's standard deviation.

        ``e_i = v_i - clip(v_i, -b sigma_i, b sigma_i)``, ``b`` = :data:`NOISE_BAND` (a soft threshold; a state without
        noise keeps its innovation). What the controller's own estimators (the back-off's error envelope) take from
        ``y - x^-``: the innovation whole carried the sensors' noise into them, and a ball-screw axis' TV-LQR, its rows
        backed off by a motor angle's noise (0.17 rad, with a transmission of 10^7 N/m a force of 3 kN), chattered its
        current to -27 A of 18.1 (issue 65); the filtered correction ``L (y - x^-)`` alone hid the model's error.

        Parameters
        ----------
        innovation : casadi.MX or casadi.SX
            ``(nx, 1)`` the measurement less the filter's prediction.

        Returns
        -------
        casadi.MX or casadi.SX
            ``(nx, 1)``.
        """
        band = ca.DM(NOISE_BAND * self.sigma)
        return innovation - ca.fmin(ca.fmax(innovation, -band), band)

    def prediction(self) -> ca.Function:
        """The state the filter's memory predicts for now (what replaces a rejected measurement).

        Returns
        -------
        casadi.Function
            ``predict(u_last (nu,1), w_inner (n,1), w_filter (n_memory,1)) -> x (nx,1)``: ``F(x^, u_act + d)``.
        """
        u_last, wf = ca.MX.sym("u_last", self.nu), ca.MX.sym("wf", self.n_memory)
        inner = ca.MX.sym("w", self.disturbance[1] if self.disturbance else 0)
        return ca.Function("predict", [u_last, inner, wf], [self.step(self._parts(wf)[0], self._input(u_last, wf, inner))],
                           ["u_last", "w", "wf"], ["x"])

    def update(self) -> ca.Function:
        """One period of the filter (see the module docstring).

        Returns
        -------
        casadi.Function
            ``filter(y (nx,1), u_last (nu,1), w_inner (n,1), w_filter (n_memory,1)) -> (x (nx,1), wf_next (n_memory,1))``:
            the filtered state and the filter's next memory (``x^``, ``P``, this ``u_last``, flag 1).
        """
        nx = self.nx
        y, u_last, wf = ca.MX.sym("y", nx), ca.MX.sym("u_last", self.nu), ca.MX.sym("wf", self.n_memory)
        inner = ca.MX.sym("w", self.disturbance[1] if self.disturbance else 0)
        x_prev, P_prev, _, ran = self._parts(wf)
        xs, us = ca.MX.sym("x", nx), ca.MX.sym("u", self.nu)
        xn = self.step(xs, us)
        Ax = ca.jacobian(xn, xs)
        if self.rhs is not None and self.p is not None and self.p.size:  # each parameter parameter_error off
            ps = ca.MX.sym("p", self.p.size)
            jf = ca.substitute(ca.jacobian(self.rhs.call([xs, us, ps])[0], ps), ps, ca.DM(self.p))
            jp = ca.mtimes(self.dt / 2 * (ca.DM.eye(nx) + Ax), jf)  # Gamma df/dp, Gamma = dt (I + A) / 2
            spread = ca.mtimes([jp, ca.DM(np.diag((self.parameter_error * self.p) ** 2)), jp.T])
        else:
            spread = ca.DM.zeros(nx, nx)
        jac = ca.Function("AB", [xs, us], [xn, Ax, ca.jacobian(xn, us), spread])
        x_minus, A, B, Qp = jac(x_prev, self._input(u_last, wf, inner))
        Q = ca.mtimes([B, ca.DM(np.diag((self.input_error * self.u_scale) ** 2)), B.T]) + ca.DM(np.diag((self.state_error * self.x_scale) ** 2)) + Qp
        P_minus = ca.mtimes([A, P_prev, A.T]) + Q
        R = ca.DM(np.diag(self.sigma ** 2))
        L = ca.solve(P_minus + R, P_minus).T  # P^- (P^- + R)^-1, both symmetric
        x_hat = x_minus + ca.mtimes(L, y - x_minus)
        IL = ca.DM.eye(nx) - L
        P = ca.mtimes([IL, P_minus, IL.T]) + ca.mtimes([L, R, L.T])  # Joseph's form: a sum of two covariances
        P = (P + P.T) / 2
        P = P + ca.diag(ca.fmax(-ca.diag(P), 0))  # its diagonal >= 0 whatever the round-off (a float32 step's)
        x_hat, P = ca.if_else(ran > 0.5, x_hat, y), ca.if_else(ran > 0.5, P, R)
        f = ca.Function("filter", [y, u_last, inner, wf], [x_hat, ca.vertcat(x_hat, ca.reshape(P, -1, 1), u_last, 1.0)],
                        ["y", "u_last", "w", "wf"], ["x", "wf_next"])
        try:  # scalar operations where the step allows it: the generated C several times faster
            return f.expand()
        except RuntimeError:
            return f

    def memory_initial(self, x: Any, u: Any) -> np.ndarray:
        """``(n_memory,)`` the filter's first memory: ``x^ = x``, ``P = R``, ``u_last = u``, flag 0.

        Parameters
        ----------
        x : array_like
            ``(nx,)`` a state.
        u : array_like
            ``(nu,)`` an input.

        Returns
        -------
        numpy.ndarray
        """
        return np.concatenate([np.asarray(x, dtype=float).reshape(-1), np.diag(self.sigma ** 2).reshape(-1, order="F"),
                               np.asarray(u, dtype=float).reshape(-1), [0.0]])

    def memory_range(self, x_range: np.ndarray, u_range: np.ndarray) -> np.ndarray:
        """``(2, n_memory)`` the plausible filter memory: ``x^`` within ``x_range``, ``|P_ij|`` at most ``span_i span_j``
        (``P_ii >= 0``), ``u_last`` within ``u_range``, the flag in ``[0, 1]``.

        Parameters
        ----------
        x_range : numpy.ndarray
            ``(2, nx)`` the plausible measurement.
        u_range : numpy.ndarray
            ``(2, nu)`` the plausible input.

        Returns
        -------
        numpy.ndarray
        """
        span = np.asarray(x_range[1], dtype=float) - np.asarray(x_range[0], dtype=float)
        big = np.outer(span, span)
        low = np.where(np.eye(self.nx, dtype=bool), 0.0, -big)
        return np.hstack([np.asarray(x_range, dtype=float), np.vstack([low.reshape(-1, order="F"), big.reshape(-1, order="F")]),
                          np.asarray(u_range, dtype=float), np.array([[0.0], [1.0]])])

    def wrap(self, function: ca.Function, reset: ca.Function, n_inner: int) -> tuple[ca.Function, ca.Function, ca.Function]:
        """A controller's step, reset and prediction with the filter in front (the loop-step interface).

        Parameters
        ----------
        function : casadi.Function
            ``control(t, x, u_last[, w][, x_hat]) -> (u[, w_next], ok)``: the controller's step on the state it is given,
            or with an input ``x_hat`` given the measurement as ``x`` (for its own estimators' innovations) and the
            filtered state as ``x_hat`` (what it acts on).
        reset : casadi.Function
            ``reset(t, x) -> (u_last[, w])``: its memory reset.
        n_inner : int
            Length of its memory ``w`` (0: none).

        Returns
        -------
        control : casadi.Function
            ``control(t, x, u_last, w) -> (u, w_next, ok)``, ``w`` the controller's memory then the filter's: the
            controller given the filtered state; ``ok`` also 0 for a non-finite filter memory.
        reset : casadi.Function
            ``reset(t, x) -> (u_last, w)``: the controller's reset, then the filter's first memory at ``x``.
        predict : casadi.Function
            ``predict(u_last, w) -> x``: :meth:`prediction` from the memory.

        Raises
        ------
        InputError
            A Function whose sizes are not the filter's.
        """
        if function.numel_in("x") != self.nx or function.numel_in("u_last") != self.nu or (n_inner and function.numel_in("w") != n_inner):
            raise InputError(f"function: expected a step of {self.nx} states, {self.nu} inputs and {n_inner} memory entries")
        nw = n_inner + self.n_memory
        t, y, u_last, w = ca.MX.sym("t"), ca.MX.sym("x", self.nx), ca.MX.sym("u_last", self.nu), ca.MX.sym("w", nw)
        inner, wf = w[:n_inner], w[n_inner:]
        head = inner[:self.disturbance[1]] if self.disturbance else ca.MX(0, 1)
        x_hat, wf_next = self.update()(y, u_last, head, wf)
        if "x_hat" in function.name_in():  # the controller's estimators take the measurement, its state the filtered one
            u, inner_next, ok = function(t, y, u_last, inner, x_hat)
        elif n_inner:
            u, inner_next, ok = function(t, x_hat, u_last, inner)
        else:
            (u, ok), inner_next = function(t, x_hat, u_last), ca.MX(0, 1)
        ok = ca.logic_and(ok, ca.sum1(ca.fabs(wf_next)) < math.inf)
        control = ca.Function("control", [t, y, u_last, w], [u, ca.vertcat(inner_next, wf_next), ok], ["t", "x", "u_last", "w"], ["u", "w_next", "ok"])
        tr, xr = ca.MX.sym("t"), ca.MX.sym("x", self.nx)
        out = reset(tr, xr)
        u0, w0 = (out[0], out[1]) if n_inner else (out if not isinstance(out, (list, tuple)) else out[0], ca.MX(0, 1))
        first = ca.vertcat(xr, ca.DM(np.diag(self.sigma ** 2).reshape(-1, order="F")), u0, 0.0)
        reset_f = ca.Function("reset", [tr, xr], [u0, ca.vertcat(w0, first)], ["t", "x"], ["u_last", "w"])
        ul, wp = ca.MX.sym("u_last", self.nu), ca.MX.sym("w", nw)
        predicted = self.prediction()(ul, wp[:self.disturbance[1]] if self.disturbance else ca.MX(0, 1), wp[n_inner:])
        predict = ca.Function("predict", [ul, wp], [predicted], ["u_last", "w"], ["x"])
        return control, reset_f, predict


def state_filter(step: ca.Function, sigma: Any, x_scale: Any, u_scale: Any, delay: int = 0,
                 disturbance: tuple[int, int] | None = None, rhs: ca.Function | None = None, p: Any = None,
                 dt: float | None = None) -> StateFilter | None:
    """The measurement filter of a loop controller, or None where no state is noisy (see the module docstring).

    Parameters
    ----------
    step : casadi.Function
        ``F(x, u) -> x_next``: the controller's own fixed step over one period (two inputs; its first output the next state).
    sigma : array_like
        ``(nx,)`` the measurement noise's standard deviation per state (>= 0; state units).
    x_scale, u_scale : array_like
        ``(nx,)``, ``(nu,)`` the states' and inputs' scales (> 0).
    delay : int, optional
        The controller's input delay (0 or 1).
    disturbance : tuple of int, optional
        Where the controller's memory holds its input-disturbance estimate (``(start, stop)``).
    rhs : casadi.Function, optional
        ``f(x, u, p) -> dx/dt``: the model's right-hand side with the parameters free (``Q``'s parameter term,
        :data:`PARAMETER_ERROR`).
    p : array_like, optional
        ``(np,)`` the parameters of ``step`` (with ``rhs``).
    dt : float, optional
        The period ``step`` spans [s] (> 0; with ``rhs``).

    Returns
    -------
    StateFilter or None
        None when every ``sigma`` is 0.

    Raises
    ------
    InputError
        ``sigma`` not ``(nx,)`` finite and >= 0, scales not finite and > 0, a step not ``F(x, u)`` of those sizes, a
        delay not 0 or 1, ``rhs`` not ``f(x, u, p)`` of those sizes with ``p`` finite and ``dt`` > 0.
    """
    s = np.asarray(sigma, dtype=float).reshape(-1)
    xs, us = np.asarray(x_scale, dtype=float).reshape(-1), np.asarray(u_scale, dtype=float).reshape(-1)
    if not isinstance(step, ca.Function) or step.n_in() != 2 or step.numel_in(0) != s.size or step.numel_in(1) != us.size:
        raise InputError(f"step: expected a casadi.Function F(x ({s.size}), u ({us.size})) -> x_next")
    if not np.all(np.isfinite(s)) or np.any(s < 0):
        raise InputError(f"sigma: expected {s.size} finite standard deviations >= 0, got {s.tolist()}")
    if xs.size != s.size or not np.all(np.isfinite(xs) & (xs > 0)) or not np.all(np.isfinite(us) & (us > 0)):
        raise InputError("x_scale, u_scale: expected finite scales > 0, one per state and per input")
    if isinstance(delay, bool) or delay not in (0, 1):
        raise InputError(f"delay: expected 0 or 1, got {delay!r}")
    pv = None if p is None else np.asarray(p, dtype=float).reshape(-1)
    if rhs is not None and (pv is None or not isinstance(rhs, ca.Function) or rhs.n_in() < 3 or rhs.numel_in(0) != s.size
                            or rhs.numel_in(1) != us.size or rhs.numel_in(2) != pv.size or not np.all(np.isfinite(pv))
                            or dt is None or not (math.isfinite(dt) and dt > 0)):
        raise InputError(f"rhs, p, dt: expected f(x ({s.size}), u ({us.size}), p), its finite parameters and the period > 0")
    if not np.any(s > 0):
        return None
    x, u = ca.MX.sym("x", s.size), ca.MX.sym("u", us.size)
    return StateFilter(step=ca.Function("F", [x, u], [step.call([x, u])[0]]), sigma=s, x_scale=xs, u_scale=us, delay=int(delay),
                       disturbance=disturbance, rhs=rhs, p=pv, dt=float(dt or 0.0))


def measurement_filter(controller: Any, sigma: Any, rhs: ca.Function | None = None, p: Any = None) -> StateFilter | None:
    """The measurement filter of a built loop controller: its own fixed step, scales, delay and disturbance estimate.

    Parameters
    ----------
    controller : MPCController or TrackingController
        The controller (its ``step`` or ``predict``: ``F(x, u)``; ``plausible_ranges``; ``delay``; an MPC's
        ``disturbance_gain``).
    sigma : array_like
        ``(nx,)`` the measurement noise's standard deviation per state.
    rhs : casadi.Function, optional
        ``f(x, u, p) -> dx/dt``: the controller's model's right-hand side with the parameters free
        (:attr:`~gtmodel.modeling.simulation.explicit.ExplicitODE.f`); default None: no parameter term in ``Q``.
    p : array_like, optional
        ``(np,)`` the controller's parameters (with ``rhs``).

    Returns
    -------
    StateFilter or None
        None when every ``sigma`` is 0 (:func:`state_filter`).

    Raises
    ------
    InputError
        A controller without a one-period step, or ``sigma`` not one per state (:func:`state_filter`).
    """
    step = getattr(controller, "step", None) or getattr(controller, "predict", None)
    if step is None:
        raise InputError(f"controller: expected a loop controller with its one-period step, got {type(controller).__name__}")
    x_scale, u_scale = controller.plausible_ranges(controller.u_lb, controller.u_ub)[:2]
    nw, nu = getattr(controller, "nw", 0), len(controller.u_names)
    disturbance = (nw, nw + nu) if getattr(controller, "disturbance_gain", 0.0) else None
    return state_filter(step, sigma, x_scale, u_scale, delay=int(controller.delay), disturbance=disturbance, rhs=rhs, p=p,
                        dt=float(controller.dt))
