"""Consistent initialisation: the initial equations (Modelica's ``initial equation``) solved at t0.

The unknowns at the start time are all variables of the (index-reduced) DAE — the states,
their derivatives, the algebraic variables and the derivatives created by Pantelides'
algorithm; the equations are all (original and differentiated) model equations, the
initial equations declared with :meth:`gtmodel.modeling.Model.initial_equation`, and one
equation ``v = value`` per fixed variable (a state given in ``x0``, or, for a model without
initial equations, the selected states at their start values). The system must be square
and structurally regular — otherwise ONE :class:`~gtmodel.errors.ModelError` names the
states that still need an initial equation (under-determined) or the equations in excess
(over-determined) — and is solved by Newton's method with line search
(``casadi.rootfinder("newton")``), the start values as guess (Pantelides (1988) on the
consistent initialisation of DAEs; Modelica Language Specification 3.6, section 8.6).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping

import casadi as ca
import numpy as np

from gtmodel.errors import ConvergenceError, ModelError
from gtmodel.modeling.structure.index_reduction import AugmentedDAE
from gtmodel.modeling.structure.analysis import Incidence, dulmage_mendelsohn, sparsity_pattern, structure_message

__all__ = ["initial_system", "solve_initial"]

_log = logging.getLogger("gtmodel")


def _cat(syms: list[ca.SX]) -> ca.SX:
    return ca.vertcat(*syms) if syms else ca.SX(0, 1)


def initial_system(aug: AugmentedDAE, fixed: Mapping[int, float]) -> tuple[list[ca.SX], list[str]]:
    """Residuals and labels of the initialisation problem, checked for structural regularity.

    Parameters
    ----------
    aug : AugmentedDAE
        The DAE after :func:`~gtmodel.modeling.structure.index_reduction.pantelides`.
    fixed : mapping of int to float
        Variable index -> fixed value at t0.

    Returns
    -------
    residuals : list of casadi.SX
        Model equations, initial equations and ``v - value`` of the fixed variables.
    labels : list of str
        Their names (``"<name> = x0"`` for a fixed variable).

    Raises
    ------
    ModelError
        One message: under-determined (naming the states that need an initial equation or
        an ``x0`` value, and the variables left undetermined), over-determined (naming the
        initial equations or fixed values in excess) or structurally singular.
    """
    s = aug.system
    res = list(aug.res) + list(s.init_res) + [aug.syms[v] - val for v, val in fixed.items()]
    labels = list(aug.eq_names) + list(s.init_names) + [f"{aug.names[v]} = x0" for v in fixed]
    pat = sparsity_pattern(res, aug.syms)
    inc = Incidence(pat, labels, list(aug.names))
    msg = structure_message(inc, f"initialisation of model {s.name!r}")
    if msg:
        dm = dulmage_mendelsohn(pat)
        states = [
            aug.names[v] for v in dm["under_vars"] if aug.diff[v] is not None and aug.order[v] == 0 and v not in fixed
        ]
        if dm["unmatched_vars"]:
            msg += (
                f"; add initial equations (Model.initial_equation) or x0 values for "
                f"{len(dm['unmatched_vars'])} of the states {states}"
            )
        if dm["unmatched_eqs"]:
            extra = [labels[i] for i in dm["over_eqs"] if i >= len(aug.res)]
            msg += f"; remove {len(dm['unmatched_eqs'])} of the initial equations / x0 values {extra}"
        raise ModelError(msg)
    return res, labels


def solve_initial(
    aug: AugmentedDAE,
    t0: float,
    u0: np.ndarray,
    p: np.ndarray,
    guess: np.ndarray,
    fixed: Mapping[int, float],
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
    fixed : mapping of int to float
        Variables fixed at a value (see :func:`initial_system`).
    tol : float, optional
        Required max-norm of the residuals (default 1e-12).

    Returns
    -------
    numpy.ndarray
        Values of all variables, shape ``(len(aug.syms),)``.

    Raises
    ------
    ModelError
        If the problem is not square and structurally regular (see :func:`initial_system`).
    ConvergenceError
        If Newton's method does not reach ``tol``, naming the largest residuals.
    """
    res, labels = initial_system(aug, fixed)
    s = aug.system
    v = _cat(aug.syms)
    par = ca.vertcat(s.t, s.u, s.p)
    F = ca.Function("init_res", [v, par], [_cat(res)])
    pv = np.concatenate([[t0], np.asarray(u0, dtype=float).ravel(), np.asarray(p, dtype=float).ravel()])
    g0 = np.asarray(guess, dtype=float).copy()
    for k, val in fixed.items():
        g0[k] = val
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
    _log.debug("initialised model %s: %d unknowns", s.name, len(sol))
    return sol
