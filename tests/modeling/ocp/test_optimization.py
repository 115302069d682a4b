"""Tests of the Optimica-style Optimization declaration, and of free parameters solved.

References: the declaration rules of the brief (free final time needs bounds, symbols
must be declared, lb <= ub); expected stored values are given literally. Free parameters:
a damping estimated from data simulated with a known damping (IDAS) is recovered.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling import CollocationTranscription, Model, Optimization

from .._builders import double_integrator


def _opt():
    m, x, v, u = double_integrator()
    return Optimization(m, final_time=2.0), m, x, v, u


def test_fixed_final_time_defaults():
    opt, *_ = _opt()
    assert opt.final_time_bounds == (2.0, 2.0)
    assert opt.final_time_guess == 2.0
    assert isinstance(opt.final_time, ca.SX) and opt.final_time.is_symbolic()


def test_free_final_time_guess_is_clipped_into_bounds():
    m, *_ = double_integrator()
    opt = Optimization(m, free_final_time=True, final_time_bounds=(0.5, 3.0), final_time_guess=10.0)
    assert opt.final_time_guess == 3.0


def test_objective_terms_accept_final_time_and_parameters():
    m, x, v, u = double_integrator()
    w = m.parameter("w", 0.1)
    opt = Optimization(m, free_final_time=True, final_time_bounds=(0.1, 5.0))
    opt.set_objective(mayer=opt.final_time + w * x, lagrange=u**2)
    assert ca.depends_on(opt.objective, opt.final_time)
    assert ca.depends_on(opt.objective_integrand, u)
    opt.objective = 2 * opt.final_time
    assert ca.depends_on(opt.objective, opt.final_time)


def test_set_bounds_per_element_and_overrides_model_bounds():
    m = Model("m")
    q = m.state("q", 3, lb=-5.0, ub=5.0)
    m.equation(m.der(q), 0.0 * q)
    opt = Optimization(m)
    opt.set_bounds(q[1], -1.0, 1.0)
    lb, ub = opt.bounds_vectors(m.flatten(), "x")
    np.testing.assert_array_equal(lb, [-5.0, -1.0, -5.0])
    np.testing.assert_array_equal(ub, [5.0, 1.0, 5.0])


def test_initial_guess_forms_are_stored():
    opt, m, x, v, u = _opt()
    opt.set_initial_guess(x, ([0.0, 2.0], [0.0, 1.0]))
    opt.set_initial_guess(v, lambda t: 0.5)
    opt.set_initial_guess(u, 0.1)
    assert set(opt.initial_guesses) == {"x", "v", "u"}
    np.testing.assert_array_equal(opt.initial_guesses["u"], [0.1])


def test_set_parameter_stores_value():
    m, *_ = double_integrator()
    m.parameter("k", [1.0, 2.0])
    opt = Optimization(m)
    opt.set_parameter("k", [3.0, 4.0])
    np.testing.assert_array_equal(opt.parameters["k"], [3.0, 4.0])


def _free_without_bounds():
    m, *_ = double_integrator()
    Optimization(m, free_final_time=True)


def _bounds_reversed():
    m, *_ = double_integrator()
    Optimization(m, free_final_time=True, final_time_bounds=(3.0, 1.0))


def _empty_horizon():
    m, *_ = double_integrator()
    Optimization(m, start_time=1.0, final_time=1.0)


def _unknown_in_objective():
    opt, *_ = _opt()
    opt.set_objective(mayer=ca.SX.sym("foo"))


def _unknown_in_path():
    opt, m, x, v, u = _opt()
    opt.add_path_constraint(x + ca.SX.sym("bar"), ub=1.0)


def _unknown_in_point():
    opt, m, x, v, u = _opt()
    opt.add_point_constraint(x * ca.SX.sym("baz"), at="final", lb=0.0, ub=0.0)


def _symbol_of_other_model():
    opt, *_ = _opt()
    other = Model("other")
    opt.add_path_constraint(other.state("y"), ub=1.0)


def _path_lb_above_ub():
    opt, m, x, v, u = _opt()
    opt.add_path_constraint(v, lb=1.0, ub=0.0, name="speed_limit")


def _point_lb_above_ub():
    opt, m, x, v, u = _opt()
    opt.add_point_constraint(x, at="start", lb=1.0, ub=0.0, name="x0_fix")


def _bounds_on_parameter():
    m, *_ = double_integrator()
    k = m.parameter("k", 1.0)
    Optimization(m).set_bounds(k, 0.0, 1.0)


def _bounds_reversed_on_variable():
    opt, m, x, v, u = _opt()
    opt.set_bounds(u, 1.0, -1.0)


def _unknown_parameter():
    opt, *_ = _opt()
    opt.set_parameter("mass", 1.0)


def _guess_on_selection():
    m = Model("m")
    q = m.state("q", 2)
    m.equation(m.der(q), -q)
    Optimization(m).set_initial_guess(q[0], 1.0)


@pytest.mark.parametrize(
    "build, match",
    [
        (_free_without_bounds, "free final time needs final_time_bounds"),
        (_bounds_reversed, "final_time_bounds"),
        (_empty_horizon, "must exceed start_time"),
        (_unknown_in_objective, r"unknown symbol\(s\) \['foo'\]"),
        (_unknown_in_path, r"unknown symbol\(s\) \['bar'\]"),
        (_unknown_in_point, r"unknown symbol\(s\) \['baz'\]"),
        (_symbol_of_other_model, r"unknown symbol\(s\) \['y'\]"),
        (_path_lb_above_ub, "'speed_limit': lower bound exceeds upper bound"),
        (_point_lb_above_ub, "'x0_fix': lower bound exceeds upper bound"),
        (_bounds_on_parameter, "is a parameter"),
        (_bounds_reversed_on_variable, "bounds of 'u': lower bound exceeds"),
        (_unknown_parameter, "no parameter 'mass'"),
        (_guess_on_selection, "whole variable"),
    ],
    ids=lambda v: getattr(v, "__name__", "")[1:] if callable(v) else "",
)
def test_declaration_model_errors(build, match):
    with pytest.raises(ModelError, match=match):
        build()


def _bad_at():
    opt, m, x, v, u = _opt()
    opt.add_point_constraint(x, at="middle")


def _vector_objective():
    opt, m, x, v, u = _opt()
    opt.set_objective(mayer=ca.vertcat(x, v))


def _mx_constraint():
    opt, *_ = _opt()
    opt.add_path_constraint(ca.MX.sym("q"))


def _bound_size():
    opt, m, x, v, u = _opt()
    opt.add_path_constraint(ca.vertcat(x, v), lb=[0.0, 0.0, 0.0])


def _not_a_model():
    Optimization("model")


def _bad_guess_shape():
    opt, m, x, v, u = _opt()
    opt.set_initial_guess(x, ([0.0, 1.0, 2.0], [0.0, 1.0]))


@pytest.mark.parametrize(
    "build, match",
    [
        (_bad_at, "at must be 'start' or 'final'"),
        (_vector_objective, "must be scalar"),
        (_mx_constraint, "MX"),
        (_bound_size, "expected 2 values, got 3"),
        (_not_a_model, "Model"),
        (_bad_guess_shape, "initial guess of 'x'"),
    ],
    ids=lambda v: getattr(v, "__name__", "")[1:] if callable(v) else "",
)
def test_declaration_input_errors(build, match):
    with pytest.raises(InputError, match=match):
        build()


# ----------------------------------------------------------------------------- free parameters
C_TRUE = 0.3


def _damped_oscillator():
    """x'' + c x' + k x = 0 (k = 4 N/m per kg), x(0) = 1, v(0) = 0; the damping c is the unknown."""
    m = Model("damped")
    c = m.parameter("c", 0.1)
    k = m.parameter("k", 4.0)
    x = m.state("x", start=1.0)
    v = m.state("v")
    m.equation(m.der(x), v)
    m.equation(m.der(v), -k * x - c * v)
    return m, c, x, v


