"""Closed-loop actuator models (Dressler (2012), eq. 6.11) as discrete transfer functions.

Independent references: the thesis' numbers as transcribed in
``tests/reference/gantry_tau_L1.toml`` (table ``[actuators]``); the difference equation
``y_k = a y_(k-1) + b u_(k-5)`` evaluated by a plain loop; the closed-form bandwidth of
a discrete first-order lag ``cos(w Ts) = (1 + a^2 - g (1 - a)^2) / (2 a)``,
``g = 10^(-dbdrop/10)`` (the delay does not change the gain); the pole-based estimate
``-ln(a) / (2 pi Ts)``; :func:`control.bandwidth` for a continuous system.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import control
import numpy as np
import pytest

from gtmodel.errors import InputError, ParameterError
from gtmodel.robots.actuator_dynamics import (
    actuator_models,
    actuator_tf,
    bandwidth,
    load_dynamics_models,
    simulate,
    step,
)
from gtmodel.robots.parameters import available_parameter_sets

REFERENCE = Path(__file__).parents[1] / "reference" / "gantry_tau_L1.toml"
DATA_FILE = Path(__file__).parents[2] / "gtmodel" / "robots" / "data" / "L1_dynamics_models.toml"

#: The bandwidth root finder against the closed form (bisection to 1e-12 rad/s).
BANDWIDTH_TOLERANCE_HZ = 1e-6
#: Pole-based estimate -ln(a)/(2 pi Ts) against the -3 dB bandwidth (first-order lag, a ~ 0.97).
POLE_ESTIMATE_TOLERANCE_HZ = 0.01
#: The thesis' "about 1.1 Hz", compared with axis 3.
THESIS_BANDWIDTH_TOLERANCE_HZ = 0.05
#: Simulation against the difference equation (floating point).
SIM_TOLERANCE = 1e-12


def _reference() -> dict:
    return tomllib.loads(REFERENCE.read_text())["actuators"]


def _closed_form_bandwidth_hz(a: float, ts: float, dbdrop: float = -3.0) -> float:
    g = 10.0 ** (-dbdrop / 10.0)
    return math.acos((1.0 + a * a - g * (1.0 - a) ** 2) / (2.0 * a)) / ts / (2.0 * math.pi)


def test_data_file_carries_the_thesis_numbers():
    """The data file's [actuators] equal the reference transcription of (6.11)."""
    ref = _reference()
    act = load_dynamics_models("L1_dynamics_models").actuators
    np.testing.assert_array_equal(act.a, ref["a"])
    np.testing.assert_array_equal(act.b, ref["b"])
    assert act.sample_time == ref["sample_time_s"]
    assert act.delay_samples == ref["delay_samples"]
    assert act.bandwidth_hz_reported == ref["bandwidth_hz_approx"]


def test_data_file_is_not_a_robot_parameter_set():
    """available_parameter_sets lists only files with kinematics + dynamics tables."""
    assert "L1_dynamics_models" not in available_parameter_sets()


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_transfer_function_is_first_order_with_five_sample_delay(axis):
    """TF coefficients are b / (z^5 - a z^4), dt = 4 ms (eq. 6.11 in z)."""
    ref = _reference()
    G = actuator_models("L1_dynamics_models")[axis]
    assert G.dt == 0.004
    num = np.asarray(G.num[0][0], dtype=float)
    den = np.asarray(G.den[0][0], dtype=float)
    np.testing.assert_allclose(np.trim_zeros(num, "f"), [ref["b"][axis]])
    np.testing.assert_allclose(den, [1.0, -ref["a"][axis], 0, 0, 0, 0])


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_simulation_matches_difference_equation(axis):
    """forced_response of the TF equals the loop y_k = a y_(k-1) + b u_(k-5)."""
    ref = _reference()
    a, b = ref["a"][axis], ref["b"][axis]
    rng = np.random.default_rng(axis)
    n = 300
    u = rng.standard_normal(n)
    y = np.zeros(n)
    for k in range(n):
        y[k] = (a * y[k - 1] if k >= 1 else 0.0) + (b * u[k - 5] if k >= 5 else 0.0)
    t = np.arange(n) * 0.004
    out = simulate(actuator_models("L1_dynamics_models")[axis], t, u).outputs
    np.testing.assert_allclose(out, y, atol=SIM_TOLERANCE)


def test_step_response_has_dead_time_and_dc_gain():
    """Step: zero for the first 5 samples, b at sample 5, final value b / (1 - a)."""
    ref = _reference()
    G = actuator_models("L1_dynamics_models")[2]
    r = step(G, duration=4.0)
    y = np.asarray(r.outputs)
    assert np.all(y[:5] == 0.0)
    assert y[5] == pytest.approx(ref["b"][2])
    assert y[-1] == pytest.approx(ref["b"][2] / (1 - ref["a"][2]), rel=1e-6)


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_bandwidth_matches_closed_form(axis):
    """bandwidth() of each axis equals the closed form of a discrete first-order lag."""
    ref = _reference()
    bw = bandwidth(actuator_models("L1_dynamics_models")[axis])
    assert bw == pytest.approx(_closed_form_bandwidth_hz(ref["a"][axis], 0.004), abs=BANDWIDTH_TOLERANCE_HZ)
    assert bw == pytest.approx(-math.log(ref["a"][axis]) / (2 * math.pi * 0.004), abs=POLE_ESTIMATE_TOLERANCE_HZ)


