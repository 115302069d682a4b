"""``gtmodel loop``: the 4 ms loop on a robot controller's interface (:mod:`gtmodel.cli` dispatches here).

::

    gtmodel loop FILE.toml --out DIR [--listen HOST:PORT] [--robot ADDR[:PORT]] [--sensor-port PORT]
                 [--idle-timeout S] [--max-cycles N] [--correction-file CSV]

runs a ``robot_loop`` file (:mod:`gtmodel.problems.kinds.robot_loop`): the controller's step
generated as C and checked, the runtime built around it, serving the robot (or its
simulator, ``gtmodel robot-sim``) that sends to the listening port until the robot stops
sending for the idle time-out, the cycle limit or a signal (Ctrl-C ends the run as the
robot stopping does: the log is flushed and the summary written). It is ``gtmodel solve``
on that file with the command line's settings; the result folder holds ``summary.json``,
the cycle log and the generated code. Docs: ``docs/robot.md``.
"""

from __future__ import annotations

import argparse
import sys
import traceback
from pathlib import Path
from typing import Any

from gtmodel.errors import InputError
from gtmodel.status import Status

__all__ = ["add_loop_parser", "loop_settings", "print_loop_summary", "loop_command"]


def add_loop_parser(sub: Any) -> argparse.ArgumentParser:
    """Add ``loop`` to the ``gtmodel`` parser.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``gtmodel`` parser's sub-commands.

    Returns
    -------
    argparse.ArgumentParser
        The ``loop`` parser.
    """
    p = sub.add_parser("loop", help="run the 4 ms loop of a robot-loop file behind KUKA RSI or ABB EGM (UDP) until the robot stops",
                       description="Generate, check and build the loop of a robot-loop file, then serve the robot (or gtmodel robot-sim) "
                                   "that sends to the listening port; Ctrl-C ends the run cleanly. Docs: docs/robot.md.")
    p.add_argument("file", type=Path, help="a robot_loop file (TOML), e.g. loops/kr500_rsi_correction.toml")
    p.add_argument("--out", type=Path, default=None, help="result folder (default: results/<name>)")
    p.add_argument("--listen", default=None, metavar="HOST:PORT", help="where the runtime listens (overrides [interface] listen)")
    p.add_argument("--robot", default=None, metavar="ADDR[:PORT]", help="the robot controller's address: only its datagrams are answered "
                   "(overrides [interface] robot; default the first valid packet's source)")
    p.add_argument("--sensor-port", type=_ascii_int, default=None, metavar="PORT", help="UDP port of the sensor stream on the listen address (overrides [interface] sensor_port)")
    p.add_argument("--idle-timeout", type=_ascii_float, default=None, metavar="S", help="end when the robot has sent nothing this long (overrides the file)")
    p.add_argument("--max-cycles", type=_ascii_int, default=None, metavar="N", help="end after N cycles (overrides the file)")
    p.add_argument("--correction-file", default=None, metavar="CSV", help="streaming: the learned correction to add (a previous run's ilc_next.csv)")
    p.add_argument("--data-dir", type=Path, action="append", default=[], metavar="DIR",
                   help="a folder data files may also come from (default: the loop file's folder and that of --correction-file); repeatable")
    p.add_argument("--no-report", action="store_true", help="do not write report.html")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    p.add_argument("--debug", action="store_true", help="show tracebacks of internal errors")
    return p


def _ascii_int(text: str) -> int:
    # int() also reads other scripts' digits (Arabic-Indic, fullwidth): a port or a count is written in ASCII
    if not (text.isascii() and text.strip().lstrip("+-").isdigit()):
        raise argparse.ArgumentTypeError(f"expected an integer in ASCII digits, got {text!r}")
    return int(text)


def _ascii_float(text: str) -> float:
    if not text.isascii():
        raise argparse.ArgumentTypeError(f"expected a number in ASCII digits, got {text!r}")
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None


def loop_settings(args: argparse.Namespace) -> dict[str, Any]:
    """The file's fields the command line sets (dotted names for :func:`gtmodel.problems.run.run_problem`).

    Parameters
    ----------
    args : argparse.Namespace
        Parsed ``gtmodel loop`` arguments.

    Returns
    -------
    dict
        ``interface.listen``, ``interface.robot``, ``interface.sensor_port``, ``interface.idle_timeout``,
        ``interface.max_cycles``, ``controller.correction_file`` for the options given.

    Raises
    ------
    InputError
        An option's value of the wrong form (the message names the option, e.g. ``--listen``).
    """
    from gtmodel.problems.kinds.schemas.robot_loop import local_address_problem, parse_address, parse_source

    for option, parse in (("listen", parse_address), ("robot", parse_source)):
        value = getattr(args, option)
        if value is not None:
            try:
                parse(value)
            except ValueError as exc:
                raise InputError(f"--{option}: {exc}") from None
    problem = local_address_problem(parse_address(args.listen)[0]) if args.listen is not None else None
    if problem is not None:
        raise InputError(f"--listen: expected {problem}, got {args.listen!r}")
    for option, lo, hi in (("sensor_port", 1, 65535), ("max_cycles", 0, 100_000_000)):
        value = getattr(args, option)
        if value is not None and not lo <= value <= hi:
            raise InputError(f"--{option.replace('_', '-')}: expected an integer in {lo}..{hi}, got {value}")
    if args.idle_timeout is not None and not 0 < args.idle_timeout <= 3600:
        raise InputError(f"--idle-timeout: expected a number in (0, 3600] s, got {args.idle_timeout}")
    out: dict[str, Any] = {}
    for option, field in (("listen", "interface.listen"), ("robot", "interface.robot"), ("sensor_port", "interface.sensor_port"),
                          ("idle_timeout", "interface.idle_timeout"), ("max_cycles", "interface.max_cycles")):
        if getattr(args, option) is not None:
            out[field] = getattr(args, option)
    if args.correction_file is not None:  # relative to where the command runs, as a user types it
        out["controller.correction_file"] = str(Path(args.correction_file).resolve())
    return out


