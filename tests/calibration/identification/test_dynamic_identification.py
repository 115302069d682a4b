"""Identification of masses and friction (Dressler (2012), ch. 6.2, eqs. 6.7-6.9, Tables 6.1-6.3)."""

from __future__ import annotations

import logging
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from gtmodel.calibration.identification import (
    TABLE_6_3_COLUMNS,
    THESIS_TABLE_6_3,
    VARIANTS,
    ConstantVelocityData,
    DynamicRegressor,
    DynamicSamples,
    FourierTrajectory,
    MotionLog,
    StribeckTerm,
    accumulated_gravity_forces,
    column_dependency,
    fit_friction,
    identify_dynamics,
    preprocess_log,
    read_motion_log,
    simulate_constant_velocity,
    simulate_log,
    subtract_gravity,
    two_direction_friction,
)
from gtmodel.errors import InputError, ModelError
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.parameters import load_parameters

REFERENCE = Path(__file__).parents[2] / "reference" / "gantry_tau_L1.toml"

#: Y theta + tau0 against the model's inverse dynamics: round-off of the same graph [N].
FORCE_TOLERANCE_N = 1e-8
#: Noise-free identification with exact derivatives: relative error of every parameter.
EXACT_RELATIVE_TOLERANCE = 1e-6
#: Acceptance: every estimate within this many standard deviations of the truth.
Z_LIMIT = 3.0
#: identify_dynamics (QR of the per-actuator row blocks) against numpy.linalg.lstsq on the
#: same rows: relative difference of every estimate.
LSTSQ_RELATIVE_TOLERANCE = 1e-10
#: Standard deviations against sigma^2 (A^T W^2 A)^-1 by NumPy (normal equations), relative.
STD_RELATIVE_TOLERANCE = 1e-8
#: Regressor compiled to C against the CasADi interpreter (same graph, IEEE arithmetic),
#: relative to the largest entry.
COMPILED_RELATIVE_TOLERANCE = 1e-12
#: Force noise of the simulated logs [N] (Gaussian, per 4 ms sample).
FORCE_NOISE_N = 5.0
#: Table 6.2: the three gravity forces of a pose sum to zero (force balance along the
#: guideways); allowed relative imbalance (guideways not exactly parallel to x here).
GRAVITY_BALANCE_RELATIVE = 0.02

#: An excitation designed by design_excitation (L1, model 2, 4 harmonics, 10 s), fixed here
#: so that these tests do not depend on IPOPT.
COEFFICIENTS = np.array([
    0.3823, 0.4933, 0.5069, 0.0003, 0.0145, 0.071, 0.005, 0.0224, 0.1255, 0.1762, 0.1252, -0.0071,
    -0.0465, 0.0211, -0.0302, -0.0974, -0.1988, -0.17, -0.1204, -0.111, -0.0951, -0.1063, -0.0129, -0.1171,
    0.1516, -0.2066, 0.1159,
])
TRAJECTORY = FourierTrajectory.from_coefficients(COEFFICIENTS, 4, 10.0)


@pytest.fixture(scope="module")
def reference():
    return tomllib.loads(REFERENCE.read_text())["dynamics"]


@pytest.fixture(scope="module")
def regressor():
    return DynamicRegressor("L1", "model_2")


@pytest.fixture(scope="module")
def motion():
    rng = np.random.default_rng(0)
    n = 40
    T = np.array([0.0, 2.9, -0.5]) + rng.uniform(-0.15, 0.15, (n, 3))
    return T, rng.normal(0, 0.3, (n, 3)), rng.normal(0, 2.0, (n, 3))


@pytest.fixture(scope="module")
def noisy_log():
    log, truth = simulate_log(TRAJECTORY, 30.0, "L1", force_noise=FORCE_NOISE_N, seed=3)
    return log, truth


# ----------------------------------------------------------------------------- regressor
@pytest.mark.parametrize("variant", ["model_2", "model_3", "full", "asymmetric"])
def test_regressor_times_theta_equals_inverse_dynamics(motion, variant):
    """Y theta + tau0 equals GantryTau3Dynamics.inverse_dynamics (eqs. 6.7/6.8) for the
    variants whose structure contains the L1 parameter set (asymmetric: Table 6.1)."""
    T, Td, Tdd = motion
    reg = DynamicRegressor("L1", variant)
    ref = GantryTau3Dynamics("L1", asymmetric=VARIANTS[variant].asymmetric).inverse_dynamics(T, Td, Tdd)
    np.testing.assert_allclose(reg.forces(reg.theta_of(), T, Td, Tdd, "tcp"), ref, atol=FORCE_TOLERANCE_N)


