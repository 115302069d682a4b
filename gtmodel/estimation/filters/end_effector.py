"""The end-effector state model of the laser tracker + IMU fusion (Cvitanic (2021), eqs. (21)-(29)).

One CasADi graph for every filter (KF, EKF, UKF, particle filter) and the generated C.

Conventions
-----------
* Quaternions are unit, Hamilton, SCALAR-FIRST ``[w, x, y, z]``; ``R(quat)`` rotates vectors of the
  tracker-target (body) frame into the world frame (:func:`gtmodel._geometry.quaternion_to_rotation`).
* State (``rotation=True``, 19-D)::

      x = [p(3), v(3), a(3), quaternion(4), w(3), alpha(3)]

  ``p, v, a``: world position, velocity, acceleration of the tracker TARGET [m, m/s, m/s^2];
  ``w, alpha``: angular velocity and acceleration in the BODY (target) frame [rad/s, rad/s^2].
  Translation only (``rotation=False``, 9-D): ``x = [p, v, a]``, the stacking
  ``[p_1..p_3, v_1..v_3, a_1..a_3]`` of :class:`~gtmodel.estimation.filters.kalman.StationaryKalman`.
* Measurement (``rotation=True``, 13-D)::

      z = [p_m(3), quat_m(4), w_m(3), a_m(3)]

  tracker target position (world) [m] and orientation, gyro and accelerometer in the IMU frame
  [rad/s, m/s^2]. ``rotation=False`` (6-D): ``z = [p_m, a_m]``, the orientation being constant and
  known (``orientation``). The accelerometer is GRAVITY-FREE (a decision: the thesis' simulation
  gives the bias and noise of the linear acceleration).

IMU-to-target transform
-----------------------
``imu_translation`` ``t`` [m] is the lever arm ``r`` from the IMU to the target, expressed in the IMU
frame (reference ``imu_to_target_translation_mm = [-180, -100, 120]``, Table 7). ``imu_rotation``
``R_TI`` maps IMU-frame coordinates to target-frame coordinates, ``v_T = R_TI v_I`` (its columns are
the IMU axes in the target frame; Table 7: ~180 deg about y, ``Ry(pi)``). So the IMU's orientation in
the world is ``R_WI = R(quat) R_TI``, the gyro reads ``w_I = R_TI^T w`` and, by the lever-arm
transform (29) of a rigid body (all vectors in one frame, here the IMU frame)::

    a_target = a_imu + alpha x r + w x (w x r)                                   (29)

the accelerometer reads ``a_imu = R_WI^T a - alpha_I x t - w_I x (w_I x t)``. The angular
acceleration of a rigid body is the same vector in every frame up to the rotation
(``d(R w)/dt = R alpha`` for body-frame ``w``), so (29) holds with body quantities rotated into the
IMU frame. The model takes the transform as an argument: a filter's BELIEF; a simulation measures
with the TRUE one.

Transition over one sample ``dt`` (21)-(28)
-------------------------------------------
* ``[p, v, a]``: constant acceleration (21)-(26), ``x <- kron(A1, I_3) x`` with
  ``A1 = [[1, dt, dt^2/2], [0, 1, dt], [0, 0, 1]]`` (:func:`constant_acceleration`, the matrix
  :class:`~gtmodel.estimation.filters.kalman.StationaryKalman` uses).
* ``[w, alpha]``: ``w <- w + alpha dt``, ``alpha`` constant (the lower 2x2 block of ``A1``).
* quaternion: the kinematics ``quat' = 1/2 quat (x) (0, w)`` (27) integrated over the sample (28)
  with the body rate ``w + alpha t``: ``quat <- quat (x) exp(phi / 2)``,
  ``phi = w dt + alpha dt^2 / 2`` (exact for a constant rate direction; the commutator term
  ``dt^3 w x alpha / 12`` is neglected), then normalised (``quat / |quat|``). ``exp`` is
  :func:`gtmodel._geometry.quat_exp` (smooth at ``phi = 0``, so the AD Jacobian is finite).
  The thesis' exact discrete form of (28) is not in the shipped spec: this is our reading; it
  agrees with the first-order form ``quat + dt/2 quat (x) (0, w)`` followed by the normalisation
  to ``O(|w dt|^3)`` per sample (5e-11 rad at 1 rad/s and 1 kHz).

Process noise (:meth:`EndEffectorModel.process_noise`): piecewise-constant white jerk per sample on
each translation axis, ``Q = sigma_j^2 G G^T`` with ``G = [dt^3/6, dt^2/2, dt]`` (the
StationaryKalman model), the same with the angular jerk on ``[w, alpha]`` (``G = [dt^2/2, dt]``),
and a small white term ``sigma_quat^2 I_4`` on the quaternion: the normalisation's Jacobian removes
the radial direction of the quaternion covariance, which this term keeps positive definite.
The thesis' Appendix B covariances (reference ``Q_diag``, ``R_diag``) are diagonal per-state
variances of the 9-D filter. ``R`` is the same (Table 7: ``R_p = (6.4 um)^2 = 4.1e-11 m^2`` against
``4.03e-11``, ``R_a = (0.39e-3 m/s^2/rtHz)^2 x 1 kHz = 1.52e-4 (m/s^2)^2`` against ``1.54e-4``).
``Q`` is not: Appendix B's ``Q_diag = [2.54e-4, 21.2e-4, 98.1e-4]`` (p, v, a per axis) is a tuned
diagonal; its acceleration entry equals the jerk model's ``(sigma_j dt)^2`` for
``sigma_j = 99 m/s^3`` at 1 kHz, but its position and velocity entries (read in m^2, (m/s)^2) are
many orders above that model's ``(sigma_j dt^3/6)^2``, ``(sigma_j dt^2/2)^2``: a filter with them
follows the tracker for the position and does not integrate the accelerometer. The jerk model is
used (the model the simulation study draws from, so NEES consistency can be checked).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from gtmodel._lazy import lazy_module
from gtmodel._arrays import as_array, as_per_axis, as_rotation, positive_float, positive_int
from gtmodel._geometry import quat_exp, quat_mul, quaternion_to_rotation
from gtmodel.errors import InputError

#: python-control, imported on first use (it imports matplotlib.pyplot: ~2 s of CPU).
control = lazy_module("control")

__all__ = [
    "IMU_TRANSLATION_M",
    "IMU_ROTATION",
    "constant_acceleration",
    "EndEffectorModel",
]

#: Lever arm IMU -> tracker target in the IMU frame [m] (reference ``imu_to_target_translation_mm``).
IMU_TRANSLATION_M = (-0.180, -0.100, 0.120)
#: Rotation IMU frame -> target frame, ``v_T = R_TI v_I``: 180 deg about y (Table 7, "~180 deg about y").
IMU_ROTATION = np.array([[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]])

_ROTATION_TOLERANCE = 1e-9


def constant_acceleration(dt: float, d: int) -> tuple[np.ndarray, np.ndarray]:
    """The constant-acceleration (white-jerk) block of ``d`` axes (Cvitanic (2021), eqs. (21)-(26)).

    Zero-order-hold discretisation (:func:`control.c2d`) of ``p' = v, v' = a, a' = jerk`` with
    the jerk constant over a sample: ``A1 = [[1, dt, dt^2/2], [0, 1, dt], [0, 0, 1]]``,
    ``G1 = [dt^3/6, dt^2/2, dt]``. The axes are stacked ``[p_1..p_d, v_1..v_d, a_1..a_d]``:
    ``A = kron(A1, I_d)``, ``G = kron(G1, I_d)``. Shared by :class:`EndEffectorModel` and
    :class:`~gtmodel.estimation.filters.kalman.StationaryKalman` (Dressler (2012), eq. 7.19).

    Parameters
    ----------
    dt : float
        Sample time [s].
    d : int
        Number of axes.

    Returns
    -------
    A : numpy.ndarray, shape (3d, 3d)
        State transition.
    G : numpy.ndarray, shape (3d, d)
        Jerk input [per m/s^3].

    Raises
    ------
    InputError
        ``dt`` not a positive number or ``d`` not a positive integer.
    """
    dt = positive_float(dt, "dt")
    d = positive_int(d, "d")
    sysc = control.ss([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]], [[0.0], [0.0], [1.0]], np.eye(3), np.zeros((3, 1)))
    sysd = control.c2d(sysc, dt, "zoh")
    eye = np.eye(d)
    return np.kron(np.asarray(sysd.A), eye), np.kron(np.asarray(sysd.B), eye)


def _lever_terms(w: Any, alpha: Any, r: Any) -> Any:
    """``alpha x r + w x (w x r)``: the target's acceleration relative to the IMU (29)."""
    return ca.cross(alpha, r) + ca.cross(w, ca.cross(w, r))


