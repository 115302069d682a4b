"""Direct multiple shooting (piecewise-constant and piecewise-linear inputs).

References, independent of the transcription:

* minimum energy rest to rest over 1 s of ``x'' = u`` with ``u`` held on ``N`` intervals:
  a least-squares problem in the ``N`` input values (the exact discrete map of the double
  integrator, solved with numpy's minimum-norm ``lstsq``); with piecewise-linear inputs the
  continuous optimum ``u = 6 - 12 t`` is representable, cost 12;
* minimum time with ``|u| <= 1`` over distance 1: ``T = 2`` (the switch at ``T/2`` falls on
  a node for even ``N``);
* maximise ``x(T)`` with ``integral(u^2) <= E``: ``sqrt(E T^3 / 3)`` (Cauchy-Schwarz), the
  optimal ``u ~ T - t`` linear, so piecewise-linear inputs reach it;
* verification: a fast oscillator ``x'' = -100 x + u`` shot with one Runge-Kutta 4 step per
  interval (``omega h = 2``) "solves" the discrete map, not the model: CVODES under its
  piecewise-constant inputs disagrees (``check_failed``), and the same problem shot with
  CVODES itself is the reference (its optimum a fifth of the coarse one).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.modeling import Model, Optimization
from gtmodel.modeling.ocp.shooting import ShootingTranscription

from .._builders import double_integrator, min_energy_problem, rest_to_rest


def _discrete_min_energy(N: int) -> float:
    h = 1.0 / N
    # x(1), v(1) after N held inputs u_k: v = h sum u_k, x = sum u_k (h^2 / 2 + h (1 - (k + 1) h))
    A = np.array([[h**2 / 2 + h * (1 - (k + 1) * h) for k in range(N)], [h] * N])
    u = np.linalg.lstsq(A, np.array([1.0, 0.0]), rcond=None)[0]  # minimum-norm solution
    return float(h * u @ u)


@pytest.mark.parametrize("controls, expected", [("constant", _discrete_min_energy(10)), ("linear", 12.0)])
def test_minimum_energy(controls, expected):
    r = ShootingTranscription(min_energy_problem(), intervals=10, controls=controls).solve()
    assert r.status == "optimal"
    assert r.objective == pytest.approx(expected, rel=1e-8)
    assert r.states["x"][-1] == pytest.approx(1.0, abs=1e-8)
    if controls == "constant":  # held on each interval in the result's samples
        u = r.sample([0.01, 0.05, 0.09])["inputs"]["u"]
        assert np.ptp(u) < 1e-9
    # verified: CVODES under the held (or linear) inputs reproduces the nodes and samples
    v = r.verification
    # (to the verifying integrator's own error: rtol 1e-6 for the default tolerance 1e-2)
    assert v.passed and v.max_abs_deviation < 1e-4 and f"piecewise {controls}" in v.to_dict()["method"]


def test_minimum_time_bang_bang():
    m, x, v, u = double_integrator()
    opt = Optimization(m, free_final_time=True, final_time_bounds=(0.5, 5.0), final_time_guess=3.0)
    opt.set_bounds(u, -1.0, 1.0)
    rest_to_rest(opt, x, v)
    opt.set_objective(mayer=opt.final_time)
    r = ShootingTranscription(opt, intervals=10).solve()
    assert r.status == "optimal" and r.final_time == pytest.approx(2.0, rel=1e-7)


def test_maximise_with_an_isoperimetric_constraint_and_a_timed_variable():
    m, x, v, u = double_integrator()
    opt = Optimization(m, final_time=2.0)
    opt.add_point_constraint(x, at="start", lb=0.0, ub=0.0)
    opt.add_point_constraint(v, at="start", lb=0.0, ub=0.0)
    opt.set_objective(mayer=x, sense="maximize")
    opt.add_constraint(opt.integral(u**2), ub=0.5)
    opt.add_constraint(opt.timed(x, 0.7) - opt.timed(x, 0.5), lb=0.0)  # interior times, inside intervals
    r = ShootingTranscription(opt, intervals=8, controls="linear").solve()
    assert r.status == "optimal"
    assert r.objective == pytest.approx(np.sqrt(0.5 * 2.0**3 / 3.0), rel=1e-7)
    (check,) = r.verification.integrals.values()  # the integral's quadrature, simulated too
    assert check["passed"] and check["simulated"] == pytest.approx(0.5, rel=1e-4)  # the integrator's rtol 1e-6


def _dae_energy(cubic=False):
    # x' = v, v' = w, 0 = w - u (or w^3 + w - u, which only Newton solves): the double
    # integrator's energy problem through an algebraic variable
    m = Model("dae")
    x, v, w, u = m.state("x"), m.state("v"), m.algebraic("w"), m.input("u")
    m.equation(m.der(x), v)
    m.equation(m.der(v), w)
    m.equation((w**3 if cubic else 0) + w - u, 0)
    opt = Optimization(m, final_time=1.0)
    opt.set_objective(lagrange=w**2)
    rest_to_rest(opt, x, v)
    return opt


@pytest.mark.parametrize("integrator", [None, "rk", "radau", "collocation"])
def test_a_dae_with_each_integrator(integrator):
    # reference: the continuous optimum u = 6 - 12 t, cost 12 (piecewise-linear inputs represent it);
    # rk and radau integrate the explicit form (w = u eliminated as codegen eliminates it)
    tr = ShootingTranscription(_dae_energy(), intervals=10, controls="linear", integrator=integrator)
    r = tr.solve()
    # (gtmodel's own collocation too: its rootfinder then solves for the states at the stage points only)
    assert tr.integrator == (integrator or "collocation") and tr.explicit and tr.stepwise
    assert r.status == "optimal" and r.objective == pytest.approx(12.0, rel=1e-6)
    # the algebraic variable of every written row (the start row included) is consistent: w = u
    assert np.max(np.abs(r.algebraics["w"] - r.inputs["u"])) < 1e-8


@pytest.mark.parametrize("kwargs, match", [
    ({"integrator": "cvodes"}, "integrates ODEs only"),
    ({"integrator": "rk", "integrator_options": {"number_of_finite_elements": 2}}, "integrates ODEs only"),
    ({"integrator": "radau", "integrator_options": {"abstol": 1e-8}}, "not to 'radau'"),
])
def test_dae_integrator_refusals(kwargs, match):
    with pytest.raises(InputError, match=match):
        ShootingTranscription(_dae_energy(), **kwargs)


@pytest.mark.parametrize("integrator", ["rk", "radau"])
def test_explicit_form_refused_where_only_newton_eliminates(integrator):
    with pytest.raises(InputError, match="cannot be eliminated symbolically .*Newton.*use 'collocation' or 'idas'"):
        ShootingTranscription(_dae_energy(cubic=True), integrator=integrator)


def test_default_for_a_dae_that_only_newton_eliminates():
    tr = ShootingTranscription(_dae_energy(cubic=True), intervals=4)
    assert tr.integrator == "collocation" and not tr.explicit and tr.stepwise


def test_collocation_solves_the_algebraic_variables_that_only_newton_eliminates():
    # w^3 + w = u: the algebraic variable among the rootfinder's unknowns at each stage point; references: CasADi's own
    # collocation plugin (integrator_options select it; the same Radau scheme, another implementation: the same optimum,
    # 12.1047527483 in 108 iterations, 2.9x the CPU measured), the IDAS verification, and w^3 + w = u in every written row
    opt = _dae_energy(cubic=True)
    r = ShootingTranscription(opt, intervals=4, steps=2, controls="linear", integrator="collocation").solve()
    ref = ShootingTranscription(opt, intervals=4, steps=2, controls="linear", integrator="collocation",
                                integrator_options={"number_of_finite_elements": 2}).solve()
    assert r.status == "optimal" and ref.status == "optimal" and r.verification.passed
    assert r.objective == pytest.approx(ref.objective, rel=1e-9)
    w, u = r.algebraics["w"], r.inputs["u"]
    assert np.max(np.abs(w**3 + w - u)) < 1e-8


@pytest.mark.parametrize("kwargs, match", [
    ({"intervals": 0}, "intervals must be a positive integer"),
    ({"controls": "cubic"}, "controls must be one of constant, linear"),
    ({"integrator": "euler"}, "integrator must be one of rk, radau, collocation, cvodes, idas"),
    ({"steps": 0}, "steps must be a positive integer"),
])
def test_bad_arguments(kwargs, match):
    with pytest.raises(InputError, match=match):
        ShootingTranscription(min_energy_problem(), **kwargs)


def test_own_rk4_matches_casadis_rk_plugin():
    # the SX Runge-Kutta 4 of the default "rk" against casadi.integrator(..., "rk", ...)
    # (used when integrator options are given): the same discretisation, the same optimum
    m = Model("pendulum")
    th, om, u = m.state("th"), m.state("om"), m.input("u")
    m.equation(m.der(th), om)
    m.equation(m.der(om), -9.81 * ca.sin(th) + u)  # nonlinear, so RK4 is not exact
    opt = Optimization(m, final_time=2.0)
    opt.set_objective(lagrange=u**2)
    for var, at, value in ((th, "start", 0.0), (om, "start", 0.0), (th, "final", 1.0), (om, "final", 0.0)):
        opt.add_point_constraint(var, at=at, lb=value, ub=value)
    own = ShootingTranscription(opt, intervals=10, steps=2).solve()
    plugin = ShootingTranscription(opt, intervals=10, steps=2, integrator_options={"number_of_finite_elements": 2}).solve()
    assert own.status == plugin.status == "optimal"
    assert own.objective == pytest.approx(plugin.objective, rel=1e-10)


def test_started_from_a_collocation_result():
    # the collocation optimum (u = 6 - 12 t, exact on any mesh) sampled onto the shooting
    # nodes is already the piecewise-linear optimum: no iteration needed
    from gtmodel.modeling import CollocationTranscription

    opt = min_energy_problem()
    r = ShootingTranscription(opt, intervals=10, controls="linear").solve(initial_guess=CollocationTranscription(opt, elements=10).solve())
    assert r.status == "optimal" and r.iterations <= 1 and r.objective == pytest.approx(12.0, rel=1e-10)


def _oscillator(integrator=None):
    m = Model("oscillator")
    x, v, u = m.state("x"), m.state("v"), m.input("u")
    m.equation(m.der(x), v)
    m.equation(m.der(v), -100.0 * x + u)
    opt = Optimization(m, final_time=2.0)
    opt.set_objective(lagrange=u**2)
    rest_to_rest(opt, x, v)
    return ShootingTranscription(opt, intervals=10, steps=1, integrator=integrator).solve()


def test_coarse_integrator_fails_its_verification():
    coarse, reference = _oscillator(), _oscillator("cvodes")
    assert reference.status == "optimal" and reference.verification.passed
    assert coarse.status == "check_failed" and not coarse.verification.passed
    assert "deviates" in coarse.verification.message and "verification failed" in coarse.message
    assert coarse.objective > 4.0 * reference.objective  # the optimum of RK4's map, not of the model
