"""Simulation of a model: integrate its flat DAE on a time grid with SUNDIALS (IDAS or CVODES).

Inputs are piecewise constant on the grid. One ``casadi.integrator`` run covers the whole
grid, except where the input jumps and the algebraic equations depend on the input
directly (a ``translational.Force`` source: the flange force is the input). There the
algebraic variables jump too, and IDAS, as CasADi calls it, does not make them consistent
again: it stops with ``IDA_ERR_FAIL``. The simulation then restarts at each change of the
input (:func:`input_segments`): one run per segment of constant input, from the last state
(``x0``) and the last algebraic values (the ``z0`` guess), where IDAS computes consistent
values (``IDACalcIC``); at a change the grid point reports those, the right limit, as it
reports the new input. The DAE is written in scaled time ``t = t0 + tau h``,
``tau in [0, 1]``, with the segment's start ``t0`` and length ``h`` as extra parameters, so
one integrator serves every segment of one output layout (a uniform grid builds one per
segment length, not one per segment) and a DAE that depends on ``t`` is shifted correctly.
Measured (two masses, a spring and a ``Force``, 18 algebraic variables, a 1000-sample grid
with the input changing at every sample): building an integrator per segment costs 1.2 ms
per segment, a call of the shared time-scaled one 0.3 ms; the whole simulation takes 0.2 s.
An ODE model (or a DAE whose algebraic equations do not see the input) keeps the single run
and gives the same results as before; only if that run fails (CVODES stepping over a fast
square wave stops with ``CV_ERR_FAILURE``) is it repeated with the restarts.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._docstrings import fill_doc
from gtmodel.errors import ConvergenceError, InputError
from gtmodel.modeling.dae import SimulationResult, _eval_outputs, _unpack, _vector_value, casadi_name

__all__ = [
    "simulate_model",
    "simulation_inputs",
    "input_intervals",
    "integrator_options",
    "time_scaled",
    "SIMULATE_DOCS",
    "INTEGRATOR_OPTIONS",
]

#: The arguments, returns and errors of a simulation, shared by :func:`simulate_model` and
#: :meth:`gtmodel.modeling.Model.simulate` (inserted by :func:`~gtmodel._docstrings.fill_doc`).
SIMULATE_DOCS = {
    "simulate_args": """
        t_grid : array_like
            Strictly increasing output times, shape ``(N,)`` with ``N >= 2``, s.
            Integration starts at ``t_grid[0]``.
        x0 : array_like or mapping, optional
            Initial state, shape ``(nx,)``, or a mapping from state names to values;
            default the declared start values. Every entry is an initial condition
            (kept through index reduction; contradictory ones are refused, naming them).
        u : float, array_like or callable, optional
            Inputs, held piecewise constant on the grid: a constant ``(nu,)``; an array
            ``(N-1, nu)`` or ``(N, nu)`` whose row ``k`` applies on ``[t_k, t_{k+1})``
            (a 1-D array is accepted when ``nu == 1``); or a callable ``u(t) -> (nu,)``
            sampled at the start of each interval (zero-order hold). Default: the
            declared input start values. Where the input changes and algebraic
            variables depend on it, the integration restarts (module
            :mod:`gtmodel.modeling.simulation.integration`) and the grid point reports the
            values consistent with the new input.
        p : mapping of str to float or array_like, optional
            Parameter overrides by name.
        integrator : {"idas", "cvodes"}, optional
            SUNDIALS integrator; CVODES only for models without algebraic variables.
        rtol, atol : float, optional
            Relative and absolute tolerances.
        z0 : array_like, optional
            Guess for the algebraic variables at ``t_grid[0]``, shape ``(nz,)``;
            default the declared start values. IDAS computes consistent values.
        options : mapping, optional
            Integrator options (:data:`~gtmodel.modeling.simulation.integration.INTEGRATOR_OPTIONS`):
            ``rtol``, ``atol`` (override the arguments), ``max_num_steps`` (steps
            allowed between two output times; SUNDIALS' default 500: raise it for tight
            tolerances on long output intervals, the cure for ``IDA_TOO_MUCH_WORK`` /
            ``CV_TOO_MUCH_WORK``), ``max_step_size``, ``initial_step`` (s),
            ``min_step_size`` (s, CVODES only), ``max_order`` (1-5, the BDF order
            limit) and ``suppress_algebraic`` (IDAS only: leave the algebraic variables
            out of the local error test, as Modelica tools do for index-1 DAEs; at
            tolerances near 1e-10 their round-off otherwise makes the steps collapse);
            passed to CasADi's SUNDIALS integrators. An unknown name or a bad value is
            refused by name (InputError).

    """,
    "simulate_returns": """
        Returns
        -------
        SimulationResult
            Trajectories on ``t_grid``.

        Raises
        ------
        InputError
            On malformed arguments.
        ModelError
            If the model cannot be flattened.
        ConvergenceError
            If the integrator fails or returns non-finite values.
    """,
}


_log = logging.getLogger("gtmodel")

#: The integrator options of a simulation: name -> (CasADi/SUNDIALS option, kind, the
#: integrators that take it). ``kind``: ``"tol"`` positive float, ``"time"`` positive
#: float in seconds (rescaled where the DAE runs in scaled time), ``"steps"`` positive int,
#: ``"order"`` int 1..5, ``"flag"`` bool.
INTEGRATOR_OPTIONS: dict[str, tuple[str, str, tuple[str, ...]]] = {
    "rtol": ("reltol", "tol", ("idas", "cvodes")),
    "atol": ("abstol", "tol", ("idas", "cvodes")),
    "max_num_steps": ("max_num_steps", "steps", ("idas", "cvodes")),
    "max_step_size": ("max_step_size", "time", ("idas", "cvodes")),
    "initial_step": ("step0", "time", ("idas", "cvodes")),
    "min_step_size": ("min_step_size", "time", ("cvodes",)),
    "max_order": ("max_multistep_order", "order", ("idas", "cvodes")),
    "suppress_algebraic": ("suppress_algebraic", "flag", ("idas",)),
}
#: The CasADi options that are times (divided by the segment length in scaled time).
TIME_OPTIONS = tuple(cas for cas, kind, _ in INTEGRATOR_OPTIONS.values() if kind == "time")


def integrator_options(options: Mapping[str, Any] | None, rtol: float, atol: float, integrator: str) -> dict[str, Any]:
    """The CasADi options of a SUNDIALS integrator from a simulation's ``rtol``, ``atol`` and ``options``.

    Parameters
    ----------
    options : mapping or None
        Option name -> value, names of :data:`INTEGRATOR_OPTIONS` (``rtol`` and ``atol``
        here override the arguments).
    rtol, atol : float
        Relative and absolute tolerances.
    integrator : {"idas", "cvodes"}
        The SUNDIALS integrator.

    Returns
    -------
    dict
        Options for ``casadi.integrator`` (``reltol``, ``abstol``, ... and warnings off).

    Raises
    ------
    InputError
        If ``integrator`` is unknown; naming the option: an unknown name (listing the allowed ones), one the integrator
        does not take, or a value that is not a positive finite number (a positive integer
        for ``max_num_steps``, 1 to 5 for ``max_order``).
    """
    if integrator not in ("idas", "cvodes"):
        raise InputError(f"integrator must be 'idas' or 'cvodes', got {integrator!r}")
    given = {"rtol": rtol, "atol": atol}
    if options is not None:
        if not isinstance(options, Mapping):
            raise InputError(f"options: expected a mapping of integrator option names to values, got {options!r}")
        unknown = sorted(str(k) for k in options if k not in INTEGRATOR_OPTIONS)
        if unknown:
            raise InputError(f"options: unknown integrator option(s) {unknown}; allowed: {sorted(INTEGRATOR_OPTIONS)}")
        given.update(options)
    out: dict[str, Any] = {"show_eval_warnings": False, "disable_internal_warnings": True}
    for name, value in given.items():
        cas, kind, plugins = INTEGRATOR_OPTIONS[name]
        if integrator not in plugins:
            raise InputError(f"options: {name!r} is an option of {' and '.join(plugins)} only, not of {integrator!r}")
        what = f"options[{name!r}]" if options is not None and name in options else name
        if kind == "flag":
            if not isinstance(value, (bool, np.bool_)):
                raise InputError(f"{what}: expected True or False, got {value!r}")
            out[cas] = bool(value)
        elif kind in ("steps", "order"):
            ok = isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))
            lo, hi = (1, 5) if kind == "order" else (1, np.inf)
            if not ok or not lo <= value <= hi:
                want = "an integer from 1 to 5" if kind == "order" else "a positive integer"
                raise InputError(f"{what}: expected {want}, got {value!r}")
            out[cas] = int(value)
        else:
            ok = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))
            if not ok or not np.isfinite(value) or value <= 0:
                raise InputError(f"{what}: expected a positive finite number, got {value!r}")
            out[cas] = float(value)
    return out


def time_scaled(opts: Mapping[str, Any], h: float) -> dict[str, Any]:
    """Integrator options for a DAE in scaled time ``t = t0 + tau h``: the step sizes divided by ``h``.

    Parameters
    ----------
    opts : mapping
        From :func:`integrator_options`.
    h : float
        Segment length, s.

    Returns
    -------
    dict
        A copy with :data:`TIME_OPTIONS` in units of ``tau``.
    """
    return {k: (v / h if k in TIME_OPTIONS else v) for k, v in opts.items()}


@fill_doc(**SIMULATE_DOCS)
def simulate_model(
    model: Any,
    t_grid: Any,
    x0: Any = None,
    u: Any = None,
    p: Mapping[str, Any] | None = None,
    integrator: str = "idas",
    rtol: float = 1e-8,
    atol: float = 1e-10,
    z0: Any = None,
    options: Mapping[str, Any] | None = None,
) -> SimulationResult:
    """Integrate the model on a time grid.

    Parameters
    ----------
    model : Model
        The model (flattened here); :meth:`gtmodel.modeling.Model.simulate` calls this.
    {simulate_args}

    {simulate_returns}
    """
    dae = model.flatten()
    t, x0v, z0v, pv, u_int = simulation_inputs(model, dae, t_grid, x0, u, p, integrator, z0)
    opts = integrator_options(options, rtol, atol, integrator)
    changes = input_segments(u_int)
    starts = changes if dae.nz and ca.depends_on(dae.alg_expr, dae.u) else np.zeros(1, int)
    try:
        if starts.size == 1:  # one run over the whole grid
            try:
                xs, zs = _integrate_once(model.name, dae, integrator, opts, t, x0v, z0v, pv, u_int)
            except RuntimeError:
                if changes.size == 1:
                    raise
                # stepping over the input jumps failed (CVODES on a square wave): restart at each
                starts = changes
                _log.debug("model %s: one %s run failed; restarting at the %d input changes",
                           model.name, integrator, changes.size - 1)
        if starts.size > 1:  # algebraic variables that jump with the input: restart at each change
            xs, zs = _integrate_segments(model.name, dae, integrator, opts, t, starts, x0v, z0v, pv, u_int)
    except RuntimeError as exc:
        lines = [ln for ln in str(exc).splitlines() if "returned" in ln] or str(exc).splitlines()
        raise ConvergenceError(
            f"simulation of model {model.name!r} with {integrator} failed: "
            f"{lines[0].strip() if lines else exc}"
        ) from exc
    if not (np.all(np.isfinite(xs)) and np.all(np.isfinite(zs))):
        raise ConvergenceError(f"simulation of model {model.name!r} produced non-finite values")
    us = np.vstack([u_int, u_int[-1:]])
    outs = _eval_outputs(dae, t, xs, zs, us, pv)
    _log.debug("simulated model %s on %d points with %s in %d run(s)", model.name, t.size, integrator, starts.size)
    return SimulationResult(
        t=t,
        x=_unpack(dae.x_vars, xs),
        z=_unpack(dae.z_vars, zs),
        u=_unpack(dae.u_vars, us),
        outputs=outs,
        p={k: pv[s].copy() for k, s in dae.p_vars.items()},
    )


def input_segments(u_int: np.ndarray) -> np.ndarray:
    """Start indices of the runs of equal inputs, shape ``(S,)`` (``0`` first).

    Parameters
    ----------
    u_int : numpy.ndarray
        Inputs per grid interval, ``(N-1, nu)``, as from :func:`input_intervals`.

    Returns
    -------
    numpy.ndarray
        Interval indices ``k`` where ``u_int[k] != u_int[k-1]``, after ``0``; segment ``s``
        covers the grid points ``starts[s] .. starts[s+1]`` (the last ends at ``N-1``).
    """
    change = np.any(u_int[1:] != u_int[:-1], axis=1) if u_int.shape[1] else np.zeros(len(u_int) - 1, bool)
    return np.concatenate([[0], 1 + np.nonzero(change)[0]]).astype(int)


def _integrate_once(name: str, dae: Any, plugin: str, opts: dict, t: np.ndarray, x0: np.ndarray,
                    z0: np.ndarray, pv: np.ndarray, u_int: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One SUNDIALS run over the whole grid; states ``(N, nx)`` and algebraics ``(N, nz)``."""
    n = t.size
    # CasADi's integrator holds u[:, k] on (tout[k-1], tout[k]]; tout[0] = t0
    u_cas = np.vstack([u_int[:1], u_int]).T if dae.nu else np.zeros((0, n))
    ddict: dict[str, Any] = {"t": dae.t, "x": dae.x, "u": dae.u, "p": dae.p, "ode": dae.ode_expr}
    if dae.nz:
        ddict["z"] = dae.z
        ddict["alg"] = dae.alg_expr
    F = ca.integrator(f"{casadi_name(name)}_sim", plugin, ddict, float(t[0]), list(t), opts)
    res = F(x0=x0, z0=z0, p=pv, u=u_cas)
    return np.array(res["xf"]).reshape(dae.nx, n).T, np.array(res["zf"]).reshape(dae.nz, n).T


