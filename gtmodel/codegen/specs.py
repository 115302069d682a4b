"""Declarations of the C functions generated from the CasADi model.

Each generated C function is described by a :class:`FunctionSpec`: which CasADi Function
it wraps (built from the robot model, never written by hand), how its public C arguments
map onto the CasADi inputs, which CasADi outputs are published, which outputs decide the
status code, and how the self-check compares it with the Python evaluation. Functions
solved by Newton's method carry a :class:`NewtonLoop` instead of one Function: a start
Function, a one-step Function and a finishing Function; the C wrapper runs the step in a
loop bounded by a maximum iteration count with an early exit on convergence.

Adding a function to the generated library is one more entry in the table of its robot
kind (:data:`FUNCTION_SPECS` for 3-link parameter sets, :data:`SIX_LINK_SPECS`,
:data:`F1_SPECS`; all in :data:`SPECS_BY_KIND`). The estimation work of Dressler (2012),
ch. 7 (stationary Kalman filter step, ILC correction lookup) does not exist in gtmodel
yet; once it provides CasADi Functions, each is one such entry.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any, Callable, Mapping

import casadi as ca
import numpy as np

from gtmodel.errors import ConvergenceError, ParameterError, UnreachablePoseError
from gtmodel.robots import f1 as _f1
from gtmodel.robots import six_link as _six
from gtmodel.robots.kinematics import DEGENERACY_TOLERANCE, SINGULARITY_TOLERANCE, GantryTau3Kinematics
from gtmodel.robots.parameters import RobotParameters, load_parameters

__all__ = [
    "STATUS_CODES",
    "IK_TOLERANCE",
    "FK_TOLERANCE",
    "JACOBIAN_TOLERANCE",
    "ACCELERATION_TOLERANCE",
    "INVERSE_DYNAMICS_TOLERANCE",
    "INVERSE_DYNAMICS_RELATIVE_TOLERANCE",
    "ROBOT_KINDS",
    "RobotModel",
    "load_robot",
    "ArgSpec",
    "OutputSpec",
    "StatusCheck",
    "NewtonLoop",
    "FunctionSpec",
    "FUNCTION_SPECS",
    "SIX_LINK_SPECS",
    "F1_SPECS",
    "SPECS_BY_KIND",
    "DEFAULT_FUNCTIONS",
    "default_functions",
]

#: Status codes returned by every generated C function (also ``#define``\ d in the header).
STATUS_CODES: dict[str, tuple[int, str]] = {
    "GT_OK": (0, "success; outputs written"),
    "GT_UNREACHABLE": (1, "pose unreachable (an arm cannot reach T, or the link spheres do not meet); outputs untouched"),
    "GT_SINGULAR": (2, "singular configuration (a link perpendicular to its guideway); outputs untouched"),
    "GT_DEGENERATE": (3, "degenerate forward kinematics (collinear sphere centres); outputs untouched"),
    "GT_BAD_ARGUMENT": (4, "NULL pointer, non-finite input or invalid configuration/solution; outputs untouched"),
    "GT_NUMERIC_ERROR": (5, "evaluation failed or produced a non-finite value; outputs untouched"),
    "GT_NOT_CONVERGED": (6, "Newton's method did not converge within the iteration limit; outputs untouched"),
}

#: Largest accepted |C - Python| of an inverse kinematics [m, rad].
IK_TOLERANCE = 1e-12
#: Largest accepted |C - Python| of a forward kinematics [m] (orientation matrix entries: same).
FK_TOLERANCE = 1e-12
#: Largest accepted |C - Python| of a Jacobian element (dimensionless).
JACOBIAN_TOLERANCE = 1e-12
#: Largest accepted |C - Python| of a TCP acceleration [m/s^2].
ACCELERATION_TOLERANCE = 1e-9
#: Largest accepted |C - Python| of an actuator force [N] (absolute floor).
INVERSE_DYNAMICS_TOLERANCE = 1e-9
#: Largest accepted |C - Python| / |Python| of an actuator force (relative).
INVERSE_DYNAMICS_RELATIVE_TOLERANCE = 1e-9

#: Robot kinds and what loads them.
ROBOT_KINDS = ("three_link", "six_link", "f1")


# ----------------------------------------------------------------------------- model
def _vector_hash(name: str, arrays: list[np.ndarray]) -> str:
    text = json.dumps([name] + [[float.hex(float(x)) for x in np.ravel(a)] for a in arrays])
    return hashlib.sha256(text.encode()).hexdigest()[:16]


class RobotModel:
    """The symbolic robot model the C functions are generated from.

    Parameters
    ----------
    robot : RobotParameters or SixLinkClosure or F1Closure
        A 3-link parameter set (``GantryTau3Kinematics``/``GantryTau3Dynamics``), the
        six-link error model of Dressler (2012), eq. 4.14, or the F1 model (eqs. 4.16-4.33).
        Values are embedded as constants.
    friction : str, optional
        Form of the friction sign for the dynamics (``"exact"``, ``"tanh"``, ``"piecewise"``).
    """

    def __init__(self, robot: Any, friction: str = "exact") -> None:
        from gtmodel.robots.f1 import F1Closure
        from gtmodel.robots.six_link import SixLinkClosure

        self.robot = robot
        self.friction = friction
        if isinstance(robot, RobotParameters):
            self.kind = "three_link"
            self.parameters: RobotParameters | None = robot
        elif isinstance(robot, SixLinkClosure):
            self.kind = "six_link"
            self.parameters = None
        elif isinstance(robot, F1Closure):
            self.kind = "f1"
            self.parameters = None
        else:
            raise ParameterError(f"robot: expected a 3-link parameter set, a six-link or an F1 model, got {type(robot).__name__}")
        self.name = str(robot.name)

    @cached_property
    def kinematics(self) -> GantryTau3Kinematics:
        """The 3-link kinematics (:class:`GantryTau3Kinematics`)."""
        return GantryTau3Kinematics(self.parameters)

    @cached_property
    def dynamics(self):
        """The rigid-body dynamics with friction (``GantryTau3Dynamics``)."""
        from gtmodel.robots.dynamics import GantryTau3Dynamics  # imported late: optional layer

        return GantryTau3Dynamics(self.parameters, friction=self.friction)

    @property
    def closure(self):
        """The six-link or F1 closure model (``SixLinkClosure`` / ``F1Closure``)."""
        return self.robot

    def parameter_hash(self) -> str:
        """Short hash of the numbers of the model (first 16 hex digits of a SHA-256).

        Returns
        -------
        str
            For a 3-link set :func:`gtmodel.codegen.generate.parameter_hash`; for the
            closure models the hash of the name, the parameter vector and the reference
            orientation / home actuator values.
        """
        if self.kind == "three_link":
            from gtmodel.codegen.generate import parameter_hash

            return parameter_hash(self.parameters)
        extra = self.robot.R0 if self.kind == "six_link" else self.robot.q_home
        return _vector_hash(self.name, [self.robot.parameter_vector(), extra])

    @property
    def description(self) -> str:
        """One line describing the robot model."""
        if self.kind == "three_link":
            return str(self.parameters.description)
        if self.kind == "six_link":
            return f"{self.name}: six-link kinematic error model (Dressler (2012), eqs. 4.14, 4.15)"
        return f"{self.name}: F1 6-DOF Gantry-Tau (Dressler (2012), eqs. 4.16-4.33)"


def load_robot(robot: Any) -> Any:
    """Load a robot for code generation: a 3-link set, the six-link or the F1 model.

    Parameters
    ----------
    robot : str or pathlib.Path or RobotParameters or SixLinkClosure or F1Closure
        A loaded model, a shipped name (``"L1"``, ``"D1"``, ``"L1_ideal"``, ``"D1_six_link"``,
        ``"F1"``) or a TOML path (a 3-link set such as a calibration's
        ``parameters.toml``, a six-link or an F1 parameter file; tried in this order).

    Returns
    -------
    RobotParameters or SixLinkClosure or F1Closure
        The model.

    Raises
    ------
    ParameterError
        No model of any kind could be loaded (the message of the 3-link attempt).
    """
    from gtmodel.robots.f1 import F1Closure, load_f1
    from gtmodel.robots.six_link import SixLinkClosure, load_six_link

    if isinstance(robot, (RobotParameters, SixLinkClosure, F1Closure)):
        return robot
    first: ParameterError | None = None
    for loader in (load_parameters, load_six_link, load_f1):
        try:
            return loader(robot)
        except ParameterError as exc:
            first = first or exc
    if isinstance(robot, (str, Path)) and not Path(robot).exists():
        raise ParameterError(
            f"unknown robot {str(robot)!r}: not a shipped set (3-link: L1, D1, L1_ideal; six-link: D1_six_link; F1) "
            "and no such file"
        )
    raise first  # type: ignore[misc]


# ----------------------------------------------------------------------------- declarations
@dataclass(frozen=True)
class ArgSpec:
    """One public argument of a generated C function.

    Parameters
    ----------
    name : str
        C parameter name.
    kind : {"vector", "matrix", "configuration", "solution"}
        ``"vector"``: ``const double name[n]`` passed as the CasADi input of the same size;
        ``"matrix"``: ``const double name[9]`` a ROW-MAJOR 3x3 matrix (transposed into
        CasADi's column-major input); ``"configuration"``: ``int`` 0-7 turned into the three
        IK root signs; ``"solution"``: ``int`` +1/-1 passed as a scalar.
    casadi_input : str
        Name of the CasADi input it feeds.
    doc : str
        Meaning and unit, for the header.
    optional : bool, optional
        The pointer may be NULL (a Newton warm start: NULL selects the default start).
    """

    name: str
    kind: str
    casadi_input: str
    doc: str
    optional: bool = False


@dataclass(frozen=True)
class OutputSpec:
    """One public output array of a generated C function.

    Parameters
    ----------
    name : str
        C parameter name (``double name[n]``, row-major for matrices).
    casadi_output : str
        Name of the CasADi output copied into it.
    doc : str
        Meaning and unit, for the header.
    """

    name: str
    casadi_output: str
    doc: str


@dataclass(frozen=True)
class StatusCheck:
    """A condition on a CasADi output that must hold, element-wise, for ``GT_OK``.

    The condition is written so that NaN fails it: ``!(value op threshold)`` gives ``status``.

    Parameters
    ----------
    casadi_output : str
        CasADi output tested.
    op : {">=", ">"}
        Comparison every element must satisfy.
    threshold : str
        C expression of the threshold (a literal or a header macro without prefix).
    status : str
        Status macro returned when the condition fails, e.g. ``"GT_UNREACHABLE"``.
    """

    casadi_output: str
    op: str
    threshold: str
    status: str


@dataclass(frozen=True)
class NewtonLoop:
    """A Newton iteration run by the C wrapper: start, bounded loop of one step, finish.

    Every Function's inputs are named like the CasADi inputs of the public arguments
    (``ArgSpec.casadi_input``) plus ``"x"`` for the iterate; the wrapper feeds them by name.
    The loop (``k = 0 .. max_iter``) evaluates ``step`` at ``x_k``; when ``residual <=
    tolerance`` (and ``valid >= 0`` if declared) the iteration has converged and the result
    is ``x_k`` (``accept="current"``) or ``x_{k+1}`` (``accept="next"``: one more Newton
    step, already computed); otherwise ``x_{k+1}`` replaces ``x_k``. No branch can run
    unbounded: at most ``max_iter + 1`` step evaluations.

    Parameters
    ----------
    size : int
        Length of the iterate ``x``.
    start : callable
        ``start(model) -> casadi.Function`` with output ``"x0"`` (and outputs tested by
        ``start_checks``): the default start value.
    step : callable
        ``step(model) -> casadi.Function`` with inputs ``"x"`` and public inputs, outputs
        ``"x_next"``, ``"residual"`` (scalar) and optionally ``"valid"`` (scalar).
    finish : callable
        ``finish(model) -> casadi.Function`` with inputs ``"x"`` and public inputs, outputs
        the published ones (and those tested by ``FunctionSpec.checks``).
    tolerance : float
        Default convergence tolerance of ``residual`` in double precision (a generation
        option overrides it).
    float_tolerance : float
        Default tolerance when the code is generated in single precision.
    max_iter : int
        Default iteration limit (a generation option overrides it).
    accept : {"current", "next"}
        Which iterate is returned on convergence (see above); chosen to match the Python
        evaluation.
    warm : tuple of str
        Public (optional) arguments holding a start value; when all are non-NULL the
        ``warm_start`` Function maps them to ``x0`` instead of ``start``.
    warm_start : callable or None
        ``warm_start(model) -> casadi.Function`` with output ``"x0"``.
    start_checks : tuple of StatusCheck
        Conditions on the outputs of ``start``.
    residual_unit : str
        Unit of ``residual`` (for the header).
    check_every : int
        Convergence is tested only at ``k`` a multiple of this (and ``k > 0`` if it is
        above 1): 1 gives the earliest exit; the F1 declarations use 4, the block size of
        the Python model (:meth:`F1Closure.ik`/``fk`` run blocks of 4 unrolled steps),
        so that the C code returns the very iterate Python returns. Above 1 (needs
        ``accept="current"``) the tests evaluate only the ``residual`` (and ``valid``)
        part of ``step``, the step itself only where the loop goes on.
    """

    size: int
    start: Callable[["RobotModel"], ca.Function]
    step: Callable[["RobotModel"], ca.Function]
    finish: Callable[["RobotModel"], ca.Function]
    tolerance: float
    float_tolerance: float
    max_iter: int
    accept: str = "next"
    warm: tuple[str, ...] = ()
    warm_start: Callable[["RobotModel"], ca.Function] | None = field(default=None, compare=False)
    start_checks: tuple[StatusCheck, ...] = ()
    residual_unit: str = "m"
    check_every: int = 1


@dataclass(frozen=True)
class FunctionSpec:
    """Declaration of one generated C function.

    Parameters
    ----------
    name : str
        Function name; the C symbol is ``<prefix>_<name>``.
    build : callable or None
        ``build(model: RobotModel) -> casadi.Function`` (None for a Newton function).
    args : tuple of ArgSpec
        Public inputs in C order.
    outputs : tuple of OutputSpec
        Public outputs in C order (after the inputs).
    checks : tuple of StatusCheck
        Status conditions, tested in this order.
    doc : str
        One paragraph for the header (with the source equation).
    tolerance : float
        Largest accepted ``|C - Python|`` in the self-check.
    unit : str
        Unit of the compared outputs (for reports).
    reference : callable or None
        ``reference(model, inputs) -> {output name: (N, n) array}``: the Python evaluation
        used by the self-check (``inputs`` maps argument names to ``(N, ...)`` arrays; rows
        the Python model refuses may be NaN and are then skipped). None: the CasADi
        Function itself, evaluated from Python.
    check_configurations : tuple of int
        IK configurations sampled by the self-check.
    unreachable : callable or None
        ``unreachable(model) -> {arg name: value}``: arguments that must give
        ``GT_UNREACHABLE`` (the other arguments come from a valid sample).
    relative_tolerance : float
        Also accepted: ``|C - Python| <= relative_tolerance |Python|`` (0: absolute only).
    newton : NewtonLoop or None
        For a function solved by Newton's method: the loop (``build`` is then unused).
    kind : str
        Robot kind the function belongs to (see :data:`ROBOT_KINDS`).
    """

    name: str
    build: Callable[[RobotModel], ca.Function] | None
    args: tuple[ArgSpec, ...]
    outputs: tuple[OutputSpec, ...]
    checks: tuple[StatusCheck, ...] = ()
    doc: str = ""
    tolerance: float = 1e-12
    unit: str = ""
    reference: Callable[[RobotModel, Mapping[str, np.ndarray]], dict[str, np.ndarray]] | None = field(
        default=None, compare=False
    )
    check_configurations: tuple[int, ...] = (0,)
    unreachable: Callable[[RobotModel], dict[str, np.ndarray]] | None = field(default=None, compare=False)
    relative_tolerance: float = 0.0
    newton: NewtonLoop | None = None
    kind: str = "three_link"


# ----------------------------------------------------------------------------- 3-link references
def _by_configuration(inputs: Mapping[str, np.ndarray], evaluate: Callable[[np.ndarray, int], np.ndarray]) -> np.ndarray:
    """Evaluate ``evaluate(rows, configuration)`` per configuration group; rows in input order."""
    conf = np.asarray(inputs["configuration"], dtype=int)
    out = None
    for c in np.unique(conf):
        rows = np.flatnonzero(conf == c)
        val = np.asarray(evaluate(rows, int(c)))
        val = val.reshape(len(rows), -1)
        if out is None:
            out = np.empty((conf.size, val.shape[1]))
        out[rows] = val
    return out


def _per_configuration(output: str, method: Callable[[RobotModel], Callable[..., np.ndarray]], names: tuple[str, ...]):
    """Reference ``{output: method(model)(*inputs[names], configuration)}``, per configuration group."""

    def reference(model: RobotModel, inputs: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
        cols = [inputs[k] for k in names]
        return {output: _by_configuration(inputs, lambda r, c: method(model)(*[x[r] for x in cols], c))}

    return reference


def _ref_fk(model: RobotModel, inputs: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    q, sol = inputs["q"], np.asarray(inputs["solution"], dtype=int)
    out = np.empty((q.shape[0], 3))
    for s in (1, -1):
        rows = np.flatnonzero(sol == s)
        if rows.size:
            out[rows] = np.reshape(model.kinematics.fk(q[rows], s), (rows.size, 3))
    return {"T": out}


def _far_pose(model: RobotModel) -> dict[str, np.ndarray]:
    """A TCP position 10 m beyond the workspace box: no arm reaches it."""
    return {"T": model.kinematics.workspace_bounds()[:, 1] + 10.0}


def _far_carts(model: RobotModel) -> dict[str, np.ndarray]:
    """Cart positions so far apart that link spheres 1 and 2 cannot meet."""
    span = 2.0 * float(np.max(model.kinematics.L)) + float(np.ptp(model.kinematics.As)) + 1.0
    return {"q": np.array([-span, 0.0, span])}


def _with_status(model: RobotModel, name: str, inputs: list[tuple[str, int]], body: Callable[..., ca.SX]) -> ca.Function:
    """A Function ``name(inputs...) -> (out, disc, cos_min)``: ``body`` plus the Jacobian's status outputs.

    ``body(**symbols)`` returns the published expression (by calling the model's own
    CasADi Functions symbolically); ``disc`` and ``cos_min`` come from
    :attr:`GantryTau3Kinematics.jacobian_function` at the same ``T`` and ``s``.
    """
    syms = {n: ca.SX.sym(n, k) for n, k in inputs}
    out = body(**syms)
    _, _, _, disc, cos_min = model.kinematics.jacobian_function(syms["T"], syms["s"])
    return ca.Function(name, list(syms.values()), [out, disc, cos_min], list(syms), ["out", "disc", "cos_min"])


def _acceleration_function(m: RobotModel) -> ca.Function:
    return _with_status(
        m, "acceleration", [("T", 3), ("T_dot", 3), ("q_ddot", 3), ("s", 3)],
        lambda T, T_dot, q_ddot, s: m.kinematics.acceleration_function(T, T_dot, q_ddot, s),
    )


def _gravity_function(m: RobotModel) -> ca.Function:
    zero = ca.DM.zeros(3)
    return _with_status(m, "gravity", [("T", 3), ("s", 3)], lambda T, s: m.dynamics.inverse_dynamics_function(T, zero, zero, s)[0])


_T = ArgSpec("T", "vector", "T", "TCP position [m], (x, y, z)")
_CONF = ArgSpec(
    "configuration",
    "configuration",
    "s",
    "IK configuration 0-7: bit i set = arm i+1 takes the + root (0 = nominal assembly)",
)
_UNREACHABLE = StatusCheck("disc", ">=", "0.0", "GT_UNREACHABLE")
_SINGULAR = StatusCheck("cos_min", ">=", "SINGULARITY_TOLERANCE", "GT_SINGULAR")
_T_DOT = ArgSpec("T_dot", "vector", "T_dot", "TCP velocity [m/s]")


def _pose_function(
    name: str,
    build: Callable[[RobotModel], ca.Function],
    extra: tuple[ArgSpec, ...],
    output: OutputSpec,
    doc: str,
    tolerance: float,
    unit: str,
    method: Callable[[RobotModel], Callable[..., np.ndarray]],
    relative_tolerance: float = 0.0,
) -> FunctionSpec:
    """Declaration of a 3-link function of ``(T, extra..., configuration)`` that needs the Jacobian.

    Status ``GT_UNREACHABLE`` / ``GT_SINGULAR`` from the Jacobian's outputs; checked against
    ``method(model)(T, extra..., configuration)``; a far pose must be unreachable.
    """
    return FunctionSpec(
        name=name,
        build=build,
        args=(_T, *extra, _CONF),
        outputs=(output,),
        checks=(_UNREACHABLE, _SINGULAR),
        doc=doc,
        tolerance=tolerance,
        relative_tolerance=relative_tolerance,
        unit=unit,
        reference=_per_configuration(output.name, method, ("T", *(a.name for a in extra))),
        unreachable=_far_pose,
    )

#: The generated functions of a 3-link parameter set, by name. Entries are declarations:
#: the maths is in the model.
FUNCTION_SPECS: dict[str, FunctionSpec] = {
    "ik": FunctionSpec(
        name="ik",
        build=lambda m: m.kinematics.ik_function,
        args=(_T, _CONF),
        outputs=(OutputSpec("q", "q", "cart positions [m]"),),
        checks=(_UNREACHABLE,),
        doc="Inverse kinematics: cart positions for a TCP position (Dressler (2012), eq. 4.9).",
        tolerance=IK_TOLERANCE,
        unit="m",
        reference=_per_configuration("q", lambda m: m.kinematics.ik, ("T",)),
        check_configurations=tuple(range(8)),
        unreachable=_far_pose,
    ),
    "fk": FunctionSpec(
        name="fk",
        build=lambda m: m.kinematics.fk_function,
        args=(
            ArgSpec("q", "vector", "q", "cart positions [m]"),
            ArgSpec(
                "solution",
                "solution",
                "solution",
                "assembly: +1 = TCP on the side of the sphere-centre plane the mean guideway points to, -1 = mirror",
            ),
        ),
        outputs=(OutputSpec("T", "T", "TCP position [m]"),),
        checks=(
            StatusCheck("j", ">", "DEGENERACY_TOLERANCE", "GT_DEGENERATE"),
            StatusCheck("h2", ">=", "0.0", "GT_UNREACHABLE"),
        ),
        doc="Forward kinematics by trilateration of the three link spheres (Dressler (2012), eq. 4.9).",
        tolerance=FK_TOLERANCE,
        unit="m",
        reference=_ref_fk,
        unreachable=_far_carts,
    ),
    "jacobian": _pose_function(
        "jacobian",
        lambda m: m.kinematics.jacobian_function,
        (),
        OutputSpec("J", "J", "Jacobian J with T_dot = J q_dot, 3x3 ROW-MAJOR: J[3*r + c] (dimensionless)"),
        "Jacobian, the inverse of J^-1 of Dressler (2012), eq. 6.5.",
        JACOBIAN_TOLERANCE,
        "",
        lambda m: m.kinematics.jacobian,
    ),
    "jacobian_inverse": _pose_function(
        "jacobian_inverse",
        lambda m: m.kinematics.jacobian_function,
        (),
        OutputSpec("Jinv", "Jinv", "inverse Jacobian with q_dot = Jinv T_dot, 3x3 ROW-MAJOR: Jinv[3*r + c] (dimensionless)"),
        "Inverse Jacobian: row i is dP_i^T / (dP_i . v_i) (Dressler (2012), eq. 6.5).",
        JACOBIAN_TOLERANCE,
        "",
        lambda m: m.kinematics.jacobian_inverse,
    ),
    "acceleration": _pose_function(
        "acceleration",
        _acceleration_function,
        (_T_DOT, ArgSpec("q_ddot", "vector", "q_ddot", "cart accelerations [m/s^2]")),
        OutputSpec("T_ddot", "out", "TCP acceleration [m/s^2]"),
        "TCP acceleration from cart accelerations, T_ddot = J q_ddot - [dP]^-1 s (Dressler (2012), eq. 6.6).",
        ACCELERATION_TOLERANCE,
        "m/s^2",
        lambda m: m.kinematics.acceleration,
    ),
    "inverse_dynamics": _pose_function(
        "inverse_dynamics",
        lambda m: m.dynamics.inverse_dynamics_function,
        (_T_DOT, ArgSpec("T_ddot", "vector", "T_ddot", "TCP acceleration [m/s^2]")),
        OutputSpec("tau", "tau", "actuator (cart) forces [N]"),
        "Inverse dynamics with cart friction: actuator forces for a TCP motion (Dressler (2012), eqs. 6.7, 6.8).",
        INVERSE_DYNAMICS_TOLERANCE,
        "N",
        lambda m: m.dynamics.inverse_dynamics,
        INVERSE_DYNAMICS_RELATIVE_TOLERANCE,
    ),
    "gravity": _pose_function(
        "gravity",
        _gravity_function,
        (),
        OutputSpec("tau", "out", "actuator forces holding the robot at rest, J^T G [N]"),
        "Gravity term: actuator forces at rest (Dressler (2012), eq. 6.7 with T_dot = T_ddot = 0; Table 6.2).",
        INVERSE_DYNAMICS_TOLERANCE,
        "N",
        lambda m: m.dynamics.gravity_forces,
        INVERSE_DYNAMICS_RELATIVE_TOLERANCE,
    ),
}


# ----------------------------------------------------------------------------- six-link
def _six_step(m: RobotModel) -> ca.Function:
    from gtmodel.robots.six_link import _vec

    six = m.closure
    X, q, s = ca.SX.sym("X", 6), ca.SX.sym("q", 3), ca.SX.sym("s", 3)
    X_next, residual, disc_min = six._step_graph(X, q, s, six._p_num, ca.DM(_vec(six.R_ref)))
    return ca.Function("step", [X, q, s], [X_next, residual, disc_min], ["x", "q", "s"], ["x_next", "residual", "valid"])


def _six_start(m: RobotModel) -> ca.Function:
    from gtmodel.robots.six_link import _vec

    six = m.closure
    q, sol = ca.SX.sym("q", 3), ca.SX.sym("solution")
    X0, h2 = six._start_graph(q, sol, six._p_num, ca.DM(_vec(six.R0)))
    return ca.Function("start", [q, sol], [X0, h2], ["q", "solution"], ["x0", "h2"])


def _six_finish(m: RobotModel) -> ca.Function:
    from gtmodel.robots.six_link import _vec

    six = m.closure
    X = ca.SX.sym("X", 6)
    R = six._orientation_graph(X, ca.DM(_vec(six.R_ref)))
    return ca.Function("finish", [X], [X[:3], R], ["x"], ["T", "R"])


def _six_ik(m: RobotModel) -> ca.Function:
    six = m.closure
    T, R, s = ca.SX.sym("T", 3), ca.SX.sym("R", 3, 3), ca.SX.sym("s", 3)
    q, disc, _ = six._ik_graph(T, R, s, six._p_num)
    return ca.Function("ik", [T, R, s], [q[[0, 1, 3]], disc], ["T", "R", "s"], ["q", "disc"])


def _ref_six_fk(model: RobotModel, inputs: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    q, sol = inputs["q"], np.asarray(inputs["solution"], dtype=int)
    n = q.shape[0]
    T, R = np.full((n, 3), np.nan), np.full((n, 9), np.nan)

    def run(rows: np.ndarray, c: int, s: int) -> None:
        try:
            res = model.closure.fk_solve(q[rows], c, s)
        except ConvergenceError:
            if rows.size == 1:
                return
            half = rows.size // 2
            run(rows[:half], c, s)
            run(rows[half:], c, s)
            return
        T[rows] = res.T
        R[rows] = res.R.reshape(-1, 9)

    conf = np.asarray(inputs["configuration"], dtype=int)
    for c in np.unique(conf):
        for s in (1, -1):
            rows = np.flatnonzero((conf == c) & (sol == s))
            if rows.size:
                run(rows, int(c), s)
    return {"T": T, "R": R}


def _ref_six_ik(model: RobotModel, inputs: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    T, R = inputs["T"], inputs["R"].reshape(-1, 3, 3)
    return {"q": _by_configuration(inputs, lambda r, c: model.closure.ik(T[r], R[r], c))}


def _six_far_carts(model: RobotModel) -> dict[str, np.ndarray]:
    return {"q": np.array([-20.0, 0.0, 20.0])}


def _six_far_pose(model: RobotModel) -> dict[str, np.ndarray]:
    return {"T": np.array([50.0, 50.0, 50.0])}


_R_ARG = ArgSpec("R", "matrix", "R", "plate orientation R_T, 3x3 rotation matrix ROW-MAJOR: R[3*r + c]")

#: The generated functions of the six-link error model (D1_six_link), by name.
SIX_LINK_SPECS: dict[str, FunctionSpec] = {
    "fk": FunctionSpec(
        name="fk",
        build=None,
        args=(
            ArgSpec("q", "vector", "q", "cart positions [m]"),
            ArgSpec("configuration", "configuration", "s", "IK configuration 0-7 of the per-link IK (0 = nominal)"),
            ArgSpec("solution", "solution", "solution", "branch of the trilateration start: +1 (nominal) or -1"),
        ),
        outputs=(
            OutputSpec("T", "T", "TCP position [m]"),
            OutputSpec("R", "R", "plate orientation R_T, 3x3 ROW-MAJOR: R[3*r + c]"),
        ),
        doc=(
            "Six-link forward kinematics by Newton-Raphson on X = (T, ZYZ angles), "
            "X_{k+1} = X_k + (df_ik/dX)^-1 (q - f_ik(X_k)) (Dressler (2012), eqs. 4.14, 4.15), "
            "started from the 3-link trilateration of links 1, 2a, 3a at the nominal orientation."
        ),
        tolerance=FK_TOLERANCE,
        unit="m",
        reference=_ref_six_fk,
        unreachable=_six_far_carts,
        newton=NewtonLoop(
            size=6,
            start=_six_start,
            step=_six_step,
            finish=_six_finish,
            tolerance=_six.FK_TOLERANCE,
            float_tolerance=2e-5,
            max_iter=_six.FK_MAX_ITER,
            accept="current",
            start_checks=(StatusCheck("h2", ">=", "0.0", "GT_UNREACHABLE"),),
            residual_unit="m (max over the six links of |q_i - f_ik,ij(X)|)",
        ),
        kind="six_link",
    ),
    "ik": FunctionSpec(
        name="ik",
        build=_six_ik,
        args=(_T, _R_ARG, ArgSpec("configuration", "configuration", "s", "IK configuration 0-7 (0 = nominal)")),
        outputs=(OutputSpec("q", "q", "cart positions [m] (IK of links 1, 2a, 3a)"),),
        checks=(_UNREACHABLE,),
        doc="Six-link inverse kinematics, closed form per link (Dressler (2012), eq. 4.14).",
        tolerance=IK_TOLERANCE,
        unit="m",
        reference=_ref_six_ik,
        unreachable=_six_far_pose,
        kind="six_link",
    ),
}


# ----------------------------------------------------------------------------- F1
def _f1_ik_step(m: RobotModel) -> ca.Function:
    f1 = m.closure
    step2, step3 = f1._ik_steps
    x, T, R = ca.SX.sym("x", 5), ca.SX.sym("T", 3), ca.SX.sym("R", 3, 3)
    x2n, e2 = step2(x[0:2], T, R)
    x3n, e3 = step3(x[2:5], T, R)
    return ca.Function(
        "step", [x, T, R], [ca.vertcat(x2n, x3n), ca.mmax(ca.fabs(ca.vertcat(e2, e3)))], ["x", "T", "R"], ["x_next", "residual"]
    )


def _f1_ik_start(m: RobotModel) -> ca.Function:
    f1 = m.closure
    T, R = ca.SX.sym("T", 3), ca.SX.sym("R", 3, 3)
    q0, _ = f1.ik_start_function.expand()(T, R)
    return ca.Function("start", [T, R], [q0[[1, 3, 2, 4, 5]]], ["T", "R"], ["x0"])


def _f1_ik_warm(m: RobotModel) -> ca.Function:
    q0 = ca.SX.sym("q0", 6)
    return ca.Function("warm", [q0], [q0[[1, 3, 2, 4, 5]]], ["q0"], ["x0"])


def _f1_ik_finish(m: RobotModel) -> ca.Function:
    f1 = m.closure
    x, T, R = ca.SX.sym("x", 5), ca.SX.sym("T", 3), ca.SX.sym("R", 3, 3)
    q1, disc = f1._arm1_closed_form(T, R)
    q = ca.vertcat(q1, x[0], x[2], x[1], x[3], x[4])
    return ca.Function("finish", [x, T, R], [q, disc], ["x", "T", "R"], ["q", "disc1"])


def _f1_fk_step(m: RobotModel) -> ca.Function:
    f1 = m.closure
    x, q = ca.SX.sym("x", 12), ca.SX.sym("q", 6)
    T_n, R_n, e = f1._fk_step(x[:3], ca.reshape(x[3:], 3, 3), q)
    return ca.Function(
        "step", [x, q], [ca.vertcat(T_n, ca.vec(R_n)), ca.mmax(ca.fabs(e))], ["x", "q"], ["x_next", "residual"]
    )


def _f1_fk_start(m: RobotModel) -> ca.Function:
    f1 = m.closure
    q = ca.SX.sym("q", 6)
    T0, R0 = f1.fk_start_function.expand()(q)
    return ca.Function("start", [q], [ca.vertcat(T0, ca.vec(R0))], ["q"], ["x0"])


def _f1_fk_warm(m: RobotModel) -> ca.Function:
    T0, R0 = ca.SX.sym("T0", 3), ca.SX.sym("R0", 3, 3)
    return ca.Function("warm", [T0, R0], [ca.vertcat(T0, ca.vec(R0))], ["T0", "R0"], ["x0"])


def _f1_fk_finish(m: RobotModel) -> ca.Function:
    x = ca.SX.sym("x", 12)
    return ca.Function("finish", [x], [x[:3], ca.reshape(x[3:], 3, 3)], ["x"], ["T", "R"])


def _f1_converged(model: RobotModel, name: str, inputs: Mapping[str, np.ndarray], warm: np.ndarray) -> np.ndarray:
    """Rows on which ``F1Closure.ik``/``fk`` converge (one pass of its own chunked Newton runner).

    The public methods raise on the first failing row; this pass (the same start values and
    mapped Newton steps, column by column) tells which rows to leave out, so that the
    public method is then called once on the rest instead of bisecting around failures.
    """
    f1 = model.closure
    ok = np.zeros(len(warm), dtype=bool)
    for start in (True, False):
        rows = np.flatnonzero(warm == start)
        if not rows.size:
            continue
        n = rows.size
        if name == "ik":
            T = inputs["T"][rows].T
            Rc = f1._R_cols(inputs["R"][rows].reshape(-1, 3, 3))
            q0 = inputs["q0"][rows].T if start else f1._ik_start_mapped(n, T, Rc)[0]
            ok[rows] = f1._run_ik(_f1.IK_MAX_ITER, T, Rc, q0)[3]
        else:
            q = inputs["q"][rows].T
            if start:
                T0, R0c = inputs["T0"][rows].T, f1._R_cols(inputs["R0"][rows].reshape(-1, 3, 3))
            else:
                T0, R0c = f1._fk_start_mapped(n, q)
            ok[rows] = f1._run_fk(_f1.FK_MAX_ITER, q, T0, R0c)[4]
    return ok


def _f1_reference(model: RobotModel, inputs: Mapping[str, np.ndarray], warm: np.ndarray, name: str, evaluate) -> None:
    """Call ``evaluate(rows, start)`` (the public F1 method) on the converging rows of each start kind.

    A row the public method still refuses is isolated by bisection and left NaN.
    """

    def run(rows: np.ndarray, start: bool) -> None:
        try:
            evaluate(rows, start)
        except (ConvergenceError, UnreachablePoseError):
            if rows.size > 1:
                run(rows[: rows.size // 2], start)
                run(rows[rows.size // 2 :], start)

    ok = _f1_converged(model, name, inputs, warm)
    for start in (True, False):
        rows = np.flatnonzero((warm == start) & ok)
        if rows.size:
            run(rows, start)


def _ref_f1_ik(model: RobotModel, inputs: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    T, R = inputs["T"], inputs["R"].reshape(-1, 3, 3)
    q0 = inputs.get("q0")
    n = T.shape[0]
    out = np.full((n, 6), np.nan)
    warm = np.zeros(n, dtype=bool) if q0 is None else np.all(np.isfinite(q0), axis=1)

    def evaluate(rows: np.ndarray, start: bool) -> None:
        out[rows] = model.closure.ik(T[rows], R[rows], q0[rows] if start else None)

    _f1_reference(model, inputs, warm, "ik", evaluate)
    return {"q": out}


def _ref_f1_fk(model: RobotModel, inputs: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    q = inputs["q"]
    T0 = inputs.get("T0")
    R0 = inputs.get("R0")
    n = q.shape[0]
    T, R = np.full((n, 3), np.nan), np.full((n, 9), np.nan)
    if T0 is None or R0 is None:
        warm = np.zeros(n, dtype=bool)
    else:
        warm = np.all(np.isfinite(T0), axis=1) & np.all(np.isfinite(R0), axis=1)

    def evaluate(rows: np.ndarray, start: bool) -> None:
        if start:
            Tr, Rr = model.closure.fk(q[rows], T0[rows], R0[rows].reshape(-1, 3, 3))
        else:
            Tr, Rr = model.closure.fk(q[rows])
        T[rows] = Tr
        R[rows] = np.reshape(Rr, (-1, 9))

    _f1_reference(model, inputs, warm, "fk", evaluate)
    return {"T": T, "R": R}


def _f1_far_pose(model: RobotModel) -> dict[str, np.ndarray]:
    return {"T": np.array([50.0, 50.0, 50.0])}


#: The generated functions of the F1 model, by name.
F1_SPECS: dict[str, FunctionSpec] = {
    "ik": FunctionSpec(
        name="ik",
        build=None,
        args=(
            _T,
            ArgSpec("R", "matrix", "R", "plate orientation R_T, 3x3 rotation matrix ROW-MAJOR: R[3*r + c]"),
            ArgSpec(
                "q0", "vector", "q0", "start value [m, rad] (the previous sample in the control loop); "
                "NULL = continuation from the home pose (about 10 us, 44,000 instructions)", optional=True,
            ),
        ),
        outputs=(OutputSpec("q", "q", "actuator values (q1, q2, q3 [m], q4, q5, q6 [rad])"),),
        checks=(StatusCheck("disc1", ">=", "0.0", "GT_UNREACHABLE"),),
        doc=(
            "F1 inverse kinematics: arm 1 in closed form (eq. 4.20), arms 2 and 3 by Newton's method on "
            "e = L^2 - ||B - A(Q)||^2 per arm (Dressler (2012), eqs. 4.27-4.29), warm-started from q0."
        ),
        tolerance=IK_TOLERANCE,
        unit="m, rad",
        reference=_ref_f1_ik,
        unreachable=_f1_far_pose,
        newton=NewtonLoop(
            size=5,
            start=_f1_ik_start,
            step=_f1_ik_step,
            finish=_f1_ik_finish,
            tolerance=_f1.IK_TOLERANCE,
            float_tolerance=1e-4,
            max_iter=_f1.IK_MAX_ITER,
            accept="current",
            check_every=_f1._CHUNK,
            warm=("q0",),
            warm_start=_f1_ik_warm,
            residual_unit="m^2 (max |L^2 - ||B - A||^2| over the links of arms 2, 3)",
        ),
        kind="f1",
    ),
    "fk": FunctionSpec(
        name="fk",
        build=None,
        args=(
            ArgSpec("q", "vector", "q", "actuator values (q1, q2, q3 [m], q4, q5, q6 [rad])"),
            ArgSpec("T0", "vector", "T0", "start position [m] (the previous sample); NULL = 5-DOF start", optional=True),
            ArgSpec("R0", "matrix", "R0", "start orientation, ROW-MAJOR 3x3; NULL = 5-DOF start", optional=True),
        ),
        outputs=(
            OutputSpec("T", "T", "TCP position [m]"),
            OutputSpec("R", "R", "plate orientation R_T, 3x3 ROW-MAJOR: R[3*r + c]"),
        ),
        doc=(
            "F1 forward kinematics by Newton's method on the link lengths with the Stewart-platform inverse "
            "Jacobian (Dressler (2012), eqs. 4.30-4.31), started from (T0, R0) or, if they are NULL, from the "
            "implicit 5-DOF solution continued from the home pose (eqs. 4.25-4.26, 4.32-4.33; about 11 us, 61,000 instructions)."
        ),
        tolerance=FK_TOLERANCE,
        unit="m",
        reference=_ref_f1_fk,
        newton=NewtonLoop(
            size=12,
            start=_f1_fk_start,
            step=_f1_fk_step,
            finish=_f1_fk_finish,
            tolerance=_f1.FK_TOLERANCE,
            float_tolerance=2e-5,
            max_iter=_f1.FK_MAX_ITER,
            accept="current",
            check_every=_f1._CHUNK,
            warm=("T0", "R0"),
            warm_start=_f1_fk_warm,
            residual_unit="m (max | ||B - A|| - L | over the six links)",
        ),
        kind="f1",
    ),
}

#: Tables of declarations per robot kind.
SPECS_BY_KIND: dict[str, dict[str, FunctionSpec]] = {
    "three_link": FUNCTION_SPECS,
    "six_link": SIX_LINK_SPECS,
    "f1": F1_SPECS,
}

#: Functions generated by default for a 3-link parameter set.
DEFAULT_FUNCTIONS: tuple[str, ...] = ("ik", "fk", "jacobian", "jacobian_inverse", "acceleration", "inverse_dynamics", "gravity")


def default_functions(kind: str) -> tuple[str, ...]:
    """Functions generated by default for a robot kind.

    Parameters
    ----------
    kind : str
        One of :data:`ROBOT_KINDS`.

    Returns
    -------
    tuple of str
        Every declared function of that kind.
    """
    return DEFAULT_FUNCTIONS if kind == "three_link" else tuple(SPECS_BY_KIND[kind])


#: Header macros (without prefix) available to :attr:`StatusCheck.threshold`.
THRESHOLD_MACROS: dict[str, float] = {
    "SINGULARITY_TOLERANCE": SINGULARITY_TOLERANCE,
    "DEGENERACY_TOLERANCE": DEGENERACY_TOLERANCE,
}
