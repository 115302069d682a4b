"""Calibration poses inside the workspace: grids and random poses, reproducible with a seed.

Poses are generated within cart travel and spherical-joint limits (Dressler (2012),
ch. 5.6) as actuator values ``q`` (what the robot is commanded to): :func:`grid_poses` (a
workspace grid through the model's IK or FK), :func:`random_poses` (rejection sampling);
:func:`link_angles` gives the spherical-joint angles of a pose.
"""

from __future__ import annotations

import dataclasses
import logging

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel.errors import ConvergenceError, InputError, UnreachablePoseError
from gtmodel.robots.closure import ClosureModel, ThreeLinkClosure
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.parameters import Limits, RobotParameters

__all__ = ["grid_poses", "random_poses", "link_angles", "L1_GRID_STEP_M", "RANDOM_POSE_MAX_ROUNDS"]

_log = logging.getLogger("gtmodel")

#: Grid step [m] of :meth:`GantryTau3Kinematics.workspace_grid` that gives 778 L1 poses
#: within the L1 limits (Table 5.1 used 779 laser-tracker poses).
L1_GRID_STEP_M = 0.1153
#: Rejection-sampling rounds of :func:`random_poses` before giving up.
RANDOM_POSE_MAX_ROUNDS = 50


def _model_limits(model: ClosureModel, limits: Limits | None) -> Limits:
    if limits is not None:
        if not isinstance(limits, Limits):
            raise InputError(f"limits: expected a gtmodel.robots.parameters.Limits, got {type(limits).__name__}")
        return limits
    for obj in (model, getattr(model, "model", None)):
        robot = getattr(obj, "robot", None)
        if isinstance(robot, RobotParameters):
            return robot.limits
        lim = getattr(obj, "limits", None)
        if isinstance(lim, Limits):
            return lim
    raise InputError(f"{model.name}: no limits known; pass limits (cart travel and spherical-joint limit)")


def _three_link_kinematics(model: ThreeLinkClosure, limits: Limits) -> GantryTau3Kinematics:
    if model.robot is not None:
        robot = dataclasses.replace(model.robot, kinematics=model.kinematics, limits=limits)
    else:  # kinematics only: GantryTau3Kinematics's workspace methods read just name and limits
        robot = RobotParameters(
            name=model.name, description="kinematic parameters only", frame="", kinematics=model.kinematics,
            dynamics=None, limits=limits,  # type: ignore[arg-type]
        )
    return GantryTau3Kinematics(robot)


def _link_cosines(model: ClosureModel, q: np.ndarray, T: np.ndarray, R: np.ndarray | None) -> np.ndarray:
    """Signed cosines of the angles between ``B_ij - A_ij`` and ``dA_ij/dq_i``, shape (N, n_links)."""
    qa = np.atleast_2d(np.asarray(q, dtype=float))
    Ta = np.atleast_2d(np.asarray(T, dtype=float))
    N = qa.shape[0]
    if qa.shape != (N, model.n_q) or Ta.shape != (N, 3):
        raise InputError(f"link_angles: expected q ({N}, {model.n_q}) and T ({N}, 3), got {qa.shape} and {Ta.shape}")
    Ra = np.broadcast_to(np.eye(3) if R is None else np.asarray(R, dtype=float), (N, 3, 3))
    p, qs = ca.SX.sym("p", model.n_parameters), ca.SX.sym("q", model.n_q)
    Ts, Rv = ca.SX.sym("T", 3), ca.SX.sym("R", 9)
    Rs = ca.reshape(Rv, 3, 3)  # column-major vec(R)
    cos = []
    for i, arm in enumerate(model.links):
        A, B, _ = model.link_points(p, qs, Ts, Rs, i)
        for j in range(len(arm)):
            g = ca.jacobian(A[:, j], qs)[:, i]
            D = B[:, j] - A[:, j]
            cos.append(ca.dot(D, g) / (ca.norm_2(D) * ca.norm_2(g)))
    f = ca.Function("link_cos", [p, qs, Ts, Rv], [ca.vertcat(*cos)]).map(N)
    Rcols = Ra.transpose(0, 2, 1).reshape(N, 9).T
    return np.array(f(model.parameter_vector(), qa.T, Ta.T, Rcols)).T


