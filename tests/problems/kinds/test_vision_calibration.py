"""``vision_calibration`` problem files end to end, and their bad input.

Independent references: the synthetic truth (true robot with actuator errors, true lens),
the laser-tracker calibration of the same poses, and the structure of Dressler (2012),
ch. 5.5 (vision error in millimetres growing towards the image border; the calibrated model
about an order of magnitude less accurate than with the tracker; parameters differing by
millimetres).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from gtmodel.calibration.vision import read_stereo_corners
from gtmodel.problems import load_problem, run_problem

from ...conftest import PROBLEMS_DIR, assert_bad_problem, assert_bad_problem_through_cli
from ...conftest import replace_once as _edit

FILE = PROBLEMS_DIR / "l1_vision_calibration.toml"

CAMERA_1_LOOK = "look_at = [-0.05, 2.85, -0.51]\n\n[[cameras]]"


@pytest.mark.slow
def test_shipped_problem_reproduces_the_structure_of_section_5_5(tmp_path):
    out = tmp_path / "out"
    outcome = run_problem(FILE, out)
    s = json.loads((out / "summary.json").read_text())
    assert outcome.status.success, s["message"]
    assert 1e-3 <= s["vision_measurement_error_mean_m"] <= 3e-3                       # thesis 1.7 mm
    assert s["vision_measurement_error_outer_half_mean_m"] > s["vision_measurement_error_inner_half_mean_m"]
    assert s["vision_error_radius_spearman"] > 0.1
    assert s["tracker_calibration_mean_error_vs_truth_m"] < 200e-6                     # thesis 125 um
    assert s["accuracy_ratio_vision_over_tracker"] >= 5                                 # thesis 1.5 mm / 125 um = 12
    assert 1e-3 <= s["parameter_difference_max_m"] <= 30e-3                             # thesis up to 9 mm
    assert s["poses_detected"] < s["poses_commanded"]                                   # detection failures
    assert s["relative_orientation"]["rotation_error_rad"] < 1e-2
    files = ("camera_views.png", "reconstruction.png", "vision_errors.png", "vision_tcp.csv", "parameters.toml")
    assert [f for f in files if not (out / f).is_file() or (out / f).stat().st_size == 0] == []


@pytest.fixture(scope="module")
def corner_file(tmp_path_factory):
    """The shipped problem's images as a corner file, and a [data] problem reading it."""
    d = tmp_path_factory.mktemp("vision_data")
    decl = load_problem(FILE).declaration
    decl.images.subset(np.arange(24)).to_csv(d / "corners.csv")
    text = FILE.read_text()
    head, tail = text.split("\n[truth]\n", 1)
    tail = tail.split("[[cameras]]", 1)[1]
    data = head + '[data]\nfile = "corners.csv"\n\n[[cameras]]' + tail
    data = data.replace("true_distortion = [-0.14, 0.1, 0.0, 0.0, 0.0]  # the lens as it is\n", "")
    data = data.replace("true_distortion = [-0.24, 0.08, 0.0, 0.0, 0.0]\n", "")
    (d / "data.toml").write_text(data)
    return d


def test_measured_corners_run(corner_file, tmp_path):
    outcome = run_problem(corner_file / "data.toml", tmp_path / "out", plots=False)
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert outcome.status.success, s["message"]
    assert s["poses_detected"] == 24 and s["tracker_calibration_mean_error_m"] is None
    assert read_stereo_corners(corner_file / "corners.csv", 20).n_poses == 24


def test_corners_noisier_than_declared_fail_the_self_check(corner_file, tmp_path):
    """The corners carry 0.5 px noise and a lens error; declared 0.1 px: check_failed (exit 1), never success."""
    text = (corner_file / "data.toml").read_text().replace("pixel_sigma = 0.5 ", "pixel_sigma = 0.1 ")
    (tmp_path / "corners.csv").write_text((corner_file / "corners.csv").read_text())
    (tmp_path / "p.toml").write_text(text)
    outcome = run_problem(tmp_path / "p.toml", tmp_path / "out", plots=False)
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert outcome.status == "check_failed" and s["message"].startswith("CHECK FAILED: reprojection RMS")


