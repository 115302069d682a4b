"""One simulated robot run: the robot's 4 ms clock, its packets, the replies, the faults and the record.

:func:`simulate` plays the ROBOT of an interface (``"rsi"`` or ``"egm"``) with a plant of
:mod:`gtmodel.robot_sim.plants`, sending to the sensor side's address (the runtime, or any
client) from one thread with absolute deadlines on :func:`time.monotonic` (never a sleep of
a period: no drift). Each period ``dt`` (4 ms) is split into ticks of the sensor stream
(1 ms): every tick sends one ``GTS1`` sample of the plant's sensor (the contract's format,
``GTS1 <seq> <t_s> <x> <y> <z>``, positions in m in the robot base frame, then the IMU's
``ax ay az`` [m/s^2] and ``wx wy wz`` [rad/s] when the plant has one) to ``sensor_target``; every ``dt`` the robot closes the last cycle (late or not), steps the
plant with the reply, and sends its packet. Between ticks it waits in :func:`select.select`
for replies.

The rules the robot applies (RSI's, used for both interfaces):

- a reply is on time when it arrives before the robot's next packet and (RSI) echoes the
  IPOC of the cycle it answers; a reply with another IPOC is ``mismatched`` (an older one:
  ``stale``); a malformed reply is counted by reason and never reaches the plant; EGM
  takes any valid reply before the next packet (EGM does not require the echo; the
  summary counts ``echoed_seqno``);
- a cycle without an on-time reply is late: the plant holds its correction (relative
  mode: no increment; absolute: the last offset); more than ``late_limit`` consecutive
  late cycles stop the robot (``stopped_by_late``; status ``check_failed``);
- if the process falls behind its clock by more than a period (a loaded machine), the
  clock is re-anchored (``clock_slips``); a packet sent more than 1 ms after its deadline
  counts in ``clock_overruns``.

What happened is in :class:`SimResult` and, with ``out_dir``, in ``sim_record.csv`` (one
row per cycle: :data:`RECORD_COLUMNS` then the plant's columns, then ``measured_x|y|z_mm``
and ``error_mm``) and ``sim_summary.json`` (:data:`SUMMARY_KEYS` and more).
"""

from __future__ import annotations

import csv
import heapq
import json
import logging
import math
import os
import select
import socket
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError
from gtmodel.robot_sim import egm, rsi
from gtmodel.robot_sim.faults import FAULT_KINDS, FaultSchedule
from gtmodel.robot_sim.plants import SimPlant, make_plant
from gtmodel.robot_sim.state import CORRECTION_MODES, ReplyError
from gtmodel.status import Status, StatusResult

__all__ = ["INTERFACES", "DEFAULT_LATE_LIMIT", "SENSOR_PERIOD_S", "WRITTEN_BY", "RECORD_FILE", "SUMMARY_FILE", "RECORD_COLUMNS",
           "SUMMARY_KEYS", "SimResult", "check_sim_out_dir", "simulate"]

_log = logging.getLogger("gtmodel")

#: The interfaces.
INTERFACES = ("rsi", "egm")
#: Default limit of consecutive late replies before the robot stops (RSI's usual setting).
DEFAULT_LATE_LIMIT = 100
#: Period of the sensor stream [s] (the tracker's 1000 Hz, Cvitanic (2021), Table 7).
SENSOR_PERIOD_S = 0.001
#: The marker of a simulator's summary (a folder holding it may be replaced by a new run).
WRITTEN_BY = "gtmodel robot-sim"
#: File names of a run's output.
RECORD_FILE = "sim_record.csv"
SUMMARY_FILE = "sim_summary.json"
#: First columns of the record (then the plant's, ``measured_x|y|z_mm``, ``error_mm``).
RECORD_COLUMNS = ("cycle", "t_s", "seq", "sent", "late", "faults")
#: Keys every summary has.
SUMMARY_KEYS = ("written_by", "status", "message", "interface", "plant", "cycles_sent", "packets_sent", "replies", "late",
                "consecutive_late_max", "late_limit", "stopped_by_late", "stopped_at_cycle", "malformed_replies", "rejected_replies",
                "stale_replies", "mismatched_replies", "duplicate_replies", "dropped_replies", "echoed_seqno", "faults_injected",
                "error_name", "error_rms_mm", "error_max_mm", "reply_latency_ms", "sensor_samples_sent", "clock_overruns", "clock_slips")
