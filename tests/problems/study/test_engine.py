"""The study engine: case keys, resume, --retry-failed, failing cases as rows, the same
table in this process and on a local Dask cluster, (Ctrl-C: test_study_interrupt.py; a
real cluster: test_study_cluster.py).

Independent references: the case folders' summary.json files (the table must equal
them), a second run of the same study (the keys must match), a run in this process
against a run on a local cluster (the same numbers).
"""

from __future__ import annotations

import json
import time
import shutil

import pandas as pd
import pytest

from gtmodel.cli import EXIT_BAD_INPUT, EXIT_NOT_OPTIMAL, main
from gtmodel.errors import InputError
from gtmodel.problems.study.cases import case_key
from gtmodel.problems import get_kind
from gtmodel.problems.study.engine import run_study
from gtmodel.problems.study.progress import StudyProgress

from .study_fixtures import SMALL_DESIGN, write_study

COMPARED = ["limits.force", "method.grid", "case", "key", "folder", "status", "final_time_s", "energy"]


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    folder = tmp_path_factory.mktemp("small")
    study = write_study(folder, SMALL_DESIGN)
    return study, run_study(study, folder / "out", workers=1)


def test_table_has_one_row_per_case_with_statuses(small):
    _, outcome = small
    t = outcome.table
    assert list(t.columns[:7]) == ["limits.force", "method.grid", "case", "key", "folder", "status", "wall_s"]
    assert len(t) == 6 and t["key"].is_unique
    assert t["status"].tolist() == ["infeasible"] * 2 + ["optimal"] * 4
    assert outcome.summary["counts"] == {"infeasible": 2, "optimal": 4}
    assert outcome.status == "infeasible" and outcome.exit_code == EXIT_NOT_OPTIMAL  # the worst case, as gtmodel solve


def test_parquet_csv_and_case_folders_agree(small):
    _, outcome = small
    parquet = pd.read_parquet(outcome.out / "table.parquet")
    csv = pd.read_csv(outcome.out / "table.csv")
    assert parquet.equals(outcome.table) and len(csv) == 6
    summaries = [json.loads((outcome.out / f / "summary.json").read_text()) for f in parquet["folder"]]
    assert [s["study"]["key"] for s in summaries] == parquet["key"].tolist()
    assert [s["status"] for s in summaries] == parquet["status"].tolist()
    assert [s["final_time_s"] for s in summaries] == [None if pd.isna(v) else v for v in parquet["final_time_s"]]


def test_rerun_runs_nothing(small):
    study, outcome = small
    ran = []
    again = run_study(study, outcome.out, workers=1, on_case=ran.append)
    assert ran == [] and again.summary["skipped"] == 6
    assert again.table.drop(columns="wall_s").equals(outcome.table.drop(columns="wall_s"))


def test_a_rerun_that_solves_nothing_keeps_the_timing_of_the_run_that_did(small, tmp_path):
    """Defect (h): a no-op rerun overwrote the first run's timings (``workers 0``)."""
    study, outcome = small
    out = tmp_path / "copy"
    shutil.copytree(outcome.out, out)
    again = run_study(study, out, workers=1)
    kept = {k: outcome.summary[k] for k in ("workers", "scheduler", "timing")}
    assert (again.summary["run_now"], {k: again.summary[k] for k in kept}) == (0, kept)


def test_deleting_one_case_folder_reruns_only_it(small, tmp_path):
    study, outcome = small
    out = tmp_path / "copy"
    shutil.copytree(outcome.out, out)
    shutil.rmtree(out / outcome.table["folder"][3])
    ran = []
    again = run_study(study, out, workers=1, on_case=ran.append)
    assert [r.label for r in ran] == [outcome.table["case"][3]]
    assert len(again.table) == 6 and again.table["key"].tolist() == outcome.table["key"].tolist()


def test_retry_failed_reruns_only_the_failed_cases(small, tmp_path):
    study, outcome = small
    out = tmp_path / "copy"
    shutil.copytree(outcome.out, out)
    ran = []
    run_study(study, out, workers=1, retry_failed=True, on_case=ran.append)
    assert sorted(r.label for r in ran) == sorted(outcome.table["case"][outcome.table["status"] == "infeasible"])


