"""The result of a path-constrained solve (:class:`PathSolution`) and its sampling."""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Callable

import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel.errors import InputError, SolverError
from gtmodel.status import StatusResult
from gtmodel.trajectory.path import Path
from gtmodel.trajectory.point_to_point import SAMPLE_TIME

__all__ = ["PathSolution"]

_log = logging.getLogger("gtmodel")


@dataclass
class PathSolution(StatusResult):
    """Time-optimal motion along a path (python-control ``OptimalControlResult`` style).

    Implements :class:`gtmodel.status.SolverResult`: :attr:`success` is True only for
    status ``"optimal"``.

    Parameters
    ----------
    status : Status
        ``"optimal"``, ``"infeasible"``, ``"max_iterations"``, ``"acceptable"`` or ``"error"``
        (keyword only).
    message : str
        What happened (keyword only); for ``"infeasible"`` the grid point and ``s`` where the problem
        fails and the constraints involved.
    final_time : float
        Duration [s]; NaN unless a profile was found.
    s : numpy.ndarray, shape (K,)
        Path coordinates of the grid (convex method) or collocation mesh.
    s_dot : numpy.ndarray, shape (K,)
        Path velocity [1/s] there (NaN when infeasible).
    s_ddot : numpy.ndarray, shape (K,)
        Path acceleration [1/s^2] there; on a grid ``s_ddot[k]`` applies on
        ``[s_k, s_{k+1})``, the last entry repeats the last interval's value.
    t : numpy.ndarray, shape (K,)
        Times of the grid/mesh points [s].
    solve_time : float
        Wall time of the solve [s] (without the evaluation of the path data).
    iterations : int
        1 for the reachability solver (one backward and one forward pass), else IPOPT's.
    method : str
        ``"reachability"``, ``"reachability+ipopt"`` (IPOPT started from the reachability
        profile, see :meth:`PathConstrainedProblem.solve`), ``"ipopt"`` or ``"collocation"``.
    path : Path
        The path.
    max_constraint_violation : float
        Largest relative violation of the constraints at the grid points (0 if none).
    setup_time : float
        Wall time of the evaluation of the path data [s].
    sampler : callable or None
        ``sampler(t) -> (s, s_dot, s_ddot)`` at times ``t`` (K,) (internal).
    evaluator : callable or None
        ``evaluator(s, s_dot, s_ddot) -> dict`` of kinematic and force samples (internal).
    breaks : numpy.ndarray or None
        Times [s] between which the motion is smooth (for the energy quadrature).
    details : dict
        Extra data (``b``, ``a`` on the grid, the IPOPT stats, the collocation result ...).
    """

    final_time: float
    s: np.ndarray
    s_dot: np.ndarray
    s_ddot: np.ndarray
    t: np.ndarray
    solve_time: float
    iterations: int
    method: str
    path: Path
    max_constraint_violation: float = float("nan")
    setup_time: float = 0.0
    sampler: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]] | None = field(default=None, repr=False)
    evaluator: Callable[..., dict[str, np.ndarray]] | None = field(default=None, repr=False)
    breaks: np.ndarray | None = field(default=None, repr=False)
    details: dict[str, Any] = field(default_factory=dict, repr=False)

    def _require_profile(self) -> None:
        if self.sampler is None or not np.isfinite(self.final_time):
            raise SolverError(f"no motion to sample: the solve ended with status {self.status!r} ({self.message})")

    def sample(self, t: np.typing.ArrayLike) -> dict[str, np.ndarray]:
        """The motion at given times.

        Parameters
        ----------
        t : array_like, shape (K,)
            Times in ``[0, final_time]`` [s].

        Returns
        -------
        dict of str to numpy.ndarray
            ``t``, ``s``, ``s_dot``, ``s_ddot`` (K,); ``T``, ``T_dot``, ``T_ddot`` (K, 3)
            [m, m/s, m/s^2]; with a robot also ``q``, ``q_dot``, ``q_ddot`` (K, 3) and
            ``tau`` (K, 3) [N] from the inverse dynamics of the model.

        Raises
        ------
        SolverError
            The solve found no motion (status not optimal/acceptable/max_iterations).
        InputError
            Times outside ``[0, final_time]``.
        """
        self._require_profile()
        t = np.asarray(t, dtype=float).reshape(-1)
        tol = 1e-9 * max(1.0, self.final_time)
        if not np.all(np.isfinite(t)) or np.any(t < -tol) or np.any(t > self.final_time + tol):
            raise InputError(f"t: expected times in [0, {self.final_time}] s")
        s, sd, sdd = self.sampler(np.clip(t, 0.0, self.final_time))
        out = {"t": t, "s": s, "s_dot": sd, "s_ddot": sdd}
        out.update(self.evaluator(s, sd, sdd))
        return out

    def trajectory(self, dt: float = SAMPLE_TIME) -> dict[str, np.ndarray]:
        """The motion resampled on a uniform time grid (controller sample time by default).

        Parameters
        ----------
        dt : float, optional
            Sample time [s]; default the loop period (:data:`gtmodel.defaults.LOOP_PERIOD_S`). The last sample is the final time.

        Returns
        -------
        dict of str to numpy.ndarray
            As :meth:`sample`, at ``t = 0, dt, 2 dt, ..., final_time``.

        Raises
        ------
        InputError
            Non-positive ``dt``.
        SolverError
            The solve found no motion.
        """
        if not (isinstance(dt, (int, float)) and np.isfinite(dt) and dt > 0):
            raise InputError(f"dt: expected a positive sample time in s, got {dt!r}")
        self._require_profile()
        tf = self.final_time
        t = np.arange(0.0, tf, dt)
        if tf - t[-1] > 1e-12:
            t = np.append(t, tf)
        return self.sample(t)

    @cached_property
    def energy(self) -> float:
        """``sum_i integral tau_i^2 dt`` [N^2 s] of the motion (NaN without a robot).

        Gauss-Legendre quadrature (6 points) on every interval between :attr:`breaks`,
        where the motion is smooth; the forces are those of the model along the motion.
        """
        self._require_profile()
        if self.breaks is None:
            return float("nan")
        nodes, weights = np.polynomial.legendre.leggauss(6)
        t0, t1 = self.breaks[:-1], self.breaks[1:]
        h = t1 - t0
        tt = (t0[:, None] + h[:, None] * (nodes[None, :] + 1) / 2).ravel()
        smp = self.sample(tt)
        if "tau" not in smp:
            return float("nan")
        f = np.sum(smp["tau"] ** 2, axis=1).reshape(h.size, nodes.size)
        return float(np.sum(h / 2 * (f @ weights)))


def _failed(status: str, message: str, path: Path, s: np.ndarray, method: str, solve_time: float, iterations: int, setup_time: float = 0.0, details: dict | None = None) -> PathSolution:
    nan = np.full(s.size, np.nan)
    _log.warning("path-constrained solve (%s): %s: %s", method, status, message)
    return PathSolution(
        status=status,
        message=message,
        final_time=float("nan"),
        s=s,
        s_dot=nan,
        s_ddot=nan.copy(),
        t=nan.copy(),
        solve_time=solve_time,
        iterations=iterations,
        method=method,
        path=path,
        setup_time=setup_time,
        details=details or {},
    )


def _profile_sampler(s: np.ndarray, x: np.ndarray, a: np.ndarray, tk: np.ndarray) -> Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Exact motion of a piecewise-constant ``s_ddot`` profile at times t."""

    def sampler(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        k = np.clip(np.searchsorted(tk, t, side="right") - 1, 0, a.size - 1)
        h = t - tk[k]
        sd = np.maximum(x[k] + a[k] * h, 0.0)
        ss = np.clip(s[k] + x[k] * h + 0.5 * a[k] * h**2, s[k], s[k + 1])
        return ss, sd, a[k].copy()

    return sampler
