"""The closure equations of the 3-link Gantry-Tau model as CasADi expressions.

The closure equation of arm ``i`` (Dressler (2012), eq. 4.9)::

    L_i^2 = || As_i + q_i v_i - T ||^2

written once, symbolically, and what follows from it: inverse kinematics (a quadratic
per arm, :func:`ik_expression`), forward kinematics (trilateration of three spheres,
:func:`fk_expression`), the inverse Jacobian (eq. 6.5), the link cosines and the
acceleration relations (eq. 6.6), plus :func:`configuration_signs` (the IK root signs
of a configuration; see :mod:`gtmodel.robots.kinematics` for the conventions).
:class:`~gtmodel.robots.kinematics.GantryTau3Kinematics` wraps them in
:class:`casadi.Function` objects; the other robot models, the trajectory planners and
the identification build their own graphs from them.
"""

from __future__ import annotations

from typing import Sequence

import casadi as ca
import numpy as np

from gtmodel.errors import InputError

__all__ = [
    "Expr",
    "closure_residual",
    "ik_expression",
    "fk_expression",
    "jacobian_inverse_expression",
    "link_cosines_expression",
    "acceleration_expression",
    "cart_acceleration_expression",
    "configuration_signs",
]

#: A CasADi expression (or a numeric array where a parameter is numeric).
Expr = ca.SX | ca.MX | ca.DM | np.ndarray


# ----------------------------------------------------------------------------- expressions
def _row(M: ca.SX | ca.MX, i: int) -> ca.SX | ca.MX:
    return M[i, :].T


def _link_vectors(T, q, As, v) -> list:
    """``dP_i = T - (As_i + q_i v_i)``, the link vector of arm i (eqs. 4.9, 6.3)."""
    return [T - (_row(As, i) + q[i] * _row(v, i)) for i in range(3)]


def closure_residual(T: Expr, q: Expr, L: Expr, As: Expr, v: Expr) -> Expr:
    """Closure equations of the 3-link model, Dressler (2012), eq. 4.9.

    Parameters
    ----------
    T : casadi.SX or casadi.MX, shape (3, 1)
        TCP position [m].
    q : casadi.SX or casadi.MX, shape (3, 1)
        Cart positions [m].
    L : casadi.SX or casadi.MX or numpy.ndarray, shape (3,)
        Link lengths [m].
    As : casadi.SX or casadi.MX or numpy.ndarray, shape (3, 3)
        Row i: joint point of arm i at ``q_i = 0`` [m].
    v : casadi.SX or casadi.MX or numpy.ndarray, shape (3, 3)
        Row i: guideway direction of arm i.

    Returns
    -------
    casadi.SX or casadi.MX, shape (3, 1)
        ``||As_i + q_i v_i - T||^2 - L_i^2`` [m^2]; zero on a consistent pose.
    """
    return ca.vertcat(*[ca.dot(dP, dP) - L[i] ** 2 for i, dP in enumerate(_link_vectors(T, q, As, v))])


def ik_expression(T: Expr, s: Expr, L: Expr, As: Expr, v: Expr) -> tuple[Expr, Expr]:
    """Inverse kinematics of the 3-link model: one quadratic per arm (eq. 4.9).

    Parameters
    ----------
    T : casadi.SX or casadi.MX, shape (3, 1)
        TCP position [m].
    s : casadi.SX or casadi.MX or sequence of float, shape (3,)
        Root sign per arm, -1 or +1 (see :func:`configuration_signs`).
    L, As, v
        Kinematic parameters, as in :func:`closure_residual`.

    Returns
    -------
    q : casadi.SX or casadi.MX, shape (3, 1)
        Cart positions [m]. Where an arm cannot reach ``T`` the square root is taken of
        zero, so ``q`` stays finite; check ``disc``.
    disc : casadi.SX or casadi.MX, shape (3, 1)
        Scaled discriminant ``(d.v)^2 - |v|^2 (|d|^2 - L^2)`` per arm [m^2]; negative
        means arm i cannot reach ``T``.
    """
    q, disc = [], []
    for i in range(3):
        vi = _row(v, i)
        d = T - _row(As, i)
        dv = ca.dot(d, vi)
        vv = ca.dot(vi, vi)
        di = dv**2 - vv * (ca.dot(d, d) - L[i] ** 2)
        q.append((dv + s[i] * ca.sqrt(ca.fmax(di, 0))) / vv)
        disc.append(di)
    return ca.vertcat(*q), ca.vertcat(*disc)


