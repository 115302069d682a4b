"""Identification of actuator (eq. 6.11) and structural (eqs. 6.14-6.15) models from data.

Independent references: the generating models (thesis numbers from
``tests/reference/gantry_tau_L1.toml``) simulated by python-control (ZOH sampling
:func:`control.sample_system`, :func:`control.forced_response`), i.e. round trips
model -> simulated PRBS/step data -> identified model; the least-squares standard
deviations as the statistical yardstick with noise; :func:`control.sample_system` as the
peer of :func:`discrete_to_continuous`; the thesis' modes 14 and 103 Hz.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import control
import numpy as np
import pytest

from gtmodel.calibration.identification import (
    discrete_to_continuous,
    identify_actuator,
    identify_state_space,
    physical_from_state_space,
    prbs,
)
from gtmodel.errors import InputError, ModelError
from gtmodel.robots.actuator_dynamics import actuator_models, simulate
from gtmodel.robots.structural import PhysicalModel

REFERENCE = Path(__file__).parents[2] / "reference" / "gantry_tau_L1.toml"

#: Modes of the identified model against the thesis / generating model.
MODE_TOLERANCE_HZ = 0.5
#: Noise-free round trip: exact up to floating point (ARX lstsq, ERA SVD, logm).
EXACT_RTOL = 1e-6
#: With noise: estimates within this many standard deviations of the truth.
N_SIGMA = 4.0
#: 1 % output noise: M, D, K within this relative (Frobenius) error of the generating ones.
NOISY_MATRIX_RTOL = 0.05
#: Sampling time of the structural experiments [s] (Nyquist 250 Hz > 103 Hz mode).
DT_STRUCTURE = 0.002
#: Samples of the structural experiment (two MLS periods of 4095).
N_STRUCTURE = 8190
SEED = 20120


def _ref() -> dict:
    return tomllib.loads(REFERENCE.read_text())


def _reference_model() -> PhysicalModel:
    c = _ref()["compliance"]
    return PhysicalModel(c["M"], c["D"], c["K"])


def _structural_data(noise: float, seed: int = SEED):
    sysd = control.sample_system(_reference_model().to_state_space(), DT_STRUCTURE)
    u = prbs(N_STRUCTURE, bits=12, channels=2)
    t = np.arange(N_STRUCTURE) * DT_STRUCTURE
    y = control.forced_response(sysd, t, u.T).outputs.T
    if noise:
        y = y + noise * y.std(axis=0) * np.random.default_rng(seed).standard_normal(y.shape)
    return t, u, y


def _actuator_data(axis: int, kind: str, noise: float = 0.0, n: int = 2000):
    t = np.arange(n) * 0.004
    u = prbs(n, bits=8, hold=25) if kind == "prbs" else np.where(t >= 0.1, 1.0, 0.0)
    y = np.asarray(simulate(actuator_models("L1_dynamics_models")[axis], t, u).outputs)
    if noise:
        y = y + noise * np.random.default_rng(SEED + axis).standard_normal(n)
    return t, u, y


# ----------------------------------------------------------------------------- PRBS
def test_prbs_is_a_maximum_length_sequence():
    """+-1 values, period 2^bits - 1, one more +1 than -1 per period (MLS property)."""
    u = prbs(2 * 1023, bits=10)
    assert set(np.unique(u)) == {-1.0, 1.0}
    np.testing.assert_array_equal(u[:1023], u[1023:])
    assert np.sum(u[:1023]) == 1.0


def test_prbs_channels_hold_amplitude():
    """Channels are shifted copies (correlation -1/period), each value held 'hold' samples."""
    u = prbs(3 * 255, bits=8, hold=3, amplitude=0.5, channels=2)
    assert u.shape == (765, 2)
    assert set(np.unique(u)) == {-0.5, 0.5}
    np.testing.assert_array_equal(u[0::3], u[1::3])
    corr = np.mean(u[:, 0] * u[:, 1]) / 0.25
    assert abs(corr) < 0.02


# ----------------------------------------------------------------------------- actuators
@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("kind", ["prbs", "step"])
def test_actuator_identification_recovers_thesis_model(axis, kind):
    """Noise-free PRBS or step data of (6.11) give back a_i, b_i of the thesis."""
    ref = _ref()["actuators"]
    r = identify_actuator(*_actuator_data(axis, kind))
    assert r.status == "optimal" and r.success
    assert r.a == pytest.approx(ref["a"][axis], rel=EXACT_RTOL)
    assert r.b == pytest.approx(ref["b"][axis], rel=EXACT_RTOL)
    assert r.delay == 5 and r.dt == pytest.approx(0.004)


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_actuator_identification_with_noise_within_std(axis):
    """1 % output noise: a, b within N_SIGMA standard deviations of the truth."""
    ref = _ref()["actuators"]
    r = identify_actuator(*_actuator_data(axis, "prbs", noise=0.01))
    assert abs(r.a - ref["a"][axis]) < N_SIGMA * r.std_a
    assert abs(r.b - ref["b"][axis]) < N_SIGMA * r.std_b
    assert r.std_a > 0 and r.std_b > 0


def test_actuator_delay_estimation():
    """delay=None picks the true 5 samples by the smallest residual (noisy data)."""
    r = identify_actuator(*_actuator_data(2, "prbs", noise=0.01), delay=None, delay_range=(1, 12))
    assert r.delay == 5
    assert min(r.residuals_by_delay, key=r.residuals_by_delay.get) == 5
    assert set(r.residuals_by_delay) == set(range(1, 13))


def test_identified_actuator_transfer_function():
    """The identified TF has the generating bandwidth and the same impulse response."""
    r = identify_actuator(*_actuator_data(0, "prbs"))
    G, G0 = r.transfer_function(), actuator_models("L1_dynamics_models")[0]
    t = np.arange(200) * 0.004
    np.testing.assert_allclose(control.impulse_response(G, t).outputs, control.impulse_response(G0, t).outputs, atol=1e-9)


_T, _U, _Y = _actuator_data(0, "prbs", n=200)
_NAN = _Y.copy()
_NAN[50] = np.nan
_T_BACK = _T.copy()
_T_BACK[10] = _T_BACK[8]
_T_IRREG = _T.copy()
_T_IRREG[100:] += 0.001


@pytest.mark.parametrize(
    "args, kwargs, match",
    [
        ((_T, _U[:-1], _Y), {}, "u: expected 200 samples like t"),
        ((_T, _U, _Y[:-3]), {}, "y: expected 200 samples"),
        ((_T, _U, _NAN), {}, "y: sample 50, column 0 is not finite"),
        ((_T_BACK, _U, _Y), {}, "t: times must increase strictly"),
        ((_T_IRREG, _U, _Y), {}, "t: samples must be equally spaced"),
        ((_T[:20], _U[:20], _Y[:20]), {}, "too few samples"),
        ((_T, np.zeros(200), np.zeros(200)), {}, "singular regressor"),
        ((_T, _U, 2.0 * np.roll(_U, 4)), {}, "singular regressor"),  # y_(k-1) = 2 u_(k-5)
        ((_T, _U, _Y), {"delay": -1}, "delay"),
        ((_T, _U, _Y), {"delay": None, "delay_range": (5, 2)}, "delay_range"),
        ((_T, np.c_[_U, _U], _Y), {}, "single-channel"),
    ],
)
def test_actuator_bad_input(args, kwargs, match):
    """Bad data raise InputError naming the argument and the problem."""
    with pytest.raises(InputError, match=match):
        identify_actuator(*args, **kwargs)


# ----------------------------------------------------------------------------- structure
def test_structural_round_trip_noise_free():
    """Reference M, D, K -> ZOH PRBS data -> ARX + ERA -> physical form gives M, D, K back."""
    c = _ref()["compliance"]
    r = identify_state_space(*_structural_data(0.0))
    assert r.status == "optimal"
    p = r.to_physical()
    np.testing.assert_allclose(p.M, c["M"], rtol=EXACT_RTOL, atol=EXACT_RTOL * np.max(np.abs(c["M"])))
    np.testing.assert_allclose(p.D, c["D"], rtol=EXACT_RTOL, atol=EXACT_RTOL * np.max(np.abs(c["D"])))
    np.testing.assert_allclose(p.K, c["K"], rtol=EXACT_RTOL, atol=EXACT_RTOL * np.max(np.abs(c["K"])))
    np.testing.assert_allclose(p.modes().frequencies_hz, c["modes_hz_reported"], atol=MODE_TOLERANCE_HZ)


@pytest.fixture(scope="module")
def noisy_physical():
    return identify_state_space(*_structural_data(0.01)).to_physical()


def test_structural_round_trip_with_noise(noisy_physical):
    """1 % output noise: modes within 0.5 Hz of the generating ones and of the thesis."""
    c = _ref()["compliance"]
    truth = _reference_model()
    p = noisy_physical
    np.testing.assert_allclose(p.modes().frequencies_hz, truth.modes().frequencies_hz, atol=MODE_TOLERANCE_HZ)
    np.testing.assert_allclose(p.modes().frequencies_hz, c["modes_hz_reported"], atol=MODE_TOLERANCE_HZ)


@pytest.mark.parametrize("name", ["M", "D", "K"])
def test_structural_matrices_with_noise_are_close(noisy_physical, name):
    """1 % output noise: M, D, K within NOISY_MATRIX_RTOL (Frobenius) of the thesis' matrices."""
    ref = np.array(_ref()["compliance"][name])
    assert np.linalg.norm(getattr(noisy_physical, name) - ref) < NOISY_MATRIX_RTOL * np.linalg.norm(ref), name


