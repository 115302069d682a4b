"""F1-type 6-DOF Gantry-Tau kinematics (Dressler (2012), eqs. 4.16-4.33) and the F1 parameter set.

Independent references used here: the figures of Table 5.5 and ch. 5.5 in
``shared/reference/gantry_tau_D1_F1.toml`` (parameter values, parameters per arm, grid
size); IK and FK check each other (two separate Newton solves from different starts);
arm 1 against its closed form written out in NumPy; the FK against the interface's
generic ``fk_newton`` (a CasADi rootfinder on the squared closure residuals); the AD
Jacobians against central differences and the Stewart-platform rows of eq. 4.31 written
out in NumPy; the default FK start against a twice finer continuation.
"""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import ConvergenceError, InputError, ParameterError, UnreachablePoseError
from gtmodel.robots.closure import quaternion_to_rotation, rotation_to_quaternion, rotation_vector_to_rotation
from gtmodel.robots.f1 import F1_FIXED_FOR_IDENTIFIABILITY, START_SUBSTEPS, F1Closure, load_f1

from tests.conftest import SHARED_REFERENCE

#: IK -> FK round trip over the grid [m] and [rad] (issue requirement).
ROUND_TRIP_TOL = 1e-10
#: Closure residuals ||A - B||^2 - L^2 at IK solutions [m^2].
CLOSURE_TOL = 1e-12
#: Arm-1 IK against its closed form [m].
CLOSED_FORM_TOL = 1e-12
#: FK against the generic fk_newton: its own stop test is max |r| <= 1e-11 m^2, i.e.
#: ~3e-12 m in link length, times an error amplification of at most 262 rad/m [m, rad].
GENERIC_FK_TOL = 1e-9
#: Default FK start against a finer continuation: both converge to FK_TOLERANCE (1e-13 m
#: in link length), times the amplification of at most 262 rad/m [m, rad].
CONTINUATION_TOL = 1e-10
#: AD Jacobians vs central differences with step FD_STEP: truncation ~h^2 * |d3 L| and
#: rounding ~eps * L / h, both below 1e-9 [m/m, m/rad].
FD_STEP = 1e-6
FD_TOL = 1e-8
#: AD pose Jacobian vs the Stewart rows written out (same formula, rounding only).
STEWART_TOL = 1e-12
#: Printed values of Table 5.5 vs the loaded ones (mm -> m is exact to rounding).
TABLE_TOL = 1e-12
#: The grid of ch. 5.5 had 1347 poses; the limits the thesis used are not given, so the
#: assumed ones may differ by this fraction.
GRID_SIZE_REL_TOL = 0.15
#: Newton steps a warm start from the previous sample may take (1 mm, 1 mrad apart).
WARM_START_MAX_ITER = 4
#: Finer continuation for the nominal-mode check (sub-steps from home).
FINE_SUBSTEPS = 2 * START_SUBSTEPS


@pytest.fixture(scope="module")
def ref() -> dict:
    return tomllib.loads((SHARED_REFERENCE / "gantry_tau_D1_F1.toml").read_text())["F1"]


@pytest.fixture(scope="module")
def model() -> F1Closure:
    return load_f1()


@pytest.fixture(scope="module")
def grid(model):
    """The 6-D workspace grid of ch. 5.5 (0.25 m, 10 deg) with its actuator values."""
    return model.workspace_grid(0.25, 10.0, return_q=True)


def _angle(Ra: np.ndarray, Rb: np.ndarray) -> np.ndarray:
    """Rotation angle of Ra Rb^T [rad] (stable for tiny angles: from the skew part)."""
    M = np.einsum("nij,nkj->nik", Ra, Rb)
    vee = np.stack([M[:, 2, 1] - M[:, 1, 2], M[:, 0, 2] - M[:, 2, 0], M[:, 1, 0] - M[:, 0, 1]], axis=1)
    return np.arcsin(np.clip(np.linalg.norm(vee, axis=1) / 2, 0, 1))


def _value(model: F1Closure, name: str) -> float:
    return float(model.parameter_vector()[model.parameter_names().index(name)])


