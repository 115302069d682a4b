"""The collocation NLP of an :class:`~gtmodel.modeling.Optimization`: variables, constraints, layout.

Method (as in JModelica.org's LocalDAECollocator): the horizon is split into ``elements``
uniform elements; in each, states are polynomials of degree ``points`` through the
element start and the ``points`` collocation points (``casadi.collocation_points``,
Radau IIA or Gauss-Legendre); inputs and algebraic variables are NLP variables at the
collocation points only. States are continuous across elements. A free final time is
handled by time scaling ``t = t0 + tau (tf - t0)``.

The decision variables are ordered stage by stage: element ``k`` holds its start state,
its copy ``tf_k`` of a free final time, then the states, algebraic variables and inputs at
its collocation points; the last block is the final state, then the free parameters. The
copies are tied by ``tf_{k+1} = tf_k`` (linear equalities, the same optimum), so that
every constraint involves the variables of one or two neighbouring elements: the KKT
matrix is banded (a single shared final time is a dense row and column), which keeps the
sparse factorisation linear in the mesh and is the structure stage-wise solvers require.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.defaults import defaults
from gtmodel.errors import InputError
from gtmodel.modeling.dae import FlatDAE
from gtmodel.modeling.ocp.optimization import Optimization
from gtmodel.modeling.ocp.result import lagrange_basis
from gtmodel.modeling.ocp.timed import PointArgs, special_values

__all__ = ["CASADI_OPTIONS", "IPOPT_DEFAULTS", "merge_options", "collocation_coefficients", "CollocationNLP", "transcribe", "element_scaling"]

#: CasADi-level nlpsol options passed through unchanged (others are options of the solver plugin).
CASADI_OPTIONS = {
    "print_time",
    "expand",
    "error_on_fail",
    "record_time",
    "verbose",
    "calc_lam_p",
    "calc_lam_x",
    "calc_f",
    "calc_g",
    "bound_consistency",
    "show_eval_warnings",
    "iteration_callback",
    "regularity_check",
    "structure_detection",
    "equality",
    "debug",
}

#: IPOPT options every collocation NLP starts from (``solver_options`` override them): the
#: dict ``defaults["ipopt.options"]`` of :mod:`gtmodel.defaults` (why ``mumps_mem_percent``
#: is 20 is written there).
IPOPT_DEFAULTS: dict[str, Any] = defaults["ipopt.options"]


def merge_options(verbose: bool, solver_options: Mapping[str, Any] | None, plugin: str = "ipopt") -> dict[str, Any]:
    """nlpsol options: the defaults (with IPOPT, :data:`IPOPT_DEFAULTS`), then ``solver_options`` (plugin options by plain name).

    Parameters
    ----------
    verbose : bool
        Show the solver's iteration log and CasADi's timing.
    solver_options : mapping or None
        Plugin options (``"max_iter"``, ``"ipopt.max_iter"`` or a nested ``{"ipopt": {...}}``)
        and CasADi nlpsol options (:data:`CASADI_OPTIONS`).
    plugin : {"ipopt", "fatrop"}, optional
        The nlpsol plugin whose options the plain names are.

    Returns
    -------
    dict
        The nested options of ``casadi.nlpsol``.

    Raises
    ------
    InputError
        A key is not a string.
    """
    inner: dict[str, Any] = {"max_iter": defaults["nlp.max_iter"], "tol": defaults["nlp.tol"],
                             **(defaults["ipopt.options"] if plugin == "ipopt" else {})}
    top: dict[str, Any] = {"error_on_fail": False}
    if verbose:
        inner["print_level"] = 5
        top["print_time"] = True
    else:
        inner["print_level"] = 0
        if plugin == "ipopt":
            inner["sb"] = "yes"
        top["print_time"] = False
        top["show_eval_warnings"] = False
    for key, value in (solver_options or {}).items():
        if not isinstance(key, str):
            raise InputError(f"solver_options keys must be strings, got {key!r}")
        if key == plugin and isinstance(value, Mapping):
            inner.update(value)
        elif key.startswith(f"{plugin}."):
            inner[key[len(plugin) + 1:]] = value
        elif key in CASADI_OPTIONS:
            top[key] = value
        else:
            inner[key] = value
    top[plugin] = inner
    return top


def collocation_coefficients(d: int, scheme: str) -> dict[str, np.ndarray]:
    """Derivative matrix, continuity, quadrature and extrapolation weights.

    ``C`` and ``D`` from ``casadi.collocation_coeff`` (Lagrange polynomials through ``0``
    and the collocation points), which keeps the exact zeros of the scheme: for Radau the
    end of an element is its last collocation point, so ``D = (0, ..., 0, 1)`` and a
    continuity constraint involves two states only. ``B`` integrates the polynomial through
    the collocation points (inputs and algebraics have no value at the element start).

    Parameters
    ----------
    d : int
        Collocation points per element.
    scheme : {"radau", "legendre"}
        The points.

    Returns
    -------
    dict of str to numpy.ndarray
        ``tau`` (d,), ``root`` (d + 1,), ``C`` (d + 1, d + 1), ``D`` (d + 1,), ``B`` (d,),
        ``L0`` and ``L1`` (d,): the points' basis at ``tau = 0`` and ``1``.
    """
    tau = np.array(ca.collocation_points(d, scheme), dtype=float)
    root = np.concatenate([[0.0], tau])
    c_, d_, _ = ca.collocation_coeff(tau.tolist())
    C = np.zeros((d + 1, d + 1))
    C[:, 1:] = np.array(c_, dtype=float)  # C[r, j]: derivative of basis r at root j (j >= 1)
    B = np.zeros(d)
    for j in range(d):
        coeff = np.zeros(d)
        coeff[j] = 1.0
        poly = np.poly1d(np.polyfit(tau, coeff, d - 1)) if d > 1 else np.poly1d([1.0])
        ipoly = np.polyint(poly)
        B[j] = ipoly(1.0) - ipoly(0.0)
    return {
        "tau": tau,
        "root": root,
        "C": C,
        "D": np.array(d_, dtype=float).reshape(-1),
        "B": B,
        "L0": lagrange_basis(tau, np.array([0.0]))[0],
        "L1": lagrange_basis(tau, np.array([1.0]))[0],
    }


@dataclass
class CollocationNLP:
    """The transcribed NLP (symbolic) and where each variable and constraint sits.

    Parameters
    ----------
    w, g, f : casadi.SX
        Scaled decision variables (nw,), constraints (ng,), objective (scalar).
    p : casadi.SX
        NLP parameters: the model parameter vector (np,).
    p_model : casadi.SX
        The model parameter vector with the free parameters replaced by their NLP variables.
    lbw, ubw, scale, lbg, ubg : numpy.ndarray
        Bounds of ``w`` (scaled), the nominal of each entry of ``w``, bounds of ``g``.
    blocks : list of tuple
        ``(kind, element, root index)`` of each variable block, in order; kinds ``x``,
        ``tf``, ``z``, ``u``, ``pf``.
    offsets : dict
        First index in ``w`` of each block.
    rows_point : list of tuple
        ``(k, j, first row)`` of the model equations and path constraints at collocation
        point ``j`` (1-based) of element ``k``.
    rows_cont : list of tuple
        ``(k, first row)`` of the continuity of the states from element ``k`` to ``k + 1``.
    rows_tf : list of tuple
        ``(k, row)`` of ``tf_{k+1} - tf_k = 0``.
    ends : list of tuple
        ``(first row, expression)`` of the point constraints at the start and final time.
    mayer : casadi.SX
        The Mayer term.
    xc, uc, zc, xn, tf : casadi.SX
        The states (nx, N (d + 1)), inputs and algebraics (., N d), final state, final time.
    point_fn, lagr_fn : casadi.Function
        ``(t, x, z, u, p, tf) -> (ode, alg, path)`` and the Lagrange integrand.
    npath : int
        Path constraints per point.
    block_sizes : list of int
        Size of each block of :attr:`blocks`.
    special : casadi.SX
        The values of the timed variables and integrals (``Optimization.special_symbols``
        order) as expressions of ``w`` and ``p``.
    """

    w: ca.SX
    g: ca.SX
    f: ca.SX
    p: ca.SX
    p_model: ca.SX
    lbw: np.ndarray
    ubw: np.ndarray
    scale: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    blocks: list
    offsets: dict
    rows_point: list
    rows_cont: list
    rows_tf: list
    ends: list
    mayer: ca.SX
    xc: ca.SX
    uc: ca.SX
    zc: ca.SX
    xn: ca.SX
    tf: ca.SX
    point_fn: ca.Function
    lagr_fn: ca.Function
    npath: int
    block_sizes: list = field(default_factory=list)
    special: ca.SX = field(default_factory=lambda: ca.SX(0, 1))


def element_scaling(N: int, fractions: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """Per element ``n_k`` and ``c_k`` with ``h_k = (tf - t0) / n_k`` and ``t_kj = t0 + (c_k + tau_j) h_k``.

    A uniform mesh has ``n_k = N`` and ``c_k = k`` (exactly); a mesh of fractions ``f_k``
    has ``n_k = 1 / f_k`` and ``c_k = (f_0 + ... + f_{k-1}) / f_k``.

    Parameters
    ----------
    N : int
        Elements.
    fractions : numpy.ndarray or None
        Element lengths as fractions of the horizon, shape ``(N,)``; None for uniform.

    Returns
    -------
    tuple of numpy.ndarray
        ``(n, c)``, each of shape ``(N,)``.
    """
    if fractions is None:
        return np.full(N, float(N)), np.arange(N, dtype=float)
    f = np.asarray(fractions, dtype=float)
    cum = np.concatenate([[0.0], np.cumsum(f)[:-1]])
    return 1.0 / f, cum / f


def transcribe(
    opt: Optimization,
    dae: FlatDAE,
    N: int,
    d: int,
    co: Mapping[str, np.ndarray],
    noms: Mapping[str, np.ndarray],
    free_index: np.ndarray,
    inline_points: bool,
    final_time_copies: bool = True,
    fractions: np.ndarray | None = None,
) -> CollocationNLP:
    """Transcribe ``opt`` by direct collocation (see the module docstring).

    Parameters
    ----------
    opt : Optimization
        The problem.
    dae : FlatDAE
        Its flattened model.
    N, d : int
        Elements and collocation points per element.
    co : mapping
        From :func:`collocation_coefficients`.
    noms : mapping
        Nominal vectors ``{"x", "z", "u", "tf", "pf"}`` (the NLP works with ``value / nominal``).
    free_index : numpy.ndarray of int
        Indices in the model parameter vector of the free parameter elements.
    inline_points : bool
        Copy the per-point expression graph into the NLP (True) or call it (False).
    final_time_copies : bool, optional
        A copy of a free final time per element tied by equalities (banded KKT matrix;
        default), or one variable shared by all elements, placed after the final state.
    fractions : numpy.ndarray or None, optional
        Element lengths as fractions of the horizon, shape ``(N,)``, summing to 1 (a
        refined mesh); default uniform.

    Returns
    -------
    CollocationNLP
    """
    nx, nz, nu = dae.nx, dae.nz, dae.nu
    t0 = opt.start_time
    args = [dae.t, dae.x, dae.z, dae.u, dae.p, opt.final_time]

    def subst(e: ca.SX) -> ca.SX:
        return ca.substitute(e, dae.xdot, dae.ode_expr) if dae.nx else e

    def fn(name: str, exprs: list[ca.SX]) -> ca.Function:
        e = ca.vertcat(*exprs) if exprs else ca.SX(0, 1)
        return ca.Function(name, args, [subst(e)])

    start_c = [c for c in opt.point_constraints if c.at == "start"]
    final_c = [c for c in opt.point_constraints if c.at == "final"]
    timed_c = [c for c in opt.point_constraints if c.at == "timed"]
    start_fn = fn("point_start", [c.expr for c in start_c])
    final_fn = fn("point_final", [c.expr for c in final_c])
    sign = opt.objective_sign  # the NLP minimises sign * objective
    lagr_fn = fn("lagrange", [sign * opt.lagrange])
    # what is imposed at each collocation point: the model equations and the path
    # constraints, one function with common subexpressions (kinematics, mass matrix) once
    path_expr = subst(ca.vertcat(*[c.expr for c in opt.path_constraints])) if opt.path_constraints else ca.SX(0, 1)
    point_out = ca.cse([dae.ode_expr, dae.alg_expr, path_expr])
    point_fn = ca.Function("point", args, point_out)
    point_call = point_fn if inline_points else ca.Function("point_call", args, point_out, {"never_inline": True})

    P_nlp = dae.p
    npf = int(free_index.size)
    PF_sym = ca.SX.sym("pf", npf)
    if npf:
        elems = [P_nlp[i] for i in range(int(P_nlp.numel()))]
        for k, i in enumerate(free_index):
            elems[int(i)] = PF_sym[k] * float(noms["pf"][k])
        P = ca.vertcat(*elems)
    else:
        P = P_nlp
    free = opt.free_final_time
    tf_nom = float(noms["tf"][0])
    x_lb, x_ub = opt.bounds_vectors(dae, "x")
    z_lb, z_ub = opt.bounds_vectors(dae, "z")
    u_lb, u_ub = opt.bounds_vectors(dae, "u")
    tf_lb = np.array([opt.final_time_bounds[0]]) if free else np.zeros(1)
    tf_ub = np.array([opt.final_time_bounds[1]]) if free else np.zeros(1)

    w: list[ca.SX] = []
    lbw: list[np.ndarray] = []
    ubw: list[np.ndarray] = []
    scale: list[np.ndarray] = []
    blocks: list[tuple[str, int, int]] = []
    offsets: dict[tuple[str, int, int], int] = {}
    g: list[ca.SX] = []
    lbg: list[np.ndarray] = []
    ubg: list[np.ndarray] = []
    n_w = [0]
    n_g = [0]

    def var(kind: str, k: int, j: int, n: int, lb: np.ndarray, ub: np.ndarray) -> ca.SX:
        v = ca.SX.sym(f"{kind}_{k}_{j}", n)
        sc = noms[kind]
        offsets[(kind, k, j)] = n_w[0]
        n_w[0] += n
        w.append(v)
        lbw.append(lb / sc)
        ubw.append(ub / sc)
        scale.append(sc)
        blocks.append((kind, k, j))
        return v * ca.DM(sc) if np.any(sc != 1.0) else v

    def con(expr: ca.SX, lb: np.ndarray, ub: np.ndarray) -> int:
        first = n_g[0]
        if expr.numel():
            n_g[0] += int(expr.numel())
            g.append(expr)
            lbg.append(np.broadcast_to(lb, (expr.numel(),)).astype(float))
            ubg.append(np.broadcast_to(ub, (expr.numel(),)).astype(float))
        return first

    path_lb = np.concatenate([c.lb for c in opt.path_constraints]) if opt.path_constraints else np.zeros(0)
    path_ub = np.concatenate([c.ub for c in opt.path_constraints]) if opt.path_constraints else np.zeros(0)
    point_lb = np.concatenate([np.zeros(nx + nz), path_lb])
    point_ub = np.concatenate([np.zeros(nx + nz), path_ub])

    Xs: list[list[ca.SX]] = []
    Us: list[list[ca.SX]] = []
    Zs: list[list[ca.SX]] = []
    rows_point: list[tuple[int, int, int]] = []
    rows_cont: list[tuple[int, int]] = []
    rows_tf: list[tuple[int, int]] = []
    J = ca.SX(0)
    quadrature: list[tuple[PointArgs, ca.SX]] = []
    element_vars: list[tuple[list[ca.SX], list[ca.SX], list[ca.SX], ca.SX]] = []
    Xk0 = var("x", 0, 0, nx, x_lb, x_ub)
    copies = free and final_time_copies
    if copies:
        unbounded = N > 1
        Tk = var("tf", 0, 0, 1, np.full(1, -np.inf) if unbounded else tf_lb, np.full(1, np.inf) if unbounded else tf_ub)
    elif free:  # one shared variable, placed after the final state
        Tk = ca.SX.sym("tf_0_0") * tf_nom
    else:
        Tk = ca.SX(opt.final_time_value)
    T_first = Tk
    # plain floats: a NumPy scalar times an SX takes NumPy's slow ufunc dispatch
    n_el_a, c0_a = element_scaling(N, fractions)
    n_el, c0 = n_el_a.tolist(), c0_a.tolist()
    C, D, B, root = co["C"].tolist(), co["D"].tolist(), co["B"].tolist(), co["root"].tolist()
    for k in range(N):
        h = (Tk - t0) / n_el[k]
        Xk = [Xk0] + [var("x", k, j, nx, x_lb, x_ub) for j in range(1, d + 1)]
        Uk = [var("u", k, j, nu, u_lb, u_ub) for j in range(1, d + 1)]
        Zk = [var("z", k, j, nz, z_lb, z_ub) for j in range(1, d + 1)]
        Xs.append(Xk)
        Us.append(Uk)
        Zs.append(Zk)
        for j in range(1, d + 1):
            tkj = t0 + (c0[k] + root[j]) * h
            xp = sum(C[r][j] * Xk[r] for r in range(d + 1) if C[r][j] != 0.0)
            fkj, akj, pkj = point_call(tkj, Xk[j], Zk[j - 1], Uk[j - 1], P, Tk)
            first = con(ca.vertcat(h * fkj - xp, akj, pkj), point_lb, point_ub)
            rows_point.append((k, j, first))
            J = J + B[j - 1] * h * lagr_fn(tkj, Xk[j], Zk[j - 1], Uk[j - 1], P, Tk)
            quadrature.append((PointArgs(tkj, Xk[j], Zk[j - 1], Uk[j - 1], Tk), B[j - 1] * h))
        element_vars.append((Xk, Uk, Zk, Tk))
        xend = sum(D[r] * Xk[r] for r in range(d + 1) if D[r] != 0.0)
        Xk0 = var("x", k + 1, 0, nx, x_lb, x_ub)
        rows_cont.append((k, con(Xk0 - xend, np.zeros(1), np.zeros(1))))
        if copies and k < N - 1:
            # only the last copy is bounded: one barrier term for the final time, as with a
            # single variable (N bounded copies would change the barrier problems' path)
            last = k + 1 == N - 1
            Tn = var("tf", k + 1, 0, 1, tf_lb if last else np.full(1, -np.inf), tf_ub if last else np.full(1, np.inf))
            rows_tf.append((k, con((Tn - Tk) / tf_nom, np.zeros(1), np.zeros(1))))
            Tk = Tn
    XN, T = Xk0, Tk
    if free and not copies:
        offsets[("tf", 0, 0)] = n_w[0]
        offsets.update({("tf", k, 0): n_w[0] for k in range(N)})
        n_w[0] += 1
        w.append(ca.symvar(Tk)[0])
        lbw.append(tf_lb / tf_nom)
        ubw.append(tf_ub / tf_nom)
        scale.append(np.array([tf_nom]))
        blocks.append(("tf", 0, 0))
    if npf:
        pf_lb = np.concatenate([lb for lb, _, _ in opt.free_parameters.values()])
        pf_ub = np.concatenate([ub for _, ub, _ in opt.free_parameters.values()])
        offsets[("pf", 0, 0)] = n_w[0]
        n_w[0] += npf
        w.append(PF_sym)
        lbw.append(pf_lb / noms["pf"])
        ubw.append(pf_ub / noms["pf"])
        scale.append(noms["pf"])
        blocks.append(("pf", 0, 0))

    def extrap(vals: list[ca.SX], weights: np.ndarray, n: int) -> ca.SX:
        return sum(weights[j] * vals[j] for j in range(d)) if n else ca.SX(0, 1)

    u_start, z_start = extrap(Us[0], co["L0"], nu), extrap(Zs[0], co["L0"], nz)
    u_final, z_final = extrap(Us[-1], co["L1"], nu), extrap(Zs[-1], co["L1"], nz)
    ends: list[tuple[int, ca.SX]] = []
    if start_c:
        e = start_fn(t0, Xs[0][0], z_start, u_start, P, T_first)
        ends.append((con(e, np.concatenate([c.lb for c in start_c]), np.concatenate([c.ub for c in start_c])), e))
    if final_c:
        e = final_fn(T, XN, z_final, u_final, P, T)
        ends.append((con(e, np.concatenate([c.lb for c in final_c]), np.concatenate([c.ub for c in final_c])), e))
    start_args = PointArgs(ca.SX(t0), Xs[0][0], z_start, u_start, T_first)
    final_args = PointArgs(T, XN, z_final, u_final, T)
    s_sym, s_val = special_values(opt, fn, P, element_vars, (start_args, final_args), quadrature, co, fractions)

    def final_value(name: str, exprs: list[ca.SX]) -> ca.SX:
        """``exprs`` with model variables at the final time and timed variables/integrals by value."""
        f = ca.Function(name, [*args, s_sym], [subst(ca.vertcat(*exprs))])
        return f(T, XN, z_final, u_final, P, T, s_val)

    if timed_c:
        e = final_value("point_timed", [c.expr for c in timed_c])
        ends.append((con(e, np.concatenate([c.lb for c in timed_c]), np.concatenate([c.ub for c in timed_c])), e))
    mayer = final_value("mayer", [sign * opt.mayer])
    J = J + mayer
    cat = lambda parts: np.concatenate(parts) if parts else np.zeros(0)  # noqa: E731
    return CollocationNLP(
        w=ca.vertcat(*w),
        g=ca.vertcat(*g) if g else ca.SX(0, 1),
        f=J,
        p=P_nlp,
        p_model=P,
        lbw=cat(lbw),
        ubw=cat(ubw),
        scale=cat(scale),
        lbg=cat(lbg),
        ubg=cat(ubg),
        blocks=blocks,
        offsets=offsets,
        rows_point=rows_point,
        rows_cont=rows_cont,
        rows_tf=rows_tf,
        ends=ends,
        mayer=mayer,
        xc=ca.horzcat(*[ca.horzcat(*Xk) for Xk in Xs]),
        uc=ca.horzcat(*[ca.horzcat(*Uk) for Uk in Us]) if nu else ca.SX(0, N * d),
        zc=ca.horzcat(*[ca.horzcat(*Zk) for Zk in Zs]) if nz else ca.SX(0, N * d),
        xn=XN,
        tf=ca.vertcat(T),
        point_fn=point_fn,
        lagr_fn=lagr_fn,
        npath=int(path_expr.numel()),
        block_sizes=[int(b.numel()) for b in w],
        special=s_val,
    )
