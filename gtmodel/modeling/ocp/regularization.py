"""Input regularisation of minimum-time problems: inputs the objective leaves undetermined, pinned.

A minimum-time objective (``final_time``, Mayer only) does not depend on the inputs. Where a state
bound is active (a drive's current at its limit while it brakes) or on a singular arc, the inputs
between the collocation points are then free within what keeps the points feasible: the NLP's
solution rings there (a belt drive's voltage 1.3 V around the 21 V its current's bound arc needs),
each mesh gives another ringing, the simulation under it deviates from the collocation states by
the ringing over the resistance, and mesh refinement saws (the drive family's drive0_38: best
deviation 0.0109 against 0.01 after 21 passes, 97 CPU-s, ``check_failed``).

The transcription minimises instead

.. math::

    J_\\varepsilon = c\\,t_f + \\varepsilon\\, c \\int_{t_0}^{t_f} \\sum_j \\left(\\frac{u_j}{s_j}\\right)^2 dt,

with ``s_j`` the input's scale: in mesh refinement (:mod:`~gtmodel.modeling.ocp.refinement`, from its second pass
on) its root mean square over the previous pass, so that the term weighs what the motion uses (drive0_38's voltage
bound is 84 V, and its first pass touches it; its motion's RMS is about 25 V); else ``max(|lb_j|, |ub_j|)``, its
bound (inputs with neither are not regularised). The term is strictly convex in the inputs, so the ringing has a
cost and goes; and it is small where it counts: the minimum time of the regularised problem exceeds the problem's by
at most ``varepsilon c`` times the integral at the problem's minimum (from ``J_eps(x_eps) <= J_eps(x*)`` and
``J_eps(x_eps) >= c t_f,eps``); with RMS scales that integral is ``n t_f`` where the motion is the previous pass's,
so the minimum time rises by about ``varepsilon`` per input. The default ``varepsilon = 1e-3``
(``defaults["ocp.input_regularization"]``) is 0.1 % per input, inside the drive family's 0.5 % test of its
references; 1e-4 was too weak to stop drive0_38's ringing (30 passes, deviation 0.0102, ``check_failed``); with
1e-3 it verifies in 14 passes (25 CPU-s; unregularised, 21 passes ``check_failed``), and drive0_04, a ball screw
that sawed alike, verifies 0.02 % above its independent reference. The result's ``objective`` is the
declared one (``c t_f``), not ``J_eps``; its ``stats["regularization"]`` states the term (weight, inputs and scales,
its value, and ``at_scales``: ``varepsilon c n t_f``, its value where each input's RMS equals its scale; the value
itself may exceed it by what the RMS grew over the previous pass's, and is the estimate of what the term costs).

Only minimum-time objectives are regularised: a Lagrange term of the user's (energy, tracking) has
its own dependence on the inputs, and a general Mayer term no scale that would bound the bias.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.defaults import defaults
from gtmodel.errors import InputError

__all__ = ["Regularization", "regularized", "regularization_weight", "input_scales"]


@dataclass
class Regularization:
    """The input regularisation a transcription added (see the module docstring).

    Parameters
    ----------
    optimization : object
        The declaration as the transcription reads it: the regularisation its Lagrange term, all else the
        original's.
    weight : float
        ``varepsilon`` (dimensionless).
    scale : float
        ``c``, the final time's coefficient in the objective.
    inputs : dict of str to float
        The regularised inputs (flat names: ``tau[0]`` for an array's element) and their scales ``s_j`` (their units).
    """

    optimization: Any
    weight: float
    scale: float
    inputs: dict[str, float] = field(default_factory=dict)

    def report(self, value: float, final_time: float) -> dict[str, Any]:
        """The record of the term at a solution (``stats["regularization"]``).

        Parameters
        ----------
        value : float
            The term's value in the NLP's objective (``varepsilon c`` times the integral).
        final_time : float
            The solution's final time, s.

        Returns
        -------
        dict
            ``{"kind", "weight", "inputs", "value", "at_scales"}``: ``at_scales`` is ``varepsilon c n t_f``, the term's
            value where each input's RMS equals its scale (the declared objective's units).
        """
        return {"kind": "input energy of a minimum-time problem", "weight": self.weight,
                "inputs": dict(self.inputs), "value": float(value),
                "at_scales": float(self.weight * self.scale * len(self.inputs) * final_time)}


def regularization_weight(value: Any) -> tuple[float, dict[str, float]]:
    """``value`` checked as a regularisation: a weight (None: the default), or a weight and the inputs' scales.

    Parameters
    ----------
    value : float or None or tuple of (float, dict of str to float)
        ``varepsilon``, in ``[0, 0.01]`` (0: off), the inputs scaled by their bounds; or ``(varepsilon, scales)``,
        the scales ``s_j > 0`` of inputs by flat name (the others by their bounds).

    Returns
    -------
    tuple of (float, dict of str to float)
        The weight and the given scales.

    Raises
    ------
    InputError
        On a weight that is not a number in ``[0, 0.01]``, or a scale that is not a positive finite number.
    """
    if isinstance(value, tuple) and len(value) == 2 and isinstance(value[1], dict):
        weight, scales = regularization_weight(value[0])[0], {}
        for name, s in value[1].items():
            if isinstance(s, bool) or not isinstance(s, (int, float, np.integer, np.floating)) or not (np.isfinite(s) and s > 0):
                raise InputError(f"regularization: the scale of input {name!r} must be a positive number, got {s!r}")
            scales[str(name)] = float(s)
        return weight, scales
    if value is None:
        return float(defaults["ocp.input_regularization"]), {}
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) or not 0 <= float(value) <= 1e-2:
        raise InputError(f"regularization: expected a weight in [0, 0.01] (0: off; the minimum time rises by at most "
                         f"the weight per regularised input), got {value!r}")
    return float(value), {}


def _time_coefficient(opt: Any) -> float | None:
    """``c`` where the objective minimised is ``c * final_time`` with ``c > 0`` alone, else None."""
    if not opt.free_final_time or opt.objective_sign != 1.0 or not ca.SX(opt.lagrange).is_zero() or opt.data_fits:
        return None
    mayer = ca.SX(opt.mayer)
    if mayer.numel() != 1 or not ca.depends_on(mayer, opt.final_time):
        return None
    coefficient = ca.jacobian(mayer, opt.final_time)
    rest = ca.simplify(mayer - coefficient * opt.final_time)
    if not coefficient.is_constant() or not rest.is_zero():
        return None
    c = float(ca.evalf(coefficient))
    return c if c > 0 and np.isfinite(c) else None


def regularized(opt: Any, dae: Any, weight: float, scales: dict[str, float] | None = None) -> tuple[Any, Regularization | None]:
    """The declaration with its inputs regularised, where it is a minimum-time problem (module docstring).

    Parameters
    ----------
    opt : Optimization
        The declaration (as the transcription carries it: after the algebraic elimination).
    dae : FlatDAE
        Its flattened model (the Lagrange term is written in its input symbols).
    weight : float
        ``varepsilon`` (:func:`regularization_weight`); 0 regularises nothing.
    scales : dict of str to float, optional
        ``s_j`` of inputs by flat name (:func:`input_scales`); the others' are their bounds.

    Returns
    -------
    tuple of (Optimization, Regularization or None)
        The problem the NLP carries (``opt`` itself where nothing is regularised: weight 0, not a
        minimum-time objective, no input with a finite bound) and the regularisation (or None).
    """
    c = _time_coefficient(opt) if weight > 0 and dae.nu else None
    if c is None:
        return opt, None
    lb, ub = opt.bounds_vectors(dae, "u")
    names = {i: f"{name}[{i - sl.start}]" if sl.stop - sl.start > 1 else name
             for name, sl in dae.u_vars.items() for i in range(sl.start, sl.stop)}
    inputs, term = {}, ca.SX(0)
    for i in range(dae.nu):
        s = (scales or {}).get(names[i], max(abs(float(lb[i])), abs(float(ub[i]))))
        if np.isfinite(s) and s > 0:
            inputs[names[i]] = s
            term = term + (dae.u[i] / s) ** 2
    if not inputs:
        return opt, None
    out = _Regularized(opt, weight * c * term)
    return out, Regularization(out, float(weight), c, inputs)


class _Regularized:
    """A declaration as the transcription reads it: its Lagrange term the regularisation, all else the original's
    (the pattern of :class:`~gtmodel.modeling.ocp.elimination.Reduction`'s problem)."""

    def __init__(self, opt: Any, lagrange: ca.SX) -> None:
        self._opt = opt
        self.lagrange = lagrange

    def __getattr__(self, name: str) -> Any:
        return getattr(self._opt, name)


def input_scales(result: Any) -> dict[str, float]:
    """The root mean square over time of a solution's inputs by flat name (the scales of the next refinement pass).

    Parameters
    ----------
    result : OptimizationResult
        A solution (its ``t``, shape ``(T,)``, and ``inputs``: name to an array of shape ``(T,)`` or ``(T, n)``).

    Returns
    -------
    dict of str to float
        ``sqrt(integral(u_j^2 dt) / (t_f - t_0))`` by the trapezoidal rule, where positive and finite (an input at 0
        throughout is left out: scaled by its bound).
    """
    out: dict[str, float] = {}
    t = np.asarray(getattr(result, "t", None) if getattr(result, "t", None) is not None else [], dtype=float).reshape(-1)
    if t.size < 2 or not t[-1] > t[0]:
        return out
    for name, values in (getattr(result, "inputs", None) or {}).items():
        v = np.asarray(values, dtype=float)
        if v.shape[:1] != t.shape:
            continue
        columns = v.reshape(t.size, -1)
        for j in range(columns.shape[1]):
            rms = float(np.sqrt(np.trapezoid(columns[:, j] ** 2, t) / (t[-1] - t[0])))
            if np.isfinite(rms) and rms > 0:
                out[f"{name}[{j}]" if columns.shape[1] > 1 else name] = rms
    return out
