"""The verdict of a loop controller's closed-loop check (gtmodel.problems.loop_check.LoopCheck.failures).

References: closed loops built by hand on the plant x_{k+1} = a x_k + u_k (closed forms: a = 1 bounded,
a = 10 runaway), so that each reason of a failure is present or absent by construction; the declared
thresholds ([check] max_ratio, max_step_time) against a ratio and step times known to be above them.
"""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import casadi as ca
import numpy as np
import pytest

from gtmodel.estimation.closed_loop.controller_loop import run_controller_loop
from gtmodel.control.bounds import bound_report
from gtmodel.codegen.check.closed_loop import plant_bounds, reference_states_at_bounds
from gtmodel.problems.loop_check import LoopCheck, reference_at_bounds

x, u, p = ca.SX.sym("x"), ca.SX.sym("u"), ca.SX.sym("p", 0)
T = np.arange(8.0)


def _run(a, law):
    step = ca.Function("step", [x, u, p], [a * x + u])
    return run_controller_loop(law, step, [1.0], T, np.ones((T.size, 1)), [-1.0], [1.0], delay=0)


@pytest.mark.parametrize("closed, feedforward, reasons", [
    (_run(1.0, lambda t, y: (0, [0.0])), _run(1.0, lambda t, y: (0, [0.5])), []),
    (_run(10.0, lambda t, y: (0, [0.0])), _run(10.0, lambda t, y: (0, [0.0])), ["the plant diverged"]),  # no ratio of runaway runs
    (_run(1.0, lambda t, y: (0, [0.0])), _run(10.0, lambda t, y: (0, [0.0])), ["the plant diverged"]),
    (_run(1.0, lambda t, y: (6, [2.0])), _run(1.0, lambda t, y: (0, [1.0])), ["8 input bound violations", "8 failed steps", "not below 1"]),
], ids=["passes", "both run away", "feedforward runs away (ratio ~1e-7)", "bounds and failed steps"])
def test_failures_name_each_reason(closed, feedforward, reasons):
    check = LoopCheck(closed=closed, feedforward=feedforward, memory_bytes=0, work_bytes=0)
    found = check.failures()
    assert len(found) == len(reasons) and all(r in f for r, f in zip(reasons, found))


PASSING = (_run(1.0, lambda t, y: (0, [0.1])), _run(1.0, lambda t, y: (0, [0.5])))  # errors 0.1 k and 0.5 k: ratio 0.2


@pytest.mark.parametrize("limits, reasons", [
    ({}, []),
    ({"max_ratio": 1e-9}, ["not below 1e-09 ([check] max_ratio)"]),
    ({"step_budget_s": 0.0}, ["step time"]),
    ({"max_ratio": 1e-9, "step_budget_s": 0.0}, ["max_ratio", "above the budget 0.0 us"]),
], ids=["defaults", "ratio above the declared", "slower than the budget", "both"])
def test_declared_limits_fail_the_check(limits, reasons):
    check = LoopCheck(closed=PASSING[0], feedforward=PASSING[1], memory_bytes=0, work_bytes=0, **limits)
    found = check.failures()
    assert len(found) == len(reasons) and all(r in f for r, f in zip(reasons, found))


def test_step_p99_is_the_summary_figure():
    check = LoopCheck(closed=PASSING[0], feedforward=PASSING[1], memory_bytes=0, work_bytes=0)
    assert check.step_p99_s == PASSING[0].step_times()["p99"] > 0.0


def test_ratio_is_the_closed_form():
    check = LoopCheck(closed=PASSING[0], feedforward=PASSING[1], memory_bytes=0, work_bytes=0, max_ratio=0.2)
    assert check.ratio_to_feedforward == pytest.approx(0.2, rel=1e-12)
    assert any("not below 0.2" in f for f in check.failures())


@pytest.mark.parametrize("u_ref, lb, ub, expected", [
    ([[0.0], [1.0], [-1.0], [0.5]], [-1.0], [1.0], 0.5),  # two of four samples at a bound
    ([[0.9995], [0.0]], [-1.0], [1.0], 0.5),  # within 1e-3 of the range 2
    ([[5.0, 0.0], [0.0, 0.0]], [-np.inf, -1.0], [5.0, 1.0], 0.5),  # a one-sided bound: within 1e-3 (1 + 5)
    ([[3.0], [4.0]], [-np.inf], [np.inf], 0.0),  # no bounds
], ids=["two of four", "within tolerance", "one-sided", "unbounded"])
def test_reference_at_bounds_counts_samples(u_ref, lb, ub, expected):
    assert reference_at_bounds(np.array(u_ref), np.array(lb), np.array(ub)) == expected


