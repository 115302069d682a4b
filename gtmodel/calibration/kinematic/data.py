"""Measured poses of a kinematic calibration, checked and padded (internal)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from gtmodel.errors import InputError
from gtmodel.robots.closure import ClosureModel


@dataclass
class _Data:
    q: np.ndarray       # (N, n_q)
    T: np.ndarray       # (N, 3)
    quat: np.ndarray    # (N, 4)
    weights: np.ndarray  # (N,)

    @property
    def N(self) -> int:
        return self.q.shape[0]

    def padded(self, M: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Inputs of M >= N poses (copies of pose 0 with zero weight appended), C order."""
        N = self.N
        pad = M - N
        def ext(a: np.ndarray) -> np.ndarray:
            return np.ascontiguousarray(np.concatenate([a, np.repeat(a[:1], pad, axis=0)]) if pad else a.copy())
        s = np.sqrt(self.weights)
        return ext(self.q), ext(self.T), ext(self.quat), np.ascontiguousarray(np.concatenate([s, np.zeros(pad)]))


def _unpack_measurements(q: Any, T: Any, quat: Any, weights: Any, model: ClosureModel | None = None) -> tuple[Any, Any, Any, Any]:
    if T is None and not isinstance(q, (np.ndarray, list, tuple)) and hasattr(q, "q") and hasattr(q, "quat"):
        m = q
        # the model builds its per-pose input rows from the measurement set (the actuator
        # values; the elasto-geometric closure appends the plate load)
        return (m.q if model is None else model.pose_inputs(m)), m.T, getattr(m, "quat", None), getattr(m, "weights", None)
    return q, T, quat, weights


def _check_data(model: ClosureModel, q: Any, T: Any, quat: Any, weights: Any) -> _Data:
    if T is None:
        raise InputError("T: measured TCP positions (N, 3) are required (or pass a MeasurementSet as q)")
    try:
        qa = np.array(q, dtype=float)
        Ta = np.array(T, dtype=float)
    except (TypeError, ValueError) as e:
        raise InputError(f"q, T: expected numeric arrays ({e})") from None
    if qa.ndim != 2 or qa.shape[1] != model.n_q:
        raise InputError(f"q: expected shape (N, {model.n_q}) (actuator values of {model.name}), got {qa.shape}")
    N = qa.shape[0]
    if Ta.shape != (N, 3):
        raise InputError(f"T: expected shape ({N}, 3) to match q, got {Ta.shape}")
    for name, a in (("q", qa), ("T", Ta)):
        bad = np.flatnonzero(~np.all(np.isfinite(a), axis=1))
        if bad.size:
            raise InputError(f"{name}: non-finite values in row(s) {bad[:10].tolist()}")
    if quat is None:
        if model.orientation:
            raise InputError(f"quat: {model.name} determines the plate orientation; measured orientations (N, 4) are required")
        qu = np.tile([1.0, 0.0, 0.0, 0.0], (N, 1))
    else:
        try:
            qu = np.array(quat, dtype=float)
        except (TypeError, ValueError) as e:
            raise InputError(f"quat: expected a numeric array ({e})") from None
        if qu.shape != (N, 4):
            raise InputError(f"quat: expected shape ({N}, 4) (w, x, y, z per pose), got {qu.shape}")
        bad = np.flatnonzero(~np.all(np.isfinite(qu), axis=1))
        if bad.size:
            raise InputError(f"quat: non-finite values in row(s) {bad[:10].tolist()}")
        nrm = np.linalg.norm(qu, axis=1)
        bad = np.flatnonzero(np.abs(nrm - 1.0) > 1e-6)
        if bad.size:
            raise InputError(f"quat: rows must be unit quaternions; row {int(bad[0])} has norm {nrm[bad[0]]:.6g}")
    if weights is None:
        w = np.ones(N)
    else:
        w = np.array(weights, dtype=float).ravel()
        if w.size != N:
            raise InputError(f"weights: expected {N} values (one per pose), got {w.size}")
        bad = np.flatnonzero(~np.isfinite(w) | (w < 0))
        if bad.size:
            raise InputError(f"weights: expected finite non-negative values; row {int(bad[0])} is {w[bad[0]]!r}")
        if not np.any(w > 0):
            raise InputError("weights: all weights are zero")
    return _Data(q=qa, T=Ta, quat=qu, weights=w)
