"""report.html, the page of a result folder (gtmodel.report.result_page, gtmodel report DIR).

The page's figures are checked against the CSV tables they were made from (the data the
run wrote), its bounds against ``summary.json``; the browser tests open the page in a real
Chromium (Debian's package, driven by Playwright) and check that it loads without console
errors and shows every figure, for each shipped problem's result.
"""

from __future__ import annotations

import base64
import json
import os
import re
import shutil
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gtmodel.cli import main
from gtmodel.errors import InputError
from gtmodel.report.result_page import MAX_POINTS, REPORT_FILE, decimate, read_csv_columns, render_report

from ..conftest import PROBLEMS_DIR, solve_through_cli

STUB_JS = "/* plotly stand-in */ window.Plotly = {newPlot: function () {}};"
SPEC = re.compile(r'<script type="application/json" class="gt-figure-spec" data-target="([^"]+)">(.*?)</script>', re.S)


def _specs(page: str) -> list[dict]:
    return [json.loads(body) for _, body in SPEC.findall(page)]


def _folder(tmp_path: Path, n: int = 11, summary: dict | None = None) -> Path:
    """A result folder as a run writes it: a trajectory table, a table without time, a PNG."""
    out = tmp_path / "res"
    out.mkdir()
    t = np.linspace(0.0, 2.0, n).tolist()
    rows = ["t,x,u,which"] + [f"{a!r},{np.sin(a).item()!r},{np.cos(a).item()!r},{'boundary' if i % 3 == 0 else 'collocation'}"
                              for i, a in enumerate(t)]
    (out / "trajectories.csv").write_text("\n".join(rows) + "\n")
    (out / "fits.csv").write_text("case,gain\nA,1.5\nB,2.5\n")
    (out / "states.png").write_bytes(b"\x89PNG\r\n\x1a\nnot-really-a-png")
    base = {
        "name": "demo", "kind": "optimal_control", "status": "check_failed", "message": "Solve_Succeeded", "objective": 1.25,
        "variables": {"states": ["x"], "inputs": ["u"], "algebraics": [], "outputs": []},
        "units": {"x": "m", "u": "N"}, "bounds": {"u": [-0.5, None], "x": [None, 0.75]},
        "verification": {"passed": False, "tolerance": 0.01, "message": "x deviates 3e-2 at t = 1.2 s",
                         "states": {"x": {"max_abs_deviation": 0.03, "at_time_s": 1.2}}},
        "benchmark": {"published": 1.0, "value": 1.25, "relative_error": 0.25, "tolerance": 0.01},
        "files": ["summary.json", "fits.csv", "states.png", "trajectories.csv"],
    }
    base.update(summary or {})
    (out / "summary.json").write_text(json.dumps(base))
    return out


def test_trajectory_figures_hold_the_table_and_the_bounds(tmp_path):
    """Each group (states, inputs) is a figure; its traces are the CSV's columns, bounds dashed lines from summary.json."""
    out = _folder(tmp_path)
    specs = _specs(render_report(out, plotly_js=STUB_JS))
    _, cols = read_csv_columns(out / "trajectories.csv")
    assert [s["layout"]["title"]["text"] for s in specs] == ["trajectories.csv: states", "trajectories.csv: inputs"]
    states, inputs = specs
    assert [tr["name"] for tr in states["data"]] == ["x", "x upper bound"] and states["data"][1]["y"] == [0.75, 0.75]
    assert [tr["name"] for tr in inputs["data"]] == ["u", "u lower bound"] and inputs["data"][1]["y"] == [-0.5, -0.5]
    np.testing.assert_allclose(states["data"][0]["y"], cols["x"], rtol=5e-6)  # 6 significant digits
    np.testing.assert_allclose(inputs["data"][0]["y"], cols["u"], rtol=5e-6)
    np.testing.assert_allclose(states["data"][0]["x"], cols["t"], rtol=5e-6)
    assert all("_bound" not in tr for tr in states["data"] + inputs["data"])
    assert states["layout"]["yaxis"]["title"]["text"] == "x [m]"


