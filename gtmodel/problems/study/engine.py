"""The one study engine: plan the cases, skip the finished ones, execute the rest, write the table.

Every batch of solves goes through :func:`run_study`: a study file (``gtmodel study``),
several problem files compared (``gtmodel solve A.toml B.toml --out DIR``) and a sweep of
one field (``gtmodel solve A.toml --sweep w=0,0.001``); the last two are studies built
by :func:`~gtmodel.problems.study.design.comparison_study`. The cases run on the
executors of :mod:`~gtmodel.problems.study.executors` (in this process or on Dask).

Everything about the input is checked before anything runs or is written: the output
folder, every problem file, every override (an unknown field is one error, no folder).
A failing case (infeasible, bad data, internal error) is a row with its status, never
fatal. Ctrl-C (or SIGTERM) cancels the remaining cases, closes the cluster and writes the
table of the finished cases with the study status ``interrupted`` (exit code 130).

Two layouts of the study folder:

- a study file: ``DIR/cases/<label>-<key[:10]>/``, resumable (a rerun solves only what
  is missing; a rerun that solves nothing keeps the timing of the run that did);
- a comparison: ``DIR/<case>/``, the folder replaced whole when the run ends, plus the
  kinds' comparison table and overlay plots (:mod:`~gtmodel.problems.study.comparison`).

Both write ``table.parquet``, ``table.csv`` (built from the case folders, one row per
case key) and ``summary.json``; the status and the exit code come from the one
:class:`~gtmodel.status.Status` table.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence

import pandas as pd

from gtmodel import _signals
from gtmodel._toml import read_toml
from gtmodel.errors import InputError, ProblemError, ResultWriteError
from gtmodel.problems.results import ResultFolder, kept_message, write_json
from gtmodel.problems.study.analyses import ANALYSES
from gtmodel.problems.study.cases import CaseRecord, CaseTask, case_key, finished_summary, resolve_document, safe_name
from gtmodel.problems.study.comparison import StudyCase, write_comparison
from gtmodel.problems.study.design import Study, comparison_study, load_study
from gtmodel.problems.study.executors import execute
from gtmodel.problems.study.preflight import check_output_folder
from gtmodel.problems.study.progress import StudyProgress
from gtmodel.problems.study.table import build_table, case_row, write_table
from gtmodel.status import Status, StatusResult

__all__ = ["StudyOutcome", "plan_cases", "run_study", "solve_study", "mark_interrupted"]

_log = logging.getLogger("gtmodel")


@dataclass
class StudyOutcome(StatusResult):
    """A finished (or interrupted) study, comparison or sweep.

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
    cases : list of StudyCase
        Every case with a result, in design order (with its solution when it was solved
        in this process and kept: a comparison).
    """

    out: Path = Path(".")
    table: pd.DataFrame = field(default_factory=pd.DataFrame)
    summary: dict = field(default_factory=dict)
    records: list[CaseRecord] = field(default_factory=list)
    cases: list[StudyCase] = field(default_factory=list)

    @property
    def exit_code(self) -> int:
        """Exit code of the ``gtmodel`` command for this study (:data:`gtmodel.status.EXIT_CODES`)."""
        return self.status.exit_code


def _unreadable_key(path: Path, label: str) -> str:
    """The key of a comparison case whose problem file cannot be read (its run reports why)."""
    return hashlib.sha256(f"unreadable:{path}:{label}".encode("utf-8")).hexdigest()


def plan_cases(study: Study, out: str | Path, plots: bool = True, verbose: bool = False, heartbeat: bool = False) -> list[CaseTask]:
    """The tasks of a study: each case's key and folder.

    The folder is ``out/cases/<label>-<key[:10]>`` for a study file and ``out/<case>`` for
    a comparison.

    Parameters
    ----------
    study : Study
        From :func:`~gtmodel.problems.study.design.load_study` or
        :func:`~gtmodel.problems.study.design.comparison_study`.
    out : str or pathlib.Path
        The study folder.
    plots : bool, optional
        Write each case's plots.
    verbose : bool, optional
        Solver progress (in-process only).
    heartbeat : bool, optional
        Log a line every few seconds while a case solves.

    Returns
    -------
    list of CaseTask
        In design order.

    Raises
    ------
    ProblemError
        An override names a field the problem file does not have (the first such case,
        before anything runs; names the study file, the case, the problem file and the
        field), two cases resolve to the same problem, the base file of a study file
        cannot be read.
    """
    out = Path(out).resolve()
    docs: dict[Path, dict[str, Any] | None] = {}
    tasks: list[CaseTask] = []
    seen: dict[str, str] = {}
    folders: set[str] = set()
    for case in study.cases:
        base = case.base or study.base
        if base not in docs:
            try:
                docs[base] = read_toml(base, ProblemError, "problem file")
            except ProblemError:
                if not study.comparison or case.overrides:
                    raise
                docs[base] = None  # a comparison: the file's own case reports it
        data = docs[base]
        try:
            key = _unreadable_key(base, case.label) if data is None else case_key(base, resolve_document(base, case.overrides, data))
        except ProblemError as exc:  # the override's fault is the study file's: name it first
            if study.path is None:
                raise
            raise ProblemError(f"{study.path}: field 'design' (case {case.label!r}): {exc}") from None
        if key in seen:
            where = f"{study.path}: field 'design': " if study.path is not None else ""
            raise ProblemError(f"{where}the cases {seen[key]!r} and {case.label!r} are the same problem")
        seen[key] = case.label
        if study.comparison:
            name = safe_name(base.stem + "".join(f"[{k}={v}]" for k, v in case.overrides.items()))
            name = next(n for n in (name, *(f"{name}_{i}" for i in range(2, len(study.cases) + 2))) if n not in folders)
            folders.add(name)
            folder = out / name
        else:
            folder = out / "cases" / f"{safe_name(case.label)}-{key[:10]}"
        tasks.append(CaseTask(case.label, key, base, dict(case.overrides), folder, dict(case.design), plots=plots,
                              verbose=verbose, heartbeat=heartbeat))
    return tasks


def _units(study: Study, tasks: Sequence[CaseTask], in_process: bool) -> list[list[CaseTask]]:
    if not (study.warm_start or (study.reuse and in_process)):
        return [[t] for t in tasks]
    chains: dict[str, list[CaseTask]] = {}
    for case, task in zip(study.cases, tasks):
        chains.setdefault(case.chain, []).append(task)
    return list(chains.values())


def _default_workers() -> int:
    return max(1, os.cpu_count() or 1)


def _case_summary(task: CaseTask, records: dict[str, CaseRecord]) -> dict | None:
    summary = finished_summary(task.folder, task.key)
    if summary is None and task.key in records and records[task.key].status is not Status.INTERRUPTED:
        summary = dict(records[task.key].summary)  # a case whose folder could not be written
    return summary


def _rows(tasks: Sequence[CaseTask], records: dict[str, CaseRecord], root: Path, analysis: Any) -> Iterator[dict]:
    for task in tasks:
        summary = _case_summary(task, records)
        if summary is not None:
            yield case_row(task, summary, root, analysis)


def run_study(study: Study | str | Path, out: str | Path | None = None, *, workers: int | None = None, scheduler: str | None = None,
              retry_failed: bool = False, plots: bool | None = None, progress: str = "off",
              on_case: Callable[[CaseRecord], None] | None = None, verbose: bool = False, heartbeat: bool = False) -> StudyOutcome:
    """Run a study, a comparison or a sweep: solve the cases not finished yet, then write the table and summary.

    Parameters
    ----------
    study : Study or str or pathlib.Path
        A study (:func:`~gtmodel.problems.study.design.load_study`,
        :func:`~gtmodel.problems.study.design.comparison_study`) or a study file.
    out : str or pathlib.Path, optional
        The study folder (default ``results/<study name>``). A study file's folder keeps
        ``cases/`` across runs (resume); a comparison's is replaced whole at the end.
    workers : int, optional
        Local worker processes (default ``os.cpu_count()``; 1 runs in this process).
    scheduler : str, optional
        Address of an existing Dask scheduler, e.g. ``"tcp://10.0.0.5:8786"``.
    retry_failed : bool, optional
        Also rerun finished cases whose status is not a success (optimal, converged).
    plots : bool, optional
        Write plots (default: the study's ``plots``).
    progress : {"off", "rich", "log"}, optional
        See :func:`~gtmodel.problems.study.progress.progress_mode`.
    on_case : callable, optional
        Called with each :class:`~gtmodel.problems.study.cases.CaseRecord` as it finishes.
    verbose : bool, optional
        Solver progress (in this process only; ignored on workers).
    heartbeat : bool, optional
        Log a line every few seconds while a case solves (in this process).

    Returns
    -------
    StudyOutcome

    Raises
    ------
    ProblemError
        A bad study file, a problem file that does not exist, an override of a field the
        problem file does not have (before anything runs or is written).
    InputError
        ``workers`` is not a positive integer, or given with ``scheduler``; the scheduler
        cannot be reached.
    ResultWriteError
        The study folder is a file (before anything runs), or the table or summary cannot
        be written.
    """
    started = time.perf_counter()
    if not isinstance(study, Study):
        study = load_study(study)
    if workers is not None and scheduler is not None:
        raise InputError("give workers or scheduler, not both")
    workers = _default_workers() if workers is None else workers
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError(f"workers: expected a positive integer, got {workers!r}")
    target = Path(out) if out is not None else Path("results") / study.name
    check_output_folder(target)
    plots = study.plots if plots is None else plots
    analysis = ANALYSES[study.analysis]
    in_process = scheduler is None and workers == 1
    verbose = verbose and in_process  # no solver logs from workers
    tasks = plan_cases(study, target, plots=plots, verbose=verbose, heartbeat=heartbeat and in_process)  # every input error first
    folder = ResultFolder(target) if study.comparison else None  # a comparison is written aside, then replaces the folder
    root = folder.path.resolve() if folder is not None else target.resolve()
    for t in tasks:
        t.folder = root / t.folder.relative_to(target.resolve())
    try:

        def pending(task: CaseTask) -> bool:
            summary = finished_summary(task.folder, task.key)
            return summary is None or (retry_failed and not Status(summary["status"]).success)

        todo = [t for t in tasks if pending(t)]
        before = {t.key: finished_summary(t.folder, t.key) for t in todo}  # what a rerun replaces
        plan_s = time.perf_counter() - started
        todo_keys = {t.key for t in todo}
        units = [[t for t in u if t.key in todo_keys] for u in _units(study, tasks, in_process)]
        units = [u for u in units if u]
        chain = study.warm_start or (study.reuse and in_process)
        records: dict[str, CaseRecord] = {}
        info: dict[str, Any] = {"workers": 0 if not units else (1 if in_process else workers), "scheduler": scheduler, "startup_s": 0.0}
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
                    execute(units, on_record, workers=workers, scheduler=scheduler, chain=chain, warm_start=study.warm_start and chain,
                            keep_solutions=study.comparison and in_process, info=info)
            except KeyboardInterrupt:
                interrupted = True
        exec_s = time.perf_counter() - exec_start
        with _signals.settled():  # the table and summary are written whole; a signal meanwhile makes the study interrupted
            timing = {"plan_s": plan_s, "execute_s": exec_s, "started": started}
            interrupted = interrupted or _signals.received()
            outcome = _finish(study, tasks, records, root, analysis, plots, interrupted, info, timing, folder, before)
            if _signals.received() and not interrupted:
                if folder is not None:
                    folder = ResultFolder(target)
                    root = folder.path.resolve()
                outcome = _finish(study, tasks, records, root, analysis, plots, True, info, timing, folder, before)
    finally:
        if folder is not None and not folder.committed:
            folder.discard()
    return outcome


def _finish(study: Study, tasks: Sequence[CaseTask], records: dict[str, CaseRecord], root: Path, analysis: Any, plots: bool,
            interrupted: bool, info: dict, timing: dict, folder: ResultFolder | None, before: dict[str, dict | None]) -> StudyOutcome:
    root.mkdir(parents=True, exist_ok=True)
    if not interrupted:
        _remove_partials(root / "cases")
    table = build_table(list(_rows(tasks, records, root, analysis)), _design_columns(tasks))
    files = write_table(table, root)
    out = folder.target.resolve() if folder is not None else root
    cases = _cases(tasks, records, root, out)
    figures: dict[str, Any] = {}
    if len(table):
        try:
            figures, more = analysis.analyse(table, root, plots)
            files += list(more)
        except Exception as exc:  # noqa: BLE001 - the table and the cases stay; the failure is reported
            _log.warning("gtmodel: analysis %r failed: %s: %s", study.analysis, type(exc).__name__, exc)
            figures = {"error": f"{type(exc).__name__}: {exc}"}
    if study.comparison:
        files += write_comparison(cases, root, plots=plots)
    found = table["status"].value_counts() if len(table) else {}
    counts = {str(s): int(found[s]) for s in Status if s in found}  # best first
    status = Status.INTERRUPTED if interrupted else Status.worst(table["status"]) if len(table) else Status.ERROR
    run = [r for r in records.values() if r.status is not Status.INTERRUPTED and r.wall_s is not None]
    missing = len(tasks) - len(table)
    # solved now: a case to run whose result is new (also one that ended while the run shut
    # down, whose record never came back); finished before: every other case with a result
    now = sum(1 for t in tasks if t.key in before and (s := _case_summary(t, records)) is not None and s != before[t.key])
    message = ", ".join(f"{n} {s}" for s, n in counts.items()) or "no case finished"
    message = f"{len(table)}/{len(tasks)} case(s) finished ({message})" + ("; interrupted by the user" if interrupted else "")
    summary = {
        "study": str(study.path) if study.path is not None else None, "name": study.name, "description": study.description,
        "base": str(study.base), "problems": list(dict.fromkeys(str(t.path) for t in tasks)),
        "sweep": {"field": study.sweep[0], "values": list(study.sweep[1])} if study.sweep else None,
        "analysis_name": study.analysis, "status": status, "message": message,
        "cases": [{"label": c.label, "folder": str(c.out.relative_to(out)), "status": c.status} for c in cases],
        "finished": len(table), "missing": missing, "counts": counts,
        "run_now": now, "skipped": len(tasks) - now - missing,
        "wall_s": time.perf_counter() - timing["started"],
        **_timing(root, run, info, timing),
        "analysis": figures,
        "table": ["table.parquet", "table.csv"],
    }
    if folder is not None:
        summary = folder.commit(summary, keep_complete=interrupted)  # an interrupted comparison keeps a complete one
        if folder.kept is not None:
            out = folder.target.resolve()
            _log.warning("%s", kept_message(folder.kept, folder.target, status))
        for r in records.values():
            r.folder = out / r.folder.relative_to(root)
        root = out
    else:
        summary["files"] = ["summary.json", *files]
        tmp = root / f".summary.json.{os.getpid()}"
        write_json(tmp, summary)
        try:
            os.replace(tmp, root / "summary.json")
        except OSError as exc:
            raise ResultWriteError(f"cannot write {root / 'summary.json'}: {exc.strerror or exc}") from None
    return StudyOutcome(status=status, message=message, out=root, table=table, summary=summary, records=list(records.values()),
                        cases=cases)


def _timing(root: Path, run: Sequence[CaseRecord], info: dict, timing: dict) -> dict[str, Any]:
    """``workers``, ``scheduler`` and ``timing`` of the summary: of this run, or, when it
    solved no case, of the earlier run that did (a no-op rerun keeps what was measured)."""
    if not run:
        try:
            before = json.loads((root / "summary.json").read_text(encoding="utf-8"))
        except (OSError, ValueError):
            before = None
        if isinstance(before, dict) and before.get("workers"):  # solved by it, or carried over from the run that did
            return {k: before.get(k) for k in ("workers", "scheduler", "timing")}
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
    return {"workers": info.get("workers"), "scheduler": info.get("scheduler"),
            "timing": {"plan_s": timing["plan_s"], "startup_s": info.get("startup_s"), "execute_s": timing["execute_s"],
                       "run_problem_s": run_s,
                       "overhead_per_case_s": gaps / len(run) if run else None,
                       "idle_per_case_s": (busy * n_workers - run_s) / len(run) if run else None}}


def _cases(tasks: Sequence[CaseTask], records: dict[str, CaseRecord], root: Path, out: Path) -> list[StudyCase]:
    """Every case with a result (finished now, before, or interrupted now), in design order."""
    cases = []
    for task in tasks:
        record = records.get(task.key)
        summary = _case_summary(task, records)
        if summary is None and record is not None:
            summary = dict(record.summary)  # interrupted now
        if summary is None:
            continue
        status = record.status if record is not None else Status(summary["status"])
        cases.append(StudyCase(task.label, task.path, dict(task.overrides), out / task.folder.relative_to(root), summary,
                               record.solution if record is not None else None, status))
    return cases


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


def solve_study(paths: Sequence[str | Path], out_dir: str | Path | None = None, sweep: tuple[str, Sequence[Any]] | None = None, *,
                warm_start: bool = False, plots: bool = True, workers: int = 1, **options: Any) -> StudyOutcome:
    """Compare several problem files, or one file over a sweep of one field (:func:`run_study` on
    :func:`~gtmodel.problems.study.design.comparison_study`).

    Parameters
    ----------
    paths : sequence of str or pathlib.Path
        Problem files (exactly one with ``sweep``).
    out_dir : str or pathlib.Path, optional
        Study folder (default ``results/<stem>_study`` or ``results/<stem>_sweep_<field>``),
        replaced whole when the run ends.
    sweep : tuple of (str, sequence), optional
        Field name and its values, e.g. ``("w", [0, 0.001, 0.01])``.
    warm_start : bool, optional
        Start each sweep case from the previous case's solution (in this process).
    plots : bool, optional
        Write PNG plots (each case's, and the overlays).
    workers : int, optional
        1 (default): in this process (a sweep is one chain reusing the NLP); more: a
        local Dask cluster (no overlay plots; with ``warm_start`` a sweep stays one chain,
        on one worker).
    **options
        Passed on to :func:`run_study` (``verbose``, ``heartbeat``, ``on_case``, ``progress``).

    Returns
    -------
    StudyOutcome

    Raises
    ------
    ProblemError
        No files, a sweep with several files, a missing problem file, an unknown swept
        field (before anything is written).
    ResultWriteError
        The study folder cannot be written.
    """
    study = comparison_study(paths, sweep, warm_start=warm_start, plots=plots)
    return run_study(study, out_dir, workers=workers, **options)


def mark_interrupted(out: str | Path) -> bool:
    """Mark a study folder's ``summary.json`` as ``interrupted`` (a run stopped before its end).

    The finished cases (``cases/``) and the table of earlier runs are kept (a rerun
    resumes from them); the summary says that the last run was interrupted, so that no
    earlier status looks current.

    Parameters
    ----------
    out : str or pathlib.Path
        The study folder.

    Returns
    -------
    bool
        Whether a summary was there and marked.
    """
    path = Path(out) / "summary.json"
    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    if not isinstance(summary, dict) or summary.get("status") not in {s.value for s in Status}:
        return False
    summary["status"] = Status.INTERRUPTED
    summary["message"] = f"interrupted by the user before the run ended (earlier: {summary.get('message')}); rerun to resume"
    summary["run_now"] = 0
    tmp = path.with_name(f".summary.json.{os.getpid()}")
    try:
        write_json(tmp, summary)
        os.replace(tmp, path)
    except OSError:
        return False
    return True
