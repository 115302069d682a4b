"""Kinematic models written as closure equations, the common ground of calibration.

Every Gantry-Tau kinematic model is a set of closure equations, one per link ``j`` of
arm ``i`` (Dressler (2012), eqs. 4.3-4.6, 4.14, 4.19-4.23)::

    || A_ij(q, s) - B_ij(T, R_T, s) ||^2 - L_ij(s)^2 = 0

with ``A_ij`` the actuator-side joint point (a function of the actuator values ``q``),
``B_ij = T + R_T B0_ij`` the plate-side joint point and ``s`` the model parameters.
:class:`ClosureModel` is the interface every model implements by giving ``A``, ``B``
and ``L`` symbolically (:meth:`ClosureModel.link_points`); from it this module derives,
once for all models,

- the closure residuals per arm (:meth:`ClosureModel.closure_function`), which are the
  calibration residuals of eqs. 5.1-5.2 and always real-valued;
- a generic forward kinematics by Newton's method on all closure equations
  (:meth:`ClosureModel.pose_function`), used for synthetic measurements and as the
  cross-check of each model's own FK;
- which parameters each arm depends on (:meth:`ClosureModel.arm_parameter_indices`),
  read from the expression graph, so arms that share no parameter are calibrated as
  separate NLPs.

Orientations enter as unit quaternions ``(w, x, y, z)`` (the measurement format) and are
reported as ZYZ Euler angles (Dressler (2012), eq. 4.15) at the user boundary.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from functools import cached_property
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._arrays import as_rows
from gtmodel._geometry import (  # noqa: F401 - re-exported: part of the robots API
    quaternion_to_rotation,
    rotation_to_quaternion,
    rotation_to_zyz,
    rotation_vector_to_rotation,
    zyz_to_rotation,
)
from gtmodel.errors import ConvergenceError, InputError
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.parameters import KinematicParameters, RobotParameters, load_parameters
from gtmodel.robots.pose_rank import POSE_RANK_RTOL, inverse_condition, jacobian_function, min_norm_gauss_newton

__all__ = [
    "ClosureModel",
    "ThreeLinkClosure",
    "quaternion_to_rotation",
    "rotation_to_quaternion",
    "zyz_to_rotation",
    "rotation_to_zyz",
    "rotation_vector_to_rotation",
    "POSE_TOLERANCE",
    "POSE_MAX_ITER",
]

#: Acceptance of :meth:`ClosureModel.fk_newton`: max |closure residual| [m^2], about 2.5e-9 m
#: of link length for 2 m links. Newton iterates to 1e-5 of it; the six-link models'
#: orientation is weakly determined (near-parallel links), which limits the attainable
#: residual to ~1e-10 m^2 on some poses.
POSE_TOLERANCE = 1e-8
#: Iteration limit of :meth:`ClosureModel.pose_function`.
POSE_MAX_ITER = 30


# ------------------------------------------------------------------ the interface
class ClosureModel(ABC):
    """A Gantry-Tau kinematic model given by its closure equations.

    Subclasses set :attr:`name`, :attr:`n_q`, :attr:`orientation`, :attr:`links` and
    implement :meth:`parameter_names`, :meth:`parameter_vector`, :meth:`link_points`,
    :meth:`with_parameters` and :meth:`transformed`; everything else derives from them.

    Attributes
    ----------
    name : str
        Model name used in reports, e.g. ``"three_link_modified"``.
    n_q : int
        Actuator values per pose (3, or 6 for the F1).
    orientation : bool
        Whether the model determines the plate orientation (six-link, F1). A model
        without it has a constant orientation and position-only FK.
    links : tuple of tuple of str
        Link names per arm, e.g. ``(("1",), ("2a", "2b"), ("3a", "3b", "3c"))``.
    """

    name: str = "closure_model"
    n_q: int = 3
    orientation: bool = False
    links: tuple[tuple[str, ...], ...] = (("1",), ("2",), ("3",))

    # -------------------------------------------------------------- to implement
    @abstractmethod
    def parameter_names(self) -> tuple[str, ...]:
        """Names of all model parameters, in the order of :meth:`parameter_vector`.

        Returns
        -------
        tuple of str
            E.g. ``("L1", "As1_x", ...)``; quaternion components end in ``_w, _x, _y, _z``.
        """

    @abstractmethod
    def parameter_vector(self) -> np.ndarray:
        """Current parameter values (SI units).

        Returns
        -------
        numpy.ndarray, shape (n_parameters,)
        """

    @abstractmethod
    def link_points(self, p: ca.SX, q: ca.SX, T: ca.SX, R: ca.SX, arm: int) -> tuple[ca.SX, ca.SX, ca.SX]:
        """Joint points and link lengths of one arm, symbolically.

        Parameters
        ----------
        p : casadi.SX, shape (n_parameters,)
            Parameter vector.
        q : casadi.SX, shape (n_q,)
            Actuator values of the pose [m, rad].
        T : casadi.SX, shape (3,)
            TCP position [m].
        R : casadi.SX, shape (3, 3)
            Plate orientation ``R_T`` (ignored by constant-orientation models).
        arm : int
            Arm index 0, 1, 2.

        Returns
        -------
        A : casadi.SX, shape (3, n_links)
            Actuator-side joint points [m].
        B : casadi.SX, shape (3, n_links)
            Plate-side joint points [m].
        L : casadi.SX, shape (n_links,)
            Link lengths [m].
        """

    @abstractmethod
    def with_parameters(self, p: np.typing.ArrayLike) -> "ClosureModel":
        """The same model with other parameter values.

        Parameters
        ----------
        p : array_like, shape (n_parameters,)
            New values.

        Returns
        -------
        ClosureModel
        """

    @abstractmethod
    def transformed(self, R: np.typing.ArrayLike, t: np.typing.ArrayLike) -> "ClosureModel":
        """The model moved into another frame, ``x' = R x + t`` (Dressler (2012), eqs. 5.3-5.4).

        Parameters
        ----------
        R : array_like, shape (3, 3)
            Rotation of the frame change.
        t : array_like, shape (3,)
            Translation [m].

        Returns
        -------
        ClosureModel
            Points and directions are transformed; lengths are unchanged.
        """

    # -------------------------------------------------------------- derived
    @property
    def n_parameters(self) -> int:
        """Number of parameters."""
        return len(self.parameter_names())

    @property
    def n_links(self) -> int:
        """Number of links (closure equations per pose)."""
        return sum(len(a) for a in self.links)

    def pose_inputs(self, measurements: Any) -> np.ndarray:
        """Per-pose inputs of the closure equations built from a measurement set.

        The actuator values ``q``. A model with further known per-pose inputs overrides
        this (the elasto-geometric closure appends the plate load). The calibration
        (:class:`~gtmodel.calibration.kinematic.CalibrationProblem`) and the evaluation
        (:func:`~gtmodel.calibration.evaluation.evaluate`, eq. 5.5) call it.

        Parameters
        ----------
        measurements : MeasurementSet
            Measured poses (:class:`gtmodel.calibration.measurements.MeasurementSet`).

        Returns
        -------
        numpy.ndarray, shape (N, n_q)
            Actuator values [m or rad].

        Raises
        ------
        InputError
            If the measurements hold another number of actuator columns than the model.
        """
        q = np.asarray(measurements.q, dtype=float)
        if q.ndim != 2 or q.shape[1] != self.n_q:
            raise InputError(f"measurements: {q.shape[-1] if q.ndim else 0} actuator columns, the model {self.name} needs {self.n_q}")
        return q

    def quaternion_indices(self) -> list[tuple[int, int, int, int]]:
        """Indices of parameters that are quaternions ``(w, x, y, z)``, as 4-tuples.

        Returns
        -------
        list of tuple of int
            Empty unless the model has orientation parameters (F1).
        """
        return []

    @cached_property
    def _symbols(self) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
        return (
            ca.SX.sym("p", self.n_parameters),
            ca.SX.sym("q", self.n_q),
            ca.SX.sym("T", 3),
            ca.SX.sym("quat", 4),
        )

    def closure_expression(self, arm: int) -> tuple[ca.SX, tuple[ca.SX, ca.SX, ca.SX, ca.SX]]:
        """Closure residuals of one arm as an expression, Dressler (2012), eqs. 5.1-5.2.

        Parameters
        ----------
        arm : int
            Arm index 0, 1, 2.

        Returns
        -------
        r : casadi.SX, shape (n_links_of_arm,)
            ``||A_ij - B_ij||^2 - L_ij^2`` [m^2] per link.
        symbols : tuple of casadi.SX
            ``(p, q, T, quat)``, the symbols ``r`` depends on.

        Raises
        ------
        InputError
            If ``arm`` is not 0, 1 or 2.
        """
        if arm not in range(len(self.links)):
            raise InputError(f"arm must be one of 0..{len(self.links) - 1}, got {arm!r}")
        p, q, T, quat = self._symbols
        A, B, L = self.link_points(p, q, T, quaternion_to_rotation(quat), arm)
        D = A - B
        r = ca.sum1(D * D).T - L * L
        return r, (p, q, T, quat)

    def closure_function(self, arm: int) -> ca.Function:
        """CasADi Function ``closure(p, q, T, quat) -> r`` of one arm (eqs. 5.1-5.2).

        Parameters
        ----------
        arm : int
            Arm index 0, 1, 2.

        Returns
        -------
        casadi.Function
            Inputs ``p`` (n_parameters), ``q`` (n_q), ``T`` (3), ``quat`` (4, ignored by
            constant-orientation models); output ``r`` (links of the arm) [m^2].

        Raises
        ------
        InputError
            If ``arm`` is not 0, 1 or 2.
        """
        r, syms = self.closure_expression(arm)
        return ca.Function(f"closure_arm{arm + 1}", list(syms), [r], ["p", "q", "T", "quat"], ["r"])

    def graphs(self) -> dict[str, ca.Function]:
        """The CasADi Functions of the model used by solvers and the code generator, by name.

        The public graph interface of a closure model: the code generator
        (:mod:`gtmodel.codegen`) and the solvers use these Functions and public members
        only. Here the closure equations of each arm, ``"closure_arm1"`` ..
        ``"closure_arm3"`` (:meth:`closure_function`: ``(p, q, T [m], quat) -> r [m^2]``);
        models add their own (inverse and forward kinematics, Newton steps, Jacobians;
        see their ``graphs``).

        Returns
        -------
        dict of str to casadi.Function
        """
        return {f"closure_arm{arm + 1}": self.closure_function(arm) for arm in range(len(self.links))}

    def arm_parameter_indices(self, arm: int) -> np.ndarray:
        """Indices of the parameters the closure equations of an arm depend on.

        Read from the expression graph (Jacobian sparsity), so a parameter shared by
        arms (e.g. the common ``v`` of the ideal model) shows up in each.

        Parameters
        ----------
        arm : int
            Arm index 0, 1, 2.

        Returns
        -------
        numpy.ndarray of int
            Sorted indices into :meth:`parameter_vector`.

        Raises
        ------
        InputError
            If ``arm`` is not 0, 1 or 2.
        """
        r, (p, *_rest) = self.closure_expression(arm)
        sp = ca.jacobian(r, p).sparsity()
        cols = sorted({int(c) for c in sp.get_col()})
        return np.array(cols, dtype=int)

    def pose_unknowns(self) -> int:
        """Number of pose unknowns of the generic FK: 3 (position) or 6 (with orientation).

        Returns
        -------
        int
        """
        return 6 if self.orientation else 3

    @cached_property
    def _pose_residual(self) -> ca.Function:
        p, q, T, _ = self._symbols
        r_vec = ca.SX.sym("r", 3)
        R0 = ca.SX.sym("R0", 3, 3)
        R = ca.mtimes(rotation_vector_to_rotation(r_vec), R0) if self.orientation else R0
        res = []
        for arm in range(len(self.links)):
            A, B, L = self.link_points(p, q, T, R, arm)
            D = A - B
            res.append(ca.sum1(D * D).T - L * L)
        x = ca.vertcat(T, r_vec) if self.orientation else T
        return ca.Function("pose_residual", [x, ca.vertcat(q, p, ca.vec(R0))], [ca.vertcat(*res)])

    def pose_function(self, max_iter: int = POSE_MAX_ITER) -> ca.Function:
        """Generic forward kinematics: Newton's method on all closure equations.

        Unknowns are ``T`` and, for models with orientation, a rotation vector ``r`` with
        ``R_T = Rot(r) R0`` about a reference orientation ``R0`` (a local parametrisation
        free of the ZYZ gimbal lock at the nominal orientation, cf. Dressler (2012),
        eq. 4.15). The system is square (as many closure equations as unknowns).

        Parameters
        ----------
        max_iter : int, optional
            Newton iteration limit.

        Returns
        -------
        casadi.Function
            ``pose(x0, qpR0) -> x`` with ``x = T`` or ``(T, r)``, ``qpR0 = (q, p, vec(R0))``.
            Non-convergence is not an exception inside the Function; :meth:`fk_newton`
            checks the residual.

        Raises
        ------
        InputError
            If the number of closure equations differs from the number of unknowns.
        """
        n_x = self.pose_unknowns()
        if self.n_links != n_x:
            raise InputError(f"{self.name}: generic FK needs as many links ({self.n_links}) as pose unknowns ({n_x})")
        return ca.rootfinder(
            "pose", "newton", self._pose_residual,
            {"abstol": 1e-5 * POSE_TOLERANCE, "max_iter": int(max_iter), "error_on_fail": False},
        )

    @cached_property
    def _pose_residual_jacobian(self) -> ca.Function:
        return jacobian_function(self._pose_residual)

    def fk_newton(
        self,
        q: np.typing.ArrayLike,
        T0: np.typing.ArrayLike,
        R0: np.typing.ArrayLike | None = None,
        max_iter: int = POSE_MAX_ITER,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics by Newton's method from a start pose (generic for every model).

        Where the closure Jacobian at the start is rank-deficient (smallest singular value
        below :data:`~gtmodel.robots.pose_rank.POSE_RANK_RTOL` times the largest: the equations do not determine the
        pose), the pose is the solution nearest to the start, by Gauss-Newton with
        minimum-norm steps; Newton's full steps there follow rounding (the D1 model 5 of
        problems/thesis/d1_error_models_thesis.toml: condition ~5e9, a first step of 0.1 rad
        that 1e-10 of parameter rounding, i.e. the BLAS kernel, decided).

        Parameters
        ----------
        q : array_like, shape (n_q,) or (N, n_q)
            Actuator values [m, rad].
        T0 : array_like, shape (3,) or (N, 3)
            Start TCP positions [m] (e.g. the nominal FK).
        R0 : array_like, shape (3, 3) or (N, 3, 3), optional
            Reference/start orientation; identity by default.
        max_iter : int, optional
            Newton iteration limit.

        Returns
        -------
        T : numpy.ndarray, shape (3,) or (N, 3)
            TCP positions [m].
        R : numpy.ndarray, shape (3, 3) or (N, 3, 3)
            Plate orientations (``R0`` for constant-orientation models).

        Raises
        ------
        ConvergenceError
            If the iteration (``max_iter`` steps) does not reach :data:`POSE_TOLERANCE`,
            naming the pose (row).
        InputError
            If the shapes do not match.
        """
        qa, single = as_rows(q, "q", self.n_q)
        N = qa.shape[0]
        T0a = np.broadcast_to(np.asarray(T0, dtype=float), (N, 3))
        R0a = np.broadcast_to(np.eye(3) if R0 is None else np.asarray(R0, dtype=float), (N, 3, 3))
        solver = self.pose_function(max_iter)
        p = self.parameter_vector()
        n_x = self.pose_unknowns()
        x0 = np.zeros((n_x, N))
        x0[:3] = T0a.T
        par = np.vstack([qa.T, np.repeat(p[:, None], N, axis=1), R0a.transpose(0, 2, 1).reshape(N, 9).T])
        x = np.array(solver.map(N)(x0, par))
        res = np.array(self._pose_residual.map(N)(x, par))
        bad = np.flatnonzero(~np.all(np.abs(res) <= POSE_TOLERANCE, axis=0) | ~np.all(np.isfinite(x), axis=0))
        # closure equations that do not determine the pose at the start (the joined arms of an
        # ArmwiseClosure whose source collapsed an arm's links onto one line): Newton's steps along
        # the undetermined directions are set by rounding, so the pose is the nearest solution instead
        deficient = np.flatnonzero(~(inverse_condition(self._pose_residual_jacobian, x0, par) >= POSE_RANK_RTOL))
        if deficient.size:
            x[:, deficient] = min_norm_gauss_newton(self._pose_residual, self._pose_residual_jacobian, x0[:, deficient],
                                                    par[:, deficient], max_iter, 1e-5 * POSE_TOLERANCE)
            res[:, deficient] = np.array(self._pose_residual.map(deficient.size)(x[:, deficient], par[:, deficient]))
            bad = np.flatnonzero(~np.all(np.abs(res) <= POSE_TOLERANCE, axis=0) | ~np.all(np.isfinite(x), axis=0))
        if bad.size:
            k = int(bad[0])
            raise ConvergenceError(
                f"{self.name}: forward kinematics did not converge for pose row {k} "
                f"(q = {qa[k].tolist()}, max |closure residual| {np.nanmax(np.abs(res[:, k])):.3g} m^2 "
                f"after at most {max_iter} Newton iterations); {bad.size} pose(s) failed"
            )
        T = x[:3].T
        if self.orientation:
            R = np.array([rotation_vector_to_rotation(x[3:, k]) @ R0a[k] for k in range(N)])
        else:
            R = np.array(R0a)
        return (T[0], R[0]) if single else (T, R)

    def fk(self, q: np.typing.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics of the model's nominal assembly mode.

        Parameters
        ----------
        q : array_like, shape (n_q,) or (N, n_q)
            Actuator values [m, rad].

        Returns
        -------
        T : numpy.ndarray, shape (3,) or (N, 3)
            TCP positions [m].
        R : numpy.ndarray, shape (3, 3) or (N, 3, 3)
            Plate orientations.

        Raises
        ------
        ConvergenceError
            If an iterative FK does not converge.
        UnreachablePoseError
            If the actuator values admit no assembly.
        """
        raise NotImplementedError  # pragma: no cover - every concrete model overrides it


# ------------------------------------------------------------------ 3-link model
class ThreeLinkClosure(ClosureModel):
    """The simplified 3-link model as a closure model, Dressler (2012), eqs. 4.7-4.9.

    ``A_i = As_i + q_i v_i`` (ideal model: one common ``v``), ``B_i = T``: the plate offset
    is absorbed in ``As_i``, so 3-D position data identify 15 (ideal) or 21 (modified)
    parameters (Dressler (2012), ch. 5.1).

    Parameters
    ----------
    parameters : KinematicParameters or RobotParameters or str or pathlib.Path
        The kinematic parameters, a parameter set or its name/path.
    model : {"ideal", "modified"}, optional
        Parametrisation; default: the parameter set's own ``model``. Asking for
        ``"ideal"`` from a modified set uses the mean guideway direction.

    Raises
    ------
    InputError
        If ``model`` is not ``"ideal"`` or ``"modified"``.
    """

    orientation = False
    n_q = 3
    links = (("1",), ("2",), ("3",))

    def __init__(self, parameters: KinematicParameters | RobotParameters | str | Path, model: str | None = None) -> None:
        if isinstance(parameters, KinematicParameters):
            kp, self.robot = parameters, None
        else:
            self.robot = parameters if isinstance(parameters, RobotParameters) else load_parameters(parameters)
            kp = self.robot.kinematics
        model = kp.model if model is None else model
        if model not in ("ideal", "modified"):
            raise InputError(f"model must be 'ideal' or 'modified', got {model!r}")
        v = np.asarray(kp.v, dtype=float)
        if model == "ideal":
            v = np.repeat(v.mean(axis=0)[None, :], 3, axis=0)
        self.kinematics = KinematicParameters(
            L=np.asarray(kp.L, dtype=float).copy(), As=np.asarray(kp.As, dtype=float).copy(), v=v, model=model, source=kp.source
        )
        self.model = model
        self.name = f"three_link_{model}"

    def parameter_names(self) -> tuple[str, ...]:
        """Names ``L1..L3, As1_x..As3_z`` then ``v_x, v_y, v_z`` (ideal) or ``v1_x..v3_z``.

        Returns
        -------
        tuple of str
        """
        names = [f"L{i + 1}" for i in range(3)] + [f"As{i + 1}_{c}" for i in range(3) for c in "xyz"]
        if self.model == "ideal":
            names += [f"v_{c}" for c in "xyz"]
        else:
            names += [f"v{i + 1}_{c}" for i in range(3) for c in "xyz"]
        return tuple(names)

    def parameter_vector(self) -> np.ndarray:
        """Current values in the order of :meth:`parameter_names`.

        Returns
        -------
        numpy.ndarray, shape (15,) or (21,)
        """
        k = self.kinematics
        vv = k.v[0] if self.model == "ideal" else k.v.ravel()
        return np.concatenate([k.L, k.As.ravel(), vv])

    def _unpack(self, p: Any) -> tuple[Any, Any, Any]:
        L = p[0:3]
        As = [p[3 + 3 * i: 6 + 3 * i] for i in range(3)]
        if self.model == "ideal":
            v = [p[12:15]] * 3
        else:
            v = [p[12 + 3 * i: 15 + 3 * i] for i in range(3)]
        return L, As, v

    def link_points(self, p: ca.SX, q: ca.SX, T: ca.SX, R: ca.SX, arm: int) -> tuple[ca.SX, ca.SX, ca.SX]:
        """``A = As_i + q_i v_i``, ``B = T``, ``L = L_i`` (eq. 4.9).

        Parameters
        ----------
        p : casadi.SX, shape (15,) or (21,)
            Parameters.
        q : casadi.SX, shape (3,)
            Cart positions [m].
        T : casadi.SX, shape (3,)
            TCP position [m].
        R : casadi.SX, shape (3, 3)
            Ignored (constant orientation).
        arm : int
            Arm index 0, 1, 2.

        Returns
        -------
        A, B : casadi.SX, shape (3, 1)
            Joint points [m].
        L : casadi.SX, shape (1,)
            Link length [m].
        """
        L, As, v = self._unpack(p)
        return As[arm] + q[arm] * v[arm], T, L[arm]

    def with_parameters(self, p: np.typing.ArrayLike) -> "ThreeLinkClosure":
        """The model with other parameter values.

        Parameters
        ----------
        p : array_like, shape (15,) or (21,)
            Values in the order of :meth:`parameter_names`.

        Returns
        -------
        ThreeLinkClosure

        Raises
        ------
        InputError
            If ``p`` has the wrong size or is not finite.
        """
        pa = np.asarray(p, dtype=float).ravel()
        if pa.size != self.n_parameters or not np.all(np.isfinite(pa)):
            raise InputError(f"{self.name}: expected {self.n_parameters} finite parameters, got {pa.size}")
        L, As, v = self._unpack(pa)
        kp = KinematicParameters(L=np.asarray(L), As=np.vstack(As), v=np.vstack(v), model=self.model, source="calibrated")
        out = ThreeLinkClosure(kp)
        out.robot = self.robot
        return out

    def transformed(self, R: np.typing.ArrayLike, t: np.typing.ArrayLike) -> "ThreeLinkClosure":
        """The model in another frame, ``x' = R x + t`` (eqs. 5.3-5.4).

        Parameters
        ----------
        R : array_like, shape (3, 3)
            Rotation.
        t : array_like, shape (3,)
            Translation [m].

        Returns
        -------
        ThreeLinkClosure
        """
        Rm = np.asarray(R, dtype=float).reshape(3, 3)
        tv = np.asarray(t, dtype=float).reshape(3)
        k = self.kinematics
        kp = KinematicParameters(L=k.L.copy(), As=k.As @ Rm.T + tv, v=k.v @ Rm.T, model=self.model, source=k.source)
        out = ThreeLinkClosure(kp)
        out.robot = self.robot
        return out

    @cached_property
    def three_link(self) -> GantryTau3Kinematics:
        """The closed-form kinematics of the same parameters (:class:`GantryTau3Kinematics`)."""
        return GantryTau3Kinematics(self.kinematics)

    def fk(self, q: np.typing.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Closed-form FK (trilateration, nominal solution), orientation identity.

        Parameters
        ----------
        q : array_like, shape (3,) or (N, 3)
            Cart positions [m].

        Returns
        -------
        T : numpy.ndarray, shape (3,) or (N, 3)
            TCP positions [m].
        R : numpy.ndarray, shape (3, 3) or (N, 3, 3)
            Identity (constant orientation).

        Raises
        ------
        UnreachablePoseError
            If the three spheres do not intersect.
        """
        T = self.three_link.fk(q)
        R = np.eye(3) if T.ndim == 1 else np.broadcast_to(np.eye(3), (T.shape[0], 3, 3)).copy()
        return T, R

    def ik(self, T: np.typing.ArrayLike, configuration: int = 0) -> np.ndarray:
        """Closed-form IK (eq. 4.9), see :meth:`GantryTau3Kinematics.ik`.

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP positions [m].
        configuration : int, optional
            IK configuration 0-7.

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            Cart positions [m].

        Raises
        ------
        UnreachablePoseError
            If a pose is out of reach.
        """
        return self.three_link.ik(T, configuration)

