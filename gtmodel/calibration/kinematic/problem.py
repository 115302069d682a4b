"""The kinematic calibration problem of a model and a parameter selection.

:class:`CalibrationProblem` builds the CasADi graphs once (per group of arms, see
:mod:`~gtmodel.calibration.kinematic.residuals`) and solves them for any data and start:
frame alignment guarded by the cost, a rank check at the start, least_squares or IPOPT
per group, quaternion re-anchoring, statistics (Dressler (2012), eqs. 5.1-5.4). What
comes before the solves (data keys and caches per data set, the frame alignment, whether
the graphs hold for the start model) is in :mod:`~gtmodel.calibration.kinematic.start`.
"""

from __future__ import annotations

import difflib
import logging
import math
import time
from typing import Any

import casadi as ca
import numpy as np
import scipy.optimize

from gtmodel.calibration.identifiability import (
    IdentifiabilityReport,
    analyze_jacobian,
    analyze_qr,
    combine_reports,
    numerical_rank,
)
from gtmodel.calibration.kinematic.data import _check_data, _Data, _unpack_measurements
from gtmodel.calibration.kinematic.graph_cache import (
    GRAPH_CACHE_SIZE,
    _arm_parameter_indices,
    _bounded_add,
    shared_groups,
)
from gtmodel.calibration.kinematic.lsq import LSQ_TOLERANCE, POLISH_MAX_STEP, POLISH_STEPS, _polish, _solve_minpack
from gtmodel.calibration.kinematic.residuals import _Evaluator, _Group
from gtmodel.calibration.kinematic.result import CalibrationResult, GroupResult
from gtmodel.calibration.kinematic.selection import ParameterSelection, _parameter_expression
from gtmodel.calibration.kinematic.start import FK_CACHE_SIZE, _ProblemStart
from gtmodel.errors import InputError, ModelError
from gtmodel.modeling.ocp.result import normalize_ipopt_status
from gtmodel.robots.closure import ClosureModel
from gtmodel.status import Status

__all__ = [
    "CalibrationProblem",
    "SOLVERS",
    "DEFAULT_SOLVER",
    "MAX_ITER",
    "LSQ_TOLERANCE",
    "POLISH_STEPS",
    "POLISH_MAX_STEP",
    "REANCHOR_ANGLE",
    "MAX_REANCHOR",
    "FK_CACHE_SIZE",
    "GRAPH_CACHE_SIZE",
]

_log = logging.getLogger("gtmodel")

#: Solver names: SciPy least_squares ("lm": MINPACK Levenberg-Marquardt, "trf": trust
#: region reflective) with the exact CasADi Jacobian, IPOPT with the exact Hessian of
#: V ("ipopt") or the Gauss-Newton Hessian 2 J^T J ("ipopt-gn").
SOLVERS = ("lm", "trf", "ipopt", "ipopt-gn")
#: Default solver, chosen by measurement (see the module docstring).
DEFAULT_SOLVER = "lm"
#: Iteration limit per group: residual evaluations (``max_nfev``) for "lm"/"trf", IPOPT
#: iterations for "ipopt"/"ipopt-gn".
MAX_ITER = 200
#: Rotation [rad] of a quaternion's local variables beyond which a failed solve is repeated
#: from the re-set anchor (the anchor is always re-set to the solution).
REANCHOR_ANGLE = 0.5
#: Maximum number of such re-anchored solves.
MAX_REANCHOR = 5

