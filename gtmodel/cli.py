"""The ``gtmodel`` command.

``gtmodel solve PROBLEM.toml [--out DIR]``
    Load, validate and solve a problem file; write ``DIR/summary.json`` (always),
    the data files of its kind and PNG plots. Exit code 0 only for an optimal solution,
    1 for a non-optimal solver status, 2 for invalid input, 3 for an internal error,
    130 when interrupted (Ctrl-C).
``gtmodel solve A.toml B.toml ... [--out DIR]`` / ``gtmodel solve A.toml --sweep w=0,0.001``
    A study: every case in ``DIR/<case>/`` and a comparison table (``comparison.md``,
    ``comparison.csv``) with overlay plots in ``DIR``. Exit code 0 only if every case is
    optimal; otherwise the worst of the cases' codes.
``gtmodel codegen --robot L1 --out DIR [--check]``
    Generate C for the real-time kinematics and inverse dynamics (3-link sets, also a
    calibration's ``parameters.toml``; ``D1_six_link``; ``F1``); ``--check`` compiles it,
    compares every function with the Python model on random and edge-case inputs and
    prints the largest error and ns/call.
"""

from __future__ import annotations

import argparse
import logging
import sys
import traceback
from pathlib import Path
from typing import Sequence

from gtmodel import __version__
from gtmodel.errors import GtModelError

__all__ = ["main", "build_parser", "EXIT_OK", "EXIT_NOT_OPTIMAL", "EXIT_BAD_INPUT", "EXIT_INTERNAL", "EXIT_INTERRUPTED"]

EXIT_OK = 0
EXIT_NOT_OPTIMAL = 1
EXIT_BAD_INPUT = 2
EXIT_INTERNAL = 3
EXIT_INTERRUPTED = 130

