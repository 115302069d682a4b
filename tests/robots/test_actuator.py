"""The piecewise-linear actuator model (Dressler (2012), eq. 5.7) as a closure model.

Independent references, per test: ``numpy.interp`` (the interpolation); the closed-form
trilateration FK of the linear 3-link model (straight guideways, after the frame fit);
the known true deviation of a bent guideway, :meth:`ActuatorErrors.deviation`, and the
FK of the true robot; the parallelogram property of the six-link layout (with link
offsets equal to the plate offsets the plate keeps its orientation and the TCP follows
the 3-link model with ``As_i - B0_i1``); the six-link model's own FK for the frame fit of a
six-link model; for the calibration, the survey frames the synthetic survey was taken in
and the FK of the true robot (bent guideways).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from scipy.spatial.transform import Rotation

from gtmodel.calibration.kinematic import CalibrationProblem
from gtmodel.calibration.measurements import CartMeasurements
from gtmodel.calibration.synthetic import (
    NO_NOISE,
    ActuatorErrors,
    line_fit_residuals,
    synthetic_cart_measurements,
    synthetic_measurements,
)
from gtmodel.calibration.poses import random_poses
from gtmodel.robots.deviated import DeviatedClosure, guideway_axes
from gtmodel.errors import InputError
from gtmodel.robots.actuator import SIX_LINK_LAYOUT, PiecewiseActuatorClosure, piecewise_linear
from gtmodel.robots.closure import ThreeLinkClosure, zyz_to_rotation
from gtmodel.robots.parameters import KinematicParameters
from gtmodel.robots.six_link import SixLinkClosure, load_six_link

#: Straight survey: piecewise model vs linear 3-link model after the frame fit [m].
STRAIGHT_TOLERANCE = 1e-9
#: Bent survey, 0.01 m node spacing: interpolation error bound |P''| h^2 / 8 of the cyclic
#: error (amplitude <= 0.1 mm, period 0.2 m: |P''| <= 0.1 m^-1) is 1.2 um [m].
INTERPOLATION_TOLERANCE = 1.5e-6
#: Bent survey: TCP error of the piecewise model vs the true robot [m].
BENT_FK_TOLERANCE = 5e-6
#: Interpolation vs numpy.interp: the sum of ramps accumulates rounding over the nodes
#: (~ M eps max|slope|; values O(1), slopes up to ~50 in the test).
INTERP_TOLERANCE = 1e-12

#: Calibration on exact data of bent guideways (interpolation error ~1 um, see above):
#: frame rotations [deg], link lengths [m] and the TCP vs the true robot [m].
CALIBRATED_FRAME_DEG = 0.5
CALIBRATED_L_TOLERANCE = 1e-5
CALIBRATED_TCP_TOLERANCE = 5e-6
#: LM iterations per arm allowed for that calibration (the thesis' ZYZ frame about the
#: survey origin needed 800-950 and stopped at the limit; the current one needs 4-5).
CALIBRATION_MAX_ITERATIONS = 20

SURVEY_NODES = np.round(np.arange(-0.65, 0.7001, 0.01), 10)
ROTATION_ANGLES = [(0.4, 0.05, -0.3), (2.0, 0.2, 0.1), (-1.0, 0.01, 0.7)]


@pytest.fixture(scope="module")
def l1() -> ThreeLinkClosure:
    return ThreeLinkClosure("L1")


@pytest.fixture(scope="module")
def survey_frames() -> tuple[np.ndarray, np.ndarray]:
    R = np.array([zyz_to_rotation(*a) for a in ROTATION_ANGLES])
    t = np.array([[1.8, -4.3, -0.08], [1.4, -3.9, 0.09], [0.5, -2.1, 0.04]])
    return R, t


@pytest.fixture(scope="module")
def q_test(l1) -> np.ndarray:
    q = random_poses(l1, 200, seed=21)
    return q[np.all(np.abs(q) < 0.64, axis=1)]  # inside the survey range [-0.65, 0.70]


def test_interpolation_matches_numpy_interp():
    """The sum-of-ramps expression equals numpy.interp inside the nodes and extends the end segments."""
    rng = np.random.default_rng(0)
    g = np.sort(rng.uniform(-1, 1, 12))
    v = rng.normal(size=12)
    x = ca.SX.sym("x")
    f = ca.Function("f", [x], [piecewise_linear(x, g, v)])
    xs = np.linspace(g[0], g[-1], 101)
    np.testing.assert_allclose(np.array(f.map(101)(xs[None, :])).ravel(), np.interp(xs, g, v), rtol=0, atol=INTERP_TOLERANCE)
    slope_end = (v[-1] - v[-2]) / (g[-1] - g[-2])
    assert float(f(g[-1] + 0.5)) == pytest.approx(v[-1] + 0.5 * slope_end, abs=INTERP_TOLERANCE)
    dfdx = ca.Function("df", [x], [ca.jacobian(piecewise_linear(x, g, v), x)])
    k = 5
    assert float(dfdx(0.5 * (g[k] + g[k + 1]))) == pytest.approx((v[k + 1] - v[k]) / (g[k + 1] - g[k]), rel=1e-12)


def test_straight_survey_reproduces_the_three_link_model(l1, survey_frames, q_test):
    """Straight guideways surveyed in their own frames: after the frame fit the piecewise model's FK
    equals the closed-form 3-link FK to 1e-9 m."""
    cart = synthetic_cart_measurements(l1, None, SURVEY_NODES, noise=NO_NOISE, frames=survey_frames)
    pw = PiecewiseActuatorClosure.from_model(l1, cart)
    T_pw, R_pw = pw.fk(q_test)
    np.testing.assert_allclose(T_pw, l1.fk(q_test)[0], rtol=0, atol=STRAIGHT_TOLERANCE)
    np.testing.assert_array_equal(R_pw, np.broadcast_to(np.eye(3), R_pw.shape))


def test_frame_fit_recovers_the_survey_frames(l1, survey_frames):
    """With a bent survey (a unique fit) the fitted (R_i, o_i) are the frames the survey was taken in."""
    errors = ActuatorErrors.table_4_1()
    true_robot = DeviatedClosure(l1, errors)
    cart = synthetic_cart_measurements(l1, errors, SURVEY_NODES, noise=NO_NOISE, frames=survey_frames)
    pw = PiecewiseActuatorClosure.from_model(true_robot, cart)
    for i in range(3):
        np.testing.assert_allclose(pw.frame_rotation(i), survey_frames[0][i], rtol=0, atol=1e-9)
        np.testing.assert_allclose(pw.frame_offset[i], survey_frames[1][i], rtol=0, atol=1e-8)


def test_bent_survey_follows_the_true_cart_path(l1, survey_frames, q_test):
    """Bent guideways (Table 4.1 magnitudes): between the nodes the piecewise joint points differ from
    the linear model by the known true deviation (to the interpolation error), the FK follows the true
    robot, and the best linear fit of the same survey cannot (tens of um)."""
    errors = ActuatorErrors.table_4_1()
    true_robot = DeviatedClosure(l1, errors)
    cart = synthetic_cart_measurements(l1, errors, SURVEY_NODES, noise=NO_NOISE, frames=survey_frames)
    pw = PiecewiseActuatorClosure.from_model(true_robot, cart)
    k = l1.kinematics
    axes = guideway_axes(l1)
    mid = 0.5 * (SURVEY_NODES[:-1] + SURVEY_NODES[1:])
    dev_pw, dev_true = [], []  # (arm, mid-node, xyz)
    for i in range(3):
        qs = np.zeros((mid.size, 3))
        qs[:, i] = mid
        dev_pw.append(pw.joint_points(qs)[:, i] - (k.As[i] + mid[:, None] * k.v[i]))
        dev_true.append(errors.deviation(i, mid, 1.0, axes[i]))
    np.testing.assert_allclose(np.array(dev_pw), np.array(dev_true), rtol=0, atol=INTERPOLATION_TOLERANCE)
    np.testing.assert_array_less(50e-6, np.max(np.linalg.norm(dev_true, axis=2), axis=1))  # every arm is bent
    T_true, _ = true_robot.fk(q_test)
    err_pw = np.linalg.norm(pw.fk(q_test)[0] - T_true, axis=1)
    # best linear actuators: a least-squares line through each arm's true joint points
    As, v, line_residual = np.empty((3, 3)), np.empty((3, 3)), np.empty(3)
    for i in range(3):
        P = cart.positions[i] @ survey_frames[0][i].T + survey_frames[1][i]
        coef = np.polyfit(cart.q[i], P, 1)
        v[i], As[i] = coef[0], coef[1]
        line_residual[i] = line_fit_residuals(cart.q[i], P).mean()
    np.testing.assert_array_less(20e-6, line_residual)  # no arm is a straight line
    linear = ThreeLinkClosure(KinematicParameters(L=k.L, As=As, v=v, model="modified"))
    err_lin = np.linalg.norm(linear.fk(q_test)[0] - T_true, axis=1)
    assert err_pw.max() < BENT_FK_TOLERANCE
    assert err_lin.mean() > 10 * err_pw.max()


def test_parameters_per_arm_and_round_trip(l1, survey_frames):
    """6 parameters per arm (L, the survey centroid c, two tilts of the guideway; 7 with the rotation
    about it, Table 5.8 model 2), read from the graph; with_parameters/parameter_vector round trip;
    the tilts turn the line frame's y and z axes; the thesis' o_i and Euler angles as properties; a
    frame change moves the FK as x' = R x + t."""
    cart = synthetic_cart_measurements(l1, None, SURVEY_NODES, noise=NO_NOISE, frames=survey_frames)
    pw = PiecewiseActuatorClosure.from_model(l1, cart)
    assert pw.n_parameters == 18
    for i in range(3):
        np.testing.assert_array_equal(pw.arm_parameter_indices(i), np.arange(6 * i, 6 * i + 6))
    assert pw.parameter_names()[:6] == ("L1", "c1_x", "c1_y", "c1_z", "frame1_ry", "frame1_rz")
    twist = PiecewiseActuatorClosure.from_model(l1, cart, free_twist=True)
    assert twist.parameter_names()[:7] == ("L1", "c1_x", "c1_y", "c1_z", "frame1_rx", "frame1_ry", "frame1_rz")
    for m in (pw, twist):
        np.testing.assert_array_equal(m.with_parameters(m.parameter_vector()).parameter_vector(), m.parameter_vector())
    for i in range(3):
        np.testing.assert_allclose(zyz_to_rotation(*pw.frame_euler_zyz[i]), pw.frame_rotation(i), rtol=0, atol=1e-12)
        c = pw.parameter_vector()[6 * i + 1: 6 * i + 4]
        np.testing.assert_allclose(pw.frame_offset[i] + pw.frame_rotation(i) @ pw.survey_centroid[i], c, rtol=0, atol=1e-12)
    # frame2_ry turns the survey about the line frame's y axis: the line direction moves, its y axis does not
    p = pw.parameter_vector()
    p[pw.parameter_names().index("frame2_ry")] = 0.01
    C = pw.line_frames[1]
    before, after = pw.frame_rotation(1) @ C, pw.with_parameters(p).frame_rotation(1) @ C
    np.testing.assert_allclose(after[:, 1], before[:, 1], rtol=0, atol=1e-15)
    assert np.degrees(np.arccos(after[:, 0] @ before[:, 0])) == pytest.approx(np.degrees(0.01), rel=1e-9)
    q = np.array([[0.1, -0.2, 0.3], [-0.4, 0.2, 0.0]])
    Rm, t = zyz_to_rotation(0.3, 0.5, -0.2), np.array([0.1, 0.2, -0.3])
    moved = pw.with_parameters(p)
    np.testing.assert_allclose(moved.transformed(Rm, t).fk(q)[0], moved.fk(q)[0] @ Rm.T + t, rtol=0, atol=1e-12)


