"""Ctrl-C during a study (a ``gtmodel study`` subprocess gets SIGINT mid-run): exit 130,
the finished cases intact, the table and summary written honestly as interrupted, and a
rerun solves only the missing cases -- in this process (``--workers 1``) and on a local
Dask cluster (``--workers 2``).

Independent reference: the case folders on disk (each finished one lists files that
exist) and the count of cases the rerun solves (exactly the missing ones).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pandas as pd
import pytest

from gtmodel.cli import EXIT_INTERRUPTED
from gtmodel.problems.study.engine import run_study

from ...conftest import REPO
from .study_fixtures import grid_design, write_study


def _finished_folders(out) -> list:
    cases = out / "cases"
    return [p for p in cases.iterdir() if (p / "summary.json").exists()] if cases.exists() else []


@pytest.mark.parametrize("workers", ["1", pytest.param("2", marks=pytest.mark.slow)], ids=["in_process", "local_cluster"])  # the cluster: ~9 s
def test_ctrl_c_stops_with_130_keeps_finished_cases_and_a_rerun_completes_the_rest(tmp_path, workers):
    n = 14
    study = write_study(tmp_path, grid_design(n, grid=2000))
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONPATH": str(REPO), "MPLBACKEND": "Agg"}
    proc = subprocess.Popen([sys.executable, "-m", "gtmodel.cli", "study", str(study), "--out", str(out), "--workers", workers, "-q"],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + 90
        while len(_finished_folders(out)) < 2 and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.05)
        assert proc.poll() is None, "the study ended before it could be interrupted"
        os.killpg(proc.pid, signal.SIGINT)  # as Ctrl-C on a terminal: to the whole process group (workers too)
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    written = (out / "summary.json").read_text() if (out / "summary.json").exists() else "no summary.json"
    # one exit 0 (all cases finished, SIGINT lost) in ~17 runs on the loaded machine, cause not
    # seen; an in-process study now also keeps a SIGINT whose KeyboardInterrupt is swallowed
    # between cases (study/test_engine.py); the message keeps what is needed if it comes back
    assert proc.returncode == EXIT_INTERRUPTED, f"exit {proc.returncode}; stderr:\n{stderr}\nsummary.json:\n{written}"
    summary = json.loads((out / "summary.json").read_text())
    table = pd.read_parquet(out / "table.parquet")
    assert summary["status"] == "interrupted" and summary["finished"] == len(table) < n
    assert (table["status"] == "optimal").all() and table["key"].is_unique
    files_intact = [all((out / f / name).exists() for name in json.loads((out / f / "summary.json").read_text())["files"])
                    for f in table["folder"]]
    assert all(files_intact)
    ran = []
    again = run_study(study, out, workers=1, on_case=ran.append)
    assert len(ran) == n - len(table) and {r.key for r in ran}.isdisjoint(table["key"])
    assert len(again.table) == n and again.table["key"].is_unique and again.status == "optimal"