def test_corner_file_with_a_missing_corner_exits_2_naming_the_row(corner_file, tmp_path, capsys):
    lines = (corner_file / "corners.csv").read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("pose,")) + 2 * 20 + 7  # corner 7 of the third pose
    pose, corner = lines[k].split(",")[:2]
    (tmp_path / "corners.csv").write_text("\n".join(lines[:k] + lines[k + 1:]) + "\n")
    text = (corner_file / "data.toml").read_text()
    assert_bad_problem_through_cli(tmp_path, capsys, text, rf"field 'data\.file'.*line \d+, column 'corner': pose {pose} lacks corner\(s\) {corner} of 20")


BAD = [
    ("one_camera", lambda t: t[: t.rindex("[[cameras]]")] + t[t.index("[pattern]"):], r"field 'cameras': expected exactly two"),
    ("zero_noise", _edit("pixel_sigma = 0.5 ", "pixel_sigma = 0.0 "), r"field 'measurement\.pixel_sigma': expected a positive number"),
    ("nan_noise", _edit("pixel_sigma = 0.5 ", "pixel_sigma = nan "), r"field 'measurement\.pixel_sigma': expected a finite number"),
    ("no_noise", _edit("pixel_sigma = 0.5 ", "# "), r"missing field 'measurement\.pixel_sigma'"),
    ("camera_sees_nothing", _edit(CAMERA_1_LOOK, "look_at = [-0.5, 9.0, -0.2]\n\n[[cameras]]"),
     r"field 'cameras\[0\]': expected a camera that sees the pattern at some pose, got 'none of \d+ poses \(behind camera"),
    ("principal_point_outside", _edit("principal_point_px = [512.0, 384.0]", "principal_point_px = [1512.0, 384.0]"),
     r"field 'cameras\[0\]': .*principal point \(1512\.0, 384\.0\) outside"),
    ("bad_distortion", _edit("distortion = [-0.2, 0.1, 0.0, 0.0, 0.0]", "distortion = [-0.2, 0.1, 0.0, 0.0]"), r"field 'cameras\[0\]\.distortion'"),
    ("pitch_not_above_side", _edit("pitch = 0.1", "pitch = 0.05"), r"field 'pattern\.pitch': expected a pitch above the side"),
    ("pattern_normal_zero", _edit("normal = [0.0, 1.0, 0.0]", "normal = [0.0, 0.0, 0.0]"), r"field 'pattern\.normal'"),
    ("huge_grid", _edit("grid_step = 0.15 ", "grid_step = 0.001 "), r"field 'truth\.grid_step': expected a step giving at most"),
    ("both_sources", _edit("\n[truth]\n", "\n[data]\nfile = \"c.csv\"\n\n[truth]\n"), r"exactly one of '\[truth\]'"),
    ("bad_start", _edit('start = "L1_ideal"', 'start = "Z9"'), r"field 'calibration\.start'"),
    ("bad_truth", _edit('parameters = "L1"', 'parameters = "Z9"'), r"field 'truth\.parameters'"),
    ("zero_grid_step", _edit("grid_step = 0.15 ", "grid_step = 0.0 "), r"field 'truth\.grid_step': expected a positive number"),
    ("bad_actuator_errors", _edit('actuator_errors = "table_4_1"', 'actuator_errors = "table_9"'), r"field 'truth\.actuator_errors'"),
    ("bad_tracker", _edit('tracker_noise = "laser_tracker"', 'tracker_noise = "tape"'), r"field 'truth\.tracker_noise'"),
    ("zero_image", _edit("image_size = [1024, 768]", "image_size = [0, 768]"), r"field 'cameras\[0\]\.image_size'"),
    ("negative_focal", _edit("focal_px = [1400.0, 1400.0]", "focal_px = [-1400.0, 1400.0]"), r"field 'cameras\[0\]\.focal_px'"),
    ("up_along_axis", _edit("look_at = [-0.05, 2.85, -0.51]\n\n[[cameras]]", "look_at = [-0.5, 5.0, -1.2]\n\n[[cameras]]"),
     r"field 'cameras\[0\]': .*parallel to the up direction"),
    ("x_axis_along_normal", _edit("x_axis = [1.0, 0.0, 0.0]", "x_axis = [0.0, 2.0, 0.0]"), r"field 'pattern\.normal': .*x_axis: must not be parallel"),
    ("zero_obliquity", _edit("max_obliquity_deg = 60.0", "max_obliquity_deg = 0.0"), r"field 'measurement\.max_obliquity_deg': expected a positive"),
    ("zero_transmission", _edit("max_obliquity_deg = 60.0", "max_obliquity_deg = 60.0\ntransmission = 0.0"), r"field 'measurement\.transmission'"),
    ("bad_parametrisation", _edit('parametrisation = "modified"', 'parametrisation = "exotic"'), r"field 'calibration\.parametrisation'"),
    ("corners_without_list", _edit('type = "five_squares"', 'type = "corners"'), r"field 'pattern\.corners': expected the corners"),
    ("collinear_corners", _edit('type = "five_squares"', 'type = "corners"\ncorners = [[0, 0], [0.1, 0], [0.2, 0], [0.3, 0]]'),
     r"field 'pattern\.corners': .*collinear"),
    ("corners_with_five_squares", _edit("pitch = 0.1", "pitch = 0.1\ncorners = [[0, 0], [0.1, 0], [0.1, 0.1], [0, 0.1]]"),
     r"field 'pattern\.corners': expected no corners"),
]


