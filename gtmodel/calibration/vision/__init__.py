"""Calibration from stereo camera images (Dressler (2012), ch. 5.5): the camera as a measuring device.

One module per job: :mod:`~gtmodel.calibration.vision.camera` (pinhole camera with
Brown-Conrady distortion as a CasADi expression, the five-square pattern),
:mod:`~gtmodel.calibration.vision.images` (synthetic images with detection failures, the
corner measurement file), :mod:`~gtmodel.calibration.vision.reconstruction` (bundle
adjustment, TCP with covariance, metric scale), :mod:`~gtmodel.calibration.vision.intersection`
(corners and TCP by intersection of the rays, a cross-check) and :mod:`~gtmodel.calibration.vision.study`
(kinematic calibration on the reconstructed TCPs beside the laser tracker's).
"""

from gtmodel.calibration.vision.camera import Camera, Pattern, look_at, projection_expression, undistort
from gtmodel.calibration.vision.images import (
    PatternMount,
    StereoImages,
    SyntheticStereo,
    actuator_grid_poses,
    read_stereo_corners,
    synthetic_stereo_images,
)
from gtmodel.calibration.vision.intersection import intersect, intersect_tcp
from gtmodel.calibration.vision.reconstruction import StereoReconstruction, bundle_adjust, reconstruct, scale_from_carts, start_values
from gtmodel.calibration.vision.study import VisionStudy, calibrate_from_images, image_radius, vision_calibration_study, vision_tcp_errors_vs_radius

__all__ = [
    "Camera", "Pattern", "look_at", "projection_expression", "undistort", "PatternMount", "StereoImages", "SyntheticStereo",
    "actuator_grid_poses", "read_stereo_corners", "synthetic_stereo_images", "StereoReconstruction", "bundle_adjust",
    "reconstruct", "scale_from_carts", "intersect", "intersect_tcp", "start_values", "VisionStudy", "calibrate_from_images", "image_radius", "vision_calibration_study",
    "vision_tcp_errors_vs_radius",
]
