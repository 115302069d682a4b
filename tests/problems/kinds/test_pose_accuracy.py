"""``pose_accuracy`` problem files end to end (Dressler (2012), ch. 4.3, Table 4.2), and their bad input.

Independent references: the published ranges of Figs. 4.8 (140-230 um) and 4.10 (90-170 um)
and the 0.2 mm saddle in the centre (the reference table ``gantry_tau_D1_F1.toml`` has no
accuracy figures, so the numbers are the thesis text's); the self-consistency the kind
promises (no Monte-Carlo sample above the exact worst case, parallelepiped = exact to nm).
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.status import Status

from ...conftest import PROBLEMS_DIR, assert_bad_problem, assert_bad_problem_through_cli, solve_through_cli
from ...conftest import replace_once as _edit

FILE = PROBLEMS_DIR / "d1_pose_accuracy.toml"
UM = 1e-6

#: A coarse, cheap variant of the shipped file (the default test run's budget).
COARSE = [_edit("step = 0.02", "step = 0.1"), _edit("samples = 20000", "samples = 2000"), _edit("random_starts = 2", "random_starts = 0")]


def _coarse(text: str) -> str:
    for e in COARSE:
        text = e(text)
    return text


@pytest.fixture(scope="module")
def coarse(tmp_path_factory):
    folder = tmp_path_factory.mktemp("pa")
    f = folder / "coarse.toml"
    f.write_text(_coarse(FILE.read_text()))
    code, summary = solve_through_cli(f, folder / "out")
    return code, summary, folder / "out"


def test_coarse_map_solves_with_every_promised_file(coarse):
    code, s, out = coarse
    assert code == 0 and s["status"] == Status.OPTIMAL
    names = ("checks.csv", "map_case_1.csv", "map_case_2.csv", "map_case_1.png", "faces_case_1.png", "error_set_case_2.png")
    assert [n for n in names if not (out / n).is_file() or (out / n).stat().st_size == 0] == []
    assert set(s["cases"]) == {"case_1", "case_2"}
    assert s["inverse"]["exact_worst_m"] <= 100 * UM * (1 + 1e-9)


@pytest.mark.parametrize("case", ["case_1", "case_2"])
def test_three_methods_agree_where_the_thesis_says(coarse, case):
    """Parallelepiped = exact NLP to nm (L >> r); no Monte-Carlo sample above the exact worst case."""
    c = coarse[1]["cases"][case]
    assert c["monte_carlo_within_exact"] and c["max_parallelepiped_gap_m"] < 1e-8
    bad = [label for label, check in c["checks"].items()
           if check["monte_carlo_max_m"] > check["exact_m"] * (1 + 1e-9) or check["exact_status"] != "optimal"]
    assert bad == []


def test_saddle_of_case_1_is_near_0_2_mm_in_the_centre(coarse):
    centre = coarse[1]["cases"]["case_1"]["checks"]["centre"]["exact_m"]
    assert centre == pytest.approx(0.2e-3, rel=0.1)


def test_thesis_shape_of_the_maps(coarse):
    """Fig. 4.9: the faces orthogonal to link 1 (smallest tolerance) are the largest; case 1's
    largest error next to an actuator, case 2's next to guideway 2 (its 58 um axial error)."""
    s = coarse[1]
    actuators = np.array(s["actuators_yz_m"])
    faces = s["cases"]["case_1"]["checks"]["centre"]["face_areas_m2"]
    nearest = {case: int(np.argmin(np.linalg.norm(actuators - np.array(s["cases"][case]["checks"]["max"]["T_m"][1:]), axis=1)))
               for case in ("case_1", "case_2")}
    assert int(np.argmax(faces)) == 0 and nearest["case_2"] == 1, (faces, nearest)
    assert np.linalg.norm(actuators[nearest["case_1"]] - s["cases"]["case_1"]["checks"]["max"]["T_m"][1:]) < 0.3


