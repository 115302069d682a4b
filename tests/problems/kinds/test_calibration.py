"""Kind ``calibration``: the shipped problems end to end, and their bad input.

Independent references: the synthetic "truth" (parameters within 3 reported standard
deviations; validation error within 20 % of the true model's error on the same noisy
poses: the noise floor) and the thesis' order of the L1 models (Table 5.1: the 21-parameter
model is more accurate than the 15-parameter one).
"""

from __future__ import annotations

import re
import time
import tomllib

import pytest

from gtmodel._escape import toml_string
from gtmodel.errors import ProblemError
from gtmodel.problems import load_problem, run_problem
from gtmodel.calibration.comparison import CalibrationDeclaration
from gtmodel.problems.kinds.calibration import MAX_GRID_CANDIDATES
from gtmodel.robots.parameters import load_parameters
from gtmodel.status import Status

from ...conftest import PROBLEMS_DIR, replace_once as _edit

L1_FILE = PROBLEMS_DIR / "l1_calibration.toml"
F1_FILE = PROBLEMS_DIR / "f1_calibration.toml"
D1_FILE = PROBLEMS_DIR / "d1_error_models.toml"
#: Validation mean error vs the true model's on the same data (issue: within 20 %).
NOISE_FLOOR_RTOL = 0.20
#: Longest accepted time to reject a bad file [s] (bad input is found before any big grid).
REJECT_SECONDS = 5.0


@pytest.fixture(scope="module")
def l1(tmp_path_factory):
    out = tmp_path_factory.mktemp("l1cal")
    outcome = run_problem(L1_FILE, out)
    return outcome, out, outcome.summary


def test_l1_calibration_is_optimal_with_the_required_summary(l1):
    outcome, out, s = l1
    assert outcome.exit_code == 0
    assert s["status"] == "optimal"
    assert s["rank"] == s["n_parameters"] == 21 and s["non_identifiable"] == []
    assert s["n_calibration"] + s["n_validation"] == 778


@pytest.mark.parametrize(
    "key",
    ["status", "mean_error_m", "max_error_m", "rms_error_m", "n_calibration", "n_validation", "rank",
     "n_parameters", "non_identifiable", "iterations", "solve_time_s"],
)
def test_l1_calibration_summary_has_the_required_key(l1, key):
    _, _, s = l1
    assert key in s


@pytest.mark.parametrize("name", ["parameters.toml", "errors.csv", "error_histogram.png"])
def test_l1_calibration_writes_the_result_file(l1, name):
    _, out, _ = l1
    assert (out / name).stat().st_size > 0


def test_l1_validation_error_is_at_the_noise_floor(l1):
    _, _, s = l1
    assert abs(s["mean_error_m"] - s["noise_floor_mean_error_m"]) <= NOISE_FLOOR_RTOL * s["noise_floor_mean_error_m"]


def test_l1_parameters_within_three_standard_deviations_of_the_truth(l1):
    _, _, s = l1
    check = s["models"][0]["parameters_vs_truth"]
    assert check["n_free"] == 21 and check["n_within_3_std"] == 21


def test_modified_model_beats_the_ideal_one(l1):
    _, _, s = l1
    modified, ideal = s["models"]
    assert modified["mean_error_m"] < ideal["mean_error_m"]


def test_parameters_file_is_a_robot_parameter_set(l1):
    _, out, s = l1
    p = load_parameters(out / "parameters.toml")
    assert p.kinematics.model == "modified" and p.kinematics.L.shape == (3,)


def test_declaration_of_the_shipped_file():
    d = load_problem(L1_FILE).declaration
    assert isinstance(d, CalibrationDeclaration)
    assert (d.solver, d.max_iter, d.align, d.pose_selection, d.truth_exact) == ("lm", 200, True, None, True)
    assert [m["name"] for m in d.models] == ["modified", "ideal"]
    assert d.measurements.n_poses == 778


def _top(line: str):
    """An edit adding a top-level ``line`` after the ``kind`` line."""
    return _edit('kind = "calibration"\n', f'kind = "calibration"\n{line}\n')


