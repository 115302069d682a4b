"""The convex reformulation (Verscheure et al. 2009): :class:`PathConstrainedProblem` and :func:`solve_path_convex`.

Solved by reachability (:mod:`.reachability`), polished or cross-checked by IPOPT on the
same gridded problem (:meth:`PathConstrainedProblem.solve_nlp`).
"""

from __future__ import annotations

import logging
import math
import time as _time
from typing import Any, Sequence

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel.errors import InputError, SingularConfigurationError, SolverError
from gtmodel.modeling.ocp.result import normalize_ipopt_status
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.kinematic_expressions import configuration_signs
from gtmodel.robots.kinematics import SINGULARITY_TOLERANCE
from gtmodel.robots.parameters import RobotParameters
from gtmodel.status import Status
from gtmodel.trajectory.path import Path
from gtmodel.trajectory.path_constrained.coefficients import _cached_dynamics, _cached_rows_function, _MapCache
from gtmodel.trajectory.path_constrained.constraints import PathConstraints
from gtmodel.trajectory.path_constrained.gridding import GriddedPathProblem, _check_grid
from gtmodel.trajectory.path_constrained.reachability import _reachability
from gtmodel.trajectory.path_constrained.solution import PathSolution, _failed, _profile_sampler

__all__ = ["PathConstrainedProblem", "solve_path_convex"]

_log = logging.getLogger("gtmodel")
_INF = math.inf


