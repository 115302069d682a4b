"""The coupled convergence check of the shipped ``l1_ilc`` recomputed from its exports (slow: the full run, ~1 min).

Independent: the (3 N, 3 N) lifted map assembled with :func:`scipy.linalg.toeplitz` from the
exported MIMO impulse responses and the estimator matrices, ``sigma_max`` by
:func:`scipy.linalg.svdvals` (gtmodel: ARPACK on a linear operator); agreement to 1e-6.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from gtmodel.problems import run_problem

from ...conftest import PROBLEMS_DIR

TOL = 1e-6
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def ilc(tmp_path_factory):
    out = tmp_path_factory.mktemp("l1_ilc_coupled")
    outcome = run_problem(PROBLEMS_DIR / "l1_ilc.toml", out)
    return outcome.summary, np.load(out / "ilc_lifted.npz"), np.load(out / "ilc_estimators.npz"), out


@pytest.mark.parametrize("case", ["1", "2A"])
def test_coupled_sigma_max_from_the_exports(ilc, case):
    s, lifted, est, _ = ilc
    c = s["cases"][case]
    n = lifted["L"].shape[0]
    T = np.zeros((3 * n, 3 * n))
    z = np.zeros(n)
    for j in range(3):
        for l in range(3):
            if c["signal"] == "actuator":
                block = scipy.linalg.toeplitz(lifted["h_actuator"][:, l], z) if l == j else 0.0
            elif l < 2:
                block = (est["F_kin_complementary"][l] @ scipy.linalg.toeplitz(lifted["h_kin"][:, l, j], z)
                         + est["F_acc_complementary"][l] @ scipy.linalg.toeplitz(lifted["h_acc"][:, l, j], z))
            else:
                block = scipy.linalg.toeplitz(lifted["h_kin"][:, l, j], z)
            T[l * n:(l + 1) * n, j * n:(j + 1) * n] = block
    Qb, Lb = np.kron(np.eye(3), lifted[f"Q_{case}"]), np.kron(np.eye(3), lifted["L"])
    sigma = scipy.linalg.svdvals(Qb @ (np.eye(3 * n) - Lb @ T))[0]
    assert sigma == pytest.approx(c["coupled_check"]["sigma_max"], abs=TOL)




def test_convergence_plot_is_written(ilc):
    assert (ilc[3] / "ilc_convergence.png").stat().st_size > 0
