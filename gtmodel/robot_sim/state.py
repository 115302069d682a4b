"""What a simulated robot sends and what it takes back, independent of the protocol.

:class:`RobotState` is the robot's own view of one cycle (what RSI's ``<Rob>`` and EGM's
``EgmRobot`` carry); :class:`Command` is a parsed reply as the offsets the robot applies
(RSI's ``RKorr``/``AKorr``; EGM's planned positions turned into offsets from the setpoint).
Units at this boundary are the protocols' own: mm for positions and linear axes, degrees
for angles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gtmodel.errors import GtModelError, InputError

__all__ = ["RobotState", "Command", "CORRECTION_MODES", "ReplyError", "euler_zyx_to_quaternion"]

#: How the robot applies a command: offsets summed cycle after cycle, or the offset itself.
CORRECTION_MODES = ("relative", "absolute")


@dataclass(frozen=True)
class RobotState:
    """The robot's view of one cycle (encoders and interpolator, not the true TCP).

    Parameters
    ----------
    cart_actual : numpy.ndarray, shape (6,)
        Actual Cartesian pose ``X, Y, Z`` [mm], ``A, B, C`` [deg] (KUKA's ZYX Euler angles).
    cart_setpoint : numpy.ndarray, shape (6,)
        The programmed (setpoint) pose before the sensor's correction, same units.
    joints_actual : numpy.ndarray, shape (n,)
        Actual joints [deg] (rotary) or [mm] (linear axes).
    joints_setpoint : numpy.ndarray, shape (n,)
        Setpoint joints, same units.
    """

    cart_actual: np.ndarray
    cart_setpoint: np.ndarray
    joints_actual: np.ndarray
    joints_setpoint: np.ndarray


@dataclass(frozen=True)
class Command:
    """A parsed reply: offsets from the setpoint, and how to apply them.

    Parameters
    ----------
    cart : numpy.ndarray or None, shape (6,) or (3,)
        Cartesian offset ``X, Y, Z`` [mm], ``A, B, C`` [deg], or None (not in the reply).
    joints : numpy.ndarray or None, shape (n,)
        Joint offsets [deg] or [mm], or None.
    mode : {"relative", "absolute"}
        ``"relative"``: the robot sums the offsets (RSI's relative correction);
        ``"absolute"``: the offset replaces the previous one.
    positions : bool, optional
        True when ``cart``/``joints`` are positions (EGM's planned pose), not offsets: the
        plant takes ``position - programmed`` as the absolute offset (default False).

    Raises
    ------
    InputError
        An unknown mode, or a non-finite offset (a reply with one is rejected before this).
    """

    cart: np.ndarray | None
    joints: np.ndarray | None
    mode: str = "relative"
    positions: bool = False

    def __post_init__(self) -> None:
        if self.mode not in CORRECTION_MODES:
            raise InputError(f"mode: expected one of {', '.join(CORRECTION_MODES)}, got {self.mode!r}")
        for name in ("cart", "joints"):
            v = getattr(self, name)
            if v is not None and not np.all(np.isfinite(v)):
                raise InputError(f"{name}: expected finite offsets, got {v!r}")


def euler_zyx_to_quaternion(a_deg: float, b_deg: float, c_deg: float) -> tuple[float, float, float, float]:
    """Unit quaternion ``(u0, u1, u2, u3)`` (scalar first) of KUKA's ``A, B, C`` angles.

    ``R = Rz(A) Ry(B) Rx(C)`` (KUKA's convention; EGM's quaternion is scalar-first).

    Parameters
    ----------
    a_deg : float
        Rotation about z [deg].
    b_deg : float
        Rotation about y [deg].
    c_deg : float
        Rotation about x [deg].

    Returns
    -------
    tuple of float
        ``(w, x, y, z)``.
    """
    a, b, c = (math.radians(v) / 2 for v in (a_deg, b_deg, c_deg))
    ca, sa, cb, sb, cc, sc = math.cos(a), math.sin(a), math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    return (ca * cb * cc + sa * sb * sc, ca * cb * sc - sa * sb * cc, ca * sb * cc + sa * cb * sc, sa * cb * cc - ca * sb * sc)


class ReplyError(GtModelError, ValueError):
    """A reply the robot cannot use: malformed, too long, hostile, non-finite or out of range.

    Parameters
    ----------
    reason : str
        A short key for the summary's counts (``"malformed"``, ``"too_long"``, ``"nonfinite"``, ...).
    message : str
        What was wrong.
    """

    def __init__(self, reason: str, message: str) -> None:
        super().__init__(message)
        self.reason = reason
