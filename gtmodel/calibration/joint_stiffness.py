"""Joint-stiffness calibration of a serial arm: complete pose (CP) and decoupled partial pose (DPP).

Cvitanic (2021), section 1. Measurements are pairs of a TCP wrench ``F = [f; m]`` (base
frame, N and N m) and the deflection screw ``dX = [dp; dphi]`` it causes (m and rad) at
known joint angles ``theta``. The joint-spring model, eq. (3),
``dX = J K_theta^-1 J^T F``, is linear in the compliances ``c_i = 1/k_i``::

    dX = A(theta, F) c,    A = J diag(J^T F)        (SerialArm.compliance_regressor)

so the nonlinear least-squares problem in ``k`` becomes a linear one in ``c``, solved
exactly (``numpy.linalg.lstsq``, or ``scipy.optimize.lsq_linear`` with ``c >= 0`` when
``bounds="positive"``).

* **CP** (complete pose): all six deflection components of every measurement, the rotation
  rows multiplied by ``rotation_weight`` (default 1: rotations in rad against translations
  in m; the thesis' "x10" is ``rotation_weight=10``). The weighting is part of the problem
  statement: it changes the result (Table 2).
* **DPP** (decoupled partial pose): step 1, eq. (4), fits joints 1-3 from the wrist-centre
  displacement ``dp_wc = dp - dphi x (p_TCP - p_wc)`` (axes 4-6 pass through the wrist
  centre, so it does not move with joints 4-6); step 2, eq. (5), fits joints 4-6 from the
  rotation left after subtracting joints 1-3: ``dphi - sum_{i<=3} z_i c_i tau_i``.

Synthetic data (:func:`synthetic_deflections`) come from the same model with stated
noise: laser-tracker position noise ``sigma_p = a + b * distance`` per coordinate and
measurement (Leica AT960 MPE 15 um + 6 um/m, Table 2 notes), rotation noise, optional
force-measurement noise (errors in variables), an optional unmodelled translational
compliance in series at the TCP (e.g. the spindle/tool, 231 MN/m), an optional unmodelled
rotation-only compliance, and optionally the complementary stiffness of eq. (2) in the truth.

Which mechanism reproduces Table 2's "unscaled CP overestimates the stiffness, x10 lowers
it"? Seeded studies (:func:`cp_dpp_study`, tests/calibration/test_joint_stiffness.py,
notebook 07): only the rotation-only compliance, with an SI (m, rad) residual, on joints
1-2 (:func:`table_2_scenario`); DPP is then biased even more, so the thesis' DPP < CP is
not reproduced. Noise, force noise, the complementary stiffness and the residual's units
alone do not produce the finding.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.optimize

from gtmodel.errors import InputError
from gtmodel.robots.serial import SerialArm
from gtmodel.status import Status, StatusResult

__all__ = [
    "TABLE_1_POSES_DEG",
    "TABLE_2_K_THETA",
    "ROTATION_WEIGHT_FOR_UNITS",
    "TABLE_2_SCENARIO_ROTATION_ONLY_STIFFNESS",
    "DPP_STEP2",
    "DeflectionData",
    "DeflectionNoise",
    "JointStiffnessResult",
    "axis_wrenches",
    "synthetic_deflections",
    "table_2_scenario",
    "calibrate_cp",
    "calibrate_dpp",
    "cp_dpp_study",
]

_log = logging.getLogger("gtmodel")

#: Cvitanic (2021), Table 1: the ten calibration poses of the KR 500-3 [deg] (rows: poses).
TABLE_1_POSES_DEG = np.array(
    [
        [19.67, -52.14, 117.9, 11.86, -66.08, -4.84],
        [26.35, -32.54, 123.49, -8.99, -90.81, -0.15],
        [58.28, -10.5, 105.98, 42.39, -115.04, -2.57],
        [44.71, -70.81, 58.16, 138.51, -41.63, -125.84],
        [-23.13, -85.41, 80.84, 70.31, 83.63, -71.78],
        [2.39, -34.82, 69.97, 115.13, 72.1, 176.98],
        [25.21, -55.7, 130.03, 169.88, 72.17, -179.78],
        [42.99, -40.39, 97.42, -177.38, 72.1, -179.8],
        [42.99, -57.91, 110.04, -155.79, 51.1, -179.83],
        [28.12, -55.4, 84.06, -167.6, 27.07, -179.85],
    ]
)

#: Cvitanic (2021), Table 2: identified joint stiffnesses of the KR 500-3 [N m/rad].
TABLE_2_K_THETA = {
    "CP": np.array([3.93, 3.46, 2.77, 1.57, 0.24, 0.17]) * 1e6,
    "DPP": np.array([2.86, 2.36, 1.67, 0.24, 0.16, 0.14]) * 1e6,
    "CP_rotations_scaled_x10": np.array([2.13, 1.59, 1.12, 1.89, 0.26, 0.17]) * 1e6,
}


#: The SI ``rotation_weight`` equivalent to a CP residual written in other units: a residual
#: with translations in mm and rotations in rad weighs rotations 1000 times less than one in
#: m and rad (the overall scale of a least-squares residual does not change its minimiser).
ROTATION_WEIGHT_FOR_UNITS = {"m_rad": 1.0, "mm_mrad": 1.0, "mm_rad": 1e-3, "mm_deg": math.degrees(1.0) / 1e3}

#: Unmodelled rotation-only stiffness of the Table 2 scenario (:func:`table_2_scenario`)
#: [N m/rad]: the mechanism that reproduces "unscaled CP overestimates joints 1-2, x10 lowers
#: them" in the seeded studies of tests/calibration/test_joint_stiffness.py. A hypothesis,
#: not a thesis figure.
TABLE_2_SCENARIO_ROTATION_ONLY_STIFFNESS = 0.3e6


#: The data of DPP's step 2 (:func:`calibrate_dpp`): the rotation, or the TCP translation as eq. (5) is written.
DPP_STEP2 = ("rotation", "tcp_translation")


def _rows(fn: Any, *args: np.ndarray) -> list[np.ndarray]:
    """Evaluate a CasADi function of the arm's graph row-wise (``Function.map``), outputs stacked as (N, r, c)."""
    n = args[0].shape[0]
    out = fn.map(n)(*[a.T for a in args])
    out = out if isinstance(out, (list, tuple)) else [out]
    return [np.array(o).reshape(o.shape[0], n, -1).transpose(1, 0, 2) for o in out]


