"""Values of timed variables and integrals in a collocation NLP (Optimica's point constraints).

An :class:`~gtmodel.modeling.Optimization` names the value of an expression at a fixed
time (:meth:`~gtmodel.modeling.Optimization.timed`) or its integral over the horizon
(:meth:`~gtmodel.modeling.Optimization.integral`) by a symbol; :func:`special_values`
gives each symbol its value as an expression of the collocation NLP's variables:

* a timed variable at an interior time ``t`` is interpolated from the collocation
  polynomials of the element that contains ``t`` (the element to the left at an element
  boundary, as :meth:`~gtmodel.modeling.ocp.result.CollocationData.evaluate` samples):
  states through the element start and its collocation points, inputs and algebraic
  variables through the collocation points. No mesh point is moved to ``t``; at an
  element boundary (``t`` a multiple of the element length from the start) the value is
  that of the mesh itself. At ``"start"``/``"final"`` the values are the point
  constraints' (initial/final state; inputs extrapolated to ``tau = 0`` / ``tau = 1``);
* an integral is the collocation quadrature (weights ``B_j``, as the Lagrange term).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from gtmodel.modeling.ocp.optimization import Integral, Optimization, Timed
from gtmodel.modeling.ocp.result import lagrange_basis

__all__ = ["PointArgs", "special_values"]


@dataclass
class PointArgs:
    """The arguments ``(t, x, z, u, T)`` of a model function at one point of the NLP.

    Parameters
    ----------
    t : casadi.SX
        Time [s].
    x, z, u : casadi.SX
        States, algebraic variables, inputs there.
    T : casadi.SX
        The final time (the element's copy of a free one).
    """

    t: ca.SX
    x: ca.SX
    z: ca.SX
    u: ca.SX
    T: ca.SX


def special_values(
    opt: Optimization,
    make_fn: Callable[[str, list[ca.SX]], ca.Function],
    P: ca.SX,
    elements: Sequence[tuple[list[ca.SX], list[ca.SX], list[ca.SX], ca.SX]],
    ends: tuple[PointArgs, PointArgs],
    quadrature: tuple[PointArgs, ca.SX],
    co: dict[str, np.ndarray],
    fractions: np.ndarray | None = None,
) -> tuple[ca.SX, ca.SX]:
    """The symbols of timed variables and integrals and their values in the NLP.

    Parameters
    ----------
    opt : Optimization
        The problem (its ``timed_variables`` and ``integrals``).
    make_fn : callable
        ``make_fn(name, exprs)``: a Function ``(t, x, z, u, p, tf) -> vertcat(exprs)``
        (``der()`` of states substituted by the model's right-hand side).
    P : casadi.SX
        The model parameter vector of the NLP (free parameters as variables).
    elements : sequence of tuple
        Per element ``(X, U, Z, T)``: states at the element start and its collocation
        points (``d + 1``), inputs and algebraics at the collocation points (``d``), and
        the element's final time.
    ends : tuple of PointArgs
        The arguments at the start and at the final time.
    quadrature : tuple
        ``(args, weights)``: the arguments at all ``M`` collocation points as columns
        (``t`` and ``T`` ``(1, M)``, ``x`` ``(nx, M)``, ...) and the quadrature weights
        ``(1, M)``; the integral of ``f`` is ``sum(weights * f(args))`` (one mapped call).
    co : dict
        Collocation coefficients (``root``, ``tau``).
    fractions : numpy.ndarray or None, optional
        Element lengths as fractions of the horizon, shape ``(N,)`` (a refined,
        non-uniform mesh); None for a uniform mesh.

    Returns
    -------
    symbols, values : casadi.SX
        Column vectors of the symbols and of their values (the same length).
    """
    specials: list[Timed | Integral] = opt.special_symbols()
    if not specials:
        return ca.SX(0, 1), ca.SX(0, 1)
    t0 = opt.start_time
    N = len(elements)
    values = []
    for v in specials:
        f = make_fn("special", [v.expr])
        if isinstance(v, Integral):
            a, weights = quadrature
            values.append(ca.mtimes(f.map(int(weights.shape[1]))(a.t, a.x, a.z, a.u, P, a.T), weights.T))
            continue
        if v.time in ("start", "final"):
            a = ends[0] if v.time == "start" else ends[1]
            values.append(f(a.t, a.x, a.z, a.u, P, a.T))
            continue
        t = float(v.time)
        if fractions is None:
            h = (opt.final_time_value - t0) / N
            s = (t - t0) / h
            k = int(np.clip(np.ceil(s - 1e-9) - 1, 0, N - 1))
            tau = float(np.clip(s - k, 0.0, 1.0))
        else:  # the element containing t (the left one at a boundary) on the non-uniform mesh
            frac = np.asarray(fractions, dtype=float)
            edges = np.concatenate([[0.0], np.cumsum(frac)])
            s_frac = (t - t0) / (opt.final_time_value - t0)
            k = int(np.clip(np.searchsorted(edges[1:], s_frac - 1e-9 * float(frac.min()), side="left"), 0, N - 1))
            tau = float(np.clip((s_frac - edges[k]) / frac[k], 0.0, 1.0))
        X, U, Z, T = elements[k]
        lx = lagrange_basis(co["root"], np.array([tau]))[0]
        lu = lagrange_basis(co["tau"], np.array([tau]))[0]
        x = sum(float(lx[r]) * X[r] for r in range(len(X)))
        u = sum(float(lu[j]) * U[j] for j in range(len(U))) if U[0].numel() else ca.SX(0, 1)
        z = sum(float(lu[j]) * Z[j] for j in range(len(Z))) if Z[0].numel() else ca.SX(0, 1)
        values.append(f(t, x, z, u, P, T))
    return ca.vertcat(*[v.symbol for v in specials]), ca.vertcat(*values)
