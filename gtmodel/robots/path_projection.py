"""The robot model projected onto a TCP path: the coefficients of the path-constrained rows.

With the TCP on a path ``T(s)``, ``T_dot = T'(s) s_dot`` and ``T_ddot = T''(s) s_dot^2 +
T'(s) s_ddot``, every limited quantity becomes ``m(s) s_ddot + c(s) s_dot^2 + d(s) s_dot +
g(s)`` (Verscheure et al. (2009); Dressler (2012), ch. 3.5). :func:`path_rows_function`
builds the ONE CasADi Function of these coefficients from the inverse dynamics of the
model (eqs. 6.7, 6.8) and its kinematics (eqs. 4.9, 6.5, 6.6), by CasADi AD: the Python
path solver (:mod:`gtmodel.trajectory.path_constrained`) evaluates it with ``map``, and
the generated C re-timing function (:mod:`gtmodel.codegen.retime`) is generated from it.
"""

from __future__ import annotations

from typing import Sequence

import casadi as ca

from gtmodel.errors import InputError
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.kinematic_expressions import link_cosines_expression

__all__ = ["PATH_LIMIT_KINDS", "PATH_ROW_COUNTS", "PATH_SQUARED_KINDS", "path_rows_function"]

#: Kinds of limits along a path, in the fixed order of the rows.
PATH_LIMIT_KINDS = ("force_limit", "cart_velocity_limit", "cart_acceleration_limit", "tcp_velocity_limit", "tcp_speed_limit", "tcp_acceleration_limit")
#: Number of rows of each kind.
PATH_ROW_COUNTS = {"force_limit": 3, "cart_velocity_limit": 3, "cart_acceleration_limit": 3, "tcp_velocity_limit": 3, "tcp_speed_limit": 1, "tcp_acceleration_limit": 3}
#: Kinds whose rows hold ``b`` only and are bounded by the squared limit, ``c b <= v^2``
#: (velocities); the others are bounded on both sides, ``|row| <= v``.
PATH_SQUARED_KINDS = ("cart_velocity_limit", "tcp_velocity_limit", "tcp_speed_limit")


def path_rows_function(dynamics: GantryTau3Dynamics | None, kinds: Sequence[str], viscous: bool = True) -> ca.Function:
    """CasADi Function ``path_rows(T, dT, ddT, sg) -> (m, c, d, g, q, dq, ddq, disc, cos)``.

    Row ``j`` of the limited quantities is ``m_j a + c_j b + d_j sqrt(b) + g_j`` with
    ``a = s_ddot`` and ``b = s_dot^2``. For the actuator forces the coefficients are
    derivatives of ``tau(s_dot, s_ddot)``, the inverse dynamics along the path, at
    ``s_dot = 1, s_ddot = 0``: ``m = dtau/ds_ddot``, ``c = 1/2 d2tau/ds_dot2``, ``d =
    dtau/ds_dot - 2 c`` (viscous friction), ``g = tau - dtau/ds_dot + c`` (gravity and
    Coulomb friction with the exact sign of ``q'(s)``); cart velocities give ``c = q'^2``,
    cart accelerations ``m = q', c = q''``, TCP velocities ``c = T'^2``, the TCP speed
    ``c = |T'|^2``, TCP accelerations ``m = T', c = T''``.

    Parameters
    ----------
    dynamics : GantryTau3Dynamics or None
        The robot model with ``friction="exact"`` (the Coulomb sign of ``q_dot = q'(s)
        s_dot`` is that of ``q'(s)`` since ``s_dot >= 0``); None for TCP limits only.
    kinds : sequence of str
        Limit kinds from :data:`PATH_LIMIT_KINDS`, in the order of the rows.
    viscous : bool, optional
        Keep viscous friction in ``d`` (default True); False sets ``d = 0``.

    Returns
    -------
    casadi.Function
        Inputs ``T``, ``dT = T'(s)``, ``ddT = T''(s)`` [m] and the IK root signs ``sg``,
        all (3,); outputs the coefficients ``m, c, d, g`` (R,) of the ``R`` rows (forces
        [N], cart quantities [m], TCP quantities [m]; per unit ``s_ddot``, ``s_dot^2``,
        ``s_dot``), and with a robot ``q, dq = q'(s), ddq = q''(s)`` [m], the IK
        discriminants ``disc`` and the link cosines ``cos`` (3,) for the workspace checks
        (empty without a robot).

    Raises
    ------
    InputError
        An unknown kind, or an actuator kind without ``dynamics``.
    """
    unknown = [k for k in kinds if k not in PATH_LIMIT_KINDS]
    if unknown:
        raise InputError(f"kinds: unknown limit kinds {unknown} (expected some of {', '.join(PATH_LIMIT_KINDS)})")
    if dynamics is None and any(k in kinds for k in PATH_LIMIT_KINDS[:3]):
        raise InputError("dynamics: force and cart limits need a robot model")
    T, dT, ddT, sg = (ca.SX.sym(n, 3) for n in ("T", "dT", "ddT", "sg"))
    M: list[ca.SX] = []
    C: list[ca.SX] = []
    D: list[ca.SX] = []
    G: list[ca.SX] = []
    zero3 = ca.SX.zeros(3)
    if dynamics is not None:
        kin = dynamics.kinematics
        q, disc = kin.ik_function(T, sg)
        dq, ddq = kin.cart_acceleration_function(T, dT, ddT, sg)
        cos = link_cosines_expression(T, q, kin.As, kin.v)
    else:
        q = dq = ddq = disc = cos = ca.SX(0, 1)
    for kind in kinds:
        if kind == "force_limit":
            sd, sdd = ca.SX.sym("sd"), ca.SX.sym("sdd")
            tau = dynamics.inverse_dynamics_function(T, dT * sd, ddT * sd**2 + dT * sdd, sg)[0]
            m = ca.jacobian(tau, sdd)
            J1 = ca.jacobian(tau, sd)
            H = ca.jacobian(J1, sd)
            m, J1, H, tau1 = (ca.substitute(e, ca.vertcat(sd, sdd), ca.DM([1.0, 0.0])) for e in (m, J1, H, tau))
            c = H / 2
            d = J1 - H
            g = tau1 - J1 + H / 2
            M.append(m)
            C.append(c)
            D.append(d if viscous else zero3)
            G.append(g)
        elif kind == "cart_velocity_limit":
            M.append(zero3)
            C.append(dq**2)
            D.append(zero3)
            G.append(zero3)
        elif kind == "cart_acceleration_limit":
            M.append(dq)
            C.append(ddq)
            D.append(zero3)
            G.append(zero3)
        elif kind == "tcp_velocity_limit":
            M.append(zero3)
            C.append(dT**2)
            D.append(zero3)
            G.append(zero3)
        elif kind == "tcp_speed_limit":
            M.append(ca.SX(0))
            C.append(ca.sumsqr(dT))
            D.append(ca.SX(0))
            G.append(ca.SX(0))
        elif kind == "tcp_acceleration_limit":
            M.append(dT)
            C.append(ddT)
            D.append(zero3)
            G.append(zero3)
    outs = [ca.vertcat(*X) for X in (M, C, D, G)] + [q, dq, ddq, disc, cos]
    names = ["m", "c", "d", "g", "q", "dq", "ddq", "disc", "cos"]
    return ca.Function("path_rows", [T, dT, ddT, sg], outs, ["T", "dT", "ddT", "sg"], names)