def test_cart_coordinates_regressor_equals_tcp_regressor(motion, regressor):
    """The cart-coordinate regressor (FK differentiated by CasADi) equals the TCP one on the
    same motion converted by the kinematics' eq. 6.6 (a second route)."""
    T, Td, Tdd = motion
    q, qd, qdd = regressor.model.kinematics.cart_motion(T, Td, Tdd)
    Yc, t0c, vc = regressor.evaluate(q, qd, qdd, "cart")
    Yt, t0t, vt = regressor.evaluate(T, Td, Tdd, "tcp")
    np.testing.assert_allclose(Yc, Yt, atol=1e-8)
    np.testing.assert_allclose(vc, vt, atol=1e-12)


@pytest.mark.parametrize("j", [0, 4, 9], ids=["m_p", "f_c1", "f_v3"])
def test_regressor_is_the_jacobian_of_the_forces(motion, regressor, j):
    """Linearity in theta: tau(theta + d e_j) - tau(theta) = d Y[:, j] (finite difference)."""
    T, Td, Tdd = motion
    th = regressor.theta_of()
    Y, _, _ = regressor.evaluate(T, Td, Tdd, "tcp")
    e = np.zeros_like(th)
    e[j] = 1.0
    diff = regressor.forces(th + e, T, Td, Tdd, "tcp") - regressor.forces(th, T, Td, Tdd, "tcp")
    np.testing.assert_allclose(diff, Y[:, :, j], atol=1e-8)


@pytest.mark.parametrize("model", sorted(THESIS_TABLE_6_3))
def test_table_6_3_constant_matches_the_reference_file(reference, model):
    """THESIS_TABLE_6_3 reproduces the reference figures (nan where the thesis took Table 6.1)."""
    t = reference["table_6_3"]
    v = THESIS_TABLE_6_3[model]
    np.testing.assert_array_equal(np.array(v["row"]), np.array(t[model], dtype=float))
    np.testing.assert_array_equal(np.array(v["residual"]), np.array(t["residual_1e7_Nm2"][model]))


# ----------------------------------------------------------------------------- identification
def test_noise_free_identification_recovers_the_parameters_exactly():
    """Exact motion and forces (no noise, no filter): least squares returns the generating
    Table 6.3 model 2 parameters to round-off."""
    log, truth = simulate_log(TRAJECTORY, 10.0, "L1", force_noise=0.0, position_noise=0.0, position_resolution=0.0, sample_time=0.02)
    s = DynamicSamples(truth["t"], truth["q"], truth["q_dot"], truth["q_ddot"], truth["tau"])
    res = identify_dynamics(s, "L1", variant="model_2", weighting="none")
    reg = DynamicRegressor("L1", "model_2")
    np.testing.assert_allclose(res.theta, reg.theta_of(), rtol=EXACT_RELATIVE_TOLERANCE)
    assert res.success and res.status == "optimal"


@pytest.mark.parametrize("method", ["butter", "savgol"])
def test_identification_recovers_model_2_within_3_std(noisy_log, regressor, method):
    """Simulated 4 ms log (Table 6.3 model 2, 5 N force noise, 1 um position noise and
    quantisation), zero-phase filtered at 10 Hz: every estimate lies within 3 reported
    standard deviations of the generating value."""
    log, _ = noisy_log
    s = preprocess_log(log, cutoff=10.0, method=method, order=4 if method == "butter" else 3)
    res = identify_dynamics(s, regressor=regressor)
    z = res.z_scores(regressor.theta_of())
    assert np.all(z <= Z_LIMIT), dict(zip(res.names, np.round(z, 2)))
    # the residual is the filtered noise: 5 N white noise at 4 ms through a 10 Hz low-pass
    expected = FORCE_NOISE_N * math.sqrt(2 * 10.0 * 0.004)
    assert np.all(res.residual_rms < 1.5 * expected)
    assert res.condition_number < 5.0


