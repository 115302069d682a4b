"""The routes of ``gtmodel codegen`` (:mod:`gtmodel.cli` dispatches here): the robot and
controller-file code, a user's model (``--model``), the tracking controller of a result
folder (``--controller DIR``) or of a tracking-controller file (``--controller FILE.toml``)
and a declared MPC (``--mpc FILE.toml``). Like every
sub-command, each route imports the layers it needs when it runs (the CLI starts fast).
"""

from __future__ import annotations

import argparse
import math

from gtmodel.errors import GtModelError
from gtmodel.status import Status

__all__ = ["codegen_command"]

EXIT_OK = Status.OPTIMAL.exit_code
EXIT_NOT_OPTIMAL = Status.ERROR.exit_code


def codegen_command(args: argparse.Namespace) -> int:
    """Run ``gtmodel codegen`` with the parsed arguments; the exit code (0 passed, 1 a failed check).

    Parameters
    ----------
    args : argparse.Namespace
        The arguments of :func:`gtmodel.cli.build_parser`'s ``codegen`` sub-command.

    Returns
    -------
    int
        The exit code.

    Raises
    ------
    GtModelError
        Bad input (the CLI turns it into exit 2).
    """
    from gtmodel.codegen import check, check_controller, generate, load_controller
    from gtmodel.codegen.out_dir import check_out_dir

    check_out_dir(args.out)  # the rule of solve --out: never a folder of the user's own files

    functions = [f.strip() for f in args.functions.split(",") if f.strip()] if args.functions else None
    if getattr(args, "accept_unverified", False) and not (args.controller is not None and args.controller.is_dir()):
        raise GtModelError("--accept-unverified applies to a --controller result folder (a controller or MPC file says "
                           "[reference] accept_unverified = true)")
    if args.mpc is not None:
        return _codegen_mpc(args)
    if args.model is not None:
        return _codegen_model(args, functions)
    if args.controller is not None and args.controller.suffix.lower() == ".toml":
        return _codegen_tracking_file(args)
    if args.controller is not None and args.controller.is_dir():
        return _codegen_tracking(args)
    if args.period is not None or args.q is not None or args.r is not None or args.mismatch is not None:
        raise GtModelError("--period, --q, --r and --mismatch apply to --model (--period) and to a --controller result folder")
    controller = load_controller(args.controller) if args.controller is not None else None
    if args.robot is None and functions is None and controller is not None and controller.kalman_step is None and controller.ilc_correction is None:
        functions = []  # the fusion filters and the lead-through step need no robot: the controller alone
    alone = "gt" if controller is not None and controller.functions == ("lead_through_step",) else "gt_fusion"
    generated = generate(
        robot=args.robot or "L1", out_dir=args.out, friction=args.friction, real=args.real, prefix=alone if functions == [] else None,
        newton_tolerance=args.newton_tolerance, max_iter=args.max_iter, functions=functions, controller=controller,
        retime_n_max=args.retime_n_max,
    )
    print(f"wrote {', '.join(str(p) for p in generated.files)}")
    print(generated.version)
    if not args.check:
        return EXIT_OK
    passed = True
    if len(generated.specs) > len(controller.specs() if controller else ()):
        report = check(generated, n=args.samples, seed=args.seed, timing=True)
        print("\n".join(report.summary_lines()))
        passed = report.passed
    if controller is not None:
        controller_report = check_controller(generated, seed=args.seed, timing=True)
        print("\n".join(controller_report.summary_lines()))
        passed = passed and controller_report.passed
    return EXIT_OK if passed else EXIT_NOT_OPTIMAL


def _codegen_mpc(args: argparse.Namespace) -> int:
    from gtmodel.codegen.check.loop_step import check_loop_step
    from gtmodel.codegen.check.mpc import build_mpc, closed_loop_check
    from gtmodel.problems.mpc_file import load_mpc_file

    if args.model is not None or args.robot is not None or args.controller is not None:
        raise GtModelError("--mpc generates the MPC of its file alone: give it without --model, --robot and --controller")
    setup = load_mpc_file(args.mpc)
    generated, library = build_mpc(setup, args.out)
    print(f"wrote {generated.source}, {generated.header}, {generated.casadi_source}")
    print(generated.version)
    if not args.check:
        return EXIT_OK
    report = check_loop_step(generated, n=min(args.samples, 200), seed=args.seed)
    return _loop_verdict(report, closed_loop_check(setup, generated, library))


def _loop_verdict(report, loop) -> int:
    """Print a loop controller's C-vs-Python report and closed loop; the exit code (1: C differs, the plant
    diverged, a bound violated, a failed step, or no better than the feedforward alone)."""
    print("\n".join(report.summary_lines()))
    print("\n".join(loop.summary_lines()))
    failures = (["the C differs from Python"] if not report.passed else []) + loop.failures()
    notes = "".join(f" [{n}]" for n in getattr(loop, "notes", []))  # an unverified reference accepted, unknown bounds: in the verdict too
    print("closed-loop check: " + ("PASSED" if not failures else "FAILED (" + "; ".join(failures) + ")") + notes)
    return EXIT_OK if not failures else EXIT_NOT_OPTIMAL


