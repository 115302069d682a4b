"""``gtmodel codegen``: its sub-commands and their routes (:mod:`gtmodel.cli` dispatches here).

One sub-command per kind of generated code, each with its own options
(:func:`add_codegen_parser`)::

    gtmodel codegen robot [NAME] --out DIR [--check]          a robot's kinematics and inverse dynamics
    gtmodel codegen model FILE:CLASS --out DIR [--check]      a user's model (explicit ODE, outputs, fixed steps)
    gtmodel codegen tracking FILE.toml|RESULT_DIR --out DIR    a tracking controller (feedforward + TV-LQR)
    gtmodel codegen mpc FILE.toml --out DIR [--check]         a real-time MPC
    gtmodel codegen controller FILE --out DIR [--check]       a controller bundle (.json/.npz; alias: filter)

The former flat forms (``gtmodel codegen --robot L1``, ``--model FILE:CLASS``, ``--controller
FILE|DIR``, ``--mpc FILE``) keep working: hidden options of ``codegen`` mapped to the same
routes. Every step that may take longer than a moment says so on the log (stderr; ``-q``
silences it), with a heartbeat while it runs, and the closed loop reports its periods. Like
every sub-command, each route imports the layers it needs when it runs (the CLI starts fast).
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import math
import os
import shutil
from pathlib import Path
from typing import Any, Iterator

from gtmodel import __version__, _signals
from gtmodel.errors import GtModelError
from gtmodel.status import Status

__all__ = ["SUBCOMMANDS", "add_codegen_parser", "codegen_command"]

EXIT_OK = Status.OPTIMAL.exit_code
EXIT_NOT_OPTIMAL = Status.ERROR.exit_code

_log = logging.getLogger("gtmodel")

#: The sub-commands of ``gtmodel codegen`` and the one line saying what each generates.
SUBCOMMANDS = {
    "robot": "C for a robot's real-time kinematics and inverse dynamics (3-link sets, a calibration's parameters.toml, "
             "D1_six_link, F1), optionally with a controller bundle and the online re-timing",
    "model": "C for a user's model: its explicit ODE, outputs and fixed-step integrators over the loop period",
    "tracking": "C for a tracking controller (feedforward + time-varying LQR, saturated) with the loop-step interface, from a "
                "tracking-controller file or an optimal_control result folder; --check runs it in closed loop",
    "mpc": "C for a real-time nonlinear MPC (CasADi's sqpmethod + qrqp generated inside) with the loop-step interface, from an "
           "MPC file; --check runs it in closed loop",
    "controller": "C for a controller bundle (.json/.npz): Kalman step, learned ILC table, the fusion KF/EKF filters, the "
                  "lead-through step",
}


def _common(p: argparse.ArgumentParser, samples: int = 10000, hidden: bool = False) -> None:
    """The options every route has (``--out``, ``--check``, ``-n``, ``--seed``, ``-q``, ``--debug``)."""
    h = (lambda text: argparse.SUPPRESS) if hidden else (lambda text: text)
    p.add_argument("--out", type=Path, required=not hidden, default=None, help=h("output folder for the C files"))
    p.add_argument("--check", action="store_true", help=h("compile with the C compiler, compare with Python, time the functions "
                                                          "(and run the closed loop of a loop controller)"))
    p.add_argument("-n", "--samples", type=int, default=samples, help=h(f"random inputs per function for --check (default {samples})"))
    p.add_argument("--seed", type=int, default=0, help=h("random seed for --check"))
    p.add_argument("-q", "--quiet", action="store_true", help=h("no progress lines"))
    p.add_argument("--debug", action="store_true", help=h("show tracebacks of internal errors"))


def _real(p: argparse.ArgumentParser, hidden: bool = False) -> None:
    p.add_argument("--real", default="double", choices=("double", "float"),
                   help=argparse.SUPPRESS if hidden else "floating-point type (default double)")


def _replan(p: argparse.ArgumentParser, hidden: bool = False) -> None:
    p.add_argument("--replan", action="store_true", help=argparse.SUPPRESS if hidden else
                   "solve the file's [reference] problem even when its plan is cached (and cache it again)")


def _robot_options(p: argparse.ArgumentParser, hidden: bool = False) -> None:
    h = (lambda text: argparse.SUPPRESS) if hidden else (lambda text: text)
    p.add_argument("--friction", default="exact", choices=("exact", "tanh", "piecewise"), help=h("friction form in inverse_dynamics"))
    p.add_argument("--newton-tolerance", type=float, default=None, help=h("tolerance of the Newton loops (default per function)"))
    p.add_argument("--max-iter", type=int, default=None, help=h("iteration limit of the Newton loops (default 20)"))
    p.add_argument("--retime-n-max", type=int, default=None, metavar="N_MAX",
                   help=h("also generate <prefix>_retime (online time-optimal re-timing along a path, at most N_MAX grid points; 3-link sets)"))


def _tracking_options(p: argparse.ArgumentParser, hidden: bool = False) -> None:
    h = (lambda text: argparse.SUPPRESS) if hidden else (lambda text: text)
    p.add_argument("--period", type=float, default=None, metavar="S",
                   help=h("a result folder's tracking controller: loop period (default 0.004 s)"))
    p.add_argument("--q", default=None, metavar="Q1,Q2,...", help=h("a result folder's tracking controller: diagonal of the LQR state "
                                                                    "weight (default Bryson's rule on the reference's ranges)"))
    p.add_argument("--r", default=None, metavar="R1,...", help=h("a result folder's tracking controller: diagonal of the LQR input "
                                                               "weight (default 1/(half the bound range)^2)"))
    p.add_argument("--mismatch", type=float, default=None, metavar="FACTOR",
                   help=h("a result folder's tracking controller with --check: the closed loop's plant parameters / the model's "
                          "(default 1, the nominal plant; no input delay, no noise)"))
    p.add_argument("--accept-unverified", action="store_true", help=h("a result folder's tracking controller: take a result whose "
                   "verification failed or was skipped (default: refused); the check's summary and verdict repeat it"))


def add_codegen_parser(sub: Any) -> argparse.ArgumentParser:
    """Add ``codegen`` and its sub-commands (:data:`SUBCOMMANDS`) to the ``gtmodel`` parser.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``gtmodel`` parser's sub-commands.

    Returns
    -------
    argparse.ArgumentParser
        The ``codegen`` parser; its former flat options (``--robot``, ``--model``,
        ``--controller``, ``--mpc``, ...) hidden but accepted.
    """
    cg = sub.add_parser(
        "codegen", help="generate C for the 4 ms loop: a robot, a user's model, a tracking controller, an MPC, a controller bundle",
        description="Generate C for the 4 ms loop, one sub-command per kind of code; each has its own options "
                    "(gtmodel codegen SUB-COMMAND --help).",
        epilog="The former flat forms keep working: gtmodel codegen --robot NAME | --model FILE:CLASS | --controller FILE|DIR | "
               "--mpc FILE --out DIR [...] (docs/codegen.md).",
    )
    # the former flat forms, hidden: mapped to the sub-commands by codegen_command
    cg.add_argument("--robot", default=None, help=argparse.SUPPRESS)
    cg.add_argument("--model", default=None, help=argparse.SUPPRESS)
    cg.add_argument("--controller", type=Path, default=None, help=argparse.SUPPRESS)
    cg.add_argument("--mpc", type=Path, default=None, help=argparse.SUPPRESS)
    cg.add_argument("--functions", default=None, help=argparse.SUPPRESS)
    _replan(cg, hidden=True)
    _real(cg, hidden=True)
    _robot_options(cg, hidden=True)
    _tracking_options(cg, hidden=True)
    _common(cg, hidden=True)
    targets = cg.add_subparsers(dest="target", title="what to generate", metavar="{" + ",".join(SUBCOMMANDS) + "}")

    def target(name: str, **kw: Any) -> argparse.ArgumentParser:
        return targets.add_parser(name, help=SUBCOMMANDS[name], description=SUBCOMMANDS[name] + ".", **kw)

    robot = target("robot")
    robot.add_argument("robot", nargs="?", default=None, metavar="NAME",
                       help="L1, D1, L1_ideal, D1_six_link, F1 or a parameter TOML path (default L1)")
    robot.add_argument("--functions", default=None, help="comma-separated subset of the functions (default all of the robot)")
    robot.add_argument("--controller", type=Path, default=None, metavar="FILE",
                       help="a controller file (.json/.npz: Kalman step, learned ILC table) whose functions are added to the library")
    _real(robot)
    _robot_options(robot)
    _common(robot)

    model = target("model")
    model.add_argument("model", metavar="FILE:CLASS", help="the model, e.g. models/cart_pendulum.py:CartPendulum, or Modelica "
                       "source: drive.mo:Pkg.Drive, an Optimica class's model: file.mop:Pkg.Opt")
    model.add_argument("--functions", default=None, help="comma-separated subset of ode, outputs, step_rk4, step_implicit (default all)")
    model.add_argument("--period", type=float, default=None, metavar="S", help="period of the fixed steps (default 0.004 s)")
    _real(model)
    _common(model)

    tracking = target("tracking")
    tracking.add_argument("controller", type=Path, metavar="FILE.toml|RESULT_DIR",
                          help="a tracking-controller file ([controller], [reference], [check]; docs/model_in_the_loop.md) or an "
                               "optimal_control result folder")
    _replan(tracking)
    _real(tracking)
    _tracking_options(tracking)
    _common(tracking, samples=2000)

    mpc = target("mpc")
    mpc.add_argument("mpc", type=Path, metavar="FILE.toml", help="an MPC file ([mpc], [reference], [check]; docs/model_in_the_loop.md)")
    _replan(mpc)
    _real(mpc)
    _common(mpc, samples=200)

    controller = target("controller", aliases=["filter"])
    controller.add_argument("controller", type=Path, metavar="FILE", help="a controller file (.json/.npz)")
    controller.add_argument("--robot", default=None, metavar="NAME", help="also the robot's functions (default: with a Kalman step "
                            "or an ILC table, L1's; the filters or the lead-through step alone otherwise)")
    controller.add_argument("--functions", default=None, help="comma-separated subset of the robot's functions")
    _real(controller)
    _common(controller)
    return cg


@contextlib.contextmanager
def _step(args: argparse.Namespace, text: str, label: str | None = None) -> Iterator[None]:
    """Say what starts (the log, stderr) and, while it runs, ``<label>: still running (N s)`` every 5 s (as ``gtmodel
    solve``); quiet with -q."""
    from gtmodel.problems.runtime import Heartbeat

    _log.info("%s ...", text)
    with Heartbeat(label or text, enabled=not getattr(args, "quiet", False)):
        yield


def _progress(args: argparse.Namespace) -> Any:
    """``progress(line)`` of the closed loop: a log line (None with -q)."""
    return None if getattr(args, "quiet", False) else (lambda line: _log.info("%s", line))


def _route(args: argparse.Namespace) -> str:
    """The sub-command of a parsed command line: given, or that of a former flat form."""
    if args.target is not None:
        return "controller" if args.target == "filter" else args.target
    if args.mpc is not None:
        return "mpc"
    if args.model is not None:
        return "model"
    if args.controller is not None and (args.controller.suffix.lower() == ".toml" or args.controller.is_dir()):
        return "tracking"
    return "robot"


def _reference_line(path: Path, kind: str, replan: bool = False) -> str | None:
    """What the file's ``[reference]`` plans (a problem re-planned with overrides), said before it is solved.

    The file is read and validated first (:func:`gtmodel.problems.loop_file.read_loop_file`), so
    that a bad file is refused, naming its field, before any progress line. A plan in the plan cache
    (:mod:`gtmodel.problems.plan_cache`) is said to be reused (unless ``--replan``); an entry found
    damaged is warned about and solved when it is read.
    """
    from gtmodel.problems.loop_file import read_loop_file
    from gtmodel.problems.plan_cache import cached_entry

    doc, file = read_loop_file(Path(path), kind)
    ref = doc.reference
    if ref.problem is None:
        return None
    how = (" with " + ", ".join(f"{k} = {v}" for k, v in ref.overrides.items()) + " (the file's [reference] overrides)") if ref.overrides else ""
    try:
        entry = None if replan else cached_entry(file.reference("reference.problem", ref.problem), ref.overrides)
    except GtModelError:
        entry = None  # a missing problem file: refused, naming the field, when the reference is read
    if entry is not None:
        return f"the reference {ref.problem}{how} is not solved here: its plan is read from the plan cache ({entry}); --replan solves it again"
    return (f"the reference is re-planned: {ref.problem} solved here{how}; a solver's line that follows is this "
            "re-planned reference's, not the problem file's own plan")


def codegen_command(args: argparse.Namespace) -> int:
    """Run ``gtmodel codegen`` with the parsed arguments; the exit code (0 passed, 1 a failed check).

    Parameters
    ----------
    args : argparse.Namespace
        The arguments of :func:`add_codegen_parser`'s parser (a sub-command or a former flat form).

    Returns
    -------
    int
        The exit code: :attr:`gtmodel.status.Status.exit_code` of the check's status
        (:func:`gtmodel.codegen.check_code`), 0 without ``--check``.

    Raises
    ------
    GtModelError
        Bad input (the CLI turns it into exit 2).
    """
    from gtmodel.codegen.out_dir import check_out_dir

    if args.out is None:
        raise GtModelError("--out: expected the output folder for the C files")
    check_out_dir(args.out)  # the rule of solve --out: never a folder of the user's own files
    route = _route(args)
    functions = [f.strip() for f in args.functions.split(",") if f.strip()] if args.functions else None
    if args.replan and not (route == "mpc" or (route == "tracking" and args.controller.suffix.lower() == ".toml")):
        raise GtModelError("--replan applies to an MPC or tracking-controller file (its [reference] problem)")
    if args.accept_unverified and not (route == "tracking" and args.controller.is_dir()):
        raise GtModelError("--accept-unverified applies to a --controller result folder (a controller or MPC file says "
                           "[reference] accept_unverified = true)")
    if route == "mpc":
        return _staged(args, lambda: _codegen_mpc(args))
    if route == "model":
        return _staged(args, lambda: _codegen_model(args, functions))
    if route == "tracking":
        return _staged(args, lambda: _codegen_tracking_file(args) if args.controller.suffix.lower() == ".toml" else _codegen_tracking(args))
    return _staged(args, lambda: _codegen_robot(args, functions))


#: The partial folder of the run under way and the ``--out`` it replaces when complete (the paths printed are the latter).
_STAGE: dict[str, str] = {}


def _staged(args: argparse.Namespace, run: Any) -> int:
    """Run a route into a partial folder beside ``--out`` and put it in place of ``--out`` when it has finished.

    A run that fails or is interrupted (an exception, Ctrl-C) leaves an earlier ``--out`` as it was and its partial
    folder removed (issue 67: the rule of ``solve --out``, :class:`gtmodel.problems.results.ResultFolder`).
    """
    from gtmodel.problems.results import remove_orphans, replace_folder

    target = Path(args.out)
    partial = target.parent / f".{target.name}.partial-{os.getpid()}"
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        remove_orphans(target.parent, target.name)
        shutil.rmtree(partial, ignore_errors=True)
        partial.mkdir()
    except OSError as exc:
        raise GtModelError(f"--out: cannot create the folder {target}: {exc.strerror or exc}") from None
    args.out, _STAGE[str(partial)] = partial, str(target)
    old = None
    try:
        code = run()
        with _signals.protected():  # a signal here is raised once --out is whole again
            old = replace_folder(partial, target)
    except BaseException:
        shutil.rmtree(partial, ignore_errors=True)
        raise
    finally:
        args.out = target
        _STAGE.clear()
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
    return code


def _shown(path: Any) -> str:
    """A path as the user named it: inside ``--out``, not inside the partial folder it is written to."""
    text = str(path)
    for partial, target in _STAGE.items():
        text = text.replace(partial, target)
    return text


def _verdict(args: argparse.Namespace, generated: Any, **options: Any) -> int:
    """Check generated code (:func:`gtmodel.codegen.check_code`), print every part and the verdict; the status's exit code."""
    from gtmodel.codegen import check_code

    from gtmodel.codegen.out_dir import SUMMARY
    from gtmodel.problems.results import write_json

    with _step(args, f"checking {generated.prefix}", f"checking {generated.prefix}"):
        result = check_code(generated, seed=args.seed, progress=_progress(args), **options)
    print("\n".join(_shown(line) for line in result.summary_lines()))
    summary = Path(args.out) / SUMMARY  # inside the partial folder: in place with the C, or not at all
    write_json(summary, {"kind": f"codegen_{_route(args)}", "prefix": generated.prefix, "gtmodel": __version__,
                         "version": str(generated.version), **result.to_dict()})
    _log.info("wrote %s (status %s)", _shown(summary), result.status)  # stderr: stdout ends with the verdict
    return result.status.exit_code


