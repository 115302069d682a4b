"""Warm-started re-solves and the solve as one CasADi Function (rockit's to_function)."""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.modeling import CollocationTranscription

from .._builders import min_energy_over_distance_parameter

COST_TOL = 1e-6


def _transcription():
    # min int u^2 over 1 s moving rest to rest over D: cost 12 D^2 (closed form)
    opt = min_energy_over_distance_parameter()
    return CollocationTranscription(opt, elements=10)


@pytest.fixture(scope="module")
def solved():
    tr = _transcription()
    return tr, tr.solve()


@pytest.mark.parametrize("distance", [0.5, 1.01, 2.0])
def test_warm_start_reaches_the_closed_form(solved, distance):
    # reference: cost 12 D^2 (closed form), the same as a cold start
    tr, first = solved
    warm = tr.solve(parameters={"D": distance}, initial_guess=first, warm_start=True)
    assert warm.status == "optimal"
    assert warm.objective == pytest.approx(12.0 * distance**2, abs=COST_TOL)
    assert warm.lam_g is not None and warm.lam_g.size == tr._lbg.size


@pytest.mark.parametrize("warm_start", [True, False])
def test_to_function_solves_for_a_parameter_vector_and_chains(solved, warm_start):
    # reference: cost 12 D^2; outputs fed back as the next call's start point
    tr, first = solved
    f = tr.to_function(warm_start=warm_start)
    assert f.name_in() == ["p", "w0", "lam_w0", "lam_g0"]
    state, costs = (first.w, first.lam_w, first.lam_g), []
    for distance in (1.5, 0.75):
        out = f(p=tr.dae.parameter_vector({"D": distance}), w0=state[0], lam_w0=state[1], lam_g0=state[2])
        state = (out["w"], out["lam_w"], out["lam_g"])
        costs.append(float(out["objective"]))
    np.testing.assert_allclose(costs, [12.0 * 1.5**2, 12.0 * 0.75**2], rtol=0, atol=COST_TOL)
    assert float(out["final_time"]) == 1.0


@pytest.mark.parametrize(
    "guess, match",
    [(None, "warm_start: initial_guess must be a result of this transcription"), ({"x": 0.0}, "warm_start: initial_guess")],
)
def test_warm_start_needs_a_result_of_this_transcription(solved, guess, match):
    tr, _ = solved
    with pytest.raises(InputError, match=match):
        tr.solve(initial_guess=guess, warm_start=True)
