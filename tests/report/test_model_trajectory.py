"""Signals of a user's model are drawn with their units and bounds (gtmodel.report.model_trajectory)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gtmodel.problems.user_model import load_user_model
from gtmodel.report.model_trajectory import MAX_PANELS, plot_signals

from ._figures import assert_line, assert_png

ROOT = Path(__file__).resolve().parents[2]


def _signals(n):
    t = np.linspace(0.0, 2.0, 21)
    return t, {f"s{i}": np.sin(t + i) for i in range(n)}


@pytest.mark.parametrize("n", [1, 3, MAX_PANELS + 2])
def test_each_signal_in_its_panel(tmp_path, n):
    t, signals = _signals(n)
    fig = plot_signals(t, signals, tmp_path / "s.png", title="demo")
    assert_png(tmp_path / "s.png")
    visible = [ax for ax in fig.axes if ax.get_visible()]
    assert len(visible) == min(n, MAX_PANELS)
    for ax, (name, y) in zip(visible, signals.items()):
        assert_line(ax, name, t, y)
    assert fig.get_suptitle() == "demo" + (f" (first {MAX_PANELS} of {n})" if n > MAX_PANELS else "")


def test_finite_bounds_are_drawn(tmp_path):
    t, signals = _signals(2)
    fig = plot_signals(t, signals, tmp_path / "s.png", bounds={"s0": (-0.2, np.inf), "s1": (-1.0, 1.0)})
    dashed = [sorted(float(ln.get_ydata()[0]) for ln in ax.get_lines() if ln.get_linestyle() == "--") for ax in fig.axes[:2]]
    assert dashed == [[-0.2], [1.0]]  # s1 = sin(t + 1) >= 0.14: its lower bound -1 is named, not drawn
    assert [tx.get_text() for tx in fig.axes[1].texts] == ["lower bound -1 (off scale)"]


@pytest.mark.parametrize("bounds", [(0.0, 1e3), (-1e4, 2.0), (1.0, 1.06)], ids=["goddard-like upper", "far lower", "near both"])
def test_axes_are_scaled_to_the_data_not_to_far_bounds(tmp_path, bounds):
    """Goddard's h and v looked flat when the axes reached a bound 10-1000x beyond the data:
    the y range is now the data's (max - min of the plotted values, independently computed)
    plus the near bounds and a margin of at most 10 % of it."""
    t = np.linspace(0.0, 1.0, 50)
    y = 1.0 + 0.05 * t**2
    fig = plot_signals(t, {"h": y}, tmp_path / "h.png", bounds={"h": bounds})
    lo, hi = fig.axes[0].get_ylim()
    span = y.max() - y.min()
    near = [b for b in bounds if y.min() - 0.5 * span <= b <= y.max() + 0.5 * span]  # within half the data's range
    low, high = min([y.min(), *near]), max([y.max(), *near])
    assert low - 0.1 * (high - low) <= lo <= low and high <= hi <= high + 0.1 * (high - low)


@pytest.mark.parametrize(
    "units, labels",
    [({"s": "m", "theta": "rad", "F": "N"}, ["s [m]", "theta [rad]", "F [N]"]), (None, ["s", "theta", "F"]), ({"s": "m"}, ["s [m]", "theta", "F"])],
)
def test_y_labels_carry_the_units(tmp_path, units, labels):
    """Defect (i) of issue 24: the cart-pendulum plots had no y units."""
    t = np.linspace(0.0, 1.0, 5)
    fig = plot_signals(t, {"s": t, "theta": 2 * t, "F": 3 * t}, tmp_path / "s.png", units=units)
    assert [ax.get_ylabel() for ax in fig.axes if ax.get_visible()] == labels


def test_cart_pendulum_model_declares_its_units():
    """The shipped user model gives every state, its input and its outputs a unit, so its plots show them."""
    model = load_user_model(ROOT / "models" / "cart_pendulum.py", "CartPendulum")
    # the tip's coordinates are lengths (s + l sin(theta), -l cos(theta)), the energy is kinetic plus potential
    assert model.units == {"s": "m", "v": "m/s", "theta": "rad", "omega": "rad/s", "F": "N", "tip_x": "m", "tip_y": "m", "energy": "J"}