def test_tcp_position_log_gives_the_same_parameters(noisy_log, regressor):
    """A log of TCP positions (the cart log mapped by the FK, eq. 4.9) goes through the
    TCP-coordinate regressor and recovers model 2 within 3 std as well."""
    log, _ = noisy_log
    T = regressor.model.kinematics.fk(log.q)
    tcp_log = MotionLog(t=log.t, tau=log.tau, T=T)
    res = identify_dynamics(preprocess_log(tcp_log), "L1", variant="model_2")
    assert tcp_log.coordinates == "tcp"
    assert np.all(res.z_scores(regressor.theta_of()) <= Z_LIMIT)


def test_stribeck_term_shows_as_low_speed_residual(regressor):
    """A Stribeck term the model lacks (40 N, v_s = 0.02 m/s) leaves the parameters within
    3 std (rows below 0.05 m/s are not fitted) and a residual at 0.02-0.05 m/s far above
    the one at high speed -- the low-speed residual of Dressler (2012), ch. 6.2."""
    log, _ = simulate_log(TRAJECTORY, 30.0, "L1", force_noise=FORCE_NOISE_N, stribeck=StribeckTerm(), seed=3)
    res = identify_dynamics(preprocess_log(log), regressor=regressor)
    assert np.all(res.z_scores(regressor.theta_of()) <= Z_LIMIT)
    low = next(b for b in res.residual_by_speed if b["v_min"] == 0.02)["rms"]
    high = next(b for b in res.residual_by_speed if b["v_min"] == 0.2)["rms"]
    assert np.all(np.array(low) > 2.5 * np.array(high))


@pytest.mark.parametrize("v", ["model_1", "model_2", "model_3", "model_4"])
def test_table_6_3_rows_have_the_thesis_layout(noisy_log, reference, v):
    """table_6_3_row puts nan exactly where the thesis' Table 6.3 has nan (friction taken
    from Table 6.1) and 0 for model 1's viscous friction."""
    s = preprocess_log(noisy_log[0])
    row = identify_dynamics(s, "L1", variant=v).table_6_3_row()
    ref = np.array(reference["table_6_3"][v], dtype=float)
    np.testing.assert_array_equal(np.isnan(row), np.isnan(ref))
    assert len(row) == len(TABLE_6_3_COLUMNS)
    if v == "model_1":
        np.testing.assert_array_equal(row[7:], 0.0)


def test_link_masses_are_poorly_identifiable(noisy_log):
    """Dressler (2012), ch. 6.2: the link masses enter eq. 6.7 only with the plate and cart
    masses (m_p + sum m_a/2 in G). At rest the m_a,i column is exactly 1/2 of the m_p
    column; in motion the pivoted QR puts the m_a last, their std is several times that of
    the cart masses of model 2, and adding them inflates the std of m_p tenfold."""
    s = preprocess_log(noisy_log[0])
    res = identify_dynamics(s, "L1", variant="full")
    base = identify_dynamics(s, "L1", variant="model_2")
    std = dict(zip(res.names, res.std))
    std2 = dict(zip(base.names, base.std))
    assert min(std[f"m_a{i}"] for i in (1, 2, 3)) > 3 * max(std2[f"m_c{i}"] for i in (1, 2, 3))
    assert std["m_p"] > 10 * std2["m_p"]
    weakest = {d["parameter"] for d in res.near_dependencies[:2]}
    assert weakest <= {"m_a1", "m_a2", "m_a3", "m_p"} and weakest & {"m_a1", "m_a2", "m_a3"}
    assert res.near_dependencies[0]["r_ratio"] < 0.05


@pytest.mark.parametrize("i", [1, 2, 3])
def test_link_mass_column_is_half_the_plate_column_at_rest(i):
    """At rest the m_a,i column of Y is 1/2 of the m_p column (eq. 6.7: m_p + sum m_a/2 in G)."""
    reg = DynamicRegressor("L1", "full")
    q, _, _ = TRAJECTORY.evaluate(np.linspace(0, 10, 50))
    Y0, _, _ = reg.evaluate(q, np.zeros_like(q), np.zeros_like(q))
    dep = column_dependency(Y0, reg.names, f"m_a{i}", on=("m_p",))
    assert dep["coefficients"]["m_p"] == pytest.approx(0.5, abs=0.01)
    assert dep["relative_residual"] < 0.01