def test_six_link_layout_parallelograms(l1, survey_frames):
    """Six-link layout (model 4) with link offsets equal to the plate offsets (parallelograms): the plate
    keeps the identity orientation and T is the 3-link FK with As_i - B0_i1 (closed form)."""
    B0 = np.array([[-0.05, -0.05, -0.10], [-0.05, -0.12, -0.08], [-0.06, 0.00, 0.14],
                   [-0.19, -0.09, 0.04], [-0.05, -0.00, -0.14], [-0.05, 0.12, 0.08]])
    cart = synthetic_cart_measurements(l1, None, SURVEY_NODES, noise=NO_NOISE, frames=survey_frames)
    three = PiecewiseActuatorClosure.from_model(l1, cart)
    first = [0, 1, 1, 3, 3, 3]
    arm = [0, 1, 1, 2, 2, 2]
    a = np.array([three.frame_rotation(arm[j]).T @ (B0[j] - B0[first[j]]) for j in range(6)])
    frames = np.array([three.frame_rotation(i) for i in range(3)])
    six = PiecewiseActuatorClosure(
        cart, l1.kinematics.L[arm], three.frame_offset, frames,
        links=SIX_LINK_LAYOUT, link_offsets=a, B0=B0,
    )
    assert six.orientation and six.n_parameters == 39
    assert [len(six.arm_parameter_indices(i)) for i in range(3)] == [9, 13, 17]
    q = np.array([[0.1, -0.2, 0.3], [-0.4, 0.2, 0.0], [0.5, 0.5, 0.5]])
    T, R = six.fk(q)
    k = l1.kinematics
    shifted = ThreeLinkClosure(KinematicParameters(L=k.L, As=k.As - B0[[0, 1, 3]], v=k.v, model="modified"))
    np.testing.assert_allclose(T, shifted.fk(q)[0], rtol=0, atol=STRAIGHT_TOLERANCE)
    np.testing.assert_allclose(R, np.broadcast_to(np.eye(3), R.shape), rtol=0, atol=1e-9)
    # the cart-side offsets as parameters: 3 more per non-first link, same equations
    free = PiecewiseActuatorClosure(
        cart, l1.kinematics.L[arm], three.frame_offset, frames,
        links=SIX_LINK_LAYOUT, link_offsets=a, B0=B0, free_link_offsets=True,
    )
    assert [len(free.arm_parameter_indices(i)) for i in range(3)] == [9, 16, 23]
    assert "a2b_x" in free.parameter_names() and "a2b_x" not in six.parameter_names()
    np.testing.assert_allclose(free.fk(q)[0], T, rtol=0, atol=STRAIGHT_TOLERANCE)


