"""Rotations and quaternions, numeric and symbolic (CasADi), in one place.

Functions accept CasADi ``SX``/``MX`` (for model graphs) or numbers (NumPy out). Where
nothing symbolic is needed, callers may equally use :class:`scipy.spatial.transform.Rotation`.
Quaternions are ``(w, x, y, z)`` (scalar first).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

__all__ = [
    "quaternion_to_rotation",
    "rotation_to_quaternion",
    "zyz_to_rotation",
    "rotation_to_zyz",
    "rotation_vector_to_rotation",
    "rotation_log",
    "rot_x",
    "rot_y",
    "rot_z",
    "quat_mul",
    "quat_exp",
    "quat_conj",
    "QUAT_EXP_SERIES_LIMIT",
]


def rot_x(a: Any) -> Any:
    """Rotation about x by ``a`` [rad].

    Parameters
    ----------
    a : float or casadi.SX or casadi.MX
        Angle [rad].

    Returns
    -------
    casadi.SX or casadi.MX or casadi.DM, shape (3, 3)
        The rotation (a CasADi expression for any input).
    """
    c, s = ca.cos(a), ca.sin(a)
    return ca.vertcat(ca.horzcat(1, 0, 0), ca.horzcat(0, c, -s), ca.horzcat(0, s, c))


def quaternion_to_rotation(quat: Any, normalise: bool = True) -> Any:
    """Rotation matrix of a quaternion ``(w, x, y, z)`` (Hamilton convention: ``R`` rotates body-frame vectors into the world frame).

    With ``normalise`` (the default) the quaternion is normalised inside the formula (``R``
    is a rotation for any non-zero ``quat``), so a calibration that lets the 4-vector drift
    cannot produce a scaled "rotation" (the failure reported in Dressler (2012), ch. 5.4).
    Without it the standard unit-quaternion form ``I + 2 w [v]x + 2 [v]x^2`` is used, whose
    derivative keeps the radial direction (the filters of :mod:`gtmodel.estimation`, whose
    state quaternion is normalised by the transition).

    Parameters
    ----------
    quat : casadi.SX or casadi.MX or casadi.DM or array_like, shape (4,)
        Quaternion ``(w, x, y, z)``: not zero (``normalise=True``) or unit (``normalise=False``).
    normalise : bool, optional
        Divide by ``|quat|^2`` inside the formula (default True).

    Returns
    -------
    casadi.SX or casadi.MX or numpy.ndarray, shape (3, 3)
        The rotation matrix (NumPy array for numeric input, including ``casadi.DM``).
    """
    numeric = not isinstance(quat, (ca.SX, ca.MX))
    qv = ca.DM(np.asarray(quat, dtype=float).reshape(4)) if numeric else quat
    w, x, y, z = qv[0], qv[1], qv[2], qv[3]
    s = 2.0 / (w * w + x * x + y * y + z * z) if normalise else 2.0
    R = ca.vertcat(
        ca.horzcat(1 - s * (y * y + z * z), s * (x * y - w * z), s * (x * z + w * y)),
        ca.horzcat(s * (x * y + w * z), 1 - s * (x * x + z * z), s * (y * z - w * x)),
        ca.horzcat(s * (x * z - w * y), s * (y * z + w * x), 1 - s * (x * x + y * y)),
    )
    return np.array(R) if numeric else R


def rotation_to_quaternion(R: np.typing.ArrayLike) -> np.ndarray:
    """Unit quaternion ``(w, x, y, z)`` with ``w >= 0`` of a rotation matrix.

    Parameters
    ----------
    R : array_like, shape (3, 3) or (N, 3, 3)
        Rotation matrices.

    Returns
    -------
    numpy.ndarray, shape (4,) or (N, 4)
        Quaternions (Shepperd's method, numerically stable for every rotation).
    """
    Rm = np.asarray(R, dtype=float)
    single = Rm.ndim == 2
    Rm = Rm.reshape(-1, 3, 3)
    out = np.empty((Rm.shape[0], 4))
    for k, M in enumerate(Rm):
        tr = np.trace(M)
        cand = np.array([tr, M[0, 0], M[1, 1], M[2, 2]])
        i = int(np.argmax(cand))
        if i == 0:
            w = 0.5 * np.sqrt(1 + tr)
            q = [w, (M[2, 1] - M[1, 2]) / (4 * w), (M[0, 2] - M[2, 0]) / (4 * w), (M[1, 0] - M[0, 1]) / (4 * w)]
        elif i == 1:
            x = 0.5 * np.sqrt(1 + 2 * M[0, 0] - tr)
            q = [(M[2, 1] - M[1, 2]) / (4 * x), x, (M[0, 1] + M[1, 0]) / (4 * x), (M[0, 2] + M[2, 0]) / (4 * x)]
        elif i == 2:
            y = 0.5 * np.sqrt(1 + 2 * M[1, 1] - tr)
            q = [(M[0, 2] - M[2, 0]) / (4 * y), (M[0, 1] + M[1, 0]) / (4 * y), y, (M[1, 2] + M[2, 1]) / (4 * y)]
        else:
            z = 0.5 * np.sqrt(1 + 2 * M[2, 2] - tr)
            q = [(M[1, 0] - M[0, 1]) / (4 * z), (M[0, 2] + M[2, 0]) / (4 * z), (M[1, 2] + M[2, 1]) / (4 * z), z]
        q = np.asarray(q)
        out[k] = q if q[0] >= 0 else -q
    return out[0] if single else out


def rot_z(a: Any) -> Any:
    """Rotation about z by ``a`` [rad].

    Parameters
    ----------
    a : float or casadi.SX or casadi.MX
        Angle [rad].

    Returns
    -------
    casadi.SX or casadi.MX or casadi.DM, shape (3, 3)
        The rotation (a CasADi expression for any input).
    """
    c, s = ca.cos(a), ca.sin(a)
    return ca.vertcat(ca.horzcat(c, -s, 0), ca.horzcat(s, c, 0), ca.horzcat(0, 0, 1))


def rot_y(b: Any) -> Any:
    """Rotation about y by ``b`` [rad].

    Parameters
    ----------
    b : float or casadi.SX or casadi.MX
        Angle [rad].

    Returns
    -------
    casadi.SX or casadi.MX or casadi.DM, shape (3, 3)
        The rotation (a CasADi expression for any input).
    """
    c, s = ca.cos(b), ca.sin(b)
    return ca.vertcat(ca.horzcat(c, 0, s), ca.horzcat(0, 1, 0), ca.horzcat(-s, 0, c))


def zyz_to_rotation(alpha: Any, beta: Any, gamma: Any) -> Any:
    """Rotation ``Rz(alpha) Ry(beta) Rz(gamma)`` (ZYZ Euler angles), Dressler (2012), eq. 4.15.

    Parameters
    ----------
    alpha, beta, gamma : float or casadi.SX or casadi.MX
        Euler angles [rad].

    Returns
    -------
    numpy.ndarray or casadi.SX or casadi.MX, shape (3, 3)
        The rotation (NumPy for numeric input).
    """
    symbolic = any(isinstance(a, (ca.SX, ca.MX)) for a in (alpha, beta, gamma))
    R = ca.mtimes([rot_z(alpha), rot_y(beta), rot_z(gamma)])
    return R if symbolic else np.array(ca.DM(R))


def rotation_to_zyz(R: np.typing.ArrayLike) -> np.ndarray:
    """ZYZ Euler angles ``(alpha, beta, gamma)`` of rotation matrices, ``beta`` in [0, pi].

    At ``beta = 0`` (gimbal lock, e.g. the nominal plate orientation) only
    ``alpha + gamma`` is defined; it is returned as ``alpha`` with ``gamma = 0``.

    Parameters
    ----------
    R : array_like, shape (3, 3) or (N, 3, 3)
        Rotation matrices.

    Returns
    -------
    numpy.ndarray, shape (3,) or (N, 3)
        Angles [rad].
    """
    Rm = np.asarray(R, dtype=float)
    single = Rm.ndim == 2
    Rm = Rm.reshape(-1, 3, 3)
    beta = np.arctan2(np.hypot(Rm[:, 0, 2], Rm[:, 1, 2]), Rm[:, 2, 2])
    lock = np.hypot(Rm[:, 0, 2], Rm[:, 1, 2]) < 1e-12
    alpha = np.where(lock, np.arctan2(Rm[:, 1, 0], Rm[:, 0, 0]), np.arctan2(Rm[:, 1, 2], Rm[:, 0, 2]))
    gamma = np.where(lock, 0.0, np.arctan2(Rm[:, 2, 1], -Rm[:, 2, 0]))
    out = np.column_stack([alpha, beta, gamma])
    return out[0] if single else out


def rotation_vector_to_rotation(r: Any) -> Any:
    """Rotation of a rotation vector (axis times angle), Rodrigues' formula.

    Smooth at ``r = 0`` (the series form is used for the coefficients), which makes it
    the local 3-parameter orientation of Newton's method and of quaternion parameters.

    Parameters
    ----------
    r : casadi.SX or casadi.MX or array_like, shape (3,)
        Rotation vector [rad].

    Returns
    -------
    casadi.SX or casadi.MX or numpy.ndarray, shape (3, 3)
        The rotation.
    """
    numeric = not isinstance(r, (ca.SX, ca.MX))
    rv = ca.DM(np.asarray(r, dtype=float).reshape(3)) if numeric else r
    th2 = ca.dot(rv, rv)
    th = ca.sqrt(th2 + 1e-300)
    small = th2 < 1e-8
    a = ca.if_else(small, 1 - th2 / 6 + th2 * th2 / 120, ca.sin(th) / th)
    b = ca.if_else(small, 0.5 - th2 / 24 + th2 * th2 / 720, (1 - ca.cos(th)) / th2)
    K = ca.skew(rv)
    R = ca.DM.eye(3) + a * K + b * ca.mtimes(K, K)
    return np.array(ca.DM(R)) if numeric else R


def rotation_log(M: Any) -> Any:
    """Rotation vector of a rotation matrix (angle below pi), the inverse of Rodrigues' formula.

    Parameters
    ----------
    M : casadi.SX or casadi.MX, shape (3, 3)
        Rotation matrix.

    Returns
    -------
    casadi.SX or casadi.MX, shape (3,)
        Rotation vector [rad] (smooth at the identity).
    """
    c = ca.fmin(ca.fmax((M[0, 0] + M[1, 1] + M[2, 2] - 1) / 2, -1), 1)
    th = ca.acos(c)
    vee = ca.vertcat(M[2, 1] - M[1, 2], M[0, 2] - M[2, 0], M[1, 0] - M[0, 1])
    f = ca.if_else(th < 1e-4, 0.5 + th * th / 12, th / (2 * ca.sin(th) + 1e-300))
    return f * vee


def quat_mul(a: Any, b: Any) -> Any:
    """Hamilton product ``a (x) b`` of quaternions ``(w, x, y, z)`` (a CasADi column).

    Parameters
    ----------
    a, b : casadi.SX or casadi.MX or casadi.DM or array_like, shape (4,)
        Quaternions.

    Returns
    -------
    casadi.SX or casadi.MX or casadi.DM, shape (4, 1)
        The product (``numpy.asarray(...).ravel()`` for NumPy).
    """
    aw, av = a[0], ca.vertcat(a[1], a[2], a[3])
    bw, bv = b[0], ca.vertcat(b[1], b[2], b[3])
    return ca.vertcat(aw * bw - ca.dot(av, bv), aw * bv + bw * av + ca.cross(av, bv))


def quat_conj(q: Any) -> Any:
    """Conjugate ``(w, -x, -y, -z)`` of a quaternion (the inverse of a unit quaternion).

    Parameters
    ----------
    q : casadi.SX or casadi.MX or casadi.DM or array_like, shape (4,)
        Quaternion ``(w, x, y, z)``.

    Returns
    -------
    casadi.SX or casadi.MX or casadi.DM, shape (4, 1)
    """
    return ca.vertcat(q[0], -q[1], -q[2], -q[3])


#: Below this squared half angle ``|r|^2 / 4`` [rad^2] :func:`quat_exp` uses its Taylor series
#: (truncation error below 1e-16; above it ``sin(theta)/theta`` loses no digits to cancellation,
#: in its values or in its AD derivatives).
QUAT_EXP_SERIES_LIMIT = 1e-2


def quat_exp(r: Any) -> Any:
    """Unit quaternion of the rotation vector ``r`` (``exp(r / 2)``), smooth at ``r = 0``.

    ``exp(r / 2) = (cos(theta), sin(theta)/theta r / 2)`` with ``theta = |r| / 2``, written in
    ``theta^2``, with the Taylor series of ``cos`` and ``sin(theta)/theta`` (to ``theta^8``) below
    ``theta^2 =`` :data:`QUAT_EXP_SERIES_LIMIT`: the expression and its AD derivatives are
    finite at ``r = 0`` and accurate to rounding on both sides of the switch (Cvitanic (2021),
    eq. (28)).

    Parameters
    ----------
    r : casadi.SX or casadi.MX or casadi.DM or array_like, shape (3,)
        Rotation vector [rad] (axis times angle).

    Returns
    -------
    casadi.SX or casadi.MX or casadi.DM, shape (4, 1)
        Scalar-first unit quaternion.
    """
    v = ca.vertcat(r[0], r[1], r[2])
    s = ca.dot(v, v) / 4.0  # theta^2
    theta = ca.sqrt(ca.fmax(s, QUAT_EXP_SERIES_LIMIT))  # the large-angle branch never sees theta = 0
    cos_series = 1 - s / 2 + s**2 / 24 - s**3 / 720 + s**4 / 40320
    sinc_series = 1 - s / 6 + s**2 / 120 - s**3 / 5040 + s**4 / 362880
    small = s < QUAT_EXP_SERIES_LIMIT
    c = ca.if_else(small, cos_series, ca.cos(theta))
    sinc = ca.if_else(small, sinc_series, ca.sin(theta) / theta)
    return ca.vertcat(c, sinc * v / 2)
