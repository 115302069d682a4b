"""Trajectory plots draw the trajectory they are given (gtmodel.report.trajectory)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from gtmodel.report.trajectory import plot_forces, plot_overlay, plot_path_profile, plot_tcp_path
from ._figures import assert_line, assert_png


def _trajectory(scale=1.0, t0=0.0):
    t = t0 + np.linspace(0, 1, 51)
    s = t - t0
    traj = {"t": t, "x": scale * s, "y": scale * s**2, "z": -scale * s}
    for i in range(3):
        traj[f"tau{i + 1}"] = scale * 400 * np.sign(np.sin(2 * np.pi * s + i))
    return traj


@pytest.mark.parametrize("title, suptitle", [("demo", "demo: TCP path"), ("", "TCP path")])
def test_tcp_path_draws_displacements_and_projections(tmp_path, title, suptitle):
    traj, start, end = _trajectory(), np.array([0.0, 0.0, 0.0]), np.array([1.0, 1.0, -1.0])
    fig = plot_tcp_path(traj, start, end, tmp_path / "p.png", title=title)
    assert_png(tmp_path / "p.png")
    ax_t, ax_xy, ax_yz = fig.axes
    for c in "xyz":
        assert_line(ax_t, f"{c} - {c}(0)", traj["t"], traj[c] - traj[c][0])
    assert_line(ax_xy, "optimal path", traj["x"], traj["y"])
    assert_line(ax_yz, "optimal path", traj["y"], traj["z"])
    assert_line(ax_xy, "start", [start[0]], [start[1]])
    assert_line(ax_yz, "end", [end[1]], [end[2]])
    assert fig.get_suptitle() == suptitle


@pytest.mark.parametrize("limit", [[450, 450, 450], [300, 400, 500]])
def test_forces_draw_each_cart_force_and_its_limits(tmp_path, limit):
    traj = _trajectory()
    fig = plot_forces(traj, limit, tmp_path / "f.png")
    assert_png(tmp_path / "f.png")
    assert len(fig.axes) == 3
    for i, ax in enumerate(fig.axes):
        assert_line(ax, f"tau{i + 1}", traj["t"], traj[f"tau{i + 1}"])
        np.testing.assert_allclose(line_y(ax, "limit"), [limit[i], limit[i]])
    np.testing.assert_allclose([ax.get_ylim() for ax in fig.axes], [(-1.15 * lim, 1.15 * lim) for lim in limit], rtol=1e-6)
    assert [ax.get_ylabel() for ax in fig.axes] == ["tau1 [N]", "tau2 [N]", "tau3 [N]"]


def line_y(ax, label):
    return [ln for ln in ax.get_lines() if ln.get_label() == label][0].get_ydata()


@pytest.mark.parametrize("n_cases", [1, 3])
def test_overlay_draws_every_case_from_its_own_start_time(tmp_path, n_cases):
    trajs = {f"case {k}": _trajectory(scale=1.0 + k, t0=2.0 * k) for k in range(n_cases)}
    forces, tcp = plot_overlay(trajs, tmp_path)
    assert_png(tmp_path / "overlay_forces.png")
    assert_png(tmp_path / "overlay_tcp.png")
    for label, tr in trajs.items():
        for i, ax in enumerate(forces.axes):
            assert_line(ax, label, tr["t"] - tr["t"][0], tr[f"tau{i + 1}"])
        for ax, (a, b) in zip(tcp.axes, (("x", "y"), ("y", "z"), ("x", "z"))):
            assert_line(ax, label, tr[a], tr[b])


def test_path_profile_draws_s_dot_and_s_ddot(tmp_path):
    s = np.linspace(0.0, 1.0, 11)
    sol = SimpleNamespace(s=s, s_dot=np.sin(np.pi * s), s_ddot=np.cos(np.pi * s[:-1]))
    fig = plot_path_profile(sol, tmp_path / "s.png", title="demo")
    assert_png(tmp_path / "s.png")
    ax1, ax2 = fig.axes
    np.testing.assert_allclose(ax1.get_lines()[0].get_xydata(), np.column_stack([s, sol.s_dot]))
    step = ax2.get_lines()[0]
    np.testing.assert_allclose(step.get_xdata(), s[:-1])
    np.testing.assert_allclose(step.get_ydata(), sol.s_ddot)
