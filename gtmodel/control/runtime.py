"""Running the robot runtime: the compiled RSI/EGM loop started, waited for, and its log and counts read.

The executable is built by :func:`gtmodel.codegen.robot_runtime.build_runtime` (this module
never imports codegen: it only starts a program). :func:`run_loop` starts it in a process group
of its own, waits until it ends (the robot stops sending for ``idle_timeout`` s, ``max_cycles``
cycles, a signal, or ``time_limit``: then SIGTERM, so that the log is flushed, and SIGKILL if it
does not end), and reads what it wrote into ``out_dir``:

- ``cycle_log.csv``: one row per datagram from the robot (:func:`read_cycle_log`), columns
  ``cycle, ipoc_or_seq, t, flags, status, latency_us, sensor_age, t_monotonic`` (the runtime's
  ``CLOCK_MONOTONIC`` at the datagram's arrival [s]: :func:`time.monotonic`'s clock on Linux), then ``x:<field>`` (the
  step's inputs), ``u:<field>`` (the step's outputs), ``reply:<field>`` (the limited value sent:
  the total correction, or the absolute position) and, for relative RSI corrections,
  ``sent:<field>`` (the increment in the datagram); numbers ``%.17g``, ``nan`` where a value does
  not exist (no step called, no reply sent). ``flags`` is a sum of
  :data:`~gtmodel.codegen.robot_runtime.RUNTIME_FLAGS` (repeated here as :data:`FLAGS`);
- ``runtime_stats.json``: the counts (:data:`STATS_KEYS`);
- ``ready.json``: the ports the runtime listens on (written once bound, :func:`read_ready`).

:class:`LoopRun` carries a :class:`~gtmodel.status.Status` (a setup failure or a crash is a
status, never None), the summary (cycles, late and missing replies, reply latency percentiles,
faults seen and what was done, real-time scheduling granted or why not) and the log's path.
"""

from __future__ import annotations

import atexit
import json
import logging
import math
import os
import signal
import subprocess
import threading
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError
from gtmodel.status import Status, StatusResult

__all__ = ["FLAGS", "STATS_KEYS", "LOG_NAME", "STATS_NAME", "READY_NAME", "LoopRun", "run_loop", "read_cycle_log", "read_ready",
           "summarize"]

log = logging.getLogger("gtmodel")

#: Bits of the cycle log's ``flags`` column (the C runtime's ``F_*``).
FLAGS = {"sent": 1, "step": 2, "held": 4, "fallback_stale": 8, "fallback_step": 16, "ramp": 32, "malformed": 64, "non_finite": 128,
         "duplicate_or_old": 256, "missing_field": 512, "deadline_held": 1024, "late_dropped": 2048, "clamped": 4096,
         "no_safe_reply": 8192, "too_long": 16384, "out_of_window": 32768, "resync": 65536, "unapplied": 131072, "sent_late": 262144}
#: The keys of ``runtime_stats.json``.
STATS_KEYS = ("format", "interface", "end", "signal", "packets", "cycles", "replies", "malformed", "too_long", "non_finite",
              "duplicate_or_old", "missing_field", "held_replies", "fallback_cycles", "fallback", "deadline_held", "late_dropped",
              "no_safe_reply", "send_errors", "compose_errors", "limit_clamps", "sensor", "step_calls", "step_status", "log",
              "realtime", "source", "strangers", "sequence", "relative", "sent_late", "start_outside_limits", "silences", "alarms",
              "events_dropped", "events", "receive_queue", "first_ipoc_or_seq", "last_ipoc_or_seq", "max_latency_us", "period_s", "reply_deadline_s",
              "stale_cycles")
