"""The joint-stiffness bars are the identified stiffnesses (gtmodel.report.stiffness_calibration)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from gtmodel.report.stiffness_calibration import plot_joint_stiffness

from ._figures import assert_png


def _result(k):
    return SimpleNamespace(k_theta=np.asarray(k, float), std_k_theta=0.05 * np.asarray(k, float))


@pytest.mark.parametrize("methods", [("CP",), ("CP", "DPP"), ("CP", "CP_rotations_scaled_x10", "DPP")])
def test_bars_are_the_stiffnesses_in_MN_m_per_rad(tmp_path, methods):
    k_true = np.array([2.0, 3.0, 1.5, 0.5, 0.6, 0.3]) * 1e6
    results = {m: _result(k_true * (1 + 0.1 * i)) for i, m in enumerate(methods)}
    fig = plot_joint_stiffness(results, methods, k_true, tmp_path / "k.png", title="demo")
    assert_png(tmp_path / "k.png")
    ax = fig.axes[0]
    bars = ax.patches
    assert len(bars) == 6 * len(methods)
    for i, m in enumerate(methods):
        np.testing.assert_allclose([b.get_height() for b in bars[6 * i:6 * (i + 1)]], results[m].k_theta / 1e6)
    truth = ax.collections[-1].get_offsets()
    np.testing.assert_allclose(np.asarray(truth), np.column_stack([np.arange(1, 7), k_true / 1e6]))
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "CP (w = 1)" in labels and "truth" in labels
    assert ax.get_yscale() == "log" and ax.get_ylabel() == "k_theta [MN m/rad]"


def test_non_finite_stiffness_is_not_drawn(tmp_path):
    k = np.array([1.0, np.inf, 1.0, 1.0, 1.0, 1.0]) * 1e6
    fig = plot_joint_stiffness({"DPP": _result(k)}, ("DPP",), None, tmp_path / "k.png")
    heights = np.array([b.get_height() for b in fig.axes[0].patches])
    assert np.isnan(heights[1]) and np.allclose(heights[[0, 2, 3, 4, 5]], 1.0)
