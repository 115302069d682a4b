"""Problem-file schemas of the motion-planning kinds, and their result folders.

Kind ``point_to_point`` (free path between two poses; Dressler (2012), ch. 3.5, Table 3.1
"direct" rows). The objective and extra constraints are written in the problem language
(:mod:`gtmodel.modeling.expressions`, documented in ``docs/problem_language.md``)::

    name = "l1_energy_w0_001"
    kind = "point_to_point"

    [robot]
    parameters = "L1"                   # shipped set name, or a path relative to the file
    configuration = 0                   # IK configuration 0-7
    friction = "tanh"                   # "tanh" | "piecewise" | "exact"
    friction_width = 0.01               # [m/s]

    [motion]
    start = [-0.2, 2.75, -0.4]          # TCP at rest [m]
    end = [0.2, 3.0, -0.6]

    [limits]
    force = [450.0, 450.0, 450.0]       # |tau_i| <= force_i [N]
    cart_velocity = [1.5, 1.5, 1.5]     # optional |qd_i| [m/s]
    cart_acceleration = [20, 20, 20]    # optional |qdd_i| [m/s^2]
    tcp_velocity = 1.5                  # optional ||T_dot|| [m/s]
    joint_angle_deg = 40.0              # optional, default the robot's limit

    [parameters]                        # named parameters of the expressions
    w = 0.001

    [optimization]
    objective = "final_time + w * integral(tau1^2 + tau2^2 + tau3^2)"
    constraints = ["abs(qd1) <= 1.2"]   # optional extra path/point constraints
    start_time = 0.0                    # optional [s]

    [optimization.final_time]
    free = true                         # free: needs bounds; fixed: needs value
    initial_guess = 1.0                 # [s]
    bounds = [0.05, 10.0]               # [s]
    # value = 1.2                       # [s], when free = false

    [initial_guess]                     # optional
    method = "trapezoid"                # "trapezoid" | "bang_bang" | "file"
    # file = "results/l1_time_optimal/trajectory.csv"

    [collocation]                       # optional
    elements = 50
    points = 3
    scheme = "radau"                    # or "legendre"

    [solver]                            # optional
    max_iter = 3000
    tol = 1e-8
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._fields import FieldReader
from gtmodel.errors import InputError, ParameterError, ProblemError, UnreachablePoseError
from gtmodel.robots.friction import DEFAULT_FRICTION_WIDTH, FRICTION_FORMS
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.parameters import RobotParameters, available_parameter_sets, load_parameters
from gtmodel.trajectory.point_to_point import PointToPoint, PointToPointSolution, check_holding_forces

__all__ = [
    "POINT_TO_POINT_SCHEMA",
    "AT_BOUND_RTOL",
    "load_robot",
    "read_named_parameters",
    "load_point_to_point",
    "point_to_point_summary",
    "write_point_to_point",
    "PATH_CONSTRAINED_SCHEMA",
    "PATH_METHODS",
    "PathConstrainedDeclaration",
    "load_path_constrained",
    "solve_path_declaration",
    "path_trajectory_columns",
    "write_path_constrained",
]

#: Relative tolerance on force limits when reporting the fraction of time at a bound.
AT_BOUND_RTOL = 1e-3

#: Allowed fields of a ``point_to_point`` problem file (dotted table -> keys).
POINT_TO_POINT_SCHEMA: dict[str, set[str]] = {
    "": {"name", "kind", "description", "robot", "motion", "limits", "parameters", "optimization", "initial_guess", "collocation", "solver"},
    "robot": {"parameters", "configuration", "friction", "friction_width"},
    "motion": {"start", "end"},
    "limits": {"force", "cart_velocity", "cart_acceleration", "tcp_velocity", "joint_angle_deg"},
    "optimization": {"objective", "constraints", "start_time", "final_time"},
    "optimization.final_time": {"free", "initial_guess", "bounds", "value"},
    "initial_guess": {"method", "file"},
    "collocation": {"elements", "points", "scheme"},
    "solver": {"max_iter", "tol"},
}

_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def load_robot(f: FieldReader, table: str = "robot") -> RobotParameters:
    """The robot parameter set named in ``[robot] parameters``.

    Parameters
    ----------
    f : FieldReader
        The problem file.
    table : str, optional
        The table holding ``parameters``.

    Returns
    -------
    RobotParameters

    Raises
    ------
    ProblemError
        Not a known set name nor a loadable file (names the field).
    """
    ref = f.get(table, "parameters")
    if not isinstance(ref, str) or not ref:
        raise f.fail(f"{table}.parameters", f"a parameter-set name ({', '.join(available_parameter_sets())}) or a file path", ref)
    if ref not in available_parameter_sets():
        ref = str((f.path.parent / ref).resolve())
    try:
        return load_parameters(ref)
    except ParameterError as exc:
        raise ProblemError(f"{f.path}: field '{table}.parameters': {exc}") from None


def read_named_parameters(f: FieldReader, reserved: set[str]) -> dict[str, float]:
    """The ``[parameters]`` table: named numbers usable in expressions.

    Parameters
    ----------
    f : FieldReader
        The problem file.
    reserved : set of str
        Names the model already defines (a parameter may not shadow them).

    Returns
    -------
    dict of str to float

    Raises
    ------
    ProblemError
        A name that is not an identifier or shadows a model name, or a value that is
        not a finite number.
    """
    out: dict[str, float] = {}
    for key in f.table("parameters", required=False):
        if not _IDENT.match(key):
            raise f.fail(f"parameters.{key}", "an identifier (letters, digits, _) as the parameter name", key)
        if key in reserved:
            raise f.fail(f"parameters.{key}", "a name that is not a model variable", key)
        out[key] = f.number("parameters", key)
    return out


#: Names the point-to-point model defines (see :func:`gtmodel.trajectory.problem_names`).
_MODEL_NAMES = (
    {c + s for c in "xyz" for s in ("", "d", "dd")}
    | {f"{n}{k}" for n in ("q", "qd", "qdd", "tau") for k in (1, 2, 3)}
    | {"power", "time", "start_time", "final_time"}
)


def load_point_to_point(f: FieldReader, name: str) -> PointToPoint:
    """Validate a ``point_to_point`` problem file and build its declaration.

    Parameters
    ----------
    f : FieldReader
        The problem file.
    name : str
        Problem name.

    Returns
    -------
    PointToPoint

    Raises
    ------
    ProblemError
        A missing, unknown or invalid field; a pose outside the workspace; a free final
        time without bounds; force limits that cannot hold the robot at rest; an invalid
        expression (names the file, field and token).
    """
    f.check_unknown(POINT_TO_POINT_SCHEMA)
    for table in ("robot", "motion", "limits", "optimization"):
        f.table(table, required=True)
    params = load_robot(f)
    configuration = f.integer("robot", "configuration", 0, 0, 7)
    friction = f.choice("robot", "friction", FRICTION_FORMS, "tanh")
    width = f.number("robot", "friction_width", DEFAULT_FRICTION_WIDTH, positive=True)
    start = f.vector("motion", "start", 3)
    end = f.vector("motion", "end", 3)
    force = f.vector("limits", "force", 3, positive=True)
    cart_velocity = f.vector("limits", "cart_velocity", 3, None, positive=True) if "cart_velocity" in f.table("limits", True) else None
    cart_acc = f.vector("limits", "cart_acceleration", 3, None, positive=True) if "cart_acceleration" in f.table("limits", True) else None
    tcp_velocity = f.number("limits", "tcp_velocity", None, positive=True) if "tcp_velocity" in f.table("limits", True) else None
    joint = None
    if "joint_angle_deg" in f.table("limits", True):
        deg = f.number("limits", "joint_angle_deg", positive=True)
        if deg >= 90:
            raise f.fail("limits.joint_angle_deg", "an angle below 90 degrees", deg)
        joint = float(np.deg2rad(deg))
    named = read_named_parameters(f, _MODEL_NAMES)
    if named.get("w", 0.0) < 0:
        raise f.fail("parameters.w", "a non-negative energy weight", named["w"])

    objective = f.string("optimization", "objective")
    constraints = f.get("optimization", "constraints", [])
    if not isinstance(constraints, list) or not all(isinstance(c, str) for c in constraints):
        raise f.fail("optimization.constraints", "a list of strings (expressions)", constraints)
    t0 = f.number("optimization", "start_time", 0.0)
    ft = "optimization.final_time"
    f.table(ft, required=True)
    free = f.boolean(ft, "free", ...)
    if free:
        if "bounds" not in f.table(ft, True):
            raise f.fail(f"{ft}.bounds", "bounds [lo, hi] for a free final time (free = true)")
        bounds = f.vector(ft, "bounds", 2)
        if not t0 < bounds[0] < bounds[1]:
            raise f.fail(f"{ft}.bounds", f"[lo, hi] with start_time ({t0}) < lo < hi", bounds.tolist())
        tf_guess = f.number(ft, "initial_guess", float(np.clip(1.0, *bounds)), positive=True)
        if not bounds[0] <= tf_guess <= bounds[1]:
            raise f.fail(f"{ft}.initial_guess", f"a time within {ft}.bounds {bounds.tolist()}", tf_guess)
        if "value" in f.table(ft, True):
            raise f.fail(f"{ft}.value", "no fixed value when free = true (use initial_guess)")
    else:
        if "value" not in f.table(ft, True):
            raise f.fail(f"{ft}.value", "the final time [s] when free = false")
        tf_guess = f.number(ft, "value", positive=True)
        if not tf_guess > t0:
            raise f.fail(f"{ft}.value", f"a final time after start_time ({t0})", tf_guess)
        bounds = np.array([tf_guess, tf_guess])
    method = f.choice("initial_guess", "method", ("trapezoid", "bang_bang", "file"), "trapezoid")
    guess: Any = method
    if method == "file":
        rel = f.string("initial_guess", "file")
        guess = (f.path.parent / rel).resolve()
        if not guess.is_file():
            raise f.fail("initial_guess.file", "an existing trajectory CSV (path relative to the problem file)", rel)
    elif "file" in f.table("initial_guess", False):
        raise f.fail("initial_guess.file", 'no file unless method = "file"')
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
            raise ProblemError(f"{f.path}: field 'motion.{key}': {exc}") from None
    try:
        decl = PointToPoint(
            robot=params,
            start=start,
            end=end,
            force_limit=force,
            w=named.get("w", 0.0),
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
            objective=objective,
            constraints=tuple(constraints),
            named_parameters=named,
            free_final_time=free,
            cart_velocity_limit=cart_velocity,
            cart_acceleration_limit=cart_acc,
            tcp_velocity_limit=tcp_velocity,
            joint_angle_limit=joint,
            guess=guess,
            origin=str(f.path),
            start_time=t0,
            )
    except InputError as exc:
        raise ProblemError(f"{f.path}: {exc}") from None
    try:
        check_holding_forces(decl)
    except InputError as exc:
        raise ProblemError(f"{f.path}: field 'limits.force': {exc}") from None
    _check_expressions(decl)
    return decl


def _check_expressions(decl: PointToPoint) -> None:
    """Parse the objective and constraints now, so that a bad expression is bad input."""
    from gtmodel.modeling.expressions import parse_constraint, parse_objective
    import casadi as ca

    names: dict[str, Any] = {n: ca.SX.sym(n) for n in _MODEL_NAMES}
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
        violation, force statistics and the problem's settings.
    """
    r = solution.result
    summary: dict[str, Any] = {
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
        "objective_expression": decl.objective,
        "constraints": list(decl.constraints),
        "parameters": dict(decl.named_parameters),
        "w": decl.named_parameters.get("w"),
        "free_final_time": decl.free_final_time,
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
    return summary


def write_point_to_point(decl: PointToPoint, solution: PointToPointSolution, out: Path, plots: bool, title: str) -> tuple[dict[str, Any], list[str]]:
    """Write the data files and plots of a solved point-to-point problem.

    Nothing but the summary fields is produced for a failed solve (its last iterate is
    not a trajectory).

    Parameters
    ----------
    decl : PointToPoint
        The declaration.
    solution : PointToPointSolution
        Its solution.
    out : pathlib.Path
        Result folder (exists).
    plots : bool
        Write PNG plots.
    title : str
        Plot title.

    Returns
    -------
    summary : dict
        :func:`point_to_point_summary`.
    files : list of str
        Files written (besides ``summary.json``).
    """
    from gtmodel.trajectory.export import write_c_header

    summary = point_to_point_summary(decl, solution)
    files: list[str] = []
    if solution.result.status in ("optimal", "acceptable"):
        traj = solution.trajectory()
        solution.write_csv(out / "trajectory.csv")
        write_c_header(traj, out / "trajectory.h", name=title)
        files += ["trajectory.csv", "trajectory.h"]
        if plots:
            from gtmodel.report.trajectory import plot_forces, plot_tcp_path

            plot_tcp_path(traj, decl.start, decl.end, out / "tcp_path.png", title=title)
            plot_forces(traj, decl.force_limit, out / "forces.png", title=title)
            files += ["tcp_path.png", "forces.png"]
    return summary, files


# ---------------------------------------------------------------------- path_constrained
#: Allowed fields of a ``path_constrained`` problem file.
PATH_CONSTRAINED_SCHEMA: dict[str, set[str]] = {
    "": {"name", "kind", "description", "robot", "motion", "path", "limits", "method", "collocation", "solver"},
    "robot": {"parameters", "configuration", "viscous_friction"},
    "motion": {"start", "end"},
    "path": {"shape", "via"},
    "limits": {"force", "cart_velocity", "cart_acceleration", "tcp_velocity", "tcp_speed", "tcp_acceleration"},
    "method": {"name", "grid", "w", "final_time_guess", "final_time_bounds"},
    "collocation": {"elements", "points", "scheme"},
    "solver": {"max_iter", "tol"},
}

#: Methods of kind ``path_constrained``: the convex reformulation (Verscheure et al.
#: (2009), solved to the exact optimum of the gridded problem) and the thesis' projection
#: solved by collocation (Dressler (2012), ch. 3.5).
PATH_METHODS = ("convex", "collocation")


@dataclass
class PathConstrainedDeclaration:
    """A validated ``path_constrained`` problem.

    Parameters
    ----------
    path : gtmodel.trajectory.path.Path
        The TCP path (checked inside the workspace).
    robot : RobotParameters
        Parameter set.
    constraints : gtmodel.trajectory.path_constrained.PathConstraints
        Limits along the path.
    method : str
        One of :data:`PATH_METHODS`.
    grid : int
        Grid points of the convex method.
    w : float
        Energy weight of the collocation method's objective
        ``final_time + w * sum_i integral tau_i^2 dt`` [1/N^2].
    configuration : int
        IK configuration.
    viscous_friction : bool
        Include viscous friction.
    options : dict
        Collocation mesh, final-time guess/bounds and solver options.
    """

    path: Any
    robot: RobotParameters
    constraints: Any
    method: str
    grid: int
    w: float
    configuration: int
    viscous_friction: bool
    options: dict


def load_path_constrained(f: FieldReader, name: str) -> PathConstrainedDeclaration:
    """Validate a ``path_constrained`` problem file.

    Parameters
    ----------
    f : FieldReader
        The problem file.
    name : str
        Problem name.

    Returns
    -------
    PathConstrainedDeclaration

    Raises
    ------
    ProblemError
        A missing, unknown or invalid field, a path outside the workspace (naming the path
        coordinate), a method that does not support the given limits.
    """
    from gtmodel.trajectory.path import Polyline, SplinePath, StraightLine
    from gtmodel.trajectory.path_constrained import PathConstraints

    f.check_unknown(PATH_CONSTRAINED_SCHEMA)
    for table in ("robot", "motion", "limits"):
        f.table(table, required=True)
    params = load_robot(f)
    configuration = f.integer("robot", "configuration", 0, 0, 7)
    viscous = f.boolean("robot", "viscous_friction", True)
    start = f.vector("motion", "start", 3)
    end = f.vector("motion", "end", 3)
    shape = f.choice("path", "shape", ("line", "polyline", "spline"), "line")
    via = f.get("path", "via", [])
    if not isinstance(via, list) or not all(isinstance(p, list) and len(p) == 3 for p in via):
        raise f.fail("path.via", "a list of [x, y, z] points [m]", via)
    if shape == "line" and via:
        raise f.fail("path.via", 'no via points for shape = "line" (use "polyline" or "spline")', via)
    if shape != "line" and not via:
        raise f.fail("path.via", f"at least one via point for shape = {shape!r}", via)
    lim = f.table("limits", True)

    def opt_vec(key: str) -> Any:
        return f.vector("limits", key, 3, positive=True) if key in lim else None

    method = f.choice("method", "name", PATH_METHODS, "convex")
    grid = f.integer("method", "grid", 500, 2, 10**6)
    w = f.number("method", "w", 0.0, nonnegative=True)
    tf_guess = f.number("method", "final_time_guess", 1.0, positive=True)
    bounds = f.vector("method", "final_time_bounds", 2, default=[0.05, 10.0], positive=True)
    if not bounds[0] < bounds[1]:
        raise f.fail("method.final_time_bounds", "[lo, hi] with 0 < lo < hi", bounds.tolist())
    if method == "convex" and w != 0.0:
        raise f.fail("method.w", 'w = 0 for method "convex" (time-optimal); use method "collocation" for an energy weight', w)
    try:
        cons = PathConstraints(
            force_limit=opt_vec("force"),
            cart_velocity_limit=opt_vec("cart_velocity"),
            cart_acceleration_limit=opt_vec("cart_acceleration"),
            tcp_velocity_limit=opt_vec("tcp_velocity"),
            tcp_speed_limit=f.number("limits", "tcp_speed", positive=True) if "tcp_speed" in lim else None,
            tcp_acceleration_limit=opt_vec("tcp_acceleration"),
        )
    except InputError as exc:
        raise ProblemError(f"{f.path}: field 'limits': {exc}") from None
    if method == "collocation" and cons.force_limit is None:
        raise f.fail("limits.force", 'force limits for method "collocation"')
    points = [start, *[np.asarray(p, dtype=float) for p in via], end]
    try:
        if shape == "line":
            path = StraightLine(start, end, robot=params, configuration=configuration)
        elif shape == "polyline":
            path = Polyline(points, robot=params, configuration=configuration)
        else:
            path = SplinePath(points, robot=params, configuration=configuration)
    except UnreachablePoseError as exc:
        raise ProblemError(f"{f.path}: field 'path': {exc}") from None
    except InputError as exc:
        raise ProblemError(f"{f.path}: field 'motion'/'path': {exc}") from None
    options = {
        "elements": f.integer("collocation", "elements", 50, 1, 10000),
        "points": f.integer("collocation", "points", 3, 1, 9),
        "scheme": f.choice("collocation", "scheme", ("radau", "legendre"), "radau"),
        "final_time_guess": tf_guess,
        "final_time_bounds": (float(bounds[0]), float(bounds[1])),
        "max_iter": f.integer("solver", "max_iter", 3000, 1, 10**6),
        "tol": f.number("solver", "tol", 1e-8, positive=True),
    }
    return PathConstrainedDeclaration(path, params, cons, method, grid, w, configuration, viscous, options)


def solve_path_declaration(decl: PathConstrainedDeclaration, verbose: bool = False) -> Any:
    """Solve a ``path_constrained`` declaration with its method.

    Parameters
    ----------
    decl : PathConstrainedDeclaration
        The declaration.
    verbose : bool, optional
        IPOPT output (collocation method).

    Returns
    -------
    gtmodel.trajectory.path_constrained.PathSolution
        Always returned; ``status`` says whether it is optimal.
    """
    from gtmodel.trajectory.path_constrained import solve_path_collocation, solve_path_convex

    if decl.method == "convex":
        return solve_path_convex(
            decl.path, decl.constraints, robot=decl.robot, grid=decl.grid, configuration=decl.configuration, viscous_friction=decl.viscous_friction
        )
    o = decl.options
    return solve_path_collocation(
        decl.path,
        decl.robot,
        decl.constraints.force_limit,
        w=decl.w,
        configuration=decl.configuration,
        viscous_friction=decl.viscous_friction,
        elements=o["elements"],
        points=o["points"],
        scheme=o["scheme"],
        final_time_guess=o["final_time_guess"],
        final_time_bounds=o["final_time_bounds"],
        max_iter=o["max_iter"],
        tol=o["tol"],
        verbose=verbose,
    )


def path_trajectory_columns(solution: Any) -> dict[str, np.ndarray]:
    """The 4 ms table of a path-constrained solution, with the columns of the free-path CSV.

    Parameters
    ----------
    solution : gtmodel.trajectory.path_constrained.PathSolution
        A solved problem.

    Returns
    -------
    dict of str to numpy.ndarray
        ``t, x, y, z, q1..q3, qd1..qd3, tau1..tau3, xd, yd, zd, s, s_dot, s_ddot``, each (K,).
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


def write_path_constrained(decl: PathConstrainedDeclaration, solution: Any, out: Path, plots: bool, title: str) -> tuple[dict[str, Any], list[str]]:
    """Summary fields, data files and plots of a solved ``path_constrained`` problem.

    Parameters
    ----------
    decl : PathConstrainedDeclaration
        The declaration.
    solution : gtmodel.trajectory.path_constrained.PathSolution
        Its solution.
    out : pathlib.Path
        Result folder (exists).
    plots : bool
        Write PNG plots.
    title : str
        Plot title.

    Returns
    -------
    summary : dict
        Status, final time, energy, iterations, solve time, method, grid and force figures.
    files : list of str
        Files written besides ``summary.json``.
    """
    from gtmodel.trajectory.export import write_c_header

    summary: dict[str, Any] = {
        "status": solution.status,
        "message": solution.message,
        "final_time_s": solution.final_time if solution.success else None,
        "energy": solution.energy if solution.success else None,
        "energy_units": "N^2 s (sum_i integral tau_i^2 dt)",
        "iterations": solution.iterations,
        "solve_time_s": solution.solve_time,
        "objective": solution.final_time if solution.success else None,
        "max_constraint_violation": None,
        "method": solution.method,
        "grid_points": int(np.size(solution.s)) if solution.s is not None else None,
        "w": decl.w,
        "robot": decl.robot.name,
    }
    files: list[str] = []
    if solution.status in ("optimal", "acceptable"):
        cols = path_trajectory_columns(solution)
        tau = np.column_stack([cols["tau1"], cols["tau2"], cols["tau3"]])
        if decl.constraints.force_limit is not None:
            limit = np.asarray(decl.constraints.force_limit)
            summary["force_limit_N"] = limit.tolist()
            summary["max_force_ratio"] = (np.abs(tau).max(axis=0) / limit).tolist()
            summary["fraction_at_force_bound"] = (np.abs(tau) >= (1 - AT_BOUND_RTOL) * limit).mean(axis=0).tolist()
        summary["sample_time_s"] = float(cols["t"][1] - cols["t"][0]) if cols["t"].size > 1 else None
        data = np.column_stack(list(cols.values()))
        np.savetxt(out / "trajectory.csv", data, delimiter=",", header=",".join(cols), comments="", fmt="%.10g")
        write_c_header(cols, out / "trajectory.h", name=title)
        files += ["trajectory.csv", "trajectory.h"]
        if plots:
            from gtmodel.report.trajectory import plot_forces, plot_path_profile, plot_tcp_path

            plot_tcp_path(cols, decl.path.start, decl.path.end, out / "tcp_path.png", title=title)
            if decl.constraints.force_limit is not None:
                plot_forces(cols, decl.constraints.force_limit, out / "forces.png", title=title)
                files.append("forces.png")
            plot_path_profile(solution, out / "profile.png", title=title)
            files += ["tcp_path.png", "profile.png"]
    return summary, files
