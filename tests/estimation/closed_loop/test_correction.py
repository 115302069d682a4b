"""Correction stability, Cvitanic (2021), eqs. (30)-(33): equivalent force, offset response, fit, loop.

Independent references: closed forms (the second difference of a step and of a constant
feed, the DC gain 1 of the offset response, the critical gain ``2 sin(pi/50)`` of an
integrator behind a 13-cycle delay on a rigid arm), a second method (python-control's
``forced_response`` against the lfilter response; the closed-loop poles against the
step-by-step simulation; the closed-loop frequency response against the simulated steady
error), the reference file (Tables 12, 13, 16, 17) and a model-generated response (the fit
recovers its own parameters).
"""

from __future__ import annotations

import math
import tomllib
from types import SimpleNamespace

import control
import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.calibration.joint_stiffness import TABLE_2_K_THETA
from gtmodel.estimation.closed_loop.correction import (
    CALIBRATION_POSES_DEG,
    TABLE_16,
    TABLE_17,
    TABLE_2_DPP_K_THETA,
    VALIDATION_POSES_DEG,
    OffsetResponseModel,
    equivalent_force,
    fit_offset_response,
    joint_angles,
    offset_response_gp,
    pose_compliance,
    truth_model,
)
from gtmodel.estimation.closed_loop.correction_loop import (
    closed_loop,
    correction_study,
    critical_gain,
    largest_stable_gain,
    path_period,
    simulate_loop,
    sine_reference,
)
from gtmodel.robots.serial import load_serial_arm

from ...conftest import SHARED_REFERENCE

DT = 0.004
SINGLE = OffsetResponseModel((200.0,), (4000.0,), (2.5e6,), 200.0)
#: Rigid limit: L(z) = K z^-12/(z-1) reaches -180 deg at w = pi/25 rad/sample, |e^jw - 1| = 2 sin(pi/50).
RIGID_CRITICAL_GAIN = 2 * math.sin(math.pi / 50)


@pytest.fixture(scope="module")
def arm():
    return load_serial_arm("serial_6r_illustrative")


@pytest.fixture(scope="module")
def truth(arm):
    return truth_model(arm, VALIDATION_POSES_DEG)


def test_tables_are_those_of_the_reference_file():
    # the reference copy of ../shared/reference/serial_kr500.toml; Table 2 DPP as in gtmodel.calibration
    ref = tomllib.loads((SHARED_REFERENCE / "serial_kr500.toml").read_text())
    dyn, loop = ref["dynamic_stiffness"], ref["closed_loop"]
    np.testing.assert_array_equal(TABLE_16["m"], dyn["m_kg"])
    np.testing.assert_array_equal(TABLE_16["c"], dyn["c_Ns_per_m"])
    np.testing.assert_allclose(TABLE_16["k"], np.array(dyn["k_MN_per_m"]) * 1e6, rtol=1e-15)
    np.testing.assert_allclose(TABLE_17["k"], np.array(dyn["second_k_MN_per_m"]) * 1e6, rtol=1e-15)
    np.testing.assert_array_equal(TABLE_17["freq_hz"], dyn["second_freq_hz"])
    np.testing.assert_array_equal(CALIBRATION_POSES_DEG, loop["calibration_poses_j2_j3_deg"])
    np.testing.assert_array_equal(VALIDATION_POSES_DEG, loop["validation_poses_j2_j3_deg"])
    np.testing.assert_allclose(TABLE_2_DPP_K_THETA, TABLE_2_K_THETA["DPP"], rtol=1e-15)
    assert round(loop["controller_delay_s"] / loop["cycle_time_s"]) == 13


def test_equivalent_force_of_a_constant_feed_is_zero():
    # eqs. (31)-(32): the feed at a constant rate has no equivalent force (closed form)
    c = 0.04233 * DT * np.arange(50)
    np.testing.assert_allclose(equivalent_force(c, DT, 200.0, feed_rate=0.04233), 0.0, atol=1e-9)


def test_equivalent_force_of_one_offset_command():
    # closed form: a step d at cycle 3 -> M d/dt^2 at cycle 3, -M d/dt^2 at cycle 4, zero elsewhere
    c = np.r_[np.zeros(3), np.full(5, 1e-4)]
    F = equivalent_force(c, DT, 200.0)
    expected = np.zeros(8)
    expected[3], expected[4] = 200.0 * 1e-4 / DT**2, -200.0 * 1e-4 / DT**2
    np.testing.assert_allclose(F, expected, rtol=1e-12, atol=1e-9)


