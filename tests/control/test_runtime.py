"""The robot runtime run against minimal robot-side peers on loopback: RSI and EGM, faults, exits, the log.

Independent checks: the peers are written here from the public formats (KUKA RSI's <Rob>/<Sen> XML
read with xml.etree; ABB EGM's messages through Python's protobuf package and ABB's egm.proto), not
from the runtime's C; a relative-RSI peer sums the increments it receives as a KUKA controller does,
and the limits are checked on what the robot would hold. The step is a trivial law built here from
a CasADi Function (u = K (r - x), K large, so that only the runtime's limits keep the replies in
bounds; ok = 0 when the first input exceeds 500, a failed step).
"""

from __future__ import annotations

import json
import logging
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from concurrent.futures import ThreadPoolExecutor

import casadi as ca
import numpy as np
import pytest

from gtmodel import _egm_pb2 as egm
from gtmodel.codegen.loop_step import LoopStep
from gtmodel.codegen.robot_runtime import RobotRuntime, RuntimeSpec, build_runtime
from gtmodel.control.runtime import FLAGS, LoopRun, read_cycle_log, read_ready, run_loop
from gtmodel.errors import InputError
from gtmodel.status import Status

from ..robot_sim.realtime import MachinePauses

LOWER, UPPER, RATE = np.array([-2.0, -1.0]), np.array([2.0, 1.0]), np.array([0.05, 0.1])
EGM_LOWER, EGM_UPPER, EGM_RATE = -90.0, 90.0, 0.5


def _step(nx: int, nu: int, law) -> LoopStep:
    t, x, ul = ca.SX.sym("t"), ca.SX.sym("x", nx), ca.SX.sym("u_last", nu)
    u, ok = law(x)
    f = ca.Function("control", [t, x, ul], [u, ok], ["t", "x", "u_last"], ["u", "ok"])
    return LoopStep("test", f, 0.004, np.full(nu, -np.inf), np.full(nu, np.inf), np.zeros(nu), [f"x{i}" for i in range(nx)],
                    [f"u{i}" for i in range(nu)])


def _huge(x):  # u = 1000 (1 - x): far outside the limits; ok = 0 when x0 > 500
    return ca.vertcat(1000 * (1 - x[0]), 1000 * (1 - x[1])), ca.if_else(x[0] > 500, 0, 1)


def _rsi(fallback="hold", correction="relative", sensor=True):
    inputs = ["RIst.X", "RIst.Y"] + (["sensor.0"] if sensor else [])
    spec = RuntimeSpec(interface="rsi", inputs=inputs, outputs=["RKorr.X", "AKorr.A1"], lower=LOWER, upper=UPPER, rate=RATE,
                       correction=correction, fallback=fallback, stale_cycles=5)
    return RobotRuntime(_step(len(inputs), 2, _huge), spec)


@pytest.fixture(scope="module")
def exes(tmp_path_factory):
    def build(name, source):
        return build_runtime(source, tmp_path_factory.mktemp(name))
    egm_step = _step(3, 3, lambda x: (x + 5.0, ca.SX(1)))
    pc_step = _step(1, 3, lambda x: (ca.vertcat(x[0], -x[0], 100.0), ca.SX(1)))
    cart_step = _step(3, 3, lambda x: (x + ca.DM([1.0, -1.0, 0.5]), ca.SX(1)))
    return {
        "egm_cart": build("egm_cart", RobotRuntime(cart_step, RuntimeSpec(
            interface="egm", egm_mode="cartesian", inputs=[f"feedback.cartesian.{a}" for a in "xyz"],
            outputs=[f"planned.cartesian.{a}" for a in "xyz"], lower=[-2000.0] * 3, upper=[2000.0] * 3, rate=[0.4] * 3))),
        "rsi": build("rsi", _rsi()),
        "rsi_ramp": build("rsi_ramp", _rsi("ramp", "absolute")),
        "rsi_plain": build("rsi_plain", _rsi(sensor=False)),
        "egm": build("egm", RobotRuntime(egm_step, RuntimeSpec(
            interface="egm", inputs=[f"feedback.joints.{i}" for i in range(3)], outputs=[f"planned.joints.{i}" for i in range(3)],
            lower=[EGM_LOWER] * 3, upper=[EGM_UPPER] * 3, rate=[EGM_RATE] * 3))),
        "egm_pc": build("egm_pc", RobotRuntime(pc_step, RuntimeSpec(
            interface="egm", egm_mode="path_correction", inputs=["feedback.cartesian.x"], outputs=["pathcorr.x", "pathcorr.y", "pathcorr.z"],
            lower=[-1.0] * 3, upper=[1.0] * 3, rate=[0.25] * 3))),
    }


