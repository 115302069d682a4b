"""A refinement pass started from the last pass's multipliers, carried onto the new mesh.

A pass started from the last pass's primal point alone (:func:`~gtmodel.modeling.ocp.refinement_guess.guess_from`)
leaves IPOPT to find every multiplier again: ``drive0_33``'s passes that split 2 to 9 of 560 to 610 elements took
247 to 759 iterations each. With the multipliers carried over, an element the new mesh keeps starts at its own
optimum. They are carried as their continuous counterparts (Radau collocation's discrete adjoint, e.g. Betts (2010),
section 4.11): a collocation equation ``h f(x_j) - sum_i D_ji x_i = 0`` at point ``j`` has multiplier ``B_j p(t_j)``
(``p`` the costate, ``B_j`` the quadrature weight), a continuity row ``p`` at the element's end; an algebraic or
path row, and a bound of a point's variable, ``h B_j nu(t_j)`` (``nu`` a multiplier density). Each is interpolated in
time (the horizon's fraction) onto the new points and ends, which reproduces an element the new mesh keeps exactly.
The loop that uses it is :func:`gtmodel.modeling.ocp.refinement.solve_refined`.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from gtmodel.modeling.ocp.collocation_bounds import elements_in_spans
from gtmodel.modeling.ocp.result import OptimizationResult

__all__ = ["MultiplierSource", "multiplier_source", "warm_start", "CARRIED_PUSH"]

#: IPOPT's push of a carried start off its bounds, of its primal point and of its bound multipliers (warm starts
#: re-solving the same NLP use 1e-9, :data:`~gtmodel.modeling.ocp.collocation_function.WARM_START_OPTIONS`): the new
#: mesh's points are interpolated, not optimal. Measured on the drive family's seed 0 (`bench_drive_family.py
#: --cached --no-reference`): with 1e-9 ``drive0_04`` took 108.7 CPU-s and ``drive0_33`` ended ``check_failed``; with
#: 1e-6, 37.2 CPU-s and ``optimal`` at 145.7 (with the primal point alone: 30.0, and 195 to 290 at the budget's edge).
CARRIED_PUSH = {"warm_start_bound_push": 1e-6, "warm_start_bound_frac": 1e-6, "warm_start_slack_bound_push": 1e-6,
                "warm_start_slack_bound_frac": 1e-6, "warm_start_mult_bound_push": 1e-6}

_KINDS = ("x", "u", "z")


@dataclass
class MultiplierSource:
    """A solved pass's multipliers and where they sit in its NLP (no symbolic data kept).

    Parameters
    ----------
    fractions : numpy.ndarray
        Element lengths as fractions of the horizon, shape ``(N,)``.
    root, weights : numpy.ndarray
        Collocation points ``tau_0 = 0, tau_1..tau_d`` in an element, shape ``(d + 1,)``; quadrature weights
        ``B_1..B_d``, shape ``(d,)``.
    nx, nr : int
        States; rows per collocation point (states, algebraic equations, path constraints).
    blocks, offsets, sizes, scale : list, dict, dict, numpy.ndarray
        The NLP's variable blocks ``(kind, element, point)``, their first index and size, each variable's
        nominal (:class:`~gtmodel.modeling.ocp.collocation_nlp.CollocationNLP`).
    rows_point, rows_cont, rows_tf : list
        First rows of the points' equations, the continuity rows and the final-time ties.
    ends : list of tuple
        ``(first row, rows)`` of the start, final and timed constraints.
    tf_scale : float
        The final time's nominal (1 for a fixed final time).
    interior : tuple
        The state bounds between the points (:func:`~gtmodel.modeling.ocp.collocation_bounds.interior_state_bounds`):
        ``(first row, elements that have them, rows per element)``; ``(0, [], 0)`` without.
    lam_w, lam_g : numpy.ndarray
        IPOPT's multipliers of the variables' bounds ``(nw,)`` and of the constraints ``(ng,)``.
    """

    fractions: np.ndarray
    root: np.ndarray
    weights: np.ndarray
    nx: int
    nr: int
    blocks: list
    offsets: dict
    sizes: dict
    scale: np.ndarray
    rows_point: list
    rows_cont: list
    rows_tf: list
    ends: list
    tf_scale: float
    interior: tuple
    lam_w: np.ndarray
    lam_g: np.ndarray


def multiplier_source(transcription: Any, result: OptimizationResult) -> MultiplierSource | None:
    """The multipliers of a pass solved by IPOPT on a collocation NLP, for :func:`warm_start`.

    Parameters
    ----------
    transcription : CollocationTranscription
        The pass's transcription.
    result : OptimizationResult
        Its result.

    Returns
    -------
    MultiplierSource or None
        None when the result has no multipliers, is not of this transcription, or the NLP is fatrop's
        (stage-ordered rows).
    """
    nlp = getattr(transcription, "nlp", None)
    if (nlp is None or result.lam_g is None or result.lam_w is None or result.transcription_key != transcription.key
            or nlp.stages is not None):
        return None
    return _layout(transcription, np.asarray(result.lam_w, dtype=float), np.asarray(result.lam_g, dtype=float))


def _layout(transcription: Any, lam_w: np.ndarray, lam_g: np.ndarray) -> MultiplierSource:
    """A :class:`MultiplierSource` of ``transcription``'s NLP with the multipliers ``lam_w``, ``lam_g``."""
    nlp, n = transcription.nlp, int(transcription.elements)
    fractions = np.full(n, 1.0 / n) if transcription.fractions is None else np.asarray(transcription.fractions, dtype=float)
    co = transcription._co
    tf = [nlp.scale[nlp.offsets[b]] for b in nlp.blocks if b[0] == "tf"]
    ends = [(int(first), int(e.numel())) for first, e in nlp.ends]
    interior: tuple = (0, np.zeros(0, dtype=int), 0)
    if transcription.bound_points:  # its rows: the last of the ends of their size (only timed constraints follow them)
        where = (np.arange(n) if transcription.bound_spans is None else elements_in_spans(fractions, transcription.bound_spans))
        x = nlp.offsets[("x", 0, 1)]
        bounded = np.isfinite(nlp.lbw[x:x + transcription.nlp_dae.nx]) | np.isfinite(nlp.ubw[x:x + transcription.nlp_dae.nx])
        per = transcription.bound_points * int(bounded.sum())
        hits = [i for i, (_f, size) in enumerate(ends) if size == per * where.size and size]
        if hits:
            interior = (ends[hits[-1]][0], where, per)
            ends = ends[:hits[-1]] + ends[hits[-1] + 1:]
    return MultiplierSource(
        fractions=fractions, root=np.asarray(co["root"], dtype=float), weights=np.asarray(co["B"], dtype=float).reshape(-1),
        nx=int(transcription.nlp_dae.nx), nr=int(transcription.nlp_dae.nx + transcription.nlp_dae.nz + nlp.npath),
        blocks=list(nlp.blocks), offsets=dict(nlp.offsets),
        sizes=dict(zip(nlp.blocks, nlp.block_sizes)), scale=np.asarray(nlp.scale, dtype=float),
        rows_point=list(nlp.rows_point), rows_cont=list(nlp.rows_cont), rows_tf=list(nlp.rows_tf),
        ends=ends, tf_scale=float(tf[0]) if tf else 1.0, interior=interior, lam_w=lam_w, lam_g=lam_g)