def test_the_page_says_what_is_not_to_be_relied_on(tmp_path):
    page = render_report(_folder(tmp_path), plotly_js=STUB_JS)
    warnings = re.search(r"<ul class='warnings'>(.*?)</ul>", page, re.S).group(1)
    assert re.findall(r"<li>(.*?)</li>", warnings) == [
        "verification failed: x deviates 3e-2 at t = 1.2 s", "benchmark: relative error 0.25 beyond its tolerance 0.01"]
    assert "<span class='status warn'>check_failed</span>" in page


def test_tables_and_plots_of_the_folder_are_in_the_page(tmp_path):
    """A table without a time column is shown as a table; a PNG is inlined byte for byte."""
    out = _folder(tmp_path)
    page = render_report(out, plotly_js=STUB_JS)
    assert "<td>A</td><td class=\"num\">1.5</td>" in page
    assert base64.b64encode((out / "states.png").read_bytes()).decode() in page


def test_a_long_table_is_min_max_decimated_keeping_its_peaks(tmp_path):
    """Independent check: NumPy's min and max of the raw column, and its first and last sample."""
    n = 3 * MAX_POINTS + 7
    out = _folder(tmp_path, n=n)
    spec = _specs(render_report(out, plotly_js=STUB_JS))[0]
    trace = spec["data"][0]
    _, cols = read_csv_columns(out / "trajectories.csv")
    assert len(trace["x"]) <= MAX_POINTS < n
    assert trace["x"][0] == cols["t"][0] and trace["x"][-1] == pytest.approx(cols["t"][-1])
    assert max(trace["y"]) == pytest.approx(max(cols["x"]), rel=5e-6) and min(trace["y"]) == pytest.approx(min(cols["x"]), rel=5e-6)
    assert f"min-max decimated to at most {MAX_POINTS} of {n} samples" in spec["layout"]["title"]["text"]  # 2 traces: MAX_POINTS each


@pytest.mark.parametrize("points", [4, 5, 10, 101, 1000])
def test_decimation_keeps_every_bucket_extreme(points):
    """A random walk with NaN gaps: the kept samples hold the global min and max, the ends, in order."""
    rng = np.random.default_rng(points)
    y = np.cumsum(rng.normal(size=5003))
    y[rng.integers(0, y.size, 40)] = np.nan
    x = np.arange(y.size) * 0.004
    xs, ys = decimate(x, y, points)
    assert xs.size <= points and xs[0] == x[0] and xs[-1] == x[-1] and np.all(np.diff(xs) > 0)
    assert np.nanmax(ys) == np.nanmax(y) and np.nanmin(ys) == np.nanmin(y)


@pytest.mark.parametrize("x, y, points, match", [
    ([0.0, 1.0], [0.0, 1.0], 3, "points: expected an integer >= 4"),
    ([0.0, 1.0], [0.0, 1.0], 4.0, "points: expected an integer >= 4"),
    ([0.0, 1.0], [0.0], 4, "x, y: expected two arrays of one shape"),
])
def test_decimation_refuses_bad_arguments(x, y, points, match):
    with pytest.raises(InputError, match=match):
        decimate(x, y, points)


def test_a_page_over_its_limit_shows_its_pngs_from_the_folder(tmp_path, monkeypatch):
    """A PNG that would take the page beyond PAGE_LIMIT is linked, not inlined, and the page says so."""
    from gtmodel.report import result_page

    out = _folder(tmp_path)
    monkeypatch.setattr(result_page, "PAGE_LIMIT", len(render_report(out, plotly_js=STUB_JS)) - 10)
    page = render_report(out, plotly_js=STUB_JS)
    assert "src='states.png'" in page and "shown from the file beside this page" in page and "data:image/png" not in page


