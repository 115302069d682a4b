"""Declarations of the C functions generated from the CasADi model.

Each generated C function is described by a :class:`FunctionSpec`: which CasADi Function
it wraps (built from the robot model, never written by hand), how its public C arguments
map onto the CasADi inputs, which CasADi outputs are published, which outputs decide the
status code, and how the self-check compares it with the Python evaluation. Adding a
function to the generated library is one more entry in :data:`FUNCTION_SPECS`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable, Mapping

import casadi as ca
import numpy as np

from gtmodel.robots.kinematics import DEGENERACY_TOLERANCE, SINGULARITY_TOLERANCE, GantryTau3Kinematics
from gtmodel.robots.parameters import RobotParameters

__all__ = [
    "STATUS_CODES",
    "IK_TOLERANCE",
    "FK_TOLERANCE",
    "JACOBIAN_TOLERANCE",
    "INVERSE_DYNAMICS_TOLERANCE",
    "RobotModel",
    "ArgSpec",
    "OutputSpec",
    "StatusCheck",
    "FunctionSpec",
    "FUNCTION_SPECS",
    "DEFAULT_FUNCTIONS",
]

#: Status codes returned by every generated C function (also ``#define``\ d in the header).
STATUS_CODES: dict[str, tuple[int, str]] = {
    "GT_OK": (0, "success; outputs written"),
    "GT_UNREACHABLE": (1, "pose unreachable (an arm cannot reach T, or the link spheres do not meet); outputs untouched"),
    "GT_SINGULAR": (2, "singular configuration (a link perpendicular to its guideway); outputs untouched"),
    "GT_DEGENERATE": (3, "degenerate forward kinematics (collinear sphere centres); outputs untouched"),
    "GT_BAD_ARGUMENT": (4, "NULL pointer, non-finite input or invalid configuration/solution; outputs untouched"),
    "GT_NUMERIC_ERROR": (5, "evaluation failed or produced a non-finite value; outputs untouched"),
}

#: Largest accepted |C - Python| of the inverse kinematics [m].
IK_TOLERANCE = 1e-12
#: Largest accepted |C - Python| of the forward kinematics [m].
FK_TOLERANCE = 1e-12
#: Largest accepted |C - Python| of a Jacobian element (dimensionless).
JACOBIAN_TOLERANCE = 1e-12
#: Largest accepted |C - Python| of an actuator force [N].
INVERSE_DYNAMICS_TOLERANCE = 1e-9


class RobotModel:
    """The symbolic robot model the C functions are generated from (kinematics, dynamics).

    Parameters
    ----------
    parameters : RobotParameters
        The parameter set (embedded as constants in the generated code).
    friction : str, optional
        Form of the friction sign for the dynamics (``"exact"``, ``"tanh"``, ``"piecewise"``).
    """

    def __init__(self, parameters: RobotParameters, friction: str = "exact") -> None:
        self.parameters = parameters
        self.friction = friction

    @cached_property
    def kinematics(self) -> GantryTau3Kinematics:
        """The 3-link kinematics (:class:`GantryTau3Kinematics`)."""
        return GantryTau3Kinematics(self.parameters)

    @cached_property
    def dynamics(self):
        """The rigid-body dynamics with friction (``GantryTau3Dynamics``)."""
        from gtmodel.robots.dynamics import GantryTau3Dynamics  # imported late: optional layer

        return GantryTau3Dynamics(self.parameters, friction=self.friction)


@dataclass(frozen=True)
class ArgSpec:
    """One public argument of a generated C function.

    Parameters
    ----------
    name : str
        C parameter name.
    kind : {"vector", "configuration", "solution"}
        ``"vector"``: ``const double name[n]`` passed as the CasADi input of the same size;
        ``"configuration"``: ``int`` 0-7 turned into the three IK root signs;
        ``"solution"``: ``int`` +1/-1 passed as a scalar.
    casadi_input : str
        Name of the CasADi input it feeds.
    doc : str
        Meaning and unit, for the header.
    """

    name: str
    kind: str
    casadi_input: str
    doc: str


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
class FunctionSpec:
    """Declaration of one generated C function.

    Parameters
    ----------
    name : str
        Function name; the C symbol is ``<prefix>_<name>``.
    build : callable
        ``build(model: RobotModel) -> casadi.Function``.
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
        used by the self-check (``inputs`` maps argument names to ``(N, ...)`` arrays).
        None: the CasADi Function itself, evaluated from Python.
    check_configurations : tuple of int
        IK configurations sampled by the self-check.
    unreachable : callable or None
        ``unreachable(model) -> {arg name: value}``: arguments that must give
        ``GT_UNREACHABLE`` (the other arguments come from a valid sample).
    """

    name: str
    build: Callable[[RobotModel], ca.Function]
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


# ----------------------------------------------------------------------------- references
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


def _ref_ik(model: RobotModel, inputs: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    T = inputs["T"]
    return {"q": _by_configuration(inputs, lambda r, c: model.kinematics.ik(T[r], c))}


def _ref_fk(model: RobotModel, inputs: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    q, sol = inputs["q"], np.asarray(inputs["solution"], dtype=int)
    out = np.empty((q.shape[0], 3))
    for s in (1, -1):
        rows = np.flatnonzero(sol == s)
        if rows.size:
            out[rows] = np.reshape(model.kinematics.fk(q[rows], s), (rows.size, 3))
    return {"T": out}


def _ref_jacobian(model: RobotModel, inputs: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    T = inputs["T"]
    return {"J": _by_configuration(inputs, lambda r, c: model.kinematics.jacobian(T[r], c))}


def _ref_inverse_dynamics(model: RobotModel, inputs: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    T, Td, Tdd = inputs["T"], inputs["T_dot"], inputs["T_ddot"]
    return {"tau": _by_configuration(inputs, lambda r, c: model.dynamics.inverse_dynamics(T[r], Td[r], Tdd[r], c))}


def _far_pose(model: RobotModel) -> dict[str, np.ndarray]:
    """A TCP position 10 m beyond the workspace box: no arm reaches it."""
    return {"T": model.kinematics.workspace_bounds()[:, 1] + 10.0}


def _far_carts(model: RobotModel) -> dict[str, np.ndarray]:
    """Cart positions so far apart that link spheres 1 and 2 cannot meet."""
    span = 2.0 * float(np.max(model.kinematics.L)) + float(np.ptp(model.kinematics.As)) + 1.0
    return {"q": np.array([-span, 0.0, span])}


_T = ArgSpec("T", "vector", "T", "TCP position [m], (x, y, z)")
_CONF = ArgSpec(
    "configuration",
    "configuration",
    "s",
    "IK configuration 0-7: bit i set = arm i+1 takes the + root (0 = nominal assembly)",
)
_UNREACHABLE = StatusCheck("disc", ">=", "0.0", "GT_UNREACHABLE")
_SINGULAR = StatusCheck("cos_min", ">=", "SINGULARITY_TOLERANCE", "GT_SINGULAR")

#: The generated functions, by name. Entries are declarations: the maths is in the model.
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
        reference=_ref_ik,
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
    "jacobian": FunctionSpec(
        name="jacobian",
        build=lambda m: m.kinematics.jacobian_function,
        args=(_T, _CONF),
        outputs=(OutputSpec("J", "J", "Jacobian J with T_dot = J q_dot, 3x3 ROW-MAJOR: J[3*r + c] (dimensionless)"),),
        checks=(_UNREACHABLE, _SINGULAR),
        doc="Jacobian, the inverse of J^-1 of Dressler (2012), eq. 6.5.",
        tolerance=JACOBIAN_TOLERANCE,
        unit="",
        reference=_ref_jacobian,
        unreachable=_far_pose,
    ),
    "inverse_dynamics": FunctionSpec(
        name="inverse_dynamics",
        build=lambda m: m.dynamics.inverse_dynamics_function,
        args=(
            _T,
            ArgSpec("T_dot", "vector", "T_dot", "TCP velocity [m/s]"),
            ArgSpec("T_ddot", "vector", "T_ddot", "TCP acceleration [m/s^2]"),
            _CONF,
        ),
        outputs=(OutputSpec("tau", "tau", "actuator (cart) forces [N]"),),
        checks=(_UNREACHABLE, _SINGULAR),
        doc="Inverse dynamics with cart friction: actuator forces for a TCP motion (Dressler (2012), eqs. 6.7, 6.8).",
        tolerance=INVERSE_DYNAMICS_TOLERANCE,
        unit="N",
        reference=_ref_inverse_dynamics,
        unreachable=_far_pose,
    ),
}

#: Functions generated by default.
DEFAULT_FUNCTIONS: tuple[str, ...] = ("ik", "fk", "jacobian", "inverse_dynamics")

#: Header macros (without prefix) available to :attr:`StatusCheck.threshold`.
THRESHOLD_MACROS: dict[str, float] = {
    "SINGULARITY_TOLERANCE": SINGULARITY_TOLERANCE,
    "DEGENERACY_TOLERANCE": DEGENERACY_TOLERANCE,
}