def test_bandwidths_against_thesis_statement():
    """Thesis: 'about 1.1 Hz'. Axis 3 is 1.09 Hz; axes 1 and 2 are about 1.4 Hz (reported honestly)."""
    bws = [bandwidth(G) for G in actuator_models("L1_dynamics_models")]
    assert bws[2] == pytest.approx(_reference()["bandwidth_hz_approx"], abs=THESIS_BANDWIDTH_TOLERANCE_HZ)
    assert 1.35 < bws[0] < 1.45 and 1.35 < bws[1] < 1.45


def test_bandwidth_continuous_uses_control_bandwidth():
    """A continuous 1/(s + 1): control.bandwidth in rad/s divided by 2 pi."""
    G = control.tf([1.0], [1.0, 1.0])
    assert bandwidth(G) == pytest.approx(control.bandwidth(G) / (2 * math.pi), rel=1e-12)


def test_bandwidth_dbdrop():
    """A -6 dB drop gives the closed form with g = 10^0.6."""
    G = actuator_models("L1_dynamics_models")[0]
    a = _reference()["a"][0]
    assert bandwidth(G, dbdrop=-6.0) == pytest.approx(_closed_form_bandwidth_hz(a, 0.004, -6.0), abs=BANDWIDTH_TOLERANCE_HZ)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: bandwidth(control.tf([1.0], [1.0, 0.0])), "DC gain"),
        (lambda: bandwidth(control.ss(-np.eye(2), np.eye(2), np.eye(2), 0)), "SISO"),
        (lambda: bandwidth(actuator_models("L1_dynamics_models")[0], dbdrop=3.0), "dbdrop"),
        (lambda: actuator_tf(1.0, 0.03), "a: expected a stable pole"),
        (lambda: actuator_tf(float("nan"), 0.03), "a: expected a finite"),
        (lambda: actuator_tf(0.9, 0.0), "b: expected a non-zero"),
        (lambda: actuator_tf(0.9, 0.03, dt=0.0), "dt"),
        (lambda: actuator_tf(0.9, 0.03, delay=-1), "delay"),
        (lambda: simulate(actuator_models("L1_dynamics_models")[0], np.arange(10) * 0.004, np.ones(9)), "u: expected shape"),
        (lambda: simulate(actuator_models("L1_dynamics_models")[0], np.arange(10) * 0.004, np.r_[np.ones(9), np.nan]), "u: non-finite"),
        (lambda: simulate(actuator_models("L1_dynamics_models")[0], np.r_[0.0, 0.008, 0.004, 0.012], np.ones(4)), "t: times must increase"),
        (lambda: simulate(actuator_models("L1_dynamics_models")[0], np.arange(10) * 0.005, np.ones(10)), "equally spaced"),
        (lambda: step(actuator_models("L1_dynamics_models")[0], duration=-1.0), "duration"),
    ],
)
def test_bad_input(call, match):
    """Bad arguments raise InputError naming the argument."""
    with pytest.raises(InputError, match=match):
        call()


@pytest.mark.parametrize(
    "old, new, match",
    [
        ("a = [0.9647, 0.9656, 0.9728]", "a = [0.9647, 1.2, 0.9728]", "actuators.a': expected poles inside"),
        ("a = [0.9647, 0.9656, 0.9728]", "a = [0.9647, 0.9656]", "actuators.b': expected an array of shape"),
        ("delay_samples = 5", "delay_samples = 2.5", "actuators.delay_samples"),
        ("sample_time_s = 0.004", "sample_time_s = -0.004", "actuators.sample_time_s': expected a positive"),
        ("sample_time_s = 0.004", "sample_time = 0.004", "unknown field 'actuators.sample_time'"),
        ("M = [[0.0278, -0.0331], [-0.1759, 0.3086]]", "M = [[0.0, 0.0], [0.0, 0.0]]", "compliance.M': expected a non-singular"),
        ("K = [[-3732.6, -1567.1], [6920.9, 556.0]]", "K = [[-3732.6, -1567.1]]", "compliance.K': expected an array of shape"),
        ('convention = "thesis"', 'convention = "other"', "compliance.convention"),
        ("\n[compliance]\n", "\n[compliance_x]\n", "unknown field 'compliance_x'"),
    ],
)
def test_bad_data_file(tmp_path, old, new, match):
    """An edited copy of the data file is refused with the file and field named."""
    text = DATA_FILE.read_text()
    assert old in text
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(ParameterError, match=match) as info:
        load_dynamics_models(path)
    assert str(path) in str(info.value)


def test_unknown_name():
    """A name that is neither shipped nor a file is refused."""
    with pytest.raises(ParameterError, match="unknown dynamics-models file"):
        load_dynamics_models("no_such_models")
