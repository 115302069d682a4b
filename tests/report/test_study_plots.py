"""Study plots draw the study tables they are given (gtmodel.report.study_plots)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from gtmodel.report.study_plots import (
    MAP_MARKERS,
    plot_accuracy_vs_poses,
    plot_normalised_errors,
    plot_parameter_spread,
    plot_sweep,
    plot_time_map,
)

from ._figures import assert_line, assert_png


@pytest.mark.parametrize("coverage", [None, (0.68, 0.95)])
def test_normalised_errors_histogram_and_the_standard_normal(tmp_path, coverage):
    z = np.random.default_rng(0).standard_normal(500)
    fig = plot_normalised_errors(z, tmp_path / "z.png", coverage=coverage)
    assert_png(tmp_path / "z.png")
    ax = fig.axes[0]
    lim = max(4.0, float(np.quantile(np.abs(z), 0.999)))
    edges = np.linspace(-lim, lim, 61)
    density = np.histogram(np.clip(z, -lim, lim), bins=edges, density=True)[0]
    np.testing.assert_allclose([p.get_height() for p in ax.patches], density)
    normal = ax.get_lines()[0]
    np.testing.assert_allclose(normal.get_ydata(), np.exp(-0.5 * normal.get_xdata() ** 2) / math.sqrt(2 * math.pi))


def test_parameter_spread_bars_and_coverage(tmp_path):
    df = pd.DataFrame({"parameter": ["a", "b", "c"], "spread_ratio": [0.9, 1.1, 1.3],
                       "coverage_1sigma": [0.7, 0.6, 0.5], "coverage_2sigma": [0.95, 0.9, 0.85]})
    fig = plot_parameter_spread(df, tmp_path / "s.png")
    assert_png(tmp_path / "s.png")
    ax1, ax2 = fig.axes
    np.testing.assert_allclose([b.get_height() for b in ax1.patches], df["spread_ratio"])
    assert_line(ax2, "within 1 sigma", np.arange(3), df["coverage_1sigma"])
    assert_line(ax2, "within 2 sigma", np.arange(3), df["coverage_2sigma"])


@pytest.mark.parametrize("methods", [None, ["condition", "random"]])
def test_accuracy_vs_poses_median_in_um(tmp_path, methods):
    n = np.array([10.0, 20.0, 40.0])
    rows = []
    for k, m in enumerate(methods or [None]):
        for i, ni in enumerate(n):
            row = {"n_calibration": ni, "truth_mean_error_m_median": 1e-5 * (3 - i) * (k + 1),
                   "truth_mean_error_m_q10": 0.5e-5, "truth_mean_error_m_q90": 4e-5}
            if m is not None:
                row["pose_method"] = m
            rows.append(row)
    groups = pd.DataFrame(rows)
    fig = plot_accuracy_vs_poses(groups, tmp_path / "a.png")
    assert_png(tmp_path / "a.png")
    ax = fig.axes[0]
    labels = {"condition": "selected, eq. 5.9", "random": "random", None: "poses"}
    for k, m in enumerate(methods or [None]):
        assert_line(ax, labels[m], n, 1e6 * 1e-5 * (3 - np.arange(3)) * (k + 1))


def test_time_map_cells_and_markers(tmp_path):
    x, y = np.meshgrid([0.0, 0.1, 0.2], [1.0, 1.2])
    x, y = x.ravel(), y.ravel()
    time_s = np.arange(6, dtype=float)
    cls = ["solved", "solved", "infeasible", "solved", "outside", "failed"]
    fig = plot_time_map(x, y, time_s, cls, tmp_path / "m.png", start=(0.1, 1.1))
    assert_png(tmp_path / "m.png")
    ax = fig.axes[0]
    grid = np.ma.getdata(ax.collections[0].get_array()).reshape(2, 3)
    mask = np.ma.getmaskarray(ax.collections[0].get_array()).reshape(2, 3)
    np.testing.assert_allclose(grid[~mask], [0.0, 1.0, 3.0])
    for key, (marker, text) in MAP_MARKERS.items():
        sel = np.array(cls) == key
        assert_line(ax, f"{text} ({int(sel.sum())})", x[sel], y[sel])
    assert_line(ax, "start", [0.1], [1.1])


@pytest.mark.parametrize("solved", [None, [True, False, True, True]])
def test_sweep_panels_draw_the_solved_cases_in_order(tmp_path, solved):
    v = np.array([3.0, 1.0, 2.0, 4.0])
    cols = {"final time [s]": 10 * v, "energy [J]": v**2}
    fig = plot_sweep("speed", v, cols, tmp_path / "w.png", solved=solved)
    assert_png(tmp_path / "w.png")
    ok = np.ones(4, bool) if solved is None else np.array(solved)
    order = np.argsort(v)
    assert [ax.get_ylabel() for ax in fig.axes] == list(cols)
    for ax, (label, c) in zip(fig.axes, cols.items()):
        first = ax.get_lines()[0]
        np.testing.assert_allclose(first.get_xdata(), v[order][ok[order]])
        np.testing.assert_allclose(first.get_ydata(), c[order][ok[order]])
        if solved is not None:
            assert_line(ax, "not solved", v[~ok], c[~ok])
