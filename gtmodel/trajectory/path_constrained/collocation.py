"""The projection method (Dressler (2012), ch. 3.5): :func:`solve_path_collocation` by direct collocation."""

from __future__ import annotations

import logging
from typing import Any, Sequence

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel.errors import InputError
from gtmodel.modeling import CollocationTranscription, Model, Optimization
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.parameters import RobotParameters
from gtmodel.trajectory.path import Path
from gtmodel.trajectory.path_constrained.coefficients import _cached_rows_function, _MapCache
from gtmodel.trajectory.path_constrained.constraints import PathConstraints
from gtmodel.trajectory.path_constrained.convex import PathConstrainedProblem
from gtmodel.trajectory.path_constrained.solution import PathSolution, _failed
from gtmodel.trajectory.point_to_point import trapezoid_profile

__all__ = ["solve_path_collocation"]

_log = logging.getLogger("gtmodel")


def solve_path_collocation(
    path: Path,
    robot: GantryTau3Dynamics | RobotParameters | str,
    force_limit: np.typing.ArrayLike,
    w: float = 0.0,
    configuration: int | Sequence[int] = 0,
    friction: str = "exact",
    viscous_friction: bool = True,
    elements: int = 50,
    points: int = 3,
    scheme: str = "radau",
    final_time_guess: float = 1.0,
    final_time_bounds: tuple[float, float] = (0.05, 10.0),
    max_iter: int = 3000,
    tol: float = 1e-8,
    verbose: bool = False,
) -> PathSolution:
    """Path-constrained optimal motion by the projection method, solved by collocation.

    Dressler (2012), ch. 3.5 ("path constrained" row of Table 3.1): states ``s`` and
    ``s_dot`` (``0 <= s <= 1``, ``s_dot >= 0``), input ``s_ddot``, the forces ``tau`` of the
    inverse dynamics along the path bounded by ``force_limit``, free final time, rest at
    both ends, objective ``final_time + w sum_i integral tau_i^2 dt``. Declared with
    :class:`gtmodel.modeling.Model` and :class:`gtmodel.modeling.Optimization`, transcribed
    by :class:`gtmodel.modeling.CollocationTranscription` and solved with IPOPT; the initial
    guess is a trapezoidal velocity profile over ``final_time_guess``.

    Parameters
    ----------
    path : Path
        The TCP path; without corners (a single phase cannot stop at a corner).
    robot : GantryTau3Dynamics or RobotParameters or str
        The robot.
    force_limit : array_like, shape (3,)
        ``|tau_i| <= force_limit_i`` [N].
    w : float, optional
        Energy weight [1/(N^2)]; default 0 (minimum time).
    configuration : int or sequence of int, optional
        IK configuration.
    friction : {"exact", "tanh"}, optional
        ``"exact"`` (default): Coulomb friction ``f_c sign(q'(s))``, as the convex method;
        ``"tanh"``: the model's smooth ``tanh(q_dot / 0.01 m/s)`` (as the free-path problem).
    viscous_friction : bool, optional
        Include viscous friction (default True; only with ``friction="exact"``).
    elements, points, scheme : int, int, str, optional
        Collocation mesh (default 50 elements, 3 Radau points).
    final_time_guess : float, optional
        Initial guess of the duration [s].
    final_time_bounds : tuple of float, optional
        Bounds of the duration [s].
    max_iter : int, optional
        IPOPT iteration limit.
    tol : float, optional
        IPOPT tolerance.
    verbose : bool, optional
        Show IPOPT's log.

    Returns
    -------
    PathSolution
        ``method="collocation"``; ``s``, ``s_dot``, ``s_ddot`` and ``t`` on the collocation
        mesh; ``details["result"]`` is the :class:`gtmodel.modeling.OptimizationResult`.

    Raises
    ------
    InputError
        Invalid limits, weight, friction form, or a path with corners.
    UnreachablePoseError
        The path leaves the workspace.
    """
    if not isinstance(path, Path):
        raise InputError(f"path: expected a gtmodel.trajectory.path.Path, got {type(path).__name__}")
    if path.corners.size:
        raise InputError(f"path: the collocation method needs a path without corners (rest at s = {path.corners.tolist()}); use the convex method")
    if friction not in ("exact", "tanh"):
        raise InputError(f"friction: expected 'exact' or 'tanh', got {friction!r}")
    if not (isinstance(w, (int, float)) and np.isfinite(w) and w >= 0):
        raise InputError(f"w: expected a non-negative weight, got {w!r}")
    constraints = PathConstraints(force_limit=force_limit)
    problem = PathConstrainedProblem(path, constraints, robot, configuration, viscous_friction)
    dyn = problem.dynamics
    rows_f = _cached_rows_function(robot, dyn, ("force_limit",), problem.viscous_friction)
    model = Model(f"path_{dyn.parameters.name}")
    s = model.state("s", 1, lb=0.0, ub=1.0)
    sd = model.state("s_dot", 1, lb=0.0)
    u = model.input("s_ddot", 1)
    model.equation(model.der(s), sd)
    model.equation(model.der(sd), u)
    T, dT, ddT = path.casadi_expression(s)
    sg = ca.DM(problem.signs)
    if friction == "exact":
        m, c, d, g = rows_f(T, dT, ddT, sg)[:4]
        tau = m * u + c * sd**2 + d * sd + g
    else:
        smooth = GantryTau3Dynamics(dyn.parameters, friction="tanh", asymmetric=dyn.asymmetric, gravity=dyn.gravity)
        tau = smooth.inverse_dynamics_function(T, dT * sd, ddT * sd**2 + dT * u, sg)[0]
    tau = model.output("tau", tau)
    wp = model.parameter("w", float(w))
    opt = Optimization(model, final_time=final_time_guess, free_final_time=True, final_time_guess=final_time_guess, final_time_bounds=final_time_bounds)
    opt.set_objective(mayer=opt.final_time, lagrange=wp * ca.sumsqr(tau))
    F = constraints.force_limit
    opt.add_path_constraint(tau, lb=-F, ub=F, name="tau")  # at the start too (the transcription imposes it there)
    opt.add_point_constraint(ca.vertcat(s, sd), at="start", lb=0.0, ub=0.0, name="rest(start)")
    opt.add_point_constraint(ca.vertcat(s - 1.0, sd), at="final", lb=0.0, ub=0.0, name="rest(final)")

    def guess(t: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return trapezoid_profile(np.zeros(3), np.array([1.0, 0.0, 0.0]), final_time_guess, np.atleast_1d(t))

    opt.set_initial_guess(s, lambda t: guess(t)[0][:, 0])
    opt.set_initial_guess(sd, lambda t: guess(t)[1][:, 0])
    opt.set_initial_guess(u, lambda t: guess(t)[2][:, 0])
    tr = CollocationTranscription(opt, elements=elements, points=points, scheme=scheme, verbose=verbose, solver_options={"max_iter": max_iter, "tol": tol})
    res = tr.solve()
    mesh_s = np.asarray(res.states["s"], dtype=float).reshape(-1)
    mesh_sd = np.asarray(res.states["s_dot"], dtype=float).reshape(-1)
    mesh_u = np.asarray(res.inputs["s_ddot"], dtype=float).reshape(-1)
    if res.status not in ("optimal", "acceptable"):
        return _failed(res.status, f"IPOPT: {res.message}", path, mesh_s, "collocation", res.solve_time, res.iterations, details={"result": res})

    def sampler(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        smp = res.sample(t)
        ss = np.clip(np.asarray(smp["states"]["s"], dtype=float).reshape(-1), 0.0, 1.0)
        v = np.maximum(np.asarray(smp["states"]["s_dot"], dtype=float).reshape(-1), 0.0)
        return ss, v, np.asarray(smp["inputs"]["s_ddot"], dtype=float).reshape(-1)

    colloc = res.collocation
    breaks = colloc.t0 + (colloc.tf - colloc.t0) * np.arange(colloc.elements + 1) / colloc.elements
    if friction == "tanh":
        smooth_tau = _MapCache(ca.Function("tau", [s, sd, u], [tau]))

        def evaluator(ss: np.ndarray, v: np.ndarray, acc: np.ndarray) -> dict[str, np.ndarray]:
            out = problem._motion(ss, v, acc)
            out["tau"] = smooth_tau(ss.size, ss[None, :], v[None, :], acc[None, :])[0].T
            return out
    else:
        evaluator = problem._motion
    _log.info("path collocation: %s after %d iterations, final time %.5f s", res.status, res.iterations, res.final_time)
    return PathSolution(
        status=res.status,
        message=f"IPOPT: {res.message}",
        final_time=float(res.final_time),
        s=mesh_s,
        s_dot=mesh_sd,
        s_ddot=mesh_u,
        t=np.asarray(res.t, dtype=float),
        solve_time=res.solve_time,
        iterations=res.iterations,
        method="collocation",
        path=path,
        max_constraint_violation=res.max_constraint_violation,
        sampler=sampler,
        evaluator=evaluator,
        breaks=breaks,
        details={"result": res, "transcription": tr},
    )