# =============================================================================== the problem
class PathConstrainedProblem:
    """Time-optimal rest-to-rest motion along a path, Verscheure et al. (2009) / TOPP-RA.

    Built once per path, limits and robot; :meth:`solve` and :meth:`solve_nlp` take the
    grid. The CasADi Function that evaluates the constraint coefficients from path samples
    is cached per robot and set of limit kinds (path data and limit values are inputs).

    Parameters
    ----------
    path : Path
        The TCP path.
    constraints : PathConstraints
        The limits.
    robot : GantryTau3Dynamics or RobotParameters or str, optional
        The robot (needed for force and cart limits; its kinematics and workspace limits
        are then checked along the path). A dynamics object with a smooth friction form is
        replaced by the same model with the exact Coulomb sign (see the module docstring).
    configuration : int or sequence of int, optional
        IK configuration (see :func:`gtmodel.robots.kinematic_expressions.configuration_signs`).
    viscous_friction : bool, optional
        Include the viscous friction ``f_v q_dot`` of the model (default True); False drops
        it (Coulomb friction and the rigid-body terms remain), e.g. to compare with solvers
        that cannot represent it. Forces sampled from the solutions use the same model.
    constrain_end : bool, optional
        Also impose the rows with ``s_ddot`` (forces, accelerations) at the last grid point,
        on the last interval's ``s_ddot`` with ``s_dot = 0`` (default True: the force on
        arrival is checked). False gives TOPP-RA's collocation scheme, which leaves them out.

    Raises
    ------
    InputError
        Not a :class:`Path`, not :class:`PathConstraints`, an actuator limit without a
        robot, or an invalid configuration.
    UnreachablePoseError
        The path leaves the robot's workspace (names the first ``s``).

    Notes
    -----
    At a corner of a polyline the arrival (with the incoming tangent) is not checked; only
    the departure is (right-continuous ``dT/ds``).
    """

    def __init__(
        self,
        path: Path,
        constraints: PathConstraints,
        robot: GantryTau3Dynamics | RobotParameters | str | None = None,
        configuration: int | Sequence[int] = 0,
        viscous_friction: bool = True,
        constrain_end: bool = True,
    ) -> None:
        if not isinstance(path, Path):
            raise InputError(f"path: expected a gtmodel.trajectory.path.Path, got {type(path).__name__}")
        if not isinstance(constraints, PathConstraints):
            raise InputError(f"constraints: expected PathConstraints, got {type(constraints).__name__}")
        if constraints.needs_robot and robot is None:
            raise InputError("robot: force and cart limits need a robot (parameter set name, RobotParameters or GantryTau3Dynamics)")
        self.path = path
        self.constraints = constraints
        self.configuration = configuration
        self.signs = configuration_signs(configuration)
        self.viscous_friction = bool(viscous_friction)
        self.constrain_end = bool(constrain_end)
        self.robot = robot
        self.dynamics: GantryTau3Dynamics | None = None
        if robot is not None:
            self.dynamics = _cached_dynamics(robot)
            path.check_workspace(self.dynamics.kinematics, configuration)
        self._rows = _MapCache(_cached_rows_function(robot, self.dynamics, constraints.kinds, self.viscous_friction))
        self._kin_rows = None
        if self.dynamics is not None:
            self._kin_rows = _MapCache(_cached_rows_function(robot, self.dynamics, ("force_limit",), self.viscous_friction))
        self._nlp: dict[tuple[int, int, bool, str], Any] = {}

    # ------------------------------------------------------------------ evaluation
    def _evaluate(self, s: np.ndarray, f: _MapCache) -> dict[str, np.ndarray]:
        T, dT, ddT = self.path.evaluate(s)
        n = s.size
        m, c, d, g, q, dq, ddq, disc, cos = f.rows(n, T, dT, ddT, np.tile(self.signs, (n, 1)))
        out = {"T": T, "dT": dT, "ddT": ddT, "m": m, "c": c, "d": d, "g": g}
        if self.dynamics is not None:
            out.update(q=q, dq=dq, ddq=ddq, disc=disc, cos=cos)
        return out

    def _check_reach(self, s: np.ndarray, ev: dict[str, np.ndarray]) -> None:
        if self.dynamics is None:
            return
        lim = self.dynamics.parameters.limits
        q, cos = ev["q"], ev["cos"]
        ok = np.all(ev["disc"] >= 0, axis=1)
        ok &= np.all((q >= lim.cart_travel[:, 0]) & (q <= lim.cart_travel[:, 1]), axis=1)
        ok &= np.all(np.abs(cos) >= np.cos(lim.joint_angle_max), axis=1)
        if not np.all(ok):
            k = int(np.argmin(ok))
            self.path.check_workspace(self.dynamics.kinematics, self.configuration, s=[s[k]])
        cmin = np.min(np.abs(cos), axis=1)
        if np.any(cmin < SINGULARITY_TOLERANCE):
            k = int(np.argmin(cmin))
            raise SingularConfigurationError(f"the path is singular at s = {s[k]:.6g}: a link is perpendicular to its guideway")

    def gridded(self, grid: int | np.typing.ArrayLike = 100) -> GriddedPathProblem:
        """Evaluate the constraint rows on a grid.

        Parameters
        ----------
        grid : int or array_like, shape (N + 1,)
            Number of uniformly spaced grid points (at least 2; the path's corners are
            added), or the grid itself: strictly increasing from 0 to 1, containing the
            corners.

        Returns
        -------
        GriddedPathProblem
            The rows at the grid points.

        Raises
        ------
        InputError
            Fewer than 2 grid points, a grid that is not strictly increasing, does not run
            from 0 to 1, or misses a corner.
        UnreachablePoseError
            A grid point is outside the workspace (names ``s``).
        SingularConfigurationError
            A grid point is singular.
        """
        t0 = _time.perf_counter()
        s = _check_grid(self.path, grid)
        ev = self._evaluate(s, self._rows)
        self._check_reach(s, ev)
        lo, hi, names = self.constraints.bounds()
        rest = np.zeros(s.size, dtype=bool)
        rest[[0, -1]] = True
        for corner in self.path.corners:
            rest[int(np.argmin(np.abs(s - corner)))] = True
        samples = {k: ev[k] for k in ("T", "dT", "ddT", "q", "dq", "ddq") if k in ev}
        return GriddedPathProblem(
            s=s, m=ev["m"], c=ev["c"], d=ev["d"], g=ev["g"], lo=lo, hi=hi, names=names, rest=rest, samples=samples,
            setup_time=_time.perf_counter() - t0, constrain_end=self.constrain_end,
        )

    def _motion(self, s: np.ndarray, sd: np.ndarray, sdd: np.ndarray) -> dict[str, np.ndarray]:
        """Kinematic and force samples along the motion (the model's inverse dynamics)."""
        if self._kin_rows is None:
            T, dT, ddT = self.path.evaluate(s)
            out = {}
        else:
            ev = self._evaluate(s, self._kin_rows)
            T, dT, ddT = ev["T"], ev["dT"], ev["ddT"]
            tau = ev["m"] * sdd[:, None] + ev["c"] * (sd**2)[:, None] + ev["d"] * sd[:, None] + ev["g"]
            out = {
                "q": ev["q"],
                "q_dot": ev["dq"] * sd[:, None],
                "q_ddot": ev["dq"] * sdd[:, None] + ev["ddq"] * (sd**2)[:, None],
                "tau": tau,
            }
        out = {"T": T, "T_dot": dT * sd[:, None], "T_ddot": ddT * (sd**2)[:, None] + dT * sdd[:, None], **out}
        return out

    def _solution(self, gp: GriddedPathProblem, b: np.ndarray, a: np.ndarray, status: str, message: str, solve_time: float, iterations: int, method: str, details: dict) -> PathSolution:
        b = np.maximum(b, 0.0)
        x = np.sqrt(b)
        with np.errstate(divide="ignore"):
            dt = 2.0 * np.diff(gp.s) / (x[:-1] + x[1:])
        if not np.all(np.isfinite(dt)):
            k = int(np.argmax(~np.isfinite(dt)))
            return _failed("infeasible", f"infeasible: s_dot is zero at both ends of interval {k} (s = {gp.s[k]:.6g} .. {gp.s[k + 1]:.6g}): the path cannot be traversed on this grid", self.path, gp.s, method, solve_time, iterations, gp.setup_time, details)
        tk = np.concatenate([[0.0], np.cumsum(dt)])
        details = {**details, "b": b, "a": a}
        return PathSolution(
            status=status,
            message=message,
            final_time=float(tk[-1]),
            s=gp.s.copy(),
            s_dot=x,
            s_ddot=np.append(a, a[-1]),
            t=tk,
            solve_time=solve_time,
            iterations=iterations,
            method=method,
            path=self.path,
            max_constraint_violation=gp.violation(b, a),
            setup_time=gp.setup_time,
            sampler=_profile_sampler(gp.s, x, a, tk),
            evaluator=self._motion,
            breaks=tk if self.dynamics is not None else None,
            details=details,
        )

    # ------------------------------------------------------------------ reachability
    def solve(self, grid: int | np.typing.ArrayLike | GriddedPathProblem = 100, polish: bool = True) -> PathSolution:
        """Solve the gridded problem by reachability analysis (TOPP-RA's two passes).

        The greedy forward pass is the optimum when every step is certified (see the module
        docstring): then the status is ``"optimal"`` and ``method`` ``"reachability"``.
        Where a step is limited by a constraint whose bound on the next ``s_dot`` falls as
        the current one rises (e.g. an axis acceleration limit near a point where that axis'
        tangent vanishes, ``|T''_j / T'_j| > 1 / (2 ds)``), the greedy profile is feasible
        but not proven optimal; it then starts IPOPT on the same gridded problem
        (:meth:`solve_nlp`), ``method`` ``"reachability+ipopt"``.

        Parameters
        ----------
        grid : int or array_like or GriddedPathProblem, optional
            Grid (see :meth:`gridded`) or an already evaluated problem; default 100 points.
        polish : bool, optional
            Run IPOPT from the greedy profile when its optimality is not certified (default
            True); if False, or if IPOPT does not improve it, the greedy profile is returned
            as ``"acceptable"``.

        Returns
        -------
        PathSolution
            Status ``"optimal"``; ``"infeasible"`` (the message names the grid point, ``s``
            and the constraints); ``"acceptable"`` when the profile is feasible but not
            proven optimal (uncertified steps without polish, or a non-convex
            viscous-friction set that split in two and whose part containing rest was kept;
            the message says where).

        Raises
        ------
        InputError
            Invalid grid.
        UnreachablePoseError
            A grid point is outside the workspace.
        SingularConfigurationError
            A grid point is singular.
        """
        gp = grid if isinstance(grid, GriddedPathProblem) else self.gridded(grid)
        t0 = _time.perf_counter()
        p, r, w, e, names, p_end, e_end = gp.one_sided()
        res = _reachability(gp.s, gp.rest, p, r, w, e, names, p_end, e_end)
        elapsed = _time.perf_counter() - t0
        if not res.ok:
            return _failed("infeasible", res.message, self.path, gp.s, "reachability", elapsed, 1, gp.setup_time, {"index": res.index})
        notes = []
        if res.splits:
            notes.append(
                f"at {res.splits} stage(s) a viscous-friction constraint admitted two separate ranges of s_dot and the "
                "range containing rest was kept"
            )
        if res.uncertified.size:
            ks = res.uncertified
            notes.append(
                f"the greedy step is not proven optimal at {ks.size} stage(s) (first: grid point {int(ks[0])}, "
                f"s = {gp.s[ks[0]]:.6g}): a constraint whose bound falls as s_dot rises limits it"
            )
        greedy = self._solution(gp, res.b, res.a, "optimal", "optimal: reachability (backward and forward pass)", elapsed, 1, "reachability", {})
        if not notes or greedy.status != "optimal":
            return greedy
        if polish and res.uncertified.size:
            nlp = self.solve_nlp(gp, initial_s_dot=greedy.s_dot)
            if nlp.status == "optimal" and nlp.final_time <= greedy.final_time * (1 + 1e-9):
                nlp.method = "reachability+ipopt"
                nlp.solve_time += elapsed
                nlp.message = f"optimal: reachability, then IPOPT from it because {'; '.join(notes)}; IPOPT ({nlp.message}) shortened the duration by {greedy.final_time - nlp.final_time:.3g} s"
                _log.info("path-constrained solve: %s", nlp.message)
                return nlp
            notes.append(f"the IPOPT polish did not improve it ({nlp.status})")
        greedy.status = Status.ACCEPTABLE
        greedy.message = "acceptable: feasible, but " + "; ".join(notes)
        _log.warning("path-constrained solve: %s", greedy.message)
        return greedy

    # ------------------------------------------------------------------ IPOPT cross-check
    def _nlp_solver(self, N: int, R: int, end: bool, options: dict) -> tuple[ca.Function, Any]:
        key = (N, R, end, repr(sorted(options["ipopt"].items())))
        if key in self._nlp:
            return self._nlp[key]
        X = ca.SX.sym("s_dot", N + 1)
        A = ca.SX.sym("a", N)
        Dl = ca.SX.sym("delta", N)
        Mc, Cc, Dc, Gc = (ca.SX.sym(n, N + 1, R) for n in ("m", "c", "d", "g"))
        Aext = ca.vertcat(A, A[-1] if end else 0)
        rows = []
        for j in range(R):
            rows.append(Mc[:, j] * Aext + Cc[:, j] * X**2 + Dc[:, j] * X + Gc[:, j])
        g = ca.vertcat(X[1:] ** 2 - X[:-1] ** 2 - 2 * Dl * A, *rows)
        f = ca.sum1(2 * Dl / (X[:-1] + X[1:]))
        pvec = ca.vertcat(Dl, ca.vec(Mc), ca.vec(Cc), ca.vec(Dc), ca.vec(Gc))
        solver = ca.nlpsol("path_nlp", "ipopt", {"x": ca.vertcat(X, A), "p": pvec, "f": f, "g": g}, options)
        self._nlp[key] = (solver, None)
        return self._nlp[key]

    def solve_nlp(
        self,
        grid: int | np.typing.ArrayLike | GriddedPathProblem = 100,
        tol: float = 1e-10,
        max_iter: int = 3000,
        verbose: bool = False,
        initial_s_dot: np.typing.ArrayLike | None = None,
    ) -> PathSolution:
        """Solve the same gridded problem with IPOPT (an independent cross-check of :meth:`solve`).

        Variables ``s_dot_k`` (N + 1) and ``a_k`` (N); constraints ``s_dot_{k+1}^2 -
        s_dot_k^2 = 2 a_k ds_k`` and the rows with ``b = s_dot^2`` (viscous friction
        exact); objective ``sum 2 ds_k / (s_dot_k + s_dot_{k+1})``. The initial guess is
        a small sine-shaped profile, independent of the reachability solution. The NLP is
        built once per grid size and options (path data and limits are its parameters and
        bounds).

        IPOPT runs without relaxing the bounds (``bound_relax_factor`` 0) and with the
        barrier parameter allowed down to ``1e-6 tol`` (adaptive): with IPOPT's defaults
        (bounds relaxed by 1e-8, ``mu_min`` 1e-11) its interior solution ended 0.003-0.3 ppm
        longer than the gridded optimum; with these and ``tol=1e-14`` it lands on it to
        below 1e-6 ppm on the velocity- and acceleration-limited line of
        ``benchmarks/bench_path_constrained.py --json`` (N = 100 to 10^4). With force
        limits IPOPT may stop at its acceptable level at 1e-14 (status ``acceptable``).

        Parameters
        ----------
        grid : int or array_like or GriddedPathProblem, optional
            Grid (see :meth:`gridded`); default 100 points.
        tol : float, optional
            IPOPT tolerance (also its constraint-violation tolerance).
        max_iter : int, optional
            IPOPT iteration limit.
        verbose : bool, optional
            Show IPOPT's log.
        initial_s_dot : array_like, shape (N + 1,), optional
            Initial guess of ``s_dot`` on the grid (default: the sine-shaped profile).

        Returns
        -------
        PathSolution
            With IPOPT's status mapped by :func:`gtmodel.modeling.ocp.result.normalize_ipopt_status`.

        Raises
        ------
        InputError
            Invalid grid or initial guess.
        SolverError
            IPOPT could not be built.
        """
        gp = grid if isinstance(grid, GriddedPathProblem) else self.gridded(grid)
        N, R = gp.N, gp.m.shape[1]
        x0 = None
        if initial_s_dot is not None:
            x0 = np.asarray(initial_s_dot, dtype=float).reshape(-1)
            if x0.shape != (N + 1,) or not np.all(np.isfinite(x0)):
                raise InputError(f"initial_s_dot: expected {N + 1} finite values, got shape {x0.shape}")
            x0 = np.maximum(x0, 0.0)
        options = {
            "ipopt": {"tol": tol, "max_iter": max_iter, "print_level": 5 if verbose else 0, "sb": "yes", "constr_viol_tol": tol,
                      "acceptable_tol": max(tol, 1e-8), "mu_min": 1e-6 * tol, "bound_relax_factor": 0.0, "mu_strategy": "adaptive"},
            "print_time": bool(verbose),
            "error_on_fail": False,
        }
        try:
            solver, _ = self._nlp_solver(N, R, gp.constrain_end, options)
        except RuntimeError as exc:
            raise SolverError(f"could not build the IPOPT solver: {exc}") from exc
        delta = np.diff(gp.s)
        pvec = np.concatenate([delta] + [np.asarray(X, dtype=float).ravel(order="F") for X in (gp.m, gp.c, gp.d, gp.g)])
        lo = np.tile(gp.lo, (N + 1, 1))
        hi = np.tile(gp.hi, (N + 1, 1))
        if not gp.constrain_end:
            lo[-1, gp.m[-1] != 0] = -_INF
            hi[-1, gp.m[-1] != 0] = _INF
        lbg = np.concatenate([np.zeros(N), lo.ravel(order="F")])
        ubg = np.concatenate([np.zeros(N), hi.ravel(order="F")])
        lbx = np.concatenate([np.zeros(N + 1), np.full(N, -_INF)])
        ubx = np.concatenate([np.where(gp.rest, 0.0, _INF), np.full(N, _INF)])
        if x0 is None:
            x0 = 0.05 * np.sqrt(np.sin(np.pi * gp.s))
            x0[gp.rest] = 0.0
        a0 = (x0[1:] ** 2 - x0[:-1] ** 2) / (2 * delta)
        t0 = _time.perf_counter()
        try:
            sol = solver(x0=np.concatenate([x0, a0]), p=pvec, lbg=lbg, ubg=ubg, lbx=lbx, ubx=ubx)
            error = None
        except RuntimeError as exc:
            error = str(exc)
        elapsed = _time.perf_counter() - t0
        stats = solver.stats()
        if error is not None:
            return _failed("error", error, self.path, gp.s, "ipopt", elapsed, 0, gp.setup_time)
        message = str(stats.get("return_status", "unknown"))
        status = normalize_ipopt_status(message)
        z = np.asarray(sol["x"], dtype=float).ravel()
        x, a = z[: N + 1], z[N + 1 :]
        if status not in ("optimal", "acceptable") or not np.all(np.isfinite(z)):
            return _failed(status if status != "optimal" else "error", f"IPOPT: {message}", self.path, gp.s, "ipopt", elapsed, int(stats.get("iter_count", 0)), gp.setup_time, {"stats": stats})
        return self._solution(gp, np.maximum(x, 0.0) ** 2, a, status, f"IPOPT: {message}", elapsed, int(stats.get("iter_count", 0)), "ipopt", {"stats": stats})


