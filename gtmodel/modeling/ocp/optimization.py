"""Optimica-style optimal control problem declarations (no transcription here).

An :class:`Optimization` wraps a :class:`~gtmodel.modeling.simulation.model.Model` and declares the
time horizon (fixed or free final time), the objective (Mayer term at the final time and
Lagrange integrand), path and point constraints, variable bounds, parameter values and
initial guesses. Transcription to an NLP lives in :mod:`gtmodel.modeling.ocp.collocation`.
A model parameter declared free (:meth:`Optimization.free_parameter`) is a decision
variable of the problem (constant in time, within bounds): parameter estimation from data
is an optimisation with free parameters and a data-fit objective.

Expressions may use every symbol the model declared (``time``, states, ``der()`` of
states, algebraics, inputs, parameters) and :attr:`Optimization.final_time`.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling.dae import FlatDAE, _as_sx, _vector_value
from gtmodel.modeling.simulation.model import Model

__all__ = ["Optimization", "Constraint"]

_log = logging.getLogger("gtmodel")


@dataclass
class Constraint:
    """A declared constraint ``lb <= expr <= ub``.

    Parameters
    ----------
    name : str
        Label used in messages.
    expr : casadi.SX
        Column expression.
    lb, ub : numpy.ndarray
        Bounds, one per element of ``expr``.
    at : str or None
        ``None`` for a path constraint, ``"start"`` or ``"final"`` for a point constraint.
    """

    name: str
    expr: ca.SX
    lb: np.ndarray
    ub: np.ndarray
    at: str | None = None


class Optimization:
    """An optimal control problem over a model (Optimica-style declaration).

    Parameters
    ----------
    model : Model
        The dynamic model.
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
        self.path_constraints: list[Constraint] = []
        self.point_constraints: list[Constraint] = []
        self.bounds: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self.initial_guesses: dict[str, Any] = {}
        self.parameters: dict[str, np.ndarray] = {}
        self.free_parameters: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray | None]] = {}
        self._flat: FlatDAE | None = None

    # ------------------------------------------------------------------ helpers
    #: Tolerance of the verification by simulation of this problem's solutions, a positive
    #: number (:mod:`gtmodel.modeling.ocp.verification`); None: ``defaults["ocp.verification_tolerance"]``.
    verification_tolerance: float | None = None

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

    def _expr(self, expr: Any, what: str) -> ca.SX:
        e = _as_sx(expr, what)
        self.model.check_symbols(e, what, extra=[self._final_time])
        return e

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

    def set_objective(self, mayer: Any = None, lagrange: Any = None) -> None:
        """Set the Mayer and/or Lagrange terms of the objective (minimised).

        Parameters
        ----------
        mayer : casadi.SX or float, optional
            Scalar expression evaluated at the final time (may use ``final_time``,
            parameters and model variables, which are taken at ``tf``). Unchanged if
            omitted.
        lagrange : casadi.SX or float, optional
            Scalar integrand over the horizon. Unchanged if omitted.

        Raises
        ------
        InputError
            If an expression is not scalar.
        ModelError
            If an expression contains symbols not declared by the model.
        """
        for label, expr in (("mayer", mayer), ("lagrange", lagrange)):
            if expr is None:
                continue
            e = self._expr(expr, f"objective ({label} term)")
            if e.numel() != 1:
                raise InputError(f"objective ({label} term) must be scalar, got {e.numel()} elements")
            setattr(self, label, e)

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
        e = self._expr(expr, f"path constraint {label!r}")
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
        label = name or f"point{len(self.point_constraints)}"
        e = self._expr(expr, f"point constraint {label!r}")
        lbv, ubv = self._bounds(lb, ub, int(e.numel()), f"point constraint {label!r}")
        self.point_constraints.append(Constraint(label, e, lbv, ubv, at))

    def set_bounds(self, variable: Any, lb: Any = -np.inf, ub: Any = np.inf) -> None:
        """Bound a state, input or algebraic variable for all ``t`` (overrides model bounds).

        Parameters
        ----------
        variable : casadi.SX
            A declared state/input/algebraic symbol, or elements of one.
        lb, ub : float or array_like, optional
            Bounds, scalar or one per selected element.

        Raises
        ------
        ModelError
            If ``variable`` is not a state, input or algebraic, or ``lb > ub``.
        """
        kind, name, idx = self.model.locate(variable)
        if kind == "parameter":
            raise ModelError(f"set_bounds: {name!r} is a parameter; bounds apply to states, inputs, algebraics")
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
            A declared state/input/algebraic symbol (whole variable), or
            :attr:`final_time`.
        values : float, array_like, tuple or callable
            A constant (scalar or ``(n,)``); a trajectory ``(t, values)`` with ``t`` of
            shape ``(K,)`` (absolute times, s) and ``values`` of shape ``(K,)`` or
            ``(K, n)``, linearly interpolated; or a callable ``f(t) -> (n,)``.

        Raises
        ------
        InputError
            If the values have the wrong shape.
        ModelError
            If ``variable`` is not a state, input, algebraic or ``final_time``.
        """
        if isinstance(variable, ca.SX) and variable.numel() == 1 and ca.is_equal(variable, self._final_time):
            v = float(np.asarray(values, dtype=float).reshape(-1)[0])
            lo, hi = self.final_time_bounds
            self.final_time_guess = float(np.clip(v, lo, hi))
            return
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
            If the value has the wrong size.
        """
        params = self.model.variables("parameter")
        if name not in params:
            raise ModelError(f"set_parameter: model {self.model.name!r} has no parameter {name!r}")
        self.parameters[name] = _vector_value(value, int(params[name].numel()), f"parameter {name!r}")

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
