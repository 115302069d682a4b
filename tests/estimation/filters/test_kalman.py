"""Stationary Kalman filter (Dressler (2012), eqs. 7.19-7.22).

Independent references: scipy.linalg.solve_discrete_are on the per-direction problem in
rescaled states (python-control's dlqe calls SciPy when slycot is absent, as here, so
the second solve is posed differently: other matrices, same answer) and the Riccati
recursion iterated to its fixed point; a NumPy predictor-corrector loop for the CasADi
step; the closed-form bound of the model error for consistent measurements; the
lifted matrices against the operator; a simulated deflection with a fixed seed.
"""

from __future__ import annotations

import casadi as ca
import control
import numpy as np
import pytest
import scipy.linalg

from gtmodel.errors import InputError
from gtmodel.estimation.filters.complementary import THESIS_CUTOFFS_HZ, ComplementaryFilter
from gtmodel.estimation.filters.kalman import DEFAULT_JERK_NOISE, DEFAULT_POSITION_NOISE, StationaryKalman, tune_position_noise

DT = 0.004
#: The specification: the gain equals a second Riccati solver to 1e-9 (relative per entry).
RICCATI_TOLERANCE = 1e-9
#: CasADi step against NumPy (same arithmetic up to operation order).
ROUNDING = 1e-12
#: The default noises put the crossover near the complementary cut-offs.
CROSSOVER_TOLERANCE_HZ = 0.02


@pytest.fixture(scope="module")
def kf():
    return StationaryKalman()


def _direction(kf, j):
    s = [j, kf.d + j, 2 * kf.d + j]
    m = [j, kf.d + j]
    return s, m


@pytest.mark.parametrize("j", [0, 1])
def test_gain_equals_second_riccati_solver(kf, j):
    """control.dlqe (stacked SI problem) vs scipy.linalg.solve_discrete_are (direction j, states [p, v dt, a dt^2])."""
    s, m = _direction(kf, j)
    S = np.diag([1.0, DT, DT**2])
    Si = np.linalg.inv(S)
    a, c, q, r = S @ kf.A[np.ix_(s, s)] @ Si, kf.C[np.ix_(m, s)] @ Si, S @ kf.Q[np.ix_(s, s)] @ S.T, kf.R[np.ix_(m, m)]
    p_scaled = scipy.linalg.solve_discrete_are(a.T, c.T, q, r)
    gain_scaled = p_scaled @ c.T @ np.linalg.inv(c @ p_scaled @ c.T + r)
    np.testing.assert_allclose(kf.P[np.ix_(s, s)], Si @ p_scaled @ Si.T, rtol=RICCATI_TOLERANCE, atol=0)
    np.testing.assert_allclose(kf.M[np.ix_(s, m)], Si @ gain_scaled, rtol=RICCATI_TOLERANCE, atol=0)


def test_gain_is_the_fixed_point_of_the_riccati_recursion(kf):
    """Third method: the covariance recursion P <- A P A^T - A P C^T (C P C^T + R)^-1 C P A^T + Q converges to P."""
    p = kf.Q.copy()
    for _ in range(3000):
        k = kf.A @ p @ kf.C.T @ np.linalg.inv(kf.C @ p @ kf.C.T + kf.R)
        p = kf.A @ p @ kf.A.T - k @ kf.C @ p @ kf.A.T + kf.Q
    np.testing.assert_allclose(p, kf.P, rtol=1e-7, atol=0)


def test_predictor_gain_is_a_times_update_gain(kf):
    """dlqe's L = A P C^T S^-1 equals A M (closed form); the estimator's poles lie inside the unit circle."""
    # to 1e-9: the Riccati solution's round-off differs between BLAS builds and kernels (2.6e-10 relative
    # measured with NumPy 2.1.3's OpenBLAS under its auto-detected kernel, 1e-11 under Haswell's)
    np.testing.assert_allclose(kf.L, kf.A @ kf.M, rtol=1e-9, atol=1e-11 * np.abs(kf.L).max())
    assert np.abs(kf.poles).max() < 1.0


