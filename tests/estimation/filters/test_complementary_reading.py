"""The complementary filter's cut-off read as Matlab's ``butter`` + ``filtfilt`` (Dressler (2012), section 7.3).

Independent reference: the crossover of LP and HP = 1 - LP found by root finding on the
zero-phase magnitude of :func:`scipy.signal.butter` designed at the cut-off itself.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.optimize
import scipy.signal

from gtmodel.errors import InputError
from gtmodel.estimation.filters.complementary import ComplementaryFilter


@pytest.mark.parametrize("reading, expected", [("matlab", [4.50, 2.63]), ("zero_phase_3db", [5.606, 3.278])])
def test_crossover_per_reading(reading, expected):
    f = ComplementaryFilter([4.50, 2.63], dt=0.004, reading=reading)
    cross = []
    for sos in f.sos:
        lp = lambda x, sos=sos: np.abs(scipy.signal.sosfreqz(sos, worN=[x], fs=250.0)[1][0]) ** 2  # noqa: E731
        cross.append(scipy.optimize.brentq(lambda x: 2 * lp(x) - 1.0, 0.1, 100.0, xtol=1e-12))
    assert cross == pytest.approx(expected, abs=1e-3)
    assert np.allclose(cross, f.design_hz, atol=1e-9)


def test_unknown_reading():
    with pytest.raises(InputError, match="reading: expected one of zero_phase_3db, matlab"):
        ComplementaryFilter([4.5, 2.63], reading="octave")
