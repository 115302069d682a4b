"""The tracking problem both loop controllers build from: model, sampled reference, bounds, parameters, scales, weights.

The TV-LQR tracking controller (:func:`gtmodel.control.tracking.tracking_controller`) and
the MPC (:func:`gtmodel.control.mpc.mpc_controller`) track the same thing: a model's
reference motion sampled at the loop period, within input bounds, with the model's
parameters, weighted by ``Q`` and ``R`` (Bryson's rule on the reference's scales by
default). :func:`tracking_problem` checks and builds that once; each controller adds only
its own law (the Riccati gains, the horizon problem), so a change to the cost's weights or
the prediction step is made here, once, for both (python-control's ``create_mpc_iosystem``
reusing its ``OptimalControlProblem`` is the pattern).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError
from gtmodel.control.reference import INDEX_EPS, delayed_start, reference_scales, sample_reference
from gtmodel.modeling import ExplicitODE
from gtmodel.modeling.simulation.step_stability import step_stability

__all__ = ["PREDICTION_METHODS", "TrackingProblem", "fixed_step", "sqrt_psd", "substep_states", "tracking_problem", "weight_matrix"]

#: Prediction steps over one period: explicit Euler on ``f`` or the ExplicitODE's fixed steps.
PREDICTION_METHODS = ("euler", "rk4", "implicit_euler", "radau2")


def substep_states(ode: ExplicitODE, dt: float, method: str = "rk4", substeps: int = 1) -> ca.Function:
    """The states after each substep of a fixed step over one period: ``S(x, u, p) -> (nx, substeps)``.

    The last column is the step's result (:meth:`TrackingProblem.step`, the same operations);
    the others are where the model is between the samples. The MPC imposes its constraint
    rows there (:mod:`gtmodel.control.mpc_constraints`), the closed-loop check counts the
    plant's declared bounds there (:func:`gtmodel.problems.loop_file.loop_setup`): the
    flexible-joint drive's MPC held 9.98 A of 10 at the 4 ms samples and drew 13.23 A inside
    a period (issue 49's loop trial).

    Parameters
    ----------
    ode : ExplicitODE
        The model.
    dt : float
        The period [s].
    method : {"euler", "rk4", "implicit_euler", "radau2"}, optional
        :data:`PREDICTION_METHODS` (``"euler"``: explicit Euler on ``f``; the others one
        :meth:`~gtmodel.modeling.simulation.explicit.ExplicitODE.step` of ``dt / substeps``).
    substeps : int, optional
        Equal steps within ``dt``.

    Returns
    -------
    casadi.Function
        ``S(x (nx,1), u (nu,1), p (np,1)) -> x_substeps (nx, substeps)``.

    Raises
    ------
    InputError
        An unknown method, ``substeps`` below 1, a bad ``dt``.
    """
    if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)) or substeps < 1:
        raise InputError(f"substeps: expected a positive number of steps per period, got {substeps!r}")
    if method not in PREDICTION_METHODS:
        raise InputError(f"method: expected one of {', '.join(PREDICTION_METHODS)}, got {method!r}")
    h = float(dt) / int(substeps)
    x, u, p = ca.SX.sym("x", ode.nx), ca.SX.sym("u", ode.nu), ca.SX.sym("p", ode.np)
    single = None if method == "euler" else ode.step(h, method)
    states, xk = [], x
    for _ in range(int(substeps)):
        xk = xk + h * ode.f(xk, u, p) if single is None else single(xk, u, p)[0]
        states.append(xk)
    return ca.Function("substeps", [x, u, p], [ca.horzcat(*states)], ["x", "u", "p"], ["x_substeps"])


def sqrt_psd(m: np.ndarray) -> np.ndarray:
    """A square root of a weight matrix: ``L`` with ``L^T L = m`` (the residuals ``L e`` of a cost ``e^T m e``).

    Parameters
    ----------
    m : numpy.ndarray
        ``(n, n)`` symmetric positive semi-definite.

    Returns
    -------
    numpy.ndarray
        ``(n, n)`` ``L = diag(sqrt(lambda)) V^T`` of the eigendecomposition ``m = V diag(lambda) V^T``
        (negative round-off eigenvalues taken as 0).
    """
    val, vec = np.linalg.eigh(0.5 * (m + m.T))
    return (vec * np.sqrt(np.clip(val, 0.0, None))).T


def weight_matrix(value: Any, size: int, default: np.ndarray, name: str) -> np.ndarray:
    """A weight matrix of a tracking problem: None (the default diagonal), a vector (the diagonal) or a matrix.

    Parameters
    ----------
    value : None, array_like
        ``(size,)`` the diagonal or ``(size, size)`` the matrix; None: ``diag(default)``.
    size : int
        Its dimension.
    default : numpy.ndarray
        ``(size,)`` the default diagonal (or a ``(size, size)`` matrix when ``value`` is None).
    name : str
        The argument's name in messages (``"Q"``, ``"R"``, ``"Qf"``).

    Returns
    -------
    numpy.ndarray
        ``(size, size)`` symmetric positive semi-definite.

    Raises
    ------
    InputError
        Another shape, non-finite entries, or not symmetric positive semi-definite.
    """
    if value is None:
        return np.diag(default)
    w = np.asarray(value, dtype=float)
    if w.ndim == 1 and w.size == size:
        w = np.diag(w)
    if w.shape != (size, size) or not np.all(np.isfinite(w)):
        raise InputError(f"{name}: expected {size} diagonal entries or a ({size}, {size}) matrix of finite numbers, got shape {w.shape}")
    if not np.allclose(w, w.T) or np.min(np.linalg.eigvalsh(0.5 * (w + w.T))) < 0:
        raise InputError(f"{name}: expected a symmetric positive semi-definite weight")
    return w


@dataclass
class TrackingProblem:
    """A model's reference motion sampled at the loop period, with its bounds, parameters, scales and weights.

    Parameters
    ----------
    ode : ExplicitODE
        The model.
    dt : float
        Loop period [s].
    t0 : float
        Time of the first sample [s].
    x_ref, u_ref : numpy.ndarray
        ``(N, nx)``, ``(N, nu)`` the reference at ``t0 + k dt``.
    x_given, u_given : numpy.ndarray
        ``(M, nx)``, ``(M, nu)`` the reference as given (its last row is the end held).
    u_lb, u_ub : numpy.ndarray
        ``(nu,)`` input bounds (``-inf`` / ``inf``: none).
    p : numpy.ndarray
        ``(np,)`` parameter values of the model.
    x_scale, u_scale : numpy.ndarray
        ``(nx,)``, ``(nu,)`` the scales of :func:`~gtmodel.control.reference.reference_scales`.
    Q, R : numpy.ndarray
        ``(nx, nx)`` state and ``(nu, nu)`` positive definite input weights.
    lead : int, optional
        Periods at rest before the given reference (:func:`~gtmodel.control.reference.delayed_start`; default 0).
    """

    ode: ExplicitODE = field(repr=False)
    dt: float
    t0: float
    x_ref: np.ndarray
    u_ref: np.ndarray
    x_given: np.ndarray
    u_given: np.ndarray
    u_lb: np.ndarray
    u_ub: np.ndarray
    p: np.ndarray
    x_scale: np.ndarray
    u_scale: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    lead: int = 0

    @property
    def x_names(self) -> list[str]:
        """The model's state names, in the order of the columns."""
        return list(self.ode.x_names)

    @property
    def u_names(self) -> list[str]:
        """The model's input names, in the order of the columns."""
        return list(self.ode.u_names)

    def terminal_weight(self, Qf: Any, default: np.ndarray) -> np.ndarray:
        """The terminal weight: ``Qf`` as given (:func:`weight_matrix`) or ``default``.

        Parameters
        ----------
        Qf : array_like or None
            ``(nx,)`` diagonal or ``(nx, nx)``; None: ``default``.
        default : numpy.ndarray
            ``(nx, nx)`` the controller's default (the MPC: ``Q``; the TV-LQR: the stationary
            Riccati solution at the held end).

        Returns
        -------
        numpy.ndarray
            ``(nx, nx)``.

        Raises
        ------
        InputError
            A weight :func:`weight_matrix` refuses.
        """
        return default if Qf is None else weight_matrix(Qf, self.ode.nx, np.ones(self.ode.nx), "Qf")

    def step(self, method: str = "rk4", substeps: int = 1) -> ca.Function:
        """:func:`fixed_step` of the problem's model over its period: ``F(x, u, p) -> x_next``.

        Parameters
        ----------
        method : str, optional
            :data:`PREDICTION_METHODS`.
        substeps : int, optional
            Steps of ``method`` within one period.

        Returns
        -------
        casadi.Function
            As :func:`fixed_step`'s.

        Raises
        ------
        InputError
            An unknown method.
        """
        return fixed_step(self.ode, self.dt, method, substeps)

    def check_step(self, method: str, substeps: int, what: str) -> None:
        """Refuse a prediction step that is unstable for the model along the reference.

        Parameters
        ----------
        method : str
            :data:`PREDICTION_METHODS` (the explicit ones are checked).
        substeps : int
            Steps of ``method`` within one period.
        what : str
            The step's role, for the message (``"the MPC's prediction step"``).

        Raises
        ------
        InputError
            A decaying mode of the model's Jacobian along the reference that the step amplifies
            (:func:`~gtmodel.modeling.simulation.step_stability.step_stability`), naming the eigenvalue, where it
            is and the substeps needed.
        """
        t = self.t0 + self.dt * np.arange(len(self.x_ref))
        stability = step_stability(self.ode.f, self.dt, method, substeps, self.x_ref, self.u_ref, self.p, t=t)
        if stability is not None and not stability.stable:
            raise InputError(stability.message(f"{what} (method, substeps)", "substeps = {n}"))

    def prediction(self, method: str = "rk4", substeps: int = 1, name: str = "F", every_substep: bool = False) -> ca.Function:
        """The step of :meth:`step` at the problem's parameters: ``F(x, u) -> x_next``.

        Parameters
        ----------
        method : str, optional
            :data:`PREDICTION_METHODS`.
        substeps : int, optional
            Steps of ``method`` within one period.
        name : str, optional
            The Function's name (the MPC's ``"F"``, the tracking law's ``"predict"``).
        every_substep : bool, optional
            The states after each substep instead (:func:`substep_states`; the last column
            is ``x_next``): where the MPC's constraint rows act between the samples.

        Returns
        -------
        casadi.Function
            ``(x (nx,1), u (nu,1)) -> x_next (nx,1)``, inputs ``x``, ``u``, output ``x_next``
            (``x_substeps (nx, substeps)`` with ``every_substep``).

        Raises
        ------
        InputError
            An unknown method.
        """
        x, u = ca.SX.sym("x", self.ode.nx), ca.SX.sym("u", self.ode.nu)
        if every_substep:
            states = substep_states(self.ode, self.dt, method, substeps)(x, u, self.p)
            return ca.Function(name, [x, u], [states], ["x", "u"], ["x_substeps"])
        return ca.Function(name, [x, u], [self.step(method, substeps).call([x, u, self.p])[0]], ["x", "u"], ["x_next"])


def fixed_step(ode: ExplicitODE, dt: float, method: str = "rk4", substeps: int = 1) -> ca.Function:
    """A model's fixed step over one period, its parameters free: ``F(x, u, p) -> x_next`` (:meth:`TrackingProblem.step`).

    Parameters
    ----------
    ode : ExplicitODE
        The model.
    dt : float
        The period [s].
    method : {"euler", "rk4", "implicit_euler", "radau2"}, optional
        :data:`PREDICTION_METHODS` (``"euler"``: explicit Euler on ``f``; the others:
        :meth:`~gtmodel.modeling.simulation.explicit.ExplicitODE.step`).
    substeps : int, optional
        Steps of ``method`` within one period.

    Returns
    -------
    casadi.Function
        ``(x (nx,1), u (nu,1), p (np,1)) -> x_next (nx,1)``, first output the next state.

    Raises
    ------
    InputError
        An unknown method.
    """
    if method != "euler":
        return ode.step(dt, method, substeps=substeps)
    x, u, p = ca.SX.sym("x", ode.nx), ca.SX.sym("u", ode.nu), ca.SX.sym("p", ode.np)
    h, xn = dt / substeps, x
    for _ in range(substeps):
        xn = xn + h * ode.f(xn, u, p)
    return ca.Function("euler_step", [x, u, p], [xn], ["x", "u", "p"], ["x_next"])


def tracking_problem(ode: ExplicitODE, t: Any, x_ref: Any, u_ref: Any, dt: float = LOOP_PERIOD_S, Q: Any = None, R: Any = None,
                     u_lb: Any = None, u_ub: Any = None, p: Any = None, min_samples: int = 1, eps: float = INDEX_EPS,
                     delay: int = 0) -> TrackingProblem:
    """The tracking problem of a model along a reference (what the TV-LQR and the MPC share).

    The reference is sampled at the loop period from its first time to its last
    (:func:`~gtmodel.control.reference.sample_reference`); the weights default to Bryson's
    rule on its scales (:func:`~gtmodel.control.reference.reference_scales`): ``Q =
    diag(1 / x_scale^2)``, ``R = diag(1 / u_scale^2)`` (Bryson & Ho, *Applied Optimal
    Control*, 1975, sec. 5.4).

    Parameters
    ----------
    ode : ExplicitODE
        The model (:func:`gtmodel.modeling.explicit_ode`).
    t : array_like
        ``(M,)`` increasing reference times [s].
    x_ref, u_ref : array_like
        ``(M, nx)``, ``(M, nu)`` reference states and inputs in the order of ``ode.x_names``, ``ode.u_names``.
    dt : float, optional
        Loop period [s] (default :data:`gtmodel.defaults.LOOP_PERIOD_S`).
    Q, R : array_like, optional
        State and input weights, diagonals or matrices (:func:`weight_matrix`; default Bryson's rule).
    u_lb, u_ub : array_like, optional
        ``(nu,)`` input bounds (default the model's declared ones).
    p : array_like, optional
        ``(np,)`` parameter values (default ``ode.p_default``).
    min_samples : int, optional
        Fewest loop periods plus one the reference must span (the TV-LQR: 2).
    eps : float, optional
        Slack of the last grid point (default :data:`~gtmodel.control.reference.INDEX_EPS`;
        the MPC's grid: its own).
    delay : int, optional
        Periods of input delay the controller compensates (default 0): a reference starting
        at rest with another first input than the one holding it there is led by that many
        periods at rest (:func:`~gtmodel.control.reference.delayed_start`, :attr:`TrackingProblem.lead`).

    Returns
    -------
    TrackingProblem

    Raises
    ------
    InputError
        A bad period or reference (times not increasing, too short, another number of
        columns than the model's states and inputs, a model without inputs); bounds of
        another length, crossed or NaN; parameters of another length; a weight
        :func:`weight_matrix` refuses; ``R`` not positive definite.
    """
    t0, xs, us = sample_reference(t, x_ref, u_ref, dt, min_samples=min_samples, eps=eps)
    if xs.shape[1] != ode.nx or us.shape[1] != ode.nu or ode.nu == 0:
        raise InputError(f"x_ref, u_ref: expected {ode.nx} state and {ode.nu} (>= 1) input columns, got {xs.shape[1]} and {us.shape[1]}")
    lb = ode.u_lb if u_lb is None else np.asarray(u_lb, dtype=float).reshape(-1)
    ub = ode.u_ub if u_ub is None else np.asarray(u_ub, dtype=float).reshape(-1)
    if lb.size != ode.nu or ub.size != ode.nu or np.any(lb > ub) or np.any(np.isnan(lb)) or np.any(np.isnan(ub)):
        raise InputError(f"u_lb, u_ub: expected {ode.nu} bounds each with u_lb <= u_ub")
    pv = ode.p_default if p is None else np.asarray(p, dtype=float).reshape(-1)
    if pv.size != ode.np:
        raise InputError(f"p: expected {ode.np} parameter values, got {pv.size}")
    t, x_ref, u_ref, lead = delayed_start(ode.f, t, x_ref, u_ref, pv, dt, delay)
    if lead:
        t0, xs, us = sample_reference(t, x_ref, u_ref, dt, min_samples=min_samples, eps=eps)
    m = np.asarray(t).size
    x_given, u_given = np.asarray(x_ref, dtype=float).reshape(m, -1), np.asarray(u_ref, dtype=float).reshape(m, -1)
    x_scale, u_scale = reference_scales(xs, us, lb, ub)
    Qm = weight_matrix(Q, ode.nx, 1.0 / x_scale**2, "Q")
    Rm = weight_matrix(R, ode.nu, 1.0 / u_scale**2, "R")
    if np.min(np.linalg.eigvalsh(Rm)) <= 0:
        raise InputError("R: expected a positive definite input weight")
    return TrackingProblem(ode=ode, dt=float(dt), t0=t0, x_ref=xs, u_ref=us, x_given=x_given, u_given=u_given, u_lb=lb.copy(),
                           u_ub=ub.copy(), p=pv, x_scale=x_scale, u_scale=u_scale, Q=Qm, R=Rm, lead=lead)
