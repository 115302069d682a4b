"""Rigid-body dynamics with friction (Dressler (2012), eqs. 6.7, 6.8).

Independent references:
- the thesis' explicit form (6.7) with M1, M2, G printed in the spec (guideways along x);
- a redundant-coordinate formulation with Lagrange multipliers, written here in NumPy:
  coordinates X = (T, q), constant mass matrix, closure constraints phi(X) = 0;
- energy balance of simulations (conservation without friction; with friction the lost
  energy equals the friction work), integrated by CVODES.
"""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import InputError, UnreachablePoseError
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.parameters import load_parameters

#: Agreement of two formulations of the inverse dynamics (relative to max |tau|).
FORMULATION_RTOL = 1e-9
#: Energy conservation over 1 s, relative to the energy scale (issue requirement).
ENERGY_RTOL = 1e-6
#: Integrator tolerances used for the energy tests.
INTEGRATOR_TOL = 1e-12

RNG = np.random.default_rng(7)


def _with_link_masses(name="L1", parallel=False):
    """Parameter set with non-zero link masses (to exercise the m_a terms) and optionally
    guideways exactly along x (the thesis' assumption for eq. 6.7)."""
    p = load_parameters(name)
    dyn = replace(p.dynamics, m_a=np.array([1.5, 2.5, 3.5]))
    kin = p.kinematics
    if parallel:
        kin = replace(kin, v=np.tile([1.0, 0.0, 0.0], (3, 1)))
    return replace(p, dynamics=dyn, kinematics=kin)


def _samples(dyn, n=20):
    G = dyn.kinematics.workspace_grid(0.1)
    T = G[RNG.choice(len(G), n, replace=False)]
    return T, RNG.normal(0, 0.5, (n, 3)), RNG.normal(0, 3.0, (n, 3))


def _thesis_6_7(p, T, T_dot, T_ddot, kin):
    """Eq. 6.7 as printed (v_i = e_x): M1 T_ddot + M2 q_ddot + G = J^-T f."""
    d = p.dynamics
    q, q_dot, q_ddot = kin.cart_motion(T, T_dot, T_ddot)
    dP = np.array([T - (kin.As[i] + q[i] * kin.v[i]) for i in range(3)])
    rY = dP[:, 1] / dP[:, 0]
    rZ = dP[:, 2] / dP[:, 0]
    ma, mc, mp = d.m_a, d.m_c, d.m_p
    M1 = np.array(
        [
            [mp + ma.sum() / 2, 0, 0],
            [np.sum(ma / 4 * rY), mp + ma.sum() / 4, 0],
            [np.sum(ma / 4 * rZ), 0, mp + ma.sum() / 4],
        ]
    )
    M2 = np.vstack([mc + ma / 2, rY * (mc + ma / 4), rZ * (mc + ma / 4)])
    G = d.g * np.array([0, 0, mp + ma.sum() / 2])
    Jinv = kin.jacobian_inverse(T)
    f = np.linalg.solve(Jinv.T, M1 @ T_ddot + M2 @ q_ddot + G)
    return f


def _redundant(p, T, T_dot, T_ddot, kin):
    """Lagrange multipliers on X = (T, q): M X_ddot + G = B f + Phi^T lam, Phi X_ddot = -Phi_dot X_dot."""
    d = p.dynamics
    As, v = kin.As, kin.v
    M = np.zeros((6, 6))
    Gx = np.zeros(6)
    M[:3, :3] += d.m_p * np.eye(3)
    Gx[2] += d.m_p * d.g
    for i in range(3):
        # cart: position As_i + q_i v_i; link midpoint: (T + As_i + q_i v_i) / 2
        Jc = np.zeros((3, 6))
        Jc[:, 3 + i] = v[i]
        Jm = np.zeros((3, 6))
        Jm[:, :3] = np.eye(3) / 2
        Jm[:, 3 + i] = v[i] / 2
        M += d.m_c[i] * Jc.T @ Jc + d.m_a[i] * Jm.T @ Jm
        Gx += d.g * (d.m_c[i] * Jc[2] + d.m_a[i] * Jm[2])
    q = kin.ik(T)
    Jinv = kin.jacobian_inverse(T)
    q_dot = Jinv @ T_dot
    Phi = np.zeros((3, 6))
    Phi_dot_Xdot = np.zeros(3)
    for i in range(3):
        dP = T - As[i] - q[i] * v[i]
        dP_dot = T_dot - q_dot[i] * v[i]
        Phi[i, :3] = 2 * dP
        Phi[i, 3 + i] = -2 * dP @ v[i]
        Phi_dot_Xdot[i] = 2 * dP_dot @ dP_dot
    # q_ddot from the second derivative of the constraints
    q_ddot = np.array([(Phi[i, :3] @ T_ddot + Phi_dot_Xdot[i]) / -Phi[i, 3 + i] for i in range(3)])
    X_ddot = np.concatenate([T_ddot, q_ddot])
    B = np.vstack([np.zeros((3, 3)), np.eye(3)])
    sol = np.linalg.solve(np.hstack([B, Phi.T]), M @ X_ddot + Gx)
    return sol[:3]


