"""What a calibration solve does before solving: caches per data set and the start.

:class:`_ProblemStart`, a base of :class:`~gtmodel.calibration.kinematic.problem.CalibrationProblem`
(it uses the problem's model, resolution, groups and caches set up there): the key of a
data set and what is kept per data set (the evaluators bound to its arrays, the nominal
FK, the chosen alignment), the frame alignment of the start model guarded by the cost
(Dressler (2012), eqs. 5.3-5.4) and whether the problem's graphs hold for the start model.
"""

from __future__ import annotations

import hashlib
import logging

import numpy as np

from gtmodel._geometry import rotation_vector_to_rotation
from gtmodel.calibration.kinematic.alignment import _nominal_positions, fit_rigid_transform
from gtmodel.calibration.kinematic.data import _Data
from gtmodel.calibration.kinematic.graph_cache import _SHARED_GRAPH_TYPES
from gtmodel.calibration.kinematic.residuals import _Evaluator
from gtmodel.robots.closure import ClosureModel

__all__ = ["FK_CACHE_SIZE"]

_log = logging.getLogger("gtmodel")

#: Nominal FK results kept per problem (keyed by the actuator values), for repeated solves
#: on the same poses (simulated calibrations, benchmarks).
FK_CACHE_SIZE = 8


class _ProblemStart:
    """Data keys, per-data-set caches and the start model of :class:`CalibrationProblem` solves."""

    def _start_cost(self, p: np.ndarray, evs: list["_Evaluator"]) -> float:
        """V (eq. 5.2) of all groups at the parameter vector ``p``."""
        pb = self._anchor(p)
        x = self._x_of(pb)
        V = 0.0
        for grp, ev in zip(self._groups, evs):
            ev.set_pb(pb)
            r = ev.residuals_only(x[grp.var_idx])
            V += float(r @ r)
        return V

    def _nominal_fk(self, model: ClosureModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Nominal FK positions, cached for the problem's own model (same q, other T)."""
        if model is not self.model:
            return _nominal_positions(model, q)
        key = hashlib.sha1(q.tobytes()).hexdigest() + str(q.shape)
        if key not in self._fk_cache:
            if len(self._fk_cache) >= FK_CACHE_SIZE:
                self._fk_cache.pop(next(iter(self._fk_cache)))
            self._fk_cache[key] = _nominal_positions(model, q)
        return self._fk_cache[key]

    def _data_key(self, data: _Data) -> str:
        """Hash of a data set (actuator values, positions, orientations, weights).

        The last data set and its key are kept: the same data again (a repeated solve)
        is recognised by comparing the arrays, without hashing them."""
        arrays = (data.q, data.T, data.quat, data.weights)
        last = self._last_data
        if last is not None and all(a.shape == b.shape and np.array_equal(a, b) for a, b in zip(arrays, last[0])):
            return last[1]
        h = hashlib.sha1()
        for a in arrays:
            a = np.ascontiguousarray(a, dtype=float)
            h.update(str(a.shape).encode())
            h.update(a.tobytes())
        key = h.hexdigest()
        self._last_data = (arrays, key)  # the checked copies made by _check_data, not the caller's
        return key

    def _evaluators(self, key: str, data: _Data) -> list[_Evaluator]:
        """Evaluators of all groups bound to the data set ``key`` (built once per data set).

        Every use sets the anchor first (``set_pb``), so a re-used evaluator carries no
        state of an earlier solve into the next.
        """
        evs = self._eval_cache.get(key)
        if evs is None:
            evs = [_Evaluator(grp, data, self.model.parameter_vector()) for grp in self._groups]
            if len(self._eval_cache) >= FK_CACHE_SIZE:
                self._eval_cache.pop(next(iter(self._eval_cache)))
            self._eval_cache[key] = evs
        return evs

    def _best_alignment(
        self, model: ClosureModel, data: _Data, evs: list["_Evaluator"], key: str | None = None, cache: bool = False
    ) -> tuple[ClosureModel, np.ndarray, np.ndarray]:
        """The start model in the measurement frame (eqs. 5.3-5.4), guarded by the cost.

        Candidates: no transform, the translation of the centroids, and the rigid fit of
        :func:`fit_rigid_transform`; the one with the lowest ``V`` at the start is used. The
        rigid fit moves a start model into a far-away device frame, but on a small pose
        cloud with a poor nominal model its rotation can be far off (worse than none).
        """
        akey = (key, model.parameter_vector().tobytes()) if cache and key is not None else None
        if akey is not None and akey in self._align_cache:
            best, R, t = self._align_cache[akey]
            return (model, np.eye(3), np.zeros(3)) if best == 0 else (model.transformed(R, t), R.copy(), t.copy())
        Tn, ok = self._nominal_fk(model, data.q)
        ok = ok & (data.weights > 0)
        cands: list[tuple[ClosureModel, np.ndarray, np.ndarray]] = [(model, np.eye(3), np.zeros(3))]
        if ok.sum() >= 3:
            w = data.weights[ok] / data.weights[ok].sum()
            t_only = w @ (data.T[ok] - Tn[ok])
            cands.append((model.transformed(np.eye(3), t_only), np.eye(3), t_only))
            R, t = fit_rigid_transform(Tn[ok], data.T[ok], data.weights[ok])
            cands.append((model.transformed(R, t), R, t))
        else:
            _log.warning(
                "%s: nominal forward kinematics succeeds for %d poses only; no frame alignment", model.name, int(ok.sum())
            )
        costs = [self._start_cost(m.parameter_vector(), evs) for m, _, _ in cands]
        best = int(np.argmin(costs))
        _log.info("frame alignment: start V %s -> candidate %d", ", ".join(f"{c:.3g}" for c in costs), best)
        if akey is not None:
            if len(self._align_cache) >= FK_CACHE_SIZE:
                self._align_cache.pop(next(iter(self._align_cache)))
            self._align_cache[akey] = (best, cands[best][1].copy(), cands[best][2].copy())
        return cands[best]

    def _equal_closures(self, other: ClosureModel, q: np.ndarray, T: np.ndarray, quat: np.ndarray) -> bool:
        """Whether ``other`` has the problem model's closure equations (at its p and one pose)."""
        if type(other) is not type(self.model) or tuple(other.parameter_names()) != self.resolution.names:
            return False
        if type(other) in _SHARED_GRAPH_TYPES:  # equations fixed by the type and the parameter names
            return True
        args = (other.parameter_vector(), q, T, quat)
        for a in range(len(self.model.links)):
            if a not in self._closure_cache:
                self._closure_cache[a] = self.model.closure_function(a)
            r0 = np.array(self._closure_cache[a](*args)).ravel()
            r1 = np.array(other.closure_function(a)(*args)).ravel()
            if not np.allclose(r0, r1, rtol=1e-12, atol=1e-15):
                return False
        return True

    def _shares_equations(self, start: ClosureModel, aligned: ClosureModel, data: _Data) -> bool:
        """Whether the problem's graphs hold for ``aligned`` (see :class:`CalibrationProblem`).

        ``with_parameters`` keeps a model's equations (the interface contract); whether
        ``transformed`` does (only parameters change) is checked once per problem with a
        test transform, and a start model that is another instance is checked explicitly.
        """
        if aligned is self.model:
            return True
        q0, T0, quat0 = data.q[0], data.T[0], data.quat[0]
        if start is not self.model and not self._equal_closures(start, q0, T0, quat0):
            return False
        if aligned is start:
            return True
        if self._transform_safe is None:
            R = rotation_vector_to_rotation([0.3, -0.2, 0.5])
            moved = self.model.transformed(R, [0.1, -0.2, 0.3])
            self._transform_safe = self._equal_closures(moved, q0, T0 @ R.T, quat0)
        return bool(self._transform_safe)
