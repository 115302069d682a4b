"""How an optimal motion is solved: IPOPT's objective scaling for the size of the cost.

Independent reference: the rule written out (factor times duration over cost, never above
the factor) on hand-computed values; the solves of the energy weights are in
tests/trajectory/test_point_to_point.py (slow).
"""

from __future__ import annotations

import math

import pytest

from gtmodel.trajectory.settings import objective_scaling


@pytest.mark.parametrize("objective, duration, expected", [
    (1.0, 1.0, 1e4),            # w = 0: the cost is the final time, the tuned factor unchanged
    (0.5, 1.0, 1e4),            # a cost below the duration: unchanged
    (2.0, 1.0, 5e3),            # the cost twice the duration: half the factor
    (28383.8, 1.0, 1e4 / 28383.8),  # l1_time_optimal, w = 1000, at the 1 s guess
    (-40.0, 2.0, 1e4 * 2.0 / 40.0),  # the size counts, not the sign
    (math.inf, 1.0, 1e4),       # a cost that cannot be evaluated: the factor
    (math.nan, 1.0, 1e4),
    (5.0, 0.0, 1e4),            # no duration to compare with: the factor
])
def test_objective_scaling(objective, duration, expected):
    assert objective_scaling(objective, duration, 1e4) == pytest.approx(expected, rel=1e-15)
