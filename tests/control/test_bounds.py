"""Declared bounds counted on a plant's samples (``gtmodel.control.bounds``): the summary line of each.

Independent check: the excess written out by hand for a sample table.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.control.bounds import bound_report


@pytest.mark.parametrize("values, line", [
    ([0.0, 1.0, -1.5], "i in [-2, 2]: -1.5 at t = 0.2 s, limit -2, -25 % (held)"),
    ([0.0, 2.5, 1.0], "i in [-2, 2]: 2.5 at t = 0.1 s, limit 2, +25 % (beyond 1 %; excess 0.5, 1 samples beyond 1 %)"),
    ([0.0, 2.01, 1.0], "i in [-2, 2]: 2.01 at t = 0.1 s, limit 2, +0.5 % (within the 1 % tolerance)"),
    ([0.0, np.nan, 0.0], "i in [-2, 2]: not finite on the plant (diverged)"),  # not 'max excess inf (inf %, value nan)'
], ids=["held", "exceeded", "tolerated", "diverged"])
def test_each_bound_says_what_the_plant_did(values, line):
    """Value, limit, percent and time written out by hand for three samples at 0, 0.1 and 0.2 s."""
    (report,) = bound_report({"i": np.array(values)}, {"i": -2.0}, {"i": 2.0}, times=np.array([0.0, 0.1, 0.2]))
    assert report.line() == line


def test_the_summary_entry_carries_the_figures():
    """The JSON entry of an exceeded upper bound: 15.355 of 15 at 0.124 s is +2.37 % (by hand), not held."""
    (report,) = bound_report({"ind.i": np.array([1.0, 15.355, -3.0])}, {"ind.i": -15.0}, {"ind.i": 15.0},
                             times={"ind.i": np.array([0.12, 0.124, 0.128])})
    entry = report.to_dict()
    assert entry == pytest.approx({"name": "ind.i", "lb": -15.0, "ub": 15.0, "value": 15.355, "limit": 15.0,
                                   "percent": 100 * 0.355 / 15, "time": 0.124, "excess": 0.355, "samples": 1, "held": False})


def test_a_one_sided_bound_reports_the_side_it_has():
    """A lower bound alone: the nearest sample's distance above it, negative (inside), by hand."""
    (report,) = bound_report({"x": np.array([3.0, 1.5])}, {"x": 1.0}, {})
    assert (report.limit, report.signed, report.value, np.isnan(report.time)) == (1.0, -0.5, 1.5, True)