def test_offset_response_has_dc_gain_one():
    # closed form: the robot follows a held command (p = c + delta, delta -> 0)
    assert float(np.squeeze(control.dcgain(SINGLE.response_ss()))) == pytest.approx(1.0, rel=1e-9)
    t, p = SINGLE.offset_response(1e-4, 500)
    assert p[0] == pytest.approx(1e-4) and p[-1] == pytest.approx(1e-4, rel=1e-6)
    assert np.max(p) > 1.3e-4  # the command excites the mode


def test_offset_response_equals_the_state_space_response(truth):
    # second method: python-control forced_response of response_ss() against the lfilter path
    model = truth[0]["x"]
    t, p = model.offset_response(1e-4, 300)
    ref = control.forced_response(model.response_ss(), T=t, U=np.full(t.size, 1e-4)).outputs
    np.testing.assert_allclose(p, np.asarray(ref).reshape(-1), rtol=1e-9, atol=1e-15)


def test_fit_recovers_a_single_mode_response():
    # model-generated data: the fit returns the parameters that generated it
    p = SINGLE.offset_response(1e-4, 250)[1]
    fit = fit_offset_response(p, 1e-4, SINGLE.mass)
    assert fit.success
    np.testing.assert_allclose([fit.m, fit.c, fit.k], [200.0, 4000.0, 2.5e6], rtol=1e-6)


def test_truth_at_the_centroid_is_the_table_means(arm):
    # closed form: at the reference pose the stiffness factor is 1
    model = truth_model(arm, CALIBRATION_POSES_DEG.mean(axis=0))[0]
    np.testing.assert_allclose(model["x"].k[0], TABLE_16["k"][:, 0].mean(), rtol=1e-12)
    np.testing.assert_allclose(model["y"].k[1], TABLE_17["k"][:, 1].mean(), rtol=1e-12)
    np.testing.assert_allclose(model["y"].natural_frequencies_hz[1], TABLE_17["freq_hz"][:, 1].mean(), rtol=1e-12)
    zeta = (TABLE_16["c"] / (2 * np.sqrt(TABLE_16["k"] * TABLE_16["m"]))).mean(axis=0)
    np.testing.assert_allclose(model["y"].damping_ratios, zeta[1], rtol=1e-12)


def test_truth_stiffness_follows_the_joint_spring_compliance(arm):
    # eq. (3): k(pose) C(pose) is the same at every pose
    C = pose_compliance(arm, joint_angles(CALIBRATION_POSES_DEG))
    models = truth_model(arm, CALIBRATION_POSES_DEG)
    product = np.array([[m[d].k[0] for d in "xyz"] for m in models]) * C
    np.testing.assert_allclose(product, product[:1].repeat(len(models), axis=0), rtol=1e-12)
    assert C[:, 0].max() / C[:, 0].min() > 3  # the x compliance varies over the plane


def _smooth(q_deg):
    """A smooth positive held-out function of (j2, j3)."""
    q = np.radians(np.atleast_2d(q_deg))
    return np.exp(0.4 * np.sin(2 * q[:, 0]) + 0.3 * np.cos(q[:, 1]))


@pytest.mark.filterwarnings("ignore::sklearn.exceptions.ConvergenceWarning")  # noise-free data: noise level at its bound
def test_gp_over_j2_j3_interpolates_a_smooth_field():
    # DynamicStiffnessGP with n_inputs = 2 on the Table 12 poses: training points to 1 %, Table 13 poses to 5 %
    base = _smooth(CALIBRATION_POSES_DEG)
    fits = [{d: SimpleNamespace(m=200 * b, c=4000 * b, k=s * b) for d, s in zip("xyz", (2e6, 5e6, 1e6))} for b in base]
    gp = offset_response_gp(CALIBRATION_POSES_DEG, fits)
    assert gp.n_inputs == 2
    np.testing.assert_allclose(gp.predict(np.radians(CALIBRATION_POSES_DEG))["k"][:, 1], 5e6 * base, rtol=1e-2)
    np.testing.assert_allclose(gp.predict(np.radians(VALIDATION_POSES_DEG))["m"][:, 0], 200 * _smooth(VALIDATION_POSES_DEG), rtol=5e-2)
    with pytest.raises(InputError, match=r"X: expected shape \(2,\) or \(N, 2\)"):
        gp.predict(np.zeros(4))