def test_six_link_frame_fit_reproduces_the_six_link_fk(survey_frames):
    """A six-link model with one guideway direction per arm, surveyed straight in rotated frames: the
    frame fit reproduces its FK, position and plate orientation (the D1 plate frame is turned ~100 deg
    from the tracker frame: the FK starts from the model's nominal orientation)."""
    d1 = load_six_link("D1_six_link")
    v = d1.v[[0, 1, 3]]
    six = SixLinkClosure(d1.L, d1.A0, v, d1.B0, v_per_arm=True, R0=d1.R0)
    cart = synthetic_cart_measurements(six, None, SURVEY_NODES, noise=NO_NOISE, frames=survey_frames)
    pw = PiecewiseActuatorClosure.from_model(six, cart)
    np.testing.assert_allclose(pw.plate_orientation, d1.R0, rtol=0, atol=1e-12)
    q = np.array([[0.1, -0.2, 0.3], [-0.4, 0.2, 0.0], [0.5, 0.5, 0.5], [-0.6, 0.6, -0.3]])
    T6, R6 = six.fk(q)
    T, R = pw.fk(q)
    np.testing.assert_allclose(T, T6, rtol=0, atol=STRAIGHT_TOLERANCE)
    np.testing.assert_allclose(R, R6, rtol=0, atol=1e-9)


