"""Grids on ``[0, 1]`` and the gridded problem (:class:`GriddedPathProblem`): rows at every grid point."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from gtmodel.errors import InputError
from gtmodel.trajectory.path import Path

__all__ = ["GriddedPathProblem", "uniform_grid"]


def uniform_grid(path: Path, points: int) -> np.ndarray:
    """Uniform grid on ``[0, 1]`` with the path's corners added.

    Parameters
    ----------
    path : Path
        The path (its :attr:`Path.corners` are inserted).
    points : int
        Number of uniformly spaced points, at least 2.

    Returns
    -------
    numpy.ndarray, shape (N + 1,)
        Increasing grid from 0 to 1 (``points`` values plus the corners not already on it).

    Raises
    ------
    InputError
        ``points`` is not an integer of at least 2.
    """
    if isinstance(points, bool) or not isinstance(points, (int, np.integer)) or points < 2:
        raise InputError(f"grid: expected at least 2 grid points, got {points!r}")
    s = np.linspace(0.0, 1.0, int(points))
    if path.corners.size:
        s = np.union1d(s, path.corners)
        s = s[np.concatenate([[True], np.diff(s) > 1e-12])]
    return s


def _check_grid(path: Path, grid: Any) -> np.ndarray:
    if isinstance(grid, (int, np.integer)) and not isinstance(grid, bool):
        return uniform_grid(path, int(grid))
    try:
        s = np.asarray(grid, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"grid: expected a number of points or an increasing array of s values, got {grid!r}") from None
    if s.ndim != 1 or s.size < 2:
        raise InputError(f"grid: expected at least 2 grid points, got shape {s.shape}")
    if not np.all(np.isfinite(s)):
        raise InputError("grid: values must be finite")
    if np.any(np.diff(s) <= 0):
        k = int(np.argmax(np.diff(s) <= 0))
        raise InputError(f"grid: expected strictly increasing s, but s[{k + 1}] = {float(s[k + 1])!r} <= s[{k}] = {float(s[k])!r}")
    if abs(s[0]) > 1e-12 or abs(s[-1] - 1.0) > 1e-12:
        raise InputError(f"grid: expected to start at s = 0 and end at s = 1, got {s[0]!r} .. {s[-1]!r}")
    s = s.copy()
    s[0], s[-1] = 0.0, 1.0
    for corner in path.corners:
        if np.min(np.abs(s - corner)) > 1e-12:
            raise InputError(f"grid: the path has a corner at s = {corner:.12g} (rest required there); include it in the grid")
    return s


# =============================================================================== gridded problem
@dataclass
class GriddedPathProblem:
    """The path-constrained problem on a grid: constraint rows at every grid point.

    Row ``j`` at grid point ``k`` reads ``lo_j <= m[k, j] a + c[k, j] b + d[k, j] sqrt(b) +
    g[k, j] <= hi_j`` with ``a = s_ddot`` and ``b = s_dot^2``.

    Parameters
    ----------
    s : numpy.ndarray, shape (N + 1,)
        Grid.
    m, c, d, g : numpy.ndarray, shape (N + 1, R)
        Row coefficients (forces [N] per unit ``a`` [1/s^2], ``b`` [1/s^2], ``sqrt(b)`` [1/s]).
    lo, hi : numpy.ndarray, shape (R,)
        Row bounds (``-inf``/``inf`` where absent).
    names : list of str
        Row names.
    rest : numpy.ndarray of bool, shape (N + 1,)
        Grid points with ``s_dot = 0`` (the ends and the corners).
    samples : dict of str to numpy.ndarray
        ``T``, ``dT``, ``ddT`` (N + 1, 3) and, with a robot, ``q``, ``dq``, ``ddq`` (N + 1, 3).
    setup_time : float
        Wall time of the evaluation [s].
    constrain_end : bool
        Whether the rows with ``a`` also hold at the last grid point, on ``a_{N-1}`` (with
        ``b_N = 0``); TOPP-RA's collocation scheme does not impose them.
    """

    s: np.ndarray
    m: np.ndarray
    c: np.ndarray
    d: np.ndarray
    g: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    names: list[str]
    rest: np.ndarray
    samples: dict[str, np.ndarray]
    setup_time: float = 0.0
    constrain_end: bool = True

    @property
    def N(self) -> int:
        """Number of intervals (grid points minus one)."""
        return self.s.size - 1

    def one_sided(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, list[str], np.ndarray, np.ndarray]:
        """The rows as one-sided constraints ``p a + r b + w sqrt(b) + e <= 0``.

        Rows with ``a`` are dropped at the last grid point (no interval starts there) and
        returned separately: with :attr:`constrain_end` they hold there on ``a_{N-1}``.

        Returns
        -------
        p, r, w, e : numpy.ndarray, shape (N + 1, M)
            Coefficients of the ``M`` one-sided rows (absent bounds omitted).
        names : list of str
            ``"<row> <= hi"`` or ``"<row> >= lo"`` per one-sided row.
        p_end, e_end : numpy.ndarray, shape (M,)
            ``p_end a_{N-1} + e_end <= 0`` at the last grid point (``b_N = 0``); zeros and -1
            (always true) for rows without ``a`` or without :attr:`constrain_end`.
        """
        cols_hi = np.flatnonzero(np.isfinite(self.hi))
        cols_lo = np.flatnonzero(np.isfinite(self.lo))
        p = np.concatenate([self.m[:, cols_hi], -self.m[:, cols_lo]], axis=1)
        r = np.concatenate([self.c[:, cols_hi], -self.c[:, cols_lo]], axis=1)
        w = np.concatenate([self.d[:, cols_hi], -self.d[:, cols_lo]], axis=1)
        e = np.concatenate([self.g[:, cols_hi] - self.hi[cols_hi], self.lo[cols_lo] - self.g[:, cols_lo]], axis=1)
        names = [f"{self.names[j]} <= {self.hi[j]:.6g}" for j in cols_hi] + [f"{self.names[j]} >= {self.lo[j]:.6g}" for j in cols_lo]
        last = p[-1] != 0
        p_end = np.where(last & self.constrain_end, p[-1], 0.0)
        e_end = np.where(last & self.constrain_end, e[-1], -1.0)
        p[-1, last] = 0.0
        r[-1, last] = 0.0
        w[-1, last] = 0.0
        e[-1, last] = -1.0
        return p, r, w, e, names, p_end, e_end

    def violation(self, b: np.ndarray, a: np.ndarray) -> float:
        """Largest violation of the rows by a profile, relative to the bound.

        Parameters
        ----------
        b : numpy.ndarray, shape (N + 1,)
            ``s_dot^2`` at the grid points [1/s^2].
        a : numpy.ndarray, shape (N,)
            ``s_ddot`` on the intervals [1/s^2].

        Returns
        -------
        float
            ``max (value - hi) / |hi|`` and ``(lo - value) / |lo|`` over rows and grid points
            (0 if all hold); rows with ``a`` are checked at the last grid point on
            ``a_{N-1}`` if :attr:`constrain_end`, else not.
        """
        b = np.maximum(np.asarray(b, dtype=float), 0.0)
        a = np.asarray(a, dtype=float)
        aa = np.append(a, a[-1] if self.constrain_end else 0.0)
        val = self.m * aa[:, None] + self.c * b[:, None] + self.d * np.sqrt(b)[:, None] + self.g
        with np.errstate(invalid="ignore", divide="ignore"):
            over = np.where(np.isfinite(self.hi), (val - self.hi) / np.maximum(np.abs(self.hi), 1e-300), -np.inf)
            under = np.where(np.isfinite(self.lo), (self.lo - val) / np.maximum(np.abs(self.lo), 1e-300), -np.inf)
        viol = np.maximum(over, under)
        if not self.constrain_end:
            viol[-1, self.m[-1] != 0] = -np.inf
        return float(max(0.0, np.max(viol)))
