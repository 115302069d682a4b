"""The thesis' form of the tool-position Kalman filter: model (7.19) with ``z_kin`` as input, extended by (7.20)-(7.21).

Dressler (2012), eqs. 7.19-7.22. Per direction ``j`` (x, y) a discrete model of the tool
position ``z`` driven by the kinematic position ``z_kin = fk(q_m)`` (the identified model
(6.13), ``z = G_c(q) z_c``)::

    x(t + Ts) = A x(t) + B u(t),   z(t) = C x(t)                                  (7.19)

is extended with a velocity and an acceleration state by forward Euler differences of ``z``
(7.20)-(7.21)::

    x_v(t + Ts) = (C (A - I) x(t) + C B u(t)) / Ts
    x_a(t + Ts) = (C (A - I) x(t) + C B u(t)) / Ts^2 - x_v(t) / Ts

and the accelerometer measures ``y = x_a``. The stationary predictor (7.22)::

    xx(t + Ts) = Abar xx(t) + Bbar u(t) + K (y(t) - Cy xx(t)),   z_hat(t) = (C 0 0) xx(t)

has the gain ``K = Abar P Cy^T (Cy P Cy^T + R2)^-1`` with ``P`` the solution of the discrete
Riccati equation (:func:`scipy.linalg.solve_discrete_are`) for the process noise
``R1 = r I`` and the measurement noise ``R2``. The thesis chose ``r`` "rather small in
order to avoid drift" and ``R2`` from the model's output-error covariance.

The input may lead the kinematic position: ``u(t) = z_kin(t + lookahead)``. The ILC filters
a recorded trial (the complementary filter (7.17) is zero phase, non-causal too), so a model
whose ``z(t)`` depends on ``z_kin(t + 1)`` (a central second difference) is still strictly
proper in ``u``. Samples past the end hold the last ``z_kin``; the filter starts at rest
(the model's steady state for ``z_kin[0]``, ``x_v = x_a = 0``).

Compared with :class:`~gtmodel.estimation.filters.kalman.StationaryKalman` (a triple
integrator measuring ``z_kin`` and ``a_m``): here ``z_kin`` is an input through the
structural model, so a deflection the model predicts needs no accelerometer; the
accelerometer corrects what the model misses.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import scipy.linalg

from gtmodel._arrays import as_finite, as_signal, positive_float, positive_int
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError

__all__ = ["ModelKalman", "extend_model", "PROCESS_NOISE_GRID"]

#: The process noises ``r`` a tuning tries (:meth:`ModelKalman.tuned`), log-spaced.
PROCESS_NOISE_GRID = tuple(10.0 ** e for e in range(-16, -3))


def extend_model(A: Any, B: Any, C: Any, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The extended model (7.21) of a SISO model (7.19): velocity and acceleration states by forward Euler.

    Dressler (2012), eqs. 7.19-7.21.

    Parameters
    ----------
    A : array_like, shape (n, n)
        State matrix of the model from ``z_kin`` to the tool position.
    B : array_like, shape (n,) or (n, 1)
        Input matrix.
    C : array_like, shape (n,) or (1, n)
        Output matrix, ``z = C x`` (no feedthrough).
    dt : float
        Sample time ``Ts`` [s].

    Returns
    -------
    Abar : numpy.ndarray, shape (n + 2, n + 2)
    Bbar : numpy.ndarray, shape (n + 2,)
    Cbar : numpy.ndarray, shape (2, n + 2)
        Rows ``z`` and ``y = x_a``.

    Raises
    ------
    InputError
        Matrices of inconsistent shapes or not finite, ``dt`` not positive.
    """
    a = as_finite(A, "A")
    if a.ndim != 2 or a.shape[0] != a.shape[1] or a.shape[0] == 0:
        raise InputError(f"A: expected a square matrix (n, n), got shape {a.shape}")
    n = a.shape[0]
    b = as_finite(B, "B").reshape(-1)
    c = as_finite(C, "C").reshape(-1)
    if b.size != n or c.size != n:
        raise InputError(f"B, C: expected {n} entries each (the states of A), got {b.size} and {c.size}")
    ts = positive_float(dt, "dt")
    ca = c @ (a - np.eye(n))
    cb = float(c @ b)
    Abar = np.zeros((n + 2, n + 2))
    Abar[:n, :n] = a
    Abar[n, :n] = ca / ts
    Abar[n + 1, :n] = ca / ts**2
    Abar[n + 1, n] = -1.0 / ts
    Bbar = np.concatenate([b, [cb / ts, cb / ts**2]])
    Cbar = np.zeros((2, n + 2))
    Cbar[0, :n] = c
    Cbar[1, n + 1] = 1.0
    return Abar, Bbar, Cbar