def test_model_matrices_closed_form(kf):
    """control.c2d of the triple integrator: A1 = [[1, dt, dt^2/2], [0, 1, dt], [0, 0, 1]], G1 = [dt^3/6, dt^2/2, dt]."""
    s, _ = _direction(kf, 0)
    np.testing.assert_allclose(kf.A[np.ix_(s, s)], [[1, DT, DT**2 / 2], [0, 1, DT], [0, 0, 1]], rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(kf.G[s, 0], [DT**3 / 6, DT**2 / 2, DT], rtol=1e-12)


def _numpy_filter(kf, z_kin, a_m, x0):
    x = x0.copy()
    out = []
    for zk, am in zip(z_kin, a_m):
        x_corr = x + kf.M @ (np.concatenate([zk, am]) - kf.C @ x)
        out.append(kf.H @ x_corr)
        x = kf.A @ x_corr
    return np.array(out), x


def test_step_function_equals_numpy_predictor_corrector(kf):
    """The CasADi step (via mapaccum in estimate) equals a NumPy predictor-corrector loop over a run."""
    rng = np.random.default_rng(3)
    zk, am = 1e-3 * rng.normal(size=(500, 2)), rng.normal(size=(500, 2))
    x0 = kf.initial_state(zk[0], am[0])
    expected, x_last = _numpy_filter(kf, zk, am, x0)
    z_hat, x_next = kf.run(zk, am)
    scale = np.abs(expected).max()
    np.testing.assert_allclose(z_hat, expected, rtol=0, atol=ROUNDING * scale)
    np.testing.assert_allclose(x_next[-1], x_last, rtol=ROUNDING, atol=ROUNDING * np.abs(x_last).max())


def test_step_function_signature(kf):
    f = kf.step_function()
    assert isinstance(f, ca.Function)
    assert f.name() == "kalman_step"
    assert [f.name_in(i) for i in range(2)] == ["x", "y"]
    assert [f.name_out(i) for i in range(2)] == ["x_next", "z_hat"]
    assert (f.size1_in(0), f.size1_in(1), f.size1_out(0), f.size1_out(1)) == (6, 4, 6, 2)
    assert kf.step_function() is f


@pytest.mark.parametrize("n", [1, 2, 50, 300])
def test_lifted_matrices_equal_the_operator(kf, n):
    """F_kin z_kin + F_acc a_m equals estimate(z_kin, a_m) on random signals (to rounding)."""
    rng = np.random.default_rng(n)
    zk, am = rng.normal(size=(n, 2)), rng.normal(size=(n, 2))
    f_kin, f_acc = kf.lifted(n)
    assert f_kin.shape == f_acc.shape == (2, n, n)
    lifted = np.column_stack([f_kin[j] @ zk[:, j] + f_acc[j] @ am[:, j] for j in range(2)])
    np.testing.assert_allclose(lifted, kf.estimate(zk, am), rtol=0, atol=ROUNDING * max(1.0, float(np.abs(f_acc).sum(axis=2).max())))


def test_default_crossovers_near_the_complementary_cutoffs(kf):
    """-3 dB of the z_kin path (brentq) at 4.50 Hz (x) and 2.63 Hz (y); |T_kin| there is 1/sqrt(2) (frequency response)."""
    fc = kf.crossover_hz()
    np.testing.assert_allclose(fc, THESIS_CUTOFFS_HZ, atol=CROSSOVER_TOLERANCE_HZ)
    t_kin, _ = kf.frequency_response(fc)
    np.testing.assert_allclose(np.abs(np.diag(t_kin)), 2**-0.5, rtol=1e-8)


def test_tuned_position_noise_gives_the_crossover():
    """tune_position_noise against the defaults (rounded to 4 digits) and against crossover_hz of its result."""
    sp = tune_position_noise(THESIS_CUTOFFS_HZ[0], jerk_noise=DEFAULT_JERK_NOISE[0])
    assert sp == pytest.approx(DEFAULT_POSITION_NOISE[0], rel=1e-2)
    assert StationaryKalman(position_noise=sp, jerk_noise=DEFAULT_JERK_NOISE[0], d=1).crossover_hz()[0] == pytest.approx(THESIS_CUTOFFS_HZ[0], abs=1e-6)


def test_nearly_complementary_at_the_resonances(kf):
    """For a consistent motion (a = -w^2 z) the estimate misses 1 - T_kin + w^2 T_acc: below 1 % at 7.4 Hz and 11.5 Hz."""
    f = np.array([0.5, 7.4, 11.5])
    t_kin, t_acc = kf.frequency_response(f)
    assert np.abs(1 - t_kin + t_acc * (2 * np.pi * f) ** 2).max() < 0.01


def test_perfect_estimate_for_consistent_measurements(kf):
    """z_kin = z, a_m = z'' of a smooth signal starting at rest: |z_hat - z| <= max|jerk| * (closed-form l1 bound).

    The samples obey x[k+1] = A x[k] + r[k] with the model residual
    r[k] = int_0^dt exp(A_c (dt - s)) B jerk(t_k + s) ds, so |r_i| <= G1_i max|jerk| (the
    kernel [s^2/2, s, 1] is positive). The initial state is exact (at rest), so the
    error of z_hat is the response of the estimator's error system (A - L C, output
    H (I - M C)) to r: bounded by max|jerk| sum_i G1_i sum_k |h_i[k]| (impulse responses
    by control.impulse_response).
    """
    t = np.arange(1500) * DT
    amp, w = 0.01, 2 * np.pi * 0.8
    z = amp * (1 - np.cos(w * t))  # at rest at t = 0
    a = amp * w**2 * np.cos(w * t)
    jerk_max = amp * w**3
    z2, a2 = np.column_stack([z, z]), np.column_stack([a, a])
    err = np.abs(kf.estimate(z2, a2) - z2).max(axis=0)
    bounds = []
    for j in range(2):
        s, _ = _direction(kf, j)
        eye = np.eye(3 * kf.d)
        sys = control.ss((kf.A - kf.L @ kf.C)[np.ix_(s, s)], np.eye(3), (kf.H @ (eye - kf.M @ kf.C))[np.ix_([j], s)], np.zeros((1, 3)), DT)
        resp = control.impulse_response(sys, T=t)
        h = np.asarray(resp.outputs).reshape(3, -1) * DT  # discrete impulse of area 1 -> unit pulse
        bounds.append(jerk_max * float(np.abs(h).sum(axis=1) @ kf.G[s, j]))
    np.testing.assert_array_less(err, bounds)  # the bound (27 um, 83 um here) is loose: the l1 norm of the worst case
    assert err.max() < 1e-6  # measured 0.06 um and 0.16 um: under the 1 um gauge resolution


def _deflection_case(amplitude_x: float, amplitude_y: float, seed: int = 7):
    """A smooth 10 mm motion plus damped oscillations (7.4 Hz x, 11.5 Hz y, zeta 0.05) starting
    smoothly at t = 1 s and again at 2 s; z'' by CasADi AD; accelerometer noise 0.07 m/s^2."""
    t = ca.SX.sym("t")

    def ring(tau, amp, f):
        w = 2 * np.pi * f
        return ca.if_else(tau > 0, amp * ca.exp(-0.05 * w * tau) * ca.sin(w * tau) * (1 - ca.exp(-((tau / 0.03) ** 2))), 0)

    motion = 0.005 * (1 - ca.cos(np.pi * t))
    z = ca.vertcat(motion + ring(t - 1, amplitude_x, 7.4) - ring(t - 2, amplitude_x, 7.4), motion + ring(t - 1, amplitude_y, 11.5) - ring(t - 2, amplitude_y, 11.5))
    acc = ca.jacobian(ca.jacobian(z, t), t)
    f = ca.Function("case", [t], [z, ca.vertcat(motion, motion), acc]).map(1000)
    z_true, z_kin, a = (np.asarray(v).T for v in f(np.arange(1000) * DT))
    a_m = a + np.random.default_rng(seed).normal(scale=0.07, size=a.shape)
    return z_true, z_kin, a, a_m


def _rms(e):
    return np.sqrt((e**2).mean(axis=0))


def test_noise_free_estimate_captures_most_of_a_deflection(kf):
    """Without accelerometer noise, a 30 um (x) / 60 um (y) deflection: the estimate's error is below half the kinematic one
    (|T_kin| at the resonances is 0.42 and 0.16)."""
    z_true, z_kin, a, _ = _deflection_case(30e-6, 60e-6)
    np.testing.assert_array_less(_rms(kf.estimate(z_kin, a) - z_true), 0.5 * _rms(z_kin - z_true))


def test_noisy_estimate_closer_to_the_truth_than_the_kinematic_position(kf):
    """Accelerometer noise 0.07 m/s^2 (seed 7): the Kalman estimate is closer to the truth than z_kin (RMS) once
    the deflection is larger than the estimate's own noise (about 45 um x, 170 um y RMS, see the module docstring):
    here 0.3 mm (x) and 2 mm (y) oscillation amplitudes (the y mode decays faster: its RMS is lower)."""
    z_true, z_kin, _, a_m = _deflection_case(0.3e-3, 2.0e-3)
    np.testing.assert_array_less(_rms(kf.estimate(z_kin, a_m) - z_true), _rms(z_kin - z_true))


def test_complementary_filter_closer_to_the_truth_than_the_kinematic_position():
    """The same with the zero-phase complementary filter, at 50 um (x) and 100 um (y) amplitudes (its noise: 6 um, 14 um)."""
    z_true, z_kin, _, a_m = _deflection_case(50e-6, 100e-6)
    np.testing.assert_array_less(_rms(ComplementaryFilter().estimate(z_kin, a_m) - z_true), _rms(z_kin - z_true))


BAD = [
    (dict(position_noise=-1e-5), "position_noise.*> 0"),
    (dict(position_noise=0.0), "position_noise"),
    (dict(jerk_noise=[1.0, -1.0]), "jerk_noise.*> 0"),
    (dict(accelerometer_noise=-0.07), "accelerometer_noise.*> 0"),
    (dict(accelerometer_noise=np.nan), "accelerometer_noise.*finite"),
    (dict(position_noise=[1e-4, 1e-4, 1e-4]), r"position_noise.*shape \(2,\)"),
    (dict(d=3), r"position_noise.*shape \(3,\)"),
    (dict(d=0), "d: expected a positive integer"),
    (dict(dt=0.0), "dt"),
    (dict(jerk_noise="loud"), "jerk_noise"),
]


@pytest.mark.parametrize("kwargs, match", BAD)
def test_bad_construction(kwargs, match):
    with pytest.raises(InputError, match=match):
        StationaryKalman(**kwargs)


BAD_CALLS = [
    (lambda k: k.estimate(np.zeros((10, 3)), np.zeros((10, 2))), "z_kin.*shape"),
    (lambda k: k.estimate(np.zeros((10, 2)), np.zeros((8, 2))), "a_m.*10 samples"),
    (lambda k: k.estimate(np.zeros((0, 2)), np.zeros((0, 2))), "z_kin"),
    (lambda k: k.estimate(np.zeros((5, 2)), [[0.0, np.inf]] * 5), "a_m.*sample 0, column 1"),
    (lambda k: k.run(np.zeros((5, 2)), np.zeros((5, 2)), x0=np.zeros(5)), r"x0.*\(6,\)"),
    (lambda k: k.lifted(0), "n"),
    (lambda k: k.frequency_response([130.0]), "f_hz.*Nyquist"),
    (lambda k: k.direction_system(2), "j: expected a direction index"),
    (lambda k: k.initial_state(np.zeros(3), np.zeros(2)), "z_kin0"),
    (lambda k: tune_position_noise(200.0), "crossover_hz"),
    (lambda k: tune_position_noise(-1.0), "crossover_hz"),
]


@pytest.mark.parametrize("call, match", BAD_CALLS)
def test_bad_calls(kf, call, match):
    with pytest.raises(InputError, match=match):
        call(kf)
