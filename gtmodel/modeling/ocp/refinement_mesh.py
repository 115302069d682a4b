"""The next mesh of an adaptive mesh refinement: where the elements are split and why.

:func:`refine_mesh` reads a verified collocation result (its element defects, its inputs' switches, its states'
excess over their bounds between the nodes) and returns the relative element lengths of the next pass's mesh;
:func:`switch_times` the inputs' switch times it locates. The refinement loop itself, and the criteria by which
its passes end, are :func:`gtmodel.modeling.ocp.refinement.solve_refined` (whose module docstring describes the
indicators).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from gtmodel.errors import InputError
from gtmodel.modeling.ocp.result import OptimizationResult
from gtmodel.modeling.ocp.verification import SWITCH_FRACTION, switch_elements
from gtmodel.modeling.ocp.verification_bounds import bound_crossings, element_bound_violations, input_bound_crossings

__all__ = ["refine_mesh", "switch_times", "SWITCH_EDGE", "halved", "finer"]


def switch_times(result: OptimizationResult) -> list[float]:
    """Switch times of the inputs: jumps at element boundaries and switches inside elements.

    Parameters
    ----------
    result : OptimizationResult
        A collocation result.

    Returns
    -------
    list of float
        Increasing times, s: element boundaries across which an input jumps by more than
        :data:`SWITCH_FRACTION` of its range, and the estimates of
        :func:`switch_elements` inside elements. Located to the width of the elements
        around them.
    """
    col = result.collocation
    if col is None or col.uc.shape[2] == 0:
        return []
    uc = col.uc
    breaks = col.breaks()
    span = uc.max(axis=(0, 1)) - uc.min(axis=(0, 1))
    jump = np.abs(uc[1:, 0, :] - uc[:-1, -1, :]) / np.where(span > 0, span, np.inf)
    times = [float(breaks[k + 1]) for k in np.nonzero(np.any(jump > SWITCH_FRACTION, axis=1))[0]]
    times += [float(breaks[k] + tau * (breaks[k + 1] - breaks[k])) for k, tau in switch_elements(result).items()]
    return sorted(times)


#: Where every element's error is within the tolerance and the deviation over the horizon is not, the elements whose
#: error exceeds this fraction of the largest, scaled by tolerance / deviation, are split (:func:`refine_mesh`).
ADD_UP = 0.6

SWITCH_EDGE = 0.03
"""A switch within this fraction of an element's edge is taken as on the boundary (the element graded, not cut at it)."""


