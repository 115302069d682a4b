"""Kalman and extended Kalman filter of the end-effector state (Cvitanic (2021), section 4.1).

Independent references: StationaryKalman's gain and Riccati solution (control.dlqe) for the
KF's covariance recursion; filterpy 2.0.0's KalmanFilter and ExtendedKalmanFilter (NumPy, Joseph
form) for the step of the CasADi graph; the chi-square distribution (Bar-Shalom et al. (2001),
sec. 5.4) for the NEES of Monte-Carlo runs simulated from the model itself; the closed-form
NEES of a pure rotation error; NumPy's Cholesky for the positive-definiteness test.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
import scipy.stats
from filterpy.kalman import ExtendedKalmanFilter as FilterpyEKF
from filterpy.kalman import KalmanFilter as FilterpyKF
from scipy.spatial.transform import Rotation

from gtmodel.errors import InputError
from gtmodel.estimation.filters.end_effector import EndEffectorModel
from gtmodel.estimation.filters.gaussian import FilterRun, cholesky_pivots
from gtmodel.estimation.filters.kalman import ExtendedKalmanFilter, KalmanFilter, StationaryKalman
from gtmodel.status import Status

DT = 0.001
#: Table 7 per-sample standard deviations: tracker position [m], orientation [rad], gyro [rad/s], accelerometer [m/s^2].
SIGMA_P, SIGMA_O = 6.4e-6, np.deg2rad(0.015)
SIGMA_G, SIGMA_A = np.deg2rad(0.0016) * np.sqrt(1 / DT), 0.39e-3 * np.sqrt(1 / DT)
JERK, ANGULAR_JERK = 20.0, 5.0
#: The specification: the KF's steady state equals StationaryKalman's gain to 1e-9.
GAIN_TOLERANCE = 1e-9
#: Two implementations of the same arithmetic (different operation order) over a few hundred steps.
SECOND_METHOD_TOLERANCE = 1e-9


def _models():
    return EndEffectorModel(DT, rotation=False, imu_rotation=np.eye(3)), EndEffectorModel(DT)


def _kf(model=None, **kw):
    model = model or _models()[0]
    args = dict(
        Q=model.process_noise(JERK),
        R=model.measurement_noise(SIGMA_P, SIGMA_A),
        x0=np.zeros(9),
        P0=np.diag(np.r_[np.full(3, 1e-8), np.full(3, 1e-4), np.full(3, 1e-2)]),
    )
    args.update(kw)
    return args


def _ekf_args(model, **kw):
    x0 = np.r_[0.1, -0.2, 0.3, 0.01, 0.02, -0.01, 0.1, 0.2, -0.1, [0.9, 0.1, -0.3, 0.2] / np.linalg.norm([0.9, 0.1, -0.3, 0.2]), 0.5, -0.3, 0.2, 0.4, 0.1, -0.2]
    args = dict(
        Q=model.process_noise(JERK, ANGULAR_JERK, quaternion=1e-9),
        R=model.measurement_noise(SIGMA_P, SIGMA_A, SIGMA_O, SIGMA_G),
        x0=x0,
        P0=np.diag(np.r_[np.full(3, 1e-10), np.full(3, 1e-6), np.full(3, 1e-4), np.full(4, 1e-8), np.full(3, 1e-6), np.full(3, 1e-4)]),
    )
    args.update(kw)
    return args


def _simulate(model, Q, R, x0, P0, n, rng):
    """A trajectory FROM the model: x_-1 ~ N(x0, P0), x_k = f(x_{k-1}) + w_k, z_k = h(x_k) + v_k."""
    xs = ca.SX.sym("x", model.nx)
    ws = ca.SX.sym("w", model.nx)
    sim = ca.Function("sim", [xs, ws], [model.transition(xs) + ws]).mapaccum("sim_run", n)
    w = rng.multivariate_normal(np.zeros(model.nx), Q, size=n, method="eigh")
    x_init = rng.multivariate_normal(x0, P0, method="cholesky")
    x_true = np.asarray(sim(x_init, w.T)).T
    z = np.asarray(model.measurement.map(n)(x_true.T)).T + rng.multivariate_normal(np.zeros(model.nz), R, size=n)
    return x_true, z


# -- the KF: StationaryKalman's steady state ------------------------------------------------------


def test_kf_covariance_recursion_converges_to_stationary_kalman():
    """KF step iterated to its fixed point: gain dx_next/dz (CasADi AD of the step) = StationaryKalman.M (control.dlqe),
    and the a-priori covariance A P+ A^T + Q = StationaryKalman.P (same Q = G diag(sigma^2) G^T and R, 3 axes)."""
    model = _models()[0]
    sk = StationaryKalman(dt=DT, accelerometer_noise=SIGMA_A, position_noise=SIGMA_P, jerk_noise=JERK, d=3)
    kf = KalmanFilter(model, **_kf(model))
    np.testing.assert_allclose(kf.Q, sk.Q, rtol=1e-14)
    np.testing.assert_allclose(kf.R, sk.R, rtol=1e-14)
    step = kf.step_function()
    runner = step.mapaccum("converge", 5000, 2)
    P = kf.P0
    for _ in range(20):  # until the recursion stops moving
        _, p_all, _ = runner(np.zeros(9), P, np.zeros((6, 5000)))
        p_new = np.asarray(p_all)[:, -9:]
        moved = np.abs(p_new - P).max() / np.abs(p_new).max()
        P = p_new
        if moved < 1e-15:
            break
    x, z = ca.SX.sym("x", 9), ca.SX.sym("z", 6)
    gain = np.asarray(ca.Function("gain", [x, z], [ca.jacobian(step(x, P, z)[0], z)])(np.zeros(9), np.zeros(6)))
    np.testing.assert_allclose(gain, sk.M, rtol=GAIN_TOLERANCE, atol=GAIN_TOLERANCE * np.abs(sk.M).max())
    np.testing.assert_allclose(sk.A @ P @ sk.A.T + sk.Q, sk.P, rtol=GAIN_TOLERANCE, atol=GAIN_TOLERANCE * np.abs(sk.P).max())


def test_kf_equals_filterpy():
    """The CasADi KF step over a simulated record equals filterpy's KalmanFilter (predict + Joseph update)."""
    model = _models()[0]
    args = _kf(model)
    _, z = _simulate(model, args["Q"], args["R"], args["x0"], args["P0"], 300, np.random.default_rng(0))
    run = KalmanFilter(model, **args).run(z)
    ref = FilterpyKF(dim_x=9, dim_z=6)
    ref.x, ref.P, ref.Q, ref.R = args["x0"].copy(), args["P0"].copy(), args["Q"], args["R"]
    ref.F, ref.H = np.asarray(model.transition_jacobian(np.zeros(9))), np.asarray(model.measurement_jacobian(np.zeros(9)))
    xs, ps = [], []
    for zk in z:
        ref.predict()
        ref.update(zk)
        xs.append(ref.x.copy())
        ps.append(ref.P.copy())
    assert run.success and run.name == "kf"
    scale = np.abs(run.x).max(axis=0)
    np.testing.assert_allclose(run.x, np.array(xs), rtol=0, atol=SECOND_METHOD_TOLERANCE * scale.max())
    np.testing.assert_allclose(run.P, np.array(ps), rtol=SECOND_METHOD_TOLERANCE, atol=SECOND_METHOD_TOLERANCE * 1e-12)