def _wrote(generated: Any) -> None:
    print(f"wrote {', '.join(_shown(p) for p in generated.files)}")
    print(generated.version)


def _codegen_robot(args: argparse.Namespace, functions: list[str] | None) -> int:
    from gtmodel.codegen import ControllerSource, RobotSource, generate_code, load_controller

    if args.period is not None or args.q is not None or args.r is not None or args.mismatch is not None:
        raise GtModelError("--period, --q, --r and --mismatch apply to --model (--period) and to a --controller result folder")
    controller = load_controller(args.controller) if args.controller is not None else None
    alone = (args.robot is None and functions is None and controller is not None and controller.kalman_step is None
             and controller.ilc_correction is None) or functions == []  # the fusion filters, the lead-through step: no robot
    if alone and controller is not None:
        source: Any = ControllerSource(controller)
    else:
        source = RobotSource(args.robot or "L1", friction=args.friction, functions=functions, newton_tolerance=args.newton_tolerance,
                             max_iter=args.max_iter, controller=controller, retime_n_max=args.retime_n_max)
    with _step(args, f"generating {source.summary()}"):
        generated = generate_code(source, args.out, real=args.real,
                                  prefix=source.default_prefix() if isinstance(source, ControllerSource) else None)
    _wrote(generated)
    if not args.check:
        return EXIT_OK
    return _verdict(args, generated, n=args.samples, timing=True)


