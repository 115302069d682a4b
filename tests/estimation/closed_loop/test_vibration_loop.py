"""The vibration loop of Cvitanic (2021), section 5.3.5: the critical gain against a Nyquist reading.

Independent reference: the gain margin read from the frequency response of
``z^-13 (P(e^{iw}) - 1)`` evaluated in closed form from the single mode's continuous compliance
(zero-order-hold discretisation by :func:`scipy.signal.cont2discrete`, not python-control), at the
phase crossovers (``1 + K L = 0``); the module bisects closed-loop poles.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.optimize
import scipy.signal

from gtmodel.errors import InputError
from gtmodel.estimation.closed_loop.correction import OffsetResponseModel
from gtmodel.estimation.closed_loop.vibration_loop import vibration_loop_critical_gain, vibration_plant

DT = 0.004


def _loop(model, w):
    """``L(e^{iw}) = z^-13 G(z)``, ``G = -M c2d(H) (1 - z^-1)^2 / dt^2`` with ``H = 1 / (m s^2 + c s + k)`` (ZOH)."""
    (m,), (c,), (k,) = model.m, model.c, model.k
    num, den, _ = scipy.signal.cont2discrete(([1.0], [m, c, k]), DT, method="zoh")
    z = np.exp(1j * w)
    H = np.polyval(np.ravel(num), z) / np.polyval(den, z)
    return z ** -13 * (-model.mass * H * (1 - 1 / z) ** 2 / DT**2)


@pytest.mark.parametrize("k", [2.5e6, 2.5e7])
def test_critical_gain_equals_the_nyquist_gain_margin(k):
    model = OffsetResponseModel((200.0,), (4000.0,), (k,), 200.0, DT)
    grid = np.linspace(1e-4, np.pi - 1e-4, 20001)
    phase = np.angle(_loop(model, grid))  # crossings of -pi (phase wraps from -pi to pi)
    idx = np.nonzero(np.diff(np.sign(np.imag(_loop(model, grid)))) != 0)[0]
    margins = []
    for i in idx:
        w = scipy.optimize.brentq(lambda x: np.imag(_loop(model, x)), grid[i], grid[i + 1], xtol=1e-14)
        L = _loop(model, w)
        if np.real(L) < 0:  # 1 + K L = 0 with K > 0
            margins.append(1.0 / abs(L))
    assert phase.size and margins
    assert vibration_loop_critical_gain(model, 13, tol=1e-9) == pytest.approx(min(margins), rel=1e-5)


def test_a_better_damped_mode_tolerates_a_larger_gain():
    # at a lightly damped resonance |G| ~ 1 / (2 zeta): ten times the damping, a larger limit
    light = vibration_loop_critical_gain(OffsetResponseModel((200.0,), (4000.0,), (2.5e7,), 200.0, DT))
    damped = vibration_loop_critical_gain(OffsetResponseModel((200.0,), (40000.0,), (2.5e7,), 200.0, DT))
    assert damped > 3 * light


def test_plant_refuses_a_bad_model():
    with pytest.raises(InputError, match="model: expected an OffsetResponseModel"):
        vibration_plant("not a model")
