"""The error histogram counts the errors of each report (gtmodel.report.calibration)."""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.calibration.evaluation import AccuracyReport
from gtmodel.report.calibration import plot_error_histogram

from ._figures import assert_png


def _report(seed, scale):
    return AccuracyReport(np.random.default_rng(seed).normal(0.0, scale, (40, 3)))


@pytest.mark.parametrize("bins", [10, 30])
@pytest.mark.parametrize("n_reports", [1, 2])
def test_histogram_counts_every_error_on_shared_edges(tmp_path, bins, n_reports):
    reports = {f"model {k}": _report(k, 1e-5 * (k + 1)) for k in range(n_reports)}
    fig = plot_error_histogram(reports, tmp_path / "h.png", bins=bins)
    assert_png(tmp_path / "h.png")
    ax = fig.axes[0]
    top = max(r.max_error for r in reports.values()) * 1e6
    edges = np.linspace(0.0, top, bins + 1)
    patches = ax.patches
    assert len(patches) == bins * n_reports
    for k, (label, r) in enumerate(reports.items()):
        heights = np.array([p.get_height() for p in patches[k * bins:(k + 1) * bins]])
        np.testing.assert_array_equal(heights, np.histogram(r.errors * 1e6, bins=edges)[0])
        lefts = np.array([p.get_x() for p in patches[k * bins:(k + 1) * bins]])
        np.testing.assert_allclose(lefts, edges[:-1], atol=1e-9)
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert texts[0].startswith("model 0: mean") and ax.get_xlabel() == "TCP error [um]"
