"""Plots are written headless as PNG files (no screen; matplotlib's object API)."""

from __future__ import annotations

import numpy as np

from gtmodel.report.trajectory import plot_forces, plot_tcp_path

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _trajectory():
    t = np.linspace(0, 1, 51)
    traj = {"t": t, "x": t, "y": t**2, "z": -t}
    for i in range(3):
        traj[f"tau{i + 1}"] = 400 * np.sign(np.sin(2 * np.pi * t + i))
    return traj


def test_tcp_path_png(tmp_path):
    out = plot_tcp_path(_trajectory(), [0, 0, 0], [1, 1, -1], tmp_path / "p.png", title="demo")
    assert out.read_bytes()[:8] == PNG_MAGIC


def test_forces_png(tmp_path):
    out = plot_forces(_trajectory(), [450, 450, 450], tmp_path / "f.png")
    assert out.read_bytes()[:8] == PNG_MAGIC
