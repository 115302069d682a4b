"""A calibration comparison: several models calibrated on the same poses and evaluated on others.

Dressler (2012), ch. 5: the measured (or synthetic) poses, optionally reduced by pose
selection (eq. 5.9, :mod:`gtmodel.calibration.pose_choice`), split alternately into
calibration and validation poses; each declared model calibrated on the first and
evaluated on the second (eq. 5.5), beside the start model and, for synthetic data, the
true robot (the noise floor). :class:`CalibrationDeclaration` is what the ``calibration``
problem kind loads; :meth:`CalibrationDeclaration.solve` gives a
:class:`CalibrationOutcome`.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from fnmatch import fnmatchcase
from typing import Any

import numpy as np

from gtmodel._docstrings import SHARED_DOCS, fill_doc
from gtmodel.calibration.evaluation import AccuracyReport, evaluate
from gtmodel.calibration.kinematic import CalibrationProblem
from gtmodel.calibration.pose_choice import choose_poses
from gtmodel.errors import GtModelError, ProblemError
from gtmodel.robots.armwise import ArmwiseClosure
from gtmodel.status import Status

__all__ = ["CalibrationDeclaration", "CalibrationOutcome", "perturbed_model", "start_report"]

_log = logging.getLogger("gtmodel")


@dataclass
class CalibrationDeclaration:
    """A validated calibration problem.

    Parameters
    ----------
    measurements : MeasurementSet
        All poses (before the calibration/validation split).
    cart : CartMeasurements or None
        Cart surveys (piecewise-linear actuator models).
    models : list of dict
        Per model: ``name``, ``type``, ``model`` (start ClosureModel), ``selection``.
    truth : ClosureModel or None
        The true robot of synthetic data (for the noise floor and parameter checks).
    noise_sigma : float or None
        Position noise of synthetic data [m].
    solver : str
        Calibration solver.
    max_iter : int
        Iteration limit.
    align : bool
        Frame alignment.
    source : str
        Where the data come from.
    pose_selection : int or None
        Number of poses to select (eq. 5.9) before splitting.
    truth_exact : bool
        The synthetic data come from ``truth`` exactly (no actuator errors), so its error on
        the data is the noise floor.
    pose_method : str
        ``"condition"`` (eq. 5.9) or ``"random"`` (with ``pose_selection``).
    pose_planned : bool
        Select on the start model's FK instead of the measured positions.
    seed : int
        Seed of the data (the random pose choice).
    build_measurements : callable, optional
        ``() -> (MeasurementSet, source)``: synthetic data made on first use of
        ``measurements`` (given as None), e.g. when solved: an F1 grid takes seconds, and
        loading a problem file stays fast.
    """

    measurements: Any
    cart: Any
    models: list
    truth: Any
    noise_sigma: float | None
    solver: str
    max_iter: int
    align: bool
    source: str
    pose_selection: int | None = None
    truth_exact: bool = True
    pose_method: str = "condition"
    pose_planned: bool = False
    seed: int = 0
    build_measurements: Any = None

    @fill_doc(**SHARED_DOCS)
    def solve(self, *, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> "CalibrationOutcome":
        """Calibrate every model on every second pose and evaluate it on the others (eq. 5.5).

        Parameters
        ----------
        {solve_args}

        Returns
        -------
        CalibrationOutcome
            A model whose evaluation failed has a ``None`` report and a message.

        Raises
        ------
        ProblemError
            Too few poses for a model's free parameters, or an unidentifiable request
            (naming the model); synthetic data that cannot be generated.
        """
        t0 = time.perf_counter()
        data = self.measurements
        selected = None
        extra: dict[str, Any] = {}
        if self.pose_selection is not None:
            choice_ = choose_poses(self.models[0], data, self.pose_selection, self.pose_method, self.pose_planned, self.seed)
            selected, extra["pose_choice"] = choice_.indices, choice_.summary()
            data = data.subset(selected)
        cal, val = data.split_alternate()
        results = []
        starts: dict[str, Any] = {}
        for spec in self.models:
            if spec["type"] == "armwise":
                results.append(_armwise(spec, {name: res for name, res, _, _ in results}, val))
                continue
            _log.info("calibrating %s (%s) on %d poses ...", spec["name"], spec["type"], cal.n_poses)
            try:
                res = CalibrationProblem(spec["model"], spec["selection"]).solve(cal, solver=self.solver, align=self.align, max_iter=self.max_iter)
            except GtModelError as exc:
                raise ProblemError(f"model '{spec['name']}': {exc}") from None
            try:
                report = evaluate(res.model, val, label=spec["name"]) if res.success else None
                msg = res.message
            except GtModelError as exc:
                report, msg = None, f"evaluation failed: {exc}"
            starts[spec["name"]] = start_report(spec["model"].transformed(res.rotation, res.translation), val)
            results.append((spec["name"], res, report, msg))
        floor = None
        if self.truth is not None:
            try:
                floor = evaluate(self.truth, val, label="true robot (noise floor)")
            except GtModelError:
                floor = None
        return CalibrationOutcome(self, cal, val, results, floor, selected, time.perf_counter() - t0, {"start_reports": starts, **extra})


def _armwise(spec: dict[str, Any], calibrated: dict[str, Any], val: Any) -> tuple[str, None, Any, str]:
    """Arms of calibrated models joined (:class:`~gtmodel.robots.armwise.ArmwiseClosure`) and evaluated (eq. 5.5).

    Dressler (2012), Table 5.3, model 5: the arms are calibrated separately, so joining the
    calibrated arms is the calibration of the joined model. A source that did not calibrate,
    or a joined model whose FK fails at a validation pose, gives no report and a message.
    """
    parts = [calibrated.get(a) for a in spec["arms"]]
    bad = [a for a, r in zip(spec["arms"], parts) if r is None or not r.success]
    if bad:
        return spec["name"], None, None, f"not joined: model(s) {bad} did not calibrate"
    try:
        model = ArmwiseClosure([r.model for r in parts], name=spec["name"])
        return spec["name"], None, evaluate(model, val, label=spec["name"]), "arms " + ", ".join(f"{i + 1}: {a}" for i, a in enumerate(spec["arms"]))
    except GtModelError as exc:
        return spec["name"], None, None, f"evaluation failed: {exc}"


def _measurements(self: CalibrationDeclaration) -> Any:
    """The poses (built by ``build_measurements`` on first use)."""
    if self.__dict__.get("_measurements") is None and self.build_measurements is not None:
        _log.info("generating the synthetic measurements ...")
        self.__dict__["_measurements"], self.source = self.build_measurements()
    return self.__dict__.get("_measurements")


def _set_measurements(self: CalibrationDeclaration, value: Any) -> None:
    self.__dict__["_measurements"] = value


CalibrationDeclaration.measurements = property(_measurements, _set_measurements)  # type: ignore[assignment]


@dataclass
class CalibrationOutcome:
    """Results of a calibration problem: one calibration and evaluation per model.

    Parameters
    ----------
    declaration : CalibrationDeclaration
        The problem.
    calibration : MeasurementSet
        The poses used to calibrate.
    validation : MeasurementSet
        The poses used to evaluate.
    results : list
        Per model: ``(name, CalibrationResult or None, AccuracyReport or None, message)``.
    noise_floor : AccuracyReport or None
        The true robot's errors on the validation poses (synthetic data only): what a
        perfect model achieves on the same noise.
    selected : numpy.ndarray or None
        Indices of the selected poses (pose selection).
    solve_time : float
        Total wall time [s].
    extra : dict
        Further figures for reports.
    """

    declaration: CalibrationDeclaration
    calibration: Any
    validation: Any
    results: list
    noise_floor: Any = None
    selected: Any = None
    solve_time: float = 0.0
    extra: dict = field(default_factory=dict)

    @property
    def status(self) -> Status:
        """Worst status over the models (``error`` if a model could not be calibrated)."""
        return Status.worst(res.status if res is not None else ("optimal" if rep is not None else "error") for _, res, rep, _ in self.results)

    @property
    def success(self) -> bool:
        """True when every model calibrated to an optimal solution."""
        return self.status == Status.OPTIMAL


def perturbed_model(model: Any, size: float, seed: int, keep: Any = ()) -> Any:
    """A model with every parameter moved by up to ``size`` (lengths/points) at random.

    Direction-like parameters (guideway ``v`` and quaternions) are perturbed by ``size``
    relative to their unit size, so the start error stays of the order of ``size`` [m].
    Parameters matching a pattern in ``keep`` (fixed ones, tie targets) are not moved:
    a calibration cannot recover a value it holds fixed.

    Parameters
    ----------
    model : ClosureModel
        The model (returned as it is for ``size = 0``).
    size : float
        Largest change of a parameter [m].
    seed : int
        Seed of :func:`numpy.random.default_rng`.
    keep : sequence of str, optional
        Parameter names or :func:`fnmatch.fnmatchcase` patterns (or name prefixes) kept.

    Returns
    -------
    ClosureModel
    """
    if size == 0.0:
        return model
    rng = np.random.default_rng(seed)
    p = model.parameter_vector().copy()
    step = rng.uniform(-size, size, p.size)
    names = model.parameter_names()
    held = [any(fnmatchcase(n, k) or n.startswith(k + "_") for k in keep) for n in names]
    p += np.where(held, 0.0, step)
    return model.with_parameters(p)


def start_report(model: Any, val: Any) -> Any:
    """The uncalibrated start on the validation poses; poses where it cannot assemble are skipped.

    Parameters
    ----------
    model : ClosureModel
        The start model (in the measurement frame).
    val : MeasurementSet
        The validation poses.

    Returns
    -------
    AccuracyReport or None
        None when the model assembles at no pose; ``skipped`` counts the poses left out.
    """
    try:
        return evaluate(model, val, label="start")
    except GtModelError:
        pass
    reps = []
    for k in range(val.n_poses):
        try:
            reps.append(evaluate(model, val.subset([k]), label="start"))
        except GtModelError:
            continue
    if not reps:
        return None
    rep = AccuracyReport(np.vstack([r.error_vectors for r in reps]), label="start")
    rep.skipped = val.n_poses - len(reps)
    return rep
