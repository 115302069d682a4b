"""Electrical library components against closed forms (MSL Modelica.Electrical.Analog)."""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.modeling import Component, connect
from gtmodel.modeling.library import electrical as el
from gtmodel.modeling.library import rotational as rot

SIM_TOL = 1e-6  # absolute, IDAS at rtol 1e-8 / atol 1e-10 against a closed form


def loop(source, *parts):
    """source.p -> parts in series -> source.n, grounded at source.n."""

    attrs = {"src": source, "gnd": el.Ground(), **{f"e{i}": p for i, p in enumerate(parts)}}

    def equations(self):
        pins = [self.src.p]
        for i in range(len(parts)):
            e = getattr(self, f"e{i}")
            connect(pins[-1], e.p)
            pins.append(e.n)
        connect(pins[-1], self.src.n)
        connect(self.src.n, self.gnd.p)

    return type("Loop", (Component,), {**attrs, "equations": equations})()


def test_rl_time_constant():
    # closed form: i = V / R (1 - exp(-t R / L)), tau = L / R = 0.125 s
    comp = loop(el.ConstantVoltage(V=2.0), el.Resistor(R=4.0), el.Inductor(L=0.5))
    t = np.linspace(0.0, 1.0, 21)
    res = comp.to_model().simulate(t)
    np.testing.assert_allclose(res.x["e1.i"], 0.5 * (1.0 - np.exp(-8.0 * t)), atol=SIM_TOL)
    np.testing.assert_allclose(res.z["e0.v"], 4.0 * res.x["e1.i"], atol=1e-9)


@pytest.mark.parametrize("volts", [1.0, -3.0])
def test_rc_charging_with_signal_voltage(volts):
    # closed form: v_C = V (1 - exp(-t / (R C)))
    comp = loop(el.SignalVoltage(), el.Resistor(R=2.0), el.Capacitor(C=0.25))
    t = np.linspace(0.0, 2.0, 21)
    res = comp.to_model().simulate(t, u=volts)
    np.testing.assert_allclose(res.x["e1.v"], volts * (1.0 - np.exp(-2.0 * t)), atol=SIM_TOL)


def test_dc_motor_steady_state_speed():
    # closed form: R i + k w = V and k i = d w at steady state  =>  w = k V / (k^2 + R d)
    class Motor(Component):
        src = el.ConstantVoltage(V=12.0)
        gnd = el.Ground()
        r = el.Resistor(R=1.0)
        ind = el.Inductor(L=1e-3)
        emf = el.EMF(k=0.5)
        rotor = rot.Inertia(J=1e-3)
        friction = rot.Damper(d=0.01)
        fixed = rot.Fixed()

        def equations(self):
            connect(self.src.p, self.r.p)
            connect(self.r.n, self.ind.p)
            connect(self.ind.n, self.emf.p)
            connect(self.emf.n, self.src.n)
            connect(self.src.n, self.gnd.p)
            connect(self.emf.flange, self.rotor.flange_a)
            connect(self.rotor.flange_b, self.friction.flange_b)
            connect(self.friction.flange_a, self.fixed.flange)

    res = Motor().to_model().simulate(np.linspace(0.0, 2.0, 5))
    w_ss = 0.5 * 12.0 / (0.25 + 1.0 * 0.01)
    assert res.x["rotor.w"][-1] == pytest.approx(w_ss, abs=1e-6)
    # EMF: torque = k i on the shaft, back-EMF k w
    assert res.z["emf.v"][-1] == pytest.approx(0.5 * w_ss, abs=1e-6)