@pytest.fixture(scope="module")
def estimation_data():
    m, _, _, _ = _damped_oscillator()
    t = np.linspace(0.0, 5.0, 501)
    return t, m.simulate(t, p={"c": C_TRUE}).x["x"]


def _estimation(t, y, nominal=None):
    m, c, x, v = _damped_oscillator()
    opt = Optimization(m, final_time=5.0)
    assert opt.free_parameter("c", lb=0.0, ub=2.0) is c
    opt.add_point_constraint(x, at="start", lb=1.0, ub=1.0)
    opt.add_point_constraint(v, at="start", lb=0.0, ub=0.0)
    opt.set_objective(lagrange=(x - ca.pw_lin(m.time, ca.DM(t), ca.DM(y))) ** 2)  # output error
    return opt


@pytest.mark.parametrize("derivatives, nominal", [("assembled", None), ("casadi", None), ("assembled", {"c": 0.5})])
def test_free_parameter_estimates_a_damping_from_simulated_data(estimation_data, derivatives, nominal):
    # checked against the damping the data were simulated with (IDAS, rtol 1e-8); the bias
    # left is the linear interpolation of the 10 ms samples (about 1e-4 relative)
    t, y = estimation_data
    tr = CollocationTranscription(_estimation(t, y), elements=50, points=3, derivatives=derivatives, nominal=nominal)
    result = tr.solve()
    assert result.status == "optimal"
    assert abs(result.parameters["c"][0] - C_TRUE) < 1e-3 * C_TRUE
    assert result.parameters["k"][0] == 4.0  # not free: unchanged