def test_a_changed_base_file_changes_every_key(small, tmp_path):
    study, outcome = small
    shutil.copytree(study.parent, tmp_path / "s", ignore=shutil.ignore_patterns("out"))
    base = tmp_path / "s" / "base.toml"
    base.write_text(base.read_text().replace("viscous_friction = true", "viscous_friction = false"))
    again = run_study(tmp_path / "s" / study.name, outcome.out.parent / "other", workers=1)
    assert not set(again.table["key"]) & set(outcome.table["key"])


def test_key_covers_the_content_of_named_data_files(tmp_path):
    """Same document, another content of the file it names -> another key (and back)."""
    data = tmp_path / "p.toml"
    data.write_text("a = 1\n")
    doc = {"robot": {"parameters": "p.toml"}, "w": 0.0}
    k1 = case_key(tmp_path / "base.toml", doc)
    data.write_text("a = 2\n")
    k2 = case_key(tmp_path / "base.toml", doc)
    data.write_text("a = 1\n")
    assert k1 != k2 and case_key(tmp_path / "base.toml", doc) == k1
    assert case_key(tmp_path / "base.toml", {**doc, "w": 0.001}) != k1


def test_bad_input_and_internal_errors_are_rows(tmp_path):
    study = write_study(tmp_path, '[design]\n[[design.cases]]\nlabel = "outside"\noverrides = { "motion.end" = [5.0, 5.0, 5.0] }\n'
                                  '[[design.cases]]\nlabel = "fine"\noverrides = { "method.grid" = 40 }\n')
    outcome = run_study(study, tmp_path / "out", workers=1)
    assert outcome.table["status"].tolist() == ["invalid_input", "optimal"]
    assert "outside the workspace" in outcome.table["message"][0]
    assert outcome.exit_code == EXIT_BAD_INPUT


def test_local_cluster_gives_the_same_table(small, tmp_path):
    """In this process vs two Dask worker processes: the same cases, keys and numbers."""
    study, outcome = small
    cluster = run_study(study, tmp_path / "cluster", workers=2)
    assert cluster.summary["workers"] == 2 and cluster.summary["run_now"] == 6
    pd.testing.assert_frame_equal(cluster.table[COMPARED], outcome.table[COMPARED], check_exact=False, rtol=1e-12)


@pytest.mark.parametrize("workers", [0, -1, True])
def test_bad_workers(tmp_path, workers):
    with pytest.raises(InputError, match="workers: expected a positive integer"):
        run_study(write_study(tmp_path, SMALL_DESIGN), tmp_path / "out", workers=workers)


def test_command_writes_the_table_and_exits_with_the_worst_status(small, tmp_path, capsys):
    study, _ = small
    code = main(["study", str(study), "--out", str(tmp_path / "o"), "--workers", "1", "-q"])
    assert code == EXIT_NOT_OPTIMAL
    assert "6/6 case(s) finished (4 optimal, 2 infeasible)" in capsys.readouterr().out
    assert json.loads((tmp_path / "o" / "summary.json").read_text())["finished"] == 6


def test_warm_started_chains_solve_each_row_in_order_and_resume_per_case(tmp_path, monkeypatch):
    """warm_start = true: one chain per force limit along the grid axis; each case after the
    first of its chain gets the previous solution; a deleted case reruns alone."""
    kind = type(get_kind("path_constrained"))
    calls = []
    original = kind.solve

    def solve(self, declaration, **kw):
        calls.append((kw.get("previous") is not None, kw.get("warm_start")))
        return original(self, declaration, **kw)

    monkeypatch.setattr(kind, "solve", solve)
    design = SMALL_DESIGN.replace("values = [40, 60]", "values = [40, 60, 80]").replace("[60.0, 60.0, 60.0], ", "")
    study = write_study(tmp_path, design, header="warm_start = true")
    outcome = run_study(study, tmp_path / "out", workers=1)
    assert calls == [(False, True), (True, True), (True, True)] * 2
    assert (outcome.table["status"] == "optimal").all()
    shutil.rmtree(tmp_path / "out" / outcome.table["folder"][1])
    calls.clear()
    again = run_study(study, tmp_path / "out", workers=1)
    assert calls == [(False, True)] and again.table["key"].tolist() == outcome.table["key"].tolist()