# ------------------------------------------------------------------ parameter set
def test_parameter_file_is_table_5_5_in_si_units(model, ref):
    """Loaded values equal Table 5.5 (mm) divided by 1000; quaternions are the printed ones normalised."""
    mm = 1e-3
    links = ref["links"]
    expected = {}  # parameter name -> Table 5.5 value in SI units
    for j, n in enumerate(links):
        expected[f"L_{n}"] = ref["L"][j] * mm
        expected.update({f"B0_{n}_{comp}": ref["B0"][n][c] * mm for c, comp in enumerate("xyz")})
    for n, xyz in ref["Abj"].items():
        expected.update({f"Abj_{n}_{comp}": xyz[c] * mm for c, comp in enumerate("xyz")})
    for i in (1, 2, 3):
        expected.update({f"A0_{i}_{comp}": ref["A0"][f"arm{i}"][c] * mm for c, comp in enumerate("xyz")})
        expected.update({f"v{i}_{comp}": ref["v"][f"arm{i}"][c] for c, comp in enumerate("xyz")})  # kept as printed
    expected.update({f"r3_{comp}": ref["r3"][c] * mm for c, comp in enumerate("xyz")})
    bad = {n: (_value(model, n), v) for n, v in expected.items() if _value(model, n) != pytest.approx(v, abs=TABLE_TOL)}
    assert not bad, bad  # name: (loaded, table)
    p = model.parameter_vector()
    names = ("q1u2", "q1u3", "q2u3")
    loaded = np.array([p[list(idx)] for idx in model.quaternion_indices()])
    printed = np.array([ref[name] for name in names], dtype=float)
    np.testing.assert_allclose(np.linalg.norm(loaded, axis=1), 1.0, rtol=0, atol=TABLE_TOL)
    np.testing.assert_allclose(loaded, printed / np.linalg.norm(printed, axis=1, keepdims=True), atol=TABLE_TOL)
    lim = model.limits
    assert lim.ball_joint_angle_max == pytest.approx(np.radians(ref["ball_joint_limit_deg"]))
    assert np.all(np.abs(lim.cart_travel) < 2.0)  # metres, not millimetres


def test_quaternion_indices_name_the_three_quaternions(model):
    names = model.parameter_names()
    assert [tuple(names[i] for i in idx) for idx in model.quaternion_indices()] == [
        tuple(f"{q}_{c}" for c in "wxyz") for q in ("q1u2", "q1u3", "q2u3")
    ]


def test_parameters_per_arm_match_eqs_5_10_to_5_12(model, ref):
    """The closure graph of each arm depends on 10, 24, 38 parameters (read from the graph)."""
    sizes = [len(model.arm_parameter_indices(a)) for a in range(3)]
    assert sizes == ref["parameters_per_arm"]
    assert model.n_parameters == sum(ref["parameters_per_arm"])


def test_fixed_for_identifiability_names_exist(model, ref):
    names = set(model.parameter_names())
    fixed = [f.split(" = ") for f in F1_FIXED_FOR_IDENTIFIABILITY]
    assert list(F1_FIXED_FOR_IDENTIFIABILITY) == ref["fixed_for_identifiability"]
    assert all(n in names for group in fixed for n in group)


# ------------------------------------------------------------------ workspace grid
def test_workspace_grid_size_is_close_to_the_thesis(grid, ref):
    """1347 poses in ch. 5.5; the cart travel and reorientation range there are not given."""
    T, R, q = grid
    assert abs(len(T) - ref["grid"]["poses_in_workspace"]) <= GRID_SIZE_REL_TOL * ref["grid"]["poses_in_workspace"]


def test_workspace_grid_respects_the_limits(model, grid):
    T, R, q = grid
    lim = model.limits
    assert np.all((q[:, :3] >= lim.cart_travel[:, 0]) & (q[:, :3] <= lim.cart_travel[:, 1]))
    assert np.all((q[:, 3:] >= lim.joint_plate_range[:, 0]) & (q[:, 3:] <= lim.joint_plate_range[:, 1]))
    assert np.max(model.ball_joint_angles(T, R, q)) <= lim.ball_joint_angle_max
    assert np.all(model.aspect_signs(T, R, q) == model.aspect_signs(*model.home, model.q_home))


def test_home_is_in_the_grid_with_zero_ball_joint_angles(model, grid):
    T, R, q = grid
    T_h, R_h = model.home
    k = int(np.argmin(np.linalg.norm(T - T_h, axis=1) + np.abs(R - R_h).reshape(-1, 9).sum(axis=1)))
    np.testing.assert_allclose(q[k], model.q_home, atol=CLOSED_FORM_TOL)
    assert np.max(model.ball_joint_angles(T_h, R_h, model.q_home)) < 1e-7


