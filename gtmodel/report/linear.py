"""Bode and step plots of a linearised model, computed by python-control.

The responses come from python-control (:func:`control.frequency_response`,
:func:`control.step_response`) of the model's :class:`control.StateSpace`
(:meth:`Linearization.to_state_space
<gtmodel.modeling.simulation.linear.Linearization.to_state_space>`); they are drawn on a
figure of this layer (:mod:`gtmodel.report._figure`), not on pyplot's global state, one
line per input-output pair. :meth:`Linearization.bode_plot
<gtmodel.modeling.simulation.linear.Linearization.bode_plot>` and ``step_plot`` call these.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._lazy import lazy_module
from gtmodel.errors import InputError
from gtmodel.report._figure import new_figure, save

#: python-control, imported on first use.
control = lazy_module("control")

__all__ = ["plot_bode", "plot_step", "state_space"]


def state_space(system: Any) -> Any:
    """A python-control LTI system of a linearisation (or the system itself).

    Parameters
    ----------
    system : Linearization or control.LTI
        A :class:`~gtmodel.modeling.simulation.linear.Linearization` (its
        ``to_state_space()``), or a python-control ``StateSpace`` / ``TransferFunction``.

    Returns
    -------
    control.LTI
        The system, with its signal names.

    Raises
    ------
    InputError
        Anything else, or a system without inputs or outputs.
    """
    if hasattr(system, "to_state_space"):
        system = system.to_state_space()
    if not isinstance(system, control.LTI):
        raise InputError(f"expected a Linearization or a python-control system, got {type(system).__name__}")
    if system.ninputs == 0 or system.noutputs == 0:
        raise InputError(f"the system has {system.ninputs} inputs and {system.noutputs} outputs: nothing to plot")
    return system


def _pairs(sys: Any) -> list[tuple[int, int, str]]:
    ins = list(sys.input_labels)
    outs = list(sys.output_labels)
    return [(i, j, f"{ins[j]} -> {outs[i]}") for i in range(sys.noutputs) for j in range(sys.ninputs)]


def plot_bode(system: Any, path: str | Path | None = None, omega: Any = None, hz: bool = False, title: str = "") -> Any:
    """Bode plot (magnitude in dB, phase in degrees) of every input-output pair.

    Parameters
    ----------
    system : Linearization or control.LTI
        As :func:`state_space`.
    path : str, pathlib.Path or None, optional
        PNG file to write (default none).
    omega : array_like, optional
        Frequencies [rad/s], shape ``(K,)``; default python-control's choice around the
        poles and zeros.
    hz : bool, optional
        Frequency axis in Hz instead of rad/s.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        Two axes (magnitude, phase); each line's label is ``"input -> output"``, its data
        python-control's response (``control.frequency_response``).

    Raises
    ------
    InputError
        As :func:`state_space`.
    """
    sys = state_space(system)
    resp = control.frequency_response(sys, None if omega is None else np.asarray(omega, dtype=float), squeeze=False)
    w = np.asarray(resp.omega) / (2 * np.pi if hz else 1.0)
    fig, (ax_m, ax_p) = new_figure(2, 1, size="plot.tall", sharex=True)
    for i, j, label in _pairs(sys):
        ax_m.semilogx(w, 20 * np.log10(np.asarray(resp.magnitude)[i, j]), label=label)
        ax_p.semilogx(w, np.degrees(np.unwrap(np.asarray(resp.phase)[i, j])), label=label)
    ax_m.set_ylabel("magnitude [dB]")
    ax_p.set_ylabel("phase [deg]")
    ax_p.set_xlabel("frequency [Hz]" if hz else "frequency [rad/s]")
    for ax in (ax_m, ax_p):
        ax.grid(True, which="both")
    ax_m.legend(fontsize="small")
    fig.suptitle(title or "Bode plot")
    return save(fig, path)


def plot_step(system: Any, path: str | Path | None = None, T: Any = None, title: str = "") -> Any:
    """Unit step responses of every input-output pair.

    Parameters
    ----------
    system : Linearization or control.LTI
        As :func:`state_space`.
    path : str, pathlib.Path or None, optional
        PNG file to write (default none).
    T : float or array_like, optional
        Final time [s] or time points, shape ``(K,)``; default python-control's choice
        from the slowest pole.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        One axes per output; each line's label is ``"input -> output"``, its data
        python-control's ``control.step_response``.

    Raises
    ------
    InputError
        As :func:`state_space`.
    """
    sys = state_space(system)
    resp = control.step_response(sys, T, squeeze=False)
    fig, axes = new_figure(sys.noutputs, 1, size=(6.4, 2.2 * sys.noutputs + 0.8), squeeze=False, sharex=True)
    outs = list(sys.output_labels)
    for i, j, label in _pairs(sys):
        axes[i, 0].plot(resp.time, np.asarray(resp.outputs)[i, j], label=label)
    for i, ax in enumerate(axes[:, 0]):
        ax.set_ylabel(outs[i])
        ax.grid(True)
        ax.legend(fontsize="small")
    axes[-1, 0].set_xlabel("t [s]")
    fig.suptitle(title or "step response")
    return save(fig, path)
