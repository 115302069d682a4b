"""The cases of a study: keys, folders, and one case solved (the part that runs on a worker).

A case is the base problem file with its overrides. Its **key** is the SHA-256 of the
canonical JSON of the resolved problem document (after the overrides) and of every data
file the document names (path and content hash), so a case is rerun exactly when its
problem changed. Its folder ``cases/<label>-<key[:10]>/`` holds the kind's usual files
written by :func:`~gtmodel.problems.run.run_problem` (atomically, see
:mod:`gtmodel.problems.results`) and a ``summary.json`` stamped with the key (field
``study``): a folder with the same key and a final status is a finished case.

:func:`run_unit` (one case, or a warm-started chain of cases) is what an executor runs, in
this process or on a Dask worker; it never raises for a failing case (the status says it).
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import re
import signal
import socket
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

from gtmodel._toml import read_toml
from gtmodel.errors import ProblemError
from gtmodel.problems.overrides import apply_override
from gtmodel.problems.results import ResultFolder, failure_summary, json_safe
from gtmodel.problems.run import run_problem
from gtmodel.status import Status

__all__ = ["CaseTask", "CaseRecord", "case_key", "resolve_document", "safe_name", "finished_summary", "run_unit",
           "record_failure", "dask_setup"]

_log = logging.getLogger("gtmodel")


def safe_name(label: str, limit: int = 80) -> str:
    """A file-name-safe version of a case label (letters, digits, ``-_.=``; at most ``limit``).

    Parameters
    ----------
    label : str
        The label.
    limit : int, optional
        Longest result.

    Returns
    -------
    str
    """
    text = re.sub(r"_+", "_", "".join(c if c.isalnum() or c in "-_.=" else "_" for c in label)).strip("_")
    return text[:limit].rstrip("_") or "case"


def resolve_document(base: Path, overrides: Mapping[str, Any], data: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The base problem document with a case's overrides applied.

    Parameters
    ----------
    base : pathlib.Path
        The base problem file.
    overrides : Mapping[str, Any]
        Field -> value.
    data : Mapping[str, Any], optional
        The parsed base file (read from ``base`` if not given).

    Returns
    -------
    dict

    Raises
    ------
    ProblemError
        The file cannot be read, or an override names a field the file does not have
        (the message names the base file and the field).
    """
    doc = dict(data) if data is not None else read_toml(base, ProblemError, "problem file")
    for key, value in overrides.items():
        doc = apply_override(doc, key, value, base)
    return doc