# ---- the peers: minimal robots from the public formats ----

class Peer:
    """A robot on loopback: sends to the runtime's port, reads the reply (its own socket), sends sensor samples."""

    def __init__(self, ready: dict, timeout: float = 0.2):
        self.addr = ("127.0.0.1", ready["listen_port"])
        self.sensor_addr = ("127.0.0.1", ready["sensor_port"])
        self.pid = ready["pid"]
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.settimeout(timeout)
        self.sock.bind(("127.0.0.1", 0))
        self.sensor_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sensor_seq = 0
        self.rounds: list[tuple[float, float | None]] = []  # each exchange's send and reply times (monotonic)

    def sensor(self, *values: float) -> None:
        self.sensor_seq += 1
        line = f"GTS1 {self.sensor_seq} {time.monotonic():.6f} " + " ".join(repr(float(v)) for v in values) + "\n"
        self.sensor_sock.sendto(line.encode(), self.sensor_addr)

    def exchange(self, data: bytes) -> bytes | None:
        sent = time.monotonic()
        self.sock.sendto(data, self.addr)
        try:
            reply = self.sock.recv(65536)
        except socket.timeout:
            reply = None
        self.rounds.append((sent, None if reply is None else time.monotonic()))
        return reply

    def close(self) -> None:
        self.sock.close()
        self.sensor_sock.close()


def rob(ipoc: int, x: float | str = 0.0, y: float | str = 0.0) -> bytes:
    return (f'<Rob Type="KUKA"><RIst X="{x}" Y="{y}" Z="0.0" A="0.0" B="0.0" C="0.0"/>'
            f'<AIPos A1="0" A2="0" A3="0" A4="0" A5="0" A6="0"/><Delay D="0"/><IPOC>{ipoc}</IPOC></Rob>').encode()


def sen(reply: bytes) -> tuple[int, np.ndarray]:
    """IPOC and (RKorr.X, AKorr.A1) of a <Sen> reply (KUKA's format, read as XML)."""
    root = ET.fromstring(reply)
    assert root.tag == "Sen" and root.get("Type") == "ImFree" and root.findtext("EStr") == "gtmodel"
    return int(root.findtext("IPOC")), np.array([float(root.find("RKorr").get("X")), float(root.find("AKorr").get("A1"))])


def session(exe, out, script, **kw) -> tuple[LoopRun, object]:
    """run_loop in a thread, the peer script in this one; the run ends by the idle timeout after the script.

    The idle time-out (1 s) outlasts a busy machine's pauses of the peer between two datagrams.
    """
    kw = {"listen": ("127.0.0.1", 0), "idle_timeout": 1.0, "time_limit": 120, **kw}
    with ThreadPoolExecutor(1) as pool:
        fut = pool.submit(run_loop, exe, out, **kw)
        peer = Peer(read_ready(out, 20))
        try:
            data = script(peer)
        finally:
            peer.close()
        return fut.result(150), data


def rsi_script(n: int, xs=None, sensor=True, start=1000, pace=0.0):
    def script(peer: Peer):
        replies = []
        for k in range(n):
            if sensor:
                peer.sensor(0.5)
            x = xs[k] if xs is not None else 0.0
            replies.append(peer.exchange(rob(start + 4 * k, x, x)))
            if pace:
                time.sleep(pace)
        return replies
    return script


def totals(replies) -> np.ndarray:
    """What a relative-mode KUKA controller holds: the running sum of the increments."""
    return np.cumsum(np.array([sen(r)[1] for r in replies]), axis=0)


def test_rsi_replies_echo_the_ipoc_and_the_held_total_stays_within_the_limits(exes, tmp_path):
    rng = np.random.default_rng(3)
    xs = rng.normal(0.0, 50.0, 300)
    run, replies = session(exes["rsi"], tmp_path / "run", rsi_script(300, xs))
    assert run.status == Status.COMPLETED and run.summary["end"] == "idle_timeout"
    assert None not in replies and [sen(r)[0] for r in replies] == [1000 + 4 * k for k in range(300)]
    held = totals(replies)
    assert np.all(held >= LOWER - 1e-12) and np.all(held <= UPPER + 1e-12)  # the %.6f increments summed
    assert np.all(np.abs(np.diff(held, axis=0)) <= RATE + 1e-12)
    log = read_cycle_log(run.log_path)
    y = np.column_stack([log["reply:RKorr.X"], log["reply:AKorr.A1"]])
    assert np.all((y >= LOWER) & (y <= UPPER)) and np.all(np.abs(np.diff(y, axis=0)) <= RATE * (1 + 1e-12))
    assert np.allclose(held, y, rtol=0, atol=1e-9)  # the robot's sum is the logged total: no drift of %.6f
    s = run.summary
    assert (s["cycles"], s["replies"], s["missing_replies"]) == (300, 300, 0)
    assert s["limit_clamps"]["upper"] + s["limit_clamps"]["lower"] + s["limit_clamps"]["rate"] > 0
    assert s["step_status"] == {"GT_OK": 300} and s["log"]["rows"] == 300 and s["log"]["dropped"] == 0
    assert set(s["reply_latency_ms"]) == {"p50", "p90", "p99", "max"}  # their size: the realtime tests below