class CalibrationProblem(_ProblemStart):
    """Calibration NLPs of a model and a parameter selection, built once, solved many times.

    The CasADi graphs depend on the model's structure and the selection only: the data
    (poses, measurements, weights) and the start values are inputs. They are evaluated
    with the parameter vector of any model with the same structure (``with_parameters``
    or ``transformed`` of ``model``): a closure model's equations depend on the instance
    only through its parameter vector (the :class:`~gtmodel.robots.closure.ClosureModel`
    contract).

    Parameters
    ----------
    model : ClosureModel
        The (nominal) model.
    selection : ParameterSelection, optional
        Free/fixed/tied parameters; default: all parameters free.

    Raises
    ------
    InputError
        If the selection does not fit the model: unknown names (with close matches), a
        parameter both free and fixed, a tie whose target is free or fixed, tie cycles,
        ties on quaternion components, or a quaternion that is only partly free.
    ModelError
        If a free parameter enters no closure equation (it cannot be identified).
    """

    def __init__(self, model: ClosureModel, selection: ParameterSelection | None = None) -> None:
        if not isinstance(model, ClosureModel):
            raise InputError(f"model: expected a ClosureModel, got {type(model).__name__}")
        self.model = model
        self.selection = selection if selection is not None else ParameterSelection()
        self.resolution = self.selection._resolve(model)
        res = self.resolution
        n_arms = len(model.links)
        arm_vars = [res.variables_of(_arm_parameter_indices(model, a)) for a in range(n_arms)]
        used = set().union(*arm_vars) if arm_vars else set()
        unused = [res.var_names[v] for v in range(res.n_vars) if v not in used]
        if unused:
            raise ModelError(
                f"{model.name}: free parameter(s) {', '.join(unused)} enter no closure equation and cannot be "
                "identified from these measurements; fix them"
            )
        # connected components of arms over shared variables
        parent = list(range(n_arms))

        def find(a: int) -> int:
            while parent[a] != a:
                parent[a] = parent[parent[a]]
                a = parent[a]
            return a

        for a in range(n_arms):
            for b in range(a + 1, n_arms):
                if arm_vars[a] & arm_vars[b]:
                    parent[find(b)] = find(a)
        comps: dict[int, list[int]] = {}
        for a in range(n_arms):
            comps.setdefault(find(a), []).append(a)
        self.arm_groups: tuple[tuple[int, ...], ...] = tuple(tuple(v) for v in comps.values())
        self._group_vars = [sorted(set().union(*[arm_vars[a] for a in arms])) for arms in self.arm_groups]
        self._groups: list[_Group] | None = None
        self._pfun: ca.Function | None = None
        self._closure_cache: dict[int, ca.Function] = {}
        self._fk_cache: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        # per data set (keyed by a hash of q, T, quat, weights): evaluators bound to its
        # padded arrays, the chosen alignment per start vector, the start rank checks passed
        self._eval_cache: dict[str, list[_Evaluator]] = {}
        self._align_cache: dict[tuple[str, bytes], tuple[int, np.ndarray, np.ndarray]] = {}
        self._rank_ok: set[tuple[str, int, bytes]] = set()
        self._transform_safe: bool | None = None
        self._last_data: tuple[tuple[np.ndarray, ...], str] | None = None
        self.build_time = 0.0

    # -------------------------------------------------------------- building
    @property
    def variable_names(self) -> tuple[str, ...]:
        """Names of all NLP variables (free parameters; quaternions as ``_rx, _ry, _rz``)."""
        return self.resolution.var_names

    def _build(self) -> float:
        if self._groups is not None:
            return 0.0
        t0 = time.perf_counter()
        self._groups = shared_groups(self.model, self.resolution, self.selection, self.arm_groups, self._group_vars)
        x = ca.SX.sym("x", self.resolution.n_vars)
        pb = ca.SX.sym("p0", self.model.n_parameters)
        p = _parameter_expression(self.resolution, x, pb, {v: v for v in range(self.resolution.n_vars)})
        self._pfun = ca.Function("p_of_x", [x, pb], [p, ca.densify(ca.jacobian(p, x))])
        n_p, n_x = self.model.n_parameters, self.resolution.n_vars
        self._pfun_io = [np.zeros(n_x), np.zeros(n_p), np.zeros(n_p), np.zeros((n_x, n_p))]
        self._pfun_fb, self._pfun_ev = self._pfun.buffer()
        for i, a in enumerate(self._pfun_io[:2]):
            if a.size:
                self._pfun_fb.set_arg(i, memoryview(a))
        for i, a in enumerate(self._pfun_io[2:]):
            if a.size:
                self._pfun_fb.set_res(i, memoryview(a))
        dt = time.perf_counter() - t0
        self.build_time += dt
        return dt

    # -------------------------------------------------------------- helpers
    def _anchor(self, p: np.ndarray) -> np.ndarray:
        """Start/anchor vector: quaternions normalised, ties applied."""
        pb = np.array(p, dtype=float)
        for qi in self.resolution.quaternions:
            v = pb[list(qi)]
            nv = np.linalg.norm(v)
            if not nv > 0:
                raise InputError(f"{self.model.name}: quaternion parameter {self.resolution.names[qi[0]]} is zero")
            pb[list(qi)] = v / nv
        for t in self.resolution.targets:
            pb[t] = pb[int(self.resolution.root[t])]
        return pb

    def _x_of(self, pb: np.ndarray) -> np.ndarray:
        """Variables at the anchor ``pb``: free scalars their values, rotations zero."""
        x = np.zeros(self.resolution.n_vars)
        for v, comp in enumerate(self.resolution.var_comp):
            if comp < 0:
                x[v] = pb[self.resolution.var_kind[self.resolution.kind_of_var[v]][1]]
        return x

    def _p_of(self, x: np.ndarray, pb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Parameter vector p(x, p0) and dp/dx (n_parameters, n_variables)."""
        xin, pin, pout, dpout = self._pfun_io
        xin[:] = x
        pin[:] = pb
        self._pfun_ev()
        return pout.copy(), dpout.T.copy()  # the buffer holds dp/dx column-major

    def _check_counts(self, data: _Data) -> None:
        n_active = int(np.sum(data.weights > 0))
        for arms, g in zip(self.arm_groups, self._group_vars):
            m = n_active * sum(len(self.model.links[a]) for a in arms)
            if g and m < len(g):
                arm_s = ", ".join(str(a + 1) for a in arms)
                raise InputError(
                    f"too few poses for arm(s) {arm_s}: {m} residuals ({n_active} poses with non-zero weight) "
                    f"for {len(g)} free parameters"
                )

    # -------------------------------------------------------------- public
    def jacobian(
        self,
        p: np.typing.ArrayLike,
        q: np.typing.ArrayLike,
        T: np.typing.ArrayLike,
        quat: np.typing.ArrayLike | None = None,
        weights: np.typing.ArrayLike | None = None,
    ) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
        """Closure residuals and their exact Jacobian with respect to all free variables.

        Parameters
        ----------
        p : array_like, shape (n_parameters,)
            Parameter values (quaternion variables are evaluated at their anchor ``p``).
        q : array_like, shape (N, n_q)
            Actuator values [m, rad].
        T : array_like, shape (N, 3)
            TCP positions [m].
        quat : array_like, shape (N, 4), optional
            Plate orientations ``(w, x, y, z)`` (required for models with orientation).
        weights : array_like, shape (N,), optional
            Pose weights (residuals are multiplied by their square root).

        Returns
        -------
        r : numpy.ndarray, shape (N, n_links)
            Weighted residuals [m^2], links in model order.
        J : numpy.ndarray, shape (N, n_links, n_variables)
            ``d r / d x`` per pose (zero where a link does not depend on a variable).
        names : tuple of str
            Variable names (columns of ``J``).

        Raises
        ------
        InputError
            Wrong shapes or non-finite data.
        """
        data = _check_data(self.model, q, T, quat, weights)
        pa = np.asarray(p, dtype=float).ravel()
        if pa.size != self.model.n_parameters or not np.all(np.isfinite(pa)):
            raise InputError(f"p: expected {self.model.n_parameters} finite parameter values, got {pa.size}")
        self._build()
        pb = self._anchor(pa)
        x_all = self._x_of(pb)
        N = data.N
        offsets = np.cumsum([0] + [len(l) for l in self.model.links])
        r_out = np.zeros((N, self.model.n_links))
        J_out = np.zeros((N, self.model.n_links, self.resolution.n_vars))
        for grp in self._groups:
            ev = _Evaluator(grp, data, pb)
            r, J = ev.residuals_jacobian(x_all[grp.var_idx])
            rows = np.concatenate([np.arange(offsets[a], offsets[a + 1]) for a in grp.arms])
            r_out[:, rows] = r.reshape(N, grp.nr)
            if grp.nx:
                J_out[np.ix_(np.arange(N), rows, grp.var_idx)] = J.reshape(N, grp.nr, grp.nx)
        return r_out, J_out, self.resolution.var_names

    def solve(
        self,
        q: Any,
        T: np.typing.ArrayLike | None = None,
        quat: np.typing.ArrayLike | None = None,
        weights: np.typing.ArrayLike | None = None,
        start: ClosureModel | np.typing.ArrayLike | None = None,
        solver: str = DEFAULT_SOLVER,
        align: bool = True,
        max_iter: int = MAX_ITER,
    ) -> CalibrationResult:
        """Calibrate: align the frame, solve each group of arms, report.

        Parameters
        ----------
        q : array_like, shape (N, n_q), or MeasurementSet
            Actuator values [m, rad] (or a measurement set with ``q, T, quat, weights``).
        T : array_like, shape (N, 3)
            Measured TCP positions [m] (omit when ``q`` is a measurement set).
        quat : array_like, shape (N, 4), optional
            Measured plate orientations ``(w, x, y, z)`` (required for models with
            orientation, ignored by constant-orientation models).
        weights : array_like, shape (N,), optional
            Non-negative pose weights; residuals are multiplied by ``sqrt(w)``.
        start : ClosureModel or array_like, optional
            Start model or parameter vector (default: the problem's model). Must have
            the structure of the problem's model.
        solver : {"lm", "trf", "ipopt", "ipopt-gn"}, optional
            Solver (default :data:`DEFAULT_SOLVER`).
        align : bool, optional
            Move the start model into the measurement frame first (eqs. 5.3-5.4).
        max_iter : int, optional
            Iteration limit per group.

        Returns
        -------
        CalibrationResult
            Never None; a non-converged solve is a status.

        Raises
        ------
        InputError
            Wrong shapes, non-finite data, unknown solver, or too few poses for the free
            parameters of some arm group (the message names the arms and the counts).
        ModelError
            If the Jacobian at the start is rank-deficient: the message lists the
            non-identifiable parameters and what they depend on; the
            :class:`~gtmodel.calibration.identifiability.IdentifiabilityReport` is
            attached as the exception's ``report`` attribute.
        """
        if solver not in SOLVERS:
            close = difflib.get_close_matches(str(solver), SOLVERS, n=2)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise InputError(f"solver: expected one of {', '.join(SOLVERS)}, got {solver!r}{hint}")
        if not (isinstance(max_iter, (int, np.integer)) and max_iter > 0):
            raise InputError(f"max_iter: expected a positive integer, got {max_iter!r}")
        q, T, quat, weights = _unpack_measurements(q, T, quat, weights, self.model)
        data = _check_data(self.model, q, T, quat, weights)
        self._check_counts(data)
        build = self._build()

        if start is None:
            start_model = self.model
        elif isinstance(start, ClosureModel):
            if tuple(start.parameter_names()) != self.resolution.names or type(start) is not type(self.model):
                raise InputError(f"start: expected a {type(self.model).__name__} with the parameters of {self.model.name}")
            start_model = start
        else:
            start_model = self.model.with_parameters(start)
        key = self._data_key(data)
        evs = self._evaluators(key, data)
        if align:
            aligned, Rf, tf = self._best_alignment(start_model, data, evs, key, start_model is self.model or not isinstance(start, ClosureModel))
        else:
            aligned, Rf, tf = start_model, np.eye(3), np.zeros(3)
        if not self._shares_equations(start_model, aligned, data):
            # the model's equations hold instance data besides its parameters: build for it
            _log.info("%s: closure equations differ from the problem's model; building for the start model", self.model.name)
            res = CalibrationProblem(aligned, self.selection).solve(
                data.q, data.T, data.quat if self.model.orientation else None, data.weights,
                solver=solver, align=False, max_iter=max_iter,
            )
            res.rotation, res.translation = Rf, tf
            res.build_time += build
            return res
        pb = self._anchor(aligned.parameter_vector())
        x_all = self._x_of(pb)
        p_init, _ = self._p_of(x_all, pb)

        t_solve = 0.0
        group_results: list[GroupResult] = []
        reports: list[IdentifiabilityReport] = []
        x_final = x_all.copy()
        pb_final = pb.copy()
        cov_x = np.zeros((self.resolution.n_vars, self.resolution.n_vars))
        offsets = np.cumsum([0] + [len(l) for l in self.model.links])
        n_arms = len(self.model.links)
        cost_arm = np.zeros(n_arms)
        cost0_arm = np.zeros(n_arms)
        residuals = np.zeros((data.N, self.model.n_links))
        for gi, (grp, ev) in enumerate(zip(self._groups, evs)):
            ev.set_pb(pb_final)
            mask = ev.mask
            m = int(mask.sum())
            x0 = x_all[grp.var_idx].copy()
            r0, J0 = ev.residuals_jacobian(x0)
            V0 = float(r0 @ r0)
            if grp.nx == 0:
                r, V = r0, V0
                group_results.append(
                    GroupResult(
                        arms=grp.arms, variable_names=(), status=Status.OPTIMAL, message="no free parameters",
                        iterations=0, initial_cost=V0, cost=V0, sigma=0.0, n_residuals=m,
                        identifiability=combine_reports([]),
                    )
                )
            else:
                rank_key = (key, gi, pb_final.tobytes())
                if rank_key not in self._rank_ok and numerical_rank(J0[mask]) < grp.nx:
                    rep0 = analyze_jacobian(J0[mask], grp.var_names)
                    arm_s = ", ".join(str(a + 1) for a in grp.arms)
                    err = ModelError(
                        f"{self.model.name}, arm(s) {arm_s}: the calibration problem is singular at the start "
                        f"(rank {rep0.rank} of {rep0.n_parameters}); not identifiable: {rep0.describe()}. "
                        "Fix or tie these parameters, or measure more varied poses"
                    )
                    err.report = rep0  # type: ignore[attr-defined]
                    raise err
                _bounded_add(self._rank_ok, rank_key)
                t0 = time.perf_counter()
                x, status, message, iters, b = self._solve_group(grp, ev, x0, solver, int(max_iter))
                # quaternions: move the anchors to the solution; if the solve failed after a
                # large local rotation, solve again from the new anchor
                for _ in range(MAX_REANCHOR if grp.has_quaternion else 0):
                    big = self._reanchor(grp, ev, x)
                    x = self._zero_rotations(grp, x)
                    if not big or status in ("optimal", "acceptable"):
                        break
                    x, status, message, it2, b2 = self._solve_group(grp, ev, x, solver, int(max_iter))
                    iters += it2
                    b += b2
                t_solve += time.perf_counter() - t0 - b
                build += b
                qr = ev.polish_qr
                if qr is not None and np.array_equal(qr.x_after, x):
                    # the report from the polishing step's factorisation (at most
                    # POLISH_MAX_STEP away), the residuals at the solution
                    r = qr.r if qr.x_after is qr.x else ev.residuals_only(x)
                    V = float(r @ r)
                    rep = analyze_qr(qr.R, qr.piv, qr.norms, m, grp.var_names, rss=V if m > grp.nx else None)
                else:
                    r, J = ev.residuals_jacobian(x)
                    V = float(r @ r)
                    rep = analyze_jacobian(J[mask], grp.var_names, residuals=r[mask] if m > grp.nx else None)
                sigma = math.sqrt(V / (m - grp.nx)) if m > grp.nx else math.inf
                reports.append(rep)
                x_final[grp.var_idx] = x
                pb_final[:] = ev.pb  # carries this group's re-anchored quaternions
                if rep.covariance.size:
                    cov_x[np.ix_(grp.var_idx, grp.var_idx)] = rep.covariance
                else:  # no residual variance (m == n): deviations unknown
                    cov_x[np.ix_(grp.var_idx, grp.var_idx)] = math.inf
                group_results.append(
                    GroupResult(
                        arms=grp.arms, variable_names=grp.var_names, status=status, message=message,
                        iterations=iters, initial_cost=V0, cost=V, sigma=sigma, n_residuals=m, identifiability=rep,
                    )
                )
                _log.info("calibration arm(s) %s: %s, %d iterations, V %.4g -> %.4g", grp.arms, status, iters, V0, V)
            r = r.reshape(data.N, grp.nr)
            r0 = r0.reshape(data.N, grp.nr)
            c = 0
            for a in grp.arms:
                nl = len(self.model.links[a])
                cost_arm[a] = float(np.sum(r[:, c:c + nl] ** 2))
                cost0_arm[a] = float(np.sum(r0[:, c:c + nl] ** 2))
                residuals[:, offsets[a]:offsets[a] + nl] = r[:, c:c + nl]
                c += nl

        # final parameters from the (re-anchored) variables; deviations through dp/dx
        p_final, dp = self._p_of(x_final, pb_final)
        for qi in self.resolution.quaternions:
            v = p_final[list(qi)]
            p_final[list(qi)] = v / np.linalg.norm(v)
        inf_vars = np.isinf(np.diag(cov_x)) if cov_x.size else np.zeros(0, dtype=bool)
        var_p = np.einsum("ij,jk,ik->i", dp, np.where(np.isinf(cov_x), 0.0, cov_x), dp)
        touches_inf = (np.abs(dp[:, inf_vars]) > 0).any(axis=1) if inf_vars.any() else np.zeros(len(p_final), dtype=bool)
        std_p = np.where(touches_inf, math.inf, np.sqrt(np.maximum(var_p, 0.0)))

        names = self.resolution.names
        status = Status.worst(g.status for g in group_results)
        message = "; ".join(f"arm(s) {','.join(str(a + 1) for a in g.arms)}: {g.message}" for g in group_results)
        qnorms = {}
        for qi in self.resolution.quaternions:
            base = names[qi[0]][:-2] if names[qi[0]].endswith("_w") else names[qi[0]]
            qnorms[base] = float(np.linalg.norm(p_final[list(qi)]))
        return CalibrationResult(
            status=status,
            message=message,
            model=aligned.with_parameters(p_final),
            parameters={n: float(v) for n, v in zip(names, p_final)},
            initial_parameters={n: float(v) for n, v in zip(names, p_init)},
            std={n: float(v) for n, v in zip(names, std_p)},
            cost=float(cost_arm.sum()),
            cost_per_arm=cost_arm,
            initial_cost_per_arm=cost0_arm,
            iterations=int(sum(g.iterations for g in group_results)),
            solve_time=t_solve,
            build_time=build,
            identifiability=combine_reports(reports),
            groups=tuple(group_results),
            rotation=Rf,
            translation=tf,
            quaternion_norms=qnorms,
            residuals=residuals,
            solver=solver,
            n_poses=data.N,
        )

    # -------------------------------------------------------------- internals
    def _reanchor(self, grp: _Group, ev: _Evaluator, x: np.ndarray) -> bool:
        """Move the group's quaternion anchors (in ``ev.pb``) to the solution ``x``.

        Returns True if some local rotation exceeded :data:`REANCHOR_ANGLE`.
        """
        x_all = self._x_of(ev.pb)
        x_all[grp.var_idx] = x
        p, _ = self._p_of(x_all, ev.pb)
        big = False
        for k, js, _ in grp.quaternion_slots:
            qi = list(self.resolution.quaternions[k])
            big |= bool(np.linalg.norm(x[js]) > REANCHOR_ANGLE)
            ev.pb[qi] = p[qi] / np.linalg.norm(p[qi])
        ev.set_pb(ev.pb.copy())  # drops the cached Jacobian
        return big

    @staticmethod
    def _zero_rotations(grp: _Group, x: np.ndarray) -> np.ndarray:
        """Group variables after re-anchoring: rotation components zero, the rest kept."""
        out = x.copy()
        for _, js, _ in grp.quaternion_slots:
            out[js] = 0.0
        return out

    _polish = staticmethod(_polish)  # lsq._polish (Gauss-Newton step, QR kept for the report)
    _solve_minpack = staticmethod(_solve_minpack)  # lsq._solve_minpack (solver "lm")

    def _solve_group(
        self, grp: _Group, ev: _Evaluator, x0: np.ndarray, solver: str, max_iter: int
    ) -> tuple[np.ndarray, str, str, int, float]:
        """Solve one group; returns x, status, message, iterations, build time spent."""
        if solver == "lm":
            return self._solve_minpack(ev, x0, max_iter)
        if solver == "trf":
            try:
                sol = scipy.optimize.least_squares(
                    ev.residuals, x0, jac=ev.jacobian, method=solver, x_scale="jac",
                    ftol=LSQ_TOLERANCE, xtol=LSQ_TOLERANCE, gtol=LSQ_TOLERANCE, max_nfev=max_iter,
                )
            except (ValueError, np.linalg.LinAlgError) as e:
                return x0, "error", f"least_squares failed: {e}", 0, 0.0
            iters = int(sol.njev) if sol.njev is not None else int(sol.nfev)
            if sol.status > 0 and np.all(np.isfinite(sol.x)):
                status = "optimal"
            elif sol.status == 0:
                status = "max_iterations"
            else:
                status = "error"
            x = sol.x
            if status == "optimal":
                x, n_polish = self._polish(ev, x)
                iters += n_polish
            return x, status, str(sol.message), iters, 0.0
        t0 = time.perf_counter()
        nlp = grp.nlp(solver, ev.M, max_iter)
        b = time.perf_counter() - t0
        # objective V / S with S the largest gradient component at the start: IPOPT's tol
        # is then a relative gradient reduction, above the rounding floor of grad V
        r0, J0 = ev.residuals_jacobian(x0)
        S = max(float(np.max(np.abs(2.0 * J0.T @ r0))), 1e-300)
        sol = nlp(x0=x0, p=ev.nlp_parameters(1.0 / S))
        st = nlp.stats()
        x = np.array(sol["x"]).ravel()
        ret = str(st.get("return_status", ""))
        status = normalize_ipopt_status(ret)
        iters = int(st.get("iter_count", 0))
        if not np.all(np.isfinite(x)):
            return x0, "error", ret, iters, b
        if ret == "Search_Direction_Becomes_Too_Small":
            # IPOPT cannot move any more; accept if a Gauss-Newton step confirms the optimum
            x_p, n_p = self._polish(ev, x)
            if n_p:
                return x_p, "acceptable", f"{ret} (optimum confirmed by {n_p} Gauss-Newton step(s))", iters + n_p, b
        return x, status, ret, iters, b
