"""Link layout, solver constants and the nominal orientation of the six-link model."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)
from scipy.spatial.transform import Rotation

from gtmodel._arrays import as_array
from gtmodel.errors import InputError

#: Link names per arm of the 3-2-1 Gantry-Tau.
SIX_LINKS: tuple[tuple[str, ...], ...] = (("1",), ("2a", "2b"), ("3a", "3b", "3c"))
_LINK_NAMES: tuple[str, ...] = tuple(name for arm in SIX_LINKS for name in arm)
_ARM_OF_LINK: tuple[int, ...] = tuple(i for i, arm in enumerate(SIX_LINKS) for _ in arm)
#: Index of the first link of each arm in the six-link order (links 1, 2a, 3a).
_FIRST_LINK: tuple[int, ...] = (0, 1, 3)

#: Newton tolerance of the FK (eq. 4.15): max over the six links of |q_i - f_ik,ij(X)| [m].
FK_TOLERANCE = 1e-12
#: Newton iteration limit of the numeric FK (:meth:`SixLinkClosure.fk_solve`).
FK_MAX_ITER = 20
#: Newton iterations unrolled in :meth:`SixLinkClosure.fk_function` (the D1 needs 2 in its
#: workspace and at most 3 on a wider grid from the trilateration start: margin of 2).
FK_UNROLLED_ITER = 5
#: Largest accepted ``max |R^T R - I|`` of an orientation given to the IK.
ROTATION_TOLERANCE = 1e-6
#: Largest disagreement [m] of the links of one arm on the cart position for a pose to
#: count as an assembly (:meth:`SixLinkClosure.in_workspace`).
_ASSEMBLY_TOLERANCE = 1e-9
#: Smallest singular value [m] of the within-arm joint-point differences that still
#: determines the nominal orientation (:func:`estimate_nominal_orientation`).
_ORIENTATION_RANK_TOLERANCE = 1e-6

_RY_MINUS_HALF_PI = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])  # Ry(-pi/2)
_EULER_AT_REFERENCE = np.array([0.0, math.pi / 2, 0.0])


def _vec(R: np.ndarray) -> np.ndarray:
    """Column-major vec of a 3x3 matrix (CasADi's ``reshape`` order)."""
    return np.asarray(R, dtype=float).reshape(3, 3).ravel(order="F")


def estimate_nominal_orientation(A0: np.typing.ArrayLike, B0: np.typing.ArrayLike) -> tuple[np.ndarray, float]:
    """Nominal plate orientation from the joint points of the link clusters.

    In a parallelogram cluster ``A0_ij - A0_ik = R_T0 (B0_ij - B0_ik)`` (Dressler (2012),
    eq. 4.14 with equal link vectors). ``R_T0`` is the orthogonal-Procrustes (Kabsch)
    solution over all within-arm pairs (arm 2: one pair, arm 3: three pairs), computed
    with :meth:`scipy.spatial.transform.Rotation.align_vectors`.

    Parameters
    ----------
    A0 : array_like, shape (6, 3)
        Cart-side joint points at ``q = 0`` in the base frame [m], links in the order
        ``1, 2a, 2b, 3a, 3b, 3c``.
    B0 : array_like, shape (6, 3)
        Plate-side joint points in the plate frame [m], same order.

    Returns
    -------
    R_T0 : numpy.ndarray, shape (3, 3)
        Rotation from the plate frame to the base frame.
    rms : float
        Root-mean-square residual ``|dA - R_T0 dB|`` over the pairs [m].

    Raises
    ------
    InputError
        If the shapes are wrong or the differences of ``B0`` (or ``A0``) do not span a
        plane (fewer than two independent directions: no unique rotation).
    """
    A = as_array(A0, (6, 3), "A0")
    B = as_array(B0, (6, 3), "B0")
    pairs = [(j, k) for arm in SIX_LINKS for a, j in enumerate(arm) for k in arm[a + 1:]]
    idx = {name: n for n, name in enumerate(_LINK_NAMES)}
    dA = np.array([A[idx[k]] - A[idx[j]] for j, k in pairs])
    dB = np.array([B[idx[k]] - B[idx[j]] for j, k in pairs])
    for name, D in (("B0", dB), ("A0", dA)):
        sv = np.linalg.svd(D, compute_uv=False)
        if sv[1] < _ORIENTATION_RANK_TOLERANCE:
            raise InputError(
                f"{name}: the within-arm differences of the joint points span no plane "
                f"(singular values {np.round(sv, 9).tolist()} m): the nominal orientation is not determined"
            )
    rot, _ = Rotation.align_vectors(dA, dB)
    R = rot.as_matrix()
    rms = float(np.sqrt(np.mean(np.sum((dA - dB @ R.T) ** 2, axis=1))))
    return R, rms


@dataclass(frozen=True)
class SixLinkFKResult:
    """Result of the six-link forward kinematics (Dressler (2012), eq. 4.15).

    Parameters
    ----------
    T : numpy.ndarray, shape (N, 3)
        TCP positions [m].
    R : numpy.ndarray, shape (N, 3, 3)
        Plate orientations ``R_T``.
    euler : numpy.ndarray, shape (N, 3)
        The Newton unknowns ``(alpha, beta, gamma)`` [rad], ZYZ angles relative to
        ``R_ref = R0 Ry(-pi/2)`` (``(0, pi/2, 0)`` at the nominal orientation).
    iterations : numpy.ndarray of int, shape (N,)
        Newton iterations used per pose.
    residual : numpy.ndarray, shape (N,)
        Final ``max |q_i - f_ik,ij(X)|`` over the six links [m].
    """

    T: np.ndarray
    R: np.ndarray
    euler: np.ndarray
    iterations: np.ndarray
    residual: np.ndarray