def _codegen_tracking_file(args: argparse.Namespace) -> int:
    from gtmodel.codegen.check.loop_step import check_loop_step
    from gtmodel.codegen.loop_step import generate_loop_step, tracking_step
    from gtmodel.codegen.check.closed_loop import closed_loop_check
    from gtmodel.problems.tracking_file import load_tracking_file

    given = [flag for flag, value in (("--model", args.model), ("--robot", args.robot), ("--functions", args.functions),
                                      ("--retime-n-max", args.retime_n_max), ("--period", args.period), ("--q", args.q),
                                      ("--r", args.r), ("--mismatch", args.mismatch),
                                      ("--real", None if args.real == "double" else args.real)) if value is not None]
    if given:
        raise GtModelError(f"--controller FILE.toml generates the tracking controller of its file alone: give it without {', '.join(given)} "
                           "(the period, weights and plant are the file's)")
    setup = load_tracking_file(args.controller)
    c = setup.controller
    generated = generate_loop_step(tracking_step(c, setup.name), args.out, prefix=f"gt_{setup.name}")
    print(f"wrote {', '.join(str(p) for p in generated.files)}")
    print(generated.version)
    print(f"tracking controller {setup.name}: {c.length} samples at {c.dt:g} s, {c.nx} states, {c.nu} inputs, "
          f"input bounds {c.u_lb.tolist()} .. {c.u_ub.tolist()}")
    if not args.check:
        return EXIT_OK
    report = check_loop_step(generated, n=min(args.samples, 2000), seed=args.seed, timing=True)
    return _loop_verdict(report, closed_loop_check(setup, generated, report.library, label="tracking controller"))


def _codegen_model(args: argparse.Namespace, functions: list[str] | None) -> int:
    from gtmodel.codegen.model_code import check_model, generate_model
    from gtmodel.problems.user_model import load_user_model, split_model_reference

    if args.controller is not None or args.robot is not None:
        raise GtModelError("--model generates a user model's library: give it without --robot and --controller")
    period = {} if args.period is None else {"dt": args.period}
    generated = generate_model(load_user_model(*split_model_reference(args.model)), args.out, functions=functions, real=args.real, **period)
    print(f"wrote {', '.join(str(p) for p in generated.files)}")
    print(generated.version)
    if not args.check:
        return EXIT_OK
    report = check_model(generated, n=args.samples, seed=args.seed, timing=True)
    print("\n".join(report.summary_lines()))
    return EXIT_OK if report.passed else EXIT_NOT_OPTIMAL


def _codegen_tracking(args: argparse.Namespace) -> int:
    from gtmodel.codegen.check.loop_step import check_loop_step
    from gtmodel.codegen.loop_step import generate_loop_step, tracking_step
    from gtmodel.problems.controller import is_result_folder, result_loop_setup, tracking_from_result
    from gtmodel.codegen.check.closed_loop import closed_loop_check
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
    controller, ode = tracking_from_result(args.controller, **({} if args.period is None else {"dt": args.period}), **weights,
                                           accept_unverified=bool(getattr(args, "accept_unverified", False)))
    if args.mismatch is not None and not (math.isfinite(args.mismatch) and 0 < args.mismatch <= 10):
        raise GtModelError(f"--mismatch: expected a factor in (0, 10] on the plant's parameters, got {args.mismatch!r}")
    generated = generate_loop_step(tracking_step(controller, f"tracking of {ode.name}"), args.out, prefix="gt_tracking", real=args.real)
    print(f"wrote {', '.join(str(p) for p in generated.files)}")
    print(generated.version)
    print(f"tracking controller of {ode.name}: {controller.length} samples at {controller.dt:g} s, "
          f"{controller.nx} states, {controller.nu} inputs, input bounds {controller.u_lb.tolist()} .. {controller.u_ub.tolist()}")
    if not args.check:
        return EXIT_OK
    report = check_loop_step(generated, n=min(args.samples, 2000), seed=args.seed, timing=True)
    if args.real != "double":  # the closed loop calls the step with doubles (ctypes), as the MPC's
        print("\n".join(report.summary_lines()))
        print("closed loop: not run for --real float")
        return EXIT_OK if report.passed else EXIT_NOT_OPTIMAL
    setup = result_loop_setup(args.controller, controller, ode, 1.0 if args.mismatch is None else args.mismatch)
    return _loop_verdict(report, closed_loop_check(setup, generated, report.library, label="tracking controller"))
