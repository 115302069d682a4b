"""Timed variables, integrals in constraints, maximisation and parameter bounds (Optimica's point constraints).

References (all closed forms, independent of the transcription):

* maximise ``x(T)`` of ``x'' = u`` from rest with ``integral(u^2) <= E``: by Cauchy-Schwarz
  ``x(T) = int (T - s) u ds <= sqrt(E T^3 / 3)``, attained by ``u ~ T - s``;
* minimise ``integral(u^2)`` from rest with ``x(t1) = 1`` at an interior time ``t1``: the
  minimum-energy reach of a free-velocity target, ``3 / t1^3`` (``u = 0`` after ``t1``);
* ``x(t0)^2 + integral(u^2)`` with ``x' = u``, ``x(T) = 1``, ``T = 1``: ``a^2 + (1 - a)^2``
  with ``a = x(t0)``, minimum ``0.5`` at ``a = 0.5``;
* minimum time rest to rest over ``D`` with ``|u| <= umax``: ``T = 2 sqrt(D / umax)``;
* the COPS hanging chain (published optimum 5.06852), its length an isoperimetric constraint.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling import CollocationTranscription, Model, Optimization
from gtmodel.modeling.ocp.methods import VerificationSettings

from .._builders import double_integrator


def _from_rest(opt, x, v):
    opt.add_point_constraint(x, at="start", lb=0.0, ub=0.0)
    opt.add_point_constraint(v, at="start", lb=0.0, ub=0.0)


def test_maximise_final_state_under_an_isoperimetric_constraint():
    m, x, v, u = double_integrator()
    opt = Optimization(m, final_time=2.0)
    _from_rest(opt, x, v)
    opt.set_objective(mayer=x, sense="maximize")
    opt.add_constraint(opt.integral(u**2), ub=0.5, name="energy")
    r = CollocationTranscription(opt, elements=10).solve()
    assert r.status == "optimal"
    assert r.objective == pytest.approx(np.sqrt(0.5 * 2.0**3 / 3.0), rel=1e-7)  # reported as maximised, positive
    t = np.linspace(0.0, 2.0, 401)
    assert np.trapezoid(r.sample(t)["inputs"]["u"] ** 2, t) == pytest.approx(0.5, rel=1e-4)
    # the verification integrates the constraint's integrand along the simulation (a quadrature of
    # CVODES, independent of the collocation quadrature): the same 0.5
    (energy,) = r.verification.integrals.values()
    assert energy["passed"] and energy["simulated"] == pytest.approx(0.5, rel=1e-7)
    assert energy["collocation"] == pytest.approx(0.5, rel=1e-7)  # the constraint, active, to the solver tolerance


@pytest.mark.parametrize("t1, elements, rel, scheme", [(0.3, 10, 1e-8, "radau"), (0.35, 20, 2e-3, "radau"), (0.3, 10, 1e-8, "legendre")],
                         ids=["on_boundary", "interior", "legendre_on_boundary"])
def test_variable_at_an_interior_time(t1, elements, rel, scheme):
    # at an element boundary the optimum is a polynomial on each element (exact); strictly
    # inside an element the kink of u at t1 is interpolated (first-order accurate)
    m, x, v, u = double_integrator()
    opt = Optimization(m, final_time=1.0)
    _from_rest(opt, x, v)
    opt.set_objective(lagrange=u**2)
    opt.add_constraint(opt.timed(x, t1), lb=1.0, ub=1.0)
    r = CollocationTranscription(opt, elements=elements, scheme=scheme).solve()
    assert r.status == "optimal"
    assert r.objective == pytest.approx(3.0 / t1**3, rel=rel)
    assert r.sample([t1])["states"]["x"][0] == pytest.approx(1.0, abs=1e-8)  # the same polynomial the result samples


def test_variable_at_an_interior_time_on_a_non_uniform_mesh():
    # t1 = 0.3 is the end of the third element of the mesh (0.1, 0.1, 0.1, 0.35, 0.35): the
    # optimum is a polynomial on each element, exact (a refined mesh once crashed here)
    m, x, v, u = double_integrator()
    opt = Optimization(m, final_time=1.0)
    _from_rest(opt, x, v)
    opt.set_objective(lagrange=u**2)
    opt.add_constraint(opt.timed(x, 0.3), lb=1.0, ub=1.0)
    r = CollocationTranscription(opt, mesh=[0.1, 0.1, 0.1, 0.35, 0.35]).solve()
    assert r.status == "optimal"
    assert r.objective == pytest.approx(3.0 / 0.3**3, rel=1e-8)
    assert r.sample([0.3])["states"]["x"][0] == pytest.approx(1.0, abs=1e-8)


def test_start_value_in_the_objective_and_mixed_time_points():
    m = Model("integrator")
    x, u = m.state("x"), m.input("u")
    m.equation(m.der(x), u)
    opt = Optimization(m, final_time=1.0)
    opt.set_objective(mayer=opt.timed(x, "start") ** 2, lagrange=u**2)
    opt.add_constraint(opt.timed(x, "final") - opt.timed(x, 0.0), lb=0.5, ub=0.5)  # x(T) - x(t0), t0 by number
    r = CollocationTranscription(opt, elements=5).solve()
    # with x(T) = x(t0) + 0.5: cost a^2 + 0.25 is least at a = 0
    assert r.objective == pytest.approx(0.25, abs=1e-8)
    assert r.states["x"][0] == pytest.approx(0.0, abs=1e-8) and r.states["x"][-1] == pytest.approx(0.5, abs=1e-8)
    assert len(opt.timed_variables) == 2  # x at "start" and at 0.0 are one timed variable


def test_bound_expression_of_a_parameter_is_imposed():
    m, x, v, u = double_integrator()
    umax = m.parameter("umax", 4.0)
    opt = Optimization(m, free_final_time=True, final_time_bounds=(0.1, 5.0), final_time_guess=2.0)
    opt.set_bounds(u, -umax, umax)
    _from_rest(opt, x, v)
    opt.add_point_constraint(x, at="final", lb=1.0, ub=1.0)
    opt.add_point_constraint(v, at="final", lb=0.0, ub=0.0)
    opt.set_objective(mayer=opt.final_time)
    tr = CollocationTranscription(opt, elements=20)
    assert tr.solve().final_time == pytest.approx(2.0 * np.sqrt(1.0 / 4.0), rel=1e-6)
    assert tr.solve(parameters={"umax": 1.0}).final_time == pytest.approx(2.0, rel=1e-6)


def test_one_sided_and_infinite_bounds():
    m, x, v, u = double_integrator()
    opt = Optimization(m)
    opt.set_bounds(u, -np.inf, 2.0)
    opt.set_bounds(v, 0.0, np.inf)
    dae = m.flatten()
    lb, ub = opt.bounds_vectors(dae, "u")
    assert (lb[0], ub[0]) == (-np.inf, 2.0)


BAD = [
    (lambda opt, x, u: opt.timed(x, 2.5), ModelError, r"t = 2\.5 s: outside the horizon \[0, 2\] s"),
    (lambda opt, x, u: opt.timed(x, "middle"), InputError, r"time must be a number, 'start' or 'final'"),
    (lambda opt, x, u: opt.timed(ca.vertcat(x, u), 1.0), InputError, r"must be scalar"),
    (lambda opt, x, u: opt.add_constraint(opt.timed(x, 1.0) + x, lb=0.0), ModelError, r"outside a timed variable or integral"),
    (lambda opt, x, u: opt.add_path_constraint(opt.integral(u**2) - x, ub=0.0), ModelError, r"unknown symbol"),
    (lambda opt, x, u: opt.set_objective(lagrange=opt.timed(x, 1.0)), ModelError, r"unknown symbol"),
    (lambda opt, x, u: opt.set_objective(mayer=x, sense="largest"), InputError, r"'minimize' or 'maximize'"),
    (lambda opt, x, u: opt.set_bounds(u, -x, 1.0), ModelError, r"parameters and final_time only"),
]


@pytest.mark.parametrize("call, exc, match", BAD, ids=[b[2][:30] for b in BAD])
def test_bad_declarations(call, exc, match):
    m, x, v, u = double_integrator()
    opt = Optimization(m, final_time=2.0)
    with pytest.raises(exc, match=match):
        call(opt, x, u)


def test_interior_time_with_a_free_final_time_is_a_fraction_of_the_horizon():
    m, x, v, u = double_integrator()
    opt = Optimization(m, free_final_time=True, final_time_bounds=(1.0, 3.0))
    with pytest.raises(ModelError, match=r"free final time only the start and the final time or a fixed fraction s of the "
                       r"horizon .* write the time as start_time \+ s \* \(final_time - start_time\)"):
        opt.timed(x, 0.5)
    with pytest.raises(ModelError, match=r"start_time \+ s \* \(final_time - start_time\) with 0 <= s <= 1"):
        opt.timed(x, 1.0 + 0.5 * opt.final_time)
    with pytest.raises(InputError, match="numbers and final_time only"):
        opt.timed(x, u * opt.final_time)
    assert opt.timed(x, 0.0) is opt.timed(x, "start") is opt.timed(x, 0 * opt.final_time)
    assert opt.timed(x, 1.0 * opt.final_time) is opt.timed(x, "final")


@pytest.mark.parametrize("method", ["collocation", pytest.param("multiple_shooting", marks=pytest.mark.slow)])
def test_speed_limit_at_half_of_a_free_horizon(method):
    # minimum time rest to rest over 1 with |u| <= 1 and v(T/2) <= 0.1: by symmetry each half
    # accelerates for a, brakes for a - 0.1 to v = 0.1 over 0.5: a^2 - 0.005 = 0.5, so
    # T = 2 (2 sqrt(0.505) - 0.1) = 2.642534 (by hand; the switches are off the mesh: O(h))
    from gtmodel.modeling.ocp.shooting import ShootingTranscription

    m, x, v, u = double_integrator()
    opt = Optimization(m, free_final_time=True, final_time_bounds=(0.5, 5.0), final_time_guess=3.0)
    opt.set_bounds(u, -1.0, 1.0)
    for var, at, value in ((x, "start", 0.0), (v, "start", 0.0), (x, "final", 1.0), (v, "final", 0.0)):
        opt.add_point_constraint(var, at=at, lb=value, ub=value)
    opt.set_objective(mayer=opt.final_time)
    opt.add_constraint(opt.timed(v, 0.5 * opt.final_time), ub=0.1)
    # the verdict of the collocation solve is its simulation under the input clipped to |u| <= 1: with the switches
    # inside elements of 20 it deviates by 0.024 in x (the polynomial input: within 0.01), checked at 0.03 here
    tr = (CollocationTranscription(opt, elements=20, verify=VerificationSettings(tolerance=3e-2)) if method == "collocation"
          else ShootingTranscription(opt, intervals=20))
    r = tr.solve()
    T = 2.0 * (2.0 * np.sqrt(0.505) - 0.1)
    assert r.status == "optimal" and r.final_time == pytest.approx(T, rel=5e-3 if method == "multiple_shooting" else 5e-4)
    assert r.sample([0.5 * r.final_time])["states"]["v"][0] == pytest.approx(0.1, abs=1e-6)  # where the point moved


def _hanging_chain():
    m = Model("chain")
    x, u = m.state("x"), m.input("u")
    m.equation(m.der(x), u)
    opt = Optimization(m, final_time=1.0)
    opt.add_point_constraint(x, at="start", lb=1.0, ub=1.0)
    opt.add_point_constraint(x, at="final", lb=3.0, ub=3.0)
    opt.set_objective(lagrange=x * ca.sqrt(1 + u**2))  # potential energy
    opt.add_constraint(opt.integral(ca.sqrt(1 + u**2)), lb=4.0, ub=4.0)  # the chain's length
    opt.set_initial_guess(x, lambda t: np.array([4 * (t - 0.5) ** 2 + 2 * t]))
    opt.set_initial_guess(u, lambda t: np.array([8 * (t - 0.5) + 2]))
    return opt


@pytest.mark.parametrize("method", ["collocation", pytest.param("multiple_shooting", marks=pytest.mark.slow)])
def test_hanging_chain_with_its_length_as_an_isoperimetric_constraint(method):
    # COPS 3.0 (Dolan, More, Munson 2004), hanging chain a = 1, b = 3, L = 4: published
    # minimum 5.06852 (their nh = 800 mesh); written with integral() as the length constraint
    # instead of an extra state
    from gtmodel.modeling.ocp.shooting import ShootingTranscription

    opt = _hanging_chain()
    tr = CollocationTranscription(opt, elements=50) if method == "collocation" else ShootingTranscription(opt, intervals=100, controls="linear")
    r = tr.solve()
    assert r.status == "optimal"
    assert r.objective == pytest.approx(5.06852, rel=2e-5)
