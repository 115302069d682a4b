"""Fusion-study plots draw the estimates they are given (gtmodel.report.fusion)."""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.report.fusion import QUANTITY_LABELS, plot_angular_acceleration, plot_sweep, plot_velocity, write_fusion_tables, write_limits_table

from ._figures import assert_line, assert_png

T = np.linspace(0.0, 1.0, 101)


def _vectors(seed):
    rng = np.random.default_rng(seed)
    truth = np.column_stack([np.sin(2 * np.pi * T), 2 * np.cos(2 * np.pi * T), 0.1 * T])
    return truth, truth + rng.normal(0, 0.05, truth.shape), truth + rng.normal(0, 0.01, truth.shape)


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_velocity_in_mm_per_s_and_error_norms(tmp_path, axis):
    truth, reg, fus = _vectors(axis)
    fig = plot_velocity(T, truth, reg, fus, tmp_path / "v.png", axis=axis)
    assert_png(tmp_path / "v.png")
    top, bottom = fig.axes
    assert_line(top, "truth", T, 1e3 * truth[:, axis])
    assert_line(top, "tracker, four-point regression", T, 1e3 * reg[:, axis])
    assert_line(top, "fusion", T, 1e3 * fus[:, axis])
    assert_line(bottom, "|error| fusion", T, np.linalg.norm(1e3 * fus - 1e3 * truth, axis=1))
    assert top.get_ylabel() == f"v_{'xyz'[axis]} [mm/s]"


def test_angular_acceleration_along_the_largest_axis_in_deg(tmp_path):
    truth, reg, fus = _vectors(3)
    peaks = np.abs(np.sin(2 * np.pi * T)) > 0.9
    fig = plot_angular_acceleration(T, truth, reg, fus, peaks, tmp_path / "a.png", title="demo")
    assert_png(tmp_path / "a.png")
    top, bottom = fig.axes
    k = 1  # the largest true component
    assert_line(top, "truth", T, np.degrees(truth[:, k]))
    assert_line(top, "fusion (EKF)", T, np.degrees(fus[:, k]))
    assert_line(bottom, "|error| regression", T, np.linalg.norm(np.degrees(reg) - np.degrees(truth), axis=1))
    assert top.get_ylabel() == "alpha_y [deg/s^2]"


@pytest.mark.parametrize("n_rows", [1, 3])
def test_sweep_bars_are_the_improvements_clipped(tmp_path, n_rows):
    rows = [{"parameter": "sample_time_s", "value": 0.001 * (i + 1),
             **{q: {"improvement_percent": 60.0 * (1 - i) - 5 * j} for j, q in enumerate(QUANTITY_LABELS)}} for i in range(n_rows)]
    quantities = ("position_mm", "velocity_mm_s")
    fig = plot_sweep(rows, tmp_path / "s.png", quantities=quantities)
    assert_png(tmp_path / "s.png")
    for ax, q in zip(fig.axes, quantities):
        heights = [b.get_height() for b in ax.patches]
        np.testing.assert_allclose(heights, np.clip([r[q]["improvement_percent"] for r in rows], -100, 100))


def test_tables_hold_the_figures(tmp_path):
    table_8 = {"sine": {"position_mm": {"sensor": 0.5, "fusion": 0.25, "change_percent": -50.0, "thesis_sensor": None, "thesis_fusion": 0.3}}}
    files = write_fusion_tables(tmp_path, "demo", table_8, {}, [], [])
    assert files == ["table_8.md", "table_8.csv"]
    header, row = (tmp_path / "table_8.csv").read_text().splitlines()
    assert row.split(",")[:5] == ["sine", "position [mm]", "0.5", "0.25", "-50"]
    assert "not in the reference data" in row


@pytest.mark.parametrize("stops_at, limit, verdict", [
    (0.35, 0.24, "reproduced"),  # log10(2.4) = 0.38 decades from the thesis' < 0.1
    (1.2, 0.98, "differs"),  # log10(9.8) = 0.99: within one decade, not within half (the page's rule)
], ids=["0.38", "0.99"])
def test_limits_table_uses_the_pages_rule(tmp_path, stops_at, limit, verdict):
    """Independent check: the log10 distance by hand against the half decade the fidelity page states."""
    row = {"motion": "3-axis", "tuning": "white_jerk", "parameter": "accel_noise_m_s2_rtHz", "thesis_limit": 0.1, "stops_at": stops_at,
           "pays_up_to": limit / 1.2, "limit": limit, "decades_from_thesis": float(np.log10(limit / 0.1)), "verdict": "reproduced",
           "search": [3.9e-4, 3.9], "evaluations": [1, 2]}
    assert write_limits_table(tmp_path, "demo", [row]) == ["table_10_limits.md", "table_10_limits.csv"]
    assert (tmp_path / "table_10_limits.csv").read_text().splitlines()[1].split(",")[7] == verdict
    assert "half a decade" in (tmp_path / "table_10_limits.md").read_text()
