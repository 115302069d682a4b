"""The elasto-geometric closure model: a 3-link model with gravity-loaded, compliant arms.

Each link's length is the loaded length ``L_i + c_i(T) f_i(T)`` of the stiffness model
(:mod:`gtmodel.robots.stiffness`: link forces of a plate load, cluster and cart
compliances per arm). Its FK is Newton's method on these closure equations from the rigid
FK. Calibrated by :func:`gtmodel.calibration.calibrate_elasto_geometric`.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel.errors import InputError
from gtmodel.robots.closure import ClosureModel, ThreeLinkClosure
from gtmodel.robots.stiffness import (
    GantryTau3Stiffness,
    arm_compliance_expression,
    link_forces_expression,
    link_unit_vectors_expression,
)
from gtmodel.robots.wrapped import WrappedClosure

__all__ = ["ElastoGeometricClosure", "COMPLIANCE_NAMES", "LOAD_NAMES"]


#: Compliance parameter names: cluster (links + joints) and cart, per arm [m/N].
COMPLIANCE_NAMES = ("c_l1", "c_l2", "c_l3", "c_a1", "c_a2", "c_a3")
#: Load parameter names: the force on the plate [N].
LOAD_NAMES = ("F_x", "F_y", "F_z")


class ElastoGeometricClosure(WrappedClosure):
    """3-link closure model with gravity-loaded, compliant arms (:mod:`gtmodel.calibration.elasto_geometric`, eq. 2).

    Parameters
    ----------
    geometric : ThreeLinkClosure
        The geometric (rigid) model, ideal or modified.
    c_link : array_like, shape (3,), optional
        Cluster compliance (links and joints) per arm [m/N]; default 0.
    c_act : array_like, shape (3,), optional
        Cart compliance along the guideway per arm [m/N]; default 0.
    F : array_like, shape (3,), optional
        Constant load on the plate in the model frame [N]; default 0.
    per_pose_load : bool, optional
        If True, the poses carry their own known plate load, added to ``F`` (e.g.
        measurements with and without a payload): the calibration and evaluation take it
        from :attr:`MeasurementSet.load <gtmodel.calibration.measurements.MeasurementSet>`
        through :meth:`pose_inputs`. The model's per-pose input (``n_q``, the ``q`` of
        :meth:`link_points` and :meth:`fk`) is then the cart positions [m] followed by the
        load ``(F_x, F_y, F_z)`` [N], 6 values. Default False (3 cart positions).

    Raises
    ------
    InputError
        If ``geometric`` is not a :class:`ThreeLinkClosure` or a value has the wrong shape or
        is not finite.
    """

    orientation = False
    n_q = 3
    links = (("1",), ("2",), ("3",))

    def __init__(
        self,
        geometric: ThreeLinkClosure,
        c_link: np.typing.ArrayLike = (0.0, 0.0, 0.0),
        c_act: np.typing.ArrayLike = (0.0, 0.0, 0.0),
        F: np.typing.ArrayLike = (0.0, 0.0, 0.0),
        per_pose_load: bool = False,
    ) -> None:
        if not isinstance(geometric, ThreeLinkClosure):
            raise InputError(f"geometric: expected a ThreeLinkClosure, got {type(geometric).__name__}")
        self.inner = geometric
        vals = []
        for name, v in (("c_link", c_link), ("c_act", c_act), ("F", F)):
            try:
                a = np.array(v, dtype=float).reshape(-1)
            except (TypeError, ValueError):
                raise InputError(f"{name}: expected 3 finite numbers, got {v!r}") from None
            if a.shape != (3,) or not np.all(np.isfinite(a)):
                raise InputError(f"{name}: expected 3 finite numbers, got {v!r}")
            vals.append(a)
        self.c_link, self.c_act, self.F = vals
        self.robot = geometric.robot
        self.per_pose_load = bool(per_pose_load)
        self.n_q = 6 if self.per_pose_load else 3
        self.name = f"elasto_geometric_{geometric.model}" + ("_loads" if self.per_pose_load else "")
        names = geometric.parameter_names()
        self._n_geo = len(names)
        idx = {n: i for i, n in enumerate(names)}
        self._As_idx = [[idx[f"As{i + 1}_{c}"] for c in "xyz"] for i in range(3)]
        if geometric.model == "ideal":
            self._v_idx = [[idx[f"v_{c}"] for c in "xyz"]] * 3
        else:
            self._v_idx = [[idx[f"v{i + 1}_{c}"] for c in "xyz"] for i in range(3)]

    def pose_inputs(self, measurements: Any) -> np.ndarray:
        """Per-pose inputs of the closure equations from a measurement set.

        The cart positions, followed with ``per_pose_load`` by the pose's known plate load
        (:attr:`MeasurementSet.load <gtmodel.calibration.measurements.MeasurementSet>`).
        The calibration (:class:`~gtmodel.calibration.kinematic.CalibrationProblem`) and
        the evaluation (:func:`~gtmodel.calibration.evaluation.evaluate`, eq. 5.5) call it.

        Parameters
        ----------
        measurements : MeasurementSet
            Measured poses (with ``load`` [N], shape (N, 3), if ``per_pose_load``).

        Returns
        -------
        numpy.ndarray, shape (N, n_q)
            ``q`` [m] (3 columns), or ``q`` [m] and ``load`` [N] (6 columns).

        Raises
        ------
        InputError
            If ``measurements`` is not a :class:`MeasurementSet`, does not hold 3 cart
            positions per pose, or holds no load while the model needs one.
        """
        if not (hasattr(measurements, "q") and hasattr(measurements, "n_q") and hasattr(measurements, "load")):
            raise InputError(f"measurements: expected a MeasurementSet, got {type(measurements).__name__}")
        if measurements.n_q != 3:
            raise InputError(f"measurements: {measurements.n_q} actuator columns, the model {self.name} needs 3")
        if not self.per_pose_load:
            return measurements.q
        if measurements.load is None:
            raise InputError(
                f"measurements: {measurements.source!r} holds no plate load (load / columns F_x_N, F_y_N, F_z_N), "
                f"which {self.name} (per_pose_load) needs for every pose"
            )
        return np.hstack([measurements.q, measurements.load])

    @classmethod
    def from_stiffness(cls, stiffness: GantryTau3Stiffness, model: str = "modified", per_pose_load: bool = False) -> "ElastoGeometricClosure":
        """The closure model of a stiffness model: its geometry, compliances and gravity load.

        Parameters
        ----------
        stiffness : GantryTau3Stiffness
            Robot, stated stiffness values and payload.
        model : {"ideal", "modified"}, optional
            Geometric parametrisation (default "modified").
        per_pose_load : bool, optional
            Loads come with the poses (:attr:`MeasurementSet.load`); the constant load is
            then zero.

        Returns
        -------
        ElastoGeometricClosure

        Raises
        ------
        InputError
            If ``stiffness`` is not a :class:`GantryTau3Stiffness`.
        """
        if not isinstance(stiffness, GantryTau3Stiffness):
            raise InputError(f"stiffness: expected a GantryTau3Stiffness, got {type(stiffness).__name__}")
        F = np.zeros(3) if per_pose_load else stiffness.gravity_force
        return cls(ThreeLinkClosure(stiffness.parameters, model=model), stiffness.c_link, stiffness.c_act, F, per_pose_load)

    @property
    def geometric(self) -> ThreeLinkClosure:
        """The geometric (rigid) model (the wrapped model)."""
        return self.inner  # type: ignore[return-value]

    # ---------------------------------------------------------------- interface
    def own_parameter_names(self) -> tuple[str, ...]:
        """``c_l1..c_a3`` [m/N], ``F_x..F_z`` [N], after the geometric names.

        Returns
        -------
        tuple of str
        """
        return COMPLIANCE_NAMES + LOAD_NAMES

    def own_parameter_vector(self) -> np.ndarray:
        """Compliances and constant load (SI: m/N, N).

        Returns
        -------
        numpy.ndarray, shape (9,)
        """
        return np.concatenate([self.c_link, self.c_act, self.F])

    def link_points(self, p: ca.SX, q: ca.SX, T: ca.SX, R: ca.SX, arm: int) -> tuple[ca.SX, ca.SX, ca.SX]:
        """``A = As_i + q_i v_i``, ``B = T``, loaded length ``L_i + c_i(T) f_i(T)`` (eq. 2).

        Parameters
        ----------
        p : casadi.SX, shape (n_parameters,)
            Parameters.
        q : casadi.SX, shape (n_q,)
            Cart positions [m] (and the pose's plate load [N] with ``per_pose_load``).
        T : casadi.SX, shape (3,)
            (Measured) TCP position [m].
        R : casadi.SX, shape (3, 3)
            Ignored (constant orientation).
        arm : int
            Arm index 0, 1, 2.

        Returns
        -------
        A, B : casadi.SX, shape (3, 1)
            Joint points [m].
        L : casadi.SX, shape (1,)
            Loaded link length [m].
        """
        n = self._n_geo
        pg = p[:n]
        if self.per_pose_load:
            q, load = q[:3], q[3:6]
        A_all = ca.vertcat(*[self.geometric.link_points(pg, q, T, R, j)[0].T for j in range(3)])
        V = ca.vertcat(*[ca.vertcat(*[p[k] for k in self._v_idx[j]]).T for j in range(3)])
        c_l, c_a, F = p[n:n + 3], p[n + 3:n + 6], p[n + 6:n + 9]
        if self.per_pose_load:
            F = F + load
        U = link_unit_vectors_expression(T, A_all)
        c = arm_compliance_expression(U, V, c_l, c_a)
        f = link_forces_expression(U, F)
        A, B, L = self.geometric.link_points(pg, q, T, R, arm)
        return A, B, L + c[arm] * f[arm]

    def rewrap(self, inner: ClosureModel, own: np.ndarray, R: np.ndarray | None) -> "ElastoGeometricClosure":
        """The model around another geometric model; a frame change rotates the load.

        Parameters
        ----------
        inner : ThreeLinkClosure
            Geometric model.
        own : numpy.ndarray, shape (9,)
            ``c_link``, ``c_act``, ``F``.
        R : numpy.ndarray, shape (3, 3) or None
            Rotation of a frame change (``F' = R F``).

        Returns
        -------
        ElastoGeometricClosure
        """
        F = own[6:9] if R is None else R @ own[6:9]
        return ElastoGeometricClosure(inner, own[0:3], own[3:6], F, self.per_pose_load)  # type: ignore[arg-type]

    def fk_inputs(self, q: np.typing.ArrayLike) -> np.ndarray:
        """Cart positions [m] (and plate loads [N] with ``per_pose_load``), checked.

        Parameters
        ----------
        q : array_like, shape (n_q,) or (N, n_q)
            Rows of :meth:`pose_inputs`.

        Returns
        -------
        numpy.ndarray

        Raises
        ------
        InputError
            Wrong number of columns.
        """
        qa = np.asarray(q, dtype=float)
        if qa.shape[-1] != self.n_q:
            raise InputError(f"q: expected {self.n_q} columns for {self.name}, got shape {qa.shape}")
        return qa

    def fk_start(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Rigid FK (trilateration) of the cart positions: the start of Newton's method on eq. (2).

        Parameters
        ----------
        q : numpy.ndarray, shape (n_q,) or (N, n_q)
            Rows of :meth:`pose_inputs`.

        Returns
        -------
        T0 : numpy.ndarray, shape (3,) or (N, 3)
            Rigid TCP positions [m].
        R0 : numpy.ndarray
            Identity (constant orientation).
        """
        return self.geometric.fk(q[..., :3])
