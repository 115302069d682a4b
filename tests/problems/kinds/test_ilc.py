"""``ilc`` problem files end to end (Dressler (2012), section 7.3), and their bad input.

Independent references: the thesis' Case-1 figures (largest singular values 0.90, 0.91, 0.93
below 1; actuator-side error about 2 % of the initial one after 5 iterations) and its
orderings of Table 7.2 (tool x falls further than y with actuator learning, the robot being
stiffer in x; the tool estimates beat actuator learning in y; the measured tool position is
the lower bound). The lifted criteria are checked against the simulation: a design they
call unstable diverges in it.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize
import scipy.signal

from gtmodel.codegen import load_controller
from gtmodel.problems import load_problem, run_problem
from gtmodel.status import Status

from ...conftest import PROBLEMS_DIR, assert_bad_problem, assert_bad_problem_through_cli
from ...conftest import replace_once as _edit

FILE = PROBLEMS_DIR / "l1_ilc.toml"
#: Case 1 after 5 iterations: at most this fraction of the initial actuator error (thesis ~2 %).
CASE_1_AFTER_5 = 0.05


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    out = tmp_path_factory.mktemp("l1_ilc")
    outcome = run_problem(FILE, out, overrides={"ilc.coupled_check": False})  # the coupled check: test_ilc_coupled.py (slow)
    return outcome.status, out, outcome.summary


def test_shipped_problem_converges_and_writes_its_files(solved):
    status, out, s = solved
    assert status == Status.CONVERGED and s["status"] == "converged"
    assert set(s["cases"]) == {"1", "2A", "2B", "3"}
    names = ("table_7_2.md", "table_7_2.csv", "ilc_iterations.csv", "ilc_actuator_errors.png", "ilc_tool_errors.png",
             "ilc_tool_path_case_1.png", "ilc_tool_path_case_3.png", "controller.json")
    assert not [n for n in names if not (out / n).is_file() or (out / n).stat().st_size == 0]
    assert len((out / "table_7_2.csv").read_text().splitlines()) == 1 + 4
    assert len((out / "ilc_iterations.csv").read_text().splitlines()) == 1 + 4 * (s["iterations"] + 1)


@pytest.mark.parametrize("channel", ["q1", "q2", "q3"])
def test_case_1_is_monotone_on_every_actuator(solved, channel):
    """Thesis: sigma_max 0.90, 0.91, 0.93 (7.16); ours must be below 1 with rho below 1 (7.15)."""
    c = solved[2]["cases"]["1"]["checks"][channel]
    assert c["sigma_max"] < 1.0 and c["rho"] < 1.0 and c["monotone"]


@pytest.mark.parametrize("actuator", [0, 1, 2])
def test_case_1_actuator_error_falls_every_iteration(solved, actuator):
    """A design the lifted check calls monotone (7.16) never increases the error in simulation."""
    e = np.array(solved[2]["cases"]["1"]["actuator_error_m"])[:, actuator]
    assert np.all(np.diff(e) < 0.0)


@pytest.mark.xfail(strict=True, reason="not reproduced: with the (6.11) models and L = 0.9 q^5 the per-iteration factor "
                                       "|1 - gamma G(f)| is 0.57 at 1 Hz and 0.80 at 2 Hz, where the square's error lies; "
                                       "case 1 reaches 24-37 % after 5 iterations, not the thesis' ~2 %")
@pytest.mark.parametrize("actuator", [0, 1, 2])
def test_case_1_actuator_error_after_5_iterations(solved, actuator):
    """Thesis: about 2 % of the initial actuator-side error after 5 iterations; bound 5 %."""
    e = np.array(solved[2]["cases"]["1"]["actuator_error_m"])[:, actuator]
    assert e[5] <= CASE_1_AFTER_5 * e[0]


def _tool(s, case):
    return s["cases"][case]["table_7_2"]


@pytest.mark.xfail(strict=True, reason="not reproduced: after 10 iterations the unlearned actuator lag (hundreds of um) "
                                       "dominates the tool error, not the structural deflection (tens of um)")
def test_case_1_tool_x_falls_further_than_y(solved):
    """Thesis: learning on the actuators helps the tool more in x (the robot is stiffer in x)."""
    t = _tool(solved[2], "1")
    assert t["tool_x"] < t["tool_y"]


@pytest.mark.parametrize("case", ["1", "2A", "2B", "3"])
def test_every_case_reduces_the_tool_error_in_x_and_y(solved, case):
    t = _tool(solved[2], case)
    assert t["tool_x"] < 0.5 and t["tool_y"] < 0.5


def test_simulation_equals_the_lifted_model(tmp_path):
    """The lifted matrices (7.9) from the impulse responses predict a simulated trial exactly:
    eps(u) = eps(0) - T u on every actuator (Case 1: the actuator plant is linear and noise-free)."""
    problem = load_problem(FILE)
    exp = problem.declaration.experiment
    case = problem.declaration.cases[0]
    T = exp.transfer_matrices(case)
    n = exp.reference.n
    u = np.column_stack([exp.reference.window * 1e-3 * np.sin(np.arange(n) * 0.05 * (i + 1)) for i in range(3)])
    e0, _ = exp.trial(case, np.zeros((n, 3)))
    e1, _ = exp.trial(case, u)
    predicted = np.column_stack([e0[:, i] - T[f"q{i + 1}"] @ u[:, i] for i in range(3)])
    assert np.max(np.abs(e1 - predicted)) < 1e-12


def test_controller_file_holds_the_learned_table(solved):
    controller = load_controller(solved[1] / "controller.json")
    assert controller.ilc_table.shape == (solved[2]["samples"], 3)
    assert np.isfinite(controller.ilc_table).all()


def test_table_7_2_markdown_has_the_thesis_column(solved):
    text = (solved[1] / "table_7_2.md").read_text()
    # Dressler (2012), section 7.4: Table 7.2 (Case 1 tool x 13.3 %, y 36.1 %; Case 2A y 23.9 %) and (7.28)
    assert "thesis" in text and "0.90, 0.91, 0.93" in text and "x 0.133, y 0.361" in text and "y 0.239" in text


UNSTABLE = _edit('q_cutoff_hz = 10.0          # the thesis: 2nd-order Butterworth at 10 Hz',
                 'q_cutoff_hz = 10.0\nrequire = "none"')


def test_a_design_the_criterion_calls_unstable_diverges(tmp_path):
    """gamma = 60 makes |1 - gamma b| > 1 on every L1 axis (b ~ 0.03): rho > 1 (7.15) and the
    simulated learning error grows: the case ends with status error, not an exception."""
    text = UNSTABLE(FILE.read_text()).replace("gamma = 0.9", "gamma = 60.0").replace("iterations = 10", "iterations = 6")
    text = text[: text.index("[[cases]]\nname = \"2A\"")]
    f = tmp_path / "unstable.toml"
    f.write_text(text)
    problem = load_problem(f)
    checks = problem.declaration.experiment.check(problem.declaration.cases[0])
    assert all(c.rho > 1.0 for c in checks.values())
    outcome = run_problem(f, tmp_path / "out", plots=False)
    assert outcome.status == Status.ERROR
    e = np.array(outcome.summary["cases"]["1"]["actuator_error_m"])
    assert e[-1, 0] > e[0, 0]
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["summary.json"]  # no table that looks like a result


BAD = [
    ("outside_workspace", _edit("corner = [0.0, 2.9, -0.5]", "corner = [0.0, 9.9, -0.5]"), r"field 'reference.corner'.*workspace"),
    ("q_above_nyquist", _edit("q_cutoff_hz = 10.0          # the thesis", "q_cutoff_hz = 200.0          # the thesis"),
     r"field 'cases\[0\]\.q_cutoff_hz'.*Nyquist"),
    ("complementary_above_nyquist", _edit("complementary_cutoff_hz = [4.50, 2.63]", "complementary_cutoff_hz = [4.50, 263.0]"),
     r"field 'estimators.complementary_cutoff_hz"),
    ("duplicate_case", _edit('name = "2A"', 'name = "1"'), r"field 'cases\[1\]\.name'"),
    ("unknown_signal", _edit('signal = "tool"', 'signal = "laser"'), r"field 'cases\[3\]\.signal'"),
    ("unknown_field", _edit("[ilc]\n", "[ilc]\nlearning_rate = 1.0\n"), r"unknown field 'ilc.learning_rate'"),
]


@pytest.mark.parametrize("case, edit, match", BAD, ids=[b[0] for b in BAD])
def test_bad_input_names_the_field(tmp_path, case, edit, match):
    assert_bad_problem(tmp_path, FILE, case, edit, match)


def test_a_design_failing_its_required_check_exits_2_before_any_trial(tmp_path, capsys, monkeypatch):
    """The lifted check (eigenvalues and SVD: seconds) runs at solve time, not at load (issue 26);
    a design failing the check it requires (gamma = 60: sigma_max > 1, 7.16) still ends as bad
    input (exit 2) naming the file and ``cases[0].require``, before any trial is simulated."""
    from gtmodel.estimation import ILCExperiment

    monkeypatch.setattr(ILCExperiment, "trial", lambda *a, **k: pytest.fail("a trial ran before the required check"))
    text = _edit("gamma = 0.9", "gamma = 60.0")(FILE.read_text())
    assert_bad_problem_through_cli(tmp_path, capsys, text, r"bad\.toml: field 'cases\[0\]\.require'.*monotone.*sigma_max")


TOL = 1e-6


def _channels(lifted, est, signal):
    """Per channel the lifted map from the correction to the learning signal (Dressler (2012), eq. 7.9)."""
    T = scipy.linalg.toeplitz
    n = lifted["L"].shape[0]
    z = np.zeros(n)
    if signal == "actuator":
        return {f"q{i + 1}": T(lifted["h_actuator"][:, i], z) for i in range(3)}
    if signal == "tool":
        return {a: T(lifted["h_tool_position"][:, j, j], z) for j, a in enumerate("xyz")}
    Fk, Fa = est[f"F_kin_{signal}"], est[f"F_acc_{signal}"]
    out = {a: Fk[j] @ T(lifted["h_kin"][:, j, j], z) + Fa[j] @ T(lifted["h_acc"][:, j, j], z) for j, a in enumerate("xy")}
    out["z"] = T(lifted["h_kin"][:, 2, 2], z)
    return out


@pytest.fixture(scope="module")
def exports(solved):
    _, out, s = solved
    return s, np.load(out / "ilc_lifted.npz"), np.load(out / "ilc_estimators.npz"), out


@pytest.mark.parametrize("case", ["1", "2A", "2B", "3"])
def test_sigma_max_per_channel_from_the_exports(exports, case):
    """Independent: lifted matrices rebuilt by scipy.linalg.toeplitz from the exported impulse responses, sigma by svdvals (1e-6)."""
    s, lifted, est, _ = exports
    c = s["cases"][case]
    n = lifted["L"].shape[0]
    Q, L = lifted[f"Q_{case}"], lifted["L"]
    again = {ch: scipy.linalg.svdvals(Q @ (np.eye(n) - L @ Tm))[0] for ch, Tm in _channels(lifted, est, c["signal"]).items()}
    assert again == pytest.approx({ch: v["sigma_max"] for ch, v in c["checks"].items()}, abs=TOL)


def test_kalman_gain_from_the_exports(exports):
    """Independent: scipy.linalg.solve_discrete_are (gtmodel: control.dlqe)."""
    _, _, est, _ = exports
    A, C, Q, R = (est[f"kalman_{k}"] for k in "ACQR")
    P = scipy.linalg.solve_discrete_are(A.T, C.T, Q, R)
    M = P @ C.T @ np.linalg.inv(C @ P @ C.T + R)
    assert np.max(np.abs(M - est["kalman_M"])) <= TOL * np.max(np.abs(M))
    assert np.max(np.abs(A @ M - est["kalman_L"])) <= TOL * np.max(np.abs(A @ M))


def test_complementary_crossover_from_the_exports(exports):
    """Independent: brentq on the zero-phase magnitude of the exported sections (gtmodel: the design frequency)."""
    s, _, est, _ = exports
    fs = 1.0 / s["sample_time_s"]

    def lp(f, sos):  # zero-phase (forward-backward) magnitude
        return np.abs(scipy.signal.sosfreqz(sos, worN=[f], fs=fs)[1][0]) ** 2

    cross = [scipy.optimize.brentq(lambda f: lp(f, sos) - (1.0 - lp(f, sos)), 0.01, 0.49 * fs, xtol=1e-12) for sos in est["complementary_sos"]]
    assert cross == pytest.approx(s["estimators"]["complementary_crossover_hz"], abs=TOL)


def test_signals_are_those_of_the_error_measure(exports):
    # per-iteration learning errors: their RMS over the fully corrected samples is the printed learning error
    s, lifted, _, out = exports
    sig = np.load(out / "ilc_signals_case_1.npz")
    mask = lifted["window"] >= 1.0 - 1e-12
    rms = np.sqrt(np.mean(sig["eps"][:, mask, :] ** 2, axis=1))
    assert rms == pytest.approx(np.array(s["cases"]["1"]["learning_error"]), rel=TOL)
    assert sig["u"].shape == sig["eps"].shape == (s["iterations"] + 1, s["samples"], 3)




@pytest.mark.parametrize("axis", ["x", "y"])
def test_thesis_form_kalman_gain_from_the_exports(exports, axis):
    """Independent: the predictor gain of (7.22) by scipy.linalg.solve_discrete_are on the exported (7.21) matrices (gtmodel: the same
    equation through ModelKalman; the tests of ModelKalman check it against control.dlqe)."""
    _, _, est, _ = exports
    Ab, Cb, r = est[f"kalman_model_Abar_{axis}"], est[f"kalman_model_Cbar_{axis}"], float(est["kalman_model_r"])
    cy, r2 = Cb[1:2], np.array([[est["kalman_model_R2"]["xy".index(axis)]]])
    P = scipy.linalg.solve_discrete_are(Ab.T, cy.T, r * np.eye(Ab.shape[0]), r2)
    K = (Ab @ P @ cy.T @ np.linalg.inv(cy @ P @ cy.T + r2)).reshape(-1)
    assert np.max(np.abs(K - est[f"kalman_model_K_{axis}"])) <= TOL * max(np.max(np.abs(K)), 1e-12)


def test_estimators_are_compared_on_the_uncorrected_trial(exports):
    # both Kalman forms computed; the summary says which is closest to the simulated truth (RMS over the corrected samples)
    s = exports[0]
    e = s["estimators"]
    rms = e["estimation_error_rms_m"]
    assert set(rms) == {"kinematic", "complementary", "kalman_triple_integrator", "kalman_model"}
    assert e["closest_to_truth"] == min(rms, key=lambda k: sum(rms[k]))
    assert e["kalman_form"] == "triple_integrator" and str(exports[2]["kalman_form"]) == "triple_integrator"
    # the (7.21) filter's model is the plant's structure: it recovers the deflection the kinematic position misses
    assert max(rms["kalman_model"]) < 0.01 * min(e["deflection_rms_m"])
