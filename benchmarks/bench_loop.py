"""The robot runtime's reply latency against a hand-written Python RSI server, on the same simulated robot (a benchmark, not a test).

Usage: python benchmarks/bench_loop.py [--cycles 15000] [--rounds 3] [--json]

Measured side by side in one run, alternated in ``--rounds`` rounds of ``cycles / rounds``
cycles each (a noisy machine's load falls on both):

- **gtmodel**: the runtime of ``loops/kr500_rsi_correction.toml`` (the pose correction's generated
  step behind RSI, built by :func:`gtmodel.codegen.robot_runtime.build_runtime`, run by
  :func:`gtmodel.control.runtime.run_loop`);
- **the peer**: ``benchmarks/peers/python_rsi.py``, the same law and limits in a plain Python
  server (``xml.etree``, an f-string reply), the set-up Cvitanic (2021) ran on the KR C4;

both serving ``gtmodel robot-sim``'s KR 500 (:func:`gtmodel.robot_sim.run.simulate`, the robot's
own 4 ms clock, the tracker at 1000 Hz) in this process. Figures: the robot side's reply
latency (send to reply received, the sim's ``reply_latency_ms``: what RSI's deadline sees) p50,
p99 and max, late replies (after the robot's next send), and the server's own receive-to-send
latency; ``ratio_p99`` is gtmodel's robot-side p99 over the peer's (below 1: gtmodel faster).
With ``--json`` the last line of stdout is one JSON object ``{"loop": {...}}``.
"""

from __future__ import annotations

import argparse
import json
import socket
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from gtmodel.codegen.loop_step import position_step  # noqa: E402
from gtmodel.codegen.robot_runtime import RobotRuntime, build_runtime  # noqa: E402
from gtmodel.control.runtime import read_ready, run_loop  # noqa: E402
from gtmodel.problems.run import load_problem  # noqa: E402
from gtmodel.robot_sim.run import simulate  # noqa: E402

LOOP_FILE = REPO / "loops" / "kr500_rsi_correction.toml"
PEER = REPO / "benchmarks" / "peers" / "python_rsi.py"


def _ports() -> int:
    while True:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        try:
            with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
                s.bind(("127.0.0.1", port + 1))
            return port
        except OSError:
            continue


def _gtmodel_round(exe: Path, work: Path, cycles: int, seed: int) -> dict:
    port = _ports()
    out = work / f"run_{seed}"
    result: dict = {}
    thread = threading.Thread(target=lambda: result.update(run=run_loop(exe, out, listen=("127.0.0.1", port), sensor_port=port + 1,
                                                                          idle_timeout=1.0)))
    thread.start()
    read_ready(out, timeout=30.0)
    sim = simulate("rsi", "kr500", ("127.0.0.1", port), ("127.0.0.1", port + 1), duration_s=cycles * 0.004, seed=seed,
                   out_dir=work / f"sim_{seed}")
    thread.join()
    lat = result["run"].summary.get("reply_latency_ms", {})
    return {"robot": sim.summary, "server": {"p50": lat.get("p50"), "p99": lat.get("p99"), "max": lat.get("max")},
            "status": str(result["run"].status)}


def _peer_round(work: Path, cycles: int, seed: int, gain: float) -> dict:
    port = _ports()
    proc = subprocess.Popen([sys.executable, str(PEER), "--port", str(port), "--sensor-port", str(port + 1), "--gain", repr(gain)],
                            stdout=subprocess.PIPE, text=True)
    proc.stdout.readline()  # {"ready": true}: bound
    sim = simulate("rsi", "kr500", ("127.0.0.1", port), ("127.0.0.1", port + 1), duration_s=cycles * 0.004, seed=seed,
                   out_dir=work / f"peer_sim_{seed}")
    server = json.loads(proc.communicate(timeout=60)[0].strip().splitlines()[-1])
    return {"robot": sim.summary, "server": server, "status": str(sim.status)}


def _pooled(rounds: list[dict], side: str, key: str) -> float:
    values = [r[side][key] for r in rounds if r[side].get(key) is not None]
    return float(np.max(values)) if key == "max" else float(np.median(values))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=int, default=15000, help="robot cycles per contender, over all rounds (default 15000: 60 s)")
    ap.add_argument("--rounds", type=int, default=3, help="alternated rounds (default 3)")
    ap.add_argument("--json", action="store_true", help="end with one JSON line")
    args = ap.parse_args()
    decl = load_problem(LOOP_FILE).declaration
    per_round = max(1, args.cycles // args.rounds)
    with tempfile.TemporaryDirectory(prefix="bench-loop-") as tmp:
        work = Path(tmp)
        exe = build_runtime(RobotRuntime(position_step(decl.controller, "bench"), decl.spec), work / "code", prefix="gt_bench")
        ours, peer = [], []
        for k in range(args.rounds):
            ours.append(_gtmodel_round(exe, work, per_round, k))
            peer.append(_peer_round(work, per_round, k, float(decl.controller.gain[0])))
    row = {"cycles_per_round": per_round, "rounds": args.rounds}
    for name, rounds in (("gtmodel", ours), ("python", peer)):
        row[f"{name}_robot_latency_ms"] = {q: _pooled([{"r": r["robot"]["reply_latency_ms"]} for r in rounds], "r", q) for q in ("p50", "p99", "max")}
        row[f"{name}_server_latency_ms"] = {q: _pooled(rounds, "server", q) for q in ("p50", "p99", "max")}
        row[f"{name}_late_replies"] = int(sum(r["robot"]["late"] for r in rounds))
        row[f"{name}_replies"] = int(sum(r["robot"]["replies"] for r in rounds))
        row[f"{name}_tcp_error_rms_mm"] = float(np.mean([r["robot"]["error_rms_mm"] for r in rounds]))
    row["ratio_p99"] = row["gtmodel_robot_latency_ms"]["p99"] / row["python_robot_latency_ms"]["p99"]
    row["ratio_server_p99"] = row["gtmodel_server_latency_ms"]["p99"] / row["python_server_latency_ms"]["p99"]
    print(f"reply latency p99, robot side: gtmodel {row['gtmodel_robot_latency_ms']['p99']:.3f} ms, Python server "
          f"{row['python_robot_latency_ms']['p99']:.3f} ms: ratio {row['ratio_p99']:.2f}")
    print(f"receive to send p99, server side: gtmodel {row['gtmodel_server_latency_ms']['p99']:.4f} ms, Python "
          f"{row['python_server_latency_ms']['p99']:.4f} ms: ratio {row['ratio_server_p99']:.3f}")
    print(f"late replies: gtmodel {row['gtmodel_late_replies']} of {row['gtmodel_replies']}, Python {row['python_late_replies']} of "
          f"{row['python_replies']}; TCP path error RMS {row['gtmodel_tcp_error_rms_mm']:.3f} / {row['python_tcp_error_rms_mm']:.3f} mm")
    if args.json:
        print(json.dumps({"loop": row}))


if __name__ == "__main__":
    main()
