"""Kinematic calibration from closure equations (Dressler (2012), eqs. 5.1-5.5).

Synthetic data: the "true" robot is the L1 modified model of Table 5.1
(``load_parameters("L1")``); poses are the IK of a workspace grid; measurements are its
TCP positions with Gaussian laser-tracker noise (10 um per coordinate, seeded). The start
is the ideal model (Table 5.1) in 21-parameter form. Independent references: the true
parameters that generated the data, the true model's own errors on the same noisy data,
a second solver, a known rigid transform, and (for quaternion parameters) a 6-link test
robot whose data come from its closed-form IK.
"""

from __future__ import annotations

import numpy as np
import pytest
import casadi as ca

from gtmodel.calibration.kinematic import (
    CalibrationProblem,
    ParameterSelection,
    calibrate,
    fit_rigid_transform,
)
from gtmodel.calibration.evaluation import tcp_errors
from gtmodel.calibration.measurements import MeasurementSet
from gtmodel.errors import InputError
from gtmodel.robots.closure import (
    ClosureModel,
    ThreeLinkClosure,
    quaternion_to_rotation,
    rotation_to_quaternion,
    rotation_vector_to_rotation,
)
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.parameters import load_parameters

#: Laser-tracker noise per coordinate [m] (Dressler (2012), ch. 5: ~10 um).
NOISE = 10e-6
#: Grid spacing giving ~800 L1 poses [m] (the thesis calibrated on 779).
GRID_STEP = 0.115
#: Number of poses used (as in Table 5.1).
N_POSES = 779
#: Parameters must lie within this many reported standard deviations of the truth.
N_SIGMA = 3.0
#: Validation error of the calibrated model relative to the true model's on the same data.
VALIDATION_RATIO = 1.2
#: Noise-free data: parameters recovered to this absolute accuracy [m, -].
EXACT_PARAMETERS = 1e-9
#: Noise-free data: cost at the solution [m^4].
EXACT_COST = 1e-20
#: Agreement of two solvers (relative, per parameter).
SOLVER_AGREEMENT = 1e-8
#: Relative agreement of the cost per arm with its expectation under the noise (4 sigma
#: of the chi-square spread).
NOISE_COST_TOL = 0.2
#: Unit-norm tolerance of calibrated quaternions.
QUATERNION_NORM = 1e-12
#: Seed of the measurement noise. With correct standard deviations all 21 parameters lie
#: within 3 sigma in ~93 % of noise draws (60-draw Monte Carlo of this set-up: 4 draws
#: had one |z| > 3, the largest 3.06; spread / reported std 0.92-1.25 per parameter).
SEED = 0


@pytest.fixture(scope="module")
def true_model():
    return ThreeLinkClosure(load_parameters("L1"))


@pytest.fixture(scope="module")
def nominal():
    return ThreeLinkClosure(load_parameters("L1_ideal"), model="modified")


@pytest.fixture(scope="module")
def poses(true_model):
    kin = GantryTau3Kinematics(load_parameters("L1"))
    T = kin.workspace_grid(GRID_STEP)
    keep = np.unique(np.linspace(0, len(T) - 1, N_POSES).round().astype(int))
    T = T[keep]
    return true_model.ik(T), T


@pytest.fixture(scope="module")
def noisy(poses):
    q, T = poses
    return q, T + NOISE * np.random.default_rng(SEED).standard_normal(T.shape)


@pytest.fixture(scope="module")
def result(nominal, noisy):
    q, T = noisy
    return calibrate(nominal, q, T)


# ------------------------------------------------------------------ L1, 21 parameters
def test_recovers_true_parameters_within_reported_std(result, true_model):
    """Every calibrated parameter lies within 3 reported standard deviations of the true
    parameter that generated the data (Gaussian noise, fixed seed)."""
    assert result.status == "optimal" and result.success
    p_true = true_model.parameter_vector()
    z = (result.parameter_vector - p_true) / np.array(list(result.std.values()))
    assert np.all(np.abs(z) < N_SIGMA), dict(zip(result.parameters, np.round(z, 2)))
    assert result.identifiability.full_rank
    assert [g.arms for g in result.groups] == [(0,), (1,), (2,)]