BAD = [
    ("no_data_no_truth", _edit("\n[truth]\n", "\n[truth_]\n"), r"unknown field 'truth_'"),
    ("both_data_and_truth", _edit("\n[truth]\n", '\n[data]\nfile = "m.csv"\n\n[truth]\n'), r"exactly one of '\[data\]'"),
    ("missing_file", _edit("[truth]\nmodel", '[data]\nfile = "nothing.csv"\n\n[truth_off]\nmodel'), r"unknown field 'truth_off'"),
    ("bad_model_type", _edit('type = "three_link"', 'type = "four_link"'), r"field 'models\[0\]\.type': expected one of three_link"),
    ("unknown_parameter", _edit('start = "L1_ideal"             # the 15', 'fixed = ["Lx"]\nstart = "L1_ideal"             # the 15'), r"models\[0\]"),
    ("bad_noise", _edit('noise = "laser_tracker"', 'noise = "ruler"'), r"field 'truth\.noise': expected one of"),
    ("too_few_poses", _edit("grid_step = 0.1153", "grid_step = 0.9"), r"too few|poses"),
    ("bad_tie", _edit('start = "L1_ideal"  ', 'ties = ["L_1"]\nstart = "L1_ideal"  '), r"field 'models\[0\]'"),
    ("bad_solver", _edit('solver = "lm"', 'solver = "newton"'), r"field 'calibration\.solver'"),
    ("no_models", lambda t: _top("models = []")(t.split("[[models]]")[0]), r"field 'models': expected one or more \[\[models\]\] tables"),
    ("models_not_tables", lambda t: _top("models = [1]")(t.split("[[models]]")[0]), r"field 'models': expected one or more \[\[models\]\] tables"),
    ("unknown_model_field", _edit('parametrisation = "ideal"', 'parametrization = "ideal"'), r"unknown field 'models\[1\]\.parametrization'"),
    ("start_not_a_string", _edit('start = "L1_ideal"  ', "start = 3  "), r"field 'models\[0\]\.start'"),
    ("start_no_such_set", _edit('start = "L1_ideal"  ', 'start = "L9"  '), r"field 'models\[0\]\.start'"),
    ("truth_no_such_set", _edit('parameters = "L1"', 'parameters = "L9"'), r"field 'truth\.parameters'"),
    ("truth_wrong_set_type", _edit('model = "three_link"', 'model = "f1"'), r"field 'truth\.parameters'"),
    ("grid_and_random", _edit("grid_step = 0.1153", "grid_step = 0.1153\nrandom_poses = 10"), r"field 'truth\.random_poses'"),
    ("too_many_random_poses", _edit("grid_step = 0.1153", "random_poses = 1000000"), r"field 'truth\.random_poses'"),
    ("pose_selection_too_many", lambda t: t + "\n[pose_selection]\nn = 100000\n", r"field 'pose_selection\.n'"),
    ("bad_align", _edit("align = true", 'align = "yes"'), r"field 'calibration\.align': expected true or false"),
    ("bad_max_iter", _edit("max_iter = 200", "max_iter = 0"), r"field 'calibration\.max_iter'"),
    ("negative_seed", _edit("seed = 0", "seed = -1"), r"field 'truth\.seed'"),
    ("cyclic_period_without_errors", _edit("seed = 0", "seed = 0\ncyclic_period = 0.01"), r"field 'truth\.cyclic_period': expected actuator_errors = 'table_4_1'"),
    ("armwise_unknown_arm", _edit("[calibration]", '[[models]]\ntype = "armwise"\narms = ["modified", "nope", "ideal"]\n\n[calibration]'),
     r"field 'models\[2\]\.arms\[1\]': expected the name of an earlier declared, calibrated model"),
    ("armwise_two_arms", _edit("[calibration]", '[[models]]\ntype = "armwise"\narms = ["modified", "ideal"]\n\n[calibration]'),
     r"field 'models\[2\]\.arms': expected the names of 3 earlier declared models"),
    ("armwise_without_arms", _edit("[calibration]", '[[models]]\ntype = "armwise"\n\n[calibration]'), r"field 'models\[2\]\.arms'"),
    ("armwise_fixed", _edit("[calibration]", '[[models]]\ntype = "armwise"\narms = ["modified", "ideal", "ideal"]\nfixed = ["L1"]\n\n[calibration]'),
     r"field 'models\[2\]\.fixed': expected nothing for type = 'armwise'"),
    ("arms_on_a_calibrated_model", _edit('name = "ideal"', 'name = "ideal"\narms = ["modified", "modified", "modified"]'),
     r"field 'models\[1\]\.arms': expected no arms"),
    ("cyclic_period_negative", _edit("seed = 0", "seed = 0\ncyclic_period = -0.01"), r"field 'truth\.cyclic_period': expected a positive number"),
]

