"""Iterative learning control: the trial-to-trial loop, the error measure, the learned table.

Dressler (2012), eqs. 7.2-7.16 and 7.25. :func:`run_ilc` repeats a trial
(``experiment(u) -> eps``, any callable: a simulation or a robot) and updates the
correction with the ILC law (7.2)::

    u_{k+1} = Q (u_k + L eps_k)

column by column (one column per actuator or tool direction), with ``Q`` and ``L`` the
operators of :mod:`gtmodel.estimation.ilc.lifted` (or anything with an ``apply`` method of the
same meaning). It knows nothing of robots. A diverging run is a result with status
``error`` (the error measure grew beyond a bound), not an exception.

:func:`error_measure` is the per-iteration figure of merit (7.25), computed over the fully
corrected samples only (where the time window is 1). The thesis' text of (7.25) is not in
the project's specification; the measure used here is the root mean square of the error
over those samples, per column, so that iteration ``k`` relative to iteration 0 is the
ratio the thesis reports (Table 7.2, Figs. 7.7-7.10).

:func:`ilc_correction_function` turns the learned correction (the last ``u``, the window
weighting already inside since ``Q`` applies it) into the CasADi function the 4 ms loop
calls every cycle with the cycle count.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

import casadi as ca
import numpy as np

from gtmodel._arrays import as_finite, as_signal, positive_float
from gtmodel.errors import InputError
from gtmodel.status import Status, StatusResult

__all__ = ["error_measure", "ILCResult", "run_ilc", "next_correction", "ilc_correction_function"]

_log = logging.getLogger("gtmodel")


def error_measure(e: Any, mask: Any = None) -> float | np.ndarray:
    """Error measure of one trial: RMS of the error over the fully corrected samples.

    Dressler (2012), eq. 7.25, taken as ``sqrt(mean(e[mask]^2))`` per column (the
    thesis' exact normalisation is not in the specification; any normalisation common
    to all iterations cancels in the ratio to iteration 0 that the thesis reports).
    The fully corrected samples are those where the Q filter's time window is 1, e.g.
    ``mask = time_window(N) == 1``.

    Parameters
    ----------
    e : array_like, shape (N,) or (N, d)
        Error signal, rows are samples (e.g. [m]).
    mask : array_like of bool, shape (N,), optional
        Samples to include (default: all).

    Returns
    -------
    float or numpy.ndarray, shape (d,)
        The measure (unit of ``e``): a float for ``(N,)``, one per column for ``(N, d)``.

    Raises
    ------
    InputError
        ``e`` not finite or of another shape; ``mask`` not boolean, of another length or
        selecting no sample.
    """
    arr = as_finite(e, "e")
    if arr.ndim not in (1, 2) or arr.shape[0] == 0:
        raise InputError(f"e: expected an error signal of shape (N,) or (N, d), got shape {arr.shape}")
    if mask is None:
        m = np.ones(arr.shape[0], dtype=bool)
    else:
        m = np.asarray(mask)
        if m.dtype != bool or m.shape != (arr.shape[0],):
            raise InputError(f"mask: expected a boolean array of shape ({arr.shape[0]},) like e's rows, got {m.dtype} {m.shape}")
        if not m.any():
            raise InputError("mask: selects no sample")
    rms = np.sqrt(np.mean(arr[m] ** 2, axis=0))
    return float(rms) if arr.ndim == 1 else rms


@dataclass(kw_only=True)
class ILCResult(StatusResult):
    """Outcome of an ILC run: the corrections, errors and error measures of every trial.

    Dressler (2012), eqs. 7.2 and 7.25. Trial ``k`` ran with ``u[k]`` and gave ``eps[k]``;
    the run has ``K + 1`` trials (0 .. K) unless it stopped early on divergence.

    Parameters
    ----------
    status : Status
        ``converged`` (every trial ran and the error measure did not end above its
        initial value) or ``error`` (diverged: the measure grew beyond the bound or became
        non-finite; or it ended above iteration 0); keyword only.
    message : str
        What happened, with the figures; keyword only.
    u : numpy.ndarray, shape (K+1, N, d)
        Correction of each trial.
    eps : numpy.ndarray, shape (K+1, N, d)
        Error returned by each trial.
    measure : numpy.ndarray, shape (K+1, d)
        Error measure (7.25) of each trial per column (:func:`error_measure`).
    logs : dict of str to numpy.ndarray
        Extra signals the experiment returned, each stacked over the trials (first axis).
    next_u : numpy.ndarray, shape (N, d)
        The correction the update computed after the last trial (the learned table to
        use next; equal to ``u[-1]`` at convergence).
    """

    u: np.ndarray
    eps: np.ndarray
    measure: np.ndarray
    logs: dict[str, np.ndarray] = field(default_factory=dict)
    next_u: np.ndarray | None = None

    @property
    def iterations(self) -> int:
        """Number of updates performed (trials run minus one)."""
        return int(self.u.shape[0]) - 1

    @property
    def relative_measure(self) -> np.ndarray:
        """Error measure of each trial relative to trial 0, shape ``(K+1, d)`` (Table 7.2)."""
        m0 = self.measure[0]
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(m0 > 0, self.measure / np.where(m0 > 0, m0, 1.0), 0.0)


def _as_2d(x: np.ndarray, name: str, shape: tuple[int, int]) -> np.ndarray:
    arr = np.asarray(x, dtype=float)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.shape != shape:
        raise InputError(f"{name}: expected shape {shape} (or ({shape[0]},) for one column), got {np.shape(x)}")
    return arr


def run_ilc(
    experiment: Callable[[np.ndarray], Any],
    u0: Any,
    Q: Any,
    L: Any,
    iterations: int = 10,
    mask: Any = None,
    divergence_factor: float = 10.0,
) -> ILCResult:
    """Run iterative learning control: trial, update, trial, ... (``iterations`` updates).

    Dressler (2012), eq. 7.2: ``u_{k+1} = Q (u_k + L eps_k)``, applied to every column
    (actuator or direction) with the same ``Q`` and ``L``; the error measure (7.25) of
    every trial over ``mask``. Divergence is a status, not an exception: the run stops
    with status ``error`` when a trial's error is not finite or its measure exceeds
    ``divergence_factor`` times that of trial 0 in any column.

    Parameters
    ----------
    experiment : callable
        ``experiment(u) -> eps`` runs one trial with the correction ``u`` (same shape as
        ``u0``) and returns the error used for learning ``eps`` (same shape), or a mapping
        with key ``"eps"`` and any other arrays to log (:attr:`ILCResult.logs`).
    u0 : array_like, shape (N,) or (N, d)
        Correction of trial 0 (usually zeros).
    Q : QFilter or object with ``apply``
        Robustness filter (:class:`gtmodel.estimation.QFilter`): ``Q.apply(x (N, d))``.
    L : LearningFilter or object with ``apply``
        Learning filter (:class:`gtmodel.estimation.LearningFilter`).
    iterations : int, optional
        Number of updates ``K >= 0`` (``K + 1`` trials; default 10).
    mask : array_like of bool, shape (N,), optional
        Samples of the error measure (default all; the thesis: the fully corrected part,
        ``time_window(N) == 1``).
    divergence_factor : float, optional
        Bound on the growth of the error measure relative to trial 0 (default 10).

    Returns
    -------
    ILCResult
        Status ``converged`` or ``error``, corrections, errors, measures and logs (also
        for a diverged run, up to the trial that diverged).

    Raises
    ------
    InputError
        ``experiment``, ``Q`` or ``L`` of the wrong kind, bad ``u0``, ``iterations``,
        ``mask`` or ``divergence_factor``; an experiment returning another shape or a
        mapping without ``"eps"`` (the message names ``experiment``).
    """
    if not callable(experiment):
        raise InputError(f"experiment: expected a callable experiment(u) -> eps, got {type(experiment).__name__}")
    for name, op in (("Q", Q), ("L", L)):
        if not callable(getattr(op, "apply", None)):
            raise InputError(f"{name}: expected a filter with an apply(x) method (QFilter, LearningFilter), got {type(op).__name__}")
    single = np.ndim(u0) == 1
    u = as_signal(u0, "u0", vector=True).copy()
    shape = u.shape
    if isinstance(iterations, bool) or not isinstance(iterations, (int, np.integer)) or iterations < 0:
        raise InputError(f"iterations: expected a non-negative integer, got {iterations!r}")
    factor = positive_float(divergence_factor, "divergence_factor")
    if mask is not None:
        error_measure(np.zeros(shape[0]), mask)  # checks the mask up front

    us: list[np.ndarray] = []
    errs: list[np.ndarray] = []
    measures: list[np.ndarray] = []
    logs: dict[str, list[np.ndarray]] = {}
    status, message = Status.CONVERGED, ""
    next_u = None
    for k in range(int(iterations) + 1):
        out = experiment(u[:, 0] if single else u.copy())
        if isinstance(out, Mapping):
            if "eps" not in out:
                raise InputError(f"experiment: returned a mapping without 'eps' (keys {sorted(out)})")
            for key, value in out.items():
                if key != "eps":
                    logs.setdefault(key, []).append(np.asarray(value))
            out = out["eps"]
        eps = _as_2d(out, "experiment", shape)
        us.append(u.copy())
        errs.append(eps)
        if not np.all(np.isfinite(eps)):
            measures.append(np.full(shape[1], np.inf))
            status, message = Status.ERROR, f"diverged: trial {k} returned a non-finite error"
            break
        m = np.atleast_1d(error_measure(eps, mask))
        measures.append(m)
        _log.info("ILC trial %d: error measure %s", k, np.array2string(m, precision=4))
        if k > 0 and np.any((measures[0] > 0) & (m > factor * measures[0])):
            j = int(np.argmax(m / np.where(measures[0] > 0, measures[0], np.inf)))
            status = Status.ERROR
            message = (
                f"diverged: the error measure of column {j} grew from {measures[0][j]:.4g} (trial 0) "
                f"to {m[j]:.4g} (trial {k}), beyond divergence_factor = {factor:g}"
            )
            break
        u = next_correction(u, eps, Q, L)
        next_u = u.copy()
    else:
        first, last = measures[0], measures[-1]
        if np.any(last > first):
            j = int(np.argmax(last - first))
            status = Status.ERROR
            message = f"the error measure of column {j} ended above its initial value: {last[j]:.4g} > {first[j]:.4g} after {iterations} iterations"
        else:
            ratio = np.where(first > 0, last / np.where(first > 0, first, 1.0), 0.0)
            message = f"{iterations} iterations; error measure relative to trial 0: " + ", ".join(f"{r:.4g}" for r in ratio)
    return ILCResult(
        status=status,
        message=message,
        u=np.stack(us),
        eps=np.stack(errs),
        measure=np.stack(measures),
        logs={key: np.stack(v) for key, v in logs.items()},
        next_u=next_u,
    )


def next_correction(u: Any, eps: Any, Q: Any, L: Any) -> np.ndarray:
    """One update of the ILC law, Dressler (2012), eq. 7.2: ``u_{k+1} = Q (u_k + L eps_k)``, column by column.

    The step :func:`run_ilc` repeats; alone, it is the next iteration of a trial run
    elsewhere, e.g. on a robot whose cycle log gives ``eps`` (``gtmodel loop``).

    Parameters
    ----------
    u : array_like, shape (N, d)
        The correction of the trial (rows are cycles, columns axes or directions).
    eps : array_like, shape (N, d)
        The trial's learning signal (reference minus measured, per cycle).
    Q : QFilter or object with ``apply``
        The robustness filter (:class:`~gtmodel.estimation.ilc.lifted.QFilter`).
    L : LearningFilter or object with ``apply``
        The learning filter (:class:`~gtmodel.estimation.ilc.lifted.LearningFilter`).

    Returns
    -------
    numpy.ndarray, shape (N, d)
        The next correction.

    Raises
    ------
    InputError
        ``u`` or ``eps`` not finite, of different shapes, or a filter's output of another shape.
    """
    u = as_signal(u, "u", vector=True)
    shape = u.shape
    eps = _as_2d(as_signal(eps, "eps", vector=True), "eps", shape)
    return _as_2d(Q.apply(u + _as_2d(L.apply(eps), "L.apply", shape)), "Q.apply", shape)


def ilc_correction_function(table: Any) -> ca.Function:
    """The learned correction as a CasADi function of the cycle count: ``ilc_correction(k) -> u``.

    Dressler (2012), eq. 7.2 and ch. 7.3: the 4 ms loop adds the learned correction of
    the current cycle to the reference. ``u = table[floor(k)]`` for ``0 <= k < N`` and
    zeros outside (also for a NaN ``k``); the lookup is a CasADi parametric index into
    the constant table (one graph: Python evaluation and generated C agree exactly).
    The time window is already inside the table (Q applied it).

    Parameters
    ----------
    table : array_like, shape (N, d)
        Learned correction per cycle (e.g. :attr:`ILCResult.next_u` or ``u[-1]``), rows
        are cycles; a 1-D ``(N,)`` table is one column.

    Returns
    -------
    casadi.Function
        ``"ilc_correction"``: input ``k`` (scalar, cycle count), output ``u`` (d x 1).

    Raises
    ------
    InputError
        ``table`` not finite, empty or of another shape.
    """
    tab = as_signal(table, "table", vector=True)
    n, d = tab.shape
    k = ca.MX.sym("k")
    row = ca.floor(k)
    inside = ca.logic_and(row >= 0, row <= n - 1)
    base = d * ca.if_else(inside, row, 0)
    values = ca.MX(ca.DM(tab.reshape(-1)))  # row-major: entry (i, j) at i * d + j
    u = ca.vertcat(*[values[base + j] for j in range(d)])
    u = ca.if_else(inside, u, ca.DM.zeros(d))
    return ca.Function("ilc_correction", [k], [u], ["k"], ["u"])