def test_validation_error_close_to_true_model(nominal, true_model, noisy):
    """Calibrate on every second pose, validate on the others (Dressler (2012), eq. 5.5,
    ch. 5.2): the mean TCP error is within 20 % of the true model's on the same noisy data."""
    q, T = noisy
    cal, val = MeasurementSet(q=q, T=T, source="synthetic L1").split_alternate()
    res = calibrate(nominal, cal)
    e_cal = tcp_errors(res.model, val.q, val.T).mean()
    e_true = tcp_errors(true_model, val.q, val.T).mean()
    assert e_cal <= VALIDATION_RATIO * e_true, (e_cal, e_true)
    start = tcp_errors(nominal, val.q, val.T).mean()
    assert start > 10 * e_cal  # the start model is far off (ideal vs modified)


def test_noise_free_data_exact(nominal, poses, true_model):
    """Noise-free measurements: cost ~0 and the true parameters to 1e-9."""
    q, T = poses
    res = calibrate(nominal, q, T)
    assert res.cost < EXACT_COST
    assert np.max(np.abs(res.parameter_vector - true_model.parameter_vector())) < EXACT_PARAMETERS


@pytest.mark.parametrize("solver", ["trf", "ipopt", "ipopt-gn"])
def test_solvers_agree(result, nominal, noisy, solver):
    """A second solver (SciPy TRF, IPOPT exact or Gauss-Newton Hessian) reaches the optimum
    of the default ("lm") to 1e-8 relative per parameter."""
    q, T = noisy
    other = calibrate(nominal, q, T, solver=solver)
    assert other.success, other.message
    rel = np.abs(other.parameter_vector - result.parameter_vector) / np.abs(result.parameter_vector)
    assert np.max(rel) < SOLVER_AGREEMENT
    assert other.cost == pytest.approx(result.cost, rel=1e-9)


def test_ideal_model_is_one_group(noisy):
    """The ideal model shares v between the arms: one 15-parameter NLP (ch. 5: arms are
    independent only without shared parameters)."""
    q, T = noisy
    ideal = ThreeLinkClosure(load_parameters("L1_ideal"))
    res = calibrate(ideal, q, T)
    assert [g.arms for g in res.groups] == [(0, 1, 2)]
    assert len(res.groups[0].variable_names) == 15
    # the ideal model cannot follow non-parallel guideways: worse than the 21-parameter fit
    assert res.cost > 100 * res.groups[0].n_residuals * (2 * 2.06 * NOISE) ** 2


def test_cost_per_arm_matches_noise(result, true_model):
    """V per arm adds up to V (eq. 5.2) and equals its expectation under the noise:
    r ~ -2 (A - T).dT, |A - T| = L, so E[V_arm] = (N - 7) 4 L^2 sigma^2 (chi-square with
    N - 7 degrees of freedom, relative spread sqrt(2 / (N - 7)) = 5 %)."""
    assert result.cost_per_arm.sum() == pytest.approx(result.cost, rel=1e-12)
    assert float(np.sum(result.residuals**2)) == pytest.approx(result.cost, rel=1e-10)
    L = true_model.kinematics.L
    expected = (result.n_poses - 7) * 4 * L**2 * NOISE**2
    assert result.cost_per_arm == pytest.approx(expected, rel=NOISE_COST_TOL)
    assert np.all(result.cost_per_arm < result.initial_cost_per_arm)


def test_fixed_and_tied_parameters(nominal, noisy):
    """Fixed parameters keep their (aligned) start values; a tie L3 = L1 makes L3 follow L1
    and joins arms 1 and 3 into one NLP."""
    q, T = noisy
    res = calibrate(nominal, q, T, fixed=["v*"], ties=["L3 = L1"])
    bad = [
        (c, res.parameters[c], res.initial_parameters[c], res.std[c])
        for c in ("v1_x", "v2_y", "v3_z")
        if not (res.parameters[c] == res.initial_parameters[c] and res.std[c] == 0.0)
    ]
    assert not bad, bad  # (name, value, start value, std) of every fixed parameter that moved
    assert res.parameters["L3"] == res.parameters["L1"]
    assert res.std["L3"] == res.std["L1"] > 0
    assert sorted(g.arms for g in res.groups) == [(0, 2), (1,)]


