"""The NEES consistency test of the fusion study (Bar-Shalom, Li and Kirubarajan (2001), sec. 5.4.2).

Independent reference: the chi-square distribution (numpy draws, scipy quantiles) on synthetic
sequences, independent and AR(1)-correlated.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.estimation.fusion.runs import nees_test


def test_nees_test_accepts_a_consistent_independent_sequence():
    # chi2(9) draws: the time average lies in the chi2(N dof)/N band, tau ~ 1
    e = np.random.default_rng(0).chisquare(9, 4000)
    r = nees_test(e, 9)
    assert r["passed"] and r["autocorrelation_time"] < 1.5 and r["fraction_below_quantile"] == pytest.approx(0.95, abs=0.01)


def test_nees_test_rejects_an_optimistic_filter():
    # errors 20 % larger than the covariance says: NEES 1.44x
    e = 1.44 * np.random.default_rng(1).chisquare(9, 4000)
    assert not nees_test(e, 9)["passed"]


def test_nees_test_widens_the_band_for_correlated_samples():
    # sum of squares of 9 unit-variance AR(1) processes (rho = 0.98): consistent but correlated;
    # the effective sample count is ~ N (1 - rho) / (1 + rho^2) for the squares
    rng = np.random.default_rng(2)
    n, rho = 20000, 0.98
    x = np.zeros((n, 9))
    for k in range(1, n):
        x[k] = rho * x[k - 1] + np.sqrt(1 - rho**2) * rng.standard_normal(9)
    r = nees_test((x**2).sum(axis=1), 9)
    assert r["passed"] and r["autocorrelation_time"] > 10
    assert r["band"][1] - r["band"][0] > 3 * (r["independent_band"][1] - r["independent_band"][0])


BAD_NEES = [
    ("short", ([1.0], 9), r"nees: expected a 1-D array of at least 2 values"),
    ("negative", ([1.0, -1.0], 9), r"nees: expected non-negative values"),
    ("dof", ([1.0, 2.0], 0), r"dof"),
]


@pytest.mark.parametrize("case, args, match", BAD_NEES, ids=[c[0] for c in BAD_NEES])
def test_bad_nees_arguments(case, args, match):
    with pytest.raises(InputError, match=match):
        nees_test(*args)


