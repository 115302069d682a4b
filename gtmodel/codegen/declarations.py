"""The declaration types of generated C functions, the status codes and the check tolerances.

Each generated C function is described by a :class:`FunctionSpec`: which CasADi Function
it wraps (built from the robot model's public graphs, never written by hand), how its
public C arguments map onto the CasADi inputs, which CasADi outputs are published, which
outputs decide the status code, and how the self-check compares it with the Python
evaluation. Functions solved by Newton's method carry a :class:`NewtonLoop` instead of one
Function: a start Function, a one-step Function and a finishing Function; the C wrapper
runs the step in a loop bounded by a maximum iteration count with an early exit on
convergence. The tables of declarations per robot kind are in
:mod:`gtmodel.codegen.specs`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable, Mapping

import casadi as ca
import numpy as np

from gtmodel.robots.kinematics import DEGENERACY_TOLERANCE, SINGULARITY_TOLERANCE

if TYPE_CHECKING:  # annotations only
    from gtmodel.codegen.robot import RobotModel

__all__ = [
    "CONTROLLER_KIND",
    "STATUS_CODES",
    "IK_TOLERANCE",
    "FK_TOLERANCE",
    "JACOBIAN_TOLERANCE",
    "ACCELERATION_TOLERANCE",
    "INVERSE_DYNAMICS_TOLERANCE",
    "INVERSE_DYNAMICS_RELATIVE_TOLERANCE",
    "THRESHOLD_MACROS",
    "ArgSpec",
    "OutputSpec",
    "StatusCheck",
    "NewtonLoop",
    "FunctionSpec",
]

#: Status codes returned by every generated C function (also ``#define``\ d in the header).
#: ``FunctionSpec.kind`` of the controller declarations (robot-independent functions).
CONTROLLER_KIND = "controller"

STATUS_CODES: dict[str, tuple[int, str]] = {
    "GT_OK": (0, "success; outputs written"),
    "GT_UNREACHABLE": (1, "pose unreachable (an arm cannot reach T, or the link spheres do not meet); outputs untouched"),
    "GT_SINGULAR": (2, "singular configuration (a link perpendicular to its guideway); outputs untouched"),
    "GT_DEGENERATE": (3, "degenerate forward kinematics (collinear sphere centres); outputs untouched"),
    "GT_BAD_ARGUMENT": (4, "NULL pointer, non-finite input or invalid configuration/solution; outputs untouched"),
    "GT_NUMERIC_ERROR": (5, "evaluation failed or produced a non-finite value; outputs untouched"),
    "GT_NOT_CONVERGED": (6, "Newton's method did not converge within the iteration limit; outputs untouched"),
    "GT_INFEASIBLE": (7, "no motion along the path satisfies the limits (re-timing); outputs untouched"),
    "GT_TOO_LARGE": (8, "more grid points than the size fixed at generation (re-timing N_MAX); outputs untouched"),
    "GT_MEMORY_RESET": (9, "a loop controller's memory was non-finite or absurd and was reset to the reference's; outputs written from it"),
    "GT_MEASUREMENT_REJECTED": (10, "a loop controller's measurement was non-finite or absurd; outputs written from the state its memory predicts"),
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

#: Header macros (without prefix) available to :attr:`StatusCheck.threshold`.
THRESHOLD_MACROS: dict[str, float] = {
    "SINGULARITY_TOLERANCE": SINGULARITY_TOLERANCE,
    "DEGENERACY_TOLERANCE": DEGENERACY_TOLERANCE,
}


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
        IK root signs; ``"solution"``: ``int`` +1/-1 passed as a scalar; ``"index"``: ``int``
        (any value, e.g. a cycle count) passed as a scalar (exact in double precision).
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


#: Single-precision code: accepted |C - Python| <= FLOAT_RELATIVE_TOLERANCE (1 + |Python|)
#: (the default of :attr:`FunctionSpec.float_tolerance`).
FLOAT_RELATIVE_TOLERANCE = 1e-4


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
    float_tolerance : float
        Single-precision code: the accepted ``|C - Python| <= float_tolerance (1 + |Python|)``
        (default :data:`FLOAT_RELATIVE_TOLERANCE`; an MPC's from its QP's conditioning).
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
    float_tolerance: float = FLOAT_RELATIVE_TOLERANCE

