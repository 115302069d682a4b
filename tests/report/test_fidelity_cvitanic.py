"""The fidelity rows of Cvitanic (2021), Tables 2 and 10 (gtmodel.report.fidelity): verdicts from the figures, and collect on a real run.

Independent reference: hand-made figures whose verdict is known (a 3-axis limit within half a decade on the thesis'
Appendix B Q, or one decade off; a 5-axis limit on our Q, which the thesis does not print; the log10 distances by hand); Table 2's ordering present or absent), and the summary the
``joint_stiffness_calibration`` kind writes for problems/thesis/kr500_table_2.toml (read back by ``collect``).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from gtmodel.problems import run_problem
from gtmodel.report import fidelity, fidelity_kr500
from gtmodel.report.fidelity_rules import Row, apply_rules

from ..conftest import PROBLEMS_DIR
from ..conftest import replace_once as _edit

SWEEP = [{"parameter": "accel_bias_m_s2", "value": 0.025, "motion": m, "velocity": {"sensor": 5.0, "fusion": 1.0}} for m in ("3-axis", "5-axis")]


def _limit(motion, limit, tuning="white_jerk", parameter="accel_bias_m_s2", stops=True):
    return {"motion": motion, "parameter": parameter, "tuning": tuning, "limit": limit, "pays_up_to": limit / 1.1,
            "stops_at": limit * 1.1 if stops else None, "verdict": "ignored: the page judges", "decades_from_thesis": None, "search": [2.5e-4, 2.5]}


def _rows(limits):
    return apply_rules([r if isinstance(r, Row) else Row(*r) for r in fidelity._table_10_rows({"table_10": SWEEP}, None if limits is None else {"limits": limits})])


def _row(limits, motion="3-axis", parameter="accel_bias_m_s2"):
    return next(r for r in _rows(limits) if f"{motion} limit of {parameter}" in r[0] or (motion is None and parameter in r[0]))


@pytest.mark.parametrize("limits, motion, verdict", [
    # the 3-axis cell is judged on the thesis' Appendix B Q (its printed 3-axis tuning): within half a decade passes
    ([_limit("3-axis", 0.1), _limit("3-axis", 0.002, "appendix_b"), _limit("5-axis", 0.003)], "3-axis", "reproduced"),
    # log10(0.0098 / 0.001) = 0.99: within one decade, not half
    ([_limit("3-axis", 0.002), _limit("3-axis", 0.0098, "appendix_b")], "3-axis", "differs"),
    # the 5-axis cell rests on our white-jerk Q (the thesis prints none for its EKF): never kinder than differs
    ([_limit("3-axis", 0.002, "appendix_b"), _limit("5-axis", 0.003)], "5-axis", "differs"),
    # without the Appendix B run the 3-axis verdict has no tuning to stand on
    ([_limit("3-axis", 0.002), _limit("5-axis", 0.003)], "3-axis", "differs"),
], ids=["3_axis_printed_q_within", "3_axis_one_decade", "5_axis_our_q", "3_axis_not_run"])
def test_table_10_cell_verdict(limits, motion, verdict):
    row = _row(limits, motion)
    assert row[4] == verdict and row[1] == "< 0.001" and row[3] == "half a decade"
    assert len(row[5]) > 20 and (row[5].startswith("verdict on the thesis' Appendix B Q") if verdict == "reproduced" else True)


def test_table_10_not_run():
    row = _row(None, None)
    assert row[4] == "not run" and row[1] == "< 0.001 / < 0.001"


def test_table_10_3_axis_translation_cannot_fail():
    # eq. (29) with alpha = omega = 0: the lever arm enters nowhere, so "no constraint" is a reading, not a reproduction
    rows = _rows([_limit("3-axis", 2540.0, "appendix_b", "transform_translation_error_mm", stops=False),
                  _limit("5-axis", 5.0, parameter="transform_translation_error_mm")])
    three = next(r for r in rows if "3-axis limit of transform_translation_error_mm" in r[0])
    assert three[4] == "check of a reading" and three[1] == "no constraint"


def test_table_10_sample_time_must_hold_on_every_seed():
    # seed 1 alone (0.0294, +0.47 decades) would pass; seed 5 (0.0340, +0.53) does not: the row differs, naming seed 5's limit
    rows = _rows([_limit("3-axis", 0.029427, "appendix_b", "sample_time_s")])
    row = next(r for r in rows if "3-axis limit of sample_time_s" in r[0])
    assert math.log10(0.029427 / 0.01) < 0.5 < math.log10(0.033982 / 0.01)  # the hand computation
    assert row[4] == "differs" and "0.034 (+0.53 decades)" in row[5] and "seeds 1, 2, 3, 4, 5: 0.029-0.034" in row[2]


@pytest.mark.slow
def test_table_10_sample_time_seed_5_from_the_thesis_file(tmp_path):
    # the deciding number of the 3-axis sample-time cell (fidelity_kr500.SEED_LIMITS), recomputed (~20-40 s): seed 5 of
    # problems/thesis/kr500_table_10.toml with the thesis' Appendix B Q, the limit search alone
    text = (PROBLEMS_DIR / "thesis" / "kr500_table_10.toml").read_text()
    text = text.replace(text[text.index("[study.sweep]"):text.index("[study.limits]")], "[study.sweep]\n" + "\n".join(
        f"{k} = []" for k in ("position_noise_mm", "orientation_noise_deg", "gyro_bias_deg_s", "gyro_noise_deg_s_rtHz", "accel_bias_m_s2",
                              "accel_noise_m_s2_rtHz", "sample_time_s", "feed_rate_mm_s", "transform_translation_error_mm",
                              "transform_orientation_error_deg")) + "\n\n")
    for old, new in (("\nseed = 1\n", "\nseed = 5\n"), ('sweep_motions = ["3-axis", "5-axis"]', 'sweep_motions = ["3-axis"]'),
                     ('tunings = ["white_jerk", "appendix_b"]', 'tunings = ["appendix_b"]\nparameters = ["sample_time_s"]'),
                     ('centred = ["sample_time_s"]', "centred = []")):
        text = _edit(old, new)(text)
    (tmp_path / "seed_5.toml").write_text(text)
    outcome = run_problem(tmp_path / "seed_5.toml", tmp_path / "out", plots=False)
    (r,) = outcome.summary["table_10_limits"]
    assert r["limit"] == pytest.approx(fidelity_kr500.SEED_LIMITS[("3-axis", "sample_time_s")][5], rel=1e-4)


def test_table_2_rows_from_a_real_run(tmp_path):
    # three seeds of the thesis file through the kind; its summary.json read as collect reads it
    path = tmp_path / "kr500_table_2.toml"
    path.write_text(_edit("seeds = 200", "seeds = 3")((PROBLEMS_DIR / "thesis" / "kr500_table_2.toml").read_text()))
    assert run_problem(path, tmp_path / "out", plots=False).exit_code == 0
    data = {"kr500_table_2": fidelity._EXTRACT["kr500_table_2"](json.loads((tmp_path / "out" / "summary.json").read_text()))}
    rows = fidelity._table_2_rows(data)
    assert data["kr500_table_2"]["monte_carlo"]["seeds"] == 3 and data["kr500_table_2"]["dpp_step2"] == "tcp_translation"
    assert rows[0][2].startswith("3 seeds: median CP / DPP") and rows[0][4] == "differs" and len(rows[0][5]) > 20
    assert "CP with rotations x10 below DPP" in rows[1][0]


@pytest.mark.slow  # 16 s: a state-estimation run
def test_thesis_metric_is_the_norm_of_per_axis_mean_abs_errors(tmp_path):
    # closed form for white Gaussian noise sigma per axis: sqrt(3 * 2 / pi) sigma = 1.382 sigma (std sqrt(3 (1 - 2 / pi)) = 1.044
    # sigma), which the thesis' sensor columns match (Table 9: 0.889 / 0.64 mm = 1.389) where the mean 3-D norm gives 1.596 sigma
    rng = np.random.default_rng(0)
    n, sigma = 200_000, 0.64e-3
    cols, data = ["t"], [np.arange(n) * 1e-3]
    for q in ("position", "velocity", "acceleration"):
        for a in "xyz":
            truth = np.sin(np.arange(n) * 1e-3)
            cols += [f"{q}_{a}_true", f"{q}_{a}_sensor", f"{q}_{a}_fusion"]
            data += [truth, truth + sigma * rng.standard_normal(n), truth + 0.5 * sigma * rng.standard_normal(n)]
    np.savetxt(tmp_path / "fusion_baseline_3_axis.csv", np.column_stack(data), delimiter=",", header=",".join(cols), comments="")
    m = fidelity.thesis_metric(tmp_path / "fusion_baseline_3_axis.csv")
    assert m["position_mm"]["sensor"]["mean"] == pytest.approx(math.sqrt(6 / math.pi) * 0.64, rel=5e-3)
    assert m["position_mm"]["sensor"]["std"] == pytest.approx(math.sqrt(3 * (1 - 2 / math.pi)) * 0.64, rel=5e-3)
    assert m["acceleration_m_s2"]["fusion"]["mean"] == pytest.approx(math.sqrt(6 / math.pi) * 0.32e-3, rel=5e-3)
    assert 0.889 / 0.64 == pytest.approx(math.sqrt(6 / math.pi), rel=6e-3)  # the thesis' Table 9 sensor column
