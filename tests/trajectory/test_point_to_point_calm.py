"""A first run that ends verified reads calmly (issue 67, item 5): `gtmodel solve problems/l1_time_optimal.toml`.

Independent of the solver's figures: the run's own summary says it ended optimal and verified; its stderr is read
line by line for what would read as a failure (a warning, a remedy, a bound "reached", "failed"), of which only the
refinement's own per-pass lines ("pass 1, ... check_failed") may name a status.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
ALARMING = re.compile(r"fail|remedy|against its bound|WARNING|error", re.IGNORECASE)


def test_a_verified_first_run_prints_no_failure(tmp_path, capsys):
    from gtmodel.cli import main

    assert main(["solve", str(REPO / "problems" / "l1_time_optimal.toml"), "--out", str(tmp_path / "R"), "--no-plots"]) == 0
    err = capsys.readouterr().err.splitlines()
    summary = json.loads((tmp_path / "R" / "summary.json").read_text())
    assert (summary["status"], summary["verification"]["passed"]) == ("optimal", True)
    alarming = [line for line in err if ALARMING.search(line) and not re.search(r"mesh refinement of .*: pass \d+, ", line)]
    assert alarming == []