def _perpendicular_turns(model: ThreeLinkClosure, angles: tuple[float, ...]) -> np.ndarray:
    """Rotations by ``angles`` about the vertical of each guideway's normal plane (no twist)."""
    R = np.empty((3, 3, 3))
    for i, angle in enumerate(angles):
        d = model.kinematics.v[i] / np.linalg.norm(model.kinematics.v[i])
        n = np.array([0.0, 0.0, 1.0]) - d[2] * d
        R[i] = Rotation.from_rotvec(angle * n / np.linalg.norm(n)).as_matrix()
    return R


def _rotation_error(Ra: np.ndarray, Rb: np.ndarray) -> np.ndarray:
    """Rotation vector of ``Ra^T Rb`` [rad]."""
    return Rotation.from_matrix(Ra.T @ Rb).as_rotvec()


def test_straight_path_frame_fit_takes_no_twist(l1):
    """On a straight joint path the rigid fit leaves the rotation about the line free; the fit takes the
    rotation of least angle, exact for survey frames turned about an axis perpendicular to the guideway
    (here the vertical of the guideway's normal plane: a levelled tracker turned about the vertical,
    corrected for the guideway's inclination): the frames are recovered."""
    t = np.array([[1.8, -4.3, -0.08], [1.4, -3.9, 0.09], [0.5, -2.1, 0.04]])
    R = _perpendicular_turns(l1, (2.4, -0.7, 3.1))
    cart = synthetic_cart_measurements(l1, None, SURVEY_NODES, noise=NO_NOISE, frames=(R, t))
    pw = PiecewiseActuatorClosure.from_model(l1, cart)
    for i in range(3):
        np.testing.assert_allclose(pw.frame_rotation(i), R[i], rtol=0, atol=1e-12)
        np.testing.assert_allclose(pw.frame_offset[i], t[i], rtol=0, atol=1e-11)  # o = c - R Pbar, |Pbar| ~ 5 m


