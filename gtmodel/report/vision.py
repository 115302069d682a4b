"""Plots of the stereo-vision calibration (Dressler (2012), ch. 5.5, Figures 5.15-5.19)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import numpy as np

from gtmodel.report._figure import new_figure, panel_size, save

__all__ = ["plot_camera_views", "plot_reconstruction", "plot_vision_errors"]


def plot_camera_views(cameras: Sequence[Any], uv: np.ndarray, path: str | Path | None = None, title: str = "",
                      missed: Sequence[np.ndarray] | None = None, n_corners_per_square: int = 4) -> Any:
    """The two camera images with the detected pattern corners (Figure 5.14's view).

    Parameters
    ----------
    cameras : sequence of 2 Camera
        The cameras (image size, principal point).
    uv : numpy.ndarray, shape (N, 2, M, 2)
        Detected corners per pose, camera, corner [px].
    path : str or pathlib.Path, optional
        PNG file.
    title : str, optional
        Figure title.
    missed : sequence of 2 numpy.ndarray, shape (n_j, 2), optional
        Pattern centres of poses a camera did not detect (drawn as crosses, where inside).
    n_corners_per_square : int, optional
        Corners drawn as one closed outline (4: squares).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = new_figure(1, 2, panel_size(2, 1, extra=0.4))
    for j, (ax, cam) in enumerate(zip(axes, cameras)):
        ax.plot([0, cam.width, cam.width, 0, 0], [0, 0, cam.height, cam.height, 0], "-", lw=1.0, color="0.3")
        pts = uv[:, j]
        ax.plot(pts[..., 0].ravel(), pts[..., 1].ravel(), ".", ms=1.0, color="tab:blue", label=f"corners, {uv.shape[0]} poses")
        for k in (0, uv.shape[0] // 2, uv.shape[0] - 1) if uv.shape[0] else ():
            for s in range(0, uv.shape[2] - n_corners_per_square + 1, n_corners_per_square):
                sq = pts[k, s:s + n_corners_per_square]
                ax.fill(sq[:, 0], sq[:, 1], color="k", alpha=0.8)
        if missed is not None and len(missed[j]):
            ax.plot(missed[j][:, 0], missed[j][:, 1], "x", color="tab:red", ms=3, label=f"not detected ({len(missed[j])})")
        ax.plot(cam.cx, cam.cy, "+", color="tab:green", ms=8, label="principal point")
        ax.set_xlim(-0.05 * cam.width, 1.05 * cam.width)
        ax.set_ylim(1.05 * cam.height, -0.05 * cam.height)
        ax.set_aspect("equal")
        ax.set_xlabel("u [px]")
        ax.set_ylabel("v [px]")
        ax.set_title(cam.name)
        ax.legend(fontsize=6, loc="lower right")
    if title:
        fig.suptitle(title)
    return save(fig, path)


def plot_reconstruction(T: np.ndarray, error: np.ndarray | None, camera_positions: np.ndarray, camera_axes: np.ndarray,
                        path: str | Path | None = None, title: str = "", error_scale: float = 20.0) -> Any:
    """Reconstructed TCPs, the cameras and the vision errors scaled (Figures 5.15 and 5.18).

    Parameters
    ----------
    T : numpy.ndarray, shape (n, 3)
        Vision TCPs [m].
    error : numpy.ndarray, shape (n, 3), or None
        Vision minus tracker [m] (drawn scaled by ``error_scale``).
    camera_positions : numpy.ndarray, shape (2, 3)
        Camera centres in the same frame [m].
    camera_axes : numpy.ndarray, shape (2, 3)
        Their optical axes (unit vectors).
    path : str or pathlib.Path, optional
        PNG file.
    title : str, optional
        Figure title.
    error_scale : float, optional
        Scale of the error lines (Figure 5.18: 20).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = new_figure(1, 1, "plot.figsize", subplot_kw={"projection": "3d"})
    ax.plot(T[:, 0], T[:, 1], T[:, 2], "*", ms=3, color="tab:blue", label="vision TCPs")
    if error is not None:
        for p, e in zip(T, error):
            q = p + error_scale * e
            ax.plot([p[0], q[0]], [p[1], q[1]], [p[2], q[2]], "-", lw=0.8, color="tab:red")
        ax.plot([], [], "-", color="tab:red", label=f"vision - tracker x {error_scale:g}")
    span = float(np.ptp(T, axis=0).max()) or 1.0
    for j, (c, a) in enumerate(zip(camera_positions, camera_axes)):
        ax.quiver(c[0], c[1], c[2], a[0], a[1], a[2], length=0.3 * span, color="k")
        ax.text(c[0], c[1], c[2], f" camera {j + 1}", fontsize=7)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.legend(fontsize=7)
    if title:
        ax.set_title(title)
    return save(fig, path)


def plot_vision_errors(measurement_error: np.ndarray | None, validation_errors: dict[str, np.ndarray],
                       path: str | Path | None = None, title: str = "") -> Any:
    """Histogram of the vision measurement error and the calibrated models' errors (Figures 5.17 and 5.19).

    Parameters
    ----------
    measurement_error : numpy.ndarray, shape (n,), or None
        ``|vision - tracker|`` per pose [m] (None: no tracker, left panel empty).
    validation_errors : dict of str to numpy.ndarray
        Label -> errors on the validation poses [m] (eq. 5.5).
    path : str or pathlib.Path, optional
        PNG file.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, (a, b) = new_figure(1, 2, panel_size(2, 1, extra=0.4))
    if measurement_error is not None:
        a.hist(measurement_error * 1e3, bins=25, color="tab:blue")
        a.axvline(measurement_error.mean() * 1e3, color="k", ls="--", label=f"mean {measurement_error.mean() * 1e3:.2f} mm")
        a.legend(fontsize=7)
    a.set_xlabel("|vision - tracker| [mm]")
    a.set_ylabel("poses")
    a.set_title("vision measurement error")
    for label, e in validation_errors.items():
        b.plot(np.arange(1, e.size + 1), e * 1e3, lw=0.8, label=f"{label} (mean {e.mean() * 1e3:.3f} mm)")
    b.set_yscale("log")
    b.set_xlabel("validation pose")
    b.set_ylabel("positioning error e_k [mm]")
    b.set_title("calibrated models, eq. 5.5")
    b.legend(fontsize=6)
    if title:
        fig.suptitle(title)
    return save(fig, path)