def test_ekf_on_the_linear_model_equals_the_kf():
    """One implementation: the EKF of the 9-D linear model gives the KF's run exactly (same graph)."""
    model = _models()[0]
    args = _kf(model)
    _, z = _simulate(model, args["Q"], args["R"], args["x0"], args["P0"], 200, np.random.default_rng(1))
    kf, ekf = KalmanFilter(model, **args).run(z), ExtendedKalmanFilter(model, **args).run(z)
    assert ekf.name == "ekf" and kf.name == "kf"
    np.testing.assert_array_equal(ekf.x, kf.x)
    np.testing.assert_array_equal(ekf.P, kf.P)


# -- the EKF ----------------------------------------------------------------------------------------


def test_ekf_equals_filterpy_with_the_same_model():
    """The 19-D EKF step equals filterpy's ExtendedKalmanFilter fed the model's CasADi f, F, h, H (NumPy, Joseph form),
    with the same quaternion sign alignment (residual) and renormalisation."""
    model = _models()[1]
    args = _ekf_args(model)
    _, z = _simulate(model, args["Q"], args["R"], args["x0"], args["P0"], 200, np.random.default_rng(2))
    z[::7, 3:7] *= -1.0  # the tracker may report -quat: the same orientation
    run = ExtendedKalmanFilter(model, **args).run(z)
    ref = FilterpyEKF(dim_x=19, dim_z=13)
    ref.x, ref.P, ref.Q, ref.R = args["x0"].copy(), args["P0"].copy(), args["Q"], args["R"]

    def hx(x):
        return np.asarray(model.measurement(x)).ravel()

    def residual(zk, zh):
        zk = zk.copy()
        if zk[3:7] @ zh[3:7] < 0:
            zk[3:7] *= -1
        return zk - zh

    xs, ps = [], []
    for zk in z:
        ref.F = np.asarray(model.transition_jacobian(ref.x))
        ref.x = np.asarray(model.transition(ref.x)).ravel()
        ref.P = ref.F @ ref.P @ ref.F.T + ref.Q
        ref.update(zk, lambda x: np.asarray(model.measurement_jacobian(x)), hx, residual=residual)
        ref.x[9:13] /= np.linalg.norm(ref.x[9:13])
        xs.append(ref.x.copy())
        ps.append(ref.P.copy())
    assert run.success
    np.testing.assert_allclose(run.x, np.array(xs), rtol=SECOND_METHOD_TOLERANCE, atol=1e-12)
    np.testing.assert_allclose(run.P, np.array(ps), rtol=1e-7, atol=SECOND_METHOD_TOLERANCE * np.abs(np.array(ps)).max())


