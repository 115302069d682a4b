"""Problem files: TOML schema, validation, dispatch to the solvers, result folders.

A problem file declares one problem; ``kind`` selects the solver. Every field is
validated on load and an error names the file, the field and what was expected.

Kind ``point_to_point`` (Dressler (2012), ch. 3.5, Table 3.1, "direct" rows)::

    name = "l1_time_optimal"            # optional, default: the file name
    kind = "point_to_point"
    description = "..."                 # optional

    [robot]
    parameters = "L1"                   # shipped set name, or a path relative to the file
    configuration = 0                   # IK configuration 0-7 (optional, default 0)
    friction = "tanh"                   # "tanh" | "piecewise" | "exact" (optional)
    friction_width = 0.01               # [m/s] (optional)

    [motion]
    start = [-0.2, 2.75, -0.4]          # TCP at rest [m]
    end = [0.2, 3.0, -0.6]              # TCP at rest [m]

    [limits]
    force = [450.0, 450.0, 450.0]       # |tau_i| <= force_i [N]

    [objective]
    w = 0.0                             # cost = final_time + w * sum_i integral tau_i^2 dt

    [final_time]                        # optional table
    initial_guess = 1.0                 # [s]
    bounds = [0.05, 10.0]               # [s]

    [collocation]                       # optional table
    elements = 50
    points = 3
    scheme = "radau"                    # or "legendre"

    [solver]                            # optional table
    max_iter = 3000
    tol = 1e-8

The result folder (``write_results``) holds ``summary.json`` (always, also on failure),
``trajectory.csv`` sampled every 4 ms and PNG plots.
"""

from __future__ import annotations

import json
import logging
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from gtmodel._toml import read_toml
from gtmodel.errors import GtModelError, InputError, ParameterError, ProblemError, UnreachablePoseError
from gtmodel.robots.friction import DEFAULT_FRICTION_WIDTH, FRICTION_FORMS
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.parameters import available_parameter_sets, load_parameters
from gtmodel.trajectory.point_to_point import PointToPoint, PointToPointSolution, check_holding_forces, solve_point_to_point

__all__ = ["KINDS", "Problem", "load_problem", "solve_problem", "write_results", "error_summary", "write_summary"]

_log = logging.getLogger("gtmodel")

#: Problem kinds understood by :func:`load_problem`.
KINDS = ("point_to_point",)
#: Relative tolerance on force limits when reporting the fraction of time at a bound.
AT_BOUND_RTOL = 1e-3

_SCHEMA: dict[str, set[str]] = {
    "": {"name", "kind", "description", "robot", "motion", "limits", "objective", "final_time", "collocation", "solver"},
    "robot": {"parameters", "configuration", "friction", "friction_width"},
    "motion": {"start", "end"},
    "limits": {"force"},
    "objective": {"w"},
    "final_time": {"initial_guess", "bounds"},
    "collocation": {"elements", "points", "scheme"},
    "solver": {"max_iter", "tol"},
}
_REQUIRED_TABLES = ("robot", "motion", "limits", "objective")


@dataclass
class Problem:
    """A validated problem file.

    Parameters
    ----------
    path : pathlib.Path
        The file.
    name : str
        Problem name.
    kind : str
        One of :data:`KINDS`.
    description : str
        Free text.
    declaration : PointToPoint
        The solver-level declaration built from the file.
    """

    path: Path
    name: str
    kind: str
    description: str
    declaration: PointToPoint


class _Fields:
    """Reads fields of a parsed TOML document with messages naming file and field."""

    def __init__(self, data: Mapping[str, Any], path: Path) -> None:
        self.data = data
        self.path = path

    def fail(self, field: str, expected: str, got: Any = ...) -> ProblemError:
        tail = "" if got is ... else f", got {got!r}"
        return ProblemError(f"{self.path}: field '{field}': expected {expected}{tail}")

    def table(self, name: str, required: bool) -> Mapping[str, Any]:
        if name not in self.data:
            if required:
                raise ProblemError(f"{self.path}: missing table '[{name}]'")
            return {}
        value = self.data[name]
        if not isinstance(value, Mapping):
            raise self.fail(name, "a table", value)
        return value

    def get(self, table: str, key: str, default: Any = ...) -> Any:
        src = self.data if table == "" else self.table(table, required=default is ...)
        field = key if table == "" else f"{table}.{key}"
        if key not in src:
            if default is ...:
                raise ProblemError(f"{self.path}: missing field '{field}'")
            return default
        return src[key]

    def number(self, table: str, key: str, default: Any = ..., positive: bool = False, nonnegative: bool = False) -> float:
        field = key if table == "" else f"{table}.{key}"
        value = self.get(table, key, default)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise self.fail(field, "a finite number", value)
        if positive and value <= 0:
            raise self.fail(field, "a positive number", value)
        if nonnegative and value < 0:
            raise self.fail(field, "a non-negative number", value)
        return float(value)

    def integer(self, table: str, key: str, default: Any, lo: int, hi: int) -> int:
        field = f"{table}.{key}"
        value = self.get(table, key, default)
        if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
            raise self.fail(field, f"an integer in {lo}..{hi}", value)
        return int(value)

    def vector(self, table: str, key: str, n: int, default: Any = ..., positive: bool = False) -> np.ndarray:
        field = f"{table}.{key}"
        value = self.get(table, key, default)
        ok = isinstance(value, list) and len(value) == n and all(
            isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in value
        )
        if not ok:
            raise self.fail(field, f"a list of {n} finite numbers", value)
        arr = np.array(value, dtype=float)
        if positive and np.any(arr <= 0):
            raise self.fail(field, f"{n} positive numbers", value)
        return arr

    def choice(self, table: str, key: str, options: tuple[str, ...], default: str) -> str:
        value = self.get(table, key, default)
        if value not in options:
            raise self.fail(f"{table}.{key}", f"one of {', '.join(options)}", value)
        return value


