"""Studies: several problem files, or one file over a sweep of one field, and a comparison.

Each case is one :func:`~gtmodel.problems.run.run_problem` into its own folder inside the
study folder; the comparison table takes its columns from the cases' kinds
(:attr:`~gtmodel.problems.base.ProblemKind.columns`), so a study of calibrations
compares errors and a study of motions compares final times (Dressler (2012), Table 3.1).
The study folder, like a result folder, is replaced only when the study ends; Ctrl-C
stops the whole study (status ``interrupted``).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence

from gtmodel.errors import ProblemError
from gtmodel.problems.base import Column
from gtmodel.problems.registry import KINDS
from gtmodel.problems.results import ResultFolder
from gtmodel.problems.study_cases import CaseRecord, CaseTask
from gtmodel.problems.study_engine import execute
from gtmodel.status import Status

__all__ = ["StudyCase", "StudyResult", "solve_study", "comparison_columns", "write_comparison"]

_log = logging.getLogger("gtmodel")


@dataclass
class StudyCase:
    """One case of a study (a file, or one value of a sweep).

    Parameters
    ----------
    label : str
        Case label (problem name, or ``name[w=0.001]``).
    path : pathlib.Path
        Problem file.
    overrides : dict
        Fields replaced for this case.
    out : pathlib.Path
        Its result folder (inside the study folder once the study is complete).
    summary : dict
        Its summary (status ``invalid_input`` with a message for bad input).
    solution : Any
        Its solution (None when it could not be loaded or solved).
    status : Status
        Its status.
    """

    label: str
    path: Path
    overrides: dict
    out: Path
    summary: dict = field(default_factory=dict)
    solution: Any = None
    status: Status = Status.OPTIMAL


@dataclass
class StudyResult:
    """A finished (or interrupted) study.

    Parameters
    ----------
    cases : list of StudyCase
        In the order solved.
    status : Status
        The worst status of the cases (``interrupted`` if it was stopped).
    out : pathlib.Path
        The study folder.
    """

    cases: list[StudyCase]
    status: Status
    out: Path

    @property
    def exit_code(self) -> int:
        """Exit code of the ``gtmodel`` command for this study."""
        return self.status.exit_code


def _safe_folder(label: str) -> str:
    return "".join(c if c.isalnum() or c in "-_.=" else "_" for c in label).strip("_")


def solve_study(
    paths: Sequence[str | Path],
    out_dir: str | Path,
    sweep: tuple[str, Sequence[Any]] | None = None,
    verbose: bool = False,
    plots: bool = True,
    warm_start: bool = False,
    on_case: Callable[[StudyCase], None] | None = None,
    heartbeat: bool = False,
    workers: int = 1,
) -> StudyResult:
    """Solve several problem files, or one file over a sweep of one field, and compare.

    The cases run on the study engine's executors
    (:func:`~gtmodel.problems.study_engine.execute`). In this process, a sweep over a
    named parameter reuses the NLP built for the first case (and, with ``warm_start``,
    starts from the previous solution). Bad input in one case is that
    case's status and the study goes on; Ctrl-C stops the study. ``out_dir`` receives one
    folder per case, ``comparison.csv``, ``comparison.md``, overlay plots and
    ``summary.json`` (the study's status and its cases).

    Parameters
    ----------
    paths : sequence of str or pathlib.Path
        Problem files (exactly one with ``sweep``).
    out_dir : str or pathlib.Path
        Study folder (replaced whole when the study ends).
    sweep : tuple of (str, sequence), optional
        Field name and its values, e.g. ``("w", [0, 0.001, 0.01])``.
    verbose : bool, optional
        Solver progress.
    plots : bool, optional
        Write PNG plots.
    warm_start : bool, optional
        Start each sweep case from the previous case's solution.
    on_case : callable, optional
        Called with each finished :class:`StudyCase` (progress reporting).
    heartbeat : bool, optional
        Log a line every few seconds during long solves.
    workers : int, optional
        1 (default): the cases one after another in this process (a sweep is one chain:
        the NLP is reused, ``warm_start`` applies); more: the cases in parallel on a local
        Dask cluster (:func:`~gtmodel.problems.study_engine.execute`; no overlay plots, no
        warm start).

    Returns
    -------
    StudyResult

    Raises
    ------
    ProblemError
        A sweep with more than one file, or no files.
    ResultWriteError
        The study folder cannot be written (names the path).
    """
    out_dir = Path(out_dir)
    if sweep is not None and len(paths) != 1:
        raise ProblemError(f"--sweep needs exactly one problem file, got {len(paths)}")
    if not paths:
        raise ProblemError("a study needs at least one problem file")
    specs = [(Path(paths[0]), {sweep[0]: v}) for v in sweep[1]] if sweep is not None else [(Path(p), {}) for p in paths]
    folder = ResultFolder(out_dir)
    cases: list[StudyCase] = []
    interrupted = False
    tasks = []
    for path, overrides in specs:
        suffix = "".join(f"[{k}={v}]" for k, v in overrides.items())
        tasks.append(CaseTask(suffix, "", path, overrides, folder.path / _safe_folder(path.stem + suffix), plots=plots,
                              verbose=verbose, heartbeat=heartbeat))
    chain = sweep is not None and workers == 1  # one chain: the NLP of the first case is reused, warm starts
    units = [tasks] if chain else [[t] for t in tasks]

    def on_record(record: CaseRecord) -> None:
        task = next(t for t in tasks if t.folder == record.folder)
        label = (record.summary.get("name") or task.path.stem) + task.label
        case = StudyCase(label, task.path, task.overrides, out_dir / task.folder.name, record.summary, record.solution, record.status)
        cases.append(case)
        if on_case is not None:
            on_case(case)

    try:
        try:
            execute(units, on_record, workers=workers, chain=chain, warm_start=warm_start and chain, keep_solutions=True)
        except KeyboardInterrupt:
            interrupted = True
        order = {t.folder.name: i for i, t in enumerate(tasks)}
        cases.sort(key=lambda c: order[c.out.name])
        status = Status.INTERRUPTED if interrupted else Status.worst(c.status for c in cases)
        files = write_comparison(cases, folder.path, plots=plots)
        folder.commit({
            "study": [str(p) for p in paths],
            "sweep": {"field": sweep[0], "values": list(sweep[1])} if sweep else None,
            "status": status,
            "message": "interrupted by the user" if interrupted else f"{len(cases)} case(s)",
            "cases": [{"label": c.label, "folder": c.out.name, "status": c.status} for c in cases],
            "comparison": files,
        })
    finally:
        if not folder.committed:
            folder.discard()
    return StudyResult(cases, status, out_dir)


def comparison_columns(cases: Sequence[StudyCase]) -> list[Column]:
    """The comparison table's columns: case, status, then each kind's own columns.

    Parameters
    ----------
    cases : sequence of StudyCase
        The cases (their kinds decide the columns, in the order first seen).

    Returns
    -------
    list of Column
    """
    cols = [Column("case", "case", "{}"), Column("status", "status", "{}")]
    seen: set[str] = {"case", "status"}
    for c in cases:
        kind = KINDS.get(c.summary.get("kind") or "")
        for col in kind.columns if kind is not None else ():
            if col.key not in seen:
                seen.add(col.key)
                cols.append(col)
    return cols


def write_comparison(cases: Sequence[StudyCase], out_dir: str | Path, plots: bool = True) -> list[str]:
    """Write the comparison table of a study and each kind's overlay plots.

    Parameters
    ----------
    cases : sequence of StudyCase
        Solved cases.
    out_dir : str or pathlib.Path
        Study folder.
    plots : bool, optional
        Also write overlay plots of the cases with a solution (e.g. ``overlay_forces.png``
        and ``overlay_tcp.png`` for motions, Dressler (2012), Figs. 3.9-3.10).

    Returns
    -------
    list of str
        File names written: ``comparison.csv``, ``comparison.md`` and the plots.
    """
    out_dir = Path(out_dir)
    cols = comparison_columns(cases)

    def value(c: StudyCase, col: Column) -> Any:
        return c.label if col.key == "case" else c.summary.get(col.key)

    def fmt(v: Any, col: Column) -> str:
        if v is None:
            return "-"
        try:
            return col.fmt.format(v)
        except (TypeError, ValueError):
            return str(v)

    csv = [",".join(c.key for c in cols)]
    csv += [",".join("" if value(c, col) is None else str(value(c, col)) for col in cols) for c in cases]
    (out_dir / "comparison.csv").write_text("\n".join(csv) + "\n", encoding="utf-8")
    md = ["| " + " | ".join(c.header for c in cols) + " |", "|" + "---|" * len(cols)]
    md += ["| " + " | ".join(fmt(value(c, col), col) for col in cols) + " |" for c in cases]
    (out_dir / "comparison.md").write_text("\n".join(md) + "\n", encoding="utf-8")
    files = ["comparison.csv", "comparison.md"]
    if plots:
        by_kind: dict[str, dict[str, Any]] = {}
        for c in cases:
            if c.solution is not None and c.status in (Status.OPTIMAL, Status.ACCEPTABLE):
                by_kind.setdefault(c.summary["kind"], {})[c.label] = c.solution
        for kind_name, solutions in by_kind.items():
            files += KINDS[kind_name].overlay(solutions, out_dir)
    return files