@pytest.mark.slow
def test_shipped_file_reproduces_table_4_2_within_10_percent(tmp_path):
    """Figs. 4.8/4.10: the exact (parallelepiped) map ranges within 10 % of the published ones."""
    code, s = solve_through_cli(FILE, tmp_path / "out")
    assert code == 0 and s["status"] == Status.OPTIMAL
    published = {"case_1": (140, 230), "case_2": (90, 170)}
    off = {case: (s["cases"][case]["map_parallelepiped_m"][0] / (lo * UM) - 1, s["cases"][case]["map_parallelepiped_m"][1] / (hi * UM) - 1)
           for case, (lo, hi) in published.items()}
    assert all(abs(a) <= 0.1 and abs(b) <= 0.1 for a, b in off.values()), off
    assert all(s["cases"][case]["monte_carlo_within_exact"] for case in published)


BAD = [
    ("zero_tolerance", _edit("[[32, 32, 32], [77", "[[0, 32, 32], [77"), r"field 'cases\[0\]\.semi_axes_um\[0\]': expected 3 positive numbers"),
    ("nan_tolerance", _edit("[[11, 28, 28], [58, 38, 38]", "[[11, 28, 28], [nan, 38, 38]"), r"field 'cases\[1\]\.semi_axes_um\[1\]': expected a list of 3 finite"),
    ("huge_tolerance", _edit("[[32, 32, 32], [77", "[[32, 32, 1e6], [77"), r"field 'cases\[0\]\.semi_axes_um\[0\]': expected numbers of magnitude <= 50000"),
    ("negative_link", _edit('reference_range_um = [140, 230]', 'reference_range_um = [140, 230]\nlink_um = [0, -1, 0]'), r"field 'cases\[0\]\.link_um': expected 3 non-negative"),
    ("section_outside", _edit("\nx = -1.6", "\nx = 40.0"), r"field 'section': expected a section with grid points in the workspace"),
    ("decreasing_range", _edit("y = [-5.8, -2.8]", "y = [-2.8, -5.8]"), r"field 'section\.y': expected an increasing range"),
    ("too_fine", _edit("step = 0.02", "step = 0.0001"), r"field 'section\.step': expected a step giving at most 200000 grid points"),
    ("same_names", _edit('name = "case_2"', 'name = "case_1"'), r"field 'cases': expected distinct case names"),
    ("unknown_inverse_case", _edit('case = "case_1"', 'case = "case_9"'), r"field 'inverse\.case': expected one of the cases"),
    ("zero_bound", _edit("tcp_error_um = 100", "tcp_error_um = 0"), r"field 'inverse\.tcp_error_um': expected a positive number"),
    ("pose_outside", _edit("seed = 0", "seed = 0\nposes = [[30.0, 0.0, 0.0]]"), r"field 'exact\.poses\[0\]'"),
    ("bad_robot", _edit('parameters = "D1"', 'parameters = "Z9"'), r"field 'robot\.parameters'"),
    ("no_cases", lambda t: t[: t.index("[[cases]]")] + t[t.index("[exact]"):].replace("[inverse]\ntcp_error_um = 100", "[inverse_]\ntcp_error_um = 100"),
     r"field 'cases'|unknown field 'inverse_'"),
]


@pytest.mark.parametrize("case, edit, match", BAD, ids=[b[0] for b in BAD])
def test_bad_input_names_the_field(tmp_path, case, edit, match):
    assert_bad_problem(tmp_path, FILE, case, edit, match)


@pytest.mark.parametrize("case, edit, match", [b for b in BAD if b[0] in ("zero_tolerance", "nan_tolerance")], ids=["zero", "nan"])
def test_bad_tolerance_exits_2_through_the_cli(tmp_path, capsys, case, edit, match):
    assert_bad_problem_through_cli(tmp_path, capsys, edit(FILE.read_text()), match)
