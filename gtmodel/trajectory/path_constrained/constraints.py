"""Limits along a path (:class:`PathConstraints`) and the bounds of their constraint rows."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from gtmodel.errors import InputError

__all__ = ["PathConstraints", "ROW_NAMES"]

_INF = math.inf


def _limit(value: Any, name: str, unit: str, size: int = 3) -> np.ndarray | None:
    if value is None:
        return None
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected {'three positive numbers' if size == 3 else 'a positive number'} in {unit}, got {value!r}") from None
    if size == 3 and arr.ndim == 0:
        arr = np.full(3, float(arr))
    want = (size,) if size > 1 else ()
    if arr.shape != want or not np.all(np.isfinite(arr)):
        raise InputError(f"{name}: expected {'three finite numbers' if size == 3 else 'a finite number'} in {unit}, got {value!r}")
    if np.any(arr <= 0):
        raise InputError(f"{name}: expected positive limits in {unit} (a limit is a bound on |value|), got {np.atleast_1d(arr).tolist()}")
    return arr


@dataclass
class PathConstraints:
    """Limits along a path: symmetric bounds on magnitudes (``|x| <= limit``).

    Parameters
    ----------
    force_limit : array_like, shape (3,), optional
        Actuator (cart) forces ``|tau_i|`` [N]; needs a robot.
    cart_velocity_limit : array_like, shape (3,), optional
        Cart velocities ``|q_dot_i|`` [m/s]; needs a robot.
    cart_acceleration_limit : array_like, shape (3,), optional
        Cart accelerations ``|q_ddot_i|`` [m/s^2]; needs a robot.
    tcp_velocity_limit : array_like, shape (3,), optional
        TCP velocity per axis ``|T_dot_j|`` [m/s].
    tcp_speed_limit : float, optional
        TCP speed ``||T_dot||`` [m/s].
    tcp_acceleration_limit : array_like, shape (3,), optional
        TCP acceleration per axis ``|T_ddot_j|`` [m/s^2].

    Raises
    ------
    InputError
        A limit that is not positive and finite, has the wrong shape, or no limit at all.

    Notes
    -----
    A scalar given for a per-axis limit applies to all three axes.
    """

    force_limit: Any = None
    cart_velocity_limit: Any = None
    cart_acceleration_limit: Any = None
    tcp_velocity_limit: Any = None
    tcp_speed_limit: Any = None
    tcp_acceleration_limit: Any = None

    def __post_init__(self) -> None:
        self.force_limit = _limit(self.force_limit, "force_limit", "N")
        self.cart_velocity_limit = _limit(self.cart_velocity_limit, "cart_velocity_limit", "m/s")
        self.cart_acceleration_limit = _limit(self.cart_acceleration_limit, "cart_acceleration_limit", "m/s^2")
        self.tcp_velocity_limit = _limit(self.tcp_velocity_limit, "tcp_velocity_limit", "m/s")
        self.tcp_speed_limit = _limit(self.tcp_speed_limit, "tcp_speed_limit", "m/s", size=1)
        self.tcp_acceleration_limit = _limit(self.tcp_acceleration_limit, "tcp_acceleration_limit", "m/s^2")
        if not self.kinds:
            raise InputError("constraints: no limit given; without limits the time-optimal motion is instantaneous")

    @property
    def kinds(self) -> tuple[str, ...]:
        """Names of the limits that are set, in a fixed order."""
        names = ("force_limit", "cart_velocity_limit", "cart_acceleration_limit", "tcp_velocity_limit", "tcp_speed_limit", "tcp_acceleration_limit")
        return tuple(n for n in names if getattr(self, n) is not None)

    @property
    def needs_robot(self) -> bool:
        """True if a limit concerns the actuators (forces or carts)."""
        return any(k in self.kinds for k in ("force_limit", "cart_velocity_limit", "cart_acceleration_limit"))

    def bounds(self) -> tuple[np.ndarray, np.ndarray, list[str]]:
        """Bounds of the constraint rows ``lo <= m a + c b + d sqrt(b) + g <= hi``.

        Returns
        -------
        lo, hi : numpy.ndarray, shape (R,)
            Row bounds (velocities appear squared: ``c b <= v^2``).
        names : list of str
            Row names, e.g. ``"tau1"``, ``"T_dot_x"``.
        """
        lo: list[float] = []
        hi: list[float] = []
        names: list[str] = []
        for kind in self.kinds:
            v = np.atleast_1d(getattr(self, kind))
            if kind in ("force_limit", "cart_acceleration_limit", "tcp_acceleration_limit"):
                lo += (-v).tolist()
                hi += v.tolist()
            else:
                lo += [-_INF] * v.size
                hi += (v**2).tolist()
            names += ROW_NAMES[kind][: v.size]
        return np.array(lo), np.array(hi), names


#: Names of the constraint rows per kind of limit, in the order of :meth:`PathConstraints.bounds`.
ROW_NAMES = {
    "force_limit": ["tau1", "tau2", "tau3"],
    "cart_velocity_limit": ["q_dot1", "q_dot2", "q_dot3"],
    "cart_acceleration_limit": ["q_ddot1", "q_ddot2", "q_ddot3"],
    "tcp_velocity_limit": ["T_dot_x", "T_dot_y", "T_dot_z"],
    "tcp_speed_limit": ["|T_dot|"],
    "tcp_acceleration_limit": ["T_ddot_x", "T_ddot_y", "T_ddot_z"],
}
