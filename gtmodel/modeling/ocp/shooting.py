"""Direct multiple shooting of an :class:`~gtmodel.modeling.Optimization` (rockit's default method).

The horizon is split into ``intervals`` uniform intervals. The decision variables are the
states ``X_k`` at the ``N + 1`` nodes, the inputs (piecewise constant: ``U_k`` on interval
``k``; piecewise linear: ``U_k`` at the nodes, linear in between), the algebraic variables
``Z_k`` at the nodes, a free final time and the free parameters. On each interval a CasADi
integrator (``casadi.integrator``) maps ``X_k`` and the interval's inputs to the state at
its end; the continuity ``X_{k+1} = F(X_k, U_k)`` is a constraint (Bock and Plitt 1984).
Time is scaled ``t = t0 + (k + s) h``, ``h = (tf - t0) / N``, so a free final time is one
more parameter of the integrator.

* Path constraints, variable bounds and the algebraic equations are imposed at the nodes
  (the inputs at the last node are those of the last interval, or its end value when
  piecewise linear); with ``"rk"``/``"radau"`` the inequalities also at every integration
  step's end inside the intervals, with ``"collocation"`` at every stage point (a motor
  current's bound is not only held at the nodes). Every written row is checked against
  them; a row beyond a bound by more than :data:`ROW_TOLERANCE` (relative) is reported in
  the result's ``warnings`` (and the summary's), never silently written. A verified solve
  also checks them at the integrator's points and along a dense re-simulation
  (:func:`gtmodel.modeling.ocp.shooting_bounds.check_between_nodes`): beyond
  :data:`~gtmodel.modeling.ocp.shooting_bounds.BOUND_TOLERANCE` (1 % of ``max(1, |bound|)``)
  the result is ``check_failed``, its message naming the bound, the time, the value and the
  excess, and ``verification.bounds["between_nodes"]`` holds the true peaks.
* The Lagrange term and :meth:`Optimization.integral` s are the integrator's quadratures.
* A timed variable at an interior time is integrated from the start of its interval to
  that time (the same integrator with the step scaled by the fraction of the interval).
* Integrators: ``"rk"`` (fixed-step classical Runge-Kutta 4, ``steps`` per interval) and
  ``"radau"`` (fixed-step 2-stage Radau IIA, implicit and L-stable, for stiff models: a DC
  motor's armature) integrate the model's explicit form, the algebraic variables
  eliminated symbolically as codegen eliminates them
  (:mod:`gtmodel.modeling.ocp.shooting_steps`), so DAEs too, without a rootfinder; one step
  is an SX function repeated by ``mapaccum``; ``"collocation"`` (gtmodel's fixed-step Radau
  IIA collocation of degree 3, :func:`~gtmodel.modeling.ocp.shooting_steps.collocation_steps`:
  a Newton rootfinder per step, on the explicit form where the algebraic variables are
  eliminated symbolically, else with them among its unknowns, so DAEs whose algebraic
  equations are not affine in their variables; its rootfinder starts from a simulation of the
  initial guess, not from constants; with ``integrator_options``, CasADi's ``collocation``
  plugin as before), with exact Hessians; ``"cvodes"`` / ``"idas"`` (SUNDIALS, variable step)
  with a limited-memory Hessian (second-order sensitivities of SUNDIALS are slow). The
  default is ``"rk"`` for ODEs and ``"collocation"`` for DAEs: on the five drive problems
  (DAEs made explicit) it was the one integrator ``optimal`` and verified on each
  (``benchmarks/bench_shooting_integrators.py``, figures in ``docs/problem_language.md``).
* The memory of the NLP is estimated before anything is built
  (:func:`gtmodel.modeling.ocp.budget.check_shooting_memory`): too many intervals times
  steps are refused at once.
* A failure (the NLP solver's, an integrator's or a rootfinder's anywhere in the solve: at
  the start, during the iterations, at the returned point, in the verification) is a result
  with :class:`~gtmodel.status.Status` ``error`` and one line (the stage, the likely cause,
  the fix; :func:`~gtmodel.modeling.ocp.shooting_bounds.failure_message`), never an
  exception; what CasADi prints meanwhile (its dumped inputs) is captured and logged at
  DEBUG (:func:`~gtmodel.modeling.ocp.shooting_bounds.quiet_casadi`).

The solution is returned as an :class:`~gtmodel.modeling.ocp.result.OptimizationResult`
whose :class:`~gtmodel.modeling.ocp.result.CollocationData` holds, per interval, the node
state and the integrated states at the three Radau points of the interval (and the
inputs there; with ``"rk"``/``"radau"`` and 3 or more steps, the ends of up to 4 of its
integration steps instead), with the node's algebraic variables and inputs, so
``sample``/``to_csv`` interpolate the integrated trajectory and the start row is
consistent with the start state. Every
solution is verified by simulation (:mod:`gtmodel.modeling.ocp.verification`, as a
collocation solution is): the piecewise constant or linear inputs drive the model in
CVODES or IDAS from the initial state, and the nodes and the integrated samples are
compared with it; beyond the tolerance the result is ``check_failed``.
"""

from __future__ import annotations

import logging
import time as _time
from collections.abc import Mapping
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError, SolverError
from gtmodel.modeling.dae import FlatDAE, _eval_outputs, _unpack, casadi_name
from gtmodel.modeling.ocp.guesses import _guess_fn
from gtmodel.modeling.ocp.infeasibility import with_culprit
from gtmodel.modeling.ocp.collocation_nlp import merge_options
from gtmodel.modeling.ocp.optimization import Integral, Optimization
from gtmodel.modeling.ocp.result import CollocationData, OptimizationResult, normalize_ipopt_status
from gtmodel.modeling.ocp.budget import check_shooting_memory
from gtmodel.modeling.ocp.shooting_steps import (EXPLICIT_INTEGRATORS, ExplicitAlgebraics, collocation_steps, explicit_algebraics,
                                                  fixed_steps, stage_grid, stage_guess)
