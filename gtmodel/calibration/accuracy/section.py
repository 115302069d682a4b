"""Worst-case TCP error maps over a workspace section, Dressler (2012), Figs. 4.8-4.10.

A section ``x = x0`` of the base frame (orthogonal to the guideways when they run along
``x``, as on the D1) is gridded in ``y`` and ``z``; every grid point inside the workspace
(reach, cart travel and a largest link-guideway angle) gets the geometric worst case
(:func:`~gtmodel.calibration.accuracy.geometric.ellipsoid_corners`, A.2), the
parallelepiped worst case and face areas (A.4, Fig. 4.9). The guideways' crossings of the
section are the actuator positions marked in the figures.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gtmodel.calibration.accuracy.geometric import ellipsoid_corners, parallelepiped
from gtmodel.calibration.accuracy.tolerances import NominalPoses, Tolerances, nominal_pose
from gtmodel.errors import InputError
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.workspace import in_ranges

__all__ = ["Section", "SectionMap", "section_poses", "section_map", "actuator_crossings"]

#: Most grid points of one section (each costs a few microseconds per case).
MAX_SECTION_POINTS = 200_000


@dataclass(frozen=True)
class Section:
    """A ``yz`` section of the workspace at ``x = x0``.

    Parameters
    ----------
    x : float
        The section's ``x`` [m].
    y : tuple of float
        ``(min, max)`` of the grid in ``y`` [m].
    z : tuple of float
        ``(min, max)`` of the grid in ``z`` [m].
    step : float
        Grid spacing [m].
    max_link_angle : float or None
        Largest link-guideway angle [rad] of a grid point (None: the parameter set's
        spherical-joint limit).
    """

    x: float
    y: tuple[float, float]
    z: tuple[float, float]
    step: float
    max_link_angle: float | None = None

    def axes(self) -> tuple[np.ndarray, np.ndarray]:
        """The grid lines in ``y`` and ``z`` [m].

        Returns
        -------
        tuple of numpy.ndarray
        """
        ys = np.arange(self.y[0], self.y[1] + self.step / 2, self.step)
        zs = np.arange(self.z[0], self.z[1] + self.step / 2, self.step)
        return ys, zs


def section_poses(kin: GantryTau3Kinematics, section: Section) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The grid of a section and which of its points lie in the workspace.

    Parameters
    ----------
    kin : GantryTau3Kinematics
        The 3-link model (a full parameter set: cart travel and joint limit).
    section : Section
        The section.

    Returns
    -------
    ys, zs : numpy.ndarray
        Grid lines [m].
    inside : numpy.ndarray of bool, shape (len(ys), len(zs))
        Grid points in the workspace.

    Raises
    ------
    InputError
        A grid of more than :data:`MAX_SECTION_POINTS` points, an empty range, or no limits.
    """
    if not section.step > 0 or section.y[1] <= section.y[0] or section.z[1] <= section.z[0]:
        raise InputError(f"section: expected increasing y and z ranges and a positive step, got {section}")
    ys, zs = section.axes()
    if ys.size * zs.size > MAX_SECTION_POINTS:
        raise InputError(f"section.step: expected a step giving at most {MAX_SECTION_POINTS} grid points, got {ys.size * zs.size}")
    if kin.parameters is None:
        raise InputError("section: needs a full parameter set (cart travel, joint limit)")
    Y, Z = np.meshgrid(ys, zs, indexing="ij")
    P = np.column_stack([np.full(Y.size, section.x), Y.ravel(), Z.ravel()])
    lim = kin.parameters.limits
    angle = lim.joint_angle_max if section.max_link_angle is None else section.max_link_angle
    inside = kin.in_workspace(P, limits=False)
    reach = P[inside]
    if reach.shape[0]:
        inside[inside] = in_ranges(kin.ik(reach), lim.cart_travel) & (kin.link_angles(reach).max(axis=1) <= angle)
    return ys, zs, inside.reshape(Y.shape)


def actuator_crossings(kin: GantryTau3Kinematics, x: float) -> np.ndarray:
    """Where the guideway lines ``As_i + t v_i`` cross the section ``x = x0``: ``(y, z)`` per arm [m].

    Parameters
    ----------
    kin : GantryTau3Kinematics
        The 3-link model.
    x : float
        The section's ``x`` [m].

    Returns
    -------
    numpy.ndarray, shape (3, 2)
    """
    t = (x - kin.As[:, 0]) / kin.v[:, 0]
    return (kin.As + t[:, None] * kin.v)[:, 1:]


@dataclass(frozen=True)
class SectionMap:
    """The worst-case maps of one tolerance case over a section (NaN outside the workspace).

    Parameters
    ----------
    ys, zs : numpy.ndarray
        Grid lines [m].
    geometric : numpy.ndarray, shape (len(ys), len(zs))
        A.2 worst case: largest distance of a corner of ``S^T`` from the nominal TCP [m].
    parallelepiped : numpy.ndarray, shape (len(ys), len(zs))
        A.4 worst case [m].
    face_areas : numpy.ndarray, shape (len(ys), len(zs), 3)
        Parallelepiped face areas per link [m^2].
    nominal : NominalPoses
        The nominal geometry at the points inside (row-major over the grid).
    inside : numpy.ndarray of bool, shape (len(ys), len(zs))
    """

    ys: np.ndarray
    zs: np.ndarray
    geometric: np.ndarray
    parallelepiped: np.ndarray
    face_areas: np.ndarray
    nominal: NominalPoses
    inside: np.ndarray

    def index(self, which: str) -> int:
        """Index into :attr:`nominal` of the ``"min"``, ``"max"`` or ``"centre"`` point of the geometric map.

        The centre is the point inside nearest to the centroid of the points inside.

        Parameters
        ----------
        which : str

        Returns
        -------
        int
        """
        values = self.geometric[self.inside]
        if which == "min":
            return int(np.argmin(values))
        if which == "max":
            return int(np.argmax(values))
        T = self.nominal.T
        return int(np.argmin(np.linalg.norm(T - T.mean(axis=0), axis=1)))


def section_map(kin: GantryTau3Kinematics, section: Section, tol: Tolerances) -> SectionMap:
    """The geometric (A.2) and parallelepiped (A.4) worst cases over a section.

    Parameters
    ----------
    kin : GantryTau3Kinematics
        The 3-link model.
    section : Section
        The section.
    tol : Tolerances
        The error bounds.

    Returns
    -------
    SectionMap

    Raises
    ------
    InputError
        No grid point inside the workspace, or a bad section (see :func:`section_poses`).
    ConvergenceError
        The A.2 iteration failed at a point.
    """
    ys, zs, inside = section_poses(kin, section)
    if not inside.any():
        raise InputError(f"section: no grid point of x = {section.x} m, y in {section.y}, z in {section.z} lies in the workspace")
    Y, Z = np.meshgrid(ys, zs, indexing="ij")
    P = np.column_stack([np.full(int(inside.sum()), section.x), Y[inside], Z[inside]])
    nominal = nominal_pose(kin, P)
    corners, _ = ellipsoid_corners(nominal, tol)
    geo = np.full(inside.shape, np.nan)
    geo[inside] = np.linalg.norm(corners - P[:, None], axis=2).max(axis=1)
    pp = parallelepiped(nominal, tol)
    par = np.full(inside.shape, np.nan)
    par[inside] = pp.worst
    areas = np.full(inside.shape + (3,), np.nan)
    areas[inside] = pp.face_areas
    return SectionMap(ys, zs, geo, par, areas, nominal, inside)