def solve_path_convex(
    path: Path,
    constraints: PathConstraints,
    robot: GantryTau3Dynamics | RobotParameters | str | None = None,
    grid: int | np.typing.ArrayLike = 100,
    configuration: int | Sequence[int] = 0,
    viscous_friction: bool = True,
    constrain_end: bool = True,
) -> PathSolution:
    """Time-optimal rest-to-rest motion along a path (Verscheure et al. (2009), TOPP-RA).

    Shorthand for ``PathConstrainedProblem(path, constraints, robot, configuration,
    viscous_friction, constrain_end).solve(grid)``; keep the problem object for sweeps.

    Parameters
    ----------
    path : Path
        The TCP path.
    constraints : PathConstraints
        The limits.
    robot : GantryTau3Dynamics or RobotParameters or str, optional
        The robot (needed for force and cart limits).
    grid : int or array_like, optional
        Number of grid points or the grid (see :meth:`PathConstrainedProblem.gridded`).
    configuration : int or sequence of int, optional
        IK configuration.
    viscous_friction : bool, optional
        Include viscous friction (default True).
    constrain_end : bool, optional
        Check the rows with ``s_ddot`` at the last grid point too (default True).

    Returns
    -------
    PathSolution
        The solution (see :meth:`PathConstrainedProblem.solve`).

    Raises
    ------
    InputError
        Invalid arguments.
    UnreachablePoseError
        The path leaves the workspace.
    """
    return PathConstrainedProblem(path, constraints, robot, configuration, viscous_friction, constrain_end).solve(grid)