def _check_unknown(data: Mapping[str, Any], path: Path) -> None:
    for table, allowed in _SCHEMA.items():
        src = data if table == "" else data.get(table, {})
        if not isinstance(src, Mapping):
            continue
        for key in src:
            if key not in allowed:
                field = key if table == "" else f"{table}.{key}"
                raise ProblemError(f"{path}: unknown field '{field}' (allowed here: {', '.join(sorted(allowed))})")


def load_problem(path: str | Path) -> Problem:
    """Read and validate a problem file.

    Parameters
    ----------
    path : str or pathlib.Path
        The TOML problem file.

    Returns
    -------
    Problem
        The validated problem, ready for :func:`solve_problem`.

    Raises
    ------
    ProblemError
        Unreadable file, TOML syntax error, a missing, unknown or invalid field, an invalid
        robot parameter set, a start or end pose outside the workspace, start equal to
        end, or force limits that cannot hold the robot at rest at start or end. The
        message names the file and the field.
    """
    path = Path(path)
    data = read_toml(path, ProblemError, "problem file")
    f = _Fields(data, path)
    kind = f.get("", "kind")
    if kind not in KINDS:
        raise f.fail("kind", f"one of {', '.join(KINDS)}", kind)
    for table in _REQUIRED_TABLES:
        f.table(table, required=True)
    for table in ("final_time", "collocation", "solver"):
        f.table(table, required=False)
    _check_unknown(data, path)
    name = f.get("", "name", path.stem)
    if not isinstance(name, str) or not name:
        raise f.fail("name", "a non-empty string", name)
    description = f.get("", "description", "")
    if not isinstance(description, str):
        raise f.fail("description", "a string", description)

    robot_ref = f.get("robot", "parameters")
    if not isinstance(robot_ref, str) or not robot_ref:
        raise f.fail("robot.parameters", f"a parameter-set name ({', '.join(available_parameter_sets())}) or a file path", robot_ref)
    if robot_ref not in available_parameter_sets():
        robot_ref = str((path.parent / robot_ref).resolve())
    try:
        params = load_parameters(robot_ref)
    except ParameterError as exc:
        raise ProblemError(f"{path}: field 'robot.parameters': {exc}") from None
    configuration = f.integer("robot", "configuration", 0, 0, 7)
    friction = f.choice("robot", "friction", FRICTION_FORMS, "tanh")
    width = f.number("robot", "friction_width", DEFAULT_FRICTION_WIDTH, positive=True)

    start = f.vector("motion", "start", 3)
    end = f.vector("motion", "end", 3)
    force = f.vector("limits", "force", 3, positive=True)
    w = f.number("objective", "w", nonnegative=True)
    tf_guess = f.number("final_time", "initial_guess", 1.0, positive=True)
    bounds = f.vector("final_time", "bounds", 2, default=[0.05, 10.0], positive=True)
    if not bounds[0] < bounds[1]:
        raise f.fail("final_time.bounds", "[lo, hi] with 0 < lo < hi", bounds.tolist())
    if not bounds[0] <= tf_guess <= bounds[1]:
        raise f.fail("final_time.initial_guess", f"a duration within final_time.bounds {bounds.tolist()}", tf_guess)
    elements = f.integer("collocation", "elements", 50, 1, 10000)
    points = f.integer("collocation", "points", 3, 1, 9)
    scheme = f.choice("collocation", "scheme", ("radau", "legendre"), "radau")
    max_iter = f.integer("solver", "max_iter", 3000, 1, 10**6)
    tol = f.number("solver", "tol", 1e-8, positive=True)

    if np.linalg.norm(end - start) < 1e-9:
        raise f.fail("motion.end", "a pose different from motion.start", end.tolist())
    kin = GantryTau3Kinematics(params)
    for key, pose in (("start", start), ("end", end)):
        try:
            kin.require_in_workspace(pose, configuration)
        except UnreachablePoseError as exc:
            raise ProblemError(f"{path}: field 'motion.{key}': {exc}") from None
    decl = PointToPoint(
        robot=params,
        start=start,
        end=end,
        force_limit=force,
        w=w,
        final_time_guess=tf_guess,
        final_time_bounds=(float(bounds[0]), float(bounds[1])),
        friction=friction,
        friction_width=width,
        configuration=configuration,
        elements=elements,
        points=points,
        scheme=scheme,
        max_iter=max_iter,
        tol=tol,
        name=name,
    )
    try:
        check_holding_forces(decl)
    except InputError as exc:
        raise ProblemError(f"{path}: field 'limits.force': {exc}") from None
    return Problem(path=path, name=name, kind=kind, description=description, declaration=decl)


