"""The executors of a study: units of cases in this process or on a Dask cluster.

Dask is the scheduler; nothing here schedules work itself:

- ``workers=1``: in this process, no Dask;
- more workers: a local :class:`dask.distributed.LocalCluster` of that many worker
  processes with one thread each (processes, not threads: CasADi and IPOPT hold the GIL);
- ``scheduler="tcp://host:8786"``: an existing cluster (:class:`dask.distributed.Client`);
  its workers must see the study folder (a shared file system) and import gtmodel.

A case whose worker dies is rescheduled by Dask on another worker, at most
``distributed.scheduler.allowed-failures`` times (set to :data:`ALLOWED_FAILURES` for a
local cluster); then it is a record with status ``internal_error``. A failing case
(infeasible, bad data, internal error) is a record with its status, never fatal.
"""

from __future__ import annotations

import importlib
import logging
import sys
import time
from typing import Any, Callable, Sequence

from gtmodel.errors import InputError
from gtmodel.problems.runtime import InterruptGuard
from gtmodel.problems.study.cases import CaseRecord, CaseTask, finished_summary, record_failure, run_unit
from gtmodel.status import Status

__all__ = ["execute", "ALLOWED_FAILURES"]

_log = logging.getLogger("gtmodel")

#: How often a case may lose its worker before it is recorded as ``internal_error``
#: (Dask's ``distributed.scheduler.allowed-failures`` of a local cluster).
ALLOWED_FAILURES = 3


def execute(units: Sequence[Sequence[CaseTask]], on_record: Callable[[CaseRecord], None], *, workers: int = 1,
            scheduler: str | None = None, chain: bool = False, warm_start: bool = False, keep_solutions: bool = False,
            info: dict | None = None) -> dict[str, Any]:
    """Run units of cases (one case each, or warm-started chains) on an executor.

    Parameters
    ----------
    units : sequence of sequence of CaseTask
        Each unit is one executor task (:func:`~gtmodel.problems.study.cases.run_unit`).
    on_record : callable
        Called in this process with each :class:`CaseRecord` as it finishes.
    workers : int, optional
        1: in this process; more: a local Dask cluster of that many processes.
    scheduler : str, optional
        Address of an existing Dask scheduler (``workers`` is then ignored).
    chain : bool, optional
        Pass each solution of a unit on to its next case.
    warm_start : bool, optional
        Start each chained case from the previous solution.
    keep_solutions : bool, optional
        Keep solutions in the records (in-process only).
    info : dict, optional
        Filled with ``workers``, ``scheduler`` and ``startup_s`` (also when interrupted).

    Returns
    -------
    dict
        ``info``.

    Raises
    ------
    KeyboardInterrupt
        Ctrl-C / SIGTERM (the remaining cases are cancelled, the cluster closed first).
    InputError
        ``workers`` is not a positive integer; the scheduler cannot be reached, has no
        worker within 120 s, or its workers cannot import gtmodel.
    """
    info = {} if info is None else info
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError(f"workers: expected a positive integer, got {workers!r}")
    if scheduler is None and workers == 1:
        info.update(workers=1, scheduler=None, startup_s=0.0)
        # the guard keeps a SIGINT that arrives between the cases' own guards even if the
        # KeyboardInterrupt it raises is swallowed (e.g. raised inside a finalizer, where
        # Python only prints "Exception ignored"): checked after every unit
        with InterruptGuard() as guard:
            for unit in units:
                records = run_unit(unit, chain, warm_start, keep_solutions)
                for r in records:
                    on_record(r)
                if any(r.status is Status.INTERRUPTED for r in records):
                    raise KeyboardInterrupt("interrupted by the user")
                guard.check()
        return info
    _execute_dask(units, on_record, workers, scheduler, chain, warm_start, info)
    return info


