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
