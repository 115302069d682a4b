"""Tests of ``solver="fatrop"``: the collocation NLP ordered stage by stage and solved by CasADi's fatrop plugin.

References: the closed forms of the double integrator (minimum energy: cost 12; minimum
time with |u| <= 1: tf = 2) and IPOPT on the same transcription (a second method: the
same optimum to 1e-6).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import InputError, SolverError
from gtmodel.modeling import CollocationTranscription, Optimization
from gtmodel.modeling.ocp.collocation import SOLVERS
from gtmodel.problems import load_problem
from gtmodel.modeling.ocp.methods import NLP_SOLVERS

from ...conftest import PROBLEMS_DIR
from .._builders import double_integrator, min_energy_problem, rest_to_rest
from .test_optimization import _free_parameter_problem


def _min_time() -> Optimization:
    m, x, v, u = double_integrator()
    opt = Optimization(m, free_final_time=True, final_time_bounds=(0.5, 5.0), final_time_guess=1.0)
    opt.objective = opt.final_time
    opt.set_bounds(u, -1.0, 1.0)
    rest_to_rest(opt, x, v)
    return opt


PROBLEMS = [
    # (name, builder, closed-form objective, transcription arguments)
    ("min_energy_radau", min_energy_problem, 12.0, {"scheme": "radau"}),
    ("min_energy_legendre", min_energy_problem, 12.0, {"scheme": "legendre"}),
    ("min_time", _min_time, 2.0, {}),
    ("min_time_scaled", _min_time, 2.0, {"nominal": {"x": 2.0, "v": 0.5, "final_time": 3.0}}),
]


@pytest.mark.parametrize("name, build, expected, kw", PROBLEMS, ids=[p[0] for p in PROBLEMS])
def test_fatrop_reaches_ipopts_optimum_on_the_same_transcription(name, build, expected, kw):
    ip = CollocationTranscription(build(), elements=20, **kw).solve()
    fa = CollocationTranscription(build(), elements=20, solver="fatrop", **kw).solve()
    assert (ip.status, fa.status) == ("optimal", "optimal"), fa.message
    assert fa.objective == pytest.approx(ip.objective, rel=1e-6, abs=1e-6)
    assert fa.objective == pytest.approx(expected, rel=1e-4)
    np.testing.assert_allclose(fa.states["x"], ip.states["x"], atol=1e-5)
    assert fa.max_constraint_violation < 1e-6
    assert fa.verification.passed


def _outputs(tr, function, rng):
    args = [rng.uniform(0.5, 1.5, tr._lbw.size), tr.dae.p_value]
    if function == "nlp_hess_l":
        args += [1.3, rng.standard_normal(tr._lbg.size)]
    out = tr.solver.get_function(function).call(args)
    return [np.array(ca.DM(o)) for o in out]


@pytest.mark.parametrize("scaling", [1.0, 40.0])
@pytest.mark.parametrize("function", ["nlp_g", "nlp_jac_g", "nlp_hess_l"])
def test_fatrop_is_given_the_compiled_derivatives_with_the_plugins_values(cache, function, scaling):
    # second method: the fatrop plugin differentiating the whole NLP graph itself (derivatives="casadi"),
    # at a random point; the Hessian's outputs are the Lagrangian's gradient and the whole symmetric matrix;
    # the constraints are assembled from the compiled point residuals (nlp_g, and jac_g's first output)
    kw = dict(elements=4, solver="fatrop", nominal={"x": 2.0, "v": 0.5, "final_time": 3.0},
              solver_options={"obj_scaling_factor": scaling})
    a = CollocationTranscription(_min_time(), compile=True, **kw)
    b = CollocationTranscription(_min_time(), derivatives="casadi", **kw)
    assert a.evaluation.startswith("compiled C")
    fa, fb = a.solver.get_function(function), b.solver.get_function(function)
    # the runtime reads the outputs in the plugin's own sparsity (the constraints and the gradient dense)
    assert [fa.sparsity_out(i).is_dense() for i in range(fa.n_out())] == [fb.sparsity_out(i).is_dense() for i in range(fb.n_out())]
    va, vb = _outputs(a, function, np.random.default_rng(0)), _outputs(b, function, np.random.default_rng(0))
    assert [v.shape for v in va] == [v.shape for v in vb]
    np.testing.assert_allclose(np.concatenate([v.ravel() for v in va]), np.concatenate([v.ravel() for v in vb]), rtol=0, atol=1e-11)


def test_a_second_fatrop_transcription_compiles_nothing(cache):
    # the compiled point derivatives are IPOPT's: one library per model, whatever the mesh and the solver;
    # fatrop adds its end terms' (start and final constraints, Mayer term), compiled once too
    CollocationTranscription(_min_time(), elements=3, compile=True)
    first = CollocationTranscription(_min_time(), elements=5, compile=True, solver="fatrop")
    assert first.evaluation.count("already loaded") == 1
    again = CollocationTranscription(_min_time(), elements=9, compile=True, solver="fatrop")
    assert again.evaluation.count("already loaded") == 2
    # the plugin is given them (its function cache), it differentiates nothing itself
    assert hash(again.solver.get_function("nlp_jac_g")) == hash(again.derivative_functions["jac_g"])
    assert hash(again.solver.get_function("nlp_hess_l")) == hash(again.derivative_functions["hess_lag"])
    assert hash(again.solver.get_function("nlp_g")) == hash(again.derivative_functions["g"])


def test_stage_structure_is_one_stage_per_element():
    tr = CollocationTranscription(_min_time(), elements=7, solver="fatrop")
    st = tr.nlp.stages
    # stage k: the start state and the final-time copy, then d (nx + nu) point variables; stage N: the final state
    assert (st["N"], st["nx"], st["nu"]) == (7, [3] * 7 + [2], [9] * 7 + [0])
    assert sum(st["nx"]) + sum(st["nu"]) == tr.nlp.w.numel()
    assert sum(st["ng"]) + sum(st["nx"][1:]) == tr.nlp.g.numel()
    assert tr.banded


BAD = [
    ({"solver": "fatrop", "banded": False}, "banded=True"),
    ({"solver": "knitro"}, "solver must be one of ipopt, fatrop"),
]


@pytest.mark.parametrize("kw, match", BAD, ids=["shared_final_time", "unknown"])
def test_bad_solver_arguments_are_refused(kw, match):
    with pytest.raises(InputError, match=match):
        CollocationTranscription(_min_time(), elements=5, **kw)


def test_free_parameters_are_refused_with_fatrop():
    with pytest.raises(InputError, match="free parameters are shared by all elements"):
        CollocationTranscription(_free_parameter_problem(), elements=5, solver="fatrop")


def test_an_integral_constraint_coupling_all_elements_is_refused():
    # the isoperimetric form of the hanging chain: integral(...) == L sums over every element
    chain = load_problem(PROBLEMS_DIR / "benchmarks" / "hanging_chain.toml").declaration.optimization
    tr = CollocationTranscription(chain, elements=4, solver="fatrop")  # its nlpsol is built at the first use
    with pytest.raises(SolverError, match="couple elements beyond neighbouring ones"):
        tr.solve()


def test_a_solve_from_a_coarse_mesh_builds_only_the_warm_solver():
    # fatrop's plugin sets up its blocks in time quadratic in the elements: the cold nlpsol a
    # coarse start never calls is not built (and the build is counted in the solve's timing)
    coarse = CollocationTranscription(_min_time(), elements=10, solver="fatrop").solve()
    tr = CollocationTranscription(_min_time(), elements=40, solver="fatrop")
    warm = tr.solve(initial_guess=coarse, warm_start=True)
    assert warm.status == "optimal" and tr._solver is None and tr._warm_solver is not None
    assert warm.timing["build"]["cpu_s"] > 0
    assert tr.solver is not tr.warm_solver() and tr._solver is not None


def test_warm_start_from_a_coarse_mesh_reaches_the_cold_optimum_in_fewer_iterations():
    # second path: the cold solve of the same 40-element NLP (and the closed form tf = 2)
    coarse = CollocationTranscription(_min_time(), elements=10, solver="fatrop").solve()
    tr = CollocationTranscription(_min_time(), elements=40, solver="fatrop")
    cold, warm = tr.solve(), tr.solve(initial_guess=coarse, warm_start=True)
    assert (coarse.status, cold.status, warm.status) == ("optimal", "optimal", "optimal")
    assert warm.objective == pytest.approx(cold.objective, rel=1e-6)
    assert warm.objective == pytest.approx(2.0, rel=1e-6)
    assert warm.iterations < cold.iterations  # 7 against 13 (the barrier started at 1e-3)
    assert tr.warm_solver() is tr.warm_solver()  # built once


@pytest.mark.parametrize("guess", [None, {"final_time": 2.0}], ids=["none", "mapping"])
def test_fatrop_warm_start_needs_a_result(guess):
    tr = CollocationTranscription(min_energy_problem(), elements=5, solver="fatrop")
    with pytest.raises(InputError, match="warm_start: initial_guess must be a collocation result"):
        tr.solve(initial_guess=guess, warm_start=True)


def test_problem_settings_offer_the_transcriptions_solvers():
    assert NLP_SOLVERS == SOLVERS
