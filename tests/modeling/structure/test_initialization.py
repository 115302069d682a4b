"""Tests of initial equations and the consistent initialisation.

References: closed-form solutions (steady states, undamped oscillators) and the Cartesian
pendulum against the same pendulum in its minimal coordinate (a second formulation).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import ConvergenceError, InputError, ModelError
from gtmodel.modeling import Model

from ._dae_builders import angle_pendulum, cartesian_pendulum

SIM_TOL = 1e-6


def first_order():
    """x' = -a x + b, 0 = y - 2 x."""
    m = Model("first_order")
    a = m.parameter("a", 2.0)
    b = m.parameter("b", 3.0)
    x = m.state("x", start=10.0)
    y = m.algebraic("y")
    m.equation(m.der(x), -a * x + b)
    m.equation(y, 2 * x)
    return m, x, y


def oscillator():
    """x'' = -4 x as x' = v, v' = -4 x."""
    m = Model("oscillator")
    x = m.state("x", start=1.0)
    v = m.state("v", start=1.0)
    m.equation(m.der(x), v)
    m.equation(m.der(v), -4.0 * x)
    return m, x, v


def test_steady_state_initialisation():
    # reference: der(x) = 0 at t0  =>  x = b / a = 1.5 for all t, y = 3 (closed form)
    m, x, _ = first_order()
    m.initial_equation(m.der(x), 0.0, name="steady")
    res = m.simulate(np.linspace(0.0, 1.0, 11))
    np.testing.assert_allclose(res.x["x"], 1.5, atol=SIM_TOL)
    np.testing.assert_allclose(res.z["y"], 3.0, atol=SIM_TOL)


def test_initial_equations_on_algebraic_and_derivative():
    # reference: y(0) = 1 => x(0) = 0.5; v(0) from x'(0) = 0 => x = 0.5 cos(2 t) (closed form)
    m, x, v = oscillator()
    y = m.algebraic("y")
    m.equation(y, 2 * x)
    m.initial_equation(y, 1.0)
    m.initial_equation(m.der(x), 0.0)
    t = np.linspace(0.0, 2.0, 21)
    res = m.simulate(t)
    np.testing.assert_allclose(res.x["x"], 0.5 * np.cos(2 * t), atol=SIM_TOL)


def test_x0_mapping_fixes_a_state_next_to_initial_equations():
    # reference: x(0) = 0.3 from x0, v(0) = 0 from the initial equation => x = 0.3 cos(2 t)
    m, x, v = oscillator()
    m.initial_equation(v, 0.0)
    t = np.linspace(0.0, 2.0, 21)
    res = m.simulate(t, x0={"x": 0.3})
    np.testing.assert_allclose(res.x["x"], 0.3 * np.cos(2 * t), atol=SIM_TOL)


def test_pendulum_initial_equations_match_minimal_coordinates():
    # reference: x(0) = 0.6 on the lower branch, at rest => theta0 = asin(0.6); the angle ODE
    m = cartesian_pendulum(theta0=0.5)
    xs, us = m.variables("state")["x"], m.variables("state")["u"]
    m.initial_equation(xs, 0.6, name="x0")
    m.initial_equation(us, 0.0, name="u0")
    t = np.linspace(0.0, 2.0, 41)
    res = m.simulate(t, rtol=1e-10, atol=1e-12)
    assert res.x["y"][0] == pytest.approx(-0.8, abs=1e-10)
    assert res.x["v"][0] == pytest.approx(0.0, abs=1e-10)
    ref = angle_pendulum(theta0=float(np.arcsin(0.6))).simulate(t, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res.x["x"], ref.outputs["pos_x"], atol=SIM_TOL)


def _under_index1():
    m, x, _ = oscillator()
    m.initial_equation(x, 1.0, name="only_x")
    m.simulate([0.0, 1.0])


def _under_pendulum():
    m = cartesian_pendulum()
    m.initial_equation(m.variables("state")["x"], 0.6, name="x0")
    m.simulate([0.0, 1.0])


def _over():
    m, x, v = oscillator()
    m.initial_equation(x, 1.0, name="ix")
    m.initial_equation(v, 0.0, name="iv")
    m.initial_equation(m.der(v), 0.0, name="iacc")
    m.simulate([0.0, 1.0])


@pytest.mark.parametrize(
    "build, match",
    [
        (_under_index1, r"initialisation of model 'oscillator' is under-determined .* or x0 values for 1 of the states \['v'"),
        (_under_pendulum, r"initialisation of model 'pendulum' is under-determined .*1 of the states \["),
        (_over, r"initialisation of model 'oscillator' is over-determined .*remove 1 of the initial equations"),
    ],
    ids=["under_index1", "under_pendulum", "over"],
)
def test_initialisation_structure_errors(build, match):
    with pytest.raises(ModelError, match=match):
        build()


def _no_real_solution():
    m, x, _ = oscillator()
    m.initial_equation(x**2, -1.0, name="impossible")
    m.initial_equation(m.der(x), 0.0)
    m.simulate([0.0, 1.0])


def test_initialisation_without_solution_raises():
    # reference: x^2 = -1 has no real root
    with pytest.raises(ConvergenceError, match=r"initialisation of model 'oscillator' did not converge.*impossible"):
        _no_real_solution()


@pytest.mark.parametrize(
    "call, error, match",
    [
        (lambda m: m.initial_equation(ca.MX.sym("q"), 0.0), InputError, "MX"),
        (lambda m: m.initial_equation(ca.SX.sym("foo"), 0.0), ModelError, r"unknown symbol\(s\) \['foo'\]"),
        (lambda m: m.initial_equation(ca.SX.zeros(2), ca.SX.zeros(3), name="sz"), InputError, "'sz': lhs has 2"),
        (lambda m: m.initial_equation(ca.SX(0, 1), 0.0, name="e"), InputError, "'e' is empty"),
    ],
    ids=["mx", "unknown_symbol", "sizes", "empty"],
)
def test_initial_equation_bad_inputs(call, error, match):
    with pytest.raises(error, match=match):
        call(oscillator()[0])
