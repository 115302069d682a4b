"""Accuracy of a (calibrated) kinematic model on measured poses.

Dressler (2012), ch. 5.2, eq. 5.5: the TCP error of pose ``k`` is
``e_k = ||T_m,k - f_fk(q_k, s)||``, evaluated with the model's forward kinematics on poses
not used for the calibration (every second grid point). For 6-D data the orientation error
is reported as the rotation angle of ``R_fk^T R_m`` and as differences of ZYZ Euler angles.
The error vectors' principal directions (ch. 5.4) show where a model is weak, and the
parameter sensitivity of eq. 5.8 (Table 5.10) which parameters matter.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gtmodel.calibration.measurements import MeasurementSet
from gtmodel.errors import InputError
from gtmodel._geometry import rotation_to_zyz
from gtmodel.robots.closure import ClosureModel

__all__ = [
    "AccuracyReport",
    "SensitivityTable",
    "evaluate",
    "parameter_sensitivity",
    "tcp_errors",
    "SENSITIVITY_STEP",
]

#: Parameter perturbation of the sensitivity study, Dressler (2012), eq. 5.8 [m or 1].
SENSITIVITY_STEP = 5e-5


@dataclass
class AccuracyReport:
    """TCP errors of a model on measured poses (Dressler (2012), eq. 5.5).

    Parameters
    ----------
    error_vectors : numpy.ndarray, shape (N, 3)
        ``T_measured - T_model`` per pose [m].
    angle_errors : numpy.ndarray or None, shape (N,)
        Rotation angle of ``R_model^T R_measured`` [rad] (6-D data only).
    euler_errors : numpy.ndarray or None, shape (N, 3)
        ZYZ Euler angles of the measurement minus those of the model, wrapped to
        ``(-pi, pi]`` [rad] (6-D data only).
    label : str
        Name of the model/data pair (reports).
    """

    error_vectors: np.ndarray
    angle_errors: np.ndarray | None = None
    euler_errors: np.ndarray | None = None
    label: str = ""
    errors: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.error_vectors = np.asarray(self.error_vectors, dtype=float).reshape(-1, 3)
        self.errors = np.linalg.norm(self.error_vectors, axis=1)

    @property
    def n_poses(self) -> int:
        """Number of poses."""
        return int(self.errors.size)

    @property
    def mean_error(self) -> float:
        """Mean TCP error [m]."""
        return float(self.errors.mean())

    @property
    def max_error(self) -> float:
        """Largest TCP error [m]."""
        return float(self.errors.max())

    @property
    def rms_error(self) -> float:
        """Root-mean-square TCP error [m]."""
        return float(np.sqrt(np.mean(self.errors**2)))

    def principal_directions(self) -> tuple[np.ndarray, np.ndarray]:
        """Principal directions of the error vectors (Dressler (2012), ch. 5.4).

        Returns
        -------
        directions : numpy.ndarray, shape (3, 3)
            Unit vectors (rows), largest spread first.
        rms : numpy.ndarray, shape (3,)
            RMS error along each direction [m] (about the origin, so a bias counts).
        """
        _, s, vt = np.linalg.svd(self.error_vectors, full_matrices=False)
        return vt, s / np.sqrt(max(self.n_poses, 1))

    def histogram(self, bins: int = 20) -> tuple[np.ndarray, np.ndarray]:
        """Histogram of the TCP errors (Dressler (2012), Fig. 3.8).

        Parameters
        ----------
        bins : int, optional
            Number of bins.

        Returns
        -------
        counts : numpy.ndarray, shape (bins,)
        edges : numpy.ndarray, shape (bins + 1,)
            Bin edges [m].
        """
        return np.histogram(self.errors, bins=bins)

    def to_dict(self) -> dict[str, Any]:
        """The figures of ``summary.json``.

        Returns
        -------
        dict
            ``mean_error_m``, ``max_error_m``, ``rms_error_m``, ``n_poses``, principal
            directions and, for 6-D data, ``mean_angle_error_deg``/``max_angle_error_deg``.
        """
        d, rms = self.principal_directions()
        out: dict[str, Any] = {
            "mean_error_m": self.mean_error,
            "max_error_m": self.max_error,
            "rms_error_m": self.rms_error,
            "n_poses": self.n_poses,
            "principal_directions": d.tolist(),
            "principal_rms_m": rms.tolist(),
        }
        if self.angle_errors is not None:
            out["mean_angle_error_deg"] = float(np.rad2deg(self.angle_errors.mean()))
            out["max_angle_error_deg"] = float(np.rad2deg(self.angle_errors.max()))
            out["max_euler_error_deg"] = np.rad2deg(np.abs(self.euler_errors).max(axis=0)).tolist()
        return out


def _check(model: ClosureModel, data: MeasurementSet) -> np.ndarray:
    """Checked per-pose model inputs: ``q``, or ``model.pose_inputs(data)`` (e.g. q and the plate load)."""
    if not isinstance(model, ClosureModel):
        raise InputError(f"model: expected a ClosureModel, got {type(model).__name__}")
    if not isinstance(data, MeasurementSet):
        raise InputError(f"measurements: expected a MeasurementSet, got {type(data).__name__}")
    return model.pose_inputs(data)


def evaluate(model: ClosureModel, measurements: MeasurementSet, label: str = "") -> AccuracyReport:
    """TCP (and orientation) errors of a model's FK on measured poses, eq. 5.5.

    Parameters
    ----------
    model : ClosureModel
        The model (e.g. the calibrated one).
    measurements : MeasurementSet
        Poses not used for its calibration.
    label : str, optional
        Name in reports.

    Returns
    -------
    AccuracyReport

    Raises
    ------
    InputError
        Mismatched actuator columns.
    ConvergenceError
        If an iterative FK fails on a pose (names the row).
    UnreachablePoseError
        If the model cannot assemble at some measured ``q``.
    """
    q = _check(model, measurements)
    T, R = model.fk(q)
    T = np.asarray(T).reshape(-1, 3)
    angle = euler = None
    if measurements.has_orientation and model.orientation:
        Rm = measurements.rotations()
        Rf = np.asarray(R).reshape(-1, 3, 3)
        Rerr = np.einsum("nji,njk->nik", Rf, Rm)
        angle = np.arccos(np.clip((np.trace(Rerr, axis1=1, axis2=2) - 1) / 2, -1.0, 1.0))
        euler = np.angle(np.exp(1j * (rotation_to_zyz(Rm) - rotation_to_zyz(Rf))))
    return AccuracyReport(measurements.T - T, angle, euler, label or model.name)


@dataclass
class SensitivityTable:
    """Parameter sensitivity of Dressler (2012), eq. 5.8 (Table 5.10).

    Parameters
    ----------
    names : tuple of str
        Parameter names.
    position : numpy.ndarray, shape (n,)
        Mean TCP displacement over the poses for a +-step change of each parameter
        (average of both signs) [m].
    orientation : numpy.ndarray, shape (n,)
        Mean plate rotation angle [rad] (zeros for constant-orientation models).
    cost : numpy.ndarray, shape (n,)
        Mean change of the closure cost sum r^2 (eq. 5.1) [m^4].
    step : float
        The perturbation.
    """

    names: tuple[str, ...]
    position: np.ndarray
    orientation: np.ndarray
    cost: np.ndarray
    step: float

    def ranked(self) -> list[tuple[str, float]]:
        """Parameters by decreasing position sensitivity.

        Returns
        -------
        list of (str, float)
            Name and mean TCP displacement [m].
        """
        order = np.argsort(-self.position)
        return [(self.names[i], float(self.position[i])) for i in order]


def parameter_sensitivity(model: ClosureModel, measurements: MeasurementSet, step: float = SENSITIVITY_STEP) -> SensitivityTable:
    """Sensitivity of the TCP pose and the closure cost to each parameter, eq. 5.8.

    Each parameter is perturbed by ``+step`` and ``-step``; the FK of the perturbed model
    is compared with the unperturbed one on the measured ``q`` (Table 5.10).

    Parameters
    ----------
    model : ClosureModel
        The model.
    measurements : MeasurementSet
        The poses (their ``q``, and ``T``/orientation for the cost).
    step : float, optional
        Perturbation [m or 1]; default 5e-5 as in the thesis.

    Returns
    -------
    SensitivityTable

    Raises
    ------
    InputError
        Non-positive step or mismatched data.
    """
    q = _check(model, measurements)
    if not (np.isfinite(step) and step > 0):
        raise InputError(f"step: expected a positive perturbation, got {step!r}")
    p0 = model.parameter_vector()
    T0, R0 = model.fk(q)
    T0 = np.asarray(T0).reshape(-1, 3)
    R0 = np.asarray(R0).reshape(-1, 3, 3)
    quat = measurements.quat if measurements.quat is not None else np.tile([1.0, 0, 0, 0], (measurements.n_poses, 1))
    closures = [model.closure_function(a).map(measurements.n_poses) for a in range(len(model.links))]

    def cost(m: ClosureModel) -> float:
        p = m.parameter_vector()
        total = 0.0
        for f in closures:
            r = np.asarray(f(p, q.T, measurements.T.T, quat.T))
            total += float(np.sum(r**2))
        return total / measurements.n_poses

    c0 = cost(model)
    n = p0.size
    pos, ori, dc = np.zeros(n), np.zeros(n), np.zeros(n)
    for j in range(n):
        for sign in (1.0, -1.0):
            p = p0.copy()
            p[j] += sign * step
            m = model.with_parameters(p)
            T, R = m.fk(q)
            pos[j] += np.mean(np.linalg.norm(np.asarray(T).reshape(-1, 3) - T0, axis=1)) / 2
            if model.orientation:
                Rerr = np.einsum("nji,njk->nik", np.asarray(R).reshape(-1, 3, 3), R0)
                ori[j] += np.mean(np.arccos(np.clip((np.trace(Rerr, axis1=1, axis2=2) - 1) / 2, -1, 1))) / 2
            dc[j] += abs(cost(m) - c0) / 2
    return SensitivityTable(tuple(model.parameter_names()), pos, ori, dc, float(step))


def tcp_errors(model: ClosureModel, q: np.typing.ArrayLike, T: np.typing.ArrayLike) -> np.ndarray:
    """TCP position errors ``e_k = ||T_k - fk(q_k)||``, Dressler (2012), eq. 5.5.

    Parameters
    ----------
    model : ClosureModel
        The (calibrated) model, in the frame of ``T``.
    q : array_like, shape (N, n_q)
        Actuator values [m, rad].
    T : array_like, shape (N, 3)
        Measured TCP positions [m].

    Returns
    -------
    numpy.ndarray, shape (N,)
        Errors [m].

    Raises
    ------
    InputError
        Mismatched shapes.
    UnreachablePoseError
        If the model's FK has no solution for some ``q``.
    ConvergenceError
        If an iterative FK does not converge.
    """
    qa = np.atleast_2d(np.asarray(q, dtype=float))
    Ta = np.atleast_2d(np.asarray(T, dtype=float))
    if Ta.shape != (qa.shape[0], 3):
        raise InputError(f"T: expected shape ({qa.shape[0]}, 3) to match q, got {Ta.shape}")
    # one implementation of eq. 5.5: the accuracy report's
    return evaluate(model, MeasurementSet(q=qa, T=Ta)).errors
