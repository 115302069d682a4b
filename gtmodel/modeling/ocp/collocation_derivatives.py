"""Constraint Jacobian and Lagrangian Hessian of a collocation NLP, assembled from per-point derivatives.

At collocation point ``(k, j)`` the nonlinear constraints ``h f(t, x, z, u), g_alg, path``
and the Lagrange term depend only on that point's ``x, z, u``, on the element's copy of
the final time and on the free parameters; the collocation polynomial, continuity and
final-time-copy terms are linear with constant coefficients. So the point functions are
differentiated once by CasADi AD (small expressions), evaluated at all points in one
``Function.map`` call, and their values placed into the sparse NLP matrices by one
constant sparse matrix product: the evaluation costs the same per point at any mesh
size. The point derivatives can be compiled to C (:func:`gtmodel._compiler.compiled_function`,
cached by a hash of the generated source, so the compiler runs once per model and the
cache serves every mesh size and every later process). The point constraints at the start
and final time and the Mayer term (few) are differentiated directly.

The same assembly serves both NLP solvers: IPOPT takes ``jac_g`` and the upper triangle of
the Hessian (nlpsol's ``jac_g``/``hess_lag`` options); fatrop (the NLP ordered stage by
stage) takes ``jac_g`` and the whole symmetric Hessian with the Lagrangian's gradient
(``nlp_hess_l``, passed through nlpsol's function ``cache``: its plugin has no
``hess_lag`` option), from the same point functions and the same compiled libraries.
"""

from __future__ import annotations

import logging
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._compiler import compiled_function
from gtmodel.modeling.ocp.collocation_nlp import CollocationNLP, element_scaling
from gtmodel.modeling.dae import casadi_name
from gtmodel.modeling.ocp.optimization import Optimization

__all__ = ["assembled_derivatives", "assembled_oracle", "COMPILE_FLAGS"]

_log = logging.getLogger("gtmodel")

#: Flags of the compiled point derivatives. The L1 robot's point Hessian (issue 17, one
#: loaded run): -O0 compiles in 1.0 s and evaluates in 18 us per point, -O1 in 2.7 s and
#: 12 us, -O2 in 3.6 s and 17 us (the CasADi interpreter: 90 us).
COMPILE_FLAGS = ("-O1", "-fPIC", "-shared")


