"""The 3-link Gantry-Tau stiffness model (:class:`GantryTau3Stiffness`) and its workspace maps (:class:`StiffnessMap`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any, Sequence

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._arrays import as_rows
from gtmodel._docstrings import fill_doc
from gtmodel.errors import InputError, SingularConfigurationError
from gtmodel.robots.kinematic_expressions import configuration_signs, ik_expression
from gtmodel.robots.kinematics import SINGULARITY_TOLERANCE, GantryTau3Kinematics
from gtmodel.robots.mapped import MappedFunction as _Mapped
from gtmodel.robots.parameters import RobotParameters, load_parameters
from gtmodel.robots.stiffness.expressions import (
    arm_compliance_expression,
    cartesian_stiffness_expression,
    link_forces_expression,
    link_unit_vectors_expression,
)
from gtmodel.robots.stiffness.parameters import MEASURED_D1_N_PER_UM, N_PER_UM, StiffnessParameters, load_stiffness

__all__ = ["StiffnessMap", "GantryTau3Stiffness"]

# numpydoc entries shared by the methods that take the same arguments (gtmodel._docstrings)
_POSE_PARAMETERS = """
Parameters
----------
T : array_like, shape (3,) or (N, 3)
    TCP position(s) [m].
"""
_POSE_OPTIONS = """
configuration : int or sequence of int, optional
    IK configuration (see :meth:`GantryTau3Kinematics.ik`).
limits : bool, optional
    Require the poses inside cart travel and joint limits (default True).
"""
_POSE_RAISES = """
Raises
------
UnreachablePoseError
    A pose is unreachable or outside the workspace limits.
InputError
    Wrong shapes (also of ``F`` where given) or non-finite values.
