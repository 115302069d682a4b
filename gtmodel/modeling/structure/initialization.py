"""Consistent initialisation: the initial equations (Modelica's ``initial equation``) solved at t0.

The unknowns at the start time are all variables of the (index-reduced) DAE — the states,
their derivatives, the algebraic variables and the derivatives created by Pantelides'
algorithm; the equations are all (original and differentiated) model equations, the
initial equations declared with :meth:`gtmodel.modeling.Model.initial_equation`, and one
condition ``v = value`` per initial condition: every start declared ``fixed=True`` (a
component modifier's start value is fixed: ``Mass(s=3)``) and every entry of the user's
``x0``, on whichever variable it names — alias elimination and index reduction do not drop
it, since the condition is written on the variable's expression in the kept variables
(Modelica's ``start``/``fixed`` semantics, Modelica Language Specification 3.6, section
8.6). Starts with ``fixed=False`` are guesses. Conditions that over-determine the model
(inconsistent or redundant initial conditions) are one error naming the conditions and
equations. A model without initial equations has its remaining degrees of freedom filled
from start values, as Modelica tools do: first the states whose start was given, then the
states of the dummy-derivative selection, each where it adds to the structural rank.
Otherwise the system must be square and structurally regular — else ONE
:class:`~gtmodel.errors.ModelError` names the states that still need an initial equation
(under-determined) or the equations in excess (over-determined) — and is solved by
Newton's method with line search
(``casadi.rootfinder("newton")``), the start values as guess (Pantelides (1988) on the
consistent initialisation of DAEs; Modelica Language Specification 3.6, section 8.6).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._lazy import lazy_module
from gtmodel.errors import ConvergenceError, InputError, ModelError
from gtmodel.modeling.dae import _vector_value, expand_names
from gtmodel.modeling.structure.analysis import (
    Incidence,
    dulmage_mendelsohn,
    matching,
    sparsity_pattern,
    structure_message,
)

#: Imported on first use (PEP 562 lazy module): the solve path of a problem file need not pay for it.
sps = lazy_module("scipy.sparse")

#: ``aug`` arguments are :class:`~gtmodel.modeling.structure.index_reduction.AugmentedDAE` s
#: (annotated ``Any``: index_reduction imports this module for structural_simplify's start).
AugmentedDAE = Any

__all__ = [
    "Condition",
    "InconsistentInitialisation",
    "InitialSystem",
    "condition_residuals",
    "fill_order",
    "guess_and_conditions",
    "initial_system",
    "solve_initial",
]

_log = logging.getLogger("gtmodel")


def _cat(syms: list[ca.SX]) -> ca.SX:
    return ca.vertcat(*syms) if syms else ca.SX(0, 1)


#: A condition ``v = value`` on a declared scalar variable (by its original name), and where it
#: comes from: ``"fixed start"`` (a start declared ``fixed=True``), ``"x0"`` or ``"start, guess"``.
Condition = tuple[float, str]


def condition_residuals(aug: AugmentedDAE, conditions: Mapping[str, Condition]) -> tuple[list[ca.SX], list[str]]:
    """Residuals ``v - value`` and labels of conditions on declared variables, through alias elimination.

    Parameters
    ----------
    aug : AugmentedDAE or ScalarDAE
        The DAE after :func:`~gtmodel.modeling.structure.index_reduction.pantelides`, or a
        :class:`~gtmodel.modeling.structure.analysis.ScalarDAE` (its ``observed`` names;
        the optimisation's initial conditions, :mod:`gtmodel.modeling.ocp.initial`).
    conditions : mapping of str to tuple
        Original scalar name (``"mass.s"``, ``"T[0]"``; an eliminated alias too) ->
        ``(value, source)``.

    Returns
    -------
    residuals : list of casadi.SX
        ``observed[name] - value``: in the variables the alias elimination kept.
    labels : list of str
        ``"mass.s = 3 (fixed start)"`` style.

    Raises
    ------
    ModelError
        If a name is no scalar state or algebraic variable of the model.
    """
    s = getattr(aug, "system", aug)
    res, labels = [], []
    for name, (value, source) in conditions.items():
        if name not in s.observed:
            raise ModelError(f"model {s.name!r}: initial condition on {name!r}, which is no state or algebraic variable")
        res.append(s.observed[name] - value)
        labels.append(f"{name} = {value:.12g} ({source})")
    return res, labels


def guess_and_conditions(model: Any, aug: AugmentedDAE, x0: Any, z0: Any) -> tuple[np.ndarray, dict[str, Condition]]:
    """Start values of all variables (x0/z0 applied) and the initial conditions by name.

    The conditions are every entry of ``x0`` (a mapping, or a vector of all states), then
    the starts declared ``fixed=True`` (an ``x0`` entry replaces the start of its state);
    ``z0`` values are guesses.

    Parameters
    ----------
    model : Model
        The model (its declared states and algebraic variables).
    aug : AugmentedDAE
        Its DAE after :func:`~gtmodel.modeling.structure.index_reduction.pantelides`.
    x0 : mapping or array_like or None
        As for :meth:`gtmodel.modeling.Model.simulate`.
    z0 : array_like or None
        Guesses of the algebraic variables, ``(nz,)``.

    Returns
    -------
    guess : numpy.ndarray
        All variables of ``aug``, ``(len(aug.syms),)``.
    conditions : dict of str to tuple
        Original scalar name -> ``(value, source)``, ``x0`` entries first.

    Raises
    ------
    InputError
        If ``x0`` names no state or has the wrong size, or ``z0`` the wrong size.
    """
    s = aug.system
    guess = np.concatenate([s.start, np.zeros(len(aug.syms) - s.n_vars)])
    index = {nm: k for k, nm in enumerate(aug.names)}
    states = [v for v in model._vars.values() if v.kind == "state"]
    algs = [v for v in model._vars.values() if v.kind == "algebraic"]
    fixed: dict[str, Condition] = {nm: (val, "fixed start") for nm, val in s.fixed_start.items()}
    conditions: dict[str, Condition] = {}  # x0 first: its entries are kept where conditions are redundant

    def put(name: str, value: float) -> None:
        if name in index:
            guess[index[name]] = value
        elif name in s.aliases:
            sign, keep = s.aliases[name]
            put(keep, sign * value)

    for name, (value, _) in fixed.items():
        put(name, value)
    if isinstance(x0, Mapping):
        known = {v.name: v for v in states}
        for name, val in x0.items():
            if name not in known:
                raise InputError(f"x0: {name!r} is not a state of model {model.name!r}")
            vals = _vector_value(val, known[name].size, f"x0[{name!r}]")
            for nm, val_ in zip(expand_names(name, known[name].size), vals):
                put(nm, float(val_))
                conditions[nm] = (float(val_), "x0")
    elif x0 is not None:
        names = [nm for v in states for nm in expand_names(v.name, v.size)]
        for nm, val_ in zip(names, _vector_value(x0, len(names), "x0")):
            put(nm, float(val_))
            conditions[nm] = (float(val_), "x0")
    conditions.update({nm: c for nm, c in fixed.items() if nm not in conditions})
    if z0 is not None:
        names = [nm for v in algs for nm in expand_names(v.name, v.size)]
        for nm, val_ in zip(names, _vector_value(z0, len(names), "z0")):
            put(nm, float(val_))
    return guess, conditions


def fill_order(aug: AugmentedDAE, guess: np.ndarray, selected: list[int]) -> list[tuple[int, float]]:
    """Candidates completing an under-specified initialisation, in priority order.

    The variables that have a derivative (the states of some dummy selection): first the
    declared states whose start was given, then the states of ``selected`` (the dummy
    selection at the guess), then the others, each in declaration order.

    Parameters
    ----------
    aug : AugmentedDAE
        The DAE after :func:`~gtmodel.modeling.structure.index_reduction.pantelides`.
    guess : numpy.ndarray
        All variables' start values, ``(len(aug.syms),)``.
    selected : list of int
        The states of a dummy selection made at ``guess``.

    Returns
    -------
    list of tuple
        ``(variable index, guess)`` for :func:`initial_system`'s ``fill``.
    """
    s = aug.system
    given = {s.aliases.get(nm, (1.0, nm))[1] for nm in s.given_start}
    chosen = set(selected)
    cand = [v for v in range(len(aug.syms)) if aug.diff[v] is not None]
    cand.sort(key=lambda v: (not (aug.order[v] == 0 and aug.names[v] in given), v not in chosen, v))
    return [(v, float(guess[v])) for v in cand]


def _rank(pat: sps.csr_matrix) -> int:
    return int(np.sum(matching(pat)[0] >= 0))


def _row(v: int, n: int) -> sps.csr_matrix:
    return sps.csr_matrix((np.ones(1, dtype=np.int8), ([0], [v])), shape=(1, n))


@dataclass
class InitialSystem:
    """The initialisation problem of :func:`initial_system`.

    Parameters
    ----------
    res, labels : list
        The square system's residuals (casadi.SX scalars) and their names.
    redundant, redundant_labels : list
        Initial equations and conditions left out as structurally redundant; they must
        hold at the solution (checked by :func:`solve_initial`).
    full_pattern : scipy.sparse.csr_matrix
        Incidence of all equations, initial equations and conditions (for the message
        naming an inconsistency), ``(len(res) + len(redundant) - n_fill, len(aug.syms))``.
    full_labels : list of str
        Its row labels.
    """

    res: list[ca.SX]
    labels: list[str]
    redundant: list[ca.SX]
    redundant_labels: list[str]
    full_pattern: sps.csr_matrix
    full_labels: list[str]


def initial_system(
    aug: AugmentedDAE,
    conditions: Mapping[str, Condition],
    fill: Sequence[tuple[int, float]] | None = None,
) -> InitialSystem:
    """The initialisation problem, checked for structural regularity.

    The equations are the model's (original and differentiated), the initial equations,
    and the ``conditions`` (``x0`` values, fixed starts). Initial equations and conditions
    that are structurally redundant (more of them than the variables they fix, e.g. the
    consistent starts of a damper's ``s_rel`` and of the mass it holds) are set aside, in
    the order initial equations, ``x0``, fixed starts, and checked at the solution: they
    must hold there (:func:`solve_initial`; redundant but consistent initial conditions
    are accepted, as Modelica tools accept them); none is dropped silently. If degrees of
    freedom remain and ``fill`` is given (a model without initial equations), the
    candidates ``v = guess`` are added in their order where each adds one to the
    structural rank (the greedy basis of the transversal matroid: the highest-priority
    independent set), as Modelica tools complete an under-specified initialisation from the
    start values of states (Modelica Language Specification 3.6, section 8.6).

    Parameters
    ----------
    aug : AugmentedDAE
        The DAE after :func:`~gtmodel.modeling.structure.index_reduction.pantelides`.
    conditions : mapping of str to tuple
        Original scalar variable name -> ``(value, source)`` (see
        :func:`condition_residuals`), in priority order.
    fill : sequence of tuple, optional
        ``(variable index in aug.syms, guess)`` candidates in priority order; default none
        (the initial equations and conditions must determine every variable).

    Returns
    -------
    InitialSystem
        The square system and the redundant initial equations and conditions.

    Raises
    ------
    ModelError
        One message: under-determined (naming the states that need an initial equation, an
        ``x0`` value or a fixed start, and the variables left undetermined) or structurally
        singular.
    """
    s = aug.system
    cres, clabels = condition_residuals(aug, conditions)
    extra_res = list(s.init_res) + cres
    extra_labels = list(s.init_names) + clabels
    n = len(aug.syms)
    pat_model = sparsity_pattern(list(aug.res), aug.syms)
    pat_extra = sparsity_pattern(extra_res, aug.syms)
    full = sps.vstack([pat_model, pat_extra], format="csr")
    res, labels = list(aug.res), list(aug.eq_names)
    redundant, redundant_labels = [], []
    rows, rank = [pat_model], _rank(pat_model)
    for i in range(len(extra_res)):
        trial = sps.vstack(rows + [pat_extra[i]], format="csr")
        r = _rank(trial)
        if r > rank:
            rows.append(pat_extra[i])
            rank = r
            res.append(extra_res[i])
            labels.append(extra_labels[i])
        else:
            redundant.append(extra_res[i])
            redundant_labels.append(extra_labels[i])
    what = f"initialisation of model {s.name!r}"
    if redundant:
        _log.debug("%s: redundant initial conditions %s (checked at the solution)", what, redundant_labels)
    if fill and rank < n:
        for v, value in fill:
            if rank == n:
                break
            trial = sps.vstack(rows + [_row(v, n)], format="csr")
            r = _rank(trial)
            if r > rank:
                rows.append(_row(v, n))
                rank = r
                res.append(aug.syms[v] - value)
                labels.append(f"{aug.names[v]} = {value:.12g} (start, guess)")
                _log.debug("%s: %s at its start value %g", what, aug.names[v], value)
    pat = sps.vstack(rows, format="csr")
    msg = structure_message(Incidence(pat, labels, list(aug.names)), what)
    if msg:
        dm = dulmage_mendelsohn(pat)
        states = [
            aug.names[v] for v in dm["under_vars"]
            if aug.diff[v] is not None and aug.order[v] == 0 and aug.names[v] not in conditions
        ]
        if dm["unmatched_vars"]:
            msg += (
                f"; add initial equations (Model.initial_equation) or x0 values for "
                f"{len(dm['unmatched_vars'])} of the states {states} (or declare their starts fixed=True)"
            )
        raise ModelError(msg)
    return InitialSystem(res, labels, redundant, redundant_labels, full, list(aug.eq_names) + extra_labels)


class InconsistentInitialisation(ModelError):
    """Initial conditions (fixed starts, ``x0``, initial equations) that contradict each other or the model."""


def _inconsistent(
    aug: AugmentedDAE, system: InitialSystem, bad: list[tuple[str, float]], conditions: Mapping[str, Condition]
) -> InconsistentInitialisation:
    """The error for redundant initial conditions that do not hold at the solution."""
    value_of = {f"{nm} = {val:.12g} ({src})": val for nm, (val, src) in conditions.items()}
    bad_text = [
        f"{lab}, but the others give {value_of[lab] + r:.6g}" if lab in value_of else f"{lab} (residual {r:.6g})"
        for lab, r in bad
    ]
    dm = dulmage_mendelsohn(system.full_pattern)
    lab = system.full_labels
    extra = [lab[i] for i in dm["over_eqs"] if i >= len(aug.res)]
    return InconsistentInitialisation(
        f"initialisation of model {aug.system.name!r} is over-determined and inconsistent: "
        f"{bad_text} do not hold where the others do; "
        f"equations {[lab[i] for i in dm['over_eqs']]} over-determine variables "
        f"{[aug.names[j] for j in dm['over_vars']]}; remove {len(bad)} of the initial equations / fixed starts / "
        f"x0 values {extra} or make them consistent"
    )


def solve_initial(
    aug: AugmentedDAE,
    t0: float,
    u0: np.ndarray,
    p: np.ndarray,
    guess: np.ndarray,
    conditions: Mapping[str, Condition],
    fill: Sequence[tuple[int, float]] | None = None,
    tol: float = 1e-12,
) -> np.ndarray:
    """Consistent values of all variables at ``t0``.

    Parameters
    ----------
    aug : AugmentedDAE
        The DAE after :func:`~gtmodel.modeling.structure.index_reduction.pantelides`.
    t0 : float
        Start time, s.
    u0 : numpy.ndarray
        Inputs at ``t0``, shape ``(nu,)``.
    p : numpy.ndarray
        Parameter vector, shape ``(npar,)``.
    guess : numpy.ndarray
        Initial guess of all variables, shape ``(len(aug.syms),)``.
    conditions : mapping of str to tuple
        Initial conditions by original variable name (see :func:`initial_system`).
    fill : sequence of tuple, optional
        Candidates completing an under-specified initialisation (see :func:`initial_system`).
    tol : float, optional
        Required max-norm of the residuals (default 1e-12).

    Returns
    -------
    numpy.ndarray
        Values of all variables, shape ``(len(aug.syms),)``.

    Raises
    ------
    ModelError
        If the problem is under-determined or structurally singular (see
        :func:`initial_system`), or over-determined and inconsistent: redundant initial
        equations or conditions that do not hold at the solution (one message naming them,
        the equations and the variables they over-determine).
    ConvergenceError
        If Newton's method does not reach ``tol``, naming the largest residuals.
    """
    system = initial_system(aug, conditions, fill)
    res, labels = system.res, system.labels
    s = aug.system
    v = _cat(aug.syms)
    par = ca.vertcat(s.t, s.u, s.p)
    F = ca.Function("init_res", [v, par], [_cat(res)])
    pv = np.concatenate([[t0], np.asarray(u0, dtype=float).ravel(), np.asarray(p, dtype=float).ravel()])
    g0 = np.asarray(guess, dtype=float).copy()
    solver = ca.rootfinder(
        "init", "newton", F, {"line_search": True, "error_on_fail": False, "abstol": tol * 1e-2, "max_iter": 200}
    )
    sol = np.array(solver(g0, pv)).ravel()
    r = np.array(F(sol, pv)).ravel()
    if not (np.all(np.isfinite(sol)) and np.max(np.abs(r), initial=0.0) <= tol * max(1.0, np.max(np.abs(sol), initial=0.0))):
        worst = np.argsort(-np.abs(np.nan_to_num(r, nan=np.inf)))[:3]
        raise ConvergenceError(
            f"initialisation of model {s.name!r} did not converge: largest residuals "
            f"{[(labels[i], float(r[i])) for i in worst]}; improve the start values"
        )
    if system.redundant:
        R = ca.Function("init_redundant", [v, par], [_cat(system.redundant)])
        rr = np.array(R(sol, pv)).ravel()
        scale = max(1.0, np.max(np.abs(sol), initial=0.0))
        bad = [(lab, float(x)) for lab, x in zip(system.redundant_labels, rr) if not abs(x) <= 1e-8 * scale]
        if bad:
            raise _inconsistent(aug, system, bad, conditions)
    _report_moved_guesses(aug, sol, conditions)
    _log.debug("initialised model %s: %d unknowns", s.name, len(sol))
    return sol


def _report_moved_guesses(aug: AugmentedDAE, sol: np.ndarray, conditions: Mapping[str, Condition]) -> None:
    """Log (warning) the given, not fixed, start values that the initialisation did not keep.

    They are guesses (``fixed=False``), but a user who gave one may have meant an initial
    condition: the message names each with its start and its initial value, and the way to
    make it one (``fixed=True`` or ``x0``).
    """
    s = aug.system
    names = [nm for nm in s.given_start if nm not in conditions and nm in s.observed]
    if not names:
        return
    values = np.array(ca.Function("observed", [_cat(aug.syms)], [_cat([s.observed[nm] for nm in names])])(sol)).ravel()
    moved = [
        f"{nm} (start {s.given_start[nm]:.6g}, initial value {val:.6g})" for nm, val in zip(names, values)
        if abs(val - s.given_start[nm]) > 1e-8 * max(1.0, abs(s.given_start[nm]))
    ]
    if moved:
        _log.warning(
            "model %s: the initialisation did not keep the start values %s; they are guesses (fixed=False): "
            "declare them fixed=True or give them in x0 to make them initial conditions",
            s.name, moved,
        )