LOG_NAME, STATS_NAME, READY_NAME = "cycle_log.csv", "runtime_stats.json", "ready.json"
#: What the runtime does with each fault (the summary's ``faults``).
_ACTIONS = {
    "malformed": "no reply (nothing to echo); counted",
    "too_long": "no reply; counted as malformed too",
    "non_finite": "held reply (the last one again); the step is not called",
    "duplicate_or_old": "held reply; the step is not called",
    "missing_field": "held reply; the step is not called",
    "stale_sensor": "fallback ({rule}); the step is not called",
    "step_failed": "fallback ({rule}) instead of the step's output",
    "deadline_held": "held reply instead of the late computed one (still within the period)",
    "late_dropped": "no reply (the period had passed; the robot counts the cycle late)",
    "no_safe_reply": "no reply (no start position yet, or the robot's start more than one rate step outside [limits])",
    "out_of_window": "held reply; the step is not called (the sequence resynchronises after consecutive consistent packets)",
    "strangers": "never parsed, answered or logged; counted by address (summary: strangers)",
    "before_lock": "no reply: not a valid packet, and no robot locked yet",
    "unapplied": "the robot reported the reply late (RSI Delay): its increment taken back from the total",
    "sent_late": "sent, but sendto returned after the period (the process stalled inside it)",
    "kernel_dropped": "dropped by the kernel before the runtime read them (the receive queue was full): a robot packet "
                      "among them gets no reply and the robot counts that cycle late (summary: receive_queue)",
}
_OWN_FILES = {LOG_NAME, STATS_NAME, READY_NAME, READY_NAME + ".tmp", STATS_NAME + ".tmp", "summary.json"}


@dataclass(kw_only=True)
class LoopRun(StatusResult):
    """The result of one run of the robot runtime.

    Parameters
    ----------
    status : Status
        ``completed`` (the robot stopped sending, or ``max_cycles``), ``interrupted`` (a
        SIGINT/SIGTERM ended it: log and counts complete), ``max_iterations`` (``time_limit``),
        ``invalid_input`` (the runtime refused its arguments), ``error`` (a setup failure such
        as a port in use, or a crash).
    message : str, optional
        What happened, in words (the runtime's stderr line on a failure).
    summary : dict, optional
        :func:`summarize` of the counts and the log (empty when the runtime wrote none).
    log_path : pathlib.Path or None, optional
        The cycle log (None when not written).
    stats : dict, optional
        ``runtime_stats.json`` as read.
    exit_code : int, optional
        The runtime's exit code (negative: the signal that killed it).
    """

    summary: dict = field(default_factory=dict)
    log_path: Path | None = None
    stats: dict = field(default_factory=dict)
    exit_code: int = 0


def read_ready(out_dir: str | Path, timeout: float = 10.0) -> dict:
    """Wait for the runtime's ``ready.json`` (written once its sockets are bound) and read it.

    Parameters
    ----------
    out_dir : str or pathlib.Path
        The run's folder.
    timeout : float, optional
        Seconds to wait.

    Returns
    -------
    dict
        ``{"listen_port": int, "sensor_port": int (-1: none), "pid": int}``.

    Raises
    ------
    TimeoutError
        Not written within ``timeout``.
    """
    path = Path(out_dir) / READY_NAME
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            return json.loads(path.read_text())
        except (OSError, ValueError):
            time.sleep(0.005)
    raise TimeoutError(f"the runtime wrote no {path} within {timeout:g} s")


def read_cycle_log(path: str | Path) -> dict[str, np.ndarray]:
    """The cycle log as arrays by column name.

    Parameters
    ----------
    path : str or pathlib.Path
        ``cycle_log.csv`` of a run.

    Returns
    -------
    dict of str to numpy.ndarray
        ``(N,)`` per column (``cycle``, ``flags``, ``status``, ``sensor_age`` as int64,
        ``ipoc_or_seq`` as uint64, exactly; the others float64, NaN where no value exists).

    Raises
    ------
    InputError
        The file is missing, has no header, or a row of the wrong length or a non-number.
    """
    p = Path(path)
    try:
        with p.open() as f:  # read by NumPy's C reader: an hour's log (900,000 rows) without a Python object per number
            header = f.readline().strip()
            if not header:
                raise InputError(f"{p}: empty cycle log (no header)")
            names = header.split(",")
            try:
                with warnings.catch_warnings():  # a log of no rows: no warning, an empty table
                    warnings.simplefilter("ignore", UserWarning)
                    data = np.loadtxt(f, delimiter=",", dtype=float, ndmin=2)
            except ValueError as exc:
                raise InputError(f"{p}: a row that is not numbers or of the wrong length ({exc})") from None
    except OSError as exc:
        raise InputError(f"{p}: cannot read the cycle log: {exc.strerror or exc}") from None
    if data.size == 0:
        data = np.zeros((0, len(names)))
    seq = None
    if "ipoc_or_seq" in names and data.shape[0]:  # 64-bit counts (a forged IPOC 2^64-1 included) read exactly, not through float
        with p.open() as f:
            f.readline()
            seq = np.loadtxt(f, delimiter=",", dtype=np.uint64, usecols=names.index("ipoc_or_seq"), ndmin=1)
    if data.shape[1] != len(names):
        raise InputError(f"{p}: expected {len(names)} values per row, got {data.shape[1]}")
    ints = {"cycle", "flags", "status", "sensor_age"}
    out = {n: (data[:, i].astype(np.int64) if n in ints or n == "ipoc_or_seq" and seq is None else data[:, i]) for i, n in enumerate(names)}
    if seq is not None:
        out["ipoc_or_seq"] = seq
    return out