def print_loop_summary(summary: dict[str, Any], out: Path) -> None:
    """Print a loop run's figures (the ``gtmodel loop`` screen).

    Parameters
    ----------
    summary : dict
        The run's ``summary.json``.
    out : pathlib.Path
        The result folder.
    """
    lines = [f"status       {summary.get('status')}: {summary.get('message', '')}"]
    run = summary.get("loop") or {}
    if run:
        lat = run.get("reply_latency_ms") or {}
        lines.append(f"cycles       {run.get('cycles')} ({run.get('replies')} replies, {run.get('missing_replies')} missing, "
                     f"{run.get('late_replies')} late, {run.get('deadline_held')} held at the deadline)")
        if lat:
            lines.append(f"latency      p50 {lat.get('p50', float('nan')):.3f} ms, p99 {lat.get('p99', float('nan')):.3f} ms, "
                         f"max {lat.get('max', float('nan')):.3f} ms (receive to reply)")
        faults = {k: v.get("count") for k, v in (run.get("faults") or {}).items() if isinstance(v, dict) and v.get("count")}
        if faults:
            lines.append("faults       " + ", ".join(f"{k} {n}" for k, n in faults.items()) + " (summary.json: what was done)")
        src, strangers = run.get("source") or {}, run.get("strangers") or {}
        if src:
            lines.append(f"robot        {src.get('robot')} ({src.get('robot_rule', '').replace('_', ' ')}); strangers: "
                         f"{strangers.get('datagrams', 0)} datagrams from {len(strangers.get('addresses') or [])} addresses, none answered")
        alarms, silences, seq = run.get("alarms") or {}, run.get("silences") or {}, run.get("sequence") or {}
        if alarms.get("holds") or seq.get("resyncs") or seq.get("out_of_window"):
            lines.append(f"alarms       {alarms.get('holds', 0)} holds of {alarms.get('hold_alarm_cycles')}+ cycles (longest "
                         f"{alarms.get('longest_hold_cycles', 0)}), {seq.get('out_of_window', 0)} datagrams out of the sequence window, "
                         f"{seq.get('resyncs', 0)} resynchronisations (summary.json: loop.alarms)")
        if silences.get("count"):
            lines.append(f"silences     {silences['count']} gaps over two periods, longest {1000 * silences.get('longest_s', 0):.1f} ms")
        lines.append(f"ended by     {run.get('end')}" + (f" ({run.get('signal')})" if run.get("signal") else ""))
        rt = run.get("realtime") or {}
        lines.append("real time    " + ("SCHED_FIFO and locked memory" if rt.get("granted") else f"not granted ({rt.get('reason')})"))
    if summary.get("ilc"):
        lines.append(f"ILC          next correction in ilc_next.csv (tracking error RMS {summary['ilc'].get('error_rms')})")
    lines.append(f"results in   {out}/ ({', '.join(summary.get('files', ['summary.json']))})")
    print("\n".join(lines))


def loop_command(args: argparse.Namespace) -> int:
    """Run ``gtmodel loop`` (called by :func:`gtmodel.cli.main` inside its guard).

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments.

    Returns
    -------
    int
        The exit code of the run's status.
    """
    from gtmodel.problems.run import run_problem

    try:
        settings = loop_settings(args)
    except InputError as exc:
        print(f"gtmodel: error: {exc}", file=sys.stderr)
        return Status.INVALID_INPUT.exit_code
    outcome = run_problem(args.file, args.out, plots=False, heartbeat=not args.quiet, report=not args.no_report, settings=settings)
    status = outcome.status
    if status is Status.INTERNAL_ERROR:
        if args.debug and outcome.error is not None:
            traceback.print_exception(outcome.error)
        print(f"gtmodel: internal error: {outcome.summary['message']} (rerun with --debug for the traceback)", file=sys.stderr)
    elif status is Status.INVALID_INPUT or (status is Status.INTERRUPTED and not outcome.summary.get("loop")):
        print(f"gtmodel: error: {outcome.summary['message']}", file=sys.stderr)
    else:
        print_loop_summary(outcome.summary, outcome.out)
    return status.exit_code
