"""A study on a real Dask cluster: a ``dask scheduler`` and two ``dask worker`` processes
on 127.0.0.1 (subprocesses), one worker killed (SIGKILL) while it runs a case; and Dask's bounded retries
(``allowed-failures``) of a case that kills every worker it runs on, on a local cluster.

Independent reference: the scheduler's own record of the tasks the killed worker was
processing; the case folders on disk (one per case, no duplicates, no partial ones); a
model file that kills the process importing it (``os._exit``).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time

import pytest

from gtmodel.problems.study import executors
from gtmodel.problems.study.engine import run_study

from ...conftest import PROBLEMS_DIR, REPO
from .study_fixtures import grid_design, write_study

distributed = pytest.importorskip("distributed")


def _stop(proc: subprocess.Popen) -> None:
    """End a process started in its own session, with its children (nanny and worker)."""
    for sig, wait in ((signal.SIGTERM, 10), (signal.SIGKILL, 10)):
        if proc.poll() is not None:
            break
        try:
            os.killpg(proc.pid, sig)
        except ProcessLookupError:
            break
        try:
            proc.wait(wait)
        except subprocess.TimeoutExpired:
            continue
    try:
        os.killpg(proc.pid, signal.SIGKILL)  # leftovers of the group (a worker whose nanny died)
    except ProcessLookupError:
        pass


@pytest.fixture
def cluster(tmp_path):
    """(scheduler address, {worker address: its `dask worker` process}); all stopped at the end."""
    env = {**os.environ, "PYTHONPATH": str(REPO), "MPLBACKEND": "Agg"}
    scheduler_file = tmp_path / "scheduler.json"
    log = open(tmp_path / "cluster.log", "w")
    dask = [sys.executable, "-m", "dask"]
    procs = []
    try:
        procs.append(subprocess.Popen([*dask, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                       "--scheduler-file", str(scheduler_file)], env=env, stdout=log, stderr=log, start_new_session=True))
        deadline, address = time.monotonic() + 60, None
        while address is None and time.monotonic() < deadline:  # the scheduler writes its file in more than one call
            try:
                address = json.loads(scheduler_file.read_text())["address"]
            except (OSError, ValueError, KeyError):
                time.sleep(0.1)
        assert address is not None, "the dask scheduler wrote no scheduler file in 60 s"
        workers = [subprocess.Popen([*dask, "worker", "--scheduler-file", str(scheduler_file), "--nthreads", "1", "--nworkers", "1",
                                     "--host", "127.0.0.1", "--no-dashboard", "--death-timeout", "60"],
                                    env=env, stdout=log, stderr=log, start_new_session=True) for _ in range(2)]
        procs += workers
        with distributed.Client(address, timeout="60s") as client:
            client.wait_for_workers(2, timeout=120)
            pids = client.run(os.getpid)
        by_group = {os.getpgid(pid): addr for addr, pid in pids.items()}
        yield address, {by_group[p.pid]: p for p in workers}
    finally:
        for p in reversed(procs):
            _stop(p)
        log.close()


@pytest.mark.slow  # ~10 s: a Dask cluster, a worker killed mid-case
def test_a_killed_worker_loses_nothing_and_duplicates_nothing(cluster, tmp_path):
    address, workers = cluster
    n = 10
    study = write_study(tmp_path, grid_design(n, grid=4000))
    victim_address, victim = next(iter(workers.items()))
    killed: list[list[str]] = []
    records = []
    done = threading.Event()
    with distributed.Client(address, timeout="60s") as monitor:

        def kill_when_busy():
            # from the study's start, not from its first finished case: on a loaded machine the victim
            # may run its cases before the first one is reported, and then never be seen processing
            deadline = time.monotonic() + 120
            while not done.is_set() and time.monotonic() < deadline:
                running = monitor.processing(workers=[victim_address]).get(victim_address, [])
                if running:  # the scheduler says the victim is processing a case: kill it now
                    os.killpg(victim.pid, signal.SIGKILL)
                    killed.append(list(running))
                    return
                time.sleep(0.01)

        watcher = threading.Thread(target=kill_when_busy, daemon=True)
        watcher.start()
        try:
            outcome = run_study(study, tmp_path / "out", scheduler=address, on_case=records.append)
        finally:
            done.set()
            watcher.join(30)
    assert killed and killed[0], "the victim worker was not processing a case"
    assert victim.wait(10) is not None  # it is gone for good (no nanny left to restart it)
    table = outcome.table
    assert outcome.status == "optimal" and outcome.summary["scheduler"] == address
    assert len(table) == n and table["key"].is_unique and (table["status"] == "optimal").all()
    assert len(records) == n and len({r.key for r in records}) == n  # each case reported once
    folders = sorted(p.name for p in (tmp_path / "out" / "cases").iterdir())
    assert folders == sorted(table["folder"].str.removeprefix("cases/"))  # one folder per case, no partial ones left


@pytest.mark.slow  # ~6 s: every retry starts a worker again
def test_a_case_that_kills_every_worker_is_a_row_after_bounded_retries(tmp_path, monkeypatch):
    """Dask reschedules it after its worker died, at most ALLOWED_FAILURES times (here 1);
    then the case is an internal_error row and the study ends (exit 3), nothing hangs."""
    monkeypatch.setattr(executors, "ALLOWED_FAILURES", 1)
    (tmp_path / "crash.py").write_text("import os\nos._exit(1)  # a model file that kills the process loading it\n")
    model = (PROBLEMS_DIR / "cart_pendulum_swing_up.toml").read_text()
    assert 'file = "../models/cart_pendulum.py"' in model
    study = write_study(tmp_path, "")
    (tmp_path / "pendulum.toml").write_text(model.replace('"../models/cart_pendulum.py"', '"crash.py"'))
    study.write_text('base = "pendulum.toml"\nplots = false\n[design]\n[[design.axes]]\nfield = "model.file"\nvalues = ["crash.py"]\n')
    outcome = run_study(study, tmp_path / "out", workers=2)
    assert outcome.table["status"].tolist() == ["internal_error"]
    assert "every worker that ran it died (dask KilledWorker" in outcome.table["message"][0]
    assert outcome.exit_code == 3
