"""Kind ``vision_calibration``: kinematic calibration from stereo camera images beside the laser tracker.

Dressler (2012), ch. 5.5: two calibrated cameras see a pattern on the end-effector plate;
the bundle adjustment gives the relative orientation of the cameras and the pattern poses,
the TCP with its covariance, and the metric scale from known cart displacements
(:mod:`gtmodel.calibration.vision`); the kinematic calibration then runs on the
reconstructed TCPs, and, where a laser tracker measured the same poses, on the tracker's,
and both are compared (Figures 5.17-5.19, Table 5.6)::

    name = "l1_vision_calibration"
    kind = "vision_calibration"

    [truth]                          # synthetic images of a declared true robot ...
    parameters = "L1"
    actuator_errors = "table_4_1"
    grid_step = 0.15                 # m, cart grid of commanded poses
    # [data]                         # ... or detected corners of a real rig
    # file = "corners.csv"           #   (format: docs/own_data.md)
    # tracker_file = "tracker.csv"   #   optional tracker data of the same poses

    [[cameras]]                      # exactly two
    image_size = [1024, 768]
    focal_px = [1400, 1400]
    principal_point_px = [512, 384]
    distortion = [-0.2, 0.1, 0, 0, 0]         # what the reconstruction assumes
    true_distortion = [-0.14, 0.1, 0, 0, 0]   # [truth] only: the lens as it is
    position = [-0.5, 5.0, -0.2]
    look_at = [0.0, 2.85, -0.5]

    [pattern]                        # five squares, 20 corners (default)
    [measurement]
    pixel_sigma = 0.5                # px
    [calibration]
    start = "L1_ideal"
    parametrisation = "modified"

The result folder holds ``summary.json`` (``status``, the reconstruction and the scale,
the vision measurement error against the tracker with its growth towards the image border,
both calibrations' validation errors against tracker and truth, the largest parameter
difference, the thesis' figures), ``vision_tcp.csv``, ``parameters.toml`` (the vision
calibration), ``parameters_tracker.toml`` and the plots ``camera_views.png``,
``reconstruction.png``, ``vision_errors.png``.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._docstrings import fill_doc
from gtmodel._tables import write_table
from gtmodel.calibration import read_measurements
from gtmodel.calibration.synthetic import ActuatorErrors, synthetic_measurements
from gtmodel.calibration.vision import (
    Camera,
    Pattern,
    PatternMount,
    StereoImages,
    VisionStudy,
    actuator_grid_poses,
    look_at,
    read_stereo_corners,
    synthetic_stereo_images,
)
from gtmodel.calibration.vision.declared import VisionDeclaration
from gtmodel.calibration.vision.reconstruction import common_displacement_pairs
from gtmodel.errors import GtModelError, ProblemError
from gtmodel.problems.base import KIND_DOCS, Column, ProblemFile, ProblemKind, Written
from gtmodel.problems.kinds.calibration_results import _write_parameters
from gtmodel.problems.kinds.schemas.vision_calibration import CameraSection, VisionCalibrationFile
from gtmodel.report.vision import plot_camera_views, plot_reconstruction, plot_vision_errors
from gtmodel.robots import available_parameter_sets
from gtmodel.robots.closure import ThreeLinkClosure

__all__ = ["VisionCalibrationKind", "VisionCalibrationFile", "VisionDeclaration", "MAX_GRID_CANDIDATES"]

_log = logging.getLogger("gtmodel")

#: Most cart-grid candidates a ``truth.grid_step`` may give (each costs a forward kinematics).
MAX_GRID_CANDIDATES = 200_000


def _camera(k: int, c: CameraSection, file: ProblemFile, distortion: Any) -> Camera:
    try:
        R = look_at(c.position, c.look_at, c.up)
        return Camera(c.name or f"camera {k + 1}", int(c.image_size[0]), int(c.image_size[1]), c.focal_px[0], c.focal_px[1],
                      c.principal_point_px[0], c.principal_point_px[1], np.asarray(distortion), R, np.asarray(c.position))
    except GtModelError as exc:
        raise file.wrap(f"cameras[{k}]", exc) from None


class VisionCalibrationKind(ProblemKind):
    """Kinematic calibration from stereo camera images beside the laser tracker (Dressler (2012), ch. 5.5)."""

    name = "vision_calibration"
    schema = VisionCalibrationFile
    title = "kinematic calibration from stereo camera images (bundle adjustment), compared with the laser tracker (Dressler (2012), ch. 5.5)"
    file_descriptions = {
        "vision_tcp.csv": "TCP positions reconstructed from the stereo images, per pose [m]",
        "parameters.toml": "robot parameters calibrated from the camera measurements",
        "parameters_tracker.toml": "robot parameters calibrated from the laser-tracker measurements of the same poses",
        "camera_views.png": "the calibration pattern as both cameras see it",
        "reconstruction.png": "reconstructed TCP positions and their measurement error",
        "vision_errors.png": "vision against laser-tracker calibration: TCP errors per pose",
    }
    columns = (
        Column("vision_measurement_error_mean_m", "vision error [m]", "{:.3e}"),
        Column("vision_calibration_mean_error_m", "vision calibration [m]", "{:.3e}"),
        Column("tracker_calibration_mean_error_m", "tracker calibration [m]", "{:.3e}"),
    )

    @fill_doc(**KIND_DOCS)
    def load(self, doc: VisionCalibrationFile, file: ProblemFile, name: str) -> VisionDeclaration:
        """Build the cameras, the pattern and the start model; read or synthesise the images.

        Parameters
        ----------
        {load_args}

        Returns
        -------
        VisionDeclaration

        Raises
        ------
        ProblemError
            Both or neither of ``[truth]`` and ``[data]``; a bad camera (principal point
            outside the image, axis along ``up``); ``true_distortion`` with ``[data]``; a
            pattern pitch not above its side; a camera that sees the pattern at no pose; too
            few poses; no cart displacement for the scale; a malformed corner file or
            tracker file (the row named); a tracker file without a pose of the corner file.
        """
        if (doc.truth is None) == (doc.data is None):
            raise ProblemError(f"{file.path}: declare exactly one of '[truth]' (synthetic images) and '[data]' (detected corners)")
        shipped = tuple(available_parameter_sets())
        start_ref = file.reference("calibration.start", doc.calibration.start, shipped)
        try:
            start = ThreeLinkClosure(start_ref, model=doc.calibration.parametrisation)
        except GtModelError as exc:
            raise file.wrap("calibration.start", exc) from None
        cams = tuple(_camera(k, c, file, c.distortion) for k, c in enumerate(doc.cameras))
        pattern = self._pattern(doc, file)
        pt = doc.pattern
        try:
            mount = PatternMount.facing(pt.normal, pt.x_axis, pt.offset)
        except GtModelError as exc:
            raise file.wrap("pattern.normal", exc) from None
        ms, cal = doc.measurement, doc.calibration
        common = dict(cameras=cams, pattern=pattern, mount=mount, start_model=start, pixel_sigma=ms.pixel_sigma,
                      transmission=ms.transmission, solver=cal.solver, max_iter=cal.max_iter)
        if doc.data is not None:
            for k, c in enumerate(doc.cameras):
                if c.true_distortion is not None:
                    raise file.fail(f"cameras[{k}].true_distortion", "no value with [data] (only synthetic images have a true lens)", c.true_distortion)
            path = file.data_file("data.file", doc.data.file)
            try:
                images = read_stereo_corners(path, pattern.n_corners, cams)
            except GtModelError as exc:
                raise file.wrap("data.file", exc) from None
            T_tracker = None
            if doc.data.tracker_file is not None:
                T_tracker = _tracker_of(images, file.data_file("data.tracker_file", doc.data.tracker_file), file)
            decl = VisionDeclaration(images, source=f"detected corners from {doc.data.file}", T_tracker=T_tracker, **common)
        else:
            decl = self._synthetic(doc, file, common)
        if decl.images.n_poses < 4:
            raise file.fail("data.file" if doc.data is not None else "truth.grid_step", "at least 4 poses seen by both cameras", decl.images.n_poses)
        if common_displacement_pairs(decl.images.q)[0].size == 0:
            raise file.fail("data.file" if doc.data is not None else "truth.grid_step",
                            "poses with a common cart displacement (all three carts moved by the same distance) for the metric scale", "none")
        return decl

    @staticmethod
    def _pattern(doc: VisionCalibrationFile, file: ProblemFile) -> Pattern:
        pt = doc.pattern
        if pt.type == "corners":
            if pt.corners is None:
                raise file.fail("pattern.corners", 'the corners of a pattern of type = "corners"')
            try:
                return Pattern(np.asarray(pt.corners, dtype=float), name="pattern")
            except GtModelError as exc:
                raise file.wrap("pattern.corners", exc) from None
        if pt.corners is not None:
            raise file.fail("pattern.corners", 'no corners with type = "five_squares" (or type = "corners")', pt.corners)
        if pt.pitch <= pt.side:
            raise file.fail("pattern.pitch", f"a pitch above the side {pt.side:g} m (squares apart)", pt.pitch)
        try:
            return Pattern.five_squares(pt.side, pt.pitch)
        except GtModelError as exc:
            raise file.wrap("pattern.side", exc) from None

    @staticmethod
    def _synthetic(doc: VisionCalibrationFile, file: ProblemFile, common: dict[str, Any]) -> VisionDeclaration:
        tr = doc.truth
        ref = file.reference("truth.parameters", tr.parameters, tuple(available_parameter_sets()))
        try:
            true_model = ThreeLinkClosure(ref)
        except GtModelError as exc:
            raise file.wrap("truth.parameters", exc) from None
        start = common["start_model"]
        travel = np.asarray(start.robot.limits.cart_travel if start.robot is not None else [[-1, 1]] * 3, dtype=float)
        n_cand = int(np.prod(np.floor(np.ptp(travel, axis=1) / tr.grid_step) + 1))
        if n_cand > MAX_GRID_CANDIDATES:
            raise file.fail("truth.grid_step", f"a step giving at most {MAX_GRID_CANDIDATES} cart-grid candidates (this gives {n_cand})", tr.grid_step)
        try:
            q = actuator_grid_poses(start, tr.grid_step)
        except GtModelError as exc:
            raise file.wrap("truth.grid_step", exc) from None
        true_cams = tuple(_camera(k, c, file, c.true_distortion if c.true_distortion is not None else c.distortion)
                          for k, c in enumerate(doc.cameras))
        errors = ActuatorErrors.table_4_1() if tr.actuator_errors == "table_4_1" else None
        exact = synthetic_measurements(true_model, q, "none", actuator_errors=errors, orientation=False)
        syn = synthetic_stereo_images(true_model, q, true_cams, common["pattern"], common["mount"], common["pixel_sigma"], tr.seed,
                                      doc.measurement.max_obliquity_deg, plate_poses=(exact.T, true_model.fk(q)[1]))
        for j in range(2):
            if not np.any(syn.detected[:, j]):
                reasons = ", ".join(f"{r}: {n}" for r, n in zip(*np.unique(syn.reason[:, j], return_counts=True)))
                raise file.fail(f"cameras[{j}]", "a camera that sees the pattern at some pose", f"none of {q.shape[0]} poses ({reasons})")
        T_tracker = None
        if syn.images.n_poses:
            T_tracker = synthetic_measurements(true_model, syn.images.q, tr.tracker_noise, actuator_errors=errors, seed=tr.seed + 1,
                                               orientation=False).T
        source = (f"SYNTHETIC: true robot {tr.parameters} (actuator errors {tr.actuator_errors}), cart grid {tr.grid_step:g} m, "
                  f"{q.shape[0]} poses, {syn.images.n_poses} seen by both cameras; tracker {tr.tracker_noise}; seed {tr.seed}")
        return VisionDeclaration(syn.images, source=source, T_tracker=T_tracker, T_true=syn.T[syn.rows], synthetic=syn,
                                 true_cameras=true_cams, **common)

    @fill_doc(**KIND_DOCS)
    def write(self, declaration: VisionDeclaration, solution: VisionStudy, out: Path, plots: bool, name: str) -> Written:
        """Summary fields, ``vision_tcp.csv``, the parameter files and the plots.

        Parameters
        ----------
        declaration : VisionDeclaration
            The problem.
        solution : VisionStudy
            Its result.
        {write_args}

        Returns
        -------
        Written
            ``status``, the study's :meth:`~gtmodel.calibration.vision.study.VisionStudy.summary`,
            the relative orientation of the cameras and, for synthetic data, its error.
        """
        s, d = solution, declaration
        summ = s.summary()
        rec = s.reconstruction
        fields: dict[str, Any] = {
            "status": s.status,
            "message": s.message,
            "source": d.source,
            **summ,
            "vision_measurement_error_mean_m": summ.get("vision_measurement_error_mean_m"),
            "vision_calibration_mean_error_m": float(s.errors.get("vision_vs_tracker", s.errors["vision_vs_vision"]).mean()),
            "tracker_calibration_mean_error_m": float(s.errors["tracker_vs_tracker"].mean()) if "tracker_vs_tracker" in s.errors else None,
            "relative_orientation": {"R21": rec.R21.tolist(), "t21_m": (rec.scale * rec.t21).tolist(),
                                     "sigma_rotation_rad": np.sqrt(np.diag(rec.cov_relative)[:3]).tolist()},
            "vision_parameters": s.vision.parameters,
            "tracker_parameters": s.tracker.parameters if s.tracker is not None else None,
            "parameter_differences_m": s.parameter_differences() or None,
            "solve_time_s": rec.solve_time_s,
        }
        if d.true_cameras is not None:
            c1, c2 = d.true_cameras
            R21 = c2.R @ c1.R.T
            fields["relative_orientation"]["rotation_error_rad"] = float(np.linalg.norm(_log_rotation(rec.R21 @ R21.T)))
        written = Written(fields)
        sig = np.sqrt(np.einsum("nii->ni", s.cov_vision))
        cols = ["pose", "q1_m", "q2_m", "q3_m", "Tx_m", "Ty_m", "Tz_m", "sigma_x_m", "sigma_y_m", "sigma_z_m", "image_radius"]
        data = [s.images.pose_ids, s.q, s.T_vision, sig, s.radius]
        if s.T_tracker is not None:
            cols += ["tracker_x_m", "tracker_y_m", "tracker_z_m", "error_m"]
            data += [s.T_tracker, np.linalg.norm(s.T_vision - s.T_tracker, axis=1)]
        frame = "tracker frame (best rigid transform)" if s.T_tracker is not None else "camera 1 frame"
        write_table(out / "vision_tcp.csv", cols, np.column_stack(data), (f" vision TCPs in the {frame}; {d.source}",), integer_columns=(0,))
        written.files.append("vision_tcp.csv")
        if s.vision.success:
            _write_parameters(s.vision, out / "parameters.toml", d, f"{name}_vision")
            written.files.append("parameters.toml")
        if s.tracker is not None and s.tracker.success:
            _write_parameters(s.tracker, out / "parameters_tracker.toml", d, f"{name}_tracker")
            written.files.append("parameters_tracker.toml")
        if plots:
            written.files += self._plots(d, s, out, name)
        return written

    @staticmethod
    def _plots(d: VisionDeclaration, s: VisionStudy, out: Path, name: str) -> list[str]:
        cams = d.true_cameras or d.cameras
        missed = None
        if d.synthetic is not None:
            syn = d.synthetic
            centres = syn.T + d.mount.offset  # the 3-link plate only translates
            missed = []
            for j, cam in enumerate(cams):
                uv, depth = cam.project(centres[~syn.detected.all(axis=1)])
                missed.append(uv[(depth > 0) & cam.inside(uv, -0.05 * cam.width)])
        plot_camera_views(cams, s.images.uv, out / "camera_views.png", f"{name}: the pattern in both cameras", missed)
        if s.T_tracker is not None:
            pos = np.array([c.position for c in cams])
            axes = np.array([c.R[2] for c in cams])
        else:  # camera 1 frame
            rec = s.reconstruction
            pos = np.array([np.zeros(3), -rec.scale * rec.R21.T @ rec.t21])
            axes = np.array([[0, 0, 1.0], rec.R21[2]])
        plot_reconstruction(s.T_vision, s.measurement_error, pos, axes, out / "reconstruction.png",
                            f"{name}: reconstructed TCPs" + (" and vision errors" if s.T_tracker is not None else ""))
        e = None if s.measurement_error is None else np.linalg.norm(s.measurement_error, axis=1)
        labels = {"vision_vs_tracker": "vision calibration", "tracker_vs_tracker": "tracker calibration"} if s.T_tracker is not None else \
            {"vision_vs_vision": "vision calibration (vs vision)"}
        plot_vision_errors(e, {lab: s.errors[k] for k, lab in labels.items()}, out / "vision_errors.png", f"{name}: vision vs laser tracker")
        return ["camera_views.png", "reconstruction.png", "vision_errors.png"]


def _log_rotation(R: np.ndarray) -> np.ndarray:
    """Rotation vector of a rotation matrix (angle below pi)."""
    c = np.clip((np.trace(R) - 1) / 2, -1.0, 1.0)
    th = np.arccos(c)
    v = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return v * (0.5 if th < 1e-8 else th / (2 * np.sin(th)))


def _tracker_of(images: StereoImages, path: Path, file: ProblemFile) -> np.ndarray:
    """Tracker TCPs of the corner file's poses, matched by the cart positions."""
    try:
        m = read_measurements(path, n_q=3, min_poses=1)
    except GtModelError as exc:
        raise file.wrap("data.tracker_file", exc) from None
    out = np.empty((images.n_poses, 3))
    for k, q in enumerate(images.q):
        hit = np.flatnonzero(np.all(np.abs(m.q - q) <= 1e-9, axis=1))
        if hit.size == 0:
            raise file.fail("data.tracker_file", f"a row with the cart positions of pose {images.pose_ids[k]} of data.file", f"none for q = {q.tolist()}")
        out[k] = m.T[hit[0]]
    return out

