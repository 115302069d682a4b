"""report.html, the page of a result folder (gtmodel.report.result_page, gtmodel report DIR).

The page's figures are checked against the CSV tables they were made from (the data the
run wrote), its bounds against ``summary.json``; the browser tests open the page in a real
Chromium (Debian's package, driven by Playwright) and check that it loads without console
errors and shows every figure, for each shipped problem's result.
"""

from __future__ import annotations

import base64
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from gtmodel.cli import main
from gtmodel.errors import InputError
from gtmodel.report.result_page import MAX_POINTS, REPORT_FILE, read_csv_columns, render_report

from ..conftest import PROBLEMS_DIR, solve_through_cli

STUB_JS = "/* plotly stand-in */ window.Plotly = {newPlot: function () {}};"
SPEC = re.compile(r'<script type="application/json" class="gt-figure-spec" data-target="([^"]+)">(.*?)</script>', re.S)


def _specs(page: str) -> list[dict]:
    return [json.loads(body.replace("<\\/", "</")) for _, body in SPEC.findall(page)]


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
    assert [(tr["name"], tr["y"]) for tr in states["data"]] == [("x", cols["x"]), ("x upper bound", [0.75, 0.75])]
    assert [(tr["name"], tr["y"]) for tr in inputs["data"]] == [("u", cols["u"]), ("u lower bound", [-0.5, -0.5])]
    assert states["data"][0]["x"] == cols["t"]
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


def test_a_long_table_is_thinned_to_max_points_with_its_last_sample(tmp_path):
    n = 3 * MAX_POINTS + 7
    out = _folder(tmp_path, n=n)
    trace = _specs(render_report(out, plotly_js=STUB_JS))[0]["data"][0]
    _, cols = read_csv_columns(out / "trajectories.csv")
    assert len(trace["x"]) == len(range(0, n, 4)) + 1 <= MAX_POINTS  # every 4th sample, and the last
    assert trace["x"][-1] == cols["t"][-1]
    assert trace["y"][:3] == [cols["x"][0], cols["x"][4], cols["x"][8]]


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
    assert shown["messages"] == []
    assert shown["status"] == summary["status"]
    assert shown["drawn"] == shown["figures"] and all(n > 0 for n in shown["traces"])
    assert shown["images"] == [True] * len(pngs)
    if summary["kind"] in ("optimal_control", "point_to_point", "path_constrained"):
        assert shown["figures"] >= 1
