"""Optimica-style optimal control problem declarations (no transcription here).

An :class:`Optimization` wraps a :class:`~gtmodel.modeling.simulation.model.Model` and declares the
time horizon (fixed or free final time), the objective (Mayer term at the final time and
Lagrange integrand), path and point constraints, variable bounds, parameter values and
initial guesses. Transcription to an NLP lives in :mod:`gtmodel.modeling.ocp.collocation`.
A model parameter declared free (:meth:`Optimization.free_parameter`) is a decision
variable of the problem (constant in time, within bounds): parameter estimation from data
is an optimisation with free parameters and a data-fit objective. Expressions may use every
symbol the model declared (``time``, states, ``der()`` of states, algebraics, inputs,
parameters) and :attr:`Optimization.final_time`.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling.dae import FlatDAE, _as_sx, _vector_value
from gtmodel.modeling.simulation.model import Model
from gtmodel.modeling.ocp.initial import model_initial_conditions
from gtmodel.modeling.ocp.terms import Constraint, Integral, Timed
from gtmodel.modeling.ocp.written import affine_guess, reduce_written

__all__ = ["Optimization", "Constraint", "Timed", "Integral"]


class Optimization:
    """An optimal control problem over a model (Optimica-style declaration).

    Parameters
    ----------
    model : Model
        The dynamic model as written: one that ``flatten()`` refuses (higher index) is
        reduced as ``simulate()`` reduces it (:mod:`gtmodel.modeling.ocp.written`);
        :attr:`model` is the reduced model, :attr:`user_model` the one given, and
        expressions may use the symbols of either.
    start_time : float, optional
        Start time ``t0``, s; default 0.
    final_time : float, optional
        Final time ``tf``, s; the value when fixed, the default guess when free;
        default 1.
    free_final_time : bool, optional
        If true, ``tf`` is a decision variable within ``final_time_bounds``.
    final_time_guess : float, optional
        Initial guess for a free final time, s; default ``final_time`` clipped into
        the bounds.
    final_time_bounds : tuple of float, optional
        ``(lo, hi)`` bounds of a free final time, s, with ``start_time < lo <= hi``.

    Raises
    ------
    InputError
        If ``model`` is not a :class:`Model` or the times are not finite numbers.
    ModelError
        If the final time is free without bounds, the bounds are inconsistent, or
        the horizon is empty.
    """

    def __init__(
        self,
        model: Model,
        start_time: float = 0.0,
        final_time: float = 1.0,
        free_final_time: bool = False,
        final_time_guess: float | None = None,
        final_time_bounds: tuple[float, float] | None = None,
    ) -> None:
        if not isinstance(model, Model):
            raise InputError(f"model must be a gtmodel.modeling.Model, got {type(model).__name__}")
        try:
            t0, tf = float(start_time), float(final_time)
        except (TypeError, ValueError) as exc:
            raise InputError("start_time and final_time must be numbers") from exc
        if not (np.isfinite(t0) and np.isfinite(tf)):
            raise InputError("start_time and final_time must be finite")
        self.user_model = model  # as given, before any reduction
        self._user_subst: tuple[ca.SX, ca.SX] | None = None
        if not model._flattens():
            model, self._user_subst = reduce_written(model)
        self.model = model
        self.start_time = t0
        self.free_final_time = bool(free_final_time)
        self._final_time = ca.SX.sym("final_time")
        if self.free_final_time:
            if final_time_bounds is None:
                raise ModelError(
                    "free final time needs final_time_bounds (lo, hi) with start_time < lo <= hi"
                )
            lo, hi = (float(b) for b in final_time_bounds)
            if not (lo <= hi) or not lo > t0 or not np.isfinite(hi):
                raise ModelError(
                    f"final_time_bounds {final_time_bounds} must satisfy start_time ({t0}) < lo <= hi < inf"
                )
            self.final_time_bounds: tuple[float, float] = (lo, hi)
            guess = tf if final_time_guess is None else float(final_time_guess)
            self.final_time_guess = float(np.clip(guess, lo, hi))
        else:
            if tf <= t0:
                raise ModelError(f"final_time ({tf}) must exceed start_time ({t0})")
            self.final_time_bounds = (tf, tf)
            self.final_time_guess = tf
        self.final_time_value = tf
        self.mayer: ca.SX = ca.SX(0)
        self.lagrange: ca.SX = ca.SX(0)
        self.sense = "minimize"
        self.timed_variables: list[Timed] = []
        self.integrals: list[Integral] = []
        self.path_constraints: list[Constraint] = []
        self.declared_point_constraints: list[Constraint] = []
        self.bounds: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self.initial_guesses: dict[str, Any] = {}
        self.data_fits: list[Any] = []  # gtmodel.modeling.ocp.estimation.fit_data
        self.parameters: dict[str, np.ndarray] = {}
        self.free_parameters: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray | None]] = {}
        self._flat: FlatDAE | None = None
    # ------------------------------------------------------------------ helpers
    #: The verification by simulation (:mod:`gtmodel.modeling.ocp.verification`): its tolerance
    #: (None: ``defaults["ocp.verification_tolerance"]``), the integrator's relative tolerance (None:
    #: 1e-3 x the tolerance within [1e-10, 1e-6]) and the SUNDIALS integrator, ``"cvodes"`` or
    #: ``"idas"`` (None: CVODES for an ODE, IDAS with algebraic variables).
    verification_tolerance: float | None = None
    verification_rtol: float | None = None
    verification_integrator: str | None = None

    @property
    def final_time(self) -> ca.SX:
        """Symbol of the final time (SX scalar), s; usable in any expression."""
        return self._final_time

    def flat(self) -> FlatDAE:
        """Flatten the model (re-done on every call, so later model edits are seen).

        Returns
        -------
        FlatDAE
            The flattened model.

        Raises
        ------
        ModelError
            If the model is inconsistent.
        """
        self._flat = self.model.flatten()
        return self._flat

    def _expr(self, expr: Any, what: str, special: bool = True) -> ca.SX:
        e = self._to_reduced(_as_sx(expr, what))
        extra = [self._final_time] + ([v.symbol for v in self.special_symbols()] if special else [])
        self.model.check_symbols(e, what, extra=extra)
        return e

    def _to_reduced(self, e: ca.SX) -> ca.SX:
        """``e`` with the symbols of the model as given replaced by their values in the reduced model."""
        return e if self._user_subst is None or not e.numel() else ca.substitute(e, *self._user_subst)

    @property
    def point_constraints(self) -> list[Constraint]:
        """The point constraints: the declared ones, then the model's own initial conditions.

        The model's starts declared ``fixed=True`` (``Mass(s=3)``) and its initial
        equations are initial conditions of the optimisation as of a simulation
        (:func:`gtmodel.modeling.ocp.initial.model_initial_conditions`), unless a declared
        start constraint states the variable's initial value itself.

        Raises
        ------
        InitialConditionConflict
            If a fixed start contradicts a declared start constraint on that variable
            (naming both).
        """
        return [*self.declared_point_constraints, *model_initial_conditions(self)]

    def special_symbols(self) -> list[Timed | Integral]:
        """The timed variables and integrals declared so far, in order.

        Returns
        -------
        list of Timed or Integral
        """
        return [*self.timed_variables, *self.integrals]

    def _depends_on_special(self, e: ca.SX) -> bool:
        syms = [v.symbol for v in self.special_symbols()]
        return bool(syms) and ca.depends_on(e, ca.vertcat(*syms))

    def _varying(self) -> ca.SX:
        """The model's time-varying symbols: time, states, their derivatives, algebraics, inputs."""
        m = self.model
        parts = [m.time] + [ca.vec(s) for k in ("state", "algebraic", "input") for s in m.variables(k).values()]
        parts += [ca.vec(m.der(s)) for s in m.variables("state").values()]
        return ca.vertcat(*parts)

    # ------------------------------------------------------------------ timed variables, integrals
    def timed(self, expr: Any, time: float | str | ca.SX) -> ca.SX:
        """A symbol for the value of ``expr`` at one fixed time (Optimica's timed variable ``x(t)``).

        Use the symbol in the objective (:meth:`set_objective`, as a Mayer term) and in
        constraints (:meth:`add_constraint`). The transcription gives it the value of
        ``expr`` with the model variables interpolated at ``time``: by collocation, from the
        polynomials of the element that contains ``time`` (states through the element start
        and its collocation points, inputs and algebraics through the collocation points);
        exact at element boundaries; by multiple shooting, integrated from the interval's
        start to ``time``.

        With a free final time, an interior time is a fixed fraction ``s`` of the horizon
        (normalised time): ``time = start_time + s * (final_time - start_time)``, written
        with the :attr:`final_time` symbol (``0.5 * opt.final_time`` from ``t0 = 0``); the
        point moves with the final time, at a fixed place in its element. A number is then
        refused: Optimica's ``x(t)`` is at a fixed time, which a free horizon may leave or
        move across elements.

        Parameters
        ----------
        expr : casadi.SX or float
            Scalar expression of model variables, parameters and :attr:`final_time`.
        time : float, {"start", "final"} or casadi.SX
            Absolute time [s] in ``[start_time, final_time]``, the start or final time, or
            an expression ``a + b * final_time`` [s] (a fixed final time substituted; with
            a free one it must be ``start_time + s (final_time - start_time)``, ``0 <= s <= 1``).

        Returns
        -------
        casadi.SX
            Scalar symbol standing for the value.

        Raises
        ------
        InputError
            If ``expr`` is not scalar or ``time`` is not a number, ``"start"``/``"final"``
            or an expression of the final time.
        ModelError
            If ``time`` is outside the horizon, or with a free final time a number other than
            the start time or an expression not of the form ``start_time + s (final_time -
            start_time)``.
        """
        e = self._expr(expr, "timed variable", special=False)
        if e.numel() != 1:
            raise InputError(f"timed variable: expression must be scalar, got {e.numel()} elements")
        t0 = self.start_time
        tol = 1e-12 * max(1.0, abs(t0), abs(self.final_time_value))
        fraction = None
        if isinstance(time, ca.SX) and not time.is_constant():
            at, fraction = self._timed_expression(time, tol)
        elif isinstance(time, str):
            if time not in ("start", "final"):
                raise InputError(f"timed variable: time must be a number, 'start' or 'final', got {time!r}")
            at = time
        else:
            try:
                t = float(time) if not isinstance(time, ca.SX) else float(ca.DM(ca.evalf(time)))
            except (TypeError, ValueError, RuntimeError):
                raise InputError(f"timed variable: time must be a number, 'start' or 'final', got {time!r}") from None
            if self.free_final_time and abs(t - t0) > tol:
                raise ModelError(
                    f"timed variable at t = {t:g} s: with a free final time only the start and the final time or a "
                    "fixed fraction s of the horizon can be used (a fixed interior time may fall outside the horizon "
                    "or move across elements as the final time changes); write the time as start_time + s * "
                    "(final_time - start_time), e.g. x(0.5 * final_time) from start_time = 0"
                )
            at = "start" if self.free_final_time else self._timed_at_number(t, tol)
        for v in self.timed_variables:
            if v.time == at and v.fraction == fraction and ca.is_equal(v.expr, e, 20):
                return v.symbol
        sym = ca.SX.sym(f"timed{len(self.timed_variables)}")
        self.timed_variables.append(Timed(sym, e, at, fraction))
        return sym

    def _timed_expression(self, time: ca.SX, tol: float) -> tuple[float | str, float | None]:
        """``(at, fraction)`` of a time written with the final time (see :meth:`timed`)."""
        T = self._final_time
        if time.numel() != 1 or any(not ca.is_equal(s, T) for s in ca.symvar(time)):
            raise InputError("timed variable: a time expression may use numbers and final_time only")
        slope = ca.jacobian(time, T)
        if ca.depends_on(slope, T):
            raise ModelError("timed variable: the time must be affine in final_time (start_time + s * (final_time - start_time))")
        b = float(ca.DM(ca.evalf(slope)))
        a = float(ca.DM(ca.evalf(ca.substitute(time, T, ca.SX(0.0)))))
        t0 = self.start_time
        if not self.free_final_time:
            t = a + b * self.final_time_value
            return self._timed_at_number(t, tol), None
        if abs(a - t0 * (1.0 - b)) > tol or not -1e-12 <= b <= 1.0 + 1e-12:
            raise ModelError(
                f"timed variable at {a:g} + {b:g} * final_time s: with a free final time an interior time must be a fixed "
                "fraction s of the horizon, start_time + s * (final_time - start_time) with 0 <= s <= 1"
            )
        if b <= 1e-12:
            return "start", None
        if b >= 1.0 - 1e-12:
            return "final", None
        return t0 + b * (self.final_time_guess - t0), b

    def _timed_at_number(self, t: float, tol: float) -> float | str:
        t0, tf = self.start_time, self.final_time_value
        if not t0 - tol <= t <= tf + tol:
            raise ModelError(f"timed variable at t = {t:g} s: outside the horizon [{t0:g}, {tf:g}] s")
        return "start" if abs(t - t0) <= tol else "final" if abs(t - tf) <= tol else t

    def integral(self, expr: Any) -> ca.SX:
        """A symbol for the integral of ``expr`` over the horizon, for constraints and objectives.

        ``opt.add_constraint(opt.integral(x**2), ub=1)`` is an isoperimetric constraint.
        The transcription gives the symbol the quadrature of the collocation points (by
        multiple shooting: the integrator's quadrature).

        Parameters
        ----------
        expr : casadi.SX or float
            Scalar integrand of model variables, ``time``, parameters, :attr:`final_time`.

        Returns
        -------
        casadi.SX
            Scalar symbol standing for the value.

        Raises
        ------
        InputError
            If ``expr`` is not scalar.
        ModelError
            If ``expr`` contains symbols not declared by the model.
        """
        e = self._expr(expr, "integral", special=False)
        if e.numel() != 1:
            raise InputError(f"integral: integrand must be scalar, got {e.numel()} elements")
        sym = ca.SX.sym(f"integral{len(self.integrals)}")
        self.integrals.append(Integral(sym, e))
        return sym

    def add_constraint(self, expr: Any, lb: Any = -np.inf, ub: Any = np.inf, name: str | None = None) -> None:
        """Add ``lb <= expr <= ub`` over timed variables and integrals (Optimica's point constraints).

        Parameters
        ----------
        expr : casadi.SX
            Column expression of symbols from :meth:`timed` and :meth:`integral`,
            parameters and :attr:`final_time` (no model variable outside them).
        lb, ub : float or array_like, optional
            Bounds (scalar or one per element); ``lb == ub`` for equalities.
        name : str, optional
            Label used in messages; default ``"point<k>"``.

        Raises
        ------
        InputError
            If bound sizes do not match.
        ModelError
            If ``expr`` contains a model variable outside a timed variable or integral,
            unknown symbols, or ``lb > ub``.
        """
        label = name or f"point{len(self.declared_point_constraints)}"
        e = self._expr(expr, f"constraint {label!r}")
        if ca.depends_on(e, self._varying()):
            raise ModelError(
                f"constraint {label!r}: a model variable appears outside a timed variable or integral; "
                "use timed(x, t) / integral(f), or add_path_constraint for a constraint at every time"
            )
        lbv, ubv = self._bounds(lb, ub, int(e.numel()), f"constraint {label!r}")
        self.declared_point_constraints.append(Constraint(label, e, lbv, ubv, "timed"))

    @staticmethod
    def _bounds(lb: Any, ub: Any, size: int, what: str) -> tuple[np.ndarray, np.ndarray]:
        lbv = _vector_value(lb, size, f"{what} lb", -np.inf)
        ubv = _vector_value(ub, size, f"{what} ub", np.inf)
        if np.any(np.isnan(lbv)) or np.any(np.isnan(ubv)):
            raise InputError(f"{what}: bounds must not be NaN")
        bad = np.nonzero(lbv > ubv)[0]
        if bad.size:
            raise ModelError(f"{what}: lower bound exceeds upper bound at elements {bad.tolist()}")
        return lbv, ubv

    # ------------------------------------------------------------------ objective
    @property
    def objective(self) -> ca.SX:
        """Mayer term: expression evaluated at the final time (variables at ``tf``)."""
        return self.mayer

    @objective.setter
    def objective(self, expr: Any) -> None:
        self.set_objective(mayer=expr)

    @property
    def objective_integrand(self) -> ca.SX:
        """Lagrange term: integrand integrated over ``[start_time, final_time]``."""
        return self.lagrange

    @objective_integrand.setter
    def objective_integrand(self, expr: Any) -> None:
        self.set_objective(lagrange=expr)

    def set_objective(self, mayer: Any = None, lagrange: Any = None, sense: str | None = None) -> None:
        """Set the Mayer and/or Lagrange terms of the objective and whether it is minimised or maximised.

        Parameters
        ----------
        mayer : casadi.SX or float, optional
            Scalar expression evaluated at the final time (may use ``final_time``,
            parameters, symbols of :meth:`timed` and :meth:`integral`, and model
            variables, which are taken at ``tf``). Unchanged if omitted.
        lagrange : casadi.SX or float, optional
            Scalar integrand over the horizon. Unchanged if omitted.
        sense : {"minimize", "maximize"}, optional
            Minimise (default) or maximise ``mayer + integral(lagrange)``; the result's
            ``objective`` is the value of that expression either way. Unchanged if omitted.

        Raises
        ------
        InputError
            If an expression is not scalar or ``sense`` is not one of the two.
        ModelError
            If an expression contains symbols not declared by the model.
        """
        if sense is not None:
            if sense not in ("minimize", "maximize"):
                raise InputError(f"objective sense must be 'minimize' or 'maximize', got {sense!r}")
            self.sense = sense
        for label, expr in (("mayer", mayer), ("lagrange", lagrange)):
            if expr is None:
                continue
            e = self._expr(expr, f"objective ({label} term)", special=label == "mayer")
            if e.numel() != 1:
                raise InputError(f"objective ({label} term) must be scalar, got {e.numel()} elements")
            setattr(self, label, e)

    @property
    def objective_sign(self) -> float:
        """``1.0`` when minimising, ``-1.0`` when maximising (the NLP minimises ``sign * objective``)."""
        return -1.0 if self.sense == "maximize" else 1.0

    # ------------------------------------------------------------------ constraints
    def add_path_constraint(
        self, expr: Any, lb: Any = -np.inf, ub: Any = np.inf, name: str | None = None
    ) -> None:
        """Add ``lb <= expr(t) <= ub`` for all ``t`` in the horizon.

        Parameters
        ----------
        expr : casadi.SX
            Column expression of model variables, ``time``, parameters, ``final_time``.
        lb, ub : float or array_like, optional
            Bounds (scalar or one per element); default unbounded.
        name : str, optional
            Label used in messages; default ``"path<k>"``.

        Raises
        ------
        InputError
            If bound sizes do not match.
        ModelError
            If ``expr`` contains unknown symbols or ``lb > ub`` (naming the constraint).
        """
        label = name or f"path{len(self.path_constraints)}"
        e = self._expr(expr, f"path constraint {label!r}", special=False)
        lbv, ubv = self._bounds(lb, ub, int(e.numel()), f"path constraint {label!r}")
        self.path_constraints.append(Constraint(label, e, lbv, ubv, None))

    def add_point_constraint(
        self,
        expr: Any,
        at: str = "final",
        lb: Any = -np.inf,
        ub: Any = np.inf,
        name: str | None = None,
    ) -> None:
        """Add ``lb <= expr <= ub`` with model variables evaluated at the start or final time.

        Parameters
        ----------
        expr : casadi.SX
            Column expression of model variables, parameters and ``final_time``.
        at : {"start", "final"}, optional
            Time point at which the variables are evaluated; default ``"final"``.
        lb, ub : float or array_like, optional
            Bounds (scalar or one per element); use ``lb == ub`` for equalities.
        name : str, optional
            Label used in messages; default ``"point<k>"``.

        Raises
        ------
        InputError
            If ``at`` is not ``"start"``/``"final"`` or bound sizes do not match.
        ModelError
            If ``expr`` contains unknown symbols or ``lb > ub`` (naming the constraint).
        """
        if at not in ("start", "final"):
            raise InputError(f"point constraint: at must be 'start' or 'final', got {at!r}")
        label = name or f"point{len(self.declared_point_constraints)}"
        e = self._expr(expr, f"point constraint {label!r}", special=False)
        lbv, ubv = self._bounds(lb, ub, int(e.numel()), f"point constraint {label!r}")
        self.declared_point_constraints.append(Constraint(label, e, lbv, ubv, at))

    def set_bounds(self, variable: Any, lb: Any = -np.inf, ub: Any = np.inf) -> None:
        """Bound a state, input or algebraic variable for all ``t`` (overrides model bounds).

        Parameters
        ----------
        variable : casadi.SX
            A declared state/input/algebraic symbol, or elements of one; an output (an
            eliminated alias) is bounded by a path constraint.
        lb, ub : float, array_like or casadi.SX, optional
            Bounds, scalar or one per selected element; ``-inf``/``inf`` (the
            defaults) leave a side open. A bound that is an expression of model
            parameters (fixed or free, :meth:`free_parameter`) and ``final_time`` is
            imposed as the path constraint ``variable - lb >= 0`` / ``ub - variable >= 0``
            at the collocation points (named ``"bounds of <name>"``).

        Raises
        ------
        ModelError
            If ``variable`` is not a state, input or algebraic, ``lb > ub``, or a
            bound expression contains model variables other than parameters.
        InputError
            If a bound has the wrong size or is NaN.
        """
        variable = self._to_reduced(_as_sx(variable, "variable"))
        if not all(variable[i].is_symbolic() for i in range(variable.numel())):  # an output, an eliminated alias
            self.add_path_constraint(variable, lb, ub, name=f"bounds of {variable}")
            return
        kind, name, idx = self.model.locate(variable)
        if kind == "parameter":
            raise ModelError(f"set_bounds: {name!r} is a parameter; bounds apply to states, inputs, algebraics")
        var = _as_sx(variable, "variable")
        symbolic = []
        for side, value in (("lb", lb), ("ub", ub)):
            if isinstance(value, ca.SX) and not value.is_constant():
                e = self._expr(value, f"bounds of {name!r} ({side})", special=False)
                if ca.depends_on(e, self._varying()):
                    raise ModelError(f"bounds of {name!r} ({side}): a bound may depend on parameters and final_time only")
                if e.numel() not in (1, var.numel()):
                    raise InputError(f"bounds of {name!r} ({side}): expected 1 or {var.numel()} elements, got {e.numel()}")
                symbolic.append((side, e))
        if symbolic:
            numeric = {s: (v if not any(s == k for k, _ in symbolic) else (-np.inf if s == "lb" else np.inf))
                       for s, v in (("lb", lb), ("ub", ub))}
            for side, e in symbolic:
                diff = var - e if side == "lb" else e - var
                self.add_path_constraint(diff, 0.0, np.inf, name=f"bounds of {name!r} ({side})")
            lb, ub = numeric["lb"], numeric["ub"]
        lbv, ubv = self._bounds(lb, ub, len(idx), f"bounds of {name!r}")
        size = int(self.model.variables(kind)[name].numel())
        cur_lb, cur_ub = self.bounds.get(name, (np.full(size, np.nan), np.full(size, np.nan)))
        cur_lb, cur_ub = cur_lb.copy(), cur_ub.copy()
        cur_lb[idx], cur_ub[idx] = lbv, ubv
        self.bounds[name] = (cur_lb, cur_ub)

    def set_initial_guess(self, variable: Any, values: Any) -> None:
        """Set the initial guess of a state, input or algebraic variable, or of ``final_time``.

        Parameters
        ----------
        variable : casadi.SX
            A declared state/input/algebraic symbol (whole variable), :attr:`final_time`,
            or a scalar output ``a v + b`` of one variable ``v`` (guessing ``v``).
        values : float, array_like, tuple or callable
            A constant (scalar or ``(n,)``); a trajectory ``(t, values)`` with ``t`` of
            shape ``(K,)`` (absolute times, s) and ``values`` of shape ``(K,)`` or
            ``(K, n)``, linearly interpolated; or a callable ``f(t) -> (n,)``.

        Raises
        ------
        InputError
            If the values have the wrong shape.
        ModelError
            If ``variable`` is not a state, input, algebraic or ``final_time``, nor affine
            in one of them.
        """
        if isinstance(variable, ca.SX) and variable.numel() == 1 and ca.is_equal(variable, self._final_time):
            v = float(np.asarray(values, dtype=float).reshape(-1)[0])
            lo, hi = self.final_time_bounds
            self.final_time_guess = float(np.clip(v, lo, hi))
            return
        if isinstance(variable, ca.SX) and variable.numel() == 1:  # an output a v + b: a guess of v
            variable, values = affine_guess(self._to_reduced(variable), values, self.model, self.parameters)
        elif isinstance(variable, ca.SX):
            variable = self._to_reduced(variable)
        kind, name, idx = self.model.locate(variable)
        if kind == "parameter":
            raise ModelError(f"set_initial_guess: {name!r} is a parameter; use set_parameter")
        size = int(self.model.variables(kind)[name].numel())
        if len(idx) != size or idx != list(range(size)):
            raise ModelError(f"set_initial_guess: pass the whole variable {name!r}, not a selection")
        if callable(values):
            guess: Any = values
        elif isinstance(values, tuple) and len(values) == 2:
            tg = np.asarray(values[0], dtype=float).reshape(-1)
            vg = np.asarray(values[1], dtype=float)
            if vg.ndim == 1:
                vg = vg.reshape(-1, 1)
            if vg.shape != (tg.size, size) or tg.size < 1 or np.any(np.diff(tg) <= 0):
                raise InputError(
                    f"initial guess of {name!r}: expected increasing t of shape (K,) and values of "
                    f"shape (K, {size}), got {tg.shape} and {np.shape(values[1])}"
                )
            guess = (tg, vg)
        else:
            guess = _vector_value(values, size, f"initial guess of {name!r}")
        self.initial_guesses[name] = guess

    def set_parameter(self, name: str, value: Any) -> None:
        """Override the value of a model parameter for this problem.

        Parameters
        ----------
        name : str
            Declared parameter name.
        value : float or array_like
            New value, same size as the parameter.

        Raises
        ------
        ModelError
            If ``name`` is not a parameter of the model.
        InputError
            If the value has the wrong size or lies outside the parameter's ``min``/``max``
            range (:meth:`Model.parameter <gtmodel.modeling.Model.parameter>`).
        """
        params = self.model.variables("parameter")
        if name not in params:
            raise ModelError(f"set_parameter: model {self.model.name!r} has no parameter {name!r}")
        v = _vector_value(value, int(params[name].numel()), f"parameter {name!r}")
        self.model.check_parameter(name, v)
        self.parameters[name] = v

    def free_parameter(self, name: str, lb: Any = -np.inf, ub: Any = np.inf, start: Any = None) -> ca.SX:
        """Make a model parameter a decision variable (constant in time) of the problem.

        The transcription optimises it together with the trajectories, within
        ``lb <= p <= ub``; the result's ``parameters`` hold its optimal value. With a
        data-fit objective, e.g. ``integral((x - pw_lin(time, t_data, y_data))^2)``,
        this estimates the parameter from data (output-error estimation, as
        JModelica.org's parameter estimation with free parameters).

        Parameters
        ----------
        name : str
            Declared parameter name.
        lb, ub : float or array_like, optional
            Bounds (scalar or one per element); default unbounded.
        start : float or array_like, optional
            Initial guess; default the parameter's value (model default or
            :meth:`set_parameter`) clipped into the bounds.

        Returns
        -------
        casadi.SX
            The parameter symbol, for use in expressions.

        Raises
        ------
        ModelError
            If ``name`` is not a parameter of the model, ``lb > ub`` or ``start`` is
            outside the bounds.
        InputError
            If bounds or start have the wrong size or are NaN.
        """
        params = self.model.variables("parameter")
        if name not in params:
            raise ModelError(
                f"free_parameter: model {self.model.name!r} has no parameter {name!r} "
                f"(parameters: {sorted(params)})"
            )
        size = int(params[name].numel())
        lbv, ubv = self._bounds(lb, ub, size, f"free parameter {name!r}")
        startv = None
        if start is not None:
            startv = _vector_value(start, size, f"free parameter {name!r} start")
            if not np.all(np.isfinite(startv)) or np.any(startv < lbv) or np.any(startv > ubv):
                raise ModelError(f"free parameter {name!r}: start {startv.tolist()} is not within its bounds")
        self.free_parameters[name] = (lbv, ubv, startv)
        return params[name]

    # ------------------------------------------------------------------ evaluation helpers
    def bounds_vectors(self, dae: FlatDAE, kind: str) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of a category, model bounds overridden by :meth:`set_bounds`.

        Parameters
        ----------
        dae : FlatDAE
            Flattened model.
        kind : {"x", "z", "u"}
            Category.

        Returns
        -------
        tuple of numpy.ndarray
            ``(lb, ub)``, each of the category's flat size.
        """
        lb = getattr(dae, f"{kind}_lb").copy()
        ub = getattr(dae, f"{kind}_ub").copy()
        for name, sl in getattr(dae, f"{kind}_vars").items():
            if name in self.bounds:
                blb, bub = self.bounds[name]
                m = ~np.isnan(blb)
                lb[sl][m] = blb[m]
                ub[sl][m] = bub[m]
        return lb, ub
