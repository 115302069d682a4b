"""Tables and plots of the tracker + IMU fusion study (Cvitanic (2021), sections 4.2-4.3).

Tables 8, 9, 10 and the filter comparison as Markdown (with the thesis' figures beside ours
where the reference data has them, "not in the reference data" otherwise) and CSV; plots in the
style of the thesis' Figs. 24-26 (our reading of them: the velocity from the four-point
regression and from the fusion against the truth; the angular acceleration from the gyro's
regression and from the fusion against the truth, the sine peaks shaded; the Table 10 sweep as
improvement per parameter value). Plain dicts and arrays in, files out; matplotlib's object
API, no pyplot state.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from gtmodel.report._figure import new_figure, save
from gtmodel.report.fidelity_rules import LIMIT_DECADES, limit_verdict

__all__ = ["write_fusion_tables", "write_limits_table", "plot_velocity", "plot_angular_acceleration", "plot_sweep", "QUANTITY_LABELS"]

#: Row labels of the tables (quantity key -> text with unit).
QUANTITY_LABELS = {
    "position_mm": "position [mm]",
    "velocity_mm_s": "velocity [mm/s]",
    "acceleration_m_s2": "acceleration [m/s^2]",
    "orientation_deg": "orientation [deg]",
    "angular_velocity_deg_s": "angular velocity [deg/s]",
    "angular_acceleration_deg_s2": "angular acceleration [deg/s^2]",
}
_NOT_IN_REFERENCE = "not in the reference data"
_METRIC = "Error metric: mean over the samples (after the warm-up) of the Euclidean norm of the error (orientation: of the rotation angle)."


def _num(v: Any, fmt: str = "{:.4g}") -> str:
    return "" if v is None else (fmt.format(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else str(v))


def _thesis(v: Any) -> str:
    return _NOT_IN_REFERENCE if v is None else _num(v)


def _write(out: Path, stem: str, title: str, intro: str, header: Sequence[str], rows: Sequence[Sequence[Any]]) -> list[str]:
    md = [f"# {title}", "", intro, "", "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    md += ["| " + " | ".join(_num(c) for c in row) + " |" for row in rows]
    csv = [",".join(header)] + [",".join(_num(c, "{:.6g}").replace(",", ";") for c in row) for row in rows]
    (out / f"{stem}.md").write_text("\n".join(md) + "\n", encoding="utf-8")
    (out / f"{stem}.csv").write_text("\n".join(csv) + "\n", encoding="utf-8")
    return [f"{stem}.md", f"{stem}.csv"]


def write_fusion_tables(out: str | Path, name: str, table_8: Mapping[str, Any], table_9: Mapping[str, Any],
                        table_10: Sequence[Mapping[str, Any]], comparison: Sequence[Mapping[str, Any]]) -> list[str]:
    """Write ``table_8``, ``table_9``, ``table_10`` and ``filter_comparison`` as ``.md`` and ``.csv``.

    Parameters
    ----------
    out : str or pathlib.Path
        The folder.
    name : str
        Problem name (titles).
    table_8 : Mapping
        Per motion per quantity ``{sensor, fusion, change_percent, thesis_sensor, thesis_fusion[, fusion_appendix_b]}``.
    table_9 : Mapping
        Per motion ``{factor, <quantity>: {baseline_sensor, baseline_fusion, sensor, fusion, ...}}``.
    table_10 : sequence of Mapping
        Rows ``{parameter, value, motion, filter, status, <quantity>: {sensor, fusion, improvement_percent}, stops_paying}``.
    comparison : sequence of Mapping
        Rows ``{motion, filter, status, samples, step_time_us, <quantity>: float, velocity_tracker_mm_s}``.

    Returns
    -------
    list of str
        The file names written (empty tables are skipped).
    """
    out = Path(out)
    files: list[str] = []
    rows = []
    for motion, table in table_8.items():
        for q, r in table.items():
            rows.append([motion, QUANTITY_LABELS.get(q, q), r.get("sensor"), r.get("fusion"), r.get("change_percent"),
                         r.get("fusion_appendix_b"), _thesis(r.get("thesis_sensor")), _thesis(r.get("thesis_fusion"))])
    if rows:
        files += _write(out, "table_8", f"{name}: Table 8 (baseline sensors, Cvitanic (2021))",
                        _METRIC + " 3-axis: Kalman filter on the 9-D model; 5-axis: EKF on the 19-D model. Sensor: the tracker "
                        "(position, orientation), the four-point regression (velocity, angular acceleration), the accelerometer moved "
                        "to the target (acceleration), the gyro (angular velocity). `fusion_appendix_b`: the KF with the thesis' "
                        "Appendix B Q.",
                        ["motion", "quantity", "sensor", "fusion", "change %", "fusion (Appendix B Q)", "thesis sensor", "thesis fusion"], rows)
    rows = []
    for motion, table in table_9.items():
        for q, r in table.items():
            if not isinstance(r, Mapping):
                continue
            rows.append([motion, QUANTITY_LABELS.get(q, q), table.get("factor"), r["baseline_sensor"], r["baseline_fusion"], r["sensor"],
                         r["fusion"], r["fusion_below_sensor"], r["fusion_above_baseline_sensor"], _NOT_IN_REFERENCE])
    if rows:
        files += _write(out, "table_9", f"{name}: Table 9 (a less accurate tracker)",
                        _METRIC + " The tracker's position and orientation noise times `factor`; the thesis' structure: the fused error is "
                        "below the noisy sensor's but above the baseline sensor's.",
                        ["motion", "quantity", "factor", "baseline sensor", "baseline fusion", "noisy sensor", "noisy fusion",
                         "fusion < noisy sensor", "fusion > baseline sensor", "thesis"], rows)
    quantities = list(QUANTITY_LABELS)
    rows = []
    for r in table_10:
        cells = [r["parameter"], r["value"], r["motion"], r["filter"], r["status"]]
        for q in quantities:
            e = r.get(q)
            cells += [e["sensor"], e["fusion"], e["improvement_percent"]] if isinstance(e, Mapping) else ["", "", ""]
        cells.append(" ".join(r.get("stops_paying", [])))
        rows.append(cells)
    if rows:
        header = ["parameter", "value", "motion", "filter", "status"]
        for q in quantities:
            header += [f"{q} sensor", f"{q} fusion", f"{q} improvement %"]
        files += _write(out, "table_10", f"{name}: Table 10 (sweeps of the Table 7 parameters)",
                        _METRIC + " One Table 7 parameter changed per row, the others at the baseline. `stops_paying`: quantities whose "
                        f"fused error is not below the sensor-only one. Thesis: {_NOT_IN_REFERENCE}.", header + ["stops paying"], rows)
    rows = []
    for r in comparison:
        rows.append([r["motion"], r["filter"], r["status"], r["samples"], r["step_time_us"], r.get("velocity_tracker_mm_s")]
                    + [r.get(q) for q in quantities])
    if rows:
        files += _write(out, "filter_comparison", f"{name}: filter comparison (error and wall time per step)",
                        _METRIC + " Wall time per step of the Python run (CasADi Functions; the PF with its particle count). "
                        f"Thesis: 1000 particles were the particle filter's real-time limit; errors {_NOT_IN_REFERENCE}.",
                        ["motion", "filter", "status", "samples", "us/step", "velocity tracker-only [mm/s]"] + [QUANTITY_LABELS[q] for q in quantities],
                        rows)
    return files


def plot_velocity(t: Any, truth: Any, regression: Any, fusion: Any, path: str | Path, title: str = "", axis: int = 1) -> Any:
    """Velocity of one axis: truth, four-point regression and fusion, and the error norms (style of Fig. 24).

    Parameters
    ----------
    t : array_like, shape (N,)
        Times [s].
    truth, regression, fusion : array_like, shape (N, 3)
        True, tracker-only and fused velocity [m/s] (plotted in mm/s).
    path : str or pathlib.Path
        PNG file.
    title : str, optional
        Figure title.
    axis : int, optional
        The axis drawn in the upper panel (0, 1, 2 for x, y, z).

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    t = np.asarray(t, float)
    tr, rg, fu = (1e3 * np.asarray(v, float) for v in (truth, regression, fusion))
    fig, ax = new_figure(2, 1, (8, 6), squeeze=False)
    c = "xyz"[axis]
    ax[0, 0].plot(t, rg[:, axis], lw=0.6, color="tab:orange", label="tracker, four-point regression")
    ax[0, 0].plot(t, fu[:, axis], lw=1, color="tab:blue", label="fusion")
    ax[0, 0].plot(t, tr[:, axis], "k--", lw=1, label="truth")
    ax[0, 0].set_ylabel(f"v_{c} [mm/s]")
    ax[1, 0].plot(t, np.linalg.norm(rg - tr, axis=1), lw=0.6, color="tab:orange", label="|error| regression")
    ax[1, 0].plot(t, np.linalg.norm(fu - tr, axis=1), lw=1, color="tab:blue", label="|error| fusion")
    ax[1, 0].set_ylabel("|v error| [mm/s]")
    ax[1, 0].set_xlabel("t [s]")
    for a in ax[:, 0]:
        a.grid(True)
        a.legend(loc="upper right", fontsize="small")
    fig.suptitle(f"{title}: velocity" if title else "velocity")
    return save(fig, path)


