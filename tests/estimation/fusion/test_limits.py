"""The Table 10 limit search (Cvitanic (2021), Table 10): decade grid, bisection, verdict.

Independent reference: a stand-in study whose fused velocity error is a known function of the
swept value (fusion / tracker = value / CROSSING), so the true limit is known in closed form and
the bracket the search returns must contain it; the verdicts are checked on hand-made rows.
The real filters are searched in the slow test of tests/problems/kinds/test_state_estimation.py.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from types import SimpleNamespace

import pytest

from gtmodel.errors import InputError
from gtmodel.estimation.fusion.limits import THESIS_TABLE_10, centred_velocity_error, decade_grid, judge, limits, velocity_limit
from gtmodel.estimation.fusion.study import FusionStudy

#: Where the stand-in's fusion stops paying (accelerometer bias, m/s^2).
CROSSING = 0.0037


@dataclass(frozen=True)
class _Spec:
    accel_bias_m_s2: float = 0.00025
    sample_time_s: float = 0.001
    gyro_bias_deg_s: float = 0.0008

    def replace(self, **kw):
        return replace(self, **kw)


@dataclass
class _Study:
    """Fusion / tracker velocity error = value / CROSSING (tracker error 1 mm/s); records the runs."""

    spec: _Spec = _Spec()
    appendix_b_q: tuple = (1.0,) * 9
    sweep_duration: float = 1.2
    duration: float = 3.0
    calls: list = field(default_factory=list)

    def run_case(self, rotation, spec, q_diag=None, duration=None, label=""):
        value = spec.accel_bias_m_s2
        self.calls.append((rotation, value, q_diag, duration))
        return SimpleNamespace(errors={"velocity_mm_s": {"sensor": 1.0, "fusion": value / CROSSING}}, status="completed", message="")


def test_decade_grid():
    assert decade_grid(2.5e-4, 2.5) == pytest.approx([2.5e-4, 2.5e-3, 2.5e-2, 2.5e-1, 2.5])
    assert decade_grid(0.01, 90.0) == pytest.approx([0.01, 0.1, 1.0, 10.0, 90.0])


@pytest.mark.parametrize("bisections", [0, 1, 4])
def test_bracket_holds_the_crossing_and_halves_in_log(bisections):
    study = _Study()
    row = velocity_limit(study, False, "accel_bias_m_s2", bisections=bisections, tuning="appendix_b")
    assert row["pays_up_to"] < CROSSING <= row["stops_at"]
    assert math.log10(row["stops_at"] / row["pays_up_to"]) == pytest.approx(1.0 / 2**bisections)
    assert row["limit"] == pytest.approx(math.sqrt(row["pays_up_to"] * row["stops_at"]))
    assert len(study.calls) == 3 + bisections  # 2.5e-4 and 2.5e-3 pay, 2.5e-2 stops, then the halvings
    assert all(q == study.appendix_b_q and d == 1.2 for _, _, q, d in study.calls)
    # the thesis' 0.001 lies 0.5-1.0 decades below our limit (the bracket's geometric mean): beyond half a decade
    # (LIMIT_DECADES; one grid step passed it before)
    assert row["decades_from_thesis"] == pytest.approx(math.log10(row["limit"] / 0.001))
    assert row["decades_from_thesis"] > 0.5 and row["verdict"] == "differs"  # 0.57 (4 halvings) to 0.9 decades (none)


def test_a_search_that_never_stops_reports_the_top_of_the_range():
    study = _Study()
    row = velocity_limit(study, True, "accel_bias_m_s2", search=(1e-5, 1e-3))
    assert row["stops_at"] is None and row["limit"] == 1e-3 and row["verdict"] == "differs"


JUDGED = [
    ("within_half_a_decade", {"thesis_limit": 0.1, "stops_at": 0.06, "limit": 0.05}, "reproduced"),
    ("0.82_decades_below_differs", {"thesis_limit": 0.1, "stops_at": 0.02, "limit": 0.015}, "differs"),  # passed with one decade
    ("0.52_decades_above_differs", {"thesis_limit": 0.1, "stops_at": 0.4, "limit": 0.33}, "differs"),
    ("two_decades_above", {"thesis_limit": 0.001, "stops_at": 0.1, "limit": 0.09}, "differs"),
    ("no_limit_found", {"thesis_limit": 0.01, "stops_at": None, "limit": 0.1}, "differs"),
    ("no_constraint_kept", {"thesis_limit": math.inf, "stops_at": None, "limit": 2540.0}, "reproduced"),
    ("no_constraint_broken", {"thesis_limit": math.inf, "stops_at": 10.0, "limit": 8.0}, "differs"),
    ("not_applicable", {"thesis_limit": None, "stops_at": None, "limit": 1.0}, "N/A"),
]


@pytest.mark.parametrize("case, row, verdict", JUDGED, ids=[c[0] for c in JUDGED])
def test_judge(case, row, verdict):
    assert judge(row)["verdict"] == verdict


def test_thesis_table_10_as_printed():
    # Cvitanic (2021), Table 10 (the translation error's 0.1 m in mm)
    assert THESIS_TABLE_10["transform_translation_error_mm"] == (math.inf, 100.0)
    assert THESIS_TABLE_10["transform_orientation_error_deg"] == (10.0, 0.1)
    assert [v[0] for v in THESIS_TABLE_10.values()].count(None) == 2


def test_limits_skip_what_a_motion_does_not_measure():
    rows = limits(_Study(), ["3-axis", "5-axis"], ["white_jerk", "appendix_b"], ["accel_bias_m_s2", "gyro_bias_deg_s"], bisections=0)
    assert [(r["motion"], r["tuning"], r["parameter"]) for r in rows] == [
        ("3-axis", "white_jerk", "accel_bias_m_s2"), ("3-axis", "appendix_b", "accel_bias_m_s2"),
        ("5-axis", "white_jerk", "accel_bias_m_s2"), ("5-axis", "white_jerk", "gyro_bias_deg_s")]


BAD = [
    ("unknown_parameter", dict(rotation=True, parameter="feed_rate_mm_s"), r"parameter: expected one of accel_noise_m_s2_rtHz"),
    ("unknown_tuning", dict(rotation=True, parameter="accel_bias_m_s2", tuning="thesis"), r"tuning: expected one of white_jerk, appendix_b"),
    ("appendix_b_5_axis", dict(rotation=True, parameter="accel_bias_m_s2", tuning="appendix_b"), r"tuning: 'appendix_b' is the thesis' 3-axis KF"),
    ("gyro_3_axis", dict(rotation=False, parameter="gyro_bias_deg_s"), r"parameter: gyro_bias_deg_s is not measured by the 3-axis model"),
    ("unknown_baseline", dict(rotation=False, parameter="accel_bias_m_s2", baseline="smoothed"), r"baseline: expected one of causal, centred, got 'smoothed'"),
    ("negative_bisections", dict(rotation=False, parameter="accel_bias_m_s2", bisections=-1), r"bisections: expected an integer >= 0, got -1"),
]


@pytest.mark.parametrize("case, kwargs, match", BAD, ids=[c[0] for c in BAD])
def test_bad_search(case, kwargs, match):
    kw = dict(kwargs)
    with pytest.raises(InputError, match=match):
        velocity_limit(_Study(), kw.pop("rotation"), kw.pop("parameter"), **kw)


def test_bad_motion():
    with pytest.raises(InputError, match=r"motions: expected '3-axis' or '5-axis', got 'planar'"):
        limits(_Study(), ["planar"])


@pytest.mark.slow
def test_centred_regression_error_is_the_noise_of_the_slope():
    # independent: the least-squares slope of four samples has the standard deviation sigma sqrt(0.2) / dt per
    # axis; the mean norm of a 3-D isotropic Gaussian is 2 sqrt(2 / pi) times it (the lag-free baseline sees only noise)
    study = FusionStudy(duration=1.2, sweep={})
    case = study.run_case(False, duration=1.2)
    expected = 2.0 * math.sqrt(2.0 / math.pi) * math.sqrt(0.2) * study.spec.position_std / study.spec.dt * 1e3
    assert centred_velocity_error(study, case, 1.2) == pytest.approx(expected, rel=0.05)
