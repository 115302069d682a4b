"""Refinement from a pass that verified at IPOPT's acceptable level: its mesh re-solved once, the best verified returned.

Independent reference: the analytic minimum-time double integrator (final time 2 s, switch at
1 s; Bryson and Ho 1975, sec. 7.3); on 10 uniform elements of the 2 s horizon the switch is on
an element boundary, so that the solution verifies and nothing is left to split.
"""

from __future__ import annotations

import copy

import pytest

from gtmodel.modeling import CollocationTranscription, Optimization
from gtmodel.modeling.ocp import refinement
from gtmodel.modeling.ocp.refinement import solve_refined
from gtmodel.status import Status

from .test_verification import min_time_double_integrator as min_time_problem


def min_time_double_integrator() -> Optimization:
    opt = min_time_problem()
    opt.verification_tolerance = 1e-6
    return opt


@pytest.mark.parametrize("status, solves", [(Status.ACCEPTABLE, 1), (Status.OPTIMAL, 0)])
def test_a_verified_acceptable_pass_is_re_solved_once_without_the_early_stop(refinement_solves, status, solves):
    # a verified pass that IPOPT left at its acceptable level is no end of the refinement: its mesh is solved again
    # from it, acceptable_iter 0; a verified optimal pass is the end
    opt = min_time_double_integrator()
    start = CollocationTranscription(opt, elements=10).solve()
    assert start.verification.passed and start.final_time == pytest.approx(2.0, abs=1e-6)
    start = copy.copy(start)
    start.status = status
    seen = refinement_solves
    # (objective_tolerance 0: no pass checks the objective on the mesh halved, tests/modeling/ocp/test_refinement_objective.py)
    res = solve_refined(opt, elements=10, start=start, max_passes=4, max_cpu_s=90.0, objective_tolerance=0.0)
    assert len(seen) == solves and all(o["acceptable_iter"] == 0 and 0 < o["max_cpu_time"] <= 90.0 for o in seen)
    assert [bool(e.get("polished")) for e in res.refinement] == [False] + [True] * solves
    assert res.status == Status.OPTIMAL if solves else res.status == status
    assert res.final_time == pytest.approx(2.0, abs=1e-6) and res.verification.passed


def test_of_verified_acceptable_passes_the_best_objective_is_returned(monkeypatch):
    # with no verified optimal pass, the verified acceptable pass with the best objective is returned (it was the pass
    # with the smallest deviation, acceptable or not): every solve reported acceptable, the start's objective set 1 %
    # above its re-solve's (the analytic 2 s)
    opt = min_time_double_integrator()
    start = CollocationTranscription(opt, elements=10).solve()
    start = copy.copy(start)
    start.status, start.objective, start.final_time = Status.ACCEPTABLE, 2.02, 2.02
    real = refinement.CollocationTranscription

    class Acceptable(real):
        def solve(self, *args, **kwargs):
            result = super().solve(*args, **kwargs)
            result.status = Status.ACCEPTABLE
            return result

    monkeypatch.setattr(refinement, "CollocationTranscription", Acceptable)
    res = solve_refined(opt, elements=10, start=start, max_passes=4)
    assert len(res.refinement) == 2 and res.status == Status.ACCEPTABLE
    assert res.final_time == pytest.approx(2.0, abs=1e-6) and "returned pass 2 of 2" in res.refinement_stop


def test_a_pass_stopped_at_the_acceptable_level_is_continued_warm_to_the_tolerance(monkeypatch):
    # a pass IPOPT stopped at its acceptable level (here: reported so) is continued in the same pass from its
    # primal-dual point (warm start: its multipliers), acceptable_iter 0, within POLISH_CPU_S; the continuation's
    # optimum is the pass's result (the analytic 2 s)
    opt = min_time_double_integrator()
    real = refinement.CollocationTranscription
    calls: list[dict] = []

    class FirstAcceptable(real):
        def solve(self, *args, **kwargs):
            result = super().solve(*args, **kwargs)
            calls.append({"warm_start": kwargs.get("warm_start", False), **self.options["ipopt"]})
            if not kwargs.get("warm_start"):
                result.status = Status.ACCEPTABLE
                result.stats = {**result.stats, "return_status": "Solved_To_Acceptable_Level"}
            return result

    monkeypatch.setattr(refinement, "CollocationTranscription", FirstAcceptable)
    res = solve_refined(opt, elements=10, max_passes=1)
    assert [c["warm_start"] for c in calls] == [False, True]
    assert calls[1]["acceptable_iter"] == 0 and 0 < calls[1]["max_cpu_time"] <= refinement.POLISH_CPU_S
    assert res.status == Status.OPTIMAL and res.verification.passed
    assert res.refinement[0]["continued"]["status"] == "optimal"
    assert res.final_time == pytest.approx(2.0, abs=1e-6)
