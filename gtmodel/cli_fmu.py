"""``gtmodel export-fmu`` and ``gtmodel import-fmu`` (:mod:`gtmodel.cli` dispatches here).

::

    gtmodel export-fmu (--model FILE:CLASS | --robot NAME | --modelica FILE.mo[:CLASS] | --controller FILE) --out NAME.fmu
                       [--fmi-version 2.0|3.0] [--interface me|cs|both] [--step S] [--sources-only]
    gtmodel import-fmu FILE.fmu [--stop-time T [--points N] [--start NAME=VALUE ...] [--input CSV] --out CSV]

``export-fmu`` writes an FMU (:func:`gtmodel.exchange.export_fmu`; a controller file's Kalman
step: :func:`gtmodel.exchange.fmu_step.export_step_fmu`) with exactly the interfaces asked
for, or refuses (FMI 3.0 export always carries model exchange: ``--interface cs`` is refused
with it). ``import-fmu`` loads an FMU as gtmodel does (:func:`gtmodel.exchange.import_fmu`),
lists it and simulates it with CVODES (:func:`gtmodel.exchange.simulate_explicit`) from the
FMU's start values, changed by ``--start``, with inputs from a table (``--input``: a CSV file
of :mod:`gtmodel._tables`' format, column ``t`` [s] and one column per input, each row held
until the next). Docs: ``docs/fmu.md``. Like :mod:`gtmodel.cli`, it imports NumPy and gtmodel's layers inside the
commands (``gtmodel --help`` builds these parsers and imports neither).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from gtmodel.errors import GtModelError

__all__ = ["add_fmu_parsers", "export_fmu_command", "import_fmu_command"]

#: Most rows of an ``--input`` table.
MAX_INPUT_ROWS = 1_000_000


def add_fmu_parsers(sub: Any) -> None:
    """Add ``export-fmu`` and ``import-fmu`` to the ``gtmodel`` parser.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``gtmodel`` parser's sub-commands.
    """
    fx = sub.add_parser("export-fmu", help="export a model as an FMU (FMI 2.0 / 3.0, model exchange and co-simulation), sources and a binary")
    what = fx.add_mutually_exclusive_group(required=True)
    what.add_argument("--model", default=None, metavar="FILE:CLASS", help="a user model, e.g. models/cart_pendulum.py:CartPendulum")
    what.add_argument("--robot", default=None, help="a robot's rigid-body dynamics with friction (cart states q, q_dot; input tau): L1, D1, ... or a parameter TOML")
    what.add_argument("--modelica", default=None, metavar="FILE.mo[:CLASS]", help="a Modelica model (through pymoca, docs/fmu.md)")
    what.add_argument("--controller", default=None, metavar="FILE", help="a controller file's Kalman step as a discrete-time co-simulation FMU (FMI 2.0, its sample period)")
    fx.add_argument("--out", type=Path, required=True, help="the .fmu file to write")
    fx.add_argument("--fmi-version", default="2.0", choices=("2.0", "3.0"), help="FMI version (default 2.0)")
    fx.add_argument("--interface", default="both", choices=("me", "cs", "both"),
                    help="model exchange, co-simulation or both (default both; FMI 3.0: me or both, its co-simulation is built on model exchange)")
    fx.add_argument("--step", type=float, default=1e-3, help="fixed step [s] of the co-simulation's embedded RK4 (default 1e-3)")
    fx.add_argument("--sources-only", action="store_true", help="pack the C sources without building a binary")
    fx.add_argument("--debug", action="store_true", help="show tracebacks of internal errors")

    fi = sub.add_parser("import-fmu", help="load an FMU (FMI 2.0/3.0 model exchange) as gtmodel does, list it, simulate it")
    fi.add_argument("fmu", type=Path, help="the .fmu file")
    fi.add_argument("--stop-time", type=float, default=None,
                    help="simulate from 0 to this time [s] with CVODES (from the start values and --start; inputs from --input, else at their start)")
    fi.add_argument("--points", type=int, default=101, help="output points of the simulation (default 101; the --input table's times are added)")
    fi.add_argument("--start", action="append", default=[], metavar="NAME=VALUE",
                    help="a start value of a state, a parameter's value or a constant input, e.g. --start theta=0.1; repeatable")
    fi.add_argument("--input", type=Path, default=None, metavar="CSV",
                    help="inputs over time: column t [s] and one column per input (named as the FMU's), each row held until the next")
    fi.add_argument("--out", type=Path, default=None, help="write the simulation to this CSV file (columns t, states, outputs)")
    fi.add_argument("--finite-differences", action="store_true", help="derivatives by finite differences even if the FMU provides directional derivatives")
    fi.add_argument("--max-members", type=int, default=None, metavar="N", help="raise the cap on the archive's members (default 10000, docs/fmu.md)")
    fi.add_argument("--max-member-mb", type=int, default=None, metavar="MB", help="raise the cap on one member's unpacked size (default 256 MiB)")
    fi.add_argument("--max-total-mb", type=int, default=None, metavar="MB", help="raise the cap on the archive's unpacked size (default 1024 MiB)")
    fi.add_argument("--max-description-mb", type=int, default=None, metavar="MB", help="raise the cap on modelDescription.xml (default 8 MiB)")
    fi.add_argument("--debug", action="store_true", help="show tracebacks of internal errors")


def export_fmu_command(args: argparse.Namespace) -> int:
    """Run ``gtmodel export-fmu``.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments.

    Returns
    -------
    int
        0 when the FMU was written.

    Raises
    ------
    GtModelError
        Bad input (``--out`` not ``.fmu``, a missing model file, ``--interface cs`` with FMI 3.0, ...).
    """
    if args.out.suffix != ".fmu":  # the checks that need no model first (fast, no CasADi)
        raise GtModelError(f"--out {args.out}: the file name must end in .fmu")
    if args.fmi_version == "3.0" and args.interface == "cs" and args.controller is None:
        raise GtModelError("--interface cs: an FMI 3.0 FMU of gtmodel always carries model exchange too (its co-simulation is built on "
                           "CasADi's model-exchange wrapper): give --interface both, or --fmi-version 2.0 for co-simulation only")
    source = args.model.rpartition(":")[0] if args.model else args.modelica or args.controller
    if source is not None:
        source = source if source.endswith((".py", ".mo")) or ":" not in source else source.rpartition(":")[0]
        if not Path(source).is_file():
            raise GtModelError(f"{source}: no such model file")
    if args.controller is not None:
        return _export_step_fmu(args)
    from gtmodel.exchange import export_fmu

    if args.model is not None:
        from gtmodel.problems.user_model import load_user_model, split_model_reference

        model = load_user_model(*split_model_reference(args.model))
    elif args.modelica is not None:
        from gtmodel.exchange.modelica import load_modelica

        file, sep, cls = args.modelica.rpartition(":")
        if not sep or not file.endswith(".mo"):
            file, cls = args.modelica, ""
        model = load_modelica(file, cls or None)
    else:
        from gtmodel.robots.model import gantry_tau_model

        model = gantry_tau_model(args.robot, states="cart")
    fmu = export_fmu(model, args.out, version=args.fmi_version, interface=args.interface, step=args.step, binary=not args.sources_only)
    asked = {"me": ("ModelExchange",), "cs": ("CoSimulation",), "both": ("ModelExchange", "CoSimulation")}[args.interface]
    if tuple(fmu.interfaces) != asked:  # never say one thing and write another
        raise GtModelError(f"--interface {args.interface}: the exporter wrote {' + '.join(fmu.interfaces)} into {fmu.path}")
    em = fmu.model
    print(f"wrote {fmu.path} (FMI {fmu.version} {' + '.join(fmu.interfaces)}, binary {fmu.platform or 'none: sources only'})")
    print(f"model {em.name}: {em.nx} states, {len(em.u_names)} inputs, {len(em.p_names)} parameters, {em.ny} outputs"
          + (f", {em.algebraic} algebraic variables solved inside" if em.algebraic else ""))
    if fmu.step is not None:
        print(f"co-simulation: fixed-step RK4, step <= {fmu.step:g} s")
    return 0


def _export_step_fmu(args: argparse.Namespace) -> int:
    from gtmodel.codegen import load_controller
    from gtmodel.exchange.fmu_step import export_step_fmu

    controller = load_controller(args.controller)
    if controller.kalman_step is None:
        raise GtModelError(f"{args.controller}: the controller has no kalman_step to export (the filters' steps carry a covariance matrix)")
    if args.fmi_version != "2.0" or args.interface == "me":
        raise GtModelError("--controller: a discrete-time step is exported as FMI 2.0 co-simulation only")
    fmu = export_step_fmu(controller.kalman_step, args.out, dt=controller.dt, binary=not args.sources_only)
    print(f"wrote {fmu.path} (FMI 2.0 CoSimulation, discrete step every {fmu.dt:g} s, binary {fmu.platform or 'none: sources only'})")
    print(f"states {', '.join(fmu.x_names)}; inputs {', '.join(fmu.u_names)}; outputs {', '.join(fmu.y_names)}")
    return 0


def start_values(em: Any, given: list[str]) -> tuple[dict[str, float], dict[str, float], dict[str, float]]:
    """The ``--start NAME=VALUE`` options split into states, parameters and inputs.

    Parameters
    ----------
    em : gtmodel.exchange.ExplicitODE
        The imported model.
    given : list of str
        The options' values.

    Returns
    -------
    tuple of dict
        ``(x0, p, u)``: name -> value.

    Raises
    ------
    GtModelError
        Not ``NAME=VALUE``, a value that is not a finite number, or a name that is no state,
        parameter or input of the model (the message lists them).
    """
    x0: dict[str, float] = {}
    p: dict[str, float] = {}
    u: dict[str, float] = {}
    for item in given:
        name, sep, text = (part.strip() for part in item.partition("="))
        if not sep or not name:
            raise GtModelError(f"--start {item}: expected NAME=VALUE, e.g. --start {(list(em.x_names) or ['x'])[0]}=0.1")
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not math.isfinite(value):
            raise GtModelError(f"--start {name}: expected a finite number, got {text!r}")
        into = x0 if name in em.x_names else p if name in em.p_names else u if name in em.u_names else None
        if into is None:
            known = "; ".join(f"{what} {', '.join(names)}" for what, names in
                              (("states", em.x_names), ("parameters", em.p_names), ("inputs", em.u_names)) if names)
            raise GtModelError(f"--start {name}: model {em.name!r} has no state, parameter or input of that name ({known or 'none'})")
        into[name] = value
    return x0, p, u


def input_table(path: Path, em: Any, t_grid: Any, constant: dict[str, float]) -> tuple[Any, Any]:
    """The inputs of an ``--input`` table on a grid: its times added, each row held until the next.

    Parameters
    ----------
    path : pathlib.Path
        The CSV file: column ``t`` [s] and one column per input (names as the FMU's).
    em : gtmodel.exchange.ExplicitODE
        The imported model.
    t_grid : numpy.ndarray
        The output times, from 0 to the stop time.
    constant : dict of str to float
        Inputs given by ``--start`` (the table's columns take precedence where both name one).

    Returns
    -------
    tuple of numpy.ndarray
        The grid with the table's times inside it added, and the inputs on it, shape
        ``(N, nu)`` (before the table's first time: its first row; inputs the table does
        not name: their start value or ``--start``).

    Raises
    ------
    GtModelError
        An unreadable table (file, line, column and what was expected), no ``t`` column, a
        column that is no input of the model, or times that do not increase.
    """
    import numpy as np

    from gtmodel._tables import column_names, label, read_table

    table = read_table(path, "input table", max_rows=MAX_INPUT_ROWS)
    columns = list(table.columns)
    if "t" not in columns:
        raise GtModelError(f"{path}: line {table.header_line}: expected a column t (time [s]) and one per input "
                           f"({', '.join(em.u_names) or 'the model has none'}); the header has {column_names(columns)}")
    for k, name in enumerate(columns):
        if name != "t" and name not in em.u_names:
            raise GtModelError(f"{path}: line {table.header_line}, {label(columns, k)}: not an input of model {em.name!r} "
                               f"(inputs: {', '.join(em.u_names) or 'none'})")
    t_col = table.data[:, columns.index("t")]
    falling = np.flatnonzero(np.diff(t_col) <= 0)
    if falling.size:
        raise GtModelError(f"{path}: line {int(table.lines[falling[0] + 1])}, column 't': expected times that increase row by row")
    grid = np.union1d(t_grid, t_col[(t_col > t_grid[0]) & (t_col < t_grid[-1])])
    u0 = {n: v for n, v in zip(em.u_names, np.asarray(em.u0, dtype=float).reshape(-1))} | constant
    u = np.tile([u0[n] for n in em.u_names], (grid.size, 1)).astype(float)
    row = np.clip(np.searchsorted(t_col, grid, side="right") - 1, 0, None)  # the last row at or before each time
    for k, name in enumerate(columns):
        if name != "t":
            u[:, list(em.u_names).index(name)] = table.data[row, k]
    return grid, u


def import_fmu_command(args: argparse.Namespace) -> int:
    """Run ``gtmodel import-fmu``.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments.

    Returns
    -------
    int
        0 when the FMU was read (and simulated, with ``--stop-time``).

    Raises
    ------
    GtModelError
        Bad input: the file, a cap, ``--start``, ``--input``, ``--stop-time`` or ``--points``.
    """
    if not args.fmu.is_file():  # before the heavy imports
        raise GtModelError(f"{args.fmu}: no such FMU file")
    if (args.start or args.input is not None) and args.stop_time is None:
        raise GtModelError("--start and --input set up a simulation: give --stop-time too")
    if args.input is not None and not args.input.is_file():
        raise GtModelError(f"--input {args.input}: no such file")
    from gtmodel.exchange import import_fmu, simulate_explicit
    from gtmodel.exchange.fmu_archive import ArchiveLimits

    mb = 1 << 20
    given = {"max_members": args.max_members, "max_member_bytes": args.max_member_mb and args.max_member_mb * mb,
             "max_total_bytes": args.max_total_mb and args.max_total_mb * mb,
             "max_description_bytes": args.max_description_mb and args.max_description_mb * mb}
    for option, value in (("--max-members", args.max_members), ("--max-member-mb", args.max_member_mb),
                          ("--max-total-mb", args.max_total_mb), ("--max-description-mb", args.max_description_mb)):
        if value is not None and value <= 0:
            raise GtModelError(f"{option}: expected a positive integer, got {value}")
    limits = ArchiveLimits(**{k: v for k, v in given.items() if v is not None})
    imported = import_fmu(args.fmu, derivatives="finite_differences" if args.finite_differences else "auto", limits=limits)
    em = imported.model
    print(f"{args.fmu}: FMI {imported.version} model exchange, model {em.name!r}"
          + (" (binary built here from its sources)" if imported.built_from_sources else ""))
    for what, names in (("states", em.x_names), ("inputs", em.u_names), ("parameters", em.p_names), ("outputs", em.y_names)):
        print(f"{what:<11} {', '.join(names) or '-'}")
    print(f"derivatives {imported.derivatives}")
    if args.stop_time is None:
        return 0
    if not (math.isfinite(args.stop_time) and args.stop_time > 0) or args.points < 2:
        raise GtModelError(f"--stop-time must be positive and --points at least 2, got {args.stop_time}, {args.points}")
    import numpy as np

    x0, p, u_const = start_values(em, args.start)
    grid = np.linspace(0.0, args.stop_time, args.points)
    u: Any = u_const or None
    if args.input is not None:
        grid, u = input_table(args.input, em, grid, u_const)
    sim = simulate_explicit(em, grid, x0=x0 or None, u=u, p=p or None)
    columns = {"t": sim.t, **sim.x, **sim.outputs}
    if args.out is not None:
        try:
            args.out.write_text(",".join(columns) + "\n" + "\n".join(
                ",".join(repr(float(columns[c][k])) for c in columns) for k in range(sim.t.size)) + "\n", encoding="utf-8")
        except OSError as exc:
            raise GtModelError(f"--out {args.out}: cannot write ({exc.strerror or exc})") from None
        print(f"wrote {args.out} ({sim.t.size} rows)")
    print("at t = " + f"{args.stop_time:g} s: " + ", ".join(f"{n} = {sim.x[n][-1]:.6g}" for n in em.x_names))
    return 0
