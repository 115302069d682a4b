"""Violations of declared bounds on a closed loop's plant, per variable (states, inputs, outputs).

A loop controller's check (:func:`gtmodel.problems.loop_check.closed_loop_check`) counts, for
every variable with a declared bound (the model's and the reference problem's: a state such as
a motor current, an algebraic variable or output, an input), the samples beyond the bound and
the largest excess. An excess up to :data:`EXCESS_TOLERANCE` of the bound's size (``|bound|``,
or the bounds' range for a bound of 0) is tolerated: the plant is a simulation with a
mismatch, and a constraint held to 1 % is held; beyond it the check fails.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["EXCESS_TOLERANCE", "TARGET_MARGIN", "BoundExcess", "aimed", "bound_report", "bound_size"]

#: Largest excess over a declared bound that the check tolerates, relative to the bound's size.
EXCESS_TOLERANCE = 0.01
#: How far inside each declared bound the loop controllers aim (the MPC's backed-off rows, the tracking law's
#: projection), relative to the bound's size: the check's tolerance, kept for what no model predicts (the first
#: periods of a mismatched plant, before an error has been measured: the drive family's controllers overshot by
#: 1.07-1.64 % aiming at the bounds themselves, issue 65).
TARGET_MARGIN = EXCESS_TOLERANCE


@dataclass
class BoundExcess:
    """The excess of one variable over its declared bounds in a run.

    Parameters
    ----------
    name : str
        Scalar variable name.
    lb, ub : float
        The declared bounds (``-inf`` / ``inf``: none).
    excess : float
        Largest ``max(lb - v, v - ub, 0)`` over the samples (``inf`` for a non-finite value).
    relative : float
        ``excess`` over the bound's size (``|bound|`` of the side exceeded, or the range
        ``ub - lb`` for a bound of 0, else 1).
    samples : int
        Samples beyond the bound by more than :data:`EXCESS_TOLERANCE` (relative).
    value : float
        The value at the largest excess, or where the bounds held, the value nearest a bound (relative to its
        size; NaN when there are no samples).
    limit : float, optional
        The bound that ``value`` is beyond or nearest (``lb`` or ``ub``; NaN when unknown).
    signed : float, optional
        ``value``'s distance beyond ``limit`` over the bound's size: positive beyond it, negative inside
        (``-0.017``: 1.7 % inside); ``relative`` is its positive part (NaN when unknown).
    time : float, optional
        When ``value`` was reached [s] (NaN when the samples had no times).
    """

    name: str
    lb: float
    ub: float
    excess: float
    relative: float
    samples: int
    value: float
    limit: float = math.nan
    signed: float = math.nan
    time: float = math.nan

    @property
    def beyond_tolerance(self) -> bool:
        """Whether the excess exceeds :data:`EXCESS_TOLERANCE` of the bound's size."""
        return not self.relative <= EXCESS_TOLERANCE

    def line(self) -> str:
        """One summary line: the bounds, the value nearest or furthest beyond them with its limit, percent and time,
        and the samples beyond 1 %.

        Returns
        -------
        str
            E.g. ``"ind.i in [-15, 15]: 15.355 at t = 0.124 s, limit 15, +2.37 % (beyond 1 %; 12 samples)"``, or
            ``"... 9.83 at t = 0.2 s, limit 10, -1.7 % (held)"``.
        """
        head = f"{self.name} in [{self.lb:g}, {self.ub:g}]"
        if not math.isfinite(self.excess):  # a diverged plant (its states not finite): no figure to print
            return f"{head}: not finite on the plant (diverged)"
        if not math.isfinite(self.value):
            return f"{head}: no samples"
        when = f" at t = {self.time:.4g} s" if math.isfinite(self.time) else ""
        limit = f", limit {self.limit:g}, {100 * self.signed:+.3g} %" if math.isfinite(self.signed) else ""
        if self.beyond_tolerance:
            verdict = f"beyond {100 * EXCESS_TOLERANCE:g} %; excess {self.excess:.4g}, {self.samples} samples beyond {100 * EXCESS_TOLERANCE:g} %"
        else:
            verdict = "held" if self.excess <= 0 else f"within the {100 * EXCESS_TOLERANCE:g} % tolerance"
        return f"{head}: {self.value:.6g}{when}{limit} ({verdict})"

    def to_dict(self) -> dict[str, float | int | str | bool | None]:
        """The figures as JSON-able values (a ``summary.json`` entry; non-finite numbers as None).

        Returns
        -------
        dict
            ``name``, ``lb``, ``ub``, ``value``, ``limit``, ``percent`` (``100 * signed``), ``time`` [s], ``excess``,
            ``samples`` beyond the tolerance and ``held`` (within :data:`EXCESS_TOLERANCE`).
        """
        def num(v: float) -> float | None:
            return float(v) if math.isfinite(v) else None

        return {"name": self.name, "lb": num(self.lb), "ub": num(self.ub), "value": num(self.value), "limit": num(self.limit),
                "percent": num(100 * self.signed), "time": num(self.time), "excess": num(self.excess), "samples": int(self.samples),
                "held": not self.beyond_tolerance}