def test_measured_quaternion_sign_does_not_matter():
    """quat and -quat are one orientation: the step's outputs are identical (sign alignment in the graph)."""
    model = _models()[1]
    ekf = ExtendedKalmanFilter(model, **_ekf_args(model))
    z = np.asarray(model.measurement(ekf.x0)).ravel() + 1e-5
    z_neg = z.copy()
    z_neg[3:7] *= -1
    step = ekf.step_function()
    for a, b in zip(step(ekf.x0, ekf.P0, z), step(ekf.x0, ekf.P0, z_neg)):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def test_ekf_quaternion_stays_unit():
    """After every update the quaternion is renormalised (to rounding)."""
    model = _models()[1]
    args = _ekf_args(model)
    _, z = _simulate(model, args["Q"], args["R"], args["x0"], args["P0"], 300, np.random.default_rng(3))
    run = ExtendedKalmanFilter(model, **args).run(z)
    np.testing.assert_allclose(np.linalg.norm(run.x[:, 9:13], axis=1), 1.0, atol=1e-15)


# -- consistency: NEES over Monte-Carlo runs --------------------------------------------------------

N_RUNS, N_STEPS = 30, 300


@pytest.mark.parametrize("kind", ["kf", "ekf"])
@pytest.mark.parametrize("q_scale, consistent", [(1.0, True), (0.01, False)])
def test_nees_consistency(kind, q_scale, consistent):
    """Bar-Shalom: the NEES averaged over N_RUNS runs simulated FROM the model (its own Q, R) lies in the two-sided
    95 % band of chi^2(N_RUNS dof) / N_RUNS at >= 90 % of the steps (expected 95 %); dof = 9 (KF) or 18 (EKF, the
    quaternion error as a rotation vector). Negative control: a filter believing Q / 100 falls outside at most steps."""
    rng = np.random.default_rng(10)
    if kind == "kf":
        model = _models()[0]
        args, cls = _kf(model), KalmanFilter
    else:
        model = _models()[1]
        args, cls = _ekf_args(model), ExtendedKalmanFilter
    q_filter = args["Q"] * q_scale
    if kind == "ekf":
        q_filter[9:13, 9:13] = args["Q"][9:13, 9:13]  # keep the normalisation's radial term
    filt = cls(model, **{**args, "Q": q_filter})
    nees, statuses = [], []
    for _ in range(N_RUNS):
        x_true, z = _simulate(model, args["Q"], args["R"], args["x0"], args["P0"], N_STEPS, rng)
        run = filt.run(z)
        statuses.append(run.status)
        nees.append(run.nees(x_true))
    assert set(statuses) == {Status.COMPLETED}
    mean = np.mean(nees, axis=0)
    dof = run.dof
    assert dof == (9 if kind == "kf" else 18)
    lo, hi = scipy.stats.chi2.ppf([0.025, 0.975], N_RUNS * dof) / N_RUNS
    inside = np.mean((mean > lo) & (mean < hi))
    assert (inside >= 0.9) == consistent, (inside, mean.mean(), lo, hi)


