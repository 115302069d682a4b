"""``docs/fidelity.md`` is what ``docs/fidelity_figures.json`` gives, and lists every row of issue 27.

Independent reference: the issue's list of thesis figures (Dressler (2012) Table 7.2, (7.28), Fig. 7.7,
the complementary crossover, the actuator bandwidths, Tables 5.2/5.3; Cvitanic (2021) Tables 2, 8, 9,
10, 14); the verdicts are recomputed from the figures by :func:`gtmodel.report.fidelity.render`.
"""

from __future__ import annotations

import json

import pytest

from gtmodel.report import fidelity

ISSUE_ROWS = [
    "(7.28) / section 7.4: sigma_max Case 1", "sigma_max Case 2A", "sigma_max Case 2B", "sigma_max Case 3",
    "Fig. 7.7: Case 1 actuator error at k = 5", "Table 7.2: Case 1 tool x / y", "Table 7.2: Case 2A tool x / y",
    "Table 7.2 structure: Cases 2A, 2B improve tool y", "complementary filter crossover",
    "Table 8: position 3-axis", "Table 8: velocity improved most", "Table 8: acceleration 3-axis", "Table 8: orientation 5-axis",
    "Table 9: tracker noise 0.64 mm", "Table 10: limit of", "self-checks of the run",
    "Table 14: largest stable P gain x", "Table 14: largest stable P gain y", "Table 14 structure",
    "actuator bandwidth of the (6.11) models", "(7.21)-(7.22): Kalman filter on the identified tool model", "Tables 5.2/5.3: D1 error models", "Table 2: joint stiffness by CP vs DPP",
]


@pytest.fixture(scope="module")
def figures():
    return json.loads(fidelity.FIGURES.read_text(encoding="utf-8"))


def test_page_is_not_stale(figures):
    # regenerate with: python -m gtmodel.report.fidelity render (after collect RESULTS)
    assert fidelity.PAGE.read_text(encoding="utf-8") == fidelity.render(figures)


@pytest.mark.parametrize("row", ISSUE_ROWS)
def test_every_issue_row_is_listed(figures, row):
    assert any(row in r[0] for r in fidelity.rows(figures))


def test_every_row_has_a_verdict_and_a_cause_where_it_differs(figures):
    verdicts = {"reproduced", "structure reproduced", "differs", "not run", "not attempted", "partly run", "see values"}
    bad = [r for r in fidelity.rows(figures) if len(r) != 6 or r[4] not in verdicts or (r[4] == "differs" and len(r[5]) <= 20)]
    assert not bad


def test_actuator_bandwidths_from_the_models():
    # independent: the -3 dB point of b / (1 - a z^-1) in closed form, |H(e^{iw})|^2 = 1/2 (Dressler (2012), eq. 6.11)
    import math
    a = [0.9647, 0.9656, 0.9728]
    dt = 0.004
    # |b / (1 - a e^{-iw})|^2 = dc^2 / 2 with dc = b / (1 - a)  <=>  1 - 2 a cos w + a^2 = 2 (1 - a)^2
    expected = [math.acos((1 + ai**2 - 2 * (1 - ai) ** 2) / (2 * ai)) / (2 * math.pi * dt) for ai in a]
    assert fidelity.actuator_bandwidths_hz() == pytest.approx(expected, rel=1e-3)


def test_collect_records_a_missing_folder_as_not_run(tmp_path):
    data = fidelity.collect(tmp_path, tmp_path / "figures.json")
    assert all(data[p] is None for p in fidelity.PROBLEMS)
    assert "not run" in fidelity.render(data)


def test_collect_refuses_a_missing_results_folder(tmp_path):
    with pytest.raises(fidelity.InputError, match="results: expected a folder of result folders"):
        fidelity.collect(tmp_path / "nope", tmp_path / "figures.json")


def test_learning_factors_from_the_models():
    # independent: 1 - gamma z^delta G(z) = 1 - gamma b / (1 - a z^-1) for G = q^-5 b / (1 - a q^-1) (Dressler (2012), eq. 6.11)
    import cmath
    import math
    a, b = [0.9647, 0.9656, 0.9728], [0.03527, 0.03425, 0.02748]
    z = {f: cmath.exp(2j * math.pi * f * 0.004) for f in fidelity.LEARNING_FACTOR_HZ}
    expected = [abs(1 - 0.9 * bi / (1 - ai / zf)) for zf in z.values() for ai, bi in zip(a, b)]
    got = fidelity.learning_factors()
    assert list(got) == [f"{f:g}" for f in z] and sum(got.values(), []) == pytest.approx(expected, rel=1e-3)


def test_collect_only_keeps_the_other_problems(tmp_path):
    figures = tmp_path / "figures.json"
    figures.write_text(json.dumps({"model": {}, "kr500_state_estimation": {"kept": 1}}))
    (tmp_path / "l1_ilc").mkdir()
    data = fidelity.collect(tmp_path, figures, only=["l1_ilc"])
    assert data["kr500_state_estimation"] == {"kept": 1} and data["l1_ilc"] is None
    with pytest.raises(fidelity.InputError, match="only: expected problems of"):
        fidelity.collect(tmp_path, figures, only=["nope"])
    with pytest.raises(fidelity.InputError, match="does not exist"):
        fidelity.collect(tmp_path, tmp_path / "none.json", only=["l1_ilc"])