def _codegen_mpc(args: argparse.Namespace) -> int:
    from gtmodel.codegen.loop_step import build_step, mpc_step
    from gtmodel.problems.mpc_file import load_mpc_file

    if args.model is not None or args.robot is not None or args.controller is not None:
        raise GtModelError("--mpc generates the MPC of its file alone: give it without --model, --robot and --controller")
    planned = _reference_line(args.mpc, "mpc", args.replan)
    with _step(args, f"reading {args.mpc}" + (f"; {planned}" if planned else ""), f"reading {args.mpc}"):
        setup = load_mpc_file(args.mpc, replan=args.replan)
    c = setup.controller
    how = f"its real-time iteration, the QP by {c.qpsol}" if c.solver == "sqpmethod" else {"hpipm": "its real-time iteration by HPIPM", "fatrop": "fatrop"}.get(c.solver, c.solver)
    with _step(args, f"generating and compiling the MPC {setup.name} ({how} inside one step)",
               f"generating and compiling {setup.name}"):
        generated, _ = build_step(mpc_step(setup.controller, setup.name, real=args.real), args.out, f"gt_{setup.name}", real=args.real)
    print(f"wrote {_shown(generated.source)}, {_shown(generated.header)}, {_shown(generated.casadi_source)}")
    print(generated.version)
    if not args.check:
        return EXIT_OK
    return _verdict(args, generated, n=min(args.samples, 200), plant=setup, label="MPC")


