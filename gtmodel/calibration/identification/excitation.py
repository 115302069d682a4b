"""Excitation trajectories for dynamic identification: finite Fourier series optimised by IPOPT.

The identification of Dressler (2012), ch. 6.2 (``tau = Y theta``, eqs. 6.7-6.8) is as
good as the regressor ``Y`` along the motion is well conditioned. Following Swevers,
Ganseman, Tukel, De Schutter and Van Brussel, "Optimal robot excitation and
identification", IEEE Trans. Robotics and Automation 13(5), 1997, every cart follows a
periodic finite Fourier series (:class:`FourierTrajectory`)::

    q_i(t) = q0_i + sum_k  a_ik / (k w) sin(k w t) - b_ik / (k w) cos(k w t),   w = 2 pi / period

(periodic: the log can hold several periods, averaged or filtered without end effects).
:func:`design_excitation` chooses the coefficients by IPOPT (``ca.nlpsol``) to make the
columns of the regressor as close to orthogonal as possible, subject to the cart
travel, velocity and acceleration limits and the workspace (the spheres of eq. 4.9
must intersect and every link stays within the spherical-joint angle) on a time grid.

Choice of the NLP formulation: the decision variables are the ``3 (2K + 1)`` Fourier
coefficients, a static NLP without dynamics or collocation, so it is written with
:func:`casadi.nlpsol` directly on the symbolic regressor of
:class:`~gtmodel.calibration.identification.DynamicRegressor` (mapped over the
grid) rather than through :mod:`gtmodel.modeling`, whose Model/Optimization layer is
made for optimal control. The regressor uses the smooth ``tanh`` sign (gradients) and
the design is then assessed with the exact sign.

Objective (a smooth surrogate of the condition number): with ``A = sum_j Y_j^T Y_j`` and
the correlation matrix ``C = D^-1/2 A D^-1/2`` (``D = diag A``) of the column-scaled
regressor, ``C = I + E`` and ``cond(C) <= (1 + ||E||) / (1 - ||E||)``; the design minimises
``||E||_F^2 - w (1/p) sum_i log(A_ii / A_ii,0)``, the second term (small ``w``) rewarding
signal energy in every column (``-log det A = -sum log A_ii - log det C``, i.e. a
D-optimal design up to the correlation part). The condition number of the
column-scaled regressor (the figure of
:func:`gtmodel.calibration.identifiability.analyze_jacobian`) is reported before and
after.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any, Sequence

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel.calibration.identification.regressor import DynamicRegressor
from gtmodel.calibration.identification.variants import ModelVariant
from gtmodel.errors import GtModelError, InputError
from gtmodel.modeling.ocp.result import normalize_ipopt_status
from gtmodel.robots.kinematic_expressions import fk_expression, link_cosines_expression
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.parameters import RobotParameters, load_parameters
from gtmodel.status import Status, StatusResult

__all__ = ["FourierTrajectory", "ExcitationDesign", "design_excitation", "regressor_condition"]

_log = logging.getLogger("gtmodel")


@dataclass(frozen=True)
class FourierTrajectory:
    """Periodic cart motion as a finite Fourier series (Swevers et al. 1997).

    ``q_i(t) = q0_i + sum_k a_ik/(k w) sin(k w t) - b_ik/(k w) cos(k w t)``, ``w = 2 pi /
    period``; so ``q_dot_i = sum_k a_ik cos(k w t) + b_ik sin(k w t)``.

    Parameters
    ----------
    q0 : numpy.ndarray, shape (3,)
        Offsets [m].
    a, b : numpy.ndarray, shape (3, K)
        Velocity amplitudes of the cosine and sine terms [m/s].
    period : float
        Period [s].

    Raises
    ------
    InputError
        Shapes or values invalid.
    """

    q0: np.ndarray
    a: np.ndarray
    b: np.ndarray
    period: float

    def __post_init__(self) -> None:
        q0 = np.asarray(self.q0, dtype=float).ravel()
        a = np.atleast_2d(np.asarray(self.a, dtype=float))
        b = np.atleast_2d(np.asarray(self.b, dtype=float))
        if q0.shape != (3,) or a.ndim != 2 or a.shape[0] != 3 or a.shape != b.shape or a.shape[1] < 1:
            raise InputError(f"FourierTrajectory: expected q0 (3,), a and b (3, K), got {q0.shape}, {a.shape}, {b.shape}")
        if not (np.all(np.isfinite(q0)) and np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
            raise InputError("FourierTrajectory: coefficients must be finite")
        if not (isinstance(self.period, (int, float)) and math.isfinite(self.period) and self.period > 0):
            raise InputError(f"period: expected a positive time in s, got {self.period!r}")
        object.__setattr__(self, "q0", q0)
        object.__setattr__(self, "a", a)
        object.__setattr__(self, "b", b)

    @property
    def harmonics(self) -> int:
        """Number of harmonics K."""
        return int(self.a.shape[1])

    @property
    def coefficients(self) -> np.ndarray:
        """``[q0, a.ravel(), b.ravel()]``, shape (3 (2K + 1),)."""
        return np.concatenate([self.q0, self.a.ravel(), self.b.ravel()])

    @classmethod
    def from_coefficients(cls, coefficients: np.typing.ArrayLike, harmonics: int, period: float) -> "FourierTrajectory":
        """Build from the coefficient vector of :attr:`coefficients`.

        Parameters
        ----------
        coefficients : array_like, shape (3 (2K + 1),)
            ``[q0, a.ravel(), b.ravel()]``.
        harmonics : int
            K.
        period : float
            Period [s].

        Returns
        -------
        FourierTrajectory

        Raises
        ------
        InputError
            Wrong length.
        """
        c = np.asarray(coefficients, dtype=float).ravel()
        K = int(harmonics)
        if c.size != 3 * (2 * K + 1):
            raise InputError(f"coefficients: expected {3 * (2 * K + 1)} values for {K} harmonics, got {c.size}")
        return cls(c[:3], c[3:3 + 3 * K].reshape(3, K), c[3 + 3 * K:].reshape(3, K), period)

    @staticmethod
    def expression(t: Any, coefficients: Any, harmonics: int, period: float) -> tuple[Any, Any, Any]:
        """The series as CasADi expressions (used by the NLP and for evaluation).

        Parameters
        ----------
        t : casadi.SX or casadi.MX, scalar
            Time [s].
        coefficients : casadi.SX or casadi.MX, shape (3 (2K + 1), 1)
            ``[q0, a.ravel(), b.ravel()]``.
        harmonics : int
            K.
        period : float
            Period [s].

        Returns
        -------
        q, q_dot, q_ddot : casadi expressions, shape (3, 1)
            Position [m], velocity [m/s], acceleration [m/s^2].
        """
        K = int(harmonics)
        w = 2 * math.pi / period
        q0 = coefficients[0:3]
        a = ca.reshape(coefficients[3:3 + 3 * K], K, 3).T  # row-major (3, K)
        b = ca.reshape(coefficients[3 + 3 * K:3 + 6 * K], K, 3).T
        q, qd, qdd = q0, 0, 0
        for k in range(1, K + 1):
            s, c = ca.sin(k * w * t), ca.cos(k * w * t)
            q = q + (a[:, k - 1] * s - b[:, k - 1] * c) / (k * w)
            qd = qd + a[:, k - 1] * c + b[:, k - 1] * s
            qdd = qdd + k * w * (-a[:, k - 1] * s + b[:, k - 1] * c)
        return q, qd, qdd

    @cached_property
    def _function(self) -> ca.Function:
        t = ca.SX.sym("t")
        q, qd, qdd = self.expression(t, ca.DM(self.coefficients), self.harmonics, self.period)
        return ca.Function("fourier", [t], [q, qd, qdd], ["t"], ["q", "q_dot", "q_ddot"])

    def evaluate(self, t: np.typing.ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, velocities and accelerations at times t.

        Parameters
        ----------
        t : array_like, shape (N,)
            Times [s].

        Returns
        -------
        q, q_dot, q_ddot : numpy.ndarray, shape (N, 3)
            [m], [m/s], [m/s^2].

        Raises
        ------
        InputError
            Non-finite or non-1-D times.
        """
        tt = np.asarray(t, dtype=float).ravel()
        if tt.size == 0 or not np.all(np.isfinite(tt)):
            raise InputError("t: expected finite times in s")
        out = self._function.map(tt.size)(tt[None, :]) if tt.size > 1 else self._function(tt[0])
        return tuple(np.asarray(o).reshape(3, -1).T for o in out)


