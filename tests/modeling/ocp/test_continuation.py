"""Step-length control of the smoothing continuation (:func:`gtmodel.modeling.ocp.continuation.narrowed_steps`).

Independent check: the factors inserted are the geometric middles written out here (``sqrt(10) = 3.1623``,
``sqrt(10 * 3.1623) = 5.6234``), with solvers stubbed so that a step from factor ``a`` to ``b`` solves exactly when
``a / b`` is at most a given ratio: the case of a held-out arm whose declared widths failed from x10 (warm, then cold)
and solved from x3.16 (the full solve is in ``docs/own_model.md``; 220 CPU-s, too slow for a test).
"""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from gtmodel.modeling.ocp.continuation import MAX_INSERTED_STEPS, narrowed_steps

WIDTH = 1e-3


def _problem():
    return SimpleNamespace(model=SimpleNamespace(name="stub", smoothing={"friction.smoothing": WIDTH}), parameters={},
                           free_parameters={})


def _result(factor, ok, verified=False, failure="infeasible", message="Infeasible_Problem_Detected"):
    return SimpleNamespace(factor=factor, status="optimal" if ok else failure, objective=factor if ok else float("nan"),
                           iterations=10, verification=object() if verified else None, message="Solve_Succeeded" if ok else message,
                           stats={})


def _solvers(reach):
    """Stubs: a step or the declared solve from factor ``a`` to ``b`` succeeds when ``a / b <= reach``."""
    calls = []

    def step(parameters, start):
        factor = parameters["friction.smoothing"] / WIDTH
        calls.append(("step", round(factor, 4)))
        return _result(factor, start.factor / factor <= reach * (1 + 1e-12))

    def declared(start):
        calls.append(("declared", round(start.factor, 4)))
        ok = start.factor <= reach * (1 + 1e-12)
        return _result(1.0, ok, verified=ok)

    return step, declared, calls


def _record(last):
    return {"declared": {"friction.smoothing": WIDTH}, "steps": [{"factor": 100.0, "status": "optimal"},
                                                                 {"factor": last, "status": "optimal"}]}


def test_a_declared_solve_that_failed_from_x10_is_reached_through_the_middle_step():
    step, declared, calls = _solvers(reach=4.0)
    record = _record(10.0)
    start, result = narrowed_steps(_problem(), step, declared, _result(10.0, True), record, _result(1.0, False))
    assert calls == [("step", 3.1623), ("declared", 3.1623)]
    assert result.verification is not None and start.factor == pytest.approx(10 ** 0.5)
    assert record["steps"][-1]["inserted"] is True and record["steps"][-1]["factor"] == pytest.approx(10 ** 0.5)


def test_a_middle_step_that_fails_halves_the_step_towards_the_last_that_solved():
    # from x10: x3.16 is a step of 3.16, beyond reach 2; x5.62 (1.78 from x10) solves, then x2.37 (2.37 from x5.62) fails
    step, declared, calls = _solvers(reach=2.0)
    record = _record(10.0)
    start, result = narrowed_steps(_problem(), step, declared, _result(10.0, True), record, _result(1.0, False))
    assert calls[:3] == [("step", 3.1623), ("step", 5.6234), ("declared", 5.6234)]
    assert len([c for c in calls if c[0] == "step"]) == MAX_INSERTED_STEPS
    assert result.verification is None and start.factor == pytest.approx(10 ** 0.75)  # the failure kept, not hidden


@pytest.mark.parametrize("start, failed", [(None, _result(1.0, False)), (_result(10.0, True), _result(1.0, True, verified=True))])
def test_nothing_is_inserted_without_a_start_or_after_a_solution(start, failed):
    step, declared, calls = _solvers(reach=4.0)
    out = narrowed_steps(_problem(), step, declared, start, _record(10.0), failed)
    assert calls == [] and out == (start, failed)


@pytest.mark.parametrize("failure, message", [
    ("error", "Error_In_Step_Computation"),  # a singular NLP (an input inert beyond a Limiter): no matter of the step
    ("max_iterations", "Maximum_Iterations_Exceeded"),
])
def test_a_failure_that_is_no_matter_of_the_step_inserts_nothing(failure, message):
    step, declared, calls = _solvers(reach=4.0)
    failed = _result(1.0, False, failure=failure, message=message)
    out = narrowed_steps(_problem(), step, declared, _result(10.0, True), _record(10.0), failed)
    assert calls == [] and out[1] is failed


def test_a_restoration_failure_is_a_start_too_far():
    from gtmodel.modeling.ocp.continuation import start_too_far

    assert start_too_far(_result(1.0, False, failure="error", message="Restoration_Failed: IPOPT's feasibility restoration ..."))
