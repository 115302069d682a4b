"""Six-link kinematic error model (Dressler (2012), eqs. 4.14-4.15) and the D1 six-link set.

Independent references used below:

- the closed-form per-link IK (quadratic roots) checks the Newton FK of eq. 4.15;
- the interface's generic Newton FK on the closure equations (rotation-vector
  orientation, CasADi rootfinder) is a second FK method;
- a synthetic six-link model built as exact parallelograms around the 3-link D1 model 1
  must keep its orientation and reproduce the closed-form 3-link trilateration;
- the thesis' Table 5.9 (shared/reference/gantry_tau_D1_F1.toml) for the numbers, and a
  Kabsch fit by NumPy's SVD for the nominal orientation (SciPy's align_vectors in the
  model);
- the D1 3-link model 1 (Table 5.8) for where the TCP is.
"""

from __future__ import annotations

import tomllib
from importlib import resources

import casadi as ca
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gtmodel.errors import ConvergenceError, InputError, ParameterError, UnreachablePoseError
from gtmodel.robots.closure import rotation_to_quaternion
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.parameters import KinematicParameters, load_parameters
from gtmodel.robots.six_link import (
    FK_MAX_ITER,
    FK_TOLERANCE,
    FK_UNROLLED_ITER,
    SIX_LINKS,
    SixLinkClosure,
    estimate_nominal_orientation,
    load_six_link,
)

from ..conftest import SHARED_REFERENCE

#: FK(IK) round trip and agreement of the links of one arm [m] (brief requirement).
ROUND_TRIP_TOL = 1e-10
#: Eq. 4.15 Newton FK vs the generic closure-equation Newton FK [m] and [-] for R.
SECOND_METHOD_TOL = 1e-10
#: Parallelogram model vs the closed-form 3-link FK [m], and its orientation vs R0 [-].
PARALLELOGRAM_TOL = 1e-10
#: Closure residual ||A - B||^2 - L^2 at FK solutions [m^2] (~2 L * 1e-12 m).
CLOSURE_TOL = 1e-10
#: Numbers copied from the thesis table.
EXACT = 0.0
#: A0_2b is the derived value rounded to 0.01 mm, like the table [m].
ROUNDING_TOL = 5e-6 + 1e-12
#: Reproduction of A0_3b, A0_3c from A0_3a by the parallelogram construction [m]
#: (measured 0.076 mm and 0.348 mm).
ARM3_RECONSTRUCTION_MAX = 0.4e-3
#: Six-link nominal FK vs the 3-link model 1 of the same robot [m] (measured 0.83 mm
#: directly, 0.34 mm after removing the mean offset of 0.50 mm).
THREE_LINK_AGREEMENT = 2e-3
THREE_LINK_AGREEMENT_AFTER_OFFSET = 0.5e-3
#: Newton iterations the D1 workspace needs from the trilateration start (measured 2).
D1_MAX_ITERATIONS = 3
#: Kabsch by SVD vs scipy's align_vectors [-].
KABSCH_TOL = 1e-12
#: Spacing of the D1 workspace grid [m] (694 poses).
GRID_STEP = 0.1
#: Orientation of the parallelogram tests' nominal start perturbation [deg].
START_PERTURBATION_DEG = 3.0
#: Sample of poses for the (slower) generic rootfinder FK.
N_SECOND_METHOD = 40

LINKS = [name for arm in SIX_LINKS for name in arm]


def _reference() -> dict:
    path = SHARED_REFERENCE / "gantry_tau_D1_F1.toml"
    if not path.exists():
        pytest.skip(f"reference data {path} not available")
    return tomllib.loads(path.read_text())["D1"]


def _kabsch_svd(dA: np.ndarray, dB: np.ndarray) -> np.ndarray:
    """Rotation R minimising sum |dA_k - R dB_k|^2 (Kabsch, by NumPy's SVD)."""
    U, _, Vt = np.linalg.svd(dA.T @ dB)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    return U @ D @ Vt


@pytest.fixture(scope="module")
def d1() -> SixLinkClosure:
    return load_six_link("D1_six_link")


@pytest.fixture(scope="module")
def three_link() -> GantryTau3Kinematics:
    return GantryTau3Kinematics("D1")


@pytest.fixture(scope="module")
def grid_q(three_link) -> np.ndarray:
    """Cart positions of the D1 workspace grid (3-link model 1, within the limits)."""
    return three_link.ik(three_link.workspace_grid(GRID_STEP))


