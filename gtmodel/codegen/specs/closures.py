"""Declarations of the C functions of the closure models: six-link error model and F1.

Every CasADi Function comes from the model's public graphs
(:meth:`SixLinkClosure.graphs <gtmodel.robots.six_link.SixLinkClosure.graphs>`,
:meth:`F1Closure.graphs <gtmodel.robots.f1.F1Closure.graphs>`); the self-check compares
with the public numeric methods.
"""

from __future__ import annotations

from typing import Mapping

import casadi as ca
import numpy as np

from gtmodel.codegen.declarations import FK_TOLERANCE, IK_TOLERANCE, ArgSpec, FunctionSpec, NewtonLoop, OutputSpec, StatusCheck
from gtmodel.codegen.robot import RobotModel
from gtmodel.codegen.specs.three_link import T_ARG, UNREACHABLE, by_configuration
from gtmodel.errors import ConvergenceError, UnreachablePoseError
from gtmodel.robots import f1 as f1_model
from gtmodel.robots import six_link as six_link_model

__all__ = ["SIX_LINK_SPECS", "F1_SPECS"]


# ----------------------------------------------------------------------------- six-link
def _six_step(m: RobotModel) -> ca.Function:
    return m.closure.graphs()["fk_step"]


def _six_start(m: RobotModel) -> ca.Function:
    return m.closure.graphs()["fk_start"]


def _six_finish(m: RobotModel) -> ca.Function:
    orientation = m.closure.graphs()["orientation"]
    X = ca.SX.sym("X", 6)
    return ca.Function("finish", [X], [X[:3], orientation(X)], ["x"], ["T", "R"])


def _six_ik(m: RobotModel) -> ca.Function:
    ik_links = m.closure.graphs()["ik_links"]
    T, R, s = ca.SX.sym("T", 3), ca.SX.sym("R", 3, 3), ca.SX.sym("s", 3)
    q, disc, _ = ik_links(T, R, s)
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
    return {"q": by_configuration(inputs, lambda r, c: model.closure.ik(T[r], R[r], c))}


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
            tolerance=six_link_model.FK_TOLERANCE,
            float_tolerance=2e-5,
            max_iter=six_link_model.FK_MAX_ITER,
            accept="current",
            start_checks=(StatusCheck("h2", ">=", "0.0", "GT_UNREACHABLE"),),
            residual_unit="m (max over the six links of |q_i - f_ik,ij(X)|)",
        ),
        kind="six_link",
    ),
    "ik": FunctionSpec(
        name="ik",
        build=_six_ik,
        args=(T_ARG, _R_ARG, ArgSpec("configuration", "configuration", "s", "IK configuration 0-7 (0 = nominal)")),
        outputs=(OutputSpec("q", "q", "cart positions [m] (IK of links 1, 2a, 3a)"),),
        checks=(UNREACHABLE,),
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
    return m.closure.graphs()["ik_step"]


def _f1_ik_start(m: RobotModel) -> ca.Function:
    f1 = m.closure
    T, R = ca.SX.sym("T", 3), ca.SX.sym("R", 3, 3)
    q0, _ = f1.graphs()["ik_start"].expand()(T, R)
    return ca.Function("start", [T, R], [q0[[1, 3, 2, 4, 5]]], ["T", "R"], ["x0"])


def _f1_ik_warm(m: RobotModel) -> ca.Function:
    q0 = ca.SX.sym("q0", 6)
    return ca.Function("warm", [q0], [q0[[1, 3, 2, 4, 5]]], ["q0"], ["x0"])


def _f1_ik_finish(m: RobotModel) -> ca.Function:
    arm1 = m.closure.graphs()["ik_arm1"]
    x, T, R = ca.SX.sym("x", 5), ca.SX.sym("T", 3), ca.SX.sym("R", 3, 3)
    q1, disc = arm1(T, R)
    q = ca.vertcat(q1, x[0], x[2], x[1], x[3], x[4])
    return ca.Function("finish", [x, T, R], [q, disc], ["x", "T", "R"], ["q", "disc1"])


def _f1_fk_step(m: RobotModel) -> ca.Function:
    return m.closure.graphs()["fk_step"]


def _f1_fk_start(m: RobotModel) -> ca.Function:
    f1 = m.closure
    q = ca.SX.sym("q", 6)
    T0, R0 = f1.graphs()["fk_start"].expand()(q)
    return ca.Function("start", [q], [ca.vertcat(T0, ca.vec(R0))], ["q"], ["x0"])


def _f1_fk_warm(m: RobotModel) -> ca.Function:
    T0, R0 = ca.SX.sym("T0", 3), ca.SX.sym("R0", 3, 3)
    return ca.Function("warm", [T0, R0], [ca.vertcat(T0, ca.vec(R0))], ["T0", "R0"], ["x0"])


def _f1_fk_finish(m: RobotModel) -> ca.Function:
    x = ca.SX.sym("x", 12)
    return ca.Function("finish", [x], [x[:3], ca.reshape(x[3:], 3, 3)], ["x"], ["T", "R"])


def _f1_converged(model: RobotModel, name: str, inputs: Mapping[str, np.ndarray], warm: np.ndarray) -> np.ndarray:
    """Rows on which ``F1Closure.ik``/``fk`` converge (``F1Closure.ik_converged``/``fk_converged``).

    The public methods raise on the first failing row; this pass (the same start values and
    Newton steps) tells which rows to leave out, so that the public method is then called
    once on the rest instead of bisecting around failures.
    """
    f1 = model.closure
    ok = np.zeros(len(warm), dtype=bool)
    for start in (True, False):
        rows = np.flatnonzero(warm == start)
        if not rows.size:
            continue
        if name == "ik":
            R = inputs["R"][rows].reshape(-1, 3, 3)
            ok[rows] = f1.ik_converged(inputs["T"][rows], R, inputs["q0"][rows] if start else None)
        elif start:
            ok[rows] = f1.fk_converged(inputs["q"][rows], inputs["T0"][rows], inputs["R0"][rows].reshape(-1, 3, 3))
        else:
            ok[rows] = f1.fk_converged(inputs["q"][rows])
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
            T_ARG,
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
            tolerance=f1_model.IK_TOLERANCE,
            float_tolerance=1e-4,
            max_iter=f1_model.IK_MAX_ITER,
            accept="current",
            check_every=f1_model.NEWTON_CHUNK,
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
            tolerance=f1_model.FK_TOLERANCE,
            float_tolerance=2e-5,
            max_iter=f1_model.FK_MAX_ITER,
            accept="current",
            check_every=f1_model.NEWTON_CHUNK,
            warm=("T0", "R0"),
            warm_start=_f1_fk_warm,
            residual_unit="m (max | ||B - A|| - L | over the six links)",
        ),
        kind="f1",
    ),
}