def _times(fractions: np.ndarray, root: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each element's start (fraction of the horizon), shape ``(N + 1,)`` with the end; each point's time ``(N, d)``."""
    breaks = np.concatenate([[0.0], np.cumsum(fractions)])
    breaks[-1] = 1.0
    return breaks, breaks[:-1, None] + root[None, 1:] * fractions[:, None]


def _interp(t_new: np.ndarray, t_old: np.ndarray, values: np.ndarray) -> np.ndarray:
    """``values`` (len(t_old), m) interpolated in time at ``t_new`` (held beyond the ends), shape ``(len(t_new), m)``."""
    if t_old.size == 0 or values.shape[1] == 0:
        return np.zeros((t_new.size, values.shape[1] if values.ndim == 2 else 0))
    return np.column_stack([np.interp(t_new, t_old, values[:, i]) for i in range(values.shape[1])])


def _carried(src: MultiplierSource, new: MultiplierSource) -> tuple[np.ndarray, np.ndarray]:
    """``(lam_w, lam_g)`` of ``new``'s NLP (its ``lam_w``/``lam_g`` only give the sizes) from ``src``'s."""
    d = src.weights.size
    b_old, t_old = _times(src.fractions, src.root)
    b_new, t_new = _times(new.fractions, new.root)
    n_old, n_new = src.fractions.size, new.fractions.size
    lam_w, lam_g = np.zeros_like(new.lam_w), np.zeros_like(new.lam_g)
    # the points' rows: the collocation equations carry B_j p(t), the algebraic and path rows h B_j nu(t)
    per_h = np.concatenate([np.zeros(src.nx), np.ones(src.nr - src.nx)])
    old_pts = np.array([src.lam_g[r:r + src.nr] / (src.weights[j - 1] * src.fractions[k] ** per_h)
                        for k, j, r in src.rows_point])
    carried = _interp(t_new.ravel(), t_old.ravel(), old_pts.reshape(-1, src.nr))
    for (k, j, r), row in zip(new.rows_point, carried):
        lam_g[r:r + new.nr] = row * new.weights[j - 1] * new.fractions[k] ** per_h
    # continuity: the costate at an element's end
    old_cont = np.array([src.lam_g[r:r + src.nx] for _k, r in src.rows_cont])
    for (_k, r), row in zip(new.rows_cont, _interp(b_new[1:], b_old[1:], old_cont)):
        lam_g[r:r + new.nx] = row
    # the final time's ties between elements (rows divided by its nominal, which grows with the elements)
    if src.rows_tf and new.rows_tf:
        old_tf = np.array([[src.lam_g[r] / src.tf_scale] for _k, r in src.rows_tf])
        for (_k, r), val in zip(new.rows_tf, _interp(b_new[1:-1], b_old[1:-1], old_tf)):
            lam_g[r] = val[0] * new.tf_scale
    if len(src.ends) == len(new.ends):  # the start, final and timed constraints: the same rows in the same order
        for (fo, no), (fn, nn) in zip(src.ends, new.ends):
            if no == nn:
                lam_g[fn:fn + nn] = src.lam_g[fo:fo + no]
    # the state bounds between the points: an element's rows from its parent's, as a density (none where it had none)
    first_o, where_o, per = src.interior
    first_n, where_n, per_n = new.interior
    if per and per == per_n:
        row_of = {int(k): first_o + i * per for i, k in enumerate(where_o)}
        for i, k in enumerate(where_n):
            o = int(np.searchsorted(b_old, 0.5 * (b_new[k] + b_new[k + 1]), side="right") - 1)
            if o in row_of:
                lam_g[first_n + i * per:first_n + (i + 1) * per] = (src.lam_g[row_of[o]:row_of[o] + per]
                                                                     * new.fractions[k] / src.fractions[o])
    # the variables' bounds: per unit nominal (lam_w is the scaled variable's); a point's as a density
    physical = src.lam_w / src.scale
    kept = {k: int(np.argmin(np.abs(b_old[:-1] - b_new[k]))) for k in range(n_new)}
    for kind in _KINDS:
        olds = [(k, j) for (kd, k, j) in src.blocks if kd == kind and 1 <= j and k < n_old]
        if not olds:
            continue
        dens = np.array([physical[src.offsets[(kind, k, j)] + np.arange(_size(src, kind, k, j))] / (src.weights[j - 1] * src.fractions[k])
                         for k, j in olds])
        t_o = np.array([t_old[k, j - 1] for k, j in olds])
        news = [(k, j) for (kd, k, j) in new.blocks if kd == kind and 1 <= j and k < n_new]
        vals = _interp(np.array([t_new[k, j - 1] for k, j in news]), t_o, dens)
        for (k, j), val in zip(news, vals):
            i = new.offsets[(kind, k, j)] + np.arange(val.size)
            lam_w[i] = val * new.weights[j - 1] * new.fractions[k] * new.scale[i]
    last_tf = [[b for b in m.blocks if b[0] == "tf"][-1:] for m in (src, new)]  # the bounded copy (or the one final time)
    for kd, k, j in new.blocks:  # an element's start the new mesh keeps, the final state and time, the free parameters
        key = None
        if kd == "x" and j == 0 and k < n_new:
            o = kept[k]
            if abs(b_old[o] - b_new[k]) < 1e-12 and abs(b_old[o + 1] - b_new[k + 1]) < 1e-12:
                key = ("x", o, 0)
        elif kd == "x" and j == 0:
            key = ("x", n_old, 0)
        elif kd == "tf" and last_tf[0] and [(kd, k, j)] == last_tf[1]:
            key = last_tf[0][0]
        elif kd == "pf" and ("pf", 0, 0) in src.offsets:
            key = ("pf", 0, 0)
        if key is not None:
            i = new.offsets[(kd, k, j)] + np.arange(_size(new, kd, k, j))
            lam_w[i] = physical[src.offsets[key] + np.arange(i.size)] * new.scale[i]
    return lam_w, lam_g


def _size(src: MultiplierSource, kind: str, k: int, j: int) -> int:
    """The size of variable block ``(kind, k, j)``."""
    return int(src.sizes[(kind, k, j)])


def warm_start(transcription: Any, source: MultiplierSource, guess: Mapping[str, Any], template: OptimizationResult,
               parameters: Mapping[str, Any] | None) -> OptimizationResult | None:
    """A start of ``transcription``'s NLP for :meth:`CollocationTranscription.solve` with ``warm_start=True``: the
    primal point of ``guess`` (as a cold start samples it) and ``source``'s multipliers carried onto its mesh.

    Parameters
    ----------
    transcription : CollocationTranscription
        The new pass's transcription (IPOPT; not fatrop's stage order).
    source : MultiplierSource
        The last pass's multipliers (:func:`multiplier_source`).
    guess : mapping
        The new pass's primal guess (:func:`~gtmodel.modeling.ocp.refinement_guess.guess_from`).
    template : OptimizationResult
        The last pass's result (copied; the start's fields replaced).
    parameters : mapping or None
        The parameter values of the solve.

    Returns
    -------
    OptimizationResult or None
        The start, or None when the two NLPs differ in their per-point rows or states (another model or
        set of path constraints), or ``transcription`` is no IPOPT collocation NLP.
    """
    opt, dae = transcription.optimization, transcription.dae
    nlp = getattr(transcription, "nlp", None)
    if nlp is None or nlp.stages is not None:
        return None
    new = _layout(transcription, np.zeros(int(nlp.w.numel())), np.zeros(int(nlp.g.numel())))
    if (new.nx, new.nr, new.weights.size) != (source.nx, source.nr, source.weights.size):
        return None
    lam_w, lam_g = _carried(source, new)
    pvec = dae.parameter_vector({**opt.parameters, **(parameters or {})})
    guesses = {**opt.initial_guesses, **{k: v for k, v in guess.items() if k != "final_time"}}
    tf = float(np.clip(float(guess.get("final_time", opt.final_time_guess)), *opt.final_time_bounds))
    start = copy.copy(template)
    start.w = transcription._initial_w(guesses, tf, pvec)
    start.transcription_key, start.lam_w, start.lam_g = transcription.key, lam_w, lam_g
    return start