def test_rank_deficient_regressor_raises_model_error_or_gives_base_parameters():
    """Data of a robot at rest (static poses, all rows kept): the friction columns of Y are
    zero, the pivoted QR finds rank 4 of 10 and the ModelError names the friction
    parameters; 'base' estimates the identifiable masses and reports infinite std."""
    rng = np.random.default_rng(1)
    T = np.array([0.0, 2.9, -0.5]) + rng.uniform(-0.2, 0.2, (60, 3))
    zero = np.zeros_like(T)
    tau = GantryTau3Dynamics("L1").inverse_dynamics(T, zero, zero)
    s = DynamicSamples(np.arange(60) * 0.1, T, zero, zero, tau, coordinates="tcp")
    with pytest.raises(ModelError, match=r"rank-deficient \(rank 4 of 10\): f_c1 \(does not affect"):
        identify_dynamics(s, "L1", variant="model_2", min_speed=0.0)
    res = identify_dynamics(s, "L1", variant="model_2", min_speed=0.0, rank_deficient="base")
    assert not res.identifiability.full_rank
    assert np.all(np.isinf(res.std[4:])) and np.all(np.isfinite(res.std[:4]))


# ----------------------------------------------------------------------------- bad input
def _log_args(n=100):
    t = np.arange(n) * 0.004
    q = np.tile([0.0, 0.0, 0.0], (n, 1)) + 0.01 * np.sin(t)[:, None]
    return t, np.zeros((n, 3)), q


def _bad_time(t):
    t = t.copy()
    t[42] = t[41]
    return t


def _nan_at(a, k, j):
    a = a.copy()
    a[k, j] = np.nan
    return a


BAD_LOGS = [
    ("short_tau", lambda t, tau, q: dict(t=t, tau=tau[:-1], q=q), r"tau: expected 100 samples"),
    ("nan_q", lambda t, tau, q: dict(t=t, tau=tau, q=_nan_at(q, 17, 1)), r"q: sample 17, column 1 is not finite"),
    ("nan_tau", lambda t, tau, q: dict(t=t, tau=_nan_at(tau, 5, 0), q=q), r"tau: sample 5, column 0 is not finite"),
    ("time_not_increasing", lambda t, tau, q: dict(t=_bad_time(t), tau=tau, q=q), r"t: times must increase strictly, but sample 42 does not"),
    ("q_and_T", lambda t, tau, q: dict(t=t, tau=tau, q=q, T=q), r"exactly one of q"),
    ("neither_q_nor_T", lambda t, tau, q: dict(t=t, tau=tau), r"exactly one of q"),
    ("tau_wrong_width", lambda t, tau, q: dict(t=t, tau=tau[:, :2], q=q), r"tau: expected shape \(N, 3\)"),
    ("too_few_samples", lambda t, tau, q: dict(t=t[:10], tau=tau[:10], q=q[:10]), r"t: expected at least 30 samples"),
]


@pytest.mark.parametrize("case, make, match", BAD_LOGS, ids=[c[0] for c in BAD_LOGS])
def test_bad_motion_log(case, make, match):
    """Inconsistent lengths, NaN, non-monotonic time: InputError naming signal and sample."""
    with pytest.raises(InputError, match=match):
        MotionLog(**make(*_log_args()))


def _nonuniform(n=400):
    t = np.arange(n) * 0.004
    t[200:] += 0.002
    return MotionLog(t=t, tau=np.zeros((n, 3)), q=np.zeros((n, 3)))


def _uniform(n=400):
    return MotionLog(t=np.arange(n) * 0.004, tau=np.zeros((n, 3)), q=np.zeros((n, 3)))


BAD_PREPROCESS = [
    ("cutoff_above_nyquist", lambda: preprocess_log(_uniform(), cutoff=200.0), r"cutoff: expected a frequency in \(0, 125"),
    ("nonuniform_sampling", lambda: preprocess_log(_nonuniform()), r"sampling is not uniform at sample 200"),
    ("unknown_method", lambda: preprocess_log(_uniform(), method="kalman"), r"method: expected 'butter' or 'savgol'"),
    ("bad_decimate", lambda: preprocess_log(_uniform(), decimate=0), r"decimate: expected a positive integer"),
    ("too_short_for_trim", lambda: preprocess_log(_uniform(100), trim=60), r"too few"),
    ("not_a_log", lambda: preprocess_log(np.zeros((10, 7))), r"log: expected a MotionLog"),
]


