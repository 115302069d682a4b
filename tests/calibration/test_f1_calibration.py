"""F1 calibration (Dressler (2012), ch. 5.4, Tables 5.4-5.5) on synthetic 6-D data."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gtmodel.calibration.kinematic import CalibrationProblem, ParameterSelection, analyze_identifiability
from gtmodel.calibration.evaluation import evaluate
from gtmodel.calibration.synthetic import device_noise, synthetic_measurements
from gtmodel.robots.f1 import load_f1

PROBLEM = Path(__file__).resolve().parents[2] / "problems" / "f1_calibration.toml"
#: Table 5.4: five fixed parameters and one tie.
TABLE_5_4_FIXED = ("Abj_2b_y", "r3_y", "r3_z", "Abj_3c_x", "Abj_3c_z")
TABLE_5_4_TIE = ("Abj_2b_z = Abj_2a_z",)
#: The shipped problem's set: Table 5.4 with r3_z replaced by the local rotation q1u3_ry
#: (the same gauge, fixed linearly; see problems/f1_calibration.toml).
SHIPPED_FIXED = ("Abj_2b_y", "r3_y", "q1u3_ry", "Abj_3c_x", "Abj_3c_z")
#: Validation mean error from the perturbed start relative to the calibration started at
#: the truth on the same data (the reachable optimum). The true model itself is ~5x better
#: on ~100 calibration poses for 63 parameters (estimation variance, not a local minimum:
#: the truth-started fit has the same cost), so "within 20 % of the true model" is not met.
OPTIMUM_RATIO = 1.05


@pytest.fixture(scope="module")
def f1_data():
    f1 = load_f1("F1")
    _, _, q = f1.workspace_grid(step_m=0.25, step_deg=10.0, return_q=True)
    data = synthetic_measurements(f1, q[::3], noise=device_noise("laser_tracker"), seed=0)
    return f1, data


def test_table_5_4_rank_deficiency(f1_data):
    f1, data = f1_data
    rep = analyze_identifiability(f1, data.q, data.T, data.quat)
    # 69 variables (72 parameters, each quaternion as 3 rotations): 6 gauge freedoms
    assert rep.n_parameters == 69
    assert rep.n_parameters - rep.rank == 6 == len(TABLE_5_4_FIXED) + len(TABLE_5_4_TIE)
    involved = set(rep.non_identifiable)
    for v in rep.non_identifiable.values():
        involved |= set(v["depends_on"])
    missing = [name for name in TABLE_5_4_FIXED + ("Abj_2b_z", "Abj_2a_z") if name not in involved]
    assert not missing, missing
    full = analyze_identifiability(f1, data.q, data.T, data.quat, fixed=TABLE_5_4_FIXED, ties=TABLE_5_4_TIE)
    assert full.rank == full.n_parameters == 63
    ours = analyze_identifiability(f1, data.q, data.T, data.quat, fixed=SHIPPED_FIXED, ties=TABLE_5_4_TIE)
    assert ours.rank == ours.n_parameters == 63
    # r3_x ~ 0.2 mm: fixing r3_z barely fixes the rotation of R1u3 about its local y
    assert ours.condition_number < 0.2 * full.condition_number


def test_calibration_reaches_noise_floor(f1_data):
    f1, data = f1_data
    rng = np.random.default_rng(1)
    start = f1.with_parameters(f1.parameter_vector() + rng.uniform(-0.004, 0.004, f1.n_parameters))
    cal, val = data.subset(np.arange(0, data.n_poses, 2)).split_alternate()
    sel = ParameterSelection(fixed=SHIPPED_FIXED, ties=TABLE_5_4_TIE)
    res = CalibrationProblem(start, sel).solve(cal, max_iter=500)
    assert res.success
    assert res.identifiability.rank == res.identifiability.n_parameters == 63
    bad = {k: n for k, n in res.quaternion_norms.items() if not abs(n - 1.0) < 1e-12}
    assert not bad, bad
    ref = CalibrationProblem(f1, sel).solve(cal, max_iter=500)
    assert res.cost == pytest.approx(ref.cost, rel=1e-6)
    assert evaluate(res.model, val).mean_error < OPTIMUM_RATIO * evaluate(ref.model, val).mean_error
