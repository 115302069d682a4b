"""Re-use between calibration calls (issue 17, item 4): shared graphs, cached alignment,
evaluators and start rank checks give the same result as a first, uncached call."""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.calibration.kinematic import CalibrationProblem, calibrate
from gtmodel.errors import ModelError

from ._l1_data import l1_poses, nominal


@pytest.fixture(scope="module")
def data():
    return l1_poses(seed=3)


def test_second_problem_shares_graphs_and_equals_first(data):
    """Two problems of equal structure share the graphs; both give bit-identical results
    (checked against each other and against a repeated solve on the cached data set)."""
    q, T = data
    first = CalibrationProblem(nominal())
    r1 = first.solve(q, T)
    second = CalibrationProblem(nominal())
    r2 = second.solve(q, T)
    r3 = second.solve(q, T)  # alignment, evaluators and rank check from the caches
    assert second._groups is first._groups
    assert r1.success and r2.success and r3.success
    np.testing.assert_array_equal(r1.parameter_vector, r2.parameter_vector)
    np.testing.assert_array_equal(r2.parameter_vector, r3.parameter_vector)
    np.testing.assert_array_equal(r2.residuals, r3.residuals)
    assert r2.cost == r3.cost and r2.std == r3.std
    np.testing.assert_array_equal(r2.rotation, r3.rotation)


def test_other_start_is_aligned_again(data):
    """A different start vector on the same data is aligned anew (the cache keys on it):
    equal to a fresh problem's result for that start."""
    q, T = data
    p0 = nominal().parameter_vector() + 1e-4
    cached = CalibrationProblem(nominal())
    cached.solve(q, T)
    r_cached = cached.solve(q, T, start=p0)
    r_fresh = CalibrationProblem(nominal()).solve(q, T, start=p0)
    np.testing.assert_array_equal(r_cached.parameter_vector, r_fresh.parameter_vector)
    np.testing.assert_array_equal(r_cached.translation, r_fresh.translation)


def test_singular_problem_raises_every_time(data):
    """The rank check is cached only when it passes: a singular problem (one pose
    repeated) raises on the second call too."""
    q, T = data
    q1, T1 = np.repeat(q[:1], 40, axis=0), np.repeat(T[:1], 40, axis=0)
    model = nominal()
    with pytest.raises(ModelError, match="singular"):
        calibrate(model, q1, T1, align=False)
    with pytest.raises(ModelError, match="singular"):
        calibrate(model, q1, T1, align=False)


def test_changed_data_in_place_is_a_new_data_set(data):
    """The last data set is recognised by value, not identity: the caller's array changed
    in place gives the result of a fresh problem on the new values (checked against it)."""
    q, T = data
    T2 = T.copy()
    problem = CalibrationProblem(nominal())
    problem.solve(q, T2)
    T2[:, 2] += 1e-4 * np.sin(np.arange(len(T2)))
    r_cached = problem.solve(q, T2)
    r_fresh = CalibrationProblem(nominal()).solve(q, T2.copy())
    np.testing.assert_array_equal(r_cached.parameter_vector, r_fresh.parameter_vector)
