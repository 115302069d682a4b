"""Direct collocation transcription of an :class:`~gtmodel.modeling.Optimization` to an NLP.

Method (as in JModelica.org's LocalDAECollocator): the horizon is split into ``elements``
uniform elements; in each, states are polynomials of degree ``points`` through the
element start and the ``points`` collocation points (``casadi.collocation_points``,
Radau IIA or Gauss-Legendre); inputs and algebraic variables are NLP variables at the
collocation points only. States are continuous across elements. A free final time is
handled by time scaling ``t = t0 + tau (tf - t0)`` with ``tf`` an NLP variable.

Conventions:

* Path constraints and variable bounds of inputs/algebraics are enforced at the
  collocation points; state bounds also at element boundaries.
* Point constraints and the Mayer term at the final time use the final state and, for
  inputs/algebraics, the last element's polynomial at ``tau = 1`` (for Radau a
  collocation point; for Legendre an extrapolation).
* Point constraints at the start time use the initial state and, for inputs/algebraics,
  the first element's Lagrange polynomial through its collocation points evaluated at
  ``tau = 0`` (an extrapolation for both schemes).
* The Lagrange term uses the quadrature of the collocation points.

Model parameters are NLP parameters (``p`` of ``nlpsol``), so one transcription can be
solved repeatedly for new parameter values and initial guesses. Free parameters
(:meth:`Optimization.free_parameter`) are NLP variables instead, one per scalar element,
shared by all collocation points (like a free final time).
"""

from __future__ import annotations

import logging
import time as _time
from collections.abc import Mapping
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError, SolverError
from gtmodel.modeling.dae import FlatDAE, _eval_outputs, _unpack, _vector_value
from gtmodel.modeling.optimization import Optimization
from gtmodel.modeling.result import (
    CollocationData,
    OptimizationResult,
    lagrange_basis,
    normalize_ipopt_status,
)
from gtmodel.status import Status

__all__ = ["CollocationTranscription", "solve"]

_log = logging.getLogger("gtmodel")

#: CasADi-level nlpsol options passed through unchanged (others are IPOPT options).
_CASADI_OPTIONS = {
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
}


def _merge_options(verbose: bool, solver_options: Mapping[str, Any] | None) -> dict[str, Any]:
    ipopt: dict[str, Any] = {"max_iter": 3000, "tol": 1e-8}
    top: dict[str, Any] = {"error_on_fail": False}
    if verbose:
        ipopt["print_level"] = 5
        top["print_time"] = True
    else:
        ipopt["print_level"] = 0
        ipopt["sb"] = "yes"
        top["print_time"] = False
        top["show_eval_warnings"] = False
    for key, value in (solver_options or {}).items():
        if not isinstance(key, str):
            raise InputError(f"solver_options keys must be strings, got {key!r}")
        if key == "ipopt" and isinstance(value, Mapping):
            ipopt.update(value)
        elif key.startswith("ipopt."):
            ipopt[key[6:]] = value
        elif key in _CASADI_OPTIONS:
            top[key] = value
        else:
            ipopt[key] = value
    top["ipopt"] = ipopt
    return top


def _collocation_coefficients(d: int, scheme: str) -> dict[str, np.ndarray]:
    """Derivative matrix, continuity, quadrature and extrapolation weights.

    ``C`` and ``D`` from ``casadi.collocation_coeff`` (Lagrange polynomials through ``0``
    and the collocation points), which keeps the exact zeros of the scheme: for Radau the
    end of an element is its last collocation point, so ``D = (0, ..., 0, 1)`` and a
    continuity constraint involves two states only. ``B`` integrates the polynomial through
    the collocation points (inputs and algebraics have no value at the element start).
    """
    tau = np.array(ca.collocation_points(d, scheme), dtype=float)
    root = np.concatenate([[0.0], tau])
    c_, d_, _ = ca.collocation_coeff(tau.tolist())
    C = np.zeros((d + 1, d + 1))
    C[:, 1:] = np.array(c_, dtype=float)  # C[r, j]: derivative of basis r at root j (j >= 1)
    # quadrature weights of the collocation points (interpolatory, without the element start)
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


