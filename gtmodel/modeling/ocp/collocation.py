"""Direct collocation transcription of an :class:`~gtmodel.modeling.Optimization` to an NLP.

The transcription itself (variables ordered stage by stage, a copy of a free final time per element) is
:mod:`gtmodel.modeling.ocp.collocation_nlp`; the constraint Jacobian and Lagrangian Hessian assembled from per-point
derivatives (optionally compiled C) are :mod:`gtmodel.modeling.ocp.collocation_derivatives`; warm-started re-solves
as one function of the parameters are :mod:`gtmodel.modeling.ocp.collocation_function`; a minimum-time objective's
input regularisation is :mod:`gtmodel.modeling.ocp.regularization`. This module holds the solvable transcription:
guesses, solves and results.

Conventions:

* Path constraints and variable bounds of inputs/algebraics are enforced at the collocation points; state bounds
  also at element boundaries.
* Point constraints and the Mayer term at the final time use the final state and, for inputs/algebraics, the last
  element's polynomial at ``tau = 1`` (for Radau a collocation point; for Legendre an extrapolation, bounded, and
  the algebraic variables consistent with it).
* Point constraints at the start time use the initial state, for the inputs the first element's Lagrange polynomial
  through its collocation points evaluated at ``tau = 0`` (an extrapolation for both schemes; the input bounds are
  imposed on it too), and the algebraic variables consistent with them
  (:func:`~gtmodel.modeling.ocp.collocation_nlp.consistent_algebraics`; the extrapolated polynomial does not satisfy
  the algebraic equations; their bounds and the path constraints are imposed there too). The result's tables hold
  the same values at the start, and say at each time which kind of point it is
  (:meth:`~gtmodel.modeling.ocp.result.CollocationData.point_kinds`).
* The Lagrange term uses the quadrature of the collocation points.

Model parameters are NLP parameters (``p`` of ``nlpsol``), so one transcription can be solved repeatedly for new
parameter values and initial guesses. Free parameters (:meth:`Optimization.free_parameter`) are NLP variables
instead, one per scalar element, shared by all collocation points.
"""

from __future__ import annotations

import logging
import time as _time
from collections.abc import Mapping
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._timing import add_phase, timed
from gtmodel.errors import InputError, SolverError
from gtmodel.modeling.ocp.budget import check_memory
from gtmodel.modeling.ocp.collocation_bounds import bound_point_taus, checked_spans
from gtmodel.modeling.ocp.collocation_derivatives import assembled_derivatives
from gtmodel.modeling.ocp.collocation_function import WARM_START_OPTIONS, nlp_solver, resolve_function
from gtmodel.modeling.ocp.diagnostics import without_inputs
from gtmodel.modeling.ocp.infeasibility import with_culprit
from gtmodel.modeling.ocp.regularization import regularization_weight, regularized
from gtmodel.modeling.ocp.elimination import fill_algebraics, reduced_problem
from gtmodel.modeling.ocp.collocation_stages import FATROP_STATUS, FATROP_WARM_START_OPTIONS, SOLVERS
from gtmodel.modeling.ocp.guesses import ResultGuess, guess_values
from gtmodel.modeling.ocp.collocation_nlp import collocation_coefficients, element_scaling, merge_options, transcribe
from gtmodel.modeling.dae import FlatDAE, _eval_outputs, _unpack, casadi_name
from gtmodel.modeling.ocp.optimization import Optimization
from gtmodel.modeling.ocp.result import IPOPT_HINTS, CollocationData, OptimizationResult, normalize_ipopt_status
from gtmodel.modeling.ocp.verification import check_result, verify_settings
from gtmodel.status import Status

__all__ = ["CollocationTranscription", "solve"]

_log = logging.getLogger("gtmodel")

