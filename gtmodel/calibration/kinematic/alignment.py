"""Frame alignment (Dressler (2012), eqs. 5.3-5.4): the rigid transform (Kabsch, by SVD)
that moves a nominal model's FK positions onto the measured TCP positions."""

from __future__ import annotations

import logging

import numpy as np

from gtmodel.errors import ConvergenceError, InputError, SingularConfigurationError, UnreachablePoseError
from gtmodel.robots.closure import ClosureModel

__all__ = ["fit_rigid_transform", "align_model", "COLLINEAR_TOLERANCE"]

_log = logging.getLogger("gtmodel")

#: Nominal FK positions whose second singular value (centred) is below this fraction of
#: the first are treated as collinear: the alignment then fits a translation only.
COLLINEAR_TOLERANCE = 1e-6


def fit_rigid_transform(
    P: np.typing.ArrayLike, Q: np.typing.ArrayLike, weights: np.typing.ArrayLike | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Rotation and translation that best map points ``P`` onto ``Q`` (Kabsch, by SVD).

    Minimises ``sum_k w_k ||R P_k + t - Q_k||^2`` over rotations ``R`` (``det R = +1``) and
    translations ``t``; used to move a nominal model into the measurement frame,
    Dressler (2012), eqs. 5.3-5.4. For (nearly) collinear ``P`` (see
    :data:`COLLINEAR_TOLERANCE`) the rotation is not determined and ``R = I`` is returned
    with the best translation.

    Parameters
    ----------
    P : array_like, shape (N, 3)
        Points in the source frame [m].
    Q : array_like, shape (N, 3)
        The same points in the target frame [m].
    weights : array_like, shape (N,), optional
        Non-negative weights (default 1).

    Returns
    -------
    R : numpy.ndarray, shape (3, 3)
        Rotation.
    t : numpy.ndarray, shape (3,)
        Translation [m].

    Raises
    ------
    InputError
        Mismatched shapes, non-finite values, fewer than 3 points or negative weights.
    """
    Pa = np.asarray(P, dtype=float)
    Qa = np.asarray(Q, dtype=float)
    if Pa.ndim != 2 or Pa.shape[1] != 3 or Pa.shape != Qa.shape:
        raise InputError(f"P, Q: expected two (N, 3) arrays of equal shape, got {Pa.shape} and {Qa.shape}")
    if Pa.shape[0] < 3:
        raise InputError(f"P, Q: need at least 3 points for a rigid transform, got {Pa.shape[0]}")
    if not (np.all(np.isfinite(Pa)) and np.all(np.isfinite(Qa))):
        raise InputError("P, Q: non-finite values")
    w = np.ones(Pa.shape[0]) if weights is None else np.asarray(weights, dtype=float).ravel()
    if w.size != Pa.shape[0] or np.any(w < 0) or not np.all(np.isfinite(w)) or w.sum() <= 0:
        raise InputError(f"weights: expected {Pa.shape[0]} finite non-negative values, not all zero")
    w = w / w.sum()
    pc = w @ Pa
    qc = w @ Qa
    X = (Pa - pc) * np.sqrt(w)[:, None]
    Y = (Qa - qc) * np.sqrt(w)[:, None]
    sx = np.linalg.svd(X, compute_uv=False)
    if sx[0] == 0 or sx[1] <= COLLINEAR_TOLERANCE * sx[0]:
        _log.warning("fit_rigid_transform: points are (nearly) collinear; fitting a translation only")
        return np.eye(3), qc - pc
    H = X.T @ Y
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(Vt.T @ U.T))
    D = np.diag([1.0, 1.0, d if d != 0 else 1.0])
    R = Vt.T @ D @ U.T
    return R, qc - R @ pc


def _nominal_positions(model: ClosureModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """FK positions of the nominal model and the mask of poses where it succeeded."""
    try:
        T, _ = model.fk(q)
        return np.atleast_2d(T), np.ones(q.shape[0], dtype=bool)
    except (UnreachablePoseError, ConvergenceError, SingularConfigurationError):
        pass
    T = np.zeros((q.shape[0], 3))
    ok = np.zeros(q.shape[0], dtype=bool)
    for k in range(q.shape[0]):
        try:
            T[k] = model.fk(q[k])[0]
            ok[k] = True
        except (UnreachablePoseError, ConvergenceError, SingularConfigurationError):
            continue
    return T, ok


def align_model(
    model: ClosureModel, q: np.typing.ArrayLike, T: np.typing.ArrayLike, weights: np.typing.ArrayLike | None = None
) -> tuple[ClosureModel, np.ndarray, np.ndarray]:
    """Move a nominal model into the measurement frame (Dressler (2012), eqs. 5.3-5.4).

    The nominal FK positions ``model.fk(q)`` are fitted to the measured positions ``T``
    by :func:`fit_rigid_transform`; poses where the nominal FK fails are left out.

    Parameters
    ----------
    model : ClosureModel
        Nominal model.
    q : array_like, shape (N, n_q)
        Actuator values of the measured poses [m, rad].
    T : array_like, shape (N, 3)
        Measured TCP positions [m].
    weights : array_like, shape (N,), optional
        Pose weights (zero-weight poses are ignored).

    Returns
    -------
    model : ClosureModel
        ``model.transformed(R, t)``.
    R : numpy.ndarray, shape (3, 3)
        Rotation from the model frame to the measurement frame.
    t : numpy.ndarray, shape (3,)
        Translation [m].

    Raises
    ------
    InputError
        If the nominal FK succeeds for fewer than 3 poses or the shapes do not match.
    """
    qa = np.atleast_2d(np.asarray(q, dtype=float))
    Ta = np.atleast_2d(np.asarray(T, dtype=float))
    Tn, ok = _nominal_positions(model, qa)
    w = np.ones(qa.shape[0]) if weights is None else np.asarray(weights, dtype=float).ravel()
    ok &= w > 0
    if ok.sum() < 3:
        raise InputError(
            f"{model.name}: the nominal forward kinematics succeeds for only {int(ok.sum())} of {qa.shape[0]} poses; "
            "the frame alignment needs at least 3 (use align=False with a model already in the measurement frame)"
        )
    R, t = fit_rigid_transform(Tn[ok], Ta[ok], w[ok])
    return model.transformed(R, t), R, t
