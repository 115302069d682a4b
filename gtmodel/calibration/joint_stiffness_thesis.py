"""The joint-stiffness experiment of Cvitanic (2021), section 3.2.1, as the thesis defines it, and its Table 2 judged.

What :mod:`gtmodel.calibration.joint_stiffness` needs to run the thesis' set-up rather than the
generic one:

* :func:`gravity_pulley_wrenches`: the thesis' loads, "directly vertical gravity loadings and
  directional loadings applied via a pulley": FORCES at the tool (no applied moment), here one
  vertical (-z) and two horizontal pulley directions (+x, +y of the base) at each Table 1 pose.
  The directions of the pulley and the load's size are not printed (a decision, named in the
  problem file).
* :func:`three_target_rotation_std`: the rotation noise of a deflection screw measured with
  "three laser tracker targets" (Figure 4) instead of a 6-DOF probe.
* :func:`summarise_table_2`: the seeded comparison of CP, CP with rotations x10 and DPP
  (:func:`~gtmodel.calibration.joint_stiffness.cp_dpp_study`) against the truth and against the
  thesis' Table 2 pattern: DPP below CP on every joint, CP x10 below DPP on the arm joints 1-3,
  and DPP "closer to the truth" (the thesis' reading of CP's scaling issue).
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from gtmodel.errors import InputError

__all__ = ["gravity_pulley_wrenches", "three_target_rotation_std", "summarise_table_2", "THESIS_RATIO_CP_OVER_DPP"]

#: Cvitanic (2021), Table 2: CP over DPP per joint (3.93 / 2.86, ..., 0.17 / 0.14).
THESIS_RATIO_CP_OVER_DPP = tuple(float(a / b) for a, b in zip((3.93, 3.46, 2.77, 1.57, 0.24, 0.17), (2.86, 2.36, 1.67, 0.24, 0.16, 0.14)))


def gravity_pulley_wrenches(n_poses: int, force: float = 1000.0) -> tuple[np.ndarray, np.ndarray]:
    """Force-only load cases of Cvitanic (2021), section 3.2.1: gravity (-z) and a pulley along +x and +y, per pose.

    Parameters
    ----------
    n_poses : int
        Number of poses (>= 1).
    force : float, optional
        Size of every load [N] (> 0, default 1000: a 102 kg mass).

    Returns
    -------
    pose_index : numpy.ndarray, shape (3 n_poses,)
        Index of the pose of each load case.
    F : numpy.ndarray, shape (3 n_poses, 6)
        Wrenches at the TCP, base frame [N, N m] (the moments are zero: a force applied at the tool).

    Raises
    ------
    InputError
        ``n_poses < 1`` or a non-positive / non-finite ``force``.
    """
    if isinstance(n_poses, bool) or int(n_poses) != n_poses or n_poses < 1:
        raise InputError(f"n_poses: expected an integer >= 1, got {n_poses!r}")
    if not np.isfinite(force) or force <= 0:
        raise InputError(f"force: expected a finite number > 0, got {force!r}")
    base = np.zeros((3, 6))
    base[0, 2], base[1, 0], base[2, 1] = -force, force, force
    return np.repeat(np.arange(int(n_poses)), 3), np.tile(base, (int(n_poses), 1))


def three_target_rotation_std(position_std: float, radius: float) -> float:
    """Rotation noise per axis of a rigid-body fit to three tracker targets [rad].

    Three targets on a circle of ``radius`` (an equilateral triangle), each measured with
    ``position_std`` per coordinate: the least-squares rotation has the covariance
    ``sigma_p^2 (sum_i [r_i]x^T [r_i]x)^-1``, i.e. ``sigma_p / (radius sqrt(3/2))`` about the two
    in-plane axes and ``sigma_p / (radius sqrt(3))`` about the normal; the larger is returned.

    Parameters
    ----------
    position_std : float
        Tracker noise per coordinate [m] (>= 0).
    radius : float
        Distance of each target from the targets' centroid [m] (> 0).

    Returns
    -------
    float
        Standard deviation per axis [rad].

    Raises
    ------
    InputError
        A negative ``position_std`` or a non-positive ``radius``.
    """
    if not (np.isfinite(position_std) and position_std >= 0):
        raise InputError(f"position_std: expected a finite number >= 0, got {position_std!r}")
    if not (np.isfinite(radius) and radius > 0):
        raise InputError(f"radius: expected a finite number > 0, got {radius!r}")
    return float(position_std / (radius * math.sqrt(1.5)))


def summarise_table_2(ratios: Mapping[str, Any], cp: str, cp_scaled: str, dpp: str = "DPP") -> dict[str, Any]:
    """CP, CP x10 and DPP over seeds against the truth and against Table 2's pattern (Cvitanic (2021), Table 2).

    Parameters
    ----------
    ratios : Mapping of str to array_like, shape (seeds, 6)
        ``k / k_true`` per seed and joint, per method (:func:`~gtmodel.calibration.joint_stiffness.cp_dpp_study`).
    cp, cp_scaled, dpp : str
        The keys of CP, CP with the rotations scaled and DPP in ``ratios``.

    Returns
    -------
    dict
        ``seeds``; per method ``median_ratio`` (6), ``mean_abs_log_ratio`` (the distance from the
        truth: mean over seeds and joints of ``|ln(k / k_true)|``); ``dpp_closer_fraction`` (seeds
        where DPP's distance is below CP's); ``median_cp_over_dpp`` (6) beside
        ``thesis_cp_over_dpp``; the thesis' pattern on the medians: ``dpp_below_cp_every_joint``,
        ``cp_scaled_below_dpp_joints_1_3``, ``dpp_closer_to_truth`` (its mean distance below CP's).

    Raises
    ------
    InputError
        A missing key or ratios of another shape than (seeds, 6).
    """
    arr = {}
    for key in (cp, cp_scaled, dpp):
        if key not in ratios:
            raise InputError(f"ratios: expected a {key!r} entry, got {', '.join(ratios)}")
        a = np.asarray(ratios[key], float)
        if a.ndim != 2 or a.shape[1] != 6:
            raise InputError(f"ratios[{key!r}]: expected shape (seeds, 6), got {a.shape}")
        arr[key] = a
    with np.errstate(divide="ignore", invalid="ignore"):
        dist = {k: np.mean(np.abs(np.log(np.abs(a))), axis=1) for k, a in arr.items()}  # per seed
    med = {k: np.median(a, axis=0) for k, a in arr.items()}
    out: dict[str, Any] = {"seeds": int(arr[dpp].shape[0])}
    for k in arr:
        out[k] = {"median_ratio": med[k].tolist(), "mean_abs_log_ratio": float(np.mean(dist[k]))}
    out["dpp_closer_fraction"] = float(np.mean(dist[dpp] < dist[cp]))
    out["median_cp_over_dpp"] = (med[cp] / med[dpp]).tolist()
    out["thesis_cp_over_dpp"] = list(THESIS_RATIO_CP_OVER_DPP)
    out["dpp_below_cp_every_joint"] = bool(np.all(med[dpp] < med[cp]))
    out["cp_scaled_below_dpp_joints_1_3"] = bool(np.all(med[cp_scaled][:3] < med[dpp][:3]))
    out["dpp_closer_to_truth"] = bool(out[dpp]["mean_abs_log_ratio"] < out[cp]["mean_abs_log_ratio"])
    return out