def fault_script(peer: Peer):
    """Valid cycles with faults between; returns (label, reply) per datagram."""
    out = []
    def valid(k, x=0.0):
        peer.sensor(0.5)
        out.append(("valid", peer.exchange(rob(1000 + 4 * k, x, x))))
    for k in range(5):
        valid(k)
    out.append(("nan", peer.exchange(rob(1020, "NaN", 0.0))))
    out.append(("duplicate", peer.exchange(rob(1020, 0.0, 0.0))))
    out.append(("old", peer.exchange(rob(1004, 0.0, 0.0))))
    out.append(("garbage", peer.exchange(b"<Rob><RIst X=\"1\"")))
    out.append(("garbage", peer.exchange(bytes(range(256)) * 3)))
    out.append(("too_long", peer.exchange(rob(1024).replace(b"</Rob>", b" " * 5000 + b"</Rob>"))))
    valid(6)
    out.append(("step_fails", peer.exchange(rob(1028, 600.0, 0.0))))
    for k in range(8, 16):  # no sensor samples: stale after 5 cycles
        out.append(("no_sensor", peer.exchange(rob(1000 + 4 * k))))
    for k in range(16, 19):
        valid(k)
    return out


def test_rsi_faults_get_the_held_reply_or_none_and_never_reach_the_step(exes, tmp_path):
    run, out = session(exes["rsi"], tmp_path / "run", fault_script)
    labels = [lab for lab, _ in out]
    got = {lab: [r for lb, r in out if lb == lab] for lab in labels}
    assert got["garbage"] == [None, None] and got["too_long"] == [None]
    assert None not in got["valid"] + got["nan"] + got["duplicate"] + got["old"] + got["step_fails"] + got["no_sensor"]
    assert [sen(r)[0] for r in got["nan"] + got["duplicate"] + got["old"]] == [1020, 1020, 1004]  # echoed as received
    assert all(np.all(sen(r)[1] == 0.0) for r in got["nan"] + got["duplicate"] + got["old"] + got["step_fails"])  # held: no increment
    no_sensor = np.array([sen(r)[1] for r in got["no_sensor"]])
    assert np.all(no_sensor[4:] == 0.0) and np.all(no_sensor[:4] != 0.0)  # fresh up to 5 cycles old, then the held fallback
    s, st = run.summary, run.stats
    assert (st["non_finite"], st["duplicate_or_old"], st["malformed"], st["too_long"], st["held_replies"]) == (1, 2, 3, 1, 3)
    assert s["fallback"] == {"rule": "hold", "stale_sensor": 4, "step_failed": 1}
    assert s["faults"]["malformed"] == {"count": 3, "action": "no reply (nothing to echo); counted"}
    assert s["faults"]["stale_sensor"]["action"] == "fallback (hold); the step is not called"
    log = read_cycle_log(run.log_path)
    stepped = (log["flags"] & FLAGS["step"]) != 0
    xs = np.column_stack([log[c] for c in ("x:RIst.X", "x:RIst.Y", "x:sensor.0")])
    assert np.all(np.isfinite(xs[stepped])) and int(stepped.sum()) == st["step_calls"] == 5 + 1 + 1 + 4 + 3  # the failed step too
    assert log["cycle"].size == len(out) - 3 and st["log"]["dropped"] == 0  # malformed datagrams: counted, not logged
    assert np.count_nonzero(log["flags"] & FLAGS["malformed"]) == 0


def test_rsi_ramp_fallback_moves_the_absolute_correction_to_zero_at_the_rate(exes, tmp_path):
    def script(peer: Peer):
        replies = []
        for k in range(60):  # x = -1: u = 2000, limited to the upper bound at the rate
            if k < 50:
                peer.sensor(0.5)
            replies.append(peer.exchange(rob(1000 + 4 * k, -1.0, -1.0)))
        return replies
    run, replies = session(exes["rsi_ramp"], tmp_path / "run", script)
    y = np.array([sen(r)[1] for r in replies])  # absolute: the total itself
    assert np.allclose(y[:50, 0], np.minimum(0.05 * np.arange(1, 51), 2.0), atol=1e-6)
    assert np.allclose(y[55:, 0], y[54, 0] - 0.05 * np.arange(1, 6), atol=1e-6)  # ramping down at the rate
    assert np.allclose(y[:55, 1], np.minimum(0.1 * np.arange(1, 56), 1.0), atol=1e-6)
    assert np.allclose(y[55:, 1], y[54, 1] - 0.1 * np.arange(1, 6), atol=1e-6)
    assert run.summary["fallback"]["rule"] == "ramp" and run.summary["fallback"]["stale_sensor"] == 5