def link_angles(model: ClosureModel, q: np.typing.ArrayLike, T: np.typing.ArrayLike, R: np.typing.ArrayLike | None = None) -> np.ndarray:
    """Angle between each link and its guideway, for any closure model.

    The link vector is ``B_ij - A_ij`` and the guideway direction ``dA_ij/dq_i`` (CasADi
    jacobian of the model's link points); the angle is taken of ``|cos|`` (0 = link along the
    guideway either way), as the spherical-joint limit of :meth:`GantryTau3Kinematics.in_workspace`.

    Parameters
    ----------
    model : ClosureModel
        The model.
    q : array_like, shape (N, n_q)
        Actuator values [m, rad].
    T : array_like, shape (N, 3)
        TCP positions [m].
    R : array_like, shape (N, 3, 3), optional
        Plate orientations (identity by default).

    Returns
    -------
    numpy.ndarray, shape (N, n_links)
        Angles in [0, pi/2] [rad].

    Raises
    ------
    InputError
        If shapes disagree.
    """
    c = _link_cosines(model, np.asarray(q, dtype=float), np.asarray(T, dtype=float), None if R is None else np.asarray(R, dtype=float))
    return np.arccos(np.clip(np.abs(c), 0.0, 1.0))


def _fk_filter(model: ClosureModel, q: np.ndarray, limits: Limits, q_ref: np.ndarray) -> np.ndarray:
    """Mask of poses whose FK exists and whose links respect the spherical-joint limit.

    Each link must also point to the same side of its cart as at the reference pose
    ``q_ref`` (the centre of travel): the nominal IK configuration (for the 3-link model
    configuration 0, ``(T - A_i) . v_i > 0``).
    """
    ok = np.zeros(q.shape[0], dtype=bool)
    T = np.full((q.shape[0], 3), np.nan)
    R = np.broadcast_to(np.eye(3), (q.shape[0], 3, 3)).copy()
    try:
        T[:], R[:] = model.fk(q)
        ok[:] = True
    except (ConvergenceError, UnreachablePoseError):
        for k in range(q.shape[0]):
            try:
                T[k], R[k] = model.fk(q[k])
                ok[k] = True
            except (ConvergenceError, UnreachablePoseError):
                pass
    if np.any(ok):
        c = _link_cosines(model, q[ok], T[ok], R[ok])
        ref = np.sign(_link_cosines(model, q_ref[None, :], *[x[None] for x in model.fk(q_ref)]))
        keep = np.all(np.abs(c) >= np.cos(limits.joint_angle_max), axis=1) & np.all(np.sign(c) == ref, axis=1)
        ok[np.flatnonzero(ok)] = keep
    return ok


def _q_box(model: ClosureModel, limits: Limits, rotary_travel: np.typing.ArrayLike | None) -> np.ndarray:
    box = np.asarray(limits.cart_travel, dtype=float)
    if model.n_q > 3:
        if rotary_travel is None:
            raise InputError(f"{model.name}: rotary_travel (range of q4..q{model.n_q} in rad) is needed for a model with n_q={model.n_q}")
        rt = np.asarray(rotary_travel, dtype=float)
        if rt.shape != (model.n_q - 3, 2) or np.any(rt[:, 0] >= rt[:, 1]):
            raise InputError(f"rotary_travel: expected shape ({model.n_q - 3}, 2) with min < max, got {rt.tolist()}")
        box = np.vstack([box, rt])
    return box


