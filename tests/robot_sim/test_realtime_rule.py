"""The ``realtime`` marker's rule: on a machine loaded over its cores the real-time counts skip, saying why."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest

from .realtime import MachinePauses, busy_reason


@pytest.mark.parametrize("load, cores, busy", [(0.5, 2, False), (2.0, 2, False), (2.5, 2, True), (15.0, 2, True), (15.0, 16, False)])
def test_busy_is_a_load_over_the_cores(monkeypatch, load, cores, busy):
    monkeypatch.delenv("GTMODEL_REALTIME_TESTS", raising=False)
    monkeypatch.setattr(os, "getloadavg", lambda: (load, load, load))
    monkeypatch.setattr(os, "cpu_count", lambda: cores)
    reason = busy_reason()
    assert (reason is not None) == busy
    assert reason is None or (f"load {load:.1f} on {cores} cores" in reason and "pytest -m realtime" in reason)


def test_realtime_tests_are_out_of_the_default_run():
    """Independent: the marker expression of pyproject.toml's addopts, read as text."""
    import tomllib
    from pathlib import Path

    opts = tomllib.loads((Path(__file__).resolve().parents[2] / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
    assert "not realtime" in opts["addopts"] and any(m.startswith("realtime:") for m in opts["markers"])


def test_always_runs_them_whatever_the_load(monkeypatch):
    monkeypatch.setattr(os, "getloadavg", lambda: (50.0, 50.0, 50.0))
    monkeypatch.setenv("GTMODEL_REALTIME_TESTS", "always")
    assert busy_reason() is None


# ---- the machine's pauses: a reply late or missing only by them is the machine's ----

def _machine(pauses: dict, above: bool = True) -> MachinePauses:
    m = MachinePauses(None)
    m.pauses = {cpu: np.array(p, dtype=float).reshape(-1, 2) for cpu, p in pauses.items()}
    m.above_runtime = above
    return m


@pytest.mark.parametrize("pauses, above, window, explained", [
    ({0: [[0.0, 0.2]]}, True, (0.0, 0.2), True),  # the whole round trip paused
    ({0: [[0.0015, 0.25]]}, True, (0.0, 0.2), True),  # all but 1.5 ms of it (the budget is 2 ms)
    ({0: [[0.01, 0.2]]}, True, (0.0, 0.2), False),  # 10 ms with the machine running: the runtime's own
    ({0: [[0.0, 0.1]], 1: [[0.1, 0.2]]}, True, (0.0, 0.2), False),  # halves on two CPUs do not add up
    ({0: [[0.0, 0.1], [0.1005, 0.2]]}, True, (0.0, 0.2), True),  # two pauses of one CPU do
    ({0: [[0.0, 0.2]]}, False, (0.0, 0.2), False),  # canaries not above the runtime explain nothing
    ({0: [[0.0, 0.0045]]}, True, (0.0, 0.005), True),  # a reply 5 ms late, 4.5 ms of it paused
    ({0: []}, True, (0.0, 0.005), False),
])
def test_a_round_trip_is_the_machines_only_when_one_cpu_paused_all_but_the_budget(pauses, above, window, explained):
    assert _machine(pauses, above).explains(*window) == explained


def test_judge_splits_misses_and_late_rounds_by_the_pauses():
    m = _machine({0: [[10.0, 10.3], [30.0005, 30.0095]], 1: [[20.0005, 20.0045]]})
    rounds = [(1.0, 1.0001), (10.0, None), (15.0, None), (20.0, 20.005), (30.0, 30.0001)]
    # round 3: received at 20.0002, 4.5 ms late, paused all but 0.5 ms of [20.0002, 20.0047];
    # round 4: the reply in the peer's hands in 0.1 ms, yet the runtime's latency (ending after sendto) 9.5 ms from
    # 30.0001: judged over the runtime's window, paused all but 0.6 ms of it
    unexplained, explained = m.judge(rounds, late={3: (20.0002, 0.0045), 4: (30.0001, 0.0095)}, timeout=0.2, ignore=frozenset({2}))
    assert ([line.split(":")[0] for line in explained], unexplained) == (["round 1", "round 3", "round 4"], [])


@pytest.mark.parametrize("pauses, union, paused", [
    ({0: [[0.0, 0.1]], 1: [[0.1, 0.2]]}, False, 0.1),
    ({0: [[0.0, 0.1]], 1: [[0.1, 0.2]]}, True, 0.2),  # halves on two CPUs: some CPU paused all the time
    ({0: [[0.0, 0.15]], 1: [[0.1, 0.3]]}, True, 0.2),  # overlapping, clipped to the window
    ({0: [], 1: [[0.05, 0.06]]}, True, 0.01),
])
def test_overlap_per_cpu_and_over_all_cpus(pauses, union, paused):
    assert _machine(pauses).overlap(0.0, 0.2, union) == pytest.approx(paused)


def test_a_missed_reply_is_judged_over_all_cpus_a_late_one_per_cpu():
    m = _machine({0: [[1.0, 1.1], [2.0, 2.0025]], 1: [[1.1, 1.2], [2.0025, 2.005]]})
    rounds = [(1.0, None), (2.0, 2.0001)]
    unexplained, explained = m.judge(rounds, late={1: (2.0, 0.005)}, timeout=0.2)
    assert [line.split(":")[0] for line in explained] == ["round 0"] and [line.split(":")[0] for line in unexplained] == ["round 1"]


def test_judge_keeps_what_the_pauses_do_not_cover():
    m = _machine({0: [[40.003, 40.005]]})  # 2 ms of round 2's 5 ms: the runtime's own 3 ms remain
    rounds = [(1.0, 1.0001), (10.0, None), (40.0, 40.0001)]
    unexplained, explained = m.judge(rounds, late={2: (40.0, 0.005)}, timeout=0.2)
    assert explained == [] and unexplained == ["round 1: no reply over 200.0 ms, the machine paused 0.0 ms of it",
                                               "round 2: late over 5.0 ms, the machine paused 2.0 ms of it"]


@pytest.mark.parametrize("paused, busy", [(0.005, False), (0.01, False), (0.011, True), (0.09, True)])
def test_a_machine_paused_over_one_percent_of_the_run_is_too_busy(monkeypatch, paused, busy):
    monkeypatch.delenv("GTMODEL_REALTIME_TESTS", raising=False)
    m = _machine({0: [[1.0, 1.0 + 100.0 * paused / 2]], 1: [[2.0, 2.0 + 100.0 * paused]]})
    m.started, m.ended = 0.0, 100.0
    reason = m.busy_reason()
    assert (reason is not None) == busy and (reason is None or f"paused {100 * paused:.1f} % of the run" in reason)
    monkeypatch.setenv("GTMODEL_REALTIME_TESTS", "always")
    assert m.busy_reason() is None


def test_a_canary_sees_a_pause_it_was_given(tmp_path):
    """Independent: the canary is stopped by SIGSTOP for 80 ms (this test's clock); its record must cover that stop."""
    import signal

    with MachinePauses(tmp_path) as m:
        cpu, proc = m._procs[0]
        time.sleep(0.05)
        stopped = time.monotonic()
        proc.send_signal(signal.SIGSTOP)
        time.sleep(0.08)
        resumed = time.monotonic()
        proc.send_signal(signal.SIGCONT)
        time.sleep(0.05)
    p = m.pauses[cpu]
    assert m.overlap(stopped + 0.002, resumed - 0.002) >= resumed - stopped - 0.004 - 1e-9
    assert np.any((p[:, 0] <= stopped + 0.002) & (p[:, 1] >= resumed))