#: Largest datagram read [bytes] (larger ones are truncated by the kernel and fail to parse).
_RECV_BYTES = 65536
#: First IPOC [ms] (any value; RSI's counter is the controller's time).
_IPOC0 = 1_000_000


@dataclass(kw_only=True)
class SimResult(StatusResult):
    """What a simulated run did.

    Parameters
    ----------
    status : Status
        ``completed``; ``check_failed`` when the robot stopped on late replies; ``error``
        (a socket error, the message says which); ``interrupted``.
    message : str
        One line.
    summary : dict
        The summary (``sim_summary.json``).
    columns : tuple of str
        Columns of ``record``.
    record : list of list
        One row per cycle.
    out_dir : pathlib.Path or None
        Where the files were written.
    """

    summary: dict = field(default_factory=dict)
    columns: tuple[str, ...] = ()
    record: list = field(default_factory=list)
    out_dir: Path | None = None

    def column(self, name: str) -> np.ndarray:
        """One numeric column of the record.

        Parameters
        ----------
        name : str
            A column name.

        Returns
        -------
        numpy.ndarray, shape (n_cycles,)

        Raises
        ------
        InputError
            An unknown or non-numeric column.
        """
        if name not in self.columns or name == "faults":
            raise InputError(f"column {name!r}: expected one of {', '.join(c for c in self.columns if c != 'faults')}")
        i = self.columns.index(name)
        return np.array([row[i] for row in self.record], dtype=float)


def check_sim_out_dir(out: str | Path) -> None:
    """A run writes only into a folder that is new, empty or its own previous output.

    The rule of every gtmodel run (DESIGN.md: "a user's files are never destroyed"; the
    same rule as :func:`gtmodel.codegen.out_dir.check_out_dir` for code generation): the
    folder may hold only ``sim_record.csv`` and a ``sim_summary.json`` that says it was
    written by ``gtmodel robot-sim``.

    Parameters
    ----------
    out : str or pathlib.Path
        The folder.

    Raises
    ------
    InputError
        ``out`` (or a parent) is a file or a symbolic link, or it holds other files.
    """
    out = Path(out)
    if out.is_symlink() or (out.exists() and not out.is_dir()):
        raise InputError(f"--out {out}: a file or symbolic link of that name is in the way; give a new or empty folder")
    for parent in out.absolute().parents:
        if parent.exists():
            if not parent.is_dir():
                raise InputError(f"--out {out}: its parent {parent} is a file")
            break
    if not out.is_dir():
        return
    names = {p.name for p in out.iterdir()}
    if not names:
        return
    ours = False
    try:
        ours = json.loads((out / SUMMARY_FILE).read_text(encoding="utf-8")).get("written_by") == WRITTEN_BY
    except (OSError, ValueError, AttributeError):
        pass
    foreign = sorted(names - {RECORD_FILE, SUMMARY_FILE})
    if foreign or not ours:
        raise InputError(f"--out {out}: it holds files a robot-sim run did not write ({', '.join((foreign or sorted(names))[:3])}); "
                         "give a new or empty folder")


def _address(value: Any, name: str) -> tuple[str, int]:
    if not (isinstance(value, (tuple, list)) and len(value) == 2 and isinstance(value[0], str) and isinstance(value[1], int)
            and not isinstance(value[1], bool) and 0 < value[1] < 65536):
        raise InputError(f"{name}: expected (host, port) with a port in 1..65535, got {value!r}")
    return value[0], value[1]


@dataclass
class _Cycle:
    k: int
    seq: int
    sent_at: float | None
    row: list
    faults: dict
    command: Any = None
    latency: float | None = None