from gtmodel.modeling.ocp.shooting_bounds import (EVALUATION_STATUSES, check_between_nodes, clean_casadi_text, failure_message,
                                                   quiet_casadi)
from gtmodel.modeling.ocp.verification import check_result, verify_settings
from gtmodel.status import Status

__all__ = ["ShootingTranscription", "INTEGRATORS", "CONTROLS", "ROW_TOLERANCE"]

_log = logging.getLogger("gtmodel")

#: Integrator plugins of the shooting intervals.
INTEGRATORS = ("rk", "radau", "collocation", "cvodes", "idas")
#: Input parametrisations per interval.
CONTROLS = ("constant", "linear")
_SAMPLE_POINTS = 3  # Radau points per interval in the result's CollocationData
#: A written row exceeds a bound or path constraint when beyond it by more than this times
#: ``max(1, |bound|)`` (IPOPT holds them at the nodes to its tolerance, far below).
ROW_TOLERANCE = 1e-6


class ShootingTranscription:
    """An optimisation problem transcribed by direct multiple shooting, solvable repeatedly.

    Parameters
    ----------
    optimization : Optimization
        The declared problem.
    intervals : int, optional
        Number of uniform shooting intervals ``N``; default 50.
    controls : {"constant", "linear"}, optional
        Inputs piecewise constant (one value per interval) or piecewise linear
        (continuous, one value per node); default ``"constant"``.
    integrator : {"rk", "radau", "collocation", "cvodes", "idas"}, optional
        Integrator; default ``"rk"`` for ODEs, ``"collocation"`` for DAEs (measured on the
        drive problems: ``benchmarks/bench_shooting_integrators.py``).
    steps : int, optional
        Fixed steps per interval of ``"rk"``/``"radau"``/``"collocation"``; default 4.
    verbose : bool, optional
        Show IPOPT output; default False.
    solver_options : mapping, optional
        IPOPT and CasADi nlpsol options (as for
        :class:`~gtmodel.modeling.ocp.collocation.CollocationTranscription`).
    integrator_options : mapping, optional
        Options of ``casadi.integrator`` (e.g. ``{"abstol": 1e-10}`` for ``"cvodes"``); with
        ``"collocation"`` they select CasADi's ``collocation`` plugin (its rootfinder started
        from constants, the bounds imposed at the nodes only) instead of gtmodel's own.
    verify : bool or VerificationSettings, optional
        Verify every solution by simulation (:func:`gtmodel.modeling.ocp.verification.verify`:
        the piecewise constant or linear inputs drive the model in CVODES or IDAS, compared
        with the nodes and the integrator's sample points) with these settings
        (:class:`~gtmodel.modeling.ocp.methods.VerificationSettings`; True: the problem's
        :attr:`Optimization.verification_tolerance`, ...; the declaration is never changed):
        the result's ``verification``; a solution that fails it is ``check_failed``. Default True.

    Raises
    ------
    InputError
        If an argument is invalid (``"cvodes"``, or CasADi's ``"rk"`` plugin through
        ``integrator_options``, for a model with algebraic variables; ``"rk"``/``"radau"``
        for one whose algebraic variables cannot be eliminated symbolically), or the NLP's
        estimated memory exceeds the limit (:func:`~gtmodel.modeling.ocp.budget.check_shooting_memory`).
    ModelError
        If the model cannot be flattened.
    SolverError
        If CasADi cannot build the integrator or the NLP solver.
    """

    def __init__(
        self,
        optimization: Optimization,
        intervals: int = 50,
        controls: str = "constant",
        integrator: str | None = None,
        steps: int = 4,
        verbose: bool = False,
        solver_options: Mapping[str, Any] | None = None,
        integrator_options: Mapping[str, Any] | None = None,
        verify: Any = True,
    ) -> None:
        if not isinstance(optimization, Optimization):
            raise InputError(f"expected an Optimization, got {type(optimization).__name__}")
        if not isinstance(intervals, (int, np.integer)) or isinstance(intervals, bool) or intervals < 1:
            raise InputError(f"intervals must be a positive integer, got {intervals!r}")
        if controls not in CONTROLS:
            raise InputError(f"controls must be one of {', '.join(CONTROLS)}, got {controls!r}")
        if not isinstance(steps, (int, np.integer)) or isinstance(steps, bool) or steps < 1:
            raise InputError(f"steps must be a positive integer, got {steps!r}")
        if integrator is not None and integrator not in INTEGRATORS:
            raise InputError(f"integrator must be one of {', '.join(INTEGRATORS)}, got {integrator!r}")
        self.optimization = optimization
        self.dae: FlatDAE = optimization.flat()
        dae = self.dae
        # the memory this NLP needs, before any of it is built (budget.check_shooting_memory)
        self.size = check_shooting_memory(int(intervals), int(steps), dae.nx, dae.nz, dae.nu)
        eliminated = explicit_algebraics(dae) if dae.nz else ExplicitAlgebraics(ca.SX(0, 1))
        self._z_expr = eliminated.z
        # the default by measured speed and correctness on the drive problems (benchmarks/bench_shooting_integrators.py,
        # docs/problem_language.md): collocation for every DAE, rk for ODEs
        self.integrator = integrator or ("rk" if dae.nz == 0 else "collocation")
        plugin_rk = self.integrator == "rk" and bool(integrator_options)
        if dae.nz and (self.integrator == "cvodes" or plugin_rk):
            raise InputError(f"integrator {self.integrator!r}{' with integrator_options (CasADi plugin)' if plugin_rk else ''} "
                             "integrates ODEs only; the model has algebraic variables (use 'rk' or 'radau' on the explicit "
                             "form, 'collocation' or 'idas')")
        if self.integrator in EXPLICIT_INTEGRATORS and eliminated.z is None:
            raise InputError(f"integrator {self.integrator!r} integrates the explicit form, but the algebraic variables of "
                             f"{dae.name!r} cannot be eliminated symbolically ({eliminated.reason}): use 'collocation' or 'idas'")
        if self.integrator == "radau" and integrator_options:
            raise InputError("integrator_options apply to CasADi's integrator plugins (rk, collocation, cvodes, idas), not to 'radau'")
        # gtmodel's own collocation (shooting_steps.collocation_steps, its rootfinder started from a simulation of
        # the guess); with integrator_options, CasADi's plugin (its rootfinder started from constants)
        self.own_collocation = self.integrator == "collocation" and not integrator_options
        self.explicit = (self.integrator in EXPLICIT_INTEGRATORS and not plugin_rk) or (self.own_collocation and eliminated.z is not None)
        #: the interval's integrator returns its steps' ends (and stage points): bounds imposed and checked there
        self.stepwise = (self.integrator in EXPLICIT_INTEGRATORS and not plugin_rk) or self.own_collocation
        self.intervals, self.controls, self.steps = int(intervals), controls, int(steps)
        self.verbose = bool(verbose)
        options = dict(solver_options or {})
        if self.integrator in ("cvodes", "idas"):
            options.setdefault("hessian_approximation", "limited-memory")
        self._solver_options = options
        self.options = merge_options(verbose, options, "ipopt")
        self.integrator_options = dict(integrator_options or {})
        self.verify, self.verify_settings = bool(verify), verify_settings(verify)  # settings None: the declaration's own
        self._build()

    # ------------------------------------------------------------------ build
    def _interval_function(self) -> ca.Function:
        """The integrator over one interval: ``(x0, z0, p = [ua, ub, P, T, k, frac]) -> (xf, zf, qf[, xs, zs, ok])``.

        On the explicit form (``"rk"``, ``"radau"``: :func:`~gtmodel.modeling.ocp.shooting_steps.fixed_steps`)
        also the states and algebraic variables at every step's end and the stage Newton's
        convergence flag."""
        opt, dae = self.optimization, self.dae
        nu, N, t0 = dae.nu, self.intervals, opt.start_time
        tau = ca.SX.sym("tau")
        ua, ub = ca.SX.sym("ua", nu), ca.SX.sym("ub", nu)
        T, k, frac = ca.SX.sym("T"), ca.SX.sym("k"), ca.SX.sym("frac")
        h = (T - t0) / N
        t = t0 + (k + tau * frac) * h
        u = ua if self.controls == "constant" else (1 - tau * frac) * ua + tau * frac * ub
        integrands = [opt.objective_sign * opt.lagrange] + [v.expr for v in opt.integrals]
        f = self._point_function("interval", [dae.ode_expr, dae.alg_expr, ca.vertcat(*integrands)])
        ode, alg, quad = f(t, dae.x, dae.z, u, dae.p, T)
        p = ca.vertcat(ua, ub, dae.p, T, k, frac)
        if self.explicit:  # z(t, x, u, p) substituted: an ODE, integrated by fixed steps
            z_of = ca.substitute(self._z_expr, ca.vertcat(dae.t, dae.u), ca.vertcat(t, u)) if dae.nz else ca.SX(0, 1)
            if dae.nz:
                ode, quad = ca.substitute([ode, quad], [dae.z], [z_of])
            problem = {"x": dae.x, "p": p, "t": tau, "ode": frac * h * ode, "quad": frac * h * quad, "zout": z_of}
            self._guess_problem = {"x": dae.x, "p": p, "t": tau, "ode": frac * h * ode}
            if self.own_collocation:
                return collocation_steps(problem, self.steps)
            return fixed_steps(problem, self.steps, self.integrator)
        problem = {"x": dae.x, "p": p, "t": tau, "ode": frac * h * ode, "quad": frac * h * quad}
        if dae.nz:
            problem.update(z=dae.z, alg=alg)
        self._guess_problem = {k: v for k, v in problem.items() if k != "quad"}
        if self.own_collocation:
            return collocation_steps(problem, self.steps)
        opts = {"number_of_finite_elements": self.steps} if self.integrator in ("rk", "collocation") else {}
        opts.update(self.integrator_options)
        try:
            return ca.integrator("interval", self.integrator, problem, 0.0, 1.0, opts)
        except RuntimeError as exc:
            raise SolverError(f"could not build the {self.integrator} integrator: {exc}") from exc

    def _point_function(self, name: str, exprs: list[ca.SX], extra: tuple[ca.SX, ...] = ()) -> ca.Function:
        """``(t, x, z, u, p, tf[, extra]) -> exprs`` with ``der()`` of states replaced by the model's right-hand side."""
        dae, opt = self.dae, self.optimization
        out = [ca.substitute(e, dae.xdot, dae.ode_expr) if dae.nx else e for e in exprs]
        return ca.Function(name, [dae.t, dae.x, dae.z, dae.u, dae.p, opt.final_time, *extra], out)

    def _build(self) -> None:
        opt, dae = self.optimization, self.dae
        nx, nz, nu, N, t0 = dae.nx, dae.nz, dae.nu, self.intervals, opt.start_time
        F = self._interval_function()
        P = ca.MX.sym("p", int(dae.p.numel()))
        free_names = list(opt.free_parameters)
        free_idx = [i for n in free_names for i in range(dae.p_vars[n].start, dae.p_vars[n].stop)]
        PF = ca.MX.sym("pf", len(free_idx))
        Pm = ca.MX(P)
        for j, i in enumerate(free_idx):
            Pm[i] = PF[j]
        X = [ca.MX.sym(f"X_{k}", nx) for k in range(N + 1)]
        nU = N if self.controls == "constant" else N + 1
        U = [ca.MX.sym(f"U_{k}", nu) for k in range(nU)]
        Z = [ca.MX.sym(f"Z_{k}", nz) for k in range(N + 1)]
        Tv = ca.MX.sym("T") if opt.free_final_time else None
        T = Tv if Tv is not None else ca.MX(opt.final_time_value)
        h = (T - t0) / N
        # the collocation integrator's rootfinder start per interval (stage values less the step's start, from a
        # simulation of the guess: _stage_guess), NLP parameters after the model's
        m_dv = int(F.size1_in(3)) if self.own_collocation else 0
        DV = [ca.MX.sym(f"dv_{k}", m_dv, self.steps) for k in range(N)] if self.own_collocation else []
        Pn = ca.vertcat(P, *[ca.vec(d) for d in DV])
        self._dv_shape = (m_dv, self.steps)

        def dv(k: int) -> dict[str, ca.MX]:
            return {"dv": DV[k]} if DV else {}

        def u_node(k: int) -> ca.MX:
            return U[min(k, nU - 1)]

        def u_pair(k: int) -> tuple[ca.MX, ca.MX]:
            return (U[k], U[k + 1]) if self.controls == "linear" else (U[k], U[k])

        g, lbg, ubg = [], [], []

        def con(e: ca.MX, lb: Any, ub: Any) -> None:
            if e.numel():
                g.append(e)
                lbg.append(np.broadcast_to(lb, (e.numel(),)).astype(float))
                ubg.append(np.broadcast_to(ub, (e.numel(),)).astype(float))

        J = ca.MX(0)
        quads = ca.MX.zeros(len(opt.integrals), 1)
        paths = [c.expr for c in opt.path_constraints]
        node_fn = self._point_function("node", [dae.alg_expr, ca.vertcat(*paths) if paths else ca.SX(0, 1)])
        path_lb = np.concatenate([c.lb for c in opt.path_constraints]) if paths else np.zeros(0)
        path_ub = np.concatenate([c.ub for c in opt.path_constraints]) if paths else np.zeros(0)
        # bounds and path constraints at every step's end between the nodes (explicit form), and
        # checked at the written rows (all integrators)
        self._check_fn, self._check_lb, self._check_ub, self._check_names = self._checked_function(paths, path_lb, path_ub)
        # inequalities only: an equality path constraint held at every step's end would over-determine
        # the piecewise inputs (it is still checked at the written rows)
        finite = np.flatnonzero((np.isfinite(self._check_lb) | np.isfinite(self._check_ub)) & (self._check_lb < self._check_ub))
        # the step ends inside an interval (rk, radau), or every stage point but the interval's end (collocation)
        c_inner = stage_grid(self.steps)[1].reshape(-1)[:-1] if self.own_collocation else np.arange(1, self.steps) / self.steps
        inner = self.stepwise and c_inner.size > 0 and finite.size > 0
        if inner:
            ins = self._check_fn.sx_in()
            inner_map = ca.Function("between", ins, [self._check_fn(*ins)[finite.tolist()]]).map(c_inner.size)
            inner_lb = np.tile(self._check_lb[finite], c_inner.size)
            inner_ub = np.tile(self._check_ub[finite], c_inner.size)
        inner_pts: list[list[ca.MX]] = [[], [], [], []]  # t, x, z, u at the integrator's points inside the intervals
        steps_x, steps_z, oks = [], [], []
        for k in range(N):
            ua, ub = u_pair(k)
            r = F(**dv(k), x0=X[k], z0=Z[k], p=ca.vertcat(ua, ub, Pm, T, k, 1.0))
            con(X[k + 1] - r["xf"], 0.0, 0.0)
            J = J + r["qf"][0]
            if opt.integrals:
                quads = quads + r["qf"][1:]
            if self.stepwise:
                steps_x.append(r["xs"])
                steps_z.append(r["zs"])
                oks.append(r["ok"])
            if self.stepwise and c_inner.size:
                u_in = ca.repmat(ua, 1, c_inner.size) if self.controls == "constant" else \
                    ca.mtimes(ua, ca.DM(1 - c_inner).T) + ca.mtimes(ub, ca.DM(c_inner).T)
                t_in = t0 + (k + ca.DM(c_inner).T) * h
                x_in, z_in = (r["xc"], r["zc"]) if self.own_collocation else (r["xs"], r["zs"])
                for store, value in zip(inner_pts, (t_in, x_in[:, :-1], z_in[:, :-1], u_in)):
                    store.append(value)
                if inner:
                    con(ca.vec(inner_map(t_in, x_in[:, :-1], z_in[:, :-1], u_in, Pm, T)), inner_lb, inner_ub)
        for k in range(N + 1):
            alg, path = node_fn(t0 + k * h, X[k], Z[k], u_node(k), Pm, T)
            con(alg, 0.0, 0.0)
            con(path, path_lb, path_ub)
        # timed variables and integrals, then the point constraints and the Mayer term
        values = []
        for v in opt.special_symbols():
            if isinstance(v, Integral):
                values.append(quads[opt.integrals.index(v)])
                continue
            f = self._point_function("timed", [v.expr])
            if v.time in ("start", "final"):
                k = 0 if v.time == "start" else N
                values.append(f(t0 + k * h, X[k], Z[k], u_node(k), Pm, T))
                continue
            # normalised time: a fixed time of a fixed horizon, or a fixed fraction of a free one
            s = N * (v.fraction if v.fraction is not None else (float(v.time) - t0) / (opt.final_time_value - t0))
            k = int(np.clip(np.ceil(s - 1e-9) - 1, 0, N - 1))
            frac = float(np.clip(s - k, 0.0, 1.0))
            ua, ub = u_pair(k)
            r = F(**dv(k), x0=X[k], z0=Z[k], p=ca.vertcat(ua, ub, Pm, T, k, frac))
            u_t = ua if self.controls == "constant" else (1 - frac) * ua + frac * ub
            t_v = float(v.time) if v.fraction is None else t0 + v.fraction * (T - t0)
            values.append(f(t_v, r["xf"], r["zf"] if nz else ca.MX(0, 1), u_t, Pm, T))
        s_sym = ca.vertcat(*[v.symbol for v in opt.special_symbols()]) if opt.special_symbols() else ca.SX(0, 1)
        s_val = ca.vertcat(*values) if values else ca.MX(0, 1)
        for at, k in (("start", 0), ("final", N), ("timed", N)):
            cs = [c for c in opt.point_constraints if c.at == at]
            if cs:
                f = self._point_function(f"point_{at}", [ca.vertcat(*[c.expr for c in cs])], (s_sym,))
                con(f(t0 + k * h, X[k], Z[k], u_node(k), Pm, T, s_val), np.concatenate([c.lb for c in cs]),
                    np.concatenate([c.ub for c in cs]))
        J_lagrange = J
        mayer = self._point_function("mayer", [opt.objective_sign * opt.mayer], (s_sym,))
        J = J + mayer(T, X[N], Z[N], u_node(N), Pm, T, s_val)

        blocks = [("x", X), ("u", U), ("z", Z)]
        w = ca.vertcat(*X, *U, *Z, *([Tv] if Tv is not None else []), PF)
        x_lb, x_ub = opt.bounds_vectors(dae, "x")
        u_lb, u_ub = opt.bounds_vectors(dae, "u")
        z_lb, z_ub = opt.bounds_vectors(dae, "z")
        lbw = [np.tile(x_lb, N + 1), np.tile(u_lb, nU), np.tile(z_lb, N + 1)]
        ubw = [np.tile(x_ub, N + 1), np.tile(u_ub, nU), np.tile(z_ub, N + 1)]
        if Tv is not None:
            lbw.append(np.array([opt.final_time_bounds[0]]))
            ubw.append(np.array([opt.final_time_bounds[1]]))
        for n in free_names:
            lbw.append(opt.free_parameters[n][0])
            ubw.append(opt.free_parameters[n][1])
        self._lbw, self._ubw = np.concatenate(lbw), np.concatenate(ubw)
        self._lbg = np.concatenate(lbg) if lbg else np.zeros(0)
        self._ubg = np.concatenate(ubg) if ubg else np.zeros(0)
        self._sizes = {"x": (N + 1, nx), "u": (nU, nu), "z": (N + 1, nz)}
        self._free_idx = np.array(free_idx, dtype=int)
        self._blocks = blocks
        gv = ca.vertcat(*g) if g else ca.MX(0, 1)
        self._fg = ca.Function("fg", [w, Pn], [J, gv])
        self.special_function = ca.Function("special", [w, Pn], [s_val])
        self.lagrange_function = ca.Function("lagrange_value", [w, Pn], [J_lagrange])
        # the result's samples: node states, and the states/inputs at the ends of (up to
        # _SAMPLE_POINTS + 1) integration steps of each interval (explicit form, 3 steps or more:
        # points where the bounds were imposed), else at the Radau points, integrated there
        samples_at_steps = self.stepwise and self.steps >= _SAMPLE_POINTS
        if samples_at_steps:
            d = min(self.steps, _SAMPLE_POINTS + 1)
            ends = [int(round((j + 1) * self.steps / d)) for j in range(d)]
            tau = np.array(ends, dtype=float) / self.steps
        else:
            tau = np.array(ca.collocation_points(_SAMPLE_POINTS, "radau"), dtype=float)
        xs, us, zs = [], [], []
        for k in range(N):
            ua, ub = u_pair(k)
            xs.append(X[k])
            for j, c in enumerate(tau):
                if samples_at_steps:
                    xs.append(steps_x[k][:, ends[j] - 1])
                    zs.append(steps_z[k][:, ends[j] - 1])
                else:
                    r = F(**dv(k), x0=X[k], z0=Z[k], p=ca.vertcat(ua, ub, Pm, T, k, float(c)))
                    xs.append(r["xf"])
                    zs.append(r["zf"] if nz else ca.MX(0, 1))
                us.append(ua if self.controls == "constant" else (1 - c) * ua + c * ub)
        ok = ca.horzcat(*oks) if oks else ca.MX.ones(1, N)
        self._samples = ca.Function("samples", [w, Pn], [ca.horzcat(*xs), ca.horzcat(*us), ca.horzcat(*zs), T, Pm,
                                                        ca.horzcat(*Z[:N]), ca.horzcat(*[u_pair(k)[0] for k in range(N)]), ok])
        self._tau = tau
        # the integrator's own points inside the intervals (none for cvodes/idas): checked by shooting_bounds
        self._inner_points = ca.Function("inner_points", [w, Pn], [ca.horzcat(*v) if v else ca.MX(0, 0) for v in inner_pts])
        # the guess simulation's arguments per interval: node state, node algebraics, the integrator's parameters
        self._interval_args = ca.Function("interval_args", [w, P], [ca.horzcat(*X[:N]), ca.horzcat(*Z[:N]), ca.horzcat(
            *[ca.vertcat(*u_pair(k), Pm, T, k, 1.0) for k in range(N)])])
        self.nlp = {"x": w, "p": Pn, "f": J, "g": gv}
        try:
            self.solver = ca.nlpsol(f"{casadi_name(dae.name)}_shooting", "ipopt", self.nlp, self.options)
        except RuntimeError as exc:
            raise SolverError(f"could not build the ipopt solver: {exc}") from exc
        self.key = (id(self), "multiple_shooting", N, self.controls, int(w.numel()), self.integrator)
        _log.debug("multiple shooting NLP for %s: %d variables, %d constraints", dae.name, w.numel(), gv.numel())

    def set_solver_options(self, solver_options: Mapping[str, Any]) -> None:
        """Rebuild the solver with further IPOPT options (the NLP is kept; about a second for a drive).

        Parameters
        ----------
        solver_options : mapping
            Options merged over the current ones, as ``solver_options`` of the constructor
            (plain IPOPT names, e.g. ``{"max_cpu_time": 120.0}``).

        Raises
        ------
        SolverError
            The solver cannot be built with these options.
        """
        self._solver_options.update(solver_options)
        self.options = merge_options(self.verbose, self._solver_options, "ipopt")
        try:
            self.solver = ca.nlpsol(f"{casadi_name(self.dae.name)}_shooting", "ipopt", self.nlp, self.options)
        except RuntimeError as exc:
            raise SolverError(f"could not build the ipopt solver: {exc}") from exc

    # ------------------------------------------------------------------ guesses
    def _initial_w(self, guesses: Mapping[str, Any], tf_guess: float, pvec: np.ndarray) -> np.ndarray:
        opt, dae, N = self.optimization, self.dae, self.intervals
        t0 = opt.start_time
        h = (tf_guess - t0) / N
        parts = []
        for kind, vars_, start in (("x", dae.x_vars, dae.x_start), ("u", dae.u_vars, None), ("z", dae.z_vars, dae.z_start)):
            count, n = self._sizes[kind]
            block = np.zeros((count, n))
            for name, sl in vars_.items():
                default = (opt.model._vars[name].start.copy() if start is None else start[sl].copy())
                f = _guess_fn(guesses.get(name), sl.stop - sl.start, name, default)
                for k in range(count):
                    tk = t0 + (k + (0.5 if kind == "u" and self.controls == "constant" else 0.0)) * h
                    block[k, sl] = f(tk)
            parts.append(block.reshape(-1))
        if opt.free_final_time:
            parts.append(np.array([tf_guess]))
        for name, (lb, ub, start) in opt.free_parameters.items():
            parts.append(start if start is not None else np.clip(pvec[dae.p_vars[name]], lb, ub))
        return np.clip(np.concatenate(parts), self._lbw, self._ubw)

    # ------------------------------------------------------------------ solve
    def solve(self, parameters: Mapping[str, Any] | None = None, initial_guess: OptimizationResult | Mapping[str, Any] | None = None) -> OptimizationResult:
        """Solve the NLP; never raises for a non-optimal outcome.

        Parameters
        ----------
        parameters : mapping of str to float or array_like, optional
            Parameter values overriding the model defaults and
            :meth:`Optimization.set_parameter`.
        initial_guess : OptimizationResult or mapping, optional
            A previous result of this transcription (its NLP vector is reused), another
            result (sampled at the nodes), or a mapping from variable names (and
            ``"final_time"``) to guesses (formats of :meth:`Optimization.set_initial_guess`).

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
        pvec = dae.parameter_vector({**opt.parameters, **dict(parameters or {})})
        guesses: dict[str, Any] = dict(opt.initial_guesses)
        tf_guess = opt.final_time_guess
        w0 = None
        if isinstance(initial_guess, OptimizationResult):
            if initial_guess.transcription_key == self.key and initial_guess.w is not None:
                w0 = np.clip(initial_guess.w, self._lbw, self._ubw)
            elif initial_guess.collocation is not None:
                res = initial_guess
                tf_guess = float(np.clip(res.final_time, *opt.final_time_bounds))
                for cat, vars_ in (("states", dae.x_vars), ("inputs", dae.u_vars), ("algebraics", dae.z_vars)):
                    for name in vars_:
                        guesses[name] = _sampled(res, cat, name)
        elif isinstance(initial_guess, Mapping):
            for name, value in initial_guess.items():
                if name == "final_time":
                    tf_guess = float(np.clip(float(value), *opt.final_time_bounds))
                elif name in {**dae.x_vars, **dae.z_vars, **dae.u_vars}:
                    guesses[name] = value
                else:
                    raise InputError(f"initial_guess: {name!r} is not a state, input or algebraic variable")
        elif initial_guess is not None:
            raise InputError("initial_guess must be an OptimizationResult or a mapping")
        if w0 is None:
            w0 = self._initial_w(guesses, tf_guess, pvec)
        t_start = _time.perf_counter()
        lam = (None, None)
        stats: dict = {}
        with quiet_casadi(passthrough=self.verbose) as out:
            failure = None
            try:
                pfull = np.concatenate([pvec, self._stage_guess(w0, pvec)])
            except RuntimeError as exc:
                failure = ("start", exc)
            else:
                try:
                    sol = self.solver(x0=w0, lbx=self._lbw, ubx=self._ubw, lbg=self._lbg, ubg=self._ubg, p=pfull)
                    w = np.array(sol["x"], dtype=float).reshape(-1)
                    lam = (np.array(sol["lam_x"], dtype=float).reshape(-1), np.array(sol["lam_g"], dtype=float).reshape(-1))
                except RuntimeError as exc:
                    failure = ("solve", exc)
                stats = dict(self.solver.stats())
        solve_time = _time.perf_counter() - t_start
        message = str(stats.get("return_status", "unknown"))
        evaluation = out.failed_evaluation() or (failure is not None)
        # IPOPT's own NaN/Inf check (an RK step overflowing, no exception raised) is such a failure too: one line
        if failure is not None or (evaluation and message in EVALUATION_STATUSES) or message == "Invalid_Number_Detected":
            stage = failure[0] if failure else "solve"
            iteration = int(stats.get("iter_count", 0) or 0)
            message = failure_message(self.integrator, "the start" if stage == "start" else f"iteration {iteration}",
                                      out.text() + (str(failure[1]) if failure else ""), self.steps)
            _log.warning("multiple shooting solve of %s: %s", dae.name, message)
            return self._error(message, stats, solve_time, w0)
        status = Status.ERROR if not np.all(np.isfinite(w)) else normalize_ipopt_status(message)
        with quiet_casadi() as out:
            res = self._result(w, pfull, status, message, stats, solve_time)
        res.message = with_culprit(res.message, res, self.optimization)  # a failed solve names its likely culprit
        if res.status == Status.ERROR:
            return res
        res.lam_w, res.lam_g = lam
        if self.verify and res.status in (Status.OPTIMAL, Status.ACCEPTABLE):
            with quiet_casadi() as out:
                try:
                    special = np.array(self.special_function(w, pfull), dtype=float).reshape(-1)
                    check_result(res, opt, special, what="multiple shooting solve", lagrange=float(self.lagrange_function(w, pfull)),
                                 settings=self.verify_settings)
                except RuntimeError as exc:
                    message = failure_message(self.integrator, "the verification", out.text() + str(exc), self.steps)
                    _log.warning("multiple shooting solve of %s: %s", dae.name, message)
                    return self._error(message, stats, solve_time, w)
            if res.verification is not None:  # a failed verifying simulation quotes CasADi: its flag only
                res.verification.message = clean_casadi_text(res.verification.message or "")
            res.message = clean_casadi_text(res.message)
        if res.status in (Status.OPTIMAL, Status.ACCEPTABLE, Status.CHECK_FAILED):
            with quiet_casadi():
                check_between_nodes(self, res, w, pfull)
        return res

    def _stage_guess(self, w0: np.ndarray, pvec: np.ndarray) -> np.ndarray:
        """The collocation integrator's rootfinder start (``dv`` of every interval, flattened), from a simulation of ``w0``.

        Empty for the other integrators (:func:`~gtmodel.modeling.ocp.shooting_steps.stage_guess`)."""
        if not self.own_collocation:
            return np.zeros(0)
        xk, zk, pk = (np.array(v, dtype=float) for v in self._interval_args(w0, pvec))
        dv, failed = stage_guess(self._guess_problem, xk, zk.reshape(-1, self.intervals) if zk.size else np.zeros((0, self.intervals)),
                                 pk, self.steps)
        if failed:
            _log.info("multiple shooting of %s: the guess of %d of %d intervals could not be simulated; their rootfinders start "
                      "from the node values", self.dae.name, failed, self.intervals)
        m, n = self._dv_shape
        # per interval its (m, steps) block, column-major as ca.vec flattens it
        return np.concatenate([dv[:, k * n:(k + 1) * n].reshape(-1, order="F") for k in range(self.intervals)])

    def _error(self, message: str, stats: dict, solve_time: float, w: np.ndarray) -> OptimizationResult:
        """A result with status ``error``, ``message`` and no trajectory."""
        return OptimizationResult(status=Status.ERROR, message=message, iterations=int(stats.get("iter_count", 0) or 0),
                                  solve_time=solve_time, objective=float("nan"), final_time=float("nan"),
                                  max_constraint_violation=float("nan"), t=np.zeros(0), states={}, inputs={}, algebraics={},
                                  outputs={}, last_iterate=True, stats=stats, dae=self.dae, w=w.copy(), transcription_key=self.key)

    def _result(self, w: np.ndarray, pvec: np.ndarray, status: str, message: str, stats: dict, solve_time: float) -> OptimizationResult:
        opt, dae, N, d = self.optimization, self.dae, self.intervals, len(self._tau)
        try:
            f_val, g_val = (np.array(v, dtype=float).reshape(-1) for v in self._fg(w, pvec))
            xs, us, zs, T, p_all, zn, un, ok = (np.array(v, dtype=float) for v in self._samples(w, pvec))
        except RuntimeError as exc:  # the integrator failed at this point
            message = f"{message}; {failure_message(self.integrator, 'the returned point', str(exc), self.steps)}"
            _log.warning("multiple shooting of %s: %s", dae.name, message)
            return self._error(message, stats, solve_time, w)
        viol = [0.0]
        if g_val.size:
            viol.append(float(np.max(np.maximum(self._lbg - g_val, g_val - self._ubg))))
        if w.size:
            viol.append(float(np.max(np.maximum(self._lbw - w, w - self._ubw))))
        tf = float(T.reshape(-1)[0])
        colloc = CollocationData(
            t0=opt.start_time, tf=tf, elements=N, points=d, scheme="radau",
            tau_root=np.concatenate([[0.0], self._tau]),
            xc=xs.reshape(dae.nx, N, d + 1).transpose(1, 2, 0),
            uc=us.reshape(dae.nu, N, d).transpose(1, 2, 0),
            zc=zs.reshape(dae.nz, N, d).transpose(1, 2, 0), shooting=self.controls,
            zn=zn.reshape(dae.nz, N).T, un=un.reshape(dae.nu, N).T,
        )
        t = colloc.mesh()
        x, u, z = colloc.evaluate(t)
        pvec = p_all.reshape(-1)
        warnings = []
        if status in (Status.OPTIMAL, Status.ACCEPTABLE):
            warnings = self._row_warnings(t, x, z, u, pvec, tf)
            bad = np.flatnonzero(ok.reshape(-1) < 0.5)
            if bad.size:
                warnings.append(f"the {self.integrator} integrator's stage Newton iteration did not converge on {bad.size} of {N} "
                                f"shooting intervals (first at t = {colloc.breaks()[bad[0]]:.6g} s): more transcription.steps")
            for text in warnings:
                _log.warning("multiple shooting solve of %s: %s", dae.name, text)
        try:
            outs = _eval_outputs(dae, t, x, z, u, pvec)
        except RuntimeError:
            outs = {}
        if status != "optimal":
            _log.warning("multiple shooting solve of %s ended with status %s (%s)", dae.name, status, message)
        return OptimizationResult(
            status=status, message=message, iterations=int(stats.get("iter_count", 0) or 0), solve_time=solve_time,
            objective=opt.objective_sign * float(f_val[0]), final_time=tf,
            max_constraint_violation=float(max(viol)) if np.all(np.isfinite(g_val)) else float("nan"),
            t=t, states=_unpack(dae.x_vars, x), inputs=_unpack(dae.u_vars, u), algebraics=_unpack(dae.z_vars, z), outputs=outs,
            parameters={k: pvec[s].copy() for k, s in dae.p_vars.items()}, last_iterate=status not in ("optimal", "acceptable"),
            stats=stats, collocation=colloc, dae=dae, w=w.copy(), transcription_key=self.key, warnings=warnings,
        )

    def _checked_function(self, paths: list[ca.SX], path_lb: np.ndarray, path_ub: np.ndarray) -> tuple[ca.Function, np.ndarray, np.ndarray, list[str]]:
        """``check(t, x, z, u, p, tf) -> [path constraints; x; z]``, its bounds and a name per entry."""
        opt, dae = self.optimization, self.dae
        x_lb, x_ub = opt.bounds_vectors(dae, "x")
        z_lb, z_ub = opt.bounds_vectors(dae, "z")
        names = [c.name or "path constraint" for c in opt.path_constraints for _ in range(int(c.expr.numel()))]
        names += [f"state {n!r}" for n in dae.x_names] + [f"algebraic variable {n!r}" for n in dae.z_names]
        exprs = [*paths, dae.x, dae.z]
        fn = self._point_function("check", [ca.vertcat(*exprs)])
        return (fn, np.concatenate([path_lb, x_lb, z_lb]).astype(float), np.concatenate([path_ub, x_ub, z_ub]).astype(float), names)

    def _row_warnings(self, t: np.ndarray, x: np.ndarray, z: np.ndarray, u: np.ndarray, pvec: np.ndarray, tf: float) -> list[str]:
        """One sentence per bound or path constraint that the written rows exceed beyond :data:`ROW_TOLERANCE`."""
        lb, ub = self._check_lb, self._check_ub
        if not (np.isfinite(lb).any() or np.isfinite(ub).any()) or t.size == 0:
            return []
        vals = np.array(self._check_fn.map(t.size)(t.reshape(1, -1), x.T, z.T, u.T, pvec, tf), dtype=float)  # (m, K)
        with np.errstate(invalid="ignore"):
            over = np.maximum(vals - ub[:, None], lb[:, None] - vals)  # > 0 outside the bounds
        finite = np.where(np.isfinite(lb), np.abs(lb), 0.0), np.where(np.isfinite(ub), np.abs(ub), 0.0)
        tol = ROW_TOLERANCE * np.maximum(1.0, np.maximum(*finite))[:, None]
        out = []
        remedy = ("more transcription.intervals or steps" if self.stepwise else
                  "integrator = \"radau\" or \"rk\" (3 or more transcription.steps) imposes the bounds at every integration step; "
                  "or more transcription.intervals")
        for i in np.flatnonzero(np.any(over > tol, axis=1)):
            j = int(np.nanargmax(over[i]))
            side, bound = ("upper", ub[i]) if vals[i, j] > ub[i] else ("lower", lb[i])
            count = int(np.sum(over[i] > tol[i]))
            out.append(f"{self._check_names[i]} exceeds its {side} bound {bound:.6g} between the shooting nodes: {vals[i, j]:.6g} "
                       f"at t = {t[j]:.6g} s ({count} of {t.size} written rows beyond the tolerance {tol[i, 0]:.2g}); {remedy}")
        return out


def _sampled(result: OptimizationResult, group: str, name: str) -> Any:
    """``f(t)``: variable ``name`` of ``result`` (``group`` states/inputs/algebraics) sampled at ``t`` (clipped to its horizon)."""

    def f(t: float) -> np.ndarray:
        return np.asarray(result.sample([min(t, result.final_time)])[group][name], dtype=float).reshape(-1)

    return f