# ------------------------------------------------------------------ IK and FK
def test_ik_then_fk_round_trip_over_the_grid(model, grid):
    """Two separate Newton solves (IK from its start, FK from its start) give the pose back."""
    T, R, _ = grid
    q = model.ik(T, R)
    T_fk, R_fk = model.fk(q)
    assert np.max(np.linalg.norm(T_fk - T, axis=1)) <= ROUND_TRIP_TOL
    assert np.max(_angle(R_fk, R)) <= ROUND_TRIP_TOL


def test_closure_residuals_vanish_at_ik_solutions(model, grid):
    """Generic interface check: closure_function (eqs. 5.1-5.2, quaternion input) is 0 at IK solutions."""
    T, R, q = grid
    quat = rotation_to_quaternion(R)
    p = model.parameter_vector()
    worst = {}
    for arm in range(3):
        f = model.closure_function(arm).map(len(T))
        worst[f"arm {arm + 1}"] = np.max(np.abs(np.asarray(f(np.repeat(p[:, None], len(T), axis=1), q.T, T.T, quat.T))))
    bad = {arm: r for arm, r in worst.items() if not r <= CLOSURE_TOL}
    assert not bad, bad


def test_ik_of_arm_1_equals_the_closed_form(model, grid):
    """q1 = (d.v + sqrt((d.v)^2 - |v|^2 (|d|^2 - L^2))) / |v|^2, d = T + R_T B0_1 - A0_1 (eq. 4.20)."""
    T, R, q = grid
    A0 = np.array([_value(model, f"A0_1_{c}") for c in "xyz"])
    v = np.array([_value(model, f"v1_{c}") for c in "xyz"])
    B0 = np.array([_value(model, f"B0_1_{c}") for c in "xyz"])
    L = _value(model, "L_1")
    d = T + R @ B0 - A0
    dv = d @ v
    q1 = (dv + np.sqrt(dv**2 - (v @ v) * (np.sum(d * d, axis=1) - L**2))) / (v @ v)
    np.testing.assert_allclose(q[:, 0], q1, atol=CLOSED_FORM_TOL, rtol=0)


def test_fk_agrees_with_generic_fk_newton(model, grid):
    """Second method: the interface's rootfinder on the squared residuals, from the FK start."""
    _, _, q = grid
    T_fk, R_fk = model.fk(q)
    T0, R0 = model.fk_start(q)
    T_g, R_g = model.fk_newton(q, T0, R0)
    assert np.max(np.linalg.norm(T_g - T_fk, axis=1)) <= GENERIC_FK_TOL
    assert np.max(_angle(R_g, R_fk)) <= GENERIC_FK_TOL


def test_fk_start_lands_on_the_nominal_assembly_mode_for_every_grid_pose(model, grid):
    """The default start (continuation from home in START_SUBSTEPS sub-steps) and a 2x finer
    continuation along the same actuator path both end at the grid pose."""
    T, R, q = grid
    T_h, R_h = model.home
    Tc, Rc = np.tile(T_h, (len(T), 1)), np.tile(R_h, (len(T), 1, 1))
    for k in range(1, FINE_SUBSTEPS + 1):
        Tc, Rc = model.fk(model.q_home + k / FINE_SUBSTEPS * (q - model.q_home), Tc, Rc)
    T_fk, R_fk = model.fk(q)
    assert np.max(np.linalg.norm(Tc - T, axis=1)) <= CONTINUATION_TOL
    assert np.max(_angle(Rc, R)) <= CONTINUATION_TOL
    assert np.max(np.linalg.norm(T_fk - Tc, axis=1)) <= CONTINUATION_TOL
    assert np.max(_angle(R_fk, Rc)) <= CONTINUATION_TOL


def test_warm_start_from_the_previous_sample_converges_in_few_steps(model, grid):
    """Real-time use (eq. 4.29): from the solution 1 mm / 1 mrad away, IK and FK need <= 4 Newton steps."""
    T, R, q = grid
    dR = rotation_vector_to_rotation([1e-3, 0.0, 0.0])
    q_new, it_ik = model.ik(T + 1e-3, dR @ R, q0=q, return_iterations=True)
    _, _, it_fk = model.fk(q_new, T, R, return_iterations=True)
    assert np.max(it_ik) <= WARM_START_MAX_ITER
    assert np.max(it_fk) <= WARM_START_MAX_ITER


