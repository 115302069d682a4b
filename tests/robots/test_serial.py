"""Serial 6R arm from a DH table: FK, geometric Jacobian, joint-spring model (3) and (7).

Independent references: closed-form positions of the illustrative arm at its home pose,
central finite differences of the FK (Jacobian), the FK of the deflected joint angles
(eq. (3) as a small-displacement limit), eq. (7) solved against eq. (3), and for the
complementary stiffness of eq. (2) central differences of ``J^T F`` and the loaded
equilibrium ``K_theta dtheta = J(theta + dtheta)^T F`` solved by fixed-point iteration.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gtmodel.errors import InputError, ParameterError, SingularConfigurationError
from gtmodel.robots.parameters import available_parameter_sets
from gtmodel.robots.serial import SerialArm, load_serial_arm

REPO_DATA = Path(__file__).resolve().parents[2] / "gtmodel" / "robots" / "data"
FD_STEP = 1e-6  # rad
FD_TOLERANCE = 1e-7  # m/rad, rad/rad
GEOMETRY_TOLERANCE = 1e-12  # m
SMALL_DEFLECTION_RELATIVE = 1e-3  # linearisation error of eq. (3) at ~1e-4 rad
IK_TOLERANCE = 1e-9
KC_FD_RELATIVE = 1e-6  # K_c against central differences, relative to max |K_c|
KC_EQUILIBRIUM_RELATIVE = 2e-2  # first-order (2) vs the nonlinear equilibrium at 5 kN
HEAVY_WRENCH = np.array([1000.0, 0.0, -5000.0, 0.0, 200.0, 0.0])  # N, N m

K_THETA = np.array([2.86, 2.36, 1.67, 0.24, 0.16, 0.14]) * 1e6  # Cvitanic (2021), Table 2 DPP
POSES = np.radians([[19.67, -52.14, 117.9, 11.86, -66.08, -4.84], [44.71, -70.81, 58.16, 138.51, -41.63, -125.84],
                    [28.12, -55.4, 84.06, -167.6, 27.07, -179.85]])


@pytest.fixture(scope="module")
def arm() -> SerialArm:
    return load_serial_arm("serial_6r_illustrative")


def _rotvec(R: np.ndarray) -> np.ndarray:
    """Small rotation vector of R (first order)."""
    return 0.5 * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])


def test_shipped_arm_is_illustrative_and_not_a_gantry_tau_set(arm):
    """The DH file is labelled as assumed values and is not listed as a 3-link parameter set."""
    assert "ILLUSTRATIVE" in arm.description
    assert "serial_6r_illustrative" not in available_parameter_sets()


def test_home_pose_matches_closed_form(arm):
    """At A2 = -90, A3 = 90 deg the upper arm is vertical and the forearm horizontal (hand geometry)."""
    home = np.radians([0, -90, 90, 0, 0, 0])
    wc = arm.wrist_centre(home)
    np.testing.assert_allclose(wc, [0.5 + 1.025, 0.0, 1.045 + 1.3 + 0.055], atol=GEOMETRY_TOLERANCE)
    # flange 0.29 m further along +x, tool tip 0.25 m further and 0.35 m off the flange axis
    T = arm.fk(home)
    np.testing.assert_allclose(np.abs(T[:3, 3] - wc), [0.29 + 0.25, 0.0, 0.35], atol=GEOMETRY_TOLERANCE)


@pytest.mark.parametrize("i", range(len(POSES)))
def test_jacobian_matches_finite_differences(arm, i):
    """Geometric Jacobian (ca.jacobian + joint axes) against central differences of the FK."""
    th = POSES[i]
    J = arm.jacobian(th)
    fd = np.zeros((6, 6))
    for j in range(6):
        e = np.zeros(6)
        e[j] = FD_STEP
        Tp, Tm = arm.fk(th + e), arm.fk(th - e)
        fd[:3, j] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * FD_STEP)
        fd[3:, j] = _rotvec(Tp[:3, :3] @ Tm[:3, :3].T) / (2 * FD_STEP)
    np.testing.assert_allclose(J, fd, atol=FD_TOLERANCE)


def test_wrist_centre_independent_of_wrist_joints(arm):
    """Spherical wrist: the wrist centre does not move with joints 4-6 (zero Jacobian columns)."""
    Jwc = arm.wrist_jacobian(POSES[0])
    assert np.max(np.abs(Jwc[:, 3:])) < GEOMETRY_TOLERANCE
    moved = POSES[0] + np.array([0, 0, 0, 0.3, -0.2, 0.5])
    np.testing.assert_allclose(arm.wrist_centre(moved), arm.wrist_centre(POSES[0]), atol=GEOMETRY_TOLERANCE)


@pytest.mark.parametrize("i", range(len(POSES)))
def test_deflection_is_fk_of_deflected_joints(arm, i):
    """Eq. (3) equals the FK change for joint deflections K^-1 J^T F (small-load limit)."""
    th = POSES[i]
    F = np.array([30.0, -20.0, 40.0, 5.0, -3.0, 4.0])
    dX = arm.deflection(th, F, K_THETA)
    dth = (arm.jacobian(th).T @ F) / K_THETA
    T0, T1 = arm.fk(th), arm.fk(th + dth)
    ref = np.concatenate([T1[:3, 3] - T0[:3, 3], _rotvec(T1[:3, :3] @ T0[:3, :3].T)])
    np.testing.assert_allclose(dX, ref, atol=SMALL_DEFLECTION_RELATIVE * np.max(np.abs(ref)))


@pytest.mark.parametrize("i", range(len(POSES)))
def test_cartesian_stiffness_inverts_deflection(arm, i):
    """K_x of eq. (7) solved for F reproduces eq. (3); regressor times compliances too."""
    th = POSES[i]
    F = np.array([1000.0, -500.0, 800.0, 100.0, -50.0, 70.0])
    Kx = arm.cartesian_stiffness(th, K_THETA)
    dX = arm.deflection(th, F, K_THETA)
    np.testing.assert_allclose(np.linalg.solve(Kx, F), dX, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(arm.compliance_regressor(th, F) @ (1 / K_THETA), dX, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(Kx, Kx.T, rtol=1e-9, atol=1e-6 * np.max(np.abs(Kx)))


@pytest.mark.parametrize("i", range(len(POSES)))
def test_complementary_stiffness_matches_finite_differences(arm, i):
    """K_c of eq. (2) (ca.jacobian of J^T F) against central differences of J(theta)^T F."""
    th = POSES[i]
    Kc = arm.complementary_stiffness(th, HEAVY_WRENCH)
    fd = np.column_stack([(arm.jacobian(th + FD_STEP * e).T - arm.jacobian(th - FD_STEP * e).T) @ HEAVY_WRENCH / (2 * FD_STEP) for e in np.eye(6)])
    assert np.max(np.abs(Kc - fd)) < KC_FD_RELATIVE * np.max(np.abs(Kc))


@pytest.mark.parametrize("i", range(len(POSES)))
def test_deflection_with_complementary_stiffness_matches_equilibrium(arm, i):
    """dX = J (K_theta - K_c)^-1 J^T F against the loaded equilibrium K dtheta = J(theta + dtheta)^T F.

    Second method: fixed-point iteration on the nonlinear equilibrium (Jacobian re-evaluated at
    the deflected angles); eq. (3) without K_c differs from it by more than (2) does.
    """
    th = POSES[i]
    dth = np.zeros(6)
    for _ in range(30):
        dth = (arm.jacobian(th + dth).T @ HEAVY_WRENCH) / K_THETA
    dX_eq = arm.jacobian(th) @ dth
    dX_c = arm.deflection(th, HEAVY_WRENCH, K_THETA, complementary=True)
    dX_3 = arm.deflection(th, HEAVY_WRENCH, K_THETA)
    err_c, err_3 = np.linalg.norm(dX_c - dX_eq), np.linalg.norm(dX_3 - dX_eq)
    assert err_c < KC_EQUILIBRIUM_RELATIVE * np.linalg.norm(dX_eq)
    assert err_c < err_3


def test_ik_round_trip(arm):
    """IK (Newton on the CasADi FK/Jacobian) returns to the FK pose from a perturbed start."""
    th = POSES[1]
    sol = arm.ik(arm.fk(th), th + 0.05)
    np.testing.assert_allclose(arm.fk(sol), arm.fk(th), atol=IK_TOLERANCE)


def test_batch_fk_matches_single(arm):
    """fk on (N, 6) equals fk row by row."""
    out = arm.fk(POSES)
    for i, th in enumerate(POSES):
        np.testing.assert_allclose(out[i], arm.fk(th), atol=0)


def test_singular_pose_raises(arm):
    """A wrist singularity (A5 = 0) makes K_x of eq. (7) undefined."""
    with pytest.raises(SingularConfigurationError, match="singular"):
        arm.cartesian_stiffness(np.radians([0, -90, 90, 0, 0, 0]), K_THETA)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda a: a.fk(np.zeros(5)), r"theta: expected shape \(6,\)"),
        (lambda a: a.fk([0, 0, np.nan, 0, 0, 0]), "theta: row 0 is not finite"),
        (lambda a: a.jacobian(np.zeros((2, 6))), r"theta: expected shape \(6,\)"),
        (lambda a: a.deflection(POSES[0], np.zeros(3), K_THETA), r"F: expected shape \(6,\)"),
        (lambda a: a.deflection(POSES[0], np.zeros(6), -K_THETA), "k_theta: expected positive"),
        (lambda a: a.cartesian_stiffness(POSES[0], np.r_[K_THETA[:5], 0.0]), "k_theta: expected positive.*entry 5"),
        (lambda a: a.deflection(POSES[0], [np.inf, 0, 0, 0, 0, 0], K_THETA), "F: expected finite"),
        (lambda a: a.ik(np.ones((4, 4)), POSES[0]), "T_target.*not rigid"),
    ],
)
def test_bad_input(arm, call, match):
    """Wrong shapes, NaN/inf and non-positive stiffness are refused with a message naming the argument."""
    with pytest.raises(InputError, match=match):
        call(arm)


@pytest.mark.parametrize(
    "text, match",
    [
        ('[dh]\nconvention = "modified"\n', "only 'standard'"),
        ('[dh]\na = [0, 0, 0]\nalpha_deg = [0,0,0,0,0,0]\nd = [0,0,0,0,0,0]\ntheta_offset_deg = [0,0,0,0,0,0]\n', r"dh.a: expected shape \(6,\)"),
        ('[dh]\na = [0,0,0,0,0,0]\nd = [0,0,0,0,0,0]\ntheta_offset_deg = [0,0,0,0,0,0]\n', "dh.alpha_deg: missing"),
        ("name = 'x'\n", r"missing table \[dh\]"),
        ("[dh\n", "invalid TOML"),
    ],
)
def test_bad_dh_file(tmp_path, text, match):
    """Invalid DH files raise ParameterError naming the file and the field."""
    p = tmp_path / "arm.toml"
    p.write_text(text)
    with pytest.raises(ParameterError, match=match):
        load_serial_arm(p)


def test_unknown_arm():
    """An unknown name is refused."""
    with pytest.raises(ParameterError, match="unknown serial arm"):
        load_serial_arm("no_such_arm")


def test_shipped_joint_limits_contain_the_thesis_poses(arm):
    """The assumed limits hold every pose of Cvitanic (2021), Tables 1, 12 and 13 (joints 1, 4-6 of Tables 12-13 as the correction study's)."""
    from gtmodel.estimation.closed_loop.correction import CALIBRATION_POSES_DEG, VALIDATION_POSES_DEG, joint_angles

    assert arm.joint_limits.shape == (6, 2)
    arm.check_joint_limits(np.radians([[19.67, -52.14, 117.9, 11.86, -66.08, -4.84], [42.99, -40.39, 97.42, -177.38, 72.1, -179.8]]))
    arm.check_joint_limits(joint_angles(np.vstack([CALIBRATION_POSES_DEG, VALIDATION_POSES_DEG])))


@pytest.mark.parametrize(
    "theta_deg, match",
    [
        ([0, -131, 90, 0, 30, 0], r"theta: row 0: joint 2 = -131 deg is outside the joint limits -130\.\.20 deg"),
        ([0, -40, 90, 0, 119, 0], r"joint 5 = 119 deg is outside the joint limits -118\.\.118 deg"),
    ],
)
def test_pose_outside_the_joint_limits(arm, theta_deg, match):
    """A pose outside the limits names the joint and its limits."""
    with pytest.raises(InputError, match=match):
        arm.check_joint_limits(np.radians(theta_deg))


def test_bad_joint_limits(tmp_path):
    """Joint limits with lower >= upper are refused, naming the joint (argument) or the file and field."""
    with pytest.raises(InputError, match="joint_limits: expected lower < upper limit, joint 3"):
        SerialArm(np.zeros(6), np.zeros(6), np.zeros(6), joint_limits=[[-1, 1], [-1, 1], [1, -1], [-1, 1], [-1, 1], [-1, 1]])
    p = tmp_path / "arm.toml"
    text = (REPO_DATA / "serial_6r_illustrative.toml").read_text()
    p.write_text(text.replace("lower_deg = [-185.0,", "lower_deg = [-185.0, 0.0,"))
    with pytest.raises(ParameterError, match=r"joint_limits\.lower_deg: expected shape \(6,\)"):
        load_serial_arm(p)