@pytest.fixture(scope="module")
def bent_data(l1):
    """The L1 with bent guideways (Table 4.1 magnitudes, no backlash): the true robot and exact TCP data."""
    errors = ActuatorErrors.table_4_1(backlash_m=0.0)
    q = random_poses(l1, 150, seed=3)
    q = q[np.all(np.abs(q) < 0.64, axis=1)]
    return errors, DeviatedClosure(l1, errors), synthetic_measurements(l1, q, noise=NO_NOISE, actuator_errors=errors, seed=5)


def _check_recovered(res, l1, true_robot, data, frames) -> None:
    assert res.status == "optimal"
    assert all(g.iterations <= CALIBRATION_MAX_ITERATIONS for g in res.groups), [g.iterations for g in res.groups]
    assert res.identifiability.full_rank
    for i in range(3):
        err = np.degrees(np.linalg.norm(_rotation_error(res.model.frame_rotation(i), frames[i])))
        assert err < CALIBRATED_FRAME_DEG, (i, err)
    np.testing.assert_allclose(res.model.L, l1.kinematics.L, rtol=0, atol=CALIBRATED_L_TOLERANCE)
    err_T = np.linalg.norm(res.model.fk(data.q)[0] - true_robot.fk(data.q)[0], axis=1)
    assert err_T.max() < CALIBRATED_TCP_TOLERANCE


def test_calibration_on_bent_guideways_converges_and_recovers_the_truth(l1, bent_data):
    """Model 2 calibrated on exact data of bent guideways, surveyed in frames turned about the vertical
    (the levelled tracker; the twist of the start is right), the start the frame fit of the nominal
    linear model: a few LM iterations per arm, and the survey frames, link lengths and true TCP are
    recovered. (The thesis' ZYZ frame about the survey origin stopped at the iteration limit.)"""
    errors, true_robot, data = bent_data
    frames = (_perpendicular_turns(l1, (2.4, -0.7, 3.1)), np.array([[1.8, -4.3, -0.08], [1.4, -3.9, 0.09], [0.5, -2.1, 0.04]]))
    cart = synthetic_cart_measurements(l1, errors, SURVEY_NODES, noise=NO_NOISE, frames=frames)
    start = PiecewiseActuatorClosure.from_model(l1, cart)
    res = CalibrationProblem(start).solve(data)
    _check_recovered(res, l1, true_robot, data, frames[0])


