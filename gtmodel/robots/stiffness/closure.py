"""Stiffness of any closure model by condensation (:func:`closure_stiffness`, the six-link geometry included)."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._geometry import rotation_vector_to_rotation
from gtmodel.errors import InputError, UnreachablePoseError
from gtmodel.robots.closure import ClosureModel
from gtmodel.robots.stiffness.parameters import StiffnessParameters, load_stiffness

__all__ = ["ClosureStiffness", "closure_stiffness"]


# ----------------------------------------------------------------------------- any closure model
@dataclass
class ClosureStiffness:
    """Stiffness of a closure model at one pose, with the carts condensed out.

    Parameters
    ----------
    T : numpy.ndarray, shape (3,)
        TCP position [m].
    R : numpy.ndarray, shape (3, 3)
        Plate orientation.
    K : numpy.ndarray, shape (6, 6) or (3, 3)
        Stiffness in the plate coordinates ``(dT, dr)`` (position [m], rotation vector
        [rad]; units N/m, N, N m/rad), carts condensed; (3, 3) for a constant-orientation
        model.
    K_locked : numpy.ndarray, shape (3, 3)
        Translational stiffness with the plate rotation held (the 3-link model's assumption)
        [N/m].
    K_free : numpy.ndarray, shape (3, 3)
        Translational stiffness for a force at the TCP with the plate free to rotate
        (rotation condensed out) [N/m]; equals ``K_locked`` for a constant-orientation model.
    k_links : numpy.ndarray, shape (n_links,)
        Axial stiffness of each closure link [N/m].
    """

    T: np.ndarray
    R: np.ndarray
    K: np.ndarray
    K_locked: np.ndarray
    K_free: np.ndarray
    k_links: np.ndarray


def closure_stiffness(model: ClosureModel, q: np.typing.ArrayLike, stiffness: StiffnessParameters | None = None) -> ClosureStiffness:
    """Static stiffness of any 3-actuator closure model (3-link or six-link), by condensation.

    The link lengths ``l_j = |A_j(q + sigma) - (T + Rot(r) R_T B0_j)|`` are differentiated
    (CasADi, the model's own :meth:`~gtmodel.robots.closure.ClosureModel.link_points`) with
    respect to the plate displacement ``x = (dT, r)`` and the cart displacements ``sigma``
    along the guideways, giving the compatibility matrix ``C = dl / d(x, sigma)``. With link
    stiffnesses ``k_l`` (tube ``E A / L_j`` in series with two joints; a 3-link model's link
    is a cluster of ``n_i`` links in parallel) and actuator stiffnesses ``k_a |dA/dq_i|^2``::

        K_full = C^T diag(k_l) C + diag(0, k_a),
        K      = K_xx - K_xs K_ss^-1 K_sx           (carts condensed)
        K_free = K_TT - K_Tr K_rr^-1 K_rT           (plate rotation condensed).

    For the 3-link model ``K`` reproduces eq. (1) with the series arm compliance (2) of the
    module docstring; for the six-link model (Dressler (2012), eq. 4.14) it adds the plate's
    rotational compliance that the translational model leaves out.

    Parameters
    ----------
    model : ClosureModel
        A model with 3 linear actuators (:class:`~gtmodel.robots.closure.ThreeLinkClosure`,
        :class:`~gtmodel.robots.six_link.SixLinkClosure`).
    q : array_like, shape (3,)
        Cart positions [m].
    stiffness : StiffnessParameters, optional
        Stiffness values (default: the shipped file).

    Returns
    -------
    ClosureStiffness

    Raises
    ------
    InputError
        A model with other than 3 actuators or arms, a link count per arm that matches
        neither 1 nor ``links_per_arm``, or a wrong ``q``.
    UnreachablePoseError
        The model cannot assemble at ``q``.
    """
    if not isinstance(model, ClosureModel) or model.n_q != 3 or len(model.links) != 3:
        raise InputError(f"model: expected a closure model with 3 linear actuators, got {getattr(model, 'name', model)!r}")
    qa = np.asarray(q, dtype=float)
    if qa.shape != (3,) or not np.all(np.isfinite(qa)):
        raise InputError(f"q: expected 3 finite cart positions [m], got {q!r}")
    st = load_stiffness("stiffness" if stiffness is None else stiffness)
    T0, R0 = model.fk(qa)
    T0, R0 = np.asarray(T0, float).reshape(3), np.asarray(R0, float).reshape(3, 3)
    p = ca.DM(model.parameter_vector())
    dT = ca.SX.sym("dT", 3)
    r = ca.SX.sym("r", 3)
    sig = ca.SX.sym("sigma", 3)
    qs = ca.SX.sym("q", 3)
    R = ca.mtimes(rotation_vector_to_rotation(r), ca.DM(R0))
    lengths, rest, k_links, k_act = [], [], [], []
    for arm, names in enumerate(model.links):
        n_arm = len(names)
        if n_arm == 1:
            n_par = int(st.links_per_arm[arm])
        elif n_arm == int(st.links_per_arm[arm]):
            n_par = 1
        else:
            raise InputError(f"{model.name}: arm {arm + 1} has {n_arm} links; expected 1 or {int(st.links_per_arm[arm])} (links_per_arm)")
        A, B, L = model.link_points(p, qs + ca.vertcat(*[sig[i] if i == arm else 0 for i in range(3)]), ca.DM(T0) + dT, R, arm)
        D = A - B
        lengths.append(ca.sqrt(ca.sum1(D * D)).T)
        Ln = np.array(ca.evalf(ca.substitute(L, qs, ca.DM(qa)))).reshape(-1)
        rest.append(Ln)
        k_links.append(n_par / (Ln / (st.E * st.link_area) + st.joints_per_link / st.k_joint))
        dA = ca.jacobian(A[:, 0], qs)[:, arm]
        k_act.append(st.k_actuator[arm] * float(ca.evalf(ca.substitute(ca.sumsqr(dA), qs, ca.DM(qa)))))
    ell = ca.vertcat(*lengths)
    orient = bool(model.orientation)
    x = ca.vertcat(dT, r) if orient else dT
    C_fun = ca.Function("C", [dT, r, sig, qs], [ca.jacobian(ell, ca.vertcat(x, sig)), ell])
    C, ell0 = (np.array(v) for v in C_fun(np.zeros(3), np.zeros(3), np.zeros(3), qa))
    if np.max(np.abs(ell0.ravel() - np.concatenate(rest))) > 1e-6:
        raise UnreachablePoseError(f"{model.name}: the model does not assemble at q = {qa.tolist()} (closure residual above 1 um)")
    kl = np.concatenate(k_links)
    Kf = C.T @ np.diag(kl) @ C
    nx = x.shape[0]
    Kf[nx:, nx:] += np.diag(k_act)
    Kxx, Kxs, Kss = Kf[:nx, :nx], Kf[:nx, nx:], Kf[nx:, nx:]
    K = Kxx - Kxs @ np.linalg.solve(Kss, Kxs.T)
    K = 0.5 * (K + K.T)
    if orient:
        KTT, KTr, Krr = K[:3, :3], K[:3, 3:], K[3:, 3:]
        K_free = KTT - KTr @ np.linalg.solve(Krr, KTr.T)
        K_locked = KTT
    else:
        K_free = K_locked = K
    return ClosureStiffness(T0, R0, K, K_locked, 0.5 * (K_free + K_free.T), kl)