def _frictionless(p):
    return replace(p, dynamics=replace(p.dynamics, f_c=np.zeros(3), f_v=np.zeros(3)))


def test_matches_thesis_equation_6_7():
    p = _frictionless(_with_link_masses(parallel=True))
    dyn = GantryTau3Dynamics(p)
    samples = list(zip(*_samples(dyn)))
    ref = np.array([_thesis_6_7(p, T, Td, Tdd, dyn.kinematics) for T, Td, Tdd in samples])
    got = np.array([dyn.inverse_dynamics(T, Td, Tdd) for T, Td, Tdd in samples])
    err, lim = np.abs(got - ref).max(axis=1), FORMULATION_RTOL * np.abs(ref).max(axis=1)
    bad = [(k, e, l) for k, (e, l) in enumerate(zip(err, lim)) if not e <= l]
    assert not bad, bad  # (sample, max |error|, allowed)


@pytest.mark.parametrize("params", ["L1", "D1", "L1_link_masses"])
def test_matches_redundant_coordinates(params):
    p = _with_link_masses() if params == "L1_link_masses" else load_parameters(params)
    p = _frictionless(p)
    dyn = GantryTau3Dynamics(p)
    T, Td, Tdd = _samples(dyn)
    got = dyn.inverse_dynamics(T, Td, Tdd)  # batched (N, 3)
    ref = np.array([_redundant(p, T[k], Td[k], Tdd[k], dyn.kinematics) for k in range(len(T))])
    err, lim = np.abs(got - ref).max(axis=1), FORMULATION_RTOL * np.abs(ref).max(axis=1)
    bad = [(k, e, l) for k, (e, l) in enumerate(zip(err, lim)) if not e <= l]
    assert not bad, bad  # (sample, max |error|, allowed)


@pytest.mark.parametrize("friction", ["exact", "tanh", "piecewise"])
def test_forward_inverts_inverse(friction):
    dyn = GantryTau3Dynamics("L1", friction=friction)
    T, Td, Tdd = _samples(dyn)
    tau = dyn.inverse_dynamics(T, Td, Tdd)
    np.testing.assert_allclose(dyn.forward_dynamics(T, Td, tau), Tdd, rtol=1e-9, atol=1e-9)


def test_friction_adds_eq_6_8():
    p = load_parameters("L1")
    with_f = GantryTau3Dynamics(p)
    without = GantryTau3Dynamics(_frictionless(p))
    T, Td, Tdd = _samples(with_f, 5)
    q_dot = np.array([with_f.kinematics.jacobian_inverse(T[k]) @ Td[k] for k in range(5)])
    expected = p.dynamics.f_c * np.sign(q_dot) + p.dynamics.f_v * q_dot
    np.testing.assert_allclose(with_f.inverse_dynamics(T, Td, Tdd) - without.inverse_dynamics(T, Td, Tdd), expected, rtol=1e-9)


def test_static_forces_balance_weight():
    """At rest, with horizontal guideways, J^-T tau carries the weight of the plate and half
    the links (G of eq. 6.7 with T_dot = 0); the carts' weight rests on the guideways."""
    dyn = GantryTau3Dynamics(_with_link_masses(parallel=True))
    T = dyn.kinematics.workspace_grid(0.2)
    tau = dyn.gravity_forces(T)
    Jinv = dyn.kinematics.jacobian_inverse(T)
    wrench = np.einsum("nij,ni->nj", Jinv, tau)  # J^-T tau
    d = dyn.parameters.dynamics
    np.testing.assert_allclose(wrench[:, 2], d.g * (d.m_p + d.m_a.sum() / 2), rtol=1e-9)
    np.testing.assert_allclose(wrench[:, :2], 0, atol=1e-9)