def test_free_parameter_default_start_is_the_value_clipped_into_the_bounds():
    m, c, x, v = _damped_oscillator()
    opt = Optimization(m)
    opt.set_parameter("c", 5.0)
    opt.free_parameter("c", lb=0.0, ub=2.0)
    tr = CollocationTranscription(opt, elements=2, points=1)
    np.testing.assert_array_equal(tr._free_start(tr.dae.parameter_vector(opt.parameters)), [2.0])


def _free_unknown():
    m, *_ = _damped_oscillator()
    Optimization(m).free_parameter("d")


def _free_reversed():
    m, *_ = _damped_oscillator()
    Optimization(m).free_parameter("c", lb=1.0, ub=0.0)


def _free_start_outside():
    m, *_ = _damped_oscillator()
    Optimization(m).free_parameter("c", lb=0.0, ub=1.0, start=2.0)


@pytest.mark.parametrize(
    "build, match",
    [
        (_free_unknown, "has no parameter 'd'"),
        (_free_reversed, "free parameter 'c': lower bound exceeds upper bound"),
        (_free_start_outside, "start .* is not within its bounds"),
    ],
    ids=["unknown", "reversed_bounds", "start_outside"],
)
def test_free_parameter_errors(build, match):
    with pytest.raises(ModelError, match=match):
        build()


def test_free_parameter_bound_size_is_an_input_error():
    m, *_ = _damped_oscillator()
    with pytest.raises(InputError, match="free parameter 'c' lb"):
        Optimization(m).free_parameter("c", lb=[0.0, 1.0])


def _free_parameter_problem():
    """Free final time, two free parameters (one scaled), in the dynamics, constraints and both objective terms."""
    m = Model("damped_nonlinear")
    c = m.parameter("c", 0.1)
    k = m.parameter("k", 4.0)
    x = m.state("x", start=1.0)
    v = m.state("v")
    u = m.input("u")
    m.equation(m.der(x), v)
    m.equation(m.der(v), -k * x - c * v * x**2 + u)
    opt = Optimization(m, free_final_time=True, final_time_bounds=(1.0, 3.0))
    opt.free_parameter("c", 0.0, 2.0)
    opt.free_parameter("k", 1.0, 9.0)
    opt.add_point_constraint(x * c, at="final", lb=0.2, ub=0.2)
    opt.add_path_constraint(v * k + c**2, ub=5.0)
    opt.set_objective(mayer=c * k * x, lagrange=c * (x - ca.sin(m.time)) ** 2 + u**2)
    return opt


@pytest.mark.parametrize("function", ["nlp_jac_g", "nlp_hess_l"])
def test_assembled_derivatives_with_free_parameters_equal_casadis(function):
    # second method: CasADi differentiating the whole NLP graph, at a random point
    a, b = (CollocationTranscription(_free_parameter_problem(), elements=3, points=2, derivatives=d, nominal={"c": 0.5})
            for d in ("assembled", "casadi"))
    rng = np.random.default_rng(0)
    args = [rng.uniform(0.5, 1.5, a._lbw.size), a.dae.p_value]
    if function == "nlp_hess_l":
        args += [1.3, rng.standard_normal(a._lbg.size)]
    va, vb = a.solver.get_function(function)(*args), b.solver.get_function(function)(*args)
    va, vb = (np.array(ca.DM(v[-1] if isinstance(v, (list, tuple)) else v)) for v in (va, vb))
    np.testing.assert_allclose(va, vb, rtol=0, atol=1e-12)
