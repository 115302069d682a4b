"""Warm-started re-solves of a collocation NLP as one CasADi Function (rockit's ``to_function``).

A sweep, a study or an online re-planner changes the parameters (weights, boundary poses
declared as model parameters) and solves again without rebuilding anything. A warm start
from the previous primal point alone restarts IPOPT's barrier at ``mu_init = 0.1``, which
pushes the iterate back into the interior and may end at another local optimum (the L1
minimum-time problem after a 1 cm change of the end pose, issue 17). Starting from the
primal point *and the multipliers* with a small barrier parameter keeps IPOPT close to
the previous optimum's active set; the tests check that it reaches the cold-start optimum.
Both the cold and the warm-start ``nlpsol`` of a transcription are built by :func:`nlp_solver`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import casadi as ca

from gtmodel.defaults import defaults
from gtmodel.errors import SolverError
from gtmodel.modeling.ocp.collocation_derivatives import assembled_oracle
from gtmodel.modeling.ocp.collocation_stages import IPOPT_ONLY, fatrop_cache

__all__ = ["WARM_START_OPTIONS", "nlp_solver", "resolve_function"]

#: IPOPT options of warm starts: the dict ``defaults["ipopt.warm_start"]`` of
#: :mod:`gtmodel.defaults` (start from the given primal-dual point with a small barrier
#: parameter and without pushing it off the bounds).
WARM_START_OPTIONS = defaults["ipopt.warm_start"]


def resolve_function(transcription: Any, name: str = "resolve", warm_start: bool = True) -> ca.Function:
    """A CasADi Function that solves ``transcription``'s NLP for given parameters and start point.

    Parameters
    ----------
    transcription : gtmodel.modeling.CollocationTranscription
        The NLP (built once; its compiled derivatives are shared).
    name : str, optional
        Function name.
    warm_start : bool, optional
        Use IPOPT with :data:`WARM_START_OPTIONS` (True, default) or the cold solver.

    Returns
    -------
    casadi.Function
        Inputs ``p`` (np,): the model parameter vector (``FlatDAE.parameter_vector``),
        ``w0`` (nw,), ``lam_w0`` (nw,), ``lam_g0`` (ng,): a previous solution's NLP vector
        and multipliers (``OptimizationResult.w``, ``lam_w``, ``lam_g``). Outputs ``w``,
        ``lam_w``, ``lam_g`` (the same sizes: feed them back for the next call),
        ``objective`` (1,) and ``final_time`` [s] (1,). Whether a call converged is in
        ``transcription.warm_solver().stats()`` (or ``.solver`` when cold).

    Notes
    -----
    The Function is a symbolic call of ``casadi.nlpsol`` (as rockit's
    ``Stage.to_function``); it can be embedded in other CasADi graphs.
    """
    solver = transcription.warm_solver() if warm_start else transcription.solver
    nw, ng = transcription._lbw.size, transcription._lbg.size
    p = ca.MX.sym("p", int(transcription.nlp.p.numel()))
    w0, lw, lg = ca.MX.sym("w0", nw), ca.MX.sym("lam_w0", nw), ca.MX.sym("lam_g0", ng)
    sol = solver(
        x0=w0, lam_x0=lw, lam_g0=lg, p=p, lbx=transcription._lbw, ubx=transcription._ubw, lbg=transcription._lbg, ubg=transcription._ubg
    )
    tf = transcription._extract(sol["x"], p)[4]
    return ca.Function(
        name,
        [p, w0, lw, lg],
        [sol["x"], sol["lam_x"], sol["lam_g"], transcription.optimization.objective_sign * sol["f"], tf],
        ["p", "w0", "lam_w0", "lam_g0"],
        ["w", "lam_w", "lam_g", "objective", "final_time"],
    )


def nlp_solver(nlp: Any, plugin: str, options: Mapping[str, Any], derivatives: Mapping[str, ca.Function],
               name: str) -> tuple[ca.Function, float]:
    """The ``casadi.nlpsol`` of a collocation NLP (its derivative functions shared), and fatrop's objective factor.

    Parameters
    ----------
    nlp : CollocationNLP
        The transcribed NLP (:func:`~gtmodel.modeling.ocp.collocation_nlp.transcribe`).
    plugin : {"ipopt", "fatrop"}
        The nlpsol plugin.
    options : mapping
        nlpsol options, the plugin's under its name (:func:`~gtmodel.modeling.ocp.collocation_nlp.merge_options`).
    derivatives : mapping of str to casadi.Function
        The assembled derivatives (empty: CasADi differentiates the NLP), IPOPT's as ``jac_g``/``hess_lag``
        options, fatrop's through its function cache (:func:`~gtmodel.modeling.ocp.collocation_stages.fatrop_cache`).
    name : str
        The model's CasADi name (the solver is ``<name>_collocation``).

    Returns
    -------
    solver : casadi.Function
    objective_scale : float
        fatrop: the factor its objective is multiplied by (its options' ``obj_scaling_factor``, which the plugin
        lacks); IPOPT: 1.

    Raises
    ------
    SolverError
        If CasADi cannot build it; with fatrop, constraints coupling elements beyond neighbouring ones say so.
    """
    nlp_options, f, scale = {**options, **derivatives}, nlp.f, 1.0
    if plugin == "fatrop":
        inner = {k: v for k, v in options["fatrop"].items() if k not in IPOPT_ONLY}
        scale = float(inner.pop("obj_scaling_factor", 1.0))
        f = f * scale
        nlp_options = {**options, "fatrop": inner, "structure_detection": "manual", **nlp.stages}
        if derivatives:  # the plugin has no jac_g/hess_lag options: its function cache, by name
            nlp_options["cache"] = fatrop_cache(dict(derivatives), scale)
    problem = {"x": nlp.w, "p": nlp.p, "f": f, "g": nlp.g}
    if plugin != "fatrop" and {"jac_g", "hess_lag"} <= set(derivatives):
        problem, more = assembled_oracle(nlp, f, name)  # the build's cost (CPU) a third
        nlp_options.update(more)
    try:
        return ca.nlpsol(f"{name}_collocation", plugin, problem, nlp_options), scale
    except RuntimeError as exc:
        if "structure of A" in str(exc) or "Structure" in str(exc):
            raise SolverError(
                f"solver fatrop: the problem's constraints couple elements beyond neighbouring ones (timed values or "
                f"integrals in constraints), which fatrop's stage structure cannot hold; use solver ipopt ({exc})"
            ) from exc
        raise SolverError(f"could not build the {plugin} solver: {exc}") from exc
