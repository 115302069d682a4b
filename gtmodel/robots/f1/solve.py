"""Numeric inverse and forward kinematics of the F1 model, Dressler (2012), eqs. 4.20-4.33.

Newton's method in chunks of unrolled steps on N poses at once (the graphs of
:mod:`gtmodel.robots.f1.graphs`), the default starts (continuation from the home pose),
the second FK start for poses the continuation misses, and the Jacobians.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from gtmodel._arrays import as_rotations, as_rows, positive_int
from gtmodel._docstrings import fill_doc
from gtmodel.errors import ConvergenceError, InputError, UnreachablePoseError
from gtmodel.robots.f1.layout import (
    POSE_DOCS,
    pose_rows,
    FK_CONTINUATION_STEPS,
    FK_MAX_ITER,
    FK_TOLERANCE,
    IK_MAX_ITER,
    IK_TOLERANCE,
    NEWTON_CHUNK,
    ROTATION_TOLERANCE,
)
from gtmodel.robots.mapped import MappedFunction

__all__ = ["F1Solvers"]


class F1Solvers:
    """Numeric IK, FK and Jacobians of :class:`~gtmodel.robots.f1.F1Closure` (a mixin of it)."""

    # -------------------------------------------------------------- numeric API
    def _mapped_ik(self, n_steps: int) -> MappedFunction:
        if n_steps not in self._ik_cache:
            self._ik_cache[n_steps] = MappedFunction(self.ik_function(n_steps).expand())
        return self._ik_cache[n_steps]

    def _mapped_fk(self, n_steps: int) -> MappedFunction:
        if n_steps not in self._fk_cache:
            self._fk_cache[n_steps] = MappedFunction(self.fk_function(n_steps).expand())
        return self._fk_cache[n_steps]

    def _run_ik(self, max_iter: int, T: np.ndarray, Rc: np.ndarray, q0: np.ndarray) -> tuple[np.ndarray, ...]:
        """Newton IK in chunks on the unconverged columns; returns (q, e, iterations, ok, disc1)."""
        N = T.shape[1]
        q, e = np.array(q0, dtype=float), np.full((6, N), np.nan)
        it, ok, disc = np.zeros(N, dtype=int), np.zeros(N, dtype=bool), np.zeros(N)
        active, done = np.arange(N), 0
        while active.size and done < max_iter:
            k = min(NEWTON_CHUNK, max_iter - done)
            cols = np.concatenate([np.arange(3 * j, 3 * j + 3) for j in active]) if active.size < N else slice(None)
            qn, en, itn, okn, dn = self._mapped_ik(k)(T[:, active], Rc[:, cols], q[:, active], n=active.size)
            q[:, active], e[:, active], disc[active] = qn, en, dn.ravel()
            it[active] += itn.ravel().astype(int)
            ok[active] = okn.ravel().astype(bool) & np.all(np.isfinite(en), axis=0) & np.all(np.isfinite(qn), axis=0)
            done += k
            active = active[~ok[active] & np.all(np.isfinite(q[:, active]), axis=0) & (disc[active] >= 0)]
        return q, e, it, ok, disc

    def _run_fk(self, max_iter: int, q: np.ndarray, T0: np.ndarray, R0c: np.ndarray) -> tuple[np.ndarray, ...]:
        """Newton FK in chunks on the unconverged columns; returns (T, R cols, e, iterations, ok)."""
        N = q.shape[1]
        T, Rc, e = np.array(T0, dtype=float), np.array(R0c, dtype=float), np.full((6, N), np.nan)
        it, ok = np.zeros(N, dtype=int), np.zeros(N, dtype=bool)
        active, done = np.arange(N), 0
        while active.size and done < max_iter:
            k = min(NEWTON_CHUNK, max_iter - done)
            cols = np.concatenate([np.arange(3 * j, 3 * j + 3) for j in active]) if active.size < N else slice(None)
            Tn, Rn, en, itn, okn = self._mapped_fk(k)(q[:, active], T[:, active], Rc[:, cols], n=active.size)
            T[:, active], e[:, active] = Tn, en
            Rc[:, cols] = Rn
            it[active] += itn.ravel().astype(int)
            ok[active] = okn.ravel().astype(bool) & np.all(np.isfinite(en), axis=0)
            done += k
            active = active[~ok[active] & np.all(np.isfinite(T[:, active]), axis=0)]
        return T, Rc, e, it, ok

    @cached_property
    def _fk_start_mapped(self) -> MappedFunction:
        return MappedFunction(self.fk_start_function.expand())

    @cached_property
    def _ik_start_mapped(self) -> MappedFunction:
        return MappedFunction(self.ik_start_function.expand())

    @cached_property
    def _jac_mapped(self) -> MappedFunction:
        return MappedFunction(self.jacobian_function)

    @staticmethod
    def _R_cols(R: np.ndarray) -> np.ndarray:
        """(N, 3, 3) -> (3, 3N) blocks for a mapped Function (column-major 3x3 inputs)."""
        return np.concatenate(list(R), axis=1) if R.shape[0] > 1 else R[0]

    @staticmethod
    def _R_from_cols(M: np.ndarray, n: int) -> np.ndarray:
        return np.asarray(M).reshape(3, n, 3).transpose(1, 0, 2)

    @cached_property
    def home(self) -> tuple[np.ndarray, np.ndarray]:
        """The home pose ``(T_home (3,) [m], R_home (3, 3))``: the FK of ``q_home``.

        Found by Newton's method from the implicit 5-DOF solution (arm 3 a
        parallelogram for the joint-plate angles, position by trilateration of arm 1 and
        the mean joint points of arms 2 and 3, plate below the carts), Dressler (2012),
        eqs. 4.25-4.26, 4.32-4.33. Every default start continues from it.

        Returns
        -------
        tuple of numpy.ndarray
        """
        T0, R0 = self._five_dof_start(self.q_home)
        return self.fk(self.q_home, T0, R0)

    def fk_start(self, q: np.typing.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """The FK start value (implicit 5-DOF solution), see :attr:`fk_start_function`.

        Parameters
        ----------
        q : array_like, shape (6,) or (N, 6)
            Actuator values [m, rad].

        Returns
        -------
        T0 : numpy.ndarray, shape (3,) or (N, 3)
            Start positions [m].
        R0 : numpy.ndarray, shape (3, 3) or (N, 3, 3)
            Start orientations.

        Raises
        ------
        InputError
            Wrong shape or non-finite values.
        """
        qa, single = as_rows(q, "q", 6)
        T0, R0 = self._fk_start_mapped(qa.T, n=qa.shape[0])
        T0 = T0.T
        R0 = self._R_from_cols(R0, qa.shape[0])
        return (T0[0], R0[0]) if single else (T0, R0)

    def fk(
        self,
        q: np.typing.ArrayLike,
        T0: np.typing.ArrayLike | None = None,
        R0: np.typing.ArrayLike | None = None,
        max_iter: int = FK_MAX_ITER,
        return_iterations: bool = False,
    ) -> tuple[np.ndarray, ...]:
        """Forward kinematics by Newton's method, Dressler (2012), eqs. 4.30-4.33.

        Parameters
        ----------
        q : array_like, shape (6,) or (N, 6)
            Actuator values [m, rad].
        T0 : array_like, shape (3,) or (N, 3), optional
            Start positions (e.g. the previous sample); default the 5-DOF start
            (:attr:`fk_start_function`), which selects the nominal assembly mode.
        R0 : array_like, shape (3, 3) or (N, 3, 3), optional
            Start orientations; given together with ``T0``.
        max_iter : int, optional
            Newton iteration limit (:data:`FK_MAX_ITER`).
        return_iterations : bool, optional
            Also return the Newton iterations used per pose.

        Returns
        -------
        T : numpy.ndarray, shape (3,) or (N, 3)
            TCP positions [m].
        R : numpy.ndarray, shape (3, 3) or (N, 3, 3)
            Plate orientations ``R_T``.
        iterations : numpy.ndarray of int, shape () or (N,)
            Only with ``return_iterations``.

        Raises
        ------
        ConvergenceError
            If ``max |(||B - A|| - L)|`` does not fall below :data:`FK_TOLERANCE` within
            ``max_iter`` iterations; the message names the first failing row.
        InputError
            Wrong shapes, non-finite values, only one of ``T0``/``R0``, or a bad ``max_iter``.
        """
        n_it = positive_int(max_iter, "max_iter")
        qa, single = as_rows(q, "q", 6)
        N = qa.shape[0]
        if (T0 is None) != (R0 is None):
            raise InputError("T0 and R0: give both start values or neither")
        if T0 is None:
            T0a, R0m = self._fk_start_mapped(qa.T, n=N)
        else:
            T0r, _ = as_rows(T0, "T0", 3)
            if T0r.shape[0] not in (1, N):
                raise InputError(f"T0: expected 1 or {N} rows, got {T0r.shape[0]}")
            T0a = np.broadcast_to(T0r, (N, 3)).T
            R0m = self._R_cols(as_rotations(R0, N, "R0", ROTATION_TOLERANCE))
        T, R, e, it, ok = self._run_fk(n_it, qa.T, T0a, R0m)
        if T0 is None and not np.all(ok) and np.any(ok):
            self._fk_continue(n_it, qa, T, R, e, it, ok)
        if not np.all(ok):
            k = int(np.argmin(ok))
            ek = np.abs(e[:, k])
            resid = f"{np.max(ek):.3g} m" if np.all(np.isfinite(ek)) else "not finite (diverged)"
            raise ConvergenceError(
                f"{self.name}: forward kinematics did not converge for pose row {k} (q = {qa[k].tolist()}): "
                f"max |link length residual| {resid} > {FK_TOLERANCE:g} m after "
                f"{n_it} Newton iterations (no assembly near the start, or max_iter too small); "
                f"{int(np.sum(~ok))} pose(s) failed"
            )
        T = T.T
        R = self._R_from_cols(R, N)
        out = (T[0], R[0], it[0]) if single else (T, R, it)
        return out if return_iterations else out[:2]

    def _fk_continue(self, n_it: int, qa: np.ndarray, T: np.ndarray, Rc: np.ndarray, e: np.ndarray, it: np.ndarray, ok: np.ndarray) -> None:
        """Second start for rows whose default-start FK failed (in place).

        A model far from the one whose home pose the default start follows (e.g. a
        calibration start perturbed by tens of mm) can leave the continuation of
        :attr:`fk_start_function` on some poses. Such a row is reached from the converged
        row nearest in ``q`` (scaled: metres, radians) by :data:`FK_CONTINUATION_STEPS`
        equal steps in ``q``, each a Newton solve started from the previous solution.
        """
        N = qa.shape[0]
        good = np.flatnonzero(ok)
        bad = np.flatnonzero(~ok)
        d = np.linalg.norm(qa[bad, None, :] - qa[None, good, :], axis=2)
        src = good[np.argmin(d, axis=1)]
        Rcols = Rc.reshape(3, N, 3)
        Tb = T[:, src].copy()
        Rb = Rcols[:, src, :].reshape(3, -1)
        fine = np.ones(bad.size, dtype=bool)
        for s in range(1, FK_CONTINUATION_STEPS + 1):
            w = s / FK_CONTINUATION_STEPS
            qs = ((1.0 - w) * qa[src] + w * qa[bad]).T
            Tb, Rb, eb, itb, okb = self._run_fk(n_it, qs, Tb, Rb)
            fine &= okb
            it[bad] += itb
        for j, k in enumerate(bad):
            if fine[j] and np.all(np.isfinite(eb[:, j])):
                T[:, k] = Tb[:, j]
                Rcols[:, k, :] = Rb.reshape(3, bad.size, 3)[:, j, :]
                e[:, k] = eb[:, j]
                ok[k] = True
        Rc[:] = Rcols.reshape(3, -1)

    def ik(
        self,
        T: np.typing.ArrayLike,
        R: np.typing.ArrayLike,
        q0: np.typing.ArrayLike | None = None,
        max_iter: int = IK_MAX_ITER,
        return_iterations: bool = False,
    ) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
        """Inverse kinematics, Dressler (2012), eqs. 4.20-4.29.

        Arm 1 in closed form; arms 2 and 3 by Newton's method (see :meth:`ik_function`).

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP positions [m].
        R : array_like, shape (3, 3) or (N, 3, 3)
            Plate orientations ``R_T``.
        q0 : array_like, shape (6,) or (N, 6), optional
            Start values (the previous solution in real-time use); default the parallel-arm
            start of :attr:`ik_start_function`.
        max_iter : int, optional
            Newton iteration limit (:data:`IK_MAX_ITER`).
        return_iterations : bool, optional
            Also return the Newton iterations used per pose.

        Returns
        -------
        q : numpy.ndarray, shape (6,) or (N, 6)
            Actuator values [m, rad].
        iterations : numpy.ndarray of int, shape () or (N,)
            Only with ``return_iterations``.

        Raises
        ------
        UnreachablePoseError
            If arm 1 cannot reach a pose (no real root of its quadratic); names the row.
        ConvergenceError
            If Newton's method for arm 2 or 3 does not reach :data:`IK_TOLERANCE` within
            ``max_iter`` iterations (pose out of reach of those arms or ``max_iter`` too
            small); names the first failing row.
        InputError
            Wrong shapes, non-finite values, ``R`` not a rotation, or a bad ``max_iter``.
        """
        n_it = positive_int(max_iter, "max_iter")
        Ta, single = as_rows(T, "T", 3)
        N = Ta.shape[0]
        Ra = as_rotations(R, N, "R", ROTATION_TOLERANCE)
        Rc = self._R_cols(Ra)
        if q0 is None:
            q0a, _ = self._ik_start_mapped(Ta.T, Rc, n=N)
        else:
            q0r, _ = as_rows(q0, "q0", 6)
            if q0r.shape[0] not in (1, N):
                raise InputError(f"q0: expected 1 or {N} rows, got {q0r.shape[0]}")
            q0a = np.broadcast_to(q0r, (N, 6)).T
        q, e, it, ok, disc = self._run_ik(n_it, Ta.T, Rc, q0a)
        if np.any(disc < 0):
            k = int(np.argmax(disc < 0))
            raise UnreachablePoseError(
                f"{self.name}: pose row {k} (T = {Ta[k].tolist()}) is unreachable for arm 1: the link-1 sphere about "
                f"B_1 misses guideway 1 (discriminant {disc[k]:.3g} m^2 < 0)"
            )
        if not np.all(ok):
            k = int(np.argmin(ok))
            raise ConvergenceError(
                f"{self.name}: inverse kinematics did not converge for pose row {k} (T = {Ta[k].tolist()}): "
                f"max |L^2 - ||B - A||^2| {np.nanmax(np.abs(e[:, k])):.3g} m^2 > {IK_TOLERANCE:g} m^2 after "
                f"{n_it} Newton iterations (pose out of reach of arm 2 or 3, or max_iter too small); "
                f"{int(np.sum(~ok))} pose(s) failed"
            )
        q = q.T
        out = (q[0], it[0]) if single else (q, it)
        return out if return_iterations else out[0]

    @fill_doc(**POSE_DOCS)
    def jacobians(self, T: np.typing.ArrayLike, R: np.typing.ArrayLike, q: np.typing.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Jacobians of the link lengths w.r.t. the pose and the actuators, eq. 4.31.

        Parameters
        ----------
        {pose_args}

        Returns
        -------
        J_X : numpy.ndarray, shape (6, 6) or (N, 6, 6)
            Stewart-platform inverse Jacobian: rows links 1, 2a, 2b, 3a, 3b, 3c, columns
            ``(T_dot [m/s], w [rad/s])`` with ``R_T_dot = [w]x R_T``.
        J_q : numpy.ndarray, shape (6, 6) or (N, 6, 6)
            Link-length rates per actuator rate (see :attr:`jacobian_function`).

        {pose_raises}
        """
        Ta, Rs, qa, single = pose_rows(T, R, q)
        N = Ta.shape[0]
        J_X, J_q = self._jac_mapped(Ta.T, self._R_cols(Rs), qa.T, n=N)
        J_X = np.asarray(J_X).reshape(6, N, 6).transpose(1, 0, 2)
        J_q = np.asarray(J_q).reshape(6, N, 6).transpose(1, 0, 2)
        return (J_X[0], J_q[0]) if single else (J_X, J_q)

    def ik_converged(self, T: np.ndarray, R: np.ndarray, q0: np.ndarray | None = None) -> np.ndarray:
        """Which poses one pass of the Newton IK solves, without raising.

        The start values and Newton steps of :meth:`ik` (from ``q0`` or the default start),
        :data:`IK_MAX_ITER` steps in blocks of :data:`NEWTON_CHUNK`; :meth:`ik` raises on the
        first failing row, this tells which rows fail.

        Parameters
        ----------
        T : numpy.ndarray, shape (N, 3)
            TCP positions [m].
        R : numpy.ndarray, shape (N, 3, 3)
            Plate orientations (not checked to be rotations).
        q0 : numpy.ndarray, shape (N, 6), optional
            Start values [m, rad]; default the start of :attr:`ik_start_function`.

        Returns
        -------
        numpy.ndarray of bool, shape (N,)
        """
        Tc = np.asarray(T, dtype=float).T
        n = Tc.shape[1]
        Rc = self._R_cols(np.asarray(R, dtype=float))
        q0c = np.asarray(q0, dtype=float).T if q0 is not None else self._ik_start_mapped(Tc, Rc, n=n)[0]
        return self._run_ik(IK_MAX_ITER, Tc, Rc, q0c)[3]

    def fk_converged(self, q: np.ndarray, T0: np.ndarray | None = None, R0: np.ndarray | None = None) -> np.ndarray:
        """Which actuator values one pass of the Newton FK solves, without raising.

        The start values and Newton steps of :meth:`fk` (from ``(T0, R0)`` or the default
        start, without its second start for failing rows), :data:`FK_MAX_ITER` steps in
        blocks of :data:`NEWTON_CHUNK`.

        Parameters
        ----------
        q : numpy.ndarray, shape (N, 6)
            Actuator values [m, rad].
        T0 : numpy.ndarray, shape (N, 3), optional
            Start positions [m]; given together with ``R0``.
        R0 : numpy.ndarray, shape (N, 3, 3), optional
            Start orientations.

        Returns
        -------
        numpy.ndarray of bool, shape (N,)
        """
        qc = np.asarray(q, dtype=float).T
        if T0 is None or R0 is None:
            T0c, R0c = self._fk_start_mapped(qc, n=qc.shape[1])
        else:
            T0c, R0c = np.asarray(T0, dtype=float).T, self._R_cols(np.asarray(R0, dtype=float))
        return self._run_fk(FK_MAX_ITER, qc, T0c, R0c)[4]
