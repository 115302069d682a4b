"""Where a collocation solution's inputs switch inside an element, and what likely fixes a failed verification.

:func:`switch_elements` (a bang-bang input's jump, which no polynomial represents) serves mesh refinement
(:mod:`gtmodel.modeling.ocp.refinement`) and :func:`verification_remedy`, the remedy a failed verification
(:func:`gtmodel.modeling.ocp.verification.verify`) names.
"""

from __future__ import annotations

import numpy as np

from gtmodel.modeling.ocp.collocation_nlp import collocation_coefficients
from gtmodel.modeling.ocp.result import OptimizationResult, lagrange_basis

__all__ = ["switch_elements", "verification_remedy", "SWITCH_FRACTION", "SPURIOUS_DEVIATION"]

#: An element holds a switch when an input changes by more than this fraction of its
#: range over the horizon between the collocation points of the element.
SWITCH_FRACTION = 0.25
#: Scaled deviation above which a failed verification is taken for a spurious minimum (the
#: hanging chain's: 0.24; the L1 motions on 12 elements: up to 0.06).
SPURIOUS_DEVIATION = 0.1


def switch_elements(result: OptimizationResult) -> dict[int, float]:
    """Elements whose inputs switch inside them, and where, as a fraction of the element.

    An input switches inside element ``k`` when it changes by more than
    :data:`SWITCH_FRACTION` of its range over the horizon between the element's own
    collocation points (a jump between elements is represented exactly: each element has
    its own polynomial). Where the levels before and after are those of the neighbouring
    elements (``a``, ``b``), the switch ``tau_s`` is the one that keeps the input's
    integral over the element: ``a tau_s + b (1 - tau_s) = sum_j B_j u_j`` with the
    quadrature weights ``B_j`` of the scheme (a bang-bang input acts on the model through
    its integral); otherwise where its polynomial crosses the middle of its values.

    Parameters
    ----------
    result : OptimizationResult
        A collocation result.

    Returns
    -------
    dict of int to float
        Element index -> ``tau_s`` in [0.02, 0.98] (the earliest over the inputs that
        switch there).
    """
    col = result.collocation
    if col is None or col.uc.shape[2] == 0:
        return {}
    uc = col.uc  # (N, d, nu)
    N = col.elements
    span = uc.max(axis=(0, 1)) - uc.min(axis=(0, 1))
    span = np.where(span > 0, span, np.inf)
    change = (uc.max(axis=1) - uc.min(axis=1)) / span
    B = collocation_coefficients(col.points, col.scheme)["B"]
    taus = np.linspace(0.0, 1.0, 401)
    basis = lagrange_basis(col.tau_root[1:], taus)
    out: dict[int, float] = {}
    for k, i in zip(*np.nonzero(change > SWITCH_FRACTION)):
        a = uc[k - 1, -1, i] if k > 0 else uc[k, 0, i]
        b = uc[k + 1, 0, i] if k < N - 1 else uc[k, -1, i]
        if abs(a - b) > SWITCH_FRACTION * span[i]:
            tau = (float(B @ uc[k, :, i]) - b) / (a - b)
        else:
            u = basis @ uc[k, :, i]
            mid = 0.5 * (uc[k, :, i].max() + uc[k, :, i].min())
            sgn = np.sign(u - mid)
            cross = np.nonzero(sgn[1:] != sgn[:-1])[0]
            tau = float(taus[cross[0] + 1]) if cross.size else 0.5
        out[int(k)] = min(out.get(int(k), 1.0), float(np.clip(tau, 0.02, 0.98)))
    return out


def verification_remedy(result: OptimizationResult, deviation: float) -> str:
    """What likely fixes a failed verification: the mesh refined, more elements, or (shooting) more intervals.

    Parameters
    ----------
    result : OptimizationResult
        The result whose verification failed.
    deviation : float
        Its largest scaled deviation.

    Returns
    -------
    str
        One sentence.
    """
    col = result.collocation
    if col.shooting is not None:
        return (f"more shooting intervals (transcription.intervals, now {col.elements}) or integrator steps "
                "(transcription.steps), or method = \"collocation\" with refine = true")
    jumps = switch_elements(result)
    breaks = col.breaks()
    if jumps:
        where = ", ".join(f"{breaks[k] + tau * (breaks[k + 1] - breaks[k]):.4g} s" for k, tau in sorted(jumps.items())[:3])
        return (f"an input jumps inside {len(jumps)} element(s) (near t = {where}), which no polynomial represents: "
                "refine = true in [transcription] (solve_refined in Python) moves element boundaries onto the jumps")
    if deviation > SPURIOUS_DEVIATION:
        return (f"a spurious minimum of the NLP is likely (deviation {deviation:.2g}): more [collocation] elements "
                f"(now {col.elements}), a better [initial_guess], or refine = true in [transcription]")
    return (f"the mesh is too coarse where it deviates: refine = true in [transcription] (solve_refined in Python) "
            f"or more [collocation] elements (now {col.elements})")
