"""Plots of the structural (compliance) model: Bode plots and impulse responses (Dressler (2012), eqs. 6.14-6.15)."""

from __future__ import annotations

from typing import Any

import numpy as np

from gtmodel.errors import ModelError
from gtmodel.robots.structural import PhysicalModel
from gtmodel.report._figure import new_figure, save

__all__ = ["plot_bode", "plot_impulse"]


def plot_bode(model: PhysicalModel, freqs_hz: Any = None, title: str = "") -> Any:
    """Bode plot (magnitude and phase of every input-output pair) with the modes marked.

    Dressler (2012), eqs. 6.14-6.15. Draws on a :class:`matplotlib.figure.Figure`
    (no pyplot state, safe under the Agg backend).

    Parameters
    ----------
    model : PhysicalModel
        The structural model.
    freqs_hz : array_like, optional
        Frequencies [Hz] (default 200 points, 1-1000 Hz, logarithmic).
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        Two axes: magnitude [dB] and phase [deg] over frequency [Hz].
    """
    f = np.logspace(0, 3, 400) if freqs_hz is None else np.asarray(freqs_hz, dtype=float)
    resp = model.frequency_response(f)
    fig, (ax_mag, ax_ph) = new_figure(2, 1, sharex=True, size=(7, 5))
    for i in range(resp.magnitude.shape[0]):
        for j in range(resp.magnitude.shape[1]):
            label = f"x{i + 1}/u{j + 1}"
            ax_mag.semilogx(f, 20.0 * np.log10(resp.magnitude[i, j]), label=label)
            ax_ph.semilogx(f, np.degrees(np.unwrap(resp.phase[i, j])), label=label)
    try:
        for k, fm in enumerate(model.modes().frequencies_hz):
            for ax in (ax_mag, ax_ph):
                ax.axvline(fm, color="0.5", ls="--", lw=0.8, label=f"mode (6.15) {fm:.1f} Hz" if ax is ax_mag else None)
    except ModelError:
        pass
    ax_mag.set_ylabel("magnitude [dB]")
    ax_ph.set_ylabel("phase [deg]")
    ax_ph.set_xlabel("frequency [Hz]")
    ax_mag.legend(fontsize="small", ncol=2)
    for ax in (ax_mag, ax_ph):
        ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(title or f"Bode plot {model.name}".strip())
    return fig

def plot_impulse(model: PhysicalModel, duration: float = 0.5, title: str = "") -> Any:
    """Impulse responses, one axis per input, one line per coordinate.

    Dressler (2012), eq. 6.14. Draws on a :class:`matplotlib.figure.Figure` (Agg-safe).

    Parameters
    ----------
    model : PhysicalModel
        The structural model.
    duration : float, optional
        Length [s] (default 0.5).
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        One axis per input.
    """
    resp = model.impulse_response(duration)
    y = np.asarray(resp.outputs)
    m = y.shape[1]
    fig, axes = new_figure(m, 1, sharex=True, size=(7, 2.6 * m))
    axes = np.atleast_1d(axes)
    for j in range(m):
        for i in range(y.shape[0]):
            axes[j].plot(resp.time, y[i, j], label=f"x{i + 1}")
        axes[j].set_ylabel(f"impulse on u{j + 1}")
        axes[j].grid(True, alpha=0.3)
        axes[j].legend(fontsize="small")
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(title or f"Impulse responses {model.name}".strip())
    return fig
