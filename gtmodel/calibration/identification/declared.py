"""A dynamic identification as declared by a problem file: data, filter, variants, and results.

Dressler (2012), ch. 6.2 and Table 6.3: :class:`DynamicIdentificationDeclaration` holds a
measured log or the settings of synthetic data (a true robot driven along an optimised or
random excitation), the filter and the model variants; :meth:`~DynamicIdentificationDeclaration.solve`
designs and simulates (synthetic data), filters, and identifies every variant by least
squares, giving a :class:`DynamicIdentificationOutcome`.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gtmodel._docstrings import SHARED_DOCS, fill_doc
from gtmodel.calibration.identification.excitation import FourierTrajectory, design_excitation
from gtmodel.calibration.identification.simulation import StribeckTerm
from gtmodel.calibration.identification.identify import identify_dynamics
from gtmodel.calibration.identification.regressor import DynamicRegressor
from gtmodel.calibration.identification.signals import preprocess_log
from gtmodel.calibration.identification.simulation import simulate_log
from gtmodel.errors import GtModelError, ProblemError
from gtmodel.robots import GantryTau3Kinematics, RobotParameters
from gtmodel.status import Status

__all__ = ["DynamicIdentificationDeclaration", "DynamicIdentificationOutcome"]

_log = logging.getLogger("gtmodel")


@dataclass
class DynamicIdentificationDeclaration:
    """A validated dynamic-identification problem.

    Parameters
    ----------
    robot : RobotParameters
        The model's parameter set (kinematics, gravity, Table 6.1 friction).
    configuration : int
        IK configuration.
    log : MotionLog or None
        The measured log (``[data]``), or None for synthetic data.
    truth : dict or None
        Synthetic-data settings (``[truth]``), with the true parameter set under ``robot``.
    excitation : dict
        Excitation settings (synthetic data).
    filter : dict
        :func:`~gtmodel.calibration.preprocess_log` options.
    variants : list of str
        Variants to identify (the first is the main result).
    weighting : str
        Row weighting.
    min_speed : float
        Rows below this cart speed are not fitted [m/s].
    source : str
        Where the data come from.
    """

    robot: RobotParameters
    configuration: int
    log: Any
    truth: dict | None
    excitation: dict
    filter: dict
    variants: list
    weighting: str
    min_speed: float
    source: str

    @fill_doc(**SHARED_DOCS)
    def solve(self, *, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> "DynamicIdentificationOutcome":
        """Design the excitation and simulate (synthetic data), filter, identify every variant.

        Parameters
        ----------
        {solve_args}

        Returns
        -------
        DynamicIdentificationOutcome
            Never None; a variant that failed has ``None`` and the message.

        Raises
        ------
        ProblemError
            The data cannot be filtered (too short, non-uniform sampling, cut-off above
            Nyquist) or the motion leaves the workspace.
        """
        decl = self
        t0 = time.perf_counter()
        design = None
        truth_theta: dict[str, Any] = {}
        try:
            if decl.log is None:
                tr, ex = decl.truth, decl.excitation
                if ex["optimize"]:
                    design = design_excitation(decl.robot, decl.variants[0] if decl.variants[0] in ("model_1", "model_2", "full") else "model_2",
                                               harmonics=ex["harmonics"], period=ex["period"], n_grid=ex["n_grid"],
                                               T_center=ex["T_center"], max_velocity=ex["max_velocity"], max_acceleration=ex["max_acceleration"],
                                               configuration=decl.configuration, seed=ex["seed"], max_iter=ex["max_iter"])
                    trajectory = design.trajectory
                    if verbose:
                        _log.info("excitation: %s, cond %.3g -> %.3g", design.message, design.condition_before, design.condition_after)
                else:
                    rng = np.random.default_rng(ex["seed"])
                    q0 = GantryTau3Kinematics(decl.robot).require_in_workspace(ex["T_center"], decl.configuration)
                    K = ex["harmonics"]
                    trajectory = FourierTrajectory(q0, 0.06 * rng.standard_normal((3, K)), 0.06 * rng.standard_normal((3, K)), ex["period"])
                strib = StribeckTerm(np.asarray(tr["stribeck_amplitude"]), tr["stribeck_velocity"]) if tr["stribeck_amplitude"] is not None else None
                log, _ = simulate_log(trajectory, tr["duration"], tr["robot"], tr["sample_time"], tr["force_noise"], tr["position_noise"],
                                      tr["position_resolution"], strib, tr["seed"], decl.configuration)
            else:
                log = decl.log
            samples = preprocess_log(log, **decl.filter)
        except GtModelError as exc:
            raise ProblemError(f"dynamic identification: {exc}") from None
        results = []
        for v in decl.variants:
            try:
                reg = DynamicRegressor(decl.robot, v, decl.configuration)
                res = identify_dynamics(samples, variant=v, weighting=decl.weighting, min_speed=decl.min_speed, rank_deficient="base", regressor=reg)
                results.append((v, res, res.message))
                if decl.truth is not None:
                    truth_theta[v] = reg.theta_of(decl.truth["robot"].dynamics)
            except GtModelError as exc:
                results.append((v, None, str(exc)))
            if verbose:
                _log.info("variant %s: %s", v, results[-1][2])
        return DynamicIdentificationOutcome(decl, results, samples, log, design, truth_theta, time.perf_counter() - t0)


@dataclass
class DynamicIdentificationOutcome:
    """Results of a dynamic-identification problem.

    Parameters
    ----------
    declaration : DynamicIdentificationDeclaration
        The problem.
    results : list
        Per variant: ``(name, DynamicIdentificationResult or None, message)``.
    samples : DynamicSamples
        The filtered data.
    log : MotionLog
        The raw log.
    design : ExcitationDesign or None
        The optimised excitation (synthetic data with ``optimize = true``).
    truth_theta : dict
        Per variant the true parameter vector (synthetic data; models 1, 3, 4 differ from
        the truth in structure, so only the shared parameters are compared).
    solve_time : float
        Total wall time [s].
    """

    declaration: DynamicIdentificationDeclaration
    results: list
    samples: Any
    log: Any
    design: Any = None
    truth_theta: dict = field(default_factory=dict)
    solve_time: float = 0.0

    @property
    def status(self) -> Status:
        """``optimal`` if every variant was identified, else ``error``."""
        return Status.OPTIMAL if all(r is not None and r.success for _, r, _ in self.results) else Status.ERROR

    @property
    def success(self) -> bool:
        """True when every variant was identified."""
        return self.status.success
