"""Problem files: reading, dispatch to the solvers by ``kind``, result folders, studies.

A problem file (TOML) declares one problem; ``kind`` selects its schema and solver:

- ``point_to_point``: free-path time/energy-optimal motion between two poses
  (:mod:`gtmodel.trajectory.problem_files` documents the fields; the objective and
  constraints are written in the problem language of ``docs/problem_language.md``).
- ``path_constrained``: time-optimal motion along a declared TCP path, by the convex
  reformulation (Verscheure et al. 2009) or the thesis' projection solved by collocation.
- ``calibration``: kinematic calibration from closure equations with identifiability
  and an accuracy report (:mod:`gtmodel.calibration.problem_files`).

Every field is validated on load and an error names the file, the field and what was
expected. A result folder holds ``summary.json`` (always, also on failure, with
``status``), the data files of the kind and PNG plots. :func:`solve_study` solves several
files or a sweep over one field and writes a comparison table (Dressler (2012),
Table 3.1) with overlay plots.
"""

from __future__ import annotations

import json
import logging
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from gtmodel._fields import FieldReader, apply_override
from gtmodel._toml import read_toml
from gtmodel.errors import GtModelError, ProblemError

__all__ = [
    "KINDS",
    "Problem",
    "StudyCase",
    "load_problem",
    "solve_problem",
    "write_results",
    "error_summary",
    "write_summary",
    "solve_study",
    "write_comparison",
]

_log = logging.getLogger("gtmodel")

#: Problem kinds understood by :func:`load_problem`, each with the module that reads,
#: solves and writes it: ``(module, load, solve, write)``. ``load(f, name)`` builds the
#: declaration from a :class:`~gtmodel._fields.FieldReader`, ``solve(decl, verbose=...)``
#: returns a solution, ``write(decl, solution, out, plots, name)`` returns the summary
#: fields and the written file names. Adding a kind is one entry here.
_KIND_HANDLERS: dict[str, tuple[str, str, str, str]] = {
    "point_to_point": ("gtmodel.trajectory.problem_files", "load_point_to_point", "", "write_point_to_point"),
    "path_constrained": ("gtmodel.trajectory.problem_files", "load_path_constrained", "solve_path_declaration", "write_path_constrained"),
    "calibration": ("gtmodel.calibration.problem_files", "load_calibration", "solve_calibration", "write_calibration"),
    "dynamic_identification": (
        "gtmodel.calibration.dynamic_problem_files",
        "load_dynamic_identification",
        "solve_dynamic_identification",
        "write_dynamic_identification",
    ),
    "elasto_geometric_calibration": (
        "gtmodel.calibration.elasto_geometric_problem_files",
        "load_elasto_geometric",
        "solve_elasto_geometric",
        "write_elasto_geometric",
    ),
    "joint_stiffness_calibration": (
        "gtmodel.calibration.joint_stiffness_problem_files",
        "load_joint_stiffness",
        "solve_joint_stiffness",
        "write_joint_stiffness",
    ),
}

#: Problem kinds understood by :func:`load_problem`.
KINDS = tuple(_KIND_HANDLERS)


def _handler(kind: str, role: int) -> Callable[..., Any]:
    import importlib

    module = importlib.import_module(_KIND_HANDLERS[kind][0])
    return getattr(module, _KIND_HANDLERS[kind][role])


@dataclass
class Problem:
    """A validated problem file.

    Parameters
    ----------
    path : pathlib.Path
        The file.
    name : str
        Problem name.
    kind : str
        One of :data:`KINDS`.
    description : str
        Free text.
    declaration : Any
        The solver-level declaration built from the file (e.g.
        :class:`~gtmodel.trajectory.PointToPoint`).
    data : dict
        The parsed file (after overrides), for sweeps.
    overrides : dict
        Fields replaced on load (``--sweep``), field -> value.
    """

    path: Path
    name: str
    kind: str
    description: str
    declaration: Any
    data: dict = field(default_factory=dict, repr=False)
    overrides: dict = field(default_factory=dict)


def load_problem(path: str | Path, overrides: Mapping[str, Any] | None = None) -> Problem:
    """Read and validate a problem file.

    Parameters
    ----------
    path : str or pathlib.Path
        The TOML problem file.
    overrides : Mapping[str, Any], optional
        Fields to replace before validation (dotted names; a bare name is looked up in
        ``[parameters]`` first), e.g. ``{"w": 0.001}``.

    Returns
    -------
    Problem
        The validated problem, ready for :func:`solve_problem`.

    Raises
    ------
    ProblemError
        Unreadable file, TOML syntax error, a missing, unknown or invalid field, an
        invalid expression, a pose outside the workspace, limits that cannot hold the robot
        at rest, an override of a field the file does not have. The message names the file
        and the field.
    """
    path = Path(path)
    data = read_toml(path, ProblemError, "problem file")
    for key, value in (overrides or {}).items():
        data = apply_override(data, key, value, path)
    f = FieldReader(data, path)
    kind = f.get("", "kind")
    if kind not in KINDS:
        raise f.fail("kind", f"one of {', '.join(KINDS)}", kind)
    name = f.get("", "name", path.stem)
    if not isinstance(name, str) or not name:
        raise f.fail("name", "a non-empty string", name)
    description = f.get("", "description", "")
    if not isinstance(description, str):
        raise f.fail("description", "a string", description)
    decl = _handler(kind, 1)(f, name)
    return Problem(path=path, name=name, kind=kind, description=description, declaration=decl, data=data, overrides=dict(overrides or {}))