def _array(value: Any, shape: tuple[int | None, ...], name: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected numbers of shape {shape}, got {value!r}") from None
    if arr.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, arr.shape)):
        want = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ")"
        raise InputError(f"{name}: expected shape {want}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        idx = np.argwhere(~np.isfinite(arr))[0]
        raise InputError(f"{name}: non-finite value at index {tuple(int(i) for i in idx)}")
    return arr


@dataclass(frozen=True)
class DeflectionData:
    """Measured (or synthetic) static deflections under known wrenches.

    Parameters
    ----------
    theta : numpy.ndarray, shape (N, 6)
        Joint angles of each measurement [rad].
    F : numpy.ndarray, shape (N, 6)
        Wrench at the TCP, base frame: force [N], moment [N m].
    dX : numpy.ndarray, shape (N, 6)
        Deflection screw: translation [m], rotation vector [rad].
    description : str, optional
        Where the data come from (synthetic: the truth and the noise).

    Raises
    ------
    InputError
        Wrong shapes, different row counts, non-finite values or fewer than 2 rows.
    """

    theta: np.ndarray
    F: np.ndarray
    dX: np.ndarray
    description: str = ""

    def __post_init__(self) -> None:
        th = _array(self.theta, (None, 6), "theta")
        F = _array(self.F, (None, 6), "F")
        dX = _array(self.dX, (None, 6), "dX")
        if not th.shape[0] == F.shape[0] == dX.shape[0]:
            raise InputError(f"theta, F, dX: expected the same number of rows, got {th.shape[0]}, {F.shape[0]}, {dX.shape[0]}")
        if th.shape[0] < 2:
            raise InputError(f"theta: expected at least 2 measurements, got {th.shape[0]}")
        object.__setattr__(self, "theta", th)
        object.__setattr__(self, "F", F)
        object.__setattr__(self, "dX", dX)

    @property
    def n(self) -> int:
        """Number of measurements."""
        return int(self.theta.shape[0])


@dataclass(frozen=True)
class DeflectionNoise:
    """Noise of a synthetic deflection measurement (each deflection = loaded - unloaded pose).

    Parameters
    ----------
    position_std : float, optional
        Constant part of the position noise per coordinate and measurement [m]
        (default 15e-6, the AT960 MPE of Table 2's notes used as a standard deviation).
    position_std_per_m : float, optional
        Distance-proportional part [m per m of tracker-to-TCP distance] (default 6e-6).
    rotation_std : float, optional
        Rotation noise per axis and measurement [rad] (default 2.6e-4 = 0.015 deg, Table 7
        baseline orientation noise).
    force_relative_std : float, optional
        Relative noise of the measured wrench (errors in variables; the calibration uses
        the noisy wrench) [-] (default 0).
    tracker_position : tuple of float, optional
        Tracker position in the base frame [m] (default (4, 0, 1)).
    """

    position_std: float = 15e-6
    position_std_per_m: float = 6e-6
    rotation_std: float = 2.6e-4
    force_relative_std: float = 0.0
    tracker_position: tuple[float, float, float] = (4.0, 0.0, 1.0)

    def __post_init__(self) -> None:
        for name in ("position_std", "position_std_per_m", "rotation_std", "force_relative_std"):
            v = getattr(self, name)
            if not np.isfinite(v) or v < 0:
                raise InputError(f"DeflectionNoise.{name}: expected a finite number >= 0, got {v!r}")
        _array(self.tracker_position, (3,), "DeflectionNoise.tracker_position")


@dataclass
class JointStiffnessResult(StatusResult):
    """Result of a joint-stiffness calibration (status, never None).

    Parameters
    ----------
    status : Status
        ``optimal`` (``success``: the regressor has full rank and every compliance is
        positive), or ``error`` (rank-deficient regressor or a non-positive compliance,
        see ``message``).
    message : str
        What happened, naming the offending joints.
    method : str
        ``"CP"`` or ``"DPP"``.
    k_theta : numpy.ndarray, shape (6,)
        Identified joint stiffnesses [N m/rad] (``inf`` where the compliance is <= 0).
    compliance : numpy.ndarray, shape (6,)
        Identified compliances ``1/k`` [rad/(N m)].
    std_compliance : numpy.ndarray, shape (6,)
        Standard deviations of the compliances [rad/(N m)]: sandwich covariance with one
        residual variance for the translation rows and one for the rotation rows (valid
        for any rotation weight).
    std_k_theta : numpy.ndarray, shape (6,)
        First-order standard deviations of ``k`` (``std_c / c^2``) [N m/rad].
    rotation_weight : float
        Factor on the rotation residual rows (CP; 1 for DPP).
    residuals : numpy.ndarray, shape (N, 6)
        Unweighted model - measurement deflection residuals [m, rad].
    rms_translation : float
        RMS of the translation residuals [m].
    rms_rotation : float
        RMS of the rotation residuals [rad].
    condition : float
        Condition number of the (weighted) regressor(s) (worst step for DPP).
    n_measurements : int
        Number of measurements used.
    extra : dict, optional
        Method-specific details (DPP: ``condition_step1``, ``condition_step2``).
    """

    method: str
    k_theta: np.ndarray
    compliance: np.ndarray
    std_compliance: np.ndarray
    std_k_theta: np.ndarray
    rotation_weight: float
    residuals: np.ndarray
    rms_translation: float
    rms_rotation: float
    condition: float
    n_measurements: int
    extra: dict[str, Any] = field(default_factory=dict)


def axis_wrenches(n_poses: int, force: float = 1000.0, moment: float = 200.0) -> tuple[np.ndarray, np.ndarray]:
    """Standard load cases: forces along +x, +y, -z and moments about x, y, z of the base at each pose.

    Six load cases per pose. The moments are needed to excite joint 6: a pure force at
    a TCP on the axis of joint 6 exerts no torque on it.

    Parameters
    ----------
    n_poses : int
        Number of poses (>= 1).
    force : float, optional
        Magnitude of the applied forces [N] (> 0, default 1000).
    moment : float, optional
        Magnitude of the applied moments [N m] (> 0, default 200).

    Returns
    -------
    pose_index : numpy.ndarray, shape (6 n_poses,)
        Index of the pose of each load case.
    F : numpy.ndarray, shape (6 n_poses, 6)
        Wrenches [N, N m].

    Raises
    ------
    InputError
        ``n_poses < 1`` or a non-positive / non-finite ``force`` or ``moment``.
    """
    if isinstance(n_poses, bool) or int(n_poses) != n_poses or n_poses < 1:
        raise InputError(f"n_poses: expected an integer >= 1, got {n_poses!r}")
    for name, v in (("force", force), ("moment", moment)):
        if not np.isfinite(v) or v <= 0:
            raise InputError(f"{name}: expected a finite number > 0, got {v!r}")
    base = np.diag([force, force, -force, moment, moment, moment]).astype(float)
    idx = np.repeat(np.arange(int(n_poses)), 6)
    return idx, np.tile(base, (int(n_poses), 1))


def synthetic_deflections(
    arm: SerialArm,
    theta: Any,
    F: Any,
    k_theta: Any,
    noise: DeflectionNoise | None = None,
    series_translational_stiffness: float | None = None,
    rotation_only_stiffness: float | None = None,
    seed: int = 0,
    complementary: bool = False,
) -> DeflectionData:
    """Synthetic (F, dX) measurements of the joint-spring model, Cvitanic (2021), eq. (3).

    ``dX_true = J K_theta^-1 J^T F (+ f / k_s on the translation if a series stiffness k_s
    is given)``, or ``J (K_theta - K_c)^-1 J^T F`` with the complementary stiffness of eq.
    (2) when ``complementary`` is set; the deflection is the difference of a loaded and an unloaded pose
    measurement, each with independent position noise ``position_std + position_std_per_m
    * |p_TCP - p_tracker|`` per coordinate and rotation noise ``rotation_std`` per axis
    (hence a factor sqrt(2) on the deflection). The returned wrench carries the relative
    force noise (the calibration sees the measured, not the applied, wrench).

    Parameters
    ----------
    arm : SerialArm
        The arm (its Jacobian and FK are used).
    theta : array_like, shape (N, 6)
        Joint angles of each measurement [rad] (degrees only at the user boundary).
    F : array_like, shape (N, 6)
        Applied wrenches [N, N m].
    k_theta : array_like, shape (6,)
        True joint stiffnesses [N m/rad], positive.
    noise : DeflectionNoise, optional
        Noise model (default :class:`DeflectionNoise` defaults). ``DeflectionNoise(0, 0, 0)``
        gives exact data.
    series_translational_stiffness : float, optional
        Unmodelled translational stiffness in series at the TCP [N/m] (e.g. 231e6 for the
        spindle of Table 2's notes); default none.
    rotation_only_stiffness : float, optional
        Unmodelled isotropic rotational stiffness [N m/rad] seen by the orientation
        measurement only: ``dphi += (m + (p_TCP - p_wc) x f) / k_r`` (moment about the
        wrist centre) without a TCP translation, e.g. a compliant 6-DOF probe mount or a
        tool holder tilting about the tool tip. A hypothesis for the CP/DPP gap of Table 2,
        not a thesis figure; default none.
    seed : int, optional
        Seed of ``numpy.random.default_rng``.
    complementary : bool, optional
        Generate the truth with the complementary stiffness ``K_c = d(J^T F)/d theta`` of
        eq. (2), which the calibration model (3) neglects (default False).

    Returns
    -------
    DeflectionData
        Measured wrenches and deflections.

    Raises
    ------
    InputError
        Wrong shapes, non-finite values, non-positive stiffness.
    """
    th = _array(theta, (None, 6), "theta")
    Fa = _array(F, (None, 6), "F")
    if th.shape[0] != Fa.shape[0]:
        raise InputError(f"theta, F: expected the same number of rows, got {th.shape[0]} and {Fa.shape[0]}")
    k = _array(k_theta, (6,), "k_theta")
    if np.any(k <= 0):
        j = int(np.flatnonzero(k <= 0)[0])
        raise InputError(f"k_theta: expected positive stiffnesses, joint {j + 1} has {float(k[j])!r}")
    if series_translational_stiffness is not None and (not np.isfinite(series_translational_stiffness) or series_translational_stiffness <= 0):
        raise InputError(f"series_translational_stiffness: expected a finite number > 0, got {series_translational_stiffness!r}")
    if rotation_only_stiffness is not None and (not np.isfinite(rotation_only_stiffness) or rotation_only_stiffness <= 0):
        raise InputError(f"rotation_only_stiffness: expected a finite number > 0, got {rotation_only_stiffness!r}")
    noise = DeflectionNoise() if noise is None else noise
    rng = np.random.default_rng(seed)
    fn = arm.loaded_deflection_function if complementary else arm.deflection_function
    dX = _rows(fn, th, Fa, np.tile(k, (th.shape[0], 1)))[0][:, :, 0]
    if series_translational_stiffness is not None:
        dX[:, :3] += Fa[:, :3] / series_translational_stiffness
    p = _rows(arm.fk_function, th)[0][:, :3, 3]
    if rotation_only_stiffness is not None:
        r = p - _rows(arm.wrist_function, th)[0][:, :, 0]
        dX[:, 3:] += (Fa[:, 3:] + np.cross(r, Fa[:, :3])) / rotation_only_stiffness
    dist = np.linalg.norm(p - np.asarray(noise.tracker_position), axis=1)
    sig_p = noise.position_std + noise.position_std_per_m * dist
    dX[:, :3] += np.sqrt(2.0) * sig_p[:, None] * rng.standard_normal((th.shape[0], 3))
    dX[:, 3:] += np.sqrt(2.0) * noise.rotation_std * rng.standard_normal((th.shape[0], 3))
    Fm = Fa * (1.0 + noise.force_relative_std * rng.standard_normal(Fa.shape))
    desc = (
        f"synthetic: k_theta = {np.round(k / 1e6, 4).tolist()} MN m/rad, {noise}, "
        f"series stiffness {series_translational_stiffness} N/m, rotation-only stiffness "
        f"{rotation_only_stiffness} N m/rad, complementary stiffness {'kept' if complementary else 'none'}, seed {seed}"
    )
    return DeflectionData(th, Fm, dX, desc)


def table_2_scenario(
    arm: SerialArm,
    seed: int = 0,
    rotation_only_stiffness: float | None = TABLE_2_SCENARIO_ROTATION_ONLY_STIFFNESS,
    noise: DeflectionNoise | None = None,
    force: float = 1000.0,
    moment: float = 200.0,
    complementary: bool = False,
) -> DeflectionData:
    """Synthetic CP/DPP experiment of Table 2: Table 1 poses, Table 2 DPP truth, a named mechanism.

    Cvitanic (2021), Tables 1-2. At each of the ten Table 1 poses the six load cases of
    :func:`axis_wrenches`; true joint stiffnesses = Table 2 DPP values; laser-tracker noise
    of :class:`DeflectionNoise`; and, by default, the unmodelled rotation-only compliance
    :data:`TABLE_2_SCENARIO_ROTATION_ONLY_STIFFNESS` (extra rotation ``(m + r x f) / k_r``
    about the wrist centre without a TCP translation). That mechanism makes the unscaled CP
    (``rotation_weight=1``, SI residual) overestimate joints 1-2 and the x10 scaling lower
    them, as from Table 2's CP to its CP x10 column; it does not reproduce DPP < CP (DPP is
    biased further up). Noise, the complementary stiffness, force noise and residual units
    alone do not reproduce the finding (see tests/calibration/test_joint_stiffness.py and
    notebook 07).

    Parameters
    ----------
    arm : SerialArm
        The arm generating the data.
    seed : int, optional
        Seed of the measurement noise.
    rotation_only_stiffness : float or None, optional
        Unmodelled rotation-only stiffness [N m/rad] (None: the joint-spring model is exact).
    noise : DeflectionNoise, optional
        Measurement noise (default :class:`DeflectionNoise` defaults).
    force : float, optional
        Applied force per load case [N] (> 0, default 1000).
    moment : float, optional
        Applied moment per load case [N m] (> 0, default 200).
    complementary : bool, optional
        Keep the complementary stiffness of eq. (2) in the truth (default False).

    Returns
    -------
    DeflectionData
        60 measurements (10 poses x 6 load cases).

    Raises
    ------
    InputError
        Non-positive ``force``, ``moment`` or ``rotation_only_stiffness``.
    """
    idx, F = axis_wrenches(len(TABLE_1_POSES_DEG), force, moment)
    theta = np.radians(TABLE_1_POSES_DEG)[idx]
    return synthetic_deflections(
        arm, theta, F, TABLE_2_K_THETA["DPP"], noise=noise, rotation_only_stiffness=rotation_only_stiffness, seed=seed, complementary=complementary
    )


def _solve(A: np.ndarray, y: np.ndarray, bounds: str, what: str, groups: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, float, list[str]]:
    """Weighted linear LS; returns c, std, condition, problems.

    The covariance is the sandwich ``(A^T A)^-1 A^T S A (A^T A)^-1`` with one residual
    variance per row group (translation rows, rotation rows), so the standard deviations
    stay valid when the weighting does not equalise the noise of the groups.
    """
    problems = []
    cond = float(np.linalg.cond(A))
    rank = np.linalg.matrix_rank(A)
    if rank < A.shape[1]:
        problems.append(f"{what}: regressor rank {rank} < {A.shape[1]} (joints not excited by these poses/wrenches)")
    if bounds == "positive":
        c = scipy.optimize.lsq_linear(A, y, bounds=(0.0, np.inf), method="bvls").x
    else:
        c = np.linalg.lstsq(A, y, rcond=None)[0]
    g = np.zeros(A.shape[0], dtype=int) if groups is None else groups
    r = A @ c - y
    dof_total = A.shape[0] - A.shape[1]
    var = np.empty(A.shape[0])
    for label in np.unique(g):
        rows = g == label
        dof = rows.sum() * dof_total / A.shape[0]  # parameters shared out in proportion to the rows
        var[rows] = float(r[rows] @ r[rows]) / dof if dof > 0 else np.inf
    try:
        AtA_inv = np.linalg.inv(A.T @ A)
        cov = AtA_inv @ (A.T * var) @ A @ AtA_inv
        std = np.sqrt(np.clip(np.diag(cov), 0, None))
    except np.linalg.LinAlgError:
        std = np.full(A.shape[1], np.inf)
    if not np.all(np.isfinite(std)):
        std = np.where(np.isfinite(std), std, np.inf)
    return c, std, cond, problems


def _result(method: str, c: np.ndarray, std: np.ndarray, cond: float, problems: list[str], arm: SerialArm, data: DeflectionData, w: float, extra: dict) -> JointStiffnessResult:
    for j in np.flatnonzero(c <= 0):
        problems.append(f"joint {j + 1}: compliance {c[j]:.3g} rad/(N m) <= 0 (not identifiable from these data; try bounds='positive' or more/other poses)")
    with np.errstate(divide="ignore"):
        k = np.where(c > 0, 1.0 / np.where(c > 0, c, 1.0), np.inf)
        std_k = np.where(c > 0, std / np.where(c > 0, c, 1.0) ** 2, np.inf)
    pred = _rows(arm.regressor_function, data.theta, data.F)[0] @ c
    res = pred - data.dX
    ok = not problems
    msg = "; ".join(problems) if problems else f"{method}: linear least squares in the compliances solved exactly"
    if problems:
        _log.warning("joint stiffness %s: %s", method, msg)
    return JointStiffnessResult(
        status=Status.OPTIMAL if ok else Status.ERROR,
        message=msg,
        method=method,
        k_theta=k,
        compliance=c,
        std_compliance=std,
        std_k_theta=std_k,
        rotation_weight=float(w),
        residuals=res,
        rms_translation=float(np.sqrt(np.mean(res[:, :3] ** 2))),
        rms_rotation=float(np.sqrt(np.mean(res[:, 3:] ** 2))),
        condition=cond,
        n_measurements=data.n,
        extra=extra,
    )


def _check_common(arm: Any, data: Any, bounds: str) -> None:
    if not isinstance(arm, SerialArm):
        raise InputError(f"arm: expected a SerialArm, got {type(arm).__name__}")
    if not isinstance(data, DeflectionData):
        raise InputError(f"data: expected a DeflectionData, got {type(data).__name__}")
    if bounds not in ("none", "positive"):
        raise InputError(f"bounds: expected 'none' or 'positive', got {bounds!r}")


def calibrate_cp(arm: SerialArm, data: DeflectionData, rotation_weight: float = 1.0, bounds: str = "none") -> JointStiffnessResult:
    """Complete-pose (CP) joint-stiffness calibration, Cvitanic (2021), eq. (3) and Table 2.

    Minimises ``sum_j || W (A(theta_j, F_j) c - dX_j) ||^2`` over the compliances
    ``c = 1/k`` with ``W = diag(1, 1, 1, w, w, w)``: rotation residuals [rad] are
    multiplied by ``w = rotation_weight`` against translation residuals [m]. The thesis
    used ``w = 1`` (CP) and ``w = 10`` (CP, rotations scaled x10). Statistically the
    efficient choice is the inverse-noise weight ``w = sigma_translation / sigma_rotation``
    [m/rad] (about 0.1 for a laser tracker with 15 um + 6 um/m and 0.015 deg): weighting
    rotations up amplifies their noise.

    Parameters
    ----------
    arm : SerialArm
        Nominal arm (Jacobian source).
    data : DeflectionData
        Measured wrenches and deflections.
    rotation_weight : float, optional
        Factor on the rotation residual rows [m/rad] (> 0, default 1).
    bounds : {"none", "positive"}, optional
        ``"positive"`` constrains ``c >= 0`` (``scipy.optimize.lsq_linear``).

    Returns
    -------
    JointStiffnessResult
        Identified stiffnesses, standard deviations and status.

    Raises
    ------
    InputError
        Wrong argument types or a non-positive / non-finite ``rotation_weight``.
    """
    _check_common(arm, data, bounds)
    if not np.isfinite(rotation_weight) or rotation_weight <= 0:
        raise InputError(f"rotation_weight: expected a finite number > 0, got {rotation_weight!r}")
    w = np.array([1, 1, 1, rotation_weight, rotation_weight, rotation_weight], dtype=float)
    A = (w[None, :, None] * _rows(arm.regressor_function, data.theta, data.F)[0]).reshape(-1, 6)
    y = (w[None, :] * data.dX).reshape(-1)
    groups = np.tile([0, 0, 0, 1, 1, 1], data.n)
    c, std, cond, problems = _solve(A, y, bounds, "CP", groups)
    return _result("CP", c, std, cond, problems, arm, data, rotation_weight, {})


def calibrate_dpp(arm: SerialArm, data: DeflectionData, bounds: str = "none", step2: str = "rotation") -> JointStiffnessResult:
    """Decoupled partial-pose (DPP) calibration, Cvitanic (2021), eqs. (4)-(5) and Table 2.

    Step 1, eq. (4): joints 1-3 from the wrist-centre displacement
    ``dp_wc = dp - dphi x (p_TCP - p_wc) = sum_{i<=3} J_wc,i c_i tau_i`` with
    ``tau = J^T F``. Step 2, eq. (5), joints 4-6 with joints 1-3 fixed: ``step2="rotation"``
    from the rotation they leave, ``dphi - sum_{i<=3} z_i c_i tau_i = sum_{i>=4} z_i c_i tau_i``;
    ``step2="tcp_translation"`` as the thesis writes (5), from the TCP's LINEAR displacement
    ("Delta X refers to the linear displacement of the end-effector"):
    ``dp - sum_{i<=3} J_v,i c_i tau_i = sum_{i>=4} J_v,i c_i tau_i`` (``J_v``: the linear rows of ``J``).

    Parameters
    ----------
    arm : SerialArm
        Nominal arm with a spherical wrist (wrist centre independent of joints 4-6).
    data : DeflectionData
        Measured wrenches and deflections (rotations are needed for both steps).
    bounds : {"none", "positive"}, optional
        ``"positive"`` constrains ``c >= 0`` in both steps.
    step2 : {"rotation", "tcp_translation"}, optional
        The data of step 2 (above).

    Returns
    -------
    JointStiffnessResult
        Identified stiffnesses (``extra`` holds the per-step conditions), status.

    Raises
    ------
    InputError
        Wrong argument types, an unknown ``step2``, or an arm whose wrist centre moves with joints 4-6.
    """
    _check_common(arm, data, bounds)
    if step2 not in DPP_STEP2:
        raise InputError(f"step2: expected one of {', '.join(DPP_STEP2)}, got {step2!r}")
    J = _rows(arm.jacobian_function, data.theta)[0]
    p_wc, Jwc = _rows(arm.wrist_function, data.theta)
    if np.max(np.abs(Jwc[:, :, 3:])) > 1e-9:
        raise InputError(f"arm {arm.name!r}: DPP needs a spherical wrist (wrist centre independent of joints 4-6)")
    r = _rows(arm.fk_function, data.theta)[0][:, :3, 3] - p_wc[:, :, 0]
    tau = np.einsum("nij,ni->nj", J, data.F)
    A1 = (Jwc[:, :, :3] * tau[:, None, :3]).reshape(-1, 3)
    y1 = (data.dX[:, :3] - np.cross(data.dX[:, 3:], r)).reshape(-1)
    c13, std13, cond1, problems = _solve(A1, y1, bounds, "DPP step 1 (wrist centre, joints 1-3)")
    rows = slice(3, 6) if step2 == "rotation" else slice(0, 3)  # eq. (5) on the rotation, or on the TCP translation
    A2 = (J[:, rows, 3:] * tau[:, None, 3:]).reshape(-1, 3)
    y2 = (data.dX[:, rows] - (J[:, rows, :3] * tau[:, None, :3]) @ c13).reshape(-1)
    c46, std46, cond2, problems2 = _solve(A2, y2, bounds, f"DPP step 2 ({step2.replace('_', ' ')}, joints 4-6)")
    c = np.concatenate([c13, c46])
    std = np.concatenate([std13, std46])
    return _result("DPP", c, std, max(cond1, cond2), problems + problems2, arm, data, 1.0,
                   {"condition_step1": cond1, "condition_step2": cond2, "step2": step2})


def cp_dpp_study(
    arm: SerialArm,
    data_for_seed: Callable[[int], DeflectionData],
    k_true: Any,
    seeds: int = 30,
    rotation_weights: tuple[float, ...] = (1.0, 10.0),
    dpp_step2: str = "rotation",
) -> dict[str, np.ndarray]:
    """Seeded Monte-Carlo comparison of CP (several rotation weights) and DPP, Cvitanic (2021), Table 2.

    For each seed ``s = 0 .. seeds-1`` the data ``data_for_seed(s)`` are calibrated by
    :func:`calibrate_cp` with every weight of ``rotation_weights`` and by
    :func:`calibrate_dpp`; the ratios ``k / k_true`` are collected.

    Parameters
    ----------
    arm : SerialArm
        Nominal arm used by the calibrations.
    data_for_seed : callable
        ``seed -> DeflectionData`` (e.g. ``lambda s: table_2_scenario(arm, s)``).
    k_true : array_like, shape (6,)
        True joint stiffnesses [N m/rad], positive.
    seeds : int, optional
        Number of seeds (>= 1, default 30).
    rotation_weights : tuple of float, optional
        CP rotation weights [m/rad] (default ``(1.0, 10.0)``; see
        :data:`ROTATION_WEIGHT_FOR_UNITS` for the weight of a residual in mm).
    dpp_step2 : {"rotation", "tcp_translation"}, optional
        The data of DPP's step 2 (:func:`calibrate_dpp`).

    Returns
    -------
    dict of str to numpy.ndarray
        ``"CP w=<weight>"`` (one key per weight, formatted with ``:g``) and ``"DPP"``, each
        of shape ``(seeds, 6)``: ``k / k_true`` per seed and joint (``inf`` where a
        compliance came out <= 0).

    Raises
    ------
    InputError
        ``seeds < 1``, a non-positive ``k_true``, or what the calibrations raise.
    """
    if isinstance(seeds, bool) or int(seeds) != seeds or seeds < 1:
        raise InputError(f"seeds: expected an integer >= 1, got {seeds!r}")
    k = _array(k_true, (6,), "k_true")
    if np.any(k <= 0):
        raise InputError(f"k_true: expected positive stiffnesses, got {k.tolist()}")
    out: dict[str, list[np.ndarray]] = {f"CP w={w:g}": [] for w in rotation_weights}
    out["DPP"] = []
    for seed in range(int(seeds)):
        data = data_for_seed(seed)
        for w in rotation_weights:
            out[f"CP w={w:g}"].append(calibrate_cp(arm, data, rotation_weight=w).k_theta / k)
        out["DPP"].append(calibrate_dpp(arm, data, step2=dpp_step2).k_theta / k)
    return {name: np.array(v) for name, v in out.items()}