def test_alignment_recovers_known_frame(nominal, poses, true_model):
    """Measurements in a rotated and shifted frame: the calibrated model equals the true
    model moved by the known transform (eqs. 5.3-5.4)."""
    q, T = poses
    R = rotation_vector_to_rotation([0.1, -0.2, 0.3])
    t = np.array([0.5, -1.0, 2.0])
    res = calibrate(nominal, q, T @ R.T + t)
    expected = true_model.transformed(R, t).parameter_vector()
    assert np.max(np.abs(res.parameter_vector - expected)) < EXACT_PARAMETERS
    assert np.max(np.abs(res.rotation - R)) < 1e-2  # nominal ~ true: the fitted frame is close


def test_fit_rigid_transform_exact_and_collinear():
    """Kabsch: an exact rigid transform of 10 points is recovered; collinear points give a
    translation only (rotation about the line undetermined)."""
    rng = np.random.default_rng(0)
    P = rng.standard_normal((10, 3))
    R = rotation_vector_to_rotation([0.3, 1.0, -0.4])
    t = np.array([1.0, 2.0, 3.0])
    Rf, tf = fit_rigid_transform(P, P @ R.T + t)
    assert np.max(np.abs(Rf - R)) < 1e-12 and np.max(np.abs(tf - t)) < 1e-12
    line = np.outer(np.linspace(0, 1, 5), [1.0, 2.0, 3.0])
    Rf, tf = fit_rigid_transform(line, line + t)
    assert np.array_equal(Rf, np.eye(3)) and tf == pytest.approx(t)


def test_weights_select_poses(nominal, noisy):
    """Zero weights remove poses: the same optimum as calibrating on the others only."""
    q, T = noisy
    w = np.zeros(len(q))
    w[::3] = 1.0
    a = calibrate(nominal, q, T, weights=w)
    b = calibrate(nominal, q[::3], T[::3])
    assert np.max(np.abs(a.parameter_vector - b.parameter_vector) / np.abs(b.parameter_vector)) < SOLVER_AGREEMENT


def test_iteration_limit_is_a_status(nominal, noisy):
    """An iteration limit ends in status "max_iterations", not an exception."""
    q, T = noisy
    res = calibrate(nominal, q, T, max_iter=1)
    assert res.status == "max_iterations" and not res.success
    assert res.model is not None and len(res.parameters) == 21


def test_problem_reused_with_other_data(nominal, noisy):
    """A CalibrationProblem builds once; another data set re-uses the graph (build time 0)."""
    q, T = noisy
    problem = CalibrationProblem(nominal)
    first = problem.solve(q[:300], T[:300])
    second = problem.solve(q[300:], T[300:])
    assert first.build_time > 0 and second.build_time == 0.0
    assert second.success


