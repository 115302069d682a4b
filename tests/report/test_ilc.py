"""ILC plots draw the errors they are given (gtmodel.report.ilc, Figs. 7.7-7.11 style)."""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.report.ilc import case_title, plot_error_measure, plot_iteration_errors, plot_tool_path

from ._figures import assert_line, assert_png


def _square(n=200, side=0.010):
    s = np.linspace(0, 4, n)
    x = side * np.clip(np.minimum(s, 3 - s), 0, 1)
    y = side * np.clip(np.minimum(s - 1, 4 - s), 0, 1)
    return np.column_stack([x, y, np.zeros(n)]) + [0.0, 2.9, -0.5]


@pytest.mark.parametrize("relative", [True, False])
def test_error_measure_draws_each_column_per_case(tmp_path, relative):
    """One panel per case, one line per column, relative to iteration 0 or in m."""
    k = np.arange(11)[:, None]
    measures = {"1": 1e-3 * 0.6**k * np.array([[1.0, 2.0, 3.0]]), "3": 1e-4 * 0.5 ** np.arange(11)}
    fig = plot_error_measure(measures, tmp_path / "m.png", labels=["q1", "q2", "q3"], relative=relative)
    assert_png(tmp_path / "m.png")
    assert len(fig.axes) == 2
    m = measures["1"]
    for j, label in enumerate(["q1", "q2", "q3"]):
        assert_line(fig.axes[0], label, np.arange(11), m[:, j] / m[0, j] if relative else m[:, j])
    m3 = measures["3"]
    assert_line(fig.axes[1], "q1", np.arange(11), m3 / m3[0] if relative else m3)
    assert fig.axes[0].get_yscale() == "log"


@pytest.mark.parametrize(
    "name, signal, title",
    [
        ("1", "actuator", "Case 1: actuator positions"),
        ("2A", "complementary", "Case 2A: complementary filter (7.17)"),
        ("2B", "kalman", "Case 2B: Kalman filter (7.19)-(7.22)"),
        ("3", "tool", "Case 3: measured tool position"),
        ("2A", None, "Case 2A"),
        ("Case 4", "other", "Case 4: other"),
    ],
)
def test_panels_are_titled_as_cases_of_table_7_2(tmp_path, name, signal, title):
    """Defect (i) of issue 24: the panels were titled "1", "2A"."""
    assert case_title(name, signal) == title
    fig = plot_error_measure({name: np.ones(3)}, tmp_path / "m.png", signals=None if signal is None else {name: signal})
    assert fig.axes[0].get_title() == title


@pytest.mark.parametrize("n_paths", [1, 2])
def test_tool_path_draws_mm_from_the_first_reference_sample(tmp_path, n_paths):
    """Reference vs iterations, in mm relative to the first reference sample."""
    ref = _square()
    paths = {f"iteration {10 * k}": ref + 5e-4 / (k + 1) for k in range(n_paths)}
    fig = plot_tool_path(ref, paths, tmp_path / "p.png", title="Case 1")
    assert_png(tmp_path / "p.png")
    ax = fig.axes[0]
    origin = ref[0, :2]
    assert_line(ax, "reference", 1e3 * (ref[:, 0] - origin[0]), 1e3 * (ref[:, 1] - origin[1]))
    for label, p in paths.items():
        assert_line(ax, label, 1e3 * (p[:, 0] - origin[0]), 1e3 * (p[:, 1] - origin[1]))
    assert ax.get_xlabel() == "x [mm]" and ax.get_ylabel() == "y [mm]"


@pytest.mark.parametrize("iterations", [None, [0, 5, 10]])
def test_iteration_errors_draw_chosen_iterations_in_mm(tmp_path, iterations):
    """Error over time of the chosen iterations (default first and last), one panel per column."""
    eps = np.random.default_rng(0).standard_normal((11, 50, 2)) * 1e-4
    dt = 0.004
    fig = plot_iteration_errors(eps, dt, tmp_path / "e.png", iterations=iterations, labels=["x", "y"])
    assert_png(tmp_path / "e.png")
    t = np.arange(50) * dt
    for j, ax in enumerate(fig.axes):
        for k in iterations or [0, 10]:
            assert_line(ax, f"iteration {k}", t, 1e3 * eps[k, :, j])
    assert [ax.get_ylabel() for ax in fig.axes] == ["x [mm]", "y [mm]"]


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
