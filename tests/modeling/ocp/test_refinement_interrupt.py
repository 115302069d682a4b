"""Ctrl-C during a mesh refinement keeps its last verified pass (:mod:`gtmodel.modeling.ocp.refinement_interrupt`, issue 67).

Independent reference: a stand-in refinement whose passes are written here (which verified, which
did not), interrupted at a chosen pass; the real one is interrupted in a subprocess by
``tests/problems/test_results.py``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import SimpleNamespace

import pytest

from gtmodel import _signals
from gtmodel.modeling.ocp.refinement_interrupt import keeps_verified_pass, recorded
from gtmodel.status import Status


@dataclass
class _Pass:
    status: Status
    passed: bool
    verification: SimpleNamespace = field(init=False)
    refinement: list | None = None
    refinement_stop: str | None = None
    solve_time: float | None = None

    def __post_init__(self):
        self.verification = SimpleNamespace(passed=self.passed, time_s=0.0, cpu_s=0.0)


def _refinement(passes, stop_with):
    """A stand-in ``solve_refined``: records ``passes`` one by one, then raises ``stop_with``; called with ``start``
    and one pass (the kept pass's re-check), it returns ``start``."""

    @keeps_verified_pass
    def solve_refined(optimization, elements=50, max_passes=10, start=None):
        history, done = recorded("history"), recorded("passes")
        if start is not None:
            return start
        for k, p in enumerate(passes):
            history.append({"pass": k + 1, "solve_time": 1.0, "verification_time": 0.5, "verification_cpu_time": 0.25})
            done.append(p)
        raise stop_with

    return solve_refined


OPTIMIZATION = SimpleNamespace(model=SimpleNamespace(name="m"))
KEPT = {
    "last_verified": ([(Status.CHECK_FAILED, False), (Status.OPTIMAL, True), (Status.OPTIMAL, True)], 3),
    "a_later_pass_unverified": ([(Status.OPTIMAL, True), (Status.CHECK_FAILED, False)], 1),
    "optimal_before_acceptable": ([(Status.OPTIMAL, True), (Status.ACCEPTABLE, True)], 1),
}


@pytest.mark.parametrize("passes, k", KEPT.values(), ids=KEPT)
def test_a_signal_returns_the_last_verified_pass_with_the_whole_history(passes, k):
    made = [_Pass(s, v) for s, v in passes]
    result = _refinement(made, KeyboardInterrupt())(OPTIMIZATION, elements=50)
    assert result.status == made[k - 1].status and result.verification.passed
    assert result.refinement_stop == f"interrupted by the user during pass {len(made) + 1}; returned pass {k} of {len(made)}"
    assert [e.get("returned", False) for e in result.refinement] == [j == k - 1 for j in range(len(made))]
    assert (result.solve_time, result.verification.time_s) == (1.0 * len(made), 0.5 * len(made))


NOT_KEPT = {
    "no_pass_yet": ([], KeyboardInterrupt),
    "none_verified": ([(Status.CHECK_FAILED, False), (Status.ERROR, False)], KeyboardInterrupt),
    "another_error": ([(Status.OPTIMAL, True)], NotImplementedError),
}


@pytest.mark.parametrize("passes, exc", NOT_KEPT.values(), ids=NOT_KEPT)
def test_without_a_verified_pass_or_a_signal_the_exception_goes_on(passes, exc):
    _signals.reset()
    with pytest.raises(exc):
        _refinement([_Pass(s, v) for s, v in passes], exc())(OPTIMIZATION)


def test_casadis_exception_for_a_signal_counts_as_the_signal():
    try:
        _signals._state.count += 1  # the handler counted it while CasADi held it
        result = _refinement([_Pass(Status.OPTIMAL, True)], SystemError("CasADi: interrupted"))(OPTIMIZATION)
    finally:
        _signals.reset()
    assert result.refinement_stop == "interrupted by the user during pass 2; returned pass 1 of 1"
