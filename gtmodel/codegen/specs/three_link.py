"""Declarations of the C functions of a 3-link parameter set (IK, FK, Jacobians, dynamics)."""

from __future__ import annotations

from typing import Callable, Mapping

import casadi as ca
import numpy as np

from gtmodel.codegen.declarations import (
    ACCELERATION_TOLERANCE,
    FK_TOLERANCE,
    IK_TOLERANCE,
    INVERSE_DYNAMICS_RELATIVE_TOLERANCE,
    INVERSE_DYNAMICS_TOLERANCE,
    JACOBIAN_TOLERANCE,
    ArgSpec,
    FunctionSpec,
    OutputSpec,
    StatusCheck,
)
from gtmodel.codegen.robot import RobotModel

__all__ = ["FUNCTION_SPECS", "DEFAULT_FUNCTIONS", "by_configuration", "T_ARG", "UNREACHABLE"]

# ----------------------------------------------------------------------------- 3-link references
def by_configuration(inputs: Mapping[str, np.ndarray], evaluate: Callable[[np.ndarray, int], np.ndarray]) -> np.ndarray:
    """Evaluate ``evaluate(rows, configuration)`` per configuration group; rows in input order.

    Parameters
    ----------
    inputs : mapping of str to numpy.ndarray
        Sampled inputs of a function, with the ``"configuration"`` column (N,).
    evaluate : callable
        ``evaluate(rows, configuration) -> array`` of the reference for those rows.

    Returns
    -------
    numpy.ndarray, shape (N, n)
        The references, rows in input order.
    """
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
        return {output: by_configuration(inputs, lambda r, c: method(model)(*[x[r] for x in cols], c))}

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


T_ARG = ArgSpec("T", "vector", "T", "TCP position [m], (x, y, z)")
_CONF = ArgSpec(
    "configuration",
    "configuration",
    "s",
    "IK configuration 0-7: bit i set = arm i+1 takes the + root (0 = nominal assembly)",
)
UNREACHABLE = StatusCheck("disc", ">=", "0.0", "GT_UNREACHABLE")
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
        args=(T_ARG, *extra, _CONF),
        outputs=(output,),
        checks=(UNREACHABLE, _SINGULAR),
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
        args=(T_ARG, _CONF),
        outputs=(OutputSpec("q", "q", "cart positions [m]"),),
        checks=(UNREACHABLE,),
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


#: Functions generated by default for a 3-link parameter set.
DEFAULT_FUNCTIONS: tuple[str, ...] = ("ik", "fk", "jacobian", "jacobian_inverse", "acceleration", "inverse_dynamics", "gravity")
