"""Kind ``robot_loop``: the loop file, and ``gtmodel loop`` against the robot-side simulators.

References (independent of the runtime's code):
- the simulators of :mod:`gtmodel.robot_sim` (the robot's side, written from the public
  protocol descriptions; their truth records the TCP the tracker saw);
- the open loop on the same plant, noise and seed (Cvitanic (2021), sec. 5: the correction
  must at least halve the TCP path error, issue 48);
- the offline ILC on the same plant model stepped without the network, the same law
  (Dressler (2012), eq. 7.2: ``u_1 = Q (u_0 + L eps_0)``): one iteration through EGM and the
  log must reduce the tracking error as the offline iteration does, within 20 %.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import socket
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest

from gtmodel.codegen.robot_loop import hour_of_log_mb
from gtmodel.errors import ProblemError
from gtmodel.estimation.ilc.iteration import error_measure, next_correction
from gtmodel.estimation.ilc.lifted import LearningFilter, QFilter, time_window
from gtmodel.problems.run import load_problem
from gtmodel.robot_sim.plants import make_plant
from gtmodel.robot_sim.run import simulate
from gtmodel.robot_sim.state import Command
from gtmodel.status import Status

from ...conftest import REPO
from ...robot_sim.realtime import skip_when_busy

LOOPS = REPO / "loops"
RSI_FILE = LOOPS / "kr500_rsi_correction.toml"
EGM_FILE = LOOPS / "l1_egm_ilc.toml"


def _copy(tmp_path: Path, source: Path, replace: dict[str, str]) -> Path:
    text = source.read_text(encoding="utf-8")
    for old, new in replace.items():
        assert old in text, old
        text = text.replace(old, new)
    target = tmp_path / source.name
    target.write_text(text, encoding="utf-8")
    if (source.parent / "data").is_dir() and not (tmp_path / "data").exists():
        shutil.copytree(source.parent / "data", tmp_path / "data")
    return target


@pytest.mark.parametrize("path", [RSI_FILE, EGM_FILE], ids=lambda p: p.stem)
def test_shipped_loop_files_load(path):
    problem = load_problem(path)
    d = problem.declaration
    assert (problem.kind, d.spec.interface, len(d.spec.outputs)) == ("robot_loop", tomllib.loads(path.read_text())["interface"]["type"], 3)


def test_settings_from_the_command_line_reach_the_declaration():
    d = load_problem(RSI_FILE, settings={"interface.listen": "127.0.0.1:40000", "interface.sensor_port": 40010,
                                         "interface.robot": "127.0.0.5"}).declaration
    assert (d.listen, d.sensor_port, d.robot, d.tracker, d.log_max_mb) == (("127.0.0.1", 40000), 40010, "127.0.0.5", "127.0.0.1", None)


def test_the_default_log_cap_fits_an_hour_at_250_hz():
    """Independent: the widest row the runtime can write, counted here from its columns, times 900,000 rows (an hour at 4 ms).

    Leading columns: cycle and IPOC (20 digits each), t and latency (%.17g: 24 characters), flags (6),
    status and sensor age (11 each), 6 commas, the newline; then per number a comma and 24 characters.
    """
    d = load_problem(RSI_FILE).declaration
    numbers = len(d.spec.inputs) + 4 * len(d.spec.outputs)  # x, u, reply, sent (relative)
    widest_row = 20 + 20 + 24 + 6 + 11 + 24 + 11 + 6 + 1 + numbers * 25
    assert hour_of_log_mb(d.spec) * 1048576 >= 900_000 * widest_row and hour_of_log_mb(d.spec) == 494.0


CLI_BAD = [
    (["--listen", "localhost:49152"], r"--listen: expected HOST:PORT with an IPv4 address"),
    (["--listen", "127.0.0.1:0"], r"--listen: expected HOST:PORT"),
    (["--robot", "robot.local"], r"--robot: expected an IPv4 address, optionally with :PORT"),
    (["--sensor-port", "70000"], r"--sensor-port: expected an integer in 1..65535, got 70000"),
    (["--idle-timeout", "0"], r"--idle-timeout: expected a number in \(0, 3600\] s"),
    (["--listen", "8.8.8.8:49152"], r"--listen: expected an address of this machine .*8.8.8.8 is not one of its interfaces' addresses"),
    (["--listen", "127.0.0.1:\u0664\u0669\u0661\u0665\u0662"], r"--listen: expected HOST:PORT with an IPv4 address"),
    (["--robot", "127.0.0.1:\u0664\u0669"], r"--robot: expected an IPv4 address, optionally with :PORT"),
]

#: Options argparse refuses by their type (exit 2 before anything runs, the option named).
CLI_TYPES = [
    (["--sensor-port", "\u0664\u0669\u0661\u0665\u0663"], r"argument --sensor-port: expected an integer in ASCII digits"),
    (["--max-cycles", "\uff11\uff10"], r"argument --max-cycles: expected an integer in ASCII digits"),
    (["--idle-timeout", "\u0661.5"], r"argument --idle-timeout: expected a number in ASCII digits"),
]


@pytest.mark.parametrize("argv, match", CLI_TYPES, ids=[a[0] for a, _ in CLI_TYPES])
def test_digits_of_other_scripts_are_refused_by_the_option(tmp_path, capsys, argv, match):
    from gtmodel.cli import main

    with pytest.raises(SystemExit) as stop:
        main(["loop", str(RSI_FILE), "--out", str(tmp_path / "out"), *argv])
    err = capsys.readouterr().err
    assert (stop.value.code, bool(re.search(match, err)), (tmp_path / "out").exists()) == (2, True, False), err


@pytest.mark.parametrize("argv, match", CLI_BAD, ids=[a[0] for a, _ in CLI_BAD])
def test_bad_command_line_values_name_the_option_not_the_file(tmp_path, capsys, argv, match):
    from gtmodel.cli import main

    code = main(["loop", str(RSI_FILE), "--out", str(tmp_path / "out"), *argv])
    err = capsys.readouterr().err
    assert code == 2 and re.search(match, err) and "interface." not in err and not (tmp_path / "out").exists()


BAD = [
    ({'type = "rsi"': 'type = "kuka"'}, RSI_FILE, r"'interface.type': expected one of rsi, egm"),
    ({'listen = "127.0.0.1:49152"': 'listen = "localhost:49152"'}, RSI_FILE, r"'interface.listen': expected HOST:PORT with an IPv4 address"),
    ({'listen = "127.0.0.1:49152"': 'listen = "127.0.0.1:70000"'}, RSI_FILE, r"'interface.listen': expected HOST:PORT.*got '127.0.0.1:70000'"),
    ({'sensor_port = 49153': 'sensor_port = 49152'}, RSI_FILE, r"'interface.sensor_port': expected a port other than the listen port"),
    ({'sen_type = "ImFree"': 'sen_type = "Im\\"/><x"'}, RSI_FILE, r"'interface.sen_type': expected 1 to 32 ASCII letters, digits or '_'"),
    ({'gain = [0.04, 0.04, 0.04]': 'gain = [0.04, 1.5, 0.04]'}, RSI_FILE, r"'controller.gain': expected numbers of magnitude <= 1"),
    ({'gain = [0.04, 0.04, 0.04]': 'gain = [0.04, 0.04]'}, RSI_FILE, r"'controller.gain': expected a list of 3 finite numbers"),
    ({'rate = [0.1, 0.1, 0.1]': 'rate = [0.1, 0.1]'}, RSI_FILE, r"'limits': expected one value per output in each of lower, upper, rate"),
    ({'lower = [-5.0, -5.0, -5.0]': 'lower = [6.0, -5.0, -5.0]'}, RSI_FILE, r"'limits': expected lower <= upper per output"),
    ({'period = 0.004                     # s, the KR C4': 'period = -0.004                    # s, the KR C4'}, RSI_FILE,
     r"'interface.period': expected a positive number"),
    ({'type = "pose_correction"': 'type = "streaming"'}, RSI_FILE, r"'controller': expected a trajectory for streaming"),
    ({'trajectory = "data/l1_square.csv"': 'trajectory = "data/missing.csv"'}, EGM_FILE, r"controller.trajectory"),
    ({'trajectory = "data/l1_square.csv"': 'trajectory = "../../../etc/passwd"'}, EGM_FILE, r"controller.trajectory"),
    ({'lower = [-110.0, 25.0, 0.0]': 'lower = [-110.0, 25.0]'}, EGM_FILE, r"'limits': expected one value per output in each of lower, upper, rate"),
    ({'upper = [-65.0, 70.0, 45.0]': 'upper = [-95.0, 70.0, 45.0]'}, EGM_FILE, r"'controller.trajectory': reference: expected every row within the bounds"),
    ({'type = "pose_correction"': 'type = "pose_correction"\ntrajectory = "x.csv"'}, RSI_FILE,
     r"'controller': expected no trajectory or correction_file for a pose_correction"),
    ({'fallback = "hold"': 'fallback = "hold"\n[ilc]'}, RSI_FILE, r"expected no \[ilc\] table"),
    ({'type = "rsi"': 'type = "egm"'}, RSI_FILE, r"expected interface.type = \"rsi\" for a pose_correction"),
    ({'gamma = 0.9': 'gamma = 5.0'}, EGM_FILE, r"'ilc.gamma': expected a number <= 2"),
    # [ilc] against the trajectory (352 rows) and the period (Nyquist 125 Hz), refused on load, before the robot runs
    ({'q_cutoff_hz = 10.0': 'q_cutoff_hz = 1000.0'}, EGM_FILE, r"l1_egm_ilc.toml: field 'ilc.q_cutoff_hz': cutoff_hz: expected a cut-off in \["),
    ({'q_cutoff_hz = 10.0': 'q_cutoff_hz = 0.001'}, EGM_FILE, r"field 'ilc.q_cutoff_hz': cutoff_hz: expected a cut-off in \["),
    ({'lead = 100': 'lead = 200'}, EGM_FILE, r"field 'ilc.lead': lead: the window \(lead-in \+ lead-out = 400 samples\) is longer"),
    ({'tukey_points = 200': 'tukey_points = 300'}, EGM_FILE, r"field 'ilc.tukey_points': tukey_points: expected at most 2 \* lead = 200"),
    ({'delta = 5 ': 'delta = 400 '}, EGM_FILE, r"field 'ilc.delta': expected a learning lead shorter than the trajectory \(352 rows\)"),
    ({'robot = "127.0.0.1"': 'robot = "192.168.1.300"'}, EGM_FILE,
     r"'interface.robot': expected an IPv4 address, optionally with :PORT"),
    ({'period = 0.004                     # s\n': 'period = 0.004\ntracker = "10.0.0.1:0"\n'}, EGM_FILE, r"'interface.tracker': expected an IPv4 address"),
    ({'period = 0.004                     # s\n': 'period = 0.004\ntracker = "10.0.0.1"\n'}, EGM_FILE,
     r"'interface.tracker': expected no tracker for a streaming loop"),
    ({'period = 0.004                     # s\n': 'period = 0.004\nlog_max_mb = 0\n'}, EGM_FILE, r"'interface.log_max_mb': expected a positive number"),
    # issue 67, item 7: addresses and deadlines named at load, before any code is generated or built
    ({'listen = "127.0.0.1:49152"': 'listen = "8.8.8.8:49152"'}, RSI_FILE,
     r"'interface.listen': expected an address of this machine \(0.0.0.0: every interface, 127.0.0.1: this machine only\); 8.8.8.8 is not"),
    ({'listen = "127.0.0.1:49152"': 'listen = "127.0.0.1:\u0664\u0669\u0661\u0665\u0662"'}, RSI_FILE,
     r"'interface.listen': expected HOST:PORT with an IPv4 address and a port in 1..65535"),
    ({'listen = "127.0.0.1:49152"': 'listen = "127.0.0.1:\uff14\uff19\uff11\uff15\uff12"'}, RSI_FILE,
     r"'interface.listen': expected HOST:PORT with an IPv4 address"),
    ({'robot = "127.0.0.1"': 'robot = "127.0.0.1:\u0664\u0669"'}, EGM_FILE, r"'interface.robot': expected an IPv4 address, optionally with :PORT"),
    ({'reply_deadline = 0.002': 'reply_deadline = 0.004'}, RSI_FILE,
     r"'interface.reply_deadline': expected a deadline shorter than the period \(0.004 s\).*got 0.004"),
    ({'reply_deadline = 0.002': 'reply_deadline = 0.009'}, EGM_FILE, r"'interface.reply_deadline': expected a deadline shorter than the period"),
    ({'period = 0.004                     # s, the KR C4': 'period = 0.001                     # s, the KR C4'}, RSI_FILE,
     r"'interface.reply_deadline': expected a deadline shorter than the period \(0.001 s\)"),
]


@pytest.mark.parametrize("replace, source, match", BAD, ids=[m for _, _, m in BAD])
def test_bad_loop_files_are_refused_naming_the_field(tmp_path, replace, source, match):
    with pytest.raises(ProblemError, match=match):
        load_problem(_copy(tmp_path, source, replace))


def test_a_correction_file_of_another_length_is_refused(tmp_path):
    path = _copy(tmp_path, EGM_FILE, {})
    (tmp_path / "short.csv").write_text("t,q1,q2,q3\n0,0,0,0\n0.004,0,0,0\n", encoding="utf-8")
    with pytest.raises(ProblemError, match=r"'controller.correction_file': expected the trajectory's 352 rows"):
        load_problem(path, settings={"controller.correction_file": "short.csv"})


# -- gtmodel loop against the simulators (a child process each, as a user runs them) ---------------------


def _free_port(pair: bool = False) -> int:
    for _ in range(50):
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        if port < 65000 and (not pair or _port_free(port + 1)):
            return port
    raise RuntimeError("no free UDP port pair")


def _port_free(port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        try:
            s.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def _bound(port: int) -> bool:
    """Whether a UDP socket is bound to the port (Linux: /proc/net/udp)."""
    try:
        rows = Path("/proc/net/udp").read_text().splitlines()[1:]
    except OSError:
        return not _port_free(port)
    return any(int(r.split()[1].split(":")[1], 16) == port for r in rows)


class Loop:
    """``gtmodel loop FILE --out DIR --listen 127.0.0.1:PORT`` as a child process, ready when its runtime is bound."""

    def __init__(self, path: Path, out: Path, port: int, *extra: str) -> None:
        self.out, self.port = out, port
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
        self.proc = subprocess.Popen([sys.executable, "-m", "gtmodel", "loop", str(path), "--out", str(out), "--listen", f"127.0.0.1:{port}",
                                      "-q", *extra], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        deadline = time.monotonic() + 240.0
        while not _bound(port):
            if self.proc.poll() is not None or time.monotonic() > deadline:
                self.proc.kill()
                raise AssertionError(f"gtmodel loop did not start: {self.proc.communicate()}")
            time.sleep(0.1)

    def finish(self) -> dict:
        out, err = self.proc.communicate(timeout=120)
        assert self.proc.returncode == 0, (out, err)
        return {**json.loads((self.out / "summary.json").read_text()), "loop_folder": str(self.out)}


def _rsi_run(tmp_path: Path, name: str, gain: str, faults: str | None = None, duration: float = 4.0):
    port = _free_port(pair=True)
    path = _copy(tmp_path / name, RSI_FILE, {"gain = [0.04, 0.04, 0.04]": f"gain = {gain}"}) if gain else RSI_FILE
    loop = Loop(path, tmp_path / f"{name}_loop", port, "--sensor-port", str(port + 1), "--idle-timeout", "1.0")
    sim = simulate("rsi", "kr500", ("127.0.0.1", port), ("127.0.0.1", port + 1), duration_s=duration, seed=3, faults=faults,
                   out_dir=tmp_path / f"{name}_sim")
    return loop.finish(), sim


@pytest.fixture(scope="module")
def kr500_runs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("kr500")
    (tmp / "open").mkdir()
    return {"open": _rsi_run(tmp, "open", "[0.0, 0.0, 0.0]"), "closed": _rsi_run(tmp, "closed", "")}


@pytest.mark.slow
def test_kr500_correction_halves_the_tcp_path_error(kr500_runs):
    """Issue 48: with the loop closed the TCP path error is at most half the open-loop error (same plant, noise, seed)."""
    (_, open_sim), (closed, closed_sim) = kr500_runs["open"], kr500_runs["closed"]
    assert (closed["status"], closed_sim.status, open_sim.status) == ("completed", Status.COMPLETED, Status.COMPLETED)
    ratio = closed_sim.summary["error_rms_mm"] / open_sim.summary["error_rms_mm"]
    assert ratio <= 0.5, (closed_sim.summary["error_rms_mm"], open_sim.summary["error_rms_mm"])


@pytest.mark.slow
def test_kr500_every_reply_echoes_and_keeps_its_limits(kr500_runs):
    """Counts that do not depend on the wall clock: every cycle answered, echoed, logged; a cycle without a reply only where
    the deadline rule dropped a reply computed past the period (a machine's pause can cause one; those are counted in the
    real-time step, below)."""
    summary, sim = kr500_runs["closed"]
    loop = summary["loop"]
    assert (loop["missing_replies"] - loop["faults"]["late_dropped"]["count"], sim.summary["mismatched_replies"]) == (0, 0)
    assert loop["log"]["dropped"] == 0 and loop["log"]["rows"] == loop["cycles"] == sim.summary["cycles_sent"]


@pytest.mark.slow
@pytest.mark.realtime
def test_kr500_every_reply_comes_within_its_deadline(request, kr500_runs):
    """A wall-clock count (a busy machine makes a reply late): in the real-time step, skipped when the load is over the cores."""
    skip_when_busy(request.node)
    summary, sim = kr500_runs["closed"]
    assert (summary["loop"]["late_replies"], summary["loop"]["faults"]["late_dropped"]["count"], sim.summary["late"]) == (0, 0, 0)


@pytest.mark.slow
def test_kr500_every_file_of_the_folder_is_described_and_shown(kr500_runs, tmp_path_factory):
    """As every kind's (tests/problems/test_base.py): a loop's folder is checked here, where a robot serves it."""
    import html

    summary, _ = kr500_runs["closed"]
    out = Path(summary["loop_folder"])
    on_disk = sorted(p.name for p in out.iterdir())
    described = summary["file_descriptions"]
    page = (out / "report.html").read_text(encoding="utf-8")
    files_section = page[page.index('<h2 id="files">'):]
    shown = [f for f in on_disk if (out / f).is_file() and html.escape(described[f], quote=True) not in files_section]
    assert ([f for f in on_disk if f not in described], sorted(summary["files"]) == on_disk, shown) == ([], True, [])


@pytest.mark.slow
def test_faults_end_in_the_documented_fallbacks_without_a_crash(tmp_path):
    faults = "garbage:rate=0.02;nan:rate=0.02;duplicate:rate=0.02;loss:rate=0.02;reorder:rate=0.01;delay:cycles=300-310;stop:at=700"
    summary, sim = _rsi_run(tmp_path, "faults", "", faults=faults, duration=4.0)
    loop = summary["loop"]
    assert summary["status"] == "completed" and loop["end"] == "idle_timeout"
    seen = {k: v["count"] for k, v in loop["faults"].items() if v["count"]}
    assert {"malformed", "non_finite", "duplicate_or_old"} <= set(seen), seen
    from gtmodel.control.runtime import read_cycle_log

    log = read_cycle_log(tmp_path / "faults_loop" / "cycle_log.csv")
    reply = np.column_stack([log[f"reply:RKorr.{a}"] for a in "XYZ"])
    sent = np.isfinite(reply).all(axis=1)
    assert np.all(np.abs(reply[sent]) <= 5.0 + 1e-9)  # the file's limits, in every reply sent
    assert np.all(np.abs(np.diff(reply[sent], axis=0)) <= 0.1 + 1e-9)  # its rate per cycle
    assert np.all(np.isfinite(np.column_stack([log[c] for c in log if c.startswith("x:")])[(log["flags"].astype(int) & 2) > 0]))
    # the log complete up to the stop: a row per cycle, malformed datagrams counted, not logged
    assert loop["log"]["dropped"] == 0 and loop["log"]["rows"] == loop["cycles"] == loop["packets"] - loop["faults"]["malformed"]["count"]
    # independent: what the simulated robot held (its own sum of the increments it applied, late ones not) within the file's limits
    held = np.column_stack([sim.column(f"correction_{a}_mm") for a in "xyz"])
    assert np.all(np.abs(held) <= 5.0 + 1e-9), np.abs(held).max()


def _offline_ilc_ratio(reference_mm: np.ndarray, ilc: dict, dt: float) -> float:
    """One ILC iteration on the L1 servo plant stepped without the network (the simulators' model, no noise)."""
    def trial(u: np.ndarray) -> np.ndarray:
        plant = make_plant("l1", np.random.default_rng(0), encoder_noise_mm=0.0, gauge_noise_mm=0.0)
        y = np.zeros_like(reference_mm)
        for k in range(len(reference_mm)):
            y[k] = plant.state().joints_actual[:3]
            plant.step(Command(cart=None, joints=reference_mm[k] + u[k], mode="absolute", positions=True))
        return reference_mm - y

    window = time_window(len(reference_mm), lead=ilc["lead"], tukey_points=ilc["tukey_points"], alpha=ilc["tukey_alpha"])
    eps0 = trial(np.zeros_like(reference_mm))
    u1 = next_correction(np.zeros_like(reference_mm), eps0, QFilter(ilc["q_cutoff_hz"], dt=dt, window=window),
                         LearningFilter(ilc["gamma"], ilc["delta"]))
    mask = window >= 1.0
    return float(np.mean(error_measure(trial(u1), mask)) / np.mean(error_measure(eps0, mask)))


@pytest.mark.slow
def test_l1_one_ilc_iteration_through_egm_reduces_the_error_as_offline(tmp_path):
    """Dressler's experiment loop closed through EGM: run 0, learn from its log, run 1 with the learned correction."""
    results = []
    correction: list[str] = []
    for i in range(2):
        port = _free_port()
        loop = Loop(EGM_FILE, tmp_path / f"loop{i}", port, "--idle-timeout", "0.5", *correction)
        sim = simulate("egm", "l1", ("127.0.0.1", port), duration_s=1.6, seed=i, out_dir=tmp_path / f"sim{i}")
        results.append((loop.finish(), sim))
        correction = ["--correction-file", str(tmp_path / f"loop{i}" / "ilc_next.csv")]
    states = [(s["status"], sim.status, s["loop"]["missing_replies"]) for s, sim in results]
    assert states == [("completed", Status.COMPLETED, 0)] * 2
    results = [s for s, _ in results]
    through_egm = np.mean(results[1]["ilc"]["error_rms"]) / np.mean(results[0]["ilc"]["error_rms"])
    doc = tomllib.loads(EGM_FILE.read_text())
    reference = np.loadtxt(LOOPS / "data" / "l1_square.csv", delimiter=",", skiprows=1)[:, 1:]
    offline = _offline_ilc_ratio(reference, doc["ilc"], doc["interface"]["period"])
    assert through_egm < 1.0
    assert abs(through_egm - offline) <= 0.2 * offline, (through_egm, offline)


@pytest.mark.slow
def test_egm_a_stranger_sending_first_and_throughout_is_never_served_nor_learned_from(tmp_path):
    """The hostile probe through ``gtmodel loop``: a stranger on 127.0.0.2 sends EgmRobot first and every 4 ms.

    Independent: the stranger's socket counts what it got; the simulated robot's record says where it was
    commanded from its first cycle (EGM's rate limit of the file, 1 mm per cycle, from its measured start).
    """
    import threading

    from gtmodel import _egm_pb2

    port = _free_port()
    loop = Loop(EGM_FILE, tmp_path / "loop", port, "--idle-timeout", "0.5")
    stranger = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    stranger.bind(("127.0.0.2", 0))
    stranger.settimeout(0.004)
    got, stop = [], threading.Event()

    def send():
        k = 0
        while not stop.is_set():
            k += 1
            m = _egm_pb2.EgmRobot()
            m.header.seqno, m.header.tm = k, 4 * k
            m.feedBack.joints.joints.extend([-67.0, 68.0, 43.0])
            m.planned.joints.joints.extend([-67.0, 68.0, 43.0])
            stranger.sendto(m.SerializeToString(), ("127.0.0.1", port))
            try:
                got.append(stranger.recv(65536))
            except socket.timeout:
                pass
    sender = threading.Thread(target=send, daemon=True)
    sender.start()
    time.sleep(0.2)  # the stranger first
    sim = simulate("egm", "l1", ("127.0.0.1", port), duration_s=1.6, seed=0, out_dir=tmp_path / "sim")
    summary = loop.finish()  # the robot's silence ends the session, whatever the stranger sends
    stop.set()
    sender.join(2.0)
    stranger.close()
    run = summary["loop"]
    assert (got, summary["status"], run["missing_replies"], run["source"]["robot_rule"]) == ([], "completed", 0, "named_address_first_port")
    assert run["strangers"]["datagrams"] > 50 and {a["address"].split(":")[0] for a in run["strangers"]["addresses"]} == {"127.0.0.2"}
    commanded = np.column_stack([sim.column(f"reference_q{i}_mm") for i in (1, 2, 3)])
    assert np.all(np.abs(np.diff(commanded, axis=0)) <= 1.0 + 1e-9)  # the file's rate from the robot's own start: no jump
    assert summary["ilc"]["rows_logged"] > 0 and np.all(np.isfinite(summary["ilc"]["error_rms"]))


@pytest.mark.slow
def test_ctrl_c_ends_the_loop_with_its_folder_written(tmp_path):
    """SIGINT to ``gtmodel loop`` stops the runtime cleanly: exit 130 (interrupted), summary and cycle log written."""
    import signal

    loop = Loop(EGM_FILE, tmp_path / "loop", _free_port())
    sim = simulate("egm", "l1", ("127.0.0.1", loop.port), duration_s=0.4, seed=0, out_dir=tmp_path / "sim")
    loop.proc.send_signal(signal.SIGINT)
    loop.proc.communicate(timeout=60)
    summary = json.loads((tmp_path / "loop" / "summary.json").read_text())
    assert (loop.proc.returncode, summary["status"], summary["loop"]["end"], sim.status) == (130, "interrupted", "signal", Status.COMPLETED)
    assert summary["loop"]["cycles"] == sim.summary["cycles_sent"] and (tmp_path / "loop" / "cycle_log.csv").is_file()