def test_without_variable_groups_every_column_is_a_panel(tmp_path):
    """Another kind's table (no ``variables`` in its summary): one figure, a panel per numeric column."""
    out = _folder(tmp_path, summary={"variables": None, "kind": "tracking"})
    (spec,) = _specs(render_report(out, plotly_js=STUB_JS))
    assert [tr["name"] for tr in spec["data"] if "bound" not in tr["name"]] == ["x", "u"]


@pytest.mark.parametrize(
    "text, match",
    [
        ("", "no header row"),
        ("# only a comment\n", "no header row"),
        ("t,x\n0,1\n1\n", r"line 3: 1 values, expected 2"),
        (b"t,x\n0,\xff\n", "cannot read the table"),
    ],
    ids=["empty", "comments only", "short row", "not UTF-8"],
)
def test_unreadable_tables_are_refused_naming_the_file(tmp_path, text, match):
    path = tmp_path / "bad.csv"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    with pytest.raises(InputError, match=match) as info:
        read_csv_columns(path)
    assert str(path) in str(info.value)


def test_a_folder_without_summary_is_not_a_result(tmp_path):
    with pytest.raises(InputError, match="no readable summary.json, not a result folder"):
        render_report(tmp_path, plotly_js=STUB_JS)


@pytest.fixture(scope="module")
def solved(tmp_path_factory) -> Path:
    """``gtmodel solve problems/benchmarks/bryson_denham.toml`` (0.1 s solve): the folder with its report."""
    out = tmp_path_factory.mktemp("solved") / "bryson_denham"
    code, _ = solve_through_cli(PROBLEMS_DIR / "benchmarks" / "bryson_denham.toml", out)
    assert code == 0
    return out


def test_solve_writes_a_self_contained_report_listed_in_the_summary(solved):
    summary = json.loads((solved / "summary.json").read_text())
    page = (solved / REPORT_FILE).read_text()
    assert REPORT_FILE in summary["files"]
    assert re.findall(r"<(?:script|link|img)[^>]+(?:src|href)=['\"](?!data:)", page) == []  # nothing fetched
    assert "Plotly.newPlot" in page and len(page) > 1_000_000  # Plotly's own script inlined
    assert summary["bounds"] == {} and summary["variables"] == {"states": ["x", "v"], "inputs": ["u"], "algebraics": [],
                                                                "outputs": []}


def test_no_report_writes_none(tmp_path):
    code, summary = solve_through_cli(PROBLEMS_DIR / "benchmarks" / "bryson_denham.toml", tmp_path / "r", "--no-report")
    assert code == 0 and REPORT_FILE not in summary["files"] and not (tmp_path / "r" / REPORT_FILE).exists()


