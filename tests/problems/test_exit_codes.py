"""The exit-code contract for names that become paths and for the signal that stopped a run.

- A problem's or study's ``name`` is the default result folder ``results/<name>``; a name
  that is not one plain path component (``../../x``, ``/tmp/x``, ``a/b``, ``..``) is refused
  with exit 2 naming the field, and nothing is written outside ``results/``.
- The process exits 128 + the number of the first signal received (130 SIGINT, 143
  SIGTERM); a run that finished before the signal keeps its code. A real signal while the
  kind writes its files leaves ``--out`` holding the interrupted summary alone.

Independent reference: the file system (what exists after the run, outside and inside
``results/``), POSIX path rules (a component has no ``/``; ``.`` and ``..`` name other
folders) and the shell's convention for a process ended by a signal (128 + its number).
"""

from __future__ import annotations

import json
import os
import signal

import pytest

from gtmodel import _signals
from gtmodel.cli import EXIT_BAD_INPUT, EXIT_INTERRUPTED, main
from gtmodel.errors import ProblemError
from gtmodel.problems import load_problem
from gtmodel.problems.results import MARKER, MAX_FILE_NAME, is_file_name
from gtmodel.problems.study.design import load_study

from ..conftest import PROBLEMS_DIR
from .study.study_fixtures import write_base

BASE = PROBLEMS_DIR / "l1_time_optimal.toml"
STUDIES_DIR = PROBLEMS_DIR.parent / "studies"
BAD_NAMES = ["../../escaped", "/tmp/escaped", "a/b", "..", ".", "a\\b", " lead", "tail ", "tab\tname", "x" * (MAX_FILE_NAME + 1),
             "é" * (MAX_FILE_NAME // 2 + 1)]
GOOD_NAMES = ["l1_time_optimal", "my problem", "1: 3-link, linear actuators", "Größe", "x" * MAX_FILE_NAME, "a..b", ".hidden"]


def _with_name(tmp_path, name: str):
    text = BASE.read_text()
    head, sep, rest = text.partition("\nname = ")
    assert sep, "the shipped file has a name line"
    path = tmp_path / "problem.toml"
    path.write_text(head + f"\nname = {json.dumps(name)}" + rest[rest.index("\n"):])
    return path


@pytest.mark.parametrize("name", GOOD_NAMES)
def test_plain_names_are_file_names(name):
    assert is_file_name(name)


@pytest.mark.parametrize("name", [*BAD_NAMES, "", 3, ["a"], None])
def test_names_that_are_not_one_path_component_are_not_file_names(name):
    assert not is_file_name(name)


@pytest.mark.parametrize("name", BAD_NAMES[:6])
def test_a_problem_name_that_climbs_out_is_refused_at_load(tmp_path, name):
    with pytest.raises(ProblemError, match=r"field 'name': expected a name of 1 to 100 bytes of printable characters"):
        load_problem(_with_name(tmp_path, name))


@pytest.mark.parametrize("name", ["../../escaped", "/tmp/gtmodel_escaped_by_name", "sub/escaped"])
def test_solve_without_out_writes_nothing_outside_results(tmp_path, monkeypatch, capsys, name):
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    problem = _with_name(tmp_path, name)
    monkeypatch.chdir(work)
    before = sorted(p for p in tmp_path.rglob("*"))
    code = main(["solve", str(problem), "-q", "--no-plots"])
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT and "field 'name'" in err and "Traceback" not in err
    new = sorted(set(tmp_path.rglob("*")) - set(before))
    assert all(p.is_relative_to(work / "results") for p in new), new  # nothing outside results/
    assert json.loads((work / "results" / "problem" / "summary.json").read_text())["status"] == "invalid_input"


def test_a_study_name_that_climbs_out_is_refused(tmp_path):
    (tmp_path / "base.toml").write_text(BASE.read_text())
    study = tmp_path / "study.toml"
    text = (STUDIES_DIR / "l1_time_optimal_map.toml").read_text()
    study.write_text(text.replace('name = "l1_time_optimal_map"', 'name = "../../escaped"')
                     .replace('base = "../problems/l1_time_optimal.toml"', 'base = "base.toml"'))
    with pytest.raises(ProblemError, match=r"field 'name': expected a name of 1 to 100 bytes"):
        load_study(study)


@pytest.mark.parametrize(("first", "code"), [("SIGINT", 130), ("SIGTERM", 143)])
def test_the_process_exits_128_plus_the_first_signal(monkeypatch, first, code):
    monkeypatch.setattr(_signals._state, "count", 2)
    monkeypatch.setattr(_signals._state, "name", first)
    assert _signals.process_exit_code(EXIT_INTERRUPTED) == code == 128 + signal.Signals[first].value
    assert _signals.process_exit_code(0) == 0  # finished before the signal: its own code stands
    assert _signals.process_exit_code(EXIT_BAD_INPUT) == EXIT_BAD_INPUT


def test_without_a_signal_130_stays_130(monkeypatch):
    monkeypatch.setattr(_signals._state, "count", 0)
    assert _signals.process_exit_code(EXIT_INTERRUPTED) == 130


@pytest.mark.parametrize(("sig", "process_code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_while_the_kind_writes_leaves_the_interrupted_summary_alone(tmp_path, monkeypatch, capsys, sig, process_code):
    """A real signal to this process, sent by the kind's writer halfway through its files."""
    from gtmodel.problems.kinds import path_constrained

    write = path_constrained.PathConstrainedKind.write

    def write_then_signal(self, declaration, solution, out, plots, name):
        written = write(self, declaration, solution, out, plots, name)  # the data files are in the partial folder
        os.kill(os.getpid(), sig)  # the handler raises KeyboardInterrupt here (an interruptible section)
        return written

    base = write_base(tmp_path, grid=50)
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.json").write_text(json.dumps({"status": "optimal", "files": ["summary.json"], "written_by": MARKER}))
    monkeypatch.setattr(path_constrained.PathConstrainedKind, "write", write_then_signal)
    code = main(["solve", str(base), "--out", str(out), "-q", "--no-plots"])
    err = capsys.readouterr().err
    assert (code, _signals.process_exit_code(code)) == (EXIT_INTERRUPTED, process_code), err
    assert json.loads((out / "summary.json").read_text())["status"] == "interrupted"
    assert sorted(p.name for p in out.iterdir()) == ["summary.json"]  # no half-written data file of the run
    assert sorted(p.name for p in tmp_path.iterdir()) == ["base.toml", "out"]  # no partial folder or lock left
    assert "Traceback" not in err
