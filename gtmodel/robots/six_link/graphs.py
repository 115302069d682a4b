"""Symbolic graphs of the six-link model: per-link IK (eq. 4.14), Newton steps of the FK (eq. 4.15).

Every numeric method of :class:`~gtmodel.robots.six_link.SixLinkClosure` and the generated
C code evaluate these CasADi graphs; :meth:`SixLinkGraphs.graphs` publishes the ones the
code generator and solvers use.
"""

from __future__ import annotations

from functools import cached_property
from typing import Any, Sequence

import casadi as ca
import numpy as np

from gtmodel._geometry import zyz_to_rotation
from gtmodel.errors import InputError
from gtmodel.robots.kinematic_expressions import configuration_signs, fk_expression
from gtmodel.robots.six_link.layout import (
    _ARM_OF_LINK,
    _EULER_AT_REFERENCE,
    _FIRST_LINK,
    FK_TOLERANCE,
    FK_UNROLLED_ITER,
    _vec,
)

__all__ = ["SixLinkGraphs"]


def _ik_link_expressions(L: Any, A0: Sequence[Any], v: Sequence[Any], B0: Sequence[Any], T: Any, R: Any, s: Any) -> tuple[Any, Any]:
    """Per-link IK of eq. 4.14: the quadratic ``|v|^2 q^2 - 2 (d.v) q + |d|^2 - L^2 = 0``.

    ``d = T + R B0_ij - A0_ij``; ``q = (d.v + s_i sqrt(disc)) / |v|^2``. Returns the six
    values, the six discriminants (negative: the link cannot reach) and the cosines of the
    angles between each link ``B_ij - A_ij`` and its guideway (spherical-joint limit).
    """
    q, disc, cos = [], [], []
    for j in range(6):
        i = _ARM_OF_LINK[j]
        d = T + ca.mtimes(R, B0[j]) - A0[j]
        dv = ca.dot(d, v[j])
        vv = ca.dot(v[j], v[j])
        dj = dv**2 - vv * (ca.dot(d, d) - L[j] ** 2)
        qj = (dv + s[i] * ca.sqrt(ca.fmax(dj, 0))) / vv
        link = d - qj * v[j]  # B_ij - A_ij
        q.append(qj)
        disc.append(dj)
        cos.append(ca.dot(link, v[j]) / (ca.norm_2(link) * ca.sqrt(vv)))
    return ca.vertcat(*q), ca.vertcat(*disc), ca.vertcat(*cos)