@pytest.mark.parametrize("case, call, match", BAD_PREPROCESS, ids=[c[0] for c in BAD_PREPROCESS])
def test_bad_preprocess_input(case, call, match):
    """Invalid filter options or logs give an InputError naming the argument."""
    with pytest.raises(InputError, match=match):
        call()


def _samples():
    return preprocess_log(simulate_log(TRAJECTORY, 6.0, "L1", seed=0)[0])


BAD_IDENTIFY = [
    ("unknown_variant", dict(variant="model_9"), r"variant: expected one of"),
    ("negative_min_speed", dict(min_speed=-1.0), r"min_speed: expected a non-negative speed"),
    ("bad_weighting", dict(weighting="robust"), r"weighting: expected 'actuator', 'none'"),
    ("bad_weights", dict(weighting=[1.0, -1.0, 1.0]), r"weighting: expected three positive"),
    ("bad_rank_option", dict(rank_deficient="ignore"), r"rank_deficient: expected 'raise' or 'base'"),
    ("no_rows_above_min_speed", dict(min_speed=10.0), r"rows with \|q_dot\| >= min_speed"),
]


@pytest.mark.parametrize("case, kwargs, match", BAD_IDENTIFY, ids=[c[0] for c in BAD_IDENTIFY])
def test_bad_identify_options(case, kwargs, match):
    """Invalid identification options give an InputError naming the argument."""
    with pytest.raises(InputError, match=match):
        identify_dynamics(_samples(), "L1", **kwargs)


def test_parameters_or_regressor_required():
    """Without a parameter set and without a prepared regressor there is no model to fit:
    an InputError naming ``parameters`` (no robot is assumed)."""
    with pytest.raises(InputError, match="parameters: expected a parameter set"):
        identify_dynamics(_samples())


def test_samples_must_be_dynamic_samples():
    """A raw MotionLog is not accepted by identify_dynamics (it must be filtered first)."""
    with pytest.raises(InputError, match="samples: expected DynamicSamples"):
        identify_dynamics(_uniform())


# ----------------------------------------------------------------------------- CSV
def test_motion_log_csv_round_trip(tmp_path, noisy_log):
    """to_csv then read_motion_log reproduces the log exactly (repr of floats)."""
    log = noisy_log[0]
    path = log.to_csv(tmp_path / "log.csv")
    back = read_motion_log(path)
    np.testing.assert_array_equal(back.t, log.t)
    np.testing.assert_array_equal(back.q, log.q)
    np.testing.assert_array_equal(back.tau, log.tau)
    assert back.coordinates == "cart"


def _csv(rows, header="t_s,q1_m,q2_m,q3_m,tau1_N,tau2_N,tau3_N"):
    return "# test log\n" + header + "\n" + "\n".join(rows) + "\n"


def _rows(n=40):
    return [f"{0.004 * k:.3f},0.1,0.2,0.3,1.0,2.0,3.0" for k in range(n)]


BAD_CSV = [
    ("time_backwards", lambda r: r[:20] + [r[10]] + r[21:], r"line 23, column 't_s': time not strictly increasing"),
    ("nan_value", lambda r: r[:5] + ["0.020,nan,0.2,0.3,1.0,2.0,3.0"] + r[6:], r"line 8, column 'q1_m': NaN/inf is not allowed"),
    ("missing_value", lambda r: r[:5] + ["0.020,0.1,0.2,0.3,1.0,2.0"] + r[6:], r"line 8: 6 values, expected 7"),
]


@pytest.mark.parametrize("case, edit, match", BAD_CSV, ids=[c[0] for c in BAD_CSV])
def test_bad_csv_rows(tmp_path, case, edit, match):
    """Malformed rows: InputError naming the file, line and column."""
    p = tmp_path / "log.csv"
    p.write_text(_csv(edit(_rows())))
    with pytest.raises(InputError, match=match):
        read_motion_log(p)


@pytest.mark.parametrize("header, match", [
    ("t_s,q1_m,q2_m,q3_m,tau1_N,tau2_N,force3", r"unknown column 'force3'"),
    ("t_s,q1_m,q2_m,q3_m,Tx_m,Ty_m,Tz_m", r"exactly one of the column sets"),
    ("q1_m,q2_m,q3_m,tau1_N,tau2_N,tau3_N,t_ms", r"unknown column 't_ms'"),
], ids=["unknown_column", "both_position_sets", "time_in_ms"])
def test_bad_csv_header(tmp_path, header, match):
    """Header errors name the header line and the column."""
    p = tmp_path / "log.csv"
    p.write_text(_csv(_rows(), header=header))
    with pytest.raises(InputError, match=match):
        read_motion_log(p)