@pytest.mark.parametrize("case, edit, match", BAD, ids=[b[0] for b in BAD])
def test_bad_problem_is_refused_naming_the_field(tmp_path, case, edit, match):
    assert_bad_problem(tmp_path, FILE, case, edit, match)


def test_tracker_file_without_a_pose_is_refused(corner_file, tmp_path):
    from gtmodel.calibration import MeasurementSet
    from gtmodel.errors import ProblemError

    images = read_stereo_corners(corner_file / "corners.csv", 20)
    MeasurementSet(q=images.q[1:], T=np.zeros((images.n_poses - 1, 3))).to_csv(tmp_path / "tracker.csv")
    (tmp_path / "corners.csv").write_text((corner_file / "corners.csv").read_text())
    text = (corner_file / "data.toml").read_text().replace('\nfile = "corners.csv"\n', '\nfile = "corners.csv"\ntracker_file = "tracker.csv"\n')
    (tmp_path / "p.toml").write_text(text)
    with pytest.raises(ProblemError, match=rf"field 'data\.tracker_file': expected a row with the cart positions of pose {images.pose_ids[0]}"):
        load_problem(tmp_path / "p.toml")


def test_a_planar_pattern_given_by_its_corners(tmp_path):
    """A 4 x 3 chessboard-like grid of corners instead of the five squares: the run converges."""
    xs, ys = np.meshgrid(np.arange(4) * 0.05 - 0.075, np.arange(3) * 0.05 - 0.05)
    corners = ", ".join(f"[{x:.3f}, {y:.3f}]" for x, y in zip(xs.ravel(), ys.ravel()))
    text = FILE.read_text().replace('type = "five_squares"', f'type = "corners"\ncorners = [{corners}]').replace("grid_step = 0.15 ", "grid_step = 0.3 ")
    (tmp_path / "p.toml").write_text(text)
    decl = load_problem(tmp_path / "p.toml").declaration
    assert decl.images.n_corners == 12 and decl.images.n_poses >= 4


def test_true_distortion_with_data_is_refused(corner_file, tmp_path):
    text = (corner_file / "data.toml").read_text().replace("distortion = [-0.18, 0.08", "true_distortion = [0.0, 0.0, 0.0, 0.0, 0.0]\ndistortion = [-0.18, 0.08", 1)
    (tmp_path / "corners.csv").write_text((corner_file / "corners.csv").read_text())
    from gtmodel.errors import ProblemError

    f = tmp_path / "p.toml"
    f.write_text(text)
    with pytest.raises(ProblemError, match=r"field 'cameras\[1\]\.true_distortion': expected no value with \[data\]"):
        load_problem(f)