def _unit_quaternion(value: Any, name: str) -> np.ndarray:
    q = as_array(value, (4,), name)
    n = float(np.linalg.norm(q))
    if n < 1e-12:
        raise InputError(f"{name}: expected a quaternion [w, x, y, z] of nonzero norm, got {q.tolist()}")
    return q / n


class EndEffectorModel:
    """The 19-D (or 9-D translation-only) end-effector state model (Cvitanic (2021), eqs. (21)-(29)).

    See the module docstring for the state, measurement and frame conventions.

    Parameters
    ----------
    dt : float
        Sample time [s].
    rotation : bool, optional
        True: the 19-D model with the quaternion, angular velocity and acceleration (EKF/UKF/PF);
        False: the linear 9-D translation-only model (KF).
    imu_translation : array_like, shape (3,), optional
        Lever arm from the IMU to the tracker target in the IMU frame [m] (the filter's belief).
    imu_rotation : array_like, shape (3, 3), optional
        Rotation ``R_TI`` from IMU-frame to target-frame coordinates (``v_T = R_TI v_I``).
    orientation : array_like, shape (4,), optional
        The constant, known target orientation of the translation-only model (normalised);
        ignored when ``rotation`` is True.

    Attributes
    ----------
    nx, nz : int
        State and measurement dimensions (19 and 13, or 9 and 6).
    dt : float
        Sample time [s].
    rotation : bool
        Which model.
    is_linear : bool
        True for the translation-only model (transition and measurement linear).
    imu_translation : numpy.ndarray, shape (3,)
    imu_rotation : numpy.ndarray, shape (3, 3)
    orientation : numpy.ndarray, shape (4,)
    state_slices : dict of str to slice
        ``"position", "velocity", "acceleration"`` and, with rotation, ``"quaternion",
        "angular_velocity", "angular_acceleration"``.
    measurement_slices : dict of str to slice
        ``"position", "accelerometer"`` and, with rotation, ``"quaternion", "gyro"``.
    transition : casadi.Function
        ``"transition"(x[nx]) -> x_next[nx]``, eqs. (21)-(28) with the quaternion normalised.
    measurement : casadi.Function
        ``"measurement"(x[nx]) -> z[nz]``, with the lever arm (29) and the IMU rotation.
    transition_jacobian : casadi.Function
        ``"transition_jacobian"(x) -> F[nx, nx]`` (CasADi AD of :attr:`transition`).
    measurement_jacobian : casadi.Function
        ``"measurement_jacobian"(x) -> H[nz, nx]`` (CasADi AD of :attr:`measurement`).
    lever_arm_acceleration : casadi.Function
        ``"lever_arm"(a_imu[3], w[3], alpha[3]) -> a_target[3]``, eq. (29) in the IMU frame with
        ``r = imu_translation`` (all vectors in the IMU frame).

    Raises
    ------
    InputError
        ``dt`` not positive, a transform of another shape or not finite, ``imu_rotation`` not a
        rotation, ``orientation`` of zero norm.
    """

    def __init__(
        self,
        dt: float,
        rotation: bool = True,
        imu_translation: Any = IMU_TRANSLATION_M,
        imu_rotation: Any = IMU_ROTATION,
        orientation: Any = (1.0, 0.0, 0.0, 0.0),
    ) -> None:
        self.dt = positive_float(dt, "dt")
        if not isinstance(rotation, (bool, np.bool_)):
            raise InputError(f"rotation: expected True or False, got {rotation!r}")
        self.rotation = bool(rotation)
        self.is_linear = not self.rotation
        self.imu_translation = as_array(imu_translation, (3,), "imu_translation")
        self.imu_rotation = as_rotation(imu_rotation, "imu_rotation", _ROTATION_TOLERANCE)
        self.orientation = _unit_quaternion(orientation, "orientation")
        self.nx = 19 if self.rotation else 9
        self.nz = 13 if self.rotation else 6
        self.state_slices = {"position": slice(0, 3), "velocity": slice(3, 6), "acceleration": slice(6, 9)}
        if self.rotation:
            self.state_slices.update(
                quaternion=slice(9, 13), angular_velocity=slice(13, 16), angular_acceleration=slice(16, 19)
            )
            self.measurement_slices = {
                "position": slice(0, 3),
                "quaternion": slice(3, 7),
                "gyro": slice(7, 10),
                "accelerometer": slice(10, 13),
            }
        else:
            self.measurement_slices = {"position": slice(0, 3), "accelerometer": slice(3, 6)}
        self._A, self._G = constant_acceleration(self.dt, 3)
        self._build()

    # -- the graph -------------------------------------------------------------------------
    def _build(self) -> None:
        x = ca.SX.sym("x", self.nx)
        sl = self.state_slices
        pva = x[0:9]
        pva_next = ca.mtimes(ca.DM(self._A), pva)  # (21)-(26)
        r_ti = ca.DM(self.imu_rotation)
        t = ca.DM(self.imu_translation)
        if self.rotation:
            quat, w, alpha = x[sl["quaternion"]], x[sl["angular_velocity"]], x[sl["angular_acceleration"]]
            a1 = self._A[np.ix_([3, 6], [3, 6])]  # [v, a] rows of kron(A1, I3) at axis 0: [[1, dt], [0, 1]]
            w_next = a1[0, 0] * w + a1[0, 1] * alpha
            phi = w * self.dt + alpha * (self.dt**2 / 2.0)
            q_next = quat_mul(quat, quat_exp(phi))  # (27)-(28)
            q_next = q_next / ca.norm_2(q_next)
            x_next = ca.vertcat(pva_next, q_next, w_next, alpha)
            r_wi = ca.mtimes(quaternion_to_rotation(quat, normalise=False), r_ti)
            w_i = ca.mtimes(r_ti.T, w)
            alpha_i = ca.mtimes(r_ti.T, alpha)
        else:
            x_next = pva_next
            r_wi = ca.DM(quaternion_to_rotation(self.orientation, normalise=False) @ self.imu_rotation)
            w_i = alpha_i = ca.DM.zeros(3)
        a_target_i = ca.mtimes(r_wi.T, x[sl["acceleration"]])
        a_imu = a_target_i - _lever_terms(w_i, alpha_i, t)  # (29) solved for the IMU's acceleration
        if self.rotation:
            z = ca.vertcat(x[sl["position"]], x[sl["quaternion"]], w_i, a_imu)
        else:
            z = ca.vertcat(x[sl["position"]], a_imu)
        self.transition = ca.Function("transition", [x], [x_next], ["x"], ["x_next"])
        self.measurement = ca.Function("measurement", [x], [z], ["x"], ["z"])
        self.transition_jacobian = ca.Function("transition_jacobian", [x], [ca.jacobian(x_next, x)], ["x"], ["F"])
        self.measurement_jacobian = ca.Function("measurement_jacobian", [x], [ca.jacobian(z, x)], ["x"], ["H"])
        a_s, w_s, al_s = ca.SX.sym("a_imu", 3), ca.SX.sym("w", 3), ca.SX.sym("alpha", 3)
        self.lever_arm_acceleration = ca.Function(
            "lever_arm", [a_s, w_s, al_s], [a_s + _lever_terms(w_s, al_s, t)], ["a_imu", "w", "alpha"], ["a_target"]
        )

    # -- noise -------------------------------------------------------------------------------
    def process_noise(self, jerk: Any, angular_jerk: Any = 0.0, quaternion: float = 1e-9) -> np.ndarray:
        """Process-noise covariance ``Q`` of one sample (white jerk, angular jerk, quaternion term).

        ``Q[p,v,a] = kron(G1 G1^T, diag(jerk^2))`` with ``G1 = [dt^3/6, dt^2/2, dt]``
        (:func:`constant_acceleration`: the StationaryKalman model ``G diag(sigma^2) G^T``);
        with rotation also ``Q[w, alpha] = kron(g g^T, diag(angular_jerk^2))``, ``g = [dt^2/2, dt]``,
        and ``Q[quaternion] = quaternion^2 I_4`` (keeps the covariance positive definite in the
        radial direction the normalisation removes; see the module docstring).

        Parameters
        ----------
        jerk : float or array_like, shape (3,)
            Standard deviation of the jerk per sample and axis [m/s^3] (>= 0).
        angular_jerk : float or array_like, shape (3,), optional
            Standard deviation of the angular jerk per sample and body axis [rad/s^3] (>= 0);
            ignored by the translation-only model.
        quaternion : float, optional
            Standard deviation of the white quaternion noise per component and sample [1]
            (> 0 with rotation; ignored without).

        Returns
        -------
        numpy.ndarray, shape (nx, nx)
            Symmetric positive semi-definite.

        Raises
        ------
        InputError
            A negative or non-finite standard deviation, another shape than a number or (3,),
            ``quaternion`` not > 0 for the rotation model.
        """
        sj = as_per_axis(jerk, 3, "jerk", nonnegative=True)
        q = np.zeros((self.nx, self.nx))
        q[:9, :9] = (self._G * sj**2) @ self._G.T
        if self.rotation:
            sw = as_per_axis(angular_jerk, 3, "angular_jerk", nonnegative=True)
            g = self._G[3:9, :]  # [dt^2/2, dt] per axis: rows of v and a
            q[13:19, 13:19] = (g * sw**2) @ g.T
            q[9:13, 9:13] = positive_float(quaternion, "quaternion") ** 2 * np.eye(4)
        return 0.5 * (q + q.T)

    def measurement_noise(
        self, position: float, accelerometer: float, orientation: float = 0.0, gyro: float = 0.0
    ) -> np.ndarray:
        """Diagonal measurement-noise covariance ``R`` from per-sample standard deviations.

        Sensor densities convert as ``sigma = density * sqrt(1 / dt)``. The quaternion's
        standard deviation per component is half the orientation angle's (``quat ~ [1, theta / 2]``).

        Parameters
        ----------
        position : float
            Tracker position noise [m] (> 0).
        accelerometer : float
            Accelerometer noise per sample [m/s^2] (> 0).
        orientation : float, optional
            Tracker orientation noise [rad] (> 0 with rotation).
        gyro : float, optional
            Gyro noise per sample [rad/s] (> 0 with rotation).

        Returns
        -------
        numpy.ndarray, shape (nz, nz)
            Diagonal, positive definite.

        Raises
        ------
        InputError
            A standard deviation not > 0 (the rotation's two only with rotation).
        """
        sp = positive_float(position, "position")
        sa = positive_float(accelerometer, "accelerometer")
        if not self.rotation:
            return np.diag(np.r_[np.full(3, sp**2), np.full(3, sa**2)])
        so = positive_float(orientation, "orientation") / 2.0
        sg = positive_float(gyro, "gyro")
        return np.diag(np.r_[np.full(3, sp**2), np.full(4, so**2), np.full(3, sg**2), np.full(3, sa**2)])

    def __repr__(self) -> str:
        return (
            f"EndEffectorModel(dt={self.dt}, rotation={self.rotation}, imu_translation={self.imu_translation.tolist()}, "
            f"imu_rotation={self.imu_rotation.tolist()}, orientation={self.orientation.tolist()})"
        )