def regressor_condition(regressor: DynamicRegressor, trajectory: FourierTrajectory, n_samples: int = 500, min_speed: float = 0.0) -> float:
    """Condition number of the column-scaled regressor along a trajectory (one period).

    Parameters
    ----------
    regressor : DynamicRegressor
        The regressor (its friction form is used as it is).
    trajectory : FourierTrajectory
        The motion.
    n_samples : int, optional
        Samples over one period (default 500).
    min_speed : float, optional
        Rows with ``|q_dot_i|`` below this [m/s] are left out (as in the identification).

    Returns
    -------
    float
        ``sigma_max / sigma_min`` of ``Y`` with unit-norm columns (``inf`` if singular).

    Raises
    ------
    UnreachablePoseError
        The trajectory leaves the workspace.
    """
    t = np.linspace(0.0, trajectory.period, int(n_samples), endpoint=False)
    q, qd, qdd = trajectory.evaluate(t)
    Y, _, v = regressor.evaluate(q, qd, qdd, "cart")
    A = Y[np.abs(v) >= min_speed]
    nrm = np.linalg.norm(A, axis=0)
    if np.any(nrm == 0):
        return math.inf
    s = np.linalg.svd(A / nrm, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else math.inf


@dataclass
class ExcitationDesign(StatusResult):
    """An optimised excitation trajectory (Swevers et al. 1997; Dressler (2012), ch. 6.2).

    Parameters
    ----------
    trajectory : FourierTrajectory
        The optimised motion.
    start : FourierTrajectory
        The initial guess.
    condition_before, condition_after : float
        Condition number of the column-scaled regressor (exact sign, rows above
        ``min_speed``) along the start and the optimised motion.
    objective_before, objective_after : float
        The NLP objective at the start and the solution.
    status : Status
        ``optimal``, ``acceptable``, ``max_iterations``, ``infeasible`` or ``error``.
    message : str
        IPOPT's return status.
    iterations : int
        IPOPT iterations.
    solve_time : float
        Wall time [s].
    max_violation : float
        Largest violation of the limits checked on a grid 10 times finer than the NLP's
        (in the constraint's unit; <= 0 means satisfied).
    info : dict
        The limits used.
    """

    trajectory: FourierTrajectory
    start: FourierTrajectory
    condition_before: float
    condition_after: float
    objective_before: float
    objective_after: float
    iterations: int
    solve_time: float
    max_violation: float
    info: dict = field(default_factory=dict)

    @property
    def success(self) -> bool:
        """True for an optimal or acceptable IPOPT solution (a design stopped at IPOPT's
        "acceptable" level is still a motion to use)."""
        return self.status in (Status.OPTIMAL, Status.ACCEPTABLE)


def design_excitation(
    parameters: RobotParameters | str | Path,
    variant: str | ModelVariant = "model_2",
    *,
    T_center: Sequence[float],
    harmonics: int = 4,
    period: float = 10.0,
    n_grid: int = 60,
    max_velocity: float = 0.5,
    max_acceleration: float = 3.0,
    travel_margin: float = 0.05,
    joint_angle_margin_deg: float = 2.0,
    energy_weight: float = 0.1,
    friction_width: float = 0.05,
    min_speed: float = 0.05,
    configuration: int | Sequence[int] = 0,
    seed: int = 0,
    max_iter: int = 150,
    start: FourierTrajectory | None = None,
) -> ExcitationDesign:
    """Optimise a Fourier excitation trajectory for the identification regressor (eqs. 6.7-6.8).

    See the module docstring for the objective; constraints on ``n_grid`` points of one
    period: cart travel (limits of the parameter set minus ``travel_margin``), ``|q_dot|
    <= max_velocity``, ``|q_ddot| <= max_acceleration``, FK spheres intersecting (eq. 4.9)
    and link angles within the spherical-joint limit minus ``joint_angle_margin_deg``.

    Parameters
    ----------
    parameters : RobotParameters or str or pathlib.Path
        Parameter set (a name of :func:`gtmodel.robots.available_parameter_sets`, a TOML
        file or the parameters).
    variant : str or ModelVariant, optional
        The regressor to condition (default ``"model_2"``).
    T_center : sequence of float, shape (3,)
        TCP position [m] whose cart positions are the initial offsets ``q0`` (keyword
        only; e.g. ``(0.0, 2.9, -0.5)`` in the L1 workspace).
    harmonics : int, optional
        Number of harmonics K (default 4).
    period : float, optional
        Period [s] (default 10 s).
    n_grid : int, optional
        Constraint and objective grid points per period (default 60).
    max_velocity : float, optional
        Cart speed limit [m/s] (default 0.5).
    max_acceleration : float, optional
        Cart acceleration limit [m/s^2] (default 3).
    travel_margin : float, optional
        Distance kept from the cart travel ends [m] (default 0.05).
    joint_angle_margin_deg : float, optional
        Margin to the spherical-joint limit [deg] (default 2).
    energy_weight : float, optional
        Weight ``w`` of the column-energy term (default 0.1).
    friction_width : float, optional
        Width of the ``tanh`` sign in the design regressor [m/s] (default 0.05).
    min_speed : float, optional
        Speed threshold of the reported condition numbers [m/s] (as in the identification).
    configuration : int or sequence of int, optional
        IK configuration (default 0).
    seed : int, optional
        Seed of the random initial coefficients.
    max_iter : int, optional
        IPOPT iteration limit (default 150).
    start : FourierTrajectory, optional
        Initial guess (default: random coefficients of 0.06 m/s about ``T_center``).

    Returns
    -------
    ExcitationDesign
        Never None; a failed solve has its status and message (the last iterate is kept).

    Raises
    ------
    InputError
        Invalid sizes or limits.
    UnreachablePoseError
        ``T_center`` outside the workspace (cart travel, joint limits).
    """
    robot = load_parameters(parameters)
    for name, val in (("period", period), ("max_velocity", max_velocity), ("max_acceleration", max_acceleration), ("friction_width", friction_width)):
        if not (isinstance(val, (int, float)) and math.isfinite(val) and val > 0):
            raise InputError(f"{name}: expected a positive number, got {val!r}")
    for name, val in (("travel_margin", travel_margin), ("joint_angle_margin_deg", joint_angle_margin_deg), ("energy_weight", energy_weight), ("min_speed", min_speed)):
        if not (isinstance(val, (int, float)) and math.isfinite(val) and val >= 0):
            raise InputError(f"{name}: expected a non-negative number, got {val!r}")
    for name, val, lo in (("harmonics", harmonics, 1), ("n_grid", n_grid, 4), ("max_iter", max_iter, 1)):
        if isinstance(val, bool) or not isinstance(val, (int, np.integer)) or val < lo:
            raise InputError(f"{name}: expected an integer >= {lo}, got {val!r}")
    K = int(harmonics)
    if n_grid < 4 * K:
        raise InputError(f"n_grid: expected at least 4 points per period of the highest harmonic ({4 * K}), got {n_grid}")
    design_reg = DynamicRegressor(robot, variant, configuration, friction="tanh", friction_width=friction_width)
    exact_reg = DynamicRegressor(robot, variant, configuration)
    p = design_reg.n_parameters
    scale = np.abs(exact_reg.theta_of())
    scale = np.where(scale > 0, scale, 1.0)

    kin = GantryTau3Kinematics(robot)
    q_center = kin.require_in_workspace(np.asarray(T_center, dtype=float), configuration)
    if start is None:
        rng = np.random.default_rng(seed)
        start = FourierTrajectory(q_center, 0.06 * rng.standard_normal((3, K)), 0.06 * rng.standard_normal((3, K)), float(period))
    elif not isinstance(start, FourierTrajectory) or start.harmonics != K or start.period != period:
        raise InputError(f"start: expected a FourierTrajectory with {K} harmonics and period {period} s")

    # --- NLP: coefficients -> grid motion -> regressor (mapped) and workspace functions
    n_c = 3 * (2 * K + 1)
    c = ca.MX.sym("c", n_c)
    tsym = ca.SX.sym("t")
    csym = ca.SX.sym("c", n_c)
    traj = ca.Function("traj", [tsym, csym], list(FourierTrajectory.expression(tsym, csym, K, period)))
    grid = np.linspace(0.0, period, int(n_grid), endpoint=False)
    Q, Qd, Qdd = traj.map(int(n_grid))(ca.DM(grid).T, ca.repmat(c, 1, int(n_grid)))
    Ybig = design_reg.cart_function.map(int(n_grid))(Q, Qd, Qdd)[0]  # (3, p n_grid)
    Ystack = ca.vertcat(*ca.horzsplit(Ybig, p)) @ ca.diag(ca.DM(scale))  # (3 n, p), columns in N
    A = Ystack.T @ Ystack
    d = ca.diag(A)
    dinv = 1.0 / ca.sqrt(d)
    C = A * (dinv @ dinv.T)
    E2 = ca.sumsqr(C) - ca.sumsqr(ca.diag(C))  # ||C - I||_F^2 (diag of C is 1)
    qs = ca.SX.sym("q", 3)
    Tq, h2, _ = fk_expression(qs, 1.0, kin.L, kin.As, kin.v)
    ws = ca.Function("ws", [qs], [ca.vertcat(h2, ca.fabs(link_cosines_expression(Tq, qs, kin.As, kin.v)))])
    W = ws.map(int(n_grid))(Q)  # (4, n)
    lim = robot.limits
    cos_lim = math.cos(lim.joint_angle_max - math.radians(joint_angle_margin_deg))
    qlo = lim.cart_travel[:, 0] + travel_margin
    qhi = lim.cart_travel[:, 1] - travel_margin
    g = ca.vertcat(ca.vec(Q), ca.vec(Qd), ca.vec(Qdd), ca.vec(W))
    lbg = np.concatenate([np.tile(qlo, n_grid), np.full(3 * n_grid, -max_velocity), np.full(3 * n_grid, -max_acceleration),
                          np.tile([1e-2, cos_lim, cos_lim, cos_lim], n_grid)])
    ubg = np.concatenate([np.tile(qhi, n_grid), np.full(3 * n_grid, max_velocity), np.full(3 * n_grid, max_acceleration),
                          np.tile([np.inf, 1.0, 1.0, 1.0], n_grid)])
    fd0 = ca.Function("d", [c], [d])
    d0 = np.maximum(np.asarray(fd0(start.coefficients)).ravel(), 1e-12)
    J = E2 - energy_weight * ca.sum1(ca.log(d / ca.DM(d0))) / p
    fJ = ca.Function("J", [c], [J])
    solver = ca.nlpsol("excitation", "ipopt", {"x": c, "f": J, "g": g}, {
        "ipopt.print_level": 0, "print_time": False, "ipopt.max_iter": int(max_iter), "ipopt.tol": 1e-6,
        "ipopt.acceptable_tol": 1e-3, "ipopt.acceptable_obj_change_tol": 1e-4, "ipopt.acceptable_iter": 5,
        "ipopt.hessian_approximation": "limited-memory", "ipopt.sb": "yes",
    })
    lbx = np.full(n_c, -np.inf)
    ubx = np.full(n_c, np.inf)
    lbx[:3], ubx[:3] = qlo, qhi
    t0 = time.perf_counter()
    try:
        sol = solver(x0=start.coefficients, lbg=lbg, ubg=ubg, lbx=lbx, ubx=ubx)
        stats = solver.stats()
        x = np.asarray(sol["x"]).ravel()
        message = str(stats.get("return_status", "unknown"))
        status = normalize_ipopt_status(message)
        iterations = int(stats.get("iter_count", 0))
    except RuntimeError as exc:  # pragma: no cover - IPOPT aborts (e.g. NaN in evaluation)
        x, message, status, iterations = start.coefficients, f"IPOPT failed: {exc}", Status.ERROR, 0
    solve_time = time.perf_counter() - t0
    best = FourierTrajectory.from_coefficients(x, K, period)
    # limits on a 10x finer grid (unit of each constraint)
    fine = np.linspace(0.0, period, 10 * int(n_grid), endpoint=False)
    q, qd, qdd = best.evaluate(fine)
    Wf = np.asarray(ws.map(fine.size)(q.T))
    viol = max(
        float(np.max(qlo - q)), float(np.max(q - qhi)), float(np.max(np.abs(qd)) - max_velocity),
        float(np.max(np.abs(qdd)) - max_acceleration), float(np.max(1e-2 - Wf[0])), float(np.max(cos_lim - Wf[1:])),
    )
    try:
        cond_before = regressor_condition(exact_reg, start, min_speed=min_speed)
    except GtModelError:  # the random start may leave the workspace
        cond_before = math.inf
    cond_after = regressor_condition(exact_reg, best, min_speed=min_speed)
    _log.info("excitation design: %s, cond %.3g -> %.3g in %.2f s", message, cond_before, cond_after, solve_time)
    return ExcitationDesign(
        trajectory=best, start=start, condition_before=cond_before, condition_after=cond_after,
        objective_before=float(fJ(start.coefficients)), objective_after=float(fJ(x)), status=status, message=message,
        iterations=iterations, solve_time=solve_time, max_violation=viol,
        info={"harmonics": K, "period_s": float(period), "n_grid": int(n_grid), "max_velocity": float(max_velocity),
              "max_acceleration": float(max_acceleration), "travel_margin": float(travel_margin),
              "joint_angle_margin_deg": float(joint_angle_margin_deg), "variant": design_reg.variant.name},
    )
