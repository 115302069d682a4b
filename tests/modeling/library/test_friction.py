"""Tests of the MSL-named friction with stiction and hard stops (gtmodel.modeling.library.friction).

References: closed forms (stick-slip on a belt: piecewise harmonic motion; a sliding cart
under Coulomb friction: uniform deceleration; impacts on a stop under a constant force:
uniformly accelerated flights shortened by the restitution e), stated per test.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling import Component, Model, connect
from gtmodel.modeling.library import translational as tr
from gtmodel.modeling.library.friction import MassWithStopAndFriction, Stribeck, add_friction

K, V_B, F_S, F_K = 4.0, 0.5, 1.0, 0.6  # N/m, m/s, N, N; mass 1 kg
EVENT_TOL = 1e-6  # s
TIGHT = {"rtol": 1e-10, "atol": 1e-12}
MU_G = 0.3 * 9.81  # Coulomb deceleration of the cart, m/s^2


def belt_with_library_friction():
    """Mass on a spring to the wall, on a belt at v_b: the friction of the library on v - v_b."""
    m = Model("belt")
    x = m.state("x")
    v = m.state("v", start=V_B)
    f = m.algebraic("f")
    m.equation(m.der(x), v)
    m.equation(m.der(v), -K * x - f)
    coulomb = Stribeck(F_prop=0.0, F_Coulomb=F_K, F_Stribeck=0.0, fexp=0.0, peak=F_S / F_K)
    add_friction(m, v - V_B, f, coulomb, a_rel=m.der(v))
    return m


def test_belt_stick_slip_matches_closed_form():
    # reference: stuck until k x = F_s (t1 = F_s/(k v_b)); slipping: harmonic about F_k/k for
    # 2 (pi - phi)/w, tan(phi) = w (F_s - F_k)/(k v_b); stuck again for 2 (F_s - F_k)/(k v_b)
    res = belt_with_library_friction().simulate(np.linspace(0.0, 10.0, 1001), **TIGHT)
    w = np.sqrt(K)
    phi = np.arctan2(w * (F_S - F_K) / K, V_B)
    t_slip, t_stick = 2.0 * (np.pi - phi) / w, 2.0 * (F_S - F_K) / (K * V_B)
    t1 = F_S / (K * V_B)
    ref = [t1, t1 + t_slip, t1 + t_slip + t_stick, t1 + 2 * t_slip + t_stick, t1 + 2 * (t_slip + t_stick),
           t1 + 3 * t_slip + 2 * t_stick, t1 + 3 * (t_slip + t_stick)]
    names = ["friction.start_backward", "friction.stuck_backward"] * 3 + ["friction.start_backward"]
    assert [e.name for e in res.events] == names
    np.testing.assert_allclose([e.t for e in res.events], ref, rtol=0, atol=EVENT_TOL)


def test_exact_coulomb_cart_stops_and_sticks_with_events():
    # reference: v = 1 - mu g t until t_stop = 1/(mu g), x_stop = 1/(2 mu g); then stuck for good
    cart = MassWithStopAndFriction(F_prop=0.0, F_Coulomb=MU_G, F_Stribeck=0.0, fexp=0.0, v=1.0)
    t = np.linspace(0.0, 10.0, 1001)
    res = cart.to_model("cart").simulate(t)
    t_stop = 1.0 / MU_G
    assert [e.name for e in res.events] == ["stuck_forward"]
    assert abs(res.events[0].t - t_stop) < EVENT_TOL
    np.testing.assert_allclose(res.x["v"], np.where(t < t_stop, 1.0 - MU_G * t, 0.0), atol=1e-7)
    np.testing.assert_allclose(res.x["s"][-1], 0.5 / MU_G, atol=1e-7)


def belt_composed(**friction):
    """Fixed -- Spring(c = 4) -- MassWithStopAndFriction on a belt at v_b (components)."""

    class Belt(Component):
        wall = tr.Fixed()
        spring = tr.Spring(c=K)
        mass = MassWithStopAndFriction(v_support=V_B, v=V_B, **friction)

        def equations(self):
            connect(self.wall.flange, self.spring.flange_a)
            connect(self.spring.flange_b, self.mass.flange_a)

    return Belt().to_model("belt")


def test_composed_belt_stick_slip_matches_closed_form():
    # reference: as test_belt_stick_slip_matches_closed_form, with the component on flanges
    model = belt_composed(F_prop=0.0, F_Coulomb=F_K, F_Stribeck=0.0, fexp=0.0, peak=F_S / F_K)
    res = model.simulate(np.linspace(0.0, 10.0, 1001), **TIGHT)
    w = np.sqrt(K)
    phi = np.arctan2(w * (F_S - F_K) / K, V_B)
    t_slip, t_stick = 2.0 * (np.pi - phi) / w, 2.0 * (F_S - F_K) / (K * V_B)
    t1 = F_S / (K * V_B)
    ref = np.cumsum([t1, t_slip, t_stick, t_slip, t_stick, t_slip, t_stick])
    names = ["mass.start_backward", "mass.stuck_backward"] * 3 + ["mass.start_backward"]
    assert [e.name for e in res.events] == names
    np.testing.assert_allclose([e.t for e in res.events], ref, rtol=0, atol=EVENT_TOL)


def pushed_mass(**kw):
    """A constant force (input f) on a MassWithStopAndFriction."""

    class Pushed(Component):
        push = tr.Force()
        mass = MassWithStopAndFriction(**kw)

        def equations(self):
            connect(self.push.flange, self.mass.flange_a)

    return Pushed().to_model("pushed")


@pytest.mark.parametrize("e, t_end", [(0.5, 2.9), (0.8, 4.0)])
def test_hard_stop_impacts_match_closed_form(e, t_end):
    # reference: constant force F = 2 N on 1 kg from rest 1 m before the stop: first impact at
    # sqrt(2 d / a), then flights 2 e^k v1 / a with v1 = sqrt(2 a d) (Newton's impact law);
    # t_end before the Zeno time 1 + 2 e / (1 - e) s of the infinitely many impacts
    a, d = 2.0, 1.0
    model = pushed_mass(F_prop=0.0, F_Coulomb=0.0, F_Stribeck=0.0, fexp=0.0, L=0.2, smax=1.1, e=e)
    res = model.simulate(np.linspace(0.0, t_end, 291), u=a, **TIGHT)
    v1 = np.sqrt(2.0 * a * d)
    ref = np.sqrt(2.0 * d / a) + np.concatenate([[0.0], np.cumsum([2.0 * e**k * v1 / a for k in range(1, 30)])])
    impacts = np.array([ev.t for ev in res.events if ev.name == "mass.stop_max"])
    assert impacts.size == np.sum(ref < t_end)
    np.testing.assert_allclose(impacts, ref[: impacts.size], rtol=0, atol=EVENT_TOL)
    assert np.all(res.x["mass.s"] <= 1.0 + 1e-9)


def test_hard_stop_without_restitution_stays_at_the_stop():
    # reference: e = 0 (MSL): net acceleration 2 - 0.5 = 1.5 m/s^2 over d = 1 m, so the mass
    # reaches smax - L/2 = 1 m at t = sqrt(2 / 1.5) s, stops there and stays (stuck at the stop)
    model = pushed_mass(F_prop=0.0, F_Coulomb=0.5, F_Stribeck=0.0, fexp=0.0, L=0.2, smax=1.1)
    res = model.simulate(np.linspace(0.0, 3.0, 301), u=2.0)
    t_hit = np.sqrt(2.0 / 1.5)
    assert [e.name for e in res.events] == ["mass.start_forward", "mass.stop_max"]
    assert abs(res.events[1].t - t_hit) < EVENT_TOL
    after = res.t > t_hit + 1e-6
    np.testing.assert_allclose(res.x["mass.s"][after], 1.0, atol=1e-9)
    np.testing.assert_allclose(res.x["mass.v"][after], 0.0, atol=1e-9)
    # stuck at the stop, the friction force takes the whole push
    np.testing.assert_allclose(res.z["mass.f"][after], 2.0, atol=1e-9)


def test_stribeck_breakaway_is_continuous():
    # reference: MSL characteristic: at v = 0+ the sliding force is F_Coulomb + F_Stribeck = f0_max (peak 1)
    fr = Stribeck(F_prop=1.0, F_Coulomb=5.0, F_Stribeck=10.0, fexp=2.0)
    assert fr.f0_max == 15.0
    assert float(fr.sliding(0.0, 1.0)) == 15.0
    # and decays to F_Coulomb + F_prop v for large v
    np.testing.assert_allclose(float(fr.sliding(10.0, 1.0)), 5.0 + 10.0 + 10.0 * np.exp(-20.0), rtol=1e-12)


# --------------------------------------------------------------------------- bad inputs
def _cart(**kw):
    MassWithStopAndFriction(**kw).to_model("cart")


def _friction_mode(mode_start):
    m = Model("m")
    v = m.state("v")
    f = m.algebraic("f")
    m.equation(m.der(v), -f)
    add_friction(m, v, f, Stribeck(), mode_start=mode_start)


def _friction_on_state():
    m = Model("m")
    v = m.state("v")
    m.equation(m.der(v), 0.0)
    add_friction(m, v, v, Stribeck())


@pytest.mark.parametrize(
    "call, error, match",
    [
        (lambda: Stribeck(F_Coulomb=-1.0), InputError, "F_Coulomb must be a finite number >= 0"),
        (lambda: Stribeck(fexp=np.inf), InputError, "fexp must be a finite number"),
        (lambda: Stribeck(peak=0.5), InputError, "peak must be >= 1"),
        (lambda: add_friction(Model("m"), ca.SX.sym("v"), ca.SX.sym("f"), 5.0), InputError, "friction must be a Stribeck"),
        (lambda: _cart(m=0.0), InputError, "MassWithStopAndFriction.m: must be >="),
        (lambda: _cart(e=1.5), InputError, r"MassWithStopAndFriction.e: must be <= 1"),
        (lambda: _cart(s=30.0), InputError, "start position s = 30.0 is outside the stops"),
        (lambda: _cart(smin=1.0, smax=0.0), InputError, "leave no room"),
        (lambda: _cart(L="1"), InputError, "MassWithStopAndFriction.L: expected a real number"),
        (lambda: _cart(mu=0.3), ModelError, r"unknown modifier\(s\) \['mu'\]"),
        (_friction_on_state, ModelError, "scalar algebraic variable, got state 'v'"),
        (lambda: _friction_mode(2), InputError, "mode_start must be -1, 0 or 1"),
    ],
    ids=[
        "negative", "inf", "peak", "friction_type", "mass", "restitution", "start", "stops", "length", "modifier",
        "force_state", "mode_start",
    ],
)
def test_bad_inputs(call, error, match):
    with pytest.raises(error, match=match):
        call()


def test_rigidly_coupled_mass_adds_inertia():
    # reference: a Mass (1 kg) rigidly on the 1 kg sliding mass (index 3: Model.simulate reduces
    # it, the friction mass keeps its states): Coulomb deceleration F_c / 2 kg, so
    # v = 1 - (F_c / 2) t until 2 / F_c
    class Coupled(Component):
        body = MassWithStopAndFriction(F_prop=0.0, F_Coulomb=MU_G, F_Stribeck=0.0, fexp=0.0, v=1.0)
        load = tr.Mass(m=1.0)

        def equations(self):
            connect(self.body.flange_b, self.load.flange_a)

    res = Coupled().to_model().simulate(np.linspace(0.0, 2.0, 201))
    assert [e.name for e in res.events] == ["body.stuck_forward"]
    assert abs(res.events[0].t - 2.0 / MU_G) < EVENT_TOL
    np.testing.assert_allclose(res.z["load.a"][res.t < 0.6], -MU_G / 2.0, atol=1e-8)
    np.testing.assert_allclose(res.x["load.v"], res.x["body.v"], atol=1e-12)


def rigid_pair_pushed(e):
    """Force -- Mass (1 kg) rigidly joined to a frictionless MassWithStopAndFriction (1 kg, stop e)."""

    class PushedPair(Component):
        push = tr.Force()
        load = tr.Mass(m=1.0)
        mass = MassWithStopAndFriction(F_prop=0.0, F_Coulomb=0.0, F_Stribeck=0.0, fexp=0.0, L=0.2, smax=1.1, e=e)

        def equations(self):
            connect(self.push.flange, self.load.flange_a)
            connect(self.load.flange_b, self.mass.flange_a)

    return PushedPair().to_model("pair")


@pytest.mark.parametrize("e, t_end", [(0.5, 3.9), (0.8, 5.0)])
def test_rigid_pair_hard_stop_impacts_match_closed_form(e, t_end):
    # reference: F = 2 N on the rigid pair (2 kg): a = 1 m/s^2 from rest 1 m before the stop;
    # impacts at sqrt(2 d / a) + sum 2 e^k v1 / a, v1 = sqrt(2 a d) (Newton's impact law); the
    # reinit of the friction mass moves the rigidly joined load with it (index reduction
    # keeps the reinit targets as states, the load's are dummies)
    a, d = 1.0, 1.0
    res = rigid_pair_pushed(e).simulate(np.linspace(0.0, t_end, 391), u=2.0, **TIGHT)
    v1 = np.sqrt(2.0 * a * d)
    ref = np.sqrt(2.0 * d / a) + np.concatenate([[0.0], np.cumsum([2.0 * e**k * v1 / a for k in range(1, 30)])])
    impacts = np.array([ev.t for ev in res.events if ev.name == "mass.stop_max"])
    assert impacts.size == np.sum(ref < t_end)
    np.testing.assert_allclose(impacts, ref[: impacts.size], rtol=0, atol=EVENT_TOL)
    np.testing.assert_allclose(res.x["load.s"], res.x["mass.s"] - 0.1, atol=1e-12)
    np.testing.assert_allclose(res.x["load.v"], res.x["mass.v"], atol=1e-12)


def test_rigid_pair_with_friction_on_a_belt_matches_closed_form():
    # reference: as test_belt_stick_slip_matches_closed_form with the 1 kg split into two rigidly
    # joined 0.5 kg masses (Fixed -- Spring -- Mass -- MassWithStopAndFriction): same closed form
    class Belt(Component):
        wall = tr.Fixed()
        spring = tr.Spring(c=K)
        load = tr.Mass(m=0.5)
        mass = MassWithStopAndFriction(
            m=0.5, v_support=V_B, v=V_B, F_prop=0.0, F_Coulomb=F_K, F_Stribeck=0.0, fexp=0.0, peak=F_S / F_K
        )

        def equations(self):
            connect(self.wall.flange, self.spring.flange_a)
            connect(self.spring.flange_b, self.load.flange_a)
            connect(self.load.flange_b, self.mass.flange_a)

    res = Belt().to_model("belt").simulate(np.linspace(0.0, 10.0, 1001), **TIGHT)
    w = np.sqrt(K)
    phi = np.arctan2(w * (F_S - F_K) / K, V_B)
    t_slip, t_stick = 2.0 * (np.pi - phi) / w, 2.0 * (F_S - F_K) / (K * V_B)
    ref = np.cumsum([F_S / (K * V_B), t_slip, t_stick, t_slip, t_stick, t_slip, t_stick])
    assert [e.name for e in res.events] == ["mass.start_backward", "mass.stuck_backward"] * 3 + ["mass.start_backward"]
    np.testing.assert_allclose([e.t for e in res.events], ref, rtol=0, atol=EVENT_TOL)


def _two_friction_masses():
    class Two(Component):
        a = MassWithStopAndFriction(v=1.0)
        b = MassWithStopAndFriction(v=1.0)

        def equations(self):
            connect(self.a.flange_b, self.b.flange_a)

    Two().to_model().simulate(np.linspace(0.0, 1.0, 11))


def _pair(**kw):
    rigid_pair_pushed(0.5).simulate(np.linspace(0.0, 1.0, 11), u=2.0, **kw)


def test_initial_equation_with_friction_events():
    # reference: as test_exact_coulomb_cart_stops_and_sticks_with_events, started at s = 0.5 m by
    # an initial equation (v = 1 m/s fixed by x0; its start value sets the initial friction
    # mode): stops at 1/(mu g) s, at 0.5 + 1/(2 mu g) m
    m = MassWithStopAndFriction(F_prop=0.0, F_Coulomb=MU_G, F_Stribeck=0.0, fexp=0.0, v=1.0).to_model("cart")
    m.initial_equation(m.variables("state")["s"], 0.5)
    res = m.simulate(np.linspace(0.0, 1.0, 101), x0={"v": 1.0})
    assert [e.name for e in res.events] == ["stuck_forward"]
    assert abs(res.events[0].t - 1.0 / MU_G) < EVENT_TOL
    np.testing.assert_allclose(res.x["s"][[0, -1]], [0.5, 0.5 + 0.5 / MU_G], atol=1e-7)


def test_initial_equations_on_the_dummies_of_a_rigid_pair():
    # reference: the load (a dummy after index reduction) placed at 0.2 m at rest by initial
    # equations, so the friction mass starts at 0.3 m, d = 0.7 m before the stop; a = 1 m/s^2:
    # first impact at sqrt(2 d / a), then flights 2 e^k v1 / a (e = 0.5)
    model = rigid_pair_pushed(0.5)
    states = model.variables("state")
    model.initial_equation(states["load.s"], 0.2)
    model.initial_equation(states["load.v"], 0.0)
    res = model.simulate(np.linspace(0.0, 3.0, 301), u=2.0, **TIGHT)
    d, a, e = 0.7, 1.0, 0.5
    v1 = np.sqrt(2.0 * a * d)
    ref = np.sqrt(2.0 * d / a) + np.concatenate([[0.0], np.cumsum([2.0 * e**k * v1 / a for k in range(1, 30)])])
    impacts = np.array([ev.t for ev in res.events if ev.name == "mass.stop_max"])
    assert impacts.size == np.sum(ref < 3.0)
    np.testing.assert_allclose(impacts, ref[: impacts.size], rtol=0, atol=EVENT_TOL)
    np.testing.assert_allclose([res.x["load.s"][0], res.x["mass.s"][0]], [0.2, 0.3], atol=1e-12)


def test_x0_on_the_dummies_of_a_rigid_pair_is_an_initial_condition():
    # reference: as test_initial_equations_on_the_dummies_of_a_rigid_pair, the load placed at
    # 0.2 m at rest by x0 (a dummy after index reduction: its value is honoured, not replaced),
    # so the friction mass starts at 0.3 m (half its length 0.2 m plus the load's 0 m further)
    res = rigid_pair_pushed(0.5).simulate(np.linspace(0.0, 0.5, 51), u=2.0, x0={"load.s": 0.2, "load.v": 0.0}, **TIGHT)
    np.testing.assert_allclose([res.x["load.s"][0], res.x["mass.s"][0]], [0.2, 0.3], atol=1e-12)
    np.testing.assert_allclose(res.x["load.s"], 0.2 + 0.5 * 1.0 * res.t**2, atol=1e-7)  # a = F / 2 kg


def _initial_underdetermined():
    # v's start a guess (a modifier's plain value would be a fixed start, an initial condition)
    m = MassWithStopAndFriction(v={"start": 1.0, "fixed": False}).to_model("cart")
    m.initial_equation(m.variables("state")["s"], 0.5)
    m.simulate(np.linspace(0.0, 1.0, 11))


@pytest.mark.parametrize(
    "call, error, match",
    [
        (_two_friction_masses, ModelError, "'a.stop_max' reinitialises 'a.s', which index reduction made a dummy"),
        (lambda: _pair(x0=[0.0, 0.0]), InputError, "give x0 as a mapping"),
        (lambda: _pair(z0=np.zeros(3)), InputError, "z0 is not supported"),
        (_initial_underdetermined, ModelError, "under-determined"),
    ],
    ids=["reinit_dummy", "x0_vector", "z0", "initial_underdetermined"],
)
def test_unsupported_event_simulations(call, error, match):
    with pytest.raises(error, match=match):
        call()
