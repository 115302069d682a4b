"""Tables and plots of the correction-stability study (Cvitanic (2021), Table 14, Figs. 35-36 style).

Every function takes plain arrays (not result objects), draws on a
:class:`matplotlib.figure.Figure` (no pyplot state, safe under Agg) or writes text:

- :func:`write_gain_table`: Table 14 layout, per validation pose the predicted and the
  simulated largest stable gain per direction, as ``.md`` and ``.csv``;
- :func:`plot_offset_response`: the response to one offset command and the fitted single
  mode (Fig. 35 style);
- :func:`plot_loop_errors`: the simulated loop error at the largest stable gain and one
  increment above (Fig. 36 style);
- :func:`plot_gains`: predicted against simulated gains per validation pose.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from gtmodel.errors import InputError
from gtmodel.report._figure import new_figure, panel_size, save

__all__ = ["write_gain_table", "plot_offset_response", "plot_loop_errors", "plot_gains"]


def _gains(values: Any, name: str, shape: tuple[int, int]) -> np.ndarray:
    arr = np.asarray(values, dtype=float)
    if arr.shape != shape:
        raise InputError(f"{name}: expected shape {shape}, got {arr.shape}")
    return arr


def write_gain_table(poses_deg: Any, directions: Sequence[str], resolutions: Mapping[str, float], predicted: Any, simulated: Any,
                     out: str | Path, stem: str = "table_14", title: str = "", note: str = "", first_pose: int = 1,
                     thesis: Mapping[str, Any] | None = None) -> list[str]:
    """Write the Table 14 layout: per validation pose, predicted and simulated gain per direction.

    Parameters
    ----------
    poses_deg : array_like, shape (V, 2)
        ``(j2, j3)`` of the validation poses [deg].
    directions : sequence of str
        Column directions, e.g. ``("x", "y")``.
    resolutions : Mapping[str, float]
        Gain step per direction [-].
    predicted : array_like, shape (V, D)
        Predicted largest stable gains [-].
    simulated : array_like, shape (V, D)
        Largest stable gains of the richer simulation [-].
    out : str or pathlib.Path
        Folder to write into.
    stem : str, optional
        File name without suffix (default ``"table_14"``).
    title : str, optional
        Heading of the Markdown file.
    note : str, optional
        A paragraph after the table (e.g. the thesis' figures beside ours).
    first_pose : int, optional
        Number of the first validation pose (the thesis numbers Table 13's poses 17-22, after
        the 16 calibration poses of Table 12).
    thesis : Mapping[str, Mapping[str, sequence of float]], optional
        The thesis' gains beside ours: ``{"predicted": {d: (V,)}, "actual": {d: (V,)}}``
        (Cvitanic (2021), Table 14).

    Returns
    -------
    list of str
        The written file names (``<stem>.md``, ``<stem>.csv``).

    Raises
    ------
    InputError
        Shapes that do not match.
    """
    q = np.asarray(poses_deg, dtype=float)
    if q.ndim != 2 or q.shape[1] != 2:
        raise InputError(f"poses_deg: expected shape (V, 2), got {q.shape}")
    dirs = list(directions)
    P = _gains(predicted, "predicted", (q.shape[0], len(dirs)))
    S = _gains(simulated, "simulated", (q.shape[0], len(dirs)))
    h = np.array([float(resolutions[d]) for d in dirs])
    within = np.abs(P - S) <= h * (1 + 1e-9)
    th_dirs = [d for d in dirs if thesis and d in thesis.get("predicted", {}) and d in thesis.get("actual", {})]
    header = (["pose", "j2_deg", "j3_deg"] + [f"{w}_{d}" for d in dirs for w in ("predicted", "simulated")]
              + [f"thesis_{w}_{d}" for d in th_dirs for w in ("predicted", "actual")] + ["within_one_increment"])
    csv = [",".join(header)]
    md_head = ("| pose | j2 [deg] | j3 [deg] | " + " | ".join(f"{d} predicted | {d} simulated" for d in dirs)
               + "".join(f" | thesis {d} predicted | thesis {d} actual" for d in th_dirs) + " | within one increment |")
    md = [md_head, "|" + "---|" * (4 + 2 * len(dirs) + 2 * len(th_dirs))]
    for v in range(q.shape[0]):
        cells = [f"{x:.4g}" for j in range(len(dirs)) for x in (P[v, j], S[v, j])]
        cells += [f"{thesis[w][d][v]:.4g}" for d in th_dirs for w in ("predicted", "actual")]  # type: ignore[index]
        ok = "yes" if within[v].all() else "no"
        csv.append(",".join([str(first_pose + v), f"{q[v, 0]:.2f}", f"{q[v, 1]:.2f}", *cells, ok]))
        md.append(f"| {first_pose + v} | {q[v, 0]:.2f} | {q[v, 1]:.2f} | " + " | ".join(cells) + f" | {ok} |")
    folder = Path(out)
    (folder / f"{stem}.csv").write_text("\n".join(csv) + "\n", encoding="utf-8")
    res = ", ".join(f"{d}: {resolutions[d]:g}" for d in dirs)
    intro = (f"# {title or 'Largest stable P gain'}: Table 14 layout (Cvitanic (2021))\n\n"
             f"Largest stable proportional gain per validation pose, predicted (single mode fitted to one offset "
             f"command, GPR over (j2, j3)) and simulated (the richer two-mode simulation); resolution {res}. "
             f"Within one increment at {int(within.all(axis=1).sum())} of {q.shape[0]} poses.\n\n")
    (folder / f"{stem}.md").write_text(intro + "\n".join(md) + "\n" + (f"\n{note}\n" if note else ""), encoding="utf-8")
    return [f"{stem}.md", f"{stem}.csv"]


def plot_offset_response(t: Any, responses: Mapping[str, Mapping[str, Any]], path: str | Path, title: str = "") -> Any:
    """Response to one offset command, truth against the fitted single mode (Fig. 35 style).

    Parameters
    ----------
    t : array_like, shape (n,)
        Time after the command [s].
    responses : Mapping[str, Mapping[str, array_like]]
        Direction -> curve label -> TCP position, each shape (n,) [m].
    path : str or pathlib.Path
        PNG file.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.

    Raises
    ------
    InputError
        No direction, or a curve of another length than ``t``.
    """
    tt = np.asarray(t, dtype=float).reshape(-1)
    if not responses:
        raise InputError("responses: expected at least one direction")
    fig, axes = new_figure(1, len(responses), sharey=True, size=panel_size(len(responses)))
    axes = np.atleast_1d(axes)
    for ax, (d, curves) in zip(axes, responses.items()):
        for label, y in curves.items():
            yy = np.asarray(y, dtype=float).reshape(-1)
            if yy.shape != tt.shape:
                raise InputError(f"responses[{d!r}][{label!r}]: expected shape {tt.shape}, got {yy.shape}")
            ax.plot(tt * 1e3, yy * 1e3, label=label, lw=1.2)
        ax.set_title(f"{d} direction")
        ax.set_xlabel("time after the command [ms]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_ylabel("TCP position [mm]")
    if title:
        fig.suptitle(title)
    return save(fig, path)


def plot_loop_errors(t: Any, runs: Mapping[str, Mapping[str, Any]], path: str | Path, title: str = "") -> Any:
    """Tracking error of the simulated correction loop at chosen gains (Fig. 36 style).

    Parameters
    ----------
    t : array_like, shape (n,)
        Time [s].
    runs : Mapping[str, Mapping[str, array_like]]
        Direction -> curve label (e.g. ``"K = 0.11 (stable)"``) -> error, shape (n,) [m];
        non-finite values are not drawn; the first curve sets the vertical scale (3x its peak).
    path : str or pathlib.Path
        PNG file.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.

    Raises
    ------
    InputError
        No direction, or an error of another length than ``t``.
    """
    tt = np.asarray(t, dtype=float).reshape(-1)
    if not runs:
        raise InputError("runs: expected at least one direction")
    fig, axes = new_figure(len(runs), 1, sharex=True, size=(9.0, 2.8 * len(runs)))
    axes = np.atleast_1d(axes)
    for ax, (d, curves) in zip(axes, runs.items()):
        for label, e in curves.items():
            ee = np.asarray(e, dtype=float).reshape(-1)
            if ee.shape != tt.shape:
                raise InputError(f"runs[{d!r}][{label!r}]: expected shape {tt.shape}, got {ee.shape}")
            ax.plot(tt, np.where(np.isfinite(ee), ee, np.nan) * 1e3, label=label, lw=0.9)
        ax.set_ylabel(f"{d} error [mm]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
        first = np.asarray(next(iter(curves.values())), dtype=float)
        lim = float(np.nanmax(np.abs(np.where(np.isfinite(first), first, np.nan)))) if np.any(np.isfinite(first)) else 0.0
        if lim > 0:
            ax.set_ylim(-3e3 * lim, 3e3 * lim)  # the first curve (the stable gain) sets the scale; a diverging run leaves it
    axes[-1].set_xlabel("time [s]")
    if title:
        fig.suptitle(title)
    return save(fig, path)


def plot_gains(directions: Sequence[str], predicted: Any, simulated: Any, path: str | Path, title: str = "") -> Any:
    """Predicted against simulated largest stable gain per validation pose, one panel per direction.

    Parameters
    ----------
    directions : sequence of str
        Directions (columns of the gain arrays).
    predicted : array_like, shape (V, D)
        Predicted gains [-].
    simulated : array_like, shape (V, D)
        Gains of the richer simulation [-].
    path : str or pathlib.Path
        PNG file.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.

    Raises
    ------
    InputError
        Shapes that do not match.
    """
    P = np.asarray(predicted, dtype=float)
    if P.ndim != 2 or P.shape[1] != len(directions):
        raise InputError(f"predicted: expected shape (V, {len(directions)}), got {P.shape}")
    S = _gains(simulated, "simulated", P.shape)
    fig, axes = new_figure(1, len(directions), size=panel_size(len(directions)))
    axes = np.atleast_1d(axes)
    pose = np.arange(1, P.shape[0] + 1)
    for j, (ax, d) in enumerate(zip(axes, directions)):
        ax.bar(pose - 0.18, P[:, j], width=0.36, label="predicted (single mode + GPR)")
        ax.bar(pose + 0.18, S[:, j], width=0.36, label="simulated (two-mode truth)")
        ax.set_title(f"{d} direction")
        ax.set_xlabel("validation pose")
        ax.set_xticks(pose)
        ax.grid(True, axis="y", alpha=0.3)
    axes[0].set_ylabel("largest stable P gain [-]")
    axes[0].legend(fontsize=8, loc="lower right", framealpha=0.9)
    if title:
        fig.suptitle(title)
    return save(fig, path)