@pytest.fixture(scope="module")
def grid_fk(d1, grid_q):
    return d1.fk_solve(grid_q)


# ------------------------------------------------------------------ the parameter set
def test_d1_set_loads_with_limits(d1):
    assert d1.n_parameters == 60
    assert d1.name == "D1_six_link"
    names = d1.parameter_names()
    assert names[:2] == ("L_1", "L_2a")
    assert {"A0_2a_x", "v_2a_y", "B0_3c_z"} <= set(names)
    np.testing.assert_array_equal(d1.limits.cart_travel, [[-0.65, 0.70]] * 3)
    assert d1.limits.joint_angle_max == pytest.approx(np.radians(40.0))


def test_d1_numbers_are_table_5_9(d1):
    """Every legible number of Table 5.9 is copied unchanged."""
    ref = _reference()["model_3"]
    assert ref["links"] == LINKS
    np.testing.assert_allclose(d1.L, ref["L"], atol=EXACT, rtol=0)
    np.testing.assert_allclose(d1.B0, ref["B0"], atol=EXACT, rtol=0)
    for j, name in enumerate(LINKS):
        if name == "2b":
            continue
        np.testing.assert_allclose(d1.A0[j], ref["A0"][name], atol=EXACT, rtol=0)
        np.testing.assert_allclose(d1.v[j], ref["v"][name], atol=EXACT, rtol=0)


def test_link_2b_is_the_parallelogram_of_2a_at_the_arm3_orientation(d1):
    """A0_2b = A0_2a + R_T0 (B0_2b - B0_2a), v_2b = v_2a, R_T0 Kabsch-fitted to arm 3 (by SVD here)."""
    ref = _reference()["model_3"]
    A0 = {k: np.array(v) for k, v in ref["A0"].items()}
    B0 = dict(zip(LINKS, np.array(ref["B0"])))
    pairs = [("3a", "3b"), ("3a", "3c"), ("3b", "3c")]
    R_T0 = _kabsch_svd(np.array([A0[k] - A0[j] for j, k in pairs]), np.array([B0[k] - B0[j] for j, k in pairs]))
    expected = A0["2a"] + R_T0 @ (B0["2b"] - B0["2a"])
    np.testing.assert_allclose(d1.A0[2], expected, atol=ROUNDING_TOL, rtol=0)
    np.testing.assert_array_equal(d1.v[2], ref["v"]["2a"])


def test_parallelogram_construction_reproduces_arm3(d1):
    """How well the 2b construction works where the answer is known: 3b and 3c from 3a."""
    ref = _reference()["model_3"]
    A0 = {k: np.array(v) for k, v in ref["A0"].items()}
    B0 = dict(zip(LINKS, np.array(ref["B0"])))
    R_T0, rms = estimate_nominal_orientation(d1.A0, d1.B0)
    err = [np.linalg.norm(A0[j] - (A0["3a"] + R_T0 @ (B0[j] - B0["3a"]))) for j in ("3b", "3c")]
    assert max(err) < ARM3_RECONSTRUCTION_MAX
    assert rms < ARM3_RECONSTRUCTION_MAX


def test_nominal_orientation_estimate_is_kabsch(d1):
    """SciPy's align_vectors (in the model) and the SVD solution agree; the model carries it."""
    pairs = [(a[i], a[k]) for a in SIX_LINKS for i in range(len(a)) for k in range(i + 1, len(a))]
    idx = {n: j for j, n in enumerate(LINKS)}
    dA = np.array([d1.A0[idx[k]] - d1.A0[idx[j]] for j, k in pairs])
    dB = np.array([d1.B0[idx[k]] - d1.B0[idx[j]] for j, k in pairs])
    R, _ = estimate_nominal_orientation(d1.A0, d1.B0)
    np.testing.assert_allclose(R, _kabsch_svd(dA, dB), atol=KABSCH_TOL, rtol=0)
    np.testing.assert_allclose(d1.R0, R, atol=KABSCH_TOL, rtol=0)


# ------------------------------------------------------------------ FK and IK on the D1
def test_fk_converges_in_few_iterations(grid_fk):
    assert len(grid_fk.T) > 500
    assert grid_fk.iterations.max() <= D1_MAX_ITERATIONS
    assert grid_fk.residual.max() <= FK_TOLERANCE


def test_ik_of_fk_round_trip_all_six_links(d1, grid_q, grid_fk):
    """q -> FK (eq. 4.15) -> closed-form IK of every link gives q back: the links of one arm agree."""
    q6 = d1.ik_links(grid_fk.T, grid_fk.R)
    np.testing.assert_allclose(q6, grid_q[:, [0, 1, 1, 2, 2, 2]], atol=ROUND_TRIP_TOL, rtol=0)


