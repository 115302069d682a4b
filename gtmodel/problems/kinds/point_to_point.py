"""Kind ``point_to_point``: free-path time/energy-optimal motion between two poses.

Dressler (2012), ch. 3.5, Table 3.1 "direct" rows. The objective and extra constraints
are written in the problem language (:mod:`gtmodel.modeling.ocp.expressions`, documented in
``docs/problem_language.md``). The field reference is ``docs/problem_files.md``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError, ProblemError, UnreachablePoseError
from gtmodel.modeling.ocp.expressions import parse_constraint, parse_objective
from gtmodel._docstrings import fill_doc
from gtmodel.problems.results import verification_fields
from gtmodel.problems.base import KIND_DOCS, ProblemFile, ProblemKind, Written
from gtmodel.problems.kinds.motion_common import MOTION_EXTRA_EMPTY_FIELDS, force_statistics, trajectory_columns
from gtmodel.problems.kinds.schemas.point_to_point import PointToPointFile
from gtmodel.problems.references import named_parameters, robot_parameters
from gtmodel.report.trajectory import OVERLAY_FILES, plot_forces, plot_overlay, plot_tcp_path
from gtmodel.trajectory.point_to_point import PointToPoint, PointToPointSolution
from gtmodel.modeling.ocp.methods import Collocation, Refinement, SolverSettings
from gtmodel.trajectory.export import TRAJECTORY_UNITS, write_c_header

__all__ = ["PointToPointKind", "PointToPointFile", "point_to_point_summary"]


#: Names the point-to-point model defines (see :func:`gtmodel.trajectory.problem_names`).
MODEL_NAMES = (
    {c + s for c in "xyz" for s in ("", "d", "dd")}
    | {f"{n}{k}" for n in ("q", "qd", "qdd", "tau") for k in (1, 2, 3)}
    | {"power", "time", "start_time", "final_time"}
)


class PointToPointKind(ProblemKind):
    """Free-path time/energy-optimal motion (:class:`~gtmodel.trajectory.PointToPoint`)."""

    name = "point_to_point"
    schema = PointToPointFile
    title = "free-path time/energy-optimal motion between two poses (Dressler (2012), ch. 3.5)"
    file_descriptions = {
        "trajectory.csv": "the trajectory sampled every 4 ms: t [s], TCP x, y, z [m], actuators q [m], qd [m/s], forces tau [N], TCP velocity [m/s]",
        "trajectory.h": "the same samples as a C header, the feedforward table of the generated loop",
        "tcp_path.png": "the TCP path in space between the start and end poses",
        "forces.png": "actuator forces against time with their limits",
    }
    columns = trajectory_columns()
    extra_empty_fields = MOTION_EXTRA_EMPTY_FIELDS

    @fill_doc(**KIND_DOCS)
    def load(self, doc: PointToPointFile, file: ProblemFile, name: str) -> PointToPoint:
        """Build the :class:`~gtmodel.trajectory.PointToPoint` declaration (see :meth:`ProblemKind.load`).

        Parameters
        ----------
        {load_args}

        Returns
        -------
        PointToPoint

        Raises
        ------
        ProblemError
            A pose outside the workspace, inconsistent final-time settings, force limits
            that cannot hold the robot at rest, an invalid expression (each naming its
            field: the declaration's own checks are reported under :data:`ARGUMENT_FIELDS`).
        """
        params = robot_parameters(file, "robot.parameters", doc.robot.parameters)
        lim = doc.limits
        joint = None if lim.joint_angle_deg is None else float(np.deg2rad(lim.joint_angle_deg))
        named = named_parameters(file, doc.parameters, MODEL_NAMES)
        opt = doc.optimization
        t0 = opt.start_time
        ft, ftn = opt.final_time, "optimization.final_time"
        if ft.free:
            if ft.bounds is None:
                raise file.fail(f"{ftn}.bounds", "bounds [lo, hi] for a free final time (free = true)")
            bounds = np.array(ft.bounds)
            if not t0 < bounds[0] < bounds[1]:
                raise file.fail(f"{ftn}.bounds", f"[lo, hi] with start_time ({t0}) < lo < hi", bounds.tolist())
            tf_guess = ft.initial_guess if ft.initial_guess is not None else float(np.clip(1.0, *bounds))
            if not bounds[0] <= tf_guess <= bounds[1]:
                raise file.fail(f"{ftn}.initial_guess", f"a time within {ftn}.bounds {bounds.tolist()}", tf_guess)
            if ft.value is not None:
                raise file.fail(f"{ftn}.value", "no fixed value when free = true (use initial_guess)")
        else:
            if ft.value is None:
                raise file.fail(f"{ftn}.value", "the final time [s] when free = false")
            tf_guess = ft.value
            if not tf_guess > t0:
                raise file.fail(f"{ftn}.value", f"a final time after start_time ({t0})", tf_guess)
            bounds = np.array([tf_guess, tf_guess])
        ig = doc.initial_guess
        guess: Any = ig.method
        if ig.method == "file":
            if ig.file is None:
                raise file.fail("initial_guess.file", 'a trajectory CSV when method = "file"')
            guess = file.data_file("initial_guess.file", ig.file)
        elif ig.file is not None:
            raise file.fail("initial_guess.file", 'no file unless method = "file"')
        start, end = np.array(doc.motion.start), np.array(doc.motion.end)
        if np.linalg.norm(end - start) < 1e-9:
            raise file.fail("motion.end", "a pose different from motion.start", end.tolist())
        col, sol, tr = doc.collocation, doc.solver, doc.transcription
        try:
            decl = PointToPoint(
                robot=params,
                start=start,
                end=end,
                force_limit=np.array(lim.force),
                w=named.get("w", 0.0),
                final_time_guess=float(tf_guess),
                final_time_bounds=(float(bounds[0]), float(bounds[1])),
                friction=doc.robot.friction,
                friction_width=doc.robot.friction_width,
                configuration=doc.robot.configuration,
                name=name,
                objective=opt.objective,
                constraints=tuple(opt.constraints),
                named_parameters=named,
                free_final_time=ft.free,
                cart_velocity_limit=None if lim.cart_velocity is None else np.array(lim.cart_velocity),
                cart_acceleration_limit=None if lim.cart_acceleration is None else np.array(lim.cart_acceleration),
                tcp_velocity_limit=lim.tcp_velocity,
                joint_angle_limit=joint,
                guess=guess,
                origin=str(file.path),
                start_time=t0,
                method=Collocation(col.elements, col.points, col.scheme, col.eliminate_algebraics),
                solver=SolverSettings(sol.name, sol.max_iter, sol.tol, sol.jit),
                refinement=Refinement(tr.refine, tr.tolerance, tr.max_elements, tr.max_passes, on_failure=tr.refine_on_failure,
                                      max_cpu_s=tr.max_cpu_s, objective_tolerance=tr.objective_tolerance,
                                      regularization=tr.regularization),
            )
        except (InputError, UnreachablePoseError) as exc:
            raise _field_error(file, exc) from None
        _check_expressions(decl)
        return decl

    @fill_doc(**KIND_DOCS)
    def write(self, declaration: PointToPoint, solution: PointToPointSolution, out: Path, plots: bool, name: str) -> Written:
        """Summary fields; ``trajectory.csv``, ``trajectory.h`` and plots of a solution.

        Nothing but the summary fields is produced for a failed solve (its last iterate
        is not a trajectory).

        Parameters
        ----------
        declaration : PointToPoint
            The declaration.
        solution : PointToPointSolution
            Its solution.
        {write_args}

        Returns
        -------
        Written
        """
        written = Written(point_to_point_summary(declaration, solution))
        if solution.result.status in ("optimal", "acceptable", "check_failed"):
            traj = solution.trajectory()
            solution.write_csv(out / "trajectory.csv")
            write_c_header(traj, out / "trajectory.h", name=name)
            written.files += ["trajectory.csv", "trajectory.h"]
            if plots:
                plot_tcp_path(traj, declaration.start, declaration.end, out / "tcp_path.png", title=name)
                plot_forces(traj, declaration.force_limit, out / "forces.png", title=name)
                written.files += ["tcp_path.png", "forces.png"]
        return written

    def overlay(self, solutions: dict[str, Any], out: Path) -> list[str]:
        """TCP-path and force overlays of a study's cases.

        Parameters
        ----------
        solutions : dict
            Label -> solution.
        out : pathlib.Path
            The study folder.

        Returns
        -------
        list of str
        """
        trajs = {label: sol.trajectory() for label, sol in solutions.items()}
        if not trajs:
            return []
        plot_overlay(trajs, out)
        return list(OVERLAY_FILES)


#: The file field of each :class:`~gtmodel.trajectory.PointToPoint` argument its checks name.
ARGUMENT_FIELDS = {"start": "motion.start", "end": "motion.end", "force_limit": "limits.force", "w": "parameters.w"}


def _field_error(file: ProblemFile, exc: Exception) -> ProblemError:
    """The declaration's error (``"argument: message"``) under the file field of the argument."""
    arg, sep, rest = str(exc).partition(": ")
    if sep and arg in ARGUMENT_FIELDS:
        return ProblemError(f"{file.path}: field '{ARGUMENT_FIELDS[arg]}': {rest}")
    return ProblemError(f"{file.path}: {exc}")


def _check_expressions(decl: PointToPoint) -> None:
    """Parse the objective and constraints now, so that a bad expression is bad input."""
    names: dict[str, Any] = {n: ca.SX.sym(n) for n in MODEL_NAMES}
    names["start_time"] = ca.SX(decl.start_time)
    names.update({k: ca.SX.sym(k) for k in decl.named_parameters})
    parse_objective(decl.objective, names, origin=decl.origin, key="optimization.objective", static=set(decl.named_parameters))
    for k, text in enumerate(decl.constraints):
        parse_constraint(text, names, origin=decl.origin, key=f"optimization.constraints[{k}]", static=set(decl.named_parameters))


def point_to_point_summary(decl: PointToPoint, solution: PointToPointSolution) -> dict[str, Any]:
    """The ``summary.json`` fields of a solved point-to-point problem.

    Parameters
    ----------
    decl : PointToPoint
        The declaration.
    solution : PointToPointSolution
        Its solution.

    Returns
    -------
    dict
        Status, final time, energy, iterations, solve time, objective, constraint
        violation, the verification by simulation, force statistics and the problem's
        settings.
    """
    r = solution.result
    summary: dict[str, Any] = {
        "status": r.status,
        "message": r.message,
        "final_time_s": r.final_time,
        "energy": solution.energy,
        "units": dict(TRAJECTORY_UNITS),
        "energy_units": "N^2 s (sum_i integral tau_i^2 dt)",
        "iterations": r.iterations,
        "solve_time_s": r.solve_time,
        "objective": r.objective,
        "max_constraint_violation": r.max_constraint_violation,
        "last_iterate": r.last_iterate,
        "objective_expression": decl.objective,
        "constraints": list(decl.constraints),
        "parameters": dict(decl.named_parameters),
        "w": decl.named_parameters.get("w"),
        "free_final_time": decl.free_final_time,
        "force_limit_N": decl.force_limit.tolist(),
        "collocation": {"elements": decl.method.elements, "points": decl.method.points, "scheme": decl.method.scheme},
        "robot": decl.parameters.name,
        **verification_fields(r),
    }
    if r.status in ("optimal", "acceptable", "check_failed"):
        traj = solution.trajectory()
        summary.update(force_statistics(traj, decl.force_limit))
        summary["sample_time_s"] = float(traj["t"][1] - traj["t"][0]) if len(traj["t"]) > 1 else None
    return summary
