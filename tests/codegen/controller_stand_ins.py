"""Stand-ins for the estimation package's controller Functions, built directly in CasADi.

Same signatures as ``gtmodel.estimation.StationaryKalman.step_function()`` and
``gtmodel.estimation.ilc_correction_function(table)`` (ILC_DESIGN.md); the codegen tests use
these until the filters/ilc branches merge (then the lead switches to the real ones).

- ``kalman_step_function(d)``: per direction the constant-acceleration model x = [p, v, a]
  (white jerk) measured by y = [z_kin; a_m], a stationary predictor-corrector
  ``x_next = A x + K (y - C A x)``, ``z_hat = p of x_next``; the gain from python-control's
  ``dlqe`` with fixed noise figures. State layout: direction-major, [p1, v1, a1, p2, ...];
  measurement layout: [z_kin (d), a_m (d)].
- ``ilc_correction_function(table)``: ``u(k) = table[k]`` for integer ``k`` in ``[0, N)``,
  0 outside: a CasADi linear interpolant on the integer grid (exact at the grid points).
"""

from __future__ import annotations

import casadi as ca
import control
import numpy as np
import scipy.linalg
import scipy.signal

DT = 0.004
#: Noise figures of the stand-in filter: position (the deflection) [m], accelerometer [m/s^2], jerk [m/s^3].
POSITION_NOISE, ACCELEROMETER_NOISE, JERK_NOISE = 20e-6, 0.07, 50.0


def kalman_matrices(d: int = 3, dt: float = DT):
    """``(A, C, K, H)`` of the stand-in filter for ``d`` directions (state 3d, measurements 2d)."""
    a1 = np.array([[1.0, dt, dt * dt / 2], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])
    g1 = np.array([[dt**3 / 6], [dt * dt / 2], [dt]])
    c1 = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    k1, _, _ = control.dlqe(a1, g1, c1, JERK_NOISE**2, np.diag([POSITION_NOISE**2, ACCELEROMETER_NOISE**2]))
    A = scipy.linalg.block_diag(*[a1] * d)
    K = np.zeros((3 * d, 2 * d))
    C = np.zeros((2 * d, 3 * d))
    H = np.zeros((d, 3 * d))
    for j in range(d):
        s = slice(3 * j, 3 * j + 3)
        K[s, [j, d + j]] = k1
        C[[j, d + j], s] = c1
        H[j, 3 * j] = 1.0
    return A, C, np.asarray(K), H


def kalman_step_function(d: int = 3, dt: float = DT) -> ca.Function:
    """``"kalman_step"(x[3d], y[2d]) -> (x_next[3d], z_hat[d])`` (see the module docstring)."""
    A, C, K, H = kalman_matrices(d, dt)
    x = ca.SX.sym("x", 3 * d)
    y = ca.SX.sym("y", 2 * d)
    xp = ca.mtimes(ca.DM(A), x)
    x_next = xp + ca.mtimes(ca.DM(K), y - ca.mtimes(ca.DM(C), xp))
    return ca.Function("kalman_step", [x, y], [x_next, ca.mtimes(ca.DM(H), x_next)], ["x", "y"], ["x_next", "z_hat"])


def ilc_correction_function(table) -> ca.Function:
    """``"ilc_correction"(k) -> u[d]``: the table row at cycle ``k``, 0 outside ``[0, N)``."""
    table = np.asarray(table, dtype=float)
    n, d = table.shape
    k = ca.MX.sym("k")
    if n == 1:
        inside = table[0]
    else:
        inside = ca.interpolant("ilc_table", "linear", [np.arange(n, dtype=float)], table.T.ravel(order="F"))(k)
    u = ca.if_else(ca.logic_and(k >= 0, k <= n - 1), inside, ca.DM.zeros(d))
    return ca.Function("ilc_correction", [k], [u], ["k"], ["u"])


def learned_table(n: int = 400, d: int = 3, seed: int = 0) -> np.ndarray:
    """A plausible learned table ``(n, d)`` [m]: tens of um, smooth, zero at both ends (Tukey window)."""
    t = np.arange(n) * DT
    rng = np.random.default_rng(seed)
    amp = rng.uniform(5e-6, 50e-6, d)
    phase = rng.uniform(0, 2 * np.pi, d)
    u = amp * np.sin(2 * np.pi * 2.5 * t[:, None] + phase)
    return u * scipy.signal.windows.tukey(n, 0.5)[:, None]
