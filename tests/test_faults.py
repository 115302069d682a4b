"""The fault suite of docs/reliability.md: what a careless or unlucky user does to a run.

Each test runs the real ``gtmodel`` command in a subprocess (``python -m gtmodel``) where
the fault needs one: real SIGINT/SIGTERM (also during start-up, and repeated), a full disk
(a tiny tmpfs where the machine lets the test mount one, else a file-size limit), two
concurrent runs, read-only and busy paths, folders of the user's own files, hostile data
files. The independent reference is the file system: the bytes of the user's files, the
``summary.json`` on disk and the files it lists, the exit code.
"""

from __future__ import annotations

import errno
import json
import os
import random
import resource
import shutil
import signal
import subprocess
import sys
import threading
import time
import warnings
from pathlib import Path

import pytest

from gtmodel.problems.results import MARKER, ResultFolder, output_lock

from .conftest import REPO
from .problems.study.study_fixtures import write_base

ENV = {**os.environ, "PYTHONPATH": str(REPO), "MPLBACKEND": "Agg"}
#: The process's exit code by the first signal that stopped the run (128 + the signal's number).
EXIT_BY_SIGNAL = {signal.SIGINT: 130, signal.SIGTERM: 143}


def _command(*args: str) -> list[str]:
    return [sys.executable, "-m", "gtmodel", *args]


def _start(*args: str, **kw) -> subprocess.Popen:
    return subprocess.Popen(_command(*args), env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)


def _run(*args: str, timeout: float = 120, **kw) -> subprocess.CompletedProcess:
    return subprocess.run(_command(*args), env=ENV, capture_output=True, text=True, timeout=timeout, **kw)


