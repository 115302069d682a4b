"""The declaration of a ``vision_calibration`` problem: what a problem file (or a script) solves.

Built by :mod:`gtmodel.problems.kinds.vision_calibration` from a problem file; its
:meth:`VisionDeclaration.solve` runs :func:`~gtmodel.calibration.vision.study.calibrate_from_images`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from gtmodel.calibration.vision.camera import Camera, Pattern
from gtmodel.calibration.vision.images import PatternMount, StereoImages, SyntheticStereo
from gtmodel.calibration.vision.study import VisionStudy, calibrate_from_images
from gtmodel.robots.closure import ThreeLinkClosure

__all__ = ["VisionDeclaration"]


@dataclass
class VisionDeclaration:
    """A loaded ``vision_calibration`` problem.

    Parameters
    ----------
    images : StereoImages
        Poses seen by both cameras.
    cameras : tuple of Camera
        The cameras as the reconstruction assumes them.
    pattern : Pattern
        The pattern.
    mount : PatternMount
        The pattern on the plate.
    start_model : ThreeLinkClosure
        The nominal model.
    pixel_sigma : float
        Corner noise [px].
    transmission : float or None
        TCP travel per cart travel (None: from the start model).
    solver : str
        Least-squares solver.
    max_iter : int
        Iteration limit.
    source : str
        Where the data come from.
    T_tracker : numpy.ndarray, shape (n, 3), or None
        Tracker TCPs of the same poses [m].
    T_true : numpy.ndarray, shape (n, 3), or None
        True TCPs [m] (synthetic).
    synthetic : SyntheticStereo or None
        The synthetic images and truth.
    true_cameras : tuple of Camera or None
        The true cameras (synthetic).
    """

    images: StereoImages
    cameras: tuple[Camera, Camera]
    pattern: Pattern
    mount: PatternMount
    start_model: ThreeLinkClosure
    pixel_sigma: float
    transmission: float | None
    solver: str
    max_iter: int
    source: str
    T_tracker: np.ndarray | None = None
    T_true: np.ndarray | None = None
    synthetic: SyntheticStereo | None = None
    true_cameras: tuple[Camera, Camera] | None = None

    def solve(self, *, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> VisionStudy:
        """Reconstruct and calibrate (:func:`~gtmodel.calibration.vision.study.calibrate_from_images`).

        Parameters
        ----------
        verbose : bool, optional
            Unused (progress goes to the ``gtmodel`` logger).
        previous : Any, optional
            Unused.
        warm_start : bool, optional
            Unused.

        Returns
        -------
        VisionStudy
        """
        return calibrate_from_images(self.images, self.cameras, self.pattern, self.start_model, self.mount, self.pixel_sigma,
                                     self.T_tracker, self.T_true, self.transmission, self.solver, self.max_iter, self.synthetic)