# ----------------------------------------------------------------------------- eq. 6.9
POSES = np.array([[0.0, 2.9, -0.5], [0.0, 2.6, -0.3], [0.0, 3.2, -0.7], [0.0, 2.7, -0.75], [0.0, 3.1, -0.3]])
SPEEDS = np.linspace(1.0 / 15, 1.0, 15)  # Table 6.1: 15 speeds up to 1 m/s


def test_gravity_forces_balance_along_the_guideways(reference):
    """Table 6.2: at each of its poses the three J^T G sum to zero (force balance along x);
    the model's J^T G for 22.38 kg does the same, with the thesis' sign pattern."""
    t62 = reference["table_6_2"]
    sums = np.array(t62["actuator_1"]) + np.array(t62["actuator_2"]) + np.array(t62["actuator_3"])
    np.testing.assert_allclose(sums, 0.0, atol=0.11)
    G = accumulated_gravity_forces(POSES, "L1", 22.38)
    assert np.all(np.abs(G.sum(axis=1)) < GRAVITY_BALANCE_RELATIVE * np.abs(G).max(axis=1))
    assert np.all(G[:, 0] < 0) and np.all(G[:, 2] > 0)


@pytest.fixture(scope="module")
def two_direction_fit():
    data = simulate_constant_velocity(POSES, SPEEDS, "L1", force_noise=2.0, seed=0)
    return two_direction_friction(data, "L1")


@pytest.mark.parametrize("key", ["f_c_plus", "f_c_minus", "f_v_plus", "f_v_minus"])
def test_two_direction_runs_recover_the_asymmetric_friction(two_direction_fit, key):
    """Runs in both directions at five poses (Table 6.1 friction, 2 N noise): the estimator
    recovers f_c+-, f_v+- of Table 6.1 within 3 std."""
    fit = two_direction_fit
    a = load_parameters("L1").dynamics.asymmetric
    z = np.abs(getattr(fit, key) - getattr(a, key)) / fit.std[key]
    assert np.all(z <= Z_LIMIT), (key, z)


def test_two_direction_runs_separate_gravity_and_asymmetric_friction(two_direction_fit):
    """Runs in both directions at five poses: the accumulated mass (9.13 kg for the L1 set)
    within 3 std, and the gravity of the model with that mass."""
    robot = load_parameters("L1")
    fit = two_direction_fit
    assert abs(fit.accumulated_mass - robot.dynamics.m_p) <= Z_LIMIT * fit.accumulated_mass_std
    np.testing.assert_allclose(fit.gravity, accumulated_gravity_forces(POSES, "L1", fit.accumulated_mass), atol=1e-9)


def test_one_direction_fit_absorbs_gravity_into_coulomb_friction():
    """Fig. 6.2 ambiguity: with positive runs only, a straight line puts J^T G into f_c+;
    subtracting the model's gravity with the true accumulated mass recovers Table 6.1."""
    robot = load_parameters("L1")
    data = simulate_constant_velocity(POSES[:1], SPEEDS, "L1", force_noise=2.0, directions="positive", seed=1)
    naive = fit_friction(data)
    G = accumulated_gravity_forces(POSES[0], "L1", robot.dynamics.m_p)
    np.testing.assert_allclose(naive.f_c_plus - robot.dynamics.asymmetric.f_c_plus, G, atol=Z_LIMIT * naive.std["f_c_plus"].max())
    clean = fit_friction(subtract_gravity(data, "L1", robot.dynamics.m_p))
    z = np.abs(clean.f_c_plus - robot.dynamics.asymmetric.f_c_plus) / clean.std["f_c_plus"]
    assert np.all(z <= Z_LIMIT)
    assert np.all(np.isnan(clean.f_c_minus))  # no negative runs


def test_two_direction_pairs_runs_with_measured_speeds():
    """Measured velocities differ a little between the + and - runs (1 %): runs are paired
    by the closest speed and the friction estimate is unchanged within its std."""
    data = simulate_constant_velocity(POSES, SPEEDS, "L1", force_noise=2.0, seed=0)
    ref = two_direction_friction(data, "L1")
    rng = np.random.default_rng(5)
    noisy = ConstantVelocityData(data.T, data.q_dot * (1 + 0.01 * rng.uniform(-1, 1, (len(data.pose), 1))), data.tau, data.pose)
    fit = two_direction_friction(noisy, "L1")
    assert np.all(np.abs(fit.f_c_plus - ref.f_c_plus) <= Z_LIMIT * ref.std["f_c_plus"])


