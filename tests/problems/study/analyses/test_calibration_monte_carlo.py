"""Analysis ``calibration_monte_carlo``: coverage of the predicted deviations, accuracy vs poses.

References: the closed form of the coverage of Gaussian errors, ``P(|e| <= k sigma_pred)
= erf(k sigma_pred / (sigma_true sqrt 2))``, on synthetic summaries with known spread; the
engine's own table for a reduced Monte-Carlo study of the shipped file (few seeds).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from gtmodel.errors import InputError
from gtmodel.problems.study.analyses import ANALYSES
from gtmodel.problems.study.analyses.calibration_monte_carlo import NORMAL_COVERAGE, CalibrationMonteCarlo
from gtmodel.problems.study.engine import run_study

from ....conftest import REPO

MC = CalibrationMonteCarlo()
N_CASES = 400
N_PARAMS = 10


def _summary(rng: np.random.Generator, spread: float, status: str = "optimal") -> dict:
    """A calibration summary whose errors are N(0, (spread * std)^2) with the reported std."""
    std = rng.uniform(1e-6, 1e-4, N_PARAMS)
    truth = rng.uniform(-1, 1, N_PARAMS)
    est = truth + spread * std * rng.standard_normal(N_PARAMS)
    params = {f"p{i}": {"estimate": est[i], "truth": truth[i], "std": std[i], "role": "free"} for i in range(N_PARAMS)}
    params["fixed"] = {"estimate": 1.0, "truth": 2.0, "std": 0.0, "role": "fixed"}
    params["tied"] = {"estimate": 1.0, "truth": 2.0, "std": 1e-6, "role": "tied"}
    params["lost"] = {"estimate": 1.0, "truth": 2.0, "std": None, "role": "non_identifiable"}
    return {"status": status, "parameters": params, "pose_method": "random", "n_calibration": 20, "truth_mean_error_m": 1e-5}


def _table(spread: float, seed: int = 0) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    rows = [{"truth.seed": k, "case": f"c{k}", "key": str(k), "folder": "", **_summary(rng, spread)} for k in range(N_CASES)]
    rows = [{k: v for k, v in r.items() if k != "parameters"} | MC.row(r) for r in rows]
    return pd.DataFrame(rows)


def test_registered():
    assert ANALYSES["calibration_monte_carlo"].name == "calibration_monte_carlo"


@pytest.mark.parametrize("k", [1, 2])
@pytest.mark.parametrize("spread", [1.0, 1.5, 0.7], ids=["honest", "too_small_std", "too_large_std"])
def test_coverage_matches_the_closed_form(tmp_path, spread, k):
    # closed form: P(|N(0, spread^2)| <= k) = erf(k / (spread sqrt 2)); tolerance 4 binomial sigmas
    fig, _ = MC.analyse(_table(spread), tmp_path, plots=False)
    n = N_CASES * N_PARAMS
    p = math.erf(k / (spread * math.sqrt(2)))
    assert fig["n_values"] == n and fig["n_parameters"] == N_PARAMS
    assert abs(fig[f"coverage_{k}sigma"] - p) <= 4 * math.sqrt(p * (1 - p) / n), (fig[f"coverage_{k}sigma"], p)
    assert fig["honest"] is (spread == 1.0)


def test_row_keeps_free_parameters_only():
    row = MC.row(_summary(np.random.default_rng(1), 1.0))
    assert row["mc_n_free"] == N_PARAMS
    assert {"z[p0]", "error[p0]", "std[p0]"} <= set(row)
    assert not any(k.endswith(("[fixed]", "[tied]", "[lost]")) for k in row)


def test_row_without_truth_is_all_none():
    assert MC.row({"status": "invalid_input"}) == {"mc_n_free": None, "mc_within_1sigma": None, "mc_within_2sigma": None}


def test_failed_cases_are_counted_not_used(tmp_path):
    table = _table(1.0)
    table.loc[:9, "status"] = "max_iterations"
    fig, _ = MC.analyse(table, tmp_path, plots=False)
    assert fig["n_cases"] == N_CASES and fig["n_cases_used"] == N_CASES - 10
    assert fig["statuses"] == {"max_iterations": 10, "optimal": N_CASES - 10}


def test_no_truth_gives_a_message_not_a_number(tmp_path):
    fig, files = MC.analyse(pd.DataFrame({"status": ["optimal"], "case": ["a"]}), tmp_path, plots=False)
    assert fig["coverage_1sigma"] is None and "truth" in fig["message"] and files == []


def test_files_and_plots(tmp_path):
    fig, files = MC.analyse(_table(1.0), tmp_path, plots=True)
    assert set(files) == {"coverage_per_parameter.csv", "accuracy_vs_poses.csv", "normalised_errors.png", "parameter_spread.png",
                          "accuracy_vs_poses.png"}
    assert all((tmp_path / f).stat().st_size > 0 for f in files)
    assert fig["accuracy_vs_poses"][0]["n_cases"] == N_CASES
    assert len(pd.read_csv(tmp_path / "coverage_per_parameter.csv")) == N_PARAMS


@pytest.mark.parametrize(
    "table, out, plots, match",
    [
        ([1, 2], None, False, r"table: expected a pandas\.DataFrame"),
        (pd.DataFrame({"case": ["a"]}), None, False, r"table: expected the column\(s\) status"),
        (pd.DataFrame({"status": ["optimal"]}), "no/such/folder", False, r"out: expected an existing folder"),
        (pd.DataFrame({"status": ["optimal"]}), None, "yes", r"plots: expected true or false"),
    ],
    ids=["not_a_table", "no_status", "no_folder", "plots_not_bool"],
)
def test_bad_arguments(tmp_path, table, out, plots, match):
    with pytest.raises(InputError, match=match):
        MC.analyse(table, tmp_path if out is None else out, plots)


def test_reduced_shipped_study(tmp_path):
    # the shipped study with 2 seeds and 40 poses (the full run: 200 seeds x 3 pose counts)
    text = (REPO / "studies" / "l1_calibration_monte_carlo.toml").read_text(encoding="utf-8")
    text = text.replace("values = [40, 120, 360]", "values = [40]").replace("seeds = 200", "seeds = 2")
    text = text.replace('base = "bases/', f'base = "{(REPO / "studies" / "bases").as_posix()}/')
    study = tmp_path / "mc.toml"
    study.write_text(text, encoding="utf-8")
    outcome = run_study(study, tmp_path / "out", workers=1, plots=False)
    table = pd.read_parquet(tmp_path / "out" / "table.parquet")
    assert len(table) == 4 and set(table["status"]) == {"optimal"}
    assert set(table["pose_method"]) == {"condition", "random"} and set(table["n_calibration"]) == {20}
    fig = outcome.summary["analysis"]
    assert fig["n_values"] == 4 * 21 and 0 <= fig["coverage_1sigma"] <= fig["coverage_2sigma"] <= 1


def test_normal_coverage_constants():
    # closed form: erf(1/sqrt 2) and erf(2/sqrt 2)
    assert NORMAL_COVERAGE[1] == pytest.approx(0.682689492, abs=1e-9)
    assert NORMAL_COVERAGE[2] == pytest.approx(0.954499736, abs=1e-9)
