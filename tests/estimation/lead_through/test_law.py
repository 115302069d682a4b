"""The lead-through law (Dressler (2012), eqs. 8.3-8.11) against closed forms of its equations.

Independent references: the projections written out by hand from (8.8)/(8.9)/(8.11) with
NumPy; the steady state of the impedance (8.6)-(8.7) in free space, ``V = D^-1 F`` (closed
form of the fixed point); the normal estimate (8.10) as ``f / |f|`` within ``phi_L``.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.estimation.lead_through import LeadThroughLaw

N_DOWN = np.array([0.0, 0.0, -1.0])


def _contact_state(law, F_t):
    """A state in contact: one step with a pressing tool force from rest."""
    return law.step(np.zeros(8), np.zeros(6), F_t).x_next


def test_free_space_impedance_reaches_the_closed_form_steady_state():
    # fixed point of V+ = V + dt M^-1 (F - D V): V* = D^-1 F (saturation not reached)
    law = LeadThroughLaw(M=2.0, D=40.0)
    F = np.array([1.0, -2.0, 0.5, 0, 0, 0])
    x = np.zeros(8)
    for _ in range(600):
        step = law.step(x, F, np.zeros(6))
        x = step.x_next
    np.testing.assert_allclose(step.V_tool[:3], F[:3] / 40.0, rtol=1e-9)
    assert not step.contact and np.all(step.V_tool[3:] == 0)


def test_in_contact_the_normal_is_force_controlled_and_the_tangent_led(seed=0):
    law = LeadThroughLaw(correction_range_deg=0.0)
    F_t = np.array([0.0, 0.0, -1.2, 0, 0, 0])  # pressing 1.2 N along n = (0, 0, -1)
    x = _contact_state(law, F_t)
    x[:6] = [0.03, -0.01, 0.2, 0.1, 0.1, 0.1]  # handle velocity, with a normal part and a rotation
    step = law.step(x, np.zeros(6), F_t)
    v_h_tangent = np.array([0.03, -0.01, 0.0])  # (8.8): normal part removed, no rotation
    v_t_normal = 0.005 * (2.0 - 1.2) * N_DOWN  # (8.9): K (f_ref - n.f_t) n
    np.testing.assert_allclose(step.V_tool, np.concatenate([v_h_tangent + v_t_normal, np.zeros(3)]), atol=1e-15)
    assert step.contact


def test_peg_in_hole_turns_the_tool_by_the_torque():
    law = LeadThroughLaw(task="peg_in_hole", force_reference=0.0, K=[0.005] * 3 + [0.5] * 3, correction_range_deg=0.0)
    F_t = np.array([0.0, 2.0, 0.0, 0.01, -0.02, 0.0])  # a wall pushes: force along +y, torque
    x = _contact_state(law, F_t)
    step = law.step(x, np.zeros(6), F_t)
    np.testing.assert_allclose(step.n, [0, 1, 0], atol=1e-15)  # (8.10) unrestricted for the peg
    np.testing.assert_allclose(step.V_tool, [0, -0.01, 0, -0.005, 0.01, 0], atol=1e-15)  # (8.11): -K F_t


@pytest.mark.parametrize("tilt_deg, phi_deg, estimated", [(5.0, 10.0, True), (5.0, 3.0, False), (5.0, 0.0, False)])
def test_normal_estimate_within_the_correction_range(tilt_deg, phi_deg, estimated):
    law = LeadThroughLaw(correction_range_deg=phi_deg)
    a = np.radians(tilt_deg)
    f = 2.0 * np.array([np.sin(a), 0.0, -np.cos(a)])
    step = law.step(_contact_state(law, np.r_[f, 0, 0, 0]), np.zeros(6), np.r_[f, 0, 0, 0])
    np.testing.assert_allclose(step.n, f / np.linalg.norm(f) if estimated else N_DOWN, atol=1e-15)


def test_a_pull_off_the_surface_releases_contact_and_contact_is_retaken_only_after_the_force_drops():
    law = LeadThroughLaw()
    press = np.array([0, 0, -2.0, 0, 0, 0])
    x = _contact_state(law, press)
    pulled = law.step(x, np.array([0, 0, 12.0, 0, 0, 0]), press)  # 12 N away from the surface > 10 N
    assert not pulled.contact and pulled.x_next[7] == 1.0
    still = law.step(pulled.x_next, np.zeros(6), press)  # force still there: not retaken (releasing)
    assert not still.contact
    gone = law.step(still.x_next, np.zeros(6), np.zeros(6))
    again = law.step(gone.x_next, np.zeros(6), press)
    assert gone.x_next[7] == 0.0 and again.contact


def test_safety_saturation_limits_the_speed():
    law = LeadThroughLaw(max_speed=0.1)
    x = np.zeros(8)
    for _ in range(20):
        step = law.step(x, np.array([500.0, 0, 0, 0, 0, 0]), np.zeros(6))
        x = step.x_next
    assert np.linalg.norm(step.V_tool[:3]) == pytest.approx(0.1, rel=1e-12)


def test_without_tool_force_control_the_tool_sensor_is_ignored():
    law = LeadThroughLaw(tool_force_control=False)
    step = law.step(np.zeros(8), np.array([0, 0, -4.0, 0, 0, 0]), np.array([0, 0, -5.0, 0, 0, 0]))
    assert not step.contact
    np.testing.assert_allclose(step.V_tool, 0.0)  # from rest the first applied reference is V_h(0) = 0
    np.testing.assert_allclose(step.x_next[:3], [0, 0, 0.004 * -4.0 / 2.0])


BAD_LAWS = [
    ("singular M", {"M": [2, 2, 0, 1, 1, 1]}, r"M: expected a symmetric positive definite matrix"),
    ("negative D", {"D": [-1, 1, 1, 1, 1, 1]}, r"D: expected a symmetric positive semi-definite"),
    ("non-symmetric K", {"K": np.triu(np.ones((6, 6)))}, r"K: expected a symmetric matrix"),
    ("phi_L above 90", {"correction_range_deg": 95.0}, r"correction_range_deg: expected phi_L in \[0, 90\]"),
    ("negative phi_L", {"correction_range_deg": -1.0}, r"correction_range_deg: expected a finite non-negative"),
    ("zero normal", {"nominal_normal": [0, 0, 0]}, r"nominal_normal: expected a non-zero direction"),
    ("unknown task", {"task": "welding"}, r"task: expected one of surface_tracking, peg_in_hole"),
    ("release below contact", {"release_force": 0.2}, r"release_force: expected above contact_force"),
    ("NaN force reference", {"force_reference": float("nan")}, r"force_reference: expected a finite force"),
    ("M of wrong shape", {"M": [1, 2, 3]}, r"M: expected a number, 6 diagonal entries or a 6x6 matrix"),
]


@pytest.mark.parametrize("case, kwargs, match", BAD_LAWS, ids=[b[0] for b in BAD_LAWS])
def test_bad_law_parameters_are_refused(case, kwargs, match):
    with pytest.raises(InputError, match=match):
        LeadThroughLaw(**kwargs)


BAD_STEPS = [
    ("NaN tool force", {"F_t": [np.nan, 0, 0, 0, 0, 0]}, r"F_t: expected 6 finite numbers"),
    ("Inf handle force", {"F_h": [np.inf, 0, 0, 0, 0, 0]}, r"F_h: expected 6 finite numbers"),
    ("short state", {"x": np.zeros(7)}, r"x: expected 8 finite numbers"),
    ("non-unit normal", {"n_n": [0, 0, -2.0]}, r"n_n: expected a unit normal"),
]


@pytest.mark.parametrize("case, override, match", BAD_STEPS, ids=[b[0] for b in BAD_STEPS])
def test_bad_step_arguments_are_refused(case, override, match):
    args = {"x": np.zeros(8), "F_h": np.zeros(6), "F_t": np.zeros(6), "n_n": N_DOWN, **override}
    with pytest.raises(InputError, match=match):
        LeadThroughLaw().step(**args)


def test_the_step_function_flags_a_non_unit_normal_for_the_generated_c():
    f = LeadThroughLaw().step_function()
    valid = [float(f(np.zeros(8), np.zeros(6), np.zeros(6), n)[3]) for n in (N_DOWN, 1.01 * N_DOWN)]
    assert valid[0] >= 0 > valid[1]