class CollocationTranscription:
    """An optimisation problem transcribed once by direct collocation, solvable repeatedly.

    Parameters
    ----------
    optimization : Optimization
        The declared problem.
    elements : int, optional
        Number of uniform elements; default 50.
    points : int, optional
        Collocation points per element (polynomial degree of states); default 3.
    scheme : {"radau", "legendre"}, optional
        Collocation points; default ``"radau"``.
    verbose : bool, optional
        Show IPOPT output and timing; default False.
    solver_options : mapping, optional
        IPOPT options (plain names such as ``"max_iter"`` or ``"ipopt.max_iter"``, or a
        nested ``{"ipopt": {...}}``) and CasADi nlpsol options (``"print_time"``,
        ``"expand"``, ...); merged over the defaults ``max_iter=3000``, ``tol=1e-8``,
        ``print_level=0``, ``print_time=False`` (and no CasADi evaluation warnings)
        unless ``verbose``.
    nominal : mapping of str to float or array_like, optional
        Nominal magnitudes of states, inputs, algebraic variables, free parameters
        (by name) and of ``"final_time"``: the NLP works with ``variable / nominal`` (Modelica's
        ``nominal`` attribute, JModelica's variable scaling), so that variables of
        different units (forces in hundreds of N, positions in m) are of order one.
        Results, guesses and bounds stay in the model's units. Default: no scaling.
    derivatives : {"assembled", "casadi"}, optional
        How the Jacobian of the constraints and the Hessian of the Lagrangian are
        built. ``"assembled"`` (default): differentiate the per-point functions (model
        equations, path constraints, Lagrange integrand) once and assemble the sparse
        matrices from their values at each collocation point; the collocation
        constraints call the per-point function instead of copying its expression
        graph. ``"casadi"``: CasADi differentiates the whole expression graph of the
        NLP (several times slower to build, the same values).

    Raises
    ------
    InputError
        If ``elements``/``points``/``scheme`` are invalid.
    ModelError
        If the model cannot be flattened.
    SolverError
        If CasADi cannot build the NLP solver.
    """

    def __init__(
        self,
        optimization: Optimization,
        elements: int = 50,
        points: int = 3,
        scheme: str = "radau",
        verbose: bool = False,
        solver_options: Mapping[str, Any] | None = None,
        nominal: Mapping[str, Any] | None = None,
        derivatives: str = "assembled",
    ) -> None:
        if not isinstance(optimization, Optimization):
            raise InputError(f"expected an Optimization, got {type(optimization).__name__}")
        if not isinstance(elements, (int, np.integer)) or isinstance(elements, bool) or elements < 1:
            raise InputError(f"elements must be a positive integer, got {elements!r}")
        if not isinstance(points, (int, np.integer)) or isinstance(points, bool) or not 1 <= points <= 9:
            raise InputError(f"points must be an integer in 1..9, got {points!r}")
        if scheme not in ("radau", "legendre"):
            raise InputError(f"scheme must be 'radau' or 'legendre', got {scheme!r}")
        self.optimization = optimization
        self.elements = int(elements)
        self.points = int(points)
        self.scheme = scheme
        if derivatives not in ("assembled", "casadi"):
            raise InputError(f"derivatives must be 'assembled' or 'casadi', got {derivatives!r}")
        self.derivatives = derivatives
        self.options = _merge_options(verbose, solver_options)
        self.dae: FlatDAE = optimization.flat()
        self.nominal = self._nominal_values(nominal)
        self._build()

    def _nominal_values(self, nominal: Mapping[str, Any] | None) -> dict[str, np.ndarray]:
        """Per-kind scale vectors ``{"x", "z", "u", "tf"}`` from the ``nominal`` mapping."""
        dae = self.dae
        free = self._free_slices()
        npf = sum(sl.stop - sl.start for sl in free.values())
        out = {"x": np.ones(dae.nx), "z": np.ones(dae.nz), "u": np.ones(dae.nu), "tf": np.ones(1), "pf": np.ones(npf)}
        known = {"final_time": ("tf", slice(0, 1))}
        for kind, vars_ in (("x", dae.x_vars), ("z", dae.z_vars), ("u", dae.u_vars), ("pf", free)):
            for name, sl in vars_.items():
                known[name] = (kind, sl)
        for name, value in (nominal or {}).items():
            if name not in known:
                raise InputError(f"nominal: {name!r} is not a state, input, algebraic variable, free parameter or 'final_time'")
            kind, sl = known[name]
            n = sl.stop - sl.start
            try:
                v = np.broadcast_to(np.asarray(value, dtype=float).reshape(-1) if np.ndim(value) else float(value), (n,))
            except (TypeError, ValueError):
                raise InputError(f"nominal of {name!r}: expected a positive number or {n} of them, got {value!r}") from None
            if not np.all(np.isfinite(v) & (v > 0)):
                raise InputError(f"nominal of {name!r}: expected positive finite values, got {value!r}")
            out[kind][sl] = v
        return out

    def _free_slices(self) -> dict[str, slice]:
        """Free parameter name -> its slice in the vector of free parameter elements."""
        out, k = {}, 0
        for name in self.optimization.free_parameters:
            n = self.dae.p_vars[name].stop - self.dae.p_vars[name].start
            out[name] = slice(k, k + n)
            k += n
        return out

    def _free_index(self) -> np.ndarray:
        """Indices in the model parameter vector of the free parameter elements, in order."""
        p_vars = self.dae.p_vars
        idx = [np.arange(p_vars[n].start, p_vars[n].stop) for n in self.optimization.free_parameters]
        return np.concatenate(idx).astype(int) if idx else np.zeros(0, dtype=int)

    def _with_free(self, p_nlp: ca.SX, pf: ca.SX) -> ca.SX:
        """The model parameter vector: ``p_nlp`` with the free elements replaced by ``pf * nominal``."""
        idx = self._free_index()
        if idx.size == 0:
            return p_nlp
        elems = [p_nlp[i] for i in range(int(p_nlp.numel()))]
        for k, i in enumerate(idx):
            elems[int(i)] = pf[k] * float(self.nominal["pf"][k])
        return ca.vertcat(*elems)

    # ------------------------------------------------------------------ build
    def _build(self) -> None:
        opt, dae = self.optimization, self.dae
        N, d = self.elements, self.points
        co = _collocation_coefficients(d, self.scheme)
        self._co = co
        nx, nz, nu = dae.nx, dae.nz, dae.nu
        t0 = opt.start_time
        assembled = self.derivatives == "assembled"

        # expression functions of (t, x, z, u, p, tf); der() replaced by the ODE rhs
        args = [dae.t, dae.x, dae.z, dae.u, dae.p, opt.final_time]

        def subst(e: ca.SX) -> ca.SX:
            return ca.substitute(e, dae.xdot, dae.ode_expr) if dae.nx else e

        def fn(name: str, exprs: list[ca.SX]) -> ca.Function:
            e = ca.vertcat(*exprs) if exprs else ca.SX(0, 1)
            return ca.Function(name, args, [subst(e)])

        start_c = [c for c in opt.point_constraints if c.at == "start"]
        final_c = [c for c in opt.point_constraints if c.at == "final"]
        start_fn = fn("point_start", [c.expr for c in start_c])
        final_fn = fn("point_final", [c.expr for c in final_c])
        mayer_fn = fn("mayer", [opt.mayer])
        lagr_fn = fn("lagrange", [opt.lagrange])
        # what is imposed at each collocation point: the model equations and the path
        # constraints, one function with common subexpressions (kinematics, mass matrix)
        # computed once
        path_expr = subst(ca.vertcat(*[c.expr for c in opt.path_constraints])) if opt.path_constraints else ca.SX(0, 1)
        point_out = ca.cse([dae.ode_expr, dae.alg_expr, path_expr])
        point_fn = ca.Function("point", args, point_out)
        # in the NLP graph a call node per point (not a copy of the graph) when the
        # derivatives are assembled from the per-point ones below
        point_call = ca.Function("point_call", args, point_out, {"never_inline": True}) if assembled else point_fn
        npath = int(path_expr.numel())

        P_nlp = dae.p  # nlpsol's parameters: the model parameter values
        npf = int(self._free_index().size)
        PF_sym = ca.SX.sym("pf", npf)
        P = self._with_free(P_nlp, PF_sym)  # free elements are NLP variables
        free = opt.free_final_time
        noms = self.nominal
        tf_nom = float(noms["tf"][0])
        T_sym = ca.SX.sym("tf")
        T = T_sym * tf_nom if free else ca.SX(opt.final_time_value)
        h = (T - t0) / N

        x_lb, x_ub = opt.bounds_vectors(dae, "x")
        z_lb, z_ub = opt.bounds_vectors(dae, "z")
        u_lb, u_ub = opt.bounds_vectors(dae, "u")

        w: list[ca.SX] = []
        lbw: list[np.ndarray] = []
        ubw: list[np.ndarray] = []
        scale: list[np.ndarray] = []
        blocks: list[tuple[str, int, int]] = []  # (kind, element, tau index)
        offsets: dict[tuple[str, int, int], int] = {}  # first index in w of each block
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
        rows_point: list[tuple[int, int, int]] = []  # (k, j, first row) of the point constraints
        rows_cont: list[tuple[int, int]] = []  # (k, first row) of the continuity constraints
        J = ca.SX(0)
        Xk0 = var("x", 0, 0, nx, x_lb, x_ub)
        for k in range(N):
            Xk = [Xk0] + [var("x", k, j, nx, x_lb, x_ub) for j in range(1, d + 1)]
            Uk = [var("u", k, j, nu, u_lb, u_ub) for j in range(1, d + 1)]
            Zk = [var("z", k, j, nz, z_lb, z_ub) for j in range(1, d + 1)]
            Xs.append(Xk)
            Us.append(Uk)
            Zs.append(Zk)
            for j in range(1, d + 1):
                tkj = t0 + (k + co["root"][j]) * h
                xp = sum(co["C"][r, j] * Xk[r] for r in range(d + 1) if co["C"][r, j] != 0.0)
                fkj, akj, pkj = point_call(tkj, Xk[j], Zk[j - 1], Uk[j - 1], P, T)
                first = con(ca.vertcat(h * fkj - xp, akj, pkj), point_lb, point_ub)
                rows_point.append((k, j, first))
                J = J + co["B"][j - 1] * h * lagr_fn(tkj, Xk[j], Zk[j - 1], Uk[j - 1], P, T)
            xend = sum(co["D"][r] * Xk[r] for r in range(d + 1) if co["D"][r] != 0.0)
            Xk0 = var("x", k + 1, 0, nx, x_lb, x_ub)
            rows_cont.append((k, con(Xk0 - xend, np.zeros(1), np.zeros(1))))
        XN = Xk0
        if free:
            offsets[("tf", 0, 0)] = n_w[0]
            n_w[0] += 1
            w.append(T_sym)
            lbw.append(np.array([opt.final_time_bounds[0]]) / tf_nom)
            ubw.append(np.array([opt.final_time_bounds[1]]) / tf_nom)
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
            if n == 0:
                return ca.SX(0, 1)
            return sum(weights[j] * vals[j] for j in range(d))

        u_start, z_start = extrap(Us[0], co["L0"], nu), extrap(Zs[0], co["L0"], nz)
        u_final, z_final = extrap(Us[-1], co["L1"], nu), extrap(Zs[-1], co["L1"], nz)
        ends: list[tuple[int, ca.SX]] = []  # (first row, expression) of the point constraints
        if start_c:
            e = start_fn(t0, Xs[0][0], z_start, u_start, P, T)
            ends.append((con(e, np.concatenate([c.lb for c in start_c]), np.concatenate([c.ub for c in start_c])), e))
        if final_c:
            e = final_fn(T, XN, z_final, u_final, P, T)
            ends.append((con(e, np.concatenate([c.lb for c in final_c]), np.concatenate([c.ub for c in final_c])), e))
        mayer = mayer_fn(T, XN, z_final, u_final, P, T)
        J = J + mayer

        wv = ca.vertcat(*w)
        gv = ca.vertcat(*g) if g else ca.SX(0, 1)
        self._blocks = blocks
        self._block_sizes = [int(b.numel()) for b in w]
        self._scale = np.concatenate(scale) if scale else np.zeros(0)
        self._lbw = np.concatenate(lbw) if lbw else np.zeros(0)
        self._ubw = np.concatenate(ubw) if ubw else np.zeros(0)
        self._lbg = np.concatenate(lbg) if lbg else np.zeros(0)
        self._ubg = np.concatenate(ubg) if ubg else np.zeros(0)
        self._fg = ca.Function("fg", [wv, P_nlp], [J, gv])
        xc = ca.horzcat(*[ca.horzcat(*Xk) for Xk in Xs])
        uc = ca.horzcat(*[ca.horzcat(*Uk) for Uk in Us]) if nu else ca.SX(0, N * d)
        zc = ca.horzcat(*[ca.horzcat(*Zk) for Zk in Zs]) if nz else ca.SX(0, N * d)
        self._extract = ca.Function("extract", [wv, P_nlp], [xc, uc, zc, XN, ca.vertcat(T), P])
        self.key = (id(self), N, d, self.scheme, int(wv.numel()))
        nlp_options = dict(self.options)
        if assembled:
            nlp_options["jac_g"], nlp_options["hess_lag"] = self._assembled_derivatives(
                wv, gv, P_nlp, point_fn, lagr_fn, offsets, rows_point, rows_cont, ends, mayer, t0, tf_nom, npath
            )
        try:
            self.solver = ca.nlpsol(
                f"{dae.name}_collocation",
                "ipopt",
                {"x": wv, "p": P_nlp, "f": J, "g": gv},
                nlp_options,
            )
        except RuntimeError as exc:
            raise SolverError(f"could not build the IPOPT solver: {exc}") from exc
        _log.debug(
            "collocation NLP for %s: %d variables, %d constraints", dae.name, wv.numel(), gv.numel()
        )

    def _assembled_derivatives(
        self,
        wv: ca.SX,
        gv: ca.SX,
        P: ca.SX,
        point_fn: ca.Function,
        lagr_fn: ca.Function,
        offsets: Mapping[tuple[str, int, int], int],
        rows_point: list[tuple[int, int, int]],
        rows_cont: list[tuple[int, int]],
        ends: list[tuple[int, ca.SX]],
        mayer: ca.SX,
        t0: float,
        tf_nom: float,
        npath: int,
    ) -> tuple[ca.Function, ca.Function]:
        """Constraint Jacobian and Lagrangian Hessian assembled from per-point derivatives.

        At collocation point ``(k, j)`` the nonlinear constraints ``h f(t, x, z, u), g_alg,
        path`` and the Lagrange term depend only on that point's ``x, z, u`` and on the
        final time; the collocation polynomial and continuity terms are linear with the
        constant coefficients ``C`` and ``D``. So the point functions are differentiated
        once (small expressions) and their derivatives, called at every point, are placed
        into the sparse NLP matrices. The point constraints at the start and final time
        (few) are differentiated directly. Returns the ``jac_g`` and ``hess_lag``
        functions of ``casadi.nlpsol``.
        """
        opt, dae, co, noms = self.optimization, self.dae, self._co, self.nominal
        N, d = self.elements, self.points
        nx, nz, nu = dae.nx, dae.nz, dae.nu
        free = opt.free_final_time
        nw, ng = int(wv.numel()), int(gv.numel())
        nr = nx + nz + npath

        # local functions of the scaled point variables v = (x, z, u[, tf][, free parameters])
        xs, zs, us = ca.SX.sym("xs", nx), ca.SX.sym("zs", nz), ca.SX.sym("us", nu)
        ts = ca.SX.sym("ts") if free else ca.SX(0, 1)
        npf = int(self._free_index().size)
        ps = ca.SX.sym("ps", npf)
        P_loc = self._with_free(P, ps)
        c, b, lam_f = ca.SX.sym("c"), ca.SX.sym("b"), ca.SX.sym("lam_f")
        lam_r = ca.SX.sym("lam_r", nr)
        T = ts * tf_nom if free else ca.SX(opt.final_time_value)
        h = (T - t0) / N
        t = t0 + c * h
        x, z, u = xs * ca.DM(noms["x"]), zs * ca.DM(noms["z"]), us * ca.DM(noms["u"])
        f, a, p = point_fn(t, x, z, u, P_loc, T)
        r = ca.vertcat(h * f, a, p)
        v = ca.vertcat(xs, zs, us, ts, ps)
        jac_r = ca.jacobian(r, v)
        lag = ca.dot(lam_r, r) + lam_f * b * h * lagr_fn(t, x, z, u, P_loc, T)
        hess_r = ca.triu(ca.hessian(lag, v)[0])
        local_in = [xs, zs, us, ts, ps, P, c]
        jac_fn = ca.Function("point_jac", local_in, [jac_r], {"never_inline": True})
        hess_fn = ca.Function("point_hess", local_in + [b, lam_f, lam_r], [hess_r], {"never_inline": True})
        jr, jc = jac_r.sparsity().get_triplet()
        hr, hc = hess_r.sparsity().get_triplet()

        lam_f_g = ca.SX.sym("lam_f")
        lam_g = ca.SX.sym("lam_g", ng)
        tf_index = [offsets[("tf", 0, 0)]] if free else []
        tf_arg = wv[tf_index[0]] if free else ca.SX(0, 1)
        pf_index = list(offsets[("pf", 0, 0)] + np.arange(npf)) if npf else []
        pf_arg = wv[offsets[("pf", 0, 0)]:offsets[("pf", 0, 0)] + npf] if npf else ca.SX(0, 1)
        jac: dict[tuple[int, int], list] = {}
        hess: dict[tuple[int, int], list] = {}

        def add(store: dict, row: int, col: int, value: Any) -> None:
            store.setdefault((row, col), []).append(value)

        for k, j, first in rows_point:
            ox, oz, ou = offsets[("x", k, j)], offsets[("z", k, j)], offsets[("u", k, j)]
            cols = np.concatenate([ox + np.arange(nx), oz + np.arange(nz), ou + np.arange(nu), tf_index, pf_index]).astype(int)
            arg = [wv[ox:ox + nx], wv[oz:oz + nz], wv[ou:ou + nu], tf_arg, pf_arg, P, k + co["root"][j]]
            for value, rr, cc in zip(jac_fn(*arg).nonzeros(), jr, jc):
                add(jac, first + rr, int(cols[cc]), value)
            # collocation polynomial: - sum_r C[r, j] x_{k,r} (scaled variables)
            for r_ in range(d + 1):
                if co["C"][r_, j] != 0.0:
                    o = offsets[("x", k, r_)]
                    for i in range(nx):
                        add(jac, first + i, o + i, -co["C"][r_, j] * noms["x"][i])
            hk = hess_fn(*arg, co["B"][j - 1], lam_f_g, lam_g[first:first + nr])
            for value, rr, cc in zip(hk.nonzeros(), hr, hc):
                R, C_ = int(cols[rr]), int(cols[cc])
                add(hess, min(R, C_), max(R, C_), value)
        for k, first in rows_cont:
            o = offsets[("x", k + 1, 0)]
            for i in range(nx):
                add(jac, first + i, o + i, noms["x"][i])
            for r_ in range(d + 1):
                if co["D"][r_] != 0.0:
                    o = offsets[("x", k, r_)]
                    for i in range(nx):
                        add(jac, first + i, o + i, -co["D"][r_] * noms["x"][i])
        # point constraints at the ends and the Mayer term: few, differentiated directly
        lag_ends = lam_f_g * mayer
        for first, e in ends:
            n = int(e.numel())
            je = ca.jacobian(e, wv)
            for value, rr, cc in zip(je.nonzeros(), *je.sparsity().get_triplet()):
                add(jac, first + rr, cc, value)
            lag_ends = lag_ends + ca.dot(lam_g[first:first + n], e)
        he = ca.triu(ca.hessian(lag_ends, wv)[0])
        for value, rr, cc in zip(he.nonzeros(), *he.sparsity().get_triplet()):
            add(hess, rr, cc, value)

        def matrix(store: dict, nrow: int, ncol: int) -> ca.SX:
            keys = sorted(store, key=lambda rc: (rc[1], rc[0]))  # column-major, as CasADi stores
            sp = ca.Sparsity.triplet(nrow, ncol, [rc[0] for rc in keys], [rc[1] for rc in keys])
            values = [ca.SX(0)] * len(keys)
            for i, key in enumerate(keys):
                terms = store[key]
                values[i] = terms[0] if len(terms) == 1 else sum(terms[1:], terms[0])
            return ca.SX(sp, ca.vertcat(*values)) if keys else ca.SX(nrow, ncol)

        jac_g = ca.Function("nlp_jac_g", [wv, P], [gv, matrix(jac, ng, nw)], ["x", "p"], ["g", "jac_g_x"])
        hess_lag = ca.Function(
            "nlp_hess_l", [wv, P, lam_f_g, lam_g], [matrix(hess, nw, nw)], ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"]
        )
        return jac_g, hess_lag


    # ------------------------------------------------------------------ guesses
    def _initial_w(self, guesses: Mapping[str, Any], tf_guess: float, pvec: np.ndarray) -> np.ndarray:
        opt, dae, co = self.optimization, self.dae, self._co
        N, t0 = self.elements, opt.start_time
        h = (tf_guess - t0) / N
        fns = {}
        for cat, vars_, start in (("x", dae.x_vars, dae.x_start), ("z", dae.z_vars, dae.z_start), ("u", dae.u_vars, None)):
            for name, sl in vars_.items():
                n = sl.stop - sl.start
                if start is None:
                    kind_syms = self.optimization.model._vars[name]
                    default = kind_syms.start.copy()
                else:
                    default = start[sl].copy()
                fns[(cat, name)] = (sl, _guess_fn(guesses.get(name), n, name, default))
        w0 = []
        for (kind, k, j), size in zip(self._blocks, self._block_sizes):
            if kind == "tf":
                w0.append(np.array([tf_guess]))
                continue
            if kind == "pf":
                w0.append(self._free_start(pvec))
                continue
            t = t0 + (k + co["root"][j]) * h
            vals = np.zeros(size)
            for (cat, _name), (sl, f) in fns.items():
                if cat == kind:
                    vals[sl] = f(t)
            w0.append(vals)
        w = np.concatenate(w0) if w0 else np.zeros(0)
        lo, hi = self._lbw, self._ubw
        return np.clip(w / self._scale, lo, hi)  # the NLP works with variable / nominal

    def _free_start(self, pvec: np.ndarray) -> np.ndarray:
        """Initial guess of the free parameter elements: their start, else the value clipped into the bounds."""
        out = []
        for name, (lb, ub, start) in self.optimization.free_parameters.items():
            out.append(start if start is not None else np.clip(pvec[self.dae.p_vars[name]], lb, ub))
        return np.concatenate(out) if out else np.zeros(0)

    # ------------------------------------------------------------------ solve
    def solve(
        self,
        parameters: Mapping[str, Any] | None = None,
        initial_guess: OptimizationResult | Mapping[str, Any] | None = None,
    ) -> OptimizationResult:
        """Solve the NLP; never raises for a non-optimal outcome.

        Parameters
        ----------
        parameters : mapping of str to float or array_like, optional
            Parameter values overriding the model defaults and
            :meth:`Optimization.set_parameter`.
        initial_guess : OptimizationResult or mapping, optional
            A previous result of this transcription (its NLP vector is reused: warm
            start), a result of another transcription (sampled), or a mapping from
            variable names (and ``"final_time"``) to guesses in the formats of
            :meth:`Optimization.set_initial_guess`. Default: the problem's guesses.

        Returns
        -------
        OptimizationResult
            With ``status`` and the solution or the last iterate.

        Raises
        ------
        InputError
            If parameters or guesses are malformed.
        """
        opt, dae = self.optimization, self.dae
        merged = {k: v for k, v in opt.parameters.items()}
        merged.update(parameters or {})
        pvec = dae.parameter_vector(merged)
        guesses: dict[str, Any] = dict(opt.initial_guesses)
        tf_guess = opt.final_time_guess
        w0 = None
        if isinstance(initial_guess, OptimizationResult):
            if initial_guess.transcription_key == self.key and initial_guess.w is not None:
                w0 = np.clip(initial_guess.w, self._lbw, self._ubw)
            elif initial_guess.collocation is not None:
                res = initial_guess
                tf_guess = float(np.clip(res.final_time, *opt.final_time_bounds))
                span_old = res.final_time - opt.start_time

                def from_result(cat: str, name: str, res: OptimizationResult = res) -> Any:
                    def f(t: float) -> np.ndarray:
                        s = opt.start_time + (t - opt.start_time) / (tf_guess - opt.start_time) * span_old
                        return np.asarray(res.sample([s])[cat][name], dtype=float).reshape(-1)

                    return f

                for cat, vars_ in (("states", dae.x_vars), ("inputs", dae.u_vars), ("algebraics", dae.z_vars)):
                    for name in vars_:
                        guesses[name] = from_result(cat, name)
        elif isinstance(initial_guess, Mapping):
            for name, value in initial_guess.items():
                if name == "final_time":
                    tf_guess = float(np.clip(float(value), *opt.final_time_bounds))
                    continue
                known = {**dae.x_vars, **dae.z_vars, **dae.u_vars}
                if name not in known:
                    raise InputError(f"initial_guess: {name!r} is not a state, input or algebraic variable")
                guesses[name] = value
        elif initial_guess is not None:
            raise InputError("initial_guess must be an OptimizationResult or a mapping")
        if w0 is None:
            w0 = self._initial_w(guesses, tf_guess, pvec)

        t_start = _time.perf_counter()
        error_msg = None
        try:
            sol = self.solver(x0=w0, lbx=self._lbw, ubx=self._ubw, lbg=self._lbg, ubg=self._ubg, p=pvec)
            w_opt = np.array(sol["x"], dtype=float).reshape(-1)
        except RuntimeError as exc:  # e.g. NaN/exception inside an evaluation
            error_msg = str(exc).strip().splitlines()[-1] if str(exc).strip() else repr(exc)
            w_opt = w0
        solve_time = _time.perf_counter() - t_start
        stats = dict(self.solver.stats())
        message = error_msg or str(stats.get("return_status", "unknown"))
        status = Status.ERROR if error_msg else normalize_ipopt_status(message)
        if not np.all(np.isfinite(w_opt)):
            status = Status.ERROR
        return self._result(w_opt, pvec, status, message, stats, solve_time)

    def _result(
        self,
        w: np.ndarray,
        pvec: np.ndarray,
        status: str,
        message: str,
        stats: dict[str, Any],
        solve_time: float,
    ) -> OptimizationResult:
        dae, opt, co = self.dae, self.optimization, self._co
        N, d = self.elements, self.points
        f_val, g_val = self._fg(w, pvec)
        f_val = float(f_val)
        g_val = np.array(g_val, dtype=float).reshape(-1)
        viol = [0.0]
        if g_val.size:
            viol.append(float(np.max(np.maximum(self._lbg - g_val, g_val - self._ubg))))
        if w.size:
            viol.append(float(np.max(np.maximum(self._lbw - w, w - self._ubw) * self._scale)))
        max_viol = float(max(viol)) if np.all(np.isfinite(g_val)) else float("nan")
        xc, uc, zc, _xn, T, p_all = self._extract(w, pvec)
        tf = float(T)
        pvec = np.array(p_all, dtype=float).reshape(-1)  # free parameters at their optimal values
        colloc = CollocationData(
            t0=opt.start_time,
            tf=tf,
            elements=N,
            points=d,
            scheme=self.scheme,
            tau_root=co["root"].copy(),
            xc=np.array(xc).reshape(dae.nx, N, d + 1).transpose(1, 2, 0),
            uc=np.array(uc).reshape(dae.nu, N, d).transpose(1, 2, 0),
            zc=np.array(zc).reshape(dae.nz, N, d).transpose(1, 2, 0),
        )
        t = colloc.mesh()
        xs, us, zs = colloc.evaluate(t)
        params = {k: pvec[s].copy() for k, s in dae.p_vars.items()}
        try:
            outs = _eval_outputs(dae, t, xs, zs, us, pvec)
        except RuntimeError:
            outs = {}
        iterations = int(stats.get("iter_count", 0) or 0)
        if status != "optimal":
            _log.warning("collocation solve of %s ended with status %s (%s)", dae.name, status, message)
        return OptimizationResult(
            status=status,
            message=message,
            iterations=iterations,
            solve_time=solve_time,
            objective=f_val,
            final_time=tf,
            max_constraint_violation=max_viol,
            t=t,
            states=_unpack(dae.x_vars, xs),
            inputs=_unpack(dae.u_vars, us),
            algebraics=_unpack(dae.z_vars, zs),
            outputs=outs,
            parameters=params,
            last_iterate=status not in ("optimal", "acceptable"),
            stats=stats,
            collocation=colloc,
            dae=dae,
            w=w.copy(),
            transcription_key=self.key,
        )


