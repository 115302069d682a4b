"""The closed-loop tracking plant (gtmodel.estimation.closed_loop.plant) against independent references.

References: closed forms of the actuator model (6.11) (DC gain ``b/(1-a)``, impulse response
``b a^(k-5)``), the static closed form of the structure (``d = -m_acc a / k``), the
continuous poles mapped by ``exp(s dt)``, the sensor specification (noise standard
deviation, 1.5 g range), and the nonlinear simulation itself as a second method for the
linearised tool impulse responses.
"""

from __future__ import annotations

import math

import control
import numpy as np
import pytest

from gtmodel.errors import InputError, UnreachablePoseError
from gtmodel.estimation import SensorModel, ToolStructure, TrackingPlant, TrackingResponse
from gtmodel.estimation.closed_loop.plant import DT, STANDARD_GRAVITY
from gtmodel.robots import GantryTau3Kinematics
from gtmodel.robots.actuator_dynamics import actuator_models, load_dynamics_models

#: Operating point of the ILC square (ILC_DESIGN: first corner), inside the L1 workspace.
T0 = np.array([0.0, 2.9, -0.5])
A = np.array([0.9647, 0.9656, 0.9728])
B = np.array([0.03527, 0.03425, 0.02748])
#: b / (1 - a) of the three L1 axes, to 7 digits (0.03527/0.0353, 0.03425/0.0344, 0.02748/0.0272).
DC_GAINS = np.array([0.9991501, 0.9956395, 1.0102941])


@pytest.fixture(scope="module")
def plant() -> TrackingPlant:
    return TrackingPlant.l1(sensors=SensorModel(accelerometer_noise=0.0, gauge_noise=0.0))


@pytest.fixture(scope="module")
def q0(plant) -> np.ndarray:
    return plant.kinematics.ik(T0)


def test_the_dc_gains_are_the_thesis_values():
    # closed form b/(1-a) against the stated 7-digit values
    np.testing.assert_allclose(B / (1 - A), DC_GAINS, atol=1e-7)


def test_constant_reference_keeps_everything_at_rest(plant, q0):
    # closed form: at rest at q_ref[0], a constant reference changes nothing
    r = plant.simulate(np.tile(q0, (50, 1)))
    np.testing.assert_array_equal(r.q, r.q_ref)
    np.testing.assert_allclose(r.z, np.tile(T0, (50, 1)), atol=1e-12)
    assert np.all(r.d == 0) and np.all(r.a == 0)


def test_step_settles_at_the_dc_gain(plant, q0):
    # closed form: steady state of b q^-5 / (1 - a q^-1) for a step h is h b / (1 - a)
    h = np.array([0.01, -0.02, 0.015])
    q_ref = np.tile(q0 + h, (2500, 1))
    q_ref[0] = q0
    r = plant.simulate(q_ref)
    np.testing.assert_allclose(r.q[-1] - q0, h * DC_GAINS, rtol=1e-6)
    # the step starts at sample 1: the first move is b h at sample 1 + 5
    np.testing.assert_allclose(r.q[:7] - q0, np.vstack([np.zeros((6, 3)), B * h]), atol=1e-15)


def test_actuator_impulse_responses_are_the_closed_form(plant):
    # closed form of (6.11): h[k] = b a^(k-5) for k >= 5, 0 before
    n = 60
    k = np.arange(n)[:, None]
    expected = np.where(k >= 5, B * A ** np.maximum(k - 5, 0), 0.0)
    np.testing.assert_allclose(plant.actuator_impulse_responses(n), expected, rtol=1e-12, atol=1e-15)


def test_structure_modes_are_the_chosen_figures():
    # closed form: one mode per direction at frequencies_hz, damping ratio zeta
    m = ToolStructure().modes()
    np.testing.assert_allclose(m.frequencies_hz, [7.4, 11.5], rtol=1e-12)
    np.testing.assert_allclose(m.natural_frequencies_hz, [7.4, 11.5], rtol=1e-12)
    np.testing.assert_allclose(m.damping_ratios, [0.05, 0.05], rtol=1e-12)


def test_static_deflection_under_constant_acceleration_is_m_over_k():
    # static closed form K d = -m_acc a: 5.595 um per m/s^2 in x, 11.19 um in y
    s = ToolStructure()
    np.testing.assert_allclose(s.static_deflection(), [22.38 / 4e6, 22.38 / 2e6], rtol=1e-15)
    n = 3000  # 12 s: e^(-zeta w t) < 1e-10 for both modes
    t = np.arange(n) * DT
    a = np.array([[1.5], [-2.0]]) * np.ones(n)
    out = control.forced_response(s.discrete(DT), t, a).outputs
    np.testing.assert_allclose(out[:2, -1], -22.38 * np.array([1.5 / 4e6, -2.0 / 2e6]), rtol=1e-9)
    np.testing.assert_allclose(out[2:, -1], 0.0, atol=1e-9)