def test_deadline_rule_sends_the_held_reply_when_the_computed_one_is_late(exes, tmp_path):
    run, replies = session(exes["rsi"], tmp_path / "run", rsi_script(20, [-1.0] * 20), reply_deadline=0.0)
    assert None not in replies and np.all(totals(replies) == 0.0)  # every computed reply later than 0 s: held
    assert run.summary["deadline_held"] == 20 and run.summary["missing_replies"] == 0


def test_idle_timeout_ends_the_run_after_the_first_packet(exes, tmp_path):
    t0 = time.monotonic()
    run, _ = session(exes["rsi_plain"], tmp_path / "run", rsi_script(3, sensor=False), idle_timeout=0.5)
    assert run.status == Status.COMPLETED and run.stats["end"] == "idle_timeout" and run.exit_code == 0
    assert 0.5 <= time.monotonic() - t0 < 10


def test_max_cycles_ends_the_run(exes, tmp_path):
    run, replies = session(exes["rsi_plain"], tmp_path / "run", rsi_script(25, sensor=False), max_cycles=20)
    assert run.stats["end"] == "max_cycles" and run.summary["cycles"] == 20 and replies[:20].count(None) == 0
    assert replies[20:] == [None] * 5


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_ends_the_run_with_the_log_flushed(exes, tmp_path, sig):
    def script(peer: Peer):
        for k in range(50):
            peer.exchange(rob(1000 + 4 * k))
        os.kill(peer.pid, sig)
    run, _ = session(exes["rsi_plain"], tmp_path / "run", script, idle_timeout=60)
    assert run.status == Status.INTERRUPTED and run.stats["signal"] == sig.name and run.exit_code == 0
    assert read_cycle_log(run.log_path)["cycle"].tolist() == list(range(1, 51)) and run.stats["log"]["written"] == 50


def test_a_crash_is_a_status(exes, tmp_path):
    def script(peer: Peer):
        peer.exchange(rob(1000))
        os.kill(peer.pid, signal.SIGKILL)
    run, _ = session(exes["rsi_plain"], tmp_path / "run", script, idle_timeout=60)
    assert run.status == Status.ERROR and "killed by signal 9 (SIGKILL)" in run.message and run.exit_code == -9


def test_without_the_privilege_the_runtime_runs_on_and_says_why(exes, tmp_path):
    wrapper = []
    if os.geteuid() == 0:  # root: drop the capabilities a real-time request needs
        if shutil.which("setpriv") is None:
            pytest.skip("root without setpriv: cannot drop CAP_SYS_NICE")
        wrapper = ["setpriv", "--bounding-set", "-sys_nice,-ipc_lock", "--inh-caps", "-sys_nice,-ipc_lock"]
    out = tmp_path / "run"
    out.mkdir()
    proc = subprocess.Popen([*wrapper, str(exes["rsi_plain"]), "--out", str(out), "--listen", "127.0.0.1:0", "--idle-timeout", "0.3"],
                            stderr=subprocess.PIPE, text=True)
    try:
        peer = Peer(read_ready(out, 20))
        replies = [peer.exchange(rob(1000 + 4 * k)) for k in range(10)]
        peer.close()
        assert proc.wait(30) == 0, proc.stderr.read()
    finally:
        proc.kill()
        proc.wait()
    stats = json.loads((out / "runtime_stats.json").read_text())
    if stats["realtime"]["sched_fifo"]:
        pytest.skip("this user may ask for SCHED_FIFO (rtprio limit): nothing refused")
    assert None not in replies and stats["replies"] == 10
    assert stats["realtime"]["granted"] is False and "SCHED_FIFO: Operation not permitted" in stats["realtime"]["reason"]


def test_realtime_not_asked_is_said(exes, tmp_path):
    run, _ = session(exes["rsi_plain"], tmp_path / "run", rsi_script(3, sensor=False), realtime=False)
    assert run.summary["realtime"] == {"granted": False, "reason": "not asked (--no-realtime)"} and run.summary["replies"] == 3


def test_time_limit_stops_a_run_that_never_ends(exes, tmp_path):
    run = run_loop(exes["rsi_plain"], tmp_path / "run", listen=("127.0.0.1", 0), time_limit=0.5)
    assert run.status == Status.MAX_ITERATIONS and run.stats["end"] == "signal" and run.summary["cycles"] == 0


