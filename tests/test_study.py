"""Studies from the command line: a sweep over the energy weight and several files at once.

Independent reference: the shape of Dressler (2012), Table 3.1 -- a larger energy weight
``w`` gives a strictly longer motion and strictly less energy -- and the per-case result
folders, which are checked against the comparison table written from them.
"""

from __future__ import annotations

import csv
import json

import pytest

from gtmodel.cli import EXIT_BAD_INPUT, EXIT_OK, main
from gtmodel.defaults import defaults

from .conftest import PROBLEMS_DIR, verification_tolerance

BASE = PROBLEMS_DIR / "l1_time_optimal.toml"
WEIGHTS = ("0", "0.001", "0.01")


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep")
    code = main(["solve", str(BASE), "--sweep", "w=" + ",".join(WEIGHTS), "--out", str(out), "--quiet", "--no-plots"])
    with open(out / "comparison.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    return code, out, rows


def test_sweep_exits_zero_and_writes_one_row_per_value(sweep):
    code, out, rows = sweep
    assert code == EXIT_OK
    assert [r["case"] for r in rows] == [f"l1_time_optimal[w={w}]" for w in ("0", "0.001", "0.01")]
    assert all(r["status"] == "optimal" for r in rows)
    assert (out / "comparison.md").read_text().startswith("| case | status | T_final [s]")


def test_larger_weight_gives_longer_time_and_less_energy(sweep):
    _, _, rows = sweep
    tf = [float(r["final_time_s"]) for r in rows]
    energy = [float(r["energy"]) for r in rows]
    assert tf[0] < tf[1] < tf[2], tf
    assert energy[0] > energy[1] > energy[2], energy


def test_comparison_rows_equal_the_case_summaries(sweep):
    _, out, rows = sweep
    summaries = {r["case"]: json.loads((out / r["case"].replace("[", "_").replace("]", "") / "summary.json").read_text())
                 for r in rows}
    bad = [
        (r["case"], field)
        for r in rows
        for field, ok in (
            ("status", summaries[r["case"]]["status"] == r["status"]),
            ("final_time_s", summaries[r["case"]]["final_time_s"] == pytest.approx(float(r["final_time_s"]), rel=1e-12)),
            ("overrides", summaries[r["case"]]["overrides"] == {"w": float(r["case"].split("w=")[1].rstrip("]"))}),
        )
        if not ok
    ]
    assert not bad, bad  # (case, field) where the comparison row and the case summary differ


def test_several_files_one_bad_records_the_error_and_exits_nonzero(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(BASE.read_text().replace('kind = "point_to_point"', 'kind = "teleport"'))
    worse = tmp_path / "worse.toml"
    worse.write_text("this is not TOML [")
    out = tmp_path / "study"
    code = main(["solve", str(bad), str(worse), "--out", str(out), "--quiet", "--no-plots"])
    assert code == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert "field 'kind'" in err and "invalid TOML" in err and "Traceback" not in err
    rows = list(csv.DictReader(open(out / "comparison.csv", newline="")))
    assert [r["status"] for r in rows] == ["invalid_input", "invalid_input"]


@pytest.mark.parametrize(
    "args, match",
    [
        (["--sweep", "w"], r"expected FIELD=VALUE1"),
        (["--sweep", "w=0,[1"], r"values must be TOML literals"),
        (["--sweep", "nonexistent=1,2"], r"cannot sweep 'nonexistent'"),
        (["--sweep", "limits.nothing=1"], r"cannot sweep 'limits.nothing'"),
    ],
    ids=["no_values", "bad_literal", "unknown_field", "unknown_dotted_field"],
)
def test_bad_sweep_arguments(tmp_path, capsys, args, match):
    import re

    code = main(["solve", str(BASE), *args, "--out", str(tmp_path / "o"), "--quiet", "--no-plots"])
    assert code == EXIT_BAD_INPUT
    assert re.search(match, capsys.readouterr().err)


def test_sweep_with_two_files_is_rejected(tmp_path, capsys):
    code = main(["solve", str(BASE), str(BASE), "--sweep", "w=0,1", "--out", str(tmp_path / "o"), "--quiet"])
    assert code == EXIT_BAD_INPUT
    assert "exactly one problem file" in capsys.readouterr().err


@pytest.mark.slow  # tens of seconds of the default run's budget (measured 2026-11-28)
def test_free_path_is_faster_and_the_straight_line_uses_less_energy(tmp_path):
    """Dressler (2012), Table 3.1 / ch. 3.5: the time-optimal free path is faster than the
    path-constrained straight line, at more energy. Both files declare the same poses and limits."""
    out = tmp_path / "table_3_1"
    files = [str(PROBLEMS_DIR / "l1_time_optimal.toml"), str(PROBLEMS_DIR / "l1_path_constrained.toml")]
    code = main(["solve", *files, "--out", str(out), "--quiet", "--no-plots"])
    assert code == EXIT_OK
    rows = {r["case"]: r for r in csv.DictReader(open(out / "comparison.csv", newline=""))}
    free, line = rows["l1_time_optimal"], rows["l1_path_constrained"]
    assert float(free["final_time_s"]) < float(line["final_time_s"])
    assert float(line["energy"]) < float(free["energy"])


def test_ctrl_c_in_a_sweep_stops_the_whole_study(tmp_path, capsys, monkeypatch):
    """A KeyboardInterrupt in the second case ends the study: no third case, exit 130."""
    from gtmodel.cli import EXIT_INTERRUPTED
    from gtmodel.problems import get_kind

    kind = get_kind("point_to_point")
    calls = []
    original = type(kind).solve

    def solve(self, declaration, **kw):
        calls.append(declaration)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return original(self, declaration, **kw)

    monkeypatch.setattr(type(kind), "solve", solve)
    # 10 elements for speed: the L1 motion deviates 4 % from its simulation there
    monkeypatch.setitem(defaults, "ocp.verification_tolerance", 0.1)
    text = BASE.read_text().replace("elements = 50 ", "elements = 10 ")
    f = tmp_path / "p.toml"
    f.write_text(text)
    out = tmp_path / "sweep"
    code = main(["solve", str(f), "--sweep", "w=0,0.001,0.01", "--out", str(out), "--quiet", "--no-plots"])
    assert code == EXIT_INTERRUPTED
    assert len(calls) == 2
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    assert [c["status"] for c in summary["cases"]] == ["optimal", "interrupted"]
    assert "interrupted" in capsys.readouterr().err


def test_two_kinds_compared_keep_each_kinds_overlays_and_list_every_file_once(tmp_path, capsys):
    """Defect (a): a free path and a straight line (two kinds) wrote their overlays under the
    same names (the second overwrote the first) and the summary listed them twice."""
    free = tmp_path / "l1_time_optimal.toml"
    free.write_text(BASE.read_text().replace("elements = 50 ", "elements = 10 "))
    line = tmp_path / "l1_path_constrained.toml"
    line.write_text((PROBLEMS_DIR / "l1_path_constrained.toml").read_text().replace("grid = 500 ", "grid = 50 "))
    out = tmp_path / "table_3_1"
    with verification_tolerance(0.1):  # 10 elements for speed: the L1 motion deviates 4 % from its simulation
        code = main(["solve", str(free), str(line), "--out", str(out), "--quiet"])
    summary = json.loads((out / "summary.json").read_text())
    overlays = sorted(f for f in summary["files"] if "overlay" in f)
    assert code == EXIT_OK
    assert len(summary["files"]) == len(set(summary["files"])), summary["files"]
    assert [c["label"] for c in summary["cases"]] == ["l1_time_optimal", "l1_path_constrained"]
    assert overlays == sorted(f"{k}_overlay_{p}.png" for k in ("point_to_point", "path_constrained") for p in ("forces", "tcp"))
    assert sorted(p.name for p in out.glob("*overlay*")) == overlays


def test_out_naming_a_file_stops_a_comparison_before_it_runs(tmp_path, capsys):
    """Defect (b) for several files: one message, up front, exit 2, nothing written."""
    blocker = tmp_path / "taken"
    blocker.write_text("not a folder")
    code = main(["solve", str(BASE), str(PROBLEMS_DIR / "l1_path_constrained.toml"), "--out", str(blocker), "--quiet"])
    err = capsys.readouterr().err
    assert (code, err) == (EXIT_BAD_INPUT, f"gtmodel: error: cannot write the result folder {blocker}: a file of that name is in the way\n")
    assert [p.name for p in tmp_path.iterdir()] == ["taken"]


def test_a_sweep_over_an_unknown_field_is_one_error_and_no_folder(tmp_path, capsys):
    """Defect (g): the error was repeated per case and a comparison folder still written."""
    out = tmp_path / "o"
    code = main(["solve", str(BASE), "--sweep", "nonexistent=1,2,3", "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT
    assert err.count("gtmodel: error") == 1 and "cannot sweep 'nonexistent'" in err, err
    assert list(tmp_path.iterdir()) == []


def test_a_mistyped_file_in_a_comparison_writes_nothing(tmp_path, capsys, monkeypatch):
    """Defect (e) for several files: the missing one is named, nothing is created."""
    monkeypatch.chdir(tmp_path)
    code = main(["solve", str(BASE), "nope.toml", "--quiet"])
    assert (code, capsys.readouterr().err) == (EXIT_BAD_INPUT, "gtmodel: error: nope.toml: cannot read the problem file (no such file)\n")
    assert list(tmp_path.iterdir()) == []