def plot_angular_acceleration(t: Any, truth: Any, regression: Any, fusion: Any, peaks: Any, path: str | Path, title: str = "") -> Any:
    """Angular acceleration along its largest axis: truth, gyro regression, fusion; sine peaks shaded (style of Fig. 25).

    Parameters
    ----------
    t : array_like, shape (N,)
        Times [s].
    truth, regression, fusion : array_like, shape (N, 3)
        True, gyro-regression and fused body angular acceleration [rad/s^2] (plotted in deg/s^2).
    peaks : array_like of bool, shape (N,)
        Samples at the sine peaks.
    path : str or pathlib.Path
        PNG file.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    t = np.asarray(t, float)
    tr, rg, fu = (np.degrees(np.asarray(v, float)) for v in (truth, regression, fusion))
    k = int(np.argmax(np.abs(tr).max(axis=0)))
    peaks = np.asarray(peaks, bool)
    fig, ax = new_figure(2, 1, (8, 6), squeeze=False)
    ax[0, 0].plot(t, rg[:, k], lw=0.5, color="tab:orange", label="gyro, four-point regression")
    ax[0, 0].plot(t, fu[:, k], lw=1, color="tab:blue", label="fusion (EKF)")
    ax[0, 0].plot(t, tr[:, k], "k--", lw=1, label="truth")
    ax[0, 0].set_ylabel(f"alpha_{'xyz'[k]} [deg/s^2]")
    ax[1, 0].plot(t, np.linalg.norm(rg - tr, axis=1), lw=0.5, color="tab:orange", label="|error| regression")
    ax[1, 0].plot(t, np.linalg.norm(fu - tr, axis=1), lw=1, color="tab:blue", label="|error| fusion")
    ax[1, 0].set_ylabel("|alpha error| [deg/s^2]")
    ax[1, 0].set_xlabel("t [s]")
    for a in ax[:, 0]:
        lo, hi = a.get_ylim()
        a.fill_between(t, lo, hi, where=peaks, color="0.85", step="mid", label="sine peaks")
        a.set_ylim(lo, hi)
        a.grid(True)
        a.legend(loc="upper right", fontsize="small")
    fig.suptitle(f"{title}: angular acceleration" if title else "angular acceleration")
    return save(fig, path)


def write_limits_table(out: str | Path, name: str, limits: Sequence[Mapping[str, Any]]) -> list[str]:
    """Write ``table_10_limits.md`` and ``.csv``: where the fused velocity stops paying, against Cvitanic (2021), Table 10.

    Parameters
    ----------
    out : str or pathlib.Path
        Result folder.
    name : str
        Problem name (the titles).
    limits : sequence of Mapping
        Rows of :func:`gtmodel.estimation.fusion.limits.velocity_limit` (nothing is written when empty).

    Returns
    -------
    list of str
        The file names written.
    """
    def lim(v: Any) -> str:
        return "N/A" if v is None else ("no constraint" if v == float("inf") else f"< {v:g}")

    rows = []
    for r in limits:
        found = r["stops_at"] is not None
        ours = (f"{r['limit']:.3g} (pays at {_num(r['pays_up_to'])}, not at {_num(r['stops_at'])})" if found and r["pays_up_to"] is not None
                else f"<= {r['search'][0]:g} (not at the low end)" if found else f"> {r['search'][1]:g} (pays over the whole range)")
        rows.append([r["motion"], r["tuning"], r.get("baseline", "causal"), r["parameter"], lim(r["thesis_limit"]), ours, r["decades_from_thesis"],
                     limit_verdict(r), len(r["evaluations"])])
    if not rows:
        return []
    return _write(Path(out), "table_10_limits", f"{name}: Table 10 limits (where the fused velocity stops paying)",
                  _METRIC + " Per row one Table 7 parameter is searched on a decade grid, the others at the baseline, then the "
                  "bracketing decade is bisected in log10; `limit` is the geometric mean of the final bracket. Tracker baseline: the "
                  "four-point regression taken as the velocity now (causal, the thesis' reading) or compared at its window's centre. Verdict (the fidelity "
                  f"page's rule, gtmodel.report.fidelity_rules): reproduced when within half a decade ({LIMIT_DECADES:g} in log10) of the "
                  "thesis' '<' limit, or, for 'no constraint', when fusion pays over the whole range.",
                  ["motion", "tuning", "tracker baseline", "parameter", "thesis", "ours", "decades from thesis", "verdict", "runs"], rows)


def plot_sweep(rows: Sequence[Mapping[str, Any]], path: str | Path, title: str = "",
               quantities: Sequence[str] = ("position_mm", "velocity_mm_s", "acceleration_m_s2", "angular_velocity_deg_s")) -> Any:
    """Table 10 as bars: the improvement of fusion over the sensor per swept value (style of Fig. 26).

    Parameters
    ----------
    rows : sequence of Mapping
        Table 10 rows (``parameter``, ``value`` and per quantity ``improvement_percent``).
    path : str or pathlib.Path
        PNG file.
    title : str, optional
        Figure title.
    quantities : sequence of str, optional
        The quantities drawn (one panel each).

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    several = len({r.get("motion") for r in rows}) > 1
    labels = [(f"{r['motion']} " if several else "") + f"{r['parameter']}={r['value']:g}" for r in rows]
    fig, ax = new_figure(len(quantities), 1, (10, 2.2 * len(quantities) + 1.5), squeeze=False)
    x = np.arange(len(rows))
    for a, q in zip(ax[:, 0], quantities):
        vals = np.array([(r.get(q) or {}).get("improvement_percent") if isinstance(r.get(q), Mapping) else np.nan for r in rows], float)
        vals = np.where(np.isfinite(vals), vals, 0.0)
        a.bar(x, np.clip(vals, -100, 100), color=np.where(vals > 0, "tab:blue", "tab:red"))
        a.axhline(0, color="k", lw=0.8)
        a.set_ylabel(f"{QUANTITY_LABELS.get(q, q).split(' [')[0]}\nimprovement %", fontsize="small")
        a.set_ylim(-100, 100)
        a.grid(True, axis="y")
        a.set_xticks(x, [] if a is not ax[-1, 0] else labels, rotation=75, fontsize="x-small")
    fig.suptitle(f"{title}: Table 10 sweep, fusion vs sensor (clipped at -100 %)" if title else "Table 10 sweep")
    return save(fig, path)
