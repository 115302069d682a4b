"""The geometric method of pose accuracy analysis, Dressler (2012), Appendix A.2-A.4.

For every arm the detached link end ``B_i`` lies between two ellipsoids centred in the
nominal joint point ``A_i^n`` with axes ``(L_i -+ r_ij) u_ij`` (eq. A.1 and the text after
it; a link-length tolerance ``l_i`` adds to every ``r_ij``). The TCP error set ``S^T`` is
the intersection of the three shells; its eight corners are intersections of one limiting
ellipsoid per arm, found by the iteration of A.2 (:func:`ellipsoid_corners`: project on
every ellipsoid along the ray from its centre, intersect the three tangent planes, repeat).
For spherical errors (A.3) the corners are the forward kinematics with the link lengths
``L_i +- r_i`` (:func:`sphere_corners`, the 3-link model's own FK). For ``L_i >> r_ij``
the shells are planes and ``S^T`` is a parallelepiped (A.4, :func:`parallelepiped`):
face pair ``F_i`` orthogonal to link ``i`` at distance ``h_i = 2 r_i``, the worst case
along one of its four diagonals.

Corner ``j`` (0-7) takes the upper shell of arm ``i`` when bit ``i`` of ``j`` is set.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from gtmodel.calibration.accuracy.tolerances import NominalPoses, Tolerances
from gtmodel.errors import ConvergenceError
from gtmodel.robots.kinematic_expressions import fk_expression

__all__ = ["CORNER_SIGNS", "ellipsoid_corners", "sphere_corners", "Parallelepiped", "parallelepiped", "fk_branch"]

#: Corner j -> the shell per arm (+1 upper, -1 lower): bit i of j set -> upper shell of arm i.
CORNER_SIGNS = np.array([[1.0 if (j >> i) & 1 else -1.0 for i in range(3)] for j in range(8)])
#: Stop the A.2 iteration when the three projections are this close [m] (step 3).
CORNER_TOLERANCE_M = 1e-13
#: Most A.2 iterations (each one a Newton step; 3-5 are enough for L >> r).
MAX_CORNER_ITERATIONS = 50


def _shell_axes(nominal: NominalPoses, tol: Tolerances) -> np.ndarray:
    """Semi-axes of the limiting ellipsoids per corner and arm, shape (8, 3, 3) [m]."""
    r = tol.semi_axes + tol.link[:, None]
    return nominal.L[None, :, None] + CORNER_SIGNS[:, :, None] * r[None]


def ellipsoid_corners(nominal: NominalPoses, tol: Tolerances) -> tuple[np.ndarray, np.ndarray]:
    """The eight corners of ``S^T`` by the iterative intersection of A.2 (its six steps).

    Step 1 starts at the nominal TCP; step 2 projects the estimate on each ellipsoid along
    the half-line from its centre; step 3 stops when the projections are within
    :data:`CORNER_TOLERANCE_M`; steps 4-5 intersect the tangent planes at the projections;
    step 6 repeats.

    Parameters
    ----------
    nominal : NominalPoses
        The nominal geometry at N poses.
    tol : Tolerances
        The error bounds.

    Returns
    -------
    corners : numpy.ndarray, shape (N, 8, 3)
        Corner positions ``T^j`` [m].
    iterations : numpy.ndarray of int, shape (N,)
        Iterations used per pose (the most over its corners).

    Raises
    ------
    ConvergenceError
        No convergence within :data:`MAX_CORNER_ITERATIONS` (a start on the far side of an
        ellipsoid, A.2); the message names the pose.
    """
    N = nominal.T.shape[0]
    c = np.broadcast_to(nominal.A[:, None], (N, 8, 3, 3))  # centres (N, 8, arm, xyz)
    R = tol.axes  # (arm, xyz, k)
    a = _shell_axes(nominal, tol)  # (8, arm, k)
    x = np.broadcast_to(nominal.T[:, None], (N, 8, 3)).copy()
    iterations = np.zeros(N, dtype=int)
    for it in range(1, MAX_CORNER_ITERATIONS + 1):
        d = x[:, :, None, :] - c  # (N, 8, arm, 3)
        local = np.einsum("ixk,njix->njik", R, d) / a[None]  # coordinates in the ellipsoid's unit sphere
        p = c + d / np.linalg.norm(local, axis=3, keepdims=True)  # step 2
        spread = np.max(np.linalg.norm(p - p[:, :, [1, 2, 0]], axis=3), axis=2)  # step 3
        done = spread < CORNER_TOLERANCE_M
        if np.all(done):
            break
        iterations[~np.all(done, axis=1)] = it
        # step 4: normals Q^-1 (p - c) with Q = R diag(a^2) R^T
        pl = np.einsum("ixk,njix->njik", R, p - c) / a[None] ** 2
        n = np.einsum("ixk,njik->njix", R, pl)
        rhs = np.einsum("njix,njix->nji", n, p)
        x = np.linalg.solve(n, rhs[..., None])[..., 0]  # step 5
    else:
        k = int(np.argmax(~np.all(done, axis=1)))
        raise ConvergenceError(f"pose accuracy: the ellipsoid intersection (Dressler (2012), A.2) did not converge "
                               f"in {MAX_CORNER_ITERATIONS} iterations at pose {nominal.T[k].tolist()}")
    return p.mean(axis=2), iterations + 1


def fk_branch(nominal: NominalPoses) -> np.ndarray:
    """The FK solution sign (+1/-1, :func:`fk_expression`) that gives the nominal TCP per pose.

    Parameters
    ----------
    nominal : NominalPoses
        The nominal geometry.

    Returns
    -------
    numpy.ndarray, shape (N,)
    """
    f = _fk_points_function()
    out = np.empty(nominal.T.shape[0])
    for k in range(nominal.T.shape[0]):
        T = np.array(f(nominal.A[k], nominal.L, nominal.v, 1.0)).ravel()
        out[k] = 1.0 if np.linalg.norm(T - nominal.T[k]) < 1e-6 else -1.0
    return out


_FK_POINTS: list[ca.Function] = []


def _fk_points_function() -> ca.Function:
    """``fk_points(A[3x3], L[3], v[3x3], solution) -> T``: trilateration from joint points (eq. 4.9)."""
    if not _FK_POINTS:
        A = ca.SX.sym("A", 3, 3)
        L = ca.SX.sym("L", 3)
        v = ca.SX.sym("v", 3, 3)
        s = ca.SX.sym("solution")
        T, _, _ = fk_expression(ca.SX.zeros(3), s, L, A, v)
        _FK_POINTS.append(ca.Function("fk_points", [A, L, v, s], [T], ["A", "L", "v", "solution"], ["T"]))
    return _FK_POINTS[0]


def sphere_corners(nominal: NominalPoses, radii: np.ndarray) -> np.ndarray:
    """The eight corners for spherical errors: FK with link lengths ``L_i +- r_i`` (A.3).

    Parameters
    ----------
    nominal : NominalPoses
        The nominal geometry at N poses.
    radii : numpy.ndarray, shape (3,)
        Error radius (or link-length tolerance) per arm [m].

    Returns
    -------
    numpy.ndarray, shape (N, 8, 3)
        Corner positions [m], ordered as :data:`CORNER_SIGNS`.
    """
    f = _fk_points_function()
    branch = fk_branch(nominal)
    N = nominal.T.shape[0]
    Ls = nominal.L[None] + CORNER_SIGNS * np.asarray(radii, dtype=float)[None]  # (8, 3)
    A = np.hstack([nominal.A[k] for k in range(N) for _ in range(8)])  # 3x3 blocks side by side
    v = np.tile(nominal.v, (1, 8 * N))
    T = np.array(f.map(8 * N)(A, np.tile(Ls.T, (1, N)), v, np.repeat(branch, 8)[None]))
    return T.T.reshape(N, 8, 3)


@dataclass(frozen=True)
class Parallelepiped:
    """The parallelepiped approximation of ``S^T``, Dressler (2012), A.4, at N poses.

    Parameters
    ----------
    half_widths : numpy.ndarray, shape (N, 3)
        ``h_i / 2`` per link: the half distance of face pair ``F_i`` [m] (``r_i`` for
        spherical errors; the ellipsoid's support along link ``i`` in general, plus ``l_i``).
    corners : numpy.ndarray, shape (N, 8, 3)
        Corner offsets from the nominal TCP [m], ordered as :data:`CORNER_SIGNS`.
    diagonals : numpy.ndarray, shape (N, 4)
        Lengths of the four diagonals [m] (corners j and 7 - j).
    face_areas : numpy.ndarray, shape (N, 3)
        Area of a face of pair ``F_i`` (orthogonal to link i) [m^2] (Fig. 4.9).
    worst : numpy.ndarray, shape (N,)
        Largest distance of a corner from the nominal TCP [m]: half the longest diagonal.
    direction : numpy.ndarray, shape (N, 3)
        Unit direction of the worst case.
    """

    half_widths: np.ndarray
    corners: np.ndarray
    diagonals: np.ndarray
    face_areas: np.ndarray
    worst: np.ndarray
    direction: np.ndarray


def support_half_widths(nominal: NominalPoses, tol: Tolerances) -> np.ndarray:
    """Half width of face pair ``F_i``: ``sqrt(u_i^T M_i u_i) + l_i`` [m], shape (N, 3).

    The largest displacement of ``A_i`` along link ``i`` within its ellipsoid (the support
    function of ``E_i^A``), plus the link-length tolerance (A.3-A.4).

    Parameters
    ----------
    nominal : NominalPoses
        The nominal geometry.
    tol : Tolerances
        The error bounds.

    Returns
    -------
    numpy.ndarray, shape (N, 3)
    """
    M = tol.shape_matrices()
    return np.sqrt(np.einsum("nix,ixy,niy->ni", nominal.u, M, nominal.u)) + tol.link[None]


def parallelepiped(nominal: NominalPoses, tol: Tolerances) -> Parallelepiped:
    """The parallelepiped approximation (A.4): faces orthogonal to the links.

    To first order the TCP error satisfies ``u_i . dT = e_i`` with ``|e_i| <= h_i / 2``
    (the displacement of ``A_i`` along its link, plus the length error), so the corners
    are ``U^-1 (s * h / 2)`` for the sign vectors ``s`` of :data:`CORNER_SIGNS`, ``U`` the
    matrix of unit link directions.

    Parameters
    ----------
    nominal : NominalPoses
        The nominal geometry at N poses.
    tol : Tolerances
        The error bounds.

    Returns
    -------
    Parallelepiped
    """
    h = support_half_widths(nominal, tol)
    Uinv = np.linalg.inv(nominal.u)  # (N, 3, 3): columns are the edge directions
    corners = np.einsum("nxi,ji,ni->njx", Uinv, CORNER_SIGNS, h)
    dist = np.linalg.norm(corners, axis=2)
    diagonals = 2.0 * dist[:, :4]
    edges = Uinv * (2.0 * h[:, None, :])  # column i: edge vector across face pair F_i
    areas = np.stack([np.linalg.norm(np.cross(edges[:, :, (i + 1) % 3], edges[:, :, (i + 2) % 3]), axis=1) for i in range(3)], axis=1)
    k = np.argmax(dist, axis=1)
    worst = dist[np.arange(dist.shape[0]), k]
    direction = corners[np.arange(dist.shape[0]), k] / worst[:, None]
    return Parallelepiped(h, corners, diagonals, areas, worst, direction)
