"""The ``gtmodel`` command.

``gtmodel solve PROBLEM.toml [--out DIR] [--data-dir DIR ...]``
    Load, validate and solve a problem file; write the result folder ``DIR`` (default
    ``results/<problem name>``): ``summary.json`` (always, listing every file), the data
    files of its kind and PNG plots. The folder is replaced only when the run is complete.
    Data files must lie in the problem file's folder or a ``--data-dir`` folder.
``gtmodel solve A.toml B.toml ... [--out DIR]`` / ``gtmodel solve A.toml --sweep w=0,0.001``
    A comparison, on the study engine (:func:`gtmodel.problems.study.run_study`): every case
    in ``DIR/<case>/``, a comparison table (``comparison.md``, ``comparison.csv``, columns
    from each kind) with each kind's overlay plots, ``table.csv`` and ``summary.json`` in
    ``DIR``. A missing file, an unknown swept field or an ``--out`` that is a file is one
    error before anything runs or is written.
``gtmodel study STUDY.toml [--workers N | --scheduler ADDRESS] [--out DIR] [--retry-failed]``
    A study file (:mod:`gtmodel.problems.study.design`): many cases of one problem file on a
    local Dask cluster, in this process (``--workers 1``) or on a cluster; resumable
    (finished cases are not rerun); ``DIR/table.parquet``, ``table.csv``, ``summary.json``.
``gtmodel schema KIND [--out FILE]`` / ``gtmodel schema --list`` / ``gtmodel schema --docs DIR``
    The JSON Schema of a kind's problem files; the kinds; the reference page and schemas.
``gtmodel codegen {robot,model,tracking,mpc,controller} ... --out DIR [--check]``
    Generate C for the 4 ms loop (:mod:`gtmodel.cli_codegen`, one sub-command per kind of
    code, each with its own options: a robot's kinematics and inverse dynamics, a user's
    model, a tracking controller or an MPC with the loop-step interface, a controller
    bundle); ``--check`` compiles it, compares it with Python and, for a loop controller,
    runs it in closed loop (:func:`gtmodel.codegen.check_code`, one status). The former flat
    forms (``--robot``, ``--model``, ``--controller``, ``--mpc``) keep working.
``gtmodel loop FILE.toml [--out DIR] [--listen HOST:PORT] [--sensor-port PORT] [--idle-timeout S] [--max-cycles N]``
    Run a ``robot_loop`` file (:mod:`gtmodel.cli_loop`, docs/robot.md): its controller's step
    generated as C and checked, the runtime built around it and run behind KUKA RSI or ABB
    EGM over UDP until the robot stops sending (or Ctrl-C); ``DIR/summary.json`` (cycles, late
    and held replies, latency percentiles, faults and what was done) and the cycle log.
``gtmodel robot-sim --interface rsi|egm --plant kr500|l1 --to HOST:PORT --duration S --out DIR``
    A robot-side simulator of the interface (:mod:`gtmodel.robot_sim`): the project's plant
    behind the protocol, sending from its own 4 ms clock, with injected faults; the
    rehearsal of ``gtmodel loop``.
``gtmodel export-fmu (--model FILE:CLASS | --robot NAME | --modelica FILE.mo[:CLASS] | --controller FILE) --out NAME.fmu``
    Export a model as an FMU (:func:`gtmodel.exchange.export_fmu`, docs/fmu.md): FMI 2.0
    or 3.0 (``--fmi-version``), model exchange and/or co-simulation as ``--interface`` says
    (FMI 3.0 always with model exchange: ``cs`` alone is refused), C sources and a binary
    for this platform; a controller file's Kalman step as a discrete-time
    co-simulation FMU (:func:`gtmodel.exchange.fmu_step.export_step_fmu`).
``gtmodel import-fmu FILE.fmu [--stop-time T [--start NAME=VALUE ...] [--input CSV] --out CSV] [--max-members N ...]``
    Load an FMU as gtmodel does (:func:`gtmodel.exchange.import_fmu`): its variables and
    where its derivatives come from; simulate it with CVODES from its start values (changed
    by ``--start``), inputs from a table (``--input``). The archive is unpacked under caps
    (:class:`gtmodel.exchange.fmu_archive.ArchiveLimits`) the options raise. Both FMU
    commands live in :mod:`gtmodel.cli_fmu`.
``gtmodel examples DIR``
    Copy the shipped example problems, their models, the studies and the loop files into
    ``DIR`` (new or empty; :mod:`gtmodel.cli_examples`), and say how to run one.
``gtmodel report RESULT_DIR``
    Write ``RESULT_DIR/report.html``: one self-contained page of a result folder (status,
    objective, verification, warnings, zoomable trajectories with their bounds, the
    model's variables, the plots; :mod:`gtmodel.report.result_page`). ``gtmodel solve``
    writes it for a single problem unless ``--no-report``.

Exit codes come from one table, :data:`gtmodel.status.EXIT_CODES` (printed by
``gtmodel --help``): 0 optimal, 1 solved but not optimal / infeasible / solver failure,
2 invalid input (also an output that cannot be written, or an ``--out`` another run is
writing), 3 internal error, 130 interrupted (Ctrl-C, SIGTERM: at any moment, also during
start-up and repeated; the handlers come first, :mod:`gtmodel.__main__`; the process
exits 143 when the first signal was SIGTERM). What each
outcome leaves in ``--out``: ``docs/reliability.md``.

Fast start: this module imports only the standard library and gtmodel's base modules;
each sub-command imports the layers it needs when it runs (the imports inside the
``_solve``/``_study``/``_schema``/``_codegen`` functions), and the input checks that need
no model (missing problem file, an output folder that is a file) come first. So
``gtmodel --help``, ``gtmodel schema --list`` and such input errors take a fraction of a
second; ``benchmarks/bench_cli_startup.py`` measures it.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import sys
import traceback
from pathlib import Path
from typing import Any, Sequence

from gtmodel import __version__, _signals
from gtmodel._toml import read_toml
from gtmodel.errors import GtModelError, ProblemError
from gtmodel.problems.overrides import parse_override
from gtmodel.problems.results import failure_summary, is_file_name, output_lock
from gtmodel.problems.study.preflight import check_output_folder, check_problem_files
from gtmodel.status import Status, exit_code_table

__all__ = ["main", "build_parser", "EXIT_OK", "EXIT_NOT_OPTIMAL", "EXIT_BAD_INPUT", "EXIT_INTERNAL", "EXIT_INTERRUPTED"]

EXIT_OK = Status.OPTIMAL.exit_code
EXIT_NOT_OPTIMAL = Status.ERROR.exit_code
EXIT_BAD_INPUT = Status.INVALID_INPUT.exit_code
EXIT_INTERNAL = Status.INTERNAL_ERROR.exit_code
EXIT_INTERRUPTED = Status.INTERRUPTED.exit_code

_log = logging.getLogger("gtmodel")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``gtmodel`` command.

    Returns
    -------
    argparse.ArgumentParser
        Parser with the sub-commands ``solve``, ``study``, ``report``, ``schema``, ``codegen``,
        ``loop``, ``robot-sim``, ``export-fmu``, ``import-fmu`` and ``examples``.
    """
    parser = argparse.ArgumentParser(
        prog="gtmodel",
        description="Gantry-Tau modelling, calibration, optimal control and C code generation",
        epilog="exit codes (status -> code):\n" + exit_code_table(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"gtmodel {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    solve = sub.add_parser("solve", help="solve a problem file and write a result folder")
    solve.add_argument("problem", type=Path, nargs="+", help="problem file(s) (TOML), e.g. problems/l1_time_optimal.toml")
    solve.add_argument("--out", type=Path, default=None, help="result folder (default: results/<problem name>), replaced when the run ends")
    solve.add_argument(
        "--sweep", default=None, metavar="FIELD=V1,V2,...", help="solve one file for several values of a field, e.g. w=0,0.001,0.01"
    )
    solve.add_argument("--warm-start", action="store_true", help="in a sweep, start each case from the previous solution")
    solve.add_argument("--workers", type=int, default=1, help="several files or a sweep: cases in parallel on a local Dask cluster (default 1)")
    group = solve.add_mutually_exclusive_group()
    group.add_argument("-q", "--quiet", action="store_true", help="no solver progress")
    group.add_argument("-v", "--verbose", action="store_true", help="solver progress even when not on a terminal")
    solve.add_argument("--no-plots", action="store_true", help="do not write PNG plots")
    solve.add_argument("--no-report", action="store_true", help="do not write report.html (the result's HTML page; a single problem only)")
    solve.add_argument("--data-dir", type=Path, action="append", default=[], metavar="DIR",
                       help="a folder data files may also come from (default: only the problem file's folder); repeatable")
    solve.add_argument("--debug", action="store_true", help="show tracebacks of internal errors")
    # Optimica (.mop) input, issue 68 (docs/optimica.md)
    solve.add_argument("--class", dest="class_name", metavar="PKG.OPTCLASS", help="the optimization class of a .mop (Optimica) file")
    solve.add_argument("--state-start-values-fixed", action="store_true", help="a .mop file: states' starts are initial conditions (JModelica.org)")

    study = sub.add_parser("study", help="run a study file (many cases of one problem file), locally or on a Dask cluster")
    study.add_argument("study", type=Path, help="study file (TOML), e.g. studies/l1_table_3_1.toml")
    where = study.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=None, help="local worker processes (default: one per core; 1 = in this process, no Dask)")
    where.add_argument("--scheduler", default=None, metavar="ADDRESS", help="an existing Dask scheduler, e.g. tcp://10.0.0.5:8786")
    study.add_argument("--out", type=Path, default=None, help="study folder (default: results/<study name>); finished cases in it are not rerun")
    study.add_argument("--retry-failed", action="store_true", help="also rerun finished cases that did not succeed")
    study.add_argument("--no-plots", action="store_true", help="do not write PNG plots")
    study.add_argument("-q", "--quiet", action="store_true", help="no progress")
    study.add_argument("-v", "--verbose", action="store_true", help="solver progress (with --workers 1)")
    study.add_argument("--data-dir", type=Path, action="append", default=[], metavar="DIR",
                       help="a folder data files may also come from (default: only the problem file's folder); repeatable")
    study.add_argument("--debug", action="store_true", help="show tracebacks of internal errors")

    rep = sub.add_parser("report", help="write RESULT_DIR/report.html, the HTML page of a result folder")
    rep.add_argument("folder", type=Path, help="a result folder written by gtmodel solve, e.g. results/l1_time_optimal")
    rep.add_argument("--debug", action="store_true", help="show tracebacks of internal errors")

    schema = sub.add_parser("schema", help="JSON Schema of a problem or loop-controller file kind, the list of kinds, or the reference docs")
    schema.add_argument("kind", nargs="?", default=None, help="a problem kind or a loop-controller file kind such as mpc (gtmodel schema --list prints them)")
    schema.add_argument("--out", type=Path, default=None, help="write the schema to this file (default: standard output)")
    schema.add_argument("--list", action="store_true", help="print the kinds, one per line")
    schema.add_argument("--docs", type=Path, default=None, metavar="DIR", help="write DIR/problem_files.md and DIR/schemas/*.schema.json")

    from gtmodel.cli_codegen import add_codegen_parser  # its sub-commands (robot, model, tracking, mpc, controller)

    add_codegen_parser(sub)
    from gtmodel.cli_loop import add_loop_parser  # gtmodel loop FILE --out DIR: the loop behind RSI / EGM

    add_loop_parser(sub)
    from gtmodel.robot_sim.cli import add_robot_sim_parser  # gtmodel robot-sim: a simulated robot behind RSI / EGM

    add_robot_sim_parser(sub)

    from gtmodel.cli_fmu import add_fmu_parsers  # gtmodel export-fmu / import-fmu

    add_fmu_parsers(sub)
    from gtmodel.cli_examples import add_examples_parser  # gtmodel examples DIR: the shipped problems and models copied out

    add_examples_parser(sub)
    return parser


def _setup_logging(quiet: bool) -> None:
    # one CLI handler at a time, bound to this call's stderr and removed when main() returns (tests, notebooks)
    for old in [h for h in _log.handlers if getattr(h, "_gtmodel_cli", False)]:
        _log.removeHandler(old)
    handler = logging.StreamHandler(sys.stderr)
    handler._gtmodel_cli = True  # type: ignore[attr-defined]
    handler.setFormatter(logging.Formatter("%(message)s"))
    _log.addHandler(handler)
    _log.setLevel(logging.WARNING if quiet else logging.INFO)


def _print_summary(summary: dict, out: Path) -> None:
    note = "  (solver's last iterate, NOT a solution)" if summary.get("last_iterate") else ""
    lines = [f"problem      {summary['name']} ({summary['kind']})", f"status       {summary['status']} ({summary['message']}){note}"]
    for key, label, fmt in (
        ("final_time_s", "final time", "{:.4f} s"),
        ("energy", "energy", "{:.6g} N^2 s"),
        ("objective", "objective", "{:.6g}"),
        ("mean_error_m", "mean error", "{:.3e} m"),
        ("max_error_m", "max error", "{:.3e} m"),
        ("iterations", "iterations", "{}"),
        ("solve_time_s", "solve time", "{:.3f} s"),
        ("max_constraint_violation", "violation", "{:.2e}"),
    ):
        if summary.get(key) is not None:
            lines.append(f"{label:<12} {fmt.format(summary[key])}")
    ver = summary.get("verification")
    if isinstance(ver, dict) and ver.get("status") == "skipped":
        lines.append(f"verified     skipped ({ver.get('message')})")
    elif isinstance(ver, dict):
        dev = ver.get("max_scaled_deviation")
        dev_text = f"{dev:.2e}" if isinstance(dev, float) else str(dev)
        verdict = "passed" if ver.get("passed") else "FAILED (a state bound between the points)" if ver.get("deviations_passed") else "FAILED"
        took = f" in {ver['time_s']:.3f} s" if isinstance(ver.get("time_s"), float) else ""
        lines.append(f"verified     {verdict}: deviation {dev_text} (tolerance {ver.get('tolerance'):.0e}) from a simulation{took}")
        for name, c in (ver.get("integrals") or {}).items():
            if not c.get("passed"):
                lines.append(f"             integral({name}): {c['collocation']:.6g} in the NLP, {c['simulated']:.6g} simulated")
        if ver.get("remedy"):
            lines.append(f"             likely remedy: {ver['remedy']}")
    bench = summary.get("benchmark")
    if isinstance(bench, dict) and "relative_error" in bench:
        flag = "within" if bench.get("within_tolerance", True) else "BEYOND"
        lines.append(f"benchmark    {bench['value']:.7g} vs published {bench['published']:.7g}: relative error "
                     f"{bench['relative_error']:.1e}, {flag} tolerance {bench.get('tolerance', float('nan')):.0e}")
    solve = (summary.get("timing") or {}).get("solve")
    if isinstance(solve, dict) and summary.get("solve_time_s") is not None:  # the solver's own time: wall and CPU
        passes = summary.get("refinement") or []
        if passes and all(isinstance(p.get("solve_cpu_time"), (int, float)) for p in passes):
            # a refined result's solve_time_s sums every pass's solve: its CPU the same passes' (timing.solve is the first's)
            cpu, scope = sum(p["solve_cpu_time"] for p in passes), f"the solver's calls over {len(passes)} passes"
        else:
            cpu, scope = solve["cpu_s"], "the solver's calls"
        lines = [f"solve time   {summary['solve_time_s']:.3f} s wall, {cpu:.3f} s CPU ({scope})"
                 if line.startswith("solve time") else line for line in lines]
    lines += _timing_lines(summary.get("timing"))
    for w in summary.get("warnings") or []:
        lines.append(f"warning      {w}")
    if summary.get("refinement"):
        last = summary["refinement"][-1]
        lines.append(f"refined      {len(summary['refinement'])} passes, {last.get('elements')} elements")
    if "fraction_at_force_bound" in summary:
        frac = ", ".join(f"{100 * f:.0f} %" for f in summary["fraction_at_force_bound"])
        lines.append(f"at bound     {frac} of the samples (tau1, tau2, tau3)")
    lines.append(f"results in   {out}/ ({', '.join(summary.get('files', ['summary.json']))})")
    print("\n".join(lines))


def _timing_lines(timing: Any) -> list[str]:
    """The run's CPU seconds per phase (``summary.json``'s ``timing``), the whole run's first."""
    if not isinstance(timing, dict) or "total" not in timing:
        return []
    total = timing["total"]
    parts = ", ".join(f"{name} {entry['cpu_s']:.2f}" for name, entry in timing.items() if name != "total")
    return [f"{'time':<12} {total['cpu_s']:.2f} s CPU ({total['wall_s']:.2f} s wall): {parts}"]


def _progress(args: argparse.Namespace) -> tuple[bool, bool]:
    """(solver log shown, heartbeat lines): the log on a terminal or with -v, else a heartbeat."""
    show = args.verbose or (not args.quiet and sys.stdout.isatty())
    return show, not args.quiet and not show


def _solve_one(args: argparse.Namespace, path: Path, target: Path) -> int:
    from gtmodel.problems.run import run_problem

    show, heartbeat = _progress(args)
    outcome = run_problem(path, target, verbose=show, plots=not args.no_plots, heartbeat=heartbeat, report=not args.no_report)
    status = outcome.status
    if status is Status.INTERRUPTED and outcome.solution is not None:  # a refinement's verified pass: the result
        _print_summary(outcome.summary, outcome.out)
        print(f"gtmodel: interrupted ({outcome.summary.get('message')})", file=sys.stderr)
        return status.exit_code
    if status is Status.INTERRUPTED:
        print("gtmodel: interrupted", file=sys.stderr)
    elif status is Status.INTERNAL_ERROR:
        if args.debug and outcome.error is not None:
            traceback.print_exception(outcome.error)
        print(f"gtmodel: internal error: {outcome.summary['message']} (rerun with --debug for the traceback)", file=sys.stderr)
    elif status is Status.INVALID_INPUT:
        print(f"gtmodel: error: {outcome.summary['message']}", file=sys.stderr)
    else:
        _print_summary(outcome.summary, outcome.out)
        return status.exit_code
    _say_written(target, outcome.written, outcome.summary, "", outcome.out)
    return status.exit_code


def _say_written(target: Path, written: bool, summary: dict, why: str, out: Path) -> None:
    """Where a run that did not finish wrote its ``summary.json``, and that a complete earlier result was kept."""
    from gtmodel.problems.results import kept_message

    status = summary.get("status")
    if written:
        print(f"gtmodel: wrote {out / 'summary.json'} (status {status})", file=sys.stderr)
    elif why:
        print(f"gtmodel: could not write {out / 'summary.json'}: {why}", file=sys.stderr)
    if written and out != target:
        print(kept_message(target, out, status), file=sys.stderr)


def _solve_study(args: argparse.Namespace, target: Path) -> int:
    from gtmodel.problems.study.design import comparison_study
    from gtmodel.problems.study.engine import run_study

    study = comparison_study(args.problem, parse_override(args.sweep) if args.sweep else None, warm_start=args.warm_start,
                             plots=not args.no_plots)
    show, heartbeat = _progress(args)

    def report(case) -> None:
        if case.status in (Status.INVALID_INPUT, Status.INTERNAL_ERROR):
            print(f"gtmodel: error: {case.label}: {case.summary.get('message')}", file=sys.stderr)
        _log.info("%s: %s", case.label, case.status)

    outcome = run_study(study, target, workers=args.workers, verbose=show, heartbeat=heartbeat, on_case=report)
    if outcome.status is Status.INTERRUPTED:
        print("gtmodel: interrupted", file=sys.stderr)
    print((outcome.out / "comparison.md").read_text(encoding="utf-8"), end="")
    print(f"results in   {outcome.out}/ (comparison.md, comparison.csv, table.csv, summary.json, one folder per case)")
    return outcome.exit_code


def _toml_name(path: Path) -> str:
    """A problem or study file's ``name`` field if it can be read, else the file's stem (as the run names it)."""
    try:
        name = read_toml(path, ProblemError, "problem file").get("name")
    except GtModelError:
        name = None
    return name if is_file_name(name) else path.stem  # a name that would climb out of results/: the run refuses it


def _solve_target(args: argparse.Namespace) -> Path:
    """The result folder of ``gtmodel solve`` (``--out``, else the default the run would take)."""
    if args.out is not None:
        return args.out
    first = args.problem[0]
    if len(args.problem) == 1 and args.sweep is None:
        return Path("results") / _toml_name(first)
    if args.sweep is not None:
        return Path("results") / (first.stem + "_sweep_" + args.sweep.split("=", 1)[0].strip().replace(".", "_"))
    return Path("results") / (first.stem + "_study")


def _guarded(target: Path, run, on_interrupt) -> int:
    """Run with the output folder locked; an interrupt anywhere inside leaves the documented folder state.

    ``run()`` does the work (interruptible); ``on_interrupt()`` writes what an interrupted
    run leaves, with further signals only counted. A second run on the same folder is
    refused by the lock before any work (exit 2).
    """
    check_output_folder(target)  # before anything is imported or written
    with output_lock(target):
        try:
            with _signals.interruptible():
                code = run()
                _signals.raise_if_pending()  # a signal that came in a protected step at the very end
            return code
        except KeyboardInterrupt:
            with _signals.settled():
                on_interrupt()
                print("gtmodel: interrupted", file=sys.stderr)
            return EXIT_INTERRUPTED


def _data_dirs(folders: list[Path]) -> None:
    """``--data-dir``: folders data files may also come from, through the environment (so
    parallel workers see them too; :data:`gtmodel.problems.base.DATA_DIRS_ENV`)."""
    for folder in folders:
        if not folder.is_dir():
            raise GtModelError(f"--data-dir {folder}: not a folder")
    if folders:
        os.environ["GTMODEL_DATA_DIRS"] = os.pathsep.join(str(d.resolve()) for d in folders)


def _solve(args: argparse.Namespace) -> int:
    check_problem_files(args.problem)  # before anything is imported or written
    if args.class_name is not None or args.state_start_values_fixed or args.problem[0].suffix == ".mop":
        return _solve_optimica(args)
    _data_dirs(args.data_dir)
    target = _solve_target(args)
    single = len(args.problem) == 1 and args.sweep is None

    def run() -> int:
        return _solve_one(args, args.problem[0], target) if single else _solve_study(args, target)

    def on_interrupt() -> None:
        from gtmodel.problems.run import write_failure

        path = args.problem[0] if single else Path(", ".join(str(p) for p in args.problem))
        summary = failure_summary(path, KeyboardInterrupt(), Status.INTERRUPTED, name=target.name)
        if single:
            summary["kind"] = _toml_kind(args.problem[0])
        _say_written(target, *write_failure(target, summary))

    return _guarded(target, run, on_interrupt)


# ---- Optimica (.mop) input (issue 68; gtmodel/problems/optimica_run.py): one file and class, as an optimal_control problem
def _solve_optimica(args: argparse.Namespace) -> int:
    from gtmodel.problems.optimica_run import optimica_target, run_optimica, write_failure
    path, target = args.problem[0], optimica_target(args.problem, args.class_name, args.sweep, args.out)
    def run() -> int:
        show, beat = _progress(args)
        o = run_optimica(path, args.class_name, target, state_start_values_fixed=args.state_start_values_fixed, verbose=show,
                         plots=not args.no_plots, heartbeat=beat, report=not args.no_report)
        if o.status in (Status.INVALID_INPUT, Status.INTERNAL_ERROR):
            print(f"gtmodel: error: {o.summary['message']}", file=sys.stderr)
        else:
            _print_summary(o.summary, o.out)
        return o.status.exit_code

    def on_interrupt() -> None:
        _say_written(target, *write_failure(target, {**failure_summary(path, KeyboardInterrupt(), Status.INTERRUPTED,
                                                                         name=target.name), "kind": "optimica"}))
    return _guarded(target, run, on_interrupt)
# ---- end of Optimica input ----


def _loop(args: argparse.Namespace) -> int:
    """``gtmodel loop``: a robot_loop file run as ``gtmodel solve`` runs a problem, with the command line's settings."""
    check_problem_files([args.file])  # before anything is imported or written
    kind = _toml_kind(args.file)
    if kind != "robot_loop":
        raise GtModelError(f"{args.file}: kind: expected a robot_loop file for gtmodel loop (docs/robot.md), got {kind!r}"
                           + ("; solve it with gtmodel solve" if kind else ""))
    target = args.out if args.out is not None else Path("results") / _toml_name(args.file)
    args.out = target
    named = [Path(args.correction_file).resolve().parent] if args.correction_file is not None else []  # named on the command line
    _data_dirs(list(args.data_dir) + [d for d in named if d.is_dir()])

    def run() -> int:
        from gtmodel.cli_loop import loop_command

        return loop_command(args)

    def on_interrupt() -> None:
        from gtmodel.problems.run import write_failure

        summary = failure_summary(args.file, KeyboardInterrupt(), Status.INTERRUPTED, name=target.name)
        summary["kind"] = kind
        _say_written(target, *write_failure(target, summary))

    return _guarded(target, run, on_interrupt)


def _toml_kind(path: Path) -> str | None:
    try:
        kind = read_toml(path, ProblemError, "problem file").get("kind")
    except GtModelError:
        return None
    return kind if isinstance(kind, str) else None


def _study(args: argparse.Namespace) -> int:
    check_problem_files([args.study], "study file")  # before anything is imported or written
    _data_dirs(args.data_dir)
    target = args.out if args.out is not None else Path("results") / _toml_name(args.study)

    def run() -> int:
        from gtmodel.problems.study.engine import run_study
        from gtmodel.problems.study.progress import progress_mode

        outcome = run_study(args.study, target, workers=args.workers, scheduler=args.scheduler, retry_failed=args.retry_failed,
                            plots=False if args.no_plots else None, progress=progress_mode(not args.quiet), verbose=args.verbose)
        if outcome.status is Status.INTERRUPTED:
            print("gtmodel: interrupted (rerun the same command to solve the missing cases)", file=sys.stderr)
        print(f"study        {outcome.summary['name']}: {outcome.status} ({outcome.message})")
        print(f"cases        {outcome.summary['run_now']} solved now, {outcome.summary['skipped']} finished before, "
              f"{outcome.summary['missing']} missing")
        print(f"results in   {outcome.out}/ (table.parquet, table.csv, summary.json, cases/)")
        return outcome.exit_code

    def on_interrupt() -> None:
        # a study folder is kept across runs (its finished cases are reused); its summary says this run was interrupted
        from gtmodel.problems.study.engine import mark_interrupted

        mark_interrupted(target)

    return _guarded(target, run, on_interrupt)


def _report(args: argparse.Namespace) -> int:
    from gtmodel.problems.run import add_report

    page = add_report(args.folder)
    print(f"wrote {page}")
    return EXIT_OK


def _schema(args: argparse.Namespace) -> int:
    from gtmodel.problems.registry import all_kinds, kind_titles

    if args.list:
        print("\n".join(f"{name:<30} {title}" for name, title in kind_titles().items()))
        return EXIT_OK
    from gtmodel.problems.docs import json_schema, write_docs

    if args.docs is not None:
        for p in write_docs(args.docs):
            print(f"wrote {p}")
        return EXIT_OK
    if args.kind is None:
        raise GtModelError(f"schema: give a kind ({', '.join(all_kinds())}), --list or --docs DIR")
    text = json.dumps(json_schema(args.kind), indent=2) + "\n"
    if args.out is None:
        sys.stdout.write(text)
    else:
        try:
            args.out.write_text(text, encoding="utf-8")
        except OSError as exc:
            raise GtModelError(f"--out {args.out}: cannot write ({exc.strerror or exc})") from None
        print(f"wrote {args.out}")
    return EXIT_OK


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``gtmodel`` command.

    SIGINT and SIGTERM are handled by :mod:`gtmodel._signals` for the whole call
    (installed here unless ``python -m gtmodel`` already did, at process start): any
    number of them, at any moment of a run, end it with status ``interrupted`` and exit
    code 130 (``docs/reliability.md``).

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit code from :data:`gtmodel.status.EXIT_CODES`: 0 success (optimal / check
        passed), 1 not optimal / check failed, 2 invalid input or unwritable output,
        3 internal error, 130 interrupted (SIGINT or SIGTERM).
    """
    previous = _signals.install()
    data_dirs = os.environ.get("GTMODEL_DATA_DIRS")  # --data-dir sets it for this call only
    args = None
    try:
        args = build_parser().parse_args(argv)
        _setup_logging(getattr(args, "quiet", False))
        if args.command == "solve":  # interruptible once the output folder is checked and locked
            return _solve(args)
        if args.command == "study":
            return _study(args)
        if args.command == "loop":
            return _loop(args)
        with _signals.interruptible():
            if args.command == "schema":
                return _schema(args)
            if args.command == "report":
                return _report(args)
            if args.command == "examples":
                from gtmodel.cli_examples import examples_command

                return examples_command(args)
            if args.command in ("export-fmu", "import-fmu"):
                from gtmodel.cli_fmu import export_fmu_command, import_fmu_command

                return (export_fmu_command if args.command == "export-fmu" else import_fmu_command)(args)
            if args.command == "robot-sim":
                from gtmodel.robot_sim.cli import robot_sim_command

                return robot_sim_command(args)
            from gtmodel.cli_codegen import codegen_command

            return codegen_command(args)
    except KeyboardInterrupt:
        print("gtmodel: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except GtModelError as exc:
        print(f"gtmodel: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except Exception as exc:  # noqa: BLE001 - reported, non-zero exit
        if _signals.received():  # CasADi turned the signal into NotImplementedError/SystemError
            print("gtmodel: interrupted", file=sys.stderr)
            return EXIT_INTERRUPTED
        if isinstance(exc, MemoryError):
            print("gtmodel: error: out of memory: the input is too large for this machine", file=sys.stderr)
            return EXIT_BAD_INPUT
        if isinstance(exc, OSError) and exc.filename is not None:  # a path the user gave (--out too long, no permission)
            print(f"gtmodel: error: {exc.filename}: {exc.strerror or exc}", file=sys.stderr)
            return EXIT_BAD_INPUT
        if getattr(args, "debug", False):
            traceback.print_exc()
        print(f"gtmodel: internal error: {type(exc).__name__}: {exc} (rerun with --debug for the traceback)", file=sys.stderr)
        return EXIT_INTERNAL
    finally:
        _signals.restore(previous)
        [_log.removeHandler(h) for h in list(_log.handlers) if getattr(h, "_gtmodel_cli", False)]  # its stderr may close
        if data_dirs is None:
            os.environ.pop("GTMODEL_DATA_DIRS", None)
        else:
            os.environ["GTMODEL_DATA_DIRS"] = data_dirs


if __name__ == "__main__":  # pragma: no cover - ``python -m gtmodel.cli``: gtmodel/__init__.py installed the handlers
    sys.exit(_signals.process_exit_code(main()))
