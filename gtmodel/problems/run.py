"""Loading, solving and writing one problem file: the one path every kind goes through.

:func:`load_problem` reads and validates a file against its kind's schema (a light module:
a bad field is reported before the kind's solvers are imported) and builds the
declaration; :func:`solve_problem` solves it (Ctrl-C swallowed by a solver still stops
the run); :func:`run_problem` does both and writes the result folder, turning every
outcome into a summary with one :class:`~gtmodel.status.Status`.
"""

from __future__ import annotations

import json
import logging
import os
import shutil
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from gtmodel import _signals
from gtmodel._timing import add_phase, merge_phases, ordered_phases, phase_sum, timed
from gtmodel._toml import read_toml
from gtmodel.problems.overrides import apply_override
from gtmodel.errors import GtModelError, ProblemError, ResultWriteError
from gtmodel.problems.base import Problem, ProblemFile
from gtmodel.problems.registry import KINDS, LOOP_KINDS, RENAMED, canonical_kind, get_kind, get_schema
from gtmodel.problems.results import (MARKER, ResultFolder, _is_run_summary, check_output_folder, failed_folder, failure_summary, finished,
                                     holds_result, is_file_name, json_safe, kept_message, output_lock, write_json)
from gtmodel.report.result_page import REPORT_FILE, write_report
from gtmodel.problems.runtime import Heartbeat, InterruptGuard
from gtmodel.problems.schema import validate_document
from gtmodel.status import Status

__all__ = ["load_problem", "solve_problem", "write_results", "run_problem", "write_failure", "add_report", "RunOutcome",
           "InterruptedWithResult", "verified_pass_kept"]

_log = logging.getLogger("gtmodel")


def load_problem(path: str | Path, overrides: Mapping[str, Any] | None = None, settings: Mapping[str, Any] | None = None) -> Problem:
    """Read and validate a problem file.

    Parameters
    ----------
    path : str or pathlib.Path
        The TOML problem file.
    overrides : Mapping[str, Any], optional
        Fields to replace before validation (dotted names; a bare name is looked up in
        ``[parameters]`` first), e.g. ``{"w": 0.001}``.
    settings : Mapping[str, Any], optional
        Fields set from the command line (dotted names), also where the file leaves them to
        their default (e.g. ``{"interface.listen": "0.0.0.0:49152"}`` from ``gtmodel loop
        --listen``); validated by the schema like the file's own.

    Returns
    -------
    Problem
        The validated problem, ready for :func:`solve_problem`.

    Raises
    ------
    ProblemError
        Unreadable or non-UTF-8 file, TOML syntax error, a missing, unknown or invalid
        field (out of its physical range included), an invalid expression, a pose outside
        the workspace, unreadable data files, an override of a field the file does not
        have. The message names the file and the field.
    """
    path = Path(path)
    data = read_toml(path, ProblemError, "problem file")
    for key, value in (overrides or {}).items():
        data = apply_override(data, key, value, path)
    for key, value in (settings or {}).items():
        data = apply_override(data, key, value, path, create=True)
    file = ProblemFile(path)
    kind_name = canonical_kind(data.get("kind"), str(path))  # a renamed kind's former name: the new one, with a warning
    if not isinstance(kind_name, str) or kind_name not in KINDS:
        if "kind" not in data:
            raise ProblemError(f"{path}: missing field 'kind'")
        if isinstance(kind_name, str) and kind_name in LOOP_KINDS:
            raise file.fail("kind", f"a problem kind ({', '.join(KINDS)}); {kind_name!r} names a loop-controller file "
                                    f"({LOOP_KINDS[kind_name].what}), generated and checked by {LOOP_KINDS[kind_name].command}", kind_name)
        raise file.fail("kind", f"one of {', '.join(KINDS)}", kind_name)
    if data.get("kind") != kind_name:
        data = {**data, "kind": kind_name}
    doc = validate_document(get_schema(kind_name), data, path)  # before the kind (its solvers) is imported
    name = doc.name or path.stem
    declaration = get_kind(kind_name).load(doc, file, name)
    return Problem(path=path, name=name, kind=kind_name, description=doc.description, declaration=declaration,
                   data=data, overrides=dict(overrides or {}))


