"""Closure residuals and their exact Jacobian of one group of arms as CasADi Functions.

One graph per group (Dressler (2012), eqs. 5.1-5.2): the closure residuals of one pose
with their Jacobian with respect to the group's variables, mapped over blocks of
:data:`CHUNK_SIZE` poses and expanded to one SX graph per block, then mapped over the
blocks; :class:`_Evaluator` evaluates them through ``Function.buffer`` on NumPy arrays,
:meth:`_Group.nlp` assembles the IPOPT NLPs ("ipopt", "ipopt-gn") on the same graphs.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from gtmodel.calibration.kinematic.data import _Data
from gtmodel.calibration.kinematic.selection import _parameter_expression, _Resolution
from gtmodel.robots.closure import ClosureModel

__all__ = ["CHUNK_SIZE", "IPOPT_TOLERANCE"]

#: IPOPT ``tol``: the objective is ``V / S``, ``S`` the largest component of grad V at the
#: start, so this is the relative reduction of the gradient. Tighter values end in
#: "Search_Direction_Becomes_Too_Small" on noisy data (the rounding of V, see ``_polish``).
IPOPT_TOLERANCE = 1e-10
#: Poses per expanded SX block of the residual/Jacobian graph.
CHUNK_SIZE = 64


class _Group:
    """Residuals and exact Jacobian of one group of arms as CasADi Functions (internal)."""

    def __init__(self, model: ClosureModel, res: _Resolution, arms: tuple[int, ...], var_idx: list[int]) -> None:
        self.arms = arms
        self.var_idx = np.array(sorted(var_idx), dtype=int)
        self.var_names = tuple(res.var_names[i] for i in self.var_idx)
        self.n_links = [len(model.links[a]) for a in arms]
        self.nr = int(sum(self.n_links))
        self.nx = int(self.var_idx.size)
        n_p = model.n_parameters
        self.n_p = n_p
        self.n_q = model.n_q
        local = {int(g): j for j, g in enumerate(self.var_idx)}
        #: (quaternion number, local variable indices, rotation components) per quaternion
        slots: dict[int, tuple[list[int], list[int]]] = {}
        for g, j in local.items():
            kind, idx = res.var_kind[res.kind_of_var[g]]
            if kind == "quat":
                js, cs = slots.setdefault(idx, ([], []))
                js.append(j)
                cs.append(res.var_comp[g])
        self.quaternion_slots = [(k, js, cs) for k, (js, cs) in slots.items()]
        self.has_quaternion = bool(self.quaternion_slots)
        x = ca.SX.sym("x", self.nx)
        pb = ca.SX.sym("p0", n_p)
        p_expr = _parameter_expression(res, x, pb, {int(g): j for j, g in enumerate(self.var_idx)})
        q = ca.SX.sym("q", model.n_q)
        T = ca.SX.sym("T", 3)
        quat = ca.SX.sym("quat", 4)
        s = ca.SX.sym("s")
        r = ca.vertcat(*[model.closure_function(a)(p_expr, q, T, quat) for a in arms]) * s
        J = ca.densify(ca.jacobian(r, x)) if self.nx else ca.DM.zeros(self.nr, 0)
        ins = [x, pb, q, T, quat, s]
        self.f_r = ca.Function("r", ins, [r])
        self.f_rJ = ca.Function("rJ", ins, [r, J])
        self.f_r_chunk = self.f_r.map("r_chunk", "serial", CHUNK_SIZE, [0, 1], []).expand()
        self.f_rJ_chunk = self.f_rJ.map("rJ_chunk", "serial", CHUNK_SIZE, [0, 1], []).expand()
        self._JtJ = ca.Function("JtJ", ins, [ca.mtimes(J.T, J)])  # mapped when IPOPT-GN needs it
        self._maps: dict[tuple[str, int], ca.Function] = {}
        self._nlps: dict[tuple[str, int, int], ca.Function] = {}

    def mapped(self, kind: str, n_chunks: int) -> ca.Function:
        key = (kind, n_chunks)
        if key not in self._maps:
            if kind == "JtJ":
                base = self._JtJ.map("JtJ_chunk", "serial", CHUNK_SIZE, [0, 1], [0]).expand()
            else:
                base = {"r": self.f_r_chunk, "rJ": self.f_rJ_chunk}[kind]
            reduce_out = [0] if kind == "JtJ" else []
            self._maps[key] = base.map(f"{kind}_{n_chunks}", "serial", n_chunks, [0, 1], reduce_out)
        return self._maps[key]

    def nlp(self, kind: str, M: int, max_iter: int) -> ca.Function:
        """IPOPT solver for M padded poses; parameter vector (scale, p0, q, T, quat, s)."""
        key = (kind, M, max_iter)
        if key in self._nlps:
            return self._nlps[key]
        nch = M // CHUNK_SIZE
        X = ca.MX.sym("x", self.nx)
        n_par = 1 + self.n_p + M * (self.n_q + 3 + 4 + 1)
        P = ca.MX.sym("P", n_par)
        o = 1 + self.n_p
        pb = P[1:o]
        Q = ca.reshape(P[o:o + M * self.n_q], self.n_q, M)
        o += M * self.n_q
        Tm = ca.reshape(P[o:o + 3 * M], 3, M)
        o += 3 * M
        QU = ca.reshape(P[o:o + 4 * M], 4, M)
        o += 4 * M
        S = ca.reshape(P[o:o + M], 1, M)
        r = self.mapped("r", nch)(X, pb, Q, Tm, QU, S)
        f = P[0] * ca.sumsqr(r)
        opts: dict[str, Any] = {
            "ipopt.print_level": 0,
            "ipopt.sb": "yes",
            "print_time": False,
            "ipopt.tol": IPOPT_TOLERANCE,
            "ipopt.max_iter": int(max_iter),
        }
        if kind == "ipopt-gn":
            lam_f = ca.MX.sym("lam_f")
            lam_g = ca.MX.sym("lam_g", 0)
            H = 2 * lam_f * P[0] * self.mapped("JtJ", nch)(X, pb, Q, Tm, QU, S)
            opts["hess_lag"] = ca.Function(
                "nlp_hess_l", [X, P, lam_f, lam_g], [ca.triu(H)], ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"]
            )
        solver = ca.nlpsol("calibration_" + kind.replace("-", "_"), "ipopt", {"x": X, "p": P, "f": f}, opts)
        self._nlps[key] = solver
        return solver


class _Evaluator:
    """Residuals and Jacobian of one group on one data set through Function.buffer (internal)."""

    def __init__(self, group: _Group, data: _Data, pb: np.ndarray) -> None:
        self.group = group
        N = data.N
        M = -(-N // CHUNK_SIZE) * CHUNK_SIZE
        self.N, self.M = N, M
        nch = M // CHUNK_SIZE
        self.x = np.zeros(group.nx)
        self.pb = np.ascontiguousarray(pb, dtype=float).copy()
        self.inputs = [self.x, self.pb, *data.padded(M)]
        #: residual rows of the poses with non-zero weight (the others are zero)
        self.mask = np.repeat(data.weights > 0, group.nr)
        self.r_out = np.zeros((M, group.nr))
        self.rJ_r = np.zeros((M, group.nr))
        self.rJ_J = np.zeros((M, max(group.nx, 1), group.nr))
        self.fb_r, self.ev_r = group.mapped("r", nch).buffer()
        self.fb_rJ, self.ev_rJ = group.mapped("rJ", nch).buffer()
        for fb in (self.fb_r, self.fb_rJ):
            for i, a in enumerate(self.inputs):
                if a.size:
                    fb.set_arg(i, memoryview(a))
        self.fb_r.set_res(0, memoryview(self.r_out))
        self.fb_rJ.set_res(0, memoryview(self.rJ_r))
        if group.nx:
            self.fb_rJ.set_res(1, memoryview(self.rJ_J))
        self.n_eval = 0
        #: factorisation of the last Gauss-Newton polishing step (CalibrationProblem._polish)
        self.polish_qr: Any = None
        self._x_J: np.ndarray | None = None
        self._r = np.zeros(0)
        self._J = np.zeros((0, 0))

    def set_pb(self, pb: np.ndarray) -> None:
        self.pb[:] = pb
        self._x_J = None
        self.polish_qr = None

    def residuals_only(self, x: np.ndarray) -> np.ndarray:
        self.x[:] = x
        self.ev_r()
        return self.r_out[: self.N].ravel().copy()

    def residuals_jacobian(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residuals and Jacobian at ``x`` (read-only arrays; copy before changing them).

        The last point's values are kept, because least_squares asks for the Jacobian at
        the point of its last residual call."""
        if self._x_J is not None and np.array_equal(self._x_J, x):
            return self._r, self._J
        self.x[:] = x
        self.ev_rJ()
        self.n_eval += 1
        r = self.rJ_r[: self.N].ravel().copy()
        J = self.rJ_J[: self.N, : self.group.nx].transpose(0, 2, 1).reshape(self.N * self.group.nr, self.group.nx).copy()
        r.flags.writeable = False
        J.flags.writeable = False
        self._x_J, self._r, self._J = np.array(x, dtype=float), r, J
        return r, J

    def residuals(self, x: np.ndarray) -> np.ndarray:
        return self.residuals_jacobian(x)[0].copy()

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        return self.residuals_jacobian(x)[1].copy()

    def residuals_view(self, x: np.ndarray) -> np.ndarray:
        """Residuals without a copy (for MINPACK, which copies them into its own arrays)."""
        return self.residuals_jacobian(x)[0]

    def jacobian_view(self, x: np.ndarray) -> np.ndarray:
        """Jacobian without a copy (for MINPACK, which copies it into its own array)."""
        return self.residuals_jacobian(x)[1]

    def nlp_parameters(self, scale: float) -> np.ndarray:
        parts = [np.array([scale]), self.pb] + [a.ravel() for a in self.inputs[2:]]
        return np.concatenate(parts)

