"""Kinematic calibration from stereo vision beside the laser tracker (Dressler (2012), ch. 5.5).

:func:`vision_calibration_study` reproduces the experiment of the thesis on synthetic
data: a true robot is measured at the same poses by the stereo rig
(:func:`~gtmodel.calibration.vision.images.synthetic_stereo_images`, reconstructed by
:func:`~gtmodel.calibration.vision.reconstruction.reconstruct`) and by a laser tracker
(:func:`~gtmodel.calibration.synthetic.synthetic_measurements`); the vision TCPs are moved
into the tracker frame by the best rigid transform (Kabsch, Figures 5.17-5.18: the vision
measurement error); the same kinematic calibration
(:func:`~gtmodel.calibration.kinematic.calibrate`) runs on every second pose of each data
set and both models are evaluated on the others (eq. 5.5, Figure 5.19), against the tracker
(as the thesis) and against the truth; their parameters are compared (Table 5.6).

The vision error has two sources here: the pixel noise of the corners, and the error of
the camera model the reconstruction assumes (``assumed_cameras``: a distortion calibrated
beforehand, slightly off), which grows towards the image border, as the thesis observed.
:func:`vision_tcp_errors_vs_radius` gives that dependence.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)
from scipy.stats import spearmanr

from gtmodel.calibration.evaluation import tcp_errors
from gtmodel.calibration.kinematic import calibrate
from gtmodel.calibration.kinematic.alignment import fit_rigid_transform
from gtmodel.calibration.kinematic.result import CalibrationResult
from gtmodel.calibration.synthetic import LASER_TRACKER, ActuatorErrors, DeviceNoise, synthetic_measurements
from gtmodel.calibration.vision.camera import Camera, Pattern
from gtmodel.calibration.vision.intersection import intersect_tcp
from gtmodel.calibration.vision.images import PatternMount, StereoImages, SyntheticStereo, synthetic_stereo_images
from gtmodel.calibration.vision.reconstruction import StereoReconstruction, reconstruct
from gtmodel.errors import InputError
from gtmodel.robots.closure import ClosureModel
from gtmodel.status import Status, StatusResult

__all__ = ["REPROJECTION_CHECK_FACTOR", "VisionStudy", "vision_calibration_study", "calibrate_from_images", "image_radius", "THESIS_FIGURES", "vision_tcp_errors_vs_radius"]

_log = logging.getLogger("gtmodel")

#: Self-check: a reprojection RMS above this many declared corner sigmas means the camera
#: model or the detections are not what was declared (the predicted covariance would not be
#: honest): the result is ``check_failed``.
REPROJECTION_CHECK_FACTOR = 2.0

#: The figures of Dressler (2012), ch. 5.5 this study is compared with.
THESIS_FIGURES = {
    "poses_measured": 282,
    "poses_detected": 125,
    "vision_measurement_error_mean_m": 1.7e-3,
    "vision_calibration_error_mean_m": 1.5e-3,
    "tracker_calibration_error_mean_m": 125e-6,
    "parameter_difference_max_m": 9e-3,
    "source": "Dressler (2012), ch. 5.5, Figures 5.17-5.19, Table 5.6",
}


def image_radius(camera: Camera, uv: np.typing.ArrayLike) -> np.ndarray:
    """Distance of pixels from the principal point relative to the image half-diagonal.

    Parameters
    ----------
    camera : Camera
        The camera.
    uv : array_like, shape (..., 2)
        Pixel coordinates [px].

    Returns
    -------
    numpy.ndarray, shape (...)
        0 at the principal point, 1 at an image corner (for a centred principal point).
    """
    a = np.asarray(uv, dtype=float)
    return np.hypot(a[..., 0] - camera.cx, a[..., 1] - camera.cy) / np.hypot(camera.width / 2, camera.height / 2)


@dataclass
class VisionStudy(StatusResult):
    """A calibration from stereo images, beside the laser tracker's where one measured too.

    Parameters
    ----------
    status : Status
        The worst of the reconstruction's and the calibrations'.
    message : str
        Summary.
    images : StereoImages
        The poses seen by both cameras.
    reconstruction : StereoReconstruction
        The stereo reconstruction (camera-1 frame).
    T_vision : numpy.ndarray, shape (n, 3)
        Vision-measured TCPs [m], in the tracker frame when a tracker measured (moved by
        the best rigid transform), else in camera 1's frame.
    cov_vision : numpy.ndarray, shape (n, 3, 3)
        Predicted covariance of ``T_vision`` [m^2].
    frame : tuple of numpy.ndarray
        ``(R, t)``: camera-1 frame (metric) to the frame of ``T_vision``.
    radius : numpy.ndarray, shape (n,)
        Largest image radius of the pattern centre over both cameras (:func:`image_radius`).
    calibration_rows, validation_rows : numpy.ndarray of int
        Rows used to calibrate and to validate (every second).
    vision : CalibrationResult
        The calibration on the vision data.
    errors : dict of str to numpy.ndarray
        Validation errors [m] (eq. 5.5): ``vision_vs_vision`` always; with a tracker
        ``vision_vs_tracker``, ``tracker_vs_tracker`` (as the thesis); with the truth
        ``vision_vs_truth``, ``tracker_vs_truth``.
    T_tracker : numpy.ndarray, shape (n, 3), or None
        Tracker-measured TCPs [m].
    tracker : CalibrationResult or None
        The calibration on the tracker data.
    T_true : numpy.ndarray, shape (n, 3), or None
        True TCPs (synthetic data) [m].
    synthetic : SyntheticStereo or None
        The synthetic images and the truth of every commanded pose.
    """

    images: StereoImages
    reconstruction: StereoReconstruction
    T_vision: np.ndarray
    cov_vision: np.ndarray
    frame: tuple[np.ndarray, np.ndarray]
    radius: np.ndarray
    calibration_rows: np.ndarray
    validation_rows: np.ndarray
    vision: CalibrationResult
    errors: dict[str, np.ndarray] = field(default_factory=dict)
    T_tracker: np.ndarray | None = None
    tracker: CalibrationResult | None = None
    T_true: np.ndarray | None = None
    synthetic: SyntheticStereo | None = None

    @property
    def q(self) -> np.ndarray:
        """Cart positions of the poses seen by both cameras, shape (n, 3) [m]."""
        return self.images.q

    @property
    def measurement_error(self) -> np.ndarray | None:
        """Vision minus tracker TCP, shape (n, 3) [m] (Figure 5.18's vectors); None without a tracker."""
        return None if self.T_tracker is None else self.T_vision - self.T_tracker

    def parameter_differences(self) -> dict[str, float]:
        """Vision minus tracker calibrated parameters (Table 5.6), by name [m or -]; empty without a tracker.

        Returns
        -------
        dict of str to float
        """
        if self.tracker is None:
            return {}
        return {k: float(self.vision.parameters[k] - self.tracker.parameters[k]) for k in self.tracker.parameters}

    def summary(self) -> dict[str, Any]:
        """The figures of the study beside the thesis' (JSON-ready).

        Returns
        -------
        dict
            Poses, reconstruction figures, the vision measurement error (mean, max,
            inner/outer half of the image radius, Spearman correlation with the radius)
            when a tracker measured, the calibrated models' validation errors, the largest
            parameter difference and :data:`THESIS_FIGURES`.
        """
        rec = self.reconstruction
        sig = np.sqrt(np.einsum("nii->ni", self.cov_vision))
        out: dict[str, Any] = {
            "poses_detected": int(self.images.n_poses),
            "reprojection_rms_px": rec.rms_px,
            "bundle_adjustment_iterations": rec.iterations,
            "scale_m_per_unit": rec.scale,
            "scale_pairs": rec.scale_pairs,
            "vision_predicted_sigma_mean_m": sig.mean(axis=0).tolist(),
            "calibration": {name: {"mean_error_m": float(v.mean()), "max_error_m": float(v.max())} for name, v in self.errors.items()},
        }
        if self.synthetic is not None:
            out["poses_commanded"] = int(self.synthetic.q.shape[0])
            out["detection_failures"] = {r: int(np.sum(np.any(self.synthetic.reason == r, axis=1))) for r in ("outside image", "behind camera", "oblique")}
        e = self.measurement_error
        if e is not None:
            e = np.linalg.norm(e, axis=1)
            inner = self.radius <= np.median(self.radius)
            diff = self.parameter_differences()
            worst = max(diff, key=lambda k: abs(diff[k]))
            out.update({
                "vision_measurement_error_mean_m": float(e.mean()),
                "vision_measurement_error_max_m": float(e.max()),
                "vision_measurement_error_inner_half_mean_m": float(e[inner].mean()),
                "vision_measurement_error_outer_half_mean_m": float(e[~inner].mean()) if np.any(~inner) else None,
                "vision_error_radius_spearman": float(spearmanr(self.radius, e).statistic) if e.size > 2 else None,
                "parameter_difference_max_m": abs(diff[worst]),
                "parameter_difference_max_name": worst,
            })
        if "vision_vs_truth" in self.errors:
            v, t = self.errors["vision_vs_truth"].mean(), self.errors["tracker_vs_truth"].mean()
            out.update({"vision_calibration_mean_error_vs_truth_m": float(v), "tracker_calibration_mean_error_vs_truth_m": float(t),
                        "accuracy_ratio_vision_over_tracker": float(v / t)})
        out["thesis"] = THESIS_FIGURES
        return out


def vision_tcp_errors_vs_radius(study: VisionStudy, bins: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Mean vision measurement error per image-radius bin (the border effect of Figure 5.18).

    Parameters
    ----------
    study : VisionStudy
        A study.
    bins : int, optional
        Number of equally populated bins.

    Returns
    -------
    radius : numpy.ndarray, shape (bins,)
        Mean radius per bin (:func:`image_radius`).
    error : numpy.ndarray, shape (bins,)
        Mean error per bin [m].

    Raises
    ------
    InputError
        The study has no tracker measurements.
    """
    if study.measurement_error is None:
        raise InputError("vision_tcp_errors_vs_radius: the study has no tracker measurements to compare with")
    e = np.linalg.norm(study.measurement_error, axis=1)
    order = np.argsort(study.radius)
    parts = np.array_split(order, bins)
    return np.array([study.radius[p].mean() for p in parts]), np.array([e[p].mean() for p in parts])


def calibrate_from_images(
    images: StereoImages,
    cameras: Sequence[Camera],
    pattern: Pattern,
    start_model: ClosureModel,
    mount: PatternMount | None = None,
    pixel_sigma: float = 0.3,
    T_tracker: np.typing.ArrayLike | None = None,
    T_true: np.typing.ArrayLike | None = None,
    transmission: float | None = None,
    solver: str = "lm",
    max_iter: int = 200,
    synthetic: SyntheticStereo | None = None,
) -> VisionStudy:
    """Reconstruct the TCPs from stereo images and calibrate on them (Dressler (2012), ch. 5.5).

    With tracker measurements of the same poses, the vision TCPs are moved into the tracker
    frame (best rigid transform, Figures 5.17-5.18) and a second calibration runs on the
    tracker data; both models are evaluated on the validation poses (every second).

    Parameters
    ----------
    images : StereoImages
        Corners of the poses seen by both cameras.
    cameras : sequence of 2 Camera
        The intrinsics and distortion the reconstruction assumes.
    pattern : Pattern
        The pattern.
    start_model : ClosureModel
        The nominal model the calibrations start from.
    mount : PatternMount, optional
        Pattern on the plate (default facing +y, centred on the TCP).
    pixel_sigma : float, optional
        Corner noise [px] (> 0).
    T_tracker : array_like, shape (n, 3), optional
        Tracker TCPs of the same poses [m].
    T_true : array_like, shape (n, 3), optional
        True TCPs (synthetic data) in the tracker frame [m].
    transmission : float, optional
        TCP travel per cart travel for the scale (default: the mean ``|v_i|`` of ``start_model``).
    solver : str, optional
        Least-squares solver of the calibrations.
    max_iter : int, optional
        Iteration limit of the calibrations.
    synthetic : SyntheticStereo, optional
        Kept in the result (synthetic data).

    Returns
    -------
    VisionStudy
        ``check_failed`` when the reprojection RMS exceeds :data:`REPROJECTION_CHECK_FACTOR`
        times ``pixel_sigma``.

    Raises
    ------
    InputError
        Fewer than 4 poses; tracker or truth of another shape; the errors of the
        reconstruction and of the calibration.
    """
    mount = PatternMount() if mount is None else mount
    n = images.n_poses
    if n < 4:
        raise InputError(f"stereo images: only {n} poses are seen by both cameras (at least 4 needed)")
    for name, arr in (("T_tracker", T_tracker), ("T_true", T_true)):
        if arr is not None and np.shape(arr) != (n, 3):
            raise InputError(f"{name}: expected shape ({n}, 3) (one TCP per pose seen by both cameras), got {np.shape(arr)}")
    if transmission is None:
        transmission = float(np.mean(np.linalg.norm(np.asarray(start_model.kinematics.v, dtype=float), axis=1)))
    rec = reconstruct(images, cameras, pattern, mount.tcp_in_pattern, pixel_sigma, scale="carts", transmission=transmission)
    T_int, _ = intersect_tcp(images, cameras, pattern, rec.R21, rec.t21, pixel_sigma, rec.R, mount.tcp_in_pattern)
    rec.message += f"; TCP by intersection within {rec.scale * np.abs(T_int - rec.T).max() * 1e3:.3g} mm of the bundle adjustment's"
    qd = images.q
    R, t = (np.eye(3), np.zeros(3)) if T_tracker is None else fit_rigid_transform(rec.T_metric, T_tracker)
    T_vis = rec.T_metric @ R.T + t
    cov = np.einsum("ij,njk,lk->nil", R, rec.cov_T_metric, R)
    radius = np.max([image_radius(c, images.uv[:, j].mean(axis=1)) for j, c in enumerate(cameras)], axis=0)
    cal, val = np.arange(0, n, 2), np.arange(1, n, 2)
    res_v = calibrate(start_model, qd[cal], T_vis[cal], solver=solver, max_iter=max_iter)
    errors = {"vision_vs_vision": tcp_errors(res_v.model, qd[val], T_vis[val])}
    res_t = None
    if T_tracker is not None:
        T_tracker = np.asarray(T_tracker, dtype=float)
        res_t = calibrate(start_model, qd[cal], T_tracker[cal], solver=solver, max_iter=max_iter)
        errors["vision_vs_tracker"] = tcp_errors(res_v.model, qd[val], T_tracker[val])
        errors["tracker_vs_tracker"] = tcp_errors(res_t.model, qd[val], T_tracker[val])
        if T_true is not None:
            T_true = np.asarray(T_true, dtype=float)
            errors["vision_vs_truth"] = tcp_errors(res_v.model, qd[val], T_true[val])
            errors["tracker_vs_truth"] = tcp_errors(res_t.model, qd[val], T_true[val])
    status = Status.worst([rec.status, res_v.status] + ([res_t.status] if res_t is not None else []))
    msg = f"{n} poses seen by both cameras; {rec.message}; vision calibration {res_v.status}"
    if rec.rms_px > REPROJECTION_CHECK_FACTOR * pixel_sigma:
        status = Status.worst([status, Status.CHECK_FAILED])
        msg = (f"CHECK FAILED: reprojection RMS {rec.rms_px:.3g} px is above {REPROJECTION_CHECK_FACTOR:g} x the declared corner noise "
               f"{pixel_sigma:g} px (camera model or detections off; the predicted covariance is not honest); " + msg)
    if T_tracker is not None:
        msg += f"; vision error mean {np.linalg.norm(T_vis - T_tracker, axis=1).mean() * 1e3:.3g} mm"
    if "vision_vs_truth" in errors:
        msg += (f"; calibrated mean error vs truth: vision {errors['vision_vs_truth'].mean() * 1e3:.3g} mm, "
                f"tracker {errors['tracker_vs_truth'].mean() * 1e6:.3g} um")
    _log.info(msg)
    return VisionStudy(images, rec, T_vis, cov, (R, t), radius, cal, val, res_v, errors, T_tracker, res_t, T_true, synthetic,
                       status=status, message=msg)


def vision_calibration_study(
    true_model: ClosureModel,
    start_model: ClosureModel,
    q: np.typing.ArrayLike,
    true_cameras: Sequence[Camera],
    assumed_cameras: Sequence[Camera],
    pattern: Pattern,
    mount: PatternMount | None = None,
    pixel_sigma: float = 0.3,
    seed: int = 0,
    tracker_noise: DeviceNoise | str = LASER_TRACKER,
    actuator_errors: ActuatorErrors | None = None,
    max_obliquity_deg: float = 60.0,
    transmission: float | None = None,
    solver: str = "lm",
    max_iter: int = 200,
) -> VisionStudy:
    """Stereo-vision calibration beside the laser tracker on the same synthetic poses (Dressler (2012), ch. 5.5).

    Parameters
    ----------
    true_model : ClosureModel
        The true robot.
    start_model : ClosureModel
        The nominal model both calibrations start from (its parametrisation is calibrated).
    q : array_like, shape (N, 3)
        Commanded poses [m] (a cart grid, :func:`~gtmodel.calibration.vision.images.actuator_grid_poses`).
    true_cameras : sequence of 2 Camera
        The cameras as they are (pose, intrinsics, distortion).
    assumed_cameras : sequence of 2 Camera
        The intrinsics and distortion the reconstruction uses.
    pattern : Pattern
        The pattern.
    mount : PatternMount, optional
        Pattern on the plate (default facing +y, centred on the TCP).
    pixel_sigma : float, optional
        Corner noise [px] (> 0).
    seed : int, optional
        Seed of pixel and tracker noise.
    tracker_noise : DeviceNoise or str, optional
        The tracker (default 10 um).
    actuator_errors : ActuatorErrors, optional
        Actuator errors of the true robot (e.g. ``ActuatorErrors.table_4_1()``, Dressler
        (2012), Table 4.1): what no kinematic model here captures, seen by both devices.
    max_obliquity_deg : float, optional
        Largest detection angle [deg].
    transmission : float, optional
        TCP travel per cart travel for the scale (default: the mean ``|v_i|`` of ``start_model``).
    solver : str, optional
        Least-squares solver of the calibrations.
    max_iter : int, optional
        Iteration limit of the calibrations.

    Returns
    -------
    VisionStudy

    Raises
    ------
    InputError
        A camera that sees the pattern at no pose (``cameras[j]`` named), fewer than 4
        poses seen by both, and the errors of the steps (bad noise, no cart displacement
        pairs, ...).
    """
    mount = PatternMount() if mount is None else mount
    if not (np.isfinite(pixel_sigma) and pixel_sigma > 0):
        raise InputError(f"pixel_sigma: expected a positive corner noise [px], got {pixel_sigma!r}")
    qa = np.atleast_2d(np.asarray(q, dtype=float))
    exact = synthetic_measurements(true_model, qa, "none", actuator_errors=actuator_errors, orientation=False)
    syn = synthetic_stereo_images(true_model, qa, true_cameras, pattern, mount, pixel_sigma, seed, max_obliquity_deg,
                                  plate_poses=(exact.T, true_model.fk(qa)[1]))
    for j, cam in enumerate(true_cameras):
        if not np.any(syn.detected[:, j]):
            reasons = ", ".join(f"{r}: {k}" for r, k in zip(*np.unique(syn.reason[:, j], return_counts=True)))
            raise InputError(f"cameras[{j}] ({cam.name}) sees the pattern at none of the {syn.q.shape[0]} poses ({reasons})")
    qd = syn.images.q
    tracker = synthetic_measurements(true_model, qd, tracker_noise, actuator_errors=actuator_errors, seed=seed + 1, orientation=False) if qd.shape[0] else None
    return calibrate_from_images(syn.images, assumed_cameras, pattern, start_model, mount, pixel_sigma,
                                 None if tracker is None else tracker.T, syn.T[syn.rows], transmission, solver, max_iter, syn)
