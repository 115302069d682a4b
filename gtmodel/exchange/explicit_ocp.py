"""Optimal control of an explicit model (an imported FMU) by direct collocation.

gtmodel's own transcription (:mod:`gtmodel.modeling.ocp.collocation_nlp`) works on the SX
expressions of a :class:`~gtmodel.modeling.Model`; an FMU is a binary, callable only as a
CasADi ``FmuFunction`` in MX graphs. This module writes the same NLP for
``xdot = f(t, x, u, p)`` in MX: the same uniform elements, collocation points and
coefficients (:func:`~gtmodel.modeling.ocp.collocation_nlp.collocation_coefficients`,
Radau IIA by default), states at the element starts and collocation points, inputs at the
collocation points, a free final time by time scaling, the Lagrange term by the points'
quadrature, IPOPT with gtmodel's defaults (:func:`~gtmodel.modeling.ocp.collocation_nlp.merge_options`).
The model is called once per collocation point (not through ``Function.map``: with an
``FmuFunction``, CasADi 3.8.2 gives the mapped call wrong Jacobian entries in this NLP,
while the values agree; tests/exchange/test_fmu_import.py checks the Jacobian). Its
derivatives are the FMU's directional derivatives or finite differences
(:attr:`~gtmodel.exchange.fmu_import.ImportedFmu.derivatives`, stated in the result).
So the optimum of a problem on an exported and re-imported gtmodel model equals that of
the same problem written natively (:func:`gtmodel.modeling.solve`), to the solver's tolerance.
"""

from __future__ import annotations

import time as _time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError
from gtmodel.modeling import ExplicitODE
from gtmodel.exchange.explicit_ops import _values
from gtmodel.modeling.ocp.collocation_nlp import collocation_coefficients, element_operators, merge_options
from gtmodel.modeling.ocp.result import normalize_ipopt_status
from gtmodel.status import StatusResult

__all__ = ["ExplicitOcpResult", "solve_explicit_ocp"]


@dataclass
class ExplicitOcpResult(StatusResult):
    """Result of :func:`solve_explicit_ocp`.

    Parameters
    ----------
    status : Status
        IPOPT's outcome as a gtmodel status (``optimal`` for Solve_Succeeded).
    message : str
        IPOPT's return status.
    objective : float
        Optimal objective.
    final_time : float
        Final time [s].
    t : numpy.ndarray
        Times of the element starts and collocation points, shape ``(K (d + 1) + 1,)``.
    x : dict of str to numpy.ndarray
        States by scalar name on :attr:`t`.
    t_u : numpy.ndarray
        Times of the collocation points, shape ``(K d,)``.
    u : dict of str to numpy.ndarray
        Inputs by scalar name on :attr:`t_u`.
    iterations : int
        IPOPT iterations.
    solve_time : float
        Wall time of the solve [s].
    derivatives : str
        Where the model's derivatives came from.
    """

    objective: float = float("nan")
    final_time: float = float("nan")
    t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    x: dict[str, np.ndarray] = field(default_factory=dict)
    t_u: np.ndarray = field(default_factory=lambda: np.zeros(0))
    u: dict[str, np.ndarray] = field(default_factory=dict)
    iterations: int = 0
    solve_time: float = 0.0
    derivatives: str = ""


def _bounds(names: list[str], given: Mapping[str, tuple[float, float]] | None, what: str) -> tuple[np.ndarray, np.ndarray]:
    lb, ub = np.full(len(names), -np.inf), np.full(len(names), np.inf)
    for k, (lo, hi) in (given or {}).items():
        if k not in names:
            raise InputError(f"{what}: no variable {k!r}; known: {names}")
        lb[names.index(k)], ub[names.index(k)] = float(lo), float(hi)
    return lb, ub


