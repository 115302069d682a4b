"""Gantry-Tau parts on the 3-D frame, and the L1 assembled from them.

Independent reference: the hand-written point-mass dynamics
``gtmodel.robots.dynamics.GantryTau3Dynamics`` (Lagrange in TCP coordinates with the IK,
Dressler (2012), eqs. (6.5)-(6.8)); the parts alone against closed forms.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling import Component, connect, inverse_model
from gtmodel.modeling.library import translational as tr
from gtmodel.modeling.library.gantry_tau import Cart, Fixed, GantryTau3, Link, Plate
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.parameters import RobotParameters, load_parameters

G = 9.81
WIDTH = 0.01  # m/s, smooth-sign width of the friction (the "tanh" form on both sides)
N_STATES = 1000
INVERSE_KNOWN = ["plate.r", "plate.v", "der(plate.v)", "cart1.q", "cart2.q", "cart3.q"]
INVERSE_UNKNOWN = ["force1.f", "force2.f", "force3.f"]


# ----------------------------------------------------------------------------- builders
def l1_parameters(link_masses=None) -> RobotParameters:
    """The L1 set (Table 5.1 kinematics, Table 6.3 model 2 dynamics), optionally with link masses [kg]."""
    params = load_parameters("L1")
    if link_masses is None:
        return params
    return dataclasses.replace(params, dynamics=dataclasses.replace(params.dynamics, m_a=np.asarray(link_masses, float)))


def l1_component(params: RobotParameters, friction: str | None = None, T0=None) -> GantryTau3:
    """GantryTau3 with the numbers of ``params`` as modifiers (start values from the IK at ``T0``)."""
    k, d = params.kinematics, params.dynamics
    g = [0.0, 0.0, -d.g]
    q0 = GantryTau3Dynamics(params).kinematics.ik(T0) if T0 is not None else np.zeros(3)
    mods = {"plate": {"m": d.m_p, "g": g, **({"r": T0} if T0 is not None else {})}}
    for i in range(3):
        A = k.As[i] + q0[i] * k.v[i]
        mods[f"cart{i + 1}"] = {"As": k.As[i], "v": k.v[i], "m": d.m_c[i], "g": g, "q": q0[i]}
        if friction:
            mods[f"cart{i + 1}"].update(f_c=d.f_c[i], f_v=d.f_v[i], friction_width=WIDTH, friction=friction)
        mods[f"link{i + 1}"] = {"L": k.L[i], "m": d.m_a[i], "g": g}
        if T0 is not None:
            mods[f"link{i + 1}"]["r_mid"] = (A + T0) / 2
    return GantryTau3(**mods)


def joint_guesses(model, params: RobotParameters, T0) -> np.ndarray:
    """Guesses of the algebraic variables: connector positions from the IK (the rest 0)."""
    k = params.kinematics
    q0 = GantryTau3Dynamics(params).kinematics.ik(T0)
    out = []
    for var in (v for v in model._vars.values() if v.kind == "algebraic"):
        comp, *rest = var.name.split(".")
        val = np.zeros(var.size)
        if var.name.endswith(".r"):
            on_cart = comp.startswith("cart") or (comp.startswith("link") and rest[0] == "frame_a")
            val = k.As[int(comp[-1]) - 1] + q0[int(comp[-1]) - 1] * k.v[int(comp[-1]) - 1] if on_cart else T0
        elif var.name.endswith(".s"):
            val = q0[int(comp[-1]) - 1:int(comp[-1])]
        out.extend(np.ravel(val))
    return np.array(out)


def random_states(params: RobotParameters, n: int, seed: int):
    """Random TCP positions in the workspace (rejection in its bounding box), velocities, accelerations."""
    kin = GantryTau3Dynamics(params).kinematics
    rng = np.random.default_rng(seed)
    box = kin.workspace_bounds()
    T = rng.uniform(box[:, 0], box[:, 1], (100 * n, 3))
    T = T[kin.in_workspace(T)][:n]
    assert len(T) == n
    return T, rng.normal(0.0, 0.5, (n, 3)), rng.normal(0.0, 3.0, (n, 3))


# ----------------------------------------------------------------------------- the L1
CASES = {
    "L1 as identified (Table 6.3: link masses 0), friction off": (None, None),
    "L1 with link masses 1, 2, 3 kg, tanh friction on both": ([1.0, 2.0, 3.0], "tanh"),
    "L1 as identified, exact Coulomb + viscous friction on both": (None, "exact"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_l1_inverse_dynamics_equals_gantry_tau3_dynamics(case):
    # reference: GantryTau3Dynamics.inverse_dynamics (hand-written Lagrange in TCP coordinates,
    # eqs. (6.5)-(6.8)); friction off there = its friction force subtracted
    link_masses, friction = CASES[case]
    params = l1_parameters(link_masses)
    model = l1_component(params, friction=friction).to_model()
    inv = inverse_model(model, known=INVERSE_KNOWN, unknown=INVERSE_UNKNOWN)
    T, Td, Tdd = random_states(params, N_STATES, seed=15)
    dyn = GantryTau3Dynamics(params, friction=friction or "exact", friction_width=WIDTH)
    q = dyn.kinematics.ik(T)
    *forces, residual = inv.function.map(N_STATES)(T.T, Td.T, Tdd.T, q[:, 0], q[:, 1], q[:, 2])
    tau = np.vstack([np.array(f).ravel() for f in forces]).T
    ref = dyn.inverse_dynamics(T, Td, Tdd)
    if friction is None:
        q_dot = np.einsum("nij,nj->ni", dyn.kinematics.jacobian_inverse(T), Td)
        ref = ref - (params.dynamics.f_c * np.sign(q_dot) + params.dynamics.f_v * q_dot)
    rel = np.max(np.abs(tau - ref), axis=1) / np.max(np.abs(ref), axis=1)
    assert np.max(rel) < 1e-9
    # the position-level closure constraints are the consistency conditions of (T, q from the IK)
    assert inv.residual_names == ["link1.length", "link2.length", "link3.length"]
    assert np.max(np.abs(np.array(residual))) < 1e-9


@pytest.mark.slow
def test_l1_simulates_with_the_closure_kept():
    # reference: GantryTau3Dynamics.forward_dynamics integrated by SciPy's DOP853 (a second
    # method: TCP coordinates, no constraint); the closure |A_i - T| = L_i to 1e-8 m
    params = l1_parameters([1.0, 2.0, 3.0])
    T0 = np.array([0.2, 3.0, -0.8])
    model = l1_component(params, friction="tanh", T0=T0).to_model()
    dyn = GantryTau3Dynamics(params, friction="tanh", friction_width=WIDTH)
    u = dyn.inverse_dynamics(T0, np.zeros(3), np.zeros(3)) + np.array([300.0, -200.0, 250.0])
    t = np.linspace(0.0, 0.2, 21)
    res = model.simulate(t, z0=joint_guesses(model, params, T0), u=u)
    k = params.kinematics
    T = res.x["plate.r"]
    closure = [np.linalg.norm(k.As[i] + np.outer(res.x[f"cart{i + 1}.q"], k.v[i]) - T, axis=1) - k.L[i] for i in range(3)]
    assert np.max(np.abs(closure)) < 1e-8
    assert np.linalg.norm(T[-1] - T0) > 0.05  # it moved

    def rhs(_, y):
        return np.concatenate([y[3:], dyn.forward_dynamics(y[:3], y[3:], u)])

    ref = solve_ivp(rhs, (0.0, 0.2), np.concatenate([T0, np.zeros(3)]), t_eval=t, method="DOP853", rtol=1e-11, atol=1e-12)
    assert np.max(np.abs(ref.y[:3].T - T)) < 1e-6


# ----------------------------------------------------------------------------- the parts
def driven_cart(friction: str) -> Component:
    """A Force on a cart on an inclined guideway whose joint frame is free."""

    class DrivenCart(Component):
        force = tr.Force()
        cart = Cart(As=[0.1, 0.2, 0.3], v=[0.8, 0.0, 0.6], m=5.0, f_c=20.0, f_v=30.0, friction_width=0.05,
                    friction=friction)

        def equations(self):
            connect(self.force.flange, self.cart.flange)

    return DrivenCart()


@pytest.mark.parametrize(
    "friction, q_dot, sigma",
    [("tanh", 0.03, np.tanh(0.03 / 0.05)), ("piecewise", 0.03, 0.6), ("piecewise", -0.2, -1.0),
     ("exact", 0.03, 1.0), ("exact", 0.0, 0.0)],
)
def test_cart_force_on_an_inclined_guideway(friction, q_dot, sigma):
    # closed form: f = m |v|^2 a - m v.g + f_c sigma(q_dot) + f_v q_dot (v = (0.8, 0, 0.6), |v| = 1)
    model = driven_cart(friction).to_model()
    inv = inverse_model(model, known=["cart.q", "cart.q_dot", "der(cart.q_dot)"], unknown=["force.f"])
    f, _ = inv.function(0.4, q_dot, 2.0)
    assert float(f) == pytest.approx(5.0 * 2.0 + 5.0 * 0.6 * G + 20.0 * sigma + 30.0 * q_dot, abs=1e-12)


def test_l1_inverse_dynamics_with_the_masses_as_input():
    # reference: GantryTau3Dynamics with the masses of p (the inverse model stays symbolic in
    # the parameters: the identification regressor of Dressler (2012), ch. 6.2, by AD)
    params = l1_parameters()
    inv = inverse_model(l1_component(params).to_model(), known=INVERSE_KNOWN, unknown=INVERSE_UNKNOWN,
                        parameter_input=True)
    masses = {"plate.m": 12.0, "cart1.m": 20.0, "cart2.m": 15.0, "cart3.m": 30.0, "link1.m": 1.0, "link2.m": 2.5,
              "link3.m": 4.0}
    p = inv.p_value.copy()
    for name, value in masses.items():
        p[inv.p_names.index(name)] = value
    d = params.dynamics
    other = dataclasses.replace(params, dynamics=dataclasses.replace(
        d, m_p=12.0, m_c=np.array([20.0, 15.0, 30.0]), m_a=np.array([1.0, 2.5, 4.0]), f_c=np.zeros(3), f_v=np.zeros(3)))
    T, Td, Tdd = random_states(params, 50, seed=16)
    q = GantryTau3Dynamics(params).kinematics.ik(T)
    *forces, _ = inv.function.map(50)(T.T, Td.T, Tdd.T, q[:, 0], q[:, 1], q[:, 2], np.tile(p[:, None], (1, 50)))
    tau = np.vstack([np.array(f).ravel() for f in forces]).T
    ref = GantryTau3Dynamics(other).inverse_dynamics(T, Td, Tdd)
    assert np.max(np.abs(tau - ref) / np.max(np.abs(ref), axis=1, keepdims=True)) < 1e-9


class CompoundPendulum(Component):
    """A link hanging from a fixed point with the plate (a point mass) at its end."""

    fixed = Fixed(r=[0.0, 0.0, 2.0])
    link = Link(L=1.2, m=0.8)
    plate = Plate(m=1.5, b_1=[0.1, 0.0, 0.0])

    def equations(self):
        connect(self.fixed.frame_b, self.link.frame_a)
        connect(self.link.frame_b, self.plate.frame_1)


def pendulum_state(theta, omega, alpha, L=1.2, b=0.1):
    """TCP position, velocity, acceleration of the compound pendulum swinging in the x-z plane."""
    e = np.array([np.sin(theta), 0.0, -np.cos(theta)])
    t = np.array([np.cos(theta), 0.0, np.sin(theta)])
    r = np.array([0.0, 0.0, 2.0]) + L * e - np.array([b, 0.0, 0.0])
    return r, L * omega * t, L * (alpha * t - omega**2 * e)


@pytest.mark.parametrize("theta, omega", [(0.0, 0.0), (0.7, 0.0), (-0.4, 2.5), (1.2, -1.0)])
def test_link_and_plate_as_a_compound_pendulum(theta, omega):
    # closed form (Lagrange in the angle): (m_p + m/4) L alpha = -(m_p + m/2) g sin(theta);
    # rod tension f_rod = (m_p + m/4) omega^2 L + (m_p + m/2) g cos(theta)
    m_p, m, L = 1.5, 0.8, 1.2
    alpha = -(m_p + m / 2) * G * np.sin(theta) / ((m_p + m / 4) * L)
    inv = inverse_model(CompoundPendulum().to_model(), known=["plate.r", "plate.v", "der(plate.v)"], unknown=["link.f_rod"])
    f_rod, residual = inv.function(*pendulum_state(theta, omega, alpha))
    assert float(f_rod) == pytest.approx((m_p + m / 4) * omega**2 * L + (m_p + m / 2) * G * np.cos(theta), abs=1e-10)
    assert np.max(np.abs(np.array(residual))) < 1e-10
    # a wrong angular acceleration is inconsistent with the equations of motion
    _, residual = inv.function(*pendulum_state(theta, omega, alpha + 0.5))
    assert np.max(np.abs(np.array(residual))) > 1e-2


@pytest.mark.parametrize(
    "build, error, match",
    [
        (lambda: Cart(mass=2.0), ModelError, r"Cart: unknown modifier\(s\) \['mass'\]"),
        (lambda: Cart(As=[1.0, 2.0]), InputError, r"Cart.As: expected 3 value\(s\)"),
        (lambda: Link(L=-1.0), InputError, r"Link.L: must be >="),
        (lambda: Plate(m="heavy"), InputError, r"Plate.m: expected a real number"),
        (lambda: Cart(friction="coulomb"), InputError, r"Cart.friction: expected one of \['tanh', 'piecewise', 'exact'\]"),
        (lambda: GantryTau3(link4={"L": 1.0}), ModelError, r"GantryTau3: unknown modifier\(s\) \['link4'\]"),
    ],
)
def test_bad_parameters(build, error, match):
    with pytest.raises(error, match=match):
        build()


class Miswired(Component):
    """A cart's 3-D joint frame connected to a translational flange."""

    force = tr.Force()
    cart = Cart()

    def equations(self):
        connect(self.force.flange, self.cart.frame_b)


def test_incompatible_connection_names_both_connectors():
    with pytest.raises(ModelError, match=r"incompatible connectors force.flange .*cart.frame_b"):
        Miswired().to_model()


#: The outputs of the L1's components and their units: a cart's friction force (f_c sigma +
#: f_v q_dot, f_c in N), a link's length error (|B - A| - L, lengths in m).
OUTPUT_UNITS = {**{f"cart{i}.f_friction": "N" for i in (1, 2, 3)}, **{f"link{i}.length_error": "m" for i in (1, 2, 3)}}


def test_the_l1_outputs_carry_their_units():
    model = l1_component(l1_parameters(None), friction="tanh").to_model()
    units = model.units
    assert {n: units.get(n) for n in model.outputs} == OUTPUT_UNITS