def test_serving_says_its_cycle_count_while_it_serves(exes, tmp_path, caplog):
    """``gtmodel loop`` says "serving" with the cycles so far (issue 67), first that it waits for the robot."""
    caplog.set_level(logging.INFO, logger="gtmodel")

    def script(peer: Peer):
        time.sleep(0.5)
        for k in range(30):
            peer.exchange(rob(1000 + 4 * k))
        time.sleep(0.5)
    run, _ = session(exes["rsi_plain"], tmp_path / "run", script, idle_timeout=1.0, progress=0.2)
    lines = [r.getMessage() for r in caplog.records if r.getMessage().startswith("loop: serving")]
    assert run.summary["cycles"] == 30
    assert lines[0].startswith("loop: serving, waiting for the robot's first datagram")
    assert "loop: serving, 30 cycles" in {line.split(" (")[0] for line in lines}


def test_setup_failures_are_a_status(exes, tmp_path):
    busy = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    busy.bind(("127.0.0.1", 0))
    try:
        run = run_loop(exes["rsi_plain"], tmp_path / "a", listen=("127.0.0.1", busy.getsockname()[1]), time_limit=10)
    finally:
        busy.close()
    assert run.status == Status.ERROR and "cannot bind the robot socket to 127.0.0.1" in run.message and run.exit_code == 3
    run = run_loop(exes["rsi_plain"], tmp_path / "b", listen=("no-host", 1), time_limit=10)
    assert run.status == Status.INVALID_INPUT and "IPv4" in run.message and run.summary == {}


def test_run_loop_refuses_a_bad_executable_or_a_foreign_folder(exes, tmp_path):
    with pytest.raises(InputError, match="executable: .* is not an executable file"):
        run_loop(tmp_path / "missing", tmp_path / "run")
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep")
    with pytest.raises(InputError, match="holds files that are not a runtime run's"):
        run_loop(exes["rsi_plain"], tmp_path / "mine")


def test_read_cycle_log_refuses_a_bad_file(tmp_path):
    bad = tmp_path / "log.csv"
    bad.write_text("cycle,flags\n1,2\n3\n")
    with pytest.raises(InputError, match="wrong length"):
        read_cycle_log(bad)
    with pytest.raises(InputError, match="cannot read the cycle log"):
        read_cycle_log(tmp_path / "none.csv")


def test_a_step_with_megabytes_of_stack_work_runs_in_the_cycle_thread(tmp_path):
    """A dense 260 x 260 QR solve (CasADi's linear solver, kept as MX: 1.6 MB of work arrays on the stack). With the
    cycle thread's stack fixed at 1 MiB this runtime was killed by SIGSEGV at its first cycle; now it is sized from the
    step's work (robot_runtime.cycle_stack_bytes). The solve takes longer than a period here: replies may be dropped
    as late, which is the deadline rule's business (not counted)."""
    n = 260
    t, x, ul = ca.MX.sym("t"), ca.MX.sym("x", 3), ca.MX.sym("u_last", 2)
    y = ca.solve((1 + x[0] ** 2) * ca.DM.eye(n) + 1e-3 * ca.repmat(x[1], n, n), ca.DM.ones(n), "qr")
    f = ca.Function("control", [t, x, ul], [ca.vertcat(1e-6 * ca.sum1(y), 0.0), ca.MX(1)], ["t", "x", "u_last"], ["u", "ok"])
    step = LoopStep("test", f, 0.004, np.full(2, -np.inf), np.full(2, np.inf), np.zeros(2), ["x0", "x1", "x2"], ["u0", "u1"])
    spec = RuntimeSpec(interface="rsi", inputs=["RIst.X", "RIst.Y", "sensor.0"], outputs=["RKorr.X", "AKorr.A1"], lower=LOWER,
                       upper=UPPER, rate=RATE, correction="relative", fallback="hold", stale_cycles=5)
    source = RobotRuntime(step, spec)
    generated = source.generate(tmp_path / "code")
    assert 8 * generated.work_sizes["control"][3] > 1.5e6
    run, _ = session(build_runtime(source, tmp_path / "code", generated=generated), tmp_path / "run", rsi_script(10))
    assert run.status == Status.COMPLETED and run.summary["cycles"] == run.summary["log"]["rows"] == 10, run.message


