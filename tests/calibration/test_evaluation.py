"""Accuracy evaluation (eq. 5.5), principal error directions and sensitivity (eq. 5.8).

Independent references: errors of a model on its own noise-free FK data are zero; the
errors of a known rigid offset are that offset (closed form); a length change moves the
TCP by at least the change projected on the link (first-order closed form).
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.calibration.evaluation import SENSITIVITY_STEP, AccuracyReport, evaluate, parameter_sensitivity
from gtmodel.report.calibration import plot_error_histogram
from gtmodel.calibration.measurements import MeasurementSet
from gtmodel.calibration.poses import grid_poses
from gtmodel.calibration.synthetic import NO_NOISE, synthetic_measurements
from gtmodel.errors import InputError
from gtmodel.robots.closure import ThreeLinkClosure

#: Noise-free FK data reproduce the model [m].
ZERO_TOL = 1e-11
#: Offset recovered exactly [m].
OFFSET_TOL = 1e-12


@pytest.fixture(scope="module")
def l1():
    model = ThreeLinkClosure("L1")
    q = grid_poses(model, 0.25)
    return model, synthetic_measurements(model, q, noise=NO_NOISE, seed=0)


def test_model_on_its_own_data_has_zero_error(l1):
    model, data = l1
    rep = evaluate(model, data)
    assert rep.max_error < ZERO_TOL
    assert rep.angle_errors is None


def test_constant_offset_is_the_error_and_its_principal_direction(l1):
    model, data = l1
    offset = np.array([30e-6, -40e-6, 0.0])
    shifted = MeasurementSet(q=data.q, T=data.T + offset)
    rep = evaluate(model, shifted)
    np.testing.assert_allclose(rep.errors, np.linalg.norm(offset), atol=OFFSET_TOL)
    d, rms = rep.principal_directions()
    assert abs(abs(d[0] @ offset) / np.linalg.norm(offset) - 1) < 1e-9
    assert rms[0] == pytest.approx(np.linalg.norm(offset), rel=1e-9)
    assert rep.to_dict()["mean_error_m"] == pytest.approx(50e-6, rel=1e-9)


def test_sensitivity_of_link_lengths_is_of_the_order_of_the_step(l1):
    model, data = l1
    table = parameter_sensitivity(model, data.subset(np.arange(0, data.n_poses, 3)))
    names = dict(zip(table.names, table.position))
    bad = {k: names[k] for k in ("L1", "L2", "L3") if not SENSITIVITY_STEP * 0.5 < names[k] < SENSITIVITY_STEP * 10}
    assert not bad, bad
    assert table.ranked()[0][1] == pytest.approx(table.position.max())
    assert np.all(table.orientation == 0.0)


def test_histogram_png_is_written(tmp_path, l1):
    model, data = l1
    rep = AccuracyReport(np.full((10, 3), 1e-5))
    plot_error_histogram({"a": rep, "b": evaluate(model, data)}, tmp_path / "h.png")
    assert (tmp_path / "h.png").stat().st_size > 0


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda m, d: evaluate("L1", d), r"model: expected a ClosureModel"),
        (lambda m, d: evaluate(m, d.q), r"measurements: expected a MeasurementSet"),
        (lambda m, d: parameter_sensitivity(m, d, step=0.0), r"step: expected a positive"),
    ],
    ids=["model_not_closure", "data_not_measurements", "zero_step"],
)
def test_bad_arguments(l1, call, match):
    model, data = l1
    with pytest.raises(InputError, match=match):
        call(model, data)
