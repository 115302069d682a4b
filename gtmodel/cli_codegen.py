"""The routes of ``gtmodel codegen`` (:mod:`gtmodel.cli` dispatches here): the robot and
controller-file code, a user's model (``--model``), the tracking controller of a result
folder (``--controller DIR``) and a declared MPC (``--mpc FILE.toml``). Like every
sub-command, each route imports the layers it needs when it runs (the CLI starts fast).
"""

from __future__ import annotations

import argparse

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
    if args.mpc is not None:
        return _codegen_mpc(args)
    if args.model is not None:
        return _codegen_model(args, functions)
    if args.controller is not None and args.controller.is_dir():
        return _codegen_tracking(args)
    if args.period is not None or args.q is not None or args.r is not None:
        raise GtModelError("--period, --q and --r apply to --model (--period) and to a --controller result folder")
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
    from gtmodel.codegen.loop_step import check_loop_step
    from gtmodel.problems.mpc_check import build_mpc, closed_loop_check
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
    print("\n".join(report.summary_lines()))
    loop = closed_loop_check(setup, generated, library)
    print("\n".join(loop.summary_lines()))
    passed = report.passed and loop.mpc.bound_violations == 0 and loop.ratio_to_feedforward < 1.0
    return EXIT_OK if passed else EXIT_NOT_OPTIMAL


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
    from gtmodel.codegen.loop_step import check_loop_step, generate_loop_step, tracking_step
    from gtmodel.problems.controller import is_result_folder, tracking_from_result

    if args.robot is not None or args.functions is not None or args.retime_n_max is not None:
        raise GtModelError("--controller RESULT_DIR generates the tracking controller alone: give it without --robot, --functions, --retime-n-max")
    if not is_result_folder(args.controller):
        raise GtModelError(f"--controller {args.controller}: a folder must be a result folder (with summary.json)")
    weights = {}
    for flag in ("q", "r"):
        text = getattr(args, flag)
        if text is not None:
            try:
                weights[flag.upper()] = [float(v) for v in text.split(",")]
            except ValueError:
                raise GtModelError(f"--{flag}: expected comma-separated numbers, got {text!r}") from None
    controller, ode = tracking_from_result(args.controller, **({} if args.period is None else {"dt": args.period}), **weights)
    generated = generate_loop_step(tracking_step(controller, f"tracking of {ode.name}"), args.out, prefix="gt_tracking", real=args.real)
    print(f"wrote {', '.join(str(p) for p in generated.files)}")
    print(generated.version)
    print(f"tracking controller of {ode.name}: {controller.length} samples at {controller.dt:g} s, "
          f"{controller.nx} states, {controller.nu} inputs, input bounds {controller.u_lb.tolist()} .. {controller.u_ub.tolist()}")
    if not args.check:
        return EXIT_OK
    report = check_loop_step(generated, n=min(args.samples, 2000), seed=args.seed, timing=True)
    print("\n".join(report.summary_lines()))
    return EXIT_OK if report.passed else EXIT_NOT_OPTIMAL
