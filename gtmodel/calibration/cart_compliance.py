"""A load-dependent cart error: each cart yields across its guideway under its arm's gravity force.

Dressler (2012) saw the carts move with the load the links put on them: on the L1 "the measured
cart position varied up to 100 um" with the end-effector's position across the guideways (section
4.3, Fig. 4.5: "small load changes caused by a redistribution of the gravity force may give rise to
substantial deviations from the actuator model"); on the D1 actuator 2's measured position "varied
significantly for different link angles ... lacking stiffness, which causes the cart to move with
a changed load from the links" (section 5.3), and the arms with fewer links, the less stiff ones,
keep the larger final costs (Table 5.8: arm 1 > 2 > 3). None of it is modelled by the kinematic
error models 1-5, so it stays in their residuals.

The model here, per arm ``i`` (first order in the displacement):

- the arm force under the plate's weight, ``f_i`` (:meth:`GantryTau3Stiffness.link_forces`, eq. 3),
  along the unit vector ``u_i`` from the cart's point ``A_i + q_i v_i`` to the TCP;
- the cart moves by ``d_i = c_i (I - v_i v_i^T) f_i u_i``: its compliance ``c_i`` [m/N] times the
  force component across the guideway ``v_i``;
- the TCP moves by ``dT`` with ``u_i . dT = u_i . d_i`` (each arm's length unchanged, the plate
  orientation unchanged), i.e. ``dT = U^-1 [u_i . d_i]``.

The compliances are not printed anywhere: :mod:`gtmodel.report.fidelity_fits` fits them to Table 5.8.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from gtmodel._arrays import as_finite
from gtmodel.errors import InputError
from gtmodel.robots.stiffness import GantryTau3Stiffness

__all__ = ["cart_compliance_offsets", "transverse_forces"]


def _forces(parameters: Any, T: Any, q: Any) -> tuple[GantryTau3Stiffness, np.ndarray, np.ndarray, np.ndarray]:
    st = GantryTau3Stiffness(parameters)
    T = as_finite(T, "T")
    q = as_finite(q, "q")
    if T.ndim != 2 or T.shape[1] != 3 or q.ndim != 2 or q.shape[0] != T.shape[0] or q.shape[1] < 3:
        raise InputError(f"T, q: expected shapes (N, 3) and (N, >=3), got {T.shape} and {q.shape}")
    f = np.asarray(st.link_forces(T, limits=False), float)
    u = np.stack([T - (np.asarray(st.As[i], float) + q[:, i:i + 1] * np.asarray(st.v[i], float)) for i in range(3)], axis=1)
    u /= np.linalg.norm(u, axis=2, keepdims=True)
    v = np.stack([np.asarray(st.v[i], float) / np.linalg.norm(st.v[i]) for i in range(3)])
    F = f[:, :, None] * u  # (N, 3 arms, 3)
    F_perp = F - np.einsum("nij,ij->ni", F, v)[:, :, None] * v[None]
    return st, u, F_perp, v


def transverse_forces(T: Any, q: Any, parameters: Any = "D1") -> np.ndarray:
    """Each arm's gravity force on its cart across the guideway.

    Parameters
    ----------
    T : array_like, shape (N, 3)
        TCP positions [m].
    q : array_like, shape (N, 3)
        Actuator values [m].
    parameters : str or RobotParameters, optional
        The robot (plate weight, geometry; default the D1).

    Returns
    -------
    numpy.ndarray, shape (N, 3, 3)
        Per pose and arm the force vector across the guideway [N].

    Raises
    ------
    InputError
        Shapes that do not match.
    """
    return _forces(parameters, T, q)[2]


def cart_compliance_offsets(T: Any, q: Any, compliance_m_per_N: Any, parameters: Any = "D1") -> np.ndarray:
    """TCP displacement of the carts' transverse compliance (module docstring).

    Parameters
    ----------
    T : array_like, shape (N, 3)
        TCP positions of the rigid robot [m].
    q : array_like, shape (N, 3)
        Actuator values [m].
    compliance_m_per_N : array_like, shape (3,)
        Transverse compliance ``c_i`` of each cart [m/N] (>= 0).
    parameters : str or RobotParameters, optional
        The robot (default the D1).

    Returns
    -------
    numpy.ndarray, shape (N, 3)
        ``dT`` [m].

    Raises
    ------
    InputError
        A compliance that is negative or not three numbers, or shapes that do not match.
    """
    c = as_finite(compliance_m_per_N, "compliance_m_per_N")
    if c.shape != (3,) or np.any(c < 0):
        raise InputError(f"compliance_m_per_N: expected three compliances >= 0 [m/N], got {c.tolist()}")
    _, u, F_perp, _ = _forces(parameters, T, q)
    b = np.einsum("nij,nij->ni", u, c[None, :, None] * F_perp)
    return np.linalg.solve(u, b[:, :, None])[:, :, 0]