def refine_mesh(result: OptimizationResult, tolerance: float, max_elements: int,
                bounds: tuple[np.ndarray, np.ndarray] | None = None,
                input_bounds: tuple[np.ndarray, np.ndarray] | None = None, persistent: bool = False) -> tuple[np.ndarray, dict[str, Any]]:
    """The next mesh: elements split where the defect exceeds the tolerance or an input switches.

    Parameters
    ----------
    result : OptimizationResult
        A verified collocation result (``result.verification`` set).
    tolerance : float
        Verification tolerance (scaled deviation); switches are located to
        ``tolerance`` times the horizon. Where the verification's deviation exceeds it with
        every element defect within it, the elements are held to the smaller of
        ``ADD_UP * max(defect) * tolerance / deviation`` (:data:`ADD_UP`) and the defect above
        which the elements hold all but ``ADD_UP * tolerance / deviation`` of the defects' sum.
        A state bound's excess is judged by the global simulation while the deviation is within
        the tolerance, else by each element's local simulation
        (:func:`~gtmodel.modeling.ocp.verification_bounds.element_bound_violations`, ``local``).
    max_elements : int
        Limit on the elements of the new mesh (the worst elements are split first).
    bounds : tuple of numpy.ndarray, optional
        The states' lower and upper bounds, each shape ``(nx,)``: an element whose simulation
        exceeds them by more than ``tolerance`` (scaled as the deviations) is cut where its
        polynomial crosses the bound and at its input's switch (else halved): when no element
        is split for its defect or switch, or with ``persistent``.
    input_bounds : tuple of numpy.ndarray, optional
        The inputs' lower and upper bounds, each shape ``(nu,)``: an element split for its defect is cut
        where an input's polynomial leaves and re-enters its bounds too
        (:func:`~gtmodel.modeling.ocp.verification_bounds.input_bound_crossings`: the kink of the clipped input
        that the verification simulates, a bang-bang voltage's junction with its bound).
    persistent : bool, optional
        The previous pass exceeded a state bound between the points too: the elements where
        this one does are split beside those split for their defects (default False: only
        when nothing else is split).

    Returns
    -------
    fractions : numpy.ndarray
        Relative element lengths of the new mesh, shape ``(M,)`` (the old mesh if
        nothing is to be split or the limit is reached).
    info : dict
        ``{"split": elements split, "switches": switch times [s] found, "limited": elements to split that
        ``max_elements`` leaves no room for}``.

    Raises
    ------
    InputError
        If the result holds no collocation data or verification.
    """
    col, v = result.collocation, result.verification
    if col is None or v is None:
        raise InputError("refine_mesh: the result holds no collocation data or verification")
    N = col.elements
    frac = np.full(N, 1.0 / N) if col.fractions is None else np.asarray(col.fractions, dtype=float)
    errors = np.asarray(v.element_errors, dtype=float)
    errors = np.where(np.isfinite(errors), errors, 1e6 * tolerance)
    deviation = float(v.max_scaled_deviation)
    limit = tolerance  # the bound check's tolerance (the deviations' may be lowered below)
    if np.isfinite(deviation) and deviation > tolerance >= errors.max(initial=0.0):
        # every element within the tolerance, the simulation over the horizon not: the local errors add up
        # (a stiff state's deviations after each switch). The deviation taken as proportional to the local errors
        # (the error equidistributed; Betts, *Practical Methods*, ch. 4, mesh refinement), every element above the
        # largest error scaled by tolerance / deviation, with the margin ADD_UP, is split: the elements that contribute
        # are split together. A target of tolerance**2 / deviation split one or two a pass, and the deviation stayed
        # (drive1_18: 0.0126 against 0.01 at 305, 307 and 326 elements, the largest element error 0.0082 each time)
        # Likewise by the errors' sum: the largest elements split until those left hold at most ADD_UP * tolerance /
        # deviation of it, the smaller of the two levels kept (drive0_33: its deviation ten times its largest defect and
        # hundreds of elements near it; split four a pass by the largest alone, its deviation sawed at 0.011 to 0.016
        # up to the pass limit)
        ranked = np.sort(errors)[::-1]
        held = np.cumsum(ranked)
        total = float(held[-1]) if held.size else 0.0
        level = ADD_UP * float(errors.max(initial=0.0)) * tolerance / deviation
        if total > 0.0:
            last = int(np.searchsorted(held, total * (1.0 - ADD_UP * tolerance / deviation)))  # the last element to split
            level = min(level, float(ranked[min(last, ranked.size - 1)]) * (1.0 - 1e-9))
        tolerance = level or tolerance * tolerance / deviation
    errors = errors / tolerance
    plans: dict[int, tuple[float, list[float]]] = {}
    for k in np.nonzero(errors > 1.0)[0]:
        parts = 2 if errors[k] < 10 else 3 if errors[k] < 100 else 4
        plans[int(k)] = (float(errors[k]), list(np.arange(1, parts) / parts))
    switches = switch_elements(result)
    for k, tau in switches.items():
        if min(tau, 1.0 - tau) < SWITCH_EDGE:
            # the jump is on the element's boundary already (the level before it is the neighbour's): a cut at it
            # leaves a sliver that resolves nothing. Where the element's defect exceeds the tolerance, the
            # transient after the jump (a motor current against its limit, faster than the element) is: the
            # element graded towards the jump, short parts first (Betts, *Practical Methods*, ch. 4; issue 49)
            if errors[k] > 1.0:
                cuts = [0.15, 0.45] if tau < 0.5 else [0.55, 0.85]
                plans[k] = (max(plans.get(k, (0.0, []))[0], 1e3), cuts)
            continue
        if frac[k] > tolerance:
            # the switch explains the element's defect: a cut at the switch; where the element's defect is
            # 10 tolerances or more (a stiff state, a motor current, following the switch), the two parts
            # halved too, so that the next pass resolves the transient after the switch as well
            cuts = [tau] if errors[k] < 10 else [tau / 2, tau, (1 + tau) / 2]
            plans[k] = (max(plans.get(k, (0.0, []))[0], 1e3), cuts)
    if input_bounds is not None and plans:
        # the verdict simulates the inputs clipped to their bounds: in a defective element whose input polynomial
        # leaves its bound, the clipped input has a kink where it does (the voltage's junction with its bound), which
        # no polynomial follows: the element cut there too, beside its equal parts or its switch
        defective = [k for k in plans if errors[k] > 1.0]
        for k, taus in input_bound_crossings(result, *input_bounds, defective, limit).items():
            cuts = list(plans[k][1])
            for tau in taus:
                if min(tau, 1.0 - tau) >= SWITCH_EDGE and all(abs(tau - c) >= 2 * SWITCH_EDGE for c in cuts):
                    cuts.append(tau)
            plans[k] = (plans[k][0], sorted(cuts))
    if bounds is not None and (not plans or persistent):
        # nothing else to split, but the simulation exceeds a state bound between the points by more than the
        # tolerance (Betts, ch. 4: a path constraint violated between the grid points refines the grid there): the
        # element cut where its state's polynomial crosses the bound (a current's junction with its limited arc, a
        # kink that no polynomial follows) and at its input's switch, else halved. Only then, so that the passes up to
        # the deviations' verification are those without the check (cut with the others, the two-mass drive's second
        # pass left for a local optimum 1.2 % slower). With ``persistent`` beside them: drive0_38's current 2.1 % over
        # its limit 0.2 ms after the start for nine passes, each splitting where its deviation sawed, never there
        # judged by each element's local simulation while the global one deviates beyond the tolerance: drifted off the
        # collocation, it crosses a bound the trajectory rides all along its arc, and splitting every element there
        # resolved nothing (drive0_33: 469 and 1,286 elements split for the current's arc, pass after pass, its 5 %
        # excess the drift's, while the three elements with the largest defects were left unsplit at the element limit)
        over = element_bound_violations(result, *bounds, local=None) / limit
        over = over if over.size == N else np.zeros(N)
        bad = [int(k) for k in np.nonzero(over > 1.0)[0] if int(k) not in plans]
        crossings = bound_crossings(result, *bounds, bad, 0.25 * limit)
        for k in bad:
            parts = 2 if over[k] < 3 else 3 if over[k] < 10 else 4
            cuts = [tau for tau in (crossings.get(k), switches.get(k)) if tau is not None and min(tau, 1.0 - tau) >= SWITCH_EDGE]
            for tau in np.arange(1, parts) / parts:
                if all(abs(tau - c) >= 2 * SWITCH_EDGE for c in cuts):
                    cuts.append(float(tau))
            plans[k] = (1e3 * over[k], sorted(cuts))
    budget = max_elements - N
    split: list[int] = []
    limited: list[int] = []  # elements to split whose cuts the element limit leaves no room for
    for k in sorted(plans, key=lambda k: -plans[k][0]):
        cuts = plans[k][1]
        if len(cuts) > budget:
            limited.append(k)
            continue
        budget -= len(cuts)
        split.append(k)
    new: list[float] = []
    for k in range(N):
        if k in split:
            edges = np.concatenate([[0.0], plans[k][1], [1.0]])
            new.extend(frac[k] * np.diff(edges))
        else:
            new.append(frac[k])
    info = {"split": sorted(split), "switches": switch_times(result), "limited": sorted(limited)}
    return np.asarray(new), info


def finer(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The common refinement of two meshes given by their relative element lengths.

    Parameters
    ----------
    a, b : numpy.ndarray
        Relative element lengths of the two meshes, each summing to 1.

    Returns
    -------
    numpy.ndarray
        Relative element lengths of the mesh whose boundaries are both meshes'.
    """
    edges = np.unique(np.round(np.concatenate([np.cumsum(a), np.cumsum(b), [0.0]]), 12))
    edges = edges[(edges >= 0) & (edges <= 1)]
    return np.diff(edges)


def halved(fractions: np.ndarray) -> np.ndarray:
    """Every element of a mesh cut into two equal halves (the mesh of an objective-convergence pass).

    Parameters
    ----------
    fractions : numpy.ndarray
        Relative element lengths, shape ``(N,)``.

    Returns
    -------
    numpy.ndarray
        Relative element lengths, shape ``(2 N,)``.
    """
    return np.repeat(np.asarray(fractions, dtype=float) / 2.0, 2)