@pytest.mark.slow
def test_an_unblocked_mpc_of_horizon_100_runs_behind_rsi(tmp_path, motor):
    """A user's case: the DC motor's MPC (horizon 100, every input free: 1.07 MB of work arrays) as the runtime's step.
    With the fixed 1 MiB cycle stack this runtime was killed by SIGSEGV (measured, 2026-11-29); now every step runs
    (the replies it computes past the deadline are the deadline rule's business, not counted here)."""
    from gtmodel.codegen.loop_step import mpc_step
    from gtmodel.codegen.robot_runtime import CYCLE_STACK_BASE, cycle_stack_bytes
    from gtmodel.control.mpc import mpc_controller

    ode = motor[0]
    tt = 0.004 * np.arange(301)
    uu = (6.0 * np.sin(2 * np.pi * tt / 0.6))[:, None]
    xx, _ = ode.simulate_steps(ode.step(0.004, "rk4", substeps=4), uu[:-1])
    c = mpc_controller(ode, tt, xx, uu, horizon=100, Q=[1e-2, 100.0, 1e-2], R=[1e-3], u_lb=[-12.0], u_ub=[12.0], method="rk4", substeps=2)
    spec = RuntimeSpec(interface="rsi", inputs=["RIst.X", "RIst.Y", "RIst.Z"], outputs=["RKorr.X"], lower=[-12.0], upper=[12.0], rate=[1.0])
    source = RobotRuntime(mpc_step(c), spec)
    generated = source.generate(tmp_path / "code")
    assert cycle_stack_bytes(generated) > CYCLE_STACK_BASE + 1_000_000
    run, _ = session(build_runtime(source, tmp_path / "code", generated=generated), tmp_path / "run", rsi_script(20, sensor=False))
    assert run.status == Status.COMPLETED and run.summary["cycles"] == 20 and run.summary["step_status"] == {"GT_OK": 20}, run.message


PERIOD = 0.004  # s, the runtime's cycle (RuntimeSpec's default)


def realtime_session(exe, tmp_path, script, **kw):
    """:func:`session` beside the machine's pause canaries: ``(run, replies, rounds, machine)``."""
    rounds = []

    def timed(peer: Peer):
        try:
            return script(peer)
        finally:
            rounds.extend(peer.rounds)
    with MachinePauses(tmp_path / "canary") as machine:
        run, replies = session(exe, tmp_path / "run", timed, **kw)
    return run, replies, rounds, machine


def judge_rsi(run: LoopRun, rounds, machine: MachinePauses, start: int = 1000, timeout: float = 0.2, ignore=frozenset()):
    """The peer's misses and the runtime's late rows (round ``k`` is IPOC ``start + 4 k``), split by the machine's pauses.

    Returns ``(unexplained, explained, late_only)``: ``late_only`` whether every cycle the runtime logged
    without a reply was one it logged late (the rule drops a reply computed past the period). A machine
    that paused more than 1 % of the run (:meth:`MachinePauses.busy_reason`) is too busy to judge the runtime by:
    the test skips, saying so.
    """
    log = read_cycle_log(run.log_path)
    late_rows = log["latency_us"] > 1e6 * PERIOD
    late = {int(s - start) // 4: (t, 1e-6 * lat)
            for s, t, lat in zip(log["ipoc_or_seq"][late_rows], log["t_monotonic"][late_rows], log["latency_us"][late_rows])}
    unsent = (log["flags"] & FLAGS["sent"]) == 0
    unexplained, explained = machine.judge(rounds, late, timeout, ignore)
    print(f"machine: {machine.describe()}", *explained, sep="\n")
    reason = machine.busy_reason()
    if reason:
        pytest.skip(reason)
    return unexplained, explained, bool(np.all(late_rows[unsent]))


@pytest.mark.realtime
def test_rsi_2000_cycles_at_4_ms_without_a_missing_reply(exes, tmp_path):
    """Independent: the peer's own clock; a reply missing or late only by a pause of the machine (canaries above the
    runtime's priority, tests/robot_sim/realtime.py) is the machine's and is printed, every other one fails."""
    run, replies, rounds, machine = realtime_session(exes["rsi"], tmp_path, rsi_script(2000, pace=0.0035))
    unexplained, explained, late_only = judge_rsi(run, rounds, machine)
    assert unexplained == [] and late_only and len(rounds) == 2000
    assert run.summary["late_replies"] <= len(explained) and run.summary["missing_replies"] <= len(explained)
    assert run.summary["log"]["rows"] == 2000 and run.summary["log"]["dropped"] == 0


