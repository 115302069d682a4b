"""Which candidate poses a calibration uses (``[pose_selection]`` of a problem file, Dressler (2012), ch. 5.6).

Two ways to keep ``n`` of the candidate poses (before the split into calibration and
validation poses):

- ``method = "condition"``: the greedy removal of eq. 5.9
  (:func:`gtmodel.calibration.select_poses`), on the measured positions or, with
  ``planned = true``, on the start model's forward kinematics at the candidates (the
  poses planned *before* measuring, ch. 5.6: the same choice for every noise seed, so a
  Monte-Carlo study computes it once per worker process, see :data:`SELECTION_CACHE_SIZE`);
- ``method = "random"``: ``n`` candidates drawn uniformly without replacement (seeded by
  the data's seed, on a stream independent of the measurement noise).

Either way the acceptance value of eq. 5.14 and the scaled condition number of the kept
poses are reported, so random and selected pose sets compare on the same figures.
"""

from __future__ import annotations

import hashlib
import logging
from dataclasses import dataclass
from typing import Any

import numpy as np

from gtmodel.calibration.kinematic import CalibrationProblem
from gtmodel.calibration.pose_selection import ACCEPTANCE_LIMIT, acceptance_value, scaled_condition_number, select_poses
from gtmodel.errors import GtModelError
from gtmodel.robots.closure import rotation_to_quaternion

__all__ = ["PoseChoice", "choose_poses", "SELECTION_CACHE_SIZE", "RANDOM_STREAM"]

_log = logging.getLogger("gtmodel")

#: Planned-pose selections (eq. 5.9) kept per process, keyed by the start parameters,
#: the candidates, ``n`` and the parameter selection (each costs seconds on the L1 grid).
SELECTION_CACHE_SIZE = 16
#: Second entropy word of the random pose choice's seed sequence, ``default_rng([seed,
#: RANDOM_STREAM])``: a stream independent of the noise drawn with ``default_rng(seed)``.
RANDOM_STREAM = 59

_CACHE: dict[str, np.ndarray] = {}


@dataclass
class PoseChoice:
    """The kept candidate poses and how good they are for calibrating.

    Parameters
    ----------
    indices : numpy.ndarray of int, shape (n,)
        Indices of the kept poses into the candidates, ascending.
    method : str
        ``"condition"`` (eq. 5.9) or ``"random"``.
    acceptance : float
        ``sigma_max^2 / sigma_min`` of the kept poses' scaled Jacobian, eq. 5.14 (``inf``
        if rank-deficient; ``nan`` if the Jacobian could not be evaluated).
    condition_number : float
        ``sigma_max / sigma_min`` of the same scaled Jacobian.
    """

    indices: np.ndarray
    method: str
    acceptance: float
    condition_number: float

    def summary(self) -> dict[str, Any]:
        """Summary fields of the choice.

        Returns
        -------
        dict
            ``pose_method``, ``selected_poses``, ``pose_acceptance`` (eq. 5.14),
            ``pose_accepted`` (below :data:`~gtmodel.calibration.pose_selection.ACCEPTANCE_LIMIT`)
            and ``pose_condition_number``.
        """
        return {
            "pose_method": self.method,
            "selected_poses": int(self.indices.size),
            "pose_acceptance": self.acceptance,
            "pose_accepted": bool(self.acceptance < ACCEPTANCE_LIMIT),
            "pose_condition_number": self.condition_number,
        }


def _key(*parts: Any) -> str:
    h = hashlib.sha1()
    for p in parts:
        h.update(np.ascontiguousarray(p).tobytes() if isinstance(p, np.ndarray) else repr(p).encode())
    return h.hexdigest()


def _planned(model: Any, q: np.ndarray) -> tuple[np.ndarray, Any] | None:
    """The start model's FK at the candidates, or None if it fails at some pose."""
    try:
        T, R = model.fk(q)
    except GtModelError:
        return None
    quat = rotation_to_quaternion(np.asarray(R).reshape(-1, 3, 3)) if model.orientation else None
    return np.atleast_2d(np.asarray(T, dtype=float)), quat


def choose_poses(spec: dict[str, Any], data: Any, n: int, method: str, planned: bool, seed: int) -> PoseChoice:
    """Keep ``n`` of the candidate poses, by eq. 5.9 or at random.

    Parameters
    ----------
    spec : dict
        The first model of the problem: ``model`` (start ClosureModel) and ``selection``
        (ParameterSelection).
    data : MeasurementSet
        The candidate poses (all measured poses).
    n : int
        Number of poses to keep (``2 <= n < data.n_poses``).
    method : {"condition", "random"}
        Greedy condition-number selection (Dressler (2012), eq. 5.9) or a uniform random
        choice.
    planned : bool
        ``"condition"`` only: select on the start model's forward kinematics at the
        candidates (falls back to the measured positions when that FK fails somewhere).
    seed : int
        Seed of the random choice (``default_rng([seed, RANDOM_STREAM])``).

    Returns
    -------
    PoseChoice

    Raises
    ------
    GtModelError
        From :func:`~gtmodel.calibration.select_poses` (the candidates do not identify
        the free parameters).
    """
    model, selection = spec["model"], spec["selection"]
    if method == "random":
        idx = np.sort(np.random.default_rng([int(seed), RANDOM_STREAM]).choice(data.n_poses, size=n, replace=False))
    else:
        T, quat = data.T, data.quat
        plan = _planned(model, data.q) if planned else None
        if plan is not None:
            T, quat = plan
        key = _key(model.parameter_vector(), data.q, T, quat if quat is not None else 0, n, repr(selection))
        idx = _CACHE.get(key) if plan is not None else None
        if idx is None:
            idx = np.sort(np.asarray(select_poses(model, data.q, n, T=T, quat=quat, selection=selection).indices))
            if plan is not None:
                if len(_CACHE) >= SELECTION_CACHE_SIZE:
                    _CACHE.pop(next(iter(_CACHE)))
                _CACHE[key] = idx
        else:
            _log.info("pose selection (eq. 5.9): %d planned poses from the cache", n)
    acc = cond = float("nan")
    try:
        sub = data.subset(idx)
        _, J, _ = CalibrationProblem(model, selection).jacobian(model.parameter_vector(), sub.q, sub.T, sub.quat)
        acc, cond = acceptance_value(J), scaled_condition_number(J)
    except GtModelError as exc:
        _log.warning("pose selection: no acceptance value (eq. 5.14): %s", exc)
    return PoseChoice(idx, method, acc, cond)
