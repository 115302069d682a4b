"""Plots of the structural model draw its frequency and impulse responses (gtmodel.report.structural)."""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.report.structural import plot_bode, plot_impulse
from gtmodel.robots.structural import PhysicalModel

from ._figures import assert_line, assert_png


@pytest.fixture(scope="module")
def model():
    return PhysicalModel.from_file("L1_dynamics_models")


@pytest.mark.parametrize("freqs", [None, np.logspace(0.5, 2.5, 50)])
def test_bode_draws_the_frequency_response_and_the_modes(model, tmp_path, freqs):
    """Magnitude [dB] and unwrapped phase [deg] of every pair; a line at each mode (6.15)."""
    fig = plot_bode(model, freqs_hz=freqs)
    f = np.logspace(0, 3, 400) if freqs is None else freqs
    resp = model.frequency_response(f)
    ax_mag, ax_ph = fig.axes
    for i in range(2):
        for j in range(2):
            assert_line(ax_mag, f"x{i + 1}/u{j + 1}", f, 20 * np.log10(resp.magnitude[i, j]))
            assert_line(ax_ph, f"x{i + 1}/u{j + 1}", f, np.degrees(np.unwrap(resp.phase[i, j])))
    for fm in model.modes().frequencies_hz:
        np.testing.assert_allclose([ln for ln in ax_mag.get_lines() if ln.get_label().startswith("mode") and
                                    abs(ln.get_xdata()[0] - fm) < 1e-9][0].get_xdata(), [fm, fm])
    fig.savefig(tmp_path / "b.png")
    assert_png(tmp_path / "b.png")


@pytest.mark.parametrize("duration", [0.1, 0.3])
def test_impulse_draws_each_coordinate_per_input(model, duration):
    """One axes per input, one line per coordinate."""
    fig = plot_impulse(model, duration=duration)
    resp = model.impulse_response(duration)
    y = np.asarray(resp.outputs)
    assert len(fig.axes) == y.shape[1]
    for j, ax in enumerate(fig.axes):
        for i in range(y.shape[0]):
            assert_line(ax, f"x{i + 1}", resp.time, y[i, j])