def test_progress_lines_when_piped(caplog):
    caplog.set_level("INFO", logger="gtmodel")
    with StudyProgress("s", 4, mode="log", every=2, interval=1e9) as bar:
        for status in ("optimal", "infeasible", "optimal", "optimal"):
            bar.update(status)
    lines = [r.getMessage() for r in caplog.records]
    assert [line.split(",")[0:2] for line in lines] == [["s: 2/4 cases done", " 1 failed"], ["s: 4/4 cases done", " 1 failed"]]


def test_progress_is_silent_when_off(caplog, capsys):
    caplog.set_level("INFO", logger="gtmodel")
    with StudyProgress("s", 2, mode="off") as bar:
        bar.update("optimal")
    assert not caplog.records and capsys.readouterr() == ("", "")


def test_an_unreachable_scheduler_is_bad_input(small, tmp_path, capsys):
    dask = pytest.importorskip("dask")
    study, _ = small
    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        code = main(["study", str(study), "--out", str(tmp_path / "o"), "--scheduler", "tcp://127.0.0.1:9", "-q"])
    assert code == EXIT_BAD_INPUT
    assert "scheduler 'tcp://127.0.0.1:9': cannot connect" in capsys.readouterr().err


@pytest.mark.slow  # tens of seconds of the default run's budget (measured 2026-11-28)
def test_warm_started_chains_on_a_local_cluster(tmp_path):
    """The same chains as units of two worker processes: the same keys and statuses as in this process."""
    design = SMALL_DESIGN.replace("[60.0, 60.0, 60.0], ", "")
    study = write_study(tmp_path, design, header="warm_start = true")
    local = run_study(study, tmp_path / "a", workers=1)
    cluster = run_study(study, tmp_path / "b", workers=2)
    assert cluster.table["key"].tolist() == local.table["key"].tolist()
    assert (cluster.table["status"] == "optimal").all() and cluster.summary["workers"] == 2


def test_solve_sweep_on_two_workers_writes_the_same_comparison(tmp_path):
    base = write_study(tmp_path, SMALL_DESIGN).parent / "base.toml"
    args = [str(base), "--sweep", "method.grid=40,60,80", "--quiet", "--no-plots"]
    assert main(["solve", *args, "--out", str(tmp_path / "one")]) == 0
    assert main(["solve", *args, "--out", str(tmp_path / "two"), "--workers", "2"]) == 0
    one, two = (pd.read_csv(tmp_path / d / "comparison.csv").drop(columns="solve_time_s") for d in ("one", "two"))
    pd.testing.assert_frame_equal(one, two)  # every column but the solve time


def test_rich_progress_bar_runs(capsys):
    with StudyProgress("s", 2, mode="rich") as bar:
        bar.update("optimal")
        bar.update("infeasible")
    assert "2/2" in capsys.readouterr().err


def test_a_sigint_swallowed_between_cases_still_interrupts_the_study(small, tmp_path, monkeypatch):
    """A SIGINT whose KeyboardInterrupt is lost outside the cases' own guards (here caught
    on purpose, as Python does in a finalizer) still stops an in-process study: status
    ``interrupted`` after the case it came in, the remaining cases not run."""
    import os
    import signal

    import gtmodel.problems.study.executors as engine

    original = engine.run_unit
    units = []

    def run_unit(unit, *args, **kw):
        records = original(unit, *args, **kw)
        units.append(records)
        if len(units) == 1:
            try:
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(0.5)  # the handler runs here
            except KeyboardInterrupt:
                pass  # swallowed
        return records

    monkeypatch.setattr(engine, "run_unit", run_unit)
    outcome = run_study(small[0], tmp_path / "again", workers=1)
    assert outcome.status == "interrupted" and len(units) == 1 and len(outcome.table) == 1
