"""Tests of a refinement pass's multipliers carried onto the next mesh (gtmodel.modeling.ocp.refinement_multipliers).

References: IPOPT's own multipliers of the same NLP (carried onto the same mesh they must come back exactly, and
IPOPT, started from them, stops at once); the double integrator x'' = u, |u| <= 1, |x'| <= 0.6, rest to rest over 1:
minimum time 0.6 + 0.6 + 0.64 / 0.6 = 2.26667 s (closed form: bang, cruise at the speed bound, bang); minimum
int u^2 over 2.5 s: 12 / 2.5^3 = 0.768 (closed form: u linear, its peak speed 0.6 exactly at the bound).
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.modeling import CollocationTranscription, Optimization
from gtmodel.modeling.ocp.refinement_guess import guess_from
from gtmodel.modeling.ocp.refinement_multipliers import multiplier_source, warm_start

from .._builders import double_integrator, rest_to_rest

CLOSED_FORM = {True: 0.6 + 0.6 + 0.64 / 0.6, False: 12 / 2.5**3}


def _problem(free: bool, path: bool = False) -> Optimization:
    m, x, v, u = double_integrator()
    opt = Optimization(m, free_final_time=free, final_time=2.5, final_time_bounds=(0.5, 5.0) if free else None,
                       final_time_guess=1.0)
    opt.set_objective(mayer=opt.final_time if free else None, lagrange=None if free else u**2)
    opt.set_bounds(u, -1.0, 1.0)
    opt.set_bounds(v, -0.6, 0.6)
    if path:
        opt.add_path_constraint(u + v, -2.0, 2.0)
    rest_to_rest(opt, x, v)
    return opt


def _mesh(n: int = 30) -> np.ndarray:
    f = np.random.default_rng(0).uniform(0.5, 1.5, n)
    return f / f.sum()


@pytest.fixture(scope="module", params=[True, False], ids=["minimum time", "minimum energy"])
def solved(request):
    opt = _problem(request.param)
    tr = CollocationTranscription(opt, elements=30, mesh=_mesh())
    return request.param, opt, tr, tr.solve()


def test_carried_onto_the_same_mesh_they_are_ipopts_own(solved):
    free, opt, tr, res = solved
    start = warm_start(CollocationTranscription(opt, elements=30, mesh=_mesh()), multiplier_source(tr, res), guess_from(res), res, None)
    np.testing.assert_allclose(start.lam_g, res.lam_g, rtol=0, atol=1e-12)
    np.testing.assert_allclose(start.lam_w, res.lam_w, rtol=0, atol=1e-12)


def test_started_from_its_own_optimum_ipopt_stops_at_once(solved):
    free, opt, tr, res = solved
    again = CollocationTranscription(opt, elements=30, mesh=_mesh())
    out = again.solve(initial_guess=warm_start(again, multiplier_source(tr, res), guess_from(res), res, None), warm_start=True)
    assert out.status == "optimal" and out.iterations <= 2
    assert out.objective == pytest.approx(res.objective, rel=1e-9)


def test_carried_onto_a_mesh_with_elements_split_it_solves_to_the_closed_form(solved):
    free, opt, tr, res = solved
    mesh = _mesh()
    finer = np.concatenate([[f / 2, f / 2] if k in (3, 10, 20) else [f] for k, f in enumerate(mesh)])
    new = CollocationTranscription(opt, elements=finer.size, mesh=finer)
    start = warm_start(new, multiplier_source(tr, res), guess_from(res), res, None)
    out = new.solve(initial_guess=start, warm_start=True)
    assert out.status == "optimal" and out.verification.passed
    assert out.objective == pytest.approx(CLOSED_FORM[free], rel=1e-4)


def test_no_multipliers_no_source(solved):
    free, opt, tr, res = solved
    other = CollocationTranscription(opt, elements=10)
    assert multiplier_source(other, res) is None  # a result of another transcription


def test_another_set_of_rows_per_point_is_not_carried(solved):
    free, opt, tr, res = solved
    with_path = CollocationTranscription(_problem(free, path=True), elements=30, mesh=_mesh())
    assert warm_start(with_path, multiplier_source(tr, res), guess_from(res), res, None) is None


@pytest.mark.parametrize("spans", [None, [(0.0, 0.3), (0.7, 1.0)]], ids=["everywhere", "two spans"])
def test_the_state_bounds_between_the_points_are_carried_too(spans):
    # the speed's bound arc (|x'| <= 0.6) with 2 more points per element: IPOPT's own multipliers come back exactly
    opt = _problem(True)
    tr = CollocationTranscription(opt, elements=30, mesh=_mesh(), bound_points=2, bound_spans=spans)
    res = tr.solve()
    source = multiplier_source(tr, res)
    first, where, per = source.interior
    assert per == 2 and where.size == (30 if spans is None else 18)  # the random mesh: 18 elements overlap the spans
    assert np.abs(res.lam_g[first:first + per * where.size]).max() > 1e-3  # active between the points: not a vacuous test
    start = warm_start(CollocationTranscription(opt, elements=30, mesh=_mesh(), bound_points=2, bound_spans=spans), source,
                       guess_from(res), res, None)
    np.testing.assert_allclose(start.lam_g, res.lam_g, rtol=0, atol=1e-12)
