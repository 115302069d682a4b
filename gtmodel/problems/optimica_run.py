"""``gtmodel solve FILE.mop --class Pkg.Opt``: an Optimica class run as an ``optimica`` problem file would run it.

:func:`load_optimica_problem` declares the class by the ``optimica`` kind's own path
(:func:`gtmodel.problems.kinds.optimica.optimica_declaration`, the kind's tables at their
defaults: direct collocation, verification by simulation, refinement on a failed
verification, IPOPT), so the solve, the result folder (``summary.json``, ``trajectories.csv``,
plots, ``report.html``) and the exit codes are those of an ``optimica`` problem file (and of
any ``optimal_control`` one). :func:`run_optimica` is :func:`gtmodel.problems.run.run_problem`
for it: every outcome becomes a status and a summary.
"""

from __future__ import annotations

import logging
from pathlib import Path

from gtmodel._timing import add_phase, merge_phases, phase_sum, timed
from gtmodel.errors import GtModelError, ProblemError
from gtmodel.exchange.optimica_syntax import CLASS_NAME_RE
from gtmodel.problems.base import Problem, ProblemFile
from gtmodel.problems.kinds.optimica import default_settings, optimica_declaration
from gtmodel.problems.results import ResultFolder
from gtmodel.problems.runtime import Heartbeat
from gtmodel.problems.run import (InterruptedWithResult, RunOutcome, _failed, _write_into, out_of_memory, solution_timing, solve_problem,
                                  write_failure)
from gtmodel.status import Status

__all__ = ["load_optimica_problem", "run_optimica", "optimica_target", "write_failure"]

_log = logging.getLogger("gtmodel")


def load_optimica_problem(path: str | Path, class_name: str, *, state_start_values_fixed: bool = False) -> Problem:
    """An Optimica ``optimization`` class as an ``optimica`` :class:`~gtmodel.problems.base.Problem` (the kind's tables at their defaults).

    Parameters
    ----------
    path : str or pathlib.Path
        The ``.mop`` file.
    class_name : str
        The ``optimization`` class (``"Pkg.Opt"``).
    state_start_values_fixed : bool, optional
        JModelica.org's compiler option (:func:`~gtmodel.exchange.optimica.load_optimica`).

    Returns
    -------
    Problem
        Kind ``optimica`` (an ``optimal_control`` declaration), named after the class's last
        part, with the kind's default collocation, verification, refinement and solver settings.

    Raises
    ------
    GtModelError
        The file cannot be read or is outside the supported subset (an
        :class:`~gtmodel.exchange.optimica.OptimicaError` naming file, line and construct).
    """
    path = Path(path)
    name = class_name.split(".")[-1]
    declaration = optimica_declaration(path, class_name, state_start_values_fixed=state_start_values_fixed,
                                       settings=default_settings(), file=ProblemFile(path), name=name)
    return Problem(path=path, name=name, kind="optimica", description=f"Optimica class {declaration.class_name} of {path.name}",
                   declaration=declaration, data={}, overrides={})


def optimica_target(problems: list[Path], class_name: str | None, sweep: str | None, out: Path | None) -> Path:
    """The result folder of ``gtmodel solve FILE.mop --class NAME`` (``--out``, else ``results/<class>``).

    Parameters
    ----------
    problems : list of pathlib.Path
        The command's files (one ``.mop`` file).
    class_name : str or None
        ``--class``.
    sweep : str or None
        ``--sweep`` (refused).
    out : pathlib.Path or None
        ``--out``.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    GtModelError
        Several files, a sweep, no ``--class``, or a class name that is not dotted identifiers.
    """
    if len(problems) != 1 or sweep is not None or class_name is None:
        raise GtModelError("an Optimica file is solved alone (no --sweep) and needs --class NAME, its optimization class "
                           "(e.g. gtmodel solve problems/optimica/double_integrator_min_time.mop --class DoubleIntegrator.MinTime)")
    if not CLASS_NAME_RE.fullmatch(class_name):
        raise GtModelError(f"--class {class_name[:60]!r}: not a dotted Modelica class name (Pkg.Opt)")
    return out if out is not None else Path("results") / class_name.split(".")[-1]


def run_optimica(path: str | Path, class_name: str, out: str | Path, *, state_start_values_fixed: bool = False,
                 verbose: bool = False, plots: bool = True, heartbeat: bool = False, report: bool = False) -> RunOutcome:
    """Load, solve and write an Optimica class as :func:`~gtmodel.problems.run.run_problem` does a problem file.

    Parameters
    ----------
    path : str or pathlib.Path
        The ``.mop`` file.
    class_name : str
        The ``optimization`` class.
    out : str or pathlib.Path
        The result folder.
    state_start_values_fixed : bool, optional
        JModelica.org's compiler option (:func:`load_optimica_problem`).
    verbose : bool, optional
        Solver progress.
    plots : bool, optional
        Write PNG plots.
    heartbeat : bool, optional
        Log a line every few seconds while solving.
    report : bool, optional
        Also write ``report.html``.

    Returns
    -------
    RunOutcome
        Never raises for bad input (status ``invalid_input``, exit 2), solver failure or
        internal errors; a missing file writes nothing.
    """
    path, target = Path(path), Path(out)
    if not path.is_file():
        return _failed(path, target, None, ProblemError(f"{path}: cannot read the Optimica file (no such file)"),
                       Status.INVALID_INPUT, write=False)
    phases: dict[str, dict[str, float]] = {}
    problem: Problem | None = None
    try:
        with timed(phases, "load"):
            problem = load_optimica_problem(path, class_name, state_start_values_fixed=state_start_values_fixed)
        label = f"solving {problem.name} (Optimica, kind optimica)"
        _log.info("%s ...", label)
        call: dict[str, dict[str, float]] = {}
        interrupted = None
        with Heartbeat(label, enabled=heartbeat), timed(call, "other"):
            try:
                solution = solve_problem(problem, verbose=verbose)
            except InterruptedWithResult as stop:
                solution, interrupted = stop.solution, stop.note
        own = solution_timing(solution)
        merge_phases(phases, own)
        rest = phase_sum(own)
        add_phase(phases, "other", call["other"]["wall_s"] - rest["wall_s"], call["other"]["cpu_s"] - rest["cpu_s"])
        with ResultFolder(target) as folder:
            summary = _write_into(folder, problem, solution, plots, report, phases, interrupted)
        return RunOutcome(path, folder.target, Status(summary["status"]), summary, problem, solution, kept=folder.kept)
    except KeyboardInterrupt as exc:
        return _failed(path, target, problem, exc, Status.INTERRUPTED)
    except GtModelError as exc:
        return _failed(path, target, problem, exc, Status.INVALID_INPUT)
    except MemoryError:
        return _failed(path, target, problem, out_of_memory(path), Status.INVALID_INPUT)
    except Exception as exc:  # noqa: BLE001 - a defect: reported with its status, never lost
        _log.debug("internal error", exc_info=True)
        return _failed(path, target, problem, exc, Status.INTERNAL_ERROR)
