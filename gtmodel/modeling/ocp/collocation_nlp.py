"""The collocation NLP of an :class:`~gtmodel.modeling.Optimization`: variables, constraints, layout.

Method (as in JModelica.org's LocalDAECollocator): the horizon is split into ``elements``
uniform elements; in each, states are polynomials of degree ``points`` through the
element start and the ``points`` collocation points (``casadi.collocation_points``,
Radau IIA or Gauss-Legendre); inputs and algebraic variables are NLP variables at the
collocation points only. States are continuous across elements. A free final time is
handled by time scaling ``t = t0 + tau (tf - t0)``.

The decision variables are ordered stage by stage: element ``k`` holds its start state,
its copy ``tf_k`` of a free final time, then the states, inputs and algebraic variables at
its collocation points; the last block is the final state, then the free parameters. The
copies are tied by ``tf_{k+1} = tf_k`` (linear equalities, the same optimum), so that
every constraint involves the variables of one or two neighbouring elements: the KKT
matrix is banded (a single shared final time is a dense row and column), which keeps the
sparse factorisation linear in the mesh and is the structure stage-wise solvers require.

The NLP is built from matrices with one column per element (the decision vector reshaped)
and the model equations, the Lagrange term and the integrals at all ``N d`` collocation
points are one mapped call each (``Function.map``): a few CasADi operations whatever the
mesh. At the start time (and, for Legendre, the final time), which is no collocation
point, the inputs are the first (last) element's polynomial and the algebraic variables
are made consistent with the states and inputs there (:func:`consistent_algebraics`), so
that a start condition on an algebraic variable constrains the motion, not an
extrapolation; the bounds of inputs and algebraic variables and the path constraints are
imposed there too. Built point by point in Python the same NLP cost 5 ms per point (hanging chain: 0.8 s, not 0.04 s).
"""

from __future__ import annotations

import functools
import logging
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.defaults import defaults
from gtmodel.errors import InputError
from gtmodel.modeling.dae import FlatDAE
from gtmodel.modeling.ocp.collocation_bounds import elements_in_spans, interior_state_bounds
from gtmodel.modeling.ocp.collocation_stages import stage_order
from gtmodel.modeling.ocp.optimization import Optimization
from gtmodel.modeling.ocp.result import lagrange_basis
from gtmodel.modeling.ocp.timed import PointArgs, special_values

_log = logging.getLogger("gtmodel")
__all__ = ["CASADI_OPTIONS", "IPOPT_DEFAULTS", "merge_options", "collocation_coefficients", "element_operators", "CollocationNLP", "transcribe", "element_scaling"]

