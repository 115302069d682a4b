"""Synthetic measurements: reproducibility, exactness without noise, noise statistics,
actuator-error magnitudes (Dressler (2012), Table 4.1) and workspace poses.

Independent references, per test: the closed-form trilateration FK of the 3-link model
and the closure equations evaluated by hand in NumPy (exact data); the device sigma
(noise statistics); the Table 4.1 figures with a line fit by ``numpy.polyfit`` (actuator
errors); :meth:`GantryTau3Kinematics.in_workspace` (poses of the generic sampler).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gtmodel.calibration.synthetic import (
    BACKLASH_M,
    LASER_TRACKER,
    NO_NOISE,
    STEREO_VISION,
    TABLE_4_1_MEAN_RESIDUAL_M,
    ActuatorErrors,
    DeviceNoise,
    backlash_directions,
    device_noise,
    synthetic_cart_measurements,
    synthetic_measurements,
)
from gtmodel.calibration.poses import L1_GRID_STEP_M, grid_poses, link_angles, random_poses
from gtmodel.robots.deviated import DeviatedClosure, guideway_axes
from gtmodel.errors import InputError
from gtmodel.robots.closure import ThreeLinkClosure, zyz_to_rotation
from gtmodel.robots.kinematics import GantryTau3Kinematics

#: Synthetic T without noise vs the closed-form FK [m] (Newton polishes to ~1e-15).
EXACT_T_TOLERANCE = 1e-9
#: Closure residual ||A - T||^2 - L^2 at exact synthetic data [m^2].
CLOSURE_TOLERANCE = 1e-12
#: Relative tolerance of a sample standard deviation (N = 2000: its own relative sampling
#: error is ~1/sqrt(2N) = 1.6 %).
NOISE_STD_RTOL = 0.10
#: Relative tolerance of the mean deviation from a linear fit vs Table 4.1.
TABLE_4_1_RTOL = 0.20
N_NOISE = 2000


@pytest.fixture(scope="module")
def l1() -> ThreeLinkClosure:
    return ThreeLinkClosure("L1")


@pytest.fixture(scope="module")
def kin() -> GantryTau3Kinematics:
    return GantryTau3Kinematics("L1")


@pytest.fixture(scope="module")
def q_random(l1) -> np.ndarray:
    return random_poses(l1, N_NOISE, seed=7)


def test_same_seed_same_data_other_seed_other_data(l1):
    """A seed reproduces a data set bit for bit (noise, backlash directions); another seed does not."""
    q = random_poses(l1, 20, seed=1)
    errors = ActuatorErrors.table_4_1()
    a = synthetic_measurements(l1, q, actuator_errors=errors, seed=5, direction="random", orientation=True)
    b = synthetic_measurements(l1, q, actuator_errors=errors, seed=5, direction="random", orientation=True)
    c = synthetic_measurements(l1, q, actuator_errors=errors, seed=6, direction="random", orientation=True)
    np.testing.assert_array_equal(a.T, b.T)
    np.testing.assert_array_equal(a.quat, b.quat)
    assert np.all(np.abs(a.T - c.T) > 0)
    np.testing.assert_array_equal(random_poses(l1, 20, seed=1), q)
    assert not np.array_equal(random_poses(l1, 20, seed=2), q)


def test_exact_data_satisfy_the_closure_equations(l1):
    """No noise, no actuator errors: T equals the closed-form FK and ||As + q v - T||^2 - L^2 ~ 0 (NumPy, by hand)."""
    q = random_poses(l1, 50, seed=3)
    ms = synthetic_measurements(l1, q, noise=NO_NOISE)
    T_fk, _ = l1.fk(q)
    np.testing.assert_allclose(ms.T, T_fk, rtol=0, atol=EXACT_T_TOLERANCE)
    k = l1.kinematics
    A = np.stack([k.As[i] + q[:, [i]] * k.v[i] for i in range(3)])  # (arm, pose, xyz)
    r = np.sum((A - ms.T) ** 2, axis=2) - np.asarray(k.L)[:, None] ** 2
    np.testing.assert_array_less(np.abs(r), CLOSURE_TOLERANCE)


def test_exact_data_with_actuator_errors_satisfy_the_deviated_closure(l1):
    """With actuator errors and backlash, T satisfies ||As + q v + d(q, dir) - T|| = L with d from
    ActuatorErrors.deviation (NumPy), the known true deviation, and differs from the linear-model FK."""
    errors = ActuatorErrors.table_4_1()
    q = random_poses(l1, 40, seed=4)
    dirs = backlash_directions(q, "pose_order")
    ms = synthetic_measurements(l1, q, noise=NO_NOISE, actuator_errors=errors, direction="pose_order")
    k = l1.kinematics
    axes = guideway_axes(l1)
    A = np.stack([k.As[i] + q[:, [i]] * k.v[i] + errors.deviation(i, q[:, i], dirs[:, i], axes[i]) for i in range(3)])
    r = np.sum((A - ms.T) ** 2, axis=2) - np.asarray(k.L)[:, None] ** 2
    np.testing.assert_array_less(np.abs(r), CLOSURE_TOLERANCE)  # every (arm, pose) element
    assert np.mean(np.linalg.norm(ms.T - l1.fk(q)[0], axis=1)) > 20e-6


@pytest.mark.parametrize("device", [LASER_TRACKER, STEREO_VISION], ids=lambda d: d.name)
def test_position_noise_statistics(l1, q_random, device):
    """Sample std of T - FK(q) per axis is the device sigma (within 10 %), mean ~ 0, for N = 2000."""
    ms = synthetic_measurements(l1, q_random, noise=device, seed=11)
    e = ms.T - l1.fk(q_random)[0]
    np.testing.assert_allclose(e.std(axis=0, ddof=1), device.position_sigma_m, rtol=NOISE_STD_RTOL)
    assert np.all(np.abs(e.mean(axis=0)) < 4 * device.position_sigma_m / np.sqrt(N_NOISE))


def test_orientation_noise_statistics(l1, q_random):
    """Measured orientations of a constant-orientation robot: rotation vectors with std = sigma (10 %)."""
    ms = synthetic_measurements(l1, q_random, noise=LASER_TRACKER, seed=12, orientation=True)
    r = Rotation.from_quat(ms.quat, scalar_first=True).as_rotvec()
    np.testing.assert_allclose(r.std(axis=0, ddof=1), LASER_TRACKER.orientation_sigma_rad, rtol=NOISE_STD_RTOL)


def test_stereo_vision_mean_error_is_table_5_6():
    """Per-axis sigma of the stereo camera reproduces the mean error 1.7 mm of Table 5.6 (chi, 3 dof)."""
    assert STEREO_VISION.mean_position_error_m == pytest.approx(1.7e-3, rel=1e-12)
    assert device_noise("laser_tracker") is LASER_TRACKER


@pytest.mark.parametrize("arm", [0, 1, 2])
def test_actuator_errors_match_table_4_1(l1, arm):
    """Mean deviation of a surveyed cart path from a linear fit (numpy.polyfit, per coordinate)
    is Table 4.1 (32, 77, 54 um) within 20 %; survey with laser-tracker noise in a rotated frame."""
    errors = ActuatorErrors.table_4_1()
    g = np.round(np.arange(-0.65, 0.7001, 0.01), 10)
    Rf = np.array([zyz_to_rotation(0.3 * i, 0.1, -0.2) for i in range(3)])
    cart = synthetic_cart_measurements(l1, errors, g, noise=LASER_TRACKER, seed=2, frames=(Rf, np.ones((3, 3))))
    q, P = cart.q[arm], cart.positions[arm]
    fit = np.column_stack([np.polyval(np.polyfit(q, P[:, c], 1), q) for c in range(3)])
    mean = np.mean(np.linalg.norm(P - fit, axis=1))
    assert mean == pytest.approx(TABLE_4_1_MEAN_RESIDUAL_M[arm], rel=TABLE_4_1_RTOL)


def test_backlash_is_the_gap_between_directions():
    """The deviation for direction +1 and -1 differs by the backlash along the guideway (closed form)."""
    errors = ActuatorErrors.table_4_1()
    q = np.linspace(-0.6, 0.6, 7)
    for_arm = [errors.deviation(i, q, -1.0) - errors.deviation(i, q, 1.0) for i in range(3)]
    np.testing.assert_allclose(np.array(for_arm), np.broadcast_to([BACKLASH_M, 0, 0], (3, 7, 3)), rtol=0, atol=1e-18)


def test_backlash_directions_from_pose_order():
    """Direction = sign of the last motion per cart; a cart at rest keeps it; +1 at the first pose."""
    q = np.array([[0, 0, 0], [1, -1, 0], [1, 0, -1], [0.5, 0, -1]], dtype=float)
    expected = [[1, 1, 1], [1, -1, 1], [1, 1, -1], [-1, 1, -1]]
    np.testing.assert_array_equal(backlash_directions(q, "pose_order"), expected)


def test_l1_grid_size(l1, kin):
    """The L1 grid step gives 700-800 poses (Table 5.1: 779), all inside the L1 workspace."""
    q = grid_poses(l1, L1_GRID_STEP_M)
    assert 700 <= q.shape[0] <= 800
    assert np.all(kin.in_workspace(l1.fk(q)[0]))


def test_generic_sampler_stays_in_the_workspace(l1, kin):
    """The generic path (any ClosureModel: sample q, FK, link angles by AD) gives poses that the
    3-link workspace test (closed-form IK and link cosines) accepts."""
    generic = DeviatedClosure(l1, ActuatorErrors.none())
    q = random_poses(generic, 100, seed=9)
    T, R = generic.fk(q)
    assert np.all(kin.in_workspace(T))
    np.testing.assert_allclose(link_angles(generic, q, T, R), kin.link_angles(T), rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda m: grid_poses(m, 0.0), r"step: expected a positive grid spacing"),
        (lambda m: random_poses(m, 0), r"n: expected a positive number of poses"),
        (lambda m: synthetic_measurements(m, np.zeros((2, 2))), r"q: expected finite actuator values of shape \(N, 3\)"),
        (lambda m: synthetic_measurements(m, np.zeros((2, 3)), noise="ruler"), r"unknown measuring device 'ruler'"),
        (
            lambda m: synthetic_measurements(m, np.zeros((2, 3)), actuator_errors=ActuatorErrors.none(), direction="up"),
            r"direction: expected 'pose_order', 'random'",
        ),
        (lambda m: synthetic_cart_measurements(m, q_grid=[0.1, 0.0]), r"q_grid \(arm 1\): expected >= 2 strictly increasing"),
        (lambda m: ActuatorErrors(np.zeros(3), -np.ones(3), np.zeros(3)), r"straightness_amplitude_m: expected non-negative"),
        (lambda m: DeviceNoise(-1.0, 0.0, "x"), r"position_sigma_m: expected a non-negative"),
        (lambda m: grid_poses(ThreeLinkClosure(m.kinematics), 0.1), r"no limits known; pass limits"),
    ],
    ids=["grid-step", "n-poses", "q-shape", "device", "direction", "cart-grid", "negative-amplitude", "negative-sigma", "no-limits"],
)
def test_bad_inputs(l1, call, match):
    """Bad arguments raise InputError naming the argument."""
    with pytest.raises(InputError, match=match):
        call(l1)
