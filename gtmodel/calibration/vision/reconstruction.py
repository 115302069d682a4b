"""Stereo reconstruction of the pattern poses: bundle adjustment, TCP with covariance, metric scale.

Dressler (2012), ch. 5.5 (relative orientation, calibration pattern position, scaling to
metric units), with the cameras' intrinsics and distortion known beforehand (as in the thesis):

1. **Start values** (:func:`start_values`): each camera's view of each pose gives the
   pattern pose in that camera from the plane-to-image homography of the undistorted
   corners (Zhang's method: DLT, then ``[r1 r2 t] ~ H``); the relative orientation of the
   cameras is the chordal mean of ``R_2k R_1k^T`` over the poses.
2. **Bundle adjustment** (:func:`bundle_adjust`, McGlone et al. 2004): the unknowns are the
   relative orientation of camera 2 in camera 1 (``X_c2 = R21 X_c1 + t21``) and the pose of
   the pattern in camera 1 at each pose (``X_c1 = R_k P + p_k``); the cost is the squared
   reprojection error of every corner in both images. Residuals and their exact Jacobian
   come from one CasADi graph (:func:`~gtmodel.calibration.vision.camera.projection_expression`
   of both cameras), mapped over the poses; the NLP is solved by Levenberg-Marquardt on the
   normal equations, reduced to the 6 shared unknowns by the Schur complement of the
   pose blocks (6 x 6 each), so a step costs O(N). Rotations are updated locally
   (``R = R0 exp([w]x)``).
3. **TCP and covariance**: ``T_k = p_k + R_k o`` (``o`` the TCP in the pattern frame); its
   covariance is ``J_T Sigma_k J_T^T`` with ``Sigma = sigma_px^2 (J^T J)^-1`` at the optimum
   (the pose block of the inverse by the Schur complement), the first-order covariance of
   the intersection (McGlone et al. 2004).
4. **Metric scale** (:func:`scale_from_carts`): the reconstruction's unit is that of the
   pattern's declared dimensions (the printed size may be off). Poses whose carts all moved
   by the same ``Delta`` are ``|Delta|`` apart (parallel guideways with a known transmission,
   the thesis' assumption), which gives the scale ``lambda`` by least squares.

The gauge: camera 1's frame, the pattern's declared size. Noise-free corners with the true
camera model give the truth to rounding (tests: ``tests/calibration/vision``).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from functools import lru_cache
from typing import Sequence

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)
from scipy.spatial.transform import Rotation

from gtmodel._geometry import rotation_vector_to_rotation
from gtmodel.calibration.vision.camera import N_INTRINSICS, Camera, Pattern, projection_expression, undistort
from gtmodel.calibration.vision.images import StereoImages
from gtmodel.errors import InputError
from gtmodel.status import Status, StatusResult

__all__ = ["StereoReconstruction", "common_displacement_pairs", "reconstruct", "bundle_adjust", "start_values", "scale_from_carts", "homography_pose", "CART_PAIR_TOLERANCE_M"]

_log = logging.getLogger("gtmodel")

#: Largest difference [m] between the three carts' displacements of a pose pair that still
#: counts as one common displacement (:func:`scale_from_carts`).
CART_PAIR_TOLERANCE_M = 1e-6
#: Bundle adjustment: stop when the largest step is below this (relative to 1 + |x|).
STEP_TOLERANCE = 1e-9
#: Bundle adjustment: iteration limit.
MAX_ITER = 100


@lru_cache(maxsize=8)
def _residual_function(n_corners: int) -> ca.Function:
    """Reprojection residuals of one pose in both cameras and their Jacobian (one SX graph)."""
    w21, t21, wk, pk = (ca.SX.sym(n, 3) for n in ("w21", "t21", "wk", "pk"))
    R21_0, Rk_0 = ca.SX.sym("R21_0", 3, 3), ca.SX.sym("Rk_0", 3, 3)
    P = ca.SX.sym("P", 3, n_corners)
    uv1, uv2 = ca.SX.sym("uv1", 2, n_corners), ca.SX.sym("uv2", 2, n_corners)
    k1, k2 = ca.SX.sym("k1", N_INTRINSICS), ca.SX.sym("k2", N_INTRINSICS)
    Rk = ca.mtimes(Rk_0, rotation_vector_to_rotation(wk))
    R21 = ca.mtimes(R21_0, rotation_vector_to_rotation(w21))
    res = []
    for j in range(n_corners):
        X1 = ca.mtimes(Rk, P[:, j]) + pk
        X2 = ca.mtimes(R21, X1) + t21
        res += [projection_expression(X1, k1) - uv1[:, j], projection_expression(X2, k2) - uv2[:, j]]
    r = ca.vertcat(*res)
    x = ca.vertcat(w21, t21, wk, pk)
    return ca.Function("stereo_residuals", [x, R21_0, Rk_0, P, uv1, uv2, k1, k2], [r, ca.jacobian(r, x)],
                       ["x", "R21_0", "Rk_0", "P", "uv1", "uv2", "k1", "k2"], ["r", "J"])


def homography_pose(pattern: Pattern, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pose of a planar pattern from its normalised, undistorted image points (Zhang 2000).

    Parameters
    ----------
    pattern : Pattern
        The pattern (corners in its plane).
    xy : numpy.ndarray, shape (M, 2)
        Normalised image coordinates ``X_c[:2] / X_c[2]`` of its corners.

    Returns
    -------
    R : numpy.ndarray, shape (3, 3)
        Pattern orientation in the camera frame.
    p : numpy.ndarray, shape (3,)
        Pattern origin in the camera frame [pattern units].
    """
    P = pattern.corners
    sP, mP = P.std() or 1.0, P.mean(axis=0)
    sx, mx = xy.std() or 1.0, xy.mean(axis=0)
    a, b = (P - mP) / sP, (xy - mx) / sx
    rows = []
    for (X, Y), (x, y) in zip(a, b):
        rows.append([X, Y, 1, 0, 0, 0, -x * X, -x * Y, -x])
        rows.append([0, 0, 0, X, Y, 1, -y * X, -y * Y, -y])
    Hn = np.linalg.svd(np.asarray(rows))[2][-1].reshape(3, 3)
    TP = np.array([[1 / sP, 0, -mP[0] / sP], [0, 1 / sP, -mP[1] / sP], [0, 0, 1]])
    Tx = np.array([[1 / sx, 0, -mx[0] / sx], [0, 1 / sx, -mx[1] / sx], [0, 0, 1]])
    H = np.linalg.solve(Tx, Hn @ TP)
    lam = 2.0 / (np.linalg.norm(H[:, 0]) + np.linalg.norm(H[:, 1]))
    H = H * lam
    if H[2, 2] < 0:  # the pattern is in front of the camera
        H = -H
    r1, r2 = H[:, 0], H[:, 1]
    U, _, Vt = np.linalg.svd(np.column_stack([r1, r2, np.cross(r1, r2)]))
    R = U @ np.diag([1, 1, np.linalg.det(U @ Vt)]) @ Vt
    return R, H[:, 2]