#: The fuzz reproducers of issue 12 (non-GtModelError exceptions or unbounded work before
#: the port): each must be a ProblemError naming its field, found quickly.
F1_FUZZ = [
    ("fixed_nested_list", _edit('fixed = ["Abj_2b_y", "r3_y", "q1u3_ry", "Abj_3c_x", "Abj_3c_z"]', 'fixed = [["Abj_2b_y"]]'),
     r"field 'models\[0\]\.fixed\[0\]'|field 'models\[0\]\.fixed': expected a list of strings"),
    ("fixed_number", _edit('fixed = ["Abj_2b_y", "r3_y", "q1u3_ry", "Abj_3c_x", "Abj_3c_z"]', "fixed = 1.0"),
     r"field 'models\[0\]\.fixed': expected a list of strings"),
    ("ties_number", _edit('ties = ["Abj_2b_z = Abj_2a_z"]', "ties = 5"), r"field 'models\[0\]\.ties': expected a list of strings"),
    ("perturbation_list", _edit("perturbation = 0.004", "perturbation = [0.1]"), r"field 'models\[0\]\.perturbation': expected a finite number"),
    ("perturbation_string", _edit("perturbation = 0.004", 'perturbation = "abc"'), r"field 'models\[0\]\.perturbation': expected a finite number"),
    ("perturbation_nan", _edit("perturbation = 0.004", "perturbation = nan"), r"field 'models\[0\]\.perturbation': expected a finite number"),
    ("perturbation_inf", _edit("perturbation = 0.004", "perturbation = inf"), r"field 'models\[0\]\.perturbation': expected a finite number"),
    ("perturbation_negative", _edit("perturbation = 0.004", "perturbation = -1.0"), r"field 'models\[0\]\.perturbation': expected a non-negative number"),
    ("perturbation_huge", _edit("perturbation = 0.004", "perturbation = 1e308"), r"field 'models\[0\]\.perturbation': expected a number <= 0\.1"),
    ("grid_step_tiny", _edit("grid_step = 0.25", "grid_step = 1e-7"), r"field 'truth\.grid_step': expected a grid step giving at most"),
    ("grid_step_fine", _edit("grid_step = 0.25", "grid_step = 0.005"), r"field 'truth\.grid_step': expected a grid step giving at most"),
    ("grid_step_deg_tiny", _edit("grid_step_deg = 10.0", "grid_step_deg = 1e-9"), r"field 'truth\.grid_step_deg': expected an angular step"),
    ("grid_step_deg_negative", _edit("grid_step_deg = 10.0", "grid_step_deg = -10.0"), r"field 'truth\.grid_step_deg': expected a positive number"),
    ("grid_step_string", _edit("grid_step = 0.25", 'grid_step = "fine"'), r"field 'truth\.grid_step': expected a finite number"),
    ("grid_step_bool", _edit("grid_step = 0.25", "grid_step = true"), r"field 'truth\.grid_step': expected a finite number"),
    ("f1_random_poses", _edit("grid_step = 0.25", "random_poses = 100"), r"field 'truth\.random_poses'"),
    ("rotary_travel_bad_shape", _edit("seed = 0", "seed = 0\nrotary_travel_deg = [1.0, 2.0]"), r"field 'truth\.rotary_travel_deg"),
    ("rotary_step_zero", _edit("seed = 0", "seed = 0\nrotary_step_deg = 0"), r"field 'truth\.rotary_step_deg': expected a positive number"),
    ("start_no_such_set", _edit('start = "F1"', 'start = "str"'), r"field 'models\[0\]\.start': expected a shipped set"),
    ("pose_selection_bool", _edit("n = 185", "n = true"), r"field 'pose_selection\.n': expected an integer"),
]


