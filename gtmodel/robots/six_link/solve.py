"""Numeric inverse and forward kinematics and the workspace test of the six-link model."""

from __future__ import annotations

import logging
from typing import Any, Sequence

import numpy as np

from gtmodel._arrays import as_rotations, as_rows
from gtmodel.errors import ConvergenceError, InputError, UnreachablePoseError
from gtmodel.robots.kinematic_expressions import configuration_signs
from gtmodel.robots.six_link.layout import (
    _ARM_OF_LINK,
    _ASSEMBLY_TOLERANCE,
    _FIRST_LINK,
    _LINK_NAMES,
    FK_MAX_ITER,
    FK_TOLERANCE,
    ROTATION_TOLERANCE,
    SixLinkFKResult,
    _vec,
)
from gtmodel.robots.workspace import within_limits

__all__ = ["SixLinkSolvers"]

_log = logging.getLogger("gtmodel")


class SixLinkSolvers:
    """Numeric IK, FK and workspace of :class:`~gtmodel.robots.six_link.SixLinkClosure` (a mixin of it)."""

    # -------------------------------------------------------------- numeric API
    def _orientations(self, R: Any, N: int) -> np.ndarray:
        if R is None:
            return np.broadcast_to(self.R0, (N, 3, 3))
        return as_rotations(R, N, "R", ROTATION_TOLERANCE)

    def ik_links(
        self, T: np.typing.ArrayLike, R: np.typing.ArrayLike | None = None, configuration: int | Sequence[int] = 0
    ) -> np.ndarray:
        """Cart position demanded by each of the six links (closed-form IK, eq. 4.14).

        On a pose the robot can assemble (e.g. an FK result) the links of one arm agree;
        for an arbitrary ``(T, R)`` they need not (the plate would be strained).

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP positions [m].
        R : array_like, shape (3, 3) or (N, 3, 3), optional
            Plate orientations ``R_T``; default the nominal orientation ``R0``.
        configuration : int or sequence of int, optional
            IK configuration 0-7 or three root signs, one per arm (default 0: the TCP
            ahead of every cart along its guideway).

        Returns
        -------
        numpy.ndarray, shape (6,) or (N, 6)
            ``q_ij`` [m] for links ``1, 2a, 2b, 3a, 3b, 3c``.

        Raises
        ------
        UnreachablePoseError
            If a link cannot reach its plate joint (names the row and the link).
        InputError
            Wrong shapes, non-finite values, ``R`` not a rotation, or an invalid
            configuration.
        """
        Tn, single = as_rows(T, "T", 3)
        N = Tn.shape[0]
        Ra = self._orientations(R, N)
        s = configuration_signs(configuration)
        f = self._ik_graph.map(N) if N > 1 else self._ik_graph
        Rcols = np.ascontiguousarray(Ra.transpose(1, 0, 2).reshape(3, 3 * N))  # horizontally stacked blocks
        q, disc, _cos = f(Tn.T, Rcols, s, self._p_num)
        q, disc = np.array(q).T, np.array(disc).T  # (N, 6)
        bad = disc < 0
        if np.any(bad):
            k, j = (int(x) for x in np.argwhere(bad)[0])
            where = "" if single else f" (row {k})"
            links = ", ".join(_LINK_NAMES[jj] for jj in np.flatnonzero(bad[k]))
            raise UnreachablePoseError(
                f"{self.name}: pose T={Tn[k].tolist()}{where} is unreachable: link(s) {links} "
                f"cannot reach their plate joint (discriminant {disc[k, j]:.3g} m^2 < 0)"
            )
        return q[0] if single else q

    def ik(
        self, T: np.typing.ArrayLike, R: np.typing.ArrayLike | None = None, configuration: int | Sequence[int] = 0
    ) -> np.ndarray:
        """Cart positions for poses: the IK of the first link of each arm (``1, 2a, 3a``), eq. 4.14.

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP positions [m].
        R : array_like, shape (3, 3) or (N, 3, 3), optional
            Plate orientations ``R_T``; default the nominal orientation ``R0``.
        configuration : int or sequence of int, optional
            IK configuration (see :meth:`ik_links`).

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            Cart positions ``q`` [m].

        Raises
        ------
        UnreachablePoseError
            If a link cannot reach (names the row and the link).
        InputError
            Wrong shapes, non-finite values, ``R`` not a rotation, or an invalid
            configuration.
        """
        q = self.ik_links(T, R, configuration)
        return q[..., list(_FIRST_LINK)]

    def fk_solve(
        self,
        q: np.typing.ArrayLike,
        configuration: int | Sequence[int] = 0,
        solution: int = 1,
        max_iter: int = FK_MAX_ITER,
    ) -> SixLinkFKResult:
        """Forward kinematics by Newton-Raphson on ``X = (T, alpha, beta, gamma)``, eq. 4.15.

        ``X_{k+1} = X_k + (d f_ik/dX)^-1 (q - f_ik(X_k))`` with the Jacobian from automatic
        differentiation, started from the 3-link trilateration of links ``1, 2a, 3a`` at
        the nominal orientation ``R0``; a pose has converged when
        ``max |q_i - f_ik,ij(X)| <= FK_TOLERANCE``. All poses are iterated together
        (``Function.map``); converged poses are frozen.

        Parameters
        ----------
        q : array_like, shape (3,) or (N, 3)
            Cart positions [m].
        configuration : int or sequence of int, optional
            IK configuration of ``f_ik`` (see :meth:`ik_links`).
        solution : {1, -1}, optional
            FK branch of the start (see :func:`gtmodel.robots.kinematic_expressions.fk_expression`).
        max_iter : int, optional
            Newton iteration limit (default :data:`FK_MAX_ITER`).

        Returns
        -------
        SixLinkFKResult
            Arrays with a leading pose axis N (N = 1 for a single ``q``).

        Raises
        ------
        ConvergenceError
            If a pose does not reach :data:`FK_TOLERANCE` within ``max_iter`` iterations
            or the iterate leaves the domain of the IK (a link cannot reach); names the
            row.
        InputError
            Wrong shape, non-finite values, or an invalid ``configuration``,
            ``solution`` or ``max_iter``.
        """
        qn, _single = as_rows(q, "q", 3)
        if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or max_iter < 0:
            raise InputError(f"max_iter: expected a non-negative integer, got {max_iter!r}")
        if solution not in (1, -1) or isinstance(solution, bool):
            raise InputError(f"solution: expected +1 or -1, got {solution!r}")
        s = configuration_signs(configuration)
        N = qn.shape[0]
        start = self._start_graph.map(N) if N > 1 else self._start_graph
        step = self._step_graph.map(N) if N > 1 else self._step_graph
        p = self._p_num
        X0, h2 = start(qn.T, float(solution), p, _vec(self.R0))
        X = np.array(X0)
        h2 = np.array(h2).ravel()
        Rref = _vec(self.R_ref)
        iterations = np.zeros(N, dtype=int)
        done = np.zeros(N, dtype=bool)
        lost = ~np.all(np.isfinite(X), axis=0)  # left the domain of the IK: stop iterating
        residual = np.full(N, np.inf)
        for k in range(int(max_iter) + 1):
            X_next, res, dmin = step(X, qn.T, s, p, Rref)
            res = np.array(res).ravel()
            dmin = np.array(dmin).ravel()
            active = ~done & ~lost
            ok = active & (res <= FK_TOLERANCE) & (dmin >= 0)
            iterations[ok] = k
            residual[active] = res[active]
            done |= ok
            active &= ~ok
            if not active.any() or k == max_iter:
                break
            X_next = np.array(X_next)
            X[:, active] = X_next[:, active]
            lost |= ~np.all(np.isfinite(X), axis=0)
        if not done.all():
            k = int(np.flatnonzero(~done)[0])
            if h2[k] < 0:
                why = "the start spheres of links 1, 2a, 3a do not intersect (no assembly near the nominal orientation)"
            elif lost[k]:
                why = "the iterate left the domain of the per-link IK (a link could not reach)"
            else:
                why = f"max |q - f_ik(X)| = {residual[k]:.3g} m > {FK_TOLERANCE:g} m"
            raise ConvergenceError(
                f"{self.name}: forward kinematics (Dressler (2012), eq. 4.15) did not converge for pose row {k} "
                f"(q = {qn[k].tolist()}) within {max_iter} Newton iterations: {why}; "
                f"{int((~done).sum())} of {N} pose(s) failed"
            )
        orient = self._orientation_graph.map(N) if N > 1 else self._orientation_graph
        R = np.array(orient(X, Rref)).reshape(3, N, 3).transpose(1, 0, 2)
        _log.debug("%s: six-link FK of %d pose(s), max %d Newton iterations", self.name, N, int(iterations.max()))
        return SixLinkFKResult(T=X[:3].T.copy(), R=R, euler=X[3:].T.copy(), iterations=iterations, residual=residual)

    def fk(
        self,
        q: np.typing.ArrayLike,
        configuration: int | Sequence[int] = 0,
        solution: int = 1,
        max_iter: int = FK_MAX_ITER,
    ) -> tuple[np.ndarray, np.ndarray]:
        """TCP position and plate orientation for cart positions (Newton FK, eq. 4.15).

        See :meth:`fk_solve` for the method; absolute ZYZ angles of ``R`` via
        :func:`gtmodel.robots.closure.rotation_to_zyz`.

        Parameters
        ----------
        q : array_like, shape (3,) or (N, 3)
            Cart positions [m].
        configuration : int or sequence of int, optional
            IK configuration of ``f_ik``.
        solution : {1, -1}, optional
            FK branch of the start.
        max_iter : int, optional
            Newton iteration limit.

        Returns
        -------
        T : numpy.ndarray, shape (3,) or (N, 3)
            TCP positions [m].
        R : numpy.ndarray, shape (3, 3) or (N, 3, 3)
            Plate orientations ``R_T``.

        Raises
        ------
        ConvergenceError
            If Newton's method does not converge (names the row).
        InputError
            Wrong shape, non-finite values or invalid options.
        """
        single = np.ndim(q) == 1
        res = self.fk_solve(q, configuration, solution, max_iter)
        return (res.T[0], res.R[0]) if single else (res.T, res.R)

    def in_workspace(
        self, T: np.typing.ArrayLike, R: np.typing.ArrayLike | None = None, configuration: int | Sequence[int] = 0
    ) -> np.ndarray:
        """Whether poses are reachable within the cart travel and the spherical-joint limit.

        Every link must reach (eq. 4.14), the links of each arm must agree on the cart
        position within ``1e-9`` m (the pose is an assembly, e.g. an FK result), every ``q_i`` must lie in the
        cart travel and every link make at most ``joint_angle_max`` with its guideway.

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP positions [m].
        R : array_like, shape (3, 3) or (N, 3, 3), optional
            Plate orientations; default ``R0``.
        configuration : int or sequence of int, optional
            IK configuration (see :meth:`ik_links`).

        Returns
        -------
        bool or numpy.ndarray of bool, shape (N,)
            True where the pose is in the workspace.

        Raises
        ------
        InputError
            Wrong shapes, or the model has no limits.
        """
        if self.limits is None:
            raise InputError(f"{self.name}: in_workspace needs limits (load the model with load_six_link or pass limits=)")
        Tn, single = as_rows(T, "T", 3)
        N = Tn.shape[0]
        Ra = self._orientations(R, N)
        s = configuration_signs(configuration)
        f = self._ik_graph.map(N) if N > 1 else self._ik_graph
        q, disc, cos = f(Tn.T, np.ascontiguousarray(Ra.transpose(1, 0, 2).reshape(3, 3 * N)), s, self._p_num)
        q, disc, cos = np.array(q).T, np.array(disc).T, np.array(cos).T
        qa = q[:, list(_FIRST_LINK)]
        ok = within_limits(qa, disc, cos, self.limits.cart_travel, self.limits.joint_angle_max)
        # the links of each arm agree on their cart's position (the pose is an assembly)
        ok &= np.all(np.abs(q - qa[:, list(_ARM_OF_LINK)]) <= _ASSEMBLY_TOLERANCE, axis=1)
        return bool(ok[0]) if single else ok


