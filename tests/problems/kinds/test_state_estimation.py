"""Kind ``state_estimation``: the fusion study of Cvitanic (2021), sec. 4.2-4.3, end to end, and its bad input.

Independent references: the thesis' Table 8 figures carried unchanged into the summary and the
tables; the summary's errors recomputed from the written ``fusion_baseline_*.csv`` (a second
reading of the runs); the judged structure (velocity >= 30 % below the four-point regression,
Table 9's ordering, NEES of the 5-axis EKF in its band).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from gtmodel.problems import load_problem, run_problem
from gtmodel.estimation.fusion.declared import StateEstimationDeclaration
from gtmodel.estimation.fusion.limits import THESIS_TABLE_10
from gtmodel.estimation.fusion.tracker_imu import TABLE_7
from gtmodel.status import Status

from ...conftest import PROBLEMS_DIR, assert_bad_problem, assert_bad_problem_through_cli, solve_through_cli
from ...conftest import replace_once as _edit

FILE = PROBLEMS_DIR / "kr500_state_estimation.toml"
SWEEP = FILE.read_text()[FILE.read_text().index("[study.sweep]"):]


def _quick(text: str) -> str:
    """The shipped file with a two-row Table 10 and a KF/EKF/UKF comparison (the baseline runs unchanged)."""
    text = text.replace(SWEEP, "[study.sweep]\n" + "\n".join(
        f"{k} = {v}" for k, v in [("position_noise_mm", "[]"), ("orientation_noise_deg", "[]"), ("gyro_bias_deg_s", "[8.0]"),
                                  ("gyro_noise_deg_s_rtHz", "[]"), ("accel_bias_m_s2", "[]"), ("accel_noise_m_s2_rtHz", "[]"),
                                  ("sample_time_s", "[0.01]"), ("feed_rate_mm_s", "[]"), ("transform_translation_error_mm", "[]"),
                                  ("transform_orientation_error_deg", "[]")]) + "\n")
    return _edit('comparison_filters = ["kf", "ekf", "ukf", "pf"]', 'comparison_filters = ["kf", "ekf", "ukf"]')(text)


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    folder = tmp_path_factory.mktemp("state_estimation")
    f = folder / "kr500_state_estimation.toml"
    f.write_text(_quick(FILE.read_text()))
    outcome = run_problem(f, folder / "out")
    return outcome, folder / "out"


def test_quick_run_writes_its_files(solved):
    outcome, out = solved
    assert outcome.exit_code == 0 and outcome.summary["status"] == "completed"
    names = ["table_8.md", "table_8.csv", "table_9.md", "table_9.csv", "table_10.md", "table_10.csv", "filter_comparison.md",
             "filter_comparison.csv", "fusion_baseline_3_axis.csv", "fusion_baseline_5_axis.csv", "velocity_3_axis.png",
             "velocity_5_axis.png", "angular_acceleration.png", "table_10.png"]
    assert not [n for n in names if not (out / n).is_file() or (out / n).stat().st_size == 0]
    s = json.loads((out / "summary.json").read_text())
    assert [(r["motion"], r["parameter"]) for r in s["table_10"]] == [("3-axis", "sample_time_s"), ("5-axis", "gyro_bias_deg_s"), ("5-axis", "sample_time_s")]
    assert [r["filter"] for r in s["filter_comparison"]] == ["kf", "ekf", "ukf", "ekf", "ukf"]
    assert isinstance(load_problem(FILE).declaration, StateEstimationDeclaration)


@pytest.mark.parametrize("motion", ["3-axis", "5-axis"])
def test_judged_structure(solved, motion):
    # the issue's lines: velocity >= 30 % below the regression, Table 9's ordering, position not degraded
    c = solved[0].summary["checks"][motion]
    assert c["velocity_fusion_30_percent_below_tracker"] and c["table_9_structure"] and c["position_fusion_not_worse_than_1_1_tracker"]
    v = solved[0].summary["velocity_mean_error_mm_s"][motion]
    assert v["fusion"] <= 0.7 * v["tracker"]


def test_nees_of_the_5_axis_run_is_not_overconfident(solved):
    # at the thesis' constant tangential speed the white jerk is the path's largest |jerk|, reached only at the crest
    # (1.84 s): elsewhere Q is generous, so the time-average NEES lies below the band (measured 13.7 against 16.7-19.3;
    # inside it with the feed along x, the former default): conservative, which the run's check (nees_not_overconfident) admits
    n = solved[0].summary["nees"]["5-axis"]
    assert n["dof"] == 18 and n["mean"] <= n["band"][1] and "nees_not_overconfident" not in solved[0].summary["failed_checks"]


def test_thesis_table_8_is_carried_beside_ours(solved):
    # reference [state_estimation.table_8]: position 0.0089 mm; acceleration 0.00018/0.00061 -> 0.00012/0.00040; w 0.070 -> 0.062
    t8 = solved[0].summary["table_8"]
    assert t8["3-axis"]["position_mm"]["thesis_sensor"] == 0.0089 and t8["5-axis"]["acceleration_m_s2"]["thesis_fusion"] == 0.00040
    assert t8["5-axis"]["angular_velocity_deg_s"]["thesis_sensor"] == 0.070 and "angular_velocity_deg_s" not in t8["3-axis"]
    assert "not in the reference data" in (solved[1] / "table_8.md").read_text()


@pytest.mark.parametrize("motion", ["3_axis", "5_axis"])
def test_summary_errors_are_those_of_the_written_runs(solved, motion):
    # second reading: the mean error norms from fusion_baseline_<motion>.csv (from the warm-up on)
    outcome, out = solved
    with open(out / f"fusion_baseline_{motion}.csv") as fh:
        header = fh.readline().strip().split(",")
    data = np.loadtxt(out / f"fusion_baseline_{motion}.csv", delimiter=",", skiprows=1)
    col = {h: data[:, k] for k, h in enumerate(header)}
    t8 = outcome.summary["table_8"][motion.replace("_", "-")]
    pairs = [(q, key, scale, who) for q, key, scale in (("velocity", "velocity_mm_s", 1e3), ("acceleration", "acceleration_m_s2", 1.0))
             for who in ("sensor", "fusion")]
    again = [scale * np.linalg.norm(np.column_stack([col[f"{q}_{c}_{who}"] - col[f"{q}_{c}_true"] for c in "xyz"]), axis=1).mean()
             for q, _, scale, who in pairs]
    assert again == pytest.approx([t8[key][who] for _, key, _, who in pairs], rel=1e-6)


@pytest.mark.slow
def test_shipped_file_through_the_cli(tmp_path):
    # the judged command: exit 0, the whole shipped study (~30 s of CPU)
    code, s = solve_through_cli(FILE, tmp_path / "out", "--no-plots")
    assert code == 0 and s["status"] == "completed"
    assert all(s["checks"][m]["velocity_fusion_30_percent_below_tracker"] and s["checks"][m]["table_9_structure"] for m in ("3-axis", "5-axis"))
    assert [r["filter"] for r in s["filter_comparison"]] == ["kf", "ekf", "ukf", "pf", "ekf", "ukf", "pf"]
    assert all(r["status"] == "completed" for r in s["filter_comparison"] + s["table_10"])


THESIS_FILE = PROBLEMS_DIR / "thesis" / "kr500_table_10.toml"


def test_thesis_table_10_file_searches_both_motions_with_both_tunings():
    study = load_problem(THESIS_FILE).declaration.study
    assert study.sweep_motions == ("3-axis", "5-axis") and study.limit_tunings == ("white_jerk", "appendix_b")
    assert study.limit_parameters == tuple(THESIS_TABLE_10) and study.comparison_filters == ()


@pytest.mark.slow
def test_table_10_limit_of_the_accelerometer_bias_on_the_thesis_file(tmp_path):
    # a part of problems/thesis/kr500_table_10.toml (~20 s): the 3-axis accelerometer bias, both tunings.
    # Independent reference: the thesis' Table 10 (< 0.001 m/s^2); the thesis' own Q (Appendix B) lands 0.93
    # decades above it: beyond half a decade (LIMIT_DECADES), so it differs (one decade passed it narrowly before);
    # our white-jerk Q a decade or more higher (it keeps the bias out of the velocity longer).
    text = THESIS_FILE.read_text()
    text = text.replace(text[text.index("[study.sweep]"):text.index("[study.limits]")], "[study.sweep]\n" + "\n".join(f"{k} = []" for k in TABLE_7) + "\n\n")
    text = _edit('sweep_motions = ["3-axis", "5-axis"]', 'sweep_motions = ["3-axis"]')(text)
    # the 3-axis rows only: the 5-axis baseline runs turn 10 deg about a fixed axis here (the thesis' normal-following
    # tool makes the 5-axis EKF overconfident, NEES 244 against [16.7, 19.4]: check_failed, the thesis file's status)
    text = _edit('rotation_law = "normal"', 'rotation_law = "sine"')(text)
    text = _edit("bisections = 4", 'bisections = 4\nparameters = ["accel_bias_m_s2"]')(text)
    (tmp_path / "t10.toml").write_text(text)
    outcome = run_problem(tmp_path / "t10.toml", tmp_path / "out")
    rows = {r["tuning"]: r for r in outcome.summary["table_10_limits"]}
    assert outcome.exit_code == 0 and set(rows) == {"white_jerk", "appendix_b"}
    assert 0.5 < rows["appendix_b"]["decades_from_thesis"] <= 1.0 and rows["appendix_b"]["verdict"] == "differs"
    assert rows["white_jerk"]["limit"] >= 10 * rows["appendix_b"]["limit"]
    ev = {t: {e["value"]: e for e in r["evaluations"]} for t, r in rows.items()}  # the bracket: fusion pays below it, not at its top
    wrong = [t for t, r in rows.items() if not (ev[t][r["pays_up_to"]]["fusion"] < ev[t][r["pays_up_to"]]["sensor"]
                                                 and ev[t][r["stops_at"]]["fusion"] >= ev[t][r["stops_at"]]["sensor"])]
    assert not wrong
    assert (tmp_path / "out" / "table_10_limits.md").is_file()


JUDGED = [
    ("zero_quaternion", _edit("initial_orientation = [1.0, 0.0, 0.0, 0.0]", "initial_orientation = [0.0, 0.0, 0.0, 0.0]"),
     r"bad\.toml: field 'path\.initial_orientation': expected a quaternion \[w, x, y, z\] of nonzero norm"),
    ("negative_noise", _edit("gyro_noise_deg_s_rtHz = 0.0016", "gyro_noise_deg_s_rtHz = -0.0016"),
     r"bad\.toml: field 'sensors\.gyro_noise_deg_s_rtHz': expected a positive number, got -0\.0016"),
    ("sample_time_longer_than_path", _edit("sample_time_s = 0.001", "sample_time_s = 5.0"),
     r"bad\.toml: field 'sensors\.sample_time_s': expected a sample time giving at least 10 samples over path\.duration = 3 s "
     r"\(at most 0\.333333 s; a sample time longer than the path has none\), got 5\.0"),
    ("covariance_not_positive_definite", _edit("initial_covariance = [1e-10, 1e-6, 1e-2, 1e-6, 1e-4, 1e-2]", "initial_covariance = [1e-10, -1e-6, 1e-2, 1e-6, 1e-4, 1e-2]"),
     r"bad\.toml: field 'filter\.initial_covariance': expected a positive definite covariance: 6 variances > 0 \(entry 1 is -1e-06\)"),
    ("q_not_positive_definite", _edit("appendix_b_q_diag = [2.54e-4", "appendix_b_q_diag = [0.0"),
     r"bad\.toml: field 'filter\.appendix_b_q_diag': expected a positive definite covariance: 9 variances > 0 \(entry 0 is 0\.0\)"),
]


@pytest.mark.parametrize("case, edit, match", JUDGED, ids=[c[0] for c in JUDGED])
def test_judged_bad_input_through_the_cli(tmp_path, capsys, case, edit, match):
    # exit 2, no traceback, one message naming the file and the field
    assert_bad_problem_through_cli(tmp_path, capsys, edit(FILE.read_text()), match)
    err = capsys.readouterr().err
    assert err.count("field '") <= 1


BAD = [
    ("zero_axis", _edit("rotation_axis = [0.5, 0.0, 0.8660254037844386]", "rotation_axis = [0.0, 0.0, 0.0]"), r"field 'path\.rotation_axis': expected a rotation axis of nonzero norm"),
    ("sweep_dt_longer", _edit("sample_time_s = [0.01]", "sample_time_s = [0.5]"), r"field 'study\.sweep\.sample_time_s': expected a sample time giving at least 10 samples over study\.sweep_duration = 3 s"),
    ("sweep_negative_noise", _edit("position_noise_mm = [0.64]", "position_noise_mm = [-0.64]"), r"field 'study\.sweep\.position_noise_mm': expected values the sensor model accepts"),
    ("too_many_samples", _edit("sample_time_s = 0.001", "sample_time_s = 1e-7"), r"field 'sensors\.sample_time_s': expected at most 200000 samples"),
    ("comparison_too_short", _edit("comparison_duration = 0.5", "comparison_duration = 0.005"), r"field 'study\.comparison_duration': expected at least 9 sample times"),
    ("warmup_too_long", _edit("warmup = 0.1", "warmup = 3.0"), r"field 'filter\.warmup': expected a warm-up shorter than path\.duration"),
    ("unknown_filter", _edit('comparison_filters = ["kf", "ekf", "ukf", "pf"]', 'comparison_filters = ["kf", "lms"]'), r"field 'study\.comparison_filters\[1\]': expected one of kf, ekf, ukf, pf"),
    ("particles_zero", _edit("particles = 1000", "particles = 0"), r"field 'study\.particles': expected an integer in 1\.\.100000"),
    ("unknown_field", _edit("seed = 1", "seed = 1\nnoise = 2"), r"unknown field 'sensors\.noise'"),
    ("seed_negative", _edit("seed = 1", "seed = -1"), r"field 'sensors\.seed': expected an integer in 0\.\."),
    ("feed_zero", _edit("feed_rate_mm_s = 42.33", "feed_rate_mm_s = 0.0"), r"field 'sensors\.feed_rate_mm_s': expected a positive number"),
    ("unknown_rotation_law", _edit("rotation_amplitude_deg = 10.0", 'rotation_amplitude_deg = 10.0\nrotation_law = "spin"'),
     r"field 'path\.rotation_law': expected one of sine, normal"),
    ("unknown_feed", _edit('\nfeed = "tangential"', '\nfeed = "arc"'),
     r"field 'path\.feed': expected one of x, tangential"),
    ("unknown_motion", _edit('sweep_motions = ["3-axis", "5-axis"]', 'sweep_motions = ["planar"]'), r"field 'study\.sweep_motions\[0\]': expected one of 3-axis, 5-axis"),
    ("unknown_tuning", _edit("[study.sweep]", '[study.limits]\ntunings = ["thesis"]\n\n[study.sweep]'), r"field 'study\.limits\.tunings\[0\]': expected one of white_jerk, appendix_b"),
]


@pytest.mark.parametrize("case, edit, match", BAD, ids=[c[0] for c in BAD])
def test_bad_state_estimation_problem(tmp_path, case, edit, match):
    assert_bad_problem(tmp_path, FILE, case, edit, match)


def test_status_is_an_enum_member(solved):
    assert solved[0].status is Status.COMPLETED


def test_tracker_imu_kalman_filter_rerun_from_the_exports(solved):
    """Independent: a plain numpy KF recursion (Joseph form) from the exported x0, P0, F, H, Q, R and the raw record."""
    s, out = solved[0].summary, solved[1]
    setup = np.load(out / "filter_setup_3_axis.npz")
    rec = np.loadtxt(out / "sensor_records_3_axis.csv", delimiter=",", skiprows=1)
    F, H, Q, R = setup["F"], setup["H"], setup["Q"], setup["R"]
    x, P = setup["x0"].copy(), setup["P0"].copy()
    xs = []
    for z in rec[1:, 1:]:  # (x0, P0) is the posterior at sample 0; every later sample: predict, update
        x, P = F @ x, F @ P @ F.T + Q
        S = H @ P @ H.T + R
        K = np.linalg.solve(S, H @ P).T
        x = x + K @ (z - H @ x)
        I_KH = np.eye(x.size) - K @ H
        P = I_KH @ P @ I_KH.T + K @ R @ K.T
        xs.append(x)
    xs = np.array(xs)
    base = np.loadtxt(out / "fusion_baseline_3_axis.csv", delimiter=",", skiprows=1)
    with open(out / "fusion_baseline_3_axis.csv") as fh:
        header = fh.readline().strip().split(",")
    col = {h: base[:, k] for k, h in enumerate(header)}
    k = np.rint(col["t"] / setup["dt"]).astype(int)  # samples of the metric
    true_v = np.column_stack([col[f"velocity_{c}_true"] for c in "xyz"])
    mine = 1e3 * np.linalg.norm(xs[k - 1, 3:6] - true_v, axis=1).mean()
    assert mine == pytest.approx(s["table_8"]["3-axis"]["velocity_mm_s"]["fusion"], rel=1e-6)
    true_p = np.column_stack([col[f"position_{c}_true"] for c in "xyz"])
    mine_p = 1e3 * np.linalg.norm(xs[k - 1, 0:3] - true_p, axis=1).mean()
    assert mine_p == pytest.approx(s["table_8"]["3-axis"]["position_mm"]["fusion"], rel=1e-3)  # truth written to 10 digits


@pytest.mark.parametrize("motion, nx, nz", [("3_axis", 9, 6), ("5_axis", 19, 13)])
def test_fusion_exports_hold_the_filter_setup(solved, motion, nx, nz):
    out = solved[1]
    setup = np.load(out / f"filter_setup_{motion}.npz")
    assert setup["x0"].shape == (nx,) and setup["P0"].shape == setup["Q"].shape == (nx, nx) and setup["R"].shape == (nz, nz)
    assert np.all(np.linalg.eigvalsh(setup["P0"]) > 0) and np.all(np.linalg.eigvalsh(setup["R"]) > 0)
    with open(out / f"sensor_records_{motion}.csv") as fh:
        assert len(fh.readline().split(",")) == 1 + nz
    assert json.loads((out / "summary.json").read_text())["failed_checks"] == []


@pytest.mark.slow
def test_table_10_transform_rows_at_constant_tangential_speed(tmp_path):
    # the two Table 10 rows the tangential feed concerns (~40 s), on the thesis file with [path] feed = "tangential" over
    # the thesis' 5 s window (one crest, at 1.84 s: its Figs. 24-25). Measured (docs/fidelity.md): the 3-axis orientation
    # error about the thesis' axis now matters (fused velocity error 0.11 -> 0.68 mm/s at 90 deg; x feed: flat) but fusion
    # still pays at 90 deg (tracker 4.56 mm/s); the 5-axis translation limit rises from 1.0 mm (x feed) to 7.5 mm, the
    # crests diluted, still a decade below the thesis' < 100 mm. Independent reference: the x-feed run of the same file.
    text = THESIS_FILE.read_text()
    text = text.replace(text[text.index("[study.sweep]"):text.index("[study.limits]")], "[study.sweep]\n" + "\n".join(f"{k} = []" for k in TABLE_7) + "\n\n")
    text = _edit("sweep_duration = 3.0", "sweep_duration = 5.0")(text)
    text = _edit('tunings = ["white_jerk", "appendix_b"]', 'tunings = ["white_jerk"]\nparameters = ["transform_orientation_error_deg", '
                                                           '"transform_translation_error_mm"]')(text)
    text = _edit('centred = ["sample_time_s"]', "centred = []")(text)
    rows = {}
    for feed in ("x", "tangential"):
        (tmp_path / f"{feed}.toml").write_text(_edit('\nfeed = "tangential"', f'\nfeed = "{feed}"')(text))
        outcome = run_problem(tmp_path / f"{feed}.toml", tmp_path / feed)
        rows[feed] = {(r["motion"], r["parameter"]): r for r in outcome.summary["table_10_limits"]}
    orient = {f: rows[f][("3-axis", "transform_orientation_error_deg")] for f in rows}
    grow = {f: orient[f]["evaluations"][-1]["fusion"] / orient[f]["evaluations"][0]["fusion"] for f in rows}
    assert grow["x"] < 1.05 and grow["tangential"] > 4.0 and orient["tangential"]["stops_at"] is None
    lim = {f: rows[f][("5-axis", "transform_translation_error_mm")]["limit"] for f in rows}
    assert 0.8 < lim["x"] < 1.25 and 6.0 < lim["tangential"] < 9.0
