"""Warnings about a solution that is optimal for the NLP but probably not what the user meant.

:func:`solution_warnings` looks at a solved :class:`~gtmodel.modeling.Optimization`:

* an input without finite bounds in a minimum-time problem (a free final time): the
  optimum then drives that input as far as the final time's lower bound lets it (a DC
  motor "optimal" in 5.1 ms at 60,694 V), which means nothing about the real system;
* a state or input whose largest magnitude in the solution exceeds
  :data:`MAGNITUDE_FACTOR` times the model's own scale of it (``max(1, |start|, finite
  |bounds|)``): a missing bound or a wrong unit, not an optimum.

:func:`without_inputs` names the cause of a failed solve of a model that has no inputs (IPOPT
reports only ``Not_Enough_Degrees_Of_Freedom``).

The model's own warnings (``Model.warnings``: connectors left open at flattening) come
first, then the transcription's (``OptimizationResult.warnings``: a bound exceeded between
shooting nodes). Each warning is one sentence naming the variable, the value and the fix; the problem
kinds print them (CLI) and write them to ``summary.json`` (``warnings``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["solution_warnings", "without_inputs", "MAGNITUDE_FACTOR"]

#: A solution value more than this many times the model's scale of the variable is flagged.
MAGNITUDE_FACTOR = 1e3


def _peaks(values: np.ndarray) -> np.ndarray:
    """Largest magnitude per column of a ``(n, m)`` array (0 for an empty one)."""
    return np.max(np.abs(values), axis=0) if values.size else np.zeros(values.shape[-1] if values.ndim > 1 else 0)


def solution_warnings(optimization: Any, result: Any) -> list[str]:
    """Warnings about a solved problem: unbounded inputs of a minimum-time problem, magnitudes far off the model's scale.

    Parameters
    ----------
    optimization : Optimization
        The problem (its model, bounds, free final time).
    result : OptimizationResult
        Its solution; nothing is said about a result without collocation data (a failed
        solve).

    Returns
    -------
    list of str
        One sentence per finding (empty when nothing is suspicious).
    """
    col, dae = getattr(result, "collocation", None), getattr(result, "dae", None)
    if col is None or dae is None or result.status not in ("optimal", "acceptable", "check_failed"):
        return []
    out: list[str] = list(getattr(optimization.model, "warnings", [])) + list(getattr(result, "warnings", []))
    u_lb, u_ub = optimization.bounds_vectors(dae, "u")
    x_lb, x_ub = optimization.bounds_vectors(dae, "x")
    u_peak = _peaks(np.asarray(col.uc, dtype=float).reshape(-1, dae.nu)) if dae.nu else np.zeros(0)
    x_peak = _peaks(np.asarray(col.xc, dtype=float).reshape(-1, dae.nx)) if dae.nx else np.zeros(0)
    unbounded = [i for i in range(dae.nu) if not (np.isfinite(u_lb[i]) and np.isfinite(u_ub[i]))]
    if optimization.free_final_time:
        for i in unbounded:
            out.append(
                f"input {dae.u_names[i]!r} has no bounds (or only one) in a minimum-time problem (free final time): "
                f"the optimum drives it as far as the final time's lower bound allows (|{dae.u_names[i]}| up to "
                f"{u_peak[i]:.4g} here, final time {result.final_time:.4g} s); give it [bounds]")
    flagged = set(unbounded) if optimization.free_final_time else set()
    for kind, names, peak, lb, ub, start in (("state", dae.x_names, x_peak, x_lb, x_ub, dae.x_start),
                                             ("input", dae.u_names, u_peak, u_lb, u_ub, np.zeros(dae.nu))):
        for i, name in enumerate(names):
            if kind == "input" and i in flagged:
                continue
            sides = [abs(v) for v in (lb[i], ub[i]) if np.isfinite(v)]
            scale = max([1.0, abs(float(start[i])), *sides])
            if peak[i] > MAGNITUDE_FACTOR * scale:
                out.append(
                    f"{kind} {name!r} reaches {peak[i]:.4g} in the solution, {peak[i] / scale:.3g} times the model's "
                    f"scale of it ({scale:.4g}: its start value and bounds): a missing bound or a wrong unit? "
                    f"bound it in [bounds] or check the model")
    return out


#: IPOPT outcomes that a model without inputs ends in: more equality constraints than unknowns, or none met.
_NO_FREEDOM = ("Not_Enough_Degrees_Of_Freedom", "Infeasible_Problem_Detected", "Restoration_Failed")


def without_inputs(optimization: Any, dae: Any, message: str) -> str:
    """The status message of a failed solve, with the cause named when the model has no inputs.

    IPOPT says ``Not_Enough_Degrees_Of_Freedom`` (or infeasible) and nothing about the model: a
    model whose inputs were forgotten (a ``ConstantVoltage`` where a ``SignalVoltage`` was
    meant) leaves nothing to choose but the final time, the free parameters and unset start
    values, too few for the boundary conditions.

    Parameters
    ----------
    optimization : Optimization
        The problem (free final time, free parameters).
    dae : FlatDAE
        Its flat model.
    message : str
        The solver's message.

    Returns
    -------
    str
        ``message``, followed by the cause when the model has no inputs and the solve ended
        in one of IPOPT's outcomes for too few unknowns; else unchanged.
    """
    if dae.nu or not any(m in message for m in _NO_FREEDOM) or "has no inputs" in message:
        return message
    free = ["the final time"] if optimization.free_final_time else []
    free += ["the free parameters"] if optimization.free_parameters else []
    free.append("the start values the boundary conditions leave free")
    kind = "a minimum-time problem (free final time)" if optimization.free_final_time else "an optimal control problem"
    choice = free[0] if len(free) == 1 else f"{', '.join(free[:-1])} and {free[-1]}"
    return (f"{message}: the model {dae.name!r} has no inputs, so in {kind} nothing but {choice} can be chosen "
            "to meet the boundary conditions and constraints; declare the input that drives it (Model.input, or an "
            "input component such as SignalVoltage, Torque or Force instead of a constant source)")
