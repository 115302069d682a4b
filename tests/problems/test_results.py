"""Result folders are never stale and never half-written; interrupts stop the whole run.

Checked against the file system itself: what is in the folder after each kind of
failure, after a SIGKILL mid-run (a real subprocess), and after SIGINT during IPOPT.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import shutil
import signal
import socket
import subprocess
import sys
import time

import pytest

from gtmodel.cli import EXIT_BAD_INPUT, EXIT_INTERRUPTED, EXIT_NOT_OPTIMAL, main
from gtmodel.errors import ResultWriteError
from gtmodel.problems.results import MARKER, ResultFolder
from gtmodel.problems.runtime import Heartbeat, InterruptGuard
from gtmodel.status import Status

from ..bad_problems import BASE
from ..conftest import REPO


def _files(folder):
    return sorted(p.name for p in folder.iterdir())


def _earlier_run(target, files):
    """A result folder an earlier run wrote: its files and its summary.json listing them."""
    target.mkdir()
    for name, text in files.items():
        (target / name).write_text(text)
    (target / "summary.json").write_text(json.dumps({"status": "optimal", "files": ["summary.json", *files]}))


def test_commit_replaces_the_folder_and_lists_every_file(tmp_path):
    target = tmp_path / "out"
    _earlier_run(target, {"old.csv": "stale"})
    folder = ResultFolder(target)
    (folder.path / "a.csv").write_text("1")
    (folder.path / "b.png").write_bytes(b"x")
    assert _files(target) == ["old.csv", "summary.json"]  # nothing visible before the commit
    summary = folder.commit({"status": "optimal"})
    assert _files(target) == ["a.csv", "b.png", "summary.json"]
    assert json.loads((target / "summary.json").read_text())["files"] == ["summary.json", "a.csv", "b.png"]
    assert summary["files"] == ["summary.json", "a.csv", "b.png"]
    assert _files(tmp_path) == ["out"]  # no partial or old folder left behind


def test_discard_leaves_the_earlier_folder_untouched(tmp_path):
    target = tmp_path / "out"
    _earlier_run(target, {"trajectory.csv": "earlier run"})
    folder = ResultFolder(target)
    (folder.path / "half.csv").write_text("half")
    folder.discard()
    assert _files(tmp_path) == ["out"]
    assert (target / "trajectory.csv").read_text() == "earlier run"


def test_orphaned_partial_folder_of_a_dead_process_is_removed(tmp_path):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True).stdout.strip()
    orphan = tmp_path / f".out.partial-{dead}"
    orphan.mkdir()
    ResultFolder(tmp_path / "out").discard()
    assert not orphan.exists()


def test_a_file_in_place_of_the_folder_is_an_io_error_naming_it(tmp_path):
    target = tmp_path / "out"
    target.write_text("a file")
    with pytest.raises(ResultWriteError, match=f"cannot write the result folder {target}"):
        ResultFolder(target)  # refused before anything is written
    assert _files(tmp_path) == ["out"]
    assert target.read_text() == "a file"


@pytest.fixture(scope="module")
def earlier_run(tmp_path_factory):
    """A successful solve of the shipped minimum-time problem into a folder."""
    out = tmp_path_factory.mktemp("earlier") / "out"
    assert main(["solve", str(BASE), "--out", str(out), "--quiet"]) == 0
    assert {"trajectory.csv", "trajectory.h", "tcp_path.png", "forces.png"} <= set(_files(out))
    return out


def _hashes(folder):
    """Every file under a folder and the SHA-256 of its bytes."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.rglob("*")) if p.is_file()}


#: Reruns that fail over a complete earlier result: each leaves it byte for byte (issue 67).
FAILED_RERUNS = {
    "bad_toml": (lambda t: t.replace("[limits]", "[limits"), "invalid TOML"),
    "force_1e308": (lambda t: t.replace("force = [450.0, 450.0, 450.0]", "force = [1e308, 450.0, 450.0]"), "limits.force"),
    "missing_guess_file": (lambda t: t.replace('method = "trapezoid"', 'method = "file"\nfile = "nowhere.csv"'), "initial_guess.file"),
}


