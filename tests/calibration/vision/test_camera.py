"""The pinhole camera with Brown-Conrady distortion, the pattern and their bad input.

Independent reference: OpenCV's projection formula written out in NumPy here (Bradski and
Kaehler, *Learning OpenCV*, ch. 11), against the CasADi graph of
:func:`gtmodel.calibration.vision.camera.projection_expression`.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.calibration.vision import Camera, Pattern, look_at, undistort
from gtmodel.errors import InputError


def _opencv_numpy(X_w, R, c, fx, fy, cx, cy, d):
    Xc = (X_w - c) @ R.T
    x, y = Xc[:, 0] / Xc[:, 2], Xc[:, 1] / Xc[:, 2]
    k1, k2, p1, p2, k3 = d
    r2 = x * x + y * y
    rad = 1 + k1 * r2 + k2 * r2 ** 2 + k3 * r2 ** 3
    xd = x * rad + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * rad + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return np.column_stack([fx * xd + cx, fy * yd + cy]), Xc[:, 2]


@pytest.mark.parametrize("d", [np.zeros(5), [-0.3, 0.12, 0.002, -0.001, -0.02], [0.1, -0.05, -0.003, 0.004, 0.01]])
def test_projection_equals_the_opencv_formula(d):
    rng = np.random.default_rng(1)
    R = look_at([0.3, -4.0, 1.0], [0.0, 0.0, 0.0])
    cam = Camera("c", 1280, 960, 1200.0, 1210.0, 640.5, 470.0, np.asarray(d), R, np.array([0.3, -4.0, 1.0]))
    X = rng.uniform(-0.8, 0.8, (50, 3))
    uv, depth = cam.project(X)
    ref, ref_depth = _opencv_numpy(X, R, cam.position, 1200.0, 1210.0, 640.5, 470.0, np.asarray(d))
    np.testing.assert_allclose(uv, ref, rtol=0, atol=1e-9)
    np.testing.assert_allclose(depth, ref_depth, rtol=1e-13)


def test_undistort_inverts_the_distortion():
    cam = Camera("c", 1024, 768, 1100.0, 1100.0, 512.0, 384.0, np.array([-0.2, 0.1, 0.001, -0.001, 0.01]), look_at([0, -3, 0], [0, 0, 0]), np.array([0, -3.0, 0]))
    X = np.random.default_rng(2).uniform(-0.5, 0.5, (30, 3))
    uv, _ = cam.project(X)
    Xc = (X - cam.position) @ cam.R.T
    np.testing.assert_allclose(undistort(cam, uv), Xc[:, :2] / Xc[:, 2:], atol=1e-10)


def test_look_at_axes():
    R = look_at([0, 0, 0], [0, 5, 0])
    np.testing.assert_allclose(R, [[1, 0, 0], [0, 0, -1], [0, 1, 0]], atol=1e-15)  # x right, y down, z forward


def test_five_squares_has_20_distinct_corners():
    p = Pattern.five_squares(0.06, 0.1)
    assert p.n_corners == 20
    np.testing.assert_allclose(p.corners.mean(axis=0), 0.0, atol=1e-15)


@pytest.mark.parametrize("make, match", [
    (lambda: Camera("cam", 0, 768, 1e3, 1e3, 1, 1), r"cam: image size must be positive"),
    (lambda: Camera("cam", 100, 100, 0.0, 1e3, 50, 50), r"cam: fx must be a positive focal length"),
    (lambda: Camera("cam", 100, 100, 1e3, float("nan"), 50, 50), r"cam: fy must be a positive focal length"),
    (lambda: Camera("cam", 100, 100, 1e3, 1e3, 150, 50), r"cam: principal point \(150, 50\) outside"),
    (lambda: Camera("cam", 100, 100, 1e3, 1e3, 50, 50, np.zeros(4)), r"cam: distortion must be 5 finite values"),
    (lambda: Camera("cam", 100, 100, 1e3, 1e3, 50, 50, np.array([np.nan, 0, 0, 0, 0])), r"cam: distortion must be 5 finite"),
    (lambda: Camera("cam", 100, 100, 1e3, 1e3, 50, 50, R=2 * np.eye(3)), r"cam: R: expected a rotation"),
    (lambda: look_at([0, 0, 0], [0, 0, 0]), r"look_at: target .* must differ"),
    (lambda: look_at([0, 0, 0], [0, 0, 2]), r"parallel to the up direction"),
    (lambda: Pattern(np.array([[0, 0], [1, 0], [2, 0], [3, 0]])), r"collinear"),
    (lambda: Pattern(np.array([[0, 0], [1, 0], [1, 1]])), r"at least 4 finite corners"),
    (lambda: Pattern(np.array([[0, 0], [1, 0], [1, 1], [1, 1]])), r"two corners coincide"),
    (lambda: Pattern.five_squares(0.1, 0.1), r"pitch > side"),
])
def test_bad_camera_and_pattern(make, match):
    with pytest.raises(InputError, match=match):
        make()
