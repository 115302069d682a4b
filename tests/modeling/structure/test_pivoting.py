"""Tests of the column-pivoted QR of the dummy-derivative choice.

Reference: LAPACK's ``dgeqp3`` through :func:`scipy.linalg.qr` (``pivoting=True``); the
module calls the ``dgeqp3`` of NumPy's own OpenBLAS where NumPy ships one, which must give
the same pivots and diagonal, bit for bit (ties included), and falls back to SciPy's.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

import gtmodel.modeling.structure.pivoting as pivoting
from gtmodel.modeling.structure.pivoting import numpy_dgeqp3, pivoted_qr


@pytest.mark.parametrize("shape", [(1, 4), (2, 2), (3, 5), (4, 3), (6, 6)])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_pivoted_qr_matches_lapack(shape, seed):
    G = np.random.default_rng(seed).normal(size=shape)
    _, R, piv = sla.qr(G, pivoting=True, mode="economic")
    diag, order = pivoted_qr(G)
    np.testing.assert_allclose(diag, np.abs(np.diag(R)), rtol=1e-12, atol=1e-14)
    np.testing.assert_array_equal(order, piv)


def _tied(seed: int) -> np.ndarray:
    """A block with exactly tied columns (a repeated column, integer entries) and one near-tie."""
    rng = np.random.default_rng(seed)
    m, n = int(rng.integers(1, 7)), int(rng.integers(2, 9))
    G = np.round(rng.normal(size=(m, n)) * 3)
    G[:, -1] = G[:, 0]
    G[:, 1] = G[:, 0] * (1 + 1e-16 * seed)
    return G


@pytest.mark.skipif(numpy_dgeqp3() is None, reason="NumPy ships no OpenBLAS of its own here (SciPy's dgeqp3 is used)")
@pytest.mark.parametrize("seed", range(12))
def test_numpy_openblas_dgeqp3_is_scipys_bit_for_bit(seed):
    G = _tied(seed) if seed % 2 else np.random.default_rng(seed).normal(size=(5, 7))
    _, R, piv = sla.qr(G, pivoting=True, mode="economic")
    diag, order = pivoted_qr(G)
    assert order.tolist() == piv.tolist() and diag.tolist() == np.abs(np.diag(R)).tolist()


def test_without_numpys_openblas_scipy_is_used(monkeypatch):
    monkeypatch.setattr(pivoting, "_DGEQP3", None)
    G = _tied(3)
    _, R, piv = sla.qr(G, pivoting=True, mode="economic")
    diag, order = pivoted_qr(G)
    assert order.tolist() == piv.tolist() and diag.tolist() == np.abs(np.diag(R)).tolist()


@pytest.mark.parametrize("model, states", [
    ("problems/drive_two_mass.toml", ["ind.i", "emf.phi", "rotor.w", "load.w", "friction.phi_rel"]),
    ("tests/fixtures/user_models/two_mass_move.toml", None),
])
def test_tied_columns_keep_the_states_lapack_chooses(model, states):
    """The two-mass blocks hold columns whose norms tie but for round-off; the states are LAPACK's
    choice, which the shipped files name (tests/problems/test_drive_models.py; the fixture's MPC file
    names shaft.phi_rel among its error states)."""
    from gtmodel.problems import load_problem
    from ...conftest import REPO

    names = load_problem(REPO / model).declaration.optimization.model.flatten().x_names
    assert names == states if states is not None else "shaft.phi_rel" in names or any(n.endswith("shaft.phi_rel") for n in names)