class SixLinkGraphs:
    """The CasADi graphs of :class:`~gtmodel.robots.six_link.SixLinkClosure` (a mixin of it)."""

    # -------------------------------------------------------------- symbolic building blocks
    @cached_property
    def _p_num(self) -> ca.DM:
        return ca.DM(self.parameter_vector())

    @cached_property
    def _ik_graph(self) -> ca.Function:
        """``ik_links(T, R, s, p) -> (q[6], disc[6], cos[6])`` (eq. 4.14), parameters symbolic."""
        T = ca.SX.sym("T", 3)
        R = ca.SX.sym("R", 3, 3)
        s = ca.SX.sym("s", 3)
        p = ca.SX.sym("p", self.n_parameters)
        L, A0, v, B0 = self._unpack(p)
        q, disc, cos = _ik_link_expressions(L, A0, v, B0, T, R, s)
        return ca.Function("ik_links", [T, R, s, p], [q, disc, cos], ["T", "R", "s", "p"], ["q", "disc", "cos"])

    @cached_property
    def _step_graph(self) -> ca.Function:
        """One Newton step of eq. 4.15: ``step(X, q, s, p, R_ref) -> (X_next, residual, disc_min)``.

        ``residual = max |q_ext - f_ik(X)|`` and ``disc_min`` are those at ``X`` (before the step).
        """
        X = ca.SX.sym("X", 6)
        q = ca.SX.sym("q", 3)
        s = ca.SX.sym("s", 3)
        p = ca.SX.sym("p", self.n_parameters)
        Rref = ca.SX.sym("R_ref", 9)
        R = self._orientation_graph(X, Rref)
        f, disc, _cos = self._ik_graph(X[:3], R, s, p)
        q_ext = ca.vertcat(*[q[i] for i in _ARM_OF_LINK])
        e = q_ext - f
        J = ca.jacobian(f, X)
        X_next = X + ca.solve(J, e)
        return ca.Function(
            "fk_step", [X, q, s, p, Rref], [X_next, ca.mmax(ca.fabs(e)), ca.mmin(disc)],
            ["X", "q", "s", "p", "R_ref"], ["X_next", "residual", "disc_min"],
        )

    @cached_property
    def _start_graph(self) -> ca.Function:
        """Start pose of the FK: 3-link trilateration of links 1, 2a, 3a at ``R0`` (eq. 4.9).

        ``start(q, solution, p, R0) -> (X0, h2)``; ``h2 < 0``: the three spheres do not meet.
        """
        q = ca.SX.sym("q", 3)
        sol = ca.SX.sym("solution")
        p = ca.SX.sym("p", self.n_parameters)
        R0 = ca.SX.sym("R0", 9)
        L, A0, v, B0 = self._unpack(p)
        R0m = ca.reshape(R0, 3, 3)
        As = ca.horzcat(*[A0[j] - ca.mtimes(R0m, B0[j]) for j in _FIRST_LINK]).T
        vs = ca.horzcat(*[v[j] for j in _FIRST_LINK]).T
        Ls = ca.vertcat(*[L[j] for j in _FIRST_LINK])
        T0, h2, _ = fk_expression(q, sol, Ls, As, vs)
        X0 = ca.vertcat(T0, ca.DM(_EULER_AT_REFERENCE))
        return ca.Function("fk_start", [q, sol, p, R0], [X0, h2], ["q", "solution", "p", "R0"], ["X0", "h2"])

    @cached_property
    def _orientation_graph(self) -> ca.Function:
        """``orientation(X, R_ref) -> R_T = R_ref Rzyz(alpha, beta, gamma)``."""
        X = ca.SX.sym("X", 6)
        Rref = ca.SX.sym("R_ref", 9)
        R = ca.mtimes(ca.reshape(Rref, 3, 3), zyz_to_rotation(X[3], X[4], X[5]))
        return ca.Function("orientation", [X, Rref], [R], ["X", "R_ref"], ["R"])

    # -------------------------------------------------------------- CasADi Functions
    def ik_links_function(self, configuration: int | Sequence[int] = 0) -> ca.Function:
        """CasADi Function ``ik_links(T[3], R[3x3]) -> (q[6], disc[6])``, eq. 4.14.

        Parameters are embedded as constants (ready for C generation).

        Parameters
        ----------
        configuration : int or sequence of int, optional
            IK configuration 0-7 or three root signs (one per arm, shared by its links),
            see :func:`gtmodel.robots.kinematic_expressions.configuration_signs`.

        Returns
        -------
        casadi.Function
            ``q`` the per-link cart positions [m] (links ``1, 2a, 2b, 3a, 3b, 3c``);
            ``disc`` the discriminants [m^2], negative where a link cannot reach.

        Raises
        ------
        InputError
            For an invalid configuration.
        """
        s = configuration_signs(configuration)
        T = ca.SX.sym("T", 3)
        R = ca.SX.sym("R", 3, 3)
        q, disc, _cos = self._ik_graph(T, R, ca.DM(s), self._p_num)
        return ca.Function("ik_links", [T, R], [q, disc], ["T", "R"], ["q", "disc"])

    def fk_function(
        self,
        n_iter: int = FK_UNROLLED_ITER,
        configuration: int | Sequence[int] = 0,
        solution: int = 1,
        parametric: bool = False,
    ) -> ca.Function:
        """FK as a CasADi Function with ``n_iter`` Newton iterations of eq. 4.15 unrolled.

        Start: 3-link trilateration of links ``1, 2a, 3a`` at the nominal orientation
        ``R0``; then ``X_{k+1} = X_k + (d f_ik/dX)^-1 (q - f_ik(X_k))``. Fixed work per
        call, no branches: suited to C generation for the 4 ms loop; check ``status``.
        Map it over N poses with ``Function.map(N)``.

        Parameters
        ----------
        n_iter : int, optional
            Number of Newton iterations (>= 1).
        configuration : int or sequence of int, optional
            IK configuration of ``f_ik`` (see :meth:`ik_links_function`).
        solution : {1, -1}, optional
            FK branch of the trilateration start (see
            :func:`gtmodel.robots.kinematic_expressions.fk_expression`).
        parametric : bool, optional
            If True the parameter vector is a second input ``p``; otherwise the current
            values are embedded as constants.

        Returns
        -------
        casadi.Function
            Inputs ``q`` (3) [m] (and ``p``); outputs ``T`` (3) [m], ``R`` (3x3),
            ``X`` (6: ``T`` and the Euler angles relative to ``R_ref``) [m, rad],
            ``residual`` = ``max |q_i - f_ik,ij(X)|`` at the result [m], and ``status``
            = 1 if ``residual <= FK_TOLERANCE`` and every link reaches, else 0.

        Raises
        ------
        InputError
            If ``n_iter`` is not a positive integer, or ``configuration`` / ``solution``
            is invalid.
        """
        if isinstance(n_iter, bool) or not isinstance(n_iter, (int, np.integer)) or n_iter < 1:
            raise InputError(f"n_iter: expected a positive integer, got {n_iter!r}")
        if solution not in (1, -1) or isinstance(solution, bool):
            raise InputError(f"solution: expected +1 or -1, got {solution!r}")
        s = ca.DM(configuration_signs(configuration))
        q = ca.MX.sym("q", 3)
        p = ca.MX.sym("p", self.n_parameters) if parametric else ca.MX(self._p_num)
        # R0 and R_ref: the model's own for the embedded case; for the parametric case the
        # reference orientation stays the model's (it is a start value, not a parameter).
        R0v = ca.MX(ca.DM(_vec(self.R0)))
        Rrefv = ca.MX(ca.DM(_vec(self.R_ref)))
        X, _h2 = self._start_graph(q, float(solution), p, R0v)
        for _ in range(int(n_iter)):
            X, _r, _d = self._step_graph(X, q, s, p, Rrefv)
        _, residual, disc_min = self._step_graph(X, q, s, p, Rrefv)
        status = ca.if_else(ca.logic_and(residual <= FK_TOLERANCE, disc_min >= 0), 1.0, 0.0)
        R = self._orientation_graph(X, Rrefv)
        ins, names = ([q, p], ["q", "p"]) if parametric else ([q], ["q"])
        return ca.Function(
            "fk_six_link", ins, [X[:3], R, X, residual, status], names, ["T", "R", "X", "residual", "status"]
        )


    # -------------------------------------------------------------- the public graph interface
    @cached_property
    def _public_graphs(self) -> dict[str, ca.Function]:
        p, R_ref, R0 = self._p_num, ca.DM(_vec(self.R_ref)), ca.DM(_vec(self.R0))
        T, R, s = ca.SX.sym("T", 3), ca.SX.sym("R", 3, 3), ca.SX.sym("s", 3)
        q_links, disc, cos = self._ik_graph(T, R, s, p)
        ik = ca.Function("ik_links", [T, R, s], [q_links, disc, cos], ["T", "R", "s"], ["q", "disc", "cos"])
        X, q, sol = ca.SX.sym("X", 6), ca.SX.sym("q", 3), ca.SX.sym("solution")
        X_next, residual, disc_min = self._step_graph(X, q, s, p, R_ref)
        step = ca.Function("fk_step", [X, q, s], [X_next, residual, disc_min], ["x", "q", "s"], ["x_next", "residual", "valid"])
        X0, h2 = self._start_graph(q, sol, p, R0)
        start = ca.Function("fk_start", [q, sol], [X0, h2], ["q", "solution"], ["x0", "h2"])
        orientation = ca.Function("orientation", [X], [self._orientation_graph(X, R_ref)], ["x"], ["R"])
        return {"ik_links": ik, "fk_start": start, "fk_step": step, "orientation": orientation}

    def graphs(self) -> dict[str, ca.Function]:
        """The CasADi Functions of the model used by solvers and the code generator, by name.

        Parameters, the nominal orientation ``R0`` and ``R_ref = R0 Ry(-pi/2)`` are embedded
        as constants. Besides the closure Functions of :meth:`ClosureModel.graphs
        <gtmodel.robots.closure.ClosureModel.graphs>`:

        ``"ik_links"``
            ``(T[3] [m], R[3x3], s[3]) -> (q[6] [m], disc[6] [m^2], cos[6])``: the per-link
            IK of eq. 4.14 (links ``1, 2a, 2b, 3a, 3b, 3c``; ``s`` the root sign per arm;
            ``disc < 0``: the link cannot reach; ``cos`` of the link-guideway angles).
        ``"fk_start"``
            ``(q[3] [m], solution) -> (x0[6], h2 [m^2])``: the FK start, 3-link
            trilateration of links ``1, 2a, 3a`` at ``R0`` (eq. 4.9; ``h2 < 0``: the
            spheres do not meet); ``x = (T [m], ZYZ angles relative to R_ref [rad])``.
        ``"fk_step"``
            ``(x[6], q[3], s[3]) -> (x_next[6], residual [m], valid [m^2])``: one Newton
            step of eq. 4.15; ``residual = max |q_i - f_ik,ij(x)|`` and ``valid`` the
            smallest discriminant, both at ``x`` (before the step).
        ``"orientation"``
            ``x[6] -> R[3x3]``: ``R_T = R_ref Rzyz(alpha, beta, gamma)``.

        Returns
        -------
        dict of str to casadi.Function
        """
        return {**super().graphs(), **self._public_graphs}  # type: ignore[misc]
