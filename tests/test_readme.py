"""The README stays a way in: its set-up commands match .ci/run, it is short, its map is complete.

Its code blocks run in tests/test_docs.py, with those of every page of docs/.
"""

from __future__ import annotations

import re

from .conftest import REPO

README = (REPO / "README.md").read_text()
SETUP = re.findall(r"```bash[^\n]*\n(.*?)```", README, flags=re.S)[0]


def test_readme_has_a_python_example():
    assert re.search(r"```python\n.*?from gtmodel\.modeling\.library import", README, flags=re.S)


def test_ci_runs_the_readme_test_command():
    commands = [line.strip() for line in SETUP.splitlines() if line.strip() and not line.startswith("#")]
    assert len([c for c in commands if "pytest" in c]) == 1
    ci = [line.strip() for line in (REPO / ".ci" / "run").read_text().splitlines()]
    assert [c for c in commands if c not in ci] == []  # both of README's commands, unchanged


def test_quick_start_command_names_a_shipped_problem():
    solve = re.search(r"gtmodel solve (\S+)", SETUP)
    assert solve and (REPO / solve.group(1)).is_file()


def test_readme_is_an_entry_point_of_about_a_thousand_words():
    words = len(README.split())
    assert words <= 1100, f"README.md has {words} words; move the detail into a page of docs/"


def test_the_map_links_every_page_and_every_link_resolves():
    links = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", README)
    local = [link for link in links if not link.startswith("http")]
    assert [link for link in local if not (REPO / link).is_file()] == []
    pages = {p.relative_to(REPO).as_posix() for p in (REPO / "docs").glob("*.md")}
    site_only = {"docs/index.md", "docs/codegen_harness.md", "docs/notebooks_list.md"}  # copies made for the site
    expected = (pages - site_only) | {"codegen/README.md", "notebooks/README.md"}
    assert expected - set(local) == set(), f"not linked from README's map: {sorted(expected - set(local))}"


def test_links_between_pages_resolve():
    # relative links of docs/*.md and the two folder READMEs point at files that exist
    broken = []
    for page in [*(REPO / "docs").glob("*.md"), REPO / "codegen" / "README.md", REPO / "notebooks" / "README.md"]:
        for link in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", page.read_text(encoding="utf-8")):
            if not link.startswith(("http:", "https:", "mailto:")) and not (page.parent / link).exists():
                broken.append(f"{page.relative_to(REPO)}: {link}")
    assert broken == []


def test_ci_runs_the_slow_tests_after_the_readme_command():
    """The slow-marked tests are left out of the default run; CI runs them after it, the real-time ones in a step of their own."""
    lines = [ln.strip() for ln in (REPO / ".ci" / "run").read_text().splitlines()]
    readme_line = next(i for i, ln in enumerate(lines) if "pytest" in ln)
    after = lines[readme_line + 1 :]
    slow = next(i for i, ln in enumerate(after) if ln.endswith('python -P -m pytest -m "slow and not realtime"'))
    assert any(ln.endswith("python -P -m pytest -m realtime -n 0") for ln in after[slow + 1 :])
