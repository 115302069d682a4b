"""The names of the former flat estimation modules stay importable from the package and its rooms."""

from __future__ import annotations

import pytest

import gtmodel.estimation
import gtmodel.estimation.filters

#: Names of the former module ``gtmodel.estimation.filters`` (README names it), now the filters room.
FILTERS_NAMES = ["FilterRun", "KalmanFilter", "ExtendedKalmanFilter", "cholesky_pivots"]


@pytest.mark.parametrize("name", FILTERS_NAMES)
def test_former_filters_module_names_are_in_the_filters_room(name):
    assert hasattr(gtmodel.estimation.filters, name)


def test_one_kalman_module_holds_every_kalman_filter():
    kalman = {"StationaryKalman", "KalmanFilter", "ExtendedKalmanFilter"}
    assert {getattr(gtmodel.estimation, n).__module__ for n in kalman} == {"gtmodel.estimation.filters.kalman"}


def test_package_exports_resolve():
    assert [n for n in gtmodel.estimation.__all__ if not hasattr(gtmodel.estimation, n)] == []