def test_report_command_adds_the_page_and_changes_nothing_else(solved, tmp_path, capsys):
    folder = tmp_path / "copy"
    shutil.copytree(solved, folder)
    (folder / REPORT_FILE).unlink()
    before = {p.name: p.read_bytes() for p in folder.iterdir() if p.name != "summary.json"}
    summary = json.loads((folder / "summary.json").read_text())
    summary["files"].remove(REPORT_FILE)
    (folder / "summary.json").write_text(json.dumps(summary))
    assert main(["report", str(folder)]) == 0
    after = json.loads((folder / "summary.json").read_text())
    assert after == {**summary, "files": [*summary["files"], REPORT_FILE]}
    assert {p.name: p.read_bytes() for p in folder.iterdir() if p.name not in ("summary.json", REPORT_FILE)} == before
    assert sorted(p.name for p in folder.iterdir()) == sorted(after["files"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["copy"]  # no partial or lock file left beside it
    assert f"wrote {folder / REPORT_FILE}" in capsys.readouterr().out


def test_report_command_refuses_a_folder_no_run_wrote(tmp_path, capsys):
    (tmp_path / "mine.txt").write_text("my notes")
    assert main(["report", str(tmp_path)]) == 2
    assert "not a gtmodel result folder" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.txt"]


# --------------------------------------------------------------------------- hostile names and folders
#: Units and column names that end or alter a script block or a JavaScript string unless escaped.
HOSTILE = ["<!--<script>", "</script><script>document.title='pwned'</script>\u2028\u2029", "a & b > c", "<!--"]


def _hostile_folder(tmp_path: Path) -> Path:
    """A result folder whose units and CSV column names hold script-block breakers."""
    out = _folder(tmp_path, summary={"units": {"x": HOSTILE[0], "u": HOSTILE[1]},
                                     "variables": {"states": ["x", HOSTILE[0]], "inputs": ["u", HOSTILE[3]]}})
    t = np.linspace(0.0, 1.0, 5)
    rows = [f"t,x,u,{HOSTILE[0]},{HOSTILE[3]},{HOSTILE[2]}"] + [",".join(repr(float(v)) for v in (a, a, -a, 2 * a, 3 * a, 4 * a)) for a in t]
    (out / "trajectories.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    return out


def test_script_blocks_hold_hostile_units_and_column_names_exactly(tmp_path):
    """Every figure's JSON block ends where it should (no ``<`` inside) and parses back to the names given.

    Independent check: the block count equals the figure containers, and ``json.loads`` of each
    block returns the unit and column strings byte for byte."""
    page = render_report(_hostile_folder(tmp_path), plotly_js=STUB_JS)
    blocks = SPEC.findall(page)
    assert len(blocks) == page.count('<div class="gt-figure"') == 3  # states, inputs, other columns
    assert not any(c in body for _, body in blocks for c in "<>&\u2028\u2029")
    specs = [json.loads(body) for _, body in blocks]
    names = [tr["name"] for s in specs for tr in s["data"] if "bound" not in tr["name"]]
    assert names == ["x", HOSTILE[0], "u", HOSTILE[3], HOSTILE[2]]
    assert specs[0]["layout"]["yaxis"]["title"]["text"] == f"x [{HOSTILE[0]}]"
    assert specs[1]["layout"]["yaxis"]["title"]["text"] == f"u [{HOSTILE[1]}]"
    assert page.count("<script") == page.count("</script>") == 2 + len(blocks)  # Plotly, the drawing script, the blocks


@pytest.fixture()
def linked_folder(tmp_path):
    """A result folder with ``states.png -> /etc/passwd``, a CSV linked from outside and listed names outside it."""
    out = _folder(tmp_path)
    outside = tmp_path / "outside.csv"
    outside.write_text("t,secret\n0,42\n1,43\n")
    (out / "states.png").unlink()
    (out / "states.png").symlink_to("/etc/passwd")
    (out / "fits.csv").unlink()
    (out / "fits.csv").symlink_to(outside)
    (out / "sub").symlink_to(tmp_path)
    (out / "notes.md").unlink(missing_ok=True)
    os.link(outside, out / "notes.md")  # a hard link to a file outside
    summary = json.loads((out / "summary.json").read_text())
    summary["files"] += ["notes.md", "../outside.csv", "/etc/passwd", "sub/outside.csv"]
    (out / "summary.json").write_text(json.dumps(summary))
    return out


def test_a_result_folder_contributes_only_regular_files_inside_it(linked_folder):
    """Links and names leading outside are left out, each with a warning in the page; nothing of theirs is inlined."""
    page = render_report(linked_folder, plotly_js=STUB_JS)
    passwd = Path("/etc/passwd").read_bytes()
    assert base64.b64encode(passwd).decode() not in page and passwd.decode().splitlines()[0] not in page
    assert "secret" not in page and "<img" not in page
    warnings = re.findall(r"<li>(.*?)</li>", re.search(r"<ul class='warnings'>(.*?)</ul>", page, re.S).group(1))
    assert [w.split(":")[0] for w in warnings[2:]] == ["fits.csv", "states.png", "notes.md", "../outside.csv", "/etc/passwd",
                                                       "sub/outside.csv"]
    assert [w.split(": ")[1].split(" (")[0].split(",")[0] for w in warnings[2:]] == [
        "a symbolic link", "a symbolic link", "a hard link", "outside the result folder", "outside the result folder",
        "a symbolic link"]


def test_report_command_never_inlines_a_linked_file(solved, tmp_path, capsys):
    """``gtmodel report`` on a folder holding ``states.png -> /etc/passwd``: exit 0, the link named, not inlined."""
    folder = tmp_path / "copy"
    shutil.copytree(solved, folder)
    (folder / "states.png").unlink()
    (folder / "states.png").symlink_to("/etc/passwd")
    assert main(["report", str(folder)]) == 0
    page = (folder / REPORT_FILE).read_text()
    assert "states.png: a symbolic link, not shown" in page
    assert Path("/etc/passwd").read_text().splitlines()[0] not in page
    assert base64.b64encode(Path("/etc/passwd").read_bytes()).decode() not in page


def test_report_command_refuses_a_linked_summary(solved, tmp_path, capsys):
    folder = tmp_path / "copy"
    shutil.copytree(solved, folder)
    (folder / "summary.json").rename(tmp_path / "elsewhere.json")
    (folder / "summary.json").symlink_to(tmp_path / "elsewhere.json")
    assert main(["report", str(folder)]) == 2
    assert "summary.json: a symbolic link" in capsys.readouterr().err


# --------------------------------------------------------------------------- in a browser
CHROMIUM = shutil.which("chromium") or ("/usr/bin/chromium" if Path("/usr/bin/chromium").exists() else None)
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
                 "--disable-sync", "--no-first-run"]
SHIPPED = sorted([*PROBLEMS_DIR.glob("*.toml"), *PROBLEMS_DIR.glob("benchmarks/*.toml"), *PROBLEMS_DIR.glob("thesis/*.toml")])
#: The shipped problem whose report the default run opens (it solves in 0.1 s); the others (1-25 s each) are marked slow.
QUICK = {"bryson_denham.toml"}


@pytest.fixture(scope="module")
def browser():
    if CHROMIUM is None:
        pytest.skip("no Chromium installed (apt-get install chromium): the report's browser test needs one")
    sync_api = pytest.importorskip("playwright.sync_api", reason="Playwright's Python package is not installed (pip install playwright)")
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield b
        b.close()


def open_page(browser, path: Path) -> dict:
    """Open a page from disk; what the browser says and shows."""
    page = browser.new_page()
    messages: list[str] = []
    page.on("console", lambda m: messages.append(f"{m.type}: {m.text}") if m.type in ("error", "warning") else None)
    page.on("pageerror", lambda e: messages.append(f"page error: {e}"))
    page.on("requestfailed", lambda r: messages.append(f"request failed: {r.url}"))
    page.goto(path.resolve().as_uri())
    page.wait_for_load_state("load")
    shown = {
        "messages": messages,
        "figures": page.locator("div.gt-figure").count(),
        "drawn": page.locator("div.gt-figure .main-svg").count() // 3,  # Plotly draws three SVG layers per figure
        "traces": page.evaluate("Array.from(document.querySelectorAll('div.gt-figure')).map(d => (d.data || []).length)"),
        "images": page.evaluate("Array.from(document.images).map(i => i.complete && i.naturalWidth > 0)"),
        "status": page.locator("span.status").first.inner_text(),
        "axes": page.evaluate(_AXES),
        "title": page.title(),
    }
    page.close()
    return shown


@pytest.mark.parametrize("path", [pytest.param(p, id=p.name, marks=() if p.name in QUICK else pytest.mark.slow) for p in SHIPPED])
def test_the_report_of_a_shipped_problem_opens_in_chromium(browser, path, tmp_path):
    out = tmp_path / "res"
    code, summary = solve_through_cli(path, out)
    assert code in (0, 1)
    shown = open_page(browser, out / REPORT_FILE)
    pngs = [f for f in summary["files"] if f.endswith(".png")]
    assert (out / REPORT_FILE).stat().st_size < MAX_PAGE_BYTES  # the state estimation's was 8.2 MB, lead-through's 4.1 MB
    unitless = [a for a in shown["axes"] if not re.search(r" \[[^\]]+\]$", a)]
    assert unitless == []  # every axis titled "name [unit]"
    assert shown["messages"] == []
    assert shown["status"] == summary["status"]
    assert shown["drawn"] == shown["figures"] and all(n > 0 for n in shown["traces"])
    assert shown["images"] == [True] * len(pngs)
    if summary["kind"] in ("optimal_control", "point_to_point", "path_constrained"):
        assert shown["figures"] >= 1


def test_a_report_with_hostile_units_and_column_names_draws_every_figure(browser, tmp_path):
    """``<!--<script>`` and ``</script>`` in units and column names: every figure drawn, no console error."""
    out = _hostile_folder(tmp_path)
    (out / "states.png").unlink()
    summary = json.loads((out / "summary.json").read_text())
    summary["files"].remove("states.png")
    (out / "summary.json").write_text(json.dumps(summary))
    (out / REPORT_FILE).write_text(render_report(out), encoding="utf-8")
    shown = open_page(browser, out / REPORT_FILE)
    assert shown["messages"] == []
    assert shown["figures"] == shown["drawn"] == 3 and shown["traces"] == [3, 3, 1]
    assert shown["title"] == "demo: check_failed"


#: Units and column names: arbitrary Unicode with script-block breakers mixed in (a column name
#: holds no comma, quote or line break: the CSV reader's rule, gtmodel._escape.csv_name).
_NAME_PARTS = st.one_of(st.text(st.characters(blacklist_categories=("Cc", "Cs", "Zl", "Zp")), max_size=6),
                        st.sampled_from(["<!--", "<script>", "</script>", "<!--<script>", "&", "]]>", "*/", "\\"]))
_NAMES = st.lists(_NAME_PARTS, min_size=1, max_size=5).map("".join).map(lambda s: s.replace(",", ";").replace('"', "'").strip())


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(units=st.lists(_NAMES.map(lambda s: s + "\u2028\u2029"), min_size=2, max_size=2), column=_NAMES.filter(
    lambda s: s and not s.startswith("#") and s not in ("t", "x", "u") and not re.fullmatch(r"(t|time)(_s| ?\[s\])?", s, re.I)))
def test_any_unit_and_column_name_stays_inside_its_script_block(tmp_path_factory, units, column):
    """Arbitrary units and column names: Python's HTML parser (independent of the writer) finds
    one JSON block per figure container, each parsing back to the names given."""
    out = _folder(tmp_path_factory.mktemp("names"), summary={"units": {"x": units[0], "u": units[1]}})
    rows = [f"t,x,u,{column}"] + [f"{a!r},{a!r},{-a!r},{2 * a!r}" for a in (0.0, 0.5, 1.0)]
    (out / "trajectories.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    page = render_report(out, plotly_js=STUB_JS)
    blocks = _ScriptBlocks.of(page)
    assert len(blocks) == page.count('<div class="gt-figure"') == 3
    specs = [json.loads(b) for b in blocks]
    assert [tr["name"] for s in specs for tr in s["data"] if "bound" not in tr["name"]] == ["x", "u", column]
    assert [s["layout"]["yaxis"]["title"]["text"] for s in specs[:2]] == [f"x [{units[0]}]" if units[0] else "x",
                                                                            f"u [{units[1]}]" if units[1] else "u"]


class _ScriptBlocks(HTMLParser):
    """The text of every ``<script type="application/json">`` element, as an HTML parser sees it."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=False)
        self.blocks: list[str] = []
        self._inside = False

    @classmethod
    def of(cls, page: str) -> list[str]:
        parser = cls()
        parser.feed(page)
        return parser.blocks

    def handle_starttag(self, tag, attrs):
        self._inside = tag == "script" and ("type", "application/json") in attrs
        if self._inside:
            self.blocks.append("")

    def handle_endtag(self, tag):
        self._inside = False

    def handle_data(self, data):
        if self._inside:
            self.blocks[-1] += data


@pytest.mark.parametrize("header", ["t,point,ind.i", "t [s],point,ind.i [A]"], ids=["before-units", "with-units"])
def test_unit_headers_name_the_same_columns(tmp_path, header):
    """A table with ``name [unit]`` headers and one written before units give the same columns (written out by hand)."""
    path = tmp_path / "trajectories.csv"
    path.write_text(header + "\n0,start,1.5\n0.5,collocation,2\n")
    names, cols = read_csv_columns(path)
    assert names == ["t", "point", "ind.i"] and cols["ind.i"] == [1.5, 2.0] and cols["point"] == ["start", "collocation"]


# --------------------------------------------------------------------------- what a reader sees first
#: The page's budget: Plotly's basic bundle (1.19 MB) and the folder's data and plots.
MAX_PAGE_BYTES = 2_000_000
_AXES = """Array.from(document.querySelectorAll('div.gt-figure')).flatMap(d => Object.keys(d._fullLayout)
  .filter(k => /^[xy]axis\\d*$/.test(k)).map(k => d._fullLayout[k].title.text))"""


def test_l1_time_optimal_opens_on_its_status_and_trajectories_with_units(browser, tmp_path):
    """The page of problems/l1_time_optimal.toml in Chromium: under 2 MB; the first section holds
    the status, the second the trajectory figure, inside the first screen (900 px); every axis of
    every figure titled ``name [unit]`` (the units of summary.json, read independently here)."""
    out = tmp_path / "l1"
    code, summary = solve_through_cli(PROBLEMS_DIR / "l1_time_optimal.toml", out)
    assert code == 0
    page_path = out / REPORT_FILE
    assert page_path.stat().st_size < MAX_PAGE_BYTES
    page = browser.new_page(viewport={"width": 1280, "height": 900})
    page.goto(page_path.resolve().as_uri())
    page.wait_for_load_state("load")
    sections = page.evaluate("Array.from(document.querySelectorAll('body > section')).map(s => s.id)")
    status = page.locator("section#status span.status").inner_text()
    top = page.evaluate("document.querySelector('section#trajectories div.gt-figure .main-svg').getBoundingClientRect().top")
    titles = page.evaluate(_AXES)
    page.close()
    assert sections[:2] == ["status", "trajectories"] and status == summary["status"]
    assert 0 < top < 900
    header = (out / "trajectory.csv").read_text().splitlines()[0].split(",")
    expected = {f"{c} [{summary['units'][c]}]" for c in header}
    assert set(titles) == expected  # t [s] on the time axes, every column with its unit


def test_the_page_lists_every_file_with_its_description(tmp_path):
    out = _folder(tmp_path, summary={"file_descriptions": {"summary.json": "the run", "fits.csv": "gains per case",
                                                           "states.png": "the states"}})
    page = render_report(out, plotly_js=STUB_JS)
    files = re.search(r'<h2 id="files">Files</h2>(.*?)</table>', page, re.S).group(1)
    rows = re.findall(r"<tr><td>([^<]*)</td><td>([^<]*)</td>", files)
    assert rows == [("summary.json", "the run"),
                    ("fits.csv", "gains per case"), ("states.png", "the states"), ("trajectories.csv", "—")]


def test_trajectories_come_before_verification_and_tables(tmp_path):
    page = render_report(_folder(tmp_path), plotly_js=STUB_JS)
    order = [page.index(mark) for mark in ('<section id="status">', '<section id="trajectories">', 'class="gt-figure"',
                                           'id="verification"', 'id="tables"', 'id="plots"', 'id="files"')]
    assert order == sorted(order)