def _chordal_mean(Rs: np.ndarray) -> np.ndarray:
    U, _, Vt = np.linalg.svd(Rs.sum(axis=0))
    return U @ np.diag([1, 1, np.linalg.det(U @ Vt)]) @ Vt


def start_values(images: StereoImages, cameras: Sequence[Camera], pattern: Pattern) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Start values of the bundle adjustment from the homographies of each view.

    Parameters
    ----------
    images : StereoImages
        Corners of N poses.
    cameras : sequence of 2 Camera
        Intrinsics and distortion (poses not used).
    pattern : Pattern
        The pattern.

    Returns
    -------
    R21 : numpy.ndarray, shape (3, 3)
    t21 : numpy.ndarray, shape (3,)
        Camera 2 in camera 1: ``X_c2 = R21 X_c1 + t21``.
    Rk : numpy.ndarray, shape (N, 3, 3)
    pk : numpy.ndarray, shape (N, 3)
        Pattern poses in camera 1.
    """
    N = images.n_poses
    M = pattern.n_corners
    xy = [undistort(cam, images.uv[:, j].reshape(-1, 2)).reshape(N, M, 2) for j, cam in enumerate(cameras)]
    poses = [[homography_pose(pattern, xy[j][k]) for k in range(N)] for j in range(2)]
    Rk = np.array([R for R, _ in poses[0]])
    pk = np.array([p for _, p in poses[0]])
    R21 = _chordal_mean(np.array([poses[1][k][0] @ Rk[k].T for k in range(N)]))
    t21 = np.mean([poses[1][k][1] - R21 @ pk[k] for k in range(N)], axis=0)
    return R21, t21, Rk, pk


@dataclass
class StereoReconstruction(StatusResult):
    """The reconstructed pattern poses and TCPs of a stereo image set.

    Parameters
    ----------
    status : Status
        ``converged`` or ``max_iterations``.
    message : str
        What happened.
    R21 : numpy.ndarray, shape (3, 3)
        Orientation of camera 2 in camera 1 (``X_c2 = R21 X_c1 + t21``).
    t21 : numpy.ndarray, shape (3,)
        Its translation [pattern units].
    R : numpy.ndarray, shape (N, 3, 3)
        Pattern orientations in camera 1.
    p : numpy.ndarray, shape (N, 3)
        Pattern origins in camera 1 [pattern units].
    T : numpy.ndarray, shape (N, 3)
        TCPs in camera 1 [pattern units].
    cov_T : numpy.ndarray, shape (N, 3, 3)
        Their covariance [pattern units^2] (first order, from ``pixel_sigma``).
    cov_relative : numpy.ndarray, shape (6, 6)
        Covariance of the relative orientation (rotation vector [rad], ``t21``).
    pixel_sigma : float
        Corner noise used for the covariance [px].
    rms_px : float
        Root-mean-square reprojection error [px].
    residuals_px : numpy.ndarray, shape (N, 2, M, 2)
        Reprojection errors (model minus measured) [px].
    iterations : int
        Levenberg-Marquardt iterations.
    scale : float
        Metric scale ``lambda`` [m per pattern unit] (1 when not fitted).
    scale_pairs : int
        Pose pairs the scale was fitted on (0: not fitted).
    solve_time_s : float
        Wall time of the bundle adjustment [s].
    """

    R21: np.ndarray
    t21: np.ndarray
    R: np.ndarray
    p: np.ndarray
    T: np.ndarray
    cov_T: np.ndarray
    cov_relative: np.ndarray
    pixel_sigma: float
    rms_px: float
    residuals_px: np.ndarray
    iterations: int
    scale: float = 1.0
    scale_pairs: int = 0
    solve_time_s: float = 0.0

    @property
    def T_metric(self) -> np.ndarray:
        """TCPs in camera 1 scaled to metres, ``lambda T``, shape (N, 3) [m]."""
        return self.scale * self.T

    @property
    def cov_T_metric(self) -> np.ndarray:
        """Their covariance ``lambda^2 cov_T`` (the scale taken as exact), shape (N, 3, 3) [m^2]."""
        return self.scale ** 2 * self.cov_T

    @property
    def sigma_T_metric(self) -> np.ndarray:
        """Standard deviations of the metric TCP coordinates, shape (N, 3) [m]."""
        return np.sqrt(np.einsum("nii->ni", self.cov_T_metric))


def _evaluate(images: StereoImages, cams: Sequence[Camera], pattern: Pattern, R21: np.ndarray, t21: np.ndarray,
              Rk: np.ndarray, pk: np.ndarray, f: ca.Function, dx: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    N = images.n_poses
    x = np.zeros((12, N))
    x[3:6] = t21[:, None]
    x[9:12] = pk.T
    if dx is not None:
        x += dx
    r, J = f(x, R21, np.hstack(list(Rk)), pattern.points.T, np.hstack(list(images.uv[:, 0].transpose(0, 2, 1))),
             np.hstack(list(images.uv[:, 1].transpose(0, 2, 1))), cams[0].constants, cams[1].constants)
    r = np.array(r).T  # (N, 4M)
    J = np.array(J).reshape(r.shape[1], N, 12).transpose(1, 0, 2)  # (N, 4M, 12)
    return r, J


def _normal(r: np.ndarray, J: np.ndarray) -> tuple[np.ndarray, ...]:
    Js, Jk = J[:, :, :6], J[:, :, 6:]
    Hss = np.einsum("nmi,nmj->ij", Js, Js)
    Hsk = np.einsum("nmi,nmj->nij", Js, Jk)
    Hkk = np.einsum("nmi,nmj->nij", Jk, Jk)
    gs = np.einsum("nmi,nm->i", Js, r)
    gk = np.einsum("nmi,nm->ni", Jk, r)
    return Hss, Hsk, Hkk, gs, gk


def _solve_schur(Hss: np.ndarray, Hsk: np.ndarray, Hkk: np.ndarray, gs: np.ndarray, gk: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    Hkk_inv = np.linalg.inv(Hkk)
    W = np.einsum("nij,njk->nik", Hsk, Hkk_inv)  # Hsk Hkk^-1
    S = Hss - np.einsum("nij,nkj->ik", W, Hsk)
    b = gs - np.einsum("nij,nj->i", W, gk)
    ds = np.linalg.solve(S, b)
    dk = np.einsum("nij,nj->ni", Hkk_inv, gk - np.einsum("nji,j->ni", Hsk, ds))
    return ds, dk


def bundle_adjust(
    images: StereoImages,
    cameras: Sequence[Camera],
    pattern: Pattern,
    start: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None,
    tcp_in_pattern: np.typing.ArrayLike = (0.0, 0.0, 0.0),
    pixel_sigma: float = 0.3,
    max_iter: int = MAX_ITER,
) -> StereoReconstruction:
    """Bundle adjustment of the relative orientation and the pattern poses (Dressler (2012), ch. 5.5).

    Parameters
    ----------
    images : StereoImages
        Corners of N >= 2 poses in both cameras.
    cameras : sequence of 2 Camera
        Intrinsics and distortion assumed for each camera (their poses are not used).
    pattern : Pattern
        The pattern, in its declared dimensions (the unit of the result).
    start : tuple, optional
        ``(R21, t21, R, p)`` start values (default :func:`start_values`).
    tcp_in_pattern : array_like, shape (3,), optional
        The TCP in the pattern frame [pattern units].
    pixel_sigma : float, optional
        Corner noise per pixel coordinate [px] for the covariance (> 0).
    max_iter : int, optional
        Iteration limit.

    Returns
    -------
    StereoReconstruction
        In camera 1's frame, ``scale`` 1 (see :func:`reconstruct` for the metric scale).

    Raises
    ------
    InputError
        Not two cameras, fewer than 2 poses, corners of another pattern, a non-positive
        or non-finite ``pixel_sigma``.
    """
    if len(cameras) != 2:
        raise InputError(f"cameras: expected 2 cameras, got {len(cameras)}")
    if images.n_poses < 2:
        raise InputError(f"stereo images: at least 2 poses seen by both cameras are needed, got {images.n_poses}")
    if images.n_corners != pattern.n_corners:
        raise InputError(f"stereo images: {images.n_corners} corners per pose, the pattern has {pattern.n_corners}")
    if not (np.isfinite(pixel_sigma) and pixel_sigma > 0):
        raise InputError(f"pixel_sigma: expected a positive corner noise [px], got {pixel_sigma!r}")
    t0 = time.perf_counter()
    o = np.asarray(tcp_in_pattern, dtype=float).reshape(3)
    R21, t21, Rk, pk = start_values(images, cameras, pattern) if start is None else (np.array(x, dtype=float) for x in start)
    f = _residual_function(pattern.n_corners).map(images.n_poses)
    r, J = _evaluate(images, cameras, pattern, R21, t21, Rk, pk, f)
    cost = 0.5 * float(np.sum(r * r))
    mu, status, it = 1e-6, Status.MAX_ITERATIONS, 0
    for it in range(1, max_iter + 1):
        Hss, Hsk, Hkk, gs, gk = _normal(r, J)
        ds, dk = _solve_schur(_damped(Hss, mu), Hsk, _damped(Hkk, mu), gs, gk)
        ds, dk = -ds, -dk
        R21n = R21 @ Rotation.from_rotvec(ds[:3]).as_matrix()
        t21n = t21 + ds[3:]
        Rkn = np.einsum("nij,njk->nik", Rk, Rotation.from_rotvec(dk[:, :3]).as_matrix())
        pkn = pk + dk[:, 3:]
        rn, Jn = _evaluate(images, cameras, pattern, R21n, t21n, Rkn, pkn, f)
        cost_n = 0.5 * float(np.sum(rn * rn))
        step = max(np.abs(ds).max(), np.abs(dk).max()) / (1 + max(np.abs(t21).max(), np.abs(pk).max()))
        _log.debug("bundle adjustment %d: cost %.17g -> %.17g, step %.3g, mu %.3g", it, cost, cost_n, step, mu)
        if cost_n <= cost:
            R21, t21, Rk, pk, r, J, cost = R21n, t21n, Rkn, pkn, rn, Jn, cost_n
            mu = mu / 10
            if step < STEP_TOLERANCE or cost == 0.0:
                status = Status.CONVERGED
                break
        else:
            if step < 100 * STEP_TOLERANCE:  # no decrease left but rounding: converged
                status = Status.CONVERGED
                break
            mu = max(mu * 10, 1e-9)
    Hss, Hsk, Hkk, gs, gk = _normal(r, J)
    Hkk_inv = np.linalg.inv(Hkk)
    W = np.einsum("nij,njk->nik", Hsk, Hkk_inv)
    S_inv = np.linalg.inv(Hss - np.einsum("nij,nkj->ik", W, Hsk))
    cov_k = Hkk_inv + np.einsum("nji,jk,nkl->nil", W, S_inv, W)  # Hkk^-1 Hsk^T S^-1 Hsk Hkk^-1
    s2 = pixel_sigma ** 2
    JT = np.concatenate([-np.einsum("nij,jk->nik", Rk, _skew(o)), np.broadcast_to(np.eye(3), (images.n_poses, 3, 3))], axis=2)
    cov_T = s2 * np.einsum("nij,njk,nlk->nil", JT, cov_k, JT)
    M = pattern.n_corners
    res = r.reshape(images.n_poses, M, 2, 2).transpose(0, 2, 1, 3)
    rms = float(np.sqrt(np.mean(r * r)))
    msg = f"bundle adjustment {status} after {it} iterations: {images.n_poses} poses, reprojection RMS {rms:.3g} px"
    _log.info(msg)
    return StereoReconstruction(R21, t21, Rk, pk, pk + Rk @ o, cov_T, s2 * S_inv, pixel_sigma, rms, res, it,
                                solve_time_s=time.perf_counter() - t0, status=status, message=msg)


def _damped(H: np.ndarray, mu: float) -> np.ndarray:
    """Marquardt's damping: ``H + mu diag(H)`` (of one matrix or a stack)."""
    return H + mu * np.einsum("...ii->...i", H)[..., None] * np.eye(H.shape[-1])


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def common_displacement_pairs(q: np.typing.ArrayLike, tolerance: float = CART_PAIR_TOLERANCE_M) -> tuple[np.ndarray, np.ndarray]:
    """Pose pairs whose carts all moved by the same non-zero distance.

    Parameters
    ----------
    q : array_like, shape (N, 3)
        Cart positions [m].
    tolerance : float, optional
        Largest spread of the three carts' displacements [m].

    Returns
    -------
    k, l : numpy.ndarray of int, shape (P,)
        The pairs (``k < l``).
    """
    qa = np.asarray(q, dtype=float)
    dq = qa[None, :, :] - qa[:, None, :]
    common = (np.ptp(dq, axis=2) <= tolerance) & (np.abs(dq[:, :, 0]) > 10 * tolerance)
    return np.nonzero(np.triu(common, 1))


