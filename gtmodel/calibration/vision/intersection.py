"""Intersection of the rays of two cameras: corner points and the TCP with their covariance.

Dressler (2012), ch. 5.5 ("calibration pattern position ... estimated, together with an
estimate of its covariance, by intersection", McGlone et al. 2004): with the relative
orientation of the cameras known (from the bundle adjustment,
:func:`~gtmodel.calibration.vision.reconstruction.bundle_adjust`), each corner seen in both
images is the point whose projections are nearest its two detections. Start: the linear
triangulation (DLT) of the undistorted rays; then Gauss-Newton on the reprojection error
of the point, whose residuals and Jacobian come from the one camera graph
(:func:`~gtmodel.calibration.vision.camera.projection_expression`), all points at once.
The covariance of a point is ``sigma_px^2 (J^T J)^-1``; the TCP is the centroid of the
pattern's intersected corners (moved by the pattern orientation when the TCP is not the
corners' centroid), its covariance the mean of the corners' (independent detections; the
uncertainty of the relative orientation is left out). This estimate does not use the
pattern's shape: beside the bundle adjustment's TCP it is an independent cross-check.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Sequence

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel.calibration.vision.camera import N_INTRINSICS, Camera, Pattern, projection_expression, undistort
from gtmodel.calibration.vision.images import StereoImages
from gtmodel.errors import ConvergenceError, InputError

__all__ = ["intersect", "intersect_tcp", "MAX_ITER"]

#: Gauss-Newton iterations of the intersection.
MAX_ITER = 50


@lru_cache(maxsize=1)
def _point_function() -> ca.Function:
    X, R21, t21 = ca.SX.sym("X", 3), ca.SX.sym("R21", 3, 3), ca.SX.sym("t21", 3)
    uv1, uv2 = ca.SX.sym("uv1", 2), ca.SX.sym("uv2", 2)
    k1, k2 = ca.SX.sym("k1", N_INTRINSICS), ca.SX.sym("k2", N_INTRINSICS)
    r = ca.vertcat(projection_expression(X, k1) - uv1, projection_expression(ca.mtimes(R21, X) + t21, k2) - uv2)
    return ca.Function("intersection_residuals", [X, R21, t21, uv1, uv2, k1, k2], [r, ca.jacobian(r, X)])


def intersect(
    uv1: np.typing.ArrayLike,
    uv2: np.typing.ArrayLike,
    cameras: Sequence[Camera],
    R21: np.typing.ArrayLike,
    t21: np.typing.ArrayLike,
    pixel_sigma: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Points seen by both cameras, by intersection of their rays (McGlone et al. 2004).

    Parameters
    ----------
    uv1, uv2 : array_like, shape (P, 2)
        Pixel coordinates in camera 1 and 2 [px].
    cameras : sequence of 2 Camera
        Intrinsics and distortion.
    R21 : array_like, shape (3, 3)
        Orientation of camera 2 in camera 1 (``X_c2 = R21 X_c1 + t21``).
    t21 : array_like, shape (3,)
        Its translation [unit of the result].
    pixel_sigma : float
        Corner noise per pixel coordinate [px] (> 0).

    Returns
    -------
    X : numpy.ndarray, shape (P, 3)
        The points in camera 1's frame.
    cov : numpy.ndarray, shape (P, 3, 3)
        Their covariance (first order).

    Raises
    ------
    InputError
        Shapes disagree or ``pixel_sigma`` is not positive.
    ConvergenceError
        Gauss-Newton does not converge in :data:`MAX_ITER` iterations.
    """
    a, b = np.atleast_2d(np.asarray(uv1, dtype=float)), np.atleast_2d(np.asarray(uv2, dtype=float))
    if a.shape != b.shape or a.shape[1] != 2:
        raise InputError(f"intersect: expected uv1 and uv2 of one shape (P, 2), got {a.shape} and {b.shape}")
    if not (np.isfinite(pixel_sigma) and pixel_sigma > 0):
        raise InputError(f"pixel_sigma: expected a positive corner noise [px], got {pixel_sigma!r}")
    R, t = np.asarray(R21, dtype=float), np.asarray(t21, dtype=float).reshape(3)
    x1, x2 = undistort(cameras[0], a), undistort(cameras[1], b)
    P1 = np.hstack([np.eye(3), np.zeros((3, 1))])
    P2 = np.hstack([R, t[:, None]])
    A = np.stack([x1[:, :1] * P1[2] - P1[0], x1[:, 1:] * P1[2] - P1[1], x2[:, :1] * P2[2] - P2[0], x2[:, 1:] * P2[2] - P2[1]], axis=1)
    Xh = np.linalg.svd(A)[2][:, -1]
    X = Xh[:, :3] / Xh[:, 3:]
    f = _point_function().map(a.shape[0])
    k1, k2 = cameras[0].constants, cameras[1].constants
    for _ in range(MAX_ITER):
        r, J = f(X.T, R, t, a.T, b.T, k1, k2)
        r = np.array(r).T  # (P, 4)
        J = np.array(J).reshape(4, -1, 3).transpose(1, 0, 2)  # (P, 4, 3)
        step = np.linalg.solve(np.einsum("pki,pkj->pij", J, J), -np.einsum("pki,pk->pi", J, r)[..., None])[..., 0]
        X = X + step
        if np.abs(step).max() <= 1e-13 * (1 + np.abs(X).max()):
            break
    else:
        raise ConvergenceError(f"intersect: Gauss-Newton did not converge in {MAX_ITER} iterations")
    _, J = f(X.T, R, t, a.T, b.T, k1, k2)
    J = np.array(J).reshape(4, -1, 3).transpose(1, 0, 2)
    return X, pixel_sigma ** 2 * np.linalg.inv(np.einsum("pki,pkj->pij", J, J))


