"""Problem files of kind dynamic_identification (Dressler (2012), ch. 6.2, Table 6.3)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from gtmodel.calibration.identification import FourierTrajectory, simulate_log
from gtmodel.errors import ProblemError
from gtmodel.problems import load_problem, solve_problem, write_results
from gtmodel.robots.parameters import load_parameters

from ..conftest import PROBLEMS_DIR, assert_bad_problem
from ..conftest import replace_once as _edit

SHIPPED = PROBLEMS_DIR / "l1_dynamic_identification.toml"
#: Acceptance: model-2 estimates within this many standard deviations of the truth.
Z_LIMIT = 3.0
#: The unmodelled Stribeck friction must make the 0.02-0.05 m/s residual this many times
#: the high-speed one.
LOW_SPEED_FACTOR = 2.5


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    out = tmp_path_factory.mktemp("l1_dynamic_identification")
    problem = load_problem(SHIPPED)
    solution = solve_problem(problem)
    summary = write_results(problem, solution, out)
    return out, summary, solution


def test_shipped_problem_identifies_model_2_within_3_std(solved):
    """The shipped synthetic problem (Table 6.3 model 2 truth, 5 N noise, Stribeck term)
    returns every model-2 parameter within 3 std of the truth, status optimal."""
    out, summary, _ = solved
    assert summary["status"] == "optimal"
    assert summary["variant"] == "model_2"
    assert summary["n_within_3_std"] == 10 and summary["max_z"] <= Z_LIMIT
    assert json.loads((out / "summary.json").read_text())["status"] == "optimal"
    for f in ("parameters.toml", "identification.csv", "residuals.png"):
        assert (out / f).is_file()


def test_summary_reports_low_speed_residual_and_excitation(solved):
    """The Stribeck term the model lacks shows as the low-speed residual; the excitation
    design lowered the condition number; the variant table holds the thesis' rows."""
    _, summary, _ = solved
    low, high = np.array(summary["residual_rms_low_speed_N"]), np.array(summary["residual_rms_high_speed_N"])
    assert np.all(low > LOW_SPEED_FACTOR * high)
    ex = summary["excitation"]
    assert ex["condition_after"] < ex["condition_before"]
    names = [v["variant"] for v in summary["variants"]]
    assert names == ["model_2", "model_1", "model_3", "model_4", "full"]
    rows = {v["variant"]: v for v in summary["variants"]}
    assert rows["model_3"]["thesis_table_6_3_row"][4] is None or math.isnan(rows["model_3"]["thesis_table_6_3_row"][4])
    # model 2 (the truth's structure) fits best, as in the thesis' Table 6.3
    rms = {k: np.mean(v["residual_rms_N"]) for k, v in rows.items() if k != "full"}
    assert min(rms, key=rms.get) == "model_2"


def test_parameters_toml_is_a_loadable_parameter_set(solved):
    """parameters.toml loads with load_parameters and holds the identified model-2 values."""
    out, summary, _ = solved
    robot = load_parameters(out / "parameters.toml")
    assert robot.dynamics.m_p == pytest.approx(summary["parameters"]["m_p"]["estimate"])
    assert robot.dynamics.f_v[2] == pytest.approx(summary["parameters"]["f_v3"]["estimate"])


LOG_PROBLEM = """
name = "log_problem"
kind = "dynamic_identification"
[robot]
parameters = "L1"
[data]
file = "log.csv"
[identification]
variants = ["model_2", "model_4"]
"""


def test_problem_with_a_log_file(tmp_path):
    """A [data] log written by MotionLog.to_csv is identified like synthetic data."""
    rng = np.random.default_rng(0)
    tr = FourierTrajectory([0.0, 0.0, 0.0], 0.12 * rng.standard_normal((3, 3)), 0.12 * rng.standard_normal((3, 3)), 6.0)
    log, _ = simulate_log(tr, 12.0, "L1", force_noise=2.0, seed=2)
    log.to_csv(tmp_path / "log.csv")
    (tmp_path / "p.toml").write_text(LOG_PROBLEM)
    problem = load_problem(tmp_path / "p.toml")
    summary = write_results(problem, solve_problem(problem), tmp_path / "out", plots=False)
    assert summary["status"] == "optimal"
    assert summary["source"].startswith("measured log")
    assert abs(summary["parameters"]["m_p"]["estimate"] - 9.13) < 0.2


BAD = [
    ("data_and_truth", lambda t: t + '\n[data]\nfile = "x.csv"\n', r"declare exactly one of '\[data\]'"),
    ("unknown_field", _edit("seed = 1", "seed = 1\nnoise = 3"), r"unknown field 'truth.noise'"),
    ("bad_variant", _edit('variants = ["model_2"', 'variants = ["model_5"'), r"field 'identification.variants'"),
    ("bad_cutoff", _edit("cutoff = 10.0", 'cutoff = "fast"'), r"field 'filter.cutoff': expected a finite number"),
    ("bad_method", _edit('method = "butter"', 'method = "kalman"'), r"field 'filter.method': expected one of butter, savgol"),
    ("negative_noise", _edit("force_noise = 5.0", "force_noise = -5.0"), r"field 'truth.force_noise': expected a non-negative"),
    ("coarse_grid", _edit("n_grid = 60", "n_grid = 10"), r"field 'excitation.n_grid'"),
    ("unreachable_centre", _edit("T_center = [0.0, 2.9, -0.5]", "T_center = [0.0, 9.0, -0.5]"), r"field 'excitation.T_center': .*unreachable"),
    ("unknown_parameter_set", _edit('parameters = "L1"              # kinematics', 'parameters = "L9"              # kinematics'), r"field 'robot.parameters'"),
]


@pytest.mark.parametrize("case, edit, match", BAD, ids=[c[0] for c in BAD])
def test_bad_problem_file(tmp_path, case, edit, match):
    """Invalid fields give one ProblemError naming the file and the field."""
    assert_bad_problem(tmp_path, SHIPPED, case, edit, match)


def test_data_file_with_bad_row(tmp_path):
    """A log file with a NaN: the ProblemError names the problem field and the log's line."""
    rows = "\n".join(f"{0.004 * k:.3f},0.1,0.2,0.3,1,2,3" for k in range(40)).replace("0.040,0.1", "0.040,nan", 1)
    (tmp_path / "log.csv").write_text("t_s,q1_m,q2_m,q3_m,tau1_N,tau2_N,tau3_N\n" + rows + "\n")
    (tmp_path / "p.toml").write_text(LOG_PROBLEM)
    with pytest.raises(ProblemError, match=r"field 'data.file': .*line 12, column 'q1_m'"):
        load_problem(tmp_path / "p.toml")


def test_excitation_with_data_is_rejected(tmp_path):
    """[excitation] belongs to synthetic data: with [data] it is an error."""
    (tmp_path / "p.toml").write_text(LOG_PROBLEM + "\n[excitation]\nharmonics = 3\n")
    with pytest.raises(ProblemError, match=r"'\[excitation\]' is for synthetic data"):
        load_problem(tmp_path / "p.toml")
