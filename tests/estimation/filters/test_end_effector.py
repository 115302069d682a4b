"""The 19-D end-effector state model (Cvitanic (2021), eqs. (21)-(29)).

Independent references: central finite differences of the CasADi transition and measurement
for the AD Jacobians; SciPy's Rotation (rotation-vector exponential) for the quaternion
kinematics of a rotation about a fixed axis; the closed-form centripetal and tangential
acceleration of a rigid body for the lever arm (29); control.c2d's matrices against the
closed form; StationaryKalman's Q for the process noise.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gtmodel._geometry import quat_exp as quaternion_from_rotation_vector
from gtmodel._geometry import quat_mul as quaternion_multiply
from gtmodel._geometry import quaternion_to_rotation as quaternion_to_rotation_matrix
from gtmodel.errors import InputError
from gtmodel.estimation.filters.end_effector import (
    IMU_ROTATION,
    IMU_TRANSLATION_M,
    EndEffectorModel,
    constant_acceleration,
)
from gtmodel.estimation.filters.kalman import StationaryKalman

#: The specification: AD Jacobians equal central finite differences to 1e-6 relative.
FD_TOLERANCE = 1e-6


def _random_state(rng, rotation=True, w_scale=1.0):
    if not rotation:
        return rng.normal(size=9)
    quat = rng.normal(size=4)
    return np.r_[rng.normal(size=9), quat / np.linalg.norm(quat), w_scale * rng.normal(size=3), w_scale * rng.normal(size=3)]


def _central_difference(fun, x, h=1e-6):
    cols = []
    for i in range(x.size):
        step = h * max(1.0, abs(x[i]))
        e = np.zeros_like(x)
        e[i] = step
        cols.append((np.asarray(fun(x + e)).ravel() - np.asarray(fun(x - e)).ravel()) / (2 * step))
    return np.column_stack(cols)


def _scipy_quat(quat):
    """Scalar-first [w, x, y, z] -> SciPy's scalar-last Rotation."""
    return Rotation.from_quat(np.r_[quat[1:], quat[0]])


@pytest.mark.parametrize("rotation", [True, False])
@pytest.mark.parametrize("dt, w_scale", [(0.001, 1.0), (0.01, 3.0), (0.5, 2.0)])  # dt 0.5: the large-angle branch of exp
@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("which", ["transition", "measurement"])
def test_jacobians_equal_finite_differences(rotation, dt, w_scale, seed, which):
    """AD Jacobian vs central finite differences of the CasADi Function itself, at a random state with w, alpha != 0."""
    model = EndEffectorModel(dt, rotation=rotation)
    x = _random_state(np.random.default_rng(seed), rotation, w_scale)
    fun = getattr(model, which)
    jac = np.asarray(getattr(model, f"{which}_jacobian")(x))
    fd = _central_difference(fun, x)
    np.testing.assert_allclose(jac, fd, rtol=FD_TOLERANCE, atol=FD_TOLERANCE * np.abs(jac).max())


def test_jacobian_finite_at_zero_rotation():
    """The exponential map is smooth at phi = 0 (Taylor branch): the Jacobian is finite and matches FD there."""
    model = EndEffectorModel(0.001)
    x = np.r_[np.zeros(9), 1.0, 0.0, 0.0, 0.0, np.zeros(6)]
    jac = np.asarray(model.transition_jacobian(x))
    assert np.all(np.isfinite(jac))
    np.testing.assert_allclose(jac, _central_difference(model.transition, x), rtol=0, atol=FD_TOLERANCE)


def test_quaternion_stays_unit():
    """2000 transitions at a fast random rotation: |quat| = 1 to rounding (the normalisation of (28))."""
    model = EndEffectorModel(0.01)
    x = _random_state(np.random.default_rng(3), w_scale=5.0)
    run = model.transition.mapaccum("run", 2000)
    xs = np.asarray(run(x))  # (19, 2000)
    norms = np.linalg.norm(xs[9:13], axis=0)
    np.testing.assert_allclose(norms, 1.0, rtol=0, atol=1e-14)