def solve_problem(problem: Problem, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> Any:
    """Solve a loaded problem with its kind's solver.

    Parameters
    ----------
    problem : Problem
        From :func:`load_problem`.
    verbose : bool, optional
        Show the solver's iteration log.
    previous : Any, optional
        The solution of the previous case of a sweep (its NLP is reused when only named
        parameters differ).
    warm_start : bool, optional
        Start from ``previous``'s solution.

    Returns
    -------
    Any
        The kind's solution; ``get_kind(problem.kind).status(solution)`` is its status.

    Raises
    ------
    GtModelError
        Bad input discovered while building or solving (e.g. degenerate data).
    KeyboardInterrupt
        Ctrl-C, SIGINT or SIGTERM during the solve (also when the solver swallowed it), unless
        the kind ends on a signal (:attr:`~gtmodel.problems.base.ProblemKind.ends_on_signal`:
        the loop of ``gtmodel loop``, whose solution then says ``interrupted`` and is written);
        an :class:`InterruptedWithResult` (carrying the solution) where a mesh refinement had
        verified a pass before the signal.
    """
    kind = get_kind(problem.kind)
    with InterruptGuard() as guard:
        solution = kind.solve(problem.declaration, verbose=verbose, previous=previous, warm_start=warm_start)
        if not kind.ends_on_signal and guard.interrupted:
            note = verified_pass_kept(solution)
            if note is not None:
                raise InterruptedWithResult(solution, note)
            guard.check()
    return solution


class InterruptedWithResult(KeyboardInterrupt):
    """Ctrl-C (SIGINT, SIGTERM) during a mesh refinement that had verified a pass: that pass is the result.

    A :class:`KeyboardInterrupt` (a caller that stops on Ctrl-C stops), carrying the solution
    the refinement returned (its last verified pass) for a caller that keeps it
    (:func:`run_problem` writes it with status ``interrupted``).

    Parameters
    ----------
    solution : object
        The kind's solution.
    note : str
        What was kept (:func:`verified_pass_kept`).
    """

    def __init__(self, solution: Any, note: str) -> None:
        super().__init__(note)
        self.solution = solution
        self.note = note


def verified_pass_kept(solution: Any) -> str | None:
    """What a mesh refinement stopped by Ctrl-C kept, if it had verified a pass; else None.

    A signal during a refinement ends it with its last verified pass
    (:mod:`gtmodel.modeling.ocp.refinement_interrupt`), or, where the solver swallowed the
    signal and the pass ended without a solution, with the verified pass the refinement
    chose; that pass is the run's result, with status ``interrupted`` (docs/reliability.md).

    Parameters
    ----------
    solution : object
        A kind's solution: an :class:`~gtmodel.modeling.OptimizationResult` or a solution
        holding one as ``result``.

    Returns
    -------
    str or None
        E.g. ``"interrupted by the user during mesh refinement; the result is its last
        verified pass (pass 2 of 2)"``.
    """
    result = solution if hasattr(solution, "refinement") else getattr(solution, "result", None)
    verification = getattr(result, "verification", None)
    if not getattr(result, "refinement", None) or verification is None or not getattr(verification, "passed", False):
        return None
    entries = [e for e in result.refinement if isinstance(e, dict)]
    k = next((i + 1 for i, e in enumerate(entries) if e.get("returned")), len(entries))
    return (f"interrupted by the user during mesh refinement; the result is its last verified pass "
            f"(pass {k} of {len(entries)})")


def solution_timing(solution: Any) -> dict[str, dict[str, float]]:
    """A solution's phase times (:mod:`gtmodel._timing`): its ``timing``, else its optimisation result's
    (``solution.result.timing``: a point-to-point solution), else none.

    Parameters
    ----------
    solution : object
        What a kind's ``solve`` returned.

    Returns
    -------
    dict
        ``phase -> {"wall_s", "cpu_s"}`` (empty when the solution records none).
    """
    own = getattr(solution, "timing", None)
    if not own:
        own = getattr(getattr(solution, "result", None), "timing", None)
    return own if isinstance(own, dict) else {}


def write_results(problem: Problem, solution: Any, out_dir: str | Path, plots: bool = True, report: bool = False,
                  timing: Mapping[str, Mapping[str, float]] | None = None) -> dict[str, Any]:
    """Write the result folder of a solved problem, replacing the folder only when complete.

    Data files and plots are written only when the solver returned a solution, never
    for a failed solve's last iterate; ``summary.json`` lists every file.

    Parameters
    ----------
    problem : Problem
        The problem.
    solution : Any
        Its solution from :func:`solve_problem`.
    out_dir : str or pathlib.Path
        Result folder (replaced whole; see :mod:`gtmodel.problems.results`).
    plots : bool, optional
        Write PNG plots (default True).
    report : bool, optional
        Also write ``report.html``, the folder's page (:mod:`gtmodel.report.result_page`;
        default False; ``gtmodel solve`` writes it unless ``--no-report``).
    timing : mapping, optional
        The run's phase times so far, ``phase -> {"wall_s", "cpu_s"}`` (s; :func:`run_problem`'s
        ``load``, the solution's ``build``, ``guess``, ``solve``, ...); default the solution's
        own (its ``timing`` attribute, if any). ``summary.json`` gets them as ``timing``, with
        ``writing`` (this call up to ``summary.json`` itself) and ``total`` (their sum).

    Returns
    -------
    dict
        The summary that was written.

    Raises
    ------
    ResultWriteError
        A file or the folder cannot be written (names the path); the earlier folder is
        left as it was.
    """
    with ResultFolder(out_dir) as folder:
        return _write_into(folder, problem, solution, plots, report, timing)


def _write_into(folder: ResultFolder, problem: Problem, solution: Any, plots: bool, report: bool,
                timing: Mapping[str, Mapping[str, float]] | None, interrupted: str | None = None, keep_earlier: bool = True) -> dict[str, Any]:
    """:func:`write_results` into ``folder``; ``interrupted``: the note of a refinement stopped by
    Ctrl-C after a verified pass (its status is then ``interrupted``). A run that did not finish
    leaves a complete earlier result as it was (:meth:`ResultFolder.commit`, ``keep_complete``), said on stderr."""
    kind = get_kind(problem.kind)
    phases = {k: dict(v) for k, v in (timing if timing is not None else solution_timing(solution)).items()}
    wall, cpu = time.perf_counter(), time.process_time()
    try:
        written = kind.write(problem.declaration, solution, folder.path, plots, problem.name)
        summary: dict[str, Any] = {"problem": str(problem.path), "name": problem.name, "kind": problem.kind}
        if problem.overrides:
            summary["overrides"] = dict(problem.overrides)
        summary.update(written.fields)
        summary["status"] = kind.status(solution)
        if interrupted:
            summary["status"] = Status.INTERRUPTED
            summary["message"] = f"{interrupted}; {summary.get('message')}" if summary.get("message") else interrupted
        names = {p.name for p in folder.path.iterdir()} | {"summary.json"} | ({REPORT_FILE} if report else set())
        summary["file_descriptions"] = kind.describe_files(sorted(names))
        if report:
            _write_report(folder.path, summary)
        add_phase(phases, "writing", time.perf_counter() - wall, time.process_time() - cpu)
        summary["timing"] = ordered_phases(phases)
        out = folder.commit(summary, keep_complete=keep_earlier and not finished(summary["status"], kind.ends_on_signal))
    except OSError as exc:  # a ResultWriteError too: one message, naming the target
        raise folder.write_error(exc) from None
    if folder.kept is not None:
        _log.warning("%s", kept_message(folder.kept, folder.target, out["status"]))
    return out


def _write_report(path: Path, summary: dict[str, Any]) -> None:
    """``report.html`` of a folder being written, from the summary as :meth:`ResultFolder.commit` will write it."""
    files = sorted({p.name for p in path.iterdir() if p.name != "summary.json"} | {REPORT_FILE})
    write_report(path, json_safe({**summary, "files": ["summary.json", *files], "written_by": MARKER}))


def add_report(folder: str | Path) -> Path:
    """Write ``report.html`` into a finished result folder (``gtmodel report DIR``).

    The page (:func:`gtmodel.report.result_page.write_report`) is written beside the
    folder's files under a hidden name and renamed into place, then ``summary.json``, which
    lists every file of its folder, is rewritten (likewise) with ``report.html`` in its
    ``files``; nothing else in the folder changes. The folder is locked as for a run
    (:func:`~gtmodel.problems.results.output_lock`: the lock file beside it, removed at the
    end, is the only file written outside it).

    Parameters
    ----------
    folder : str or pathlib.Path
        A result folder: its ``summary.json`` is a run's summary (status and the
        ``written_by`` marker).

    Returns
    -------
    pathlib.Path
        The written page.

    Raises
    ------
    ResultWriteError
        ``folder`` is not a result folder (no run's ``summary.json``, or a symbolic link in
        its place), is in use by a run, or cannot be written (names the folder). Files of
        the folder that are symbolic links or lead outside it are left out of the page with
        a warning in it (:func:`gtmodel.report.result_page.render_report`).
    """
    folder = Path(folder)
    summary_path = folder / "summary.json"
    if summary_path.is_symlink():
        raise ResultWriteError(f"{summary_path}: a symbolic link; a result folder contributes only regular files inside it")
    if not _is_run_summary(summary_path):
        raise ResultWriteError(f"{folder}: not a gtmodel result folder (no summary.json of a run); give the folder a "
                               "`gtmodel solve` wrote")
    with output_lock(folder):
        summary = json.loads(summary_path.read_text(encoding="utf-8"))
        files = list(summary.get("files") or ["summary.json"])
        if REPORT_FILE not in files:
            files.append(REPORT_FILE)
        summary["files"] = files
        hidden = [folder / f".{name}.partial-{os.getpid()}" for name in (REPORT_FILE, "summary.json")]
        try:
            write_report(folder, summary, path=hidden[0])
            write_json(hidden[1], summary)
            os.replace(hidden[0], folder / REPORT_FILE)
            os.replace(hidden[1], summary_path)  # summary.json last, as a run writes it
        except OSError as exc:
            raise ResultWriteError(f"cannot write the report of {folder}: {exc.strerror or exc}") from None
        finally:
            for p in hidden:
                p.unlink(missing_ok=True)
    return folder / REPORT_FILE


@dataclass
class RunOutcome:
    """What :func:`run_problem` did.

    Parameters
    ----------
    path : pathlib.Path
        The problem file.
    out : pathlib.Path
        The result folder.
    status : Status
        The outcome (also ``invalid_input``, ``internal_error``, ``interrupted``).
    summary : dict
        The summary as written (or as it would have been, if writing failed).
    problem : Problem or None
        The loaded problem (None when loading failed).
    solution : Any
        The kind's solution (None when there is none).
    error : BaseException or None
        The exception that ended the run early, if any.
    written : bool
        Whether the result folder was written.
    kept : pathlib.Path or None
        The result folder left as it was: the run did not finish over a complete earlier
        result, and ``out`` is the folder beside it that it wrote instead
        (:func:`~gtmodel.problems.results.failed_folder`); None otherwise.
    """

    path: Path
    out: Path
    status: Status
    summary: dict
    problem: Problem | None = None
    solution: Any = None
    error: BaseException | None = None
    written: bool = True
    kept: Path | None = None

    @property
    def exit_code(self) -> int:
        """Exit code of the ``gtmodel`` command for this outcome."""
        return self.status.exit_code


def run_problem(
    path: str | Path,
    out: str | Path | None = None,
    overrides: Mapping[str, Any] | None = None,
    verbose: bool = False,
    plots: bool = True,
    previous: Any = None,
    warm_start: bool = False,
    heartbeat: bool = False,
    report: bool = False,
    settings: Mapping[str, Any] | None = None,
    keep_earlier: bool = True,
) -> RunOutcome:
    """Load, solve and write one problem; every outcome becomes a status and a summary.

    Parameters
    ----------
    path : str or pathlib.Path
        The problem file.
    out : str or pathlib.Path, optional
        Result folder (default ``results/<problem name>``).
    overrides : Mapping[str, Any], optional
        Field overrides (a sweep case).
    verbose : bool, optional
        Solver progress.
    plots : bool, optional
        Write PNG plots.
    previous : Any, optional
        Previous solution of a sweep.
    warm_start : bool, optional
        Start from ``previous``.
    heartbeat : bool, optional
        Log a line every few seconds while solving (when nothing else shows progress).
    report : bool, optional
        Also write ``report.html`` (:func:`write_results`).
    settings : Mapping[str, Any], optional
        Command-line settings of fields (:func:`load_problem`).
    keep_earlier : bool, optional
        A run that did not finish leaves a complete earlier result in ``out`` as it was
        and writes ``<out>.failed`` instead (default True; a study's case folders, which
        the study reruns by its own rules, pass False).

    Returns
    -------
    RunOutcome
        Never raises for bad input, solver failure or internal errors (their status says
        so); a :class:`KeyboardInterrupt` is recorded as ``interrupted`` (the caller
        decides whether to stop). A problem file that does not exist writes nothing.
    """
    path = Path(path)
    target = Path(out) if out is not None else Path("results") / path.stem
    problem: Problem | None = None
    if not path.is_file():  # a mistyped path: reported, nothing written (no results/<typo>/)
        what = "it is a folder" if path.is_dir() else "no such file"
        return _failed(path, target, None, ProblemError(f"{path}: cannot read the problem file ({what})"), Status.INVALID_INPUT,
                       write=False)
    phases: dict[str, dict[str, float]] = {}
    folder: ResultFolder | None = None
    solution: Any = None
    try:
        with timed(phases, "load"):
            problem = load_problem(path, overrides, settings)
        target = Path(out) if out is not None else Path("results") / problem.name
        label = f"solving {problem.name} ({problem.kind})"
        _log.info("%s ...", label)
        call: dict[str, dict[str, float]] = {}
        interrupted = None
        with Heartbeat(label, enabled=heartbeat), timed(call, "other"):
            try:
                solution = solve_problem(problem, verbose=verbose, previous=previous, warm_start=warm_start)
            except InterruptedWithResult as stop:  # the refinement's last verified pass: the result, status interrupted
                solution, interrupted = stop.solution, stop.note
        own = solution_timing(solution)
        merge_phases(phases, own)
        rest = phase_sum(own)  # what the solve call spent outside its timed phases (flattening, the kind's own work)
        add_phase(phases, "other", call["other"]["wall_s"] - rest["wall_s"], call["other"]["cpu_s"] - rest["cpu_s"])
        if interrupted:  # the run is stopping: its kept pass is written, further signals only counted
            with _signals.settled(), ResultFolder(target) as folder:
                summary = _write_into(folder, problem, solution, plots, report, phases, interrupted, keep_earlier)
            return RunOutcome(path, folder.target, Status(summary["status"]), summary, problem, solution, kept=folder.kept)
        with InterruptGuard() as guard, ResultFolder(target) as folder:
            summary = _write_into(folder, problem, solution, plots, report, phases, keep_earlier=keep_earlier)
            if not get_kind(problem.kind).ends_on_signal:  # a loop's signal ended its run: its results stand
                guard.check()
        return RunOutcome(path, folder.target, Status(summary["status"]), summary, problem, solution, kept=folder.kept)
    except KeyboardInterrupt as exc:
        if folder is not None and folder.committed:  # the signal came once the folder was in place: its result stands
            summary = json.loads((folder.target / "summary.json").read_text(encoding="utf-8"))
            return RunOutcome(path, folder.target, Status(summary["status"]), summary, problem, solution, kept=folder.kept)
        return _failed(path, target, problem, exc, Status.INTERRUPTED, keep_earlier=keep_earlier)
    except GtModelError as exc:  # a ResultWriteError too: the earlier result must not look current
        return _failed(path, target, problem, exc, Status.INVALID_INPUT, keep_earlier=keep_earlier)
    except Exception as exc:  # noqa: BLE001 - a defect: reported with its status, never lost
        if _signals.received():  # CasADi turns a signal inside a solver into NotImplementedError/SystemError
            return _failed(path, target, problem, KeyboardInterrupt("interrupted"), Status.INTERRUPTED, keep_earlier=keep_earlier)
        if isinstance(exc, MemoryError):  # too large for this machine: bad input, with a status and a message
            return _failed(path, target, problem, out_of_memory(path), Status.INVALID_INPUT, keep_earlier=keep_earlier)
        _log.debug("internal error", exc_info=True)
        return _failed(path, target, problem, exc, Status.INTERNAL_ERROR, keep_earlier=keep_earlier)


def out_of_memory(what: Path | str) -> ProblemError:
    """The error a :class:`MemoryError` becomes: bad input (exit 2) naming what was too large.

    Parameters
    ----------
    what : pathlib.Path or str
        The problem file (or the command's input).

    Returns
    -------
    ProblemError
        To be recorded or raised by the caller.
    """
    return ProblemError(f"{what}: out of memory: the problem or a data file it names is too large for this machine "
                        "(reduce collocation.elements/points, the data files, or run where more memory is available)")


def _failed(path: Path, target: Path, problem: Problem | None, error: BaseException, status: Status, write: bool = True,
            keep_earlier: bool = True) -> RunOutcome:
    kind = get_kind(problem.kind) if problem is not None else None
    summary = failure_summary(
        path, error, status, kind=problem.kind if problem else _peek_kind(path), name=problem.name if problem else _peek_name(path),
        empty_fields=kind.empty_fields if kind is not None else (),
    )
    written, kept, out = False, None, target
    if write:
        with _signals.protected():
            written, summary, why, out = write_failure(target, summary, keep_earlier)
        kept = target if out != target else None
        if not written and not isinstance(error, ResultWriteError):  # else the run's own message says it
            _log.warning("gtmodel: could not write %s: %s", out / "summary.json", why)
    return RunOutcome(path, out, status, summary, problem, None, error, written, kept)


def write_failure(target: Path, summary: dict[str, Any], keep_earlier: bool = True) -> tuple[bool, dict[str, Any], str, Path]:
    """Write a failed run's ``summary.json`` alone, never over a complete earlier result.

    Where ``target`` holds a complete result (:func:`~gtmodel.problems.results.holds_result`),
    it is left as it was and the summary goes to the folder beside it,
    ``<target>.failed`` (:func:`~gtmodel.problems.results.failed_folder`). Else the summary
    replaces ``target``; if even that cannot be written (a full disk), the earlier folder
    (a failed run's summary, never a complete result nor a folder of the user's) is
    removed, so that it cannot look current, and the write is tried once more.

    Parameters
    ----------
    target : pathlib.Path
        The result folder.
    summary : dict
        The failed run's summary (:func:`~gtmodel.problems.results.failure_summary`).
    keep_earlier : bool, optional
        Leave a complete earlier result as it was (default True); False replaces it (a
        study's case folder).

    Returns
    -------
    tuple of (bool, dict, str, pathlib.Path)
        Whether it was written, the summary as written, why not (empty if written), and
        the folder it went to (``target``, or the folder beside it).
    """
    out = target
    try:
        with ResultFolder(target) as folder:
            written = folder.commit(summary, keep_complete=keep_earlier)
            return True, written, "", folder.target
    except ResultWriteError as exc:
        why = str(exc)
    if keep_earlier and holds_result(target):  # a complete earlier result is never removed for a failed run's summary
        return False, summary, why, failed_folder(target)
    try:
        check_output_folder(target)  # never remove what is not a gtmodel result folder
    except ResultWriteError:
        return False, summary, why, out
    aside = target.parent / f".{target.name}.old-{os.getpid()}"
    try:
        if target.is_dir():
            os.replace(target, aside)
            shutil.rmtree(aside, ignore_errors=True)
    except OSError:
        pass
    try:  # the earlier files are gone: there may be room now
        with ResultFolder(target) as folder:
            return True, folder.commit(summary), "", out
    except ResultWriteError:
        pass
    gone = "; the earlier summary there was removed so that it cannot look current" if not target.exists() else ""
    return False, summary, why + gone, out


def _peek_name(path: Path) -> str:
    """The name of a problem that could not be loaded: its ``name`` field if readable, else the file's stem."""
    try:
        name = read_toml(path, ProblemError, "problem file").get("name") if path.is_file() else None
    except GtModelError:
        name = None
    return name if is_file_name(name) else path.stem


def _peek_kind(path: Path) -> str | None:
    try:
        kind = read_toml(path, ProblemError, "problem file").get("kind")
    except GtModelError:
        return None
    kind = RENAMED.get(kind, kind) if isinstance(kind, str) else kind
    return kind if isinstance(kind, str) and kind in KINDS else None
