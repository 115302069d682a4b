"""Analysis ``sweep``: the kind's columns against the swept field (Table 3.1 as a study).

References: a synthetic table (the values are passed through unchanged, the unsolved
case keeps its status and loses its values); the shipped study file's design.
"""

from __future__ import annotations

import pandas as pd
import pytest

from gtmodel.errors import InputError
from gtmodel.problems.study.analyses.sweep import Sweep, sweep_columns
from gtmodel.problems.study.design import load_study

from ....conftest import REPO

SWEEP = Sweep()


def _table() -> pd.DataFrame:
    return pd.DataFrame({"w": [0.01, 0.0, 0.001], "case": ["c", "a", "b"], "key": "k", "folder": "f",
                         "status": ["optimal", "optimal", "infeasible"], "wall_s": 1.0, "kind": "point_to_point",
                         "final_time_s": [0.9, 0.675, 0.8], "energy": [1e5, 4e5, 2e5], "iterations": [40, 49, 3000],
                         "solve_time_s": [1.0, 1.8, 9.0]})


def test_columns_come_from_the_kind():
    assert [c for c, _, _ in sweep_columns(_table())] == ["final_time_s", "energy", "iterations", "solve_time_s"]


def test_sweep_rows_sorted_with_statuses(tmp_path):
    fig, files = SWEEP.analyse(_table(), tmp_path, plots=True)
    assert files == ["sweep.csv", "sweep.md", "sweep.png"]
    assert fig["axis"] == "w" and [r["w"] for r in fig["rows"]] == [0.0, 0.001, 0.01]
    assert [r["final_time_s"] for r in fig["rows"]] == [0.675, None, 0.9]
    assert "| 0.001 | infeasible | - |" in (tmp_path / "sweep.md").read_text()


def test_no_numeric_axis_gives_a_message(tmp_path):
    fig, files = SWEEP.analyse(_table().assign(w=["a", "b", "c"]), tmp_path, plots=False)
    assert "numeric design column" in fig["message"] and files == []


@pytest.mark.parametrize(
    "table, out, match",
    [
        (None, None, r"table: expected a pandas\.DataFrame"),
        (pd.DataFrame({"w": [0.0]}), None, r"table: expected the column\(s\) status"),
        (pd.DataFrame({"status": ["optimal"]}), 3, r"out: expected an existing folder"),
    ],
    ids=["none", "no_status", "out_not_a_path"],
)
def test_bad_arguments(tmp_path, table, out, match):
    with pytest.raises(InputError, match=match):
        SWEEP.analyse(table, tmp_path if out is None else out, False)


@pytest.mark.parametrize(
    "name, analysis, cases",
    [("l1_table_3_1", "sweep", 3), ("l1_time_optimal_map", "time_optimal_map", 99), ("l1_calibration_monte_carlo", "calibration_monte_carlo", 1200)],
)
def test_shipped_studies_load(name, analysis, cases):
    study = load_study(REPO / "studies" / f"{name}.toml")
    assert (study.analysis, len(study.cases)) == (analysis, cases)