def _guess_fn(spec: Any, size: int, name: str, default: np.ndarray) -> Any:
    """Turn a guess specification into ``f(t) -> (size,)``."""
    if spec is None:
        return lambda t: default
    if callable(spec):
        return lambda t: _vector_value(spec(t), size, f"initial guess of {name!r}")
    if isinstance(spec, tuple) and len(spec) == 2:
        tg = np.asarray(spec[0], dtype=float).reshape(-1)
        vg = np.asarray(spec[1], dtype=float).reshape(tg.size, -1)
        if vg.shape[1] != size:
            raise InputError(f"initial guess of {name!r}: expected {size} columns, got {vg.shape[1]}")
        return lambda t: np.array([np.interp(t, tg, vg[:, i]) for i in range(size)])
    const = _vector_value(spec, size, f"initial guess of {name!r}")
    return lambda t: const


def solve(
    optimization: Optimization,
    elements: int = 50,
    points: int = 3,
    scheme: str = "radau",
    verbose: bool = False,
    solver_options: Mapping[str, Any] | None = None,
    initial_guess: OptimizationResult | Mapping[str, Any] | None = None,
) -> OptimizationResult:
    """Transcribe by direct collocation and solve with IPOPT.

    Parameters
    ----------
    optimization : Optimization
        The declared problem.
    elements : int, optional
        Number of uniform elements; default 50.
    points : int, optional
        Collocation points per element; default 3.
    scheme : {"radau", "legendre"}, optional
        Collocation scheme; default ``"radau"``.
    verbose : bool, optional
        Show IPOPT output; default False.
    solver_options : mapping, optional
        IPOPT/CasADi options merged over the defaults (see
        :class:`CollocationTranscription`).
    initial_guess : OptimizationResult or mapping, optional
        See :meth:`CollocationTranscription.solve`.

    Returns
    -------
    OptimizationResult
        The result; ``success`` is True only for status ``"optimal"``.

    Raises
    ------
    InputError
        On invalid transcription arguments or guesses.
    ModelError
        If the model cannot be flattened.
    SolverError
        If the NLP solver cannot be built.
    """
    tr = CollocationTranscription(
        optimization,
        elements=elements,
        points=points,
        scheme=scheme,
        verbose=verbose,
        solver_options=solver_options,
    )
    return tr.solve(initial_guess=initial_guess)