def test_casadi_functions_report_status_and_iterations(model):
    """ik_function / fk_function (fixed unrolled iterations, for C code) at the home pose."""
    T_h, R_h = model.home
    q, e, it, ok, disc = model.ik_function()(T_h, R_h, model.q_home)
    assert int(ok) == 1 and int(it) == 0 and float(disc) > 0
    np.testing.assert_allclose(np.asarray(q).ravel(), model.q_home, atol=CLOSED_FORM_TOL)
    T, R, e, it, ok = model.fk_function(3)(model.q_home, T_h + 0.01, R_h)
    assert int(ok) == 1 and 0 < int(it) <= 3
    _, _, _, _, ok = model.fk_function(1)(model.q_home, T_h + 0.01, R_h)
    assert int(ok) == 0


# ------------------------------------------------------------------ Jacobians
@pytest.fixture(scope="module")
def sample(grid):
    T, R, q = grid
    idx = np.linspace(0, len(T) - 1, 4).astype(int)
    return T[idx], R[idx], q[idx]


def _link_lengths(model: F1Closure, T: np.ndarray, R: np.ndarray, q: np.ndarray) -> np.ndarray:
    p = ca.DM(model.parameter_vector())
    out = []
    for arm in range(3):
        A, B, _ = model.link_points(p, ca.DM(q), ca.DM(T), ca.DM(R), arm)
        out.append(np.linalg.norm(np.asarray(B - A), axis=0))
    return np.concatenate(out)


def test_pose_jacobian_equals_central_differences(model, sample):
    """d||B - A|| / d(T, w) (AD) against central differences, R_T <- Rot(w) R_T."""
    for T, R, q in zip(*sample):
        J_X, _ = model.jacobians(T, R, q)
        fd = np.empty((6, 6))
        for k in range(6):
            e = np.zeros(6)
            e[k] = FD_STEP
            plus = _link_lengths(model, T + e[:3], rotation_vector_to_rotation(e[3:]) @ R, q)
            minus = _link_lengths(model, T - e[:3], rotation_vector_to_rotation(-e[3:]) @ R, q)
            fd[:, k] = (plus - minus) / (2 * FD_STEP)
        np.testing.assert_allclose(J_X, fd, atol=FD_TOL, rtol=0)


def test_actuator_jacobian_equals_central_differences(model, sample):
    for T, R, q in zip(*sample):
        _, J_q = model.jacobians(T, R, q)
        fd = np.empty((6, 6))
        for k in range(6):
            e = np.zeros(6)
            e[k] = FD_STEP
            fd[:, k] = (_link_lengths(model, T, R, q + e) - _link_lengths(model, T, R, q - e)) / (2 * FD_STEP)
        np.testing.assert_allclose(J_q, fd, atol=FD_TOL, rtol=0)


def test_pose_jacobian_is_the_stewart_inverse_jacobian(model, sample):
    """Eq. 4.31 with the rotation vector: row = [AB^T, (R_T B0 x AB)^T] / |AB|."""
    p = ca.DM(model.parameter_vector())
    for T, R, q in zip(*sample):
        rows = []
        for arm in range(3):
            A, B, _ = (np.asarray(x) for x in model.link_points(p, ca.DM(q), ca.DM(T), ca.DM(R), arm))
            for j in range(A.shape[1]):
                AB = B[:, j] - A[:, j]
                RB0 = B[:, j] - T
                rows.append(np.concatenate([AB, np.cross(RB0, AB)]) / np.linalg.norm(AB))
        np.testing.assert_allclose(model.jacobians(T, R, q)[0], np.array(rows), atol=STEWART_TOL, rtol=0)


