"""The thesis' form of the tool-position Kalman filter, model (7.21) with z_kin as input (Dressler (2012), eqs. 7.19-7.22).

Independent references: the simulated plant (python-control ``forced_response`` of the structure
(6.14)) for the model (6.13) of :meth:`ToolStructure.kinematic_model`; python-control's
``dlqe`` for the gain (its ``L`` is the predictor gain ``A P C^T (C P C^T + R)^-1`` of (7.22));
the literal forward-Euler differences of the model's output for the extension (7.20)-(7.21);
the filter run sample by sample for the lifted matrices.
"""

from __future__ import annotations

import control
import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.estimation import ToolStructure
from gtmodel.estimation.filters.model_kalman import ModelKalman, extend_model

DT = 0.004


@pytest.fixture(scope="module")
def models():
    return ToolStructure().kinematic_model(DT)


def _square_wave_kinematic(n=300):
    """A smooth 1 mm move in x and 2 mm in y, at rest at both ends (m)."""
    s = np.clip((np.arange(n) - 50) / 150.0, 0.0, 1.0)
    p = s**3 * (10 - 15 * s + 6 * s**2)
    return np.column_stack([1e-3 * p, 2e-3 * p])


@pytest.mark.parametrize("j", [0, 1])
def test_kinematic_model_is_the_simulated_plant(models, j):
    st = ToolStructure()
    zk = _square_wave_kinematic()
    a_kin = np.zeros_like(zk)
    a_kin[1:-1] = (zk[2:] - 2 * zk[1:-1] + zk[:-2]) / DT**2
    t = np.arange(len(zk)) * DT
    d = np.asarray(control.forced_response(st.discrete(DT), t, a_kin.T).outputs)[:2].T  # the plant's structure
    A, B, C = models[j]
    u = np.concatenate([zk[2:, j], [zk[-1, j]] * 2])  # u(t) = z_kin(t + 2)
    x = np.linalg.solve(np.eye(5) - A, B) * zk[0, j]
    z = []
    for k in range(len(zk)):
        z.append(C @ x)
        x = A @ x + B * u[k]
    assert np.max(np.abs(np.array(z) - (zk[:, j] + d[:, j]))) < 1e-12
    assert np.max(np.abs(d[:, j])) > 1e-7  # the deflection is there to be modelled


def test_extension_is_the_forward_euler_of_7_20(models):
    A, B, C = models[0]
    Ab, Bb, Cb = extend_model(A, B, C, DT)
    u = _square_wave_kinematic()[2:, 0]
    x = np.zeros(7)
    z, xv, xa = [], [], []
    for k in range(len(u)):
        z.append(Cb[0] @ x), xv.append(x[5]), xa.append(Cb[1] @ x)
        x = Ab @ x + Bb * u[k]
    z, xv, xa = map(np.array, (z, xv, xa))
    assert np.allclose(xv[1:], np.diff(z) / DT, atol=1e-12)
    assert np.allclose(xa[2:], np.diff(z, 2) / DT**2, atol=1e-9)


@pytest.mark.parametrize("j", [0, 1])
@pytest.mark.parametrize("r", [1e-14, 1e-8])
def test_gain_is_dlqe_predictor_gain(models, r, j):
    kf = ModelKalman(models, DT, 0.07**2, r, lookahead=2)
    Ab, cy = kf.Abar[j], kf.Cbar[j][1:2]
    L, P, _ = control.dlqe(Ab, np.eye(7), cy, r * np.eye(7), np.array([[0.07**2]]))
    assert np.allclose(kf.K[j], np.asarray(L).reshape(-1), rtol=1e-6, atol=1e-12)
    assert np.allclose(kf.P[j], P, rtol=1e-6, atol=1e-18)


def test_lifted_matrices_are_the_filter(models):
    kf = ModelKalman(models, DT, 0.07**2, 1e-10, lookahead=2)
    n = 120
    rng = np.random.default_rng(0)
    zk, am = 1e-3 * rng.normal(size=(n, 2)), rng.normal(size=(n, 2))
    f_kin, f_acc = kf.lifted(n)
    lifted = np.column_stack([f_kin[j] @ zk[:, j] + f_acc[j] @ am[:, j] for j in range(2)])
    assert np.allclose(lifted, kf.estimate(zk, am), atol=1e-15)


def test_tuned_filter_recovers_the_exact_model(models):
    """With the exact model (6.13) the estimate follows the true position (the accelerometer only corrects model errors)."""
    st = ToolStructure()
    zk = _square_wave_kinematic()
    a_kin = np.zeros_like(zk)
    a_kin[1:-1] = (zk[2:] - 2 * zk[1:-1] + zk[:-2]) / DT**2
    out = np.asarray(control.forced_response(st.discrete(DT), np.arange(len(zk)) * DT, a_kin.T).outputs)
    z, a = zk + out[:2].T, a_kin + out[2:].T
    a_m = a + 0.07 * np.random.default_rng(1).normal(size=a.shape)
    kf, tuning = ModelKalman.tuned(models, DT, zk, a_m, z, lookahead=2, grid=(1e-16, 1e-12, 1e-8))
    err = np.sqrt(np.mean((z - kf.estimate(zk, a_m)) ** 2, axis=0))
    assert np.all(err < 0.05 * np.sqrt(np.mean((z - zk) ** 2, axis=0)))
    assert tuning["process_noise"] in tuning["grid"] and len(tuning["rms_m"]) == len(tuning["grid"])


@pytest.mark.parametrize("kwargs, match", [
    ({"models": []}, "models: expected one"),
    ({"measurement_noise": 0.0}, "measurement_noise: expected positive"),
    ({"process_noise": -1.0}, "process_noise"),
    ({"lookahead": -1}, "lookahead: expected a non-negative"),
    ({"models": [(np.eye(2), [1.0], [1.0, 0.0])]}, "B, C: expected 2 entries"),
])
def test_bad_input_names_the_argument(models, kwargs, match):
    args = {"models": models, "dt": DT, "measurement_noise": 0.07**2, "process_noise": 1e-10, "lookahead": 2} | kwargs
    with pytest.raises(InputError, match=match):
        ModelKalman(**args)
