"""Correction-stability plots and tables carry the values they are given (gtmodel.report.correction)."""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.report.correction import plot_gains, plot_loop_errors, plot_offset_response, write_gain_table

from ._figures import assert_line, assert_png

T = np.linspace(0.0, 0.2, 51)


@pytest.mark.parametrize("directions", [("x",), ("x", "y")])
def test_offset_response_in_ms_and_mm(tmp_path, directions):
    responses = {d: {"truth": 1e-4 * np.sin(40 * T + k), "single mode": 1e-4 * np.sin(41 * T + k)} for k, d in enumerate(directions)}
    fig = plot_offset_response(T, responses, tmp_path / "r.png", title="demo")
    assert_png(tmp_path / "r.png")
    assert [ax.get_title() for ax in fig.axes] == [f"{d} direction" for d in directions]
    for ax, (d, curves) in zip(fig.axes, responses.items()):
        for label, y in curves.items():
            assert_line(ax, label, T * 1e3, y * 1e3)


@pytest.mark.parametrize("directions", [("x",), ("x", "y")])
def test_loop_errors_in_mm_scaled_by_the_first_curve(tmp_path, directions):
    runs = {d: {"K = 0.11 (stable)": 1e-5 * np.sin(30 * T), "K = 0.12": 1e-5 * np.exp(20 * T)} for d in directions}
    runs[directions[0]]["K = 0.12"][-3:] = np.inf  # a diverged run: not drawn
    fig = plot_loop_errors(T, runs, tmp_path / "l.png")
    assert_png(tmp_path / "l.png")
    peaks = [np.abs(curves["K = 0.11 (stable)"]).max() for curves in runs.values()]
    np.testing.assert_allclose([ax.get_ylim() for ax in fig.axes], [(-3e3 * p, 3e3 * p) for p in peaks], rtol=1e-6)
    assert [ax.get_ylabel() for ax in fig.axes] == [f"{d} error [mm]" for d in directions]
    for ax, (d, curves) in zip(fig.axes, runs.items()):
        for label, e in curves.items():
            assert_line(ax, label, T, np.where(np.isfinite(e), e, np.nan) * 1e3)


@pytest.mark.parametrize("n_poses", [1, 4])
def test_gain_bars_and_table_are_the_gains(tmp_path, n_poses):
    rng = np.random.default_rng(n_poses)
    P, S = rng.uniform(0.05, 0.2, (n_poses, 2)), rng.uniform(0.05, 0.2, (n_poses, 2))
    fig = plot_gains(("x", "y"), P, S, tmp_path / "g.png")
    assert_png(tmp_path / "g.png")
    for j, ax in enumerate(fig.axes):
        heights = [b.get_height() for b in ax.patches]
        np.testing.assert_allclose(heights, np.concatenate([P[:, j], S[:, j]]))
    files = write_gain_table(rng.uniform(-30, 30, (n_poses, 2)), ("x", "y"), {"x": 0.01, "y": 0.01}, P, S, tmp_path)
    rows = (tmp_path / "table_14.csv").read_text().splitlines()
    assert files == ["table_14.md", "table_14.csv"] and len(rows) == n_poses + 1
    cells = np.array([[float(c) for c in r.split(",")[3:7]] for r in rows[1:]])
    np.testing.assert_allclose(cells, np.column_stack([P[:, 0], S[:, 0], P[:, 1], S[:, 1]]), rtol=1e-3)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda p: plot_offset_response(T, {}, p), "responses"),
        (lambda p: plot_offset_response(T, {"x": {"a": T[:-1]}}, p), "responses"),
        (lambda p: plot_loop_errors(T, {}, p), "runs"),
        (lambda p: plot_gains(("x",), np.zeros((2, 2)), np.zeros((2, 2)), p), "predicted"),
        (lambda p: plot_gains(("x",), np.zeros((2, 1)), np.zeros((3, 1)), p), "simulated"),
    ],
)
def test_bad_input(tmp_path, call, match):
    with pytest.raises(InputError, match=match):
        call(tmp_path / "x.png")
