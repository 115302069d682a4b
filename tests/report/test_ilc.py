"""ILC plots are written headless as PNG files (gtmodel.report.ilc, Figs. 7.7-7.11 style)."""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.report.ilc import plot_error_measure, plot_iteration_errors, plot_tool_path

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _square(n=200, side=0.010):
    s = np.linspace(0, 4, n)
    x = side * np.clip(np.minimum(s, 3 - s), 0, 1)
    y = side * np.clip(np.minimum(s - 1, 4 - s), 0, 1)
    return np.column_stack([x, y, np.zeros(n)]) + [0.0, 2.9, -0.5]


def test_error_measure_png(tmp_path):
    """One panel per case, log scale."""
    k = np.arange(11)[:, None]
    measures = {"Case 1": 1e-3 * 0.6**k * np.ones((1, 3)), "Case 3": 1e-4 * 0.5 ** np.arange(11)}
    out = plot_error_measure(measures, tmp_path / "m.png", labels=["q1", "q2", "q3"])
    assert out.read_bytes()[:8] == PNG_MAGIC


def test_tool_path_png(tmp_path):
    """Reference vs iteration 0 vs the last iteration."""
    ref = _square()
    out = plot_tool_path(ref, {"iteration 0": ref + 5e-4, "iteration 10": ref + 1e-5}, tmp_path / "p.png", title="Case 1")
    assert out.read_bytes()[:8] == PNG_MAGIC


def test_iteration_errors_png(tmp_path):
    """Error over time of the first and last iteration."""
    eps = np.random.default_rng(0).standard_normal((11, 50, 2)) * 1e-4
    out = plot_iteration_errors(eps, 0.004, tmp_path / "e.png", labels=["x", "y"])
    assert out.read_bytes()[:8] == PNG_MAGIC


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda p: plot_error_measure({}, p), "measures"),
        (lambda p: plot_tool_path(np.zeros(5), {}, p), "reference"),
        (lambda p: plot_tool_path(np.zeros((5, 2)), {"a": np.zeros((4, 2))}, p), "paths"),
        (lambda p: plot_iteration_errors(np.zeros((3, 5)), 0.004, p), "eps"),
        (lambda p: plot_iteration_errors(np.zeros((3, 5, 1)), 0.004, p, iterations=[3]), "iterations"),
    ],
)
def test_bad_input(tmp_path, call, match):
    """Wrong shapes raise InputError naming the argument."""
    with pytest.raises(InputError, match=match):
        call(tmp_path / "x.png")
