"""Time- and energy-optimal point-to-point motion of a Gantry-Tau (Dressler (2012), ch. 3.5).

The problem of Table 3.1 ("direct" rows): the TCP moves from rest at ``start`` to rest at
``end`` (zero velocity and acceleration at both ends), the actuator forces are bounded,
and the cost is::

    C = final_time + w * sum_i integral tau_i^2 dt

with the final time free. It is declared on the rigid-body model of
:func:`gtmodel.robots.gantry_tau_model` (TCP states, smooth friction) as an
:class:`gtmodel.modeling.Optimization` and transcribed by direct collocation
(:mod:`gtmodel.modeling.ocp.collocation`). The initial guess is the straight line with a trapezoidal
velocity profile (the thesis' choice) and the forces of the inverse dynamics along it."""

from __future__ import annotations

import functools
import logging
from dataclasses import InitVar, dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._docstrings import SHARED_DOCS, fill_doc
from gtmodel._tables import read_table
from gtmodel._timing import merge_phases, timed
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError, UnreachablePoseError
from gtmodel.modeling import CollocationTranscription, Model, Optimization, OptimizationResult
from gtmodel.modeling.ocp.coarse_start import solve_from_coarse
from gtmodel.modeling.ocp.expressions import parse_constraint, parse_objective
from gtmodel.modeling.ocp.refinement import solve_refined
from gtmodel.modeling.ocp.result import lagrange_basis
from gtmodel.modeling.ocp.verification import refinement_passes
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.friction import DEFAULT_FRICTION_WIDTH
from gtmodel.robots.kinematic_expressions import (
    cart_acceleration_expression,
    configuration_signs,
    link_cosines_expression,
)
from gtmodel.robots.model import gantry_tau_model
from gtmodel.robots.parameters import RobotParameters, load_parameters
from gtmodel.status import Status
from gtmodel.trajectory.model_ocp import COARSE_START_ELEMENTS, COARSE_START_MIN_ELEMENTS
from gtmodel.trajectory.rest_to_rest import bang_bang_duration, check_holding_forces, trapezoid_profile
from gtmodel.modeling.ocp.methods import Collocation, Refinement, SolverSettings
from gtmodel.trajectory.settings import objective_scaling

__all__ = [
    "PointToPoint",
    "PointToPointSolution",
    "DEFAULT_OBJECTIVE",
    "problem_names",
    "bang_bang_duration",
    "trapezoid_profile",
    "build_optimization",
    "check_holding_forces",
    "solve_point_to_point",
    "SAMPLE_TIME",
    "SOLVER_OPTIONS",
    "TRAJECTORY_COLUMNS",
    "GUESS_MAX_ROWS",
    "GUESS_MAX_BYTES",
    "START_POSE",
    "END_POSE",
]

_log = logging.getLogger("gtmodel")

#: Controller sample time [s] of the resampled trajectory (Dressler (2012), ch. 3.2).
SAMPLE_TIME = LOOP_PERIOD_S
#: IPOPT options of :func:`solve_point_to_point` (besides ``max_iter`` and ``tol``). The
#: cost (seconds, of order one, gradient on the final time only) is small next to the
#: barrier terms of the ~1300 force bounds and path constraints of the default mesh, so
#: at the first barrier parameters IPOPT stretches the motion to keep the forces off their
#: limits (the L1 problem: from 1 s to 1.5 s, then back). Scaled by 1e4, the barrier
#: problems stay close to the bang-bang optimum; IPOPT's tolerances apply to the scaled
#: problem, so the optimum is resolved at least as tightly. With the forces in units of
#: their limits (:func:`solve_point_to_point`) this halves the iterations of the L1
#: problem and six variants of it (median 165 -> 70; the L1 problem 119 -> 49).
#: ``perturb_always_cd`` is neutral on the median but gives the L1 problem 49 instead of 64.
#: The objective scaling is applied only with a free final time, and for a cost in seconds:
#: :func:`~gtmodel.trajectory.settings.objective_scaling` divides it by the cost's size at the guess in units of the guess's
#: duration (an energy weight makes the cost thousands of times larger).
SOLVER_OPTIONS = {"obj_scaling_factor": 1e4, "perturb_always_cd": "yes"}
#: Model parameters holding the boundary poses [m] (NLP parameters of the transcription).
START_POSE, END_POSE = "T_start_pose", "T_end_pose"
#: Leading columns of the trajectory table, in this order.
#: Most rows and largest size [bytes] of a trajectory file given as an initial guess (a motion
#: of seconds at any spacing; a larger file is refused before it is parsed).
GUESS_MAX_ROWS = 100_000
GUESS_MAX_BYTES = 20_000_000
TRAJECTORY_COLUMNS = ("t", "x", "y", "z", "q1", "q2", "q3", "qd1", "qd2", "qd3", "tau1", "tau2", "tau3")


