"""Mechanistic milling force (12)-(17) and spindle-angle pose optimisation (18)-(19).

Independent references: Altintas' closed-form average milling forces per revolution, the
single-tooth force formula at a given angle, the joint-spring deflection (3) evaluated
directly, the FK of the IK solutions, and the quasi-static limit of the dynamic
objective. Arm: the ILLUSTRATIVE 6R geometry (assumed DH values).
"""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from gtmodel.calibration.joint_stiffness import TABLE_1_POSES_DEG, TABLE_2_K_THETA
from gtmodel.errors import InputError
from gtmodel.robots.serial import load_serial_arm
from gtmodel.trajectory.milling import TABLE_3_COEFFICIENTS, MillingCoefficients, MillingProcess, optimise_spindle_angle

from ..conftest import SHARED_REFERENCE

AVERAGE_RELATIVE = 2e-3  # grid quadrature of a discontinuous force, 7200 samples/rev
EXACT_RELATIVE = 1e-12
QUASI_STATIC_RELATIVE = 0.02
FK_TOLERANCE = 1e-8


def _closed_form_average(p: MillingProcess) -> np.ndarray:
    """Altintas (2012), average forces per revolution with edge terms."""
    K, N, a, c = p.coefficients, p.n_teeth, p.axial_depth, p.feed_per_tooth

    def prim(phi):
        fx = (N * a * c / (8 * np.pi)) * (K.K_tc * np.cos(2 * phi) - K.K_rc * (2 * phi - np.sin(2 * phi))) + (N * a / (2 * np.pi)) * (-K.K_te * np.sin(phi) + K.K_re * np.cos(phi))
        fy = (N * a * c / (8 * np.pi)) * (K.K_tc * (2 * phi - np.sin(2 * phi)) + K.K_rc * np.cos(2 * phi)) - (N * a / (2 * np.pi)) * (K.K_te * np.cos(phi) + K.K_re * np.sin(phi))
        fz = (N * a / (2 * np.pi)) * (-K.K_ac * c * np.cos(phi) + K.K_ae * phi)
        return np.array([fx, fy, fz])

    return prim(p.exit_angle) - prim(p.entry_angle)


def test_coefficients_match_table_3():
    """Table 3 coefficients equal the transcribed reference."""
    ref = tomllib.loads((SHARED_REFERENCE / "serial_kr500.toml").read_text())["milling_coefficients"]
    K = TABLE_3_COEFFICIENTS
    assert (K.K_te, K.K_tc, K.K_re, K.K_rc, K.K_ae, K.K_ac) == (
        ref["K_te_N_per_m"], ref["K_tc_Pa"], ref["K_re_N_per_m"], ref["K_rc_Pa"], ref["K_ae_N_per_m"], ref["K_ac_Pa"])


@pytest.mark.parametrize(
    "n_teeth, entry, exit_",
    [(2, 0.0, math.pi), (3, 0.0, math.pi / 2), (4, math.pi / 2, math.pi), (2, math.pi / 3, 2 * math.pi / 3)],
    ids=["slot", "up-milling-half", "down-milling-half", "partial"],
)
def test_average_force_matches_closed_form(n_teeth, entry, exit_):
    """Mean of the CasADi force over one revolution equals the closed-form average."""
    p = MillingProcess(n_teeth, 3000.0, 1e-4, 2e-3, entry, exit_)
    spr = 7200
    t = (np.arange(spr) + 0.5) * p.revolution_time / spr
    mean = p.force(t).mean(axis=0)
    ref = _closed_form_average(p)
    np.testing.assert_allclose(mean, ref, rtol=AVERAGE_RELATIVE, atol=AVERAGE_RELATIVE * np.max(np.abs(ref)))


def test_single_tooth_force_at_angle():
    """At phi = 60 deg one tooth cuts: forces from h = f_t sin(phi) by hand."""
    p = MillingProcess(1, 6000.0, 1e-4, 3e-3, 0.0, math.pi)
    phi = math.radians(60)
    K, a, h = TABLE_3_COEFFICIENTS, 3e-3, 1e-4 * math.sin(phi)
    Ft, Fr, Fa = K.K_tc * a * h + K.K_te * a, K.K_rc * a * h + K.K_re * a, K.K_ac * a * h + K.K_ae * a
    ref = [-Ft * math.cos(phi) - Fr * math.sin(phi), Ft * math.sin(phi) - Fr * math.cos(phi), Fa]
    t = phi / (2 * math.pi * 6000 / 60)
    np.testing.assert_allclose(p.force([t])[0], ref, rtol=EXACT_RELATIVE)
    assert np.all(p.force([t + p.revolution_time * 0.75])[0] == 0)  # tooth out of cut


@pytest.fixture(scope="module")
def case():
    arm = load_serial_arm("serial_6r_illustrative")
    th0 = np.radians(TABLE_1_POSES_DEG[1])
    return arm, arm.fk(th0), th0, MillingProcess(2, 3000.0, 1e-4, 2e-3, 0.0, math.pi / 2), TABLE_2_K_THETA["DPP"]


