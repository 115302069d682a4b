"""Shared fixtures for the modelling-layer tests."""

from __future__ import annotations

import pytest

from gtmodel.modeling import solve

from ._builders import min_energy_problem


@pytest.fixture(scope="session")
def min_energy_result():
    """Radau solution of :func:`min_energy_problem` with 10 elements, 3 points."""
    return solve(min_energy_problem(), elements=10, points=3, scheme="radau")