def _execute_dask(units: Sequence[Sequence[CaseTask]], on_record: Callable[[CaseRecord], None], workers: int,
                  scheduler: str | None, chain: bool, warm_start: bool, info: dict) -> None:
    import dask  # slow to import: only when a cluster is used
    from distributed import Client, KilledWorker, LocalCluster, as_completed

    start = time.perf_counter()
    cluster = None
    config = {"distributed.scheduler.allowed-failures": ALLOWED_FAILURES}
    if sys.platform.startswith("linux"):
        # forkserver: the workers are forked from a single-threaded server process, not from this one, whose
        # threads (Dask's event loop, logging) may hold a lock at the moment of a fork: a worker forked from
        # here hung in its first log line's flush, the buffer lock of the stream inherited locked (seen
        # 2026-11-25 in the test suite). Two workers start in 0.8 s (0.2 s forked from here, 13-16 s
        # spawned; the 2-core machine); the workers' preload hook resets signals and logging. A script
        # that starts a study needs Python's `if __name__ == "__main__":` guard, as with spawn
        config["distributed.worker.multiprocessing-method"] = "forkserver"
    with dask.config.set(config):
        if scheduler is not None:
            try:
                client = Client(scheduler)  # waits distributed.comm.timeouts.connect (30 s)
            except (OSError, TimeoutError, ValueError) as exc:
                raise InputError(f"scheduler {scheduler!r}: cannot connect ({type(exc).__name__}: {exc})") from None
        else:
            cluster = LocalCluster(n_workers=min(workers, max(1, len(units))), threads_per_worker=1, processes=True,
                                   dashboard_address=None, scheduler_kwargs={"dashboard_address": ":0"},  # no port 8787 clash
                                   silence_logs=logging.ERROR, preload=["gtmodel.problems.study.cases"])
            client = Client(cluster)
    futures: dict[Any, Sequence[CaseTask]] = {}
    try:
        try:
            client.wait_for_workers(1 if cluster is None else len(cluster.workers), timeout=120)
        except TimeoutError:
            raise InputError(f"scheduler {scheduler!r}: no worker joined within 120 s") from None
        if scheduler is not None:  # a local cluster's workers preload it (cases.dask_setup)
            try:  # import on every worker: part of the startup
                client.run(importlib.import_module, "gtmodel.problems.study.cases")
            except ImportError as exc:
                raise InputError(f"scheduler {scheduler!r}: its workers cannot import gtmodel ({exc})") from None
        info.update(workers=len(client.scheduler_info().get("workers", {})), scheduler=scheduler,
                    startup_s=time.perf_counter() - start)
        for unit in units:
            futures[client.submit(run_unit, list(unit), chain, warm_start, False, pure=False)] = unit
        for fut in as_completed(list(futures)):
            unit = futures.pop(fut)
            try:
                records = fut.result()
            except KilledWorker as exc:  # Dask gave up after allowed-failures worker deaths
                records = _unfinished(unit, f"every worker that ran it died (dask KilledWorker: {exc})")
            except Exception as exc:  # noqa: BLE001 - a failing task is that case's row, never fatal
                records = _unfinished(unit, f"{type(exc).__name__}: {exc}")
            fut.release()
            for r in records:
                on_record(r)
    finally:
        _close(client, cluster, list(futures))


def _unfinished(unit: Sequence[CaseTask], message: str) -> list[CaseRecord]:
    """Records for the cases of a unit that no worker finished (finished ones are read back)."""
    out = []
    for task in unit:
        summary = finished_summary(task.folder, task.key)
        if summary is not None:
            out.append(CaseRecord(task.label, task.key, task.folder, Status(summary["status"]),
                                  (summary.get("study") or {}).get("wall_s"), summary))
        else:
            out.append(record_failure(task, message))
    return out


def _close(client: Any, cluster: Any, pending: list) -> None:
    try:
        if pending:
            client.cancel(pending, force=True)
        client.close(timeout=10)
    except Exception as exc:  # noqa: BLE001 - closing must not hide the study's outcome
        _log.debug("closing the dask client: %s", exc)
    if cluster is not None:
        try:
            cluster.close(timeout=20)
        except Exception as exc:  # noqa: BLE001
            _log.debug("closing the local cluster: %s", exc)