def summarize(stats: dict, columns: dict[str, np.ndarray] | None) -> dict:
    """The run's summary from the runtime's counts and its cycle log.

    Parameters
    ----------
    stats : dict
        ``runtime_stats.json``.
    columns : dict of str to numpy.ndarray or None
        :func:`read_cycle_log` (None: no log).

    Returns
    -------
    dict
        ``cycles``, ``packets``, ``replies``, ``missing_replies`` (cycles with an IPOC/seqno but
        no reply), ``late_replies`` (sent later than the period), ``deadline_held``,
        ``reply_latency_ms`` (``p50``, ``p90``, ``p99``, ``max`` over the replies sent),
        ``faults`` (per fault ``count`` and ``action``), ``fallback``, ``limit_clamps``,
        ``sensor``, ``step_status``, ``log`` (rows, dropped, capped, bytes, max_bytes), ``realtime``
        (granted, reason), ``end``; the network guard's ``source`` (the robot and tracker of the
        session and how each was fixed), ``strangers`` (datagrams and addresses), ``sequence``
        (out of the window, resynchronisations), ``start_outside_limits``, ``silences`` (count,
        longest, events), ``alarms`` (holds of more than ``hold_alarm_cycles``, resynchronisations,
        events), ``events`` (all, at most 256; more in ``events_dropped``) and ``receive_queue`` (the
        datagrams the kernel dropped on each socket for a full queue, and each queue's granted size).
    """
    period = float(stats.get("period_s", LOOP_PERIOD_S))
    latency = np.zeros(0)
    rows = 0
    if columns is not None and "flags" in columns:
        sent = (columns["flags"] & FLAGS["sent"]) != 0
        latency = columns["latency_us"][sent] / 1000.0
        rows = int(columns["flags"].size)
    pct = {f"p{q}": (float(np.percentile(latency, q)) if latency.size else math.nan) for q in (50, 90, 99)}
    pct["max"] = float(latency.max()) if latency.size else math.nan
    rule = stats.get("fallback", "hold")
    fallback = stats.get("fallback_cycles", {})
    counts = {k: stats.get(k, 0) for k in ("malformed", "too_long", "non_finite", "duplicate_or_old", "missing_field",
                                            "deadline_held", "late_dropped", "no_safe_reply", "sent_late")}
    counts["stale_sensor"] = fallback.get("stale_sensor", 0)
    counts["step_failed"] = fallback.get("step_failed", 0)
    counts["out_of_window"] = stats.get("sequence", {}).get("out_of_window", 0)
    counts["strangers"] = stats.get("strangers", {}).get("datagrams", 0)
    counts["before_lock"] = stats.get("source", {}).get("before_lock", 0)
    counts["unapplied"] = stats.get("relative", {}).get("unapplied", 0)
    counts["kernel_dropped"] = stats.get("receive_queue", {}).get("kernel_dropped", 0)
    events = list(stats.get("events", []))
    faults = {k: {"count": int(v), "action": _ACTIONS[k].format(rule=rule)} for k, v in counts.items()}
    cycles = int(stats.get("cycles", 0))
    return {
        "interface": stats.get("interface"),
        "end": stats.get("end"),
        "signal": stats.get("signal"),
        "packets": int(stats.get("packets", 0)),
        "cycles": cycles,
        "replies": int(stats.get("replies", 0)),
        "missing_replies": cycles - int(stats.get("replies", 0)),
        "late_replies": int(np.count_nonzero(latency > 1000.0 * period)),
        "deadline_held": int(stats.get("deadline_held", 0)),
        "reply_latency_ms": pct,
        "faults": faults,
        "fallback": {"rule": rule, **{k: int(v) for k, v in fallback.items()}},
        "limit_clamps": stats.get("limit_clamps", {}),
        "sensor": stats.get("sensor", {}),
        "step_status": stats.get("step_status", {}),
        "log": {"rows": rows, **stats.get("log", {})},
        "realtime": {"granted": bool(stats.get("realtime", {}).get("granted", False)),
                     "reason": stats.get("realtime", {}).get("reason", "")},
        "source": stats.get("source", {}),
        "strangers": stats.get("strangers", {"datagrams": 0, "addresses": []}),
        "sequence": stats.get("sequence", {}),
        "start_outside_limits": int(stats.get("start_outside_limits", 0)),
        "silences": {**stats.get("silences", {"count": 0}), "events": [e for e in events if e.get("kind") == "silence"]},
        "alarms": {**stats.get("alarms", {"holds": 0}), "events": [e for e in events if e.get("kind") in ("hold", "resync", "sensor_resync")]},
        "events": events,
        "events_dropped": int(stats.get("events_dropped", 0)),
        "receive_queue": stats.get("receive_queue", {}),
    }