@pytest.mark.parametrize("alpha_scale", [0.0, 0.7])
def test_transition_of_a_fixed_axis_rotation_is_the_quaternion_exponential(alpha_scale):
    """Fixed axis n, w(t) = (w0 + alpha t) n: quat(t) = quat0 (x) exp((w0 t + alpha t^2 / 2) n) (SciPy's from_rotvec)."""
    dt, n_steps = 0.002, 500
    model = EndEffectorModel(dt)
    axis = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
    q0 = np.array([0.3, -0.5, 0.1, 0.8]) / np.linalg.norm([0.3, -0.5, 0.1, 0.8])
    w0, alpha = 2.5, alpha_scale
    x0 = np.r_[np.zeros(9), q0, w0 * axis, alpha * axis]
    xs = np.asarray(model.transition.mapaccum("run", n_steps)(x0))
    t = dt * n_steps
    expected = _scipy_quat(q0) * Rotation.from_rotvec((w0 * t + alpha * t**2 / 2) * axis)
    got = _scipy_quat(xs[9:13, -1])
    assert (got.inv() * expected).magnitude() < 1e-12
    np.testing.assert_allclose(xs[13:16, -1], (w0 + alpha * t) * axis, rtol=1e-12)


@pytest.mark.parametrize("phi", [[0.0, 0.0, 0.0], [1e-4, -2e-4, 3e-5], [0.15, 0.1, -0.05], [1.0, -2.0, 0.5]])
def test_exponential_map_against_scipy(phi):
    """Both branches of quaternion_from_rotation_vector equal SciPy's from_rotvec (scalar-last, reordered)."""
    q = np.asarray(quaternion_from_rotation_vector(np.array(phi))).ravel()
    ref = Rotation.from_rotvec(phi).as_quat()
    np.testing.assert_allclose(q, np.r_[ref[3], ref[:3]], rtol=0, atol=1e-15)


def test_rotation_matrix_and_product_against_scipy():
    """R(p (x) q) = R(p) R(q) and R(quat) equals SciPy's as_matrix."""
    rng = np.random.default_rng(4)
    p, q = (v / np.linalg.norm(v) for v in rng.normal(size=(2, 4)))
    pq = np.asarray(quaternion_multiply(p, q)).ravel()
    np.testing.assert_allclose(np.asarray(quaternion_to_rotation_matrix(pq)), (_scipy_quat(p) * _scipy_quat(q)).as_matrix(), atol=1e-15)


@pytest.mark.parametrize("w, alpha", [([0.0, 0.0, 2.0], [0.0, 0.0, 0.0]), ([0.0, 0.0, 2.0], [0.0, 0.0, 5.0]), ([1.0, -0.5, 0.3], [0.2, 0.4, -0.1])])
def test_lever_arm_closed_form(w, alpha):
    """(29) for the IMU at rest on the axis: a_target = alpha x r - |w|^2 r_perp (centripetal), closed form."""
    model = EndEffectorModel(0.001)
    w, alpha, r = np.array(w), np.array(alpha), np.array(IMU_TRANSLATION_M)
    got = np.asarray(model.lever_arm_acceleration(np.zeros(3), w, alpha)).ravel()
    n = w / np.linalg.norm(w)
    r_perp = r - (r @ n) * n
    np.testing.assert_allclose(got, np.cross(alpha, r) - (w @ w) * r_perp, rtol=1e-13, atol=1e-15)


def test_measurement_of_a_body_rotating_about_the_imu():
    """Body pivoting about the IMU: the target's world acceleration R(quat) (alpha x r_T + w x (w x r_T)), r_T = R_TI t:
    the modelled accelerometer reads 0 and the gyro R_TI^T w (closed form of the rigid body)."""
    model = EndEffectorModel(0.001)
    rng = np.random.default_rng(5)
    x = _random_state(rng)
    quat, w, alpha = x[9:13], x[13:16], x[16:19]
    r_t = IMU_ROTATION @ np.array(IMU_TRANSLATION_M)
    x[6:9] = _scipy_quat(quat).as_matrix() @ (np.cross(alpha, r_t) + np.cross(w, np.cross(w, r_t)))
    z = np.asarray(model.measurement(x)).ravel()
    ms = model.measurement_slices
    np.testing.assert_allclose(z[ms["accelerometer"]], 0.0, atol=1e-14)
    np.testing.assert_allclose(z[ms["gyro"]], [-w[0], w[1], -w[2]], rtol=1e-15)  # Ry(pi)^T w
    np.testing.assert_allclose(z[ms["position"]], x[0:3])
    np.testing.assert_allclose(z[ms["quaternion"]], quat)


