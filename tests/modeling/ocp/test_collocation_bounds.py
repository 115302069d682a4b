"""State bounds imposed on the collocation polynomial between its points (collocation_bounds, and the refinement's use).

Independent references: numpy's ``polyfit`` through the element's nodes (not the project's Lagrange basis) for the
rows' values; the polynomial sampled densely by ``CollocationData.evaluate`` for what the rows change in a solve.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.modeling import CollocationTranscription, Model, Optimization
from gtmodel.modeling.ocp.collocation_bounds import (bound_point_taus, checked_spans, elements_in_spans, excess_spans, interior_state_bounds,
                                                     merged_spans)

RADAU3 = np.array([0.0, (4 - np.sqrt(6)) / 10, (4 + np.sqrt(6)) / 10, 1.0])


@pytest.mark.parametrize("points, match", [(0, "positive integer"), (-2, "positive integer"), (2.5, "positive integer"),
                                           (True, "positive integer")])
def test_bound_points_must_be_a_positive_integer(points, match):
    with pytest.raises(InputError, match=match):
        bound_point_taus(points)


@pytest.mark.parametrize("spans, match", [(3, "pairs"), (["ab"], "pair"), ([(0.5, 0.2)], "s0 <= s1"), ([(0.0, 1.5)], "s1 <= 1"),
                                           ([(float("nan"), 0.5)], "s0 <= s1")])
def test_bound_spans_are_checked(spans, match):
    with pytest.raises(InputError, match=match):
        checked_spans(spans)


def test_rows_are_the_polynomial_through_the_nodes_at_the_midpoints():
    # two states, the second bounded; two elements of values at [0, Radau points]: the rows are numpy's cubic through
    # them at (j + 1/2) / 4, divided by the nominal 2
    rng = np.random.default_rng(3)
    values = rng.normal(size=(2, 4, 2))  # (element, node, state)
    X_all = ca.DM(values.transpose(1, 2, 0).reshape(8, 2))  # column k: node-major, the states of each node
    rows, lo, hi = interior_state_bounds(ca.SX(X_all), 2, RADAU3, np.array([-np.inf, -1.0]), np.array([np.inf, 3.0]),
                                         np.array([1.0, 2.0]), 4)
    taus = (np.arange(4) + 0.5) / 4
    expected = np.concatenate([np.polyval(np.polyfit(RADAU3, values[k, :, 1], 3), taus) / 2.0 for k in range(2)])
    assert np.allclose(np.array(ca.DM(rows)).ravel(), expected, atol=1e-12)
    assert np.array_equal(lo, np.full(8, -0.5)) and np.array_equal(hi, np.full(8, 1.5))


def test_rows_of_chosen_elements_only():
    # the same values as above, element 1 alone: the second half of the rows
    rng = np.random.default_rng(3)
    values = rng.normal(size=(2, 4, 2))
    X_all = ca.SX(ca.DM(values.transpose(1, 2, 0).reshape(8, 2)))
    args = (X_all, 2, RADAU3, np.array([-np.inf, -1.0]), np.array([np.inf, 3.0]), np.array([1.0, 2.0]), 4)
    both, one = (np.array(ca.DM(interior_state_bounds(*args, elements=e)[0])).ravel() for e in (None, np.array([1])))
    assert np.array_equal(one, both[4:])


# a mesh of fractions 0.1, 0.2, 0.3, 0.4 (edges 0, 0.1, 0.3, 0.6, 1): which elements overlap the spans, by hand
@pytest.mark.parametrize("spans, expected", [([(0.0, 0.05)], [0]), ([(0.1, 0.3)], [1]), ([(0.25, 0.65)], [1, 2, 3]),
                                             ([(0.0, 0.05), (0.9, 1.0)], [0, 3]), ([], [])])
def test_elements_in_spans(spans, expected):
    assert elements_in_spans(np.array([0.1, 0.2, 0.3, 0.4]), spans).tolist() == expected


def test_excess_spans_widen_each_marked_element_by_its_neighbours_and_merge():
    fractions = np.array([0.1, 0.2, 0.3, 0.4])
    spans = excess_spans(fractions, np.array([0.0, 0.02, 0.004, 0.0]), 0.005)  # element 1 marked: elements 0 to 2
    assert len(spans) == 1 and np.allclose(spans[0], (0.0, 0.6))
    assert merged_spans([(0.5, 0.7), (0.0, 0.2), (0.1, 0.3)]) == [(0.0, 0.3), (0.5, 0.7)]


def test_no_rows_without_a_bounded_state():
    rows, lo, hi = interior_state_bounds(ca.SX.sym("x", 4, 3), 1, RADAU3, np.array([-np.inf]), np.array([np.inf]), np.ones(1), 4)
    assert rows.numel() == 0 and lo.size == 0 and hi.size == 0


class Lag(Model):
    """x' = -x + u."""

    def __init__(self) -> None:
        super().__init__("lag")
        x, u = self.state("x"), self.input("u")
        self.equation(self.der(x), -x + u)


def solved(bound_points):
    """x' = -x + u from 0, |u| <= 24, x <= 0.8, pulled towards 1 on [0, 1] s, 4 elements of 3 Radau points."""
    m = Lag()
    opt = Optimization(m, final_time=1.0)
    x, u = m.variables("state")["x"], m.variables("input")["u"]
    opt.set_bounds(u, -24.0, 24.0)
    opt.set_bounds(x, -10.0, 0.8)
    opt.add_point_constraint(x, at="start", lb=0.0, ub=0.0)
    opt.set_objective(lagrange=(x - 1.0) ** 2 + 1e-4 * u**2)
    return CollocationTranscription(opt, elements=4, points=3, verify=False, bound_points=bound_points).solve()


def polynomial_max(result, taus):
    b = result.collocation.breaks()
    t = (b[:-1, None] + np.asarray(taus)[None, :] * np.diff(b)[:, None]).ravel()
    return float(np.max(result.collocation.evaluate(t)[0][:, 0]))


@pytest.fixture(scope="module")
def pair():
    return {n: solved(n) for n in (0, 4)}


def test_without_rows_the_polynomial_crosses_the_bound_between_the_points(pair):
    # the case the rows exist for: every collocation point keeps x <= 0.8, the polynomial between them does not
    res = pair[0]
    assert np.max(res.collocation.xc[:, :, 0]) <= 0.8 + 1e-7 and polynomial_max(res, np.linspace(0, 1, 401)) > 0.8 + 1e-3


def test_with_rows_the_polynomial_keeps_the_bound_at_them_and_nearly_between(pair):
    without, with_rows = pair[0], pair[4]
    assert with_rows.status.value == "optimal" and polynomial_max(with_rows, bound_point_taus(4)) <= 0.8 + 1e-7
    dense = np.linspace(0, 1, 401)
    assert polynomial_max(with_rows, dense) - 0.8 < 0.25 * (polynomial_max(without, dense) - 0.8)