def test_identified_poles_match_generating_poles():
    """Poles of the identified (continuous) model equal those of the reference state space."""
    r = identify_state_space(*_structural_data(0.0))
    poles = discrete_to_continuous(r.sys).poles()
    ref = _reference_model().to_state_space().poles()
    np.testing.assert_allclose(np.sort_complex(poles), np.sort_complex(ref), rtol=EXACT_RTOL)
    assert r.hankel_singular_values[4] < 1e-10 * r.hankel_singular_values[0]


def test_discrete_to_continuous_inverts_sample_system():
    """control.sample_system (ZOH) followed by discrete_to_continuous returns A, B."""
    sysc = _reference_model().to_state_space()
    back = discrete_to_continuous(control.sample_system(sysc, DT_STRUCTURE))
    np.testing.assert_allclose(back.A, sysc.A, rtol=1e-8, atol=1e-8 * np.max(np.abs(sysc.A)))
    np.testing.assert_allclose(back.B, sysc.B, rtol=1e-8, atol=1e-8 * np.max(np.abs(sysc.B)))


@pytest.mark.parametrize("name", ["M", "D", "K"])
@pytest.mark.parametrize("convention", ["thesis", "standard"])
def test_physical_form_is_invariant_to_state_coordinates(convention, name):
    """A random similarity transform of the reference state space gives the same M, D, K."""
    truth = _reference_model().with_convention(convention)
    sys = truth.to_state_space()
    T = np.random.default_rng(SEED).standard_normal((4, 4)) + 3 * np.eye(4)
    Ti = np.linalg.inv(T)
    moved = control.ss(T @ sys.A @ Ti, T @ sys.B, sys.C @ Ti, sys.D)
    p = physical_from_state_space(moved, convention=convention)
    np.testing.assert_allclose(getattr(p, name), getattr(truth, name), rtol=1e-8, atol=1e-8 * np.max(np.abs(getattr(truth, name))))