def fk_expression(q: Expr, solution: Expr | float, L: Expr, As: Expr, v: Expr) -> tuple[Expr, Expr, Expr]:
    """Forward kinematics by trilateration of the three spheres (eq. 4.9).

    Parameters
    ----------
    q : casadi.SX or casadi.MX, shape (3, 1)
        Cart positions [m].
    solution : casadi.SX or casadi.MX or float
        +1 for the intersection on the side of the mean guideway direction, -1 for the
        mirror image.
    L, As, v
        Kinematic parameters, as in :func:`closure_residual`.

    Returns
    -------
    T : casadi.SX or casadi.MX, shape (3, 1)
        TCP position [m] (finite even where the spheres do not meet; check ``h2``).
    h2 : casadi.SX or casadi.MX, scalar
        Squared distance of the TCP from the plane of the sphere centres [m^2];
        negative means the spheres do not intersect (no pose for ``q``).
    j : casadi.SX or casadi.MX, scalar
        Distance of the third centre from the line through the first two [m]; near zero
        the centres are collinear and the pose is not unique.
    """
    A = [_row(As, i) + q[i] * _row(v, i) for i in range(3)]
    d21 = A[1] - A[0]
    d31 = A[2] - A[0]
    d = ca.norm_2(d21)
    ex = d21 / d
    i_ = ca.dot(ex, d31)
    ey_raw = d31 - i_ * ex
    j = ca.norm_2(ey_raw)
    ey = ey_raw / j
    ez = ca.cross(ex, ey)
    x = (L[0] ** 2 - L[1] ** 2 + d**2) / (2 * d)
    y = (L[0] ** 2 - L[2] ** 2 + i_**2 + j**2) / (2 * j) - (i_ / j) * x
    h2 = L[0] ** 2 - x**2 - y**2
    vbar = (_row(v, 0) + _row(v, 1) + _row(v, 2)) / 3
    side = ca.sign(ca.dot(ez, vbar))
    side = ca.if_else(side == 0, 1, side)
    z = solution * side * ca.sqrt(ca.fmax(h2, 0))
    T = A[0] + x * ex + y * ey + z * ez
    return T, h2, j


def jacobian_inverse_expression(T: Expr, q: Expr, As: Expr, v: Expr) -> Expr:
    """Inverse Jacobian ``q_dot = J^-1 T_dot``, Dressler (2012), eq. 6.5.

    Row i is ``dP_i^T / (dP_i . v_i)`` with ``dP_i = T - (As_i + q_i v_i)``; for
    ``v_i = e_x`` this is ``(1, dY_i/dX_i, dZ_i/dX_i)`` as printed in the thesis.

    Parameters
    ----------
    T : casadi.SX or casadi.MX, shape (3, 1)
        TCP position [m].
    q : casadi.SX or casadi.MX, shape (3, 1)
        Cart positions [m] consistent with ``T``.
    As, v
        Kinematic parameters, as in :func:`closure_residual`.

    Returns
    -------
    casadi.SX or casadi.MX, shape (3, 3)
        ``J^-1`` (dimensionless).
    """
    return ca.vertcat(*[dP.T / ca.dot(dP, _row(v, i)) for i, dP in enumerate(_link_vectors(T, q, As, v))])


def link_cosines_expression(T: Expr, q: Expr, As: Expr, v: Expr) -> Expr:
    """Cosine of the angle between each link and its guideway direction.

    ``c_i = dP_i . v_i / (|dP_i| |v_i|)`` with ``dP_i = T - (As_i + q_i v_i)``: +1 for a link
    pointing along ``v_i`` (the nominal assembly), 0 where the Jacobian of eq. 6.5 is
    singular. The spherical-joint limit is ``|c_i| >= cos(joint_angle_max)``.

    Parameters
    ----------
    T : casadi.SX or casadi.MX, shape (3, 1)
        TCP position [m].
    q : casadi.SX or casadi.MX, shape (3, 1)
        Cart positions [m] consistent with ``T``.
    As, v
        Kinematic parameters, as in :func:`closure_residual`.

    Returns
    -------
    casadi.SX or casadi.MX, shape (3, 1)
        The three cosines (dimensionless).
    """
    return ca.vertcat(
        *[ca.dot(dP, _row(v, i)) / (ca.norm_2(dP) * ca.norm_2(_row(v, i))) for i, dP in enumerate(_link_vectors(T, q, As, v))]
    )