@pytest.mark.parametrize("edit, match", FAILED_RERUNS.values(), ids=FAILED_RERUNS)
def test_a_failed_rerun_leaves_every_file_of_the_earlier_result_byte_identical(tmp_path, capsys, earlier_run, edit, match):
    out = tmp_path / "out"
    subprocess.run(["cp", "-r", str(earlier_run), str(out)], check=True)
    before = _hashes(out)
    broken = tmp_path / "broken.toml"
    broken.write_text(edit(BASE.read_text()))
    assert main(["solve", str(broken), "--out", str(out), "--quiet"]) == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    failed = json.loads((tmp_path / "out.failed" / "summary.json").read_text())
    assert _hashes(out) == before
    assert (failed["status"], failed["files"], failed["earlier_result_kept"]) == ("invalid_input", ["summary.json"], str(out))
    assert match in failed["message"] and f"the earlier result in {out}/ is kept as it was" in err
    assert _files(tmp_path) == ["broken.toml", "out", "out.failed"]


def test_a_complete_rerun_replaces_every_file_and_the_failed_folder_beside(tmp_path, earlier_run):
    """A run that finished (here: infeasible, exit 1) replaces the folder whole: no file of the earlier
    run survives, and the ``out.failed`` of an earlier failed run is removed."""
    out = tmp_path / "out"
    subprocess.run(["cp", "-r", str(earlier_run), str(out)], check=True)
    (tmp_path / "bad.toml").write_text("kind = [")
    assert main(["solve", str(tmp_path / "bad.toml"), "--out", str(out), "--quiet"]) == EXIT_BAD_INPUT
    assert (tmp_path / "out.failed" / "summary.json").is_file()
    infeasible = tmp_path / "infeasible.toml"
    infeasible.write_text(BASE.read_text().replace("force = [450.0, 450.0, 450.0]", "force = [152.0, 152.0, 152.0]")
                          .replace("elements = 50 ", "elements = 10 "))
    assert main(["solve", str(infeasible), "--out", str(out), "--quiet"]) == EXIT_NOT_OPTIMAL
    summary = json.loads((out / "summary.json").read_text())
    assert _files(out) == sorted(summary["files"]) == ["report.html", "summary.json"]  # a solved run's page, not optimal
    assert summary["status"] in ("infeasible", "max_iterations") and "earlier_result_kept" not in summary
    assert _files(tmp_path) == ["bad.toml", "infeasible.toml", "out"]


def _solve_process(out, *extra, problem=BASE):
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(REPO))
    return subprocess.Popen(
        [sys.executable, "-m", "gtmodel.cli", "solve", str(problem), "--out", str(out), "--no-plots", *extra],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=REPO,
    )


def _wait_for(proc, text, timeout=120):
    """Read stderr lines until one contains ``text`` (the solve has started)."""
    t0 = time.monotonic()
    lines = []
    while time.monotonic() - t0 < timeout:
        line = proc.stderr.readline()
        lines.append(line)
        if text in line:
            return
        if not line and proc.poll() is not None:
            break
    pytest.fail(f"never saw {text!r}: {lines}")


def test_sigkill_mid_run_leaves_the_earlier_folder_intact(tmp_path, earlier_run):
    out = tmp_path / "out"
    subprocess.run(["cp", "-r", str(earlier_run), str(out)], check=True)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    # 400 elements: the solve lasts seconds, so the kill lands mid-run on a fast machine too
    # (at 50 elements the run could finish inside the 0.5 s and replace the folder legitimately)
    slow = tmp_path / "slow.toml"
    slow.write_text(BASE.read_text().replace("elements = 50 ", "elements = 400 "))
    proc = _solve_process(out, "-v", problem=slow)
    _wait_for(proc, "solving")
    time.sleep(0.5)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