def test_summary_notes_a_reference_at_its_bounds():
    check = LoopCheck(closed=PASSING[0], feedforward=PASSING[1], memory_bytes=0, work_bytes=0, reference_at_bounds=0.6)
    assert any("at an input bound in 60 %" in line for line in check.summary_lines()) and check.failures() == []
    quiet = LoopCheck(closed=PASSING[0], feedforward=PASSING[1], memory_bytes=0, work_bytes=0, reference_at_bounds=0.1)
    assert not any("input bound in" in line for line in quiet.summary_lines())


def test_summary_notes_a_reference_riding_a_state_bound():
    # a minimum-time plan at its current limit: the feedback has no room on that state (held-out drives, issue 49)
    x_ref = np.array([[0.0, 5.0], [1.0, 5.0], [2.0, 4.0], [3.0, 4.999]])
    setup = SimpleNamespace(x_ref=x_ref, names=(["phi", "i"], ["v"], []),
                            bounds=SimpleNamespace(lb={"i": -5.0, "phi": -10.0}, ub={"i": 5.0, "phi": 10.0}))
    shares = reference_states_at_bounds(setup)
    assert shares == {"i": 0.75}  # 5.0, 5.0 and 4.999 (within 1e-3 of 5): three of four samples; phi never at its bound
    check = LoopCheck(closed=PASSING[0], feedforward=PASSING[1], memory_bytes=0, work_bytes=0, states_at_bounds=shares)
    assert any(line.startswith("note: the reference rides the declared bound of i in 75 % of the samples")
               for line in check.summary_lines()) and check.failures() == []


def test_a_state_bound_exceeded_between_the_samples_fails_the_check():
    # x_k = 1 + 0.1 k at the samples (max 1.7 of a 1.71 bound: held); a state inside period 3 at 1.8 (by hand) exceeds it
    closed = _run(1.0, lambda t, y: (0, [0.1]))
    closed.x_interior = np.zeros((closed.t.size, 1, 1)) + 1.0
    closed.x_interior[3, 0, 0] = 1.8
    setup = SimpleNamespace(bounds=SimpleNamespace(lb={"x": -np.inf}, ub={"x": 1.71}), names=(["x"], ["u"], []), loop={},
                            outputs=None, plant_p=np.zeros(0))
    (at_samples,) = plant_bounds(setup, closed)
    (between,) = plant_bounds(setup, closed, between=True)
    assert not at_samples.beyond_tolerance and between.value == pytest.approx(1.8) and between.beyond_tolerance
    assert plant_bounds(setup, dataclasses.replace(closed, x_interior=None), between=True) == []
    check = LoopCheck(closed=closed, feedforward=PASSING[1], memory_bytes=0, work_bytes=0, bounds=[at_samples], bounds_between=[between])
    (why,) = check.failures()
    assert why.startswith("x beyond its bound between the samples by 0.09 (5.26 % > 1 %") and "has no constraint rows" in why
    # a tracking controller that holds the state bounds itself: the remedy names its back-off, not 'no constraint rows'
    (why_limited,) = dataclasses.replace(check, state_limits=True).failures()
    assert "backed off by its measured one-period prediction error" in why_limited and "no constraint rows" not in why_limited
    when = closed.t[3] + 0.5 * (closed.t[4] - closed.t[3])  # the one interior state of period 3: half-way through it
    assert f"  between the samples (the plant step's substeps): x in [-inf, 1.71]: 1.8 at t = {when:.4g} s, limit 1.71, +5.26 % " \
           "(beyond 1 %; excess 0.09, 1 samples beyond 1 %)" in check.summary_lines()


def test_a_diverged_plant_prints_no_ratio():
    # both run away (a = 10: x_k = 10^k): the summary names the divergence and prints no ratio that could read as passing
    check = LoopCheck(closed=_run(10.0, lambda t, y: (0, [0.0])), feedforward=_run(10.0, lambda t, y: (0, [0.0])),
                      memory_bytes=0, work_bytes=0, max_ratio=0.5)
    ratio = [line for line in check.summary_lines() if line.startswith("RMS ratio")]
    assert len(ratio) == 1 and "none (the plant diverged" in ratio[0] and "below the limit" not in ratio[0]


