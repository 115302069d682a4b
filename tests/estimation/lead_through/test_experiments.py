"""The experiments of Dressler (2012), ch. 8.4 in simulation: the structure the thesis reports.

References: the thesis' own observations (Figure 8.4: with tool force control contact is
kept and the force held at 2 N, without it contact is lost and the force peaks; Figure 8.5:
the oscillation grows with the correction range; ch. 8.4: the 3 mm peg enters the 4 mm hole,
a hole as narrow as the peg rejects it); the servo against SciPy's exact first-order
response (an independent integration).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from gtmodel.errors import InputError
from gtmodel.estimation.lead_through import LeadThroughLaw, Operator, PegHole, Servo, Surface, simulate
from gtmodel.estimation.lead_through.experiments import (
    FORCE_BAND_N,
    PEAK_LIMIT_N,
    correction_range_study,
    peg_in_hole,
    surface_tracking,
)


@pytest.fixture(scope="module")
def figure_8_4():
    return surface_tracking(), surface_tracking(LeadThroughLaw(tool_force_control=False))


def test_with_tool_force_control_contact_is_kept_at_2_newton(figure_8_4):
    r = figure_8_4[0]
    assert r.contact_kept and r.force_error <= FORCE_BAND_N and r.released


def test_without_tool_force_control_contact_is_lost_or_the_force_peaks(figure_8_4):
    r = figure_8_4[1]
    assert r.lost_contact_fraction > 0.1 and r.peak_force > PEAK_LIMIT_N


@pytest.mark.slow
def test_the_oscillation_grows_with_the_correction_range():
    rows = correction_range_study()
    stds = [r.force_std for r in rows]
    assert stds[0] < stds[1] < stds[2]
    assert rows[0].lost_contact_fraction == 0.0 < rows[2].lost_contact_fraction  # 10 deg: close to losing contact


@pytest.fixture(scope="module")
def pegs():
    return peg_in_hole(), peg_in_hole(PegHole(hole_radius=1.5e-3))


def test_the_peg_enters_the_misaligned_hole(pegs):
    r = pegs[0]
    assert r.inserted and r.max_force < 30.0
    assert r.angle_end_deg < r.angle_start_deg  # the torque turns it towards the hole's axis


def test_with_zero_clearance_the_peg_is_rejected(pegs):
    assert pegs[1].max_insertion < pegs[1].hole.peg_radius and not pegs[1].inserted


def test_the_servo_is_the_exact_first_order_response():
    # free space, tool force control unused: the TCP follows V_tool through a 50 Hz first-order lag
    law = LeadThroughLaw(M=1.0, D=10.0)
    run = simulate(law, Surface(1e3, normal=(0, 0, 1), point=(0, 0, -1.0)), Operator(force=[(0.0, (0, 0, 0.5))]), 0.4,
                   start=(0, 0, 0), tool_noise=0.0, handle_noise=0.0)
    ws = 2 * np.pi * Servo().bandwidth_hz
    A, B, C, D = (np.array(m, dtype=float) for m in ([[0.0, 1.0], [0.0, -ws]], [[0.0], [ws]], [[1.0, 0.0]], [[0.0]]))  # v_ref -> position
    Ad, Bd, Cd, Dd, _ = signal.cont2discrete((A, B, C, D), law.dt, method="zoh")
    z = signal.dlsim((Ad, Bd, Cd, Dd, law.dt), run.V_tool[:, 2])[1].ravel()
    np.testing.assert_allclose(run.p[1:, 2], z[1:], atol=1e-12)


@pytest.mark.parametrize("kwargs, match", [
    ({"duration": 0.0}, r"duration: expected a finite positive"),
    ({"duration": 1e4}, r"duration: expected at most 600 s"),
    ({"start": (0, 0)}, r"start: expected 3 finite numbers"),
    ({"tool_noise": -1.0}, r"tool_noise: expected a finite non-negative"),
])
def test_bad_simulation_arguments(kwargs, match):
    args = {"duration": 1.0, **kwargs}
    with pytest.raises(InputError, match=match):
        simulate(LeadThroughLaw(), Surface(1e3), Operator(force=[(0.0, (0, 0, 0))]), **args)


@pytest.mark.parametrize("kwargs, match", [
    ({"stiffness": -5.0}, r"stiffness: expected a finite positive"),
    ({"stiffness": 1e3, "normal": (0, 0, 0)}, r"normal: expected a non-zero direction"),
])
def test_bad_surfaces(kwargs, match):
    with pytest.raises(InputError, match=match):
        Surface(**kwargs)


@pytest.mark.parametrize("kwargs, match", [
    ({"hole_radius": 1e-3}, r"hole_radius: expected at least peg_radius"),
    ({"misalignment_deg": 50.0}, r"misalignment_deg: expected an angle in \[0, 45\)"),
])
def test_bad_holes(kwargs, match):
    with pytest.raises(InputError, match=match):
        PegHole(**kwargs)