def _handles_signals(pid: int) -> bool:
    """Whether the process catches SIGINT and SIGTERM (``SigCgt`` of /proc/<pid>/status)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    caught = int(next(line.split()[1] for line in status.splitlines() if line.startswith("SigCgt:")), 16)
    return all(caught & (1 << (s - 1)) for s in (signal.SIGINT, signal.SIGTERM))


def _earlier_result(out: Path) -> None:
    """A complete earlier result folder (an optimal run's files)."""
    out.mkdir(parents=True)
    (out / "trajectory.csv").write_text("t,x\n0,0\n")
    (out / "summary.json").write_text(json.dumps({"status": "optimal", "files": ["summary.json", "trajectory.csv"],
                                                  "written_by": MARKER}))


def _summary(out: Path) -> dict:
    return json.loads((out / "summary.json").read_text())


def _only_summary(out: Path) -> bool:
    return sorted(p.name for p in out.iterdir()) == ["summary.json"]


def _earlier_kept(out: Path, status: str) -> bool:
    """The earlier result byte for byte, and the run's own summary (status ``status``) alone in ``<out>.failed``."""
    failed = out.parent / f"{out.name}.failed"
    return ((out / "trajectory.csv").read_text() == "t,x\n0,0\n" and _summary(out)["status"] == "optimal"
            and sorted(p.name for p in out.iterdir()) == ["summary.json", "trajectory.csv"]
            and _summary(failed)["status"] == status and _only_summary(failed) and _summary(failed)["earlier_result_kept"] == str(out))


def _no_partials(parent: Path) -> bool:
    return not [p for p in parent.iterdir() if ".partial-" in p.name or ".old-" in p.name or p.name.endswith(".lock")]


# ----------------------------------------------------------------------------- --out refused up front


@pytest.fixture
def base(tmp_path) -> Path:
    """l1_path_constrained.toml on a coarse grid: a complete solve in about a second."""
    return write_base(tmp_path, grid=50)


def test_a_folder_of_the_users_files_is_refused_and_left_byte_identical(tmp_path, base):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_bytes(b"my notes\x00")
    (mine / "summary.json").write_text('{"status": "optimal"}')  # not gtmodel's: no marker, no file list
    done = _run("solve", str(base), "--out", str(mine), "-q")
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("gtmodel: error:") == 1 and f"result folder {mine}:" in done.stderr
    assert sorted(p.name for p in mine.iterdir()) == ["notes.txt", "summary.json"]
    assert (mine / "notes.txt").read_bytes() == b"my notes\x00" and _no_partials(tmp_path)


@pytest.mark.parametrize("where, message", [
    ("file/sub", "its parent {tmp}/file is a file"),
    ("file", "a file of that name is in the way"),
    ("link", "it is a symbolic link, which a run would replace by a folder; give the folder it points to ({tmp}/earlier)"),
    (".", "it holds the current folder"),
], ids=["under_a_file", "a_file", "a_symlink", "the_current_folder"])
def test_a_bad_out_is_one_plain_message_naming_it(tmp_path, base, where, message):
    (tmp_path / "file").write_text("x")
    _earlier_result(tmp_path / "earlier")
    (tmp_path / "link").symlink_to(tmp_path / "earlier")
    done = _run("solve", str(base), "--out", where, "-q", cwd=tmp_path)
    assert done.returncode == 2
    assert done.stderr == f"gtmodel: error: cannot write the result folder {where}: {message.format(tmp=tmp_path)}\n" \
        or (where == "." and done.stderr.startswith(f"gtmodel: error: will not write the result folder .: {message}"))
    assert "File exists" not in done.stderr and (tmp_path / "file").read_text() == "x"


def test_a_busy_out_is_refused_at_once_naming_the_other_run(tmp_path, base):
    out = tmp_path / "out"
    _earlier_result(out)
    with output_lock(out):  # another run holds it
        t0 = time.monotonic()
        done = _run("solve", str(base), "--out", str(out), "-q")
        assert time.monotonic() - t0 < 30  # before any solve
    assert done.returncode == 2
    assert f"cannot write the result folder {out}: another gtmodel run (process {os.getpid()}) is writing it" in done.stderr
    assert _summary(out)["status"] == "optimal"  # the other run's folder is not touched


def _mount_tmpfs(path: Path, options: str) -> bool:
    path.mkdir(parents=True, exist_ok=True)
    if os.geteuid() != 0 or shutil.which("mount") is None:
        return False
    return subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(path)], capture_output=True).returncode == 0


def _umount(path: Path) -> None:
    subprocess.run(["umount", "-l", str(path)], capture_output=True)


def test_a_read_only_out_is_refused_before_any_work(tmp_path, base):
    ro = tmp_path / "ro"
    mounted = _mount_tmpfs(ro, "ro,size=64k")
    if not mounted:
        if os.geteuid() == 0:
            pytest.skip("root without mount: permissions do not make a folder read-only")
        ro.chmod(0o555)
    try:
        t0 = time.monotonic()
        done = _run("solve", str(base), "--out", str(ro / "out"), "-q")
        assert done.returncode == 2 and time.monotonic() - t0 < 30
        assert done.stderr == f"gtmodel: error: cannot write the result folder {ro / 'out'}: {ro} is not writable\n"
    finally:
        _umount(ro) if mounted else ro.chmod(0o755)


# ----------------------------------------------------------------------------- signals


@pytest.mark.parametrize("signals", [(signal.SIGINT,), (signal.SIGTERM,), (signal.SIGINT, signal.SIGINT, signal.SIGTERM)],
                         ids=["sigint", "sigterm", "repeated"])
def test_a_signal_during_start_up_ends_interrupted_with_130_or_143_and_the_earlier_result_kept(tmp_path, base, signals):
    out = tmp_path / "out"
    _earlier_result(out)
    proc = _start("solve", str(base), "--out", str(out), "-q")
    try:
        deadline = time.monotonic() + 30
        while not _handles_signals(proc.pid) and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.002)
        for s in signals:  # at once: the heavy imports are still running
            proc.send_signal(s)
            time.sleep(0.01)
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == EXIT_BY_SIGNAL[signals[0]], err
    assert "Traceback" not in err and err.count("gtmodel: interrupted") == 1
    assert _earlier_kept(out, "interrupted") and _no_partials(tmp_path)