def _load_bad(tmp_path, base, case, edit):
    f = tmp_path / f"{case}.toml"
    f.write_text(edit(base.read_text()))
    t0 = time.perf_counter()
    with pytest.raises(ProblemError) as info:
        load_problem(f)
    return f, info.value, time.perf_counter() - t0


@pytest.mark.parametrize("case, edit, match", BAD, ids=[c[0] for c in BAD])
def test_bad_calibration_files(tmp_path, case, edit, match):
    f, err, _ = _load_bad(tmp_path, L1_FILE, case, edit)
    assert re.search(match, str(err)), err
    assert str(f) in str(err).splitlines()[0]


@pytest.mark.parametrize("case, edit, match", F1_FUZZ, ids=[c[0] for c in F1_FUZZ])
def test_fuzz_reproducers_are_errors_naming_their_field(tmp_path, case, edit, match):
    _, err, seconds = _load_bad(tmp_path, F1_FILE, case, edit)
    assert re.search(match, str(err)), err
    assert seconds < REJECT_SECONDS


@pytest.mark.parametrize(
    "edit, match",
    [
        (_edit("grid_step = 0.1153", "grid_step = 0.005"), r"field 'truth\.grid_step': expected a grid step giving at most"),
        (_edit("grid_step = 0.1153", "grid_step = 1e-300"), r"field 'truth\.grid_step': expected a grid step giving at most"),
    ],
    ids=["l1_0.005", "l1_1e-300"],
)
def test_three_link_grid_is_bounded_up_front(tmp_path, edit, match):
    _, err, seconds = _load_bad(tmp_path, L1_FILE, "grid", edit)
    assert re.search(match, str(err)), err
    assert f"at most {MAX_GRID_CANDIDATES['three_link']}" in str(err)
    assert seconds < REJECT_SECONDS


def test_six_link_grid_is_bounded_up_front(tmp_path):
    _, err, seconds = _load_bad(tmp_path, D1_FILE, "grid", _edit("grid_step = 0.10", "grid_step = 0.01"))
    assert re.search(r"field 'truth\.grid_step': expected a grid step giving at most", str(err)), err
    assert seconds < REJECT_SECONDS


def test_six_link_selection_larger_than_the_grid_is_refused_before_the_data_are_built(tmp_path):
    # the D1 grid's synthetic data are built at solve time (0.9 CPU-s of forward kinematics);
    # a selection of more poses than the grid's candidates is refused at load all the same
    _, err, seconds = _load_bad(tmp_path, D1_FILE, "selection", lambda t: t + "\n[pose_selection]\nn = 100000\n")
    assert re.search(r"field 'pose_selection\.n': expected fewer poses than the \d+ candidates", str(err)), err
    assert seconds < REJECT_SECONDS


