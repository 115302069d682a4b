"""The linearised contact loop against python-control (a second construction) and the simulation.

Independent references: the same loop built with python-control (the continuous servo and
integrator discretised by ``c2d`` with a zero-order hold, closed with ``feedback``), whose
poles must equal ours; the oscillation frequency of the simulated stiff-surface run (the
force spectrum's peak) within 10 % of the predicted one; a gain just above the largest
stable one makes the simulated contact force grow.
"""

from __future__ import annotations

import math

import control
import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.estimation.lead_through import LeadThroughLaw, Operator, Servo, Surface, simulate
from gtmodel.estimation.lead_through.experiments import correction_range_study
from gtmodel.estimation.lead_through.stability import contact_loop, largest_stable_gain

DT = 0.004


def _control_poles(K, k, d, servo):
    ws = 2 * math.pi * servo.bandwidth_hz
    plant = control.ss([[0.0, 1.0], [0.0, -ws]], [[0.0], [ws]], [[k, d]], [[0.0]])  # v_ref -> f
    disc = control.c2d(plant, DT, "zoh")
    if servo.delay_samples:
        disc = control.series(control.tf([1], [1, 0], DT), disc)
    loop = control.feedback(disc, K)
    return np.sort_complex(np.asarray(control.poles(loop)))


@pytest.mark.parametrize("K, k, d, delay", [(0.005, 1e5, 20.0, 0), (0.005, 2e3, 20.0, 0), (0.002, 5e4, 0.0, 1), (0.01, 2e4, 5.0, 1)])
def test_poles_equal_python_control(K, k, d, delay):
    servo = Servo(50.0, delay)
    ours = np.sort_complex(contact_loop(K, k, d, servo, DT).poles)
    np.testing.assert_allclose(ours, _control_poles(K, k, d, servo), atol=1e-9)


def test_largest_stable_gain_is_the_stability_boundary():
    g = largest_stable_gain(1e5, 20.0)
    assert contact_loop(0.999 * g, 1e5, 20.0).stable and not contact_loop(1.001 * g, 1e5, 20.0).stable


def test_the_largest_stable_gain_falls_with_the_stiffness():
    gains = [largest_stable_gain(k, 20.0) for k in (1e3, 1e4, 1e5)]
    assert gains[0] > gains[1] > gains[2]


def test_the_predicted_frequency_is_the_simulated_one():
    row = correction_range_study(ranges=(10.0,), duration=4.0)[0]
    assert row.frequency_hz == pytest.approx(row.predicted_hz, rel=0.10)


def test_above_the_largest_stable_gain_the_simulated_force_grows():
    surface = Surface(1e5, 20.0)
    g = largest_stable_gain(1e5, 20.0)
    operator = Operator(force=[(0.0, (0, 0, -3.0))])
    runs = [simulate(LeadThroughLaw(K=[f * g] * 3 + [0] * 3, max_speed=10.0), surface, operator, 1.5, tool_noise=0.01) for f in (0.8, 1.3)]
    forces = [r.normal_force(surface.normal)[-100:] for r in runs]
    assert np.ptp(forces[0]) < 0.5 and np.ptp(forces[1]) > 10 * np.ptp(forces[0])
    assert forces[1].min() == 0.0  # the growing oscillation ends in contact lost (a limit cycle of the unilateral contact)


@pytest.mark.parametrize("args, match", [
    ((-1.0, 1e5), r"gain: expected a finite non-negative"),
    ((0.005, 0.0), r"stiffness: expected a finite positive"),
    ((0.005, 1e5, -1.0), r"damping: expected a finite non-negative"),
])
def test_bad_loop_arguments(args, match):
    with pytest.raises(InputError, match=match):
        contact_loop(*args)
