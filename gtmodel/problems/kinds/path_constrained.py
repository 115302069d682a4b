"""Kind ``path_constrained``: time-optimal (or energy-weighted) motion along a given TCP path.

Dressler (2012), ch. 3.5, Table 3.1 "path constrained" rows: the TCP is restricted to a
path (a line, a polyline or a spline through via points), the states reduce to the path
coordinate ``s`` and its rate. Two methods (:data:`PATH_METHODS`): ``"convex"``, the convex
reformulation of Verscheure et al. (2009) solved to the exact optimum of the gridded
problem (:func:`~gtmodel.trajectory.solve_path_convex`), and ``"collocation"``, the
thesis' projection solved by collocation (:func:`~gtmodel.trajectory.solve_path_collocation`).
The field reference is ``docs/problem_files.md``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

import numpy as np

from gtmodel.errors import InputError, UnreachablePoseError
from gtmodel._docstrings import fill_doc
from gtmodel.problems.base import KIND_DOCS, ProblemFile, ProblemKind, Written
from gtmodel.problems.kinds.motion_common import MOTION_EXTRA_EMPTY_FIELDS, force_statistics, trajectory_columns
from gtmodel.problems.kinds.schemas.path_constrained import MAX_GRID_POINTS, MAX_VIA_POINTS, PathConstrainedFile
from gtmodel.problems.references import robot_parameters
from gtmodel.report.trajectory import OVERLAY_FILES, plot_forces, plot_overlay, plot_path_profile, plot_tcp_path
from gtmodel.trajectory import (
    PathConstraints,
    PathSolution,
    Polyline,
    SplinePath,
    StraightLine,
)
from gtmodel.trajectory.export import TRAJECTORY_UNITS, write_c_header
from gtmodel.trajectory.path_constrained.declared import PATH_METHODS, PathConstrainedDeclaration
from gtmodel.modeling.ocp.methods import Collocation, SolverSettings

__all__ = [
    "PATH_METHODS",
    "MAX_GRID_POINTS",
    "MAX_VIA_POINTS",
    "PathConstrainedFile",
    "PathConstrainedDeclaration",
    "PathConstrainedKind",
    "path_trajectory_columns",
]

def path_trajectory_columns(solution: PathSolution) -> dict[str, np.ndarray]:
    """The 4 ms table of a path-constrained solution, with the columns of the free-path CSV.

    Parameters
    ----------
    solution : gtmodel.trajectory.PathSolution
        A solved problem.

    Returns
    -------
    dict of str to numpy.ndarray
        ``t, x, y, z, q1..q3, qd1..qd3, tau1..tau3, xd, yd, zd, s, s_dot, s_ddot``, each (K,).

    Raises
    ------
    SolverError
        The solution has no motion (not solved).
    """
    tr = solution.trajectory()
    cols: dict[str, np.ndarray] = {"t": tr["t"]}
    for k, c in enumerate("xyz"):
        cols[c] = tr["T"][:, k]
    for name, key in (("q", "q"), ("qd", "q_dot"), ("tau", "tau")):
        for k in range(3):
            cols[f"{name}{k + 1}"] = tr[key][:, k]
    for k, c in enumerate("xyz"):
        cols[f"{c}d"] = tr["T_dot"][:, k]
    for key in ("s", "s_dot", "s_ddot"):
        cols[key] = tr[key]
    return cols


class PathConstrainedKind(ProblemKind):
    """Motion along a given TCP path (:func:`~gtmodel.trajectory.solve_path_convex`, :func:`~gtmodel.trajectory.solve_path_collocation`)."""

    name = "path_constrained"
    schema = PathConstrainedFile
    title = "time-optimal motion along a given TCP path (Dressler (2012), ch. 3.5; Verscheure et al. (2009))"
    file_descriptions = {
        "trajectory.csv": "the trajectory sampled every 4 ms: t [s], TCP x, y, z [m], actuators q [m], qd [m/s], forces tau [N], TCP velocity [m/s]",
        "trajectory.h": "the same samples as a C header, the feedforward table of the generated loop",
        "tcp_path.png": "the TCP path in space along the given path",
        "forces.png": "actuator forces against time with their limits",
        "profile.png": "the path speed profile: s_dot against the path parameter s",
    }
    columns = trajectory_columns()
    extra_empty_fields = MOTION_EXTRA_EMPTY_FIELDS

    @fill_doc(**KIND_DOCS)
    def load(self, doc: PathConstrainedFile, file: ProblemFile, name: str) -> PathConstrainedDeclaration:
        """Build the path, the limits and the solver settings (see :meth:`ProblemKind.load`).

        Parameters
        ----------
        {load_args}

        Returns
        -------
        PathConstrainedDeclaration

        Raises
        ------
        ProblemError
            Via points inconsistent with the shape, coinciding consecutive points, no
            limit, a limit or weight the method does not support, a path outside the
            workspace (naming the path coordinate ``s``).
        """
        params = robot_parameters(file, "robot.parameters", doc.robot.parameters)
        configuration = doc.robot.configuration
        shape, via = doc.path.shape, doc.path.via
        if shape == "line" and via:
            raise file.fail("path.via", 'no via points for shape = "line" (use "polyline" or "spline")', via)
        if shape != "line" and not via:
            raise file.fail("path.via", f"at least one via point for shape = {shape!r}", via)
        method = doc.method
        if method.name == "convex" and method.w != 0.0:
            raise file.fail("method.w", 'w = 0 for method "convex" (time-optimal); use method "collocation" for an energy weight', method.w)
        lo, hi = method.final_time_bounds
        if not lo < hi:
            raise file.fail("method.final_time_bounds", "[lo, hi] with 0 < lo < hi", [lo, hi])
        if method.name == "collocation" and not lo <= method.final_time_guess <= hi:
            raise file.fail("method.final_time_guess", f"a time within method.final_time_bounds {[lo, hi]}", method.final_time_guess)
        lim = doc.limits
        given = [key for key, value in lim if value is not None]
        if not given:
            raise file.fail("limits", "at least one limit (force, cart_velocity, cart_acceleration, tcp_velocity, tcp_speed, tcp_acceleration)")
        if method.name == "collocation":
            if lim.force is None:
                raise file.fail("limits.force", 'force limits for method "collocation"')
            other = [key for key in given if key != "force"]
            if other:
                raise file.fail(f"limits.{other[0]}", 'only force limits with method "collocation" (use method "convex" for the others)', getattr(lim, other[0]))
        try:
            cons = PathConstraints(
                force_limit=lim.force,
                cart_velocity_limit=lim.cart_velocity,
                cart_acceleration_limit=lim.cart_acceleration,
                tcp_velocity_limit=lim.tcp_velocity,
                tcp_speed_limit=lim.tcp_speed,
                tcp_acceleration_limit=lim.tcp_acceleration,
            )
        except InputError as exc:
            raise file.wrap("limits", exc) from None
        start, end = np.array(doc.motion.start), np.array(doc.motion.end)
        points = [start, *(np.array(p) for p in via), end]
        names = ["motion.start", *(f"path.via[{k}]" for k in range(len(via))), "motion.end"]
        for k in range(len(points) - 1):
            if np.linalg.norm(points[k + 1] - points[k]) < 1e-9:
                raise file.fail(names[k + 1], f"a point different from {names[k]}", points[k + 1].tolist())
        try:
            if shape == "line":
                path = StraightLine(start, end, robot=params, configuration=configuration)
            elif shape == "polyline":
                path = Polyline(points, robot=params, configuration=configuration)
            else:
                path = SplinePath(points, robot=params, configuration=configuration)
        except UnreachablePoseError as exc:
            raise file.wrap("path", exc) from None
        except InputError as exc:
            raise file.wrap("path", exc) from None
        col, sol = doc.collocation, doc.solver
        return PathConstrainedDeclaration(
            path=path,
            robot=params,
            constraints=cons,
            method=method.name,
            grid=method.grid,
            w=method.w,
            configuration=configuration,
            viscous_friction=doc.robot.viscous_friction,
            collocation=Collocation(col.elements, col.points, col.scheme, col.eliminate_algebraics),
            final_time_guess=method.final_time_guess,
            final_time_bounds=(float(lo), float(hi)),
            solver=SolverSettings(max_iter=sol.max_iter, tol=sol.tol),
        )

    @fill_doc(**KIND_DOCS)
    def write(self, declaration: PathConstrainedDeclaration, solution: PathSolution, out: Path, plots: bool, name: str) -> Written:
        """Summary fields; ``trajectory.csv``, ``trajectory.h`` and plots of a solution.

        Nothing but the summary fields is produced unless the solve is optimal or
        acceptable.

        Parameters
        ----------
        declaration : PathConstrainedDeclaration
            The declaration.
        solution : PathSolution
            Its solution.
        {write_args}

        Returns
        -------
        Written
            Status, final time, energy, iterations, solve time, method, grid and force figures.
        """
        d = declaration
        written = Written({
            "status": solution.status,
            "message": solution.message,
            "final_time_s": solution.final_time if solution.success else None,
            "energy": solution.energy if solution.success else None,
            "units": dict(TRAJECTORY_UNITS),
            "energy_units": "N^2 s (sum_i integral tau_i^2 dt)",
            "iterations": solution.iterations,
            "solve_time_s": solution.solve_time,
            "objective": solution.final_time if solution.success else None,
            "max_constraint_violation": None,
            "method": solution.method,
            "grid_points": int(np.size(solution.s)) if solution.s is not None else None,
            "w": d.w,
            "robot": d.robot.name,
        })
        if solution.status not in ("optimal", "acceptable"):
            return written
        cols = path_trajectory_columns(solution)
        force_limit = d.constraints.force_limit
        if force_limit is not None:
            written.fields["force_limit_N"] = np.asarray(force_limit).tolist()
            written.fields.update(force_statistics(cols, force_limit))
        written.fields["sample_time_s"] = float(cols["t"][1] - cols["t"][0]) if cols["t"].size > 1 else None
        data = np.column_stack(list(cols.values()))
        np.savetxt(out / "trajectory.csv", data, delimiter=",", header=",".join(cols), comments="", fmt="%.10g")
        write_c_header(cols, out / "trajectory.h", name=name)
        written.files += ["trajectory.csv", "trajectory.h"]
        if plots:
            plot_tcp_path(cols, d.path.start, d.path.end, out / "tcp_path.png", title=name)
            if force_limit is not None:
                plot_forces(cols, force_limit, out / "forces.png", title=name)
                written.files.append("forces.png")
            plot_path_profile(solution, out / "profile.png", title=name)
            written.files += ["tcp_path.png", "profile.png"]
        return written

    def overlay(self, solutions: Mapping[str, PathSolution], out: Path) -> list[str]:
        """TCP-path and force overlays of a study's cases (the columns of :func:`path_trajectory_columns`).

        Parameters
        ----------
        solutions : Mapping[str, PathSolution]
            Label -> solved solution.
        out : pathlib.Path
            The study folder.

        Returns
        -------
        list of str
            ``overlay_forces.png``, ``overlay_tcp.png`` (none without solutions).
        """
        trajs = {label: path_trajectory_columns(sol) for label, sol in solutions.items()}
        if not trajs:
            return []
        plot_overlay(trajs, out)
        return list(OVERLAY_FILES)