def _simulate_carts(dyn, q0, duration=1.0, with_work=False):
    """Zero actuator force, cart coordinates; returns energy (and friction work) at 0 and t_f."""
    q = ca.SX.sym("q", 3)
    qd = ca.SX.sym("qd", 3)
    t = dyn.cart_terms(q, qd)
    ffric = dyn.friction_force(qd)
    qdd = ca.solve(t["M"], -ffric - t["h"] - t["G"])
    work = ca.SX.sym("w")
    x = ca.vertcat(q, qd, work)
    ode = ca.vertcat(qd, qdd, ca.dot(ffric, qd))
    F = ca.integrator("F", "cvodes", {"x": x, "ode": ode}, 0, duration, {"abstol": INTEGRATOR_TOL, "reltol": INTEGRATOR_TOL})
    E = ca.Function("E", [x], [t["KE"] + t["V"], t["KE"]])
    x0 = np.r_[q0, np.zeros(3), 0.0]
    xf = np.asarray(F(x0=x0)["xf"]).ravel()
    E0, _ = (float(e) for e in E(x0))
    Ef, KEf = (float(e) for e in E(xf))
    return E0, Ef, KEf, xf[-1]


def test_frictionless_free_motion_conserves_energy():
    p = _frictionless(_with_link_masses())
    dyn = GantryTau3Dynamics(p)
    q0 = dyn.kinematics.ik([0.0, 2.84, -0.54])
    E0, Ef, KEf, _ = _simulate_carts(dyn, q0)
    assert KEf > 10.0  # it really moved (fell) during the second
    assert abs(Ef - E0) <= ENERGY_RTOL * KEf


def test_friction_work_equals_energy_lost():
    dyn = GantryTau3Dynamics(_with_link_masses(), friction="tanh", friction_width=0.05)
    q0 = dyn.kinematics.ik([0.0, 2.84, -0.54])
    E0, Ef, KEf, work = _simulate_carts(dyn, q0)
    assert work > 1.0
    assert abs((E0 - Ef) - work) <= ENERGY_RTOL * max(KEf, work)


BAD = [
    ("shape_mismatch", dict(T=[0.0, 2.84, -0.54], T_dot=np.zeros((2, 3)), T_ddot=np.zeros(3)), InputError, "expected equal shapes"),
    ("unreachable", dict(T=[5.0, 5.0, 5.0], T_dot=np.zeros(3), T_ddot=np.zeros(3)), UnreachablePoseError, "arm 1"),
    ("nan", dict(T=[0.0, 2.84, -0.54], T_dot=[np.nan, 0, 0], T_ddot=np.zeros(3)), InputError, "T_dot: row 0"),
]


@pytest.mark.parametrize("case, kwargs, exc, match", BAD, ids=[b[0] for b in BAD])
def test_bad_inputs(case, kwargs, exc, match):
    with pytest.raises(exc, match=match):
        GantryTau3Dynamics("L1").inverse_dynamics(**kwargs)


def test_bad_friction_form():
    with pytest.raises(InputError, match="friction: expected one of exact, tanh, piecewise"):
        GantryTau3Dynamics("L1", friction="stribeck")


def test_asymmetric_needs_parameters():
    with pytest.raises(InputError, match="asymmetric"):
        GantryTau3Dynamics("D1", asymmetric=True)


def test_tcp_closed_form_equals_automatic_differentiation_of_the_energies():
    """tcp_terms (closed form via eq. 6.6) against lagrange_terms (CasADi AD of KE and V)."""
    from gtmodel.robots.dynamics import lagrange_terms
    from gtmodel.robots.kinematic_expressions import ik_expression

    dyn = GantryTau3Dynamics(_with_link_masses())
    T = ca.SX.sym("T", 3)
    Td = ca.SX.sym("Td", 3)
    s = -np.ones(3)
    closed = dyn.tcp_terms(T, Td, s)
    q, _ = ik_expression(T, s, dyn.L, dyn.As, dyn.v)
    M, h, G, KE, V = lagrange_terms(T, Td, dyn._bodies(T, q), dyn.parameters.dynamics.g)
    f = ca.Function("f", [T, Td], [closed["M"] - M, closed["h"] - h, closed["G"] - G, closed["KE"] - KE, closed["V"] - V, M, h])
    bad = []
    for k, (Tk, Tdk, _) in enumerate(zip(*_samples(dyn, 10))):
        dM, dh, dG, dKE, dV, M_ref, h_ref = (np.asarray(x) for x in f(Tk, Tdk))
        checks = {
            "M": np.abs(dM).max() <= FORMULATION_RTOL * np.abs(M_ref).max(),
            "h": np.abs(dh).max() <= FORMULATION_RTOL * max(np.abs(h_ref).max(), 1.0),
            "G": np.abs(dG).max() <= 1e-9,
            "KE": np.abs(dKE).max() <= 1e-9,
            "V": np.abs(dV).max() <= 1e-9,
        }
        bad += [(k, term) for term, ok in checks.items() if not ok]
    assert not bad, bad  # (sample, term) where closed form and AD differ