#: The objective of Dressler (2012), ch. 3.5 (Table 3.1) in the problem language.
DEFAULT_OBJECTIVE = "final_time + w * integral(tau1^2 + tau2^2 + tau3^2)"


@dataclass
class PointToPoint:
    """Declaration of a point-to-point optimal motion (free path between two poses).

    Parameters
    ----------
    robot : RobotParameters or str
        Parameter set or its name/path.
    start, end : array_like, shape (3,)
        TCP positions at rest [m].
    force_limit : array_like, shape (3,)
        Symmetric bound on each actuator force, ``|tau_i| <= force_limit_i`` [N].
    w : float
        Value of the named parameter ``w`` (energy weight of the default objective
        ``final_time + w * sum integral tau^2 dt``) [s / (N^2 s)], unless
        ``named_parameters`` sets it.
    final_time_guess : float
        Initial guess of the duration [s]; the duration itself if the final time is fixed.
    final_time_bounds : tuple of float
        Bounds of the free duration [s].
    friction, friction_width : str, float
        Friction form used in the optimisation and its width [m/s] (smooth by default).
    configuration : int
        IK configuration of the robot (see :func:`gtmodel.robots.configuration_signs`).
    name : str
        Name of the problem (used in reports).
    objective : str
        Objective in the problem language (:mod:`gtmodel.modeling.ocp.expressions`), over the
        names of :func:`problem_names`.
    constraints : sequence of str
        Extra path or point constraints in the problem language.
    named_parameters : Mapping[str, float]
        Values of the named parameters used in ``objective`` and ``constraints``.
    free_final_time : bool
        Minimise over the duration (True) or fix it to ``final_time_guess``.
    cart_velocity_limit, cart_acceleration_limit : array_like, shape (3,), optional
        ``|q_dot_i|`` [m/s] and ``|q_ddot_i|`` [m/s^2] bounds along the motion.
    tcp_velocity_limit : float, optional
        ``||T_dot||`` bound [m/s].
    joint_angle_limit : float, optional
        Spherical-joint limit [rad] (link angle to its guideway); default the robot's.
    guess : str or pathlib.Path or PointToPointSolution
        ``"trapezoid"`` (straight line, trapezoidal velocity: the thesis' choice),
        ``"bang_bang"`` (the same line with the duration estimated from the force limits),
        a trajectory CSV written by :meth:`PointToPointSolution.write_csv`, or a previous
        solution.
    origin : str
        Where the declaration comes from (file name), used in error messages.
    start_time : float
        Start time ``t0`` [s]; the final time and its bounds are absolute times.
    method : Collocation
        The transcription (JModelica's defaults: 50 elements, 3 Radau points).
    solver : SolverSettings
        The NLP solver, its iteration limit and tolerance, compiled C derivatives.
    refinement : Refinement
        Verification tolerance and adaptive mesh refinement
        (:func:`gtmodel.modeling.ocp.refinement.solve_refined`): off by default (the thesis'
        50 elements, verified all the same); on, the mesh is split where the states deviate
        from their simulation until the verification passes.
    elements, points, scheme : int, int, str, optional
        Shortcuts replacing the fields of ``method``.
    max_iter, tol, jit : int, float, bool, optional
        Shortcuts replacing the fields of ``solver``.

    Raises
    ------
    InputError
        Malformed numbers, or force limits that cannot hold the robot at rest at ``start``
        or ``end`` (each naming the argument).
    UnreachablePoseError
        ``start`` or ``end`` outside the workspace (naming which).

    Notes
    -----
    The physical invariants (poses in the workspace, force limits above the holding
    forces) are checked here, once; transcribing and solving trust them.
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
    name: str = "point_to_point"
    objective: str = DEFAULT_OBJECTIVE
    constraints: tuple[str, ...] = ()
    named_parameters: dict[str, float] = field(default_factory=dict)
    free_final_time: bool = True
    cart_velocity_limit: Any = None
    cart_acceleration_limit: Any = None
    tcp_velocity_limit: float | None = None
    joint_angle_limit: float | None = None
    guess: Any = "trapezoid"
    origin: str = "<python>"
    start_time: float = 0.0
    method: Collocation = field(default_factory=Collocation)
    solver: SolverSettings = field(default_factory=SolverSettings)
    refinement: Refinement = field(default_factory=Refinement)
    elements: InitVar[int | None] = None
    points: InitVar[int | None] = None
    scheme: InitVar[str | None] = None
    max_iter: InitVar[int | None] = None
    tol: InitVar[float | None] = None
    jit: InitVar[bool | None] = None
    parameters: RobotParameters = field(init=False, repr=False)

    def __post_init__(self, elements: int | None, points: int | None, scheme: str | None, max_iter: int | None,
                      tol: float | None, jit: bool | None) -> None:
        method = {k: v for k, v in (("elements", elements), ("points", points), ("scheme", scheme)) if v is not None}
        solver = {k: v for k, v in (("max_iter", max_iter), ("tol", tol), ("jit", jit)) if v is not None}
        if method:
            self.method = replace(self.method, **method)
        if solver:
            self.solver = replace(self.solver, **solver)
        self.parameters = load_parameters(self.robot)
        for key in ("start", "end", "force_limit"):
            arr = np.asarray(getattr(self, key), dtype=float)
            if arr.shape != (3,) or not np.all(np.isfinite(arr)):
                raise InputError(f"{key}: expected three finite numbers, got {getattr(self, key)!r}")
            setattr(self, key, arr)
        if np.any(self.force_limit <= 0):
            raise InputError(f"force_limit: expected positive forces in N, got {self.force_limit.tolist()}")
        for key in ("cart_velocity_limit", "cart_acceleration_limit"):
            val = getattr(self, key)
            if val is not None:
                arr = np.asarray(val, dtype=float)
                if arr.shape != (3,) or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
                    raise InputError(f"{key}: expected three positive finite numbers, got {val!r}")
                setattr(self, key, arr)
        for key in ("tcp_velocity_limit", "joint_angle_limit"):
            val = getattr(self, key)
            if val is not None and not (np.isfinite(val) and val > 0):
                raise InputError(f"{key}: expected a positive number, got {val!r}")
        if not (np.isfinite(self.w) and self.w >= 0):
            raise InputError(f"w: expected a non-negative weight, got {self.w!r}")
        named = {k: float(v) for k, v in dict(self.named_parameters).items()}
        if "w" not in named and (self.objective == DEFAULT_OBJECTIVE or self.w != 0.0):
            named["w"] = float(self.w)
        self.named_parameters = named
        self.w = named.get("w", 0.0)
        self.constraints = tuple(self.constraints)
        if np.linalg.norm(self.end - self.start) < 1e-9:
            raise InputError("start and end: the poses coincide, there is no motion to optimise")
        if not self.free_final_time and not self.final_time_guess > 0:
            raise InputError(f"final_time_guess: a fixed duration must be positive, got {self.final_time_guess!r}")
        dyn = GantryTau3Dynamics(self.parameters, friction=self.friction, friction_width=self.friction_width)
        for label, pose in (("start", self.start), ("end", self.end)):
            try:
                dyn.kinematics.require_in_workspace(pose, self.configuration)
            except UnreachablePoseError as exc:
                raise UnreachablePoseError(f"{label}: {exc}") from None
        check_holding_forces(self, dyn)

    @fill_doc(**SHARED_DOCS)
    def solve(self, *, verbose: bool = False, previous: PointToPointSolution | None = None, warm_start: bool = False) -> PointToPointSolution:
        """Transcribe and solve (:func:`solve_point_to_point`).

        Parameters
        ----------
        {solve_args}

        Returns
        -------
        PointToPointSolution
        """
        return solve_point_to_point(self, verbose=verbose, previous=previous, warm_start=warm_start)


#: Read access under the former flat names (``problem.elements`` is ``problem.method.elements``, ...).
for _name, _part in (("elements", "method"), ("points", "method"), ("scheme", "method"), ("max_iter", "solver"), ("tol", "solver"), ("jit", "solver")):
    setattr(PointToPoint, _name, property(lambda self, _n=_name, _p=_part: getattr(getattr(self, _p), _n), doc=f"``{_part}.{_name}``"))


def problem_names(model: Model, optimization: Optimization, named_parameters: dict[str, ca.SX]) -> dict[str, ca.SX]:
    """The names the problem language knows for the Gantry-Tau TCP-state model.

    Parameters
    ----------
    model : gtmodel.modeling.Model
        From :func:`gtmodel.robots.gantry_tau_model` with ``states="tcp"``.
    optimization : gtmodel.modeling.Optimization
        The problem (for ``final_time``).
    named_parameters : dict of str to casadi.SX
        Declared named parameters (symbols of the model).

    Returns
    -------
    dict of str to casadi.SX
        ``x, y, z`` (TCP [m]), ``xd, yd, zd`` [m/s], ``xdd, ydd, zdd`` [m/s^2],
        ``q1..q3`` (carts [m]), ``qd1..qd3`` [m/s], ``qdd1..qdd3`` [m/s^2],
        ``tau1..tau3`` (cart forces [N]), ``power`` (sum tau_i qd_i [W]), ``time``,
        ``start_time``, ``final_time`` and the named parameters.
    """
    st, out = model.variables("state"), model.outputs
    T, T_dot = st["T"], st["T_dot"]
    tau = model.variables("input")["tau"]
    T_ddot = model.der(T_dot)
    kin = model.dynamics.kinematics
    q, q_dot = out["q"], out["q_dot"]
    q_ddot = cart_acceleration_expression(T, T_dot, T_ddot, q, q_dot, kin.As, kin.v)
    names: dict[str, ca.SX] = {}
    for k, c in enumerate("xyz"):
        names[c], names[f"{c}d"], names[f"{c}dd"] = T[k], T_dot[k], T_ddot[k]
    for k in range(3):
        names[f"q{k + 1}"], names[f"qd{k + 1}"], names[f"qdd{k + 1}"] = q[k], q_dot[k], q_ddot[k]
        names[f"tau{k + 1}"] = tau[k]
    names["power"] = out["power"]
    names["time"] = model.time
    names["final_time"] = optimization.final_time
    names["start_time"] = ca.SX(optimization.start_time)
    names.update(named_parameters)
    return names


def build_optimization(problem: PointToPoint) -> tuple[Optimization, Model]:
    """Declare the point-to-point problem as an :class:`Optimization` (not yet transcribed).

    Parameters
    ----------
    problem : PointToPoint
        The declaration.

    Returns
    -------
    optimization : gtmodel.modeling.Optimization
        The objective and extra constraints parsed from the problem language, free or fixed
        final time, force bounds, rest-to-rest point constraints (position, velocity,
        acceleration), cart-travel, spherical-joint and optional velocity/acceleration
        path constraints, and the initial guess.
    model : gtmodel.modeling.Model
        The robot model (TCP states) it is declared on.

    Raises
    ------
    InputError
        The guess file is unusable.
    ProblemError
        An objective or constraint expression is invalid (names the origin, the field and
        the offending token).

    Notes
    -----
    Path constraints (cart travel, joint angles, limits) and force bounds hold at the
    collocation points, as in any direct collocation; between them the polynomials are not
    bounded.
    """
    p = problem.parameters
    model = gantry_tau_model(
        p, states="tcp", friction=problem.friction, friction_width=problem.friction_width, configuration=problem.configuration
    )
    kin = model.dynamics.kinematics
    psyms = {k: model.parameter(k, v) for k, v in problem.named_parameters.items()}
    T, T_dot, tau = model.variables("state")["T"], model.variables("state")["T_dot"], model.variables("input")["tau"]
    dyn = model.dynamics
    if isinstance(problem.guess, str) and problem.guess == "bang_bang":
        tf0 = float(np.clip(problem.start_time + bang_bang_duration(problem, dyn), *problem.final_time_bounds))
    else:
        tf0 = problem.final_time_guess
    opt = Optimization(
        model,
        start_time=problem.start_time,
        final_time=tf0,
        free_final_time=problem.free_final_time,
        final_time_guess=tf0 if problem.free_final_time else None,
        final_time_bounds=problem.final_time_bounds if problem.free_final_time else None,
    )
    names = problem_names(model, opt, psyms)
    obj = parse_objective(problem.objective, names, origin=problem.origin, key="optimization.objective", static=set(psyms))
    opt.set_objective(mayer=obj.mayer, lagrange=obj.lagrange)
    for k, text in enumerate(problem.constraints):
        c = parse_constraint(text, names, origin=problem.origin, key=f"optimization.constraints[{k}]", static=set(psyms))
        if c.at is None:
            opt.add_path_constraint(c.expr, lb=c.lb, ub=c.ub, name=text)
        else:
            opt.add_point_constraint(c.expr, at=c.at, lb=c.lb, ub=c.ub, name=text)
    # the force at the start time is the first element's polynomial extrapolated to it: the
    # collocation transcription bounds it too, so the sampled forces stay within the limits
    opt.set_bounds(tau, -problem.force_limit, problem.force_limit)
    T_ddot = model.der(T_dot)
    # poses as NLP parameters: re-solves for new poses reuse the NLP (resolve_point_to_point)
    poses = (("start", model.parameter(START_POSE, problem.start)), ("final", model.parameter(END_POSE, problem.end)))
    for at, pose in poses:
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
    limit = p.limits.joint_angle_max if problem.joint_angle_limit is None else problem.joint_angle_limit
    opt.add_path_constraint(ca.DM(signs) * cos, lb=float(np.cos(limit)), ub=1.0, name="joint_angle")
    if problem.cart_velocity_limit is not None:
        lim = problem.cart_velocity_limit
        opt.add_path_constraint(model.outputs["q_dot"], lb=-lim, ub=lim, name="cart_velocity")
    if problem.cart_acceleration_limit is not None:
        lim = problem.cart_acceleration_limit
        q_ddot = ca.vertcat(*(names[f"qdd{k + 1}"] for k in range(3)))
        opt.add_path_constraint(q_ddot, lb=-lim, ub=lim, name="cart_acceleration")
    if problem.tcp_velocity_limit is not None:
        opt.add_path_constraint(ca.sumsqr(T_dot), lb=0.0, ub=problem.tcp_velocity_limit**2, name="tcp_velocity")
    _set_guess(problem, opt, T, T_dot, tau, dyn, tf0)
    return opt, model


def _set_guess(problem: PointToPoint, opt: Optimization, T, T_dot, tau, dyn: GantryTau3Dynamics, tf0: float) -> None:
    """Initial guess: trapezoid / bang-bang line, a trajectory CSV, or a previous solution."""
    guess = problem.guess
    if isinstance(guess, PointToPointSolution):
        r = guess.result
        opt.set_initial_guess(T, lambda t: np.asarray(r.sample(np.atleast_1d(t))["states"]["T"]).ravel())
        opt.set_initial_guess(T_dot, lambda t: np.asarray(r.sample(np.atleast_1d(t))["states"]["T_dot"]).ravel())
        mesh_tau = np.asarray(r.inputs["tau"]).reshape(-1, 3)
        opt.set_initial_guess(tau, lambda t: np.array([np.interp(t, r.t, mesh_tau[:, k]) for k in range(3)]).ravel())
        if problem.free_final_time:
            opt.final_time_guess = float(np.clip(r.final_time, *problem.final_time_bounds))
        return
    if isinstance(guess, (str, Path)) and str(guess) not in ("trapezoid", "bang_bang"):
        data = _read_guess_csv(Path(guess))
        tg = data["t"]
        Tg = np.column_stack([data[c] for c in "xyz"])
        Tdg = np.column_stack([data[f"{c}d"] for c in "xyz"])
        taug = np.column_stack([data[f"tau{k}"] for k in (1, 2, 3)])

        def interp(arr):
            return lambda t: np.array([np.interp(t, tg, arr[:, k]) for k in range(3)]).ravel()

        opt.set_initial_guess(T, interp(Tg))
        opt.set_initial_guess(T_dot, interp(Tdg))
        opt.set_initial_guess(tau, interp(taug))
        if problem.free_final_time:
            opt.final_time_guess = float(np.clip(tg[-1], *problem.final_time_bounds))
        return

    def line(t):
        return trapezoid_profile(problem.start, problem.end, tf0 - problem.start_time, np.atleast_1d(t) - problem.start_time)

    opt.set_initial_guess(T, lambda t: line(t)[0].ravel())
    opt.set_initial_guess(T_dot, lambda t: line(t)[1].ravel())
    opt.set_initial_guess(
        tau,
        lambda t: np.clip(
            dyn.inverse_dynamics(*(g.ravel() for g in line(t)), problem.configuration), -problem.force_limit, problem.force_limit
        ),
    )


def _read_guess_csv(path: Path) -> dict[str, np.ndarray]:
    """Read a trajectory CSV (as written by :meth:`PointToPointSolution.write_csv`) for a guess."""
    need = ["t", "x", "y", "z", "xd", "yd", "zd", "tau1", "tau2", "tau3"]
    try:
        table = read_table(path, "trajectory file", max_rows=GUESS_MAX_ROWS, max_bytes=GUESS_MAX_BYTES)
        table.check_columns(need)
    except InputError as exc:
        raise InputError(f"guess: {exc}") from None
    out = {c: table.column(c) for c in need}
    if out["t"].size < 2 or np.any(np.diff(out["t"]) <= 0):
        raise InputError(f"guess: trajectory file {path} needs >= 2 rows with increasing t")
    return out


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
    transcription : gtmodel.modeling.CollocationTranscription, optional
        The NLP it was solved with (reused by sweeps).
    """

    problem: PointToPoint
    result: OptimizationResult
    energy: float
    transcription: Any = field(default=None, repr=False, compare=False)

    @property
    def success(self) -> bool:
        """True only for an optimal solution."""
        return self.result.success

    @property
    def status(self) -> Status:
        """The status of :attr:`result` (:class:`gtmodel.status.SolverResult` protocol)."""
        return self.result.status

    @property
    def message(self) -> str:
        """The solver's message of :attr:`result`."""
        return self.result.message

    def trajectory(self, dt: float = SAMPLE_TIME) -> dict[str, np.ndarray]:
        """The solution resampled on a uniform grid (controller sample time by default).

        Parameters
        ----------
        dt : float, optional
            Sample time [s]; default :data:`SAMPLE_TIME` (the loop period).

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
        t = np.arange(float(self.result.t[0]), tf, dt)
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
    u = np.einsum("nd,kdu->knu", basis, np.asarray(c.uc, dtype=float))  # (elements, n, nu) at the Gauss nodes
    return float((c.tf - c.t0) / c.elements * np.sum(weights / 2 * np.sum(u**2, axis=2)))


def _scale_objective(tr: CollocationTranscription, problem: PointToPoint, options: dict[str, Any]) -> float | None:
    """Set the objective scaling of this problem's weights (:func:`~gtmodel.trajectory.settings.objective_scaling`) on the transcription's solver; return it (None: unscaled)."""
    if "obj_scaling_factor" not in options:  # a fixed final time: no scaling
        return None
    duration = tr.optimization.final_time_guess - tr.optimization.start_time
    scaling = objective_scaling(tr.objective_at_guess(problem.named_parameters), duration, options["obj_scaling_factor"])
    if scaling != tr.options[tr.plugin].get("obj_scaling_factor"):
        tr.set_solver_options({"obj_scaling_factor": scaling})
        _log.debug("%s: objective scaling %.4g", problem.name, scaling)
    return scaling


def _coarse_start(opt: Optimization, problem: PointToPoint, common: dict[str, Any], options: dict[str, Any]) -> OptimizationResult:
    """The problem on :data:`~gtmodel.trajectory.model_ocp.COARSE_START_ELEMENTS` elements (unverified): a fine mesh's start."""
    coarse = CollocationTranscription(opt, elements=COARSE_START_ELEMENTS, points=problem.method.points,
                                      scheme=problem.method.scheme, verify=False, **common)
    _scale_objective(coarse, problem, options)
    return coarse.solve(parameters=problem.named_parameters)