@pytest.mark.realtime
def test_a_stopped_runtime_is_not_excused_as_a_paused_machine(exes, tmp_path):
    """Independent of the rule's unit tests: the runtime itself stopped (SIGSTOP, 300 ms; the machine running) misses
    replies that the canaries do not explain, so the rule above fails a runtime that stalls."""
    import threading

    def script(peer: Peer):
        replies = rsi_script(100, pace=0.0035)(peer)
        os.kill(peer.pid, signal.SIGSTOP)
        threading.Timer(0.3, os.kill, (peer.pid, signal.SIGCONT)).start()
        return replies + rsi_script(100, start=1400, pace=0.0035)(peer)
    run, replies, rounds, machine = realtime_session(exes["rsi"], tmp_path, script)
    unexplained, explained, _ = judge_rsi(run, rounds, machine)
    assert run.status == Status.COMPLETED and unexplained[0].startswith("round 100: no reply over 200.0 ms"), unexplained


@pytest.mark.slow
@pytest.mark.realtime
def test_rsi_15000_cycles_at_4_ms_latency(exes, tmp_path):
    run, replies, rounds, machine = realtime_session(exes["rsi"], tmp_path, rsi_script(15000, pace=0.0035), time_limit=300)
    lat = run.summary["reply_latency_ms"]
    print(f"15000 cycles: p50 {lat['p50']:.4f} ms, p90 {lat['p90']:.4f} ms, p99 {lat['p99']:.4f} ms, max {lat['max']:.4f} ms; "
          f"realtime {run.summary['realtime']}")
    unexplained, explained, late_only = judge_rsi(run, rounds, machine)
    assert unexplained == [] and late_only and run.summary["missing_replies"] <= len(explained)
    assert run.summary["log"]["rows"] == 15000 and lat["p99"] < 1.0


# ---- EGM ----

def egm_robot(seq: int, joints, planned=None, tm: int | None = None) -> bytes:
    r = egm.EgmRobot()
    r.header.seqno = seq
    r.header.tm = tm if tm is not None else 4 * seq
    r.header.mtype = egm.EgmHeader.MSGTYPE_DATA
    r.feedBack.joints.joints.extend(joints)
    r.planned.joints.joints.extend(planned if planned is not None else joints)
    r.feedBack.cartesian.pos.x, r.feedBack.cartesian.pos.y, r.feedBack.cartesian.pos.z = 500.0, 0.0, 800.0
    r.motorState.state = egm.EgmMotorState.MOTORS_ON
    r.mciState.state = egm.EgmMCIState.MCI_RUNNING
    r.rapidExecState.state = egm.EgmRapidCtrlExecState.RAPID_RUNNING
    return r.SerializeToString()


def test_egm_replies_echo_the_seqno_start_at_the_planned_position_and_hold_on_faults(exes, tmp_path):
    def script(peer: Peer):
        out = []
        q = [10.0, -20.0, 30.0]
        for k in range(1, 31):
            if k == 10:
                out.append(("nan", peer.exchange(egm_robot(k, [float("nan"), 0.0, 0.0], planned=q))))
            elif k == 11:
                out.append(("garbage", peer.exchange(b"\x08\x96\x01garbage\xff\xff")))
                out.append(("dup", peer.exchange(egm_robot(k - 1, q))))
            else:
                out.append(("valid", peer.exchange(egm_robot(k, q))))
        return out
    run, out = session(exes["egm"], tmp_path / "run", script)
    assert [r for lab, r in out if lab == "garbage"] == [None]
    msgs = [(lab, egm.EgmSensor.FromString(r)) for lab, r in out if r is not None]
    assert [m.header.seqno for _, m in msgs] == list(range(1, 11)) + [10] + list(range(12, 31))  # the duplicate's own seqno
    msgs = [m for _, m in sorted(msgs, key=lambda lm: lm[1].header.seqno)]
    assert all(m.header.mtype == egm.EgmHeader.MSGTYPE_CORRECTION and len(m.planned.joints.joints) == 3 for m in msgs)
    q = np.array([list(m.planned.joints.joints) for m in msgs])
    # the first reply is one rate step from the robot's planned position, towards x + 5 deg
    assert np.allclose(q[0], [10.5, -19.5, 30.5]) and np.all(np.isfinite(q))
    assert np.all(np.abs(np.diff(q, axis=0)) <= EGM_RATE + 1e-12) and np.all((q >= EGM_LOWER) & (q <= EGM_UPPER))
    assert np.array_equal(q[9], q[8]) and np.array_equal(q[10], q[8])  # seqno 10 (NaN): held; its duplicate held too
    assert run.stats["non_finite"] == 1 and run.stats["malformed"] == 1 and run.stats["duplicate_or_old"] == 1
    assert run.summary["interface"] == "egm" and run.summary["missing_replies"] == 0


