"""Tests of the NumPy column-pivoted QR of the dummy-derivative choice.

Reference: LAPACK's ``dgeqp3`` through :func:`scipy.linalg.qr` (``pivoting=True``), a peer
implementation of the same algorithm.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from gtmodel.modeling.structure.pivoting import pivoted_qr


@pytest.mark.parametrize("shape", [(1, 4), (2, 2), (3, 5), (4, 3), (6, 6)])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_pivoted_qr_matches_lapack(shape, seed):
    G = np.random.default_rng(seed).normal(size=shape)
    _, R, piv = sla.qr(G, pivoting=True, mode="economic")
    diag, order = pivoted_qr(G)
    np.testing.assert_allclose(diag, np.abs(np.diag(R)), rtol=1e-12, atol=1e-14)
    np.testing.assert_array_equal(order, piv)


@pytest.mark.parametrize(
    "G, first",
    [([[1.0, 1.0, 0.0], [0.0, 0.0, 1.0]], [0, 2]), ([[0.0, 2.0], [0.0, 0.0]], [1, 0]), ([[0.0, 0.0]], [0, 1])],
    ids=["tie-to-first", "zero-column-last", "all-zero"],
)
def test_pivoted_qr_ties_and_zero_columns(G, first):
    """Ties go to the first column (as LAPACK's idamax); a zero column comes last; a zero matrix keeps its order."""
    diag, order = pivoted_qr(np.array(G))
    np.testing.assert_array_equal(order[: len(first)], first)
    assert np.all(np.diff(diag) <= 1e-15)


def test_a_tie_within_round_off_goes_to_the_column_first_in_g():
    """The two-mass drive's dummy-derivative block (problems/drive_two_mass.toml): at the fourth step
    columns 1 and 3 have norms equal but for round-off (0.577109856824761 and ...7612); the column first
    in G wins, which is also LAPACK dgeqp3's choice here (scipy.linalg.qr, the independent check)."""
    G = np.array([[1.0, 0, 0, 0, -20, 0], [0, 1, -1, 0, 1, 0], [0, 0, -1, 1, 0, 1], [0, 0, 0, 0, 0, 1]])
    _, piv = pivoted_qr(G)
    _, _, lapack = sla.qr(G, mode="economic", pivoting=True)
    assert list(piv[:4]) == [4, 5, 2, 1] == list(lapack[:4])


@pytest.mark.parametrize("order", [[0, 1], [1, 0]])
def test_equal_columns_keep_g_order(order):
    # two orthogonal unit columns tie exactly: the first in G is the first pivot, whichever it is
    G = np.eye(2)[:, order]
    assert list(pivoted_qr(G)[1]) == [0, 1]