def _codegen_tracking_file(args: argparse.Namespace) -> int:
    from gtmodel.codegen.loop_step import generate_loop_step, tracking_step
    from gtmodel.problems.tracking_file import load_tracking_file

    given = [flag for flag, value in (("--model", args.model), ("--robot", args.robot), ("--functions", args.functions),
                                      ("--retime-n-max", args.retime_n_max), ("--period", args.period), ("--q", args.q),
                                      ("--r", args.r), ("--mismatch", args.mismatch)) if value is not None]
    if given:
        raise GtModelError(f"--controller FILE.toml generates the tracking controller of its file alone: give it without {', '.join(given)} "
                           "(the period, weights and plant are the file's)")
    planned = _reference_line(args.controller, "tracking_controller", args.replan)
    with _step(args, f"reading {args.controller} and computing the LQR gains" + (f"; {planned}" if planned else ""),
               f"reading {args.controller}"):
        setup = load_tracking_file(args.controller, replan=args.replan)
    c = setup.controller
    with _step(args, f"generating the tracking controller {setup.name}"):
        generated = generate_loop_step(tracking_step(c, setup.name), args.out, prefix=f"gt_{setup.name}", real=args.real)
    _wrote(generated)
    print(f"tracking controller {setup.name}: {c.length} samples at {c.dt:g} s, {c.nx} states, {c.nu} inputs, "
          f"input bounds {c.u_lb.tolist()} .. {c.u_ub.tolist()}")
    if not args.check:
        return EXIT_OK
    return _verdict(args, generated, n=min(args.samples, 2000), timing=True, plant=setup, label="tracking controller")


