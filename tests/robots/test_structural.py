"""Structural model in physical form (Dressler (2012), eqs. 6.14-6.15).

Independent references: the thesis' modes 14 and 103 Hz (``tests/reference/
gantry_tau_L1.toml``, table ``[compliance]``); :func:`scipy.linalg.eigvals` of
``(-K, M)`` (``det(M lambda + K) = 0``); the poles of the undamped model, which must be
``+- j 2 pi f`` of the modes; the transfer matrix ``(M s^2 - D s - K)^-1 B`` evaluated
directly with :func:`numpy.linalg.solve`; the quadratic eigenproblem
``det(M s^2 - D s - K) = 0`` at the state-space poles.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

from gtmodel.errors import InputError, ModelError
from gtmodel.robots.structural import PhysicalModel

REFERENCE = Path(__file__).parents[1] / "reference" / "gantry_tau_L1.toml"

#: Modes against the thesis' rounded 14 and 103 Hz.
MODE_TOLERANCE_HZ = 0.5
#: Same computation by another route (floating point, eigenvalues up to 4e5).
NUMERIC_RTOL = 1e-9


def _reference() -> dict:
    return tomllib.loads(REFERENCE.read_text())["compliance"]


def _ref_matrices():
    ref = _reference()
    return np.array(ref["M"]), np.array(ref["D"]), np.array(ref["K"])


def test_data_file_carries_the_thesis_matrices():
    """PhysicalModel.from_file has the reference M, D, K (copied, not computed)."""
    M, D, K = _ref_matrices()
    p = PhysicalModel.from_file("L1_dynamics_models")
    np.testing.assert_array_equal(p.M, M)
    np.testing.assert_array_equal(p.D, D)
    np.testing.assert_array_equal(p.K, K)
    assert p.convention == "thesis"


def test_modes_match_thesis():
    """(6.15) modes of the reference M, K are the thesis' 14 and 103 Hz."""
    modes = PhysicalModel(*_ref_matrices()).modes()
    np.testing.assert_allclose(modes.frequencies_hz, _reference()["modes_hz_reported"], atol=MODE_TOLERANCE_HZ)


def test_modes_match_scipy_eigvals():
    """sqrt(eigvals(-K, M)) / 2 pi, i.e. det(M lambda + K) = 0, computed directly."""
    M, D, K = _ref_matrices()
    lam = np.sort(scipy.linalg.eigvals(-K, M).real)
    modes = PhysicalModel(M, D, K).modes()
    np.testing.assert_allclose(modes.eigenvalues, lam, rtol=NUMERIC_RTOL)
    np.testing.assert_allclose(modes.frequencies_hz, np.sqrt(lam) / (2 * math.pi), rtol=NUMERIC_RTOL)


def test_mode_shapes_solve_the_eigenproblem():
    """(M lambda + K) phi = 0 for every mode shape."""
    M, D, K = _ref_matrices()
    modes = PhysicalModel(M, D, K).modes()
    pairs = list(zip(modes.eigenvalues, modes.shapes.T))
    residual = [(np.linalg.norm((M * lam + K) @ phi), 1e-9 * np.linalg.norm(K) * np.linalg.norm(phi)) for lam, phi in pairs]
    bad = [(mode, r, lim) for mode, (r, lim) in enumerate(residual) if not r <= lim]
    assert not bad, bad  # (mode, |(M lambda + K) phi|, allowed)
    peaks = [np.max(np.abs(phi)) for _, phi in pairs]
    assert peaks == pytest.approx([1.0] * len(pairs))  # each shape normalised to a unit peak


def test_undamped_poles_are_the_modes():
    """With D = 0 the state-space poles are +- j 2 pi f of the (6.15) modes."""
    M, _, K = _ref_matrices()
    p = PhysicalModel(M, np.zeros((2, 2)), K)
    poles = p.to_state_space().poles()
    np.testing.assert_allclose(np.abs(poles.real), 0.0, atol=1e-6 * np.max(np.abs(poles)))
    f = np.sort(np.abs(poles.imag)) / (2 * math.pi)
    np.testing.assert_allclose(f, np.repeat(p.modes().frequencies_hz, 2), rtol=NUMERIC_RTOL)


