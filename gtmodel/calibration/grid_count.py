"""Grid sizes counted before a grid is built (a mistyped step is a load-time error, not minutes later).

:func:`axis_count` counts the points of one axis, :func:`grid_candidates` the poses a
synthetic calibration grid of a 3-link, six-link or F1 truth would examine (Dressler
(2012), ch. 5.6), so a step giving too many is refused up front.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from gtmodel.robots import GantryTau3Kinematics

__all__ = ["axis_count", "grid_candidates", "f1_position_box"]


def axis_count(lo: float, hi: float, step: float) -> float:
    """Points of ``numpy.arange(lo, hi + step / 2, step)``, counted without building it.

    For bounding grid sizes up front (a typo of a grid step must be a load-time error,
    not minutes and gigabytes later). Python floats: an overflow is ``inf``, no warning.

    Parameters
    ----------
    lo, hi : float
        The range.
    step : float
        The step (> 0).

    Returns
    -------
    float
        The count (``inf`` if it overflows).
    """
    n = (float(hi) - float(lo) + float(step) / 2) / float(step)
    return max(0.0, float(math.ceil(n))) if math.isfinite(n) else math.inf


def grid_candidates(truth: Any, tkind: str, step: float, step_deg: float = 10.0, rotary_travel_deg: Any = None,
                    rotary_step_deg: float = 10.0) -> tuple[float, float]:
    """Grid points a synthetic grid would examine: ``(total, orientation factor)``.

    - 3-link: the TCP grid over the workspace box (:meth:`GantryTau3Kinematics.workspace_bounds`);
    - six-link: the ``q`` grid over the cart travel (and the rotary ranges);
    - F1: positions in the box within reach of every guideway segment (an upper bound of
      the positions the F1's own 6-D grid examines) times the orientations within the
      reorientation range.

    Parameters
    ----------
    truth : ClosureModel
        The true robot (3-link, six-link or F1 closure model).
    tkind : str
        ``"three_link"``, ``"six_link"`` or ``"f1"``.
    step : float
        Grid step of positions (3-link, F1) or actuators (six-link) [m].
    step_deg : float, optional
        Orientation step of the F1's 6-D grid [deg].
    rotary_travel_deg : array_like, shape (n_q - 3, 2), optional
        ``[min, max]`` of each rotary actuator of a six-link model [deg].
    rotary_step_deg : float, optional
        Grid step of the rotary actuators [deg].

    Returns
    -------
    total : float
        The grid points (``inf`` if it overflows; 0 for a model without limits).
    orientation : float
        The factor of the total due to orientations or rotary actuators.
    """
    if tkind == "three_link":
        if truth.robot is None:
            return 0.0, 1.0  # no limits: grid_poses says so
        kin = GantryTau3Kinematics(dataclasses.replace(truth.robot, kinematics=truth.kinematics))
        return math.prod(axis_count(lo, hi, step) for lo, hi in kin.workspace_bounds()), 1.0
    if tkind == "six_link":
        lim = getattr(truth, "limits", None)
        if lim is None:
            return 0.0, 1.0
        n = math.prod(axis_count(lo, hi, step) for lo, hi in np.asarray(lim.cart_travel, dtype=float))
        rot = 1.0
        if truth.n_q > 3 and rotary_travel_deg is not None:
            rot = math.prod(axis_count(lo, hi, rotary_step_deg) for lo, hi in rotary_travel_deg)
        return n * rot, rot
    lim = truth.limits
    if lim is None:
        return 0.0, 1.0
    lo, hi = f1_position_box(truth, lim)
    spans = [(float(h) - float(l)) / float(step) for l, h in zip(lo, hi)]
    positions = math.prod(math.floor(x) + 1.0 if math.isfinite(x) else math.inf for x in spans)
    ratio = [float(r) / float(step_deg) for r in np.degrees(lim.reorientation_range)]
    rot = math.prod(2.0 * math.floor(x + 1e-9) + 1.0 if math.isfinite(x) else math.inf for x in ratio)
    return positions * rot, rot


def f1_position_box(truth: Any, lim: Any) -> tuple[np.ndarray, np.ndarray]:
    """A box containing every F1 TCP position whose joints ``B_ij`` are within reach.

    Per link ``ij``: the cart's travel segment ``A0_i + [q_min, q_max] v_i`` grown by
    ``L_ij`` (plus the joint-plate offset ``|Abj_ij|`` on arms 2 and 3 and ``|r3|`` on arm
    3) and ``|B0_ij|``; the box is the intersection over the links (the box the F1's own
    workspace grid fills, from the parameter names of Dressler (2012), Table 5.4).

    Parameters
    ----------
    truth : F1 closure model
        The robot (its parameter names and ``links``).
    lim : limits
        Its limits (``cart_travel``, shape (3, 2) [m]).

    Returns
    -------
    lo, hi : numpy.ndarray, shape (3,)
        Corners of the box [m].
    """
    p = dict(zip(truth.parameter_names(), truth.parameter_vector()))

    def vec(name: str) -> np.ndarray:
        return np.array([p[f"{name}_{c}"] for c in "xyz"])

    lo, hi = np.full(3, -np.inf), np.full(3, np.inf)
    for arm, links in enumerate(truth.links):
        seg = np.array([vec(f"A0_{arm + 1}") + lim.cart_travel[arm, k] * vec(f"v{arm + 1}") for k in range(2)])
        for n in links:
            reach = p[f"L_{n}"] + (np.linalg.norm(vec(f"Abj_{n}")) if arm > 0 else 0.0) + (np.linalg.norm(vec("r3")) if arm == 2 else 0.0)
            grow = reach + np.linalg.norm(vec(f"B0_{n}"))
            lo, hi = np.maximum(lo, seg.min(axis=0) - grow), np.minimum(hi, seg.max(axis=0) + grow)
    return lo, hi
