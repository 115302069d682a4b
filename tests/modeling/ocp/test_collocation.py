"""Tests of the direct collocation transcription and IPOPT solve.

References: closed-form optimal controls of the double integrator x'' = u, rest to rest
over distance 1 (stated per test).
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.modeling import CollocationTranscription, Model, Optimization, OptimizationResult, solve

from .._builders import double_integrator, min_energy_over_distance_parameter, min_energy_problem, rest_to_rest

COST_TOL = 1e-6  # min-energy cost: the cubic solution is exactly representable (d = 3)
TRAJ_TOL = 1e-6  # trajectory vs closed form on the mesh
MIN_TIME_TOL = 1e-5  # min-time tf: bang-bang with active bounds, IPOPT tol 1e-8
SCHEMES = ["radau", "legendre"]


@pytest.mark.parametrize("scheme", SCHEMES)
def test_min_energy_matches_closed_form(scheme):
    # reference: min int_0^1 u^2 dt, x(0)=v(0)=0, x(1)=1, v(1)=0
    #   => u = 6 - 12 t, x = 3 t^2 - 2 t^3, cost 12
    res = solve(min_energy_problem(), elements=20, points=3, scheme=scheme)
    assert res.success and res.status == "optimal" and not res.last_iterate
    assert res.objective == pytest.approx(12.0, abs=COST_TOL)
    np.testing.assert_allclose(res.inputs["u"], 6.0 - 12.0 * res.t, atol=TRAJ_TOL)
    np.testing.assert_allclose(res.states["x"], 3 * res.t**2 - 2 * res.t**3, atol=TRAJ_TOL)
    np.testing.assert_allclose(res.outputs["kinetic"], 0.5 * (6 * res.t - 6 * res.t**2) ** 2, atol=TRAJ_TOL)
    assert res.max_constraint_violation < 1e-8
    assert res.final_time == 1.0


@pytest.mark.parametrize("scheme", SCHEMES)
def test_min_time_bang_bang(scheme):
    # reference: min tf with |u| <= 1, rest to rest over 1  =>  tf = 2, u = +1 then -1 (switch at 1)
    m, x, v, u = double_integrator()
    opt = Optimization(m, free_final_time=True, final_time_bounds=(0.5, 5.0), final_time_guess=1.0)
    opt.objective = opt.final_time
    opt.set_bounds(u, -1.0, 1.0)
    rest_to_rest(opt, x, v)
    res = solve(opt, elements=50, points=3, scheme=scheme)
    assert res.status == "optimal"
    assert res.final_time == pytest.approx(2.0, abs=MIN_TIME_TOL)
    t, uu = res.t, res.inputs["u"]
    away = np.abs(t - 1.0) > 0.1
    np.testing.assert_allclose(uu[away], np.where(t[away] < 1.0, 1.0, -1.0), atol=1e-4)
    assert res.states["x"][-1] == pytest.approx(1.0, abs=1e-8)


def test_path_constraint_with_der_and_algebraic():
    # reference: x'' = z/2 with algebraic z = 2 u, min int u^2: same closed form as
    # min energy (cost 12, u = 6 - 12 t); the path constraint der(v) <= 10 is inactive
    # (max u'' = 6) and exercises der() substitution in constraints.
    m = Model("dae_di")
    x = m.state("x")
    v = m.state("v")
    z = m.algebraic("z")
    u = m.input("u")
    m.equation(m.der(x), v)
    m.equation(2.0 * m.der(v), z)
    m.equation(z, 2.0 * u)
    opt = Optimization(m, final_time=1.0)
    opt.set_objective(lagrange=u**2)
    opt.add_path_constraint(m.der(v), ub=10.0, name="acc")
    rest_to_rest(opt, x, v)
    res = solve(opt, elements=10)
    assert res.status == "optimal"
    assert res.objective == pytest.approx(12.0, abs=COST_TOL)
    at = np.char.startswith(res.collocation.point_kinds(), "collocation")
    np.testing.assert_allclose(res.algebraics["z"][at], 2 * (6.0 - 12.0 * res.t[at]), atol=TRAJ_TOL)
    # the start (no collocation point): z consistent with the input written there (z = 2 u)
    np.testing.assert_allclose(res.algebraics["z"], 2 * res.inputs["u"], atol=1e-12)


def test_active_path_constraint():
    # reference: min energy with |v| <= 1.2 (unconstrained peak speed 1.5): the
    # constraint must hold at every collocation point and raise the cost above 12.
    m, x, v, u = double_integrator()
    opt = Optimization(m, final_time=1.0)
    opt.set_objective(lagrange=u**2)
    opt.add_path_constraint(v, lb=-1.2, ub=1.2, name="speed")
    rest_to_rest(opt, x, v)
    res = solve(opt, elements=20)
    assert res.status == "optimal"
    assert res.objective > 12.0 + 0.1
    assert np.max(res.states["v"]) <= 1.2 + 1e-7


def test_start_point_constraint_on_input_uses_extrapolation_at_tau0():
    # reference: documented convention, u(t0) is the first element's polynomial at tau = 0,
    # the value the table writes at t0
    opt = min_energy_problem()
    u = opt.model.variables("input")["u"]
    opt.add_point_constraint(u, at="start", lb=0.0, ub=0.0, name="u_start")
    res = solve(opt, elements=10)
    assert res.status == "optimal"
    assert res.sample([0.0])["inputs"]["u"][0] == pytest.approx(0.0, abs=1e-8)
    assert res.collocation.point_kinds()[0] == "start" and res.inputs["u"][0] == pytest.approx(0.0, abs=1e-8)
    assert res.objective > 12.0  # an extra constraint cannot lower the cost


@pytest.mark.parametrize("scheme", SCHEMES)
def test_input_bounds_hold_at_the_extrapolated_start(scheme):
    # reference: the bound itself. Unbounded, min int u^2 rest to rest gives u = 6 - 12 t (the
    # closed form); with |u| <= 5.9 the extrapolated start (and Legendre's final) values, which
    # are no collocation points, are bounded too (without: 6.0023 written at t0, measured)
    opt = min_energy_problem()
    u = opt.model.variables("input")["u"]
    opt.set_bounds(u, -5.9, 5.9)
    res = solve(opt, elements=10, scheme=scheme)
    assert res.status == "optimal"
    assert np.max(np.abs(res.inputs["u"])) <= 5.9 + 1e-7


def test_repeated_solves_with_parameters_and_warm_start():
    # reference: min energy over distance D in 1 s has cost 12 D^2 (scaling of the closed form)
    tr = CollocationTranscription(min_energy_over_distance_parameter(), elements=10)
    first = tr.solve()
    second = tr.solve(parameters={"D": 2.0}, initial_guess=first)
    third = tr.solve(parameters={"D": 0.5}, initial_guess={"x": ([0.0, 1.0], [0.0, 0.5])})
    assert first.objective == pytest.approx(12.0, abs=COST_TOL)
    assert second.objective == pytest.approx(48.0, abs=COST_TOL)
    assert third.objective == pytest.approx(3.0, abs=COST_TOL)
    assert second.parameters["D"][0] == 2.0


def test_infeasible_problem_reports_status_without_exception():
    # reference: with |u| <= 0.001 the reachable distance in 1 s is at most 0.0005 < 1
    opt = min_energy_problem()
    opt.set_bounds(opt.model.variables("input")["u"], -0.001, 0.001)
    res = solve(opt, elements=10)
    assert isinstance(res, OptimizationResult)
    assert res.status == "infeasible"
    assert not res.success and res.last_iterate
    assert res.message.startswith("Infeasible_Problem_Detected; likely culprit: the largest violations at the last iterate: "
                                  "'x_final' at the final time by ")  # the unreachable end named (gtmodel.modeling.ocp.infeasibility)
    assert res.max_constraint_violation > 0.1


def test_iteration_limit_is_reported():
    # reference: IPOPT stops after max_iter iterations with Maximum_Iterations_Exceeded
    m, x, v, u = double_integrator()
    opt = Optimization(m, free_final_time=True, final_time_bounds=(0.5, 5.0))
    opt.objective = opt.final_time
    opt.set_bounds(u, -1.0, 1.0)
    rest_to_rest(opt, x, v)
    res = solve(opt, elements=10, solver_options={"max_iter": 2})
    assert res.status == "max_iterations" and not res.success
    assert res.iterations == 2
    assert res.message.split(";")[0] == "Maximum_Iterations_Exceeded"  # and the likely culprit at the last iterate


def test_objective_at_guess_and_new_solver_options():
    # reference: tf + int_0^tf u^2 dt at the guess tf = 2, u = 0.5 is 2 + 0.25 * 2 = 2.5 (the
    # quadrature is exact for constants)
    m, x, v, u = double_integrator()
    opt = Optimization(m, free_final_time=True, final_time_bounds=(0.5, 5.0), final_time_guess=2.0)
    opt.set_objective(mayer=opt.final_time, lagrange=u**2)
    opt.set_bounds(u, -1.0, 1.0)
    rest_to_rest(opt, x, v)
    opt.set_initial_guess(u, 0.5)
    tr = CollocationTranscription(opt, elements=10, solver_options={"tol": 1e-9})
    assert tr.objective_at_guess() == pytest.approx(2.5, rel=1e-12)
    # a rebuilt solver keeps the options given at construction and adds the new one
    tr.set_solver_options({"max_iter": 2})
    res = tr.solve()
    assert res.status == "max_iterations" and res.iterations == 2
    assert (tr.options["ipopt"]["tol"], tr.options["ipopt"]["max_iter"]) == (1e-9, 2)
    tr.set_solver_options({"max_iter": 200})
    assert tr.solve().status == "optimal"


def test_nan_in_evaluation_is_an_error_status():
    # reference: sqrt of a negative number is NaN at every admissible point
    m, x, v, u = double_integrator()
    opt = Optimization(m, final_time=1.0)
    opt.set_objective(lagrange=(-1.0 - u**2) ** 0.5)
    rest_to_rest(opt, x, v)
    res = solve(opt, elements=5)
    assert res.status == "error" and not res.success
    assert res.message


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"elements": 0}, "elements must be a positive integer"),
        ({"points": 0}, "points must be an integer"),
        ({"scheme": "hermite"}, "scheme must be 'radau' or 'legendre'"),
        ({"initial_guess": {"nope": 1.0}}, "'nope' is not a state"),
        ({"initial_guess": 3.0}, "initial_guess must be"),
    ],
    ids=["elements", "points", "scheme", "guess_name", "guess_type"],
)
def test_solve_input_errors(kwargs, match):
    with pytest.raises(InputError, match=match):
        solve(min_energy_problem(), **kwargs)
