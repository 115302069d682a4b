"""Rank-aware pose iteration of the generic closure forward kinematics.

:meth:`gtmodel.robots.closure.ClosureModel.fk_newton` solves the closure equations
``|A_ij - B_ij|^2 = L_ij^2`` (Dressler (2012), eq. 4.14) for the plate pose ``x = (T, r)`` by
Newton's method. Where their Jacobian is rank-deficient (an arm whose links coincide, as a
free-B0 six-link calibration leaves them: each link's least-squares problem is the same
function of the same data), Newton's full steps along the undetermined directions are set by
rounding, e.g. by the BLAS kernel that calibrated the parameters; here the rank is decided
relative to the largest singular value and the pose is the solution nearest to the start.
Poses are the columns of ``x`` and ``par = (q, p, vec(R0))``, as in ``fk_newton``.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._arrays import as_rows

__all__ = ["POSE_RANK_RTOL", "closure_inverse_condition"]

#: Rank decision of the closure Jacobian: singular values below this fraction of the largest are
#: directions the equations do not determine. Well-posed Gantry-Tau models have condition ~20 (the
#: D1 six-link: 19); an arm whose links coincide gives 1e9-1e15.
POSE_RANK_RTOL = 1e-8


def jacobian_function(residual: ca.Function) -> ca.Function:
    """``J(x, par)``: the Jacobian of ``residual(x, par)`` with respect to ``x`` (internal)."""
    x, par = residual.sx_in()
    return ca.Function("pose_residual_jacobian", [x, par], [ca.jacobian(residual(x, par), x)])


def _stacked(jac: ca.Function, x: np.ndarray, par: np.ndarray) -> np.ndarray:
    n = x.shape[1]
    J = np.array(jac.map(n)(x, par))
    return J.reshape(J.shape[0], n, x.shape[0]).transpose(1, 0, 2)


def inverse_condition(jac: ca.Function, x: np.ndarray, par: np.ndarray) -> np.ndarray:
    """Per pose: smallest over largest singular value of ``jac`` (internal; 0 where not finite)."""
    J = _stacked(jac, x, par)
    ok = np.all(np.isfinite(J), axis=(1, 2))
    out = np.zeros(J.shape[0])
    if ok.any():
        sv = np.linalg.svd(J[ok], compute_uv=False)
        out[ok] = sv[:, -1] / sv[:, 0]
    return out


def min_norm_gauss_newton(residual: ca.Function, jac: ca.Function, x0: np.ndarray, par: np.ndarray, max_iter: int, tol: float) -> np.ndarray:
    """Gauss-Newton with minimum-norm steps ``-pinv(J) r`` (singular values below
    :data:`POSE_RANK_RTOL` times the largest dropped) from ``x0`` until ``max |r| <= tol``
    (internal): the iterate moves only in the determined directions and stops at the solution
    nearest to the start in ``(T [m], r [rad])``."""
    x = np.array(x0, dtype=float)
    n = x.shape[1]
    res_n = residual.map(n)
    for _ in range(int(max_iter)):
        r = np.array(res_n(x, par))
        if not np.all(np.isfinite(r)) or np.all(np.abs(r) <= tol):
            break
        dx = -np.einsum("kij,jk->ik", np.linalg.pinv(_stacked(jac, x, par), rcond=POSE_RANK_RTOL), r)
        x = x + dx
        if np.all(np.abs(dx) <= 1e-15 * (1.0 + np.abs(x))):
            break
    return x


def closure_inverse_condition(model: Any, q: np.typing.ArrayLike, T: np.typing.ArrayLike, R: np.typing.ArrayLike) -> np.ndarray:
    """How well a closure model's equations determine the pose: ``sigma_min / sigma_max`` of their Jacobian.

    The Jacobian of the closure residuals ``|A - B|^2 - L^2`` (Dressler (2012), eq. 4.14)
    with respect to ``T`` and, for models with orientation, a rotation vector about ``R``.
    Below :data:`POSE_RANK_RTOL`: a direction the equations do not determine.

    Parameters
    ----------
    model : gtmodel.robots.closure.ClosureModel
        The model.
    q : array_like, shape (n_q,) or (N, n_q)
        Actuator values [m, rad].
    T : array_like, shape (3,) or (N, 3)
        TCP positions [m].
    R : array_like, shape (3, 3) or (N, 3, 3)
        Plate orientations.

    Returns
    -------
    numpy.ndarray, shape (N,)
        The inverse condition number per pose (1: perfectly conditioned, 0: singular or not finite).

    Raises
    ------
    InputError
        If ``q`` has the wrong shape.
    """
    qa, _ = as_rows(q, "q", model.n_q)
    N = qa.shape[0]
    x = np.zeros((model.pose_unknowns(), N))
    x[:3] = np.broadcast_to(np.asarray(T, dtype=float), (N, 3)).T
    Ra = np.broadcast_to(np.asarray(R, dtype=float), (N, 3, 3))
    par = np.vstack([qa.T, np.repeat(model.parameter_vector()[:, None], N, axis=1), Ra.transpose(0, 2, 1).reshape(N, 9).T])
    return inverse_condition(model._pose_residual_jacobian, x, par)