def solve_explicit_ocp(
    em: ExplicitODE,
    final_time: float = 1.0,
    free_final_time: bool = False,
    final_time_bounds: tuple[float, float] = (1e-3, 1e3),
    start: Mapping[str, float] | None = None,
    final: Mapping[str, float] | None = None,
    input_bounds: Mapping[str, tuple[float, float]] | None = None,
    state_bounds: Mapping[str, tuple[float, float]] | None = None,
    lagrange: Callable[[dict[str, Any]], Any] | None = None,
    minimize_final_time: bool | None = None,
    p: Any = None,
    elements: int = 50,
    points: int = 3,
    scheme: str = "radau",
    solver_options: Mapping[str, Any] | None = None,
    derivatives: str = "",
    guess: ExplicitOcpResult | None = None,
) -> ExplicitOcpResult:
    """Solve an optimal control problem on an explicit model by direct collocation.

    Minimise ``[tf] + integral(lagrange)`` subject to ``xdot = f(t, x, u, p)``, the start
    state, final-state equalities and bounds.

    Parameters
    ----------
    em : ExplicitODE
        The model (``import_fmu(...).model``, or a gtmodel model's ``explicit_model``).
    final_time : float, optional
        Final time [s] (the guess of a free one); default 1.
    free_final_time : bool, optional
        Optimise the final time within ``final_time_bounds`` [s].
    final_time_bounds : tuple of float, optional
        Bounds of a free final time [s].
    start : mapping of str to float, optional
        Start states by scalar name; the others start at the model's start values.
    final : mapping of str to float, optional
        Final-state equalities by scalar name.
    input_bounds, state_bounds : mapping of str to (float, float), optional
        Bounds by scalar name (inputs at the collocation points, states at every point).
    lagrange : callable, optional
        ``lagrange(v) -> MX`` scalar integrand, ``v`` maps scalar names of states and inputs
        (and ``"time"``) to MX values at a collocation point.
    minimize_final_time : bool, optional
        Add ``tf`` to the objective; default ``free_final_time``.
    p : mapping or array_like, optional
        Parameter values; default the model's.
    elements, points : int, optional
        Uniform elements and collocation points per element; default 50 and 3.
    scheme : {"radau", "legendre"}, optional
        Collocation points; default Radau IIA.
    solver_options : mapping, optional
        IPOPT options (as for :func:`gtmodel.modeling.solve`).
    derivatives : str, optional
        Where ``f``'s derivatives come from, copied into the result (e.g.
        :attr:`ImportedFmu.derivatives`); default CasADi's algorithmic differentiation.
    guess : ExplicitOcpResult, optional
        A solution of the same transcription (same names, elements and points) to start
        from; default straight lines from the start to the final states.

    Returns
    -------
    ExplicitOcpResult
        Status, objective, final time and trajectories (a solver failure is a status).

    Raises
    ------
    InputError
        Unknown names, ``elements``/``points`` < 1, a non-positive final time.
    """
    if int(elements) < 1 or int(points) < 1:
        raise InputError(f"elements and points must be >= 1, got {elements}, {points}")
    if not final_time > 0:
        raise InputError(f"final_time must be positive, got {final_time}")
    K, d = int(elements), int(points)
    co = collocation_coefficients(d, scheme)
    nx, nu = em.nx, len(em.u_names)
    pv = _values(em, "p", p)
    x0 = _values(em, "x", start)
    xlb, xub = _bounds(em.x_names, state_bounds, "state_bounds")
    ulb, uub = _bounds(em.u_names, input_bounds, "input_bounds")
    tfs = ca.MX.sym("tf") if free_final_time else ca.MX(float(final_time))
    X = ca.MX.sym("X", nx, K * (d + 1) + 1)  # per element: start, d points; then the final state
    U = ca.MX.sym("U", nu, K * d)
    h = tfs / K
    cols = [k * (d + 1) + 1 + j for k in range(K) for j in range(d)]
    tau = np.array([(k + co["tau"][j]) / K for k in range(K) for j in range(d)])
    Xc = ca.horzcat(*[X[:, c] for c in cols])
    Tc = tfs * ca.DM(tau).T
    xdot_c = ca.horzcat(*[em.rhs(Tc[c], Xc[:, c], U[:, c], ca.DM(pv))[0] for c in range(K * d)])
    g, J = [], ca.MX(0)
    K_der, K_end = element_operators(co, nx)  # the collocation equations of gtmodel's own transcription
    for k in range(K):
        base = k * (d + 1)
        Xk = ca.vec(X[:, base:base + d + 1])  # the element start and its points, stacked
        g.append(ca.mtimes(K_der, Xk) - h * ca.vec(xdot_c[:, k * d:(k + 1) * d]))
        g.append(X[:, base + d + 1] - ca.mtimes(K_end, Xk))
    if lagrange is not None:
        for c in range(K * d):
            v = {n: Xc[i, c] for i, n in enumerate(em.x_names)}
            v.update({n: U[i, c] for i, n in enumerate(em.u_names)})
            v["time"] = Tc[c]
            J = J + h * co["B"][c % d] * lagrange(v)
    if minimize_final_time if minimize_final_time is not None else free_final_time:
        J = J + tfs
    fin_idx = [em.x_names.index(n) for n in (final or {})]
    for n in final or {}:
        if n not in em.x_names:
            raise InputError(f"final: no state {n!r}; known: {em.x_names}")
    g.append(X[:, 0] - x0)
    if fin_idx:
        g.append(ca.vertcat(*[X[i, -1] for i in fin_idx]) - ca.DM([float(final[em.x_names[i]]) for i in fin_idx]))
    w = [ca.vec(X), ca.vec(U)] + ([tfs] if free_final_time else [])
    nlp = {"x": ca.vertcat(*w), "f": J, "g": ca.vertcat(*g)}
    lbw = np.concatenate([np.tile(xlb, X.shape[1]), np.tile(ulb, K * d)] + ([[final_time_bounds[0]]] if free_final_time else []))
    ubw = np.concatenate([np.tile(xub, X.shape[1]), np.tile(uub, K * d)] + ([[final_time_bounds[1]]] if free_final_time else []))
    # guess: states from the start to the final values, inputs mid-range (0 when unbounded)
    xf = x0.copy()
    for i in fin_idx:
        xf[i] = float(final[em.x_names[i]])
    s = np.linspace(0, 1, X.shape[1])
    xg = (x0[:, None] + (xf - x0)[:, None] * s[None, :]).T.reshape(-1)
    ug = np.where(np.isfinite(ulb) & np.isfinite(uub), 0.5 * (ulb + uub), np.clip(em.u0, ulb, uub))
    w0 = np.concatenate([xg, np.tile(ug, K * d)] + ([[final_time]] if free_final_time else []))
    if guess is not None:
        try:
            w0 = np.concatenate([np.array([guess.x[n] for n in em.x_names]).T.reshape(-1),
                                 np.array([guess.u[n] for n in em.u_names]).T.reshape(-1)]
                                + ([[guess.final_time]] if free_final_time else []))
        except (KeyError, ValueError) as exc:
            raise InputError(f"guess: not a solution of this transcription ({exc})") from None
        if w0.size != lbw.size:
            raise InputError(f"guess: {w0.size} values for {lbw.size} NLP variables (another mesh?)")
    solver = ca.nlpsol("explicit_ocp", "ipopt", nlp, merge_options(False, solver_options))
    t0 = _time.perf_counter()
    sol = solver(x0=w0, lbx=lbw, ubx=ubw, lbg=0.0, ubg=0.0)
    elapsed = _time.perf_counter() - t0
    stats = solver.stats()
    wopt = np.array(sol["x"], dtype=float).reshape(-1)
    Xv = wopt[: nx * X.shape[1]].reshape(X.shape[1], nx).T
    Uv = wopt[nx * X.shape[1]: nx * X.shape[1] + nu * K * d].reshape(K * d, nu).T
    tf = float(wopt[-1]) if free_final_time else float(final_time)
    t_x = np.concatenate([[(k + r) / K for k in range(K) for r in np.concatenate([[0.0], co["tau"]])], [1.0]]) * tf
    return ExplicitOcpResult(
        status=normalize_ipopt_status(stats.get("return_status", "")), message=str(stats.get("return_status", "")),
        objective=float(sol["f"]), final_time=tf, t=t_x, x={n: Xv[i] for i, n in enumerate(em.x_names)},
        t_u=tau * tf, u={n: Uv[i] for i, n in enumerate(em.u_names)}, iterations=int(stats.get("iter_count", 0)),
        solve_time=elapsed, derivatives=derivatives or "algorithmic differentiation (CasADi)",
    )
