"""Plots of the structural model (gtmodel.report.structural)."""

from __future__ import annotations

from matplotlib.figure import Figure

from gtmodel.report.structural import plot_bode, plot_impulse
from gtmodel.robots.structural import PhysicalModel


def test_plots_return_figures():
    """Bode and impulse plots are matplotlib Figures (Agg-safe, no pyplot)."""
    p = PhysicalModel.from_file("L1_dynamics_models")
    fig = plot_bode(p)
    assert isinstance(fig, Figure) and len(fig.axes) == 2
    fig = plot_impulse(p, duration=0.3)
    assert isinstance(fig, Figure) and len(fig.axes) == 2
