"""A benchmark prints no ratio against a peer that did not reach its optimum (issue 67, item 3).

Fake peer records stand for the peers (rockit, acados): nothing here runs a peer or a long benchmark.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from .conftest import benchmark_module

ROOT = Path(__file__).resolve().parents[1]
#: rockit-meco 0.6.7's record on dc_motor_min_energy before its peer eliminated the algebraic variables.
FAILED = {"objective": float("nan"), "iterations": -1, "whole_call_s": 9.8, "whole_call_cpu_s": 9.42,
          "status": "failed: Infeasible_Problem_Detected"}
SOLVED = {"objective": 0.2673567892, "iterations": 6, "whole_call_s": 5.1, "whole_call_cpu_s": 4.9, "status": "optimal"}
BENCH = {"sign": 1.0, "published": 0.2667243572, "source": "closed form"}


@pytest.fixture(scope="module")
def suite():
    """benchmarks/bench_ocp_suite.py as a module."""
    with benchmark_module("bench_ocp_suite") as module:
        yield module


@pytest.fixture(scope="module")
def mpc():
    """benchmarks/bench_mpc.py as a module."""
    with benchmark_module("bench_mpc") as module:
        yield module


def test_a_failed_rockit_call_gives_no_ratio(suite):
    """One failed call among the repeats: no ratio, wall or CPU, and the reason names the peer and its status."""
    cols = suite.peer_columns([SOLVED, FAILED, SOLVED], BENCH, whole=0.3, whole_cpu=0.28)
    assert cols["ratio_to_rockit"] is None and cols["ratio_to_rockit_cpu"] is None
    assert cols["peer_failed"] == "rockit: Infeasible_Problem_Detected, no ratio"
    json.dumps(cols)  # null in --json


@pytest.mark.parametrize("record, reason", [
    ({**SOLVED, "objective": float("nan")}, "rockit: optimal but its objective is nan, no ratio"),
    ({**SOLVED, "status": "Maximum_Iterations_Exceeded"}, "rockit: Maximum_Iterations_Exceeded, no ratio"),
    ({**SOLVED, "status": "not translated: a variable at the interior time 0.5 s"},
     "rockit: not translated: a variable at the interior time 0.5 s, no ratio"),
])
def test_other_failures_give_no_ratio(suite, record, reason):
    """A NaN objective, a status other than optimal, a problem not translated: each its reason."""
    assert suite.peer_failure([record]) == reason


def test_a_converged_peer_gives_the_ratio_of_the_medians(suite):
    cols = suite.peer_columns([SOLVED, {**SOLVED, "whole_call_s": 4.9, "whole_call_cpu_s": 4.7}], BENCH, whole=0.5, whole_cpu=0.48)
    assert cols["peer_failed"] is None
    assert cols["ratio_to_rockit"] == pytest.approx(0.5 / 5.0) and cols["ratio_to_rockit_cpu"] == pytest.approx(0.48 / 4.8)


def test_the_printed_rows_say_why_and_print_no_number(suite, capsys):
    """The main table's row and the time table's: ``-`` in both ratio columns and the reason at the end."""
    row = {"name": "dc_motor_min_energy", "published": 0.2667243572, "objective": 0.2667341, "relative_error": 3.7e-5,
           "iterations": 6, "verified": True, "max_scaled_deviation": 3.5e-3, "solve_s": 0.25, "verification_s": 0.05,
           "whole_call_s": 0.7, "solve_cpu_s": 0.25, "verification_cpu_s": 0.045, "whole_call_over_solve_cpu": 2.8,
           **suite.peer_columns([FAILED], BENCH, whole=0.7, whole_cpu=0.7)}
    suite.print_row(row)
    suite.print_time_table([row])
    lines = [line for line in capsys.readouterr().out.splitlines() if line.startswith("dc_motor_min_energy")]
    assert len(lines) == 2
    # 0.071 = 0.7 / 9.8: the ratio a failed peer used to get
    assert [line for line in lines if not line.endswith("rockit: Infeasible_Problem_Detected, no ratio") or "0.071" in line] == []


def test_run_one_against_a_failed_peer(suite, monkeypatch):
    """The whole row of the smallest benchmark with a fake failed rockit (gtmodel's own solve is real: about 1 s)."""
    monkeypatch.setattr(suite, "rockit_or_failure", lambda decl, mesh=None: dict(FAILED))
    row = suite.run_one(ROOT / "problems" / "benchmarks" / "double_integrator_min_time.toml", cli=False, rockit=True)
    assert row["ratio_to_rockit"] is None and row["ratio_to_rockit_cpu"] is None
    assert row["peer_failed"] == "rockit: Infeasible_Problem_Detected, no ratio"
    assert row["status"] == "optimal"


def _acados(cpu: float, failed: int = 0) -> dict:
    """A fake acados figure of :func:`bench_mpc.acados_finish` for one QP solver."""
    return {"cpu_step_median_s": cpu, "cpu_step_p99_s": 2 * cpu, "cpu_step_max_s": 3 * cpu, "tracking_rms": 1e-3,
            "first_control_rel_diff": 1e-9, "first_control_range_diff": 1e-10, "sqp_first_control_rel_diff": 1e-9, "agreement_states": 5,
            "nearest_first_control_rel_diff": cpu * 1e-3, "nearest_first_control_range_diff": cpu * 1e-4,
            "failed_steps": failed, "diverged": False}


ROW = {"horizon": 20, "cpu_step_median_s": 150e-6, "cpu_step_p99_s": 400e-6, "tracking_rms": 1.1e-3}


def test_the_acados_headline_is_its_fastest_converging_configuration(mpc):
    """qpOASES faster than the default HPIPM: the headline ratio is to qpOASES, the default's beside it."""
    keys = mpc.acados_keys(ROW, {"PARTIAL_CONDENSING_HPIPM": _acados(260e-6), "FULL_CONDENSING_QPOASES": _acados(140e-6)})
    assert keys["acados_config"].startswith("SQP_RTI FULL_CONDENSING_QPOASES")
    assert keys["ratio_to_acados_median"] == pytest.approx(150 / 140)
    assert keys["acados_default_config"].startswith("SQP_RTI PARTIAL_CONDENSING_HPIPM")
    assert keys["ratio_to_acados_default_median"] == pytest.approx(150 / 260)
    assert keys["peer_failed"] is None
    # issue 65's figures at the least p99 (qpOASES here): the ratio and its agreement, relative and over the input range
    assert keys["acados_best_p99_ratio"] == pytest.approx(400 / 280)
    assert (keys["acados_best_first_control_rel_diff"], keys["acados_best_first_control_range_diff"]) == (1e-9, 1e-10)
    # and the agreement judged: that configuration's against the nearer of gtmodel's converged inputs (qpOASES' fake ones)
    assert (keys["first_control_rel_diff"], keys["first_control_range_diff"]) == pytest.approx((140e-9, 140e-10), rel=1e-12)


def test_an_acados_configuration_with_failed_steps_is_not_the_headline(mpc):
    """The faster qpOASES failed steps: the headline is the default HPIPM; both failed: no ratio, and why."""
    keys = mpc.acados_keys(ROW, {"PARTIAL_CONDENSING_HPIPM": _acados(260e-6), "FULL_CONDENSING_QPOASES": _acados(140e-6, failed=3)})
    assert keys["acados_config"].startswith("SQP_RTI PARTIAL_CONDENSING_HPIPM")
    assert keys["ratio_to_acados_median"] == pytest.approx(150 / 260)
    both = mpc.acados_keys(ROW, {"PARTIAL_CONDENSING_HPIPM": _acados(260e-6, failed=1), "FULL_CONDENSING_QPOASES": _acados(140e-6, failed=3)})
    assert both["ratio_to_acados_median"] is None and both["ratio_to_acados_p99"] is None
    assert both["peer_failed"].startswith("acados: no configuration converged")


@pytest.fixture(scope="module")
def solve_bench():
    """benchmarks/bench_solve.py as a module."""
    with benchmark_module("bench_solve") as module:
        yield module


def _acados_solve(cpu: float, status: int = 0) -> dict:
    """A fake answer of the acados peer's ``--serve`` mode (one solve)."""
    return {"solve_cpu_s": cpu, "time_tot_s": cpu, "iterations": 65, "status": status, "final_time_s": 0.671593,
            "final_state_violation": 0.0, "config": "acados 0.2.2 SQP (fake)"}


def test_bench_solve_alternates_acados_with_gtmodel_in_the_same_rounds(solve_bench, monkeypatch):
    """Each round: gtmodel (IPOPT, fatrop), then acados, then the Opti peers; never acados in a phase of its own."""
    calls = []

    class Server:
        def solve(self):
            calls.append("acados")
            return _acados_solve(0.36)

    monkeypatch.setattr(solve_bench, "ours", lambda decl: calls.append(f"gtmodel {decl}") or (0.2, 0.675, 49, "optimal", 0.24, None, {}))
    monkeypatch.setattr(solve_bench, "peer_opti", lambda decl, expand=False: calls.append(f"opti {expand}") or (1.0, 0.675, 69, "ok", 0.9))
    mine, fruns, aruns, fast, peer = solve_bench.solve_rounds("ipopt", "fatrop", Server(), 3)
    assert calls == ["gtmodel ipopt", "gtmodel fatrop", "acados", "opti True", "opti False"] * 3
    assert len(mine) == len(fruns) == len(aruns) == len(fast) == len(peer) == 3


def test_bench_solve_ratio_is_like_with_like(solve_bench):
    """The ratio of medians over the same rounds, the faster configuration named; a failed acados round: no ratio."""
    runs = [_acados_solve(0.36), _acados_solve(0.40), _acados_solve(0.30)]
    summary = solve_bench.acados_summary(runs, 0.6754484)
    assert summary["acados_solve_cpu_s"] == pytest.approx(0.36) and summary["acados_failed"] is None
    ratio = solve_bench.ratio_to_acados({"IPOPT": [0.24, 0.26, 0.22], "fatrop": [0.21, 0.25, 0.20]},
                                        summary["acados_solve_cpu_s_all"], summary["acados_failed"])
    assert ratio["ratio_cpu_to_acados_config"] == "fatrop" and ratio["ratio_cpu_to_acados"] == pytest.approx(0.21 / 0.36)
    assert ratio["ratio_cpu_to_acados_rounds"] == pytest.approx([0.21 / 0.36, 0.25 / 0.40, 0.20 / 0.30])
    failed = solve_bench.acados_summary([_acados_solve(0.36), _acados_solve(0.5, status=4)], 0.6754484)
    assert failed["acados_failed"] == "acados: status 4 in 1 of 2 rounds, no ratio"
    none = solve_bench.ratio_to_acados({"IPOPT": [0.24, 0.26]}, failed["acados_solve_cpu_s_all"], failed["acados_failed"])
    assert none["ratio_cpu_to_acados"] is None and none["peer_failed"] == failed["acados_failed"]
