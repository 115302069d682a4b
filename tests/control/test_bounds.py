"""Declared bounds counted on a plant's samples (``gtmodel.control.bounds``): the summary line of each.

Independent check: the excess written out by hand for a sample table.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.control.bounds import bound_report


@pytest.mark.parametrize("values, line", [
    ([0.0, 1.0], "i in [-2, 2]: held"),
    ([0.0, 2.5], "i in [-2, 2]: max excess 0.5 (25 %, value 2.5), 1 samples beyond 1 %"),
    ([0.0, np.nan], "i in [-2, 2]: not finite on the plant (diverged)"),  # not 'max excess inf (inf %, value nan)'
], ids=["held", "exceeded", "diverged"])
def test_each_bound_says_what_the_plant_did(values, line):
    (report,) = bound_report({"i": np.array(values)}, {"i": -2.0}, {"i": 2.0})
    assert report.line() == line