def scale_from_carts(q: np.typing.ArrayLike, T: np.typing.ArrayLike, transmission: float = 1.0,
                     tolerance: float = CART_PAIR_TOLERANCE_M) -> tuple[float, int, float]:
    """Metric scale from poses whose carts moved by one common displacement (Dressler (2012), ch. 5.5).

    A pair ``(k, l)`` with ``q_l - q_k = Delta (1, 1, 1)`` (within ``tolerance``) moves the
    TCP by ``c |Delta|`` along parallel guideways (``c`` the transmission: TCP travel per
    metre of cart travel, ``|v|`` of the model's guideway direction);
    ``lambda = sum c |Delta| |d| / sum |d|^2`` with ``d = T_l - T_k`` (least squares of
    ``lambda |d| = c |Delta|``).

    Parameters
    ----------
    q : array_like, shape (N, 3)
        Cart positions [m].
    T : array_like, shape (N, 3)
        Reconstructed TCPs [any unit].
    transmission : float, optional
        TCP travel per cart travel ``c`` [-] (default 1).
    tolerance : float, optional
        Largest spread of the three carts' displacements of a pair [m].

    Returns
    -------
    scale : float
        ``lambda`` [m per unit of ``T``].
    pairs : int
        Number of pairs used.
    spread : float
        RMS of ``lambda |d| - |Delta|`` over the pairs [m].

    Raises
    ------
    InputError
        No pair of poses with a common cart displacement.
    """
    qa, Ta = np.asarray(q, dtype=float), np.asarray(T, dtype=float)
    k, l_ = common_displacement_pairs(qa, tolerance)
    if k.size == 0:
        raise InputError("scale: no two poses whose carts all moved by the same distance (needed for the metric scale; "
                         "measure poses on a cart grid, or give the scale)")
    if not (np.isfinite(transmission) and transmission > 0):
        raise InputError(f"transmission: expected a positive factor, got {transmission!r}")
    delta = transmission * np.abs((qa[l_] - qa[k]).mean(axis=1))
    d = np.linalg.norm(Ta[l_] - Ta[k], axis=1)
    lam = float(np.sum(delta * d) / np.sum(d * d))
    return lam, int(k.size), float(np.sqrt(np.mean((lam * d - delta) ** 2)))