def _structure(problem: PointToPoint) -> tuple:
    """What must be equal for two declarations to share one transcription."""
    skip = {"named_parameters", "w", "name", "parameters", "guess", "origin"}
    key = lambda v: tuple(np.ravel(v)) if isinstance(v, np.ndarray) else v.name if isinstance(v, RobotParameters) else v  # noqa: E731
    return tuple((f.name, key(getattr(problem, f.name))) for f in fields(problem) if f.name not in skip) + (
        ("parameter_names", tuple(sorted(problem.named_parameters))),)


def solve_point_to_point(
    problem: PointToPoint,
    verbose: bool = False,
    previous: PointToPointSolution | None = None,
    warm_start: bool = False,
) -> PointToPointSolution:
    """Transcribe by collocation and solve a point-to-point problem with IPOPT.

    Parameters
    ----------
    problem : PointToPoint
        The declaration.
    verbose : bool, optional
        Show IPOPT's iteration log.
    previous : PointToPointSolution, optional
        A solution of a problem that differs only in its named parameters (a sweep): its
        NLP is reused instead of rebuilt.
    warm_start : bool, optional
        Start from ``previous``'s solution instead of the declared guess.

    Returns
    -------
    PointToPointSolution
        Always returned; ``solution.result.status`` says whether it is optimal.

    Raises
    ------
    ProblemError
        Invalid objective or constraint expression.

    Notes
    -----
    The NLP works with the forces in units of their limits (``nominal`` of
    :class:`~gtmodel.modeling.CollocationTranscription`) and with the IPOPT options
    :data:`SOLVER_OPTIONS`; neither changes the problem, only the path IPOPT takes.
    """
    options = {"max_iter": problem.solver.max_iter, "tol": problem.solver.tol, **SOLVER_OPTIONS}
    if not problem.free_final_time:  # the objective scaling is tuned for a cost in seconds (free final time); a
        options.pop("obj_scaling_factor")  # fixed-time energy cost (~1e5 N^2 s) needs none
    ref = problem.refinement
    if previous is not None and previous.transcription is not None and _structure(previous.problem) == _structure(problem):
        tr = previous.transcription
        guess = previous.result if warm_start else None
        _scale_objective(tr, problem, options)
        result = tr.solve(parameters=problem.named_parameters, initial_guess=guess)
    else:
        phases: dict[str, dict[str, float]] = {}
        with timed(phases, "build"):  # the robot's model and the problem's expressions (the NLP's build: the transcription's)
            opt, _ = build_optimization(problem)
        guess = previous.result if (warm_start and previous is not None) else None
        common = {"verbose": verbose, "solver_options": options, "nominal": {"tau": problem.force_limit},
                  "compile": problem.solver.jit, "solver": problem.solver.name, "eliminate_algebraics": problem.method.eliminate_algebraics}
        tr = CollocationTranscription(opt, elements=problem.method.elements, points=problem.method.points,
                                      scheme=problem.method.scheme, verify=ref.verification, **common)
        scaling = _scale_objective(tr, problem, options)
        refined = functools.partial(solve_refined, opt, elements=problem.method.elements, points=problem.method.points,
                                    scheme=problem.method.scheme, max_elements=None if ref.max_elements is None else max(ref.max_elements, problem.method.elements),
                                    max_passes=ref.max_passes, max_cpu_s=ref.max_cpu_s, parameters=problem.named_parameters,
                                    objective_tolerance=ref.objective_tolerance, verification=ref.verification,
                                    regularization=ref.regularization)
        if ref.refine:
            tr = None  # each pass is a new mesh (with the first mesh's objective scaling): no NLP kept for a sweep to reuse
            if scaling is not None:
                common["solver_options"] = {**options, "obj_scaling_factor": scaling}
            with timed(phases, "refinement"):  # every pass: its build, guess, solve and verification
                result = refined(initial_guess=guess, **common)
        else:
            # a fine mesh from a coarse solve, by either solver (IPOPT near it: coarse_start.WARM_MU)
            fine = problem.method.elements >= COARSE_START_MIN_ELEMENTS and guess is None
            first = refinement_passes(solve_from_coarse) if ref.on_failure and ref.verify else solve_from_coarse  # checks quiet
            result = first(tr, (lambda: _coarse_start(opt, problem, common, options)) if fine else None, initial_guess=guess, parameters=problem.named_parameters)
            merge_phases(phases, result.timing)
            if ref.on_failure and ref.verify and result.status == Status.CHECK_FAILED:  # refined from this solution within the budget
                _log.info("%s: refining the mesh from this first solution, whose simulation is not yet within the tolerance", problem.name)
                tr = None  # the result's mesh is no longer this transcription's
                with timed(phases, "refinement"):
                    result = refined(start=result, **common)
        result.timing = phases  # as a model's OCP: build, guess, solve, verification, refinement (CPU and wall)
    _log.info("%s: %s after %d iterations, final time %.4f s", problem.name, result.status, result.iterations, result.final_time)
    return PointToPointSolution(problem=problem, result=result, energy=_energy(result), transcription=tr)
