"""The tool-force contact loop linearised: poles, oscillation frequency, largest stable gain.

In contact the motion along the normal is set by the tool force P controller alone (eqs.
8.4, 8.9: the handle's normal component is projected out, eq. 8.8). Linearised about a
steady contact, along the normal:

* the controller: ``v_ref(k) = K_n (f_ref - f(k))`` with ``K_n = n^T K n``, sampled every ``dt``;
* the servo: the velocity ``v`` follows ``v_ref`` (applied ``delay_samples`` later) as a
  first-order lag of bandwidth ``w_s``, exact under a zero-order hold;
* the penetration ``delta`` integrates ``v``; the contact force ``f = k delta + d v``.

The discrete state ``[delta, v]`` (and the delayed reference with ``delay_samples = 1``)
gives the closed-loop matrix whose eigenvalues are the loop's poles; the dominant pair's
angle gives the oscillation frequency ``|arg z| / (2 pi dt)`` the simulation shows when the
loop rings (Dressler (2012), Figure 8.5: 68 Hz on the metal plate). Surface noise aside,
what grows the oscillation with the correction range ``phi_L`` is the noisy normal estimate
(eq. 8.10) leaking the operator's tangential motion into the normal direction: the loop's
input, not its poles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gtmodel._arrays import finite_float
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.estimation.lead_through.simulation import Servo

__all__ = ["ContactLoop", "contact_loop", "largest_stable_gain"]




@dataclass(frozen=True)
class ContactLoop:
    """The linearised contact loop along the normal.

    Parameters
    ----------
    A : numpy.ndarray, shape (n, n)
        Closed-loop transition matrix (state ``[delta, v]``, plus the delayed reference).
    poles : numpy.ndarray of complex, shape (n,)
        Its eigenvalues, largest magnitude first.
    dt : float
        Sample time [s].
    """

    A: np.ndarray
    poles: np.ndarray
    dt: float

    @property
    def spectral_radius(self) -> float:
        """Largest pole magnitude (below 1: stable)."""
        return float(np.abs(self.poles[0]))

    @property
    def stable(self) -> bool:
        """True when every pole lies inside the unit circle."""
        return self.spectral_radius < 1.0

    @property
    def frequency_hz(self) -> float:
        """Oscillation frequency of the dominant complex pole [Hz] (0 for a real one)."""
        z = self.poles[0]
        return float(abs(np.angle(z)) / (2 * math.pi * self.dt))

    @property
    def damping_ratio(self) -> float:
        """Damping ratio of the dominant pole (from ``s = log(z) / dt``)."""
        s = np.log(complex(self.poles[0])) / self.dt
        return float(-s.real / max(abs(s), 1e-300))


def contact_loop(gain: float, stiffness: float, damping: float = 0.0, servo: Servo | None = None, dt: float = LOOP_PERIOD_S) -> ContactLoop:
    """The contact loop along the normal, linearised (see the module).

    Parameters
    ----------
    gain : float
        Force gain along the normal ``K_n`` [m/(N s)], non-negative.
    stiffness : float
        Contact stiffness [N/m], positive.
    damping : float, optional
        Contact damping [N s/m], non-negative.
    servo : Servo, optional
        Bandwidth and delay (default :class:`~gtmodel.estimation.lead_through.simulation.Servo`).
    dt : float, optional
        Sample time [s].

    Returns
    -------
    ContactLoop

    Raises
    ------
    InputError
        A negative gain or damping, a stiffness or ``dt`` that is not positive.
    """
    K = finite_float(gain, "gain", "m/(N s)", nonnegative=True)
    k = finite_float(stiffness, "stiffness", "N/m", positive=True)
    d = finite_float(damping, "damping", "N s/m", nonnegative=True)
    dt = finite_float(dt, "dt", "s", positive=True)
    servo = Servo() if servo is None else servo
    ws = 2 * math.pi * servo.bandwidth_hz
    e = math.exp(-ws * dt)
    g = (1.0 - e) / ws
    A0 = np.array([[1.0, g], [0.0, e]])
    B = np.array([dt - g, 1.0 - e])
    C = np.array([-K * k, -K * d])  # v_ref = K (f_ref - k delta - d v), deviations
    if servo.delay_samples == 0:
        A = A0 + np.outer(B, C)
    else:
        A = np.zeros((3, 3))
        A[:2, :2], A[:2, 2], A[2, :2] = A0, B, C
    poles = np.linalg.eigvals(A)
    order = np.lexsort((-np.abs(np.imag(poles)), -np.abs(poles)))
    return ContactLoop(A=A, poles=poles[order], dt=dt)


def largest_stable_gain(stiffness: float, damping: float = 0.0, servo: Servo | None = None, dt: float = LOOP_PERIOD_S,
                        upper: float = 10.0, rtol: float = 1e-6) -> float:
    """The largest force gain ``K_n`` [m/(N s)] for which the contact loop is stable (bisection).

    Parameters
    ----------
    stiffness : float
        Contact stiffness [N/m].
    damping : float, optional
        Contact damping [N s/m].
    servo : Servo, optional
        Bandwidth and delay.
    dt : float, optional
        Sample time [s].
    upper : float, optional
        Upper end of the search [m/(N s)] (returned when still stable there).
    rtol : float, optional
        Relative accuracy of the bisection.

    Returns
    -------
    float

    Raises
    ------
    InputError
        Bad loop arguments (see :func:`contact_loop`).
    """
    lo, hi = 0.0, float(upper)
    if contact_loop(hi, stiffness, damping, servo, dt).stable:
        return hi
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if contact_loop(mid, stiffness, damping, servo, dt).stable else (lo, mid)
    return lo
