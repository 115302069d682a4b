"""How a refinement pass is started again (gtmodel.modeling.ocp.refinement_guess)."""

from __future__ import annotations

import pytest

from gtmodel.modeling import CollocationTranscription
from gtmodel.modeling.ocp.refinement_guess import solved_cold
from gtmodel.status import Status

from .test_verification import min_time_double_integrator


@pytest.fixture
def failed():
    """A transcription of the minimum-time double integrator whose solve was held to 2 IPOPT iterations, and that result."""
    tr = CollocationTranscription(min_time_double_integrator(), elements=10, solver_options={"max_iter": 2})
    return tr, tr.solve()


@pytest.mark.parametrize("max_iter, cpu_left, status, retried", [
    (3000, 60.0, Status.OPTIMAL, "optimal"),          # cold again, solved: the closed form's 2 s (below)
    (2, 60.0, Status.MAX_ITERATIONS, "max_iterations"),  # cold again, no solution either: the warm result, said so
    (3000, 0.5, Status.MAX_ITERATIONS, None),         # no CPU left of the budget: no retry
])
def test_solved_cold_returns_a_solution_or_the_failed_pass(failed, max_iter, cpu_left, status, retried):
    tr, result = failed
    assert result.status == Status.MAX_ITERATIONS and result.verification is None
    tr.set_solver_options({"max_iter": max_iter})
    out = solved_cold(tr, result, None, None, cpu_left)
    assert out.status == status
    assert (out.stats.get("cold_retry") or {}).get("status") == retried
    if status == Status.OPTIMAL:
        assert out.final_time == pytest.approx(2.0, abs=0.05) and out.stats["cold_retry"]["warm_status"] == "max_iterations"
