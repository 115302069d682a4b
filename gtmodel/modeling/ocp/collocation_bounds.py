"""State bounds imposed on the collocation polynomial between its points, not only at them.

Direct collocation imposes a state's bounds at the collocation points; between them the
state's polynomial (and the trajectory it approximates) may cross the bound. On the drive
family's ball-screw axis (``drive0_03``, minimum time, the current at its bound through the
deceleration) the current's polynomial reached 14.54 A between the points of a pass whose
points all kept 14.3 A, and refinement by splitting alone stalled at a 1.9 % excess over 16
passes. :func:`interior_state_bounds` writes the bounds at ``points`` more places in every
element as linear rows of the NLP: the polynomial through the element's start and its
collocation points evaluated there (Betts, *Practical Methods for Optimal Control*, 2nd ed.,
sec. 4.8: path constraints enforced at intermediate points), so that the verification's dense
check (:mod:`~gtmodel.modeling.ocp.verification_bounds`) sees the excess shrink with the
element, as the defect does. The mesh refinement switches them on once a pass's verifying
simulation exceeds a state bound between the points (:data:`BOUND_POINTS` per element).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError
from gtmodel.modeling.ocp.result import lagrange_basis

__all__ = ["BOUND_POINTS", "bound_point_taus", "interior_state_bounds", "elements_in_spans", "excess_spans", "merged_spans", "checked_spans"]

#: The extra points per element at which the refinement imposes the state bounds once a pass exceeds one between the points.
BOUND_POINTS = 4


def bound_point_taus(points: int) -> np.ndarray:
    """The places of the extra bound rows on the unit element: the midpoints of ``points`` equal parts.

    Parameters
    ----------
    points : int
        Extra points per element, >= 1.

    Returns
    -------
    numpy.ndarray
        ``(j + 1/2) / points`` for ``j = 0 .. points - 1``, shape ``(points,)``.

    Raises
    ------
    InputError
        If ``points`` is not a positive integer.
    """
    if isinstance(points, bool) or not isinstance(points, (int, np.integer)) or points < 1:
        raise InputError(f"bound_points: expected a positive integer, got {points!r}")
    return (np.arange(points) + 0.5) / points


def interior_state_bounds(X_all: ca.SX, nx: int, root: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                          nominal: np.ndarray, points: int, elements: np.ndarray | None = None) -> tuple[ca.SX, np.ndarray, np.ndarray]:
    """Rows ``lower <= x(t_k + tau h_k) <= upper`` of the bounded states at :func:`bound_point_taus` in every element.

    Parameters
    ----------
    X_all : casadi.SX
        The elements' states, shape ``(nx (d + 1), N)``: column ``k`` stacks the state at the
        element's start and at its ``d`` collocation points (physical units).
    nx : int
        States.
    root : numpy.ndarray
        ``[0, tau_1, ..., tau_d]`` on the unit element, shape ``(d + 1,)``.
    lower, upper : numpy.ndarray
        The states' bounds, each shape ``(nx,)`` (``-inf``/``inf`` for none).
    nominal : numpy.ndarray
        The states' nominal values, shape ``(nx,)``: the rows are divided by them.
    points : int
        Extra points per element, >= 1.
    elements : numpy.ndarray of int, optional
        The elements that get the rows (default all ``N``; :func:`elements_in_spans`).

    Returns
    -------
    tuple of (casadi.SX, numpy.ndarray, numpy.ndarray)
        The rows (``points * nb * n``, element-major; ``nb`` the bounded states, ``n`` the elements) and their
        lower and upper bounds (scaled as the rows). No rows when no state is bounded.

    Raises
    ------
    InputError
        If ``points`` is not a positive integer.
    """
    bounded = np.flatnonzero(np.isfinite(lower) | np.isfinite(upper))
    taus = bound_point_taus(points)
    if elements is not None:
        X_all = X_all[:, [int(k) for k in elements]]
    if not bounded.size or not X_all.shape[1]:
        return ca.SX(0, 1), np.zeros(0), np.zeros(0)
    basis = lagrange_basis(np.asarray(root, dtype=float), taus)  # (points, d + 1)
    nom = np.asarray(nominal, dtype=float)[bounded]
    A = np.zeros((points * bounded.size, X_all.shape[0]))
    for e in range(points):
        for b, s in enumerate(bounded):
            A[e * bounded.size + b, s::nx] = basis[e] / nom[b]
    rows = ca.vec(ca.mtimes(ca.DM(A), X_all))
    n_el = int(X_all.shape[1])
    lo = np.tile(np.tile(np.asarray(lower, dtype=float)[bounded] / nom, points), n_el)
    hi = np.tile(np.tile(np.asarray(upper, dtype=float)[bounded] / nom, points), n_el)
    return rows, lo, hi


def elements_in_spans(fractions: np.ndarray, spans: list[tuple[float, float]]) -> np.ndarray:
    """The elements of a mesh that overlap any of ``spans`` (parts of the horizon, as fractions of it).

    Parameters
    ----------
    fractions : numpy.ndarray
        The mesh's element lengths as fractions of the horizon, shape ``(N,)``, summing to 1.
    spans : list of tuple of (float, float)
        ``(s0, s1)`` with ``0 <= s0 <= s1 <= 1``.

    Returns
    -------
    numpy.ndarray of int
        Increasing element indices.
    """
    edges = np.concatenate([[0.0], np.cumsum(np.asarray(fractions, dtype=float))])
    hit = np.zeros(edges.size - 1, dtype=bool)
    for s0, s1 in spans:
        hit |= (edges[:-1] < s1) & (edges[1:] > s0)
    return np.flatnonzero(hit)


def excess_spans(fractions: np.ndarray, excess: np.ndarray, level: float) -> list[tuple[float, float]]:
    """The parts of the horizon where a pass exceeded a state bound: its elements over ``level``, one more each side.

    Parameters
    ----------
    fractions : numpy.ndarray
        The pass's element lengths as fractions of the horizon, shape ``(N,)``.
    excess : numpy.ndarray
        Per element the largest scaled excess of its verifying simulation over the state bounds, shape ``(N,)``
        (:func:`~gtmodel.modeling.ocp.verification_bounds.element_bound_violations`).
    level : float
        The excess that marks an element, >= 0.

    Returns
    -------
    list of tuple of (float, float)
        ``(s0, s1)`` fractions of the horizon, one per marked element (widened by its neighbours: the next pass's
        solution moves by about an element).
    """
    edges = np.clip(np.concatenate([[0.0], np.cumsum(np.asarray(fractions, dtype=float))]), 0.0, 1.0)
    edges[-1] = 1.0  # the horizon's end, not the sum's round-off above it
    n = edges.size - 1
    return [(float(edges[max(k - 1, 0)]), float(edges[min(k + 2, n)])) for k in np.flatnonzero(np.asarray(excess) > level)]


def merged_spans(spans: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """``spans`` sorted, overlapping ones merged.

    Parameters
    ----------
    spans : list of tuple of (float, float)
        ``(s0, s1)`` fractions of the horizon.

    Returns
    -------
    list of tuple of (float, float)
        Disjoint, increasing.
    """
    out: list[tuple[float, float]] = []
    for s0, s1 in sorted(spans):
        if out and s0 <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], s1))
        else:
            out.append((s0, s1))
    return out


def checked_spans(spans: Any) -> list[tuple[float, float]]:
    """``spans`` as pairs of floats ``0 <= s0 <= s1 <= 1`` (fractions of the horizon), checked up front.

    Parameters
    ----------
    spans : iterable of pairs of float
        ``(s0, s1)`` per part of the horizon.

    Returns
    -------
    list of tuple of (float, float)

    Raises
    ------
    InputError
        Naming ``bound_spans`` and the pair that is not two numbers with ``0 <= s0 <= s1 <= 1``.
    """
    out = []
    try:
        pairs = list(spans)
    except TypeError:
        raise InputError(f"bound_spans: expected pairs (s0, s1) of fractions of the horizon, got {spans!r}") from None
    for pair in pairs:
        try:
            s0, s1 = (float(v) for v in pair)
        except (TypeError, ValueError):
            raise InputError(f"bound_spans: expected a pair (s0, s1) of numbers, got {pair!r}") from None
        if not 0.0 <= s0 <= s1 <= 1.0:
            raise InputError(f"bound_spans: expected 0 <= s0 <= s1 <= 1 (fractions of the horizon), got {pair!r}")
        out.append((s0, s1))
    return out