def test_two_direction_needs_partner_runs():
    """A run without its opposite-direction partner is named in an InputError."""
    data = simulate_constant_velocity(POSES[:1], SPEEDS[:3], "L1", directions="positive")
    with pytest.raises(InputError, match="needs a partner run in the opposite direction"):
        two_direction_friction(data, "L1")


def test_constant_velocity_data_validates_lengths():
    """Runs with mismatched arrays: InputError naming the argument."""
    with pytest.raises(InputError, match=r"q_dot: expected 2 samples"):
        ConstantVelocityData(np.zeros((2, 3)), np.zeros((3, 3)), np.zeros((2, 3)), [0, 0])


# ----------------------------------------------------------------------------- fast paths
def _stacked_rows(samples, reg, min_speed, weights=(1.0, 1.0, 1.0)):
    """The fitted rows by hand: (sample, actuator) with |q_dot| >= min_speed, weighted."""
    Y, tau0, v = reg.evaluate(samples.x, samples.x_dot, samples.x_ddot, samples.coordinates)
    k, i = np.nonzero(np.abs(v) >= min_speed)
    w = np.asarray(weights)[i]
    return Y[k, i, :] * w[:, None], (samples.tau - tau0)[k, i] * w, Y, tau0, v


@pytest.mark.parametrize("weighting", ["none", (1.0, 0.5, 2.0)])
def test_least_squares_equals_numpy_lstsq(noisy_log, regressor, weighting):
    """Peer library: numpy.linalg.lstsq (SVD) on the same, explicitly stacked and weighted
    rows gives the estimates to 1e-10 relative; the standard deviations equal
    sqrt(diag(sigma^2 (A^T W^2 A)^-1)) formed by NumPy, the residual sums and the
    per-speed-bin RMS equal those of the explicit residual."""
    s = preprocess_log(noisy_log[0], cutoff=10.0, decimate=1)
    res = identify_dynamics(s, regressor=regressor, weighting=weighting, parallel_filter=False)
    w = (1.0, 1.0, 1.0) if weighting == "none" else weighting
    A, b, Y, tau0, v = _stacked_rows(s, regressor, res.info["min_speed"], w)
    theta, *_ = np.linalg.lstsq(A, b, rcond=None)
    np.testing.assert_allclose(res.theta, theta, rtol=LSTSQ_RELATIVE_TOLERANCE, atol=0)
    m, p = A.shape
    r = b - A @ theta
    cov = float(r @ r) / (m - p) * np.linalg.inv(A.T @ A)
    np.testing.assert_allclose(res.std, np.sqrt(np.diag(cov)), rtol=STD_RELATIVE_TOLERANCE)
    r_all = s.tau - tau0 - Y @ res.theta
    fitted = np.abs(v) >= res.info["min_speed"]
    ss = [np.sum(r_all[fitted[:, i], i] ** 2) for i in range(3)]
    np.testing.assert_allclose(res.residual_ss, ss, rtol=1e-12)
    sel = [[(np.abs(v[:, i]) >= row["v_min"]) & (np.abs(v[:, i]) < row["v_max"]) for i in range(3)] for row in res.residual_by_speed]
    counts = np.array([[int(s_i.sum()) for s_i in s_b] for s_b in sel])
    rms = np.array([[math.sqrt(np.mean(r_all[s_i, i] ** 2)) if s_i.any() else math.nan for i, s_i in enumerate(s_b)] for s_b in sel])
    np.testing.assert_array_equal(np.array([row["n"] for row in res.residual_by_speed]), counts)
    np.testing.assert_allclose(np.array([row["rms"] for row in res.residual_by_speed]), rms, rtol=1e-12, equal_nan=True)