def test_fk_of_ik_round_trip(d1, grid_fk):
    """FK(IK(T, R)) = (T, R) on the D1 poses (T, R) the robot assembles over its workspace grid."""
    T, R = d1.fk(d1.ik(grid_fk.T, grid_fk.R))
    np.testing.assert_allclose(T, grid_fk.T, atol=ROUND_TRIP_TOL, rtol=0)
    np.testing.assert_allclose(R, grid_fk.R, atol=ROUND_TRIP_TOL, rtol=0)


@pytest.mark.parametrize("arm", range(3))
def test_closure_residuals_vanish_at_fk(d1, grid_q, grid_fk, arm):
    p = d1.parameter_vector()
    quat = rotation_to_quaternion(grid_fk.R)
    N = len(grid_q)
    r = np.asarray(d1.closure_function(arm).map(N)(p, grid_q.T, grid_fk.T.T, quat.T))
    assert r.shape == (len(SIX_LINKS[arm]), N)
    assert np.abs(r).max() < CLOSURE_TOL


def test_fk_agrees_with_generic_closure_newton(d1, three_link, grid_q, grid_fk):
    """Second method: ClosureModel.fk_newton, started from the 3-link model-1 FK (mm away)."""
    k = np.linspace(0, len(grid_q) - 1, N_SECOND_METHOD).astype(int)
    T0 = three_link.fk(grid_q[k])
    T, R = d1.fk_newton(grid_q[k], T0, d1.R0)
    np.testing.assert_allclose(T, grid_fk.T[k], atol=SECOND_METHOD_TOL, rtol=0)
    np.testing.assert_allclose(R, grid_fk.R[k], atol=SECOND_METHOD_TOL, rtol=0)


def test_nominal_fk_matches_three_link_model_1(three_link, grid_q, grid_fk):
    """Table 5.9 vs Table 5.8: the same robot, so the TCP agrees to within a few mm."""
    d = grid_fk.T - three_link.fk(grid_q)
    assert np.linalg.norm(d, axis=1).max() < THREE_LINK_AGREEMENT
    assert np.linalg.norm(d - d.mean(axis=0), axis=1).max() < THREE_LINK_AGREEMENT_AFTER_OFFSET


def test_orientation_stays_near_nominal(d1, grid_fk):
    """Nearly parallelograms: the plate turns by hundredths of a degree over the workspace."""
    angle = Rotation.from_matrix(np.einsum("ji,njk->nik", d1.R0, grid_fk.R)).magnitude()
    assert np.degrees(angle).max() < 0.5


def test_grid_poses_are_in_workspace(d1, grid_fk):
    assert d1.in_workspace(grid_fk.T, grid_fk.R).mean() > 0.99


def test_unrolled_fk_function_matches(d1, grid_q, grid_fk):
    f = d1.fk_function()
    T, R, X, residual, status = (np.asarray(o) for o in f.map(len(grid_q))(grid_q.T))
    np.testing.assert_allclose(T.T, grid_fk.T, atol=ROUND_TRIP_TOL, rtol=0)
    np.testing.assert_allclose(R.reshape(3, -1, 3).transpose(1, 0, 2), grid_fk.R, atol=ROUND_TRIP_TOL, rtol=0)
    assert np.all(status == 1.0)
    assert residual.max() <= FK_TOLERANCE
    assert FK_UNROLLED_ITER > D1_MAX_ITERATIONS


def test_parametric_fk_function(d1, grid_q, grid_fk):
    f = d1.fk_function(parametric=True)
    T = np.asarray(f(grid_q[0], d1.parameter_vector())[0]).ravel()
    np.testing.assert_allclose(T, grid_fk.T[0], atol=ROUND_TRIP_TOL, rtol=0)


def test_unrolled_fk_function_reports_failure(d1):
    out = d1.fk_function()(np.array([5.0, -5.0, 5.0]))
    assert float(out[4]) == 0.0


def test_single_pose_shapes(d1, grid_q, grid_fk):
    T, R = d1.fk(grid_q[5])
    assert T.shape == (3,) and R.shape == (3, 3)
    np.testing.assert_allclose(T, grid_fk.T[5], atol=ROUND_TRIP_TOL, rtol=0)
    assert d1.ik(T, R).shape == (3,)
    assert d1.ik_links(T, R).shape == (6,)


