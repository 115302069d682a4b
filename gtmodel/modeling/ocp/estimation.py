"""Parameter estimation from measured data: a least-squares objective and the statistics of its estimates.

JModelica.org's ``MeasurementData`` use case, Optimica style: :func:`fit_data` declares
that an expression of the model (an output, a state) was measured at given times; each
measurement becomes a timed variable (:meth:`Optimization.timed`), so the residual
``y(t_i) - y_i`` is exact at the transcription's mesh and interpolated between.
:func:`least_squares` is the objective ``sum_i w_i (y(t_i) - y_i)^2`` with ``w_i =
1 / sigma_i^2`` (the chi-square of the fit) or given weights.

:func:`estimate_statistics` reports, after the solve, the residual statistics and the
covariance of the free parameters from the Gauss-Newton Hessian ``J^T W J`` of the
residuals, reduced to the directions the constraints of the transcription leave free
(Bard 1974, *Nonlinear Parameter Estimation*, ch. 7; Bock's constrained Gauss-Newton):
with ``A`` the Jacobian of the equality and active constraints and active bounds of the
NLP at the solution, the covariance of all NLP variables is the upper-left block of the
inverse of the KKT matrix ``[[J^T W J, A^T], [A, 0]]``; the free parameters' block is
their covariance. With standard deviations given it is used as it is (``chi2/dof``
measures whether they are right); with weights it is scaled by the residual variance
``s^2 = SSR / (m - p)``.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling.ocp.optimization import Optimization


__all__ = ["DataFit", "fit_data", "least_squares", "estimate_statistics"]

_log = logging.getLogger("gtmodel")


@dataclass
class DataFit:
    """One measured signal: its times, values, weights and the timed variables standing for the model's values.

    Parameters
    ----------
    name : str
        Label (the measured name).
    times : numpy.ndarray
        Measurement times [s], shape ``(m,)``.
    values : numpy.ndarray
        Measured values, shape ``(m,)``.
    weights : numpy.ndarray
        Weights of the squared residuals, shape ``(m,)``.
    std_given : bool
        Whether the weights are ``1 / sigma^2`` of given standard deviations.
    symbols : list of casadi.SX
        The timed variables, one per time.
    """

    name: str
    times: np.ndarray
    values: np.ndarray
    weights: np.ndarray
    std_given: bool
    symbols: list = field(default_factory=list)


def fit_data(
    opt: Optimization, expr: Any, times: Any, values: Any, std: Any = None, weight: Any = None, name: str = "data"
) -> DataFit:
    """Declare measurements of ``expr`` at ``times`` (a data fit of the problem).

    Parameters
    ----------
    opt : Optimization
        The problem (fixed final time; the measurement times within the horizon).
    expr : casadi.SX
        Scalar expression of the model's variables that was measured (an output, a state).
    times : array_like
        Measurement times [s], shape ``(m,)``.
    values : array_like
        Measured values, shape ``(m,)``, in the unit of ``expr``.
    std : float or array_like, optional
        Standard deviations of the measurements (weights ``1 / std^2``); positive.
    weight : float or array_like, optional
        Weights of the squared residuals instead of ``std``; default 1.
    name : str, optional
        Label in the statistics.

    Returns
    -------
    DataFit
        Stored on ``opt.data_fits``; :func:`least_squares` sums them.

    Raises
    ------
    InputError
        If shapes differ, a value is not finite, ``std``/``weight`` are not positive or
        both are given.
    ModelError
        If a time is outside the horizon or the final time is free.
    """
    if opt.free_final_time:
        raise ModelError(f"data {name!r}: measurements are at fixed times; fit them on a fixed final time (free = false)")
    t = np.asarray(times, dtype=float).reshape(-1)
    y = np.asarray(values, dtype=float).reshape(-1)
    if t.shape != y.shape or t.size == 0:
        raise InputError(f"data {name!r}: times and values must have the same non-zero length, got {t.size} and {y.size}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        raise InputError(f"data {name!r}: times and values must be finite numbers")
    if std is not None and weight is not None:
        raise InputError(f"data {name!r}: give std or weight, not both")
    spec = std if std is not None else (1.0 if weight is None else weight)
    s = np.broadcast_to(np.asarray(spec, dtype=float), t.shape).astype(float)
    if not np.all(np.isfinite(s) & (s > 0)):
        raise InputError(f"data {name!r}: {'std' if std is not None else 'weight'} must be positive and finite")
    fit = DataFit(name, t, y, 1.0 / s**2 if std is not None else s, std is not None)
    fit.symbols = [opt.timed(expr, float(ti)) for ti in t]
    opt.data_fits.append(fit)
    return fit


def least_squares(opt: Optimization) -> ca.SX:
    """The weighted least-squares objective of all data fits, ``sum w_i (y(t_i) - y_i)^2``.

    Parameters
    ----------
    opt : Optimization
        The problem with :func:`fit_data` declarations.

    Returns
    -------
    casadi.SX
        Scalar Mayer term over timed variables (for :meth:`Optimization.set_objective`).
    """
    total = ca.SX(0)
    for fit in opt.data_fits:
        r = ca.vertcat(*fit.symbols) - ca.DM(fit.values)
        total = total + ca.dot(ca.DM(fit.weights), r**2)
    return total


def estimate_statistics(transcription: Any, result: Any) -> dict[str, Any]:
    """Residual statistics and free-parameter estimates with standard deviations (Gauss-Newton).

    Parameters
    ----------
    transcription : CollocationTranscription or ShootingTranscription
        The transcription that produced ``result`` (its NLP, constraints and the values of
        timed variables ``special_function``).
    result : OptimizationResult
        Its solution (``w``, ``parameters``).

    Returns
    -------
    dict
        ``residuals``: per data fit ``{"rms", "max_abs", "mean", "n"}``; ``n_data``,
        ``n_parameters``, ``ssr`` (weighted sum of squares), ``chi2_per_dof`` (``ssr /
        (n_data - n_parameters)``); ``estimates``: per free parameter element ``{"value",
        "std", "ci95"}``; ``covariance`` (``(np, np)`` list); ``identifiable`` (False when
        the reduced Gauss-Newton Hessian is singular, then ``std`` is NaN).
    """
    opt = transcription.optimization
    dae = transcription.dae
    w = np.asarray(result.w, dtype=float)
    pvec = dae.parameter_vector(opt.parameters)
    specials = opt.special_symbols()
    index = {id(v.symbol): i for i, v in enumerate(specials)}
    sval = np.array(transcription.special_function(w, pvec), dtype=float).reshape(-1)
    rows, res, wts, stats = [], [], [], {}
    for fit in opt.data_fits:
        idx = [index[id(s)] for s in fit.symbols]
        r = sval[idx] - fit.values
        rows += idx
        res.append(r)
        wts.append(fit.weights)
        stats[fit.name] = {"n": int(r.size), "rms": float(np.sqrt(np.mean(r**2))), "max_abs": float(np.max(np.abs(r))),
                           "mean": float(np.mean(r))}
    r, W = np.concatenate(res), np.concatenate(wts)
    free = [(n, i) for n in opt.free_parameters for i in range(dae.p_vars[n].stop - dae.p_vars[n].start)]
    m, npar = int(r.size), len(free)
    ssr = float(np.sum(W * r**2))
    dof = m - npar
    out: dict[str, Any] = {"residuals": stats, "n_data": m, "n_parameters": npar, "ssr": ssr,
                           "chi2_per_dof": ssr / dof if dof > 0 else float("nan")}
    cov = _covariance(transcription, w, pvec, rows, W) if npar else np.zeros((0, 0))
    identifiable = bool(np.all(np.isfinite(cov)))
    std_given = all(f.std_given for f in opt.data_fits)
    if not std_given and dof > 0:
        cov = cov * (ssr / dof)
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None)) if npar else np.zeros(0)
    estimates = {}
    for k, (n, i) in enumerate(free):
        value = float(np.ravel(result.parameters[n])[i])
        key = n if dae.p_vars[n].stop - dae.p_vars[n].start == 1 else f"{n}[{i}]"
        estimates[key] = {"value": value, "std": float(sd[k]), "ci95": [value - 1.96 * float(sd[k]), value + 1.96 * float(sd[k])]}
    out.update(estimates=estimates, covariance=cov.tolist(), identifiable=identifiable,
               weights="1/std^2" if std_given else "given (covariance scaled by SSR/(m - p))")
    return out


def _covariance(transcription: Any, w: np.ndarray, pvec: np.ndarray, rows: Sequence[int], W: np.ndarray) -> np.ndarray:
    """Covariance of the free parameters: the pf block of the inverse KKT matrix with the Gauss-Newton Hessian."""
    fn = transcription.special_function
    wsym = fn.mx_in(0)
    psym = fn.mx_in(1)
    J_fn = ca.Function("jr", [wsym, psym], [ca.jacobian(fn(wsym, psym)[rows, :] if rows else ca.MX(0, 1), wsym)])
    g_fn = ca.Function("jg", [wsym, psym], [ca.jacobian(transcription._fg(wsym, psym)[1], wsym)])
    Jr = ca.DM(J_fn(w, pvec))
    A = ca.DM(g_fn(w, pvec))
    lbg, ubg, lbw, ubw = transcription._lbg, transcription._ubg, transcription._lbw, transcription._ubw
    g = np.array(transcription._fg(w, pvec)[1], dtype=float).reshape(-1)
    active_g = np.nonzero((lbg == ubg) | _at_bound(g, lbg, ubg))[0]
    active_w = np.nonzero((lbw == ubw) | _at_bound(w, lbw, ubw))[0]
    nw = w.size
    # the KKT matrix in CasADi's sparse format, factorised by its CSparse LU (no SciPy import)
    Aw = ca.DM(ca.Sparsity.triplet(active_w.size, nw, np.arange(active_w.size).tolist(), active_w.tolist()), 1.0)
    A_act = ca.vertcat(A[active_g.tolist(), :], Aw)
    H = ca.mtimes(Jr.T, ca.mtimes(ca.diag(ca.DM(W)), Jr))
    na = int(A_act.shape[0])
    K = ca.blockcat([[H, A_act.T], [A_act, ca.DM(na, na)]])
    scale = getattr(transcription, "_scale", np.ones(nw))
    pf_cols = _free_columns(transcription, nw)
    rhs = np.zeros((nw + na, len(pf_cols)))
    rhs[pf_cols, np.arange(len(pf_cols))] = 1.0
    try:
        sol = np.array(ca.solve(K, ca.DM(rhs), "csparse"), dtype=float)
    except RuntimeError:  # singular: a parameter the data do not determine
        sol = np.full(rhs.shape, np.nan)
    if not np.all(np.isfinite(sol)):
        _log.warning("parameter estimation: the reduced Gauss-Newton Hessian is singular (parameters not identifiable)")
        return np.full((len(pf_cols), len(pf_cols)), np.nan)
    cov = sol[pf_cols, :]
    s = scale[pf_cols]
    cov = 0.5 * (cov + cov.T) * np.outer(s, s)
    if not np.all(np.isfinite(cov)) or np.any(np.diag(cov) < -1e-12 * np.max(np.abs(cov), initial=1.0)):
        return np.full_like(cov, np.nan)
    return cov


def _at_bound(v: np.ndarray, lb: np.ndarray, ub: np.ndarray, tol: float = 1e-7) -> np.ndarray:
    """Entries of ``v`` at a finite bound (active inequalities at the solution)."""
    with np.errstate(invalid="ignore"):
        low = np.isfinite(lb) & (v - lb <= tol * (1.0 + np.abs(lb)))
        high = np.isfinite(ub) & (ub - v <= tol * (1.0 + np.abs(ub)))
    return low | high


def _free_columns(transcription: Any, nw: int) -> np.ndarray:
    """Indices in ``w`` of the free parameter elements (the last entries of both transcriptions)."""
    n = sum(transcription.dae.p_vars[k].stop - transcription.dae.p_vars[k].start for k in transcription.optimization.free_parameters)
    return np.arange(nw - n, nw)
