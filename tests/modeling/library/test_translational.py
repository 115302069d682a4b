"""Translational library components against closed forms (MSL Modelica.Mechanics.Translational)."""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.modeling import Component, connect
from gtmodel.modeling.library import translational as tr

SIM_TOL = 1e-6  # absolute, IDAS at rtol 1e-8 / atol 1e-10 against a closed form


def chain(*parts, **kw):
    """A component connecting parts flange to flange: part0.flange(_b) -- part1.flange_a ..."""

    attrs = {f"p{i}": p for i, p in enumerate(parts)}

    def equations(self):
        items = [getattr(self, f"p{i}") for i in range(len(parts))]
        for left, right in zip(items, items[1:]):
            a = left.flange if "flange" in left.connectors() else left.flange_b
            b = right.flange if "flange" in right.connectors() else right.flange_a
            connect(a, b)

    return type("Chain", (Component,), {**attrs, "equations": equations})(**kw)


def test_mass_spring_frequency():
    # closed form: m x'' = -c (x - s0 - s_rel0 - L/2) about the equilibrium; x(t) = x_eq + 0.1 cos(w t)
    c, m, s0, rel0, L = 400.0, 4.0, 0.5, 0.2, 0.1
    x_eq = s0 + rel0 + L / 2
    comp = chain(tr.Fixed(s0=s0), tr.Spring(c=c, s_rel0=rel0), tr.Mass(m=m, L=L, s=x_eq + 0.1))
    t = np.linspace(0.0, 1.0, 51)
    res = comp.to_model().simulate(t)
    np.testing.assert_allclose(res.x["p2.s"], x_eq + 0.1 * np.cos(np.sqrt(c / m) * t), atol=SIM_TOL)
    # MSL Mass: flange_a.s = s - L/2
    np.testing.assert_allclose(res.z["p2.flange_a.s"], res.x["p2.s"] - L / 2, atol=1e-12)


def test_damper_velocity_decays_exponentially():
    # closed form: m v' = -d v  =>  v = v0 exp(-d t / m), s = v0 m / d (1 - exp(-d t / m))
    comp = chain(tr.Fixed(), tr.Damper(d=3.0), tr.Mass(m=1.5, v=2.0))
    t = np.linspace(0.0, 2.0, 21)
    res = comp.to_model().simulate(t)
    np.testing.assert_allclose(res.x["p2.v"], 2.0 * np.exp(-2.0 * t), atol=SIM_TOL)
    np.testing.assert_allclose(res.x["p2.s"], 1.0 * (1.0 - np.exp(-2.0 * t)), atol=SIM_TOL)


def test_spring_damper_matches_damped_oscillator():
    # closed form: underdamped m x'' + d x' + c x = 0, x(0) = 1, x'(0) = 0
    c, d, m = 4.0, 0.4, 2.0
    comp = chain(tr.Fixed(), tr.SpringDamper(c=c, d=d, s_rel=1.0), tr.Mass(m=m, s=1.0))  # consistent starts
    t = np.linspace(0.0, 10.0, 101)
    res = comp.to_model().simulate(t)
    w0, zeta = np.sqrt(c / m), d / (2.0 * np.sqrt(c * m))
    wd = w0 * np.sqrt(1.0 - zeta**2)
    x = np.exp(-zeta * w0 * t) * (np.cos(wd * t) + zeta * w0 / wd * np.sin(wd * t))
    np.testing.assert_allclose(res.x["p2.s"], x, atol=SIM_TOL)


@pytest.mark.parametrize("force", [1.0, -2.5])
def test_force_accelerates_mass(force):
    # closed form: s = F t^2 / (2 m), acceleration a = F / m
    comp = chain(tr.Force(), tr.Mass(m=2.0))
    t = np.linspace(0.0, 1.0, 11)
    res = comp.to_model().simulate(t, u=force)
    np.testing.assert_allclose(res.x["p1.s"], force * t**2 / 4.0, atol=SIM_TOL)
    np.testing.assert_allclose(res.z["p1.a"], force / 2.0, atol=1e-12)


def test_fixed_holds_position_and_takes_the_reaction_force():
    # closed form: static equilibrium under a constant force F through a spring: the cut force
    # into the fixed flange is F (transmitted), the spring is compressed by F / c
    comp = chain(tr.Fixed(s0=1.0), tr.SpringDamper(c=100.0, d=20.0), tr.Mass(m=1.0, s=1.0), tr.Force())
    res = comp.to_model().simulate(np.linspace(0.0, 20.0, 5), u=-5.0)
    assert res.z["p0.flange.s"][-1] == 1.0
    assert res.z["p0.flange.f"][-1] == pytest.approx(-5.0, abs=1e-6)
    assert res.x["p2.s"][-1] == pytest.approx(1.0 - 0.05, abs=1e-6)