def bound_size(bound: float, lb: float, ub: float) -> float:
    """The size a bound's excess is relative to: ``|bound|``, or for a bound of 0 the range ``ub - lb`` (else 1).

    Parameters
    ----------
    bound : float
        The side (``lb`` or ``ub``).
    lb, ub : float
        Both sides (``-inf`` / ``inf``: none).

    Returns
    -------
    float
        Positive.
    """
    if bound != 0 and math.isfinite(bound):
        return abs(bound)
    return ub - lb if math.isfinite(lb) and math.isfinite(ub) and ub > lb else 1.0


def aimed(lb: float, ub: float) -> tuple[float, float]:
    """The bounds a controller aims at: each finite side :data:`TARGET_MARGIN` of its size inside the declared one.

    Parameters
    ----------
    lb, ub : float
        The declared bounds (``-inf`` / ``inf``: none).

    Returns
    -------
    tuple of float
        ``(lb', ub')``, never crossing (their middle where the margins would).
    """
    lo = lb + TARGET_MARGIN * bound_size(lb, lb, ub) if math.isfinite(lb) else lb
    hi = ub - TARGET_MARGIN * bound_size(ub, lb, ub) if math.isfinite(ub) else ub
    return (lo, hi) if lo <= hi else ((lb + ub) / 2, (lb + ub) / 2)


def bound_report(values: dict[str, np.ndarray], lb: dict[str, float], ub: dict[str, float],
                 times: np.ndarray | dict[str, np.ndarray] | None = None) -> list[BoundExcess]:
    """The excess of every bounded variable over its bounds, with the value nearest or furthest beyond them and when.

    Parameters
    ----------
    values : dict of str to numpy.ndarray
        ``(K,)`` samples by scalar name (variables without a bound are skipped).
    lb, ub : dict of str to float
        Declared bounds by name (a name with either is reported).
    times : numpy.ndarray or dict of str to numpy.ndarray, optional
        ``(K,)`` the samples' times [s], shared or by name (default none: :attr:`BoundExcess.time` NaN).

    Returns
    -------
    list of BoundExcess
        One per bounded variable present in ``values``, in the order of ``lb``.
    """
    out = []
    for name in lb:
        if name not in values:
            continue
        v = np.asarray(values[name], dtype=float).reshape(-1)
        lo, hi = float(lb[name]), float(ub.get(name, math.inf))
        size_lo, size_hi = bound_size(lo, lo, hi), bound_size(hi, lo, hi)
        with np.errstate(invalid="ignore"):
            side_lo, side_hi = (lo - v) / size_lo, (v - hi) / size_hi  # > 0 beyond; -inf for an infinite bound
            signed = np.where(~np.isfinite(v), np.inf, np.maximum(side_lo, side_hi))
        if not v.size:
            out.append(BoundExcess(name=name, lb=lo, ub=hi, excess=0.0, relative=0.0, samples=0, value=math.nan))
            continue
        k = int(np.argmax(signed))
        rel = np.maximum(signed, 0.0)
        t = times.get(name) if isinstance(times, dict) else times
        when = float(np.asarray(t, dtype=float).reshape(-1)[k]) if t is not None and np.size(t) == v.size else math.nan
        limit = lo if np.isfinite(v[k]) and side_lo[k] >= side_hi[k] else hi
        excess = math.inf if not np.isfinite(v[k]) else max(lo - v[k], v[k] - hi, 0.0)
        out.append(BoundExcess(name=name, lb=lo, ub=hi, excess=float(excess), relative=float(rel[k]),
                               samples=int(np.count_nonzero(rel > EXCESS_TOLERANCE)), value=float(v[k]),
                               limit=float(limit) if math.isfinite(limit) else math.nan,
                               signed=float(signed[k]) if np.isfinite(signed[k]) else (math.inf if signed[k] > 0 else math.nan),
                               time=when))
    return out
