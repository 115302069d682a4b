"""The identification plot draws measured and model forces and their residuals (gtmodel.report.identification)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from gtmodel.calibration import DynamicRegressor
from gtmodel.report.identification import plot_identification_residuals

from ._figures import assert_line, assert_png


@pytest.fixture(scope="module")
def motion():
    rng = np.random.default_rng(0)
    n = 30
    T = np.array([0.0, 2.9, -0.5]) + rng.uniform(-0.1, 0.1, (n, 3))
    return np.linspace(0.0, 1.0, n), T, rng.normal(0, 0.3, (n, 3)), rng.normal(0, 2.0, (n, 3))


@pytest.mark.parametrize("smoothed", [False, True])
def test_measured_model_and_residual_per_actuator(tmp_path, motion, smoothed):
    t, T, Td, Tdd = motion
    reg = DynamicRegressor("L1", "model_2")
    theta = reg.theta_of()
    model = reg.forces(theta, T, Td, Tdd, "tcp")
    measured = model + np.array([5.0, -3.0, 1.0])
    smoother = (lambda x: 0.5 * x) if smoothed else None
    samples = SimpleNamespace(t=t, x=T, x_dot=Td, x_ddot=Tdd, tau=measured, coordinates="tcp", smoother=smoother)
    result = SimpleNamespace(theta=theta, residual_rms=np.array([5.0, 3.0, 1.0]), info={"min_speed": 0.01})
    fig = plot_identification_residuals("L1", 0, "model_2", samples, result, tmp_path / "r.png", title="demo")
    assert_png(tmp_path / "r.png")
    top, bottom = fig.axes[:3], fig.axes[3:]
    drawn = smoother(model) if smoothed else model
    q_dot = reg.evaluate(T, Td, Tdd, "tcp")[2]
    for i in range(3):
        assert_line(top[i], "measured (filtered)", t, measured[:, i])
        assert_line(top[i], "model (same filter)", t, drawn[:, i], rtol=1e-9, atol=1e-9)
        res = bottom[i].get_lines()[0]
        np.testing.assert_allclose(res.get_xdata(), q_dot[:, i], rtol=1e-9)
        np.testing.assert_allclose(res.get_ydata(), measured[:, i] - drawn[:, i], rtol=1e-9, atol=1e-9)
    assert fig.get_suptitle() == "demo: residual RMS [5.0, 3.0, 1.0] N"
