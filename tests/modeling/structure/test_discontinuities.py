"""Tests of sign() switched by events with Filippov sliding (gtmodel.modeling.structure.discontinuities).

References: closed forms of Coulomb friction (uniform deceleration to rest, breakaway when
the force exceeds the friction), a triangle wave, stated per test.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import ConvergenceError
from gtmodel.modeling import Model
from gtmodel.modeling.structure.discontinuities import sign_modes
from gtmodel.modeling.simulation.event_simulation import simulate_events
from gtmodel.modeling.simulation.integration import simulate_model

MU_G = 0.3 * 9.81  # Coulomb deceleration, m/s^2
EVENT_TOL = 1e-6  # s


def coulomb_cart(v0=1.0, with_input=False):
    m = Model("cart")
    x = m.state("x")
    v = m.state("v", start=v0)
    force = m.input("u") if with_input else 0.0
    m.equation(m.der(x), v)
    m.equation(m.der(v), force - MU_G * ca.sign(v))
    m.output("friction", MU_G * ca.sign(v))
    return m


def test_plain_sign_still_fails_without_events():
    # reference: the observation (simulate_model integrates the model as written)
    with pytest.raises(ConvergenceError, match="IDA_TOO_MUCH_WORK"):
        simulate_model(coulomb_cart(), np.linspace(0.0, 10.0, 101))


def test_exact_coulomb_cart_simulates_10_s_and_sticks():
    # reference: v = 1 - mu g t until 1/(mu g), x = 1/(2 mu g) after; then at rest (sliding mode)
    t = np.linspace(0.0, 10.0, 101)
    res = coulomb_cart().simulate(t)
    t_stop = 1.0 / MU_G
    assert [(e.name, e.modes) for e in res.events] == [("sign_0.down", {"sign_0": 0.0})]
    assert abs(res.events[0].t - t_stop) < EVENT_TOL
    np.testing.assert_allclose(res.x["v"], np.where(t < t_stop, 1.0 - MU_G * t, 0.0), atol=1e-7)
    np.testing.assert_allclose(res.x["x"][t > t_stop], 0.5 / MU_G, atol=1e-7)
    # stuck: the Filippov value of sign(v) is 0 (no force to hold), so is the friction output
    np.testing.assert_allclose(res.z["sign_0_value"][t > t_stop], 0.0, atol=1e-9)
    np.testing.assert_allclose(res.outputs["friction"][t > t_stop], 0.0, atol=1e-9)


def test_pushed_cart_sticks_then_breaks_away():
    # reference: u = 4 on [0, 1): v = (4 - mu g) t; u = 1 on [1, 4): decelerates at mu g - 1 to rest;
    # stuck while |u| <= mu g; u = -4 from t = 4: slides back at (-4 + mu g) m/s^2
    t = np.linspace(0.0, 5.0, 51)
    u = np.where(t[:-1] < 1.0, 4.0, np.where(t[:-1] < 4.0, 1.0, -4.0))
    res = coulomb_cart(0.0, with_input=True).simulate(t, u=u)
    v1 = 4.0 - MU_G
    t_rest = 1.0 + v1 / (MU_G - 1.0)
    assert [(e.name, e.modes["sign_0"]) for e in res.events] == [("sign_0.down", 0.0), ("sign_0.leave_down", -1.0)]
    np.testing.assert_allclose([e.t for e in res.events], [t_rest, 4.0], rtol=0, atol=EVENT_TOL)
    np.testing.assert_allclose(res.x["v"][-1], -(4.0 - MU_G) * 1.0, atol=1e-6)


def test_triangle_wave_with_cvodes_switching():
    # reference: x' = sign(sin t), x(0) = 0: x = t on [0, pi], 2 pi - t on [pi, 2 pi], ...
    m = Model("triangle")
    x = m.state("x")
    m.equation(m.der(x), ca.sign(ca.sin(m.time)))
    t = np.linspace(0.0, 10.0, 101)
    res = m.simulate(t, integrator="cvodes")
    np.testing.assert_allclose([e.t for e in res.events], [np.pi, 2 * np.pi, 3 * np.pi], atol=1e-8)
    tri = np.pi - np.abs(np.mod(t, 2 * np.pi) - np.pi)
    np.testing.assert_allclose(res.x["x"], tri, atol=1e-7)


def test_chattering_switching_stops_at_max_events():
    # reference: without sliding (CVODES), the cart at rest switches sign at every step: Zeno
    switched = sign_modes(coulomb_cart(), sliding=False)
    with pytest.raises(ConvergenceError, match="max_events = 30"):
        simulate_events(switched, np.linspace(0.0, 1.0, 11), integrator="cvodes", max_events=30)


def test_rewrite_leaves_the_model_unchanged():
    # reference: the rewrite is a copy; a model without sign() is not rewritten
    m = coulomb_cart()
    before = [str(r) for _, r in m._equations]
    new = sign_modes(m)
    assert [str(r) for _, r in m._equations] == before and m._events is None
    assert "sign_0" in new.variables("parameter") and "sign_0_value" in new.variables("algebraic")
    plain = Model("plain")
    y = plain.state("y")
    plain.equation(plain.der(y), -y)
    assert sign_modes(plain) is None