"""
_pose_doc = fill_doc(pose_parameters=_POSE_PARAMETERS, pose_options=_POSE_OPTIONS, pose_raises=_POSE_RAISES)


@dataclass
class StiffnessMap:
    """Static stiffness over a set of TCP positions (a workspace section).

    Parameters
    ----------
    T : numpy.ndarray, shape (N, 3)
        TCP positions [m].
    K : numpy.ndarray, shape (N, 3, 3)
        Cartesian stiffness ``K_x`` [N/m].
    gravity_deflection : numpy.ndarray, shape (N, 3)
        TCP deflection under the plate's gravity load (with payload) [m].
    stiffness : StiffnessParameters
        The stated values used.
    payload_kg : float
        Payload on the plate [kg].
    """

    T: np.ndarray
    K: np.ndarray
    gravity_deflection: np.ndarray
    stiffness: StiffnessParameters
    payload_kg: float

    @property
    def eigenvalues(self) -> np.ndarray:
        """Principal stiffnesses, ascending, (N, 3) [N/m]."""
        return np.linalg.eigvalsh(self.K)

    @property
    def min_stiffness(self) -> np.ndarray:
        """Smallest principal stiffness (weakest direction) per pose, (N,) [N/m]."""
        return self.eigenvalues[:, 0]

    @property
    def axis_stiffness(self) -> np.ndarray:
        """Stiffness along x, y, z: ``1 / (K_x^-1)_jj`` (force along axis j over the deflection along it), (N, 3) [N/m]."""
        return 1.0 / np.diagonal(np.linalg.inv(self.K), axis1=1, axis2=2)

    def summary(self) -> dict[str, Any]:
        """Ranges over the poses in N/um and um, with the measured D1 figure.

        Returns
        -------
        dict
            ``min_eigenvalue_N_per_um``, ``max_eigenvalue_N_per_um``, ``axis_N_per_um`` (x, y, z
            ranges), ``gravity_deflection_um`` (mean, max of the norm), ``measured_D1_N_per_um``.
        """
        ev = self.eigenvalues / N_PER_UM
        ax = self.axis_stiffness / N_PER_UM
        dn = np.linalg.norm(self.gravity_deflection, axis=1) * 1e6
        return {
            "n_poses": int(self.T.shape[0]),
            "min_eigenvalue_N_per_um": [float(ev[:, 0].min()), float(ev[:, 0].max())],
            "max_eigenvalue_N_per_um": [float(ev[:, 2].min()), float(ev[:, 2].max())],
            "axis_N_per_um": {c: [float(ax[:, j].min()), float(ax[:, j].max())] for j, c in enumerate("xyz")},
            "gravity_deflection_um": {"mean": float(dn.mean()), "max": float(dn.max())},
            "payload_kg": float(self.payload_kg),
            "measured_D1_N_per_um": list(MEASURED_D1_N_PER_UM),
        }


# ----------------------------------------------------------------------------- the model
class GantryTau3Stiffness:
    """Static stiffness and deflections of a 3-link Gantry-Tau (module docstring eqs. 1-3).

    Parameters
    ----------
    parameters : RobotParameters or str or pathlib.Path
        Robot parameter set (kinematics, plate and link masses, limits) or its name/path.
    stiffness : StiffnessParameters or str or pathlib.Path, optional
        Stiffness values (default: the shipped ``stiffness.toml``, :func:`load_stiffness`).
    payload_kg : float, optional
        Payload on the plate (spindle, tool) [kg], default 0.

    Raises
    ------
    InputError
        A negative or non-finite payload.
    ParameterError
        An invalid parameter set or stiffness file.

    Notes
    -----
    The CasADi Function :attr:`statics_function` has the kinematic parameters embedded; the
    compliances are inputs, so one graph serves every set of stiffness values.
    """

    def __init__(
        self,
        parameters: RobotParameters | str | Path,
        stiffness: StiffnessParameters | str | Path | None = None,
        payload_kg: float = 0.0,
    ) -> None:
        self.parameters = load_parameters(parameters)
        self.stiffness = load_stiffness("stiffness" if stiffness is None else stiffness)
        try:
            m = float(payload_kg)
        except (TypeError, ValueError):
            raise InputError(f"payload_kg: expected a non-negative mass in kg, got {payload_kg!r}") from None
        if not (math.isfinite(m) and m >= 0):
            raise InputError(f"payload_kg: expected a non-negative mass in kg, got {payload_kg!r}")
        self.payload_kg = m
        self.kinematics = GantryTau3Kinematics(self.parameters)
        kp = self.parameters.kinematics
        self.L, self.As, self.v = np.asarray(kp.L, float), np.asarray(kp.As, float), np.asarray(kp.v, float)
        self.c_link, self.c_act = self.stiffness.compliances(self.L)

    # ------------------------------------------------------------------ loads
    @property
    def plate_mass(self) -> float:
        """Mass carried by the plate joints: ``m_p + payload + sum m_a / 2`` [kg] (eq. 6.7's ``G``)."""
        d = self.parameters.dynamics
        return float(d.m_p + self.payload_kg + 0.5 * np.sum(d.m_a))

    @property
    def gravity_force(self) -> np.ndarray:
        """Gravity load on the plate ``(0, 0, -g m)`` [N], ``m`` = :attr:`plate_mass`."""
        return np.array([0.0, 0.0, -self.parameters.dynamics.g * self.plate_mass])

    # ------------------------------------------------------------------ CasADi
    @cached_property
    def statics_function(self) -> ca.Function:
        """CasADi Function ``statics(T[3], s[3], F[3], c_link[3], c_act[3])``.

        Outputs ``K`` (3x3) [N/m], ``k`` (3) arm stiffness [N/m], ``f`` (3) arm forces [N],
        ``dT`` (3) deflection [m], ``disc`` (3) IK discriminants, ``cos_min`` (1) smallest
        ``|cos|`` of a link to its guideway. Eqs. (1)-(3), IK of eq. 4.9.
        """
        T = ca.SX.sym("T", 3)
        s = ca.SX.sym("s", 3)
        F = ca.SX.sym("F", 3)
        cl = ca.SX.sym("c_link", 3)
        cact = ca.SX.sym("c_act", 3)
        q, disc = ik_expression(T, s, self.L, self.As, self.v)
        A = ca.vertcat(*[(ca.DM(self.As[i]) + q[i] * ca.DM(self.v[i])).T for i in range(3)])
        U = link_unit_vectors_expression(T, A)
        c = arm_compliance_expression(U, self.v, cl, cact)
        K = cartesian_stiffness_expression(U, c)
        f = link_forces_expression(U, F)
        dT = ca.solve(K, F)
        cos = ca.vertcat(*[ca.fabs(ca.dot(U[i, :].T, ca.DM(self.v[i]))) / float(np.linalg.norm(self.v[i])) for i in range(3)])
        return ca.Function(
            "statics", [T, s, F, cl, cact], [K, 1.0 / c, f, dT, disc, ca.mmin(cos)],
            ["T", "s", "F", "c_link", "c_act"], ["K", "k", "f", "dT", "disc", "cos_min"],
        )

    @cached_property
    def _statics(self) -> _Mapped:
        return _Mapped(self.statics_function)

    # ------------------------------------------------------------------ numpy glue
    def _poses(self, T: Any, configuration: Any, limits: bool) -> tuple[np.ndarray, bool, np.ndarray]:
        Tn, single = as_rows(T, "T", 3)
        s = configuration_signs(configuration)
        self.kinematics.ik(Tn, configuration)  # UnreachablePoseError naming the arm
        if limits:
            ok = np.atleast_1d(self.kinematics.in_workspace(Tn, configuration))
            if not np.all(ok):
                k = int(np.argmin(ok))
                self.kinematics.require_in_workspace(Tn[k], configuration)  # raises with the details
        return Tn, single, s

    def _forces(self, F: Any, n: int, single: bool) -> np.ndarray:
        if F is None:
            return np.repeat(self.gravity_force[None, :], n, axis=0)
        try:
            Fa = np.array(F, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"F: expected a force of shape (3,) or ({n}, 3) in N, got {F!r}") from None
        if Fa.shape == (3,):
            Fa = np.repeat(Fa[None, :], n, axis=0)
        if Fa.shape != (n, 3):
            raise InputError(f"F: expected a force of shape (3,) or ({n}, 3) in N (one per pose), got shape {np.shape(F)}")
        bad = ~np.all(np.isfinite(Fa), axis=1)
        if np.any(bad):
            raise InputError(f"F: row {int(np.argmax(bad))} is not finite: {Fa[np.argmax(bad)].tolist()}")
        return Fa

    def _evaluate(self, T: Any, F: Any, configuration: Any, limits: bool) -> tuple[list[np.ndarray], bool, int]:
        Tn, single, s = self._poses(T, configuration, limits)
        n = Tn.shape[0]
        Fa = self._forces(F, n, single)
        K, k, f, dT, _, cos_min = self._statics(Tn.T, s[:, None], Fa.T, self.c_link[:, None], self.c_act[:, None])
        cos_min = cos_min.ravel()
        if np.any(cos_min < SINGULARITY_TOLERANCE):
            j = int(np.argmin(cos_min))
            raise SingularConfigurationError(f"pose T={Tn[j].tolist()} is singular: a link is perpendicular to its guideway")
        K = K.reshape(3, n, 3).transpose(1, 0, 2) if n > 1 else K[None]
        return [K, k.T, f.T, dT.T], single, n

    def _output(self, index: int, T: Any, F: Any, configuration: Any, limits: bool) -> np.ndarray:
        """Output ``index`` of :meth:`_evaluate` (K, k, f, dT), per pose or for the single pose given."""
        out, single, _ = self._evaluate(T, F, configuration, limits)
        return out[index][0] if single else out[index]

    # ------------------------------------------------------------------ public
    @_pose_doc
    def cartesian_stiffness(self, T: np.typing.ArrayLike, configuration: int | Sequence[int] = 0, limits: bool = True) -> np.ndarray:
        """Cartesian stiffness ``K_x(T) = sum_i k_i u_i u_i^T`` (Dressler (2012), ch. 6.3; eq. 1).

        {pose_parameters}
        {pose_options}

        Returns
        -------
        numpy.ndarray, shape (3, 3) or (N, 3, 3)
            ``K_x`` [N/m].

        {pose_raises}
        """
        return self._output(0, T, None, configuration, limits)

    @_pose_doc
    def arm_stiffness(self, T: np.typing.ArrayLike, configuration: int | Sequence[int] = 0, limits: bool = True) -> np.ndarray:
        """Effective axial stiffness ``k_i = 1 / c_i`` of each arm at a pose (eq. 2).

        {pose_parameters}
        {pose_options}

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            ``k_i`` [N/m].

        {pose_raises}
        """
        return self._output(1, T, None, configuration, limits)

    @_pose_doc
    def link_forces(
        self, T: np.typing.ArrayLike, F: np.typing.ArrayLike | None = None, configuration: int | Sequence[int] = 0, limits: bool = True
    ) -> np.ndarray:
        """Axial arm forces balancing a plate force, ``U^T f = F`` (eq. 3).

        {pose_parameters}
        F : array_like, shape (3,) or (N, 3), optional
            Force on the plate [N]; default the gravity load :attr:`gravity_force`.
        {pose_options}

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            Arm (cluster) forces [N], tension positive.

        {pose_raises}
        """
        return self._output(2, T, F, configuration, limits)

    @_pose_doc
    def deflection(
        self, T: np.typing.ArrayLike, F: np.typing.ArrayLike | None = None, configuration: int | Sequence[int] = 0, limits: bool = True
    ) -> np.ndarray:
        """TCP deflection ``dT = K_x^-1 F`` under a force on the plate (eq. 3).

        {pose_parameters}
        F : array_like, shape (3,) or (N, 3), optional
            Force at the TCP/plate [N]; default the gravity load :attr:`gravity_force`.
        {pose_options}

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            ``dT`` [m].

        {pose_raises}
        """
        return self._output(3, T, F, configuration, limits)

    @_pose_doc
    def gravity_deflection(self, T: np.typing.ArrayLike, configuration: int | Sequence[int] = 0, limits: bool = True) -> np.ndarray:
        """TCP deflection under the plate's own weight and the payload, ``K_x^-1 F_g``.

        {pose_parameters}
        {pose_options}

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            ``dT`` [m].

        {pose_raises}
        """
        return self.deflection(T, None, configuration, limits)

    def section_grid(self, x: float | None = None, step: float = 0.05, configuration: int | Sequence[int] = 0) -> np.ndarray:
        """TCP positions of a yz section of the workspace (a regular grid at fixed ``x``).

        Parameters
        ----------
        x : float, optional
            Section coordinate [m]; default the median ``x`` of a 0.1 m workspace grid.
        step : float, optional
            Grid spacing in y and z [m].
        configuration : int or sequence of int, optional
            IK configuration.

        Returns
        -------
        numpy.ndarray, shape (N, 3)
            Grid points inside the workspace [m].

        Raises
        ------
        InputError
            Non-positive step, or no grid point of the section lies in the workspace.
        """
        if not (isinstance(step, (int, float)) and np.isfinite(step) and step > 0):
            raise InputError(f"step: expected a positive spacing in m, got {step!r}")
        box = self.kinematics.workspace_bounds()
        x0 = float(np.median(self.kinematics.workspace_grid(0.1, configuration)[:, 0])) if x is None else float(x)
        ys = np.arange(box[1, 0], box[1, 1] + step / 2, step)
        zs = np.arange(box[2, 0], box[2, 1] + step / 2, step)
        Y, Z = np.meshgrid(ys, zs, indexing="ij")
        P = np.column_stack([np.full(Y.size, x0), Y.ravel(), Z.ravel()])
        P = P[self.kinematics.in_workspace(P, configuration)]
        if P.shape[0] == 0:
            raise InputError(f"no point of the section x = {x0} m (step {step} m) lies in the workspace")
        return P

    @_pose_doc
    def stiffness_map(self, T: np.typing.ArrayLike, configuration: int | Sequence[int] = 0, limits: bool = True) -> StiffnessMap:
        """Stiffness and gravity deflection over a set of poses (e.g. :meth:`section_grid`).

        Parameters
        ----------
        T : array_like, shape (N, 3)
            TCP positions [m].
        {pose_options}

        Returns
        -------
        StiffnessMap

        {pose_raises}
        """
        Tn, _ = as_rows(T, "T", 3)
        (K, _, _, dT), _, _ = self._evaluate(Tn, None, configuration, limits)
        return StiffnessMap(Tn, K, dT, self.stiffness, self.payload_kg)