def test_physical_form_with_known_input_matrix():
    """With a non-identity B the same B recovers M, D, K (B removes the scale ambiguity)."""
    c = _ref()["compliance"]
    B = np.array([[2.0, 0.0], [0.5, 1.0]])
    truth = PhysicalModel(c["M"], c["D"], c["K"], B)
    p = physical_from_state_space(truth.to_state_space(), B=B)
    np.testing.assert_allclose(p.M, truth.M, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(p.K, truth.K, rtol=1e-9, atol=1e-9)


_TS, _US, _YS = _structural_data(0.0)
_YS_NAN = _YS.copy()
_YS_NAN[100, 1] = np.nan


@pytest.mark.parametrize(
    "args, kwargs, match",
    [
        ((_TS, _US[:-1], _YS), {}, "u: expected 8190 samples like t"),
        ((_TS, _US, _YS_NAN), {}, "y: sample 100, column 1 is not finite"),
        ((_TS[::-1], _US, _YS), {}, "t: times must increase"),
        ((_TS[:150], _US[:150], _YS[:150]), {}, "too few samples"),
        ((_TS, np.c_[_US[:, 0], _US[:, 0]], _YS), {}, "singular regressor"),
        ((_TS, _US, np.zeros_like(_YS)), {}, "identically zero"),
        ((_TS, _US, _YS), {"markov_length": 100}, "markov_length"),
        ((_TS, _US, _YS), {"arx_order": 0}, "arx_order"),
    ],
)
def test_state_space_bad_input(args, kwargs, match):
    """Bad data raise InputError naming the argument and the problem."""
    with pytest.raises(InputError, match=match):
        identify_state_space(*args, **kwargs)


@pytest.mark.parametrize(
    "sys, kwargs, err, match",
    [
        (control.ss(-np.eye(3), np.ones((3, 2)), np.ones((2, 3)), 0), {}, InputError, "expected 2n states"),
        (_reference_model().to_state_space(), {"B": np.eye(3)}, InputError, "B: expected a finite matrix"),
        (_reference_model().to_state_space(), {"convention": "x"}, InputError, "convention"),
        (
            control.ss(np.diag([-1.0, -2.0, -3.0, -4.0]), np.ones((4, 2)), np.array([[1.0, 1, 0, 0], [2.0, 2, 0, 0]]), 0),
            {},
            ModelError,
            "singular",
        ),
        ("not a system", {}, InputError, "StateSpace"),
    ],
)
def test_physical_form_bad_input(sys, kwargs, err, match):
    """Systems that are no 2nd-order model in position outputs are refused."""
    with pytest.raises(err, match=match):
        physical_from_state_space(sys, **kwargs)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"n_samples": 1}, "n_samples"),
        ({"n_samples": 10, "bits": 1}, "bits"),
        ({"n_samples": 10, "hold": 0}, "hold"),
        ({"n_samples": 10, "amplitude": -1.0}, "amplitude"),
        ({"n_samples": 10, "channels": 0}, "channels"),
    ],
)
def test_prbs_bad_input(kwargs, match):
    """Out-of-range PRBS arguments raise InputError naming the argument."""
    with pytest.raises(InputError, match=match):
        prbs(**kwargs)
