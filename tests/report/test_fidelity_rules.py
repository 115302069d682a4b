"""The verdict rules of issue 47 (gtmodel.report.fidelity_rules): patterns, unprinted quantities, limits, mechanisms, self-checks.

Independent reference: hand-made rows whose verdict follows from the rule as the page states it, with the
numbers of the issue (Dressler (2012), (7.28): 0.86 / 0.93 / 0.95; Table 7.2's 43.5 um drop against a 1.69 um
deflection; Cvitanic (2021), Table 10's "< 0.1" against limits whose log10 distance is computed by hand here).
"""

from __future__ import annotations

import math

import pytest

from gtmodel.report import fidelity_rules as rules
from gtmodel.report.fidelity_rules import Case, Mechanism, Row

THESIS = {"2A": 0.86, "2B": 0.93, "3": 0.95}  # Dressler (2012), (7.28)


def _sigma_rows(ours, verdict="structure reproduced"):
    group = "(7.28) Cases [test]"
    return [Row(f"sigma_max Case {n}", str(THESIS[n]), str(o), "0.02", verdict, "Q a choice", (Case(group, n, THESIS[n], o, 0.02),))
            for n, o in zip(THESIS, ours)]


@pytest.mark.parametrize("ours, verdict", [
    ((0.9276, 0.9274, 0.9274), "differs"),  # the case: one Q, one margin in every case
    ((0.87, 0.93, 0.95), "structure reproduced"),  # the thesis' figures within the tolerance
    ((0.80, 0.87, 0.89), "structure reproduced"),  # shifted by 0.06: every gap the thesis' (0.07, 0.09, 0.02)
    ((0.86, 0.88, 0.95), "differs"),  # right order, but the 2A-2B gap 0.02 against the thesis' 0.07 (beyond 2 x 0.02)
    ((0.95, 0.93, 0.86), "differs"),  # reversed
], ids=["one_margin", "as_the_thesis", "shifted", "gap_too_small", "reversed"])
def test_structure_needs_the_thesis_pattern_across_cases(ours, verdict):
    row = rules.apply_rules(_sigma_rows(ours))[0]  # Case 2A: every other case is more than the tolerance from its 0.86
    assert row.verdict == verdict and (verdict != "differs" or row.cause.startswith("the thesis' pattern across the cases is not reproduced"))


@pytest.mark.parametrize("verdict, unprinted, expected", [
    ("reproduced", "our 5-axis EKF Q", "differs"),
    ("predicted", "our 5-axis EKF Q", "differs"),
    ("structure reproduced", "a Kalman model equal to the simulated plant", "differs"),
    ("reproduced", "", "reproduced"),
    ("differs", "our 5-axis EKF Q", "differs"),
], ids=["reproduced", "predicted", "structure", "nothing_unprinted", "already_differs"])
def test_no_row_rests_on_what_the_thesis_does_not_print(verdict, unprinted, expected):
    row = rules.apply_rules([Row("Table 10: limit of gyro_bias_deg_s", "< 1", "2.7", "half a decade", verdict, "set by our Q", unprinted=unprinted)])[0]
    assert row.verdict == expected and (unprinted == "" or verdict == "differs" or row.cause.startswith(f"rests on {unprinted}"))


@pytest.mark.parametrize("ours, thesis, passes", [
    (0.24, 0.1, True),  # log10(2.4) = 0.380
    (0.35, 0.1, False),  # log10(3.5) = 0.544
    (0.0317, 0.1, True),  # log10(0.317) = -0.499
    (0.03, 0.1, False),  # log10(0.3) = -0.523
    (2.7, 1.0, True),  # log10(2.7) = 0.431
    (0.0098, 0.001, False),  # 0.991: within one decade, not half
    (None, 0.1, False),  # no limit found over the search
], ids=["0.38", "0.54", "-0.499", "-0.52", "gyro_bias", "one_decade", "none"])
def test_limits_within_half_a_decade(ours, thesis, passes):
    assert (ours is not None and abs(math.log10(ours / thesis)) <= 0.5) == passes  # the hand computation
    assert rules.limit_within(ours, thesis) == passes
    row = rules.apply_rules([Row("Table 10: 3-axis limit", f"< {thesis:g}", str(ours), "half a decade", "predicted", "fit held", limits=((ours, thesis),))])[0]
    assert row.verdict == ("predicted" if passes else "differs") and (passes or row.cause.startswith("beyond half a decade"))


@pytest.mark.parametrize("thesis, stops_at, limit, verdict", [
    (0.1, 0.35, 0.24, "reproduced"),  # log10(2.4) = 0.380
    (0.001, 0.011, 0.0098, "differs"),  # log10(9.8) = 0.991: the former one-decade rule passed it
    (0.1, None, 3.9, "differs"),  # fusion pays over the whole search: no limit found
    (math.inf, None, 2540.0, "reproduced"),  # "no constraint" and fusion pays over the whole search
    (math.inf, 1.2, 1.0, "differs"),  # "no constraint" but fusion stops paying
    (None, 0.5, 0.4, "N/A"),  # the thesis' N/A (a rotation-only parameter of the 3-axis motion)
], ids=["0.38", "0.99", "none_found", "no_constraint", "constraint_found", "n_a"])
def test_one_limit_rule_for_every_report(thesis, stops_at, limit, verdict):
    """limit_verdict is the page's half-decade rule, which gtmodel.report.fusion's table_10_limits also prints."""
    assert rules.limit_verdict({"thesis_limit": thesis, "stops_at": stops_at, "limit": limit}) == verdict


@pytest.mark.parametrize("effect, capacity, verdict", [
    (43.5, 1.69, "differs"),  # Table 7.2 [l1_ilc_thesis]: a 43.5 um drop against a 1.69 um deflection
    (1.2, 1.69, "structure reproduced"),
    (1.69, 1.69, "structure reproduced"),
], ids=["not_the_mechanism", "within", "equal"])
def test_an_ordering_needs_the_thesis_mechanism(effect, capacity, verdict):
    row = rules.apply_rules([Row("Table 7.2 structure", "36.1 % -> 23.9 %", "7.9 % -> 6.4 %", "ordering", "structure reproduced", "lag",
                                 mechanism=Mechanism(effect, capacity, "drop against deflection"))])[0]
    assert row.verdict == verdict and (verdict != "differs" or "not by the thesis' mechanism" in row.cause)


@pytest.mark.parametrize("verdict", ["reproduced", "differs"])
def test_self_checks_are_not_thesis_rows(verdict):
    row = rules.apply_rules([Row("self-checks of the run", "-", "status completed", "-", verdict, "exit 1 on failure", self_check=True)])[0]
    assert row.verdict == "self-check" and row.verdict in rules.STATUSES and row.verdict not in rules.VERDICTS
