"""Why a loop controller failed its closed-loop check, with numbers.

:func:`excess_predictions`: what the controller's own model predicted where a state went beyond its
declared bound (the model's error on the plant, the measurement's noise, the filter's estimate, or the
step itself); :func:`noise_gain`: how far a tracking law's gain moves its input for a one-sigma
error of the measured states (a gain no input weight lowers: a linearisation in which a weighted
state barely moves under the input). Both are read by :class:`~gtmodel.codegen.check.closed_loop.LoopCheck`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from gtmodel.control.bounds import EXCESS_TOLERANCE, BoundExcess, bound_size
from gtmodel.estimation.closed_loop.controller_loop import LoopSummary

#: A loop-controller file's setup (:class:`gtmodel.problems.loop_file.LoopSetup`), used through its attributes.
LoopSetup = Any

__all__ = ["NOISE_GAIN_NOTE", "excess_predictions", "prediction_text", "noise_gain", "noise_gain_text"]

#: :func:`noise_gain` (the input's one-sigma response over its half range) above which a failure names the gain.
NOISE_GAIN_NOTE = 1.0


def _rollout(F: Any, x: np.ndarray, inputs: np.ndarray) -> np.ndarray:
    """``F`` applied from ``x`` under each row of ``inputs`` in turn: the state after them."""
    x = np.asarray(x, dtype=float).reshape(-1)
    for u in inputs:
        x = np.asarray(F(x, u), dtype=float).reshape(-1)
    return x


def excess_predictions(setup: LoopSetup, run: LoopSummary, bounds: list[BoundExcess], label: str = "controller",
                       x_hat: np.ndarray | None = None) -> list[dict[str, Any]]:
    """What the controller's own model predicted where a state went furthest beyond its declared bound.

    For each state bound of ``bounds`` beyond :data:`~gtmodel.control.bounds.EXCESS_TOLERANCE` at sample ``k``,
    the controller's one-period prediction (the MPC's :attr:`~gtmodel.control.mpc.MPCController.step`, the tracking
    law's ``predict``) is run from the plant's state at ``k - 1 - delay`` (what the controller had measured when it
    chose the input acting before ``k``) through the inputs applied, to ``k``, and again from the state it measured
    (with the check's noise, :attr:`~gtmodel.estimation.closed_loop.controller_loop.LoopSummary.y`). A prediction
    inside the bound says the excess is the model's error on this plant (a margin or a back-off answers it); one
    beyond it from the true state but inside from the measured one, that the measurement's noise carried the step
    there (the step held the bound for what it saw: filter the measurement, or plan with margin); one beyond it from
    the measured state too, that the step's own inputs take its model there (the step did not hold the bound: a
    real-time iteration's one linearisation, soft rows outweighed, or no rows). On a drive-family vertical ball screw
    (``drive0_03``) the MPC's current reached 15.84 A of 14.3 where its model predicted 14.86 A from the plant's state
    two periods before and 13.22 A from the measured one: the model's error 0.98 A, the noise's effect 1.64 A.
    Without a prediction function (a tracking law without delay or state limits), a plant in other states
    than the model's, or an excess before ``1 + delay`` periods: nothing. The prediction is the model's alone: an
    MPC's input-disturbance estimate (``disturbance_gain``) and its back-off are not in it.

    Parameters
    ----------
    setup : LoopSetup
        The file's controller, bounds, names and loop options (``delay``).
    run : LoopSummary
        The closed-loop run under the controller.
    bounds : list of BoundExcess
        Its bounds at the samples (:func:`~gtmodel.codegen.check.closed_loop.plant_bounds`).
    label : str, optional
        The controller's name in the text (``"MPC"``).
    x_hat : numpy.ndarray, optional
        ``(n, nx)`` the state the controller's measurement filter estimated at each sample (its memory,
        :attr:`~gtmodel.control.mpc.MPCController.state_filter`); default None: no filter.

    Returns
    -------
    list of dict
        ``name``, ``time`` [s], ``value`` (the plant's), ``limit``, ``predicted``, ``error`` (value - predicted),
        ``error_relative`` (over the bound's size), ``predicted_percent`` (the prediction beyond the limit, signed as
        :attr:`~gtmodel.control.bounds.BoundExcess.signed`, in %), ``predicted_from_measured`` and ``measured_percent``
        (the same prediction from the state the controller measured, with the check's noise: NaN where the run recorded
        no measurements of every state), with ``x_hat`` also ``predicted_from_estimate`` and ``estimate_percent``
        (from the filter's estimate) and ``estimate_worst`` (``name``, ``estimate``, ``value``, ``sigmas``: the state whose
        estimate was furthest off the plant's, in standard deviations of its noise), ``periods`` (predicted),
        ``inputs_at_bounds`` (input name
        to its last applied value, for the inputs at a bound, within 1e-9 of their range, in any period predicted), ``controller``.
    """
    F = getattr(setup.controller, "step", None)
    F = F if F is not None else getattr(setup.controller, "predict", None)
    x_names, u_names, _ = setup.names
    if F is None or "output" in setup.loop or len(x_names) != run.x.shape[1] or int(F.size1_in(0)) != run.x.shape[1]:
        return []
    delay = int(setup.loop.get("delay", 1))
    t = np.asarray(run.t, dtype=float).reshape(-1)
    lb, ub = np.asarray(run.u_lb, dtype=float), np.asarray(run.u_ub, dtype=float)
    out = []
    for b in bounds:
        if not (b.beyond_tolerance and b.name in x_names and math.isfinite(b.time)):
            continue
        k, j = int(np.argmin(np.abs(t - b.time))), x_names.index(b.name)
        start = k - 1 - delay
        if start < 0 or not np.all(np.isfinite(run.x[start:k + 1])):
            continue
        x = _rollout(F, run.x[start], run.u[start:k])
        y = getattr(run, "y", None)
        seen = float(_rollout(F, y[start], run.u[start:k])[j]) if y is not None and np.shape(y) == np.shape(run.x) else math.nan
        applied = run.u[start:k]
        size, side, extra = bound_size(b.limit, b.lb, b.ub), 1.0 if b.limit == b.ub else -1.0, {}
        if x_hat is not None and len(x_hat) > start and np.all(np.isfinite(x_hat[start])):
            est = float(_rollout(F, x_hat[start], run.u[start:k])[j])
            sigma = np.asarray(setup.controller.state_filter.sigma, dtype=float)
            off = np.abs(x_hat[start] - run.x[start]) / np.where(sigma > 0, sigma, np.inf)
            i = int(np.argmax(off))
            extra = {"predicted_from_estimate": est, "estimate_percent": float(100 * side * (est - b.limit) / size),
                     "estimate_worst": {"name": x_names[i], "estimate": float(x_hat[start][i]), "value": float(run.x[start, i]),
                                        "sigmas": float(off[i])}}
        span = np.where(np.isfinite(ub - lb), ub - lb, 1.0)
        at = {u_names[i] if i < len(u_names) else f"u[{i}]": float(applied[-1, i]) for i in range(applied.shape[1])
              if np.any(np.minimum(np.abs(applied[:, i] - lb[i]), np.abs(applied[:, i] - ub[i])) <= 1e-9 * span[i])}
        out.append({"name": b.name, "time": float(t[k]), "value": float(run.x[k, j]), "limit": float(b.limit), "predicted": float(x[j]),
                    "error": float(run.x[k, j] - x[j]), "error_relative": float((run.x[k, j] - x[j]) / size),
                    "predicted_percent": float(100 * side * (x[j] - b.limit) / size), "periods": k - start,
                    "predicted_from_measured": seen, "measured_percent": float(100 * side * (seen - b.limit) / size),
                    "inputs_at_bounds": at, "controller": label, **extra})
    return out


def prediction_text(e: dict[str, Any]) -> str:
    """One entry of :func:`excess_predictions` as a clause.

    Parameters
    ----------
    e : dict
        An entry of :func:`excess_predictions`.

    Returns
    -------
    str
    """
    saturated = [f"{n} {v:.4g}" for n, v in e["inputs_at_bounds"].items()]
    tolerance = 100 * EXCESS_TOLERANCE
    seen = e.get("predicted_from_measured", math.nan)
    if e["predicted_percent"] <= tolerance:
        cause = ("the model predicted the bound held: the excess is the model's error on this plant (plan with more margin "
                 "below the bound, or the MPC's constraint_backoff)")
    elif math.isfinite(estimated := e.get("predicted_from_estimate", math.nan)) and e["estimate_percent"] <= tolerance:
        worst = e["estimate_worst"]
        cause = (f"from the state its measurement filter estimated its model predicted {estimated:.4g}, within the bound: the "
                 f"estimate's share {e['predicted'] - estimated:+.4g}, the model's error's {e['error']:+.4g} (the estimate most off "
                 f"in {worst['name']}, {worst['estimate']:.4g} for {worst['value']:.4g}, {worst['sigmas']:.3g} times its noise; the "
                 "filter's model is the controller's, not this plant's: plan with more margin below the bound)")
    elif math.isfinite(seen) and e["measured_percent"] <= tolerance:
        cause = (f"from the state it measured (the check's noise) its model predicted {seen:.4g}, within the bound: the "
                 "measurement's noise carried the step beyond it (filter the measurement, weight the noisy states less, or "
                 "plan with more margin below the bound)")
    else:
        cause = ("the inputs it applied take its own model beyond the bound too"
                 + (f" (from the state it measured: {seen:.4g})" if math.isfinite(seen) else "")
                 + ": not the model's error, the step did not hold the bound (an MPC's single real-time iteration or soft "
                 "rows, a law without rows; weight the variable more, or plan with more margin below the bound)")
    return (f"{e['name']} {e['value']:.4g} of {e['limit']:g} at t = {e['time']:.4g} s; the {e['controller']}'s model, run "
            f"{e['periods']} period(s) from the plant's state with the inputs applied, predicted {e['predicted']:.4g} "
            f"({e['predicted_percent']:+.3g} % of the bound beyond it; the model's error {e['error']:+.4g}, "
            f"{100 * e['error_relative']:+.3g} % of the bound): {cause}"
            + (f"; the inputs at their bounds then: {', '.join(saturated)}" if saturated else ""))


def noise_gain(controller: Any, sigma: Any, x_names: list[str], u_names: list[str]) -> dict[str, Any] | None:
    """How far a tracking law's gain moves its input for a one-sigma error of every measured state.

    For each period's gain ``K_k`` (and the held end's ``K_hold``) of a law ``u = u*_k + K_k (x - x*_k)``,
    the input's standard deviation for independent state errors of standard deviation ``sigma``:
    ``s_k,i = sqrt(sum_j (K_k,ij sigma_j)^2)``, against the input's half range. Above
    :data:`NOISE_GAIN_NOTE` the noise alone (before any filter) drives the input across its range: the
    gain of a linearisation in which a weighted state barely moves under the input (a load held by a
    regularised Coulomb friction or inside a backlash at rest: the Riccati gain then tends to
    ``(B^T P B)^-1 B^T P A``, which no input weight lowers). A held-out gear drive's TV-LQR at rest turned
    a 1.2 mrad error of the load position into hundreds of volts, and cycled there with its input weight
    10^5 times larger as with the file's.

    Parameters
    ----------
    controller : object
        The loop controller; read are ``K`` ``(n, nu, nx)`` and, if present, ``K_hold`` ``(nu, nx)``, ``t0``, ``dt``,
        ``u_lb``, ``u_ub`` (a controller without ``K``, such as the MPC: None).
    sigma : array_like
        ``(m,)`` standard deviations of the first ``m <= nx`` states' errors (the check's ``noise``); the others 0.
    x_names, u_names : list of str
        State and input names.

    Returns
    -------
    dict or None
        ``input``, ``value`` (its one-sigma response), ``relative`` (over its half range, NaN without bounds),
        ``time`` [s] (the period's; ``inf``: the held end), ``state`` (the largest contribution), ``share`` (its part of
        ``value``) and ``gain`` (``K_k,ij``), at the largest ``relative`` (``value`` without bounds); None without gains
        or noise.
    """
    K = getattr(controller, "K", None)
    if K is None:
        return None
    K = np.asarray(K, dtype=float)
    hold = getattr(controller, "K_hold", None)
    if hold is not None:
        K = np.concatenate([K, np.asarray(hold, dtype=float).reshape(1, *K.shape[1:])])
    s = np.zeros(K.shape[2])
    given = np.abs(np.asarray(sigma, dtype=float).reshape(-1))[:K.shape[2]]
    s[:given.size] = given
    if K.size == 0 or not np.any(s > 0):
        return None
    parts = np.abs(K) * s
    value = np.sqrt(np.sum(parts ** 2, axis=2))  # (n, nu)
    half = (np.asarray(controller.u_ub, dtype=float) - np.asarray(controller.u_lb, dtype=float)) / 2
    half = np.where(np.isfinite(half) & (half > 0), half, np.nan)
    relative = value / half
    score = np.where(np.isfinite(relative), relative, value)
    k, i = np.unravel_index(int(np.argmax(score)), score.shape)
    j = int(np.argmax(parts[k, i]))
    n = K.shape[0] - (hold is not None)
    return {"input": u_names[i], "value": float(value[k, i]), "relative": float(relative[k, i]),
            "time": float(controller.t0 + k * controller.dt) if k < n else math.inf, "state": x_names[j],
            "share": float(parts[k, i, j] / value[k, i]) if value[k, i] > 0 else 0.0, "gain": float(K[k, i, j])}


def noise_gain_text(g: dict[str, Any] | None) -> str:
    """:func:`noise_gain` as a clause when it is above :data:`NOISE_GAIN_NOTE` (empty otherwise).

    Parameters
    ----------
    g : dict or None
        From :func:`noise_gain`.

    Returns
    -------
    str
    """
    if g is None or not g["relative"] > NOISE_GAIN_NOTE:
        return ""
    when = "after the end (the held gain)" if math.isinf(g["time"]) else f"at t = {g['time']:.4g} s"
    return (f"its gain {when} turns a one-sigma error of the measured states ([check] noise, before any filter) into "
            f"{g['value']:.4g} of {g['input']} ({g['relative']:.3g} times its half range; {100 * g['share']:.0f} % of it from "
            f"{g['state']}, gain {g['gain']:.4g}): a linearisation in which a weighted state barely moves under the input "
            "(a load held by a regularised friction or inside a backlash at rest) gives gains no input weight lowers; "
            "weight that state less there, or take the MPC")