def test_discrete_poles_are_exp_of_the_continuous_poles():
    # c2d maps every pole s of PhysicalModel.modes() to exp(s dt)
    s = ToolStructure()
    expected = np.exp(s.physical_model().modes().poles * DT)
    got = s.discrete(DT).poles()
    np.testing.assert_allclose(np.sort_complex(got), np.sort_complex(expected), rtol=1e-12)


def test_structure_outputs_acceleration_consistent_with_deflection():
    # second method: d'' from the state space equals the second difference of d (smooth input)
    s = ToolStructure()
    n = 2000
    t = np.arange(n) * DT
    a = np.vstack([np.sin(2 * math.pi * 2.0 * t), np.cos(2 * math.pi * 3.0 * t)])
    out = control.forced_response(s.discrete(DT), t, a).outputs
    dd_fd = np.diff(out[:2], n=2, axis=1) / DT**2
    np.testing.assert_allclose(dd_fd[:, 500:], out[2:, 501:-1], atol=2e-3 * np.abs(out[2:]).max())


def test_noise_free_sensors_measure_the_truth(plant, q0):
    # definition: zero noise gives a_m = a, z_m = z; exact encoders q_m = q
    q_ref = plant.kinematics.ik(T0 + np.outer(np.minimum(np.arange(200) * DT, 0.3) ** 2, [0.1, 0.1, 0.0]))
    r = plant.simulate(q_ref)
    assert isinstance(r, TrackingResponse) and r.status == "completed"
    np.testing.assert_array_equal(r.a_m, r.a)
    np.testing.assert_array_equal(r.z_m, r.z)
    np.testing.assert_array_equal(r.q_m, r.q)
    np.testing.assert_array_equal(r.z, r.T_kin + r.d)
    assert np.all(r.d[:, 2] == 0) and np.abs(r.d[:, :2]).max() > 0
    assert r.t.shape == (200,) and all(getattr(r, f).shape == (200, 3) for f in ("q", "T_ref", "T_kin", "d", "z", "a_kin", "a", "a_m", "z_m"))


N_NOISE = 20000


@pytest.mark.parametrize("field, std", [("accelerometer", 0.07), ("gauge", 1e-6)])
def test_noise_statistics(field, std):
    # specification: zero mean, standard deviation as given (sampling error of the
    # estimated std ~ 1/sqrt(2 N) = 0.5 %; 4 sigma bounds)
    sensors = SensorModel(seed=3)
    a_m, z_m = sensors.measure(np.zeros((N_NOISE, 3)), np.zeros((N_NOISE, 3)))
    x = a_m if field == "accelerometer" else z_m
    np.testing.assert_allclose(x.std(axis=0), std, rtol=4 / math.sqrt(2 * N_NOISE))
    assert np.all(np.abs(x.mean(axis=0)) < 4 * std / math.sqrt(N_NOISE))


def test_noise_is_reproducible_per_trial_and_independent_between_trials():
    sensors = SensorModel(seed=7)
    zeros = np.zeros((1000, 3))
    first = sensors.measure(zeros, zeros, trial=1)[0]
    np.testing.assert_array_equal(first, sensors.measure(zeros, zeros, trial=1)[0])
    assert abs(np.corrcoef(first.ravel(), sensors.measure(zeros, zeros, trial=2)[0].ravel())[0, 1]) < 0.1


def test_accelerometer_clips_at_1_5_g():
    # specification: range 1.5 g = 14.709975 m/s^2; 20 m/s^2 minus 0.07 noise stays above it
    a = np.array([[20.0, -20.0, 1.0]] * 100)
    a_m, _ = SensorModel().measure(a, np.zeros_like(a))
    r = 1.5 * STANDARD_GRAVITY
    np.testing.assert_array_equal(a_m[:, 0], r)
    np.testing.assert_array_equal(a_m[:, 1], -r)
    assert np.all(np.abs(a_m[:, 2] - 1.0) < 1.0)


@pytest.mark.parametrize("j", [0, 1, 2], ids=["x", "y", "z"])
def test_tool_impulse_responses_equal_the_nonlinear_simulation(plant, q0, j):
    # second method: the nonlinear plant with a 1 um impulse of the tool reference at sample 1
    # (IK of T0 + eps e_j), divided by eps, against the linearised responses (7.9)
    n, eps = 120, 1e-6
    lin = plant.tool_impulse_responses(T0, n)
    T_ref = np.tile(T0, (n + 1, 1))
    T_ref[1, j] += eps
    r = plant.simulate(plant.kinematics.ik(T_ref))
    scale = np.abs(lin["kin"][:, j]).max()
    np.testing.assert_allclose((r.T_kin[1:, j] - T0[j]) / eps, lin["kin"][:, j], atol=1e-4 * scale)
    np.testing.assert_allclose((r.z[1:, j] - T0[j]) / eps, lin["tool_position"][:, j], atol=1e-4 * scale)
    np.testing.assert_allclose(r.a[1:, j] / eps, lin["acc"][:, j], atol=1e-4 * np.abs(lin["acc"][:, j]).max())
    # the cross terms the diagonal model leaves out
    others = [l for l in range(3) if l != j]
    sim_cross = np.abs(r.T_kin[1:, others] - T0[others]).max(axis=0) / eps / scale
    np.testing.assert_allclose(sim_cross, lin["cross_coupling"][others, j], rtol=1e-3)


