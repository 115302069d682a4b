"""The controller Functions the codegen tests generate C for: the real ones of gtmodel.estimation.

- ``kalman_step_function(d, dt)``: :meth:`gtmodel.estimation.StationaryKalman.step_function`
  for ``d`` directions (the per-direction model x = [p, v, a], measurements
  y = [z_kin; a_m]) with the x-direction noise figures of the L1 defaults.
- ``ilc_correction_function(table)``: :func:`gtmodel.estimation.ilc_correction_function`.
- ``learned_table(n, d, seed)``: a plausible learned table (test data, not a model).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import scipy.signal

from gtmodel.estimation import StationaryKalman, ilc_correction_function
from gtmodel.estimation.kalman import DEFAULT_JERK_NOISE, DEFAULT_POSITION_NOISE

__all__ = ["DT", "kalman_filter", "kalman_step_function", "ilc_correction_function", "learned_table"]

DT = 0.004


def kalman_filter(d: int = 3, dt: float = DT) -> StationaryKalman:
    """The stationary Kalman filter of ``d`` directions (x-direction noise figures of the L1 defaults)."""
    return StationaryKalman(dt=dt, position_noise=DEFAULT_POSITION_NOISE[0], jerk_noise=DEFAULT_JERK_NOISE[0], d=d)


def kalman_step_function(d: int = 3, dt: float = DT) -> ca.Function:
    """``"kalman_step"(x[3d], y[2d]) -> (x_next[3d], z_hat[d])`` of :func:`kalman_filter`."""
    return kalman_filter(d, dt).step_function()


def learned_table(n: int = 400, d: int = 3, seed: int = 0) -> np.ndarray:
    """A plausible learned table ``(n, d)`` [m]: tens of um, smooth, zero at both ends (Tukey window)."""
    t = np.arange(n) * DT
    rng = np.random.default_rng(seed)
    amp = rng.uniform(5e-6, 50e-6, d)
    phase = rng.uniform(0, 2 * np.pi, d)
    u = amp * np.sin(2 * np.pi * 2.5 * t[:, None] + phase)
    return u * scipy.signal.windows.tukey(n, 0.5)[:, None]


# ----------------------------------------------------------------------------- filter steps (stand-ins)
FILTER_DT = 0.001


def _cholesky_pivots(M: ca.SX) -> tuple[ca.SX, ca.SX]:
    """Lower Cholesky factor of ``M`` and its diagonal (an SX loop; NaN pivots when not PD)."""
    n = M.shape[0]
    L = ca.SX.zeros(n, n)
    for j in range(n):
        s = M[j, j] - (ca.sumsqr(L[j, :j]) if j else 0)
        L[j, j] = ca.sqrt(s)
        for i in range(j + 1, n):
            L[i, j] = (M[i, j] - (ca.dot(L[i, :j], L[j, :j]) if j else 0)) / L[j, j]
    return L, ca.diag(L)


def _solve_spd(L: ca.SX, B: ca.SX) -> ca.SX:
    """``(L L^T)^-1 B`` by forward and back substitution."""
    n = L.shape[0]
    Y = ca.SX.zeros(B.shape)
    for i in range(n):
        Y[i, :] = (B[i, :] - (ca.mtimes(L[i, :i], Y[:i, :]) if i else 0)) / L[i, i]
    X = ca.SX.zeros(B.shape)
    for i in reversed(range(n)):
        X[i, :] = (Y[i, :] - (ca.mtimes(L[i + 1:, i].T, X[i + 1:, :]) if i < n - 1 else 0)) / L[i, i]
    return X


def _quat_mul(a, b):
    w1, v1, w2, v2 = a[0], a[1:4], b[0], b[1:4]
    return ca.vertcat(w1 * w2 - ca.dot(v1, v2), w1 * v2 + w2 * v1 + ca.cross(v1, v2))


def _quat_rot(q):
    w, x, y, z = q[0], q[1], q[2], q[3]
    return ca.vertcat(
        ca.horzcat(1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
        ca.horzcat(2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
        ca.horzcat(2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)),
    )


def standin_filter_step(rotation: bool, dt: float = FILTER_DT) -> ca.Function:
    """A stand-in of ``KalmanFilter``/``ExtendedKalmanFilter.step_function()`` (same signature and contract).

    Constant-acceleration translation (nx 9, z = [p, a]); with ``rotation`` the 19-D model
    (quaternion by the exponential map of ``w dt``, then normalised; z = [p, quat, w, R^T a]).
    Joseph form, P symmetrised, quaternion sign-aligned and renormalised, pivots of S and P_next.
    """
    A1 = np.array([[1, dt, dt**2 / 2], [0, 1, dt], [0, 0, 1]])
    G1 = np.array([[dt**3 / 6], [dt**2 / 2], [dt]])
    A, G = np.kron(A1, np.eye(3)), np.kron(G1, np.eye(3))
    nx, nz = (19, 13) if rotation else (9, 6)
    x, P, z = ca.SX.sym("x", nx), ca.SX.sym("P", nx, nx), ca.SX.sym("z", nz)
    Q = np.zeros((nx, nx))
    Q[:9, :9] = 50.0**2 * G @ G.T
    R = np.diag([4.1e-11] * 3 + ([1e-8] * 4 + [1e-5] * 3 if rotation else []) + [1.52e-4] * 3)
    if rotation:
        Q[13:, 13:] = 20.0**2 * np.kron(G1[1:] @ G1[1:].T, np.eye(3))
        Q[9:13, 9:13] = 1e-12 * np.eye(4)

    def f(s):
        out = [ca.mtimes(A, s[:9])]
        if rotation:
            q, w, al = s[9:13], s[13:16], s[16:19]
            th = w * dt
            ang = ca.sqrt(ca.sumsqr(th) + 1e-30)
            dq = ca.vertcat(ca.cos(ang / 2), ca.sin(ang / 2) * th / ang)
            qn = _quat_mul(q, dq)
            out += [qn / ca.norm_2(qn), w + al * dt, al]
        return ca.vertcat(*out)

    def h(s):
        if not rotation:
            return ca.vertcat(s[0:3], s[6:9])
        return ca.vertcat(s[0:3], s[9:13], s[13:16], ca.mtimes(_quat_rot(s[9:13]).T, s[6:9]))

    xp = f(x)
    F = ca.jacobian(f(x), x)
    Pp = ca.mtimes([F, P, F.T]) + Q
    xs = ca.SX.sym("xs", nx)
    H = ca.substitute(ca.jacobian(h(xs), xs), xs, xp)
    S = ca.mtimes([H, Pp, H.T]) + R
    S = (S + S.T) / 2
    L, piv_s = _cholesky_pivots(S)
    K = _solve_spd(L, ca.mtimes(H, Pp)).T
    zz = z
    if rotation:
        qm = z[3:7]
        qm = ca.if_else(ca.dot(qm, xp[9:13]) < 0, -qm, qm)
        zz = ca.vertcat(z[:3], qm, z[7:])
    xn = xp + ca.mtimes(K, zz - ca.substitute(h(xs), xs, xp))
    if rotation:
        xn = ca.vertcat(xn[:9], xn[9:13] / ca.norm_2(xn[9:13]), xn[13:])
    IKH = ca.SX.eye(nx) - ca.mtimes(K, H)
    Pn = ca.mtimes([IKH, Pp, IKH.T]) + ca.mtimes([K, R, K.T])
    Pn = (Pn + Pn.T) / 2
    _, piv_p = _cholesky_pivots(Pn)
    return ca.Function("ekf_step" if rotation else "kf_step", [x, P, z], [xn, Pn, ca.vertcat(piv_s, piv_p)],
                       ["x", "P", "z"], ["x_next", "P_next", "pivots"])
