"""Simulation of models that need the structural passes: initial equations, aliases, high index.

:meth:`gtmodel.modeling.Model.simulate` calls :func:`simulate_structured` when the model has
initial equations or ``flatten()`` refuses it. The steps:

1. alias elimination and the structural check (:mod:`gtmodel.modeling.structure.analysis`);
2. Pantelides' algorithm (:func:`~gtmodel.modeling.structure.index_reduction.pantelides`);
3. consistent initial values (:func:`~gtmodel.modeling.structure.initialization.solve_initial`);
4. the index-1 DAE of a dummy-derivative selection made at the current point, integrated
   by IDAS; after each chunk of the (refined) grid the selection quality
   (:func:`~gtmodel.modeling.structure.index_reduction.selection_quality`) is checked at every point,
   and from the first point where it drops below ``SWITCH_RATIO`` the selection is remade
   there and integration restarts from the (consistent) values at that point — the
   dummy-state switch of Mattsson & Soederlind (1993), section 5 (a Cartesian pendulum
   passing ``x = 0`` switches between ``x`` and ``y`` as dummies); a chunk also ends where
   the input changes if the residuals depend on the input (the algebraic variables jump:
   IDAS restarts there, as in :mod:`gtmodel.modeling.simulation.integration`);
5. the values mapped back to the declared variables and outputs, as in a
   :class:`~gtmodel.modeling.SimulationResult` of an index-1 model.

Index-1 models that only have initial equations go to
:func:`~gtmodel.modeling.simulation.integration.simulate_model` with the consistent ``x0``/``z0``.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._docstrings import fill_doc
from gtmodel.errors import ConvergenceError, InputError
from gtmodel.modeling.dae import SimulationResult, _vector_value, casadi_name, expand_names
from gtmodel.modeling.structure.index_reduction import (
    AugmentedDAE,
    Selection,
    pantelides,
    quality_function,
    reduced_system,
    select_dummies,
    selection_quality,
)
from gtmodel.modeling.structure.initialization import fill_order, guess_and_conditions, solve_initial
from gtmodel.modeling.simulation.integration import (
    SIMULATE_DOCS,
    input_intervals,
    input_segments,
    integrator_options,
    simulate_model,
)
from gtmodel.modeling.structure.analysis import eliminate_aliases, require_regular, scalarize

__all__ = ["simulate_structured", "consistent_start", "SWITCH_RATIO", "CHECK_POINTS"]

_log = logging.getLogger("gtmodel")

#: Re-select the dummy derivatives where the current block's |det| falls below this
#: fraction of the best (pivoted-QR) block's; the new selection starts at ratio >= 1, so the
#: factor is also the hysteresis against chattering.
SWITCH_RATIO = 0.5
#: The selection is checked on at least this many points of the simulated span (the user's
#: grid is refined when coarser), so a pendulum cannot cross a singular configuration unseen.
CHECK_POINTS = 1000
#: Points integrated per IDAS call before the selection is checked (divided by 4 after an
#: integrator failure, which a selection turning singular inside the chunk causes; doubled
#: back after each success).
CHUNK = 20


def _cat(syms: list[ca.SX]) -> ca.SX:
    return ca.vertcat(*syms) if syms else ca.SX(0, 1)


def _parameter_vector(model: Any, p: Mapping[str, Any] | None) -> tuple[np.ndarray, dict[str, slice]]:
    params = [v for v in model._vars.values() if v.kind == "parameter"]
    slices, k = {}, 0
    for v in params:
        slices[v.name] = slice(k, k + v.size)
        k += v.size
    vec = np.concatenate([v.start for v in params]) if params else np.zeros(0)
    for name, value in (p or {}).items():
        if name not in slices:
            raise InputError(f"model {model.name!r} has no parameter {name!r}; parameters: {sorted(slices)}")
        sl = slices[name]
        vec[sl] = _vector_value(value, sl.stop - sl.start, f"parameter {name!r}")
    return vec, slices


def _refine(t: np.ndarray, n_check: int) -> tuple[np.ndarray, np.ndarray]:
    """Fine grid with at least ``n_check`` intervals and the user-grid positions in it."""
    h = (t[-1] - t[0]) / n_check
    pieces, pos = [t[:1]], [0]
    for a, b in zip(t[:-1], t[1:]):
        m = max(1, math.ceil((b - a) / h - 1e-9))
        pieces.append(a + (b - a) * np.arange(1, m + 1) / m)
        pos.append(pos[-1] + m)
    tf = np.concatenate(pieces)
    tf[np.array(pos)] = t
    return tf, np.array(pos)


def _integrate(aug: AugmentedDAE, sel: Selection, tf: np.ndarray, v0: np.ndarray, uf: np.ndarray,
               pv: np.ndarray, opts: dict) -> np.ndarray:
    """IDAS on the reduced DAE of ``sel`` over the grid ``tf``; all variables per row."""
    s = aug.system
    states, algs = reduced_system(aug, sel)
    dae = {
        "t": s.t, "x": _cat([aug.syms[v] for v in states]), "z": _cat([aug.syms[v] for v in algs]),
        "u": s.u, "p": s.p, "ode": _cat([aug.syms[aug.diff[v]] for v in states]), "alg": _cat(aug.res),
    }
    # the values are consistent (solve_initial, or the previous segment): give IDACalcIC the
    # state derivatives too, else its line search can fail from xdot = 0 on restarts
    opts = {**opts, "init_xdot": [float(v0[aug.diff[v]]) for v in states]}
    n = tf.size
    u_cas = np.vstack([uf[:1], uf]).T if s.u.numel() else np.zeros((0, n))
    x0 = v0[states]
    if not states:  # purely algebraic after reduction: IDAS needs a state, add a constant one
        dae["x"], dae["ode"], x0 = ca.SX.sym("_none"), ca.SX(0), np.zeros(1)
        opts["init_xdot"] = [0.0]
    try:
        F = ca.integrator(f"{casadi_name(s.name)}_dd", "idas", dae, float(tf[0]), list(tf), opts)
        out = F(x0=x0, z0=v0[algs], p=pv, u=u_cas)
    except RuntimeError as exc:
        lines = [ln for ln in str(exc).splitlines() if "returned" in ln] or str(exc).splitlines()
        raise ConvergenceError(
            f"simulation of model {s.name!r} (index reduced, dummies "
            f"{sorted(aug.names[v] for v in sel.dummies)}) failed near t = {tf[0]:g} s: "
            f"{lines[0].strip() if lines else exc}"
        ) from exc
    vals = np.empty((n, len(aug.syms)))
    if states:
        vals[:, states] = np.array(out["xf"]).reshape(len(states), n).T
    vals[:, algs] = np.array(out["zf"]).reshape(len(algs), n).T
    if not np.all(np.isfinite(vals)):
        raise ConvergenceError(f"simulation of model {s.name!r} produced non-finite values")
    return vals


def _switching_run(aug: AugmentedDAE, tf: np.ndarray, uf: np.ndarray, pv: np.ndarray, v0: np.ndarray,
                   opts: dict) -> tuple[np.ndarray, list[float]]:
    """Integrate with dummy re-selection; all variables on ``tf`` and the switch times."""
    n = tf.size
    vals = np.empty((n, len(aug.syms)))
    vals[0] = v0
    k, switches, current, chunk = 0, [], None, CHUNK
    # algebraic variables that jump with the input: IDAS restarts at each change (consistent there)
    jumps = input_segments(uf) if uf.size and ca.depends_on(_cat(aug.res), aug.system.u) else np.zeros(1, int)
    cuts = np.append(jumps[1:], n - 1)
    while k < n - 1:
        sel = select_dummies(aug, (tf[k], vals[k], uf[min(k, n - 2)], pv))
        if current is not None and sel.dummies != current.dummies:
            switches.append(float(tf[k]))
            _log.debug("%s: dummy derivatives %s at t = %g s", aug.system.name,
                       sorted(aug.names[v] for v in sel.dummies), tf[k])
        current = sel
        kend = min(k + chunk, n - 1) if sel.levels else n - 1  # nothing to re-select: one run
        kend = min(kend, int(cuts[np.searchsorted(cuts, k, side="right")]))
        try:
            seg = _integrate(aug, sel, tf[k:kend + 1], vals[k], uf[k:kend], pv, opts)
        except ConvergenceError:
            if kend - k == 1 or not sel.levels:
                raise
            chunk = max(1, (kend - k) // 4)  # the selection may turn singular inside: look closer
            continue
        chunk = min(CHUNK, 2 * chunk)
        stop = kend
        if sel.levels:
            qf = quality_function(aug, sel).map(kend - k)
            useg = uf[k:kend]
            blocks = qf(tf[k + 1:kend + 1].reshape(1, -1), seg[1:].T, useg.T if useg.size else np.zeros((0, kend - k)),
                        np.tile(pv.reshape(-1, 1), (1, kend - k)))
            blocks = blocks if isinstance(blocks, (list, tuple)) else [blocks]
            for j in range(kend - k):
                pts = [np.array(b)[:, j * len(lv[1]):(j + 1) * len(lv[1])] for b, lv in zip(blocks, sel.levels)]
                if selection_quality(sel, pts) < SWITCH_RATIO:
                    stop = k + 1 + j
                    break
        if k in jumps[1:]:  # at an input change: the right limit (consistent with the new input)
            vals[k] = seg[0]
        vals[k + 1:stop + 1] = seg[1:stop - k + 1]
        k = stop
    return vals, switches


def _check_grid(t_grid: Any, integrator: str) -> np.ndarray:
    t = np.asarray(t_grid, dtype=float).reshape(-1)
    if t.size < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise InputError("t_grid must be finite, strictly increasing, with at least 2 points")
    if integrator not in ("idas", "cvodes"):
        raise InputError(f"integrator must be 'idas' or 'cvodes', got {integrator!r}")
    return t


def _initial_point(model: Any, t: np.ndarray, x0: Any, u: Any, p: Mapping[str, Any] | None, z0: Any) -> tuple:
    """Structural passes and the consistent initial values (steps 1-3 of the module docstring)."""
    full = scalarize(model)
    require_regular(full)  # on the user's own equations, so that the message names them
    system = eliminate_aliases(full)
    aug = pantelides(system)
    pv, p_slices = _parameter_vector(model, p)
    u_int = input_intervals(u, t, int(system.u.numel()), system.u_start)
    guess, conditions = guess_and_conditions(model, aug, x0, z0)
    u0 = u_int[0]
    fill = None
    if not system.init_res:  # the remaining degrees of freedom at start values (Modelica tools)
        sel0 = select_dummies(aug, (t[0], guess, u0, pv))
        fill = fill_order(aug, guess, reduced_system(aug, sel0)[0])
    v0 = solve_initial(aug, float(t[0]), u0, pv, guess, conditions, fill)
    obs_names = [nm for v in model._vars.values() if v.kind in ("state", "algebraic")
                 for nm in expand_names(v.name, v.size)]
    obs = ca.Function("observed", [_cat(aug.syms)], [_cat([system.observed[nm] for nm in obs_names])])
    return system, aug, pv, p_slices, u_int, v0, obs, obs_names


def consistent_start(
    model: Any, t_grid: Any, x0: Any = None, u: Any = None, p: Mapping[str, Any] | None = None, z0: Any = None,
) -> dict[str, np.ndarray]:
    """Consistent values of the declared states and algebraic variables at ``t_grid[0]``.

    Steps 1-3 of the module docstring (structural check, alias elimination, Pantelides, the
    consistent initialisation with the :meth:`~gtmodel.modeling.Model.initial_equation` s
    and the states named in an ``x0`` mapping fixed), as :func:`simulate_structured` does
    before integrating. :meth:`Model.simulate` uses it for a model with when-clauses.

    Parameters
    ----------
    model : Model
        The model.
    t_grid : array_like
        Output times, ``(N,)``, s; the values are at ``t_grid[0]`` (inputs of the first interval).
    x0, u, p, z0 : optional
        As for :meth:`Model.simulate` (``x0`` entries are initial conditions, ``z0`` guesses).

    Returns
    -------
    dict of str to numpy.ndarray
        Declared state and algebraic variable name -> value, ``(size,)``.

    Raises
    ------
    InputError
        On malformed arguments.
    ModelError
        If the model is structurally singular or the initialisation is not square.
    ConvergenceError
        If the initialisation does not converge.
    """
    t = _check_grid(t_grid, "idas")
    *_, v0, obs, obs_names = _initial_point(model, t, x0, u, p, z0)
    ov = dict(zip(obs_names, np.array(obs(v0)).ravel()))
    return {v.name: np.array([ov[nm] for nm in expand_names(v.name, v.size)])
            for v in model._vars.values() if v.kind in ("state", "algebraic")}


@fill_doc(**SIMULATE_DOCS)
def simulate_structured(
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
    """Simulate a model with initial equations, aliases or a high index (see the module docstring).

    The ``x0`` entries (a mapping, or a vector of all states) and the starts declared
    ``fixed=True`` are initial conditions on the variables they name
    (:mod:`gtmodel.modeling.structure.initialization`); without initial equations the
    remaining freedom is taken from start values (given starts first, then the states of
    the dummy-derivative selection made at the start values); all other values are
    guesses. The switch times of the dummy selection are logged (debug).

    Parameters
    ----------
    model : Model
        The model.
    {simulate_args}

    {simulate_returns}
    """
    t = _check_grid(t_grid, integrator)
    opts = integrator_options(options, rtol, atol, integrator)  # bad options refused before any work
    system, aug, pv, p_slices, u_int, v0, obs, obs_names = _initial_point(model, t, x0, u, p, z0)
    if aug.n_differentiated == 0 and not system.aliases and model._flattens():
        ov = np.array(obs(v0)).ravel()
        nx = sum(v.size for v in model._vars.values() if v.kind == "state")
        return simulate_model(model, t, ov[:nx], u, p, integrator, rtol, atol, ov[nx:], options)
    if integrator != "idas":
        raise InputError(f"model {model.name!r} needs index reduction or alias elimination; use integrator 'idas'")
    if aug.n_differentiated:
        tf, pos = _refine(t, CHECK_POINTS)
        uf = np.repeat(u_int, np.diff(pos), axis=0)
    else:
        tf, pos, uf = t, np.arange(t.size), u_int
    vals, switches = _switching_run(aug, tf, uf, pv, v0, opts)
    vals = vals[pos]
    if switches:
        _log.debug("model %s: dummy derivatives switched at t = %s s", model.name, switches)
    n = t.size
    ov = np.array(obs.map(n)(vals.T)).reshape(len(obs_names), n).T
    us = np.vstack([u_int, u_int[-1:]])
    col = {nm: k for k, nm in enumerate(obs_names)}

    def group(kind: str, data: np.ndarray, names: dict[str, int]) -> dict[str, np.ndarray]:
        out = {}
        for v in model._vars.values():
            if v.kind == kind:
                cols = [names[nm] for nm in expand_names(v.name, v.size)]
                out[v.name] = data[:, cols[0]].copy() if v.size == 1 else data[:, cols].copy()
        return out

    outputs: dict[str, np.ndarray] = {}
    if system.outputs:
        s = system
        fo = ca.Function("outputs", [s.t, _cat(aug.syms), s.u, s.p], list(s.outputs.values())).map(n)
        res = fo(t.reshape(1, -1), vals.T, us.T if us.size else np.zeros((0, n)), np.tile(pv.reshape(-1, 1), (1, n)))
        res = res if isinstance(res, (list, tuple)) else [res]
        for (name, e), r in zip(s.outputs.items(), res):
            a = np.array(r).reshape(int(e.numel()), n).T
            outputs[name] = a[:, 0].copy() if a.shape[1] == 1 else a
    u_names = {nm: k for k, nm in enumerate(system.u_names)}
    return SimulationResult(
        t=t,
        x=group("state", ov, col),
        z=group("algebraic", ov, col),
        u=group("input", us, u_names),
        outputs=outputs,
        p={k: pv[sl].copy() for k, sl in p_slices.items()},
    )

