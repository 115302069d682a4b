"""A joint-stiffness calibration as declared by a problem file: arm, data, and the three methods' results.

Cvitanic (2021), eqs. (3)-(5) and Table 2: :class:`JointStiffnessDeclaration` holds the
nominal arm and the deflection data (measured or synthetic);
:meth:`JointStiffnessDeclaration.solve` runs CP (weight 1), CP with the scaled rotation
weight and DPP, giving a :class:`JointStiffnessOutcome`.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from gtmodel._docstrings import SHARED_DOCS, fill_doc
from gtmodel.calibration.joint_stiffness import DeflectionData, calibrate_cp, calibrate_dpp, cp_dpp_study
from gtmodel.calibration.joint_stiffness_thesis import summarise_table_2
from gtmodel.errors import GtModelError, ProblemError
from gtmodel.robots import SerialArm
from gtmodel.status import Status

__all__ = ["JointStiffnessDeclaration", "JointStiffnessOutcome"]

_log = logging.getLogger("gtmodel")


@dataclass
class JointStiffnessDeclaration:
    """A validated joint-stiffness calibration problem.

    Parameters
    ----------
    arm : SerialArm
        Nominal arm (Jacobian source; also generates synthetic data).
    data : DeflectionData
        Measurements (synthetic or read from a file).
    k_true : numpy.ndarray or None, shape (6,)
        True joint stiffnesses of synthetic data [N m/rad] (None for measured data).
    scaled_rotation_weight : float
        CP rotation weight of the scaled variant [m/rad] (the thesis' 10).
    bounds : str
        ``"none"`` or ``"positive"``.
    source : str
        Description of the data.
    rotation_weight : float, optional
        CP rotation weight [m/rad] (1: a residual in m and rad).
    dpp_step2 : str, optional
        The data of DPP's step 2 (:func:`~gtmodel.calibration.calibrate_dpp`).
    data_for_seed : callable or None, optional
        ``seed -> DeflectionData`` of the synthetic experiment (the Monte Carlo; None: none).
    seeds : int, optional
        Monte-Carlo seeds (``data_for_seed(0 .. seeds - 1)``; 1: none).
    """

    arm: SerialArm
    data: DeflectionData
    k_true: np.ndarray | None
    scaled_rotation_weight: float
    bounds: str
    source: str
    rotation_weight: float = 1.0
    dpp_step2: str = "rotation"
    data_for_seed: Callable[[int], DeflectionData] | None = None
    seeds: int = 1

    @fill_doc(**SHARED_DOCS)
    def solve(self, *, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> "JointStiffnessOutcome":
        """Run the CP (rotation weight), CP (scaled rotation weight) and DPP calibrations, and the Monte Carlo.

        Cvitanic (2021), eqs. (3)-(5) and Table 2 (:func:`~gtmodel.calibration.calibrate_cp`,
        :func:`~gtmodel.calibration.calibrate_dpp`); with ``seeds > 1`` the seeded comparison
        against the truth (:func:`~gtmodel.calibration.cp_dpp_study`,
        :func:`~gtmodel.calibration.joint_stiffness_thesis.summarise_table_2`).

        Parameters
        ----------
        {solve_args}

        Returns
        -------
        JointStiffnessOutcome
            One result per method (each with its status).

        Raises
        ------
        ProblemError
            A calibration that cannot be posed (e.g. an arm without a spherical wrist for DPP).
        """
        decl = self
        t0 = time.perf_counter()
        try:
            results = {
                "CP": calibrate_cp(decl.arm, decl.data, decl.rotation_weight, decl.bounds),
                "CP_rotations_scaled_x10": calibrate_cp(decl.arm, decl.data, decl.scaled_rotation_weight, decl.bounds),
                "DPP": calibrate_dpp(decl.arm, decl.data, decl.bounds, decl.dpp_step2),
            }
            monte_carlo = None
            if decl.seeds > 1 and decl.data_for_seed is not None and decl.k_true is not None:
                w, ws = decl.rotation_weight, decl.scaled_rotation_weight
                ratios = cp_dpp_study(decl.arm, decl.data_for_seed, decl.k_true, decl.seeds, (w, ws), decl.dpp_step2)
                monte_carlo = summarise_table_2(ratios, f"CP w={w:g}", f"CP w={ws:g}")
        except GtModelError as exc:
            raise ProblemError(str(exc)) from None
        if verbose:
            for m, r in results.items():
                _log.info("joint stiffness %s: k = %s MN m/rad (%s)", m, np.round(r.k_theta / 1e6, 3).tolist(), r.status)
        return JointStiffnessOutcome(results, time.perf_counter() - t0, monte_carlo)


@dataclass
class JointStiffnessOutcome:
    """Results of a joint-stiffness calibration problem.

    Parameters
    ----------
    results : dict of str to JointStiffnessResult
        One result per name of :data:`METHODS`.
    solve_time : float
        Wall time [s].
    monte_carlo : dict or None, optional
        The seeded comparison against the truth (:func:`~gtmodel.calibration.joint_stiffness_thesis.summarise_table_2`).
    """

    results: dict[str, Any]
    solve_time: float
    monte_carlo: dict[str, Any] | None = None

    @property
    def status(self) -> Status:
        """Worst status of the calibrations."""
        return Status.worst(Status(r.status) for r in self.results.values())
