"""Rotational library components against closed forms (MSL Modelica.Mechanics.Rotational)."""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.modeling import Component, connect
from gtmodel.modeling.library import rotational as rot
from gtmodel.modeling.library import translational as tr

SIM_TOL = 1e-6  # absolute, IDAS at rtol 1e-8 / atol 1e-10 against a closed form


class GearedOscillator(Component):
    """Inertia -- gear -- torsional spring -- fixed."""

    motor = rot.Inertia(J=0.01, phi=1.0)
    gear = rot.IdealGear(ratio=5.0)
    spring = rot.Spring(c=50.0)
    fixed = rot.Fixed()

    def equations(self):
        connect(self.motor.flange_b, self.gear.flange_a)
        connect(self.gear.flange_b, self.spring.flange_a)
        connect(self.spring.flange_b, self.fixed.flange)


def test_inertia_spring_frequency_through_gear():
    # closed form: the spring seen from the motor is c / ratio^2: w = sqrt(c / (ratio^2 J)) = sqrt(200)
    t = np.linspace(0.0, 1.0, 51)
    res = GearedOscillator().to_model().simulate(t)
    w = np.sqrt(50.0 / (25.0 * 0.01))
    np.testing.assert_allclose(res.x["motor.phi"], np.cos(w * t), atol=SIM_TOL)
    # gear ratio: flange_a.phi = ratio * flange_b.phi; torques: ratio * tau_a + tau_b = 0
    np.testing.assert_allclose(res.z["gear.flange_b.phi"], res.x["motor.phi"] / 5.0, atol=1e-12)
    # (algebraic variables hold to the integrator tolerance, torques are ~10 N m)
    np.testing.assert_allclose(5.0 * res.z["gear.flange_a.tau"] + res.z["gear.flange_b.tau"], 0.0, atol=SIM_TOL)


@pytest.mark.parametrize("ratio", [0.5, 4.0])
def test_torque_through_gear_accelerates_inertia(ratio):
    # closed form: torque tau on flange_a gives ratio * tau on flange_b: w = ratio tau t / J
    class Driven(Component):
        torque = rot.Torque()
        gear = rot.IdealGear(ratio=ratio)
        load = rot.Inertia(J=2.0)

        def equations(self):
            connect(self.torque.flange, self.gear.flange_a)
            connect(self.gear.flange_b, self.load.flange_a)

    res = Driven().to_model().simulate(np.linspace(0.0, 1.0, 3), u=3.0)
    np.testing.assert_allclose(res.x["load.w"], ratio * 3.0 * res.t / 2.0, atol=SIM_TOL)


@pytest.mark.parametrize("cls, kw", [(rot.Damper, {"d": 0.2}), (rot.SpringDamper, {"c": 0.0, "d": 0.2})])
def test_damper_speed_decays(cls, kw):
    # closed form: J w' = -d w  =>  w = w0 exp(-d t / J)
    class Braked(Component):
        fixed = rot.Fixed()
        damper = cls(**kw)
        wheel = rot.Inertia(J=0.1, w=10.0)

        def equations(self):
            connect(self.fixed.flange, self.damper.flange_a)
            connect(self.damper.flange_b, self.wheel.flange_a)

    res = Braked().to_model().simulate(np.linspace(0.0, 1.0, 11))
    np.testing.assert_allclose(res.x["wheel.w"], 10.0 * np.exp(-2.0 * res.t), atol=SIM_TOL)


def test_torsional_spring_damper_matches_damped_oscillator():
    # closed form: underdamped J phi'' + d phi' + c phi = 0, phi(0) = 1, phi'(0) = 0
    c, d, J = 4.0, 0.4, 2.0

    class Torsion(Component):
        fixed = rot.Fixed()
        shaft = rot.SpringDamper(c=c, d=d, phi_rel=1.0)  # start values consistent: phi_rel = disc.phi
        disc = rot.Inertia(J=J, phi=1.0)

        def equations(self):
            connect(self.fixed.flange, self.shaft.flange_a)
            connect(self.shaft.flange_b, self.disc.flange_a)

    t = np.linspace(0.0, 10.0, 101)
    res = Torsion().to_model().simulate(t)
    w0, zeta = np.sqrt(c / J), d / (2.0 * np.sqrt(c * J))
    wd = w0 * np.sqrt(1.0 - zeta**2)
    phi = np.exp(-zeta * w0 * t) * (np.cos(wd * t) + zeta * w0 / wd * np.sin(wd * t))
    np.testing.assert_allclose(res.x["disc.phi"], phi, atol=SIM_TOL)


def test_rolling_wheel_converts_torque_to_force():
    # closed form: torque tau on a pulley of radius r pulls the mass with tau / r: s = tau t^2 / (2 r m)
    class Belt(Component):
        torque = rot.Torque()
        pulley = rot.IdealRollingWheel(radius=0.05)
        cart = tr.Mass(m=10.0)

        def equations(self):
            connect(self.torque.flange, self.pulley.flangeR)
            connect(self.pulley.flangeT, self.cart.flange_a)

    res = Belt().to_model().simulate(np.linspace(0.0, 1.0, 11), u=2.0)
    np.testing.assert_allclose(res.x["cart.s"], 2.0 / 0.05 * res.t**2 / 20.0, atol=SIM_TOL)
    np.testing.assert_allclose(res.z["pulley.flangeR.phi"], res.x["cart.s"] / 0.05, atol=1e-9)
