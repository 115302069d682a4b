"""One self-contained HTML page of a result folder: ``report.html`` (``gtmodel report DIR``).

The page opens on what a reader asks first: the status and message, the objective and the
final time, the warnings, then the trajectories of every CSV table with a time column as
zoomable Plotly figures (one panel per column, panels sharing the time axis, every axis
titled with its unit, the bounds of the variables drawn as dashed lines where
``summary.json`` has them). Below come the verification block, the benchmark comparison,
the other summary fields, the model's variables with their units and bounds, the other
tables, the kind's PNG plots, the folder's files with what each holds (``summary.json``'s
``file_descriptions``) and the whole ``summary.json``.

Plotly's *basic* bundle (scatter, bar and pie traces: :data:`PLOTLY_JS`, plotly.js
4.1.1, MIT licence beside it, vendored from the ``plotly.js-basic-dist-min`` package) is
inlined, about 1.2 MB, so the page needs no network and no other file: it can be mailed
or archived alone.

The optimal-control summary names its variable groups (``variables``: states, inputs,
algebraics, outputs), their ``units`` and ``bounds``; other kinds' tables are plotted
column by column, with the units their ``units`` field gives. A page stays under
:data:`PAGE_LIMIT` bytes: its traces share :data:`MAX_PAGE_SAMPLES` samples (at most
:data:`MAX_POINTS` each); a longer trace is min-max decimated (each bucket of rows keeps its
smallest and largest value, so peaks and bound touches survive; said in the figure's title,
the full data in the CSV file) and values keep 6 significant digits; the PNG plots are
inlined while the page stays under the limit, else shown from the folder beside the page
(said under each). A CSV file larger than :data:`MAX_CSV_BYTES` is listed, not read.

This module renders and writes the page only; where it may be written (a result folder's
rules, ``summary.json`` listing it) is the problem layer's business
(:func:`gtmodel.problems.run.add_report`, ``write_results(report=True)``).
"""

from __future__ import annotations

import base64
import csv
import json
import logging
import math
import os
import re
import stat
from pathlib import Path, PurePosixPath
from typing import Any, Mapping

import numpy as np

from gtmodel._escape import html_text, json_script
from gtmodel._tables import split_unit
from gtmodel.errors import InputError
from gtmodel.status import Status

__all__ = ["REPORT_FILE", "PLOTLY_JS", "MAX_POINTS", "MAX_PAGE_SAMPLES", "PAGE_LIMIT", "MAX_CSV_BYTES", "decimate", "render_report",
           "write_report", "read_csv_columns"]

log = logging.getLogger("gtmodel")

#: The page's file name in a result folder.
REPORT_FILE = "report.html"
#: Plotly's basic bundle (plotly.js 4.1.1: scatter, bar, pie), inlined in every page; its MIT licence beside it.
PLOTLY_JS = Path(__file__).resolve().parent / "assets" / "plotly-basic.min.js"
#: Most samples of one trace (a longer table is min-max decimated, :func:`decimate`).
MAX_POINTS = 4000
#: Most samples of all the traces of one page together (each trace at least :data:`MIN_POINTS`).
MAX_PAGE_SAMPLES = 24_000
#: Fewest samples a trace is decimated to.
MIN_POINTS = 400
#: Largest page, bytes: PNG plots beyond it are shown from the folder, not inlined.
PAGE_LIMIT = 2_000_000
#: Largest CSV file read into the page, bytes.
MAX_CSV_BYTES = 50_000_000
#: Most panels of one figure (further columns go to the next figure).
MAX_PANELS = 16
#: Rows of a table without a time column shown in the page.
MAX_TABLE_ROWS = 200
#: Height of one row of panels in a figure, px.
_PANEL_HEIGHT = 190

_TIME_COLUMNS = re.compile(r"^(t|time)(_s| ?\[s\])?$", re.IGNORECASE)
_GROUPS = ("states", "inputs", "algebraics", "outputs")
_STATUS_CLASS = {0: "ok", 1: "warn"}  # exit code -> colour; 2, 3, 130: "bad"

_CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:0 auto;max-width:1200px;padding:1em 2em;color:#222}
h1{font-size:1.6em;margin-bottom:.2em} h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.6em}
.status{display:inline-block;padding:.15em .6em;border-radius:.3em;font-weight:bold;color:#fff}
.ok{background:#2e7d32} .warn{background:#ef6c00} .bad{background:#c62828}
table{border-collapse:collapse;margin:.5em 0} td,th{border:1px solid #ddd;padding:.25em .6em;text-align:left;vertical-align:top}
th{background:#f4f4f4} td.num{text-align:right;font-variant-numeric:tabular-nums}
.scroll{overflow-x:auto} pre{background:#f7f7f7;padding:.6em;overflow-x:auto;font-size:.85em}
ul.warnings li{color:#b71c1c} .gt-figure{width:100%} img.png{max-width:100%;border:1px solid #eee}
.muted{color:#666}
"""

_SCRIPT = """
document.querySelectorAll("script.gt-figure-spec").forEach(function (node) {
  var spec = JSON.parse(node.textContent);
  var div = document.getElementById(node.dataset.target);
  Plotly.newPlot(div, spec.data, spec.layout, {responsive: true, displaylogo: false});
});
"""


_esc = html_text


def _fmt(value: Any) -> str:
    if isinstance(value, bool) or value is None:
        return "—" if value is None else str(value).lower()
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def _is_scalar(value: Any) -> bool:
    return value is None or isinstance(value, (str, int, float, bool))


def _finite(value: Any) -> float | None:
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def read_csv_columns(path: str | Path) -> tuple[list[str], dict[str, list[Any]]]:
    """The columns of a CSV file gtmodel wrote, numbers where every value is one.

    Lenient where :func:`gtmodel._tables.read_table` is strict, since a result table may
    hold text columns (case names) and empty or non-finite values: a column whose values
    all read as numbers (``nan``, ``inf`` and empty fields as NaN) is numeric, any other
    column text. Lines starting with ``#`` are skipped. A header cell ``name [unit]`` names
    the column ``name`` (:func:`gtmodel._tables.split_unit`; the summary holds the units).

    Parameters
    ----------
    path : str or pathlib.Path
        The CSV file (UTF-8, header row first).

    Returns
    -------
    tuple
        ``(header, columns)``: the column names in file order and name -> list of values
        (float for a numeric column, str otherwise), each as long as the number of rows.

    Raises
    ------
    InputError
        The file cannot be read, is not UTF-8, has no header or a row of another length
        (names the file and line).
    """
    path = Path(path)
    try:
        text = _read_regular(path).decode("utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read the table ({exc})") from None
    rows = [(i + 1, r) for i, r in enumerate(csv.reader(text.splitlines())) if r and not r[0].lstrip().startswith("#")]
    if not rows:
        raise InputError(f"{path}: no header row")
    header = [split_unit(h)[0] for h in rows[0][1]]  # "name [unit]" (a model result's units) or "name"
    body: list[list[str]] = []
    for lineno, row in rows[1:]:
        if len(row) != len(header):
            raise InputError(f"{path}, line {lineno}: {len(row)} values, expected {len(header)} (the header's columns)")
        body.append(row)
    columns: dict[str, list[Any]] = {}
    for j, name in enumerate(header):
        raw = [r[j].strip() for r in body]
        try:
            columns[name] = [float(v) if v else math.nan for v in raw]
        except ValueError:
            columns[name] = raw
    return header, columns


def _read_regular(path: Path) -> bytes:
    """The bytes of a regular file, never through a symbolic link (``O_NOFOLLOW``; a FIFO or device refused)."""
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0))
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise OSError(f"{path}: not a regular file")
        with os.fdopen(fd, "rb", closefd=False) as fh:
            return fh.read()
    finally:
        os.close(fd)


def _inside(folder: Path, name: Any) -> str | None:
    """Why ``name`` may not contribute to the page of ``folder`` (None: a regular file inside it).

    A result folder contributes only regular files inside it: a relative name without
    ``..``, no symbolic link on the way, a file with one link (a hard link may be a file
    elsewhere) and a path that resolves inside the folder.
    """
    if not isinstance(name, str) or not name or "\x00" in name:
        return "not a file name"
    parts = PurePosixPath(name).parts
    if not parts:
        return "not a file name"
    if PurePosixPath(name).is_absolute() or ".." in parts or "\\" in name:
        return "outside the result folder"
    path = folder
    for part in parts:
        path = path / part
        try:
            mode = path.lstat().st_mode
        except OSError:
            return "missing"
        if stat.S_ISLNK(mode):
            return "a symbolic link"
    if not stat.S_ISREG(mode):
        return "a folder" if stat.S_ISDIR(mode) else "not a regular file"
    if path.lstat().st_nlink > 1:
        return "a hard link (its content may be a file outside the folder)"
    if not path.resolve().is_relative_to(folder.resolve()):
        return "outside the result folder"
    return None


def _folder_files(folder: Path, summary: Mapping[str, Any]) -> tuple[list[str], list[str]]:
    """The files of the folder the page shows (``summary["files"]``, else the folder's entries) and the refusals.

    Returns
    -------
    files : list of str
        Names of regular files inside the folder (:func:`_inside`).
    refused : list of str
        One warning per name left out for a reason other than being missing (a symbolic
        link, outside the folder, not a regular file), for the page's warnings.
    """
    listed = summary.get("files")
    names = list(listed) if isinstance(listed, (list, tuple)) and listed else sorted(p.name for p in folder.iterdir())
    files, refused = [], []
    for name in names:
        why = _inside(folder, name)
        if why is None:
            files.append(name)
        elif why not in ("missing", "a folder"):  # a kind's sub-folder (gtmodel loop's code/) is not shown, nor suspicious
            shown = str(name)[:120].encode("unicode_escape").decode("ascii")
            refused.append(f"{shown}: {why}, not shown (a result folder contributes only regular files inside it)")
            log.warning("report: %s", refused[-1])
    return files, refused


def _time_column(header: list[str], columns: Mapping[str, list[Any]]) -> str | None:
    for name in header:
        if _TIME_COLUMNS.match(name) and columns[name] and isinstance(columns[name][0], float):
            return name
    return None


def _base(name: str) -> str:
    """``"T[0]"`` -> ``"T"`` (a vector variable's element in its table column)."""
    return name.split("[", 1)[0]


def _bound_pair(bounds: Mapping[str, Any], name: str) -> tuple[float | None, float | None]:
    """``(lo, hi)`` of a column (``None`` for an open side); ``"T[1]"`` takes element 1 of ``T``'s bounds."""
    pair = bounds.get(name)
    index = None
    if pair is None:
        pair = bounds.get(_base(name))
        m = re.search(r"\[(\d+)\]$", name)
        index = int(m.group(1)) if m else None
    if not isinstance(pair, (list, tuple)) or len(pair) != 2:
        return None, None
    out = []
    for side in pair:
        if isinstance(side, (list, tuple)):
            side = side[index] if index is not None and index < len(side) else None
        out.append(_finite(side))
    return out[0], out[1]


def _json_list(values: Any) -> list[float | None]:
    """Finite values to 6 significant digits (what a plot shows), others ``None`` (a gap)."""
    return [float(f"{v:.6g}") if math.isfinite(v) else None for v in map(float, values)]


def decimate(x: Any, y: Any, points: int) -> tuple[np.ndarray, np.ndarray]:
    """Min-max decimation of a trace for display: each bucket of rows keeps its smallest and largest value.

    Parameters
    ----------
    x, y : array_like
        ``(n,)`` the samples (time, value); ``y`` may hold NaN (never chosen over a number).
    points : int
        Most samples kept, at least 4 (the first and the last sample always among them).

    Returns
    -------
    x, y : numpy.ndarray
        ``(m,)`` the kept samples in their order, ``m <= points`` (all of them when
        ``n <= points``): the extremes of ``y`` over every bucket of ``ceil(n / b)`` rows,
        ``b = (points - 2) // 2`` buckets, so that no peak is lost.

    Raises
    ------
    InputError
        ``points`` below 4, or ``x`` and ``y`` of different lengths.
    """
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if isinstance(points, bool) or not isinstance(points, int) or points < 4:
        raise InputError(f"points: expected an integer >= 4, got {points!r}")
    if x.shape != y.shape or x.ndim != 1:
        raise InputError(f"x, y: expected two arrays of one shape (n,), got {x.shape} and {y.shape}")
    n = x.size
    if n <= points:
        return x, y
    buckets = (points - 2) // 2
    size = math.ceil(n / buckets)
    pad = buckets * size - n
    low = np.concatenate([np.where(np.isnan(y), np.inf, y), np.full(pad, np.inf)]).reshape(buckets, size)
    high = np.concatenate([np.where(np.isnan(y), -np.inf, y), np.full(pad, -np.inf)]).reshape(buckets, size)
    start = np.arange(buckets) * size
    keep = np.flatnonzero(np.bincount(np.concatenate([[0, n - 1], np.minimum(start + low.argmin(axis=1), n - 1),  # sorted, once each
                                                      np.minimum(start + high.argmax(axis=1), n - 1)]), minlength=n))
    return x[keep], y[keep]


def _unit(units: Mapping[str, str], name: str) -> str:
    """The unit of a column (``"T[1]"`` takes ``T``'s), ``""`` where the summary names none."""
    unit = units.get(name, units.get(_base(name)))
    return str(unit) if unit not in (None, "") else ""


def _axis_title(name: str, unit: str) -> str:
    return f"{name} [{unit}]" if unit else name


def _figure_spec(title: str, t: list[float], panels: list[tuple[str, list[float]]], bounds: Mapping[str, Any],
                 units: Mapping[str, str], t_label: str) -> dict[str, Any]:
    """A Plotly figure: one panel per signal, all panels on one time axis, bounds as dashed lines.

    Up to four panels are stacked; more are laid out in two columns (a row of panels
    :data:`_PANEL_HEIGHT` high), every panel's axes titled with their units.
    """
    t_span = [min(t), max(t)] if t else [0.0, 1.0]
    cols = 1 if len(panels) <= 4 else 2
    rows = math.ceil(len(panels) / cols)
    data: list[dict[str, Any]] = []
    layout: dict[str, Any] = {
        "title": {"text": title},
        "grid": {"rows": rows, "columns": cols, "pattern": "independent", "roworder": "top to bottom",
                 "xgap": 0.12, "ygap": 0.35},
        "height": 110 + _PANEL_HEIGHT * rows,
        "showlegend": False,
        "margin": {"l": 80, "r": 20, "t": 50, "b": 40},
        "hovermode": "x unified",
    }
    for k, (name, values) in enumerate(panels):
        suffix = "" if k == 0 else str(k + 1)
        xaxis, yaxis = f"x{suffix}", f"y{suffix}"
        data.append({"type": "scatter", "mode": "lines", "name": name, "x": list(t), "y": list(values),
                     "xaxis": xaxis, "yaxis": yaxis, "line": {"color": "#1f77b4"}})
        for side, b in zip(("lower bound", "upper bound"), _bound_pair(bounds, name)):
            if b is not None:
                data.append({"type": "scatter", "mode": "lines", "name": f"{name} {side}", "x": t_span, "y": [b, b],
                             "xaxis": xaxis, "yaxis": yaxis, "line": {"color": "#444", "dash": "dash", "width": 1},
                             "hoverinfo": "name+y", "_bound": True})
        layout[f"yaxis{suffix}"] = {"title": {"text": _axis_title(name, _unit(units, name)), "font": {"size": 12}}}
        layout[f"xaxis{suffix}"] = {"title": {"text": t_label, "font": {"size": 11}, "standoff": 2},
                                    **({} if k == 0 else {"matches": "x"})}
    return {"data": data, "layout": layout}


class _Png:
    """A PNG plot of the folder, inlined or shown from the folder when the page is assembled (:meth:`_Page.html`)."""

    def __init__(self, name: str, data: bytes) -> None:
        self.name, self.data = name, data

    def html(self, inline: bool) -> str:
        if inline:
            src = "data:image/png;base64," + base64.b64encode(self.data).decode("ascii")
            return f"<h3>{_esc(self.name)}</h3><img class='png' alt='{_esc(self.name)}' src='{src}'>"
        return (f"<h3>{_esc(self.name)}</h3><img class='png' alt='{_esc(self.name)}' src='{_esc(self.name)}'>"
                f"<p class='muted'>shown from the file beside this page (not inlined: the page stays under "
                f"{PAGE_LIMIT / 1e6:g} MB)</p>")


class _Page:
    """The page being assembled: sections of HTML, the figures' specifications and the PNG plots.

    Figures and PNGs are placeholders until :meth:`html`, which shares the page's samples
    among the traces (:data:`MAX_PAGE_SAMPLES`, :func:`decimate`) and inlines PNGs while the
    page stays under :data:`PAGE_LIMIT`.
    """

    def __init__(self) -> None:
        self.parts: list[Any] = []
        self.figures: list[dict[str, Any]] = []

    def add(self, text: str) -> None:
        self.parts.append(text)

    def figure(self, spec: dict[str, Any]) -> None:
        self.figures.append(spec)
        self.parts.append(spec)

    def png(self, name: str, data: bytes) -> None:
        self.parts.append(_Png(name, data))

    def _traces(self) -> list[dict[str, Any]]:
        return [tr for spec in self.figures for tr in spec["data"] if not tr.get("_bound")]

    def _figure_html(self, k: int, spec: dict[str, Any], points: int) -> str:
        n = 0
        for tr in spec["data"]:
            bound = tr.pop("_bound", False)
            if not bound:
                n = max(n, len(tr["x"]))
                x, y = decimate(tr["x"], tr["y"], points)
                tr["x"], tr["y"] = _json_list(x), _json_list(y)
        if n > points:
            spec["layout"]["title"]["text"] += f" (min-max decimated to at most {points} of {n} samples; every sample in the CSV file)"
        div = f"gt-figure-{k}"
        return (f'<div class="gt-figure" id="{div}"></div>'
                f'<script type="application/json" class="gt-figure-spec" data-target="{div}">{json_script(spec)}</script>')

    def html(self, head: str, tail: str) -> str:
        """The page: ``head``, the parts (figures decimated, PNGs inlined within the limit), ``tail``."""
        traces = len(self._traces())
        points = min(MAX_POINTS, max(MIN_POINTS, MAX_PAGE_SAMPLES // max(traces, 1)))
        out: list[Any] = []
        figures = 0
        for part in self.parts:
            if isinstance(part, dict):
                figures += 1
                part = self._figure_html(figures, part, points)
            out.append(part)
        size = len(head) + len(tail) + sum(len(p) for p in out if isinstance(p, str))
        for i, part in enumerate(out):
            if isinstance(part, _Png):
                inline = size + 4 * len(part.data) // 3 + 200 <= PAGE_LIMIT
                out[i] = part.html(inline)
                size += len(out[i])
        return head + "\n".join(out) + tail

    def table(self, header: list[str], rows: list[list[Any]]) -> None:
        head = "".join(f"<th>{_esc(h)}</th>" for h in header)
        body = "".join("<tr>" + "".join(
            f'<td class="num">{_esc(_fmt(v))}</td>' if isinstance(v, (int, float)) and not isinstance(v, bool)
            else f"<td>{_esc(_fmt(v))}</td>" for v in row) + "</tr>" for row in rows)
        self.add(f'<div class="scroll"><table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table></div>')


def _status_class(status: Any) -> str:
    try:
        return _STATUS_CLASS.get(Status(status).exit_code, "bad")
    except ValueError:
        return "bad"


def _warnings(summary: Mapping[str, Any]) -> list[str]:
    """The summary's own ``warnings`` and what its fields say is not to be relied on."""
    out = [str(w) for w in summary.get("warnings") or []]
    if summary.get("last_iterate"):
        out.append("the trajectories are the solver's last iterate, not a solution")
    ver = summary.get("verification")
    if isinstance(ver, Mapping) and ver.get("passed") is False:
        out.append(f"verification failed: {ver.get('message') or 'the simulation deviates from the solution'}")
    bench = summary.get("benchmark")
    if isinstance(bench, Mapping):
        err, tol = _finite(bench.get("relative_error")), _finite(bench.get("tolerance"))
        if err is not None and tol is not None and err > tol:
            out.append(f"benchmark: relative error {err:.3g} beyond its tolerance {tol:.3g}")
    return list(dict.fromkeys(out))


def _summary_section(page: _Page, summary: Mapping[str, Any]) -> None:
    skip = {"name", "kind", "status", "message", "files", "written_by"}
    rows = [[k, v if _is_scalar(v) else "; ".join(_fmt(x) for x in v)] for k, v in summary.items() if k not in skip and
            (_is_scalar(v) or (isinstance(v, list) and len(v) <= 20 and all(_is_scalar(x) for x in v)))]
    page.add("<h2>Summary</h2>")
    page.table(["field", "value"], rows)
    for key in ("transcription", "model", "refinement"):
        value = summary.get(key)
        if value:
            page.add(f"<h3>{_esc(key)}</h3><pre>{_esc(json.dumps(value, indent=2))}</pre>")


def _verification_section(page: _Page, ver: Any) -> None:
    page.add('<h2 id="verification">Verification</h2>')
    if not isinstance(ver, Mapping):
        page.add('<p class="muted">not verified (a failed solve, or the check was not run)</p>')
        return
    verdict = '<span class="status ok">passed</span>' if ver.get("passed") else '<span class="status bad">failed</span>'
    page.add(f"<p>{verdict} {_esc(ver.get('method', ''))}</p>")
    page.table(["field", "value"], [[k, v] for k, v in ver.items() if _is_scalar(v) and k != "passed"])
    for key, value in ver.items():
        if isinstance(value, Mapping) and value and all(isinstance(v, Mapping) for v in value.values()):
            cols = list(dict.fromkeys(c for v in value.values() for c in v))
            page.add(f"<h3>{_esc(key)}</h3>")
            page.table([key[:-1] if key.endswith("s") else key, *cols], [[n, *(v.get(c) for c in cols)] for n, v in value.items()])


def _variables(summary: Mapping[str, Any], header: list[str]) -> dict[str, list[str]]:
    """Columns of a trajectory table by variable group (``summary["variables"]``), else one group."""
    groups = summary.get("variables")
    if not isinstance(groups, Mapping):
        return {"": header}
    out: dict[str, list[str]] = {}
    for group, names in groups.items():
        names = set(names or [])
        cols = [h for h in header if h in names or _base(h) in names]
        if cols:
            out[str(group)] = cols
    rest = [h for h in header if not any(h in c for c in out.values())]
    if rest:
        out["other columns"] = rest
    return out


def _csv_section(page: _Page, folder: Path, name: str, summary: Mapping[str, Any], figures: bool) -> bool:
    """Draw a CSV table: its figures (``figures=True``; a table with a time column) or the table itself.

    Returns
    -------
    bool
        Whether the table is a time series (drawn as figures, not as a table).
    """
    path = folder / name
    size = path.lstat().st_size
    if size > MAX_CSV_BYTES:
        if not figures:
            page.add(f"<h3>{_esc(name)}</h3><p class='muted'>{size / 1e6:.0f} MB: too large to show (limit {MAX_CSV_BYTES / 1e6:.0f} MB)</p>")
        return False
    try:
        header, columns = read_csv_columns(path)
    except InputError as exc:
        if not figures:
            page.add(f"<h3>{_esc(name)}</h3><p class='muted'>not shown: {_esc(exc)}</p>")
        return False
    n = len(next(iter(columns.values()), []))
    time = _time_column(header, columns)
    numeric = [h for h in header if h != time and all(isinstance(v, float) for v in columns[h])]
    if time is not None and numeric and n > 1:
        if figures:
            bounds = summary.get("bounds") if isinstance(summary.get("bounds"), Mapping) else {}
            units = summary.get("units") if isinstance(summary.get("units"), Mapping) else {}
            for group, cols in _variables(summary, numeric).items():
                for start in range(0, len(cols), MAX_PANELS):
                    chunk = cols[start:start + MAX_PANELS]
                    title = f"{name}: {group}" if group else name
                    if len(cols) > MAX_PANELS:
                        title += f" ({start + 1}-{start + len(chunk)} of {len(cols)})"
                    page.figure(_figure_spec(title, columns[time], [(c, columns[c]) for c in chunk], bounds, units, f"{time} [s]"))
        return True
    if not figures:
        page.add(f"<h3>{_esc(name)}</h3>")
        page.table(header, [[columns[h][i] for h in header] for i in range(min(n, MAX_TABLE_ROWS))])
        if n > MAX_TABLE_ROWS:
            page.add(f"<p class='muted'>first {MAX_TABLE_ROWS} of {n} rows</p>")
    return False


def _files_section(page: _Page, folder: Path, files: list[str], summary: Mapping[str, Any]) -> None:
    """The folder's files, each with what it holds (``summary["file_descriptions"]``) and its size."""
    described = summary.get("file_descriptions") if isinstance(summary.get("file_descriptions"), Mapping) else {}
    rows = [[f, str(described.get(f) or "—"), (folder / f).lstat().st_size] for f in files]
    page.add('<h2 id="files">Files</h2>')
    page.table(["file", "what it holds", "bytes"], rows)


def _variables_section(page: _Page, summary: Mapping[str, Any]) -> None:
    groups = summary.get("variables")
    params = summary.get("model_parameters")
    if not isinstance(groups, Mapping) and not isinstance(params, Mapping):
        return
    page.add('<h2 id="variables">Model variables</h2>')
    bounds = summary.get("bounds") if isinstance(summary.get("bounds"), Mapping) else {}
    units = summary.get("units") if isinstance(summary.get("units"), Mapping) else {}
    if isinstance(groups, Mapping):
        rows = []
        for group, names in groups.items():
            for n in names or []:
                lo, hi = bounds.get(n, (None, None)) if isinstance(bounds.get(n), (list, tuple)) else (None, None)
                rows.append([n, group, units.get(n, ""), json.dumps(lo) if isinstance(lo, list) else lo,
                             json.dumps(hi) if isinstance(hi, list) else hi])
        page.table(["variable", "kind", "unit", "lower bound", "upper bound"], rows)
    if isinstance(params, Mapping) and params:
        page.add("<h3>parameters</h3>")
        page.table(["parameter", "value", "unit"], [[k, json.dumps(v) if not _is_scalar(v) else v, units.get(k, "")]
                                                    for k, v in params.items()])


def render_report(folder: str | Path, summary: Mapping[str, Any] | None = None, plotly_js: str | None = None) -> str:
    """The HTML page of a result folder.

    Parameters
    ----------
    folder : str or pathlib.Path
        The result folder (its CSV tables, PNG plots and Markdown tables are read).
    summary : Mapping[str, Any], optional
        Its summary; default the folder's ``summary.json``.
    plotly_js : str, optional
        Plotly's script to inline; default the vendored basic bundle :data:`PLOTLY_JS` (a
        test may pass a stand-in).

    Returns
    -------
    str
        The page, one self-contained HTML document.

    Raises
    ------
    InputError
        No ``summary.json`` to read (and none given), or it is not a JSON object.
    """
    folder = Path(folder)
    if summary is None:
        try:
            summary = json.loads(_read_regular(folder / "summary.json").decode("utf-8"))
        except (OSError, ValueError) as exc:
            raise InputError(f"{folder}: no readable summary.json, not a result folder ({exc})") from None
    if not isinstance(summary, Mapping):
        raise InputError(f"{folder / 'summary.json'}: expected a JSON object")
    if plotly_js is None:
        plotly_js = PLOTLY_JS.read_text(encoding="utf-8")
    page = _Page()
    name, kind, status = summary.get("name", folder.name), summary.get("kind"), summary.get("status", "unknown")
    files, refused = _folder_files(folder, summary)
    warnings = _warnings(summary) + refused
    page.add('<section id="status">')
    page.add(f"<h1>{_esc(name)}</h1><p>{_esc(kind or 'result')} &middot; <span class='status {_status_class(status)}'>"
             f"{_esc(status)}</span> {_esc(summary.get('message', ''))}</p>")
    if summary.get("description"):
        page.add(f"<p>{_esc(summary['description'])}</p>")
    key = [(k, summary[k]) for k in ("objective", "final_time_s", "solve_time_s", "iterations") if _is_scalar(summary.get(k))
           and summary.get(k) is not None]
    if key:
        page.add("<p>" + " &middot; ".join(f"<b>{_esc(k)}</b> {_esc(_fmt(v))}" for k, v in key) + "</p>")
    page.add("<ul class='warnings'>" + "".join(f"<li>{_esc(w)}</li>" for w in warnings) + "</ul>" if warnings
             else "<p class='muted' id='warnings'>no warnings</p>")
    page.add("</section>")
    csvs = [f for f in files if f.endswith(".csv")]
    page.add('<section id="trajectories"><h2>Trajectories</h2>')
    series = [f for f in csvs if _csv_section(page, folder, f, summary, figures=True)]
    if not series:
        page.add("<p class='muted'>no table with a time column in this folder</p>")
    page.add("</section>")
    if "verification" in summary:
        _verification_section(page, summary["verification"])
    if isinstance(summary.get("benchmark"), Mapping):
        page.add("<h2>Benchmark</h2>")
        page.table(["field", "value"], [[k, v] for k, v in summary["benchmark"].items()])
    _summary_section(page, summary)
    _variables_section(page, summary)
    tables = [f for f in csvs if f not in series]
    if tables or any(f.endswith(".md") for f in files):
        page.add('<h2 id="tables">Tables</h2>')
    for f in tables:
        _csv_section(page, folder, f, summary, figures=False)
    for f in (f for f in files if f.endswith(".md")):
        page.add(f"<h3>{_esc(f)}</h3><pre>{_esc(_read_regular(folder / f).decode('utf-8', errors='replace'))}</pre>")
    pngs = [f for f in files if f.endswith(".png")]
    if pngs:
        page.add('<h2 id="plots">Plots</h2>')
        for f in pngs:
            page.png(f, _read_regular(folder / f))
    _files_section(page, folder, files, summary)
    page.add(f"<h2>summary.json</h2><details><summary>show</summary><pre>{_esc(json.dumps(summary, indent=2))}</pre></details>")
    title = _esc(f"{name}: {status}")
    return page.html("<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>"
                     "<meta name='viewport' content='width=device-width, initial-scale=1'>"
                     f"<link rel='icon' href='data:,'><title>{title}</title><style>{_CSS}</style>"
                     f"<script>{plotly_js}</script></head>\n<body>\n",
                     f"\n<script>{_SCRIPT}</script>\n</body></html>\n")


def write_report(folder: str | Path, summary: Mapping[str, Any] | None = None, path: str | Path | None = None) -> Path:
    """Write the HTML page of a result folder (:func:`render_report`).

    Parameters
    ----------
    folder : str or pathlib.Path
        The result folder.
    summary : Mapping[str, Any], optional
        Its summary; default the folder's ``summary.json``.
    path : str or pathlib.Path, optional
        The file to write; default ``folder / "report.html"``.

    Returns
    -------
    pathlib.Path
        The written page.

    Raises
    ------
    InputError
        As :func:`render_report`.
    OSError
        The page cannot be written.
    """
    folder = Path(folder)
    target = Path(path) if path is not None else folder / REPORT_FILE
    target.write_text(render_report(folder, summary), encoding="utf-8")
    return target
