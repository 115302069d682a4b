"""Running a study: plan the cases, skip the finished ones, execute the rest, write the table.

The executors (Dask is the scheduler; nothing here schedules work itself):

- ``workers=1``: in this process, no Dask;
- default: a local :class:`dask.distributed.LocalCluster` of ``os.cpu_count()`` worker
  processes with one thread each (processes, not threads: CasADi and IPOPT hold the GIL);
- ``scheduler="tcp://host:8786"``: an existing cluster (:class:`dask.distributed.Client`);
  its workers must see the study folder (a shared file system) and import gtmodel.

A case whose worker dies is rescheduled by Dask on another worker, at most
``distributed.scheduler.allowed-failures`` times (set to :data:`ALLOWED_FAILURES` for a
local cluster); then it is a row with status ``internal_error``. A failing case
(infeasible, bad data, internal error) is a row with its status, never fatal. Ctrl-C (or
SIGTERM) cancels the remaining cases, closes the cluster and writes the table of the
finished cases with the study status ``interrupted`` (exit code 130); a rerun solves only
what is missing. The table is built from the case folders alone, one row per case key.
"""

from __future__ import annotations

import importlib
import logging
import os
import shutil
import signal
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence

import pandas as pd

from gtmodel._toml import read_toml
from gtmodel.errors import InputError, ProblemError, ResultWriteError
from gtmodel.problems.analyses import ANALYSES
from gtmodel.problems.results import write_json
from gtmodel.problems.runtime import InterruptGuard
from gtmodel.problems.study_cases import (CaseRecord, CaseTask, case_key, finished_summary, record_failure,
                                          resolve_document, run_unit, safe_name)
from gtmodel.problems.study_file import Study, load_study
from gtmodel.problems.study_progress import StudyProgress
from gtmodel.problems.study_table import build_table, case_row, write_table
from gtmodel.status import Status, StatusResult

__all__ = ["StudyOutcome", "plan_cases", "execute", "run_study", "ALLOWED_FAILURES"]

_log = logging.getLogger("gtmodel")

#: How often a case may lose its worker before it is recorded as ``internal_error``
#: (Dask's ``distributed.scheduler.allowed-failures`` of a local cluster).
ALLOWED_FAILURES = 3


@dataclass
class StudyOutcome(StatusResult):
    """A finished (or interrupted) study.

    Parameters
    ----------
    status : Status
        The worst status of the cases; ``interrupted`` if it was stopped.
    message : str
        Counts per status.
    out : pathlib.Path
        The study folder.
    table : pandas.DataFrame
        One row per finished case.
    summary : dict
        The study's ``summary.json``.
    records : list of CaseRecord
        The cases solved by this run (not the skipped ones), in the order they finished.
    """

    out: Path = Path(".")
    table: pd.DataFrame = field(default_factory=pd.DataFrame)
    summary: dict = field(default_factory=dict)
    records: list[CaseRecord] = field(default_factory=list)

    @property
    def exit_code(self) -> int:
        """Exit code of the ``gtmodel`` command for this study."""
        return self.status.exit_code


def plan_cases(study: Study, out: str | Path, plots: bool = True, verbose: bool = False) -> list[CaseTask]:
    """The tasks of a study: each case's key and folder ``out/cases/<label>-<key[:10]>``.

    Parameters
    ----------
    study : Study
        From :func:`~gtmodel.problems.study_file.load_study`.
    out : str or pathlib.Path
        The study folder.
    plots : bool, optional
        Write each case's plots.
    verbose : bool, optional
        Solver progress (in-process only).

    Returns
    -------
    list of CaseTask
        In design order.

    Raises
    ------
    ProblemError
        An override names a field the base file does not have (the first such case,
        before anything runs; names the study file, the case, the base file and the
        field), or two cases resolve to the same problem.
    """
    out = Path(out).resolve()
    data = read_toml(study.base, ProblemError, "problem file")
    tasks: list[CaseTask] = []
    seen: dict[str, str] = {}
    for case in study.cases:
        try:
            key = case_key(study.base, resolve_document(study.base, case.overrides, data))
        except ProblemError as exc:  # the override's fault is the study file's: name it first
            raise ProblemError(f"{study.path}: field 'design' (case {case.label!r}): {exc}") from None
        if key in seen:
            raise ProblemError(f"{study.path}: field 'design': the cases {seen[key]!r} and {case.label!r} are the same problem")
        seen[key] = case.label
        tasks.append(CaseTask(case.label, key, study.base, dict(case.overrides), out / "cases" / f"{safe_name(case.label)}-{key[:10]}",
                              dict(case.design), plots=plots, verbose=verbose))
    return tasks