@pytest.mark.slow
def test_sigint_during_ipopt_stops_with_status_interrupted(tmp_path):
    out = tmp_path / "out"
    text = BASE.read_text().replace("elements = 50 ", "elements = 400 ")
    slow = tmp_path / "slow.toml"
    slow.write_text(text)
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(REPO))
    proc = subprocess.Popen(
        [sys.executable, "-m", "gtmodel.cli", "solve", str(slow), "--out", str(out), "--no-plots", "-v"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=REPO,
    )
    t0 = time.monotonic()
    while time.monotonic() - t0 < 120:  # wait for IPOPT's iteration log
        line = proc.stdout.readline()
        if line.lstrip().startswith("1 ") or "iter" in line:
            break
    proc.send_signal(signal.SIGINT)
    code = proc.wait(timeout=120)
    err = proc.stderr.read()
    assert code == EXIT_INTERRUPTED, err
    assert "interrupted" in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    assert _files(out) == ["summary.json"]


def test_interrupt_guard_turns_a_swallowed_sigint_into_keyboardinterrupt():
    with pytest.raises(KeyboardInterrupt):
        with InterruptGuard() as guard:
            try:
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(0.1)
            except KeyboardInterrupt:
                pass  # what a solver does
            guard.check()


def test_heartbeat_logs_while_running(caplog):
    # waits for the third line (up to 30 s) rather than counting lines in a fixed 0.3 s: a loaded machine delays the
    # heartbeat's thread (the default run saw 2 lines in 0.3 s beside a benchmark)
    caplog.set_level(logging.INFO, logger="gtmodel")

    def lines() -> list[str]:
        return [r.getMessage() for r in caplog.records if "still running" in r.getMessage()]

    with Heartbeat("solving x", interval=0.05):
        deadline = time.monotonic() + 30.0
        while len(lines()) < 3 and time.monotonic() < deadline:
            time.sleep(0.05)
    lines = lines()
    assert len(lines) >= 3
    assert lines[0].startswith("solving x: still running")


def test_heartbeat_keeps_quiet_while_the_run_says_something_itself(caplog):
    """The loop's serving lines replace the heartbeat's (issue 67): a line at least every interval silences it."""
    caplog.set_level(logging.INFO, logger="gtmodel")
    with Heartbeat("solving x", interval=0.1):
        for _ in range(8):
            logging.getLogger("gtmodel").info("serving")
            time.sleep(0.05)
        time.sleep(0.45)  # then silence: the heartbeat speaks again
    lines = [r.getMessage() for r in caplog.records]
    first = lines.index(next(m for m in lines if "still running" in m))
    assert lines.count("serving") == 8 and first >= 8


def test_heartbeat_disabled_is_silent(caplog):
    caplog.set_level(logging.INFO, logger="gtmodel")
    with Heartbeat("solving x", interval=0.05, enabled=False):
        time.sleep(0.2)
    assert not [r for r in caplog.records if "still running" in r.getMessage()]


#: Folders of a user's own files: a run must refuse them, not replace them (issue 26, item 1).
USER_FOLDERS = {
    "problem_files": {"a.toml": "kind = 'x'\n", "b.toml": "kind = 'y'\n"},
    "only_a_hidden_repo": {".git/HEAD": "ref: refs/heads/main\n"},
    "a_foreign_summary": {"summary.json": '{"total": 3}', "data.csv": "1,2\n"},
}


def _make(folder, files):
    for name, text in files.items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_text(text)
    return {p.relative_to(folder): p.read_text() for p in folder.rglob("*") if p.is_file()}


@pytest.mark.parametrize("files", USER_FOLDERS.values(), ids=USER_FOLDERS)
def test_a_folder_of_the_users_files_is_refused_by_the_cli_and_left_as_it_was(tmp_path, capsys, files):
    """Also a bad problem file (whose run writes only a summary) must not empty it."""
    mine = tmp_path / "mine"
    mine.mkdir()
    before = _make(mine, files)
    codes = [main(["solve", str(p), "--out", str(mine)]) for p in (REPO / "problems" / "l1_time_optimal.toml", tmp_path / "missing.toml")]
    assert codes == [EXIT_BAD_INPUT, EXIT_BAD_INPUT]
    assert f"will not write the result folder {mine}: it holds files that no gtmodel run wrote" in capsys.readouterr().err
    assert {p.relative_to(mine): p.read_text() for p in mine.rglob("*") if p.is_file()} == before


@pytest.mark.parametrize("files", USER_FOLDERS.values(), ids=USER_FOLDERS)
def test_result_folder_refuses_a_folder_of_the_users_files(tmp_path, files):
    """The library path (run_problem, studies) goes through ResultFolder: the same rule."""
    before = _make(tmp_path, files)
    with pytest.raises(ResultWriteError, match="it holds files that no gtmodel run wrote"):
        ResultFolder(tmp_path)
    assert {p.relative_to(tmp_path): p.read_text() for p in tmp_path.rglob("*") if p.is_file()} == before


def test_an_empty_folder_and_an_earlier_result_folder_are_written(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    for _ in range(2):  # empty, then the folder the first commit wrote
        with ResultFolder(out) as folder:
            folder.commit({"status": "optimal"})
    assert _files(out) == ["summary.json"]


def test_an_interrupted_rerun_leaves_the_earlier_result_byte_identical(tmp_path, earlier_run):
    """SIGINT to a real ``gtmodel solve`` once it is solving: exit 130, the earlier folder as it was."""
    out = tmp_path / "out"
    subprocess.run(["cp", "-r", str(earlier_run), str(out)], check=True)
    before = _hashes(out)
    slow = tmp_path / "slow.toml"
    slow.write_text(BASE.read_text().replace("elements = 50 ", "elements = 400 "))
    proc = _solve_process(out, "-v", problem=slow)
    _wait_for(proc, "solving")
    time.sleep(0.5)
    proc.send_signal(signal.SIGINT)
    code = proc.wait(timeout=60)
    err = proc.stderr.read()
    failed = json.loads((tmp_path / "out.failed" / "summary.json").read_text())
    assert (code, failed["status"], _hashes(out)) == (EXIT_INTERRUPTED, "interrupted", before), err
    assert f"the earlier result in {out}/ is kept as it was; this run (interrupted) is in {out}.failed/" in err


@pytest.fixture
def signal_after_refinement(monkeypatch):
    """The kind's solve returns, then a Ctrl-C is counted: as when IPOPT swallowed it in a refinement's last pass."""
    from gtmodel import _signals
    from gtmodel.problems.registry import get_kind

    kind = type(get_kind("point_to_point"))
    solve = kind.solve

    def solve_then_signal(self, *args, **kwargs):
        solution = solve(self, *args, **kwargs)
        _signals._state.count += 1
        return solution

    monkeypatch.setattr(kind, "solve", solve_then_signal)
    yield
    _signals.reset()


@pytest.mark.slow  # a refined solve in this process: about 10 s
def test_ctrl_c_during_refinement_keeps_the_last_verified_pass_as_the_result(tmp_path, capsys, signal_after_refinement):
    out = tmp_path / "out"
    code = main(["solve", str(BASE), "--out", str(out), "--quiet", "--no-plots", "--no-report"])
    summary = json.loads((out / "summary.json").read_text())
    err = capsys.readouterr().err
    assert (code, summary["status"], summary["verification"]["passed"]) == (EXIT_INTERRUPTED, "interrupted", True)
    assert summary["final_time_s"] is not None and {"trajectory.csv", "trajectory.h"} <= set(summary["files"])
    assert "the result is its last verified pass" in summary["message"] and "gtmodel: interrupted (" in err
    assert summary["refinement"] and any(p.get("returned") for p in summary["refinement"])


def test_commit_keeps_a_complete_result_and_writes_the_failed_folder_beside(tmp_path):
    target = tmp_path / "out"
    _earlier_run(target, {"trajectory.csv": "earlier run"})
    with ResultFolder(target) as folder:
        written = folder.commit({"status": "invalid_input"}, keep_complete=True)
    assert (folder.kept, folder.target, written["earlier_result_kept"]) == (target, tmp_path / "out.failed", str(target))
    assert (target / "trajectory.csv").read_text() == "earlier run" and _files(tmp_path) == ["out", "out.failed"]


def test_a_failed_run_over_a_failed_runs_summary_replaces_it(tmp_path):
    target = tmp_path / "out"
    for status in ("invalid_input", "interrupted"):
        with ResultFolder(target) as folder:
            folder.commit({"status": status}, keep_complete=True)
    assert json.loads((target / "summary.json").read_text())["status"] == "interrupted" and _files(tmp_path) == ["out"]


def test_a_folder_of_the_users_files_beside_is_never_written(tmp_path):
    """``out.failed`` holding the user's files: the failed run's summary is not written there (nor anywhere)."""
    target = tmp_path / "out"
    _earlier_run(target, {"trajectory.csv": "earlier run"})
    mine = tmp_path / "out.failed"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    folder = ResultFolder(target)
    with pytest.raises(ResultWriteError, match=f"will not write the result folder {mine}: it holds files that no gtmodel run wrote"):
        folder.commit({"status": "invalid_input"}, keep_complete=True)
    folder.discard()
    assert (mine / "notes.txt").read_text() == "mine" and _files(mine) == ["notes.txt"] and _files(tmp_path) == ["out", "out.failed"]
    assert (target / "trajectory.csv").read_text() == "earlier run"


@pytest.mark.parametrize("status, ends_on_signal, expected", [
    ("optimal", False, True), ("infeasible", False, True), ("check_failed", False, True), ("error", False, False),
    ("invalid_input", False, False), ("internal_error", False, False), ("interrupted", False, False), ("interrupted", True, True),
])
def test_which_runs_finished(status, ends_on_signal, expected):
    from gtmodel.problems.results import finished

    assert finished(status, ends_on_signal) is expected


@pytest.mark.slow  # a real refinement interrupted in a subprocess: about 10 to 20 s
def test_sigint_after_a_verified_refinement_pass_writes_that_pass_with_status_interrupted(tmp_path):
    """The shipped problem refines after its first solve; SIGINT right after pass 2 (verified) is logged."""
    out = tmp_path / "out"
    proc = _solve_process(out)
    _wait_for(proc, "pass 2,")
    proc.send_signal(signal.SIGINT)
    code = proc.wait(timeout=120)
    err = proc.stderr.read()
    summary = json.loads((out / "summary.json").read_text())
    assert (code, summary["status"], summary["verification"]["passed"]) == (EXIT_INTERRUPTED, "interrupted", True), err
    assert summary["final_time_s"] is not None and "trajectory.csv" in summary["files"] and (out / "trajectory.csv").is_file()
    assert summary["refinement_stop"].startswith("interrupted by the user during pass 3; returned pass 2")


@pytest.mark.slow  # the loop's C is generated and compiled: about 20 s
@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc: the loop's runtime is compiled")
def test_a_loop_whose_port_is_taken_keeps_the_earlier_cycle_log(tmp_path):
    """``gtmodel loop`` exits 1 (status error) when its port is taken: the earlier cycle log stays byte for byte."""
    out = tmp_path / "loop"
    _earlier_run(out, {"cycle_log.csv": "cycle,t\n0,0\n"})
    summary = json.loads((out / "summary.json").read_text())
    (out / "summary.json").write_text(json.dumps({**summary, "status": "completed", "written_by": MARKER}))
    before = _hashes(out)
    taken = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    taken.bind(("127.0.0.1", 0))
    try:
        env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(REPO))
        done = subprocess.run([sys.executable, "-m", "gtmodel.cli", "loop", str(REPO / "loops" / "l1_egm_ilc.toml"), "--out", str(out),
                               "--listen", f"127.0.0.1:{taken.getsockname()[1]}", "--idle-timeout", "2", "--quiet"],
                              capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300)
    finally:
        taken.close()
    failed = json.loads((tmp_path / "loop.failed" / "summary.json").read_text())
    assert (done.returncode, failed["status"], _hashes(out)) == (EXIT_NOT_OPTIMAL, "error", before), done.stderr
    assert "Address already in use" in failed["message"] and f"the earlier result in {out}/ is kept as it was" in done.stderr


def test_an_interrupted_comparison_keeps_a_complete_earlier_comparison(tmp_path, monkeypatch):
    """``gtmodel solve A.toml B.toml``: Ctrl-C before any case finished leaves the earlier comparison byte for byte."""
    from gtmodel.problems.study import engine
    from gtmodel.problems.study.design import comparison_study

    from .study.study_fixtures import write_base

    out = tmp_path / "cmp"
    _earlier_run(out, {"comparison.md": "| earlier |\n", "table.csv": "status\noptimal\n"})
    before = _hashes(out)

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(engine, "execute", interrupted)
    base = write_base(tmp_path)
    other = tmp_path / "other.toml"
    other.write_text(base.read_text().replace("grid = 50 ", "grid = 40 ", 1))
    outcome = engine.run_study(comparison_study([base, other], plots=False), out)
    failed = json.loads((tmp_path / "cmp.failed" / "summary.json").read_text())
    assert (outcome.status, outcome.out, _hashes(out)) == (Status.INTERRUPTED, (tmp_path / "cmp.failed").resolve(), before)
    assert (failed["status"], failed["earlier_result_kept"]) == ("interrupted", str(out))


@pytest.mark.parametrize("keep_earlier, left", [(True, ["out", "out.failed"]), (False, ["out"])], ids=["a_run", "a_study_case"])
def test_write_failure_keeps_a_complete_result_unless_told_not_to(tmp_path, keep_earlier, left):
    from gtmodel.problems.run import write_failure

    target = tmp_path / "out"
    _earlier_run(target, {"trajectory.csv": "earlier run"})
    written, summary, why, folder = write_failure(target, {"status": "interrupted"}, keep_earlier)
    assert (written, why, folder, _files(tmp_path)) == (True, "", tmp_path / left[-1], left)
    assert ((target / "trajectory.csv").exists(), summary.get("earlier_result_kept")) == (keep_earlier, str(target) if keep_earlier else None)