#: Process groups of the runtimes running now: killed at this process's exit (the runtime also
#: ends by itself when this process dies: ``--exit-with-parent``).
_RUNNING: set[int] = set()
_RUNNING_LOCK = threading.Lock()


@atexit.register
def _kill_running() -> None:
    with _RUNNING_LOCK:
        groups = list(_RUNNING)
    for pgid in groups:
        try:
            os.killpg(pgid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass


def _check_out_dir(out: Path) -> None:
    if out.exists() and not out.is_dir():
        raise InputError(f"out_dir: {out} is a file, expected a folder")
    if out.is_dir():
        foreign = sorted(p.name for p in out.iterdir() if p.name not in _OWN_FILES)
        if foreign:
            raise InputError(f"out_dir: {out} holds files that are not a runtime run's ({', '.join(foreign[:5])}); "
                             "expected a new, empty or earlier run's folder")
    out.mkdir(parents=True, exist_ok=True)
    for name in (READY_NAME, STATS_NAME, LOG_NAME):
        (out / name).unlink(missing_ok=True)


#: The runtime's stderr lines said to the user as they come (``gtmodel loop``: through the ``gtmodel`` logger).
_SAID = ("gt_runtime: alarm", "gt_runtime: warning")


def _pump_stderr(stream: Any, lines: list[str]) -> None:
    """Read the runtime's stderr as it comes: alarms and warnings logged at once, every line kept."""
    for line in stream:
        line = line.rstrip("\n")
        lines.append(line)
        if line.startswith(_SAID):
            log.warning("%s", line)


def _stop(proc: subprocess.Popen, grace: float = 3.0) -> None:
    """SIGTERM (the runtime flushes its log), then SIGKILL to the whole group."""
    if proc.poll() is None:
        try:
            proc.send_signal(signal.SIGTERM)
            proc.wait(grace)
        except subprocess.TimeoutExpired:
            pass
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
    proc.wait()


class _Serving:
    """The cycle log's rows so far, counted from the bytes added since the last look (the writer flushes when idle)."""

    def __init__(self, path: Path) -> None:
        self.path, self.offset, self.lines, self.start = path, 0, 0, time.monotonic()

    def rows(self) -> int:
        try:
            with open(self.path, "rb") as f:
                f.seek(self.offset)
                chunk = f.read()
        except OSError:
            return 0
        self.offset += len(chunk)
        self.lines += chunk.count(b"\n")
        return max(self.lines - 1, 0)  # the header row

    def say(self) -> None:
        rows, seconds = self.rows(), time.monotonic() - self.start
        if rows:
            log.info("loop: serving, %d cycles (%.0f s)", rows, seconds)
        else:
            log.info("loop: serving, waiting for the robot's first datagram (%.0f s)", seconds)


def _wait(proc: subprocess.Popen, time_limit: float | None, serving: _Serving, progress: float | None) -> None:
    """``proc.wait(time_limit)``, saying every ``progress`` s how the serving goes."""
    if progress is None:
        proc.wait(timeout=time_limit)
        return
    deadline = None if time_limit is None else time.monotonic() + time_limit
    while True:
        left = None if deadline is None else deadline - time.monotonic()
        try:
            proc.wait(timeout=progress if left is None else max(min(progress, left), 0.0))
            return
        except subprocess.TimeoutExpired:
            if deadline is not None and time.monotonic() >= deadline:
                raise
            serving.say()


def run_loop(executable: str | Path, out_dir: str | Path, *, listen: tuple[str, int] | None = None, sensor_port: int | None = None,
             idle_timeout: float = 2.0, max_cycles: int | None = None, time_limit: float | None = None,
             reply_deadline: float | None = None, realtime: bool = True, end_on_signal: bool = False, robot: str | None = None,
             tracker: str | None = None, log_max_mb: float | None = None, progress: float | None = 5.0) -> LoopRun:
    """Run the robot runtime until it ends, and read its counts and log.

    Parameters
    ----------
    executable : str or pathlib.Path
        From :func:`gtmodel.codegen.robot_runtime.build_runtime`.
    out_dir : str or pathlib.Path
        Folder of the log and counts: new, empty, or an earlier run's (whose files are replaced).
    listen : tuple of (str, int), optional
        IPv4 address and UDP port to listen on (port 0: any free one, see :func:`read_ready`);
        None: ``0.0.0.0`` and the interface's usual port (RSI 49152, EGM 6510).
    sensor_port : int, optional
        UDP port of the ``GTS1`` sensor stream (when the step reads ``sensor.*``); None: the
        listen port + 1 (0 when listening on port 0).
    idle_timeout : float, optional
        Seconds without a datagram from the robot, after the first one, that end the run.
    max_cycles : int, optional
        End after this many cycles (None: no limit).
    time_limit : float, optional
        Seconds after which the run is stopped (SIGTERM, status ``max_iterations``); None: none.
    reply_deadline : float, optional
        Override of the generated reply deadline [s].
    realtime : bool, optional
        Ask for SCHED_FIFO and mlockall (the runtime says in its counts whether granted).
    end_on_signal : bool, optional
        A SIGINT/SIGTERM of this process (a :class:`KeyboardInterrupt`) ends the run as a
        signal to the runtime does: the runtime is stopped, its log flushed, and the run
        returned with status ``interrupted`` (``gtmodel loop``: Ctrl-C ends the loop and the
        result folder is written). Default False: the interrupt is raised after the stop.
    robot : str, optional
        The robot's IPv4 address, optionally ``ADDR:PORT``: only its datagrams are answered
        (None: the first valid packet's source is locked for the session).
    tracker : str, optional
        The sensor stream's source, the same way (None: the first valid sample's source).
    log_max_mb : float, optional
        The cycle log's cap [MB] (rows past it are counted in ``log.capped``, not written);
        None: the runtime's default, 1024 MB.
    progress : float, optional
        Seconds between the progress lines logged (INFO) while the runtime serves:
        ``loop: serving, N cycles (T s)``, the cycle log's rows so far, or ``loop: serving,
        waiting for the robot's first datagram (T s)``; None: no lines. Default 5.

    Returns
    -------
    LoopRun
        Status, summary, counts and the log's path.

    Raises
    ------
    InputError
        ``executable`` is not an executable file, ``out_dir`` holds foreign files, ``robot`` or
        ``tracker`` is not a string, ``log_max_mb`` not a positive number.
    KeyboardInterrupt
        A SIGINT/SIGTERM of this process without ``end_on_signal`` (the runtime is stopped
        first, its log flushed).
    """
    exe = Path(executable)
    if not (exe.is_file() and os.access(exe, os.X_OK)):
        raise InputError(f"executable: {exe} is not an executable file (build it with gtmodel.codegen.robot_runtime.build_runtime)")
    out = Path(out_dir)
    _check_out_dir(out)
    cmd = [str(exe.resolve()), "--out", str(out.resolve()), "--idle-timeout", repr(float(idle_timeout)), "--exit-with-parent"]
    if listen is not None:
        cmd += ["--listen", f"{listen[0]}:{int(listen[1])}"]
    if sensor_port is not None:
        cmd += ["--sensor-port", str(int(sensor_port))]
    if max_cycles is not None:
        cmd += ["--max-cycles", str(int(max_cycles))]
    if reply_deadline is not None:
        cmd += ["--reply-deadline", repr(float(reply_deadline))]
    if not realtime:
        cmd += ["--no-realtime"]
    for option, value in (("--robot", robot), ("--tracker", tracker)):
        if value is not None:
            if not isinstance(value, str):
                raise InputError(f"{option[2:]}: expected an IPv4 address, optionally ADDR:PORT, got {value!r}")
            cmd += [option, value]
    if log_max_mb is not None:
        if isinstance(log_max_mb, bool) or not isinstance(log_max_mb, (int, float)) or not 0 < log_max_mb <= 1e6:
            raise InputError(f"log_max_mb: expected a number in (0, 1e6] MB, got {log_max_mb!r}")
        cmd += ["--log-max-mb", repr(float(log_max_mb))]
    log.info("runtime: %s", " ".join(cmd))
    timed_out = signalled = False
    proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            errors="replace", start_new_session=True)
    with _RUNNING_LOCK:
        _RUNNING.add(proc.pid)
    lines: list[str] = []
    pump = threading.Thread(target=_pump_stderr, args=(proc.stderr, lines), daemon=True)
    pump.start()
    try:
        try:
            _wait(proc, time_limit, _Serving(out / LOG_NAME), progress)
        except subprocess.TimeoutExpired:
            timed_out = True
            _stop(proc)
    except KeyboardInterrupt as exc:
        _stop(proc)
        if not end_on_signal:
            raise
        signalled = str(exc) or "a signal"
    except BaseException:
        _stop(proc)
        raise
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)  # stragglers of the group
        except (ProcessLookupError, PermissionError):
            pass
        with _RUNNING_LOCK:
            _RUNNING.discard(proc.pid)
    proc.wait()
    pump.join(10.0)
    proc.stderr.close()
    code = proc.returncode
    said = [ln for ln in lines if ln.startswith(_SAID)]
    err = "\n".join(ln for ln in lines if not ln.startswith(_SAID)).strip()
    stats: dict[str, Any] = {}
    try:
        stats = json.loads((out / STATS_NAME).read_text())
    except (OSError, ValueError):
        pass
    log_path = out / LOG_NAME if (out / LOG_NAME).is_file() else None
    columns = None
    if log_path is not None:
        try:
            columns = read_cycle_log(log_path)
        except InputError as exc:
            log.warning("runtime: %s", exc)
    summary = summarize(stats, columns) if stats else {}
    if summary:
        summary["warnings"] = [ln for ln in said if ln.startswith(_SAID[1])]
    if timed_out:
        status, message = Status.MAX_ITERATIONS, f"stopped at the time limit of {time_limit:g} s"
    elif code == 2:
        status, message = Status.INVALID_INPUT, err or "the runtime refused its arguments"
    elif code < 0:
        status, message = Status.ERROR, f"the runtime was killed by signal {-code} ({signal.Signals(-code).name if -code in signal.valid_signals() else '?'})"
    elif code != 0 or not stats:
        status, message = Status.ERROR, err or f"the runtime ended with exit code {code} and wrote no counts"
    elif stats.get("end") == "signal":
        by = f"{signalled} to this process (the runtime stopped with SIGTERM)" if signalled else stats.get("signal")
        status, message = Status.INTERRUPTED, f"stopped by {by}; log and counts complete"
    else:
        status, message = Status.COMPLETED, f"ended by {stats.get('end')} after {stats.get('cycles', 0)} cycles"
    return LoopRun(status=status, message=message, summary=summary, log_path=log_path, stats=stats, exit_code=code)