# ------------------------------------------------------------------ frames and parameters
def test_transformed_model_assembles_at_transformed_poses(model, sample):
    """x' = Rm x + t: the same q assemble at T' = Rm T + t, R_T' = Rm R_T (B0 unchanged)."""
    Rm = rotation_vector_to_rotation([0.3, -0.2, 1.1])
    t = np.array([1.0, -2.0, 0.5])
    moved = model.transformed(Rm, t)
    T, R, q = sample
    T2, R2 = moved.fk(q, T @ Rm.T + t, Rm @ R)
    np.testing.assert_allclose(T2, T @ Rm.T + t, atol=ROUND_TRIP_TOL)
    np.testing.assert_allclose(R2, Rm @ R, atol=ROUND_TRIP_TOL)
    p = moved.parameter_vector()
    for idx, name in zip(moved.quaternion_indices(), ("q1u2", "q1u3")):
        old = quaternion_to_rotation(model.parameter_vector()[list(idx)])
        np.testing.assert_allclose(quaternion_to_rotation(p[list(idx)]), Rm @ old, atol=CLOSED_FORM_TOL)


def test_with_parameters_keeps_home_and_limits(model):
    other = model.with_parameters(model.parameter_vector())
    np.testing.assert_array_equal(other.parameter_vector(), model.parameter_vector())
    assert other.limits is model.limits
    np.testing.assert_allclose(other.home[0], model.home[0], atol=CLOSED_FORM_TOL)


# ------------------------------------------------------------------ errors
def test_unreachable_pose_for_arms_2_and_3_raises_convergence_error(model):
    T_h, R_h = model.home
    T = np.array([T_h, T_h + [1.0, 0.0, 0.0]])
    with pytest.raises(ConvergenceError, match=r"did not converge for pose row 1 .*1 pose\(s\) failed"):
        model.ik(T, R_h)


def test_pose_out_of_reach_of_arm_1_raises_unreachable(model):
    T_h, R_h = model.home
    with pytest.raises(UnreachablePoseError, match=r"pose row 0 .* unreachable for arm 1"):
        model.ik(T_h + [3.0, 0.0, 0.0], R_h)


def test_too_few_iterations_raise_convergence_error(model, grid):
    T, R, q = grid
    k = int(np.argmax(np.abs(q[:, 4] - model.q_home[4])))  # far from home in q5
    with pytest.raises(ConvergenceError, match=r"inverse kinematics did not converge for pose row 0 .*after 2 Newton"):
        model.ik(T[k:k + 1], R[k:k + 1], q0=model.q_home, max_iter=2)
    with pytest.raises(ConvergenceError, match=r"forward kinematics did not converge for pose row 0 .*after 2 Newton"):
        model.fk(q[k:k + 1], *model.home, max_iter=2)


BAD_ARGUMENTS = [
    ("ik T shape", lambda m, T, R: m.ik(T[:2], R), InputError, r"T: expected shape \(3,\) or \(N, 3\)"),
    ("ik T not finite", lambda m, T, R: m.ik([np.nan, 0, 0], R), InputError, r"T: row 0 is not finite"),
    ("ik R not a rotation", lambda m, T, R: m.ik(T, 2 * R), InputError, r"R: matrix 0 is not a rotation"),
    ("ik R count", lambda m, T, R: m.ik(np.array([T, T]), np.array([R, R, R])), InputError, r"R: expected shape \(3, 3\) or \(2, 3, 3\)"),
    ("ik q0 shape", lambda m, T, R: m.ik(T, R, q0=np.zeros(5)), InputError, r"q0: expected shape \(6,\)"),
    ("ik max_iter 0", lambda m, T, R: m.ik(T, R, max_iter=0), InputError, r"max_iter: expected a positive integer"),
    ("fk q shape", lambda m, T, R: m.fk(np.zeros(5)), InputError, r"q: expected shape \(6,\) or \(N, 6\)"),
    ("fk T0 without R0", lambda m, T, R: m.fk(m.q_home, T0=T), InputError, r"T0 and R0: give both"),
    ("fk max_iter float", lambda m, T, R: m.fk(m.q_home, max_iter=2.5), InputError, r"max_iter: expected a positive integer"),
    ("jacobians rows", lambda m, T, R: m.jacobians(np.array([T, T]), R, m.q_home), InputError, r"q: expected 2 rows"),
    ("grid step_m", lambda m, T, R: m.workspace_grid(step_m=0.0), InputError, r"step_m: expected a positive spacing"),
    ("grid step_deg", lambda m, T, R: m.workspace_grid(step_deg=-10.0), InputError, r"step_deg: expected a positive spacing"),
    ("grid range", lambda m, T, R: m.workspace_grid(reorientation_deg=[10.0, 10.0]), InputError, r"reorientation_deg: expected three angles"),
    ("with_parameters size", lambda m, T, R: m.with_parameters(np.zeros(5)), InputError, r"expected 72 finite parameters"),
    ("transformed R", lambda m, T, R: m.transformed(2 * np.eye(3), np.zeros(3)), InputError, r"R: matrix 0 is not a rotation"),
    ("transformed t", lambda m, T, R: m.transformed(np.eye(3), [0.0, 1.0]), InputError, r"t: expected a finite translation"),
    ("link_points arm", lambda m, T, R: m.link_points(ca.DM(m.parameter_vector()), ca.DM(m.q_home), ca.DM(T), ca.DM(R), 3), InputError, r"arm must be one of 0..2"),
    ("q_home size", lambda m, T, R: F1Closure(m.parameter_vector(), np.zeros(5)), InputError, r"q_home: expected 6 finite"),
    ("no limits", lambda m, T, R: F1Closure(m.parameter_vector(), m.q_home).in_workspace(T, R, m.q_home), InputError, r"in_workspace: the model has no limits"),
    ("unknown set", lambda m, T, R: load_f1("F2"), ParameterError, r"unknown F1 parameter set 'F2'"),
]