def test_tool_impulse_responses_start_after_the_delay(plant):
    # 5 samples of actuator delay: nothing moves before sample 5 (the second difference of
    # T_kin makes the acceleration and the deflection start one sample earlier, at 4)
    lin = plant.tool_impulse_responses(T0, 30)
    assert np.all(lin["kin"][:5] == 0) and np.all(lin["acc"][:4] == 0) and np.abs(lin["acc"][4]).min() > 0
    np.testing.assert_array_equal(np.diag(lin["cross_coupling"]), 1.0)


def _acts(dt=DT):
    return actuator_models(load_dynamics_models("L1_dynamics_models")) if dt == DT else [control.tf([0.1], [1, -0.9], dt)] * 3


BAD = [
    ("frequencies_short", lambda: ToolStructure(frequencies_hz=(7.4,)), InputError, r"frequencies_hz: expected 2 positive"),
    ("frequency_tiny", lambda: ToolStructure(frequencies_hz=(1e-300, 11.5)), InputError, r"frequencies_hz: expected resonances of at least 0.01 Hz"),  # fuzz: overflowed k / w^2
    ("stiffness_negative", lambda: ToolStructure(stiffness=(4e6, -1.0)), InputError, r"stiffness: expected 2 positive"),
    ("damping_one", lambda: ToolStructure(damping=(1.0, 0.05)), InputError, r"damping: expected damping ratios below 1"),
    ("damping_nan", lambda: ToolStructure(damping=(math.nan, 0.05)), InputError, r"damping: expected 2 positive finite"),
    ("mass_zero", lambda: ToolStructure(mass=0.0), InputError, r"mass: expected a finite number > 0"),
    ("noise_negative", lambda: SensorModel(accelerometer_noise=-0.1), InputError, r"accelerometer_noise: expected a non-negative"),
    ("gauge_inf", lambda: SensorModel(gauge_noise=math.inf), InputError, r"gauge_noise: expected a non-negative finite"),
    ("range_zero", lambda: SensorModel(accelerometer_range=0.0), InputError, r"accelerometer_range: expected a finite number > 0"),
    ("seed_float", lambda: SensorModel(seed=1.5), InputError, r"seed: expected a non-negative integer"),
    ("seed_negative", lambda: SensorModel(seed=-1), InputError, r"seed: expected a non-negative integer"),
    ("trial_negative", lambda: SensorModel().measure(np.zeros((2, 3)), np.zeros((2, 3)), trial=-1), InputError, r"trial: expected"),
    ("measure_mismatch", lambda: SensorModel().measure(np.zeros((2, 3)), np.zeros((3, 3))), InputError, r"z: expected the shape \(2, 3\)"),
    ("kinematics_name", lambda: TrackingPlant("L1", _acts()), InputError, r"kinematics: expected a GantryTau3Kinematics"),
    ("two_actuators", lambda: TrackingPlant(GantryTau3Kinematics("L1"), _acts()[:2]), InputError, r"actuators: expected a list of 3"),
    ("actuator_dt", lambda: TrackingPlant(GantryTau3Kinematics("L1"), _acts(0.01)), InputError, r"actuators\[0\]: expected sample time dt = 0.004"),
    ("actuator_continuous", lambda: TrackingPlant(GantryTau3Kinematics("L1"), [control.tf([1], [1, 1])] * 3), InputError, r"actuators\[0\]: expected a discrete SISO"),
    ("structure_type", lambda: TrackingPlant(GantryTau3Kinematics("L1"), _acts(), structure=object()), InputError, r"structure: expected a ToolStructure"),
    ("dt_zero", lambda: TrackingPlant(GantryTau3Kinematics("L1"), _acts(), dt=0.0), InputError, r"dt: expected a finite number > 0"),
    ("q_ref_width", lambda: TrackingPlant.l1().simulate(np.zeros((10, 2))), InputError, r"q_ref: expected shape \(3,\) or \(N, 3\)"),
    ("q_ref_one_row", lambda: TrackingPlant.l1().simulate(np.zeros(3)), InputError, r"q_ref: expected at least 2 samples"),
    ("q_ref_nan", lambda: TrackingPlant.l1().simulate([[0.0, 0.0, 0.0], [math.nan, 0.0, 0.0]]), InputError, r"q_ref: row 1 is not finite"),
    ("impulse_n_zero", lambda: TrackingPlant.l1().actuator_impulse_responses(0), InputError, r"n: expected a positive integer"),
    ("T0_two_rows", lambda: TrackingPlant.l1().tool_impulse_responses(np.tile(T0, (2, 1)), 10), InputError, r"T0: expected one position"),
    ("T0_unreachable", lambda: TrackingPlant.l1().tool_impulse_responses([0.0, 10.0, 0.0], 10), UnreachablePoseError, r"unreachable"),
]


@pytest.mark.parametrize("case, call, error, match", BAD, ids=[c[0] for c in BAD])
def test_bad_input(case, call, error, match):
    with pytest.raises(error, match=match):
        call()