@pytest.mark.slow  # a solve long enough to be interrupted at random moments: about a minute
def test_signals_at_random_moments_always_give_130_or_the_finished_result(tmp_path):
    base = write_base(tmp_path, grid=3000)
    out = tmp_path / "out"
    rng = random.Random(26)
    wrong = []
    for k in range(8):
        shutil.rmtree(out, ignore_errors=True)
        shutil.rmtree(tmp_path / "out.failed", ignore_errors=True)
        _earlier_result(out)
        proc = _start("solve", str(base), "--out", str(out), "-q")
        time.sleep(rng.uniform(0.3, 6.0))
        sent = [rng.choice([signal.SIGINT, signal.SIGTERM]) for _ in range(rng.randint(1, 3))]
        for s in sent:
            proc.send_signal(s)
            time.sleep(rng.uniform(0.0, 0.2))
        _, err = proc.communicate(timeout=120)
        summary = _summary(out)
        interrupted = proc.returncode == EXIT_BY_SIGNAL[sent[0]] and _earlier_kept(out, "interrupted")
        finished = (proc.returncode == 0 and summary["status"] == "optimal"  # written before the signal: it stands
                    and all((out / f).exists() for f in summary["files"]) and not (tmp_path / "out.failed").exists())
        if not (interrupted or finished) or "Traceback" in err or not _no_partials(tmp_path):
            wrong.append((k, proc.returncode, summary["status"], err))
    assert not wrong


# ----------------------------------------------------------------------------- a failed write


