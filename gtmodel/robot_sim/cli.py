"""``gtmodel robot-sim``: a simulated robot (KUKA RSI or ABB EGM) sending to a sensor side.

::

    gtmodel robot-sim --interface rsi|egm [--plant kr500|l1] --to HOST:PORT [--sensor-to HOST:PORT]
                      --duration S [--faults SPEC] [--seed N] [--correction relative|absolute]
                      [--late-limit N] [--sen-type TYPE] --out DIR

(:func:`add_robot_sim_parser` adds it to the ``gtmodel`` command's sub-parsers,
:func:`robot_sim_command` runs it.) The run itself is :func:`gtmodel.robot_sim.run.simulate`,
imported when the command runs (the ``gtmodel`` command starts fast).
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path
from typing import Any

from gtmodel._lazy import lazy_module
from gtmodel.errors import GtModelError
from gtmodel.status import Status

__all__ = ["DEFAULT_TARGETS", "DEFAULT_PLANTS", "host_port", "add_robot_sim_parser", "robot_sim_command"]

#: The simulation, imported when the command runs.
_run = lazy_module("gtmodel.robot_sim.run")

_log = logging.getLogger("gtmodel")

#: Default sensor-side address per interface (RSI's and EGM's usual ports).
DEFAULT_TARGETS = {"rsi": "127.0.0.1:49152", "egm": "127.0.0.1:6510"}
#: Default plant per interface.
DEFAULT_PLANTS = {"rsi": "kr500", "egm": "l1"}


def host_port(text: str) -> tuple[str, int]:
    """``HOST:PORT`` as ``(host, port)`` (an argparse type).

    Parameters
    ----------
    text : str
        E.g. ``"127.0.0.1:49152"``.

    Returns
    -------
    tuple of (str, int)

    Raises
    ------
    argparse.ArgumentTypeError
        No colon, an empty host, or a port outside 1..65535.
    """
    host, sep, port = str(text).rpartition(":")
    if not sep or not host or not (port.isascii() and port.isdigit()) or not 0 < int(port) < 65536:  # ASCII: int() reads other scripts' digits
        raise argparse.ArgumentTypeError(f"expected HOST:PORT with a port in 1..65535, got {text!r}")
    return host, int(port)


def add_robot_sim_parser(sub: Any) -> argparse.ArgumentParser:
    """Add ``robot-sim`` to the sub-parsers of the ``gtmodel`` command.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``add_subparsers()`` object.

    Returns
    -------
    argparse.ArgumentParser
        The sub-command's parser.
    """
    p = sub.add_parser("robot-sim", help="a simulated robot (KUKA RSI or ABB EGM at 4 ms) with the project's plant models, "
                       "sending to a sensor side (rehearse a loop against it)",
                       description="Plays the robot of KUKA RSI or ABB EGM: sends from its own 4 ms clock to --to, applies the "
                       "replies through a plant model (kr500: the KR 500 on Cvitanic's sine path with pose-offset corrections; "
                       "l1: the L1 Gantry-Tau's servos), streams the tracker (GTS1 lines, 1000 Hz) to --sensor-to, injects "
                       "faults, and writes sim_record.csv and sim_summary.json into --out.")
    p.add_argument("--interface", choices=("rsi", "egm"), required=True, help="the protocol")
    p.add_argument("--plant", choices=("kr500", "l1"), default=None, help="the plant (default: kr500 for rsi, l1 for egm)")
    p.add_argument("--to", type=host_port, default=None, metavar="HOST:PORT",
                   help="the sensor side (default 127.0.0.1:49152 for rsi, 127.0.0.1:6510 for egm)")
    p.add_argument("--sensor-to", type=host_port, default=None, metavar="HOST:PORT", help="the sensor stream's target (default: --to's port + 1)")
    p.add_argument("--duration", type=float, default=60.0, metavar="S", help="length of the run [s] (default 60)")
    p.add_argument("--faults", default=None, metavar="SPEC", help="fault schedule, e.g. 'loss:rate=0.01;garbage:at=100;stop:at=5000' "
                   "(kinds: loss, drop, delay, duplicate, reorder, garbage, nan, ipoc_jump, stop)")
    p.add_argument("--seed", type=int, default=0, help="seed of the noise and the fault rates (default 0)")
    p.add_argument("--correction", choices=("relative", "absolute"), default="relative",
                   help="how the robot applies RSI corrections: summed increments (relative, default) or offsets (absolute)")
    p.add_argument("--late-limit", type=int, default=None, metavar="N", help="consecutive late replies before the robot stops (default 100)")
    p.add_argument("--sen-type", default="ImFree", metavar="TYPE", help="the <Sen Type> the RSI robot accepts (default ImFree)")
    p.add_argument("--out", type=Path, required=True, help="output folder: new, empty, or a previous robot-sim run's")
    p.add_argument("-q", "--quiet", action="store_true", help="no summary line")
    return p


def robot_sim_command(args: argparse.Namespace) -> int:
    """Run ``gtmodel robot-sim``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options of :func:`add_robot_sim_parser`.

    Returns
    -------
    int
        The exit code of the run's status (0 completed; 1 stopped on late replies or a
        socket error; 2 bad input; 130 interrupted).
    """
    target = args.to or host_port(DEFAULT_TARGETS[args.interface])
    plant = args.plant or DEFAULT_PLANTS[args.interface]
    try:
        result = _run.simulate(args.interface, plant, target, sensor_target=args.sensor_to, duration_s=args.duration, faults=args.faults,
                               seed=args.seed, out_dir=args.out, correction=args.correction, late_limit=args.late_limit, sen_type=args.sen_type)
    except GtModelError as exc:
        print(f"gtmodel robot-sim: {exc}", file=sys.stderr)
        return Status.INVALID_INPUT.exit_code
    s = result.summary
    rms, mx = (f"{v:.4f}" if v is not None else "-" for v in (s["error_rms_mm"], s["error_max_mm"]))
    if not args.quiet:
        print(f"robot-sim {args.interface}/{plant}: {result.status} ({result.message}); {s['cycles_sent']} cycles, {s['replies']} replies, "
              f"{s['late']} late (max {s['consecutive_late_max']} in a row), {s['malformed_replies']} malformed; {s['error_name']} "
              f"RMS {rms} mm, max {mx} mm; {args.out}")
    return result.status.exit_code
