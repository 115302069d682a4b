"""Warm-started re-solves of a collocation NLP as one CasADi Function (rockit's ``to_function``).

A sweep, a study or an online re-planner changes the parameters (weights, boundary poses
declared as model parameters) and solves again without rebuilding anything. A warm start
from the previous primal point alone restarts IPOPT's barrier at ``mu_init = 0.1``, which
pushes the iterate back into the interior and may end at another local optimum (the L1
minimum-time problem after a 1 cm change of the end pose, issue 17). Starting from the
primal point *and the multipliers* with a small barrier parameter keeps IPOPT close to
the previous optimum's active set; the tests check that it reaches the cold-start optimum.
"""

from __future__ import annotations

from typing import Any

import casadi as ca

from gtmodel.defaults import defaults

__all__ = ["WARM_START_OPTIONS", "resolve_function"]

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