def _dP_matrix(T, q, As, v):
    return ca.vertcat(*[dP.T for dP in _link_vectors(T, q, As, v)])


def _s_vector(T_dot, q_dot, v):
    return ca.vertcat(*[ca.sumsqr(T_dot - q_dot[i] * _row(v, i)) for i in range(3)])


def acceleration_expression(T: Expr, T_dot: Expr, q: Expr, q_dot: Expr, q_ddot: Expr, As: Expr, v: Expr) -> Expr:
    """TCP acceleration from cart accelerations, Dressler (2012), eq. 6.6.

    ``T_ddot = J q_ddot - [dP]^-1 s`` with ``s_i = |T_dot - q_dot_i v_i|^2`` (for
    ``v_i = e_x``: ``(T_dot_x - q_dot_i)^2 + T_dot_y^2 + T_dot_z^2``). Derived by
    differentiating the closure equation twice.

    Parameters
    ----------
    T, T_dot : casadi.SX or casadi.MX, shape (3, 1)
        TCP position [m] and velocity [m/s].
    q, q_dot, q_ddot : casadi.SX or casadi.MX, shape (3, 1)
        Cart positions [m], velocities [m/s] and accelerations [m/s^2].
    As, v
        Kinematic parameters, as in :func:`closure_residual`.

    Returns
    -------
    casadi.SX or casadi.MX, shape (3, 1)
        TCP acceleration [m/s^2].
    """
    dP = _dP_matrix(T, q, As, v)
    D = ca.diag(ca.vertcat(*[ca.dot(dP[i, :].T, _row(v, i)) for i in range(3)]))
    return ca.solve(dP, D @ q_ddot - _s_vector(T_dot, q_dot, v))


def cart_acceleration_expression(T: Expr, T_dot: Expr, T_ddot: Expr, q: Expr, q_dot: Expr, As: Expr, v: Expr) -> Expr:
    """Cart accelerations from the TCP motion: eq. 6.6 solved for ``q_ddot``.

    ``q_ddot_i = (dP_i . T_ddot + s_i) / (dP_i . v_i)``.

    Parameters
    ----------
    T, T_dot, T_ddot : casadi.SX or casadi.MX, shape (3, 1)
        TCP position [m], velocity [m/s], acceleration [m/s^2].
    q, q_dot : casadi.SX or casadi.MX, shape (3, 1)
        Cart positions [m] and velocities [m/s] consistent with ``T``, ``T_dot``.
    As, v
        Kinematic parameters, as in :func:`closure_residual`.

    Returns
    -------
    casadi.SX or casadi.MX, shape (3, 1)
        Cart accelerations [m/s^2].
    """
    s = _s_vector(T_dot, q_dot, v)
    return ca.vertcat(
        *[(ca.dot(dP, T_ddot) + s[i]) / ca.dot(dP, _row(v, i)) for i, dP in enumerate(_link_vectors(T, q, As, v))]
    )


_SIGNS = [np.array([1.0 if (c >> i) & 1 else -1.0 for i in range(3)]) for c in range(8)]


def configuration_signs(configuration: int | Sequence[int]) -> np.ndarray:
    """Root signs ``s`` of the three IK quadratics for an IK configuration.

    Parameters
    ----------
    configuration : int or sequence of int
        An integer 0-7 (bit i set = arm i+1 takes the ``+`` root) or three signs
        (each -1 or +1).

    Returns
    -------
    numpy.ndarray, shape (3,)
        Signs, each -1.0 or +1.0.

    Raises
    ------
    InputError
        For an integer outside 0-7 or signs other than -1/+1.
    """
    if isinstance(configuration, (int, np.integer)) and not isinstance(configuration, bool):
        c = int(configuration)
        if not 0 <= c <= 7:
            raise InputError(f"configuration: expected an integer 0-7, got {c}")
        return _SIGNS[c].copy()  # a copy: the caller may change it
    try:
        s = np.array(configuration, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"configuration: expected an integer 0-7 or three signs, got {configuration!r}") from None
    if s.shape != (3,) or not np.all(np.isin(s, (-1.0, 1.0))):
        raise InputError(f"configuration: expected an integer 0-7 or three signs -1/+1, got {configuration!r}")
    return s
