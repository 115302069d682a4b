"""How an optimal-motion problem is solved: IPOPT's objective scaling for the size of a cost.

The method and solver objects (:class:`Collocation`, :class:`MultipleShooting`,
:class:`SolverSettings`, :class:`Refinement`) live beside the transcriptions they configure,
in :mod:`gtmodel.modeling.ocp.methods`; this former path re-exports them.
"""

from __future__ import annotations

import math

from gtmodel.modeling.ocp.methods import (
    NLP_SOLVERS,
    SCHEMES,
    Collocation,
    MultipleShooting,
    Refinement,
    SolverSettings,
    VerificationSettings,
)

__all__ = ["Collocation", "MultipleShooting", "SolverSettings", "Refinement", "VerificationSettings", "SCHEMES",
           "NLP_SOLVERS", "objective_scaling"]


def objective_scaling(objective: float, duration: float, factor: float) -> float:
    """IPOPT's ``obj_scaling_factor`` for a cost of size ``objective`` at a guess lasting ``duration``.

    ``factor`` is tuned for a cost in seconds, of the size of the motion's duration (Dressler
    (2012), ch. 3.5 with ``w = 0``: the cost is the final time). A cost larger than the
    guess's duration (the energy term of ``final_time + w * integral(...)`` outweighing the
    time) is scaled by ``duration / |objective|`` besides, so that the cost IPOPT sees at the
    guess is ``factor * duration`` for every weight (before IPOPT's own gradient-based
    scaling). With the fixed ``factor``, ``w`` = 10 and 1000 on
    ``problems/l1_time_optimal.toml`` (a cost of 285 and 2.8e4 at the guess of 1 s) made IPOPT creep along
    the flat energy valley, the final time growing towards its bound, for 3000 iterations
    (81 and 85 CPU-s, against 1.6 for ``w = 0``); scaled, every ``w`` up to the 1e6 cap of
    named numbers ends in 21-256 iterations (at most 5.2 CPU-s). The scaling changes IPOPT's
    path and the tolerance it applies, not the problem (in a non-convex one it may change
    which local optimum is found); a cost no larger than the duration (``w = 0``) keeps
    ``factor`` exactly.

    Parameters
    ----------
    objective : float
        The cost at the initial guess (:meth:`~gtmodel.modeling.CollocationTranscription.objective_at_guess`).
    duration : float
        The guess's duration [s], positive.
    factor : float
        The scaling of a cost in seconds (:data:`gtmodel.trajectory.point_to_point.SOLVER_OPTIONS`).

    Returns
    -------
    float
        ``factor * min(1, duration / |objective|)`` (``factor`` for a non-finite or zero cost).
    """
    size = abs(float(objective))
    if not math.isfinite(size) or not duration > 0 or size <= duration:
        return float(factor)
    return float(factor) * duration / size
