"""Phase times (gtmodel._timing): sums by hand-counted tables, a busy loop's CPU time against its wall time."""

from __future__ import annotations

import time

import pytest

from gtmodel._timing import PHASES, add_phase, merge_phases, ordered_phases, phase_sum, timed


def test_timed_adds_wall_and_cpu_of_a_busy_block():
    phases: dict = {}
    with timed(phases, "solve"):
        # busy until both clocks passed 20 ms: the process's CPU time counts its other threads too
        # (a test worker's), so it can run ahead of the wall clock
        end_cpu, end_wall = time.process_time() + 0.02, time.perf_counter() + 0.02
        while time.process_time() < end_cpu or time.perf_counter() < end_wall:
            pass
    with pytest.raises(ZeroDivisionError), timed(phases, "solve"):  # a block that raises is timed too
        1 / 0
    assert phases["solve"]["cpu_s"] >= 0.02 and phases["solve"]["wall_s"] >= 0.02


def test_phases_merge_and_sum_as_counted_by_hand():
    phases: dict = {}
    add_phase(phases, "build", 1.0, 0.5)
    merge_phases(phases, {"build": {"wall_s": 2.0, "cpu_s": 1.0}, "writing": {"wall_s": 0.25, "cpu_s": 0.125}})
    assert phases == {"build": {"wall_s": 3.0, "cpu_s": 1.5}, "writing": {"wall_s": 0.25, "cpu_s": 0.125}}
    assert phase_sum({**phases, "total": {"wall_s": 99.0, "cpu_s": 99.0}}) == {"wall_s": 3.25, "cpu_s": 1.625}


def test_ordered_phases_follow_the_run_and_end_with_their_total():
    out = ordered_phases({"writing": {"wall_s": 1.0, "cpu_s": 1.0}, "custom": {"wall_s": 2.0, "cpu_s": 0.0},
                          "load": {"wall_s": 0.5, "cpu_s": -1e-9}})
    assert list(out) == ["load", "writing", "custom", "total"]
    assert out["load"]["cpu_s"] == 0.0  # never below zero (a difference of two clocks)
    assert out["total"] == {"wall_s": 3.5, "cpu_s": 1.0}
    assert set(PHASES) >= {"load", "build", "guess", "solve", "verification", "refinement", "writing", "total"}