# ------------------------------------------------------------------ parallelogram model
def _parallelogram_model(R_T0: np.ndarray, start: np.ndarray | None, v_per_arm: bool) -> tuple[SixLinkClosure, KinematicParameters]:
    """Six-link model from the 3-link D1 model 1: A0_ij = As_i + R_T0 B0_ij, v_ij = v_i, L_ij = L_i."""
    kp = load_parameters("D1").kinematics
    rng = np.random.default_rng(7)
    B0 = rng.uniform(-0.2, 0.2, size=(6, 3))
    arm = [0, 1, 1, 2, 2, 2]
    A0 = kp.As[arm] + B0 @ R_T0.T
    v = kp.v if v_per_arm else kp.v[arm]
    model = SixLinkClosure(kp.L[arm], A0, v, B0, v_per_arm=v_per_arm, R0=start, name="parallelogram")
    return model, kp


_R_D1 = Rotation.from_euler("ZYZ", [85.078, 100.678, -88.506], degrees=True).as_matrix()
_TILT = Rotation.from_rotvec(np.radians(START_PERTURBATION_DEG) * np.array([0.6, -0.48, 0.64])).as_matrix()
PARALLELOGRAM_CASES = [
    ("d1_orientation_estimated_start", _R_D1, None, False),
    ("d1_orientation_tilted_start", _R_D1, _R_D1 @ _TILT, False),
    ("identity_tilted_start", np.eye(3), _TILT, False),
    ("identity_estimated_start_v_per_arm", np.eye(3), None, True),
    ("d1_orientation_tilted_start_v_per_arm", _R_D1, _TILT @ _R_D1, True),
]