class _Run:
    """The state of one run (counters, sockets, the open cycle)."""

    def __init__(self, interface: str, plant: SimPlant, target: tuple[str, int], sensor_target: tuple[str, int], n_cycles: int,
                 schedule: FaultSchedule, seed: int, correction: str, period: float, late_limit: int, sen_type: str) -> None:
        self.interface, self.plant, self.target, self.sensor_target = interface, plant, target, sensor_target
        self.n_cycles, self.schedule, self.correction, self.period, self.late_limit, self.sen_type = n_cycles, schedule, correction, period, late_limit, sen_type
        self.rng = np.random.default_rng([int(seed), 1])
        self.garbage_rng = np.random.default_rng([int(seed), 2])
        self.c = {k: 0 for k in ("cycles_sent", "packets_sent", "replies", "late", "consecutive_late_max", "stale_replies", "mismatched_replies",
                                 "duplicate_replies", "dropped_replies", "echoed_seqno", "datagrams_received", "sensor_samples_sent",
                                 "clock_overruns", "clock_slips")}
        self.rejected: dict[str, int] = {}
        self.faults = {k: 0 for k in FAULT_KINDS}
        self.consecutive = 0
        self.stopped_by_late = False
        self.stopped_at: int | None = None
        self.rows: list = []
        self.errors: list[float] = []
        self.latencies: list[float] = []
        self.jump = 0
        self.cycle: _Cycle | None = None
        self.recent: set[int] = set()
        self.pending: list = []
        self.measured = np.full(3, np.nan)
        self.sensor_seq = 0
        self.sock = self.sensor = None

    # -- sockets -------------------------------------------------------------------
    def open(self, bind_host: str) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.setblocking(False)
        self.sock.bind((bind_host, 0))
        self.sensor = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sensor.setblocking(False)
        self.sensor.bind((bind_host, 0))

    def close(self) -> None:
        for s in (self.sock, self.sensor):
            if s is not None:
                s.close()

    def _send(self, sock: socket.socket, data: bytes, addr: tuple[str, int]) -> bool:
        try:
            sock.sendto(data, addr)
            return True
        except BlockingIOError:
            return False
        except ConnectionRefusedError:  # an ICMP "port unreachable" of an earlier datagram (nobody listens yet)
            return False

    # -- replies -------------------------------------------------------------------
    def drain(self) -> None:
        while True:
            try:
                data, _ = self.sock.recvfrom(_RECV_BYTES)
            except (BlockingIOError, InterruptedError):
                return
            except ConnectionRefusedError:
                continue
            self.c["datagrams_received"] += 1
            self._reply(data, time.monotonic())

    def _reply(self, data: bytes, now: float) -> None:
        cyc = self.cycle
        if cyc is None:
            self.c["mismatched_replies"] += 1
            return
        if "drop" in cyc.faults:
            self.c["dropped_replies"] += 1
            return
        try:
            if self.interface == "rsi":
                reply = rsi.parse_sen(data, self.sen_type)
                seq, command = reply.ipoc, reply.command(self.correction)
            else:
                reply = egm.parse_egm_sensor(data)
                seq, command = reply.seqno, reply.command
        except ReplyError as exc:
            self.rejected[exc.reason] = self.rejected.get(exc.reason, 0) + 1
            return
        if self.interface == "rsi" and (seq != cyc.seq or cyc.sent_at is None):
            self.c["stale_replies" if seq in self.recent else "mismatched_replies"] += 1
            return
        if cyc.command is not None:
            self.c["duplicate_replies"] += 1
            if self.interface == "rsi":
                return
        else:
            self.c["replies"] += 1
            if cyc.sent_at is not None:
                cyc.latency = now - cyc.sent_at
                self.latencies.append(cyc.latency)
        if self.interface == "egm" and seq == cyc.seq:
            self.c["echoed_seqno"] += 1
        cyc.command = command

    # -- cycles --------------------------------------------------------------------
    def close_cycle(self) -> None:
        cyc = self.cycle
        if cyc is None:
            return
        late = cyc.command is None
        self.c["late"] += late
        self.consecutive = self.consecutive + 1 if late else 0
        self.c["consecutive_late_max"] = max(self.c["consecutive_late_max"], self.consecutive)
        cyc.row[4] = int(late)
        self.rows.append(cyc.row)
        self.plant.step(cyc.command)
        self.cycle = None
        if self.consecutive > self.late_limit:
            self.stopped_by_late = True
            self.stopped_at = cyc.k + 1

    def sensor_sample(self, t: float) -> None:
        values = self.plant.sensor_values(self.rng)
        self.measured = values[:3]
        text = (f"GTS1 {self.sensor_seq} {t:.6f} " + " ".join(f"{v:.10g}" for v in values[:16]) + "\n").encode("ascii")
        if self._send(self.sensor, text, self.sensor_target):
            self.c["sensor_samples_sent"] += 1
        self.sensor_seq += 1

    def open_cycle(self, k: int, now: float, deadline: float, next_deadline: float) -> None:
        faults = self.schedule.at(k)
        for kind in faults:
            self.faults[kind] += 1
        if "ipoc_jump" in faults:
            self.jump += faults["ipoc_jump"].jump
        seq_cycles = k + self.jump
        state = self.plant.state()
        if self.interface == "rsi":
            seq = _IPOC0 + int(round(seq_cycles * self.period * 1000))
            packet = rsi.compose_rob(state, seq, self.c["late"], "nan" in faults)
        else:
            seq = seq_cycles + 1
            packet = egm.compose_egm_robot(state, seq, int(round(seq_cycles * self.period * 1000)), "nan" in faults)
        t = k * self.period
        row = [k, t, seq, 0, 0, "+".join(sorted(faults)), *self.plant.record(), *(self.measured * 1e3), self.plant.error_mm()]
        self.errors.append(row[-1])
        sent_at = None
        if "garbage" in faults:
            n = int(self.garbage_rng.integers(1, 200))
            self._send(self.sock, self.garbage_rng.integers(0, 256, n, dtype=np.uint8).tobytes(), self.target)
        if "loss" not in faults:
            row[3] = 1
            if "delay" in faults:
                heapq.heappush(self.pending, (now + faults["delay"].delay_ms / 1000, k, packet))
            elif "reorder" in faults:
                heapq.heappush(self.pending, (next_deadline + 0.0002, k, packet))
            else:
                self._send(self.sock, packet, self.target)
                if now - deadline > 0.001:
                    self.c["clock_overruns"] += 1
            sent_at = now
            self.c["packets_sent"] += 1
            if "duplicate" in faults:
                self._send(self.sock, packet, self.target)
        self.c["cycles_sent"] += 1
        self.recent.add(seq)
        if len(self.recent) > 64:
            self.recent.discard(min(self.recent))
        self.cycle = _Cycle(k, seq, sent_at, row, faults)

    def send_pending(self, now: float) -> None:
        while self.pending and self.pending[0][0] <= now:
            _, _, packet = heapq.heappop(self.pending)
            self._send(self.sock, packet, self.target)

    def loop(self) -> None:
        tpc = max(1, int(round(self.period / SENSOR_PERIOD_S)))
        tick_dt = self.period / tpc
        t0 = time.monotonic() + 0.005
        tick = 0
        stop = self.schedule.stop_cycle
        while True:
            deadline = t0 + tick * tick_dt
            wake = min(deadline, self.pending[0][0]) if self.pending else deadline
            now = time.monotonic()
            if now < wake:
                readable, _, _ = select.select([self.sock], [], [], wake - now)
                if readable:
                    self.drain()
                continue
            now = time.monotonic()
            self.send_pending(min(now, deadline))  # what is due before the tick goes first, the rest after it (in time order)
            if now < deadline:
                continue
            if now - deadline > self.period:  # the process stalled: the robot's clock (and what it holds back) moves on from now
                self.c["clock_slips"] += 1
                shift = now - deadline
                t0 += shift
                self.pending = [(due + shift, k, packet) for due, k, packet in self.pending]
                deadline = now
            if tick % tpc == 0:
                k = tick // tpc
                self.drain()
                self.close_cycle()
                if self.stopped_by_late:
                    return
                if k >= self.n_cycles:
                    return
                if stop is not None and k >= stop:
                    self.faults["stop"] += 1
                    self.stopped_at = k
                    return
                self.sensor_sample(tick * tick_dt)
                self.open_cycle(k, time.monotonic(), deadline, t0 + (tick + tpc) * tick_dt)
            else:
                self.sensor_sample(tick * tick_dt)
            tick += 1

    def summary(self, status: Status, message: str) -> dict:
        err = np.asarray(self.errors, dtype=float)
        lat = np.asarray(self.latencies) * 1e3
        pct = {"p50": float(np.percentile(lat, 50)), "p99": float(np.percentile(lat, 99)), "max": float(lat.max())} if lat.size else None
        c = self.c
        return {
            "written_by": WRITTEN_BY, "status": str(status), "message": message, "interface": self.interface, "plant": self.plant.name,
            "plant_parameters": self.plant.parameters(), "target": list(self.target), "sensor_target": list(self.sensor_target),
            "period_s": self.period, "correction": self.correction, "cycles_requested": self.n_cycles,
            "cycles_sent": c["cycles_sent"], "packets_sent": c["packets_sent"], "replies": c["replies"], "datagrams_received": c["datagrams_received"],
            "late": c["late"], "consecutive_late_max": c["consecutive_late_max"], "late_limit": self.late_limit,
            "stopped_by_late": self.stopped_by_late, "stopped_at_cycle": self.stopped_at,
            "malformed_replies": int(sum(self.rejected.values())), "rejected_replies": dict(sorted(self.rejected.items())),
            "stale_replies": c["stale_replies"], "mismatched_replies": c["mismatched_replies"], "duplicate_replies": c["duplicate_replies"],
            "dropped_replies": c["dropped_replies"], "echoed_seqno": c["echoed_seqno"] if self.interface == "egm" else None,
            "faults_injected": dict(self.faults),
            "error_name": self.plant.error_name,
            "error_rms_mm": float(np.sqrt(np.mean(err**2))) if err.size else None,
            "error_max_mm": float(err.max()) if err.size else None,
            "reply_latency_ms": pct, "sensor_samples_sent": c["sensor_samples_sent"],
            "clock_overruns": c["clock_overruns"], "clock_slips": c["clock_slips"],
        }


