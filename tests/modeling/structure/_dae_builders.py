"""High-index and constrained models shared by the structural-pass tests (pendulum, slider-crank)."""

from __future__ import annotations

import casadi as ca
import numpy as np

from gtmodel.modeling import Model

G = 9.81


def cartesian_pendulum(theta0: float = 2.0, length: float = 1.0, mass: float = 1.0) -> Model:
    """Point mass on a massless rod in Cartesian coordinates (x, y, u, v, lam): index 3."""
    m = Model("pendulum")
    L = m.parameter("L", length)
    g = m.parameter("g", G)
    mm = m.parameter("m", mass)
    x = m.state("x", start=length * np.sin(theta0))
    y = m.state("y", start=-length * np.cos(theta0))
    u = m.state("u")
    v = m.state("v")
    lam = m.algebraic("lam")
    m.equation(m.der(x), u, name="vel_x")
    m.equation(m.der(y), v, name="vel_y")
    m.equation(mm * m.der(u), -lam * x, name="force_x")
    m.equation(mm * m.der(v), -lam * y - mm * g, name="force_y")
    m.equation(x**2 + y**2, L**2, name="length")
    m.output("energy", 0.5 * mm * (u**2 + v**2) + mm * g * y)
    return m


def angle_pendulum(theta0: float = 2.0, length: float = 1.0) -> Model:
    """The same pendulum in its minimal coordinate: theta'' = -(g/L) sin(theta) (an ODE)."""
    m = Model("pendulum_angle")
    th = m.state("theta", start=theta0)
    w = m.state("w")
    m.equation(m.der(th), w)
    m.equation(m.der(w), -G / length * ca.sin(th))
    m.output("pos_x", length * ca.sin(th))
    m.output("pos_y", -length * ca.cos(th))
    return m


SLIDER = {"r": 0.1, "l": 0.3, "J1": 0.01, "J2": 0.005, "m3": 0.5}


def slider_crank(theta0: float = 0.3, w0: float = 5.0, torque: bool = False) -> Model:
    """Crank (angle theta), rod (angle phi), slider (s) with two loop-closure constraints: index 3.

    Generalised coordinates q = (theta, phi, s), constraint C(q) = 0, equations of motion
    M q'' = Q - C_q^T lam (C_q by CasADi AD); Q = (tau, 0, 0) with an input crank torque
    ``tau`` if ``torque``, else no external force (energy is conserved).
    """
    r, l, J1, J2, m3 = (SLIDER[k] for k in ("r", "l", "J1", "J2", "m3"))
    m = Model("slider_crank")
    th = m.state("theta", start=theta0)
    ph = m.state("phi")
    s = m.state("s")
    w = m.state("w", start=w0)
    wp = m.state("wphi")
    vs = m.state("vs")
    lam = m.algebraic("lam", 2)
    q, qd = ca.vertcat(th, ph, s), ca.vertcat(w, wp, vs)
    C = ca.vertcat(r * ca.cos(th) + l * ca.cos(ph) - s, r * ca.sin(th) - l * ca.sin(ph))
    M = ca.diag(ca.vertcat(J1, J2, m3))
    m.equation(m.der(q), qd, name="kinematics")
    Q = ca.vertcat(m.input("tau"), 0.0, 0.0) if torque else ca.SX.zeros(3)
    m.equation(M @ m.der(qd), Q - ca.jacobian(C, q).T @ lam, name="motion")
    m.equation(C, 0.0, name="loop")
    m.output("energy", 0.5 * (J1 * w**2 + J2 * wp**2 + m3 * vs**2))
    return m


def slider_crank_minimal(theta0: float = 0.3, w0: float = 5.0) -> Model:
    """The slider-crank in its minimal coordinate theta (Lagrange's equation, CasADi AD).

    phi(theta) = asin(r sin(theta) / l), s(theta) = r cos(theta) + l cos(phi);
    T = m(theta) w^2 / 2 with m = J1 + J2 phi'^2 + m3 s'^2;  m theta'' + m'(theta) w^2 / 2 = 0.
    """
    r, l, J1, J2, m3 = (SLIDER[k] for k in ("r", "l", "J1", "J2", "m3"))
    m = Model("slider_crank_minimal")
    th = m.state("theta", start=theta0)
    w = m.state("w", start=w0)
    ph = ca.asin(r * ca.sin(th) / l)
    s = r * ca.cos(th) + l * ca.cos(ph)
    mass = J1 + J2 * ca.jacobian(ph, th) ** 2 + m3 * ca.jacobian(s, th) ** 2
    m.equation(m.der(th), w)
    m.equation(mass * m.der(w), -0.5 * ca.jacobian(mass, th) * w**2)
    m.output("s", s)
    return m