_log = logging.getLogger("gtmodel")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``gtmodel`` command.

    Returns
    -------
    argparse.ArgumentParser
        Parser with the sub-commands ``solve`` and ``codegen``.
    """
    parser = argparse.ArgumentParser(prog="gtmodel", description="Gantry-Tau modelling, optimal control and C code generation")
    parser.add_argument("--version", action="version", version=f"gtmodel {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    solve = sub.add_parser("solve", help="solve a problem file and write a result folder")
    solve.add_argument("problem", type=Path, nargs="+", help="problem file(s) (TOML), e.g. problems/l1_time_optimal.toml")
    solve.add_argument("--out", type=Path, default=None, help="result folder (default: results/<problem name>)")
    solve.add_argument(
        "--sweep", default=None, metavar="FIELD=V1,V2,...", help="solve one file for several values of a field, e.g. w=0,0.001,0.01"
    )
    solve.add_argument("--warm-start", action="store_true", help="in a sweep, start each case from the previous solution")
    group = solve.add_mutually_exclusive_group()
    group.add_argument("-q", "--quiet", action="store_true", help="no solver progress")
    group.add_argument("-v", "--verbose", action="store_true", help="solver progress even when not on a terminal")
    solve.add_argument("--no-plots", action="store_true", help="do not write PNG plots")
    solve.add_argument("--debug", action="store_true", help="show tracebacks of internal errors")

    cg = sub.add_parser("codegen", help="generate C for the real-time kinematics and inverse dynamics")
    cg.add_argument("--robot", default="L1", help="L1, D1, L1_ideal, D1_six_link, F1 or a parameter TOML path (default L1)")
    cg.add_argument("--out", type=Path, required=True, help="output folder for the C files")
    cg.add_argument("--friction", default="exact", choices=("exact", "tanh", "piecewise"), help="friction form in inverse_dynamics")
    cg.add_argument("--real", default="double", choices=("double", "float"), help="floating-point type (default double)")
    cg.add_argument("--newton-tolerance", type=float, default=None, help="tolerance of the Newton loops (default per function)")
    cg.add_argument("--max-iter", type=int, default=None, help="iteration limit of the Newton loops (default 20)")
    cg.add_argument("--functions", default=None, help="comma-separated subset of the functions (default all of the robot)")
    cg.add_argument("--check", action="store_true", help="compile with gcc, compare with the Python model, time each function")
    cg.add_argument("-n", "--samples", type=int, default=10000, help="random valid inputs per function for --check (default 10000)")
    cg.add_argument("--seed", type=int, default=0, help="random seed for --check")
    cg.add_argument("--debug", action="store_true", help="show tracebacks of internal errors")
    return parser


def _setup_logging(quiet: bool) -> None:
    # one CLI handler at a time, bound to the current stderr (main() may run repeatedly in
    # one process, e.g. from tests or notebooks, each time with another sys.stderr)
    for old in [h for h in _log.handlers if getattr(h, "_gtmodel_cli", False)]:
        _log.removeHandler(old)
    handler = logging.StreamHandler(sys.stderr)
    handler._gtmodel_cli = True  # type: ignore[attr-defined]
    handler.setFormatter(logging.Formatter("%(message)s"))
    _log.addHandler(handler)
    _log.setLevel(logging.WARNING if quiet else logging.INFO)


def _try_write_summary(write_summary, out: Path, summary: dict) -> None:
    """Write an error summary; if even that fails, say so (the exit code is non-zero anyway)."""
    try:
        target = write_summary(out, summary)
    except OSError as exc:
        print(f"gtmodel: error: cannot write {out / 'summary.json'}: {exc.strerror}", file=sys.stderr)
        return
    print(f"gtmodel: wrote {target} (status error)", file=sys.stderr)


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
    if "fraction_at_force_bound" in summary:
        frac = ", ".join(f"{100 * f:.0f} %" for f in summary["fraction_at_force_bound"])
        lines.append(f"at bound     {frac} of the samples (tau1, tau2, tau3)")
    lines.append(f"results in   {out}/ ({', '.join(summary.get('files', ['summary.json']))})")
    print("\n".join(lines))


def _solve_one(args: argparse.Namespace, path: Path) -> int:
    from gtmodel.problems import error_summary, load_problem, solve_problem, write_results, write_summary

    out = args.out if args.out is not None else Path("results") / path.stem
    kind = None
    try:
        problem = load_problem(path)
        kind = problem.kind
        out = args.out if args.out is not None else Path("results") / problem.name
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            print(f"gtmodel: error: --out {out}: cannot create the result folder ({exc.strerror})", file=sys.stderr)
            return EXIT_BAD_INPUT
        show_progress = args.verbose or (not args.quiet and sys.stdout.isatty())
        _log.info("solving %s (%s) ...", problem.name, problem.kind)
        solution = solve_problem(problem, verbose=show_progress)
        summary = write_results(problem, solution, out, plots=not args.no_plots)
    except GtModelError as exc:
        print(f"gtmodel: error: {exc}", file=sys.stderr)
        _try_write_summary(write_summary, out, error_summary(path, exc, kind))
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        _try_write_summary(write_summary, out, error_summary(path, RuntimeError("interrupted by the user"), kind))
        print("gtmodel: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:  # noqa: BLE001 - reported, summarised, non-zero exit
        _try_write_summary(write_summary, out, error_summary(path, exc, kind))
        if args.debug:
            traceback.print_exc()
        print(f"gtmodel: internal error: {type(exc).__name__}: {exc} (rerun with --debug for the traceback)", file=sys.stderr)
        return EXIT_INTERNAL
    _print_summary(summary, out)
    return EXIT_OK if summary["status"] == "optimal" else EXIT_NOT_OPTIMAL


def _solve_study(args: argparse.Namespace) -> int:
    from gtmodel._fields import parse_override
    from gtmodel.problems import solve_study

    try:
        sweep = parse_override(args.sweep) if args.sweep else None
    except GtModelError as exc:
        print(f"gtmodel: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if sweep is not None and len(args.problem) != 1:
        print(f"gtmodel: error: --sweep needs exactly one problem file, got {len(args.problem)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    default = args.problem[0].stem + ("_sweep_" + sweep[0].replace(".", "_") if sweep else "_study")
    out = args.out if args.out is not None else Path("results") / default
    show_progress = args.verbose or (not args.quiet and sys.stdout.isatty())
    codes: list[int] = []

    def report(case) -> None:
        s = case.summary
        status = s.get("status")
        if status == "error":
            print(f"gtmodel: error: {case.label}: {s.get('message')}", file=sys.stderr)
            codes.append(EXIT_BAD_INPUT)
        else:
            codes.append(EXIT_OK if status == "optimal" else EXIT_NOT_OPTIMAL)
        _log.info("%s: %s", case.label, status)

    try:
        solve_study(
            args.problem, out, sweep=sweep, verbose=show_progress, plots=not args.no_plots, warm_start=args.warm_start, on_case=report
        )
    except GtModelError as exc:
        print(f"gtmodel: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("gtmodel: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:  # noqa: BLE001
        if args.debug:
            traceback.print_exc()
        print(f"gtmodel: internal error: {type(exc).__name__}: {exc} (rerun with --debug for the traceback)", file=sys.stderr)
        return EXIT_INTERNAL
    print((out / "comparison.md").read_text(encoding="utf-8"), end="")
    print(f"results in   {out}/ (comparison.md, comparison.csv, one folder per case)")
    return max(codes) if codes else EXIT_BAD_INPUT


def _solve(args: argparse.Namespace) -> int:
    if len(args.problem) == 1 and args.sweep is None:
        return _solve_one(args, args.problem[0])
    return _solve_study(args)


def _codegen(args: argparse.Namespace) -> int:
    from gtmodel.codegen import check, generate

    try:
        functions = [f.strip() for f in args.functions.split(",") if f.strip()] if args.functions else None
        generated = generate(
            robot=args.robot, out_dir=args.out, friction=args.friction, real=args.real,
            newton_tolerance=args.newton_tolerance, max_iter=args.max_iter, functions=functions,
        )
        print(f"wrote {', '.join(str(p) for p in generated.files)}")
        print(generated.version)
        if not args.check:
            return EXIT_OK
        report = check(generated, n=args.samples, seed=args.seed, timing=True)
    except GtModelError as exc:
        print(f"gtmodel: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except Exception as exc:  # noqa: BLE001
        if args.debug:
            traceback.print_exc()
        print(f"gtmodel: internal error: {type(exc).__name__}: {exc} (rerun with --debug for the traceback)", file=sys.stderr)
        return EXIT_INTERNAL
    print("\n".join(report.summary_lines()))
    return EXIT_OK if report.passed else EXIT_NOT_OPTIMAL


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``gtmodel`` command.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit code: 0 success (optimal / check passed), 1 not optimal / check failed,
        2 invalid input, 3 internal error, 130 interrupted.
    """
    args = build_parser().parse_args(argv)
    _setup_logging(getattr(args, "quiet", False))
    if args.command == "solve":
        return _solve(args)
    return _codegen(args)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
