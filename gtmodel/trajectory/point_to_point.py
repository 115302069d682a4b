"""Time- and energy-optimal point-to-point motion of a Gantry-Tau (Dressler (2012), ch. 3.5).

The problem of Table 3.1 ("direct" rows): the TCP moves from rest at ``start`` to rest at
``end`` (zero velocity and acceleration at both ends), the actuator forces are bounded,
and the cost is::

    C = final_time + w * sum_i integral tau_i^2 dt

with the final time free. It is declared on the rigid-body model of
:func:`gtmodel.robots.gantry_tau_model` (TCP states, smooth friction) as an
:class:`gtmodel.modeling.Optimization` and transcribed by direct collocation
(:mod:`gtmodel.modeling.collocation`). The initial guess is the straight line with a
trapezoidal velocity profile (the thesis' choice) and the forces of the inverse dynamics
along it.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError, UnreachablePoseError
from gtmodel.modeling import CollocationTranscription, Model, Optimization, OptimizationResult
from gtmodel.modeling.result import lagrange_basis
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.friction import DEFAULT_FRICTION_WIDTH
from gtmodel.robots.kinematics import configuration_signs, link_cosines_expression
from gtmodel.robots.model import gantry_tau_model
from gtmodel.robots.parameters import RobotParameters, load_parameters

__all__ = [
    "PointToPoint",
    "PointToPointSolution",
    "trapezoid_profile",
    "build_optimization",
    "check_holding_forces",
    "solve_point_to_point",
    "SAMPLE_TIME",
    "TRAJECTORY_COLUMNS",
]

_log = logging.getLogger("gtmodel")

#: Controller sample time [s] of the resampled trajectory (Dressler (2012), ch. 3.2).
SAMPLE_TIME = 0.004
#: Leading columns of the trajectory table, in this order.
TRAJECTORY_COLUMNS = ("t", "x", "y", "z", "q1", "q2", "q3", "qd1", "qd2", "qd3", "tau1", "tau2", "tau3")


@dataclass
class PointToPoint:
    """Declaration of a point-to-point optimal motion.

    Parameters
    ----------
    robot : RobotParameters or str
        Parameter set or its name/path.
    start, end : array_like, shape (3,)
        TCP positions at rest [m].
    force_limit : array_like, shape (3,)
        Symmetric bound on each actuator force, ``|tau_i| <= force_limit_i`` [N].
    w : float
        Energy weight in ``final_time + w * sum integral tau^2 dt`` [s / (N^2 s)].
    final_time_guess : float
        Initial guess of the duration [s].
    final_time_bounds : tuple of float
        Bounds of the free duration [s].
    friction, friction_width : str, float
        Friction form used in the optimisation and its width [m/s] (smooth by default).
    configuration : int
        IK configuration of the robot (see :func:`gtmodel.robots.configuration_signs`).
    elements, points, scheme : int, int, str
        Collocation mesh (JModelica's defaults: 50 elements, 3 Radau points).
    max_iter, tol : int, float
        IPOPT iteration limit and tolerance.
    name : str
        Name of the problem (used in reports).
    """

    robot: RobotParameters | str
    start: Any
    end: Any
    force_limit: Any
    w: float = 0.0
    final_time_guess: float = 1.0
    final_time_bounds: tuple[float, float] = (0.05, 10.0)
    friction: str = "tanh"
    friction_width: float = DEFAULT_FRICTION_WIDTH
    configuration: int = 0
    elements: int = 50
    points: int = 3
    scheme: str = "radau"
    max_iter: int = 3000
    tol: float = 1e-8
    name: str = "point_to_point"
    parameters: RobotParameters = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.parameters = load_parameters(self.robot)
        for key in ("start", "end", "force_limit"):
            arr = np.asarray(getattr(self, key), dtype=float)
            if arr.shape != (3,) or not np.all(np.isfinite(arr)):
                raise InputError(f"{key}: expected three finite numbers, got {getattr(self, key)!r}")
            setattr(self, key, arr)
        if np.any(self.force_limit <= 0):
            raise InputError(f"force_limit: expected positive forces in N, got {self.force_limit.tolist()}")
        if not (np.isfinite(self.w) and self.w >= 0):
            raise InputError(f"w: expected a non-negative weight, got {self.w!r}")
        if np.linalg.norm(self.end - self.start) < 1e-9:
            raise InputError("start and end: the poses coincide, there is no motion to optimise")


def trapezoid_profile(start, end, duration: float, t, ramp: float = 1.0 / 3.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Straight line with a trapezoidal velocity profile.

    Parameters
    ----------
    start, end : array_like, shape (3,)
        End points [m].
    duration : float
        Duration [s].
    t : array_like, shape (K,)
        Times in ``[0, duration]`` [s].
    ramp : float, optional
        Fraction of the duration spent accelerating (and decelerating); default 1/3.

    Returns
    -------
    T, T_dot, T_ddot : numpy.ndarray, each shape (K, 3)
        Position [m], velocity [m/s] and acceleration [m/s^2].

    Raises
    ------
    InputError
        Non-positive duration or ``ramp`` outside (0, 0.5].
    """
    if not duration > 0:
        raise InputError(f"duration: expected a positive time in s, got {duration!r}")
    if not 0 < ramp <= 0.5:
        raise InputError(f"ramp: expected a fraction in (0, 0.5], got {ramp!r}")
    start = np.asarray(start, dtype=float)
    delta = np.asarray(end, dtype=float) - start
    t = np.clip(np.asarray(t, dtype=float).reshape(-1), 0.0, duration)
    ta = ramp * duration
    a = 1.0 / (ta * (duration - ta))  # peak path acceleration for unit length
    s = np.where(t < ta, 0.5 * a * t**2, np.where(t <= duration - ta, a * ta * (t - ta / 2), 1 - 0.5 * a * (duration - t) ** 2))
    sd = np.where(t < ta, a * t, np.where(t <= duration - ta, a * ta, a * (duration - t)))
    sdd = np.where(t < ta, a, np.where(t <= duration - ta, 0.0, -a))
    return start + np.outer(s, delta), np.outer(sd, delta), np.outer(sdd, delta)


def check_holding_forces(problem: PointToPoint, dynamics: GantryTau3Dynamics | None = None) -> None:
    """Check that the force limits can hold the robot at rest at both end poses.

    At rest friction is zero in every form, so the actuators must supply exactly
    ``J^T G`` (Dressler (2012), eq. 6.7 with ``T_dot = T_ddot = 0``); if that exceeds a
    limit, the rest-to-rest problem is infeasible whatever the solver does.

    Parameters
    ----------
    problem : PointToPoint
        The declaration.
    dynamics : GantryTau3Dynamics, optional
        The dynamics to use (default: built from the problem's parameter set).

    Raises
    ------
    InputError
        A holding force exceeds its limit; the message gives both.
    """
    dyn = dynamics or GantryTau3Dynamics(problem.parameters, friction=problem.friction, friction_width=problem.friction_width)
    for label, pose in (("start", problem.start), ("end", problem.end)):
        hold = dyn.gravity_forces(pose, problem.configuration)
        if np.any(np.abs(hold) > problem.force_limit):
            raise InputError(
                f"force_limit: {problem.force_limit.tolist()} N cannot hold the robot at rest at the {label} pose "
                f"{pose.tolist()}, which needs {np.round(hold, 2).tolist()} N (gravity, eq. 6.7)"
            )


def build_optimization(problem: PointToPoint) -> tuple[Optimization, Model]:
    """Declare the point-to-point problem as an :class:`Optimization` (not yet transcribed).

    Parameters
    ----------
    problem : PointToPoint
        The declaration.

    Returns
    -------
    optimization : gtmodel.modeling.Optimization
        Objective ``final_time + w * integral(sum tau^2)``, free final time, force bounds,
        rest-to-rest point constraints (position, velocity, acceleration), cart-travel
        and spherical-joint path constraints, trapezoid initial guess.
    model : gtmodel.modeling.Model
        The robot model (TCP states) it is declared on.

    Raises
    ------
    UnreachablePoseError
        ``start`` or ``end`` is outside the workspace (names which and why).
    InputError
        The force limits cannot hold the robot at rest at ``start`` or ``end``.

    Notes
    -----
    Path constraints (cart travel, joint angles) and force bounds hold at the collocation
    points, as in any direct collocation; between them the polynomials are not bounded.
    """
    p = problem.parameters
    model = gantry_tau_model(
        p, states="tcp", friction=problem.friction, friction_width=problem.friction_width, configuration=problem.configuration
    )
    kin = model.dynamics.kinematics
    for label, pose in (("start", problem.start), ("end", problem.end)):
        try:
            kin.require_in_workspace(pose, problem.configuration)
        except UnreachablePoseError as exc:
            raise UnreachablePoseError(f"{label}: {exc}") from None
    check_holding_forces(problem, model.dynamics)
    w = model.parameter("w", problem.w)
    T, T_dot, tau = model.variables("state")["T"], model.variables("state")["T_dot"], model.variables("input")["tau"]
    opt = Optimization(
        model,
        start_time=0.0,
        final_time=problem.final_time_guess,
        free_final_time=True,
        final_time_guess=problem.final_time_guess,
        final_time_bounds=problem.final_time_bounds,
    )
    opt.set_objective(mayer=opt.final_time, lagrange=w * ca.sumsqr(tau))
    opt.set_bounds(tau, -problem.force_limit, problem.force_limit)
    # the force at the start time is the first element's polynomial extrapolated to it:
    # bound it too, so that the sampled forces stay within the limits everywhere
    opt.add_point_constraint(tau, at="start", lb=-problem.force_limit, ub=problem.force_limit, name="tau(start)")
    T_ddot = model.der(T_dot)
    for at, pose in (("start", problem.start), ("final", problem.end)):
        opt.add_point_constraint(T - pose, at=at, lb=0.0, ub=0.0, name=f"T({at})")
        opt.add_point_constraint(T_dot, at=at, lb=0.0, ub=0.0, name=f"T_dot({at})")
        opt.add_point_constraint(T_ddot, at=at, lb=0.0, ub=0.0, name=f"T_ddot({at})")
    # cart travel and spherical-joint limits along the motion
    q = model.outputs["q"]
    travel = p.limits.cart_travel
    opt.add_path_constraint(q, lb=travel[:, 0], ub=travel[:, 1], name="cart_travel")
    # spherical-joint limit |cos(link, guideway)| >= cos(limit); the sign of the cosine is
    # fixed by the IK configuration (+ for root sign -1), so the constraint is smooth
    signs = -configuration_signs(problem.configuration)
    cos = link_cosines_expression(T, q, kin.As, kin.v)
    cos_lim = float(np.cos(p.limits.joint_angle_max))
    opt.add_path_constraint(ca.DM(signs) * cos, lb=cos_lim, ub=1.0, name="joint_angle")

    tf0 = problem.final_time_guess
    dyn = model.dynamics

    def guess(t):
        Tg, Tdg, Tddg = trapezoid_profile(problem.start, problem.end, tf0, np.atleast_1d(t))
        return Tg, Tdg, Tddg

    opt.set_initial_guess(T, lambda t: guess(t)[0].ravel())
    opt.set_initial_guess(T_dot, lambda t: guess(t)[1].ravel())
    opt.set_initial_guess(
        tau,
        lambda t: np.clip(
            dyn.inverse_dynamics(*(g.ravel() for g in guess(t)), problem.configuration), -problem.force_limit, problem.force_limit
        ),
    )
    return opt, model


@dataclass
class PointToPointSolution:
    """Solution of a point-to-point problem.

    Parameters
    ----------
    problem : PointToPoint
        The declaration.
    result : gtmodel.modeling.OptimizationResult
        The optimisation result (status, iterations, trajectories, ...).
    energy : float
        ``sum_i integral tau_i^2 dt`` [N^2 s], exact for the collocation polynomials.
    """

    problem: PointToPoint
    result: OptimizationResult
    energy: float

    @property
    def success(self) -> bool:
        """True only for an optimal solution."""
        return self.result.success

    def trajectory(self, dt: float = SAMPLE_TIME) -> dict[str, np.ndarray]:
        """The solution resampled on a uniform grid (controller sample time by default).

        Parameters
        ----------
        dt : float, optional
            Sample time [s]; default 0.004 s.

        Returns
        -------
        dict of str to numpy.ndarray
            Columns :data:`TRAJECTORY_COLUMNS` then ``xd, yd, zd`` (TCP velocity [m/s]),
            each shape (K,); the last sample is the final time.

        Notes
        -----
        States (and the cart motion computed from them) are the collocation polynomials.
        Forces are interpolated linearly between the collocation points (and the start
        time): a polynomial through bang-bang values overshoots, while linear
        interpolation never leaves the limits that hold at the points. The price: replayed
        open-loop through the model, the linear forces drift about 6 mm from the path of
        the L1 problem over 0.68 s (the polynomial: 0.7 mm, but up to 28 % over the limit);
        a position loop is expected to absorb it.

        Raises
        ------
        InputError
            Non-positive ``dt``.
        """
        if not dt > 0:
            raise InputError(f"dt: expected a positive sample time in s, got {dt!r}")
        tf = self.result.final_time
        t = np.arange(0.0, tf, dt)
        t = np.append(t, tf) if tf - t[-1] > 1e-12 else t
        s = self.result.sample(t)
        T = np.asarray(s["states"]["T"]).reshape(-1, 3)
        T_dot = np.asarray(s["states"]["T_dot"]).reshape(-1, 3)
        mesh_tau = np.asarray(self.result.inputs["tau"]).reshape(-1, 3)
        tau = np.column_stack([np.interp(t, self.result.t, mesh_tau[:, k]) for k in range(3)])
        q = np.asarray(s["outputs"]["q"]).reshape(-1, 3)
        q_dot = np.asarray(s["outputs"]["q_dot"]).reshape(-1, 3)
        cols = {"t": t}
        for k, c in enumerate("xyz"):
            cols[c] = T[:, k]
        for name, arr in (("q", q), ("qd", q_dot), ("tau", tau)):
            for k in range(3):
                cols[f"{name}{k + 1}"] = arr[:, k]
        for k, c in enumerate("xyz"):
            cols[f"{c}d"] = T_dot[:, k]
        return cols

    def write_csv(self, path: str | Path, dt: float = SAMPLE_TIME) -> Path:
        """Write :meth:`trajectory` as CSV with a header line.

        Parameters
        ----------
        path : str or pathlib.Path
            Output file.
        dt : float, optional
            Sample time [s].

        Returns
        -------
        pathlib.Path
            The written file.
        """
        cols = self.trajectory(dt)
        path = Path(path)
        data = np.column_stack(list(cols.values()))
        np.savetxt(path, data, delimiter=",", header=",".join(cols), comments="", fmt="%.10g")
        return path


def _energy(result: OptimizationResult) -> float:
    """Exact integral of sum tau^2 over the collocation polynomials (Gauss-Legendre)."""
    c = result.collocation
    if c is None:
        return float("nan")
    nodes, weights = np.polynomial.legendre.leggauss(c.points + 1)
    x = (nodes + 1) / 2
    basis = lagrange_basis(c.tau_root[1:], x)  # (n, d)
    h = (c.tf - c.t0) / c.elements
    total = 0.0
    for k in range(c.elements):
        u = basis @ c.uc[k]  # (n, nu)
        total += h * np.sum(weights / 2 * np.sum(u**2, axis=1))
    return float(total)


def solve_point_to_point(problem: PointToPoint, verbose: bool = False) -> PointToPointSolution:
    """Transcribe by collocation and solve a point-to-point problem with IPOPT.

    Parameters
    ----------
    problem : PointToPoint
        The declaration.
    verbose : bool, optional
        Show IPOPT's iteration log.

    Returns
    -------
    PointToPointSolution
        Always returned; ``solution.result.status`` says whether it is optimal.

    Raises
    ------
    UnreachablePoseError
        ``start`` or ``end`` outside the workspace.
    """
    opt, _ = build_optimization(problem)
    tr = CollocationTranscription(
        opt,
        elements=problem.elements,
        points=problem.points,
        scheme=problem.scheme,
        verbose=verbose,
        solver_options={"max_iter": problem.max_iter, "tol": problem.tol},
    )
    result = tr.solve()
    _log.info("%s: %s after %d iterations, final time %.4f s", problem.name, result.status, result.iterations, result.final_time)
    return PointToPointSolution(problem=problem, result=result, energy=_energy(result))