def solve_problem(problem: Problem, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> Any:
    """Solve a loaded problem with the solver its ``kind`` selects.

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
        The kind's solution object (e.g. :class:`~gtmodel.trajectory.PointToPointSolution`);
        its ``result.status`` says whether it is optimal.

    Raises
    ------
    GtModelError
        Bad input discovered while building the problem.
    """
    if problem.kind == "point_to_point":
        from gtmodel.trajectory.point_to_point import solve_point_to_point

        return solve_point_to_point(problem.declaration, verbose=verbose, previous=previous, warm_start=warm_start)
    if problem.kind not in _KIND_HANDLERS:  # pragma: no cover - checked on load
        raise ProblemError(f"{problem.path}: kind {problem.kind!r} has no solver")
    return _handler(problem.kind, 2)(problem.declaration, verbose=verbose)


def _json_safe(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, np.ndarray):
        return [_json_safe(float(x)) for x in value.ravel()]
    if isinstance(value, (np.floating,)):
        return _json_safe(float(value))
    if isinstance(value, (np.integer,)):
        return int(value)
    return value


def write_summary(out_dir: str | Path, summary: Mapping[str, Any]) -> Path:
    """Write ``summary.json`` (non-finite numbers become ``null``).

    Parameters
    ----------
    out_dir : str or pathlib.Path
        Result folder (created if missing).
    summary : Mapping[str, Any]
        The summary fields.

    Returns
    -------
    pathlib.Path
        The written file.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    target = out / "summary.json"
    target.write_text(json.dumps({k: _json_safe(v) for k, v in summary.items()}, indent=2) + "\n", encoding="utf-8")
    return target


def error_summary(problem_path: str | Path, error: BaseException, kind: str | None = None) -> dict[str, Any]:
    """Summary of a problem that could not be solved (bad input or an exception).

    Parameters
    ----------
    problem_path : str or pathlib.Path
        The problem file.
    error : BaseException
        What went wrong.
    kind : str or None, optional
        The problem kind, if known.

    Returns
    -------
    dict
        ``problem``, ``kind``, ``status = "error"``, ``message`` and the numeric fields set
        to None.
    """
    return {
        "problem": str(problem_path),
        "kind": kind,
        "status": "error",
        "message": str(error) if isinstance(error, GtModelError) else f"{type(error).__name__}: {error}",
        "final_time_s": None,
        "energy": None,
        "iterations": None,
        "solve_time_s": None,
        "objective": None,
        "max_constraint_violation": None,
    }


def write_results(problem: Problem, solution: Any, out_dir: str | Path, plots: bool = True) -> dict[str, Any]:
    """Write the result folder of a solved problem.

    ``summary.json`` is always written. Data files (``trajectory.csv`` every 4 ms,
    ``trajectory.h``) and plots are written only when the solver returned a solution
    (status optimal or acceptable), never for a failed solve's last iterate.

    Parameters
    ----------
    problem : Problem
        The problem.
    solution : Any
        Its solution from :func:`solve_problem`.
    out_dir : str or pathlib.Path
        Result folder (created if missing).
    plots : bool, optional
        Write PNG plots (default True).

    Returns
    -------
    dict
        The summary that was written.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    summary: dict[str, Any] = {"problem": str(problem.path), "name": problem.name, "kind": problem.kind}
    if problem.overrides:
        summary["overrides"] = dict(problem.overrides)
    if problem.kind not in _KIND_HANDLERS:  # pragma: no cover - checked on load
        raise ProblemError(f"{problem.path}: kind {problem.kind!r} has no result writer")
    fields, files = _handler(problem.kind, 3)(problem.declaration, solution, out, plots, problem.name)
    summary.update(fields)
    summary["files"] = ["summary.json", *files]
    write_summary(out, summary)
    return summary


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
        Its result folder.
    summary : dict
        Its summary (status ``error`` with a message for bad input).
    solution : Any
        Its solution (None only when it could not be loaded or solved).
    """

    label: str
    path: Path
    overrides: dict
    out: Path
    summary: dict = field(default_factory=dict)
    solution: Any = None


def solve_study(
    paths: Sequence[str | Path],
    out_dir: str | Path,
    sweep: tuple[str, Sequence[Any]] | None = None,
    verbose: bool = False,
    plots: bool = True,
    warm_start: bool = False,
    on_case: Callable[[StudyCase], None] | None = None,
) -> list[StudyCase]:
    """Solve several problem files, or one file over a sweep of one field, and compare.

    Each case gets its own result folder ``out_dir/<label>``; a sweep over a named
    parameter reuses the NLP built for the first case (and, with ``warm_start``, starts
    from the previous solution). Bad input in one case is recorded as its error summary
    and the study goes on. ``out_dir`` receives ``comparison.csv``, ``comparison.md`` and
    overlay plots (:func:`write_comparison`).

    Parameters
    ----------
    paths : sequence of str or pathlib.Path
        Problem files (exactly one with ``sweep``).
    out_dir : str or pathlib.Path
        Study folder.
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

    Returns
    -------
    list of StudyCase
        In the order solved.

    Raises
    ------
    ProblemError
        A sweep with more than one file.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    if sweep is not None and len(paths) != 1:
        raise ProblemError(f"--sweep needs exactly one problem file, got {len(paths)}")
    specs: list[tuple[Path, dict]] = []
    if sweep is not None:
        key, values = sweep
        specs = [(Path(paths[0]), {key: v}) for v in values]
    else:
        specs = [(Path(p), {}) for p in paths]
    cases: list[StudyCase] = []
    previous = None
    for path, overrides in specs:
        label = path.stem + "".join(f"[{k}={v}]" for k, v in overrides.items())
        case = StudyCase(label=label, path=path, overrides=overrides, out=out_dir / _safe_folder(label))
        try:
            problem = load_problem(path, overrides)
            case.label = problem.name + "".join(f"[{k}={v}]" for k, v in overrides.items())
            case.out = out_dir / _safe_folder(case.label)
            solution = solve_problem(problem, verbose=verbose, previous=previous if sweep else None, warm_start=warm_start)
            case.solution = solution
            case.summary = write_results(problem, solution, case.out, plots=plots)
            previous = solution
        except GtModelError as exc:
            case.summary = error_summary(path, exc)
            write_summary(case.out, case.summary)
        cases.append(case)
        if on_case is not None:
            on_case(case)
    write_comparison(cases, out_dir, plots=plots)
    return cases


def _safe_folder(label: str) -> str:
    return "".join(c if c.isalnum() or c in "-_.=" else "_" for c in label).strip("_")


#: Columns of the comparison table (Dressler (2012), Table 3.1).
_COMPARISON = (
    ("case", "case"),
    ("status", "status"),
    ("final_time_s", "T_final [s]"),
    ("energy", "energy [N^2 s]"),
    ("iterations", "iterations"),
    ("solve_time_s", "solve time [s]"),
)


def write_comparison(cases: Sequence[StudyCase], out_dir: str | Path, plots: bool = True) -> list[Path]:
    """Write the comparison table of a study and overlay plots.

    Parameters
    ----------
    cases : sequence of StudyCase
        Solved cases.
    out_dir : str or pathlib.Path
        Study folder.
    plots : bool, optional
        Also write ``overlay_forces.png`` and ``overlay_tcp.png`` (Dressler (2012),
        Figs. 3.9-3.10) from the cases that have a trajectory.

    Returns
    -------
    list of pathlib.Path
        Files written: ``comparison.csv``, ``comparison.md`` and the plots.
    """
    out_dir = Path(out_dir)
    rows = []
    for c in cases:
        s = c.summary
        rows.append([c.label, s.get("status"), s.get("final_time_s"), s.get("energy"), s.get("iterations"), s.get("solve_time_s")])

    def fmt(v: Any, k: int) -> str:
        if v is None:
            return "-"
        if isinstance(v, float):
            return f"{v:.5g}" if k != 2 else f"{v:.5f}"
        return str(v)

    csv_lines = [",".join(k for k, _ in _COMPARISON)]
    csv_lines += [",".join("" if v is None else str(v) for v in r) for r in rows]
    (out_dir / "comparison.csv").write_text("\n".join(csv_lines) + "\n", encoding="utf-8")
    md = ["| " + " | ".join(h for _, h in _COMPARISON) + " |", "|" + "---|" * len(_COMPARISON)]
    md += ["| " + " | ".join(fmt(v, k) for k, v in enumerate(r)) + " |" for r in rows]
    (out_dir / "comparison.md").write_text("\n".join(md) + "\n", encoding="utf-8")
    files = [out_dir / "comparison.csv", out_dir / "comparison.md"]
    if plots:
        from gtmodel.report.trajectory import plot_overlay

        from gtmodel.trajectory.problem_files import path_trajectory_columns

        trajs = {
            c.label: (path_trajectory_columns(c.solution) if c.summary.get("kind") == "path_constrained" else c.solution.trajectory())
            for c in cases
            if c.solution is not None and c.summary.get("status") in ("optimal", "acceptable") and "final_time_s" in c.summary
        }
        if trajs:
            files += plot_overlay(trajs, out_dir)
    return files
