"""The comparison table and overlay plots of several cases (``gtmodel solve A.toml B.toml``, ``--sweep``).

The table takes its columns from the cases' kinds
(:attr:`~gtmodel.problems.base.ProblemKind.columns`), so a comparison of calibrations
compares errors and one of motions compares final times (Dressler (2012), Table 3.1);
each kind draws the overlays of its own cases (:meth:`~gtmodel.problems.base.ProblemKind.overlay`).
The cases are run by the study engine (:func:`~gtmodel.problems.study.engine.run_study`).
"""

from __future__ import annotations

import logging
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

from gtmodel._escape import csv_field
from gtmodel.problems.base import Column
from gtmodel.problems.registry import KINDS
from gtmodel.status import Status

__all__ = ["StudyCase", "comparison_columns", "write_comparison", "write_overlays"]

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

    csv = [",".join(csv_field(c.key) for c in cols)]
    csv += [",".join("" if value(c, col) is None else csv_field(value(c, col)) for col in cols) for c in cases]
    (out_dir / "comparison.csv").write_text("\n".join(csv) + "\n", encoding="utf-8")
    md = ["| " + " | ".join(c.header for c in cols) + " |", "|" + "---|" * len(cols)]
    md += ["| " + " | ".join(fmt(value(c, col), col) for col in cols) + " |" for c in cases]
    (out_dir / "comparison.md").write_text("\n".join(md) + "\n", encoding="utf-8")
    files = ["comparison.csv", "comparison.md"]
    if plots:
        files += write_overlays(cases, out_dir)
    return files


def write_overlays(cases: Sequence[StudyCase], out_dir: str | Path) -> list[str]:
    """Each kind's overlay plots of its solved cases, one set of files per kind.

    With cases of one kind the files keep the kind's names (``overlay_forces.png``, ...);
    with several kinds each kind's files are prefixed with its name
    (``point_to_point_overlay_forces.png``), so no kind overwrites another's.

    Parameters
    ----------
    cases : sequence of StudyCase
        The cases (those with a solution and status optimal or acceptable are drawn).
    out_dir : str or pathlib.Path
        Study folder.

    Returns
    -------
    list of str
        File names written, each once.
    """
    out_dir = Path(out_dir)
    by_kind: dict[str, dict[str, Any]] = {}
    for c in cases:
        if c.solution is not None and (c.status.success or c.status is Status.ACCEPTABLE):
            by_kind.setdefault(c.summary["kind"], {})[c.label] = c.solution
    if len(by_kind) == 1:
        ((kind_name, solutions),) = by_kind.items()
        return list(dict.fromkeys(KINDS[kind_name].overlay(solutions, out_dir)))
    files: list[str] = []
    for kind_name, solutions in by_kind.items():
        with tempfile.TemporaryDirectory(prefix=".overlay-", dir=out_dir) as tmp:
            for name in dict.fromkeys(KINDS[kind_name].overlay(solutions, Path(tmp))):
                shutil.move(Path(tmp) / name, out_dir / f"{kind_name}_{name}")
                files.append(f"{kind_name}_{name}")
    return files