def test_free_twist_is_recovered_from_the_bends(l1, survey_frames, bent_data):
    """Survey frames of arbitrary orientation: the start's rotation about the guideway is up to 20 deg
    off. The default model keeps it (its rotation about the line does not move, the fit is poor); with
    free_twist the calibration recovers it from the bends of the guideways, and everything else."""
    errors, true_robot, data = bent_data
    cart = synthetic_cart_measurements(l1, errors, SURVEY_NODES, noise=NO_NOISE, frames=survey_frames)
    start = PiecewiseActuatorClosure.from_model(l1, cart)
    start_twist = [abs(_rotation_error(start.frame_rotation(i), survey_frames[0][i]) @ start.line_frames[i][:, 0]) for i in range(3)]
    assert max(start_twist) > np.radians(10)
    fixed = CalibrationProblem(start).solve(data)
    assert fixed.status == "optimal"
    twist = [
        _rotation_error(start.frame_rotation(i) @ start.line_frames[i], fixed.model.frame_rotation(i) @ start.line_frames[i])[0]
        for i in range(3)
    ]
    np.testing.assert_array_less(np.abs(twist), 1e-12)  # line-frame axes: no rotation about the line, every arm
    free = CalibrationProblem(PiecewiseActuatorClosure.from_model(l1, cart, free_twist=True)).solve(data)
    _check_recovered(free, l1, true_robot, data, survey_frames[0])
    assert fixed.cost > 10 * free.cost


def _cart(n: int = 5) -> CartMeasurements:
    g = np.linspace(-0.65, 0.7, n)
    return CartMeasurements(q=(g, g, g), positions=tuple(np.column_stack([g, 0 * g, 0 * g]) for _ in range(3)))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(L=[2.0, 2.0, -1.0]), r"L: link lengths must be positive"),
        (dict(L=[2.0, 2.0]), r"L: expected finite values of shape \(3,\)"),
        (dict(frame_offset=np.zeros((2, 3))), r"frame_offset: expected finite values of shape \(3, 3\)"),
        (dict(links=(("1", "2"), ("3",))), r"links: expected THREE_LINK_LAYOUT"),
        (dict(B0=np.ones((3, 3))), r"link_offsets, B0 and plate_orientation belong to the six-link layout"),
        (dict(frame_rotation=np.broadcast_to(np.eye(3), (3, 3, 3))), r"give exactly one of frame_rotation"),
        (dict(frame_euler_zyz=None), r"give exactly one of frame_rotation"),
        (dict(frame_euler_zyz=None, frame_rotation=np.broadcast_to(2 * np.eye(3), (3, 3, 3))), r"frame_rotation\[0\]: expected a rotation"),
        (dict(cart=object()), r"cart: expected cart measurements with attributes q and positions"),
        (
            dict(L=np.full(6, 2.0), links=SIX_LINK_LAYOUT, link_offsets=np.ones((6, 3))),
            r"link_offsets: row 0 \(first link of arm 1\) must be zero",
        ),
    ],
    ids=["negative-L", "L-shape", "offset-shape", "layout", "B0-three-link", "both-rotations", "no-rotation", "not-a-rotation",
         "cart-type", "first-link-offset"],
)
def test_constructor_rejects_bad_input(kwargs, match):
    """Bad constructor arguments raise InputError naming the argument."""
    args = dict(cart=_cart(), L=[2.0, 2.0, 2.0], frame_offset=np.zeros((3, 3)), frame_euler_zyz=np.zeros((3, 3)))
    args.update(kwargs)
    with pytest.raises(InputError, match=match):
        PiecewiseActuatorClosure(**args)


def test_fk_outside_the_survey_range(l1):
    """q outside the surveyed range is an InputError naming the actuator, unless extrapolation is asked for."""
    cart = synthetic_cart_measurements(l1, None, SURVEY_NODES, noise=NO_NOISE)
    pw = PiecewiseActuatorClosure.from_model(l1, cart)
    with pytest.raises(InputError, match=r"q2 = 0\.8 \(row 0\) is outside the surveyed range"):
        pw.fk([0.0, 0.8, 0.0])
    pwx = PiecewiseActuatorClosure.from_model(l1, cart, extrapolate=True)
    np.testing.assert_allclose(pwx.fk([0.0, 0.8, 0.0])[0], l1.fk([0.0, 0.8, 0.0])[0], rtol=0, atol=STRAIGHT_TOLERANCE)
