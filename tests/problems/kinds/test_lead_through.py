"""Kind ``lead_through``: the shipped problems end to end, the controller file, bad input.

Independent references: the thesis' observations of ch. 8.4 (the checks' structure), the
CSV record re-run through the controller step Function (a second evaluation of the same
run: the controller's outputs in the file are those of the step), and the generated C of
``controller.json`` against Python over the recorded run (``gtmodel codegen --controller``).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from gtmodel.codegen import load_controller
from gtmodel.problems import run_problem

from ...conftest import PROBLEMS_DIR, assert_bad_problem_through_cli, replace_once as _edit

SURFACE = PROBLEMS_DIR / "irb140_lead_through_surface.toml"
PEG = PROBLEMS_DIR / "irb140_lead_through_peg.toml"


@pytest.fixture(scope="module")
def surface(tmp_path_factory):
    out = tmp_path_factory.mktemp("lead_through_surface")
    return run_problem(SURFACE, out, plots=True), out


@pytest.fixture(scope="module")
def peg(tmp_path_factory):
    out = tmp_path_factory.mktemp("lead_through_peg")
    return run_problem(PEG, out, plots=False), out


def test_surface_problem_completes_with_every_check(surface):
    outcome, out = surface
    s = outcome.summary
    assert outcome.exit_code == 0 and s["status"] == "completed"
    assert set(s["checks"]) == {"force_held", "released", "without_control_lost_or_peaks", "oscillation_grows_with_range", "frequency_predicted"}
    assert all(c["passed"] for c in s["checks"].values())
    files = ["summary.json", "controller.json", "surface_tracking.csv", "correction_ranges.csv", "stability.csv",
             "surface_tracking.png", "surface_path.png", "correction_ranges.png", "stability.png"]
    assert sorted(s["files"]) == sorted(files) and all((out / f).stat().st_size > 0 for f in files)


def test_figure_8_4_structure(surface):
    s = surface[0].summary
    assert s["surface_tracking"]["lost_contact_fraction"] == 0.0 and s["surface_tracking"]["force_error_n"] <= 0.5
    w = s["without_force_control"]
    assert w["lost_contact_fraction"] > 0 or w["peak_force_n"] > 5.0


def test_figure_8_5_structure(surface):
    rows = surface[0].summary["correction_ranges"]
    assert [r["correction_range_deg"] for r in rows] == [0.0, 5.0, 10.0]
    assert rows[0]["force_std"] < rows[1]["force_std"] < rows[2]["force_std"]
    assert abs(rows[2]["frequency_hz"] / rows[2]["predicted_hz"] - 1) <= 0.10


def test_the_csv_record_is_the_controller_step(surface):
    # second evaluation: the recorded inputs through the step of controller.json give the recorded outputs
    _, out = surface
    names = (out / "surface_tracking.csv").read_text().splitlines()[0].split(",")
    data = np.loadtxt(out / "surface_tracking.csv", delimiter=",", skiprows=1)
    col = {n: data[:, i] for i, n in enumerate(names)}
    pick = lambda prefix, axes: np.column_stack([col[f"{prefix}_{a}"] for a in axes])  # noqa: E731
    six = ("x", "y", "z", "rx", "ry", "rz")
    step = load_controller(out / "controller.json").lead_through_step
    x = np.column_stack([col[f"xs{i}"] for i in range(8)])
    _, v, _, _ = step.map(len(x))(x.T, pick("fh", six).T, pick("ft", six).T, pick("nn", "xyz").T)
    np.testing.assert_allclose(np.asarray(v).T, pick("v", six), atol=1e-15)


def test_the_stability_table_falls_with_the_stiffness(surface):
    gains = [r["largest_stable_gain"] for r in surface[0].summary["stability"]]
    assert len(gains) == 8 and all(a > b for a, b in zip(gains, gains[1:]))


def test_peg_problem_completes(peg):
    outcome, _ = peg
    s = outcome.summary
    assert outcome.exit_code == 0 and s["status"] == "completed", s["message"]
    assert s["peg_in_hole"]["inserted"] and not s["peg_zero_clearance"]["inserted"]
    assert s["peg_in_hole"]["max_insertion_m"] >= 0.019


def test_a_failed_check_is_check_failed_exit_1(tmp_path):
    # a 0.3 N force reference: noise and the operator break the contact, so the Figure 8.4 check fails
    text = _edit("force_reference = 2.0 ", "force_reference = 0.3 ")(SURFACE.read_text())
    f = tmp_path / "p.toml"
    f.write_text(text)
    outcome = run_problem(f, tmp_path / "out", plots=False)
    assert outcome.summary["status"] == "check_failed" and outcome.exit_code == 1
    assert not all(c["passed"] for c in outcome.summary["checks"].values())
    assert "checks failed" in outcome.summary["message"]


BAD = [
    ("negative stiffness", _edit("stiffness = 2.0e3", "stiffness = -2.0e3"), r"surface\.stiffness.*positive"),
    ("singular M", _edit("mass = [2.0, 2.0, 2.0,", "mass = [2.0, 0.0, 2.0,"), r"controller\.mass.*positive definite"),
    ("zero normal", _edit("nominal_normal = [0.0, 0.0, -1.0]", "nominal_normal = [0.0, 0.0, 0.0]"), r"controller\.nominal_normal.*non-zero"),
    ("phi_L outside [0, 90]", _edit("correction_range_deg = 10.0", "correction_range_deg = 95.0"), r"controller\.correction_range_deg.*<= 90"),
    ("release below contact", _edit("release_force = 10.0", "release_force = 0.1"), r"controller\.release_force.*above contact_force"),
    ("no surface", _edit("[surface]", "[unused_surface]"), r"unused_surface"),
    ("ranges without a stiff surface", _edit("[stiff_surface]", "[surface_b]"), r"surface_b"),
    ("range above 90", _edit("correction_ranges_deg = [0.0, 5.0, 10.0]", "correction_ranges_deg = [0.0, 95.0]"), r"experiment\.correction_ranges_deg"),
    ("duration too long", _edit("duration = 6.5", "duration = 1e9"), r"experiment\.duration.*<= 120"),
]


@pytest.mark.parametrize("case, edit, match", BAD, ids=[b[0] for b in BAD])
def test_bad_input_through_the_cli(tmp_path, capsys, case, edit, match):
    """Each bad input: exit 2, one message naming the file and the field."""
    assert_bad_problem_through_cli(tmp_path, capsys, edit(SURFACE.read_text()), match)


def test_a_hole_narrower_than_the_peg_is_one_plain_message(tmp_path, capsys):
    text = PEG.read_text().replace("hole_radius = 2.0e-3", "hole_radius = 1.0e-3")
    assert_bad_problem_through_cli(tmp_path, capsys, text, r"field 'peg\.hole_radius': expected at least peg_radius \(0\.0015 m\), got 0\.001 m")


def test_peg_without_its_table_is_refused(tmp_path, capsys):
    text = PEG.read_text()
    text = text[:text.index("[peg]")] + text[text.index("[experiment]"):]
    assert_bad_problem_through_cli(tmp_path, capsys, text, r"peg.*a \[peg\] table")


def test_summary_json_round_trips(surface):
    assert json.loads((surface[1] / "summary.json").read_text())["kind"] == "lead_through"
