"""Children of gtmodel (gtmodel._compiler.run_child): none outlives gtmodel.

Independent check: the kernel's process table (``/proc/<pid>/stat``) one second after
gtmodel ended, for the processes its child started (their PIDs written by the child
itself, not reported by gtmodel).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gtmodel import _compiler
from gtmodel._compiler import run_child
from gtmodel.errors import CodegenError

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc and the parent-death signal are Linux's")

# A child like a compiler driver: it starts children of its own (cc1, as) and waits.
_CHILD = "echo $$ >> {pids}; sleep 30 & echo $! >> {pids}; sleep 30 & echo $! >> {pids}; wait"
# gtmodel as the command runs it: the signal handler installed, the work interruptible.
_GTMODEL = """
import sys
from gtmodel import _signals
from gtmodel._compiler import run_compiler
handled = sys.argv[2] == "handled"
if handled:
    _signals.install()
try:
    with _signals.interruptible():
        run_compiler(["sh", "-c", sys.argv[1]], "a slow build")
except KeyboardInterrupt:
    sys.exit(_signals.process_exit_code(130))
"""


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return False
    return state not in ("Z", "X")  # a zombie has ended


def _pids(file: Path, n: int, deadline: float) -> list[int]:
    while time.monotonic() < deadline:
        if file.is_file() and len(lines := file.read_text().split()) >= n:
            return [int(x) for x in lines]
        time.sleep(0.05)
    raise AssertionError(f"the child did not start within the time: {file.read_text() if file.is_file() else 'no file'}")


# (signal sent to gtmodel's PID alone, whether gtmodel handles signals, expected exit code)
CASES = [
    ("SIGTERM", "handled", 143),  # the command: KeyboardInterrupt in run_child kills the group
    ("SIGINT", "handled", 130),
    ("SIGTERM", "default", -signal.SIGTERM),  # a library user's process killed outright: parent-death signal
    ("SIGKILL", "handled", -signal.SIGKILL),  # no clean-up at all in gtmodel: parent-death signal
]


@pytest.mark.parametrize(("sig", "mode", "code"), CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_no_child_is_alive_one_second_after_gtmodel_ends_on_a_signal_to_its_pid(tmp_path, sig, mode, code):
    pids = tmp_path / "pids"
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])}
    proc = subprocess.Popen([sys.executable, "-c", _GTMODEL, _CHILD.format(pids=pids), mode], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        children = _pids(pids, 3, time.monotonic() + 60)
        os.kill(proc.pid, getattr(signal, sig))
        rc = proc.wait(timeout=10)
        time.sleep(1.0)
        alive = [p for p in children if _alive(p)]
    finally:
        proc.kill()
        proc.communicate()
    assert (rc, alive) == (code, []), proc.stderr


def test_a_finished_child_leaves_no_straggler(tmp_path):
    pids = tmp_path / "pids"
    run = run_child(["sh", "-c", f"sleep 30 & echo $! > {pids}; echo done"], timeout=20)
    time.sleep(0.2)
    assert (run.returncode, run.stdout, _alive(int(pids.read_text()))) == (0, "done\n", False)


def test_a_child_past_its_time_is_killed_with_its_children(tmp_path):
    pids = tmp_path / "pids"
    t0 = time.monotonic()
    with pytest.raises(subprocess.TimeoutExpired):
        run_child(["sh", "-c", _CHILD.format(pids=pids)], timeout=1.0)
    children = _pids(pids, 3, time.monotonic() + 5)
    time.sleep(0.2)
    assert ([p for p in children if _alive(p)], time.monotonic() - t0 < 10) == ([], True)


@pytest.mark.parametrize(("cmd", "expected"), [
    (["sh", "-c", "echo out; echo err >&2; exit 3"], (3, "out\n", "err\n")),
    (["sh", "-c", "kill -TERM $$"], (128 + signal.SIGTERM, "", "")),
])
def test_exit_code_and_output_are_the_childs(cmd, expected):
    run = run_child(cmd, timeout=20)
    assert (run.returncode, run.stdout, run.stderr) == expected


def test_a_missing_program_is_file_not_found():
    with pytest.raises(FileNotFoundError, match="no executable 'gtmodel-no-such-program'"):
        run_child(["gtmodel-no-such-program"])


def test_a_compiler_timeout_names_the_size_of_the_c_and_how_to_shrink_it(tmp_path, monkeypatch):
    # the held-out compliant screw's radau2 MPC step: 33.5-150 MB of C that gcc did not finish in 300 s (issue 49)
    source = tmp_path / "step.c"
    source.write_text("x" * 2_500_000)

    def timeout(cmd, timeout):
        raise subprocess.TimeoutExpired(cmd, timeout)

    monkeypatch.setattr(_compiler, "run_child", timeout)
    with pytest.raises(CodegenError, match=r"step: the compiler did not finish within 300 s on 2.5 MB of C; .*fewer substeps .*an explicit method for an implicit one"):
        _compiler.run_compiler(["gcc", "-c", str(source)], "step")
    with pytest.raises(CodegenError, match=r"step: the compiler did not finish within 300 s$"):
        _compiler.run_compiler(["gcc", "-c", str(tmp_path / "absent.c")], "step")
