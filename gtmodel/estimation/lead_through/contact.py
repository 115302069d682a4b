"""Contact models of the lead-through experiments (Dressler (2012), ch. 8.4) as CasADi expressions.

Each model gives the wrench the tool exerts on the workpiece, ``[f (N); tau (N m)]`` about
the tool centre point (TCP), from the tool pose ``(p, R)`` and velocity: what an ideal tool
force sensor measures (:mod:`gtmodel.estimation.lead_through.law` conventions). Both are
penalty models: the workpiece pushes back in proportion to the penetration, and only while
in contact (unilateral: contact can be lost). Friction is left out (the thesis' rolling tool
on the surface; the peg's walls are taken as smooth).

* :class:`Surface`: a plane through ``point`` with the normal ``normal`` pointing into the
  workpiece, stiffness ``k`` and damping ``d``: ``f = max(0, k delta + d delta') n`` for a
  penetration ``delta > 0`` of the TCP; no torque (point contact at the TCP).
* :class:`PegHole`: a cylindrical peg of radius ``peg_radius`` whose tip is the TCP and whose
  axis is the tool's z axis (pointing away from the tip), and a cylindrical hole of radius
  ``hole_radius`` and depth ``depth`` in a block with a horizontal top face through
  ``mouth``, its axis ``axis`` (into the block) misaligned from the vertical. Contact forces
  come from the penetration of the peg's end points into the hole's walls: the tip, and
  the point where the peg crosses the top face (the peg is straight and the hole convex,
  so the largest wall penetration is at one of them). The peg's flat end enters the hole
  only where it lies wholly within the mouth (tip within ``hole_radius - peg_radius`` of
  the axis); elsewhere the top face pushes it up. The bottom pushes the tip back along the
  axis. One stiffness ``k`` for all (the thesis' match is compliant).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._arrays import finite_float
from gtmodel.errors import InputError

__all__ = ["CARDBOARD", "METAL_PLATE", "Surface", "PegHole", "surface_of"]




def _point(v: Any, name: str) -> np.ndarray:
    arr = np.asarray(v, dtype=float) if np.asarray(v).dtype.kind in "fiu" else None
    if arr is None or arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise InputError(f"{name}: expected 3 finite numbers [m], got {v!r}")
    return arr


def _unit(v: Any, name: str) -> np.ndarray:
    arr = _point(v, name)
    norm = float(np.linalg.norm(arr))
    if norm < 1e-9:
        raise InputError(f"{name}: expected a non-zero direction, got {arr.tolist()}")
    return arr / norm


@dataclass(frozen=True)
class Surface:
    """A compliant plane the tool presses on (surface tracking, Dressler (2012), Figures 8.4-8.5).

    Parameters
    ----------
    stiffness : float
        Contact stiffness ``k`` [N/m], positive (a negative stiffness is refused).
    damping : float, optional
        Contact damping ``d`` [N s/m], non-negative.
    normal : array_like, shape (3,), optional
        Normal into the workpiece (normalised); default down, ``(0, 0, -1)``.
    point : array_like, shape (3,), optional
        A point of the undeformed surface [m].

    Raises
    ------
    InputError
        A stiffness that is not positive, a negative damping, a zero normal, a non-finite point.
    """

    stiffness: float
    damping: float = 0.0
    normal: Any = (0.0, 0.0, -1.0)
    point: Any = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "stiffness", finite_float(self.stiffness, "stiffness", "N/m", positive=True))
        object.__setattr__(self, "damping", finite_float(self.damping, "damping", "N s/m", nonnegative=True))
        object.__setattr__(self, "normal", _unit(self.normal, "normal"))
        object.__setattr__(self, "point", _point(self.point, "point"))

    def wrench(self, p: ca.SX, R: ca.SX, v: ca.SX) -> ca.SX:
        """Wrench of the tool on the surface, ``(6, 1)`` [N, N m].

        Parameters
        ----------
        p : casadi.SX, shape (3, 1)
            TCP position [m].
        R : casadi.SX, shape (3, 3)
            Tool orientation (unused: point contact).
        v : casadi.SX, shape (6, 1)
            TCP twist [m/s, rad/s].

        Returns
        -------
        casadi.SX, shape (6, 1)
        """
        n = ca.DM(self.normal)
        delta = ca.dot(n, p - ca.DM(self.point))
        push = ca.fmax(0.0, self.stiffness * delta + self.damping * ca.dot(n, v[:3]))
        return ca.vertcat(ca.if_else(delta > 0, push, 0.0) * n, ca.SX.zeros(3))

    def penetration(self, p: np.ndarray) -> np.ndarray:
        """Penetration of TCP positions into the surface [m] (negative: above it).

        Parameters
        ----------
        p : numpy.ndarray, shape (N, 3)
            TCP positions [m].

        Returns
        -------
        numpy.ndarray, shape (N,)
        """
        return (np.asarray(p, dtype=float) - self.point) @ self.normal


#: The thesis' plain cardboard box (compliant) and the metal plate on it (stiff), assumed figures.
CARDBOARD = Surface(stiffness=2.0e3, damping=20.0)
METAL_PLATE = Surface(stiffness=1.0e5, damping=20.0)


def surface_of(name: str) -> Surface:
    """The named surface of the experiments: ``"cardboard"`` or ``"metal_plate"``.

    Parameters
    ----------
    name : {"cardboard", "metal_plate"}
        Surface name.

    Returns
    -------
    Surface

    Raises
    ------
    InputError
        Another name.
    """
    table = {"cardboard": CARDBOARD, "metal_plate": METAL_PLATE}
    if name not in table:
        raise InputError(f"surface: expected one of {', '.join(table)}, got {name!r}")
    return table[name]


@dataclass(frozen=True)
class PegHole:
    """A cylindrical peg on the tool and a misaligned hole (peg-in-hole, Dressler (2012), Figure 8.6).

    Parameters
    ----------
    peg_radius : float, optional
        Peg radius [m] (thesis: a 3 mm match: 1.5 mm).
    hole_radius : float, optional
        Hole radius [m], at least ``peg_radius`` (thesis: 4 mm hole: 2 mm; equal: zero clearance).
    depth : float, optional
        Hole depth along its axis [m].
    misalignment_deg : float, optional
        Angle of the hole's axis from the vertical [deg], about the y axis, in [0, 45).
    mouth : array_like, shape (3,), optional
        Centre of the hole's mouth on the block's (horizontal) top face [m].
    stiffness : float, optional
        Wall stiffness [N/m] (the peg's compliance dominates).

    Raises
    ------
    InputError
        A non-positive size or stiffness, a hole smaller than the peg, a misalignment outside
        [0, 45) degrees, a non-finite mouth.
    """

    peg_radius: float = 1.5e-3
    hole_radius: float = 2.0e-3
    depth: float = 0.02
    misalignment_deg: float = 5.0
    mouth: Any = (0.0, 0.0, 0.0)
    stiffness: float = 2.0e4

    def __post_init__(self) -> None:
        for name, unit in (("peg_radius", "m"), ("hole_radius", "m"), ("depth", "m"), ("stiffness", "N/m")):
            object.__setattr__(self, name, finite_float(getattr(self, name), name, unit, positive=True))
        if self.hole_radius < self.peg_radius:
            raise InputError(f"hole_radius: expected at least peg_radius ({self.peg_radius} m), got {self.hole_radius} m")
        a = finite_float(self.misalignment_deg, "misalignment_deg", "deg", nonnegative=True)
        if a >= 45.0:
            raise InputError(f"misalignment_deg: expected an angle in [0, 45) degrees, got {self.misalignment_deg!r}")
        object.__setattr__(self, "misalignment_deg", a)
        object.__setattr__(self, "mouth", _point(self.mouth, "mouth"))

    @property
    def axis(self) -> np.ndarray:
        """Unit axis of the hole, into the block (down, tilted by the misalignment about y)."""
        a = math.radians(self.misalignment_deg)
        return np.array([math.sin(a), 0.0, -math.cos(a)])

    def _radial(self, q: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX]:
        """Depth along the axis, radial distance and radial unit vector of a point."""
        a = ca.DM(self.axis)
        r = q - ca.DM(self.mouth)
        s = ca.dot(r, a)
        radial = r - s * a
        rho = ca.sqrt(ca.dot(radial, radial) + 1e-30)
        return s, rho, radial / rho

    def wrench(self, p: ca.SX, R: ca.SX, v: ca.SX) -> ca.SX:
        """Wrench of the peg on the block about the tip, ``(6, 1)`` [N, N m].

        Parameters
        ----------
        p : casadi.SX, shape (3, 1)
            Peg tip (TCP) [m].
        R : casadi.SX, shape (3, 3)
            Tool orientation; its third column is the peg axis (from the tip up).
        v : casadi.SX, shape (6, 1)
            TCP twist (unused: no damping).

        Returns
        -------
        casadi.SX, shape (6, 1)
        """
        k, top = self.stiffness, float(self.mouth[2])
        u = R[:, 2]
        s_tip, rho_tip, e_tip = self._radial(p)
        below = top - p[2]  # depth of the tip below the top face
        # the peg's flat end falls into the hole only when it lies wholly within the mouth;
        # elsewhere it sits on the top face (the rim region, up to r_p deep), else it is in the hole
        in_mouth = rho_tip <= self.hole_radius - self.peg_radius
        on_face = ca.logic_and(ca.logic_and(below > 0, below < self.peg_radius), ca.logic_not(in_mouth))
        inside = ca.logic_and(below > 0, ca.logic_not(on_face))
        # forces on the peg
        f_face = ca.if_else(on_face, k * below, 0.0) * ca.DM([0.0, 0.0, 1.0])
        wall_tip = ca.fmax(0.0, rho_tip + self.peg_radius - self.hole_radius)
        f_tip = ca.if_else(ca.logic_and(inside, s_tip <= self.depth), -k * wall_tip, 0.0) * e_tip
        f_bottom = ca.if_else(ca.logic_and(inside, s_tip > self.depth), -k * (s_tip - self.depth), 0.0) * ca.DM(self.axis)
        lam = below / ca.fmax(u[2], 1e-3)  # along the peg from the tip to the top face
        m = p + lam * u
        _, rho_m, e_m = self._radial(m)
        wall_m = ca.fmax(0.0, rho_m + self.peg_radius - self.hole_radius)
        f_mouth = ca.if_else(inside, -k * wall_m, 0.0) * e_m
        on_peg = f_face + f_tip + f_bottom + f_mouth
        torque_on_peg = ca.cross(m - p, f_mouth)
        return -ca.vertcat(on_peg, torque_on_peg)

    def insertion(self, p: np.ndarray) -> np.ndarray:
        """Depth of the peg tip along the hole's axis below the mouth [m] (negative: above).

        Parameters
        ----------
        p : numpy.ndarray, shape (N, 3)
            Tip positions [m].

        Returns
        -------
        numpy.ndarray, shape (N,)
        """
        return (np.asarray(p, dtype=float) - self.mouth) @ self.axis
