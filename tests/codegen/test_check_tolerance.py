"""A self-check never reports a function OK outside its tolerance as printed (issue 24, defect (d)).

``gtmodel codegen --real float --check`` printed ``max |C - Python| = 2.0e-04 N (tol 0.0001) OK``:
the single-precision tolerance is relative (``1e-4 (1 + |Python|)``) but was printed as if
absolute. The line now prints the rule and the share of it used, and a check whose
difference is above its tolerance is FAILED whatever its comparison said.
"""

from __future__ import annotations

import re

import numpy as np

from gtmodel.codegen import check_generated as check, generate
from gtmodel.codegen.check import FLOAT_RELATIVE_TOLERANCE, CheckReport, FunctionCheck, within


def _report(*functions: FunctionCheck) -> CheckReport:
    return CheckReport(robot="L1", prefix="gt_L1", n=10, seed=0, functions=functions, probes=())


def test_a_difference_above_an_absolute_tolerance_is_failed():
    above = FunctionCheck("ik", 10, 2e-12, 1e-12, "m", 0, True)  # a comparison that claimed to pass
    assert not above.ok
    report = _report(above)
    assert not report.passed
    lines = report.summary_lines()
    assert lines[1] == "ik: max |C - Python| = 2.0e-12 m (tol 1e-12) FAILED"
    assert lines[-1] == "FAILED"
    assert _report(FunctionCheck("ik", 10, 1e-12, 1e-12, "m", 0, True)).passed


def test_a_relative_rule_is_printed_with_the_share_used():
    used = FunctionCheck("inverse_dynamics", 10, 2e-4, 1e-4, "N", 0, True, tolerance_rule="x (1 + |Python|)", max_ratio=0.7)
    assert used.ok
    assert _report(used).summary_lines()[1] == (
        "inverse_dynamics: max |C - Python| = 2.0e-04 N (tol 0.0001 x (1 + |Python|), worst 70% of it) OK")
    over = FunctionCheck("inverse_dynamics", 10, 2e-4, 1e-4, "N", 0, True, tolerance_rule="x (1 + |Python|)", max_ratio=1.5)
    assert not over.ok and not _report(over).passed
    assert _report(over).summary_lines()[1].endswith("(tol 0.0001 x (1 + |Python|), worst 150% of it) FAILED")


def test_within_bounds_each_element_by_its_rule():
    r = np.array([0.0, 1.0, 100.0])
    # single precision: 1e-4 (1 + |r|) per element
    worst, _, ratio, ok = within(r + np.array([5e-5, 1e-4, 1e-2]), r, "float", 1e-12)
    assert ok and np.isclose(worst, 1e-2) and np.isclose(ratio, 1e-2 / (1e-4 * 101))
    *_, ratio, ok = within(r + np.array([2e-4, 0, 0]), r, "float", 1e-12)
    assert not ok and np.isclose(ratio, 2.0)
    # double: absolute, or relative where declared
    assert within(r + 2e-12, r, "double", 1e-12)[3] is False
    assert within(r + np.array([0, 0, 2e-10]), r, "double", 1e-12, rtol=1e-11)[3] is True
    assert within(np.array([np.nan]), np.array([1.0]), "double", 1.0) == (np.inf, np.inf, np.inf, False)


def test_float_check_prints_the_rule_and_is_within_it(tmp_path):
    gen = generate("L1", tmp_path / "gen", real="float", functions=("ik", "inverse_dynamics"))
    report = check(gen, n=200, build_dir=tmp_path / "build")
    lines = report.summary_lines()
    assert report.passed, "\n".join(lines)
    rule = re.compile(r"\(tol 0\.0001 x \(1 \+ \|Python\|\), worst ([0-9.e+-]+)% of it\) OK$")
    bad = [(f.name, f.tolerance, f.max_ratio, line) for f, line in zip(report.functions, lines[1:])
           if not (f.tolerance == FLOAT_RELATIVE_TOLERANCE and f.max_ratio <= 1.0 and (m := rule.search(line)) and float(m.group(1)) <= 100)]
    assert not bad, bad