def reconstruct(
    images: StereoImages,
    cameras: Sequence[Camera],
    pattern: Pattern,
    tcp_in_pattern: np.typing.ArrayLike = (0.0, 0.0, 0.0),
    pixel_sigma: float = 0.3,
    scale: float | str = "carts",
    transmission: float = 1.0,
    max_iter: int = MAX_ITER,
) -> StereoReconstruction:
    """Bundle adjustment, TCPs with covariance and the metric scale (Dressler (2012), ch. 5.5).

    Parameters
    ----------
    images : StereoImages
        Corners of N >= 2 poses in both cameras.
    cameras : sequence of 2 Camera
        Intrinsics and distortion assumed for each camera.
    pattern : Pattern
        The pattern in its declared dimensions.
    tcp_in_pattern : array_like, shape (3,), optional
        The TCP in the pattern frame [pattern units].
    pixel_sigma : float, optional
        Corner noise [px] (> 0), for the covariance.
    scale : float or "carts", optional
        ``"carts"``: fitted by :func:`scale_from_carts`; a number: given [m per pattern unit].
    transmission : float, optional
        TCP travel per cart travel, for ``scale="carts"``.
    max_iter : int, optional
        Iteration limit of the bundle adjustment.

    Returns
    -------
    StereoReconstruction

    Raises
    ------
    InputError
        See :func:`bundle_adjust` and :func:`scale_from_carts`; a non-positive scale.
    """
    rec = bundle_adjust(images, cameras, pattern, tcp_in_pattern=tcp_in_pattern, pixel_sigma=pixel_sigma, max_iter=max_iter)
    if isinstance(scale, str):
        if scale != "carts":
            raise InputError(f"scale: expected 'carts' or a positive number, got {scale!r}")
        rec.scale, rec.scale_pairs, spread = scale_from_carts(images.q, rec.T, transmission)
        rec.message += f"; scale {rec.scale:.9g} m/unit from {rec.scale_pairs} cart displacements (spread {spread:.3g} m)"
    else:
        if not (np.isfinite(scale) and scale > 0):
            raise InputError(f"scale: expected a positive number [m per pattern unit], got {scale!r}")
        rec.scale = float(scale)
    return rec
