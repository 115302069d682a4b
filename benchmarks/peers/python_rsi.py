"""The peer of benchmarks/bench_loop.py: an RSI sensor server in plain Python, as Cvitanic (2021) ran one.

Usage: python benchmarks/peers/python_rsi.py --port PORT --sensor-port PORT2 --gain K [--cycles N]

The same law as loops/kr500_rsi_correction.toml (eq. (33): the total correction
``u += K (RSol - 1000 tracker)``, limited to +-5 mm and 0.1 mm per cycle; RSI's relative mode:
the increment is sent), written the way a hand-written server is: ``xml.etree`` for ``<Rob>``,
an f-string for ``<Sen>``, the tracker's ``GTS1`` datagrams read between robot packets. It
serves until the robot has been silent for 1 s after its first packet, then prints one JSON
line with its own receive-to-send latencies (ms) and exits.
"""

from __future__ import annotations

import argparse
import json
import select
import socket
import time
import xml.etree.ElementTree as ET

import numpy as np

LIMIT_MM, RATE_MM = 5.0, 0.1


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--port", type=int, required=True)
    ap.add_argument("--sensor-port", type=int, required=True)
    ap.add_argument("--gain", type=float, default=0.04)
    args = ap.parse_args()
    robot = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    robot.bind(("127.0.0.1", args.port))
    sensor = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sensor.bind(("127.0.0.1", args.sensor_port))
    sensor.setblocking(False)
    print(json.dumps({"ready": True}), flush=True)
    tracker = np.zeros(3)
    total = np.zeros(3)
    latencies: list[float] = []
    started = False
    while True:
        ready, _, _ = select.select([robot, sensor], [], [], 1.0)
        if not ready:
            if started:
                break
            continue
        if sensor in ready:
            while True:
                try:
                    line = sensor.recv(512).decode("ascii", "replace").split()
                except BlockingIOError:
                    break
                if len(line) >= 6 and line[0] == "GTS1":
                    tracker = np.array([float(v) for v in line[3:6]])
        if robot in ready:
            data, peer = robot.recvfrom(4096)
            t0 = time.perf_counter()
            started = True
            try:
                root = ET.fromstring(data)
                ipoc = root.findtext("IPOC").strip()
                rsol = root.find("RSol")
                r = np.array([float(rsol.get(a)) for a in "XYZ"])
            except (ET.ParseError, AttributeError, TypeError, ValueError):
                continue
            new = np.clip(total + args.gain * (r - 1000.0 * tracker), -LIMIT_MM, LIMIT_MM)
            new = np.clip(new, total - RATE_MM, total + RATE_MM)
            inc, total = new - total, new
            reply = (f'<Sen Type="ImFree"><EStr>python</EStr><RKorr X="{inc[0]:.6f}" Y="{inc[1]:.6f}" Z="{inc[2]:.6f}" '
                     f'A="0.000000" B="0.000000" C="0.000000"/><IPOC>{ipoc}</IPOC></Sen>')
            robot.sendto(reply.encode("ascii"), peer)
            latencies.append((time.perf_counter() - t0) * 1e3)
    lat = np.asarray(latencies) if latencies else np.full(1, np.nan)
    print(json.dumps({"replies": len(latencies), "p50": float(np.percentile(lat, 50)), "p99": float(np.percentile(lat, 99)),
                      "max": float(np.max(lat))}), flush=True)


if __name__ == "__main__":
    main()