def test_bad_file_gives_invalid_input_and_no_data_files(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text(_edit('noise = "laser_tracker"', 'noise = "ruler"')(L1_FILE.read_text()))
    outcome = run_problem(f, tmp_path / "out", plots=False)
    assert outcome.status == Status.INVALID_INPUT and outcome.exit_code == 2
    assert re.search(r"field 'truth\.noise'", outcome.summary["message"])
    assert outcome.summary["files"] == ["summary.json"]


def _measured(tmp_path, csv_text: str):
    csv = tmp_path / "m.csv"
    if isinstance(csv_text, bytes):
        csv.write_bytes(csv_text)
    else:
        csv.write_text(csv_text)
    f = tmp_path / "p.toml"
    text = L1_FILE.read_text()
    head, _, tail = text.partition("\n[truth]\n")
    tail = tail.split("[[models]]", 1)[1]
    f.write_text(head + '\n[data]\nfile = "m.csv"\n\n[[models]]' + tail)
    return f


def test_measured_data_file_with_a_bad_row_names_the_row(tmp_path):
    f = _measured(tmp_path, "q1_m,q2_m,q3_m,Tx_m,Ty_m,Tz_m\n0,0,0,0.1,2.9,-0.5\n0.1,0.1,nan,0.1,2.9,-0.5\n")
    with pytest.raises(ProblemError, match=r"field 'data\.file': .*m\.csv: line 3, column 'q3_m'"):
        load_problem(f)


@pytest.mark.parametrize(
    "content",
    [b"", b"q1_m,q2_m,q3_m,Tx_m,Ty_m,Tz_m\n", b"q1_m,q2_m,q3_m,Tx_m,Ty_m,Tz_m\n0,0,0,0.1,2.9,-0.5\xff\n", b"\xff\xfe\x00q"],
    ids=["empty", "header_only", "not_utf8_row", "not_utf8"],
)
def test_unreadable_measurement_files_name_the_field(tmp_path, content):
    f = _measured(tmp_path, content)
    with pytest.raises(ProblemError, match=r"field 'data\.file'"):
        load_problem(f)


def test_missing_measurement_file_names_the_field(tmp_path):
    f = _measured(tmp_path, "")
    (tmp_path / "m.csv").unlink()
    with pytest.raises(ProblemError, match=r"field 'data\.file': expected .*an existing file"):
        load_problem(f)


def test_problem_file_not_utf8(tmp_path):
    f = tmp_path / "p.toml"
    f.write_bytes(L1_FILE.read_bytes().replace(b"L1 21-parameter", b"L1 \xff21-parameter"))
    with pytest.raises(ProblemError):
        load_problem(f)


@pytest.mark.slow  # tens of seconds of the default run's budget (measured 2026-11-28)
def test_d1_piecewise_actuator_models_beat_the_linear_ones(tmp_path):
    """Dressler (2012), Table 5.3: with actuator non-linearity in the data, the piecewise-linear
    actuator models (2, 4) are more accurate than their linear counterparts (1, 3)."""
    outcome = run_problem(D1_FILE, tmp_path / "d1", plots=False)
    assert outcome.exit_code == 0
    models = {m["name"][0]: m for m in outcome.summary["models"]}
    assert all(m["status"] == "optimal" for m in models.values())
    assert models["2"]["mean_error_m"] < models["1"]["mean_error_m"]
    assert models["4"]["mean_error_m"] < models["3"]["mean_error_m"]


def test_measured_orientation_range_against_scipy_euler():
    """Fig. 4.7's figure: ZYZ angle ranges of the measured plate orientation (scipy's intrinsic 'ZYZ' as reference)."""
    import numpy as np
    from scipy.spatial.transform import Rotation

    from gtmodel.calibration import MeasurementSet
    from gtmodel.problems.kinds.calibration_results import measured_orientation_range_deg

    rng = np.random.default_rng(3)
    nominal = Rotation.from_euler("ZYZ", [85.0, 100.0, -88.0], degrees=True)
    rots = Rotation.from_rotvec(rng.normal(scale=np.radians(0.1), size=(40, 3))) * nominal
    quat = rots.as_quat()[:, [3, 0, 1, 2]]
    data = MeasurementSet(q=np.zeros((40, 3)), T=np.zeros((40, 3)), quat=quat)
    e = rots.as_euler("ZYZ", degrees=True)
    assert measured_orientation_range_deg(data) == pytest.approx(list(e.max(axis=0) - e.min(axis=0)), abs=1e-9)
    assert measured_orientation_range_deg(MeasurementSet(q=np.zeros((2, 3)), T=np.zeros((2, 3)))) is None


def test_a_problem_name_with_quotes_and_brackets_reads_back_from_the_parameters_file(tmp_path):
    """The problem's name goes into ``parameters.toml`` as a TOML string (gtmodel._escape.toml_string):
    tomllib reads the calibrated set's name back exactly, and no table is injected."""
    shown = 'l1 "quoted" ] [evil] x = "1'  # a name that names a folder: printable, no '/' or '\\'
    text = _edit('name = "l1_calibration"', f"name = {toml_string(shown)}")(L1_FILE.read_text())
    problem = tmp_path / "quoted.toml"
    problem.write_text(text, encoding="utf-8")
    outcome = run_problem(problem, tmp_path / "out")
    data = tomllib.loads((tmp_path / "out" / "parameters.toml").read_text(encoding="utf-8"))
    assert outcome.summary["name"] == shown
    assert data["name"] == f"{shown}_calibrated" and "evil" not in data
    assert load_parameters(tmp_path / "out" / "parameters.toml").kinematics.model == "modified"