def _integrate_segments(name: str, dae: Any, plugin: str, opts: dict, t: np.ndarray, starts: np.ndarray,
                        x0: np.ndarray, z0: np.ndarray, pv: np.ndarray,
                        u_int: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One run per segment of constant input, restarted from the last state (module docstring)."""
    tau, t0, h = ca.SX.sym("tau"), ca.SX.sym("t0"), ca.SX.sym("h")
    tt = t0 + tau * h  # time-scaled DAE: one integrator serves every segment of one output layout
    ddict = {"t": tau, "x": dae.x, "u": dae.u, "p": ca.vertcat(dae.p, t0, h),
             "ode": h * ca.substitute(dae.ode_expr, dae.t, tt)}
    if dae.nz:
        ddict.update(z=dae.z, alg=ca.substitute(dae.alg_expr, dae.t, tt))
    cache: dict[tuple[float, ...], ca.Function] = {}
    n = t.size
    xs, zs = np.empty((n, dae.nx)), np.empty((n, dae.nz))
    ends = np.append(starts[1:], n - 1)
    for a, b in zip(starts, ends):
        h_s = float(t[b] - t[a])
        # from 0: a segment reports its consistent start values, the right limit at a change
        # (as the reported input u[a] and the outputs; the event simulation does the same)
        fracs = tuple(np.round(np.append((t[a:b] - t[a]) / h_s, 1.0), 13))
        key = fracs + ((h_s,) if any(k in opts for k in TIME_OPTIONS) else ())  # step sizes in units of h
        F = cache.get(key)
        if F is None:  # a uniform grid needs one per segment length
            if len(cache) >= 64:
                cache.pop(next(iter(cache)))
            F = cache[key] = ca.integrator(f"{casadi_name(name)}_segment", plugin, ddict, 0.0, list(fracs), time_scaled(opts, h_s))
        res = F(x0=xs[a] if a else x0, z0=zs[a] if a else z0, p=np.concatenate([pv, [t[a], h_s]]), u=u_int[a])
        xs[a:b + 1] = np.array(res["xf"]).reshape(dae.nx, len(fracs)).T
        zs[a:b + 1] = np.array(res["zf"]).reshape(dae.nz, len(fracs)).T
    return xs, zs


def input_intervals(u: Any, t: np.ndarray, nu: int, u_default: np.ndarray) -> np.ndarray:
    """Inputs held on the grid intervals, shape ``(N-1, nu)`` (the ``u`` forms of :func:`simulate_model`).

    Parameters
    ----------
    u : None, float, array_like or callable
        As the ``u`` argument of :func:`simulate_model`.
    t : numpy.ndarray
        The checked time grid, shape ``(N,)``, s.
    nu : int
        Number of scalar inputs.
    u_default : numpy.ndarray
        Input start values, shape ``(nu,)``.

    Returns
    -------
    numpy.ndarray
        Row ``k`` applies on ``[t_k, t_{k+1})``.

    Raises
    ------
    InputError
        If ``u`` has the wrong shape or non-finite values.
    """
    n = t.size
    if u is None:
        u_int = np.tile(u_default, (n - 1, 1))
    elif callable(u):
        u_int = np.array([_vector_value(u(tk), nu, f"u({tk})") for tk in t[:-1]])
    else:
        ua = np.asarray(u, dtype=float)
        if ua.size == nu and not (nu == 1 and ua.ndim == 1 and ua.size in (n - 1, n) and ua.size > 1):
            u_int = np.tile(ua.reshape(-1), (n - 1, 1))
        else:
            if ua.ndim == 1 and nu == 1:
                ua = ua.reshape(-1, 1)
            if ua.ndim != 2 or ua.shape[1] != nu or ua.shape[0] not in (n - 1, n):
                raise InputError(
                    f"u: expected a constant of {nu} values or an array of shape "
                    f"({n - 1}, {nu}) or ({n}, {nu}), got shape {np.shape(u)}"
                )
            u_int = ua[: n - 1]
    u_int = np.asarray(u_int, dtype=float).reshape(n - 1, nu)
    if not np.all(np.isfinite(u_int)):
        raise InputError("u contains non-finite values")
    return u_int


def simulation_inputs(
    model: Any, dae: Any, t_grid: Any, x0: Any, u: Any, p: Any, integrator: str, z0: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Check and convert the arguments of a simulation (shared with the event simulation).

    Parameters
    ----------
    model : Model
        The model, for its name and declared input start values.
    dae : FlatDAE
        Its flattened DAE.
    t_grid, x0, u, p, integrator, z0
        As for :func:`simulate_model`.

    Returns
    -------
    tuple of numpy.ndarray
        ``(t, x0, z0, p, u)``: the grid ``(N,)``, initial state ``(nx,)``, algebraic guess
        ``(nz,)``, parameter vector ``(npar,)`` and inputs per interval ``(N-1, nu)``.

    Raises
    ------
    InputError
        On malformed arguments.
    """
    t = np.asarray(t_grid, dtype=float).reshape(-1)
    if t.size < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise InputError("t_grid must be finite, strictly increasing, with at least 2 points")
    if integrator not in ("idas", "cvodes"):
        raise InputError(f"integrator must be 'idas' or 'cvodes', got {integrator!r}")
    if integrator == "cvodes" and dae.nz:
        raise InputError("integrator 'cvodes' cannot handle algebraic variables; use 'idas'")
    # initial state
    if x0 is None:
        x0v = dae.x_start.copy()
    elif isinstance(x0, Mapping):
        x0v = dae.x_start.copy()
        for name, val in x0.items():
            if name not in dae.x_vars:
                raise InputError(f"x0: {name!r} is not a state of model {model.name!r}")
            sl = dae.x_vars[name]
            x0v[sl] = _vector_value(val, sl.stop - sl.start, f"x0[{name!r}]")
    else:
        x0v = _vector_value(x0, dae.nx, "x0")
    z0v = dae.z_start.copy() if z0 is None else _vector_value(z0, dae.nz, "z0")
    pv = dae.parameter_vector(p)
    u_default = np.concatenate(
        [v.start for v in model._vars.values() if v.kind == "input"]
    ) if dae.nu else np.zeros(0)
    u_int = input_intervals(u, t, dae.nu, u_default)
    return t, x0v, z0v, pv, u_int
