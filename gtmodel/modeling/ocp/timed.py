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
  that of the mesh itself. A time at a fixed fraction ``s`` of a free horizon
  (``Timed.fraction``) lies at a fixed place of its element, ``t = t0 + s (T - t0)``. At ``"start"``/``"final"`` the values are the point
  constraints' (initial/final state; inputs extrapolated to ``tau = 0`` / ``tau = 1``);
* an integral is the collocation quadrature (weights ``B_j``, as the Lagrange term).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

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
    elements: Any,
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
    elements : object
        The NLP's element variables: ``len(elements)`` is the number of elements ``N`` and
        ``elements.interpolate(ks, lx, lu)`` gives the states ``(nx, n)``, inputs, algebraic
        variables and element final times ``(1, n)`` in elements ``ks`` (``(n,)``) with the
        Lagrange weights ``lx`` ``(d + 1, n)`` (through the element start and its points) and
        ``lu`` ``(d, n)`` (through its points).
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
    values: list[ca.SX] = [ca.SX(0, 1)] * len(specials)
    interior: list[int] = []
    for i, v in enumerate(specials):
        if isinstance(v, Integral):
            a, weights = quadrature
            f = make_fn("special", [v.expr])
            values[i] = ca.mtimes(f.map(int(weights.shape[1]))(a.t, a.x, a.z, a.u, P, a.T), weights.T)
        elif v.time in ("start", "final"):
            a = ends[0] if v.time == "start" else ends[1]
            values[i] = make_fn("special", [v.expr])(a.t, a.x, a.z, a.u, P, a.T)
        else:
            interior.append(i)
    if interior:
        # a fixed time of a fixed horizon, or a fixed fraction of a free one (normalised time)
        fracs = [specials[i].fraction for i in interior]
        times = np.array([np.nan if fr is not None else float(specials[i].time) for fr, i in zip(fracs, interior)])
        if fractions is None:
            s = np.array([fr * N if fr is not None else (t - t0) / ((opt.final_time_value - t0) / N) for fr, t in zip(fracs, times)])
            ks = np.clip(np.ceil(s - 1e-9) - 1, 0, N - 1).astype(int)
            taus = np.clip(s - ks, 0.0, 1.0)
        else:  # the element containing t (the left one at a boundary) on the non-uniform mesh
            frac = np.asarray(fractions, dtype=float)
            edges = np.concatenate([[0.0], np.cumsum(frac)])
            s_frac = np.array([fr if fr is not None else (t - t0) / (opt.final_time_value - t0) for fr, t in zip(fracs, times)])
            ks = np.clip(np.searchsorted(edges[1:], s_frac - 1e-9 * float(frac.min()), side="left"), 0, N - 1).astype(int)
            taus = np.clip((s_frac - edges[ks]) / frac[ks], 0.0, 1.0)
        # the states through the element start and its points, inputs and algebraics through
        # its points, at every interior time at once (columns)
        x, u, z, T = elements.interpolate(ks, lagrange_basis(co["root"], taus).T, lagrange_basis(co["tau"], taus).T)
        # one mapped call per distinct expression (a data table measures one expression at many times)
        groups: list[list[int]] = []
        for c, i in enumerate(interior):
            for g in groups:
                if ca.is_equal(specials[interior[g[0]]].expr, specials[i].expr, 2):
                    g.append(c)
                    break
            else:
                groups.append([c])
        for g in groups:
            f = make_fn("special", [specials[interior[g[0]]].expr])
            tg = ca.horzcat(*[t0 + fracs[c] * (T[:, c] - t0) if fracs[c] is not None else ca.DM(times[c]) for c in g])
            row = f.map(len(g))(tg, x[:, g], z[:, g], u[:, g], P, T[:, g])
            for j, c in enumerate(g):
                values[interior[c]] = row[0, j]
    return ca.vertcat(*[v.symbol for v in specials]), ca.vertcat(*values)