def test_damped_poles_solve_quadratic_eigenproblem_and_are_stable():
    """State-space poles s satisfy det(M s^2 - D s - K) = 0 (thesis form) and are stable."""
    M, D, K = _ref_matrices()
    p = PhysicalModel(M, D, K)
    modes = p.modes()
    det = [(abs(np.linalg.det(M * s**2 - D * s - K)), 1e-8 * np.prod(np.linalg.svd(M * abs(s) ** 2, compute_uv=False)))
           for s in modes.poles]
    bad = [(modes.poles[i], d, lim) for i, (d, lim) in enumerate(det) if not d <= lim]
    assert not bad, bad  # (pole, |det|, allowed)
    assert np.all(modes.poles.real < 0)
    np.testing.assert_allclose(modes.natural_frequencies_hz, [14.21, 100.56], atol=0.01)
    np.testing.assert_allclose(modes.damping_ratios, [0.167, 0.0068], atol=0.001)


@pytest.mark.parametrize("f_hz", [1.0, 14.0, 50.0, 103.0, 400.0])
def test_frequency_response_matches_direct_evaluation(f_hz):
    """control frequency response equals (M s^2 - D s - K)^-1 B at s = j 2 pi f."""
    M, D, K = _ref_matrices()
    B = np.array([[1.0, 0.5], [0.0, 2.0]])
    p = PhysicalModel(M, D, K, B)
    s = 2j * math.pi * f_hz
    G = np.linalg.solve(M * s**2 - D * s - K, B)
    resp = p.frequency_response([f_hz])
    H = resp.magnitude[:, :, 0] * np.exp(1j * resp.phase[:, :, 0])
    np.testing.assert_allclose(H, G, rtol=1e-9)


def test_conventions_describe_the_same_system():
    """Standard form (M, -D, -K) has the same poles, modes and response as the thesis form."""
    M, D, K = _ref_matrices()
    thesis = PhysicalModel(M, D, K)
    standard = thesis.with_convention("standard")
    np.testing.assert_array_equal(standard.K, -K)
    np.testing.assert_allclose(np.sort_complex(standard.to_state_space().poles()), np.sort_complex(thesis.to_state_space().poles()))
    np.testing.assert_allclose(standard.modes().frequencies_hz, thesis.modes().frequencies_hz)
    back = standard.with_convention("thesis")
    np.testing.assert_allclose(back.D, D)


def test_wrong_convention_is_reported():
    """The thesis' matrices read as the textbook form have no oscillatory mode."""
    with pytest.raises(ModelError, match="sign convention"):
        PhysicalModel(*_ref_matrices(), convention="standard").modes()


def test_impulse_response_shape_and_decay():
    """Impulse responses (n, m, T) start at 0 and decay (stable model)."""
    r = PhysicalModel.from_file("L1_dynamics_models").impulse_response(duration=3.0, n_points=3001)
    y = np.asarray(r.outputs)
    assert y.shape == (2, 2, 3001)
    np.testing.assert_allclose(y[:, :, 0], 0.0, atol=1e-12)
    assert np.max(np.abs(y[:, :, -100:])) < 1e-2 * np.max(np.abs(y))


_M, _D, _K = _ref_matrices()


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"M": np.ones((2, 3)), "D": _D, "K": _K}, "M: expected a square"),
        ({"M": _M, "D": np.ones((3, 3)), "K": _K}, "D: expected a matrix of shape 2x2"),
        ({"M": _M, "D": _D, "K": [[1.0, np.nan], [0.0, 1.0]]}, "K: expected finite"),
        ({"M": [[1.0, 2.0], [2.0, 4.0]], "D": _D, "K": _K}, "M: expected a non-singular"),
        ({"M": _M, "D": _D, "K": _K, "B": np.ones((3, 2))}, "B: expected a matrix of shape 2xn"),
        ({"M": _M, "D": _D, "K": _K, "convention": "other"}, "convention"),
        ({"M": "abc", "D": _D, "K": _K}, "M: expected a matrix of numbers"),
    ],
)
def test_bad_model(kwargs, match):
    """Invalid matrices raise InputError naming the argument."""
    with pytest.raises(InputError, match=match):
        PhysicalModel(**kwargs)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda p: p.frequency_response([-1.0]), "freqs_hz"),
        (lambda p: p.frequency_response([]), "freqs_hz"),
        (lambda p: p.impulse_response(duration=0.0), "duration"),
        (lambda p: p.impulse_response(n_points=3), "n_points"),
        (lambda p: p.with_convention("x"), "convention"),
    ],
)
def test_bad_arguments(call, match):
    """Bad method arguments raise InputError naming the argument."""
    with pytest.raises(InputError, match=match):
        call(PhysicalModel.from_file("L1_dynamics_models"))
