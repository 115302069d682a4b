"""Initial guesses of an :class:`~gtmodel.modeling.Optimization` from a table or a simulation.

:meth:`Optimization.set_initial_guess` takes a constant, a trajectory ``(t, values)`` or
a function of time per variable. This module fills them in bulk:

* :func:`guess_from_table`: the columns of a trajectory table (a CSV read with
  :func:`gtmodel._tables.read_table`, e.g. the ``trajectories.csv`` of an earlier result)
  that name the model's states, inputs and algebraic variables, linearly interpolated
  onto the mesh (held constant beyond the table's ends); its times may be rescaled to the
  problem's horizon;
* :func:`guess_by_simulation`: the model simulated from its initial state under given
  inputs (JModelica's default initial guess), every state, algebraic variable and input
  sampled on a fine grid.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling.dae import _vector_value
from gtmodel.modeling.ocp.optimization import Optimization

__all__ = ["guess_from_table", "guess_by_simulation", "guess_values", "ResultGuess"]

_log = logging.getLogger("gtmodel")


def _whole_variables(opt: Optimization) -> dict[str, int]:
    """State, input and algebraic variable names -> their sizes."""
    return {n: int(s.numel()) for k in ("state", "input", "algebraic") for n, s in opt.model.variables(k).items()}


def guess_from_table(
    opt: Optimization,
    columns: Sequence[str],
    data: Any,
    time_column: str = "t",
    rescale: bool = False,
    aliases: Mapping[str, str] | None = None,
    ignore: Sequence[str] = (),
) -> list[str]:
    """Set the initial guesses from the columns of a trajectory table.

    Parameters
    ----------
    opt : Optimization
        The problem whose guesses are set.
    columns : sequence of str
        Column names of ``data``: the time column and scalar variable names (or aliases).
    data : array_like
        Values, shape ``(K, len(columns))``, rows in increasing time [s].
    time_column : str, optional
        Name of the time column [s]; default ``"t"``.
    rescale : bool, optional
        Map the table's time span linearly onto ``[start_time, final_time guess]``
        (a guess of another horizon, e.g. an earlier free-final-time result); default
        False (absolute times).
    aliases : mapping of str to str, optional
        Column name -> declared variable name (e.g. ``mass_s -> mass.s``).
    ignore : sequence of str, optional
        Columns that are known but not guessed (e.g. the model's outputs).

    Returns
    -------
    list of str
        The variables whose guesses were set.

    Raises
    ------
    InputError
        If there is no time column, the times are not strictly increasing, or a column
        names no variable of the model (the table of another problem).
    """
    data = np.asarray(data, dtype=float)
    cols = list(columns)
    if time_column not in cols:
        raise InputError(f"no time column {time_column!r} (columns: {', '.join(cols)})")
    if data.ndim != 2 or data.shape[1] != len(cols) or data.shape[0] < 1:
        raise InputError(f"expected a table of shape (K, {len(cols)}), got {data.shape}")
    t = data[:, cols.index(time_column)]
    if np.any(np.diff(t) <= 0):
        raise InputError(f"the times of column {time_column!r} must increase strictly")
    sizes = _whole_variables(opt)
    names = {n: n for n in sizes} | dict(aliases or {})
    unknown = [c for c in cols if c != time_column and c not in ignore and names.get(c, c) not in sizes]
    if unknown:
        raise InputError(
            f"columns {', '.join(unknown)} name no state, input or algebraic variable of model "
            f"{opt.model.name!r} (a table of another problem?); its variables: {', '.join(sorted(sizes))}"
        )
    if rescale and t.size > 1:
        t0, tf = opt.start_time, opt.final_time_guess
        t = t0 + (t - t[0]) / (t[-1] - t[0]) * (tf - t0)
    done = []
    for c in cols:
        name = names.get(c, c)
        if c == time_column or name not in sizes:
            continue
        if sizes[name] != 1:
            raise InputError(f"column {c!r}: {name!r} has {sizes[name]} elements; guesses from tables are for scalars")
        sym = opt.model.variables(_kind(opt, name))[name]
        values = data[:, cols.index(c)]
        opt.set_initial_guess(sym, (t, values) if t.size > 1 else float(values[0]))
        done.append(name)
    _log.debug("initial guess of %s from a table: %s", opt.model.name, done)
    return done


def _kind(opt: Optimization, name: str) -> str:
    for k in ("state", "input", "algebraic"):
        if name in opt.model.variables(k):
            return k
    raise ModelError(f"{name!r} is no state, input or algebraic variable")  # pragma: no cover - checked by callers


def guess_by_simulation(
    opt: Optimization,
    inputs: Mapping[str, float | Callable[[float], float]] | None = None,
    x0: Mapping[str, float] | None = None,
    samples: int = 201,
    parameters: Mapping[str, Any] | None = None,
) -> Any:
    """Set the initial guesses from a simulation of the model under given inputs.

    The model is integrated (:meth:`~gtmodel.modeling.Model.simulate`, IDAS) over
    ``[start_time, final_time guess]`` from ``x0`` (default: the fixed start values of the
    problem's start point constraints ``x(start_time) == c`` on whole scalar states, then the
    declared start values), with each input a constant or a function of time (default
    its start value), held piecewise constant on a grid of ``samples`` points. The
    states, algebraic variables and inputs are the guesses on that grid.

    Parameters
    ----------
    opt : Optimization
        The problem whose guesses are set.
    inputs : mapping of str to float or callable, optional
        Input name -> constant or ``f(t) -> float`` [the input's unit; t in s].
    x0 : mapping of str to float, optional
        Initial states by name (override the start point constraints).
    samples : int, optional
        Points of the simulation grid; default 201.
    parameters : mapping of str to float, optional
        Parameter values (default :meth:`Optimization.set_parameter` values, then the model's).

    Returns
    -------
    SimulationResult
        The simulation.

    Raises
    ------
    InputError
        If an input name is not an input of the model, or ``samples < 2``.
    ConvergenceError
        If the simulation fails.
    """
    model = opt.model
    ins = model.variables("input")
    for name in inputs or {}:
        if name not in ins:
            raise InputError(f"{name!r} is not an input of model {model.name!r} (inputs: {', '.join(ins) or 'none'})")
    if int(samples) < 2:
        raise InputError(f"samples must be at least 2, got {samples}")
    start = {}
    states = model.variables("state")
    for c in opt.point_constraints:
        if c.at == "start" and c.expr.numel() == 1 and c.lb[0] == c.ub[0] and c.expr.is_symbolic():
            for n, s in states.items():
                if s.numel() == 1 and ca.is_equal(c.expr, s, 1):
                    start[n] = float(c.lb[0])
    start.update(x0 or {})
    t = np.linspace(opt.start_time, opt.final_time_guess, int(samples))
    dae = model.flatten()
    u_default = {n: model._vars[n].start.copy() for n in dae.u_vars}

    def u_of(tt: float) -> np.ndarray:
        out = np.zeros(dae.nu)
        for n, sl in dae.u_vars.items():
            spec = (inputs or {}).get(n)
            out[sl] = u_default[n] if spec is None else (spec(tt) if callable(spec) else spec)
        return out

    params = {**{k: v for k, v in opt.parameters.items()}, **dict(parameters or {})}
    sim = model.simulate(t, x0=start or None, u=u_of if dae.nu else None, p=params or None)
    K = sim.t.size
    for group in (sim.x, sim.z, sim.u):
        for name, values in group.items():
            if name in _whole_variables(opt):
                opt.set_initial_guess(model.variables(_kind(opt, name))[name], (sim.t, np.asarray(values).reshape(K, -1)))
    return sim


class ResultGuess:
    """The guesses of every state, input and algebraic variable from one result, sampled once per point set.

    A coarse solution interpolated onto a fine mesh (:mod:`gtmodel.modeling.ocp.coarse_start`):
    its collocation polynomials are evaluated at all the fine mesh's points in one call
    (:meth:`~gtmodel.modeling.ocp.result.CollocationData.evaluate`), not once per variable
    and point; the time axis is stretched from ``[start_time, tf_guess]`` onto the result's
    horizon (a free final time).

    Parameters
    ----------
    result : OptimizationResult
        A result holding collocation data (``result.collocation``, ``result.dae``).
    start_time : float
        The problem's start time, s.
    tf_guess : float
        The final time the guess is built for, s.
    """

    def __init__(self, result: Any, start_time: float, tf_guess: float) -> None:
        self.result, self.start_time, self.tf_guess = result, float(start_time), float(tf_guess)
        self._cache: tuple[bytes, dict[str, np.ndarray]] | None = None

    def names(self) -> list[str]:
        """The variables this result guesses.

        Returns
        -------
        list of str
            Its states, inputs and algebraic variables.
        """
        dae = self.result.dae
        return [*dae.x_vars, *dae.u_vars, *dae.z_vars]

    def values(self, t: np.ndarray) -> dict[str, np.ndarray]:
        """Every variable at times ``t``, from one evaluation of the polynomials (kept for the same ``t``).

        Parameters
        ----------
        t : numpy.ndarray
            Times on the new horizon, s, shape ``(K,)``.

        Returns
        -------
        dict of str to numpy.ndarray
            Name -> values, shape ``(K, size)``.
        """
        t = np.asarray(t, dtype=float).reshape(-1)
        key = t.tobytes()
        if self._cache is None or self._cache[0] != key:
            res, t0 = self.result, self.start_time
            s = t0 + (t - t0) / (self.tf_guess - t0) * (res.final_time - t0)
            xs, us, zs = res.collocation.evaluate(np.clip(s, res.collocation.t0, res.collocation.tf))
            dae = res.dae
            out = {name: xs[:, sl] for name, sl in dae.x_vars.items()}
            out.update({name: us[:, sl] for name, sl in dae.u_vars.items()})
            out.update({name: zs[:, sl] for name, sl in dae.z_vars.items()})
            self._cache = (key, out)
        return self._cache[1]


def guess_values(spec: Any, size: int, name: str, default: np.ndarray, t: np.ndarray) -> np.ndarray:
    """A guess specification evaluated at all times of a mesh at once.

    Parameters
    ----------
    spec : None, float, array_like, (t, values) tuple, callable or ResultGuess
        As :meth:`Optimization.set_initial_guess` (a callable ``f(t) -> (size,)`` is called per
        time: a user's function of a scalar time); a :class:`ResultGuess` is evaluated once
        for all times and variables.
    size : int
        Scalar elements of the variable.
    name : str
        The variable's name (for messages).
    default : numpy.ndarray
        The value without a guess, shape ``(size,)``.
    t : numpy.ndarray
        Times, s, shape ``(K,)``.

    Returns
    -------
    numpy.ndarray
        Shape ``(K, size)``.

    Raises
    ------
    InputError
        If a tuple guess has the wrong number of columns, or a value the wrong size.
    """
    t = np.asarray(t, dtype=float).reshape(-1)
    if isinstance(spec, ResultGuess):
        return np.asarray(spec.values(t)[name], dtype=float).reshape(t.size, size)
    if spec is None:
        return np.broadcast_to(np.asarray(default, dtype=float).reshape(1, size), (t.size, size))
    if isinstance(spec, tuple) and len(spec) == 2:
        tg = np.asarray(spec[0], dtype=float).reshape(-1)
        vg = np.asarray(spec[1], dtype=float).reshape(tg.size, -1)
        if vg.shape[1] != size:
            raise InputError(f"initial guess of {name!r}: expected {size} columns, got {vg.shape[1]}")
        return np.column_stack([np.interp(t, tg, vg[:, i]) for i in range(size)]) if size else np.zeros((t.size, 0))
    if callable(spec):
        return np.array([_vector_value(spec(ti), size, f"initial guess of {name!r}") for ti in t]).reshape(t.size, size)
    const = _vector_value(spec, size, f"initial guess of {name!r}")
    return np.broadcast_to(const.reshape(1, size), (t.size, size))


def _guess_fn(spec: Any, size: int, name: str, default: np.ndarray) -> Any:
    """Turn a guess specification into ``f(t) -> (size,)``."""
    if spec is None:
        return lambda t: default
    if callable(spec):
        return lambda t: _vector_value(spec(t), size, f"initial guess of {name!r}")
    if isinstance(spec, tuple) and len(spec) == 2:
        tg = np.asarray(spec[0], dtype=float).reshape(-1)
        vg = np.asarray(spec[1], dtype=float).reshape(tg.size, -1)
        if vg.shape[1] != size:
            raise InputError(f"initial guess of {name!r}: expected {size} columns, got {vg.shape[1]}")
        return lambda t: np.array([np.interp(t, tg, vg[:, i]) for i in range(size)])
    const = _vector_value(spec, size, f"initial guess of {name!r}")
    return lambda t: const
