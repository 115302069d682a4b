"""The inverse question: the largest tolerances that keep the worst TCP error under a bound.

Kim and Choi (2000)'s inverse error-bound analysis, as Dressler (2012), ch. 4.3 names it:
given the shape of each arm's tolerance (the ellipsoid and link tolerance of a
:class:`~gtmodel.calibration.accuracy.tolerances.Tolerances`) and a TCP error bound
``e_max``, find per-arm factors ``k_i`` of the largest tolerance volume (``max sum log k_i``)
with the worst case at every analysed pose at most ``e_max``. With the parallelepiped
(A.4, exact to first order) the worst case at pose ``p`` is ``max_s |U_p^-1 (s * k * h_p)|``,
so the problem is convex: ``|G_ps k| <= e_max`` for the four diagonal sign vectors ``s``
(a CasADi NLP solved by IPOPT, constraints added where violated). The answer is then checked
with the exact worst-case NLP at the poses where it is tightest and scaled down by the
second-order excess, if any. The uniform answer (one factor for all arms) is given too.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from gtmodel.calibration.accuracy.exact import worst_case
from gtmodel.calibration.accuracy.geometric import CORNER_SIGNS, support_half_widths
from gtmodel.calibration.accuracy.tolerances import NominalPoses, Tolerances
from gtmodel.errors import InputError
from gtmodel.status import Status

__all__ = ["InverseResult", "largest_tolerances"]

#: Most cutting-plane rounds of the inverse NLP.
_MAX_ROUNDS = 20
#: Poses checked with the exact NLP after the convex solve.
_EXACT_CHECKS = 3


@dataclass(frozen=True)
class InverseResult:
    """Largest tolerances for a TCP error bound.

    Parameters
    ----------
    tcp_error : float
        The bound ``e_max`` [m].
    factors : numpy.ndarray, shape (3,)
        Per-arm factors ``k_i`` on the declared tolerances (largest volume).
    tolerances : Tolerances
        The declared tolerances scaled by ``factors``.
    uniform_factor : float
        The largest single factor on all arms.
    exact_worst : float
        Exact worst case [m] with ``tolerances`` at the tightest checked pose (<= ``tcp_error``).
    tightest_pose : numpy.ndarray, shape (3,)
        That pose [m].
    status : str
        ``"optimal"`` or the IPOPT failure.
    """

    tcp_error: float
    factors: np.ndarray
    tolerances: Tolerances
    uniform_factor: float
    exact_worst: float
    tightest_pose: np.ndarray
    status: str


def _linear_worst(G: np.ndarray, k: np.ndarray) -> np.ndarray:
    """``max_s |G_ps k|`` per pose, G of shape (N, 4, 3, 3)."""
    return np.linalg.norm(np.einsum("nsxi,i->nsx", G, k), axis=2).max(axis=1)


def largest_tolerances(nominal: NominalPoses, shape: Tolerances, tcp_error: float) -> InverseResult:
    """Per-arm factors of the largest tolerance volume with the worst case under ``tcp_error``.

    Parameters
    ----------
    nominal : NominalPoses
        The poses the bound must hold at (e.g. a workspace section), N >= 1.
    shape : Tolerances
        The shape of every arm's tolerance (scaled by the factors).
    tcp_error : float
        The TCP error bound [m], positive.

    Returns
    -------
    InverseResult

    Raises
    ------
    InputError
        ``tcp_error`` not a positive finite number.
    """
    if not (isinstance(tcp_error, (int, float)) and np.isfinite(tcp_error) and tcp_error > 0):
        raise InputError(f"tcp_error: expected a positive TCP error bound in m, got {tcp_error!r}")
    h = support_half_widths(nominal, shape)  # (N, 3)
    Uinv = np.linalg.inv(nominal.u)
    G = np.einsum("nxi,si,ni->nsxi", Uinv, CORNER_SIGNS[:4], h)  # corners j and 7-j are opposite
    worst_ref = _linear_worst(G, np.ones(3))
    uniform = float(tcp_error / worst_ref.max())
    kvar = ca.MX.sym("k", 3)
    active = list(np.argsort(-worst_ref)[:5])
    k = np.full(3, uniform)
    status = Status.OPTIMAL.value
    for _ in range(_MAX_ROUNDS):
        Gs = G[active].reshape(-1, 3, 3)
        g = ca.vertcat(*[ca.sumsqr(ca.DM(Gi) @ kvar) for Gi in Gs]) / tcp_error**2
        solver = ca.nlpsol("inverse", "ipopt", {"x": kvar, "f": -ca.sum1(ca.log(kvar)), "g": g},
                           {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.tol": 1e-12})
        sol = solver(x0=k, lbx=1e-9, ubx=np.inf, lbg=-np.inf, ubg=1.0)
        if not solver.stats()["success"]:
            status = Status.ERROR.value
            break
        k = np.array(sol["x"]).ravel()
        lw = _linear_worst(G, k)
        viol = [int(n) for n in np.argsort(-lw)[:5] if lw[n] > tcp_error * (1 + 1e-9) and n not in active]
        if not viol:
            break
        active += viol
    scaled = shape.scaled(k)
    lw = _linear_worst(G, k)
    exact = 0.0
    tight = 0
    for n in np.argsort(-lw)[:_EXACT_CHECKS]:
        e = worst_case(nominal, int(n), scaled, corner_starts_used=1, random_starts=0).error
        if e > exact:
            exact, tight = e, int(n)
    if exact > tcp_error:  # second-order excess of the exact set over the parallelepiped
        k = k * tcp_error / exact
        scaled = shape.scaled(k)
        exact = worst_case(nominal, tight, scaled, corner_starts_used=1, random_starts=0).error
        uniform *= tcp_error / exact
    return InverseResult(float(tcp_error), k, scaled, uniform, exact, nominal.T[tight].copy(), status)