def _codegen_model(args: argparse.Namespace, functions: list[str] | None) -> int:
    from gtmodel.codegen import UserModelSource, generate_code
    from gtmodel.problems.user_model import load_user_model, split_model_reference

    if args.controller is not None or args.robot is not None:
        raise GtModelError("--model generates a user model's library: give it without --robot and --controller")
    if args.period is not None and not (math.isfinite(args.period) and args.period > 0):
        raise GtModelError(f"--period: expected a positive loop period in seconds, got {args.period!r}")
    with _step(args, f"loading {args.model} and reducing it to an explicit ODE"):
        model = load_user_model(*split_model_reference(args.model))
    source = UserModelSource(model, functions=functions, **({} if args.period is None else {"dt": args.period}))
    with _step(args, f"generating {source.summary()}"):
        generated = generate_code(source, args.out, real=args.real)
    _wrote(generated)
    if not args.check:
        return EXIT_OK
    return _verdict(args, generated, n=args.samples, timing=True)


def _codegen_tracking(args: argparse.Namespace) -> int:
    from gtmodel.codegen.loop_step import generate_loop_step, tracking_step
    from gtmodel.problems.controller import is_result_folder, result_loop_setup, tracking_from_result
    from gtmodel.problems.loop_file import MAX_PERIOD_S, MAX_WEIGHT, MIN_PERIOD_S

    if args.robot is not None or args.functions is not None or args.retime_n_max is not None:
        raise GtModelError("--controller RESULT_DIR generates the tracking controller alone: give it without --robot, --functions, --retime-n-max")
    if not is_result_folder(args.controller):
        raise GtModelError(f"--controller {args.controller}: a folder must be a result folder (with summary.json)")
    if args.period is not None and not MIN_PERIOD_S <= args.period <= MAX_PERIOD_S:  # the ranges of a tracking-controller file
        raise GtModelError(f"--period: expected a loop period of {MIN_PERIOD_S:g} to {MAX_PERIOD_S:g} s, got {args.period!r}")
    weights = {}
    for flag in ("q", "r"):
        text = getattr(args, flag)
        if text is not None:
            try:
                weights[flag.upper()] = [float(v) for v in text.split(",")]
            except ValueError:
                raise GtModelError(f"--{flag}: expected comma-separated numbers, got {text!r}") from None
            if not all(0 <= v <= MAX_WEIGHT for v in weights[flag.upper()]):
                raise GtModelError(f"--{flag}: expected comma-separated finite weights of 0 to {MAX_WEIGHT:g}, got {text!r}")
    if args.mismatch is not None and not (math.isfinite(args.mismatch) and 0 < args.mismatch <= 10):
        raise GtModelError(f"--mismatch: expected a factor in (0, 10] on the plant's parameters, got {args.mismatch!r}")
    with _step(args, f"reading the result folder {args.controller} and computing the LQR gains"):
        controller, ode = tracking_from_result(args.controller, **({} if args.period is None else {"dt": args.period}), **weights,
                                               accept_unverified=bool(args.accept_unverified))
    with _step(args, f"generating the tracking controller of {ode.name}"):
        generated = generate_loop_step(tracking_step(controller, f"tracking of {ode.name}"), args.out, prefix="gt_tracking", real=args.real)
    _wrote(generated)
    print(f"tracking controller of {ode.name}: {controller.length} samples at {controller.dt:g} s, "
          f"{controller.nx} states, {controller.nu} inputs, input bounds {controller.u_lb.tolist()} .. {controller.u_ub.tolist()}")
    if not args.check:
        return EXIT_OK
    setup = result_loop_setup(args.controller, controller, ode, 1.0 if args.mismatch is None else args.mismatch)
    return _verdict(args, generated, n=min(args.samples, 2000), timing=True, plant=setup, label="tracking controller")
