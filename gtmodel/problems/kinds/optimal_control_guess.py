"""The ``[initial_guess]`` table of an ``optimal_control`` problem file, declared on its Optimization.

Methods (``method``): ``"linear"`` between the boundary values, ``"start"`` (the model's
start values), ``"simulation"`` (the model simulated under ``inputs``,
:func:`gtmodel.modeling.ocp.guesses.guess_by_simulation`) and ``"file"`` (a CSV or an
earlier result folder, :func:`gtmodel.modeling.ocp.guesses.guess_from_table`); then
``values`` override single variables with numbers or expressions of time. Every error
names the file and the field.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._tables import read_table
from gtmodel.errors import GtModelError, ModelError
from gtmodel.modeling import Optimization, parse_expression
from gtmodel.modeling.ocp.written import affine_guess
from gtmodel.modeling.ocp.guesses import guess_by_simulation, guess_from_table
from gtmodel.problems.base import ProblemFile
from gtmodel.problems.kinds.schemas.optimal_control import InitialGuessSection

__all__ = ["declare_initial_guess", "time_function"]

#: The table a result folder holds (``trajectories.csv``; ``trajectory.csv`` of the robot kinds).
RESULT_TABLES = ("trajectories.csv", "trajectory.csv")


def time_function(file: ProblemFile, field: str, value: float | str, opt: Optimization, table: dict[str, Any]) -> Any:
    """A number, or ``f(t) -> float`` for an expression of ``time``, ``final_time`` (its guess) and parameters.

    Parameters
    ----------
    file : ProblemFile
        The problem file (messages).
    field : str
        Dotted field name.
    value : float or str
        The number or expression.
    opt : Optimization
        The problem (parameter values, final-time guess).
    table : dict
        The name table of the expressions.

    Returns
    -------
    float or callable

    Raises
    ------
    ProblemError
        An invalid expression, or one of other variables than time and parameters.
    """
    if not isinstance(value, str):
        return float(value)
    e = parse_expression(value, table, str(file.path), field)
    dae = opt.flat()
    e = ca.substitute(e, ca.vertcat(opt.final_time, dae.p), ca.vertcat(opt.final_time_guess, dae.parameter_vector(opt.parameters)))
    if any(not ca.is_equal(s, opt.model.time) for s in ca.symvar(e)):
        raise file.fail(field, "an expression of time, final_time and parameters", value)
    f = ca.Function("guess", [opt.model.time], [e])
    return lambda t: float(f(t))


def _table_path(file: ProblemFile, section: InitialGuessSection) -> Path:
    if section.file is None:
        raise file.fail("initial_guess.file", 'a CSV file or result folder with method = "file"')
    ref = Path(section.file)
    path = ref if ref.is_absolute() else (file.path.parent / ref).resolve()
    if path.is_dir():
        for name in RESULT_TABLES:
            if (path / name).is_file():
                return path / name
        raise file.fail("initial_guess.file", f"a result folder holding {' or '.join(RESULT_TABLES)}", section.file)
    if not path.is_file():
        raise file.fail("initial_guess.file", f"an existing CSV file or result folder (relative to {file.path.parent})", section.file)
    return path


def declare_initial_guess(
    file: ProblemFile,
    section: InitialGuessSection,
    opt: Optimization,
    boundary: dict[str, dict[str, float]],
    variables: dict[str, tuple[str, ca.SX]],
    vkeys: dict[str, str],
    table: dict[str, Any],
    final_time_guessed: bool,
) -> None:
    """Declare the guesses of ``[initial_guess]`` on ``opt``.

    Parameters
    ----------
    file : ProblemFile
        The problem file.
    section : InitialGuessSection
        The validated table.
    opt : Optimization
        The problem.
    boundary : dict
        ``{"start": {...}, "final": {...}}`` boundary values by declared name.
    variables : dict
        Scalar states, inputs and algebraics: name -> (kind, symbol).
    vkeys : dict
        Key or alias -> declared name.
    table : dict
        Name table of the expressions.
    final_time_guessed : bool
        Whether the file gives the final time's guess (else a table's last time is used).

    Raises
    ------
    ProblemError
        Naming the file and the field (``initial_guess.file``, ``initial_guess.values.<name>``, ...).
    """
    if section.method != "file" and section.file is not None:
        raise file.fail("initial_guess.file", 'method = "file" with a file (or no file)')
    if section.method != "simulation" and section.inputs:
        raise file.fail("initial_guess.inputs", 'method = "simulation" with inputs (or no inputs)')
    if section.method == "linear":
        _linear_guess(opt, boundary, variables)
    elif section.method == "file":
        path = _table_path(file, section)
        try:
            data = read_table(path, "initial guess", text_columns=("point",))
            outputs = list(opt.model.outputs)
            ignore = outputs + [k for k, n in _alias_map(outputs).items()]
            guess_from_table(opt, data.columns, data.data, section.time_column, aliases=vkeys, ignore=ignore)
        except GtModelError as exc:
            raise file.wrap("initial_guess.file", exc) from None
        t = data.data[:, list(data.columns).index(section.time_column)]
        if opt.free_final_time and not final_time_guessed:
            opt.set_initial_guess(opt.final_time, float(t[-1]))
    elif section.method == "simulation":
        inputs = {}
        ins = opt.model.variables("input")
        for key, value in section.inputs.items():
            name = vkeys.get(key, key)
            if name not in ins:
                raise file.fail(f"initial_guess.inputs.{key}", f"an input of the model ({', '.join(ins) or 'none'})", key)
            inputs[name] = time_function(file, f"initial_guess.inputs.{key}", value, opt, table)
        try:
            guess_by_simulation(opt, inputs)
        except GtModelError as exc:
            raise file.wrap("initial_guess.method", exc) from None
    for key, value in section.values.items():
        if key not in vkeys:
            raise file.fail(f"initial_guess.values.{key}", f"one of the model's variables ({', '.join(sorted(variables))})", key)
        f = time_function(file, f"initial_guess.values.{key}", value, opt, table)
        try:
            opt.set_initial_guess(variables[vkeys[key]][1], f if callable(f) else np.array([f]))
        except GtModelError as exc:  # an output that is no affine function of one variable
            raise file.wrap(f"initial_guess.values.{key}", exc) from None


def _alias_map(names: Any) -> dict[str, str]:
    return {re.sub(r"[^A-Za-z0-9_]", "_", n): n for n in names}


def _linear_guess(opt: Optimization, boundary: dict[str, dict[str, float]], variables: dict[str, tuple[str, ca.SX]]) -> None:
    """Initial guesses linear in time between the start and final boundary values (by declared name)."""
    t0, tf = opt.start_time, opt.final_time_guess
    start, final = boundary["start"], boundary["final"]
    for key, (kind, sym) in variables.items():
        if kind == "output" and not _guessable(opt, sym):
            continue  # an output that is no affine function of one variable: nothing to guess through
        if key in start and key in final:
            opt.set_initial_guess(sym, ([t0, tf], [start[key], final[key]]))
        elif key in start or key in final:
            opt.set_initial_guess(sym, start.get(key, final.get(key)))


def _guessable(opt: Optimization, expr: ca.SX) -> bool:
    """Whether a guess of ``expr`` is a guess of one variable (``a v + b``, :func:`~gtmodel.modeling.ocp.written.affine_guess`)."""
    try:
        affine_guess(expr, 0.0, opt.model, opt.parameters)
    except ModelError:
        return False
    return True
