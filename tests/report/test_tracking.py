"""Tracking plots draw the errors and paths they are given, in mm or um (gtmodel.report.tracking)."""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.report.tracking import plot_actuator_error, plot_deflection, plot_tool_error, plot_tool_path

from ._figures import assert_line, assert_png, line

T = np.linspace(0.0, 1.0, 26)


def _error(amplitude):
    return amplitude * np.column_stack([np.sin(T), np.cos(T), T])


@pytest.mark.parametrize("amplitude, scale, unit", [(2e-3, 1e3, "mm"), (2e-5, 1e6, "um")])
@pytest.mark.parametrize(
    "plot, labels",
    [
        (plot_actuator_error, ("q1 - q1_ref", "q2 - q2_ref", "q3 - q3_ref")),
        (plot_deflection, ("d_x", "d_y", "d_z")),
        (plot_tool_error, ("x - x_ref", "y - y_ref", "z - z_ref")),
    ],
)
def test_errors_in_mm_from_one_mm_on_else_um(tmp_path, plot, labels, amplitude, scale, unit):
    e = _error(amplitude)
    fig = plot(T, e, tmp_path / "e.png", end_time=0.5)
    assert_png(tmp_path / "e.png")
    assert [ax.get_ylabel() for ax in fig.axes] == [f"{label} [{unit}]" for label in labels]
    for i, (ax, label) in enumerate(zip(fig.axes, labels)):
        assert_line(ax, label, T, e[:, i] * scale)
        np.testing.assert_allclose(line(ax, "end of the motion").get_xdata(), [0.5, 0.5])


def test_tool_error_draws_the_deflection_beside(tmp_path):
    e, d = _error(2e-3), _error(1e-3)
    fig = plot_tool_error(T, e, tmp_path / "e.png", deflection=d)
    for i, ax in enumerate(fig.axes):
        assert_line(ax, f"deflection {'xyz'[i]}", T, d[:, i] * 1e3)


def test_tool_path_in_three_planes(tmp_path):
    ref = np.column_stack([T, 2 * T, 3 * T])
    z = ref + 1e-4
    fig = plot_tool_path(ref, z, tmp_path / "p.png", title="demo")
    assert_png(tmp_path / "p.png")
    for ax, (a, b) in zip(fig.axes, ((0, 1), (1, 2), (0, 2))):
        assert_line(ax, "reference", ref[:, a], ref[:, b])
        assert_line(ax, "tool", z[:, a], z[:, b])
    assert fig.get_suptitle() == "demo: tool path"
