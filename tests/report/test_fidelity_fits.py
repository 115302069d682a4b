"""Fitted, then predicted (gtmodel.report.fidelity_fits): the 3-axis KF tuning fitted to Cvitanic (2021), Table 8, and the D1 cart compliance fitted to Dressler (2012), Table 5.8.

Independent references: the thesis' Tables 8 and 9 as printed, their ratios by hand (0.00012 / 0.00018 = 2/3,
0.41 / 0.889 = 0.461, 0.00048 / 0.0018 = 0.267) and Table 5.8's final costs by hand.
"""

from __future__ import annotations

import json

import pytest

from gtmodel.report import fidelity_fits as fits


@pytest.fixture(scope="module")
def stored():
    return json.loads(fits.FITS.read_text(encoding="utf-8"))


def test_thesis_ratios_by_hand():
    assert fits.TABLE_8_RATIOS["acceleration_m_s2"] == pytest.approx(2 / 3)
    assert fits.TABLE_9_RATIOS == pytest.approx({"position_mm": 0.4612, "acceleration_m_s2": 0.2667}, abs=1e-4)


def test_the_fit_meets_table_8(stored):
    # the fitted Q gives Table 8's acceleration ratio, leaves the position unchanged to Table 8's rounding (0.0089 -> 0.0089 mm:
    # the ratio within 0.00885 / 0.00895), and makes the velocity the most improved quantity (section 4.3.2)
    f = stored["cvitanic_tables_8_10"]["fit"]
    assert f["table_8"]["acceleration_m_s2"] == pytest.approx(2 / 3, abs=1e-3)
    assert f["table_8"]["position_mm"] >= 0.00885 / 0.00895
    assert f["table_8"]["velocity_mm_s"] <= f["table_8"]["acceleration_m_s2"] + 1e-6


@pytest.mark.parametrize("ratio, verdict", [(0.461, "predicted"), (0.55, "predicted"), (0.56, "differs"), (0.36, "differs")])
def test_table_9_verdict_within_20_percent(stored, ratio, verdict):
    data = json.loads(json.dumps(stored))
    data["cvitanic_tables_8_10"]["predicted"]["table_9"]["position_mm"]["ratio"] = ratio
    row = next(r for r in fits.fit_rows(data) if "Table 9: tracker noise 0.64 mm" in r.figure)
    assert row.verdict == verdict and "fitted Q_p" in row.cause


def test_every_prediction_names_the_fit_it_holds(stored):
    rows = fits.fit_rows(stored)
    assert rows[0].reading and "fitted" in rows[0].ours
    assert all("fitted Q_p" in r.cause and "held fixed" in r.cause for r in rows[1:])


def test_not_run_without_the_file():
    assert [r.verdict for r in fits.fit_rows(None)] == ["not run"]


def test_the_d1_fit_meets_table_5_8(stored):
    # Table 5.8 by hand: sqrt(V / 61) / (2 x 2.0435 m) of 5.458e-6 / 3.661e-6 m^4 = 73.2 / 59.9 um; arm 3 cannot fall below its unloaded error
    f = stored["d1_cart_compliance"]
    assert f["arm_um"][:2] == pytest.approx([73.2, 59.9], abs=0.3)
    assert f["compliance_um_per_N"][2] == pytest.approx(0.0, abs=1e-3) and f["arm_um"][2] == pytest.approx(f["unloaded"]["arm_um"][2], abs=0.5)


def test_the_fitted_problem_file_holds_the_stored_compliance(stored):
    # problems/thesis/d1_error_models_fitted.toml is the thesis file with the fitted compliance (4 significant digits)
    import tomllib
    c = tomllib.loads(fits.D1_FITTED_FILE.read_text())["truth"]["cart_compliance"]
    assert c == pytest.approx([1e-6 * v for v in stored["d1_cart_compliance"]["compliance_um_per_N"]], rel=1e-3, abs=1e-9)
    thesis = tomllib.loads(fits.D1_THESIS_FILE.read_text())
    fitted = tomllib.loads(fits.D1_FITTED_FILE.read_text())
    fitted["truth"].pop("cart_compliance")
    assert {k: v for k, v in fitted.items() if k not in ("name", "description")} == {k: v for k, v in thesis.items() if k not in ("name", "description")}


def test_the_l1_fit_meets_table_7_2_case_1(stored):
    # Table 7.2 as printed: Case 1 tool y 0.361; the fitted stiffness is softer than the thesis set-up's 2e6 N/m
    f = stored["l1_stiffness_y"]
    assert f["case_1"]["tool_y"] == pytest.approx(0.361, abs=2e-3) and f["stiffness_y_N_per_m"] < 2e6


def test_the_fitted_ilc_file_holds_the_stored_stiffness(stored):
    import tomllib
    from gtmodel.problems.fidelity_fits import L1_FITTED_FILE
    k = tomllib.loads(L1_FITTED_FILE.read_text())["structure"]["stiffness"][1]
    assert k == pytest.approx(stored["l1_stiffness_y"]["stiffness_y_N_per_m"], rel=1e-3)


@pytest.mark.parametrize("where, value, verdict", [
    (None, None, "predicted"),  # as stored: 0.265-0.277 on seeds 1-5, 0.258-0.265 at the crossing below the minimum
    ("seed", 0.20, "differs"),  # one seed out of 20 % of the thesis' 0.267 (0.20 / 0.267 = 0.75)
    ("crossing", 0.33, "differs"),  # the other Q_a that meets Table 8 out of 20 % (0.33 / 0.267 = 1.24)
    ("seed", 0.31, "predicted"),  # 0.31 / 0.267 = 1.16
], ids=["stored", "one_seed_off", "other_crossing_off", "one_seed_within"])
def test_table_9_holds_on_every_seed_and_crossing(stored, where, value, verdict):
    data = json.loads(json.dumps(stored))
    s3 = data["cvitanic_tables_8_10"]["seeds"]["tangential"]["3"]
    if where == "seed":
        s3["table_9"]["acceleration_m_s2"] = value
    elif where == "crossing":
        s3["other_crossing"]["table_9"]["acceleration_m_s2"] = value
    row = next(r for r in fits.fit_rows(data) if "Table 9: accelerometer noise 0.0039" in r.figure)
    assert row.verdict == verdict


def test_a_fit_reached_on_one_seed_says_so(stored):
    # the feed along x reaches Table 8's 2/3 on seed 1 only (issue 47: 0.677-0.679 elsewhere); the thesis' tangential feed on all five
    seeds = stored["cvitanic_tables_8_10"]["seeds"]
    assert [k for k, v in seeds["x"].items() if v["reached"]] == ["1"] and all(v["reached"] for v in seeds["tangential"].values())
    assert "2/3 reached on 1 of 5 seeds (seed 1 only)" in fits.fit_rows(stored)[0].ours


def test_table_8_is_out_of_reach_at_the_implied_noise(stored):
    # issue 47: at 1.1e-4 m/s^2 per sample (3.6e-6 m/s^2/rtHz at 1 kHz) no diagonal Q brings the fused error below the sensor-only one;
    # without a bias the accelerometer-only error is the thesis' 0.00018 (1.596 x 1.14e-4 by hand)
    runs = stored["cvitanic_tables_8_10"]["table_8_at_implied_noise"]
    assert all(r["ratio"] > 0.99 for r in runs) and runs[1]["sensor_m_s2"] == pytest.approx(1.596 * 3.6e-6 * 1000**0.5, rel=0.05)
