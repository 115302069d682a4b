"""Discrete LQR gains, and the gain at rest a loop can trust in the rest point's neighbourhood.

:func:`dlqr` (time-invariant) and :func:`riccati_gains` (the backward recursion along a
reference) are the LQR designs of :mod:`gtmodel.control.tracking`.

A model at rest is linearised where its smooth friction and backlash change their slope
most: a Coulomb friction regularised over a band of speeds ``dv`` has its steepest slope,
``F_c / dv``, at zero speed, which the Jacobian there reads as a large viscous damping; a
smoothed backlash reads half its stiffness at zero stretch. An LQR designed on that Jacobian
alone relies on the band: the first disturbance that carries the speed out of it removes the
damping the gain was computed with, and the loop can be unstable there (a belt drive's held
end: closed-loop spectral radius 0.73 at the rest point, 1.31 a tenth of the load speed's
range away; in the closed loop a limit cycle of 16 A around the end position).
:func:`rest_linearization` therefore linearises the step also at the rest state moved by
:data:`~gtmodel.defaults.REST_NEIGHBOURHOOD` of each state's range, either way, one state at a
time, and keeps the rest point's own linearisation when its LQR gain is stable on every one of
them (:func:`closed_loop_radius`, with the input delay the law compensates); otherwise it takes
the linearisation whose LQR gain is stable on all of them with the least largest spectral radius, if
one is (a gear drive's end, a tenth of its motor speed's range away, 47 rad/s through its backlash,
left every candidate above 1: its own is kept) (a
robust choice among the sampled models; the multi-model view of Boyd & Barratt, *Linear
Controller Design: Limits of Performance*, ch. 10, by enumeration instead of an LMI).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg

from gtmodel.defaults import REST_NEIGHBOURHOOD
from gtmodel.errors import InputError

__all__ = ["dlqr", "riccati_gains", "closed_loop_radius", "RestLinearization", "rest_linearization", "rest_groups"]


def dlqr(A: Any, B: Any, Q: Any, R: Any) -> tuple[np.ndarray, np.ndarray]:
    """Time-invariant discrete LQR: the gain of ``u = -K x`` minimising ``sum x'Qx + u'Ru``.

    The stationary solution of the discrete algebraic Riccati equation (Anderson & Moore, *Optimal Control: Linear
    Quadratic Methods*, sec. 2.4), as python-control's ``dlqr``.

    Parameters
    ----------
    A : array_like
        ``(nx, nx)`` state matrix of ``x_{k+1} = A x_k + B u_k``.
    B : array_like
        ``(nx, nu)`` input matrix.
    Q : array_like
        ``(nx, nx)`` state weight, symmetric positive semi-definite.
    R : array_like
        ``(nu, nu)`` input weight, symmetric positive definite.

    Returns
    -------
    K : numpy.ndarray
        ``(nu, nx)`` gain, ``K = (R + B'PB)^{-1} B'PA``.
    P : numpy.ndarray
        ``(nx, nx)`` stabilising solution of the discrete algebraic Riccati equation
        (:func:`scipy.linalg.solve_discrete_are`).

    Raises
    ------
    InputError
        Inconsistent shapes, or no stabilising solution (the pair is not stabilisable).
    """
    A, B, Q, R = (np.atleast_2d(np.asarray(v, dtype=float)) for v in (A, B, Q, R))
    nx, nu = B.shape
    if A.shape != (nx, nx) or Q.shape != (nx, nx) or R.shape != (nu, nu):
        raise InputError(f"dlqr: expected A ({nx}, {nx}), B ({nx}, {nu}), Q ({nx}, {nx}), R ({nu}, {nu}); "
                         f"got {A.shape}, {B.shape}, {Q.shape}, {R.shape}")
    try:
        P = scipy.linalg.solve_discrete_are(A, B, Q, R)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise InputError(f"dlqr: no stabilising solution of the Riccati equation ({exc})") from None
    K = np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)
    return K, P


def riccati_gains(A: np.ndarray, B: np.ndarray, Q: np.ndarray, R: np.ndarray, Qf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Time-varying LQR gains by the backward discrete Riccati recursion (Anderson & Moore, sec. 2.4).

    Parameters
    ----------
    A : numpy.ndarray
        ``(N, nx, nx)`` state matrices ``A_k``.
    B : numpy.ndarray
        ``(N, nx, nu)`` input matrices ``B_k``.
    Q : numpy.ndarray
        ``(nx, nx)`` stage state weight.
    R : numpy.ndarray
        ``(nu, nu)`` input weight (positive definite).
    Qf : numpy.ndarray
        ``(nx, nx)`` terminal weight ``P_N``.

    Returns
    -------
    K : numpy.ndarray
        ``(N, nu, nx)`` gains, ``K_k = (R + B_k' P_{k+1} B_k)^{-1} B_k' P_{k+1} A_k``.
    P : numpy.ndarray
        ``(N + 1, nx, nx)`` cost-to-go matrices, ``P_k = Q + A_k' P_{k+1} (A_k - B_k K_k)``
        (symmetrised).
    """
    n, nx, nu = B.shape
    K = np.zeros((n, nu, nx))
    P = np.zeros((n + 1, nx, nx))
    P[n] = Qf
    for k in range(n - 1, -1, -1):
        Pk = P[k + 1]
        K[k] = np.linalg.solve(R + B[k].T @ Pk @ B[k], B[k].T @ Pk @ A[k])
        Pn = Q + A[k].T @ Pk @ (A[k] - B[k] @ K[k])
        P[k] = 0.5 * (Pn + Pn.T)
    return K, P


def closed_loop_radius(K: np.ndarray, A: np.ndarray, B: np.ndarray, delay: int = 0) -> float:
    """Spectral radius of ``u = -K x`` on ``x_{k+1} = A x_k + B u_k``, with the law's input delay.

    The closed loop's state matrix, its eigenvalues by :func:`numpy.linalg.eigvals` (a discrete loop is asymptotically
    stable iff all lie inside the unit circle; Franklin, Powell & Workman, *Digital Control of Dynamic Systems*, sec. 4.4).

    Parameters
    ----------
    K : numpy.ndarray
        ``(nu, nx)`` gain.
    A : numpy.ndarray
        ``(nx, nx)`` state matrix.
    B : numpy.ndarray
        ``(nx, nu)`` input matrix.
    delay : {0, 1}, optional
        0: ``A - B K``. 1: the input computed at ``t_k`` acts from ``t_{k+1}`` and the law
        predicts the state then with the same model (:attr:`TrackingController.delay
        <gtmodel.control.tracking.TrackingController.delay>`): ``u_k = -K (A x_k + B u_{k-1})``,
        the state ``(x_k, u_{k-1})`` with ``[[A, B], [-K A, -K B]]``.

    Returns
    -------
    float
        The largest eigenvalue magnitude (below 1: asymptotically stable).
    """
    if delay:
        M = np.block([[A, B], [-K @ A, -K @ B]])
    else:
        M = A - B @ K
    return float(np.max(np.abs(np.linalg.eigvals(M))))


@dataclass(frozen=True)
class RestLinearization:
    """The linearisation a rest point's gains are designed on (:func:`rest_linearization`).

    Parameters
    ----------
    A : numpy.ndarray
        ``(nx, nx)`` the chosen state matrix (the rest point's own, or a neighbour's).
    B : numpy.ndarray
        ``(nx, nu)`` its input matrix.
    radius_own : float
        The largest closed-loop spectral radius over the neighbourhood's linearisations of the
        LQR gain of the rest point's own linearisation (``inf``: that pair not stabilisable).
    radius : float
        The same of the chosen linearisation's gain (``radius_own`` when the rest point's own is kept).
    moved : str
        Where the chosen linearisation was taken: ``""`` the rest point itself, else e.g.
        ``"load.v + 0.357"`` (the state and its displacement).
    """

    A: np.ndarray
    B: np.ndarray
    radius_own: float
    radius: float
    moved: str = ""


def rest_linearization(jacobians: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]], x: np.ndarray, scale: np.ndarray,
                       Q: np.ndarray, R: np.ndarray, delay: int = 0, names: list[str] | None = None,
                       fraction: float = REST_NEIGHBOURHOOD) -> RestLinearization:
    """The linearisation at rest whose LQR gain holds the rest point's neighbourhood (module docstring).

    Parameters
    ----------
    jacobians : callable
        ``jacobians(x (nx,)) -> (A, B)``: the Jacobians of the model's one-period step at state ``x``
        and the input that holds the rest point (augmented by the law's integrators, if any).
    x : numpy.ndarray
        ``(nx,)`` the rest state.
    scale : numpy.ndarray
        ``(nx,)`` the states' scales (their ranges along the reference,
        :func:`~gtmodel.control.reference.reference_scales`); the neighbours are ``x +- fraction scale_i e_i``.
    Q : numpy.ndarray
        ``(n, n)`` the LQR's state weight (``n`` the rows of ``A``: ``nx`` and the integrators).
    R : numpy.ndarray
        ``(nu, nu)`` its input weight.
    delay : {0, 1}, optional
        The input delay the law compensates (:func:`closed_loop_radius`).
    names : list of str, optional
        ``(nx,)`` the states' names for :attr:`RestLinearization.moved` (default ``x[i]``).
    fraction : float, optional
        The neighbourhood's size over each state's scale (default :data:`~gtmodel.defaults.REST_NEIGHBOURHOOD`).

    Returns
    -------
    RestLinearization
        The rest point's own linearisation when its gain's largest radius over the neighbours is below 1, or when no
        neighbour's gain brings it below 1; else the neighbour's whose gain has the least largest radius.
    """
    x = np.asarray(x, dtype=float)
    points, labels = [x], [""]
    for i in range(x.size):
        for sign in (-1.0, 1.0):
            d = sign * fraction * float(scale[i])
            if d != 0.0:
                points.append(x + d * np.eye(x.size)[i])
                labels.append(f"{names[i] if names else f'x[{i}]'} {'+' if d > 0 else '-'} {abs(d):.3g}")
    pairs = [tuple(np.asarray(m, dtype=float) for m in jacobians(p)) for p in points]

    def worst(j: int) -> float:
        try:
            K = dlqr(*pairs[j], Q, R)[0]
        except InputError:
            return float("inf")
        return max(closed_loop_radius(K, A, B, delay) for A, B in pairs)

    own = worst(0)
    if own < 1.0:
        return RestLinearization(*pairs[0], radius_own=own, radius=own)
    radii = [own] + [worst(j) for j in range(1, len(pairs))]
    best = int(np.argmin(radii))
    if radii[best] >= 1.0:  # no neighbour's gain holds them all: the rest point's own (the loop may still hold it)
        return RestLinearization(*pairs[0], radius_own=own, radius=own)
    return RestLinearization(*pairs[best], radius_own=own, radius=radii[best], moved=labels[best])


def rest_groups(x_ref: np.ndarray, scale: np.ndarray, tol: float = 1e-9) -> list[tuple[int, int]]:
    """The runs of samples where a reference rests: ``[(start, stop), ...]``, ``x_ref[start:stop]`` one state.

    Parameters
    ----------
    x_ref : numpy.ndarray
        ``(N, nx)`` the sampled reference.
    scale : numpy.ndarray
        ``(nx,)`` the states' scales.
    tol : float, optional
        The largest change of a state over a period, over its scale, counted as rest (default 1e-9).

    Returns
    -------
    list of tuple of int
        The runs of at least two samples whose states stay within ``tol`` of the run's first.
    """
    x_ref = np.asarray(x_ref, dtype=float)
    n = x_ref.shape[0]
    s = np.where(np.asarray(scale, dtype=float) > 0, scale, 1.0)
    groups, k = [], 0
    while k < n:
        stop = k + 1
        while stop < n and np.all(np.abs(x_ref[stop] - x_ref[k]) <= tol * s):
            stop += 1
        if stop - k >= 2:
            groups.append((k, stop))
        k = stop
    return groups
