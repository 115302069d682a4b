"""The per-step reachability pass against today's (pre issue 17) pass, kept as a test helper.

Reference: ``tests/trajectory/_reference_reachability.py``, the old whole-grid ``.tolist()``
loop verbatim. Both do the same floating-point operations in the same order, so the profiles
are compared to 1e-12 relative (in practice bit for bit) on random instances and on the
package's own problems (whose optimum is also checked against IPOPT in test_path_constrained).
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.trajectory.path import StraightLine
from gtmodel.trajectory.path_constrained import PathConstrainedProblem, PathConstraints
from gtmodel.trajectory.path_constrained.reachability import _reachability
from tests.trajectory._reference_reachability import reference_reachability

REL_TOL = 1e-12  # same operations in the same order: rounding-identical


def random_instance(seed: int, points: int, viscous: bool, end_rows: bool):
    """Rows ``p a + r b + w sqrt(b) + e <= 0`` that rest (a = b = 0) satisfies (e < 0).

    One velocity-type row (p = 0), and rows with p of both signs; r >= 0, w of both signs
    when ``viscous``; a non-uniform grid with rest at both ends.
    """
    rng = np.random.default_rng(seed)
    s = np.concatenate([[0.0], np.sort(rng.uniform(0.0, 1.0, points - 1)), [1.0]])
    n, M = s.size, 5
    p = rng.uniform(0.2, 2.0, (n, M)) * np.array([0.0, 1.0, -1.0, 1.0, -1.0])
    r = rng.uniform(0.0, 1.0, (n, M))
    w = rng.uniform(-0.3, 0.3, (n, M)) if viscous else np.zeros((n, M))
    e = -rng.uniform(0.5, 2.0, (n, M))
    rest = np.zeros(n, dtype=bool)
    rest[[0, -1]] = True
    names = [f"row{j}" for j in range(M)]
    p_end, e_end = (np.array([1.0, -1.0]), np.array([-1.0, -1.0])) if end_rows else (None, None)
    return s, rest, p, r, w, e, names, p_end, e_end


def assert_same(new, old):
    assert new.ok == old.ok
    assert new.message == old.message
    assert new.index == old.index
    assert new.splits == old.splits
    if old.ok:
        np.testing.assert_allclose(new.b, old.b, rtol=REL_TOL, atol=0.0)
        np.testing.assert_allclose(new.a, old.a, rtol=REL_TOL, atol=1e-300)
        np.testing.assert_array_equal(new.uncertified, old.uncertified)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("points", [2, 37, 400])
@pytest.mark.parametrize("viscous", [False, True])
@pytest.mark.parametrize("end_rows", [False, True])
def test_random_instances_equal_old_pass(seed, points, viscous, end_rows):
    """Reference: the old pass on the same random rows (rounding-identical)."""
    args = random_instance(seed, points, viscous, end_rows)
    new, old = _reachability(*args), reference_reachability(*args)
    assert old.ok  # feasible by construction (rest satisfies every row)
    assert_same(new, old)


def test_infeasible_instance_same_message():
    """Reference: the old pass; a row forbidding any acceleration from rest fails both at the same point."""
    s, rest, p, r, w, e, names, p_end, e_end = random_instance(0, 50, False, False)
    e[20:, 1] = 0.5  # p > 0 row: a <= -0.5 / p < 0 everywhere from point 20
    e[20:, 3] = 0.5
    new, old = _reachability(s, rest, p, r, w, e, names), reference_reachability(s, rest, p, r, w, e, names)
    assert not old.ok
    assert_same(new, old)


def _trapezoid():
    line = StraightLine([0.0, 0.0, 0.0], [0.8, 0.3, -0.2])
    return PathConstrainedProblem(line, PathConstraints(tcp_velocity_limit=1.0, tcp_acceleration_limit=5.0), constrain_end=False)


def _l1_viscous():
    line = StraightLine([-0.2, 2.75, -0.4], [0.2, 3.0, -0.6], robot="L1")
    return PathConstrainedProblem(line, PathConstraints(force_limit=450.0), robot="L1")


@pytest.mark.parametrize("make", [_trapezoid, _l1_viscous], ids=["trapezoid", "l1_viscous"])
def test_package_problems_equal_old_pass(make):
    """Reference: the old pass on the rows of the benchmark cases (300 points)."""
    gp = make().gridded(300)
    p, r, w, e, names, p_end, e_end = gp.one_sided()
    args = (gp.s, gp.rest, p, r, w, e, names, p_end, e_end)
    assert_same(_reachability(*args), reference_reachability(*args))