def _sorted_unique(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``numpy.unique(keys, return_inverse=True)`` of integer keys, without importing ``numpy.ma`` (numpy 2.4's unique does)."""
    order = np.argsort(keys, kind="stable")
    k = keys[order]
    new = np.ones(k.size, dtype=bool)
    new[1:] = k[1:] != k[:-1]
    inverse = np.empty(k.size, dtype=np.int64)
    inverse[order] = np.cumsum(new) - 1
    return k[new], inverse


class _Assembly:
    """Triplets ``(row, col) += coefficient * value[source]`` of one sparse matrix (numpy arrays, added in bulk)."""

    def __init__(self) -> None:
        self.parts: list[tuple[np.ndarray, ...]] = []

    def add(self, row: Any, col: Any, source: Any, coefficient: Any = 1.0) -> None:
        """Add the triplets of the broadcast arrays ``row``, ``col``, ``source``, ``coefficient``."""
        r, c, s, v = np.broadcast_arrays(np.asarray(row, dtype=np.int64), np.asarray(col, dtype=np.int64),
                                         np.asarray(source, dtype=np.int64), np.asarray(coefficient, dtype=float))
        self.parts.append((r.ravel(), c.ravel(), s.ravel(), v.ravel()))

    def matrix(self, values: ca.MX, n_values: int, nrow: int, ncol: int) -> ca.MX:
        """The sparse ``nrow x ncol`` matrix whose nonzeros are ``S @ values``."""
        if not self.parts or not sum(p[0].size for p in self.parts):
            return ca.MX(nrow, ncol)
        r, c, s, v = (np.concatenate([p[i] for p in self.parts]) for i in range(4))
        keys, key_of = _sorted_unique(c * nrow + r)  # column-major, as CasADi stores
        sp = ca.Sparsity.triplet(nrow, ncol, (keys % nrow).tolist(), (keys // nrow).tolist())
        # S (len(keys) x n_values, CSC): S[i, source] = the sum of the coefficients of that
        # pair (duplicates summed as scipy.sparse's sum_duplicates does)
        nk = int(keys.size)
        entries, entry_of = _sorted_unique(s * nk + key_of)  # column-major, rows sorted within a column
        summed = np.zeros(entries.size)
        np.add.at(summed, entry_of, v)
        colind = np.concatenate([[0], np.cumsum(np.bincount(entries // nk, minlength=n_values))])
        S = ca.DM(ca.Sparsity(nk, n_values, colind.tolist(), (entries % nk).tolist()), summed)
        return ca.sparsity_cast(ca.mtimes(S, values), sp)


def _local_functions(nlp: CollocationNLP, opt: Optimization, dae: Any, N: int, noms: Any, free_index: np.ndarray) -> tuple:
    """Per-point ``jac(v) (nr, nv)`` and ``triu hess(v) (nv, nv)`` of the scaled point variables."""
    nx, nz, nu = dae.nx, dae.nz, dae.nu
    free = opt.free_final_time
    t0 = opt.start_time
    xs, zs, us = ca.SX.sym("xs", nx), ca.SX.sym("zs", nz), ca.SX.sym("us", nu)
    ts = ca.SX.sym("ts") if free else ca.SX(0, 1)
    npf = int(free_index.size)
    ps = ca.SX.sym("ps", npf)
    P = nlp.p
    if npf:
        elems = [P[i] for i in range(int(P.numel()))]
        for k, i in enumerate(free_index):
            elems[int(i)] = ps[k] * float(noms["pf"][k])
        P_loc = ca.vertcat(*elems)
    else:
        P_loc = P
    c, b, lam_f = ca.SX.sym("c"), ca.SX.sym("b"), ca.SX.sym("lam_f")
    nr = nx + nz + nlp.npath
    lam_r = ca.SX.sym("lam_r", nr)
    tn = ca.SX.sym("tf_nominal")  # an input: the compiled code serves every mesh size
    T = ts * tn if free else ca.SX(opt.final_time_value)
    n_el = ca.SX.sym("elements")
    h = (T - t0) / n_el
    t = t0 + c * h
    x, z, u = xs * ca.DM(noms["x"]), zs * ca.DM(noms["z"]), us * ca.DM(noms["u"])
    f, a, p = nlp.point_fn(t, x, z, u, P_loc, T)
    r = ca.vertcat(h * f, a, p)
    v = ca.vertcat(xs, zs, us, ts, ps)
    jac_r = ca.jacobian(r, v)
    lag = ca.dot(lam_r, r) + lam_f * b * h * nlp.lagr_fn(t, x, z, u, P_loc, T)
    hess_lag, grad_lag = ca.hessian(lag, v)
    local_in = [xs, zs, us, ts, ps, P, c, tn, n_el]
    names = ["xs", "zs", "us", "ts", "ps", "p", "c", "tf_nominal", "elements"]
    # the second outputs (the point's residuals, its Lagrangian's gradient) are fatrop's (constraints and
    # gradient in the same pass); IPOPT's calls leave them unused, one library serves both solvers
    jac_fn = ca.Function(f"{casadi_name(dae.name)}_point_jac", local_in, [jac_r, ca.densify(r)], names, ["jac", "r"])
    hess_fn = ca.Function(f"{casadi_name(dae.name)}_point_hess", local_in + [b, lam_f, lam_r], [ca.triu(hess_lag), ca.densify(grad_lag)],
                          names + ["b", "lam_f", "lam_r"], ["hess", "grad"])
    return jac_fn, hess_fn


def _nz(x: ca.MX) -> ca.MX:
    """The nonzeros of ``x`` as a column (CasADi's column-major order)."""
    return ca.sparsity_cast(x, ca.Sparsity.dense(x.nnz(), 1)) if x.nnz() else ca.MX(0, 1)


def assembled_oracle(nlp: CollocationNLP, f: ca.SX, name: str) -> tuple[dict[str, ca.MX], dict[str, ca.Function]]:
    """IPOPT's NLP for ``casadi.nlpsol`` when ``jac_g`` and ``hess_lag`` are assembled: calls of SX functions.

    With the derivatives given, nlpsol needs of the NLP's graph only ``f``, ``g`` and ``grad_f``.
    Given as SX, nlpsol builds several SX functions of the whole graph (0.25 CPU-s of the
    0.37 s build of dc_motor_min_energy's 200 elements); as MX calling an SX function of ``f``,
    one of ``g`` and one of ``(f, grad_f)``, 0.08 s, with the same values (the same expressions,
    evaluated by the same SX functions) and the same iterations. ``f`` and ``g`` are separate
    functions because IPOPT asks for them in separate calls (``nlp_f``, ``nlp_g``): from one
    function of ``(f, g)`` each objective evaluation also evaluated the model at every
    collocation point (on the L1's 50 elements 0.17 ms a call, as much as ``g``; its own graph,
    a few microseconds).

    Parameters
    ----------
    nlp : CollocationNLP
        The transcription (its ``w``, ``p``, ``g``).
    f : casadi.SX
        The objective as the solver minimises it (scalar).
    name : str
        A CasADi name prefix.

    Returns
    -------
    tuple of (dict, dict)
        ``{"x", "p", "f", "g"}`` (MX) for nlpsol, and ``{"grad_f": Function}`` for its options.
    """
    f_fn = ca.Function(f"{name}_f", [nlp.w, nlp.p], [f], ["x", "p"], ["f"])
    g_fn = ca.Function(f"{name}_g", [nlp.w, nlp.p], [nlp.g], ["x", "p"], ["g"])
    grad_f = ca.Function(f"{name}_grad_f", [nlp.w, nlp.p], [f, ca.gradient(f, nlp.w)], ["x", "p"], ["f", "grad_f_x"])
    x, p = ca.MX.sym("x", nlp.w.sparsity()), ca.MX.sym("p", nlp.p.sparsity())
    return {"x": x, "p": p, "f": f_fn(x, p), "g": g_fn(x, p)}, {"grad_f": grad_f}


def assembled_derivatives(
    nlp: CollocationNLP,
    opt: Optimization,
    dae: Any,
    N: int,
    d: int,
    co: Any,
    noms: Any,
    free_index: np.ndarray,
    compile: bool,
    fractions: np.ndarray | None = None,
    stagewise: bool = False,
) -> tuple[dict[str, ca.Function], str]:
    """The ``jac_g`` and ``hess_lag`` Functions of ``casadi.nlpsol`` for ``nlp`` (and fatrop's ``g``).

    Parameters
    ----------
    nlp : CollocationNLP
        From :func:`gtmodel.modeling.ocp.collocation_nlp.transcribe`.
    opt : Optimization
        The problem.
    dae : FlatDAE
        Its model.
    N, d : int
        Elements and points per element.
    co : mapping
        Collocation coefficients.
    noms : mapping
        Nominal vectors.
    free_index : numpy.ndarray of int
        Model-parameter indices of the free parameters.
    compile : bool
        Evaluate the point derivatives through compiled C (cached), else interpreted.
    fractions : numpy.ndarray or None, optional
        Element lengths as fractions of the horizon (a refined mesh); default uniform.
    stagewise : bool, optional
        ``nlp`` is fatrop's stage-wise transcription (``transcribe(..., stagewise=True)``:
        its continuity rows have a unit coefficient on the scaled states), and the Hessian
        is returned as fatrop's plugin asks for it (below). Default False (IPOPT's).

    Returns
    -------
    functions : dict of casadi.Function
        ``"jac_g"``: ``(x, p) -> (g, jac_g_x)``, named ``nlp_jac_g``. ``"hess_lag"``: named
        ``nlp_hess_l``; IPOPT's ``(x, p, lam_f, lam_g) -> triu_hess_gamma_x_x`` (the upper
        triangle); with ``stagewise`` ``(x, p, lam_f, lam_g) -> (grad_gamma_x,
        hess_gamma_x_x)``, the gradient ``lam_f grad f + jac_g' lam_g`` (from the point
        Hessians' own pass) and the whole symmetric Hessian of ``gamma = lam_f f + lam_g' g``.
        With ``stagewise`` also ``"g"``: ``(x, p) -> g``, named ``nlp_g``, assembled as the
        Jacobian is (the point residuals of the same compiled pass; IPOPT's ``g`` is the NLP graph's).
    how : str
        How the point derivatives are evaluated (compiled, cached, interpreted and why).
    """
    nx, nz, nu = dae.nx, dae.nz, dae.nu
    free = opt.free_final_time
    npf = int(free_index.size)
    nw, ng = int(nlp.w.numel()), int(nlp.g.numel())
    nr = nx + nz + nlp.npath
    nv = nx + nz + nu + (1 if free else 0) + npf
    offs = nlp.offsets
    jac_fn, hess_fn = _local_functions(nlp, opt, dae, N, noms, free_index)
    how = "CasADi interpreter"
    if compile:
        jac_fn, how_j = compiled_function(jac_fn, COMPILE_FLAGS, "collocation")
        hess_fn, how = compiled_function(hess_fn, COMPILE_FLAGS, "collocation")
        _log.debug("collocation point derivatives of %s: %s; %s", dae.name, how_j, how)
    M = len(nlp.rows_point)
    # per point: the columns of its local variables v = (x, z, u[, tf_k][, pf]) in w
    cols = np.zeros((M, nv), dtype=int)
    rows = np.zeros((M, nr), dtype=int)
    cpos = np.zeros(M)
    nel = np.zeros(M)
    n_el, c0 = element_scaling(N, fractions)
    bw = np.zeros(M)
    pf_cols = offs[("pf", 0, 0)] + np.arange(npf) if npf else np.zeros(0, dtype=int)
    for m, (k, j, first) in enumerate(nlp.rows_point):
        tf_col = [offs[("tf", k, 0)]] if free else []
        cols[m] = np.concatenate(
            [offs[("x", k, j)] + np.arange(nx), offs[("z", k, j)] + np.arange(nz), offs[("u", k, j)] + np.arange(nu), tf_col, pf_cols]
        )
        rows[m] = first + np.arange(nr)
        cpos[m] = c0[k] + co["root"][j]
        nel[m] = n_el[k]
        bw[m] = co["B"][j - 1]

    w = ca.MX.sym("x", nw)
    P = ca.MX.sym("p", int(nlp.p.numel()))
    lam_f = ca.MX.sym("lam_f")
    lam_g = ca.MX.sym("lam_g", ng)

    def gather(vec: ca.MX, idx: np.ndarray) -> ca.MX:
        n = idx.shape[1]
        if n == 0:
            return ca.MX(0, M)
        return ca.reshape(vec[idx.reshape(-1).tolist()], n, M)

    ends_t = ca.MX(0, 1) if not free else gather(w, cols[:, nx + nz + nu:nx + nz + nu + 1])
    args = [
        gather(w, cols[:, :nx]),
        gather(w, cols[:, nx:nx + nz]),
        gather(w, cols[:, nx + nz:nx + nz + nu]),
        ends_t if free else ca.MX(0, 1),
        w[pf_cols.tolist()] if npf else ca.MX(0, 1),
        P,
        ca.DM(cpos).T,
        float(noms["tf"][0]),
        float(N) if fractions is None else ca.DM(nel).T,
    ]
    jm, rm = jac_fn.map(M, "serial")(*args)
    hm, gm = hess_fn.map(M, "serial")(*args, ca.DM(bw).T, lam_f, gather(lam_g, rows))
    jr, jc = jac_fn.sparsity_out(0).get_triplet()
    hr, hc = hess_fn.sparsity_out(0).get_triplet()
    nj, nh = len(jr), len(hr)

    # the end point constraints and the Mayer term, differentiated directly in the few variables they read
    # (e_cols); for fatrop compiled as the point functions are (the start's path constraints are a point's: L1
    # robot, 89 us of the Hessian's 400 interpreted). IPOPT's stay interpreted: a timed constraint or an
    # integral reads the mesh, and a compiled library per mesh size would cost IPOPT more than it gains.
    e_all = ca.vertcat(*[e for _, e in nlp.ends]) if nlp.ends else ca.SX(0, 1)
    e_rows = np.concatenate([first + np.arange(int(e.numel())) for first, e in nlp.ends]) if nlp.ends else np.zeros(0, dtype=int)
    lam_e = ca.SX.sym("lam_e", int(e_all.numel()))
    lam_fs = ca.SX.sym("lam_f")
    # the columns of w the end terms read: the structural nonzero columns of their Jacobian (one sparsity
    # pass, not a Python loop over every symbol of w)
    e_cols = _sorted_unique(np.asarray(ca.jacobian_sparsity(ca.vertcat(e_all, nlp.mayer), nlp.w).get_col(), dtype=np.int64))[0]
    v_e = nlp.w[e_cols.tolist()] if e_cols.size else ca.SX.sym("v_e", 0)
    he_loc, ge_loc = ca.hessian(lam_fs * nlp.mayer + ca.dot(lam_e, e_all), v_e)
    ends_jac = ca.Function(f"{casadi_name(dae.name)}_ends_jac", [v_e, nlp.p], [ca.jacobian(e_all, v_e), ca.densify(e_all)],
                           ["v", "p"], ["jac", "e"])
    ends_hess = ca.Function(f"{casadi_name(dae.name)}_ends_hess", [v_e, nlp.p, lam_fs, lam_e], [ca.triu(he_loc), ca.densify(ge_loc)],
                            ["v", "p", "lam_f", "lam_e"], ["hess", "grad"])
    if compile and stagewise:
        ends_jac, _ = compiled_function(ends_jac, COMPILE_FLAGS, "collocation")
        ends_hess, how_e = compiled_function(ends_hess, COMPILE_FLAGS, "collocation")
        how = f"{how}; end terms: {how_e}"
    w_e = w[e_cols.tolist()] if e_cols.size else ca.MX(0, 1)
    je_val, e_val = ends_jac(w_e, P)
    he_val, ge_val = ends_hess(w_e, P, lam_f, lam_g[e_rows.tolist()] if e_rows.size else ca.MX(0, 1))

    # Jacobian: values = [point jacobians (M nj), end jacobian, 1]
    jr, jc, hr, hc = (np.asarray(a, dtype=np.int64) for a in (jr, jc, hr, hc))
    jac = _Assembly()
    lin = _Assembly()  # the linear terms alone (fatrop's constraints and gradient): constant coefficients

    def linear(row: Any, col: Any, coefficient: Any) -> None:
        jac.add(row, col, one, coefficient)
        lin.add(row, col, 0, coefficient)

    jac.add(rows[:, jr], cols[:, jc], np.arange(M)[:, None] * nj + np.arange(nj)[None, :])
    # the sparsity of the functions' outputs, as evaluated (a structural entry of the SX that
    # is identically zero, e.g. the Hessian of abs(v) at the start, is dropped there)
    je_r, je_c = (np.asarray(a, dtype=np.int64) for a in je_val.sparsity().get_triplet())
    jac.add(e_rows[je_r] if je_r.size else je_r, e_cols[je_c] if je_c.size else je_c, M * nj + np.arange(je_r.size))
    one = M * nj + len(je_r)
    nom_x = np.asarray(noms["x"], dtype=float)
    ix = np.arange(nx)
    C, D = np.asarray(co["C"], dtype=float), np.asarray(co["D"], dtype=float)
    # the linear terms, all points at once: xoff[k, r] is the first column of x_{k,r}
    xoff = np.full((N + 1, d + 1), -1, dtype=np.int64)
    for (kind, k, r_), o in offs.items():
        if kind == "x":
            xoff[k, r_] = o
    pk, pj, pfirst = (np.array([t[i] for t in nlp.rows_point], dtype=np.int64) for i in range(3))
    for r_ in range(d + 1):  # collocation polynomial: - sum_r C[r, j] x_{k,r}
        sel = C[r_, pj] != 0.0
        linear(pfirst[sel, None] + ix, xoff[pk[sel], r_][:, None] + ix, -C[r_, pj[sel]][:, None] * nom_x)
    ck, cfirst = (np.array([t[i] for t in nlp.rows_cont], dtype=np.int64) for i in range(2))
    nom_c = np.ones(nx) if stagewise else nom_x  # stage-wise continuity: x_{k+1} - F(x_k, u_k) in scaled states
    linear(cfirst[:, None] + ix, xoff[ck + 1, 0][:, None] + ix, nom_c)
    for r_ in range(d + 1):
        if D[r_] != 0.0:
            linear(cfirst[:, None] + ix, xoff[ck, r_][:, None] + ix, -D[r_] * nom_c)
    if nlp.rows_tf:
        tk, trow = (np.array([t[i] for t in nlp.rows_tf], dtype=np.int64) for i in range(2))
        toff = np.array([offs[("tf", k, 0)] for k in range(N)], dtype=np.int64)
        linear(trow, toff[tk + 1], 1.0)
        linear(trow, toff[tk], -1.0)
    jvals = ca.vertcat(_nz(jm), _nz(je_val), ca.MX(1))
    jac_mx = jac.matrix(jvals, one + 1, ng, nw)

    hess = _Assembly()
    R, C_ = cols[:, hr], cols[:, hc]
    src = np.arange(M)[:, None] * nh + np.arange(nh)[None, :]
    hess.add(np.minimum(R, C_), np.maximum(R, C_), src)
    he_r, he_c = (e_cols[np.asarray(a, dtype=np.int64)] for a in he_val.sparsity().get_triplet())
    he_src = M * nh + np.arange(len(he_r))
    hess.add(he_r, he_c, he_src)
    if stagewise:  # fatrop: the whole symmetric matrix, the same values mirrored below the diagonal
        off, he_off = R != C_, he_r != he_c
        hess.add(np.maximum(R, C_)[off], np.minimum(R, C_)[off], src[off])
        hess.add(he_c[he_off], he_r[he_off], he_src[he_off])
    hvals = ca.vertcat(_nz(hm), _nz(he_val))
    hess_mx = hess.matrix(hvals, M * nh + len(he_r), nw, nw)

    names_in = ["x", "p", "lam_f", "lam_g"]
    if stagewise:
        return _stagewise_functions((w, P, lam_f, lam_g), (rm, gm, e_val, ge_val), jac_mx, hess_mx, lin, (rows, cols, e_rows, e_cols)), how
    g_fn = ca.Function("nlp_g", [nlp.w, nlp.p], [nlp.g])
    jac_g = ca.Function("nlp_jac_g", [w, P], [g_fn(w, P), jac_mx], ["x", "p"], ["g", "jac_g_x"])
    hess_lag = ca.Function("nlp_hess_l", [w, P, lam_f, lam_g], [hess_mx], names_in, ["triu_hess_gamma_x_x"])
    return {"jac_g": jac_g, "hess_lag": hess_lag}, how


def _stagewise_functions(inputs: tuple, values: tuple, jac_mx: ca.MX, hess_mx: ca.MX, lin: _Assembly, index: tuple) -> dict[str, ca.Function]:
    """fatrop's ``nlp_g``, ``nlp_jac_g`` and ``nlp_hess_l`` (``inputs``: the symbols ``x, p, lam_f, lam_g``): the
    constraints assembled as the Jacobian is (the point and end residuals of the Jacobians' own pass, the linear
    terms as one constant matrix), the Lagrangian's gradient from the Hessians' own pass (the point and end
    gradients, the linear terms' transpose)."""
    w, P, lam_f, lam_g = inputs
    rm, gm, e_val, ge_val = values
    rows, cols, e_rows, e_cols = index
    M, nr = rows.shape
    nv = cols.shape[1]
    nw, ng = int(w.numel()), int(lam_g.numel())
    A = lin.matrix(ca.DM(1), 1, ng, nw)  # constant: the linear terms' coefficients
    g = _Assembly()
    g.add(rows, 0, np.arange(M)[:, None] * nr + np.arange(nr)[None, :])
    g.add(e_rows, 0, M * nr + np.arange(e_rows.size))
    g_val = ca.densify(g.matrix(ca.vertcat(_nz(rm), e_val), M * nr + e_rows.size, ng, 1) + ca.mtimes(A, w))
    grad = _Assembly()
    grad.add(cols, 0, np.arange(M)[:, None] * nv + np.arange(nv)[None, :])
    grad.add(e_cols, 0, M * nv + np.arange(e_cols.size))
    grad_l = ca.densify(grad.matrix(ca.vertcat(_nz(gm), ge_val), M * nv + e_cols.size, nw, 1) + ca.mtimes(A.T, lam_g))
    nlp_g = ca.Function("nlp_g", [w, P], [g_val], ["x", "p"], ["g"])
    jac_g = ca.Function("nlp_jac_g", [w, P], [g_val, jac_mx], ["x", "p"], ["g", "jac_g_x"])
    hess_lag = ca.Function("nlp_hess_l", [w, P, lam_f, lam_g], [grad_l, hess_mx], ["x", "p", "lam_f", "lam_g"], ["grad_gamma_x", "hess_gamma_x_x"])
    return {"g": nlp_g, "jac_g": jac_g, "hess_lag": hess_lag}