def test_nees_of_a_pure_rotation_error_closed_form():
    """Estimate = truth except the quaternion, rotated by dtheta; P_quat = sigma^2 / 4 I_4, the rest I:
    NEES = |dtheta|^2 / sigma^2 (J J^T = 4 I_3 for J = 2 d vec(q^* (x) q) / dq)."""
    x_hat = np.r_[np.zeros(9), [1.0, 0.0, 0.0, 0.0], np.zeros(6)]
    dtheta = np.array([1e-3, -2e-3, 0.5e-3])
    q = Rotation.from_rotvec(dtheta).as_quat()
    x_true = x_hat.copy()
    x_true[9:13] = np.r_[q[3], q[:3]]
    sigma = 1e-3
    P = np.eye(19)
    P[9:13, 9:13] = sigma**2 / 4 * np.eye(4)
    run = FilterRun(status=Status.OPTIMAL, name="ekf", x=x_hat[None], P=P[None], step_time_s=0.0, quaternion_slice=slice(9, 13))
    np.testing.assert_allclose(run.nees(x_true[None]), [dtheta @ dtheta / sigma**2], rtol=1e-12)


@pytest.mark.parametrize("kind, nx, nz", [("kf", 9, 6), ("ekf", 19, 13)])
def test_step_function_signature(kind, nx, nz):
    """The interface of FUSION_DESIGN.md: "<kind>_step"(x[nx], P[nx, nx], z[nz]) -> (x_next, P_next, pivots[nz + nx]), cached."""
    model = _models()[0 if kind == "kf" else 1]
    filt = KalmanFilter(model, **_kf(model)) if kind == "kf" else ExtendedKalmanFilter(model, **_ekf_args(model))
    step = filt.step_function()
    got = (
        step.name(),
        step.name_in(),
        step.name_out(),
        [step.size_in(i) for i in range(3)],
        [step.size_out(i) for i in range(3)],
        step is filt.step_function(),
    )
    assert got == (f"{kind}_step", ["x", "P", "z"], ["x_next", "P_next", "pivots"], [(nx, 1), (nx, nx), (nz, 1)], [(nx, 1), (nx, nx), (nz + nx, 1)], True)


def test_compiled_run_equals_the_interpreter(monkeypatch, tmp_path):
    """compiled=True: C generated from the same graph (cached library) gives the interpreter's run to 1e-12."""
    monkeypatch.setenv("GTMODEL_CACHE_DIR", str(tmp_path))
    model = _models()[0]
    args = _kf(model)
    _, z = _simulate(model, args["Q"], args["R"], args["x0"], args["P0"], 500, np.random.default_rng(5))
    ref, fast = KalmanFilter(model, **args).run(z), KalmanFilter(model, **args, compiled=True).run(z)
    np.testing.assert_allclose(fast.x, ref.x, rtol=1e-12, atol=1e-12 * np.abs(ref.x).max())
    np.testing.assert_allclose(fast.P, ref.P, rtol=1e-12, atol=1e-12 * np.abs(ref.P).max())


# -- the positive-definiteness test in the graph ----------------------------------------------------