#: CasADi-level nlpsol options passed through unchanged (others are options of the solver plugin).
CASADI_OPTIONS = {
    "print_time", "expand", "error_on_fail", "record_time", "verbose", "calc_lam_p", "calc_lam_x", "calc_f", "calc_g",
    "bound_consistency", "show_eval_warnings", "iteration_callback", "regularity_check", "structure_detection",
    "equality", "debug",
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
    return {key: value.copy() for key, value in _coefficients(int(d), str(scheme)).items()}


@functools.lru_cache(maxsize=32)
def _coefficients(d: int, scheme: str) -> dict[str, np.ndarray]:
    """:func:`collocation_coefficients`, computed once per ``(d, scheme)`` (a refined solve asks for them per pass)."""
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


def element_operators(co: Mapping[str, np.ndarray], nx: int) -> tuple[ca.DM, ca.DM]:
    """The collocation equations of one element as two sparse matrices on its stacked states.

    Parameters
    ----------
    co : mapping
        :func:`collocation_coefficients` of the scheme (its ``C`` and ``D``).
    nx : int
        States.

    Returns
    -------
    tuple of casadi.DM
        ``K_der (nx d, nx (d + 1))``: applied to ``[x_0; x_1; ...; x_d]`` (the element start and
        its points), the polynomial's derivative at the points, ``sum_r C[r, j] x_r``, which
        the collocation equations set to ``h f(t_j, x_j, ...)``; ``K_end (nx, nx (d + 1))``: its
        value at the element end, ``sum_r D[r] x_r``, the next element's start.
    """
    eye = np.eye(int(nx))
    K_der = ca.DM(ca.sparsify(ca.DM(np.kron(np.asarray(co["C"], dtype=float)[:, 1:].T, eye))))
    return K_der, ca.DM(ca.sparsify(ca.DM(np.kron(np.asarray(co["D"], dtype=float)[None, :], eye))))


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
    consistent : casadi.Function or None
        :func:`consistent_algebraics` of the model (the algebraic variables at a point that
        is no collocation point).
    stages : dict or None
        With ``stagewise``: the stage structure of fatrop (``N`` and the per-stage state,
        control and path-constraint counts ``nx``, ``nu``, ``ng``, each of length ``N + 1``).
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
    consistent: ca.Function | None = None
    stages: dict | None = None


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
    stagewise: bool = False,
    bound_points: int = 0,
    bound_spans: list[tuple[float, float]] | None = None,
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
    stagewise : bool, optional
        Order the constraints as fatrop's optimal-control structure requires (see
        :func:`~gtmodel.modeling.ocp.collocation_stages.stage_order`): per element first the gap-closing equalities (continuity of
        the states and the final-time copy, ``x_{k+1} - F(x_k, u_k)``, unit coefficient on the
        next element's variables), then the collocation equations, path constraints and
        the element's point constraints; the point constraints at the final time and the
        Mayer term read the last element's end state (equal to the final state wherever the
        continuity holds). Needs ``final_time_copies`` and no free parameters. Default False.
    bound_points : int, optional
        Extra points per element at which the state bounds hold on the polynomial too
        (:func:`~gtmodel.modeling.ocp.collocation_bounds.interior_state_bounds`); 0 (default):
        at the collocation points only. Not with ``stagewise`` (logged).
    bound_spans : list of tuple of (float, float), optional
        With ``bound_points``: only the elements overlapping these fractions of the horizon get them.

    Returns
    -------
    CollocationNLP

    Raises
    ------
    InputError
        ``stagewise`` with free parameters (shared by all stages).
    """
    nx, nz, nu = dae.nx, dae.nz, dae.nu
    t0 = opt.start_time
    if stagewise and free_index.size:
        raise InputError("solver fatrop: free parameters are shared by all elements, which fatrop's stage structure cannot hold")
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
    free = opt.free_final_time
    tf_nom = float(noms["tf"][0])
    x_lb, x_ub = opt.bounds_vectors(dae, "x")
    z_lb, z_ub = opt.bounds_vectors(dae, "z")
    u_lb, u_ub = opt.bounds_vectors(dae, "u")
    tf_lb = np.array([opt.final_time_bounds[0]]) if free else np.zeros(1)
    tf_ub = np.array([opt.final_time_bounds[1]]) if free else np.zeros(1)

    path_lb = np.concatenate([c.lb for c in opt.path_constraints]) if opt.path_constraints else np.zeros(0)
    path_ub = np.concatenate([c.ub for c in opt.path_constraints]) if opt.path_constraints else np.zeros(0)
    point_lb = np.concatenate([np.zeros(nx + nz), path_lb])
    point_ub = np.concatenate([np.zeros(nx + nz), path_ub])

    # ---- the layout of w (numbers only): per element k the blocks x_k0, tf_k (copies of a
    # free final time), x_kj, u_kj, z_kj (j = 1..d); then x_N0, a shared tf, the free parameters
    copies = free and final_time_copies
    ntf = 1 if copies else 0
    se = nx + ntf + d * (nx + nu + nz)
    blocks: list[tuple[str, int, int]] = []
    offsets: dict[tuple[str, int, int], int] = {}
    sizes: list[int] = []
    lbw_l: list[np.ndarray] = []
    ubw_l: list[np.ndarray] = []
    scale_l: list[np.ndarray] = []
    pos = 0

    def block(kind: str, k: int, j: int, n: int, lb: np.ndarray, ub: np.ndarray, sc: np.ndarray) -> None:
        nonlocal pos
        offsets[(kind, k, j)] = pos
        blocks.append((kind, k, j))
        sizes.append(n)
        lbw_l.append(lb / sc)
        ubw_l.append(ub / sc)
        scale_l.append(sc)
        pos += n

    unbounded = np.full(1, -np.inf), np.full(1, np.inf)
    for k in range(N):
        block("x", k, 0, nx, x_lb, x_ub, noms["x"])
        if copies:  # only the last copy is bounded: one barrier term for the final time, as with
            # a single variable (N bounded copies would change the barrier problems' path)
            lo, hi = (tf_lb, tf_ub) if k == N - 1 else unbounded
            block("tf", k, 0, 1, lo, hi, noms["tf"])
        for kind, n, lb, ub in (("x", nx, x_lb, x_ub), ("u", nu, u_lb, u_ub), ("z", nz, z_lb, z_ub)):
            for j in range(1, d + 1):
                block(kind, k, j, n, lb, ub, noms[kind])
    block("x", N, 0, nx, x_lb, x_ub, noms["x"])
    if free and not copies:  # one shared variable, placed after the final state
        offsets.update({("tf", k, 0): pos for k in range(1, N)})
        block("tf", 0, 0, 1, tf_lb, tf_ub, np.array([tf_nom]))
    if npf:
        pf_lb = np.concatenate([lb for lb, _, _ in opt.free_parameters.values()])
        pf_ub = np.concatenate([ub for _, ub, _ in opt.free_parameters.values()])
        block("pf", 0, 0, npf, pf_lb, pf_ub, noms["pf"])
    nw = pos

    # ---- the symbols, as matrices with one column per element (a few CasADi operations
    # whatever the mesh: the per-point work is one mapped call of the point function)
    w_sym = ca.SX.sym("w", nw)
    P = P_nlp
    if npf:  # the model parameter vector with the free parameters replaced by their NLP variables
        elems = [P_nlp[i] for i in range(int(P_nlp.numel()))]
        for k, i in enumerate(free_index):
            elems[int(i)] = w_sym[nw - npf + k] * float(noms["pf"][k])
        P = ca.vertcat(*elems)
    E = ca.reshape(w_sym[0:N * se], se, N)

    def scaled(m: ca.SX, sc: np.ndarray, reps: int) -> ca.SX:
        """``m`` (reps * len(sc) x N) times its nominals (the NLP works with value / nominal)."""
        if not m.numel() or np.all(sc == 1.0):
            return m
        return m * ca.DM(np.tile(np.tile(np.asarray(sc, dtype=float), reps)[:, None], (1, m.shape[1])))

    o = nx + ntf
    X0 = scaled(E[0:nx, :], noms["x"], 1)
    Xp = scaled(E[o:o + d * nx, :], noms["x"], d)
    Up = scaled(E[o + d * nx:o + d * (nx + nu), :], noms["u"], d)
    Zp = scaled(E[o + d * (nx + nu):se, :], noms["z"], d)
    XN = scaled(ca.reshape(w_sym[N * se:N * se + nx], nx, 1), noms["x"], 1)  # (nx, 1) also of a 1 x 1 w_sym
    n_el_a, c0_a = element_scaling(N, fractions)
    if copies:
        Trow = E[nx:nx + 1, :] * tf_nom if tf_nom != 1.0 else E[nx:nx + 1, :]
    elif free:
        Tsh = w_sym[offsets[("tf", 0, 0)]] * tf_nom
        Trow = ca.repmat(Tsh, 1, N)
    else:
        Trow = ca.SX(ca.DM(np.full((1, N), float(opt.final_time_value))))
    T_first, T = Trow[0, 0], Trow[0, N - 1]
    h_row = (Trow - t0) / ca.DM(n_el_a[None, :])
    M = N * d

    def per_point(row: ca.SX) -> ca.SX:
        """An element row (1 x N) repeated at its d points (1 x N d, element-major)."""
        return ca.reshape(ca.repmat(row, d, 1), 1, M)

    root = np.asarray(co["root"], dtype=float)
    t_pts = t0 + ca.reshape(ca.DM(c0_a[None, :] + root[1:, None]) * ca.repmat(h_row, d, 1), 1, M)
    h_pts, T_pts = per_point(h_row), per_point(Trow)
    X_pts = ca.reshape(Xp, nx, M)
    U_pts = ca.reshape(Up, nu, M)
    Z_pts = ca.reshape(Zp, nz, M)
    X_all = ca.vertcat(X0, Xp)  # (nx (d + 1), N): the element start, then its points
    K_der, K_end = element_operators(co, nx)
    xp = ca.reshape(ca.mtimes(K_der, X_all), nx, M)
    F, A_alg, P_path = point_call.map(M)(t_pts, X_pts, Z_pts, U_pts, P, T_pts)
    R = ca.vertcat(ca.repmat(h_pts, nx, 1) * F - xp, A_alg, P_path)  # (nr, M)
    nr = int(R.shape[0])
    cont = ca.horzcat(X0[:, 1:], XN) - ca.mtimes(K_end, X_all)
    if stagewise:  # fatrop's gap-closing form x_{k+1} - F(x_k, u_k): unit coefficient on the scaled next state
        cont = cont / ca.DM(np.tile(np.asarray(noms["x"], dtype=float)[:, None], (1, N)))
    parts = [ca.reshape(R, nr * d, N), cont]
    if copies:
        tie = E[nx:nx + 1, 1:] - E[nx:nx + 1, :N - 1] if stagewise else (Trow[0, 1:] - Trow[0, :N - 1]) / tf_nom
        parts.append(ca.horzcat(tie, ca.SX(1, 1)))
    g_el = ca.vec(ca.vertcat(*parts))
    n_gel = N * (nr * d + nx + ntf) - ntf  # the last element has no copy to tie
    g_el = g_el[0:n_gel]
    el_lb = np.concatenate([np.tile(point_lb, d), np.zeros(nx + ntf)])
    el_ub = np.concatenate([np.tile(point_ub, d), np.zeros(nx + ntf)])
    g: list[ca.SX] = [g_el]
    lbg: list[np.ndarray] = [np.tile(el_lb, N)[:n_gel]]
    ubg: list[np.ndarray] = [np.tile(el_ub, N)[:n_gel]]
    size_el = nr * d + nx + ntf
    rows_point = [(k, j, k * size_el + (j - 1) * nr) for k in range(N) for j in range(1, d + 1)]
    rows_cont = [(k, k * size_el + nr * d) for k in range(N)]
    rows_tf = [(k, k * size_el + nr * d + nx) for k in range(N - 1)] if copies else []
    n_g = [n_gel]

    def con(expr: ca.SX, lb: np.ndarray, ub: np.ndarray) -> int:
        first = n_g[0]
        if expr.numel():
            n_g[0] += int(expr.numel())
            g.append(expr)
            lbg.append(np.broadcast_to(lb, (expr.numel(),)).astype(float))
            ubg.append(np.broadcast_to(ub, (expr.numel(),)).astype(float))
        return first

    weights_pts = ca.DM(np.tile(np.asarray(co["B"], dtype=float), N)[None, :]) * h_pts  # quadrature B_j h_k
    J = ca.mtimes(lagr_fn.map(M)(t_pts, X_pts, Z_pts, U_pts, P, T_pts), weights_pts.T)

    L0, L1 = ca.DM(np.asarray(co["L0"], dtype=float)), ca.DM(np.asarray(co["L1"], dtype=float))
    # the inputs at the start (and a Legendre final time), no collocation points: the element's
    # polynomial through its points, extrapolated (as the verification's simulation applies it)
    u_start = ca.mtimes(U_pts[:, 0:d], L0) if nu else ca.SX(0, 1)
    u_final = ca.mtimes(U_pts[:, M - d:M], L1) if nu else ca.SX(0, 1)
    consistent = consistent_algebraics(dae, opt.final_time, subst)
    z_start = consistent(t0, X0[:, 0], ca.mtimes(Z_pts[:, 0:d], L0), u_start, P, T_first) if nz else ca.SX(0, 1)
    z_final = (consistent(T, XN, ca.mtimes(Z_pts[:, M - d:M], L1), u_final, P, T) if nz and float(co["root"][-1]) != 1.0
               else ca.mtimes(Z_pts[:, M - d:M], L1) if nz else ca.SX(0, 1))
    ends: list[tuple[int, ca.SX]] = []
    at: list[str] = []  # the stage of each of ``ends`` for fatrop's order: "start" (element 0) or "final" (element N - 1)
    # the path constraints and the bounds of the algebraic variables hold at the start too (the
    # tables write its consistent values; the collocation points impose them everywhere else)
    if path_lb.size:
        e = point_fn(t0, X0[:, 0], z_start, u_start, P, T_first)[2]
        ends.append((con(e, path_lb, path_ub), e))
        at.append("start")
    extrapolated = [("start", z_start, z_lb, z_ub), ("start", u_start, u_lb, u_ub)]
    if float(co["root"][-1]) != 1.0:  # Legendre: the final time is no collocation point either
        extrapolated += [("final", z_final, z_lb, z_ub), ("final", u_final, u_lb, u_ub)]
    for where, vals, lo, hi in extrapolated:  # the bounds of inputs and algebraics hold there too
        bounded = np.flatnonzero(np.isfinite(lo) | np.isfinite(hi)) if vals.numel() else np.zeros(0, dtype=int)
        if bounded.size:
            e = vals[bounded.tolist()]
            ends.append((con(e, lo[bounded], hi[bounded]), e))
            at.append(where)
    if start_c:
        e = start_fn(t0, X0[:, 0], z_start, u_start, P, T_first)
        ends.append((con(e, np.concatenate([c.lb for c in start_c]), np.concatenate([c.ub for c in start_c])), e))
        at.append("start")
    # the final state as the final constraints and the Mayer term see it: with ``stagewise``
    # the last element's end state (a variable of stage N - 1, as are u_final, z_final, T)
    XF = ca.mtimes(K_end, X_all[:, N - 1]) if stagewise else XN
    if final_c:
        e = final_fn(T, XF, z_final, u_final, P, T)
        ends.append((con(e, np.concatenate([c.lb for c in final_c]), np.concatenate([c.ub for c in final_c])), e))
        at.append("final")
    if bound_points and stagewise:
        _log.info("collocation of %s: no state bounds between the points with fatrop", dae.name)
    elif bound_points:  # the state bounds between the points too (the rows the refinement adds)
        where = None if bound_spans is None else elements_in_spans(np.full(N, 1.0 / N) if fractions is None else fractions, bound_spans)
        e, lo, hi = interior_state_bounds(X_all, nx, co["root"], x_lb, x_ub, noms["x"], bound_points, where)
        if e.numel():
            ends.append((con(e, lo, hi), e))
    start_args = PointArgs(ca.SX(t0), X0[:, 0], z_start, u_start, T_first)
    final_args = PointArgs(T, XF, z_final, u_final, T)
    element_vars = _ElementVars(X_all, Up, Zp, Trow, nx, nu, nz, d)
    quadrature = (PointArgs(t_pts, X_pts, Z_pts, U_pts, T_pts), weights_pts)
    s_sym, s_val = special_values(opt, fn, P, element_vars, (start_args, final_args), quadrature, co, fractions)

    def final_value(name: str, exprs: list[ca.SX]) -> ca.SX:
        """``exprs`` with model variables at the final time and timed variables/integrals by value."""
        f = ca.Function(name, [*args, s_sym], [subst(ca.vertcat(*exprs))])
        return f(T, XF, z_final, u_final, P, T, s_val)

    if timed_c:
        e = final_value("point_timed", [c.expr for c in timed_c])
        ends.append((con(e, np.concatenate([c.lb for c in timed_c]), np.concatenate([c.ub for c in timed_c])), e))
        at.append("final")
    mayer = final_value("mayer", [sign * opt.mayer])
    J = J + mayer
    cat = lambda parts: np.concatenate(parts) if parts else np.zeros(0)  # noqa: E731
    g_all, lbg_all, ubg_all, stages = ca.vertcat(*g), cat(lbg), cat(ubg), None
    if stagewise:
        order, stages = stage_order(N, nr * d, nx, ntf, [(first, int(e.numel())) for first, e in ends], at)
        inverse = np.empty(order.size, dtype=int)
        inverse[order] = np.arange(order.size)
        g_all, lbg_all, ubg_all = g_all[order.tolist()], lbg_all[order], ubg_all[order]
        rows_point = [(k, j, int(inverse[r])) for k, j, r in rows_point]
        rows_cont = [(k, int(inverse[r])) for k, r in rows_cont]
        rows_tf = [(k, int(inverse[r])) for k, r in rows_tf]
        ends = [(int(inverse[first]), e) for first, e in ends]
        stages["nx"] = [nx + ntf] * N + [nx]
        stages["nu"] = [d * (nx + nu + nz)] * N + [0]
    return CollocationNLP(
        w=w_sym,
        g=g_all,
        f=J,
        p=P_nlp,
        p_model=P,
        lbw=cat(lbw_l),
        ubw=cat(ubw_l),
        scale=cat(scale_l),
        lbg=lbg_all,
        ubg=ubg_all,
        blocks=blocks,
        offsets=offsets,
        rows_point=rows_point,
        rows_cont=rows_cont,
        rows_tf=rows_tf,
        ends=ends,
        mayer=mayer,
        xc=ca.reshape(X_all, nx, N * (d + 1)),
        uc=U_pts if nu else ca.SX(0, M),
        zc=Z_pts if nz else ca.SX(0, M),
        xn=XN,
        tf=ca.vertcat(T),
        point_fn=point_fn,
        lagr_fn=lagr_fn,
        npath=int(path_expr.numel()),
        block_sizes=sizes,
        special=s_val,
        consistent=consistent,
        stages=stages,
    )


#: Newton steps of :func:`consistent_algebraics` (exact after the first for algebraic
#: equations linear in the algebraic variables, as those of composed components are).
CONSISTENCY_NEWTON_STEPS = 2


def consistent_algebraics(dae: FlatDAE, final_time: ca.SX, subst: Any) -> ca.Function:
    """The algebraic variables at a point that is no collocation point, consistent with the states there.

    The transcription has algebraic variables at the collocation points only; at the start
    time (and, for Legendre, the final time) their polynomial's extrapolation ``z_e`` does
    not satisfy the algebraic equations ``0 = g(t, x, z, u, p)`` with the states there, so a
    condition on an algebraic variable (a load's speed tied to the motor's by a gear) would
    hold on the extrapolation and not on the motion. This function takes
    :data:`CONSISTENCY_NEWTON_STEPS` Newton steps on ``g`` in ``z`` from ``z_e``:
    ``z <- z - (dg/dz)^-1 g(t, x, z, u, p)`` (the initialisation system of the index-1 DAE
    at that point, the states and inputs given; the DAE is index 1, so ``dg/dz`` is
    regular).

    Parameters
    ----------
    dae : FlatDAE
        The flat (index-1) model.
    final_time : casadi.SX
        The final-time symbol of the optimisation.
    subst : callable
        Replaces ``der()`` of the states by the right-hand side.

    Returns
    -------
    casadi.Function
        ``(t, x, z_e, u, p, final_time) -> z`` (column vectors of the model's sizes).
    """
    g = subst(dae.alg_expr)
    g_jac = ca.jacobian(g, dae.z)
    z = dae.z
    for _ in range(CONSISTENCY_NEWTON_STEPS):
        z = z - ca.solve(ca.substitute(g_jac, dae.z, z), ca.substitute(g, dae.z, z))
    return ca.Function("consistent_algebraics", [dae.t, dae.x, dae.z, dae.u, dae.p, final_time], [z])


class _ElementVars:
    """The element variables of the NLP as :func:`~gtmodel.modeling.ocp.timed.special_values` reads them:
    the states at the start and the ``d`` points of each element ``X_all`` ``(nx (d + 1), N)``,
    the inputs and algebraics at the points ``Up`` ``(nu d, N)``, ``Zp``, the element final
    times ``Trow`` ``(1, N)``."""

    def __init__(self, X_all: ca.SX, Up: ca.SX, Zp: ca.SX, Trow: ca.SX, nx: int, nu: int, nz: int, d: int) -> None:
        self._m, self._n, self._d = (X_all, Up, Zp, Trow), (nx, nu, nz), d

    def __len__(self) -> int:
        return int(self._m[3].shape[1])

    def interpolate(self, ks: np.ndarray, lx: np.ndarray, lu: np.ndarray) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
        """States, inputs, algebraics ``(n., n)`` and final times ``(1, n)`` in elements ``ks`` with weights ``lx`` ``(d + 1, n)``, ``lu`` ``(d, n)``."""
        (X_all, Up, Zp, Trow), (nx, nu, nz), d = self._m, self._n, self._d
        cols = [int(k) for k in ks]

        def combine(m: ca.SX, n: int, weights: np.ndarray) -> ca.SX:
            if not n:
                return ca.SX(0, len(cols))
            sel = m[:, cols]
            out = None
            for r in range(weights.shape[0]):
                term = sel[r * n:(r + 1) * n, :] * ca.DM(np.tile(weights[r][None, :], (n, 1)))
                out = term if out is None else out + term
            return out

        return combine(X_all, nx, lx), combine(Up, nu, lu), combine(Zp, nz, lu), Trow[:, cols]