def _write(out: Path, columns: tuple[str, ...], rows: list, summary: dict) -> None:
    out.mkdir(parents=True, exist_ok=True)
    tmp = out / (RECORD_FILE + ".tmp")
    with open(tmp, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(columns)
        for row in rows:
            w.writerow([f"{v:.9g}" if isinstance(v, float) else v for v in row])
    os.replace(tmp, out / RECORD_FILE)
    tmp = out / (SUMMARY_FILE + ".tmp")
    tmp.write_text(json.dumps(summary, indent=2, allow_nan=False, default=str) + "\n", encoding="utf-8")
    os.replace(tmp, out / SUMMARY_FILE)


def simulate(interface: str, plant: str | SimPlant, target: tuple[str, int], sensor_target: tuple[str, int] | None = None,
             duration_s: float = 10.0, faults: str | FaultSchedule | None = None, seed: int = 0, out_dir: str | Path | None = None,
             correction: str = "relative", period: float = LOOP_PERIOD_S, late_limit: int | None = None, sen_type: str = rsi.DEFAULT_SEN_TYPE,
             plant_options: dict | None = None, bind_host: str | None = None) -> SimResult:
    """Play the robot of an interface with a plant for ``duration_s``, against the sensor side at ``target``.

    Parameters
    ----------
    interface : {"rsi", "egm"}
        The protocol.
    plant : {"kr500", "l1"} or SimPlant
        The plant (:mod:`gtmodel.robot_sim.plants`), by name (built with ``seed`` and
        ``plant_options``) or an instance.
    target : tuple of (str, int)
        The sensor side's address and port (RSI's usual 49152, EGM's 6510).
    sensor_target : tuple of (str, int), optional
        Where the sensor stream goes (default ``target``'s port + 1).
    duration_s : float, optional
        Length of the run [s] (``round(duration_s / period)`` cycles), > 0, at most 86400.
    faults : str or FaultSchedule, optional
        The fault schedule (:mod:`gtmodel.robot_sim.faults`; a string is parsed with ``seed``).
    seed : int, optional
        Seed of the noise and the fault rates.
    out_dir : str or pathlib.Path, optional
        Folder of ``sim_record.csv`` and ``sim_summary.json``: new, empty, or a previous
        run's (:func:`check_sim_out_dir`); checked before the run.
    correction : {"relative", "absolute"}, optional
        How the robot applies RSI's corrections (summed increments, or offsets).
    period : float, optional
        Cycle time [s] (0.004); the plant's must be the same.
    late_limit : int, optional
        Consecutive late cycles tolerated before the robot stops (default
        :data:`DEFAULT_LATE_LIMIT`), >= 0.
    sen_type : str, optional
        The ``<Sen Type>`` the RSI robot accepts (default ``"ImFree"``).
    plant_options : dict, optional
        Keyword arguments of the plant's class (when ``plant`` is a name).
    bind_host : str, optional
        Local address of the robot's sockets (default: ``target``'s host when it is a loopback
        address, else all interfaces).

    Returns
    -------
    SimResult
        Status ``completed`` (the run ended: duration reached or a ``stop`` fault),
        ``check_failed`` (stopped on late replies), ``error`` (a socket error) or
        ``interrupted`` (Ctrl-C); never None.

    Raises
    ------
    InputError
        A bad argument or ``out_dir`` (before anything is sent).
    """
    if interface not in INTERFACES:
        raise InputError(f"interface: expected one of {', '.join(INTERFACES)}, got {interface!r}")
    target = _address(target, "target")
    sensor_target = (target[0], target[1] + 1 if target[1] < 65535 else target[1] - 1) if sensor_target is None else _address(sensor_target, "sensor_target")
    if correction not in CORRECTION_MODES:
        raise InputError(f"correction: expected one of {', '.join(CORRECTION_MODES)}, got {correction!r}")
    if not (isinstance(period, (int, float)) and math.isfinite(period) and 0.0005 <= period <= 1.0):
        raise InputError(f"period: expected a cycle time in [0.0005, 1] s, got {period!r}")
    if not (isinstance(duration_s, (int, float)) and math.isfinite(duration_s) and 0 < duration_s <= 86400):
        raise InputError(f"duration_s: expected a duration in (0, 86400] s, got {duration_s!r}")
    late_limit = DEFAULT_LATE_LIMIT if late_limit is None else late_limit
    if not isinstance(late_limit, int) or isinstance(late_limit, bool) or late_limit < 0:
        raise InputError(f"late_limit: expected an integer >= 0, got {late_limit!r}")
    if not isinstance(seed, int) or seed < 0:
        raise InputError(f"seed: expected a non-negative integer, got {seed!r}")
    schedule = faults if isinstance(faults, FaultSchedule) else FaultSchedule.from_spec(faults, seed)
    if out_dir is not None:
        check_sim_out_dir(out_dir)
    if isinstance(plant, str):
        options = dict(plant_options or {})
        if plant == "kr500":
            options.setdefault("dt", float(period))
        plant = make_plant(plant, np.random.default_rng([seed, 0]), **options)
    if not isinstance(plant, SimPlant):
        raise InputError(f"plant: expected a plant name or a SimPlant, got {type(plant).__name__}")
    if abs(plant.dt - period) > 1e-12:
        raise InputError(f"period: the plant {plant.name} runs at {plant.dt} s, got {period} s")
    if bind_host is None:
        bind_host = target[0] if target[0].startswith("127.") or target[0] == "localhost" else "0.0.0.0"
    run = _Run(interface, plant, target, sensor_target, max(1, int(round(duration_s / period))), schedule, seed, correction, float(period),
               late_limit, sen_type)
    status, message = Status.COMPLETED, ""
    try:
        run.open(bind_host)
        run.loop()
    except KeyboardInterrupt:
        status, message = Status.INTERRUPTED, "interrupted"
    except OSError as exc:
        status, message = Status.ERROR, f"socket error: {exc}"
    finally:
        run.close()
    if status == Status.COMPLETED:
        if run.stopped_by_late:
            status, message = Status.CHECK_FAILED, f"robot stopped: {run.consecutive} consecutive late replies (limit {late_limit}) at cycle {run.stopped_at}"
        elif run.stopped_at is not None:
            message = f"robot stopped sending at cycle {run.stopped_at} (stop fault)"
        else:
            message = f"{run.c['cycles_sent']} cycles of {period} s"
    summary = run.summary(status, message)
    columns = (*RECORD_COLUMNS, *plant.record_columns, "measured_x_mm", "measured_y_mm", "measured_z_mm", "error_mm")
    out = None
    if out_dir is not None:
        out = Path(out_dir)
        summary["files"] = [RECORD_FILE, SUMMARY_FILE]
        _write(out, columns, run.rows, summary)
    _log.info("robot-sim %s/%s: %s (%s)", interface, plant.name, status, message)
    return SimResult(status=status, message=message, summary=summary, columns=columns, record=run.rows, out_dir=out)
