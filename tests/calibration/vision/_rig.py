"""A small stereo rig for the vision tests: the L1 with parallel guideways, two cameras, a cart grid."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from gtmodel.calibration.vision import Camera, Pattern, actuator_grid_poses, look_at
from gtmodel.robots.closure import ThreeLinkClosure

#: Grid step of the test poses [m] (about 30 poses).
STEP = 0.3
DIST_1 = np.array([-0.2, 0.1, 0.001, -0.0015, 0.02])
DIST_2 = np.array([-0.15, 0.05, -0.001, 0.0005, 0.0])


@lru_cache(maxsize=1)
def model() -> ThreeLinkClosure:
    """L1 with one common guideway direction: a common cart shift moves the TCP exactly by |v| Delta."""
    return ThreeLinkClosure("L1_ideal")


@lru_cache(maxsize=1)
def poses() -> np.ndarray:
    return actuator_grid_poses(model(), STEP)


def centre() -> np.ndarray:
    return model().fk(poses())[0].mean(axis=0)


def camera(name: str, position, distortion=np.zeros(5), f: float = 1100.0) -> Camera:
    return Camera(name, 1024, 768, f, f * 1.01, 510.0, 386.0, np.asarray(distortion), look_at(position, centre()), np.asarray(position, float))


def cameras(distorted: bool = True) -> tuple[Camera, Camera]:
    z = np.zeros(5)
    return (camera("camera 1", [-0.6, 5.8, -0.3], DIST_1 if distorted else z),
            camera("camera 2", [0.7, 5.8, -0.45], DIST_2 if distorted else z))


def pattern() -> Pattern:
    return Pattern.five_squares()


def transmission() -> float:
    return float(np.linalg.norm(model().kinematics.v[0]))
