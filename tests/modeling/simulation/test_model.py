"""Tests of Model declarations, flattening and simulation.

References: closed-form solutions of linear ODEs/DAEs (stated per test).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import ConvergenceError, InputError, ModelError
from gtmodel.modeling import FlatDAE, Model

SIM_TOL = 1e-6  # absolute tolerance vs closed form at rtol=1e-8/atol=1e-10
EXACT_TOL = 1e-12  # for results that are exact up to rounding (piecewise-constant input)


def oscillator(k=4.0, c=0.4, mass=2.0):
    m = Model("oscillator")
    kk = m.parameter("k", k)
    cc = m.parameter("c", c)
    mm = m.parameter("mass", mass)
    x = m.state("x", start=1.0)
    v = m.state("v", start=0.0)
    m.equation(m.der(x), v)
    m.equation(mm * m.der(v), -kk * x - cc * v)  # implicit in der(v): solved on flatten
    m.output("energy", 0.5 * mm * v**2 + 0.5 * kk * x**2)
    return m


def oscillator_closed_form(t, k, c, mass):
    """Underdamped m x'' + c x' + k x = 0, x(0) = 1, x'(0) = 0."""
    w0 = np.sqrt(k / mass)
    zeta = c / (2.0 * np.sqrt(k * mass))
    wd = w0 * np.sqrt(1.0 - zeta**2)
    e = np.exp(-zeta * w0 * t)
    x = e * (np.cos(wd * t) + zeta * w0 / wd * np.sin(wd * t))
    v = -e * (w0**2 / wd) * np.sin(wd * t)
    return x, v


@pytest.mark.parametrize("integrator", ["idas", "cvodes"])
def test_damped_oscillator_matches_closed_form(integrator):
    # reference: closed-form underdamped response (oscillator_closed_form)
    t = np.linspace(0.0, 10.0, 101)
    res = oscillator().simulate(t, integrator=integrator)
    x_ref, v_ref = oscillator_closed_form(t, 4.0, 0.4, 2.0)
    np.testing.assert_allclose(res.x["x"], x_ref, atol=SIM_TOL)
    np.testing.assert_allclose(res.x["v"], v_ref, atol=SIM_TOL)
    e_ref = 0.5 * 2.0 * v_ref**2 + 0.5 * 4.0 * x_ref**2
    np.testing.assert_allclose(res.outputs["energy"], e_ref, atol=SIM_TOL)


def test_parameter_override_in_simulate():
    # reference: closed form with k = 9, c = 0 (undamped, x = cos(3 t / sqrt(2)))
    t = np.linspace(0.0, 3.0, 31)
    res = oscillator().simulate(t, p={"k": 9.0, "c": 0.0})
    np.testing.assert_allclose(res.x["x"], np.cos(np.sqrt(9.0 / 2.0) * t), atol=SIM_TOL)
    assert res.p["k"][0] == 9.0


def test_index1_dae_matches_closed_form():
    # reference: x' = -z + u, 0 = z - a x  =>  x = u/a + (x0 - u/a) exp(-a t), z = a x
    m = Model("dae")
    a = m.parameter("a", 2.0)
    x = m.state("x", start=1.0)
    z = m.algebraic("z")
    u = m.input("u")
    m.equation(m.der(x), -z + u)
    m.equation(z, a * x)
    t = np.linspace(0.0, 2.0, 21)
    res = m.simulate(t, u=0.5)
    x_ref = 0.25 + 0.75 * np.exp(-2.0 * t)
    np.testing.assert_allclose(res.x["x"], x_ref, atol=SIM_TOL)
    np.testing.assert_allclose(res.z["z"], 2.0 * x_ref, atol=SIM_TOL)
    np.testing.assert_allclose(res.u["u"], 0.5)


def test_time_dependent_der_coefficient_is_solved_symbolically():
    # reference: (2 + sin t) x' = cos t  =>  x = x0 + ln(2 + sin t) - ln 2
    m = Model("implicit")
    x = m.state("x", start=0.5)
    m.equation((2.0 + ca.sin(m.time)) * m.der(x), ca.cos(m.time))
    t = np.linspace(0.0, 5.0, 26)
    res = m.simulate(t)
    np.testing.assert_allclose(res.x["x"], 0.5 + np.log(2.0 + np.sin(t)) - np.log(2.0), atol=SIM_TOL)


def test_coupled_constant_mass_matrix():
    # reference: [[2, 1], [1, 1]] [x', y']^T = [1, 0]^T  =>  x' = 1, y' = -1
    m = Model("coupled")
    x = m.state("x")
    y = m.state("y")
    m.equation(2 * m.der(x) + m.der(y), 1.0)
    m.equation(m.der(x) + m.der(y), 0.0)
    t = np.array([0.0, 1.0, 2.0])
    res = m.simulate(t)
    np.testing.assert_allclose(res.x["x"], t, atol=SIM_TOL)
    np.testing.assert_allclose(res.x["y"], -t, atol=SIM_TOL)


def integrator_model():
    m = Model("integrator")
    x = m.state("x")
    u = m.input("u")
    m.equation(m.der(x), u)
    return m


@pytest.mark.parametrize(
    "u, expected",
    [
        # reference: exact integral of a piecewise-constant input
        (np.array([1.0, -1.0, 2.0]), [0.0, 1.0, 0.0, 2.0]),
        (np.array([1.0, -1.0, 2.0, 7.0]), [0.0, 1.0, 0.0, 2.0]),  # N values: last ignored
        (lambda t: t, [0.0, 0.0, 1.0, 3.0]),  # zero-order hold of u(t) = t
        (3.0, [0.0, 3.0, 6.0, 9.0]),
    ],
    ids=["piecewise_N-1", "piecewise_N", "callable_zoh", "constant"],
)
def test_input_forms(u, expected):
    res = integrator_model().simulate([0.0, 1.0, 2.0, 3.0], u=u)
    np.testing.assert_allclose(res.x["x"], expected, atol=SIM_TOL)


def test_vector_state_names_and_dataframe():
    # reference: T' = -T, T(0) = (1, 2, 3)  =>  T = T(0) exp(-t)
    m = Model("vec")
    T = m.state("T", 3, start=[1.0, 2.0, 3.0])
    m.equation(m.der(T), -T)
    m.output("norm2", ca.sumsqr(T))
    flat = m.flatten()
    assert isinstance(flat, FlatDAE)
    assert flat.x_names == ["T[0]", "T[1]", "T[2]"]
    assert flat.x_vars == {"T": slice(0, 3)}
    t = np.linspace(0, 1, 5)
    res = m.simulate(t)
    assert res.x["T"].shape == (5, 3)
    np.testing.assert_allclose(res.x["T"], np.outer(np.exp(-t), [1, 2, 3]), atol=SIM_TOL)
    df = res.to_dataframe()
    assert list(df.columns) == ["t", "T[0]", "T[1]", "T[2]", "norm2"]


def test_der_of_single_element():
    # reference: x0' = 1, x1' = -x1 from (0, 1): x0 = t, x1 = exp(-t)
    m = Model("elements")
    X = m.state("X", 2, start=[0.0, 1.0])
    m.equation(m.der(X[0]), 1.0)
    m.equation(m.der(X[1]), -X[1])
    res = m.simulate([0.0, 1.0])
    np.testing.assert_allclose(res.x["X"][-1], [1.0, np.exp(-1.0)], atol=SIM_TOL)


def test_integrator_failure_raises():
    # reference: x' = x^2, x(0) = 1 has the solution 1/(1 - t), which blows up at t = 1
    m = Model("blowup")
    x = m.state("x", start=1.0)
    m.equation(m.der(x), x**2)
    with pytest.raises(ConvergenceError, match="failed"):
        m.simulate([0.0, 2.0])


# --------------------------------------------------------------------------- bad inputs
def _nonlinear_der():
    m = Model("m")
    x = m.state("x")
    m.equation(m.der(x) ** 2, 1.0)


def _unknown_symbol():
    m = Model("m")
    x = m.state("x")
    m.equation(m.der(x), ca.SX.sym("foo"))


def _der_of_parameter():
    m = Model("m")
    m.der(m.parameter("k", 1.0))


def _duplicate_name():
    m = Model("m")
    m.state("x")
    m.input("x")


def _state_lb_above_ub():
    Model("m").state("x", lb=1.0, ub=0.0)


def _too_few_equations():
    m = Model("m")
    x = m.state("x")
    m.state("y")
    m.equation(m.der(x), 1.0)
    m.flatten()


def _der_missing():
    m = Model("m")
    x = m.state("x")
    y = m.state("y")
    m.equation(m.der(x), y)
    m.equation(x + y, 0.0)
    m.flatten()


def _high_index():
    m = Model("m")
    x = m.state("x")
    z = m.algebraic("z")
    m.equation(m.der(x), z)
    m.equation(x, 1.0)
    m.flatten()


def _singular_constant_mass():
    m = Model("m")
    x = m.state("x")
    y = m.state("y")
    m.equation(m.der(x) + m.der(y), 1.0)
    m.equation(2 * m.der(x) + 2 * m.der(y), 0.0)
    m.flatten()


@pytest.mark.parametrize(
    "build, match",
    [
        (_nonlinear_der, "nonlinear in der"),
        (_unknown_symbol, r"unknown symbol\(s\) \['foo'\]"),
        (_der_of_parameter, r"der\(\) needs a declared state"),
        (_duplicate_name, "already declared"),
        (_state_lb_above_ub, "lower bound exceeds upper bound"),
        (_too_few_equations, "1 scalar equations but 2 states"),
        (_der_missing, r"der\(\) of state\(s\) \['y'\]"),
        (_high_index, "not index 1"),
        (_singular_constant_mass, r"singular for states \['x', 'y'\]"),
    ],
    ids=lambda v: getattr(v, "__name__", "")[1:] if callable(v) else "",
)
def test_model_errors(build, match):
    with pytest.raises(ModelError, match=match):
        build()


def _dae_model():
    m = Model("m")
    x = m.state("x")
    z = m.algebraic("z")
    m.equation(m.der(x), z)
    m.equation(z, -x)
    return m


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: Model("m").state("1x"), "identifier"),
        (lambda: Model("m").state("x", shape=(2, 2)), "column vectors"),
        (lambda: Model("m").parameter("k", [1.0, np.nan]), "finite"),
        (lambda: Model("m").equation(ca.MX.sym("q"), 0.0), "MX"),
        (lambda: _dae_model().simulate([0.0, 1.0], integrator="cvodes"), "cvodes"),
        (lambda: _dae_model().simulate([1.0, 0.0]), "strictly increasing"),
        (lambda: _dae_model().simulate([0.0, 1.0], p={"nope": 1.0}), "no parameter 'nope'"),
        (lambda: integrator_model().simulate([0.0, 1.0, 2.0], u=np.ones((5, 1))), "u: expected"),
        (lambda: _dae_model().simulate([0.0, 1.0], integrator="rk"), "integrator must be"),
    ],
    ids=["name", "shape", "param_nan", "mx", "cvodes_dae", "grid", "param_name", "u_shape", "plugin"],
)
def test_input_errors(call, match):
    with pytest.raises(InputError, match=match):
        call()


@pytest.mark.parametrize("kwargs, value, match", [
    ({"min": 1e-3}, 0.0, r"parameter 'm': 0 is outside its range \[0\.001, inf\]"),
    ({"max": 10.0}, 11.0, r"parameter 'm': 11 is outside its range \[-inf, 10\]"),
])
def test_a_parameter_value_outside_its_range_is_refused(kwargs, value, match):
    # Modelica's min/max on a parameter: the default and every override are checked
    m = Model("ranged")
    m.parameter("m", 1.0, **kwargs)
    with pytest.raises(InputError, match=match):
        m.check_parameter("m", value)
    with pytest.raises(InputError, match=match):
        Model("ranged_default").parameter("m", value, **kwargs)


def test_a_parameter_range_with_min_above_max_is_refused():
    with pytest.raises(ModelError, match=r"lower bound exceeds upper bound"):
        Model("ranged").parameter("m", 1.0, min=2.0, max=0.0)
