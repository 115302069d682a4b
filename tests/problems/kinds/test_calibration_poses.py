"""Kind ``calibration``, ``[pose_selection]``: random or eq. 5.9 pose choice, and the truth comparison.

References: the synthetic truth (estimate - truth within a few predicted deviations; TCP
error against the noise-free truth at the noise level); reproducibility of seeded choices;
the planned selection (eq. 5.9 on the start model's FK) does not depend on the noise seed.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import ProblemError
from gtmodel.problems import load_problem, run_problem, solve_problem
from gtmodel.calibration.pose_choice import choose_poses
from gtmodel.problems.kinds.calibration_results import parameters_vs_truth

from ...conftest import REPO, replace_once as _edit

BASE = REPO / "studies" / "bases" / "l1_calibration_poses.toml"
#: Laser-tracker noise per axis [m] (the data's), the scale of the calibrated TCP error.
NOISE_M = 10e-6


def _choice(seed: int, method: str, n: int = 40):
    decl = load_problem(BASE, {"truth.seed": seed, "pose_selection.method": method, "pose_selection.n": n}).declaration
    return choose_poses(decl.models[0], decl.measurements, n, method, decl.pose_planned, decl.seed)


def test_random_choice_is_seeded():
    a, b, c = _choice(1, "random"), _choice(1, "random"), _choice(2, "random")
    assert np.array_equal(a.indices, b.indices) and not np.array_equal(a.indices, c.indices)
    assert a.indices.size == 40 and np.all(np.diff(a.indices) > 0)


def test_planned_selection_does_not_depend_on_the_noise():
    a, b = _choice(1, "condition"), _choice(2, "condition")
    assert np.array_equal(a.indices, b.indices)
    # eq. 5.14 on the kept poses: the greedy eq. 5.9 choice is better conditioned than a random one
    assert a.acceptance < _choice(1, "random").acceptance


@pytest.fixture(scope="module")
def summary(tmp_path_factory):
    out = tmp_path_factory.mktemp("poses") / "out"
    return run_problem(BASE, out, overrides={"pose_selection.method": "random", "pose_selection.n": 120}, plots=False).summary


def test_summary_reports_the_pose_choice(summary):
    assert (summary["pose_method"], summary["selected_poses"], summary["n_calibration"]) == ("random", 120, 60)
    assert summary["pose_acceptance"] > 0 and summary["pose_accepted"] in (True, False)


def test_parameters_against_the_truth(summary):
    # the truth is the synthetic data's robot, in the measurement frame: all 21 free and close
    params = summary["parameters"]
    z = np.array([(p["estimate"] - p["truth"]) / p["std"] for p in params.values()])
    assert len(params) == 21 and {p["role"] for p in params.values()} == {"free"}
    assert np.max(np.abs(z)) < 5.0


def test_tcp_error_against_the_noise_free_truth(summary):
    assert 0 < summary["truth_mean_error_m"] < NOISE_M


def test_fixed_parameters_are_marked():
    p = load_problem(BASE, {"pose_selection.method": "random", "models": [{"name": "m", "type": "three_link", "start": "L1_ideal",
                                                                             "fixed": ["L1"]}]})
    sol = solve_problem(p)
    table = parameters_vs_truth(sol.results[0][1], p.declaration.truth)
    assert table["L1"]["role"] == "fixed" and sum(v["role"] == "free" for v in table.values()) == 20


@pytest.mark.parametrize(
    "edit, match",
    [
        (_edit('method = "condition"', 'method = "best"'), r"field 'pose_selection\.method': expected one of condition, random"),
        (_edit("planned = true ", 'planned = "yes" '), r"field 'pose_selection\.planned': expected true or false"),
        (_edit("n = 120 ", "n = 778 "), r"field 'pose_selection\.n'"),
    ],
    ids=["bad_method", "planned_not_bool", "n_all_candidates"],
)
def test_bad_pose_selection(tmp_path, edit, match):
    f = tmp_path / "bad.toml"
    f.write_text(edit(BASE.read_text(encoding="utf-8")), encoding="utf-8")
    with pytest.raises(ProblemError, match=match):
        load_problem(f)