@pytest.mark.parametrize("case, call, error, match", BAD_ARGUMENTS, ids=[c[0] for c in BAD_ARGUMENTS])
def test_bad_arguments(model, case, call, error, match):
    T_h, R_h = model.home
    with pytest.raises(error, match=match):
        call(model, T_h, R_h)


SHIPPED = Path(__file__).resolve().parents[2] / "gtmodel" / "robots" / "data" / "F1.toml"

BAD_FILES = [
    ("unit", '\nlength_unit = "mm"', '\nlength_unit = "cm"', r"field 'length_unit': expected 'mm' or 'm'"),
    ("L shape", "L = [1922.58, 1501.86, 1504.27, 1501.99, 1501.19, 1505.24]", "L = [1922.58, 1501.86]", r"field 'kinematics.L': expected finite numbers of shape \(6,\)"),
    ("L negative", "L = [1922.58,", "L = [-1922.58,", r"field 'kinematics.L': expected positive link lengths"),
    ("quaternion zero", "q1u2 = [0.6308, 0.0054, 0.0054, 0.7467]", "q1u2 = [0.0, 0.0, 0.0, 0.0]", r"field 'kinematics.q1u2': expected a quaternion"),
    ("v zero", "arm1 = [0.00, 0.00, 0.99]", "arm1 = [0.00, 0.00, 0.00]", r"field 'kinematics.v.arm1': expected a guideway direction"),
    ("Abj missing", ', "3c" = [0.00, 55.19, 187.36] }', " }", r"missing field 'kinematics.Abj.3c'"),
    ("home missing", "[home]", "[home_position]", r"unknown field 'home_position'"),
    ("limits unknown", "ball_joint_angle_max_deg = 45.0", "ball_joint_angle_max_deg = 45.0\nfoo = 1", r"unknown field 'limits.foo'"),
    ("travel order", "cart_travel = [[-600.0, 600.0],", "cart_travel = [[600.0, -600.0],", r"field 'limits.cart_travel': expected rows \(min, max\)"),
    ("ball angle", "ball_joint_angle_max_deg = 45.0", "ball_joint_angle_max_deg = 95.0", r"field 'limits.ball_joint_angle_max_deg': expected an angle in \(0, 90\)"),
    ("home outside", "joint_plate_angles_deg = [-90.0, 90.0, 0.0]", "joint_plate_angles_deg = [-90.0, 90.0, 80.0]", r"home actuator values lie outside the limits"),
    ("syntax", "[limits]", "[limits", r"invalid TOML"),
]


@pytest.mark.parametrize("case, old, new, match", BAD_FILES, ids=[c[0] for c in BAD_FILES])
def test_bad_parameter_files_name_file_and_field(tmp_path, case, old, new, match):
    text = SHIPPED.read_text(encoding="utf-8")
    assert old in text, case
    path = tmp_path / "F1_bad.toml"
    path.write_text(text.replace(old, new, 1), encoding="utf-8")
    with pytest.raises(ParameterError, match=match) as info:
        load_f1(path)
    assert re.search(re.escape(str(path)), str(info.value))
