"""The sine path of Cvitanic (2021), sec. 4.2: closed-form truth (3-axis and 5-axis).

Independent references: finite differences of the closed form, the quaternion kinematics
q' = q (x) (0, w) / 2 by finite differences, the reference sine ``y = A sin(2 pi f x)``.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.estimation.fusion.sine_path import FEED_RATE_M_S, SinePath
from gtmodel.estimation.fusion.tracker_imu import TABLE_7

DT = 1e-3


def test_default_feed_is_the_table_7_baseline():
    assert FEED_RATE_M_S == pytest.approx(TABLE_7["feed_rate_mm_s"]["baseline"] * 1e-3, rel=1e-15)


@pytest.fixture(scope="module")
def five_axis():
    return SinePath(1.5, rotation=True, orientation=(0.9, 0.1, -0.2, 0.3))


@pytest.mark.parametrize("lo, hi, d", [(0, 3, 3), (3, 6, 6)], ids=["p->v", "v->a"])
def test_truth_derivatives_match_finite_differences(five_axis, lo, hi, d):
    # central differences of the closed form at a fine step
    h = 1e-5
    tr = five_axis.truth(h)
    fd = (tr.x[2:, lo:hi] - tr.x[:-2, lo:hi]) / (2 * h)
    np.testing.assert_allclose(fd, tr.x[1:-1, d:d + 3], atol=1e-6 * max(1.0, np.abs(fd).max()))


def test_quaternion_kinematics_match_the_angular_velocity(five_axis):
    # q' = q (x) (0, w) / 2 with w in the body frame, by central differences
    h = 1e-5
    tr = five_axis.truth(h)
    q, w = tr.x[:, 9:13], tr.x[:, 13:16]
    dq = (q[2:] - q[:-2]) / (2 * h)
    qm, wm = q[1:-1], w[1:-1]
    prod = np.column_stack([-(qm[:, 1:] * wm).sum(1), qm[:, :1] * wm + np.cross(qm[:, 1:], wm)])
    np.testing.assert_allclose(dq, prod / 2, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)


def test_alpha_is_the_derivative_of_w(five_axis):
    h = 1e-5
    tr = five_axis.truth(h)
    np.testing.assert_allclose((tr.x[2:, 13:16] - tr.x[:-2, 13:16]) / (2 * h), tr.x[1:-1, 16:19], atol=1e-5)


def test_path_is_the_reference_sine():
    # y = A sin(2 pi f x) along the path, x at the feed rate; 0.833 Hz at 42.33 mm/s
    tr = SinePath(2.0).truth(DT)
    x, y = tr.position[:, 0] - 1.5, tr.position[:, 1]
    np.testing.assert_allclose(y, 0.0762 * np.sin(2 * np.pi * 19.685 * x), atol=1e-15)
    assert SinePath(2.0).omega / (2 * np.pi) == pytest.approx(19.685 * 0.04233)




@pytest.fixture(scope="module")
def normal_tool():
    return SinePath(1.2, rotation=True, rotation_axis=(0.0, 0.0, 1.0), rotation_law="normal")


def test_normal_tool_stays_normal_to_the_path(normal_tool):
    # the thesis' 5-axis motion (Fig. 22): the body y axis, turned by the quaternion, is perpendicular to the velocity
    # and the body x axis along it (independent: the rotation matrix of each quaternion)
    tr = normal_tool.truth(DT)
    w, x, y, z = tr.quaternion.T
    body_x = np.column_stack([1 - 2 * (y**2 + z**2), 2 * (x * y + w * z), 2 * (x * z - w * y)])
    body_y = np.column_stack([2 * (x * y - w * z), 1 - 2 * (x**2 + z**2), 2 * (y * z + w * x)])
    v = tr.velocity / np.linalg.norm(tr.velocity, axis=1)[:, None]
    np.testing.assert_allclose((body_y * v).sum(1), 0.0, atol=1e-12)
    np.testing.assert_allclose((body_x * v).sum(1), 1.0, atol=1e-12)


def test_normal_tool_turns_at_curvature_times_speed_at_the_crests():
    # at a crest (t = 0.3 s) the slope is 0 and |w| = y'' v_f = A (2 pi f)^2 v_f = 49.3 rad/s; its derivatives by central differences
    tr = SinePath(0.35, rotation=True, rotation_axis=(0.0, 0.0, 1.0), rotation_law="normal").truth(1e-5)
    assert np.abs(tr.angular_velocity[:, 2]).max() == pytest.approx(0.0762 * (2 * np.pi * 19.685) ** 2 * 0.04233, rel=1e-6)
    h = 1e-5
    np.testing.assert_allclose((tr.x[2:, 13:16] - tr.x[:-2, 13:16]) / (2 * h), tr.x[1:-1, 16:19], atol=1e-6 * np.abs(tr.x[:, 16:19]).max())
    np.testing.assert_allclose((tr.x[2:, 16:19] - tr.x[:-2, 16:19]) / (2 * h), tr.angular_jerk[1:-1], atol=1e-5 * np.abs(tr.angular_jerk).max())


def test_unknown_rotation_law():
    with pytest.raises(InputError, match=r"rotation_law: expected one of sine, normal, got 'spin'"):
        SinePath(1.0, rotation=True, rotation_law="spin")


# -- constant tangential speed (the thesis' "constant tangential velocity, or feed rate", sec. 4.2) -------------------

@pytest.fixture(scope="module")
def tangential():
    return SinePath(2.5, rotation=True, rotation_axis=(0.0, 0.0, 1.0), rotation_law="normal", feed="tangential")


@pytest.fixture(scope="module")
def tangential_fine():
    # 1.9 s at 1e-5 s: through the first crest (1.84 s)
    return SinePath(1.9, rotation=True, rotation_axis=(0.0, 0.0, 1.0), rotation_law="normal", feed="tangential").truth(1e-5)


def test_tangential_speed_is_the_feed_rate(tangential, tangential_fine):
    # |v| = v_f to 1e-9, and v is the derivative of p (central differences, independent of the chain rule)
    tr = tangential.truth(DT)
    np.testing.assert_allclose(np.linalg.norm(tr.velocity, axis=1), 0.04233, rtol=0, atol=1e-9)
    fine = tangential_fine
    fd = (fine.position[2:] - fine.position[:-2]) / 2e-5
    np.testing.assert_allclose(fd, fine.velocity[1:-1], atol=1e-8)
    for lo, d in ((3, 6), (6, 9)):  # a = v', jerk = a'
        fd = (fine.x[2:, lo:lo + 3] - fine.x[:-2, lo:lo + 3]) / 2e-5
        ref = fine.x[1:-1, d:d + 3] if d < 9 else fine.jerk[1:-1]
        np.testing.assert_allclose(fd, ref, atol=1e-6 * np.abs(ref).max())


def test_tangential_arc_length_is_feed_times_time(tangential):
    # independent: the arc length integral sqrt(1 + (A k cos k x)^2) by adaptive quadrature, not the elliptic form
    from scipy.integrate import quad

    tr = tangential.truth(DT)
    k, m = 2 * np.pi * 19.685, 0.0762 * 2 * np.pi * 19.685
    x, y = tr.position[:, 0] - 1.5, tr.position[:, 1]
    np.testing.assert_allclose(y, 0.0762 * np.sin(k * x), atol=1e-15)
    idx = np.arange(0, tr.t.size, 250)
    s = [quad(lambda u: np.sqrt(1 + (m * np.cos(k * u)) ** 2), 0.0, x[i], limit=200, epsabs=1e-13)[0] for i in idx]
    np.testing.assert_allclose(s, 0.04233 * tr.t[idx], rtol=0, atol=1e-11)


def test_tangential_tool_stays_normal_and_crests_near_the_thesis_spike(tangential, tangential_fine):
    # the tool normal to the path (body x along v); the first crest near 1.8 s (Cvitanic (2021), Figs. 24-25)
    tr = tangential.truth(DT)
    w, x, y, z = tr.quaternion.T
    body_x = np.column_stack([1 - 2 * (y**2 + z**2), 2 * (x * y + w * z), 2 * (x * z - w * y)])
    np.testing.assert_allclose((body_x * tr.velocity).sum(1) / 0.04233, 1.0, atol=1e-12)
    assert tr.t[np.argmax(tr.position[:, 1])] == pytest.approx(1.84, abs=0.01)
    h, fine = 1e-5, tangential_fine  # w' = alpha by central differences
    np.testing.assert_allclose((fine.x[2:, 13:16] - fine.x[:-2, 13:16]) / (2 * h), fine.x[1:-1, 16:19], atol=1e-6 * np.abs(fine.x[:, 16:19]).max())


@pytest.mark.parametrize("rotation, law", [(False, "sine"), (True, "sine"), (True, "normal")])
def test_x_feed_unchanged_bit_for_bit(rotation, law):
    # the default feed is the closed form in t (as before the tangential option), bit for bit
    a, b = SinePath(1.0, rotation=rotation, rotation_law=law), SinePath(1.0, rotation=rotation, rotation_law=law, feed="x")
    ta, tb = a.truth(DT), b.truth(DT)
    assert np.array_equal(ta.x, tb.x) and np.array_equal(ta.jerk, tb.jerk)
    t = np.arange(1001) * DT
    w0 = 2.0 * np.pi * 19.685 * 0.04233
    assert np.array_equal(ta.position, np.array([1.5, 0.0, 1.0]) + np.column_stack([0.04233 * t, 0.0762 * np.sin(w0 * t), 0 * t]))
    assert np.array_equal(ta.velocity[:, 1], 0.0762 * w0 * np.cos(w0 * t))


def test_unknown_feed():
    with pytest.raises(InputError, match=r"feed: expected one of x, tangential, got 'arc'"):
        SinePath(1.0, feed="arc")