def test_actuator_weighting_equals_lstsq_on_weighted_rows(noisy_log, regressor):
    """Two-step actuator weighting: the reported weights are 1/RMS of the unweighted fit's
    residual per actuator (recomputed here from numpy.linalg.lstsq), and the estimate is
    lstsq on the rows weighted with them (to 1e-10 relative)."""
    s = preprocess_log(noisy_log[0], cutoff=10.0, decimate=1)
    res = identify_dynamics(s, regressor=regressor, weighting="actuator", parallel_filter=False)
    A, b, _, _, v = _stacked_rows(s, regressor, res.info["min_speed"])
    th0, *_ = np.linalg.lstsq(A, b, rcond=None)
    i = np.nonzero(np.abs(v) >= res.info["min_speed"])[1]
    r = b - A @ th0
    w = np.array([1.0 / math.sqrt(np.mean(r[i == a] ** 2)) for a in range(3)])
    np.testing.assert_allclose(res.weights, w, rtol=1e-9)
    Aw, bw, *_ = _stacked_rows(s, regressor, res.info["min_speed"], res.weights)
    theta, *_ = np.linalg.lstsq(Aw, bw, rcond=None)
    np.testing.assert_allclose(res.theta, theta, rtol=LSTSQ_RELATIVE_TOLERANCE, atol=0)


def _compiler_available() -> bool:
    from gtmodel.codegen.build import find_compiler
    from gtmodel.errors import CompilerNotFoundError

    try:
        find_compiler()
    except CompilerNotFoundError:
        return False
    return True


@pytest.fixture
def compile_everything(monkeypatch, tmp_path):
    """Compile from the first sample, into an empty cache folder."""
    import gtmodel.calibration.identification.regressor as di

    monkeypatch.setattr(di, "_COMPILE_MIN_SAMPLES", 1)
    monkeypatch.setenv("GTMODEL_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("GTMODEL_COMPILE", raising=False)
    return tmp_path


@pytest.mark.skipif(not _compiler_available(), reason="no C compiler")
def test_compiled_regressor_equals_the_interpreter_and_is_cached(motion, compile_everything, monkeypatch, caplog):
    """Second route: the regressor compiled to C from the CasADi graph (cached shared
    library) gives the CasADi interpreter's Y, tau0 and q_dot to round-off, in cart and
    TCP coordinates; a second regressor of the same model reuses the library (no build)."""
    T, Td, Tdd = motion
    reg = DynamicRegressor("L1", "model_4")
    q, qd, qdd = reg.model.kinematics.cart_motion(T, Td, Tdd)
    with caplog.at_level(logging.INFO, logger="gtmodel"):
        out = {c: reg.evaluate(*x, c) for c, x in (("cart", (q, qd, qdd)), ("tcp", (T, Td, Tdd)))}
    assert sum("compiled C (built" in m for m in caplog.messages) == 2, caplog.messages
    assert len(list(compile_everything.glob("regressor/*.so"))) == 2
    monkeypatch.setenv("GTMODEL_COMPILE", "0")
    ref = DynamicRegressor("L1", "model_4")
    for c, x in (("cart", (q, qd, qdd)), ("tcp", (T, Td, Tdd))):
        for a, b in zip(out[c], ref.evaluate(*x, c)):
            np.testing.assert_allclose(a, b, rtol=0, atol=COMPILED_RELATIVE_TOLERANCE * np.max(np.abs(b)))
    monkeypatch.delenv("GTMODEL_COMPILE")
    caplog.clear()
    with caplog.at_level(logging.INFO, logger="gtmodel"):
        DynamicRegressor("L1", "model_4").evaluate(T, Td, Tdd, "tcp")
    assert any("compiled C (" in m for m in caplog.messages), caplog.messages
    assert not any("built" in m for m in caplog.messages), caplog.messages


def test_regressor_falls_back_to_the_interpreter_without_compiler(motion, compile_everything, monkeypatch, caplog):
    """No C compiler (CC names no executable): the regressor is evaluated by the CasADi
    interpreter, says so in the log, and gives the same forces as the model's inverse
    dynamics (eqs. 6.7/6.8)."""
    monkeypatch.setenv("CC", str(compile_everything / "no-such-compiler"))
    T, Td, Tdd = motion
    reg = DynamicRegressor("L1", "model_2")
    with caplog.at_level(logging.INFO, logger="gtmodel"):
        tau = reg.forces(reg.theta_of(), T, Td, Tdd, "tcp")
    assert any("CasADi interpreter (no C compiler" in m for m in caplog.messages), caplog.messages
    np.testing.assert_allclose(tau, GantryTau3Dynamics("L1").inverse_dynamics(T, Td, Tdd), atol=FORCE_TOLERANCE_N)