def grid_poses(
    model: ClosureModel,
    step: float,
    limits: Limits | None = None,
    rotary_travel: np.typing.ArrayLike | None = None,
    rotary_step: float | None = None,
) -> np.ndarray:
    """Actuator values of a regular grid of poses inside the workspace (Dressler (2012), ch. 5.6).

    - :class:`ThreeLinkClosure`: a regular TCP grid of spacing ``step``
      (:meth:`GantryTau3Kinematics.workspace_grid`, IK configuration 0), kept where the
      carts stay within travel and the links within the spherical-joint limit; returned as
      its IK solutions.
    - any other model: a regular grid in ``q`` over the cart travel (and ``rotary_travel``),
      kept where the model's FK exists and every link is within the joint limit
      (:func:`link_angles`).

    Parameters
    ----------
    model : ClosureModel
        The (nominal) model the poses are planned with.
    step : float
        Grid spacing [m] (TCP grid for the 3-link model, ``q`` grid otherwise).
    limits : Limits, optional
        Cart travel and joint-angle limit; default the model's parameter set's limits.
    rotary_travel : array_like, shape (n_q - 3, 2), optional
        Range of ``q4..`` [rad] (models with ``n_q > 3``).
    rotary_step : float, optional
        Grid spacing of ``q4..`` [rad] (models with ``n_q > 3``).

    Returns
    -------
    numpy.ndarray, shape (N, n_q)
        Actuator values [m, rad], N >= 1.

    Raises
    ------
    InputError
        If ``step`` is not positive, no limits are known, the rotary ranges are missing,
        or no grid point lies in the workspace.
    """
    if not (np.isfinite(step) and step > 0):
        raise InputError(f"step: expected a positive grid spacing [m], got {step!r}")
    lim = _model_limits(model, limits)
    if isinstance(model, ThreeLinkClosure):
        kin = _three_link_kinematics(model, lim)
        T = kin.workspace_grid(step)
        if T.shape[0] == 0:
            raise InputError(f"{model.name}: no grid point with step {step} m lies in the workspace")
        return kin.ik(T, 0)
    box = _q_box(model, lim, rotary_travel)
    if model.n_q > 3 and not (rotary_step is not None and np.isfinite(rotary_step) and rotary_step > 0):
        raise InputError(f"rotary_step: expected a positive spacing [rad] for q4..q{model.n_q}, got {rotary_step!r}")
    steps = [step] * 3 + [rotary_step] * (model.n_q - 3)
    axes = [np.arange(lo, hi + s / 2, s) for (lo, hi), s in zip(box, steps)]
    q = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, model.n_q)
    q = q[np.all(q <= box[:, 1] + 1e-12, axis=1)]
    ok = _fk_filter(model, q, lim, box.mean(axis=1))
    if not np.any(ok):
        raise InputError(f"{model.name}: no grid point with step {step} lies in the workspace")
    _log.info("%s: %d of %d grid poses in the workspace", model.name, int(ok.sum()), q.shape[0])
    return q[ok]


def random_poses(
    model: ClosureModel,
    n: int,
    seed: int | None = 0,
    limits: Limits | None = None,
    rotary_travel: np.typing.ArrayLike | None = None,
) -> np.ndarray:
    """Actuator values of random poses inside the workspace (uniform, rejection sampling).

    - :class:`ThreeLinkClosure`: TCP positions uniform in the workspace box, kept by
      :meth:`GantryTau3Kinematics.in_workspace`, returned as IK solutions (configuration 0).
    - any other model: ``q`` uniform in the cart travel (and ``rotary_travel``), kept where
      FK exists and every link is within the joint limit (:func:`link_angles`).

    Parameters
    ----------
    model : ClosureModel
        The (nominal) model.
    n : int
        Number of poses.
    seed : int or None, optional
        Seed of :func:`numpy.random.default_rng`.
    limits : Limits, optional
        Cart travel and joint-angle limit; default the model's parameter set's limits.
    rotary_travel : array_like, shape (n_q - 3, 2), optional
        Range of ``q4..`` [rad] (models with ``n_q > 3``).

    Returns
    -------
    numpy.ndarray, shape (n, n_q)
        Actuator values [m, rad].

    Raises
    ------
    InputError
        If ``n`` is not a positive integer, no limits are known, or fewer than ``n`` poses
        were found in :data:`RANDOM_POSE_MAX_ROUNDS` rounds of sampling.
    """
    if not isinstance(n, (int, np.integer)) or n < 1:
        raise InputError(f"n: expected a positive number of poses, got {n!r}")
    lim = _model_limits(model, limits)
    rng = np.random.default_rng(seed)
    batch = max(4 * int(n), 256)
    found: list[np.ndarray] = []
    count = 0
    if isinstance(model, ThreeLinkClosure):
        kin = _three_link_kinematics(model, lim)
        box = kin.workspace_bounds()
        for _ in range(RANDOM_POSE_MAX_ROUNDS):
            T = rng.uniform(box[:, 0], box[:, 1], (batch, 3))
            T = T[kin.in_workspace(T)]
            if T.shape[0]:
                found.append(kin.ik(T, 0))
                count += T.shape[0]
            if count >= n:
                break
    else:
        box = _q_box(model, lim, rotary_travel)
        for _ in range(RANDOM_POSE_MAX_ROUNDS):
            q = rng.uniform(box[:, 0], box[:, 1], (batch, model.n_q))
            q = q[_fk_filter(model, q, lim, box.mean(axis=1))]
            found.append(q)
            count += q.shape[0]
            if count >= n:
                break
    if count < n:
        raise InputError(f"{model.name}: found only {count} of {n} poses in the workspace after {RANDOM_POSE_MAX_ROUNDS} sampling rounds")
    return np.vstack(found)[:n]