@pytest.mark.parametrize(
    "matrix, definite",
    [
        (np.diag([4.0, 1.0, 9.0]), True),
        (np.array([[2.0, 1.0, 0.0], [1.0, 2.0, 1.0], [0.0, 1.0, 2.0]]), True),
        (np.diag([4.0, 0.0, 9.0]), False),
        (np.array([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), False),
        (-np.eye(3), False),
    ],
)
def test_cholesky_pivots_against_numpy(matrix, definite):
    """SX Cholesky: pivots all finite and > 0 exactly when NumPy's Cholesky succeeds; then L equals NumPy's."""
    a = ca.SX.sym("a", 3, 3)
    lmat, piv = cholesky_pivots(a)
    lmat, piv = (np.asarray(v) for v in ca.Function("chol", [a], [lmat, piv])(matrix))
    assert bool(np.all(np.isfinite(piv) & (piv > 0))) == definite
    if definite:
        np.testing.assert_allclose(lmat, np.linalg.cholesky(matrix), rtol=1e-14)


@pytest.mark.parametrize("kind", ["kf", "ekf"])
def test_step_pivots_flag_a_covariance_that_is_not_positive_definite(kind):
    """The step's pivots are all > 0 for a good P and not (0, negative sqrt -> NaN) for P = -I or a P with a negative eigenvalue."""
    model = _models()[0 if kind == "kf" else 1]
    filt = (KalmanFilter(model, **_kf(model)) if kind == "kf" else ExtendedKalmanFilter(model, **_ekf_args(model)))
    step = filt.step_function()
    z = np.asarray(model.measurement(filt.x0)).ravel()
    good = np.asarray(step(filt.x0, filt.P0, z)[2]).ravel()
    assert good.shape == (model.nz + model.nx,) and np.all(good > 0)
    bad_p = filt.P0.copy()
    bad_p[0, 0] = -bad_p[0, 0]
    flagged = [not np.all(np.isfinite(piv) & (piv > 0)) for piv in (np.asarray(step(filt.x0, p, z)[2]) for p in (-filt.P0, bad_p))]
    assert flagged == [True, True]


def test_run_reports_a_diverged_filter():
    """A covariance that is not positive definite inside the run: status "error", message naming sample 0, no NaN rows."""
    model = _models()[0]
    kf = KalmanFilter(model, **_kf(model))
    kf.P0 = -kf.P0  # bypasses the constructor's check on purpose
    run = kf.run(np.zeros((10, 6)))
    assert run.status == Status.ERROR and not run.success
    assert "sample 0" in run.message and run.x.shape == (0, 9) and run.P.shape == (0, 9, 9)


def test_run_result_shapes_and_time():
    """FilterRun: (N, nx) means, (N, nx, nx) symmetric covariances, a positive time per step."""
    model = _models()[1]
    args = _ekf_args(model)
    _, z = _simulate(model, args["Q"], args["R"], args["x0"], args["P0"], 50, np.random.default_rng(4))
    run = ExtendedKalmanFilter(model, **args).run(z)
    assert run.x.shape == (50, 19) and run.P.shape == (50, 19, 19) and run.step_time_s > 0
    np.testing.assert_array_equal(run.P, run.P.transpose(0, 2, 1))


# -- bad input ----------------------------------------------------------------------------------------


def _bad_ekf(**kw):
    model = _models()[1]
    return ExtendedKalmanFilter(model, **_ekf_args(model, **kw))


def _bad_kf(**kw):
    model = _models()[0]
    return KalmanFilter(model, **_kf(model, **kw))


def _x0_zero_quaternion():
    x0 = _ekf_args(_models()[1])["x0"].copy()
    x0[9:13] = 0.0
    return x0


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: _bad_ekf(x0=_x0_zero_quaternion()), r"x0: the quaternion .* zero norm"),
        (lambda: _bad_ekf(x0=np.zeros(18)), r"x0: expected a finite state of shape \(19,\)"),
        (lambda: _bad_ekf(x0=np.full(19, np.nan)), "x0"),
        (lambda: _bad_kf(Q=-np.eye(9)), "Q: expected a positive semi-definite"),
        (lambda: _bad_kf(Q=np.eye(8)), r"Q: expected shape \(9, 9\)"),
        (lambda: _bad_kf(Q=np.triu(np.ones((9, 9)))), "Q: expected a symmetric"),
        (lambda: _bad_kf(R=np.zeros((6, 6))), "R: expected a positive definite"),
        (lambda: _bad_kf(R=-np.eye(6)), "R: expected a positive definite"),
        (lambda: _bad_kf(R=np.eye(13)), r"R: expected shape \(6, 6\)"),
        (lambda: _bad_kf(P0=np.diag(np.r_[-1.0, np.ones(8)])), "P0: expected a positive definite"),
        (lambda: _bad_kf(P0=np.ones((9, 9))), "P0: expected a positive definite"),
        (lambda: _bad_kf(P0=np.eye(9)[:, :8]), r"P0: expected shape \(9, 9\)"),
        (lambda: _bad_kf(P0="identity"), "P0: expected a numeric"),
        (lambda: KalmanFilter(_models()[0], **_kf(), compiled="yes"), "compiled: expected True or False"),
        (lambda: KalmanFilter(_models()[1], **_ekf_args(_models()[1])), "model: expected a linear model"),
        (lambda: ExtendedKalmanFilter("model", **_kf()), "model: expected an EndEffectorModel"),
        (lambda: _bad_kf().run(np.zeros((10, 5))), r"z: expected shape \(N, 6\)"),
        (lambda: _bad_kf().run(np.full((10, 6), np.inf)), "z: sample 0, column 0 is not finite"),
        (lambda: FilterRun(status="optimal", x=np.zeros((2, 9)), P=np.tile(np.eye(9), (2, 1, 1))).nees(np.zeros((3, 9))), "x_true: expected 2 samples"),
    ],
)
def test_bad_input(call, match):
    with pytest.raises(InputError, match=match):
        call()
