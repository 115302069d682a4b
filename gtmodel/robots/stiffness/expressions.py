"""The stiffness equations in CasADi (module docstring of :mod:`gtmodel.robots.stiffness`, eqs. 1-3)."""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

__all__ = [
    "link_unit_vectors_expression",
    "arm_compliance_expression",
    "cartesian_stiffness_expression",
    "link_forces_expression",
    "deflection_expression",
]


def _row(M: Any, i: int) -> Any:
    return M[i, :].T


def link_unit_vectors_expression(T: Any, A: Any) -> Any:
    """Unit link vectors ``u_i = (T - A_i) / |T - A_i|`` (eq. 4.9: ``A_i = As_i + q_i v_i``).

    Parameters
    ----------
    T : casadi.SX or casadi.MX, shape (3, 1)
        TCP position [m].
    A : casadi.SX or casadi.MX, shape (3, 3)
        Row i: cart joint point ``A_i`` of arm i [m].

    Returns
    -------
    casadi.SX or casadi.MX, shape (3, 3)
        ``U``, row i = ``u_i^T`` (dimensionless).
    """
    rows = []
    for i in range(3):
        d = T - A[i, :].T
        rows.append((d / ca.norm_2(d)).T)
    return ca.vertcat(*rows)


def arm_compliance_expression(U: Any, v: Any, c_link: Any, c_act: Any) -> Any:
    """Axial compliance of each arm at a pose, eq. (2) of the module docstring.

    ``c_i = c_link,i + c_act,i (u_i . w_i)^2`` with ``w_i = v_i / |v_i|``: the links and
    joints of the cluster in series with the cart's compliance along its guideway, seen
    along the link.

    Parameters
    ----------
    U : casadi.SX or casadi.MX, shape (3, 3)
        Unit link vectors (rows), :func:`link_unit_vectors_expression`.
    v : casadi.SX or numpy.ndarray, shape (3, 3)
        Row i: guideway direction of arm i.
    c_link : casadi.SX or array_like, shape (3,)
        Cluster compliance ``(1/k_l + 2/k_j) / n_i`` [m/N].
    c_act : casadi.SX or array_like, shape (3,)
        Actuator compliance ``1/k_a`` along the guideway [m/N].

    Returns
    -------
    casadi.SX or casadi.MX, shape (3, 1)
        ``c_i`` [m/N].
    """
    out = []
    for i in range(3):
        w = _row(v, i)
        cos = ca.dot(_row(U, i), w) / ca.norm_2(w)
        out.append(c_link[i] + c_act[i] * cos**2)
    return ca.vertcat(*out)


def cartesian_stiffness_expression(U: Any, c: Any) -> Any:
    """Cartesian stiffness ``K_x = sum_i u_i u_i^T / c_i = U^T diag(1/c) U``, eq. (1).

    Dressler (2012), ch. 6.3 (spec section 4): ``K_x = sum k_i u_i u_i^T``.

    Parameters
    ----------
    U : casadi.SX or casadi.MX, shape (3, 3)
        Unit link vectors (rows).
    c : casadi.SX or casadi.MX, shape (3, 1)
        Arm compliances [m/N], :func:`arm_compliance_expression`.

    Returns
    -------
    casadi.SX or casadi.MX, shape (3, 3)
        ``K_x`` [N/m], symmetric.
    """
    return ca.mtimes([U.T, ca.diag(1.0 / c), U])


def link_forces_expression(U: Any, F: Any) -> Any:
    """Axial arm forces that balance a force on the plate: ``U^T f = F``, eq. (3).

    Parameters
    ----------
    U : casadi.SX or casadi.MX, shape (3, 3)
        Unit link vectors (rows).
    F : casadi.SX or casadi.MX or array_like, shape (3,)
        External force on the plate [N] (gravity: ``-m g e_z``).

    Returns
    -------
    casadi.SX or casadi.MX, shape (3, 1)
        ``f`` [N], tension positive (the whole cluster's force).
    """
    return ca.solve(U.T, ca.vec(F) if isinstance(F, (ca.SX, ca.MX)) else ca.DM(np.asarray(F, dtype=float).reshape(3)))


def deflection_expression(U: Any, c: Any, F: Any) -> Any:
    """TCP deflection under a plate force, ``dT = K_x^-1 F``, eq. (3).

    Parameters
    ----------
    U : casadi.SX or casadi.MX, shape (3, 3)
        Unit link vectors (rows).
    c : casadi.SX or casadi.MX, shape (3, 1)
        Arm compliances [m/N].
    F : casadi.SX or casadi.MX or array_like, shape (3,)
        Force on the plate [N].

    Returns
    -------
    casadi.SX or casadi.MX, shape (3, 1)
        ``dT`` [m].
    """
    Fv = ca.vec(F) if isinstance(F, (ca.SX, ca.MX)) else ca.DM(np.asarray(F, dtype=float).reshape(3))
    return ca.solve(cartesian_stiffness_expression(U, c), Fv)
