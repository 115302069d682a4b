"""The robust Q filter of Dressler (2012), Cases 2 and 3: shaped below margin / loop gain, zero phase, lifted exactly.

Independent references: the FIR's magnitude evaluated by a direct DTFT sum (numpy) against the wanted
``min(|B|^2, margin / g)``; the lifted matrix against the filter applied to a random signal.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.estimation.ilc.lifted import RobustQFilter

F = np.linspace(0.0, 125.0, 129)


def test_magnitude_follows_the_cap_and_the_low_pass():
    g = np.where((F > 9.0) & (F < 13.0), 2.0, 1.0)  # a resonance where |1 - L T| = 2
    q = RobustQFilter(30.0, F, g, margin=0.9, taps=201)
    h = q.fir
    k = np.arange(h.size) - h.size // 2
    dtft = np.abs(np.exp(-2j * np.pi * np.outer(F, k) * q.dt) @ h)  # independent DTFT of the centred taps
    assert np.allclose(dtft, q.magnitude(F), atol=1e-9)
    assert np.max(dtft[(F > 10.0) & (F < 12.0)] * 2.0) < 0.95  # robust at the resonance
    assert dtft[F == 0.0][0] == pytest.approx(0.9, abs=0.02)  # 0.9 / g at DC
    assert np.all(dtft[F > 60.0] < 0.05)  # the 30 Hz low-pass


def test_lifted_matrix_is_the_operator():
    q = RobustQFilter(30.0, F, np.ones(F.size), window=np.hanning(80))
    x = np.random.default_rng(0).normal(size=80)
    assert np.allclose(q.lifted(80) @ x, q.apply(x), atol=1e-14)


@pytest.mark.parametrize("kwargs, match", [
    ({"margin": 1.5}, "margin: expected a number in \\(0, 1\\)"),
    ({"taps": 100}, "taps: expected an odd FIR length"),
    ({"loop_gain": -np.ones(F.size)}, "loop_gain: expected positive gains"),
    ({"freqs_hz": F[:-1]}, "freqs_hz: expected an increasing grid from 0 to 125 Hz"),
])
def test_bad_design_input(kwargs, match):
    args = {"cutoff_hz": 30.0, "freqs_hz": F, "loop_gain": np.ones(F.size)} | kwargs
    with pytest.raises(InputError, match=match):
        RobustQFilter(**args)