def solve_problem(problem: Problem, verbose: bool = False) -> PointToPointSolution:
    """Solve a loaded problem with the solver its ``kind`` selects.

    Parameters
    ----------
    problem : Problem
        From :func:`load_problem`.
    verbose : bool, optional
        Show the solver's iteration log.

    Returns
    -------
    PointToPointSolution
        The solution (check ``solution.result.status``).
    """
    return solve_point_to_point(problem.declaration, verbose=verbose)


def _json_safe(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, np.ndarray):
        return [_json_safe(float(x)) for x in value.ravel()]
    if isinstance(value, (np.floating,)):
        return _json_safe(float(value))
    if isinstance(value, (np.integer,)):
        return int(value)
    return value


def write_summary(out_dir: str | Path, summary: Mapping[str, Any]) -> Path:
    """Write ``summary.json`` (non-finite numbers become ``null``).

    Parameters
    ----------
    out_dir : str or pathlib.Path
        Result folder (created if missing).
    summary : Mapping[str, Any]
        The summary fields.

    Returns
    -------
    pathlib.Path
        The written file.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    target = out / "summary.json"
    target.write_text(json.dumps({k: _json_safe(v) for k, v in summary.items()}, indent=2) + "\n", encoding="utf-8")
    return target


def error_summary(problem_path: str | Path, error: BaseException, kind: str | None = None) -> dict[str, Any]:
    """Summary of a problem that could not be solved (bad input or an exception).

    Parameters
    ----------
    problem_path : str or pathlib.Path
        The problem file.
    error : BaseException
        What went wrong.
    kind : str or None, optional
        The problem kind, if known.

    Returns
    -------
    dict
        ``problem``, ``kind``, ``status = "error"``, ``message`` and the numeric fields set
        to None.
    """
    return {
        "problem": str(problem_path),
        "kind": kind,
        "status": "error",
        "message": str(error) if isinstance(error, GtModelError) else f"{type(error).__name__}: {error}",
        "final_time_s": None,
        "energy": None,
        "iterations": None,
        "solve_time_s": None,
        "objective": None,
        "max_constraint_violation": None,
    }


def write_results(problem: Problem, solution: PointToPointSolution, out_dir: str | Path, plots: bool = True) -> dict[str, Any]:
    """Write the result folder of a solved problem.

    ``summary.json`` is always written. The trajectory (``trajectory.csv``, every 4 ms)
    and the plots (``tcp_path.png``, ``forces.png``) are written only when the solver
    returned a solution (status optimal or acceptable), never for a failed solve's last
    iterate.

    Parameters
    ----------
    problem : Problem
        The problem.
    solution : PointToPointSolution
        Its solution.
    out_dir : str or pathlib.Path
        Result folder (created if missing).
    plots : bool, optional
        Write PNG plots (default True).

    Returns
    -------
    dict
        The summary that was written.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    r = solution.result
    decl = problem.declaration
    summary: dict[str, Any] = {
        "problem": str(problem.path),
        "name": problem.name,
        "kind": problem.kind,
        "status": r.status,
        "message": r.message,
        "final_time_s": r.final_time,
        "energy": solution.energy,
        "energy_units": "N^2 s (sum_i integral tau_i^2 dt)",
        "iterations": r.iterations,
        "solve_time_s": r.solve_time,
        "objective": r.objective,
        "max_constraint_violation": r.max_constraint_violation,
        "last_iterate": r.last_iterate,
        "w": decl.w,
        "force_limit_N": decl.force_limit.tolist(),
        "collocation": {"elements": decl.elements, "points": decl.points, "scheme": decl.scheme},
        "robot": decl.parameters.name,
    }
    if r.status in ("optimal", "acceptable"):
        traj = solution.trajectory()
        tau = np.column_stack([traj["tau1"], traj["tau2"], traj["tau3"]])
        summary["max_force_ratio"] = (np.abs(tau).max(axis=0) / decl.force_limit).tolist()
        summary["fraction_at_force_bound"] = (np.abs(tau) >= (1 - AT_BOUND_RTOL) * decl.force_limit).mean(axis=0).tolist()
        summary["sample_time_s"] = float(traj["t"][1] - traj["t"][0]) if len(traj["t"]) > 1 else None
        solution.write_csv(out / "trajectory.csv")
        summary["files"] = ["summary.json", "trajectory.csv"]
        if plots:
            from gtmodel.trajectory.plots import plot_forces, plot_tcp_path

            plot_tcp_path(traj, decl.start, decl.end, out / "tcp_path.png", title=problem.name)
            plot_forces(traj, decl.force_limit, out / "forces.png", title=problem.name)
            summary["files"] += ["tcp_path.png", "forces.png"]
    write_summary(out, summary)
    return summary