class ModelKalman:
    """Stationary Kalman filter of the tool position on model (7.21), ``z_kin`` as input (Dressler (2012), eqs. 7.19-7.22).

    See the module docstring for the model, the predictor and the look-ahead.

    Parameters
    ----------
    models : sequence of tuple
        Per direction ``(A, B, C)`` of model (7.19) (``A`` (n, n), ``B`` (n,), ``C`` (n,)).
    dt : float, optional
        Sample time [s].
    measurement_noise : float or array_like, shape (d,), optional
        ``R2``: variance of the accelerometer's output error per direction [(m/s^2)^2].
    process_noise : float, optional
        ``r`` of ``R1 = r I`` (the same for every state and direction).
    lookahead : int, optional
        Samples by which the input leads the kinematic position, ``u(t) = z_kin(t + lookahead)``.

    Attributes
    ----------
    d : int
        Number of directions.
    Abar, Bbar, Cbar : list of numpy.ndarray
        Per direction the extended model (7.21) (:func:`extend_model`).
    R1 : list of numpy.ndarray
        Per direction ``r I``.
    R2 : numpy.ndarray, shape (d,)
        Measurement-noise variances.
    P : list of numpy.ndarray
        Per direction the Riccati solution (a-priori covariance).
    K : list of numpy.ndarray, shape (n + 2,)
        Per direction the predictor gain (7.22).

    Raises
    ------
    InputError
        A bad model, a non-positive noise or ``dt``, a negative look-ahead, or a Riccati
        equation without a stabilising solution.
    """

    def __init__(self, models: Sequence[tuple[Any, Any, Any]], dt: float = LOOP_PERIOD_S, measurement_noise: Any = 0.07**2,
                 process_noise: float = 1e-10, lookahead: int = 0) -> None:
        self.dt = positive_float(dt, "dt")
        if not models:
            raise InputError("models: expected one (A, B, C) per direction")
        self.d = len(models)
        r2 = np.broadcast_to(as_finite(measurement_noise, "measurement_noise"), (self.d,)).astype(float)
        if np.any(r2 <= 0):
            raise InputError(f"measurement_noise: expected positive variances, got {measurement_noise!r}")
        self.R2 = r2
        self.process_noise = positive_float(process_noise, "process_noise")
        if isinstance(lookahead, bool) or not isinstance(lookahead, (int, np.integer)) or lookahead < 0:
            raise InputError(f"lookahead: expected a non-negative number of samples, got {lookahead!r}")
        self.lookahead = int(lookahead)
        self.models = [(np.asarray(A, float), np.asarray(B, float).reshape(-1), np.asarray(C, float).reshape(-1)) for A, B, C in models]
        self.Abar, self.Bbar, self.Cbar, self.R1, self.P, self.K = [], [], [], [], [], []
        for j, (A, B, C) in enumerate(self.models):
            Ab, Bb, Cb = extend_model(A, B, C, self.dt)
            R1 = self.process_noise * np.eye(Ab.shape[0])
            cy = Cb[1:2]
            try:
                P = scipy.linalg.solve_discrete_are(Ab.T, cy.T, R1, np.array([[r2[j]]]))
            except (ValueError, np.linalg.LinAlgError) as exc:
                raise InputError(f"models[{j}]: the Riccati equation (7.22) has no stabilising solution ({exc})") from None
            K = (Ab @ P @ cy.T / (cy @ P @ cy.T + r2[j])).reshape(-1)
            self.Abar.append(Ab), self.Bbar.append(Bb), self.Cbar.append(Cb), self.R1.append(R1), self.P.append(P), self.K.append(K)

    @classmethod
    def tuned(cls, models: Sequence[tuple[Any, Any, Any]], dt: float, z_kin: Any, a_m: Any, z: Any, lookahead: int = 0,
              mask: Any = None, grid: Sequence[float] = PROCESS_NOISE_GRID) -> tuple["ModelKalman", dict[str, Any]]:
        """The filter tuned on a record as the thesis did: ``R2`` from the model's output error, ``r`` by the estimation error.

        Dressler (2012), section 7.2 (after eq. 7.22): ``R2`` "based on the output error
        covariance of model (7.21)": here the mean square of ``a_m - x_a`` with ``x_a`` the
        acceleration state of the model run open loop from ``z_kin``, per direction; ``R1 = r I``
        with ``r`` "determined by inspection to minimize the estimation error": here the
        ``r`` of ``grid`` with the smallest RMS of ``z - z_hat`` (over ``mask``), summed over
        the directions (the thesis compared with the gauges' ``z``).

        Parameters
        ----------
        models : sequence of tuple
            Per direction ``(A, B, C)`` of model (7.19).
        dt : float
            Sample time [s].
        z_kin, a_m, z : array_like, shape (N, d)
            Kinematic position [m], measured acceleration [m/s^2], true (gauge) position [m].
        lookahead : int, optional
            Input look-ahead in samples.
        mask : array_like of bool, shape (N,), optional
            Samples the RMS is taken over (default all).
        grid : sequence of float, optional
            Candidate ``r`` (default :data:`PROCESS_NOISE_GRID`).

        Returns
        -------
        ModelKalman
            The filter with the chosen ``r``.
        dict
            ``measurement_noise`` (d,), ``process_noise``, ``grid`` and ``rms_m`` (per ``r``, (d,)).

        Raises
        ------
        InputError
            Signals of other shapes, an empty grid or a non-positive ``r``.
        """
        probe = cls(models, dt, 1.0, 1.0, lookahead)
        zk = as_signal(z_kin, "z_kin", probe.d)
        am = as_signal(a_m, "a_m", probe.d, zk.shape[0], like="z_kin")
        zt = as_signal(z, "z", probe.d, zk.shape[0], like="z_kin")
        sel = np.ones(zk.shape[0], bool) if mask is None else np.asarray(mask, bool).reshape(-1)
        if sel.shape != (zk.shape[0],):
            raise InputError(f"mask: expected {zk.shape[0]} flags, got shape {np.shape(mask)}")
        if not len(grid):
            raise InputError("grid: expected at least one process noise")
        probe.K = [np.zeros_like(k) for k in probe.K]  # open loop: the model's own acceleration state
        x_a = probe._run(zk[:, :, None], am[:, :, None], output=1)[:, :, 0]
        r2 = np.maximum(np.mean((am - x_a)[sel] ** 2, axis=0), np.finfo(float).tiny)
        rms = []
        for r in grid:
            f = cls(models, dt, r2, r, lookahead)
            rms.append(np.sqrt(np.mean((zt - f.estimate(zk, am))[sel] ** 2, axis=0)))
        best = int(np.argmin([float(np.sum(e)) for e in rms]))
        chosen = cls(models, dt, r2, grid[best], lookahead)
        return chosen, {"measurement_noise": r2.tolist(), "process_noise": float(grid[best]), "grid": [float(g) for g in grid],
                        "rms_m": [e.tolist() for e in rms]}

    def _inputs(self, z_kin: np.ndarray) -> np.ndarray:
        """``u(t) = z_kin(t + lookahead)``, the last sample held, (N, d, m)."""
        if self.lookahead == 0:
            return z_kin
        tail = np.repeat(z_kin[-1:], self.lookahead, axis=0)
        return np.concatenate([z_kin[self.lookahead:], tail], axis=0)[: z_kin.shape[0]]

    def _run(self, z_kin: np.ndarray, a_m: np.ndarray, output: int = 0) -> np.ndarray:
        """The predictor (7.22) on ``m`` signals at once: ``z_kin``, ``a_m`` (N, d, m) -> ``z_hat`` (N, d, m) (``output`` 1: ``x_a``)."""
        n = z_kin.shape[0]
        u = self._inputs(z_kin)
        out = np.empty_like(z_kin)
        for j in range(self.d):
            A, B, C = self.models[j]
            Ab, Bb, K = self.Abar[j], self.Bbar[j], self.K[j]
            cz, cy = self.Cbar[j][0], self.Cbar[j][1]
            nx = A.shape[0]
            x = np.zeros((Ab.shape[0], z_kin.shape[2]))
            x[:nx] = np.linalg.solve(np.eye(nx) - A, B)[:, None] * z_kin[0, j][None, :]  # at rest at z_kin[0]
            for t in range(n):
                out[t, j] = (cz if output == 0 else cy) @ x
                x = Ab @ x + Bb[:, None] * u[t, j][None, :] + K[:, None] * (a_m[t, j] - cy @ x)[None, :]
        return out

    def estimate(self, z_kin: Any, a_m: Any) -> np.ndarray:
        """Tool-position estimate ``z_hat`` (Dressler (2012), eq. 7.22), started at rest.

        Parameters
        ----------
        z_kin : array_like, shape (N, d)
            Kinematic tool position ``fk(q_m)`` [m], rows ``dt`` apart.
        a_m : array_like, shape (N, d)
            Measured tool acceleration [m/s^2].

        Returns
        -------
        numpy.ndarray, shape (N, d)
            Estimated tool position [m].

        Raises
        ------
        InputError
            Signals of another shape or length, or not finite.
        """
        zk = as_signal(z_kin, "z_kin", self.d)
        am = as_signal(a_m, "a_m", self.d, zk.shape[0], like="z_kin")
        return self._run(zk[:, :, None], am[:, :, None])[:, :, 0]

    def lifted(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Lifted matrices of :meth:`estimate`: ``z_hat[:, j] = F_kin[j] z_kin[:, j] + F_acc[j] a_m[:, j]``.

        Built by running the filter on the ``n`` unit vectors of each input at once (the
        initial state and the held end included): equal to :meth:`estimate` to rounding.

        Parameters
        ----------
        n : int
            Number of samples.

        Returns
        -------
        F_kin : numpy.ndarray, shape (d, n, n)
        F_acc : numpy.ndarray, shape (d, n, n)

        Raises
        ------
        InputError
            ``n`` not a positive integer.
        """
        n = positive_int(n, "n")
        eye = np.broadcast_to(np.eye(n)[:, None, :], (n, self.d, n)).copy()
        zero = np.zeros((n, self.d, n))
        f_kin = self._run(eye, zero).transpose(1, 0, 2)
        f_acc = self._run(zero, eye).transpose(1, 0, 2)
        return f_kin, f_acc

    def __repr__(self) -> str:
        return f"ModelKalman(d={self.d}, states={[m[0].shape[0] for m in self.models]}, r={self.process_noise:g}, lookahead={self.lookahead})"