def _file_hash(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _named_files(node: Any, folder: Path, found: dict[str, str]) -> None:
    """Every string of the document that names an existing file (relative to ``folder``)."""
    if isinstance(node, dict):
        for v in node.values():
            _named_files(v, folder, found)
    elif isinstance(node, list):
        for v in node:
            _named_files(v, folder, found)
    elif isinstance(node, str) and node and len(node) < 4096 and node not in found:
        try:
            p = Path(node) if Path(node).is_absolute() else folder / node
            if p.is_file():
                found[node] = _file_hash(p)
        except (OSError, ValueError):
            pass


def case_key(base: Path, document: Mapping[str, Any]) -> str:
    """The key of a case: SHA-256 of its resolved document and the data files it names.

    Parameters
    ----------
    base : pathlib.Path
        The base problem file (data file names are relative to its folder).
    document : Mapping[str, Any]
        The resolved problem document (:func:`resolve_document`).

    Returns
    -------
    str
        64 hexadecimal digits.
    """
    files: dict[str, str] = {}
    _named_files(dict(document), Path(base).parent, files)
    canonical = json.dumps({"document": json_safe(dict(document)), "files": files}, sort_keys=True, separators=(",", ":"),
                           ensure_ascii=True, allow_nan=False)
    return hashlib.sha256(canonical.encode("utf-8")).hexdigest()


@dataclass
class CaseTask:
    """One case to solve (picklable: sent to Dask workers).

    Parameters
    ----------
    label : str
        Case label.
    key : str
        Case key (:func:`case_key`).
    path : pathlib.Path
        The base problem file.
    overrides : dict
        Field -> value.
    folder : pathlib.Path
        The case's result folder.
    design : dict, optional
        Design columns (stamped into the summary).
    plots : bool, optional
        Write the case's PNG plots.
    verbose : bool, optional
        Solver progress.
    heartbeat : bool, optional
        Log a line every few seconds while solving.
    """

    label: str
    key: str
    path: Path
    overrides: dict[str, Any]
    folder: Path
    design: dict[str, Any] = field(default_factory=dict)
    plots: bool = True
    verbose: bool = False
    heartbeat: bool = False


@dataclass
class CaseRecord:
    """What solving one case gave.

    Parameters
    ----------
    label : str
        Case label.
    key : str
        Case key.
    folder : pathlib.Path
        Its result folder.
    status : Status
        Its status (``interrupted`` when stopped).
    wall_s : float or None
        Seconds inside :func:`~gtmodel.problems.run.run_problem` (load, solve, write) [s];
        None for a case no worker finished.
    summary : dict
        Its summary as written.
    written : bool
        Whether the folder was written.
    solution : Any, optional
        The kind's solution (only when run in this process and asked for).
    started : float or None, optional
        When :func:`~gtmodel.problems.run.run_problem` started (``time.time()``) [s].
    worker : str, optional
        The process that ran it (``host:pid``).
    """

    label: str
    key: str
    folder: Path
    status: Status
    wall_s: float | None
    summary: dict[str, Any]
    written: bool = True
    solution: Any = None
    started: float | None = None
    worker: str = ""


def finished_summary(folder: Path, key: str) -> dict[str, Any] | None:
    """The summary of a finished case in ``folder`` with this key, else None.

    Parameters
    ----------
    folder : pathlib.Path
        The case folder.
    key : str
        The expected key.

    Returns
    -------
    dict or None
        None when there is no readable ``summary.json``, its key differs, or its status
        is ``interrupted`` (an unfinished case).
    """
    try:
        summary = json.loads((Path(folder) / "summary.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(summary, dict) or (summary.get("study") or {}).get("key") != key:
        return None
    if summary.get("status") not in {s.value for s in Status} or summary["status"] == Status.INTERRUPTED:
        return None
    return summary


def _stamp(folder: Path, task: CaseTask, wall_s: float) -> dict[str, Any] | None:
    """Add the case's key, label, design and time to its summary.json (atomic replace)."""
    path = folder / "summary.json"
    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
        summary["study"] = {"key": task.key, "label": task.label, "design": task.design, "wall_s": wall_s}
        tmp = folder / f".summary.json.{os.getpid()}"
        tmp.write_text(json.dumps(json_safe(summary), indent=2) + "\n", encoding="utf-8")
        os.replace(tmp, path)
        return summary
    except (OSError, ValueError) as exc:
        _log.warning("gtmodel: could not stamp %s: %s", path, exc)
        return None


def _run_one(task: CaseTask, previous: Any, warm_start: bool, keep_solution: bool) -> tuple[CaseRecord, Any]:
    started = time.time()
    start = time.perf_counter()
    outcome = run_problem(task.path, task.folder, task.overrides, verbose=task.verbose, plots=task.plots,
                          previous=previous, warm_start=warm_start, heartbeat=task.heartbeat, keep_earlier=False)  # the study reruns its cases
    wall = time.perf_counter() - start
    summary = outcome.summary
    if task.key and outcome.written and outcome.status is not Status.INTERRUPTED:
        summary = _stamp(task.folder, task, wall) or summary
    record = CaseRecord(task.label, task.key, task.folder, outcome.status, wall, summary, outcome.written,
                        outcome.solution if keep_solution else None, started, f"{socket.gethostname()}:{os.getpid()}")
    return record, outcome.solution


def run_unit(tasks: Sequence[CaseTask], chain: bool = False, warm_start: bool = False,
             keep_solutions: bool = False) -> list[CaseRecord]:
    """Solve one case, or a chain of cases in order (the job of one executor task).

    In a chain, each case gets the previous case's solution (its NLP is reused where
    the kind supports it) and, with ``warm_start``, starts from it. A case that stops
    with ``interrupted`` ends the chain (the remaining cases are not run).

    Parameters
    ----------
    tasks : sequence of CaseTask
        The cases (one, unless ``chain``).
    chain : bool, optional
        Pass each solution on to the next case.
    warm_start : bool, optional
        Start each case of a chain from the previous solution.
    keep_solutions : bool, optional
        Keep the solutions in the records (in-process only: they are not sent back from
        workers).

    Returns
    -------
    list of CaseRecord
        One per case run, in order. Never raises for a failing case.
    """
    records = []
    previous = None
    for task in tasks:
        record, solution = _run_one(task, previous if chain else None, warm_start and chain, keep_solutions)
        records.append(record)
        if record.status is Status.INTERRUPTED:
            break
        if solution is not None:
            previous = solution
    return records


def record_failure(task: CaseTask, message: str, status: Status = Status.INTERNAL_ERROR) -> CaseRecord:
    """Record a case that no worker could finish (e.g. its worker died too often).

    Writes the case folder with a failure summary (stamped with the key) so that the
    table has its row; a folder that cannot be written is logged and the record kept.

    Parameters
    ----------
    task : CaseTask
        The case.
    message : str
        What happened.
    status : Status, optional
        Default ``internal_error``.

    Returns
    -------
    CaseRecord
    """
    summary = failure_summary(task.path, message, status)
    summary["study"] = {"key": task.key, "label": task.label, "design": task.design, "wall_s": None}
    written = False
    try:
        with ResultFolder(task.folder) as folder:
            summary = folder.commit(summary)
            written = True
    except Exception as exc:  # noqa: BLE001 - the record keeps the failure
        _log.warning("gtmodel: could not write %s: %s", task.folder, exc)
    return CaseRecord(task.label, task.key, task.folder, Status(status), None, summary, written)


def dask_setup(worker: Any = None) -> None:
    """Dask preload hook of a local cluster's workers (this module is their ``preload``).

    A worker process ignores SIGINT: Ctrl-C on a terminal reaches the whole process group,
    and the study's own process stops the cases and closes the cluster (no traceback from
    every worker); SIGTERM gets its default action back, and the ``gtmodel`` logger drops
    the handlers a forked worker inherited (warnings still reach standard error, info
    lines do not). Importing this module on start also makes gtmodel's import part of
    the worker's startup, not of its first case.

    Parameters
    ----------
    worker : distributed.Worker, optional
        The starting worker (unused).
    """
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
    for handler in list(_log.handlers):
        _log.removeHandler(handler)
    _log.setLevel(logging.WARNING)