def test_translation_only_measurement_rotates_the_acceleration():
    """rotation=False: a_m = (R(orientation) R_TI)^T a, no lever-arm term (w = 0); closed form with SciPy's matrix."""
    q = np.array([0.9, 0.1, -0.3, 0.2]) / np.linalg.norm([0.9, 0.1, -0.3, 0.2])
    model = EndEffectorModel(0.004, rotation=False, orientation=q)
    x = np.arange(9.0)
    z = np.asarray(model.measurement(x)).ravel()
    np.testing.assert_allclose(z[3:6], (_scipy_quat(q).as_matrix() @ IMU_ROTATION).T @ x[6:9], rtol=1e-13)
    assert model.is_linear and model.nx == 9 and model.nz == 6


def test_constant_acceleration_closed_form():
    """control.c2d of the triple integrator: A1 = [[1, dt, dt^2/2], [0, 1, dt], [0, 0, 1]], G1 = [dt^3/6, dt^2/2, dt]."""
    dt = 0.004
    a, g = constant_acceleration(dt, 3)
    a1 = np.array([[1, dt, dt**2 / 2], [0, 1, dt], [0, 0, 1]])
    np.testing.assert_allclose(a, np.kron(a1, np.eye(3)), rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(g, np.kron(np.array([[dt**3 / 6], [dt**2 / 2], [dt]]), np.eye(3)), rtol=1e-12, atol=1e-20)


def test_process_noise_is_the_stationary_kalman_model():
    """The 9-D Q equals StationaryKalman's G diag(sigma^2) G^T (d = 3, per-axis jerk)."""
    jerk = np.array([50.0, 100.0, 150.0])
    kf = StationaryKalman(dt=0.001, jerk_noise=jerk, position_noise=1e-5, accelerometer_noise=0.01, d=3)
    model = EndEffectorModel(0.001, rotation=False)
    np.testing.assert_allclose(model.process_noise(jerk), kf.Q, rtol=1e-14, atol=0)


def test_process_noise_rotation_blocks():
    """19-D Q: the angular-jerk block kron(g g^T, sigma^2) with g = [dt^2/2, dt], the quaternion term on the diagonal."""
    dt = 0.001
    q = EndEffectorModel(dt).process_noise(10.0, 2.0, quaternion=1e-8)
    g = np.array([dt**2 / 2, dt])
    np.testing.assert_allclose(q[13:19, 13:19], np.kron(np.outer(g, g), 4.0 * np.eye(3)), rtol=1e-12)
    np.testing.assert_allclose(q[9:13, 9:13], 1e-16 * np.eye(4))
    eig = np.linalg.eigvalsh(q)
    assert eig.min() >= -1e-14 * eig.max()  # positive semi-definite up to rounding


def _model(**kw):
    return EndEffectorModel(**{"dt": 0.001, **kw})


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: _model(dt=0.0), "dt"),
        (lambda: _model(dt=-1e-3), "dt"),
        (lambda: _model(rotation="yes"), "rotation"),
        (lambda: _model(imu_translation=[0.1, 0.2]), "imu_translation"),
        (lambda: _model(imu_translation=[0.1, np.nan, 0.0]), "imu_translation"),
        (lambda: _model(imu_rotation=np.diag([1.0, 1.0, -1.0])), "imu_rotation"),
        (lambda: _model(imu_rotation=np.eye(2)), "imu_rotation"),
        (lambda: _model(rotation=False, orientation=[0, 0, 0, 0]), "orientation.*nonzero norm"),
        (lambda: _model().process_noise(-1.0, 1.0), "jerk"),
        (lambda: _model().process_noise(1.0, [1.0, -1.0, 1.0]), "angular_jerk"),
        (lambda: _model().process_noise(1.0, [1.0, 1.0]), "angular_jerk"),
        (lambda: _model().process_noise(1.0, 1.0, quaternion=0.0), "quaternion"),
        (lambda: _model().measurement_noise(-1e-6, 1e-3, 1e-4, 1e-3), "position"),
        (lambda: _model().measurement_noise(1e-6, 1e-3), "orientation"),
        (lambda: constant_acceleration(0.001, 0), "d"),
    ],
)
def test_bad_input(call, match):
    with pytest.raises(InputError, match=match):
        call()