# ------------------------------------------------------------------ quaternion parameters
class HexaToolClosure(ClosureModel):
    """Six one-link arms (a hexaglide) with a plate-pattern rotation given as a quaternion.

    ``A_i = As_i + q_i v_i``, ``B_i = T + R_T R(qt) b_i`` with fixed plate points ``b_i``;
    parameters ``L1..L6``, ``As1..As6``, ``v1..v6`` and the quaternion ``qt``. Test model:
    its IK is closed form per link, which generates the data independently of the solver.
    """

    name = "hexa_tool"
    n_q = 6
    orientation = True
    links = tuple((str(i + 1),) for i in range(6))
    ang = np.radians(np.arange(6) * 60.0)
    b = 0.2 * np.column_stack([np.zeros(6), np.cos(ang + 0.5), np.sin(ang + 0.5)])
    T_home = np.array([1.0, 0.0, 0.0])

    def __init__(self, L, As, v, qt):
        self.L, self.As, self.v, self.qt = (np.asarray(a, dtype=float) for a in (L, As, v, qt))

    @classmethod
    def nominal(cls):
        As = np.column_stack([np.zeros(6), np.cos(cls.ang), np.sin(cls.ang)])
        v = np.tile([1.0, 0.0, 0.0], (6, 1))
        L = np.linalg.norm(As - cls.T_home - cls.b, axis=1)
        return cls(L, As, v, [1.0, 0.0, 0.0, 0.0])

    def parameter_names(self):
        return tuple(
            [f"L{i + 1}" for i in range(6)]
            + [f"As{i + 1}_{c}" for i in range(6) for c in "xyz"]
            + [f"v{i + 1}_{c}" for i in range(6) for c in "xyz"]
            + ["qt_w", "qt_x", "qt_y", "qt_z"]
        )

    def parameter_vector(self):
        return np.concatenate([self.L, self.As.ravel(), self.v.ravel(), self.qt])

    def quaternion_indices(self):
        return [(42, 43, 44, 45)]

    def link_points(self, p, q, T, R, arm):
        As = p[6 + 3 * arm: 9 + 3 * arm]
        v = p[24 + 3 * arm: 27 + 3 * arm]
        Rt = quaternion_to_rotation(p[42:46])
        return As + q[arm] * v, T + ca.mtimes(R, ca.mtimes(Rt, ca.DM(self.b[arm]))), p[arm]

    def with_parameters(self, p):
        p = np.asarray(p, dtype=float)
        return HexaToolClosure(p[:6], p[6:24].reshape(6, 3), p[24:42].reshape(6, 3), p[42:46])

    def transformed(self, R, t):
        R = np.asarray(R, dtype=float)
        return HexaToolClosure(self.L, self.As @ R.T + t, self.v @ R.T, self.qt)

    def ik(self, T, R):
        P = T[:, None, :] + np.einsum("kij,lj->kli", R, self.b @ quaternion_to_rotation(self.qt).T)
        d = P - self.As[None]
        vv = np.sum(self.v**2, axis=1)
        vd = np.einsum("kli,li->kl", d, self.v)
        disc = vd**2 - vv * (np.sum(d * d, axis=2) - self.L**2)
        return (vd - np.sqrt(disc)) / vv

    def fk(self, q):
        return self.fk_newton(q, self.T_home)


@pytest.fixture(scope="module")
def hexa_data():
    nominal = HexaToolClosure.nominal()
    rng = np.random.default_rng(7)
    true_qt = rotation_to_quaternion(rotation_vector_to_rotation([0.0, 0.5, 0.6]))  # 0.78 rad
    true = HexaToolClosure(
        nominal.L + 1e-3 * rng.standard_normal(6), nominal.As + 1e-3 * rng.standard_normal((6, 3)), nominal.v, true_qt
    )
    N = 60
    T = true.T_home + 0.1 * rng.uniform(-1, 1, (N, 3))
    R = np.array([rotation_vector_to_rotation(0.15 * rng.uniform(-1, 1, 3)) for _ in range(N)])
    return nominal, true, true.ik(T, R), T, rotation_to_quaternion(R)


@pytest.mark.parametrize("solver", ["lm", "ipopt-gn"])
def test_quaternion_parameter_recovered_with_unit_norm(hexa_data, solver):
    """A quaternion parameter 0.78 rad from its start (beyond the re-anchoring angle) is
    recovered from noise-free data generated by the closed-form IK; its norm is 1 to 1e-12."""
    nominal, true, q, T, quat = hexa_data
    res = calibrate(nominal, q, T, quat, fixed=["v*"], solver=solver)
    assert res.success, res.message
    assert abs(res.quaternion_norms["qt"] - 1.0) < QUATERNION_NORM
    p = res.parameter_vector
    R_cal = quaternion_to_rotation(p[42:46])
    assert np.max(np.abs(R_cal - quaternion_to_rotation(true.qt))) < EXACT_PARAMETERS
    assert np.max(np.abs(p[:24] - true.parameter_vector()[:24])) < EXACT_PARAMETERS
    assert "qt_rx" in res.groups[0].variable_names and len(res.groups[0].variable_names) == 27
    assert res.std["qt_w"] >= 0.0


