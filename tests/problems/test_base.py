"""Every file of every result folder is described (gtmodel.problems.base: ProblemKind.file_descriptions).

Each kind declares the files its ``write`` may put in a result folder with one line each;
the run writes the descriptions into ``summary.json`` (``file_descriptions``) and the report
lists them. The check here is the folder a real run wrote (the shipped problem of each
kind solved through the command line): every file in it has a description, and the page
shows each. A kind that starts writing a file it does not describe fails its case.
"""

from __future__ import annotations

import html

import pytest

from gtmodel.problems.base import COMMON_FILES
from gtmodel.problems.registry import KINDS, get_kind
from gtmodel.report.result_page import REPORT_FILE

from ..conftest import PROBLEMS_DIR, solve_through_cli

#: One shipped problem per result kind; those solving in a few seconds run by default.
SHIPPED = {
    "point_to_point": ("l1_time_optimal.toml", False),
    "path_constrained": ("l1_path_constrained.toml", False),
    "calibration": ("l1_calibration.toml", True),
    "elasto_geometric_calibration": ("l1_elasto_geometric.toml", False),
    "dynamic_identification": ("l1_dynamic_identification.toml", False),
    "joint_stiffness_calibration": ("kr500_joint_stiffness.toml", True),
    "vision_calibration": ("l1_vision_calibration.toml", True),
    "replay": ("l1_tracking.toml", True),
    "ilc": ("l1_ilc.toml", True),
    "state_estimation": ("kr500_state_estimation.toml", True),
    "correction_stability": ("kr500_correction_stability.toml", True),
    "optimal_control": ("benchmarks/goddard_rocket.toml", False),
    "optimica": ("optimica/double_integrator_min_time.toml", False),
    "lead_through": ("irb140_lead_through_peg.toml", True),
    "pose_accuracy": ("d1_pose_accuracy.toml", True),
    "automated_calibration": ("l1_automated_calibration.toml", True),
}


#: Kinds that serve a robot (their files in loops/, run by gtmodel loop): they wait for a robot, so
#: their folders are checked against the robot simulators in their own tests, likewise
#: (tests/problems/kinds/test_robot_loop.py: every file described, listed and shown).
SERVED = ("robot_loop",)


def test_every_kind_has_a_shipped_problem_here():
    assert sorted(SHIPPED) == sorted(k for k in KINDS if k not in SERVED)


@pytest.mark.parametrize("kind", [pytest.param(k, marks=pytest.mark.slow if slow else (), id=k) for k, (_, slow) in SHIPPED.items()])
def test_every_file_a_kind_writes_is_described_and_listed_in_the_report(tmp_path, kind):
    out = tmp_path / "res"
    code, summary = solve_through_cli(PROBLEMS_DIR / SHIPPED[kind][0], out)
    assert code == 0 and summary["kind"] == kind
    on_disk = sorted(p.name for p in out.iterdir())
    described = summary["file_descriptions"]
    assert [f for f in on_disk if f not in described] == []  # an undescribed file names itself here
    assert sorted(summary["files"]) == on_disk
    page = (out / REPORT_FILE).read_text(encoding="utf-8")
    files_section = page[page.index('<h2 id="files">'):]
    assert [f for f in on_disk if html.escape(described[f], quote=True) not in files_section] == []


@pytest.mark.parametrize("names, expected", [
    (["summary.json", "report.html"], dict(COMMON_FILES)),
    (["ilc_tool_path_case_2A.png", "ilc_signals_case_3.npz"], {"ilc_tool_path_case_2A.png": "ilc_tool_path_case_*.png",
                                                              "ilc_signals_case_3.npz": "ilc_signals_case_*.npz"}),
    (["mystery.bin", "table_7_2.md"], {"table_7_2.md": "table_7_2.md"}),
], ids=["common", "per-case patterns", "undescribed left out"])
def test_describe_files_matches_names_and_patterns(names, expected):
    ilc = get_kind("ilc")
    declared = {**COMMON_FILES, **ilc.file_descriptions}
    want = {n: declared.get(v, v) for n, v in expected.items()}
    assert ilc.describe_files(names) == want
