"""Single-mode dynamic stiffness per direction (8): FRF, fit, simulation, GP over poses (9)-(11).

Independent references: the closed-form FRF 1/(k - m w^2 + j c w), round trips on the
Table 16 values of Cvitanic (2021) (tests/reference/serial_kr500.toml), python-control's
``forced_response`` as a second simulation method and the static limit F/k, and a smooth
held-out function for the Gaussian-process interpolation. The GP pose inputs are
ILLUSTRATIVE (the thesis gives no coordinates of its Table 16 poses).
"""

from __future__ import annotations

import tomllib

import control
import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.robots.dynamic_stiffness import (
    DynamicStiffnessGP,
    fit_single_mode,
    simulate_single_mode,
    single_mode_frf,
)

from ..conftest import SHARED_REFERENCE

FRF_RELATIVE = 1e-10
FIT_RELATIVE = 1e-6  # noise-free round trip
NOISY_FIT_RELATIVE = 0.05  # 2 % complex noise on the FRF
SIM_RELATIVE = 0.01  # ZOH filter vs forced_response (linear interpolation), 10 kHz sampling
GP_TRAIN_RELATIVE = 0.01
GP_HELD_OUT_RELATIVE = 0.05

_REF = tomllib.loads((SHARED_REFERENCE / "serial_kr500.toml").read_text())["dynamic_stiffness"]
TABLE_16 = [(np.array(_REF["m_kg"][i]), np.array(_REF["c_Ns_per_m"][i]), np.array(_REF["k_MN_per_m"][i]) * 1e6) for i in range(12)]


def test_frf_matches_closed_form():
    """python-control's frequency response equals 1/(k - m w^2 + j c w)."""
    m, c, k = 166.5, 3261.3, 1.9e6
    f = np.linspace(1, 100, 50)
    w = 2 * np.pi * f
    np.testing.assert_allclose(single_mode_frf(m, c, k, f), 1 / (k - m * w**2 + 1j * c * w), rtol=FRF_RELATIVE)


@pytest.mark.parametrize("d", range(3), ids=["x", "y", "z"])
@pytest.mark.parametrize("pose", range(12))
def test_fit_round_trip_table_16(pose, d):
    """Fit (m, c, k) to the synthetic FRF of each Table 16 pose and direction (noise-free)."""
    m, c, k = TABLE_16[pose]
    fn = np.sqrt(k[d] / m[d]) / (2 * np.pi)
    f = np.linspace(0.3 * fn, 3 * fn, 200)
    res = fit_single_mode(f, single_mode_frf(m[d], c[d], k[d], f))
    assert res.success and res.status == "optimal"
    np.testing.assert_allclose([res.m, res.c, res.k], [m[d], c[d], k[d]], rtol=FIT_RELATIVE)


def test_fit_with_noise():
    """2 % complex noise (seeded): parameters within 5 %, standard deviations reported."""
    m, c, k = TABLE_16[0][0][0], TABLE_16[0][1][0], TABLE_16[0][2][0]
    fn = np.sqrt(k / m) / (2 * np.pi)
    f = np.linspace(0.3 * fn, 3 * fn, 300)
    H = single_mode_frf(m, c, k, f)
    rng = np.random.default_rng(3)
    Hn = H * (1 + 0.02 * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)))
    res = fit_single_mode(f, Hn)
    np.testing.assert_allclose([res.m, res.c, res.k], [m, c, k], rtol=NOISY_FIT_RELATIVE)
    assert np.all(res.std > 0) and np.all(np.isfinite(res.std))


def test_simulation_matches_forced_response_and_static_limit():
    """ZOH simulation vs python-control forced_response; a constant force settles at F/k."""
    m, c, k = TABLE_16[4]
    t = np.arange(0, 1.5, 1e-4)
    F = np.column_stack([np.sin(2 * np.pi * 12 * t) * 1000, np.full(t.size, 500.0), np.sign(np.sin(2 * np.pi * 3 * t)) * 200])
    x = simulate_single_mode(m, c, k, t, F)
    ref = np.column_stack(
        [control.forced_response(control.tf([1], [m[i], c[i], k[i]]), T=t, U=F[:, i]).outputs for i in range(3)]
    )
    np.testing.assert_array_less(np.max(np.abs(x - ref), axis=0), SIM_RELATIVE * np.max(np.abs(ref), axis=0))
    np.testing.assert_allclose(x[-1, 1], 500.0 / k[1], rtol=1e-3)