def test_egm_path_correction_replies_with_egm_sensor_path_corr(exes, tmp_path):
    def script(peer: Peer):
        out = []
        for k in range(1, 11):
            r = egm.EgmRobot()
            r.header.seqno, r.header.tm = k, 4 * k
            r.feedBack.cartesian.pos.x, r.feedBack.cartesian.pos.y, r.feedBack.cartesian.pos.z = 0.6, 0.0, 0.0
            out.append(peer.exchange(r.SerializeToString()))
        return out
    run, out = session(exes["egm_pc"], tmp_path / "run", script)
    msgs = [egm.EgmSensorPathCorr.FromString(r) for r in out]
    assert [m.header.seqno for m in msgs] == list(range(1, 11))
    assert all(m.header.mtype == egm.EgmHeader.MSGTYPE_PATH_CORRECTION for m in msgs)
    pos = np.array([[m.pathCorr.pos.x, m.pathCorr.pos.y, m.pathCorr.pos.z] for m in msgs])
    assert np.allclose(pos[0], [0.25, -0.25, 0.25]) and np.allclose(pos[-1], [0.6, -0.6, 1.0])
    assert run.status == Status.COMPLETED and json.dumps(run.summary)


def test_egm_cartesian_guidance_echoes_the_orientation(exes, tmp_path):
    def script(peer: Peer):
        out = []
        for k in range(1, 6):
            r = egm.EgmRobot()
            r.header.seqno, r.header.tm = k, 4 * k
            r.feedBack.cartesian.pos.x, r.feedBack.cartesian.pos.y, r.feedBack.cartesian.pos.z = 500.0, 0.0, 800.0
            p = r.planned.cartesian
            p.pos.x, p.pos.y, p.pos.z = 500.0, 0.0, 800.0
            p.orient.u0, p.orient.u1, p.orient.u2, p.orient.u3 = 0.0, 1.0, 0.0, 0.0
            out.append(peer.exchange(r.SerializeToString()))
        return out
    run, out = session(exes["egm_cart"], tmp_path / "run", script)
    msgs = [egm.EgmSensor.FromString(r) for r in out]
    pos = np.array([[m.planned.cartesian.pos.x, m.planned.cartesian.pos.y, m.planned.cartesian.pos.z] for m in msgs])
    # from the planned start, at 0.4 mm per cycle towards feedback + (1, -1, 0.5)
    assert np.allclose(pos, [[500.0 + min(0.4 * k, 1.0), -min(0.4 * k, 1.0), 800.0 + min(0.4 * k, 0.5)] for k in range(1, 6)])
    assert [(m.planned.cartesian.orient.u0, m.planned.cartesian.orient.u1) for m in msgs] == [(0.0, 1.0)] * 5
    assert run.summary["replies"] == 5 and not any(m.planned.joints.joints for m in msgs)


def test_sensor_samples_that_are_old_malformed_or_non_finite_are_dropped_and_counted(exes, tmp_path):
    def script(peer: Peer):
        send = lambda line: peer.sensor_sock.sendto(line, peer.sensor_addr)  # noqa: E731
        replies = []
        for line in (b"GTS1 5 0.0 0.5\n", b"GTS1 3 0.0 0.7\n", b"GTS1 5 0.0 0.7\n", b"GTS1 6 0.0 nan\n", b"GTS1 7 0.0\n",
                     b"GTS1 8 0.0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17\n", b"garbage", b"GTS1 9 0.0 0.25\n"):
            send(line)
        time.sleep(0.05)
        replies.append(peer.exchange(rob(1000)))
        return replies
    run, replies = session(exes["rsi"], tmp_path / "run", script)
    assert run.stats["sensor"] == {"accepted": 2, "malformed": 3, "non_finite": 1, "duplicate_or_old": 2, "too_few_values": 0}
    log = read_cycle_log(run.log_path)
    assert log["x:sensor.0"].tolist() == [0.25] and replies[0] is not None  # the newest valid sample


def test_the_runtime_ends_cleanly_when_the_python_that_started_it_is_killed(exes, tmp_path):
    out = tmp_path / "run"
    code = f"from gtmodel.control.runtime import run_loop; run_loop({str(exes['rsi_plain'])!r}, {str(out)!r}, listen=('127.0.0.1', 0), idle_timeout=60)"
    parent = subprocess.Popen([sys.executable, "-c", code])
    try:
        ready = read_ready(out, 30)
        parent.kill()
        parent.wait(10)
        deadline = time.monotonic() + 10
        while not (out / "runtime_stats.json").exists() and time.monotonic() < deadline:
            time.sleep(0.05)
    finally:
        parent.kill()
        parent.wait()
    stats = json.loads((out / "runtime_stats.json").read_text())
    assert stats["end"] == "signal" and stats["signal"] == "SIGTERM"
    with pytest.raises(ProcessLookupError):
        for _ in range(100):  # the runtime's process is gone
            os.kill(ready["pid"], 0)
            time.sleep(0.05)