def test_declared_bounds_beyond_one_percent_fail_per_variable():
    # x_k = 1 + 0.1 k (a = 1, u = 0.1): the largest state 1.7 at k = 7; bounds by hand: x <= 1.69 (0.6 % excess: held),
    # x <= 1.5 (13.3 % excess, samples k = 6, 7 beyond 1.515), u <= 0.1 (held exactly)
    closed = _run(1.0, lambda t, y: (0, [0.1]))
    values = {"x": closed.x[:, 0], "u": closed.u[:, 0]}
    lenient, strict = (bound_report(values, {"x": -np.inf, "u": -1.0}, {"x": hi, "u": 0.1}) for hi in (1.69, 1.5))
    assert [b.beyond_tolerance for b in lenient] == [False, False] and lenient[0].relative == pytest.approx(0.01 / 1.69, rel=1e-9)
    assert strict[0].samples == 2 and strict[0].excess == pytest.approx(0.2, rel=1e-9) and strict[0].value == pytest.approx(1.7)
    check = LoopCheck(closed=closed, feedforward=PASSING[1], memory_bytes=0, work_bytes=0, bounds=strict)
    assert [f for f in check.failures() if f.startswith("x beyond its bound by 0.2 (13.3 %")]
    assert any("x in [-inf, 1.5]: 1.7, limit 1.5, +13.3 % (beyond 1 %; excess 0.2, 2 samples" in line  # no times given: none printed
               for line in check.summary_lines())


def test_notes_head_the_summary():
    check = LoopCheck(closed=PASSING[0], feedforward=PASSING[1], memory_bytes=0, work_bytes=0, notes=["reference NOT verified (x)"])
    assert check.summary_lines()[0] == "notes: reference NOT verified (x)"


def test_a_ratio_that_fails_names_the_bounds_the_controller_rode():
    # x_k = 1 + 0.1 k: the largest state 1.7 at k = 7 against x <= 1.71 (0.58 % inside: binding, by hand), and the ratio
    # 0.2 above a limit of 0.1: the failure says which bound held the controller back, with its figures
    closed, feedforward = PASSING
    (bound,) = bound_report({"x": closed.x[:, 0]}, {"x": -np.inf}, {"x": 1.71}, times=closed.t)
    check = LoopCheck(closed=closed, feedforward=feedforward, memory_bytes=0, work_bytes=0, max_ratio=0.1, bounds=[bound])
    (why,) = check.failures()
    assert why.endswith(f"; the bounds it rode: x 1.7 of 1.71 (-0.58 %) at t = {closed.t[7]:.4g} s")


def test_the_estimates_are_printed_written_and_named_where_the_ratio_fails():
    # an MPC's input-disturbance estimate as closed_loop_check reads it from the memory (memory_estimates): a summary
    # line, summary.json's "estimates", and the ratio's failure says what the controller compensated
    closed, feedforward = PASSING
    est = {"kind": "input disturbance", "name": "src.v", "largest": -1.5, "time": 0.1, "last": -1.2, "relative": 0.03125}
    check = LoopCheck(closed=closed, feedforward=feedforward, memory_bytes=0, work_bytes=0, max_ratio=0.1, label="MPC", estimates=[est])
    text = "input disturbance src.v: largest -1.5 at t = 0.1 s (3.12 % of its range), last -1.2"
    assert f"  {text}" in check.summary_lines() and "the MPC's estimates (its memory after each period):" in check.summary_lines()
    assert check.failures()[0].endswith(f"; its estimates: {text}")
    assert check.to_dict()["estimates"] == [est]


@pytest.mark.parametrize("law, expected", [
    (lambda t, y: (0, [0.5 * (-1) ** round(t / (T[1] - T[0]))]), 1.0),  # +-0.5 of a [-1, 1] input each period: every period turns back
    (lambda t, y: (0, [0.1]), 0.0),                                      # a steady input: none
], ids=["alternating", "steady"])
def test_an_input_that_turns_back_every_period_is_named(law, expected):
    # the applied input u_k = 0.5 (-1)^k (by hand: each step of 1.0 is half the bounds' range, beyond SWING, and reverses)
    closed = _run(1.0, law)
    check = LoopCheck(closed=closed, feedforward=PASSING[1], memory_bytes=0, work_bytes=0, max_ratio=1e-9)
    assert check.alternation == pytest.approx(expected)
    assert ("limit cycle at half the sampling frequency" in check.failures()[0]) == (expected > 0)