def test_quaternion_single_rotation_components_fixed(hexa_data):
    """Fixing local rotation components (qt_rx, qt_rz, as the identifiability report names
    them): a true tool rotation about y only is recovered with the one free component."""
    nominal, true, q, T, quat = hexa_data
    true_y = true.with_parameters(
        np.concatenate([true.parameter_vector()[:42], rotation_to_quaternion(rotation_vector_to_rotation([0.0, 0.4, 0.0]))])
    )
    R = np.array([quaternion_to_rotation(qq) for qq in quat])
    q_y = true_y.ik(T, R)
    res = calibrate(nominal, q_y, T, quat, fixed=["v*", "qt_rx", "qt_rz"])
    assert res.success and res.cost < EXACT_COST
    assert [n for n in res.groups[0].variable_names if n.startswith("qt")] == ["qt_ry"]
    assert np.max(np.abs(res.parameter_vector - true_y.parameter_vector())) < EXACT_PARAMETERS


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"free": ["L*", "qt_w"]}, r"free all four components or none"),
        ({"ties": ["qt_x = L1"]}, r"quaternion components cannot be tied"),
        ({"quat": None}, r"quat: hexa_tool determines the plate orientation"),
        ({"quat": "bad-norm"}, r"quat: rows must be unit quaternions; row 0"),
    ],
    ids=["partly-free", "tie", "missing-orientation", "norm"],
)
def test_quaternion_bad_input(hexa_data, kwargs, match):
    nominal, _, q, T, quat = hexa_data
    kw = dict(kwargs)
    qu = kw.pop("quat", quat)
    if isinstance(qu, str):
        qu = quat * 1.1
    with pytest.raises(InputError, match=match):
        calibrate(nominal, q, T, qu, fixed=None if "free" in kw else ["v*"], **kw)


# ------------------------------------------------------------------ bad input
def _bad(q, T, what):
    q, T = q.copy(), T.copy()
    kw: dict = {}
    if what == "few":
        q, T = q[:6], T[:6]
    elif what == "nan":
        T[3, 1] = np.nan
    elif what == "q-shape":
        q = q[:, :2]
    elif what == "T-shape":
        T = T[:-1]
    elif what == "free-unknown":
        kw["free"] = ["L4"]
    elif what == "fixed-unknown":
        kw["fixed"] = ["As1_q"]
    elif what == "free-and-fixed":
        kw.update(free=["L1", "L2"], fixed=["L1"])
    elif what == "tie-form":
        kw["ties"] = ["L1 = L2 = L3"]
    elif what == "tie-cycle":
        kw["ties"] = ["L1 = L2", "L2 = L1"]
    elif what == "tie-target-fixed":
        kw.update(ties=["L2 = L1"], fixed=["L2"])
    elif what == "solver":
        kw["solver"] = "ipopt_gn"
    elif what == "weights-negative":
        kw["weights"] = -np.ones(len(q))
    elif what == "weights-length":
        kw["weights"] = np.ones(3)
    elif what == "max-iter":
        kw["max_iter"] = 0
    elif what == "both-selections":
        kw.update(selection=ParameterSelection(fixed=["L1"]), free=["L2"])
    return q, T, kw


@pytest.mark.parametrize(
    "what, match",
    [
        ("few", r"too few poses for arm\(s\) 1: 6 residuals \(6 poses with non-zero weight\) for 7 free parameters"),
        ("nan", r"T: non-finite values in row\(s\) \[3\]"),
        ("q-shape", r"q: expected shape \(N, 3\)"),
        ("T-shape", r"T: expected shape \(779, 3\) to match q"),
        ("free-unknown", r"free: unknown parameter name 'L4'; close matches: L3, L2, L1"),
        ("fixed-unknown", r"fixed: unknown parameter name 'As1_q'; close matches: As1_"),
        ("free-and-fixed", r"'L1' is both free and fixed"),
        ("tie-form", r"ties: expected 'target = source'"),
        ("tie-cycle", r"ties: cycle through L1, L2"),
        ("tie-target-fixed", r"fixed: 'L2' is the target of a tie"),
        ("solver", r"solver: expected one of lm, trf, ipopt, ipopt-gn, got 'ipopt_gn' \(did you mean 'ipopt-gn'\?\)"),
        ("weights-negative", r"weights: expected finite non-negative values; row 0"),
        ("weights-length", r"weights: expected 779 values"),
        ("max-iter", r"max_iter: expected a positive integer"),
        ("both-selections", r"give either selection or free/fixed/ties"),
    ],
)
def test_bad_input(nominal, noisy, what, match):
    q, T, kw = _bad(*noisy, what)
    w = kw.pop("weights", None)
    with pytest.raises(InputError, match=match):
        calibrate(nominal, q, T, weights=w, **kw)
