"""Data files stay where the problem lives (``ProblemFile.data_file``, docs/reliability.md):
a problem file from someone else naming a file outside its folder (absolute, ``..``, a
symbolic link), a special file (``/proc``, a FIFO) is refused with exit 2, and no content of
that file reaches the message or ``summary.json``.

Independent reference: the file system (a marker string written outside the problem's folder
must appear in no output; ``os.path.realpath`` decides what is inside).
"""

from __future__ import annotations

import json
import os

import pytest

from gtmodel.cli import EXIT_BAD_INPUT, main
from gtmodel.errors import ProblemError
from gtmodel.problems import load_problem

from ..conftest import PROBLEMS_DIR, replace_once as _edit
from .kinds.test_replay import _trajectory

MARKER = "FOREIGN-CONTENT-51c9"
TRACKING = (PROBLEMS_DIR / "l1_tracking.toml").read_text()


def _problem(folder, ref: str):
    f = folder / "track.toml"
    f.write_text(_edit('problem = "l1_time_optimal.toml"', f'file = "{ref}"')(TRACKING))
    return f


@pytest.fixture
def layout(tmp_path):
    """``work/`` holds the problem; ``foreign/`` beside it holds a file with a marker."""
    work, foreign = tmp_path / "work", tmp_path / "foreign"
    work.mkdir()
    foreign.mkdir()
    (foreign / "secret.csv").write_text(f"t,x\n{MARKER},1\n")
    (work / "link.csv").symlink_to(foreign / "secret.csv")
    os.mkfifo(work / "fifo.csv")
    return work, foreign


CASES = [
    ("absolute_outside", lambda w, f: str(f / "secret.csv"), "a data file inside the problem file's folder"),
    ("climbing", lambda w, f: "../foreign/secret.csv", "a data file inside the problem file's folder"),
    ("symlink_out", lambda w, f: "link.csv", "a data file inside the problem file's folder"),
    ("etc_passwd", lambda w, f: "/etc/passwd", "a data file inside the problem file's folder"),
    ("proc_environ", lambda w, f: "/proc/self/environ", r"a regular data file \(not a device, FIFO"),
    ("fifo", lambda w, f: "fifo.csv", r"(an existing file|a regular data file \(not a device, FIFO)"),
    ("device", lambda w, f: "/dev/zero", r"(an existing file|a regular data file \(not a device, FIFO)"),
]


@pytest.mark.parametrize(("case", "ref", "match"), CASES, ids=[c[0] for c in CASES])
def test_a_data_file_outside_the_problems_folder_is_refused(layout, case, ref, match):
    work, foreign = layout
    with pytest.raises(ProblemError, match=rf"field 'trajectory\.file': expected {match}") as info:
        load_problem(_problem(work, ref(work, foreign)))
    assert MARKER not in str(info.value) and "root:" not in str(info.value)


def test_through_the_cli_exit_2_and_no_foreign_content_in_the_summary(layout, capsys):
    work, _ = layout
    out = work / "out"
    code = main(["solve", str(_problem(work, "link.csv")), "--out", str(out), "--quiet", "--no-plots"])
    err = capsys.readouterr().err
    summary = (out / "summary.json").read_text()
    assert (code, json.loads(summary)["status"]) == (EXIT_BAD_INPUT, "invalid_input")
    assert MARKER not in err + summary and "Traceback" not in err


def test_a_folder_named_with_data_dir_is_allowed(layout, monkeypatch):
    work, foreign = layout
    csv = _trajectory(foreign / "traj.csv", last=0.0013)
    with pytest.raises(ProblemError, match="inside the problem file's folder"):
        load_problem(_problem(work, str(csv)))
    monkeypatch.setenv("GTMODEL_DATA_DIRS", str(foreign))  # what `gtmodel solve --data-dir` sets
    assert load_problem(_problem(work, str(csv))).declaration.source == csv


def test_data_dir_must_be_a_folder(tmp_path, capsys):
    f = _problem(tmp_path, "x.csv")
    assert main(["solve", str(f), "--data-dir", str(tmp_path / "nowhere"), "--out", str(tmp_path / "o")]) == EXIT_BAD_INPUT
    assert "--data-dir" in capsys.readouterr().err


def test_the_data_dir_option_lets_a_run_read_there_and_is_forgotten_afterwards(layout, capsys):
    work, foreign = layout
    csv = _trajectory(foreign / "traj.csv", last=0.0013)
    problem = _problem(work, str(csv))
    assert main(["solve", str(problem), "--out", str(work / "a"), "--quiet", "--no-plots"]) == EXIT_BAD_INPUT
    code = main(["solve", str(problem), "--data-dir", str(foreign), "--out", str(work / "b"), "--quiet", "--no-plots"])
    assert code in (0, 1), capsys.readouterr().err  # loaded and solved (a status of the tracking run)
    assert "GTMODEL_DATA_DIRS" not in os.environ
