"""The workspace test shared by the Gantry-Tau models: reach, actuator ranges, joint angles.

One implementation of the limits part of every model's ``in_workspace``
(:meth:`GantryTau3Kinematics.in_workspace <gtmodel.robots.kinematics.GantryTau3Kinematics.in_workspace>`,
:meth:`SixLinkClosure.in_workspace <gtmodel.robots.six_link.SixLinkClosure.in_workspace>`,
:meth:`F1Closure.in_workspace <gtmodel.robots.f1.F1Closure.in_workspace>`), Dressler (2012),
ch. 5.5: every link reaches its guideway (the IK discriminant is not negative), every
actuator value lies in its range (cart travel, joint-plate angles), and every link makes at
most the largest joint angle with its guideway.
"""

from __future__ import annotations

import numpy as np

__all__ = ["in_ranges", "within_limits"]


def in_ranges(q: np.ndarray, ranges: np.ndarray) -> np.ndarray:
    """Whether every actuator value lies in its range (bounds included).

    Parameters
    ----------
    q : numpy.ndarray, shape (N, n)
        Actuator values [m or rad].
    ranges : numpy.ndarray, shape (n, 2)
        Row i is ``(min, max)`` of actuator i.

    Returns
    -------
    numpy.ndarray of bool, shape (N,)
    """
    return np.all((q >= ranges[:, 0]) & (q <= ranges[:, 1]), axis=1)


def within_limits(
    q: np.ndarray,
    disc: np.ndarray,
    cos: np.ndarray | None = None,
    cart_travel: np.ndarray | None = None,
    joint_angle_max: float | None = None,
) -> np.ndarray:
    """The workspace test: reach, cart travel and link-guideway angle per pose.

    Parameters
    ----------
    q : numpy.ndarray, shape (N, n_arms)
        Cart positions [m].
    disc : numpy.ndarray, shape (N, n_links)
        IK discriminants [m^2] (negative: the link cannot reach its guideway).
    cos : numpy.ndarray, shape (N, n_links), optional
        Cosines of the angles between each link and its guideway; needed with
        ``joint_angle_max``.
    cart_travel : numpy.ndarray, shape (n_arms, 2), optional
        ``(q_min, q_max)`` per cart [m]; None: no travel test.
    joint_angle_max : float, optional
        Largest angle [rad] of a link to its guideway, tested as ``|cos| >=
        cos(joint_angle_max)``; None: no angle test.

    Returns
    -------
    numpy.ndarray of bool, shape (N,)
        True where every link reaches and the limits hold.
    """
    ok = np.all(disc >= 0, axis=1)
    if cart_travel is not None:
        ok &= in_ranges(q, cart_travel)
    if joint_angle_max is not None:
        ok &= np.all(np.abs(cos) >= np.cos(joint_angle_max), axis=1)
    return ok