@pytest.mark.parametrize(
    "R_T0, start, v_per_arm", [c[1:] for c in PARALLELOGRAM_CASES], ids=[c[0] for c in PARALLELOGRAM_CASES]
)
def test_parallelogram_model_is_the_three_link_model(R_T0, start, v_per_arm, grid_q):
    """Exact parallelograms: orientation stays R_T0 and T is the 3-link trilateration (eq. 4.9).

    The tilted starts make Newton work (the start is 3 deg off); the identity cases sit at
    the absolute-ZYZ gimbal lock, which the relative Euler angles avoid.
    """
    model, kp = _parallelogram_model(R_T0, start, v_per_arm)
    q = grid_q[:: max(1, len(grid_q) // 60)]
    res = model.fk_solve(q)
    np.testing.assert_allclose(res.T, GantryTau3Kinematics(kp).fk(q), atol=PARALLELOGRAM_TOL, rtol=0)
    np.testing.assert_allclose(res.R, np.broadcast_to(R_T0, res.R.shape), atol=PARALLELOGRAM_TOL, rtol=0)
    if start is not None:
        assert res.iterations.min() >= 2  # the tilted start is not already the answer


# ------------------------------------------------------------------ interface pieces
@pytest.mark.parametrize("arm", range(3))
def test_arm_parameters_follow_the_links(d1, arm):
    names = np.array(d1.parameter_names())
    links = SIX_LINKS[arm]
    got = set(names[d1.arm_parameter_indices(arm)])
    expected = {f"{k}_{l}{c}" for l in links for k in ("A0", "v", "B0") for c in ("_x", "_y", "_z")}
    expected |= {f"L_{l}" for l in links}
    assert got == expected


def test_v_per_arm_parameter_names():
    model, _ = _parallelogram_model(np.eye(3), None, True)
    assert model.n_parameters == 51
    assert "v_2_y" in model.parameter_names() and "v_2a_y" not in model.parameter_names()
    names = np.array(model.parameter_names())
    assert {"v_3_x", "v_3_y", "v_3_z"} <= set(names[model.arm_parameter_indices(2)])


def test_with_parameters_round_trip(d1, grid_q, grid_fk):
    same = d1.with_parameters(d1.parameter_vector())
    np.testing.assert_array_equal(same.parameter_vector(), d1.parameter_vector())
    np.testing.assert_array_equal(same.R0, d1.R0)
    T, _ = same.fk(grid_q[:5])
    np.testing.assert_allclose(T, grid_fk.T[:5], atol=ROUND_TRIP_TOL, rtol=0)


def test_transformed_model_moves_the_poses(d1, grid_q, grid_fk):
    """Frame change x' = R x + t: FK gives R T + t and R R_T; B0 (plate frame) is unchanged."""
    Rf = Rotation.from_euler("xyz", [10.0, -25.0, 140.0], degrees=True).as_matrix()
    t = np.array([1.0, -2.0, 0.5])
    moved = d1.transformed(Rf, t)
    np.testing.assert_array_equal(moved.B0, d1.B0)
    np.testing.assert_allclose(moved.R0, Rf @ d1.R0, atol=1e-15, rtol=0)
    T, R = moved.fk(grid_q[:20])
    np.testing.assert_allclose(T, grid_fk.T[:20] @ Rf.T + t, atol=ROUND_TRIP_TOL, rtol=0)
    np.testing.assert_allclose(R, np.einsum("ij,njk->nik", Rf, grid_fk.R[:20]), atol=ROUND_TRIP_TOL, rtol=0)


def test_link_points_shapes(d1):
    p = ca.SX.sym("p", d1.n_parameters)
    A, B, L = d1.link_points(p, ca.SX.sym("q", 3), ca.SX.sym("T", 3), ca.SX.sym("R", 3, 3), 2)
    assert A.shape == (3, 3) and B.shape == (3, 3) and L.shape == (3, 1)


# ------------------------------------------------------------------ failures
def test_far_joint_values_do_not_converge(d1):
    with pytest.raises(ConvergenceError, match=r"pose row 0 .*do not intersect"):
        d1.fk([5.0, -5.0, 5.0])


def test_one_iteration_is_not_enough(d1, grid_q):
    with pytest.raises(ConvergenceError, match=r"pose row 0 .*within 1 Newton iterations: max \|q - f_ik\(X\)\|"):
        d1.fk(grid_q[:1], max_iter=1)


def test_failing_row_is_named(d1, grid_q):
    q = grid_q[:5].copy()
    q[3] = [5.0, -5.0, 5.0]
    with pytest.raises(ConvergenceError, match=r"pose row 3 .*1 of 5 pose\(s\) failed"):
        d1.fk(q)


def test_unreachable_pose_names_row_and_link(d1, grid_fk):
    T = grid_fk.T[:3].copy()
    T[1] = [5.0, 5.0, 5.0]
    with pytest.raises(UnreachablePoseError, match=r"\(row 1\) is unreachable: link\(s\) 1, 2a, 2b"):
        d1.ik(T, grid_fk.R[:3])


def _tmp_file(tmp_path, replace: tuple[str, str] | None = None, drop: str | None = None):
    text = (resources.files("gtmodel.robots") / "data" / "D1_six_link.toml").read_text()
    if replace is not None:
        assert replace[0] in text
        text = text.replace(replace[0], replace[1], 1)
    if drop is not None:
        text = "\n".join(line for line in text.splitlines() if not line.startswith(drop))
    path = tmp_path / "six.toml"
    path.write_text(text)
    return path


_NOT_ROT = np.diag([1.0, 1.0, 1.1])
BAD_ARGUMENTS = [
    ("L_shape", lambda m: SixLinkClosure(m.L[:5], m.A0, m.v, m.B0), InputError, r"L: expected shape \(6,\)"),
    ("L_negative", lambda m: SixLinkClosure(-m.L, m.A0, m.v, m.B0), InputError, "L: expected positive"),
    ("v_norm", lambda m: SixLinkClosure(m.L, m.A0, 3 * m.v, m.B0), InputError, "v: expected guideway directions"),
    ("v_per_arm_shape", lambda m: SixLinkClosure(m.L, m.A0, m.v, m.B0, v_per_arm=True), InputError, r"v: expected shape \(3, 3\)"),
    ("R0_not_rotation", lambda m: SixLinkClosure(m.L, m.A0, m.v, m.B0, R0=_NOT_ROT), InputError, "R0: expected a rotation matrix"),
    ("A0_nan", lambda m: SixLinkClosure(m.L, np.full((6, 3), np.nan), m.v, m.B0), InputError, "A0: expected finite"),
    ("ik_T_shape", lambda m: m.ik(np.zeros((2, 2))), InputError, r"T: expected shape \(3,\) or \(N, 3\)"),
    ("ik_R_not_rotation", lambda m: m.ik(np.zeros(3), _NOT_ROT), InputError, "R: matrix 0 is not a rotation"),
    ("ik_R_count", lambda m: m.ik(np.zeros((2, 3)), np.stack([np.eye(3)] * 3)), InputError, r"R: expected shape \(3, 3\) or \(2, 3, 3\)"),
    ("ik_configuration", lambda m: m.ik(np.zeros(3), configuration=9), InputError, "configuration: expected an integer 0-7"),
    ("fk_q_shape", lambda m: m.fk(np.zeros(4)), InputError, r"q: expected shape \(3,\) or \(N, 3\)"),
    ("fk_q_nan", lambda m: m.fk([[0.0, 0.0, 0.0], [np.nan, 0.0, 0.0]]), InputError, "q: row 1 is not finite"),
    ("fk_max_iter", lambda m: m.fk(np.zeros(3), max_iter=-1), InputError, "max_iter: expected a non-negative integer"),
    ("fk_solution", lambda m: m.fk(np.zeros(3), solution=0), InputError, r"solution: expected \+1 or -1"),
    ("fk_function_n_iter", lambda m: m.fk_function(n_iter=0), InputError, "n_iter: expected a positive integer"),
    ("transformed_R", lambda m: m.transformed(_NOT_ROT, np.zeros(3)), InputError, "R: expected a rotation matrix"),
    ("transformed_t", lambda m: m.transformed(np.eye(3), np.zeros(2)), InputError, r"t: expected shape \(3,\)"),
    ("with_parameters_size", lambda m: m.with_parameters(np.zeros(5)), InputError, "expected 60 finite parameters, got 5"),
    ("link_points_arm", lambda m: m.link_points(ca.SX.sym("p", 60), ca.SX.sym("q", 3), ca.SX.sym("T", 3), ca.SX.eye(3), 3), InputError, "arm must be one of 0..2"),
    ("closure_arm", lambda m: m.closure_function(5), InputError, "arm must be one of 0..2"),
    ("in_workspace_no_limits", lambda m: SixLinkClosure(m.L, m.A0, m.v, m.B0).in_workspace(np.zeros(3)), InputError, "in_workspace needs limits"),
    ("estimate_degenerate", lambda m: estimate_nominal_orientation(m.A0, np.zeros((6, 3))), InputError, "B0: the within-arm differences .* span no plane"),
]


@pytest.mark.parametrize("call, error, match", [c[1:] for c in BAD_ARGUMENTS], ids=[c[0] for c in BAD_ARGUMENTS])
def test_bad_arguments(d1, call, error, match):
    with pytest.raises(error, match=match):
        call(d1)


BAD_FILES = [
    ("unknown_name", "X9", None, r"unknown six-link parameter set 'X9'"),
    ("three_link_set", "D1", None, r"D1\.toml \(shipped\): a 3-link parameter set"),
    ("missing_link", ('"3b" = 2.04352, "3c" = 2.04352 }', '"3b" = 2.04352 }'), None, r"six\.toml: missing field 'six_link\.L\.3c'"),
    ("negative_length", ('"1" = 2.04422', '"1" = -2.0'), None, r"six\.toml: field 'six_link\.L\.1': expected a positive number"),
    ("short_point", ('"2a" = [-3.13100, -3.52723, 0.79856]', '"2a" = [-3.13100, -3.52723]'), None, r"field 'six_link\.A0\.2a': expected an array of shape \(3,\)"),
    ("wrong_model", ('model = "six_link"', 'model = "three_link"'), None, r"field 'model': expected 'six_link'"),
    ("unknown_field", ("v_per_arm = false", "v_per_arm = false\nspeed = 3"), None, r"unknown field 'six_link\.speed'"),
    ("missing_limits", None, "joint_angle_max_deg", r"missing field 'limits\.joint_angle_max_deg'"),
    ("bad_travel", ("cart_travel = [[-0.65, 0.70]", "cart_travel = [[0.70, -0.65]"), None, r"field 'limits\.cart_travel': expected rows"),
    ("not_toml", ('name = "D1_six_link"', "name = "), None, r"six\.toml: invalid TOML"),
]


@pytest.mark.parametrize("replace, drop, match", [c[1:] for c in BAD_FILES], ids=[c[0] for c in BAD_FILES])
def test_bad_parameter_files(tmp_path, replace, drop, match):
    target = replace if isinstance(replace, str) else _tmp_file(tmp_path, replace, drop)
    with pytest.raises(ParameterError, match=match):
        load_six_link(target)


def test_file_path_loads_the_same(tmp_path, d1):
    m = load_six_link(_tmp_file(tmp_path))
    np.testing.assert_array_equal(m.parameter_vector(), d1.parameter_vector())


def test_constants_are_sane():
    assert 0 < FK_TOLERANCE < 1e-9
    assert FK_MAX_ITER >= FK_UNROLLED_ITER >= 1