def test_rigid_arm_reaches_the_delay_integrator_limit():
    # closed form 2 sin(pi/50) for K z/(z-1) z^-13 around a plant of gain 1
    rigid = OffsetResponseModel((1.0,), (2 * 0.7 * 1e5,), (1e10,), 1.0)
    assert critical_gain(rigid, tol=1e-7) == pytest.approx(RIGID_CRITICAL_GAIN, rel=1e-4)


@pytest.mark.parametrize("v", [0, 5])
@pytest.mark.parametrize("direction, resolution", [("x", 0.01), ("y", 0.01)])
def test_simulation_and_poles_give_the_same_gain(truth, v, direction, resolution):
    # second method: the closed-loop poles of python-control against the step-by-step simulation
    model = truth[v][direction]
    sim = largest_stable_gain(model, resolution, "simulation")
    eig = largest_stable_gain(model, resolution, "eigenvalues")
    assert sim.gain == eig.gain and sim.status == eig.status == "completed"
    assert eig.gain <= critical_gain(model) < eig.gain + resolution


def test_steady_error_matches_the_closed_loop_frequency_response(truth):
    # second method: |1 - T(e^{jwT})| A is the amplitude of the periodic error at a stable gain
    model, K = truth[0]["y"], 0.05
    n = int(round(20.0 / DT))
    sim = simulate_loop(model, K, sine_reference(n))
    w = 2 * np.pi / path_period()
    T = closed_loop(model, K)
    S = 1 - complex(np.squeeze(T(np.exp(1j * w * DT))))
    period = int(round(path_period() / DT))
    assert sim.stable
    np.testing.assert_allclose(np.max(np.abs(sim.error[-period:])), abs(S) * 0.0508, rtol=5e-3)


def test_unstable_gain_is_reported_unstable(truth):
    # just above the critical gain the error grows from one path period to the next
    model = truth[0]["y"]
    sim = simulate_loop(model, critical_gain(model) + 0.02, sine_reference(2500))
    assert not sim.stable and sim.growth > 1.01 and sim.status == "completed"


@pytest.mark.filterwarnings("ignore::sklearn.exceptions.ConvergenceWarning")
def test_study_on_a_subset(arm):
    # the study end to end on 8 calibration and 2 validation poses; both methods agree
    s = correction_study(arm, CALIBRATION_POSES_DEG[::2], VALIDATION_POSES_DEG[:2], ("y",), duration=6.0)
    assert s.predicted_gain.shape == (2, 1) and s.success
    np.testing.assert_array_equal(s.predicted_gain, s.predicted_gain_eigenvalues)
    np.testing.assert_array_equal(s.simulated_gain, s.simulated_gain_eigenvalues)
    assert s.within_one_increment().all()


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda a: equivalent_force(np.zeros((3, 2))), r"command: expected shape \(n,\)"),
        (lambda a: equivalent_force([0.0, np.nan]), "command: row 1 is not finite"),
        (lambda a: equivalent_force([0.0, 1.0], dt=-1.0), "dt: expected"),
        (lambda a: OffsetResponseModel((1.0,), (1.0, 2.0), (1.0,), 1.0), "same number"),
        (lambda a: OffsetResponseModel((1.0,), (-1.0,), (1.0,), 1.0), r"c\[0\]: expected"),
        (lambda a: SINGLE.offset_response(-1e-4, 10), "amplitude: expected"),
        (lambda a: fit_offset_response(np.ones(5), 1e-4, 1.0), "at least 20 cycles"),
        (lambda a: truth_model(a, [[-150.0, 90.0]]), r"joint 2 = -150 deg is outside the joint limits -130\.\.20 deg"),
        (lambda a: pose_compliance(a, joint_angles([[-40.0, 170.0]])), "joint 3 = 170 deg is outside"),
        (lambda a: largest_stable_gain(SINGLE, 0.0), "resolution: expected"),
        (lambda a: largest_stable_gain(SINGLE, 0.01, method="bode"), "method: expected one of simulation, eigenvalues"),
        (lambda a: simulate_loop(SINGLE, 0.1, np.zeros(100)), "at least 2 windows"),
        (lambda a: correction_study(a, directions=("w",)), "directions: expected"),
    ],
)
def test_bad_input(arm, call, match):
    """Bad arguments are refused with a message naming the argument (and the joint)."""
    with pytest.raises(InputError, match=match):
        call(arm)