def test_static_objective_is_deflection_eq3(case):
    """Eq. (18) at each feasible grid angle equals |dp| of eq. (3) evaluated directly; IK reaches T(A)."""
    arm, T, th0, proc, k = case
    res = optimise_spindle_angle(arm, T, th0, proc, k, A_deg=np.arange(-180, 180, 30.0), n_revolutions=2)
    assert res.success and res.status == "optimal"
    feasible = np.flatnonzero(res.feasible)
    dp = np.array([np.linalg.norm(arm.deflection(res.theta[i], np.r_[res.F_peak, 0, 0, 0], k)[:3]) for i in feasible])
    np.testing.assert_array_less(np.abs(res.static_objective[feasible] - dp), EXACT_RELATIVE * 1e3 * dp)
    Ti = np.array([arm.fk(res.theta[i]) for i in feasible])
    np.testing.assert_allclose(Ti[:, :3, 3], np.broadcast_to(T[:3, 3], (feasible.size, 3)), atol=FK_TOLERANCE)
    np.testing.assert_allclose(Ti[:, :3, 2], np.broadcast_to(T[:3, 2], (feasible.size, 3)), atol=FK_TOLERANCE)  # spindle axis unchanged
    assert np.nanmax(res.static_objective) > 1.2 * np.nanmin(res.static_objective)  # A matters
    assert res.static_objective[list(res.A_deg).index(res.best_static_deg)] == np.nanmin(res.static_objective)


def test_joint_limits_make_angles_infeasible(case):
    """Angles whose IK leaves the joint limits are reported infeasible, not silently used."""
    arm, T, th0, proc, k = case
    lim = np.column_stack([th0 - 0.3, th0 + 0.3])
    res = optimise_spindle_angle(arm, T, th0, proc, k, A_deg=np.arange(-180, 180, 30.0), theta_limits=lim, n_revolutions=1)
    assert res.feasible[list(res.A_deg).index(0.0)] and not np.all(res.feasible)
    assert np.all(np.isnan(res.static_objective[~res.feasible]))
    assert "joint limits" in res.message


def test_settled_dynamic_objective_is_periodic(case):
    """In steady state (after 1.5 s) the peak does not depend on the window length (2 vs 6 revolutions)."""
    arm, T, th0, proc, k = case

    def dyn(theta, p, A):
        return np.array([200.0, 150, 250]), np.array([4000.0, 3000, 3500]), np.array([1e6, 0.5e6, 0.8e6])

    r2 = optimise_spindle_angle(arm, T, th0, proc, k, dynamics=dyn, A_deg=[0.0], n_revolutions=2, settle_time=1.5)
    r6 = optimise_spindle_angle(arm, T, th0, proc, k, dynamics=dyn, A_deg=[0.0], n_revolutions=6, settle_time=1.5)
    np.testing.assert_allclose(r2.dynamic_objective, r6.dynamic_objective, rtol=1e-3)


def test_dynamic_objective_quasi_static_limit(case):
    """Fast, critically damped modes (k = 1 MN/m, 3 kHz): eq. (19) -> max_t |F(t)| / k."""
    arm, T, th0, proc, k = case
    kd, m = 1e6, 1e6 / (2 * np.pi * 3000) ** 2
    c = 2 * np.sqrt(kd * m)

    def dyn(theta, p, A):
        return np.full(3, m), np.full(3, c), np.full(3, kd)

    res = optimise_spindle_angle(arm, T, th0, proc, k, dynamics=dyn, A_deg=[-10.0, 0.0, 10.0], n_revolutions=2, samples_per_revolution=10000)
    ref = np.max(np.linalg.norm(res.extra["F_base"], axis=1)) / kd
    np.testing.assert_allclose(res.dynamic_objective, ref, rtol=QUASI_STATIC_RELATIVE)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: MillingProcess(0, 3000, 1e-4, 2e-3), "n_teeth"),
        (lambda: MillingProcess(2, -3000, 1e-4, 2e-3), "spindle_speed_rpm"),
        (lambda: MillingProcess(2, 3000, float("nan"), 2e-3), "feed_per_tooth"),
        (lambda: MillingProcess(2, 3000, 1e-4, 2e-3, 2.0, 1.0), "entry_angle, exit_angle"),
        (lambda: MillingCoefficients(1, 1, -1, 1, 1, 1), "K_re"),
        (lambda: MillingProcess(2, 3000, 1e-4, 2e-3).force([[0.0]]), "t: expected a finite 1-D"),
        (lambda: MillingProcess(2, 3000, 1e-4, 2e-3).time_grid(1, 4), "samples_per_revolution"),
    ],
)
def test_bad_process_input(call, match):
    """Bad cutting conditions are refused with a message naming the argument."""
    with pytest.raises(InputError, match=match):
        call()


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(k_theta=np.zeros(6)), "k_theta"),
        (dict(A_deg=[10.0, 0.0]), "A_deg: expected a finite strictly increasing"),
        (dict(theta0=np.zeros(5)), "theta0"),
        (dict(dynamics="gp"), "dynamics"),
        (dict(theta_limits=np.zeros((6, 2))), "theta_limits"),
        (dict(settle_time=-1.0), "settle_time"),
        (dict(R_workpiece=2 * np.eye(3)), "R_workpiece"),
        (dict(T_nominal=np.eye(3)), "T_nominal"),
        (dict(process="slot"), "process: expected a MillingProcess"),
    ],
)
def test_bad_optimisation_input(case, kwargs, match):
    """Bad optimisation arguments are refused with a message naming the argument."""
    arm, T, th0, proc, k = case
    args = dict(arm=arm, T_nominal=T, theta0=th0, process=proc, k_theta=k, A_deg=[0.0, 10.0])
    args.update(kwargs)
    with pytest.raises(InputError, match=match):
        optimise_spindle_angle(**args)