#: Default mesh size from which a free final time is copied per element (banded KKT). L1 minimum-time
#: problem, IPOPT + MUMPS, CPU time per iteration (issue 17): one shared variable 13.0 ms at 50 elements and
#: 127 ms at 400 (9.7x for 8x the mesh), copies 14.0 and 94 ms (6.7x); the copies take 61/66/166/93
#: iterations at 50/100/200/400 elements against 49/65/103/96: below a few hundred one variable is faster.
BANDED_MIN_ELEMENTS = 300


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
        IPOPT options (plain names such as ``"max_iter"`` or ``"ipopt.max_iter"``, or a nested ``{"ipopt": {...}}``)
        and CasADi nlpsol options (``"print_time"``, ``"expand"``, ...); merged over the defaults ``max_iter=3000``,
        ``tol=1e-8``, ``print_level=0``, ``print_time=False`` (and no CasADi evaluation warnings) unless ``verbose``,
        and with IPOPT :data:`~gtmodel.modeling.ocp.collocation_nlp.IPOPT_DEFAULTS`.
    nominal : mapping of str to float or array_like, optional
        Nominal magnitudes of states, inputs, algebraic variables, free parameters (by name) and of ``"final_time"``:
        the NLP works with ``variable / nominal`` (Modelica's ``nominal`` attribute, JModelica's variable scaling), so
        that variables of different units (forces in hundreds of N, positions in m) are of order one. Results, guesses
        and bounds stay in the model's units. Default: no scaling.
    derivatives : {"assembled", "casadi"}, optional
        How the Jacobian of the constraints and the Hessian of the Lagrangian are built. ``"assembled"`` (default):
        differentiate the per-point functions (model equations, path constraints, Lagrange integrand) once and
        assemble the sparse matrices from their values at each collocation point; the collocation constraints call the
        per-point function instead of copying its expression graph. ``"casadi"``: CasADi differentiates the whole
        expression graph of the NLP (several times slower to build, the same values).
    compile : bool, optional
        With ``derivatives="assembled"``: evaluate the per-point derivatives through C generated from their CasADi
        graph, compiled once with the system compiler and cached by a hash of the source
        (:func:`gtmodel._compiler.compiled_function`); the same values, several times faster per evaluation. Without a
        compiler (or with ``GTMODEL_COMPILE=0``) the interpreter is used. Default False.
    solver : {"ipopt", "fatrop"}, optional
        The ``casadi.nlpsol`` plugin (:data:`SOLVERS`); ``solver_options`` are its options. ``"fatrop"``: stage by
        stage with final-time copies (``banded``), the same derivatives
        (:func:`~gtmodel.modeling.ocp.collocation_stages.fatrop_cache`); not with free parameters.
    banded : bool, optional
        A free final time as one copy per element tied by equalities, so that the KKT matrix is banded, or as one
        variable shared by all elements (a dense row and column). The same optimum (see
        :mod:`gtmodel.modeling.ocp.collocation_nlp`); default banded from :data:`BANDED_MIN_ELEMENTS` elements on.
    mesh : array_like, optional
        Relative element lengths, shape ``(N,)`` (positive; normalised to sum to 1), for a non-uniform mesh (mesh
        refinement, :mod:`gtmodel.modeling.ocp.refinement`); ``elements`` is then ``N``. Default: ``elements`` uniform
        elements.
    verify : bool or VerificationSettings, optional
        Verify every solution by simulation (:func:`~gtmodel.modeling.ocp.verification.verify`) with these
        :class:`~gtmodel.modeling.ocp.methods.VerificationSettings` (True: the problem's own; never written onto it):
        the result's ``verification``; a failing solution is ``check_failed``. Default True.
    eliminate_algebraics : bool, optional
        Substitute the algebraic variables by their expressions of the states, inputs and parameters where
        :mod:`~gtmodel.modeling.ocp.elimination` can (the NLP then has none; the result's are evaluated at the
        solution); else each is an NLP variable at every collocation point. Default True.
    bound_points : int, optional
        Extra points per element at which the state bounds hold on the polynomial too (the rows the mesh refinement
        adds where a state exceeded a bound between the points: :mod:`~gtmodel.modeling.ocp.collocation_bounds`); 0
        (default): at the collocation points only. Not with fatrop (its stage structure): ignored there, with a log
        line.
    bound_spans : list of tuple of (float, float), optional
        With ``bound_points``: only the elements overlapping these parts of the horizon (fractions of it, ``(s0,
        s1)``) get the rows; default every element.
    regularization : float or tuple of (float, dict of str to float), optional
        Weight of the input energy added to a minimum-time objective, or the weight and the inputs' scales
        (:mod:`~gtmodel.modeling.ocp.regularization`; the result's objective is the declared one); None: the default
        weight, ``defaults["ocp.input_regularization"]``; default 0, off (mesh refinement's later passes set it).

    Raises
    ------
    InputError
        If ``elements``/``points``/``scheme`` are invalid, or the NLP's estimated memory exceeds the limit
        (:func:`gtmodel.modeling.ocp.budget.check_memory`; checked before anything is built).
    ModelError
        If the model cannot be flattened.
    SolverError
        If CasADi cannot build the NLP solver: raised where it is first needed (the first :meth:`solve`, or
        :attr:`solver`), since it is built then.
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
        compile: bool = False,
        solver: str = "ipopt",
        banded: bool | None = None,
        mesh: Any = None,
        verify: Any = True,
        eliminate_algebraics: bool = True,
        bound_points: int = 0,
        bound_spans: Any = None,
        regularization: float | None = 0.0,
    ) -> None:
        if not isinstance(optimization, Optimization):
            raise InputError(f"expected an Optimization, got {type(optimization).__name__}")
        self.fractions: np.ndarray | None = None
        if mesh is not None:
            f = np.asarray(mesh, dtype=float).reshape(-1)
            if f.size < 1 or not np.all(np.isfinite(f) & (f > 0)):
                raise InputError(f"mesh: expected positive finite relative element lengths, got {mesh!r}")
            self.fractions = f / f.sum()
            elements = int(f.size)
        self.verify, self.verify_settings = bool(verify), verify_settings(verify)  # settings None: the declaration's
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
        if solver not in SOLVERS:
            raise InputError(f"solver must be one of {', '.join(SOLVERS)}, got {solver!r}")
        self.plugin = solver
        self.objective_scale = 1.0  # fatrop: the factor its objective is multiplied by (obj_scaling_factor)
        self.compile = bool(compile)
        self.banded = self.elements >= BANDED_MIN_ELEMENTS if banded is None else bool(banded)
        if solver == "fatrop":
            if banded is False:
                raise InputError("solver fatrop: a free final time must be copied per element (banded=True), its stage structure has no shared variable")
            self.banded = True
        self.verbose, self.eliminate_algebraics = bool(verbose), bool(eliminate_algebraics)
        self.bound_points = int(bound_points) if bound_points and bound_point_taus(bound_points).size else 0
        self.bound_spans = None if bound_spans is None else checked_spans(bound_spans)
        self.regularization_weight = regularization_weight(regularization)
        self._solver_options = dict(solver_options or {})
        self.options = merge_options(verbose, solver_options, solver)
        self._unreported: dict[str, dict[str, float]] = {}  # the build's time, reported with the first solve
        with timed(self._unreported, "build"):
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

    def _build(self) -> None:
        opt, dae = self.optimization, self.dae
        self._co = co = collocation_coefficients(self.points, self.scheme)
        stagewise = self.plugin == "fatrop"
        assembled = self.derivatives == "assembled"
        free_index = self._free_index()
        if self.banded and opt.free_final_time and not stagewise:
            # N copies of the final time: scaled by sqrt(N), IPOPT's regularisation of the
            # Hessian, delta_w |step|^2, weighs a common change of all copies as it would
            # weigh a change of one shared variable (not for fatrop: L1, 400 elements, 185
            # iterations with it, 110 without; 47 and 51 on 50 elements)
            self.nominal["tf"] = self.nominal["tf"] * np.sqrt(self.elements)
        self._noms = self.nominal
        # the problem the NLP carries: the algebraic variables eliminated where they can be (elimination)
        self.reduction = reduced_problem(opt, dae, free_index, self.scheme != "radau") if self.eliminate_algebraics else None
        if self.reduction is not None:
            opt, dae, self._noms = self.reduction.optimization, self.reduction.dae, {**self.nominal, "z": np.ones(0)}
        opt, self.regularization = regularized(opt, dae, *self.regularization_weight)  # a minimum-time problem's inputs pinned
        self.nlp_dae = dae
        # before any of the NLP is built, with the algebraic variables it carries (none when eliminated)
        self.size = check_memory(self.elements, self.points, dae.nx, dae.nz, dae.nu)
        nlp = transcribe(
            opt, dae, self.elements, self.points, co, self._noms, free_index, inline_points=not assembled, final_time_copies=self.banded,
            fractions=self.fractions, stagewise=stagewise, bound_points=self.bound_points, bound_spans=self.bound_spans)
        self.nlp = nlp
        wv, gv, P_nlp = nlp.w, nlp.g, nlp.p
        self._blocks = nlp.blocks
        self._block_sizes = nlp.block_sizes
        self._scale, self._lbw, self._ubw, self._lbg, self._ubg = nlp.scale, nlp.lbw, nlp.ubw, nlp.lbg, nlp.ubg
        self._fg = ca.Function("fg", [wv, P_nlp], [nlp.f, gv])
        self.special_function = ca.Function("special", [wv, P_nlp], [nlp.special])
        #: The objective's Lagrange term as the NLP integrates it (its quadrature), signed as the NLP minimises it.
        self.lagrange_function = ca.Function("lagrange_value", [wv, P_nlp], [nlp.f - nlp.mayer])
        self._extract = ca.Function("extract", [wv, P_nlp], [nlp.xc, nlp.uc, nlp.zc, nlp.xn, nlp.tf, nlp.p_model])
        self.key = (id(self), self.elements, self.points, self.scheme, int(wv.numel()), self.bound_points,
                    None if self.fractions is None else tuple(self.fractions.tolist()))
        self.derivative_functions: dict[str, ca.Function] = {}
        self.evaluation = "CasADi interpreter (whole NLP graph" + (", differentiated by the fatrop plugin)" if stagewise else ")")
        if assembled:
            self.derivative_functions, self.evaluation = assembled_derivatives(
                nlp, opt, dae, self.elements, self.points, co, self._noms, free_index, self.compile, self.fractions, stagewise
            )
        self._solver: ca.Function | None = None  # built when first needed (the solver property)
        self._warm_solver: ca.Function | None = None
        _log.debug("collocation NLP for %s: %d variables, %d constraints", dae.name, wv.numel(), gv.numel())

    @property
    def solver(self) -> ca.Function:
        """The ``casadi.nlpsol`` of cold starts, built at first use as :meth:`warm_solver` is (a solve from a coarse
        mesh never builds it: fatrop's plugin sets up its blocks in time quadratic in the elements, 3.6 CPU-s at 400).

        Raises
        ------
        SolverError
            If CasADi cannot build it (e.g. fatrop on constraints coupling elements beyond neighbouring ones).
        """
        if self._solver is None:
            self._solver = self._nlpsol(self.options)
        return self._solver

    def _nlpsol(self, options: Mapping[str, Any]) -> ca.Function:
        """A ``casadi.nlpsol`` of this NLP with ``options`` (:func:`~gtmodel.modeling.ocp.collocation_function.nlp_solver`)."""
        solver, self.objective_scale = nlp_solver(self.nlp, self.plugin, options, self.derivative_functions, casadi_name(self.dae.name))
        return solver

    def _initial_w(self, guesses: Mapping[str, Any], tf_guess: float, pvec: np.ndarray) -> np.ndarray:
        opt, dae, co = self.optimization, self.nlp_dae, self._co  # no algebraic variables when eliminated
        N, t0 = self.elements, opt.start_time
        n_el, c0 = element_scaling(N, self.fractions)
        kinds = [kind for kind, _k, _j in self._blocks]
        ks, js = (np.array([b[i] for b in self._blocks], dtype=int) for i in (1, 2))
        inner = ks < N
        t = np.full(len(kinds), float(tf_guess))
        t[inner] = t0 + (c0[ks[inner]] + co["root"][js[inner]]) * (tf_guess - t0) / n_el[ks[inner]]
        values: dict[str, np.ndarray] = {}  # per kind: (blocks of that kind, size); all times at once (one point set)
        for cat, vars_, start in (("x", dae.x_vars, dae.x_start), ("z", dae.z_vars, dae.z_start), ("u", dae.u_vars, None)):
            rows = [i for i, kind in enumerate(kinds) if kind == cat]
            block = np.zeros((len(rows), sum(sl.stop - sl.start for sl in vars_.values())))
            for name, sl in vars_.items():
                default = self.optimization.model._vars[name].start.copy() if start is None else start[sl].copy()
                block[:, sl] = guess_values(guesses.get(name), sl.stop - sl.start, name, default, t)[rows]
            values[cat] = block
        w0, row = [], {"x": 0, "z": 0, "u": 0}
        for kind in kinds:
            if kind == "tf":
                w0.append(np.array([tf_guess]))
            elif kind == "pf":
                w0.append(self._free_start(pvec))
            else:
                w0.append(values[kind][row[kind]])
                row[kind] += 1
        w = np.concatenate(w0) if w0 else np.zeros(0)
        return np.clip(w / self._scale, self._lbw, self._ubw)  # the NLP works with variable / nominal

    def _free_start(self, pvec: np.ndarray) -> np.ndarray:
        """Initial guess of the free parameter elements: their start, else the value clipped into the bounds."""
        out = []
        for name, (lb, ub, start) in self.optimization.free_parameters.items():
            out.append(start if start is not None else np.clip(pvec[self.dae.p_vars[name]], lb, ub))
        return np.concatenate(out) if out else np.zeros(0)

    def solve(
        self,
        parameters: Mapping[str, Any] | None = None,
        initial_guess: OptimizationResult | Mapping[str, Any] | None = None,
        warm_start: bool = False,
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
        warm_start : bool, optional
            IPOPT, with a previous result of this transcription as ``initial_guess``: from its
            primal point *and multipliers* with a small barrier parameter (:data:`WARM_START_OPTIONS`
            of :mod:`~gtmodel.modeling.ocp.collocation_function`); fatrop (no start multipliers):
            from a result of any mesh of the problem, the barrier started small
            (:data:`~gtmodel.modeling.ocp.collocation_stages.FATROP_WARM_START_OPTIONS`).
            Default False (the primal point only, a cold barrier).

        Returns
        -------
        OptimizationResult
            With ``status`` and the solution or the last iterate.

        Raises
        ------
        InputError
            If parameters or guesses are malformed, or the problem's verification
            tolerance is not a positive number.
        """
        opt, dae = self.optimization, self.dae
        merged = {k: v for k, v in opt.parameters.items()}
        merged.update(parameters or {})
        pvec = dae.parameter_vector(merged)
        guesses: dict[str, Any] = dict(opt.initial_guesses)
        tf_guess = opt.final_time_guess
        w0 = None
        phases, self._unreported = self._unreported, {}
        guess_wall, guess_cpu = _time.perf_counter(), _time.process_time()
        if isinstance(initial_guess, OptimizationResult):
            if initial_guess.transcription_key == self.key and initial_guess.w is not None:
                w0 = np.clip(initial_guess.w, self._lbw, self._ubw)
            elif initial_guess.collocation is not None:
                res = initial_guess
                tf_guess = float(np.clip(res.final_time, *opt.final_time_bounds))
                sampled = ResultGuess(res, opt.start_time, tf_guess)  # one evaluation for all variables and points
                guesses.update({name: sampled for name in sampled.names()})
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

        warm: dict[str, np.ndarray] = {}
        if warm_start and self.plugin == "fatrop":
            if not (isinstance(initial_guess, OptimizationResult) and initial_guess.collocation is not None):
                raise InputError("warm_start: initial_guess must be a collocation result of this problem (fatrop starts from its primal point)")
        elif warm_start:
            if not (isinstance(initial_guess, OptimizationResult) and initial_guess.transcription_key == self.key
                    and initial_guess.lam_g is not None):
                raise InputError("warm_start: initial_guess must be a result of this transcription (with its multipliers)")
            warm = {"lam_x0": initial_guess.lam_w, "lam_g0": initial_guess.lam_g}
        add_phase(phases, "guess", _time.perf_counter() - guess_wall, _time.process_time() - guess_cpu)
        with timed(phases, "build"):  # a solver built at its first use is part of the build
            solver = self.warm_solver() if warm_start else self.solver
        t_start, cpu_start = _time.perf_counter(), _time.process_time()
        error_msg = None
        lam = (None, None)
        try:
            sol = solver(x0=w0, lbx=self._lbw, ubx=self._ubw, lbg=self._lbg, ubg=self._ubg, p=pvec, **warm)
            w_opt = np.array(sol["x"], dtype=float).reshape(-1)
            lam = (np.array(sol["lam_x"], dtype=float).reshape(-1), np.array(sol["lam_g"], dtype=float).reshape(-1))
        except RuntimeError as exc:  # e.g. NaN/exception inside an evaluation
            error_msg = str(exc).strip().splitlines()[-1] if str(exc).strip() else repr(exc)
            w_opt = w0
        solve_time = _time.perf_counter() - t_start
        add_phase(phases, "solve", solve_time, _time.process_time() - cpu_start)
        stats = dict(solver.stats())
        if self.plugin == "fatrop":
            message = error_msg or f"fatrop: {stats.get('unified_return_status', 'unknown')} (return flag {stats.get('return_status')})"
            status = Status.ERROR if error_msg else FATROP_STATUS.get(str(stats.get("unified_return_status")), Status.ERROR)
            if stats.get("success") and not error_msg:
                status = Status.OPTIMAL
            if lam[0] is not None:  # multipliers of the problem as declared, not of the scaled objective
                lam = (lam[0] / self.objective_scale, lam[1] / self.objective_scale)
        else:
            message = error_msg or str(stats.get("return_status", "unknown"))
            status = Status.ERROR if error_msg else normalize_ipopt_status(message)
            message = f"{message}: {IPOPT_HINTS[message]}" if message in IPOPT_HINTS else message
            message = without_inputs(opt, dae, message)
        if not np.all(np.isfinite(w_opt)):
            status = Status.ERROR
        res = self._result(w_opt, pvec, status, message, stats, solve_time)
        res.message = with_culprit(res.message, res, self.optimization)  # a failed solve names its likely culprit
        res.lam_w, res.lam_g = lam
        res.timing = phases
        if self.verify and res.status in (Status.OPTIMAL, Status.ACCEPTABLE):
            with timed(phases, "verification"):
                self.check(res, special=np.array(self.special_function(w_opt, pvec), dtype=float).reshape(-1),
                           lagrange=float(self.lagrange_function(w_opt, pvec)))
        return res

    def check(self, result: OptimizationResult, special: np.ndarray | None = None, lagrange: float | None = None) -> OptimizationResult:
        """Verify a solution by simulation and downgrade it to ``check_failed`` if it fails.

        Sets ``result.verification`` (:func:`gtmodel.modeling.ocp.verification.verify` with
        this transcription's verification settings, else the problem's); an ``optimal``
        or ``acceptable`` result whose verification fails becomes ``check_failed`` with
        the verification's message.

        Parameters
        ----------
        result : OptimizationResult
            A result of this transcription.
        special : numpy.ndarray, optional
            The values of the problem's timed variables and integrals in the NLP (in the
            order of :meth:`Optimization.special_symbols`); given, the integrals are
            verified too (their simulated quadrature against these values).
        lagrange : float, optional
            The NLP's value of the objective's Lagrange term (its quadrature, signed as
            minimised); given, verified against the simulation's quadrature too.

        Returns
        -------
        OptimizationResult
            ``result``, changed in place.
        """
        return check_result(result, self.optimization, special, lagrange=lagrange, settings=self.verify_settings)

    def objective_at_guess(self, parameters: Mapping[str, Any] | None = None) -> float:
        """The NLP objective at the problem's declared initial guess (e.g. to choose its scaling).

        Parameters
        ----------
        parameters : mapping of str to float or array_like, optional
            Parameter values, as for :meth:`solve`.

        Returns
        -------
        float
            The objective (Mayer plus Lagrange term) of the guess.

        Raises
        ------
        InputError
            Malformed parameters or guesses.
        """
        opt = self.optimization
        pvec = self.dae.parameter_vector({**opt.parameters, **(parameters or {})})
        w0 = self._initial_w(dict(opt.initial_guesses), opt.final_time_guess, pvec)
        return float(self._fg(w0, pvec)[0])

    def set_solver_options(self, solver_options: Mapping[str, Any]) -> None:
        """Rebuild the solver with further options (the NLP and its derivative functions are kept).

        Parameters
        ----------
        solver_options : mapping
            Options merged over the current ones, as ``solver_options`` of the constructor
            (plain plugin names, e.g. ``{"obj_scaling_factor": 10.0}``).

        Raises
        ------
        SolverError
            The solver cannot be built with these options.
        """
        self._solver_options.update(solver_options)
        self.options = merge_options(self.verbose, self._solver_options, self.plugin)
        self._solver = self._nlpsol(self.options)  # built now: bad options are refused here
        self._warm_solver = None

    def warm_solver(self) -> ca.Function:
        """The nlpsol of warm starts (built once; shares the derivative functions).

        Returns
        -------
        casadi.Function
            IPOPT with :data:`~gtmodel.modeling.ocp.collocation_function.WARM_START_OPTIONS`,
            fatrop with :data:`~gtmodel.modeling.ocp.collocation_stages.FATROP_WARM_START_OPTIONS`.
        """
        if self._warm_solver is None:
            warm = WARM_START_OPTIONS if self.plugin == "ipopt" else FATROP_WARM_START_OPTIONS
            opts = {**self.options, self.plugin: {**self.options[self.plugin], **warm}}
            self._warm_solver = self._nlpsol(opts)
        return self._warm_solver

    def to_function(self, name: str = "resolve", warm_start: bool = True) -> ca.Function:
        """This NLP's solve as one CasADi Function of the parameters and a start point (rockit's ``to_function``).

        See :func:`gtmodel.modeling.ocp.collocation_function.resolve_function`.

        Parameters
        ----------
        name : str, optional
            Function name.
        warm_start : bool, optional
            Use the warm-start solver (multipliers and a small barrier parameter).

        Returns
        -------
        casadi.Function
            ``(p, w0, lam_w0, lam_g0) -> (w, lam_w, lam_g, objective, final_time)``.
        """
        return resolve_function(self, name, warm_start)

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
        reg = self.regularization and self.regularization.report(float(self.lagrange_function(w, pvec)), float(self._extract(w, pvec)[4]))
        f_val = opt.objective_sign * (float(f_val) - (reg["value"] if reg else 0.0))  # the NLP minimises sign * objective
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
            zc=np.array(zc).reshape(-1, N, d).transpose(1, 2, 0),
            fractions=None if self.fractions is None else self.fractions.copy(),
        )
        t = colloc.mesh()
        xs, us, zs = colloc.evaluate(t)
        zs = fill_algebraics(colloc, t, xs, us, zs, pvec, tf, self.nlp.consistent, self.reduction)
        params = {k: pvec[s].copy() for k, s in dae.p_vars.items()}
        try:
            outs = _eval_outputs(dae, t, xs, zs, us, pvec)
        except RuntimeError:
            outs = {}
        iterations = int(stats.get("iter_count", 0) or 0)
        stats["eliminated_algebraics"] = self.reduction.eliminated if self.reduction is not None else 0
        stats.update({"regularization": reg} if reg else {})
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
