"""fatrop's stage order of the collocation NLP (:func:`gtmodel.modeling.ocp.collocation_nlp.transcribe`
with ``stagewise``): one stage per element, its gap-closing rows first, then its path rows."""

from __future__ import annotations

import casadi as ca
import numpy as np

from gtmodel.modeling.ocp.methods import NLP_SOLVERS
from gtmodel.status import Status

__all__ = ["stage_order", "fatrop_cache", "SOLVERS", "IPOPT_ONLY", "FATROP_STATUS", "FATROP_WARM_START_OPTIONS"]

#: nlpsol plugins a transcription can be solved with. ``"fatrop"``: the NLP ordered stage by
#: stage (``transcribe(..., stagewise=True)``), structure given explicitly; its plugin takes no
#: ``jac_g``/``hess_lag`` options, so the assembled derivatives are put in its function cache
#: under the names it asks for (``nlp_jac_g``, ``nlp_hess_l``; docs/verification.md).
SOLVERS = NLP_SOLVERS  # one list, the method objects' (SolverSettings.name)
#: IPOPT options fatrop lacks (dropped; ``obj_scaling_factor`` scales the objective it is given).
IPOPT_ONLY = ("perturb_always_cd", "sb", "mumps_mem_percent", "linear_solver")
#: fatrop options of a warm start from a solution of the problem (of this or a coarser mesh,
#: interpolated): the barrier parameter starts at 1e-3 instead of 0.1. L1 minimum time on 400
#: elements from the 50-element solution: 34 iterations and 1.2 CPU-s, against 86 and 2.9 s with
#: mu_init 0.1 and 110 and 4.2 s from the declared guess (mu_init 1e-2: 38, 1e-4: 41, 1e-5: 49
#: iterations, the last at a neighbouring local optimum).
FATROP_WARM_START_OPTIONS = {"mu_init": 1e-3}
#: fatrop's unified return status -> gtmodel status (success is ``optimal``).
FATROP_STATUS = {"SOLVER_RET_LIMITED": Status.MAX_ITERATIONS, "SOLVER_RET_NAN": Status.ERROR}


def stage_order(N: int, n_points: int, nx: int, ntf: int, ends: list[tuple[int, int]], at: list[str]) -> tuple[np.ndarray, dict]:
    """The permutation of the constraints into fatrop's stage order, and the path constraints per stage.

    The standard order holds per element ``k`` the ``n_points`` rows of its collocation
    points, then its ``nx`` continuity rows and (``ntf``, all but the last element) the
    final-time tie; then the point constraints (``ends``: ``(first row, count)``, each at the
    ``"start"`` or ``"final"`` point as ``at`` says). Stage ``k`` of fatrop is: the gap-closing rows (continuity,
    tie), then the point rows, then the start constraints (``k = 0``) or the final and timed
    ones (``k = N - 1``); stage ``N`` (the final state) has none.

    Parameters
    ----------
    N : int
        Number of elements (stages with constraints).
    n_points : int
        Collocation rows per element.
    nx : int
        Number of states (continuity rows per element).
    ntf : int
        Final-time tie rows per element (0 or 1; none after the last element).
    ends : list of tuple of int
        ``(first row, count)`` of each block of point constraints, in the standard order.
    at : list of str
        ``"start"`` or ``"final"`` for each of ``ends``.

    Returns
    -------
    order : numpy.ndarray
        The rows of the standard order in stage order, shape ``(number of rows,)``.
    stages : dict
        ``{"N": N, "ng": [path rows per stage, ..., 0]}`` (fatrop's ``ng``, length ``N + 1``).
    """
    size_el = n_points + nx + ntf
    rest = [np.arange(first, first + n) for first, n in ends]
    first_ends = [r for r, where in zip(rest, at) if where == "start"]
    last_ends = [r for r, where in zip(rest, at) if where == "final"]
    order, ng_stage = [], []
    for k in range(N):
        base = k * size_el
        dyn = np.arange(base + n_points, base + n_points + nx + (ntf if k < N - 1 else 0))
        path = [np.arange(base, base + n_points)]
        if k == 0:
            path += first_ends
        if k == N - 1:
            path += last_ends
        path_rows = np.concatenate(path)
        order += [dyn, path_rows]
        ng_stage.append(int(path_rows.size))
    return np.concatenate(order).astype(int), {"N": N, "ng": ng_stage + [0]}


def fatrop_cache(derivatives: dict[str, ca.Function], objective_scale: float) -> dict[str, ca.Function]:
    """fatrop's function cache (nlpsol's ``cache`` option) of the assembled derivatives: its plugin takes no
    ``jac_g``/``hess_lag`` options, so they go in under the names it asks for.

    Parameters
    ----------
    derivatives : dict
        ``{"g": ..., "jac_g": ..., "hess_lag": ...}`` of
        :func:`~gtmodel.modeling.ocp.collocation_derivatives.assembled_derivatives` (with ``stagewise``).
    objective_scale : float
        The factor fatrop's objective is multiplied by (its Hessian's ``lam_f`` is scaled by it).

    Returns
    -------
    dict
        ``{"nlp_g": ..., "nlp_jac_g": ..., "nlp_hess_l": ...}``.
    """
    hess_l = derivatives["hess_lag"]
    if objective_scale != 1.0:
        x, p, lam_f, lam_g = hess_l.mx_in()
        hess_l = ca.Function("nlp_hess_l", [x, p, lam_f, lam_g], hess_l(x, p, objective_scale * lam_f, lam_g),
                             hess_l.name_in(), hess_l.name_out())
    return {"nlp_g": derivatives["g"], "nlp_jac_g": derivatives["jac_g"], "nlp_hess_l": hess_l}
