"""Kind ``optimal_control``: parameter estimation from measured data (``[[data]]``).

A decay ``x' = -k x`` whose rate ``k`` and (free) initial value are fitted to noisy
samples of ``a exp(-k t)``. Reference: ``scipy.optimize.curve_fit`` of the closed form
(the same weighted least squares, ``absolute_sigma=True``): the estimates and their
standard deviations agree, which checks the Gauss-Newton covariance reduced by the
transcription's constraints (the free initial value is estimated too). Bad input: exit 2
naming the file and field (NaN in the CSV, a missing column, a time outside the horizon).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import curve_fit

from gtmodel.problems import run_problem
from gtmodel.status import Status

from ...conftest import assert_bad_problem_through_cli

MODEL = '''
from gtmodel.modeling import Model


class Decay:
    def build(self):
        m = Model("decay")
        x = m.state("x", start=1.0)
        k = m.parameter("k", 1.0)
        m.equation(m.der(x), -k * x)
        m.output("y", x)
        return m
'''
PROBLEM = '''
kind = "optimal_control"
[model]
file = "decay.py"
class = "Decay"
[optimization.final_time]
free = false
value = 2.0
[free_parameters]
k = [0.0, 10.0]
[[data]]
file = "measured.csv"
time_column = "t"
measures = ["y"]
columns = ["y_meas"]
std = [0.02]
[transcription]
method = "{method}"
intervals = 40
[collocation]
elements = 40
'''
SIGMA = 0.02


@pytest.fixture
def folder(tmp_path):
    rng = np.random.default_rng(1)
    t = np.linspace(0.1, 2.0, 20)
    y = 2.0 * np.exp(-1.3 * t) + SIGMA * rng.standard_normal(t.size)
    (tmp_path / "decay.py").write_text(MODEL)
    (tmp_path / "measured.csv").write_text("t,y_meas\n" + "".join(f"{a:.17g},{b:.17g}\n" for a, b in zip(t, y)))
    return tmp_path, t, y


@pytest.mark.parametrize("method", ["collocation", "multiple_shooting"])
def test_estimates_and_standard_deviations_match_scipy(folder, method):
    tmp, t, y = folder
    (tmp / "p.toml").write_text(PROBLEM.format(method=method))
    outcome = run_problem(tmp / "p.toml", tmp / "out", plots=False)
    assert outcome.status == Status.OPTIMAL
    popt, pcov = curve_fit(lambda t, k, a: a * np.exp(-k * t), t, y, p0=[1.0, 1.0], sigma=np.full(t.size, SIGMA), absolute_sigma=True)
    est = outcome.summary["estimation"]
    assert est["estimates"]["k"]["value"] == pytest.approx(popt[0], rel=1e-6)
    assert est["estimates"]["k"]["std"] == pytest.approx(np.sqrt(pcov[0, 0]), rel=1e-4)
    assert outcome.summary["model_parameters"]["k"] == pytest.approx(popt[0], rel=1e-6)
    residual = y - popt[1] * np.exp(-popt[0] * t)
    assert est["residuals"]["y"]["rms"] == pytest.approx(np.sqrt(np.mean(residual**2)), rel=1e-4)
    assert est["chi2_per_dof"] == pytest.approx(np.sum((residual / SIGMA) ** 2) / (t.size - 1), rel=1e-4)


@pytest.mark.slow
def test_refined_mesh_keeps_the_estimates(folder):
    # [transcription] refine with [[data]]: the mesh of 10 elements (data times between its
    # points) is refined to the tolerance, and the statistics are those of the refined
    # mesh's transcription: the same estimates as scipy's fit of the closed form
    tmp, t, y = folder
    text = PROBLEM.format(method="collocation").replace("elements = 40", "elements = 10")
    text = text.replace("intervals = 40", "refine = true\ntolerance = 1e-6")
    (tmp / "r.toml").write_text(text)
    outcome = run_problem(tmp / "r.toml", tmp / "out", plots=False)
    assert outcome.status == Status.OPTIMAL and len(outcome.summary["refinement"]) > 1
    assert outcome.summary["verification"]["passed"] and outcome.summary["verification"]["tolerance"] == 1e-6
    popt, pcov = curve_fit(lambda t, k, a: a * np.exp(-k * t), t, y, p0=[1.0, 1.0], sigma=np.full(t.size, SIGMA), absolute_sigma=True)
    est = outcome.summary["estimation"]["estimates"]["k"]
    assert est["value"] == pytest.approx(popt[0], rel=1e-6) and est["std"] == pytest.approx(np.sqrt(pcov[0, 0]), rel=1e-4)


BAD = [
    ("nan_in_csv", lambda p, c: (p, c.replace("\n0.2", "\nnan", 1)), r"field 'data\[0\]\.file': .*measured\.csv.*line 3"),
    ("missing_column", lambda p, c: (p.replace('columns = ["y_meas"]', 'columns = ["y_m"]'), c), r"field 'data\[0\]\.columns': expected a column of measured\.csv \(t, y_meas\), got 'y_m'"),
    ("unknown_measured_name", lambda p, c: (p.replace('measures = ["y"]', 'measures = ["z"]'), c), r"field 'data\[0\]\.measures': expected names of the model's outputs, states or algebraic variables \(.*x.*y"),
    ("time_outside_horizon", lambda p, c: (p.replace("value = 2.0", "value = 1.0"), c), r"field 'data\[0\]\.file': timed variable at t = 1\.1 s: outside the horizon \[0, 1\] s"),
    ("std_and_weights", lambda p, c: (p.replace("std = [0.02]", "std = [0.02]\nweights = [1.0]"), c), r"field 'data\[0\]\.weights': expected std or weights, not both"),
    ("std_count", lambda p, c: (p.replace("std = [0.02]", "std = [0.02, 0.03]"), c), r"field 'data\[0\]\.std': expected one value or one per measured name \(1\)"),
    ("std_negative", lambda p, c: (p.replace("std = [0.02]", "std = [-0.02]"), c), r"field 'data\[0\]\.std': expected 1 positive numbers"),
    ("data_with_free_final_time", lambda p, c: (p.replace("free = false\nvalue = 2.0", "free = true\nbounds = [1.0, 3.0]"), c), r"field 'data\[0\]\.file': data 'y': measurements are at fixed times; fit them on a fixed final time"),
    ("csv_missing", lambda p, c: (p.replace('file = "measured.csv"', 'file = "nope.csv"'), c), r"field 'data\[0\]\.file'"),
    ("time_column_missing", lambda p, c: (p.replace('time_column = "t"', 'time_column = "time"'), c), r"field 'data\[0\]\.time_column': expected a column of measured\.csv"),
]


@pytest.mark.parametrize("case, edit, match", BAD, ids=[b[0] for b in BAD])
def test_bad_data_through_cli(folder, capsys, case, edit, match):
    tmp, _, _ = folder
    problem, csv = edit(PROBLEM.format(method="collocation"), (tmp / "measured.csv").read_text())
    (tmp / "measured.csv").write_text(csv)
    assert_bad_problem_through_cli(tmp, capsys, problem, match)