def _units(study: Study, tasks: Sequence[CaseTask]) -> list[list[CaseTask]]:
    if not study.warm_start:
        return [[t] for t in tasks]
    chains: dict[str, list[CaseTask]] = {}
    for case, task in zip(study.cases, tasks):
        chains.setdefault(case.chain, []).append(task)
    return list(chains.values())


def execute(units: Sequence[Sequence[CaseTask]], on_record: Callable[[CaseRecord], None], *, workers: int = 1,
            scheduler: str | None = None, chain: bool = False, warm_start: bool = False, keep_solutions: bool = False,
            info: dict | None = None) -> dict[str, Any]:
    """Run units of cases (one case each, or warm-started chains) on an executor.

    Parameters
    ----------
    units : sequence of sequence of CaseTask
        Each unit is one executor task (:func:`~gtmodel.problems.study_cases.run_unit`).
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
        # fork: a worker starts with gtmodel imported (0.3 s instead of 13-16 s with spawn,
        # measured on the 2-core machine); the workers' preload hook resets signals and logging
        config["distributed.worker.multiprocessing-method"] = "fork"
    with dask.config.set(config):
        if scheduler is not None:
            try:
                client = Client(scheduler)  # waits distributed.comm.timeouts.connect (30 s)
            except (OSError, TimeoutError, ValueError) as exc:
                raise InputError(f"scheduler {scheduler!r}: cannot connect ({type(exc).__name__}: {exc})") from None
        else:
            cluster = LocalCluster(n_workers=min(workers, max(1, len(units))), threads_per_worker=1, processes=True,
                                   dashboard_address=None, scheduler_kwargs={"dashboard_address": ":0"},  # no port 8787 clash
                                   silence_logs=logging.ERROR, preload=["gtmodel.problems.study_cases"])
            client = Client(cluster)
    futures: dict[Any, Sequence[CaseTask]] = {}
    try:
        try:
            client.wait_for_workers(1 if cluster is None else len(cluster.workers), timeout=120)
        except TimeoutError:
            raise InputError(f"scheduler {scheduler!r}: no worker joined within 120 s") from None
        if scheduler is not None:  # a local cluster's workers preload it (study_cases.dask_setup)
            try:  # import on every worker: part of the startup
                client.run(importlib.import_module, "gtmodel.problems.study_cases")
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


class _NoInterrupt:
    """SIGINT/SIGTERM ignored while the final table and summary are written (main thread)."""

    def __enter__(self) -> "_NoInterrupt":
        self._old = {}
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                self._old[sig] = signal.signal(sig, signal.SIG_IGN)
        return self

    def __exit__(self, *exc: Any) -> None:
        for sig, handler in self._old.items():
            signal.signal(sig, handler)


def _default_workers() -> int:
    return max(1, os.cpu_count() or 1)


def _rows(tasks: Sequence[CaseTask], records: dict[str, CaseRecord], root: Path, analysis: Any) -> Iterator[dict]:
    for task in tasks:
        summary = finished_summary(task.folder, task.key)
        if summary is None and task.key in records and records[task.key].status is not Status.INTERRUPTED:
            summary = dict(records[task.key].summary)  # a case whose folder could not be written
        if summary is not None:
            yield case_row(task, summary, root, analysis)


def run_study(study: Study | str | Path, out: str | Path | None = None, *, workers: int | None = None, scheduler: str | None = None,
              retry_failed: bool = False, plots: bool | None = None, progress: str = "off",
              on_case: Callable[[CaseRecord], None] | None = None, verbose: bool = False) -> StudyOutcome:
    """Run a study: solve the cases not finished yet, then write the table and summary.

    Parameters
    ----------
    study : Study or str or pathlib.Path
        A loaded study or a study file.
    out : str or pathlib.Path, optional
        The study folder (default ``results/<study name>``); it keeps ``cases/`` across
        runs (resume), ``table.parquet``, ``table.csv``, ``summary.json`` and the plots.
    workers : int, optional
        Local worker processes (default ``os.cpu_count()``; 1 runs in this process).
    scheduler : str, optional
        Address of an existing Dask scheduler, e.g. ``"tcp://10.0.0.5:8786"``.
    retry_failed : bool, optional
        Also rerun finished cases whose status is not a success (optimal, converged).
    plots : bool, optional
        Write plots (default: the study file's ``plots``).
    progress : {"off", "rich", "log"}, optional
        See :func:`~gtmodel.problems.study_progress.progress_mode`.
    on_case : callable, optional
        Called with each :class:`CaseRecord` as it finishes.
    verbose : bool, optional
        Solver progress (in this process only; ignored on workers).

    Returns
    -------
    StudyOutcome

    Raises
    ------
    ProblemError
        A bad study file, or an override of a field the base file does not have (before
        anything runs).
    InputError
        ``workers`` is not a positive integer, or given with ``scheduler``; the scheduler
        cannot be reached.
    ResultWriteError
        The table or summary cannot be written.
    """
    started = time.perf_counter()
    if not isinstance(study, Study):
        study = load_study(study)
    if workers is not None and scheduler is not None:
        raise InputError("give workers or scheduler, not both")
    workers = _default_workers() if workers is None else workers
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError(f"workers: expected a positive integer, got {workers!r}")
    out = Path(out) if out is not None else Path("results") / study.name
    plots = study.plots if plots is None else plots
    analysis = ANALYSES[study.analysis]
    in_process = scheduler is None and workers == 1
    tasks = plan_cases(study, out, plots=plots, verbose=verbose and in_process)  # no solver logs from workers
    root = Path(out).resolve()

    def pending(task: CaseTask) -> bool:
        summary = finished_summary(task.folder, task.key)
        return summary is None or (retry_failed and not Status(summary["status"]).success)

    todo = [t for t in tasks if pending(t)]
    plan_s = time.perf_counter() - started
    todo_keys = {t.key for t in todo}
    units = [[t for t in u if t.key in todo_keys] for u in _units(study, tasks)]
    units = [u for u in units if u]
    records: dict[str, CaseRecord] = {}
    info: dict[str, Any] = {"workers": 0 if not units else (1 if in_process else workers),
                            "scheduler": scheduler, "startup_s": 0.0}
    interrupted = False
    exec_start = time.perf_counter()
    _log.info("%s: %d case(s), %d to run, %d finished", study.name, len(tasks), len(todo), len(tasks) - len(todo))
    with StudyProgress(study.name, len(todo), mode=progress) as bar:  # type: ignore[arg-type]

        def on_record(record: CaseRecord) -> None:
            records[record.key] = record
            if record.status is not Status.INTERRUPTED:
                bar.update(record.status)
            if on_case is not None:
                on_case(record)

        try:
            if units:
                execute(units, on_record, workers=workers, scheduler=scheduler, chain=study.warm_start,
                        warm_start=study.warm_start, info=info)
        except KeyboardInterrupt:
            interrupted = True
    exec_s = time.perf_counter() - exec_start
    with _NoInterrupt():
        return _finish(study, tasks, records, root, analysis, plots, interrupted, info,
                       {"plan_s": plan_s, "execute_s": exec_s, "started": started})


def _finish(study: Study, tasks: Sequence[CaseTask], records: dict[str, CaseRecord], root: Path, analysis: Any, plots: bool,
            interrupted: bool, info: dict, timing: dict) -> StudyOutcome:
    root.mkdir(parents=True, exist_ok=True)
    if not interrupted:
        _remove_partials(root / "cases")
    table = build_table(list(_rows(tasks, records, root, analysis)), _design_columns(tasks))
    files = write_table(table, root)
    figures: dict[str, Any] = {}
    if len(table):
        try:
            figures, more = analysis.analyse(table, root, plots)
            files += list(more)
        except Exception as exc:  # noqa: BLE001 - the table and the cases stay; the failure is reported
            _log.warning("gtmodel: analysis %r failed: %s: %s", study.analysis, type(exc).__name__, exc)
            figures = {"error": f"{type(exc).__name__}: {exc}"}
    found = table["status"].value_counts() if len(table) else {}
    counts = {str(s): int(found[s]) for s in Status if s in found}  # best first
    status = Status.INTERRUPTED if interrupted else Status.worst(table["status"]) if len(table) else Status.ERROR
    run = [r for r in records.values() if r.status is not Status.INTERRUPTED and r.wall_s is not None]
    run_s = sum(r.wall_s for r in run)  # type: ignore[misc]
    n_workers = max(1, int(info.get("workers") or 1))
    busy = timing["execute_s"] - float(info.get("startup_s") or 0.0)
    by_worker: dict[str, list[CaseRecord]] = {}
    for r in run:
        if r.started is not None:
            by_worker.setdefault(r.worker, []).append(r)
    # the machinery between a worker's cases: its span from first start to last end minus its time in run_problem
    gaps = sum(max(r.started + r.wall_s for r in rs) - min(r.started for r in rs) - sum(r.wall_s for r in rs)  # type: ignore[operator]
               for rs in by_worker.values())
    missing = len(tasks) - len(table)
    message = ", ".join(f"{n} {s}" for s, n in counts.items()) or "no case finished"
    message = f"{len(table)}/{len(tasks)} case(s) finished ({message})" + ("; interrupted by the user" if interrupted else "")
    summary = {
        "study": str(study.path), "name": study.name, "description": study.description, "base": str(study.base),
        "analysis_name": study.analysis, "status": status, "message": message,
        "cases": len(tasks), "finished": len(table), "missing": missing, "counts": counts,
        "run_now": len(run), "skipped": len(tasks) - len(run) - missing,
        "workers": info.get("workers"), "scheduler": info.get("scheduler"),
        "wall_s": time.perf_counter() - timing["started"],
        "timing": {"plan_s": timing["plan_s"], "startup_s": info.get("startup_s"), "execute_s": timing["execute_s"],
                   "run_problem_s": run_s,
                   "overhead_per_case_s": gaps / len(run) if run else None,
                   "idle_per_case_s": (busy * n_workers - run_s) / len(run) if run else None},
        "analysis": figures,
        "table": ["table.parquet", "table.csv"],
        "files": ["summary.json", *files],
    }
    tmp = root / f".summary.json.{os.getpid()}"
    write_json(tmp, summary)
    try:
        os.replace(tmp, root / "summary.json")
    except OSError as exc:
        raise ResultWriteError(f"cannot write {root / 'summary.json'}: {exc.strerror or exc}") from None
    return StudyOutcome(status=status, message=message, out=root, table=table, summary=summary, records=list(records.values()))


def _remove_partials(cases: Path) -> None:
    """Partial folders of workers killed mid-write (every case of this run has ended).

    :class:`~gtmodel.problems.results.ResultFolder` removes them by process id, which
    cannot tell a worker on another host, nor a killed one not yet reaped.
    """
    if cases.is_dir():
        for p in cases.iterdir():
            if p.name.startswith(".") and (".partial-" in p.name or ".old-" in p.name) and p.is_dir():
                shutil.rmtree(p, ignore_errors=True)


def _design_columns(tasks: Sequence[CaseTask]) -> list[str]:
    cols: list[str] = []
    for t in tasks:
        cols += [k for k in t.design if k not in cols]
    return cols