def test_a_write_failure_keeps_the_earlier_result_and_writes_the_summary_beside_with_one_message(tmp_path, monkeypatch, capsys):
    """In this process: the kind's writer fails with ENOSPC (as on a full disk)."""
    from gtmodel.cli import main
    from gtmodel.problems.kinds import path_constrained

    def full(*args, **kw):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    base = write_base(tmp_path, grid=50)
    out = tmp_path / "out"
    _earlier_result(out)
    monkeypatch.setattr(path_constrained.PathConstrainedKind, "write", full)
    code = main(["solve", str(base), "--out", str(out), "-q", "--no-plots"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.splitlines()[0] == f"gtmodel: error: cannot write the result folder {out}: No space left on device"
    assert ".partial-" not in err and err.count("gtmodel: error") == 1
    assert _earlier_kept(out, "invalid_input") and _no_partials(tmp_path)


@pytest.mark.slow  # a real full disk: a solve in a subprocess (about 5 s)
def test_a_full_disk_keeps_the_earlier_result_as_it_was(tmp_path, base):
    disk = tmp_path / "disk"
    mounted = _mount_tmpfs(disk, "size=64k")
    limit = None
    if not mounted:  # no tmpfs here: a file-size limit makes the big files fail the same way (EFBIG)
        disk.mkdir(exist_ok=True)
        limit = lambda: resource.setrlimit(resource.RLIMIT_FSIZE, (20_000, 20_000))  # noqa: E731
    try:
        out = disk / "out"
        _earlier_result(out)
        done = _run("solve", str(base), "--out", str(out), "-q", preexec_fn=limit)
        assert done.returncode == 2, done.stderr
        assert done.stderr.splitlines()[0].startswith(f"gtmodel: error: cannot write the result folder {out}: ")
        assert ".partial-" not in done.stderr and "Traceback" not in done.stderr
        assert _earlier_kept(out, "invalid_input") and _no_partials(disk)
    finally:
        if mounted:
            _umount(disk)


# ----------------------------------------------------------------------------- concurrent runs


def test_a_reader_never_finds_the_folder_missing_while_it_is_replaced(tmp_path):
    out = tmp_path / "out"
    _earlier_result(out)
    missing = []
    stop = threading.Event()

    def read() -> None:
        while not stop.is_set():
            if not (out / "summary.json").exists():
                missing.append(time.monotonic())
            time.sleep(0)  # let the writer run

    reader = threading.Thread(target=read)
    reader.start()
    try:
        for k in range(60):
            with ResultFolder(out) as folder:
                (folder.path / "data.csv").write_text(f"{k}\n")
                folder.commit({"status": "optimal"})
    finally:
        stop.set()
        reader.join()
    assert not missing and (out / "data.csv").read_text() == "59\n" and _no_partials(tmp_path)


@pytest.mark.slow  # two solves in subprocesses at once (about 5 s)
def test_two_concurrent_runs_give_one_complete_folder_and_a_plain_message_to_the_other(tmp_path, base):
    out = tmp_path / "out"
    procs = [_start("solve", str(base), "--out", str(out), "-q", "--no-plots") for _ in range(2)]
    results = [(p.wait(timeout=180), p.stderr.read()) for p in procs]
    codes = sorted(c for c, _ in results)
    assert codes == [0, 2], results
    lost = next(err for c, err in results if c == 2)
    assert "another gtmodel run" in lost and "is writing it" in lost and "Traceback" not in lost
    summary = _summary(out)
    assert summary["status"] == "optimal" and all((out / f).exists() for f in summary["files"]) and _no_partials(tmp_path)


# ----------------------------------------------------------------------------- data files


def _rows(path: Path, header: str, row: str, n: int) -> Path:
    path.write_text(header + "\n" + (row + "\n") * n)
    return path


@pytest.mark.parametrize("reader, header, row", [
    ("gtmodel.calibration.measurements:read_measurements", "q1_m,q2_m,q3_m,Tx_m,Ty_m,Tz_m", "0,0,0,0,0,0"),
    ("gtmodel.calibration.measurements:read_cart_measurements", "arm,q_m,x_m,y_m,z_m", "1,0,0,0,0"),
    ("gtmodel.calibration.identification.signals:read_motion_log", "t_s,q1_m,q2_m,q3_m,tau1_N,tau2_N,tau3_N", "0,0,0,0,0,0,0"),
    ("gtmodel.problems.kinds.joint_stiffness_calibration:read_deflection_csv", ",".join(
        ["theta1_deg", "theta2_deg", "theta3_deg", "theta4_deg", "theta5_deg", "theta6_deg", "fx_N", "fy_N", "fz_N",
         "mx_Nm", "my_Nm", "mz_Nm", "dx_m", "dy_m", "dz_m", "drx_rad", "dry_rad", "drz_rad"]), ",".join(["0"] * 18)),
    ("gtmodel.trajectory.point_to_point:_read_guess_csv", "t,x,y,z,xd,yd,zd,tau1,tau2,tau3", "0,0,0,0,0,0,0,0,0,0"),
], ids=["poses", "cart_survey", "motion_log", "deflections", "initial_guess"])
def test_a_million_rows_are_refused_within_a_second(tmp_path, reader, header, row):
    import importlib

    from gtmodel.errors import GtModelError

    module, name = reader.split(":")
    read = getattr(importlib.import_module(module), name)
    path = _rows(tmp_path / "big.csv", header, row, 10**6)
    t0 = time.process_time()
    with pytest.raises(GtModelError, match=r"big\.csv: .*(bytes, expected at most|more than)"):
        read(path)
    assert time.process_time() - t0 < 1.0


@pytest.mark.parametrize("reader", [
    "gtmodel.calibration.measurements:read_measurements",
    "gtmodel.problems.kinds.joint_stiffness_calibration:read_deflection_csv",
], ids=["poses", "deflections"])
def test_duplicated_rows_are_refused_naming_both_lines(tmp_path, reader):
    import importlib

    from gtmodel.errors import GtModelError

    module, name = reader.split(":")
    read = getattr(importlib.import_module(module), name)
    if name == "read_measurements":
        header, rows = "q1_m,q2_m,q3_m,Tx_m,Ty_m,Tz_m", ["0,0,0,1,2,3", "0,0,0.1,1,2,3", "0,0,0,1,2,3"]
    else:
        header = ",".join([f"theta{i}_deg" for i in range(1, 7)] + ["fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm",
                                                                     "dx_m", "dy_m", "dz_m", "drx_rad", "dry_rad", "drz_rad"])
        rows = [",".join(["1"] * 18), ",".join(["2"] * 18), ",".join(["1"] * 18)]
    path = tmp_path / "dup.csv"
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    with pytest.raises(GtModelError, match=r"dup\.csv: line 4: duplicated row, identical to line 2"):
        read(path)


def test_a_motion_log_message_shows_plain_numbers(tmp_path):
    from gtmodel.calibration.identification.signals import read_motion_log
    from gtmodel.errors import GtModelError

    path = tmp_path / "log.csv"
    path.write_text("t_s,q1_m,q2_m,q3_m,tau1_N,tau2_N,tau3_N\n" + "".join(f"{t},0,0,0,0,0,0\n" for t in (0.0, 0.004, 0.008, 0.008)))
    with pytest.raises(GtModelError) as info:
        read_motion_log(path)
    assert "np." not in str(info.value) and "(0.008 after 0.008)" in str(info.value)


def test_the_high_speed_residual_of_a_slow_log_is_null_without_a_warning():
    from gtmodel.problems.kinds.dynamic_identification import _rms_of_bins

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert _rms_of_bins([float("nan"), float("nan")]) is None
        assert _rms_of_bins([]) is None
        assert _rms_of_bins([3.0, float("nan"), 4.0]) == pytest.approx((12.5) ** 0.5)


# ----------------------------------------------------------------------------- studies


def test_an_interrupted_study_counts_a_case_that_ended_while_it_shut_down_as_solved_now(tmp_path, monkeypatch):
    """A worker finishes a case but its record never comes back (Ctrl-C): on a fresh folder
    nothing finished before, so the summary says 1 solved now, 0 finished before."""
    from gtmodel.problems.study import engine
    from gtmodel.problems.study.cases import run_unit

    from .problems.study.study_fixtures import SMALL_DESIGN, write_study

    def interrupted_after_one_case(units, on_record, **kw):
        run_unit(units[0][:1])  # its folder is written; no record reaches the engine
        raise KeyboardInterrupt

    monkeypatch.setattr(engine, "execute", interrupted_after_one_case)
    outcome = engine.run_study(write_study(tmp_path, SMALL_DESIGN), tmp_path / "out", workers=1)
    s = outcome.summary
    assert (s["status"], s["run_now"], s["skipped"], s["missing"]) == ("interrupted", 1, 0, 5)


# ----------------------------------------------------------------------------- cheap checks first


def test_the_f1_calibration_loads_in_well_under_a_second_and_reports_a_typo_in_fixed_at_once(tmp_path):
    """The 6-D workspace grid and the synthetic measurements (about 5 CPU-s) are made when
    the problem is solved; loading checks the names first."""
    from gtmodel.errors import ProblemError
    from gtmodel.problems import get_kind, load_problem

    shipped = REPO / "problems" / "f1_calibration.toml"
    get_kind("calibration")  # the kind's imports are not the load
    t0 = time.process_time()
    declaration = load_problem(shipped).declaration
    assert time.process_time() - t0 < 1.0
    typo = tmp_path / "typo.toml"
    typo.write_text(shipped.read_text().replace('"r3_y"', '"r3_yy"', 1))
    t0 = time.process_time()
    with pytest.raises(ProblemError, match=r"typo\.toml: field 'models\[0\]'.*r3_yy"):
        load_problem(typo)
    assert time.process_time() - t0 < 1.0
    assert declaration.source.startswith("synthetic (generated when solved)")