def _smooth(X):
    """A smooth positive held-out function of (x, y, z, A)."""
    return np.exp(0.3 * np.sin(2 * X[:, 0]) + 0.2 * X[:, 1] - 0.1 * X[:, 2] ** 2 + 0.15 * np.cos(X[:, 3]))


@pytest.mark.filterwarnings("ignore::sklearn.exceptions.ConvergenceWarning")  # noise-free data: noise level at its bound
def test_gp_reproduces_training_points_and_interpolates():
    """9 GPs: training points reproduced to 1 %, held-out smooth function to 5 %."""
    rng = np.random.default_rng(0)
    X = np.column_stack([rng.uniform(1.5, 2.5, 25), rng.uniform(-0.5, 1.5, 25), rng.uniform(0.6, 1.6, 25), rng.uniform(-np.pi / 2, np.pi / 2, 25)])
    base = _smooth(X)
    m = np.column_stack([200 * base, 100 * base, 250 * base])
    c = np.column_stack([4000 * base, 5000 * base, 300 * base])
    k = np.column_stack([2e6 * base, 5e6 * base, 1e6 * base])
    gp = DynamicStiffnessGP(X, m, c, k)
    pred = gp.predict(X)
    np.testing.assert_allclose(pred["k"], k, rtol=GP_TRAIN_RELATIVE)
    Xt = np.column_stack([rng.uniform(1.7, 2.3, 10), rng.uniform(-0.2, 1.2, 10), rng.uniform(0.8, 1.4, 10), rng.uniform(-1.0, 1.0, 10)])
    pt, std = gp.predict(Xt, return_std=True)
    np.testing.assert_allclose(pt["m"][:, 0], 200 * _smooth(Xt), rtol=GP_HELD_OUT_RELATIVE)
    np.testing.assert_allclose(pt["k"][:, 1], 5e6 * _smooth(Xt), rtol=GP_HELD_OUT_RELATIVE)
    assert np.all(std["c"] >= 0)


F_OK = np.linspace(5, 50, 20)
H_OK = single_mode_frf(200, 3000, 2e6, F_OK)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: fit_single_mode(F_OK[::-1], H_OK), "strictly increasing"),
        (lambda: fit_single_mode(np.r_[F_OK[:5], F_OK[4], F_OK[6:]], H_OK), "strictly increasing"),
        (lambda: fit_single_mode(-F_OK, H_OK), "positive frequencies"),
        (lambda: fit_single_mode(F_OK[:2], H_OK[:2]), "n >= 3"),
        (lambda: fit_single_mode(F_OK, H_OK[:-1]), "one value per frequency"),
        (lambda: fit_single_mode(F_OK, np.where(np.arange(20) == 3, np.nan, H_OK)), "H: non-finite value at index 3"),
        (lambda: fit_single_mode(F_OK, -H_OK), "non-positive"),
        (lambda: single_mode_frf(0.0, 3000, 2e6, F_OK), "m: expected a finite number > 0"),
        (lambda: single_mode_frf(200, 3000, -2e6, F_OK), "k: expected a finite number > 0"),
        (lambda: simulate_single_mode([1, 1], [1, 1, 1], [1, 1, 1], np.arange(5.0), np.zeros((5, 3))), r"m: expected shape \(3,\)"),
        (lambda: simulate_single_mode([1, 1, 1], [1, 1, 1], [1, 1, 1], np.r_[0, 1, 3.0], np.zeros((3, 3))), "equally spaced"),
        (lambda: simulate_single_mode([1, 1, 1], [1, 1, 1], [1, 1, 1], np.arange(5.0), np.zeros((5, 2))), r"F: expected shape \(5, 3\)"),
        (lambda: DynamicStiffnessGP(np.zeros((5, 3)), np.ones((5, 3)), np.ones((5, 3)), np.ones((5, 3))), r"X: expected shape \(N, 4\)"),
        (lambda: DynamicStiffnessGP(np.zeros((5, 3)), np.ones((5, 3)), np.ones((5, 3)), np.ones((5, 3)), n_inputs=2), r"X: expected shape \(N, 2\) with"),
        (lambda: DynamicStiffnessGP(np.zeros((5, 2)), np.ones((5, 3)), np.ones((5, 3)), np.ones((5, 3)), n_inputs=0), "n_inputs: expected a positive integer"),
        (lambda: DynamicStiffnessGP(np.random.default_rng(0).random((5, 4)), np.ones((5, 3)), np.ones((5, 3)), -np.ones((5, 3))), "k: expected finite positive"),
    ],
)
def test_bad_input(call, match):
    """Bad frequencies/FRF/parameters/shapes are refused with a message naming the argument."""
    with pytest.raises(InputError, match=match):
        call()
