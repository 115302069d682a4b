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

__all__ = ["EXCESS_TOLERANCE", "BoundExcess", "bound_report"]

#: Largest excess over a declared bound that the check tolerates, relative to the bound's size.
EXCESS_TOLERANCE = 0.01


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
        The value at the largest excess (NaN when none).
    """

    name: str
    lb: float
    ub: float
    excess: float
    relative: float
    samples: int
    value: float

    @property
    def beyond_tolerance(self) -> bool:
        """Whether the excess exceeds :data:`EXCESS_TOLERANCE` of the bound's size."""
        return not self.relative <= EXCESS_TOLERANCE

    def line(self) -> str:
        """One summary line: the bounds, the largest excess (absolute and relative) and the samples beyond 1 %.

        Returns
        -------
        str
        """
        if self.excess <= 0:
            return f"{self.name} in [{self.lb:g}, {self.ub:g}]: held"
        if not math.isfinite(self.excess):  # a diverged plant (its states not finite): no figure to print
            return f"{self.name} in [{self.lb:g}, {self.ub:g}]: not finite on the plant (diverged)"
        return (f"{self.name} in [{self.lb:g}, {self.ub:g}]: max excess {self.excess:.4g} ({100 * self.relative:.3g} %, value "
                f"{self.value:.6g}), {self.samples} samples beyond {100 * EXCESS_TOLERANCE:g} %")


def _size(bound: float, lb: float, ub: float) -> float:
    if bound != 0 and math.isfinite(bound):
        return abs(bound)
    return ub - lb if math.isfinite(lb) and math.isfinite(ub) and ub > lb else 1.0


def bound_report(values: dict[str, np.ndarray], lb: dict[str, float], ub: dict[str, float]) -> list[BoundExcess]:
    """The excess of every bounded variable over its bounds.

    Parameters
    ----------
    values : dict of str to numpy.ndarray
        ``(K,)`` samples by scalar name (variables without a bound are skipped).
    lb, ub : dict of str to float
        Declared bounds by name (a name with either is reported).

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
        below, above = np.maximum(lo - v, 0.0), np.maximum(v - hi, 0.0)
        size_lo, size_hi = _size(lo, lo, hi), _size(hi, lo, hi)
        rel = np.where(~np.isfinite(v), np.inf, np.maximum(below / size_lo, above / size_hi))
        exc = np.where(~np.isfinite(v), np.inf, np.maximum(below, above))
        k = int(np.argmax(rel)) if v.size else 0
        out.append(BoundExcess(name=name, lb=lo, ub=hi, excess=float(exc[k]) if v.size else 0.0, relative=float(rel[k]) if v.size else 0.0,
                               samples=int(np.count_nonzero(rel > EXCESS_TOLERANCE)), value=float(v[k]) if v.size else math.nan))
    return out
