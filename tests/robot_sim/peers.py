"""Minimal sensor-side peers for the simulator tests (written here, not the project's runtime).

:class:`RsiPeer` answers every ``<Rob>`` with a ``<Sen>`` echoing its IPOC. With a ``gain`` it
closes a P correction loop on the tracker stream: ``RKorr = gain (RSol - tracker)`` (mm),
which the robot sums (RSI's relative correction: an accumulating P loop, Cvitanic (2021),
sec. 5, eq. (33)). ``misbehave`` maps a reply count to a bad datagram sent instead
(garbage, a DOCTYPE bomb, a NaN correction, a wrong IPOC, ...). :class:`EgmPeer` answers
each ``EgmRobot`` with an ``EgmSensor`` holding planned joints (the fed-back joints plus
``offset``), echoing the seqno. Both run in a thread and bind 127.0.0.1 on free ports.
"""

from __future__ import annotations

import socket
import threading
import time

import numpy as np

from gtmodel import _egm_pb2
from gtmodel.robot_sim import rsi


class _Peer(threading.Thread):
    def __init__(self) -> None:
        super().__init__(daemon=True)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.1)
        self.sensor = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sensor.bind(("127.0.0.1", 0))
        self.sensor.setblocking(False)
        self.running = True
        self.received = 0
        self.replied = 0
        self.unparsed = 0
        self.samples = 0
        self.latest: np.ndarray | None = None

    @property
    def target(self) -> tuple[str, int]:
        return self.sock.getsockname()

    @property
    def sensor_target(self) -> tuple[str, int]:
        return self.sensor.getsockname()

    def _read_sensor(self) -> None:
        while True:
            try:
                data, _ = self.sensor.recvfrom(1024)
            except BlockingIOError:
                return
            parts = data.split()
            if len(parts) >= 6 and parts[0] == b"GTS1":
                self.latest = np.array([float(v) for v in parts[3:6]]) * 1e3  # m -> mm
                self.samples += 1

    def run(self) -> None:
        while self.running:
            try:
                data, addr = self.sock.recvfrom(65536)
            except (socket.timeout, OSError):
                continue
            self.received += 1
            self._read_sensor()
            reply = self.answer(data)
            if reply is not None:
                self.sock.sendto(reply, addr)
                self.replied += 1

    def answer(self, data: bytes) -> bytes | None:  # pragma: no cover - overridden
        raise NotImplementedError

    def __enter__(self):
        self.start()
        return self

    def __exit__(self, *exc) -> None:
        time.sleep(0.05)  # the last datagrams in flight
        self.running = False
        self.join(2.0)
        self.sock.close()
        self.sensor.close()


class RsiPeer(_Peer):
    def __init__(self, gain: float = 0.0, misbehave: dict[int, bytes] | None = None, silent: bool = False, constant=None) -> None:
        super().__init__()
        self.gain = gain
        self.misbehave = dict(misbehave or {})
        self.misbehaved: list[int] = []
        self.silent = silent
        self.constant = None if constant is None else np.asarray(constant, dtype=float)

    def answer(self, data: bytes) -> bytes | None:
        if self.silent:
            return None
        try:
            ipoc, fields = rsi.parse_rob(data)
        except Exception:
            self.unparsed += 1
            return None
        if self.replied in self.misbehave:
            bad = self.misbehave.pop(self.replied)
            self.misbehaved.append(ipoc)
            return bad.replace(b"{ipoc}", str(ipoc).encode())
        if self.constant is not None:
            return rsi.compose_sen(ipoc, self.constant)
        corr = np.zeros(6)
        if self.gain and self.latest is not None and np.all(np.isfinite(fields["RSol"])):
            corr[:3] = self.gain * (fields["RSol"][:3] - self.latest)
        return rsi.compose_sen(ipoc, corr)


class EgmPeer(_Peer):
    def __init__(self, offset_mm: float = 1.0, misbehave: dict[int, bytes] | None = None) -> None:
        super().__init__()
        self.offset = offset_mm
        self.misbehave = dict(misbehave or {})
        self.seqnos: list[int] = []

    def answer(self, data: bytes) -> bytes | None:
        msg = _egm_pb2.EgmRobot()
        try:
            msg.ParseFromString(data)
        except Exception:
            self.unparsed += 1
            return None
        joints = np.array(msg.feedBack.joints.joints)
        if not np.all(np.isfinite(joints)) or joints.size == 0:
            self.unparsed += 1
            return None
        self.seqnos.append(msg.header.seqno)
        if self.replied in self.misbehave:
            return self.misbehave.pop(self.replied)
        reply = _egm_pb2.EgmSensor()
        reply.header.seqno = msg.header.seqno
        reply.header.mtype = _egm_pb2.EgmHeader.MSGTYPE_CORRECTION
        reply.planned.joints.joints.extend(float(v) for v in self.q0(joints))
        return reply.SerializeToString()

    def q0(self, joints: np.ndarray) -> np.ndarray:
        if not hasattr(self, "_q0"):
            self._q0 = joints + self.offset
        return self._q0
