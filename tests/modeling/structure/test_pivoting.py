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
