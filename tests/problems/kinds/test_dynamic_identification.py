"""Problem files of kind dynamic_identification (Dressler (2012), ch. 6.2, Table 6.3)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import time

from gtmodel.calibration import FourierTrajectory, simulate_log
from gtmodel.errors import ProblemError
from gtmodel.problems import load_problem, run_problem, solve_problem, write_results
from gtmodel.robots import load_parameters
from gtmodel.status import Status

from ...conftest import PROBLEMS_DIR, assert_bad_problem
from ...conftest import replace_once as _edit

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


@pytest.mark.parametrize("name", ["parameters.toml", "identification.csv", "residuals.png"])
def test_shipped_problem_writes_the_result_file(solved, name):
    out, _, _ = solved
    assert (out / name).is_file()


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
    ("unknown_truth_set", _edit('parameters = "L1"              # the true', 'parameters = "L9"              # the true'), r"field 'truth.parameters'"),
    ("missing_truth_file", _edit('parameters = "L1"              # the true', 'parameters = "no/such.toml"   # the true'),
     r"field 'truth.parameters': expected a shipped set .*or an existing file"),
    ("neither_data_nor_truth", lambda t: t[: t.index("\n[truth]")] + t[t.index("\n[filter]"):], r"declare exactly one of '\[data\]'"),
    ("duplicate_variant", _edit('variants = ["model_2", "model_1"', 'variants = ["model_2", "model_2"'), r"field 'identification.variants': expected a non-empty list of distinct"),
    ("empty_variants", _edit('variants = ["model_2", "model_1", "model_3", "model_4", "full"]', "variants = []"), r"field 'identification.variants'"),
    ("savgol_order_1", lambda t: _edit('method = "butter"', 'method = "savgol"')(_edit("order = 4", "order = 1")(t)), r"field 'filter.order': expected an integer >= 2"),
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


#: A bad file must be refused within this time [s] (nothing simulated, nothing allocated).
LOAD_TIME_LIMIT_S = 1.0

#: Values out of their physical range, of the wrong type or too large to simulate: each is
#: refused at load time, fast, naming the field.
OUT_OF_RANGE = [
    ("too_many_samples", "sample_time = 0.004", "sample_time = 1e-7", r"field 'truth.sample_time': expected at most 100000 samples"),
    ("too_long", "duration = 30.0", "duration = 1e308", r"field 'truth.duration': expected a number <= 10000"),
    ("duration_zero", "duration = 30.0", "duration = 0", r"field 'truth.duration': expected a positive number"),
    ("duration_nan", "duration = 30.0", "duration = nan", r"field 'truth.duration': expected a finite number"),
    ("sample_time_inf", "sample_time = 0.004", "sample_time = inf", r"field 'truth.sample_time': expected a finite number"),
    ("force_noise_1e308", "force_noise = 5.0", "force_noise = 1e308", r"field 'truth.force_noise': expected a number <= 1e\+07"),
    ("position_noise_1e308", "position_noise = 1e-6", "position_noise = 1e308", r"field 'truth.position_noise'"),
    ("resolution_negative", "position_resolution = 1e-6", "position_resolution = -1", r"field 'truth.position_resolution'"),
    ("stribeck_1e308", "stribeck_amplitude = [40.0, 40.0, 40.0]", "stribeck_amplitude = [1e308, 40.0, 40.0]", r"field 'truth.stribeck_amplitude'"),
    ("stribeck_short", "stribeck_amplitude = [40.0, 40.0, 40.0]", "stribeck_amplitude = [40.0]", r"field 'truth.stribeck_amplitude': expected a list of 3"),
    ("stribeck_string", "stribeck_amplitude = [40.0, 40.0, 40.0]", 'stribeck_amplitude = "big"', r"field 'truth.stribeck_amplitude'"),
    ("stribeck_velocity_zero", "stribeck_velocity = 0.02", "stribeck_velocity = 0", r"field 'truth.stribeck_velocity'"),
    ("seed_bool", "seed = 1", "seed = true", r"field 'truth.seed': expected an integer"),
    ("harmonics_huge", "harmonics = 4", "harmonics = 1000000", r"field 'excitation.harmonics': expected an integer in 1..20"),
    ("n_grid_huge", "n_grid = 60", "n_grid = 100000000", r"field 'excitation.n_grid': expected an integer in 8..1000"),
    ("period_1e308", "period = 10.0", "period = 1e308", r"field 'excitation.period'"),
    ("velocity_1e308", "max_velocity = 0.5", "max_velocity = 1e308", r"field 'excitation.max_velocity'"),
    ("acceleration_negative", "max_acceleration = 3.0", "max_acceleration = -1", r"field 'excitation.max_acceleration'"),
    ("centre_1e308", "T_center = [0.0, 2.9, -0.5]", "T_center = [0.0, 1e308, -0.5]", r"field 'excitation.T_center'"),
    ("centre_short", "T_center = [0.0, 2.9, -0.5]", "T_center = [0.0, 2.9]", r"field 'excitation.T_center': expected a list of 3"),
    ("optimize_string", "optimize = true", 'optimize = "yes"', r"field 'excitation.optimize': expected true or false"),
    ("max_iter_zero", "max_iter = 150", "max_iter = 0", r"field 'excitation.max_iter'"),
    ("cutoff_inf", "cutoff = 10.0", "cutoff = inf", r"field 'filter.cutoff': expected a finite number"),
    ("order_huge", "order = 4", "order = 1000", r"field 'filter.order'"),
    ("min_speed_1e308", "min_speed = 0.05", "min_speed = 1e308", r"field 'identification.min_speed'"),
    ("variants_string", 'variants = ["model_2", "model_1", "model_3", "model_4", "full"]', 'variants = "model_2"', r"field 'identification.variants'"),
    ("configuration_8", "configuration = 0", "configuration = 8", r"field 'robot.configuration': expected an integer in 0..7"),
    ("parameters_number", 'parameters = "L1"              # kinematics', "parameters = 1              # kinematics", r"field 'robot.parameters': expected a non-empty string"),
]


@pytest.mark.parametrize("case, old, new, match", OUT_OF_RANGE, ids=[c[0] for c in OUT_OF_RANGE])
def test_out_of_range_value_is_refused_fast(tmp_path, case, old, new, match):
    t0 = time.perf_counter()
    assert_bad_problem(tmp_path, SHIPPED, case, _edit(old, new), match)
    assert time.perf_counter() - t0 < LOAD_TIME_LIMIT_S


def test_log_file_relative_to_the_problem_file(tmp_path):
    """[data] file follows the one reference rule: relative to the problem file, not the cwd."""
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "p.toml").write_text(LOG_PROBLEM)
    (tmp_path / "log.csv").write_text("t_s,q1_m,q2_m,q3_m,tau1_N,tau2_N,tau3_N\n")
    with pytest.raises(ProblemError, match=r"field 'data.file': expected an existing file \(relative to .*sub\)"):
        load_problem(tmp_path / "sub" / "p.toml")


BAD_LOG = [
    ("empty", b"", r"field 'data.file': "),
    ("header_only", b"t_s,q1_m,q2_m,q3_m,tau1_N,tau2_N,tau3_N\n", r"field 'data.file': "),
    ("not_utf8", b"t_s,q1_m,q2_m,q3_m,tau1_N,tau2_N,tau3_N\n# caf\xe9\n0,0,0,0,0,0,0\n", r"field 'data.file': .*UTF-8"),
]


@pytest.mark.parametrize("case, content, match", BAD_LOG, ids=[c[0] for c in BAD_LOG])
def test_bad_log_file(tmp_path, case, content, match):
    """An empty, header-only or non-UTF-8 log: a ProblemError naming data.file."""
    (tmp_path / "log.csv").write_bytes(content)
    (tmp_path / "p.toml").write_text(LOG_PROBLEM)
    with pytest.raises(ProblemError, match=match):
        load_problem(tmp_path / "p.toml")


def test_truth_parameters_relative_to_the_problem_file(tmp_path):
    """[truth] parameters may be a parameter-set file beside the problem file."""
    (tmp_path / "true_robot.toml").write_text(load_parameters_text())
    text = SHIPPED.read_text().replace('parameters = "L1"              # the true', 'parameters = "true_robot.toml" # the true', 1)
    (tmp_path / "p.toml").write_text(text)
    decl = load_problem(tmp_path / "p.toml").declaration
    assert decl.truth["robot"].dynamics.m_p == load_parameters("L1").dynamics.m_p


def load_parameters_text() -> str:
    """The text of the shipped L1 parameter set."""
    from importlib import resources

    return (resources.files("gtmodel.robots") / "data" / "L1.toml").read_text(encoding="utf-8")


def test_bad_file_gives_invalid_input_and_no_result_files(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text(SHIPPED.read_text().replace("cutoff = 10.0", "cutoff = -1.0"))
    outcome = run_problem(f, tmp_path / "out")
    assert outcome.status == Status.INVALID_INPUT
    assert "filter.cutoff" in outcome.summary["message"]
    assert outcome.summary["files"] == ["summary.json"]