def intersect_tcp(
    images: StereoImages,
    cameras: Sequence[Camera],
    pattern: Pattern,
    R21: np.typing.ArrayLike,
    t21: np.typing.ArrayLike,
    pixel_sigma: float,
    R_pattern: np.typing.ArrayLike | None = None,
    tcp_in_pattern: np.typing.ArrayLike = (0.0, 0.0, 0.0),
) -> tuple[np.ndarray, np.ndarray]:
    """TCP of each pose from its intersected corners (the pattern's shape unused).

    Parameters
    ----------
    images : StereoImages
        Corners of N poses in both cameras.
    cameras : sequence of 2 Camera
        Intrinsics and distortion.
    pattern : Pattern
        The pattern (only its corners' centroid is used).
    R21 : array_like, shape (3, 3)
        Relative orientation of the cameras.
    t21 : array_like, shape (3,)
        Its translation [unit of the result].
    pixel_sigma : float
        Corner noise [px] (> 0).
    R_pattern : array_like, shape (N, 3, 3), optional
        Pattern orientations in camera 1, needed when the TCP is not the corners' centroid.
    tcp_in_pattern : array_like, shape (3,), optional
        The TCP in the pattern frame [unit of the result].

    Returns
    -------
    T : numpy.ndarray, shape (N, 3)
        TCPs in camera 1's frame.
    cov : numpy.ndarray, shape (N, 3, 3)
        Their covariance (corners independent; relative orientation taken as exact).

    Raises
    ------
    InputError
        A TCP away from the corners' centroid without ``R_pattern``; see :func:`intersect`.
    """
    N, M = images.n_poses, images.n_corners
    offset = np.asarray(tcp_in_pattern, dtype=float).reshape(3) - pattern.points.mean(axis=0)
    if np.any(offset != 0) and R_pattern is None:
        raise InputError("intersect_tcp: the TCP is not the corners' centroid; give R_pattern (from the bundle adjustment)")
    X, cov = intersect(images.uv[:, 0].reshape(-1, 2), images.uv[:, 1].reshape(-1, 2), cameras, R21, t21, pixel_sigma)
    T = X.reshape(N, M, 3).mean(axis=1)
    if np.any(offset != 0):
        T = T + np.asarray(R_pattern, dtype=float) @ offset
    return T, cov.reshape(N, M, 3, 3).sum(axis=1) / M ** 2
