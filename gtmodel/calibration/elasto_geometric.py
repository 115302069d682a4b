"""Elasto-geometric calibration: closure equations with gravity-induced link deflection.

Dressler (2012), ch. 5.3 names stiffness in links and joints and gravity-induced link forces
as the next step for calibration accuracy. A compliant Gantry-Tau under the load ``F`` on
its plate (plate, payload and half the link weights) sits at

    T_m = FK(q) + K_x(T)^-1 F                                                     (1)

(:mod:`gtmodel.robots.stiffness`, eqs. 1-3: ``K_x = U^T diag(1/c) U``), not at its rigid
forward kinematics ``FK(q)``. Along each link this is, to first order,
``u_i . (T_m - T_rigid) = c_i f_i`` with the arm force ``f = U^-T F`` and the arm compliance
``c_i = c_l,i + c_a,i (u_i . w_i)^2`` (links and joints in series with the cart's guideway
compliance). The elasto-geometric closure equation of arm ``i`` therefore replaces the link
length by the loaded one (Dressler (2012), eq. 4.9 with eq. 5.1):

    || As_i + q_i v_i - T_m ||^2 - (L_i + c_i(T_m) f_i(T_m))^2 = 0.                     (2)

Choice made here: ``U``, ``c_i`` and ``f_i`` are evaluated symbolically at the *measured* TCP
``T_m`` with the model's current geometry (the difference to the unloaded pose changes
``c_i f_i`` by ~1e-4 relative, ~0.02 um here). :class:`ElastoGeometricClosure` is a
:class:`~gtmodel.robots.closure.ClosureModel` whose link lengths depend on compliance
parameters and on the pose (:mod:`gtmodel.robots.elasto_geometric`), so the whole calibration machinery (frame alignment, LM with the
exact CasADi Jacobian, standard deviations, QR identifiability, FK by Newton's method on
(2), evaluation by eq. 5.5) applies unchanged. The arm forces couple the arms (``f`` depends
on all three link directions), so the three arms form one NLP.

Parameters: the 15/21 geometric parameters of the 3-link model, then ``c_l1..c_l3``
(cluster compliance, links and joints [m/N]), ``c_a1..c_a3`` (cart compliance along the
guideway [m/N]) and ``F_x, F_y, F_z`` (the load on the plate [N], in the model frame; rotated
with the frame alignment). The load is fixed by default: compliances and load enter only
as the products ``c_i f_i``, so they are not separable (one must be known: the payload mass).

Identifiability (checked by the column-pivoted QR of :mod:`~gtmodel.calibration.identifiability`):

- ``c_i`` is separable from ``L_i`` only if the arm force ``f_i`` varies over the poses: for
  a constant ``f_i``, ``c_i f_i`` is a constant change of the link length. Poses that only
  translate along the guideways (all carts moved together) keep every link direction and
  therefore every arm force: there the compliances are not identifiable.
- Link and joint compliance of one cluster carry the same force in series: only their sum
  ``c_l`` is identifiable (hence one parameter per cluster).
- ``c_l,i`` and ``c_a,i`` differ by the factor ``(u_i . w_i)^2`` (0.6-1 over a 40 deg joint
  cone): separable, but strongly correlated (large standard deviations).

What the data must contain: with one constant load (gravity of plate and payload) the arm
forces vary little over the workspace, so the deflection is nearly a constant change of the
link lengths and the geometric parameters absorb it (synthetic L1, 40 kg: geometric-only
validation error 16.3 um against the 15.9 um noise floor; compliance standard deviations
larger than the values). Measuring the poses with known different loads (with and without a
payload) separates the compliances: ``per_pose_load=True`` takes each pose's plate load from
the measurement set's ``load`` field (:attr:`~gtmodel.calibration.measurements.MeasurementSet.load`,
CSV columns ``F_x_N, F_y_N, F_z_N``); then the geometric-only model stays at ~80 um while the elasto-geometric
model reaches the noise floor (``problems/l1_elasto_geometric.toml``).

Synthetic data of a compliant robot (:func:`compliant_measurements`) come from eq. (1)
evaluated with :class:`~gtmodel.robots.stiffness.GantryTau3Stiffness` (the stiffness model,
not a copy), plus the device noise.
"""

from __future__ import annotations

import fnmatch
import logging
import time
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel.calibration.kinematic import (
    DEFAULT_SOLVER,
    MAX_ITER,
    CalibrationProblem,
    CalibrationResult,
    ParameterSelection,
    analyze_identifiability,
)
from gtmodel.calibration.evaluation import AccuracyReport, evaluate
from gtmodel.calibration.identifiability import IdentifiabilityReport
from gtmodel.calibration.measurements import MeasurementSet
from gtmodel.calibration.synthetic import LASER_TRACKER, DeviceNoise, device_noise
from gtmodel.errors import InputError
from gtmodel.status import Status
from gtmodel.robots.closure import ThreeLinkClosure
from gtmodel.robots.elasto_geometric import COMPLIANCE_NAMES, LOAD_NAMES, ElastoGeometricClosure
from gtmodel.robots.stiffness import GantryTau3Stiffness

__all__ = [
    "compliant_measurements",
    "compliance_selection",
    "calibrate_elasto_geometric",
    "compliance_identifiability",
    "explain_identifiability",
    "ElastoGeometricStudy",
    "elasto_geometric_study",
]

_log = logging.getLogger("gtmodel")

# ------------------------------------------------------------------ synthetic data
def compliant_measurements(
    stiffness: GantryTau3Stiffness,
    q: np.typing.ArrayLike,
    noise: DeviceNoise | str = LASER_TRACKER,
    seed: int | None = 0,
    payloads_kg: np.typing.ArrayLike | None = None,
) -> MeasurementSet:
    """Measurements of a compliant robot: ``T_m = FK(q) + K_x^-1 F + noise`` (eq. 1).

    The rigid TCP is the closed-form FK of the robot's kinematics; the deflection under the
    gravity load ``F`` (plate, payload, half the link masses) comes from the stiffness model
    (:meth:`GantryTau3Stiffness.deflection`); the device adds Gaussian noise.

    Parameters
    ----------
    stiffness : GantryTau3Stiffness
        The true robot (geometry, stiffness values, payload).
    q : array_like, shape (N, 3)
        Cart positions [m].
    noise : DeviceNoise or str, optional
        Device noise (default the laser tracker, 10 um per axis).
    seed : int or None, optional
        Seed of :func:`numpy.random.default_rng`.
    payloads_kg : array_like, shape (N,), optional
        Payload of each pose [kg] (poses measured with different payloads). Default: every
        pose with ``stiffness.payload_kg`` and no ``load`` field (one constant load).

    Returns
    -------
    MeasurementSet
        ``q`` and the measured ``T``; with ``payloads_kg`` the ``load`` field holds the
        plate load of each pose [N] (for :class:`ElastoGeometricClosure` with
        ``per_pose_load``). ``source`` states the payload and the stiffness values.

    Raises
    ------
    InputError
        Wrong shape or non-finite ``q``, negative or mis-shaped payloads, unknown device.
    UnreachablePoseError
        The robot cannot assemble at some ``q``.
    """
    if not isinstance(stiffness, GantryTau3Stiffness):
        raise InputError(f"stiffness: expected a GantryTau3Stiffness, got {type(stiffness).__name__}")
    qa = np.atleast_2d(np.asarray(q, dtype=float))
    if qa.ndim != 2 or qa.shape[1] != 3 or qa.shape[0] == 0 or not np.all(np.isfinite(qa)):
        raise InputError(f"q: expected finite cart positions of shape (N, 3), got shape {np.shape(q)}")
    N = qa.shape[0]
    g = stiffness.parameters.dynamics.g
    if payloads_kg is None:
        F = np.repeat(stiffness.gravity_force[None, :], N, axis=0)
        what = f"payload {stiffness.payload_kg:g} kg (plate load {-stiffness.gravity_force[2]:.1f} N)"
    else:
        m = np.asarray(payloads_kg, dtype=float).reshape(-1)
        if m.shape != (N,) or not np.all(np.isfinite(m)) or np.any(m < 0):
            raise InputError(f"payloads_kg: expected {N} non-negative masses [kg] (one per pose), got shape {np.shape(payloads_kg)}")
        base = stiffness.plate_mass - stiffness.payload_kg
        F = np.column_stack([np.zeros(N), np.zeros(N), -g * (base + m)])
        what = f"payloads {sorted(set(np.round(m, 6).tolist()))} kg per pose (plate load in the load field)"
    dev = device_noise(noise)
    rng = np.random.default_rng(seed)
    e = rng.standard_normal(qa.shape) * dev.position_sigma_m
    T_rigid = np.atleast_2d(stiffness.kinematics.fk(qa))
    dT = np.atleast_2d(stiffness.deflection(T_rigid, F, limits=False))
    src = (
        f"synthetic compliant robot: {stiffness.parameters.name}, {what}, {stiffness.stiffness.describe()}; "
        f"{N} poses, device {dev.name} (sigma {dev.position_sigma_m:.3g} m), seed {seed}"
    )
    return MeasurementSet(
        q=qa, T=T_rigid + dT + e, source=src, comments=(" " + src,), load=None if payloads_kg is None else F
    )


# ------------------------------------------------------------------ calibration
def compliance_selection(
    free_compliance: str | Sequence[str] = ("c_l*", "c_a*"),
    fixed: str | Sequence[str] = (),
    free_load: bool = False,
) -> ParameterSelection:
    """Parameter selection of an elasto-geometric calibration.

    Parameters
    ----------
    free_compliance : str or sequence of str, optional
        Compliance names or patterns to estimate (default all six); the others stay at
        their start values.
    fixed : str or sequence of str, optional
        Further (geometric) parameters to hold.
    free_load : bool, optional
        Estimate the plate load too (default False: it is not separable from the
        compliances; only useful to show that in an identifiability report).

    Returns
    -------
    ParameterSelection

    Raises
    ------
    InputError
        A pattern in ``free_compliance`` that matches no compliance name.
    """
    pats = (free_compliance,) if isinstance(free_compliance, str) else tuple(free_compliance)
    for pat in pats:
        if not any(fnmatch.fnmatchcase(n, pat) for n in COMPLIANCE_NAMES):
            raise InputError(f"free_compliance: {pat!r} matches no compliance parameter ({', '.join(COMPLIANCE_NAMES)})")
    held = [n for n in COMPLIANCE_NAMES if not any(fnmatch.fnmatchcase(n, p) for p in pats)]
    fx = (fixed,) if isinstance(fixed, str) else tuple(fixed)
    return ParameterSelection(fixed=tuple(held) + (() if free_load else LOAD_NAMES) + fx)


def calibrate_elasto_geometric(
    start: ElastoGeometricClosure,
    q: Any,
    T: np.typing.ArrayLike | None = None,
    weights: np.typing.ArrayLike | None = None,
    *,
    free_compliance: str | Sequence[str] = ("c_l*", "c_a*"),
    fixed: str | Sequence[str] = (),
    solver: str = DEFAULT_SOLVER,
    align: bool = True,
    max_iter: int = MAX_ITER,
) -> CalibrationResult:
    """Calibrate geometry and compliances from measured poses (eq. 2 in eqs. 5.1-5.4).

    A :class:`~gtmodel.calibration.kinematic.CalibrationProblem` of the elasto-geometric
    closure model with the load fixed (:func:`compliance_selection`).

    Parameters
    ----------
    start : ElastoGeometricClosure
        Start model (geometry, start compliances, the known load).
    q : array_like, shape (N, n_q), or MeasurementSet
        A measurement set (with ``load`` [N] for a ``per_pose_load`` model), or the rows
        of :meth:`ElastoGeometricClosure.pose_inputs` (cart positions [m], then the load [N]).
    T : array_like, shape (N, 3), optional
        Measured TCP positions [m] (omit for a measurement set).
    weights : array_like, shape (N,), optional
        Pose weights.
    free_compliance : str or sequence of str, optional
        Compliances to estimate.
    fixed : str or sequence of str, optional
        Further parameters to hold.
    solver : {"lm", "trf", "ipopt", "ipopt-gn"}, optional
        Solver.
    align : bool, optional
        Move the start model into the measurement frame first (eqs. 5.3-5.4).
    max_iter : int, optional
        Iteration limit.

    Returns
    -------
    CalibrationResult

    Raises
    ------
    InputError
        Bad data, names or options.
    ModelError
        A singular problem at the start (non-identifiable parameters with their dependencies,
        e.g. a compliance on poses with constant arm forces).
    """
    if not isinstance(start, ElastoGeometricClosure):
        raise InputError(f"start: expected an ElastoGeometricClosure, got {type(start).__name__}")
    sel = compliance_selection(free_compliance, fixed)
    return CalibrationProblem(start, sel).solve(q, T, None, weights, solver=solver, align=align, max_iter=max_iter)


def compliance_identifiability(
    model: ElastoGeometricClosure,
    q: Any,
    T: np.typing.ArrayLike | None = None,
    *,
    free_compliance: str | Sequence[str] = ("c_l*", "c_a*"),
    fixed: str | Sequence[str] = (),
    free_load: bool = False,
) -> IdentifiabilityReport:
    """Identifiability of compliances together with the geometric parameters (QR, Table 5.4).

    Parameters
    ----------
    model : ElastoGeometricClosure
        Linearisation point (e.g. the calibrated model).
    q : array_like, shape (N, n_q), or MeasurementSet
        A measurement set (with ``load`` [N] for a ``per_pose_load`` model), or the rows
        of :meth:`ElastoGeometricClosure.pose_inputs` (cart positions [m], then the load [N]).
    T : array_like, shape (N, 3), optional
        TCP positions in the model's frame [m].
    free_compliance : str or sequence of str, optional
        Compliances analysed.
    fixed : str or sequence of str, optional
        Parameters held.
    free_load : bool, optional
        Analyse the load too (it is not separable from the compliances).

    Returns
    -------
    IdentifiabilityReport

    Raises
    ------
    InputError
        Bad data or names.
    """
    if not isinstance(model, ElastoGeometricClosure):
        raise InputError(f"model: expected an ElastoGeometricClosure, got {type(model).__name__}")
    sel = compliance_selection(free_compliance, fixed, free_load)
    return analyze_identifiability(model, q, T, selection=sel)


def explain_identifiability(report: IdentifiabilityReport) -> list[str]:
    """Why each non-identifiable compliance or load is not separable (module docstring).

    Parameters
    ----------
    report : IdentifiabilityReport
        From :func:`compliance_identifiability` or a calibration.

    Returns
    -------
    list of str
        One sentence per non-identifiable compliance/load parameter, or link length that
        depends on a compliance (empty if all are identifiable).
    """
    out = []
    for name, info in report.non_identifiable.items():
        deps = set(info.get("depends_on", {}))
        if name in LOAD_NAMES or deps & set(LOAD_NAMES):
            out.append(
                f"{name}: the load and the compliances enter only as products c_i f_i (f = U^-T F); "
                "one of them must be known (fix the load: the payload mass)"
            )
        elif (name in COMPLIANCE_NAMES and any(d.startswith("L") for d in deps)) or (
            name.startswith("L") and deps & set(COMPLIANCE_NAMES)
        ):
            arm = name[-1]
            if name.startswith("L"):
                name = f"{', '.join(sorted(deps & set(COMPLIANCE_NAMES)))} / {name}"
            out.append(
                f"{name}: compliance not separable from the link length L{arm}: the arm force f_{arm} is (nearly) the same "
                f"at every pose, so c f_{arm} is a constant length change (measure poses with varied link directions)"
            )
        elif name in COMPLIANCE_NAMES and deps & set(COMPLIANCE_NAMES):
            out.append(
                f"{name}: not separable from {', '.join(sorted(deps & set(COMPLIANCE_NAMES)))}: the factor (u.w)^2 "
                "between cluster and cart compliance varies too little over these poses"
            )
        elif name in COMPLIANCE_NAMES:
            out.append(f"{name}: not identifiable (depends on {', '.join(sorted(deps)) or 'nothing'})")
    return out


# ------------------------------------------------------------------ the comparison
@dataclass
class ElastoGeometricStudy:
    """A compliant robot calibrated with and without the compliance model.

    Parameters
    ----------
    truth : GantryTau3Stiffness
        The true robot (geometry, stiffness values, payload).
    true_model : ElastoGeometricClosure
        Its closure model (true compliances and load).
    calibration, validation : MeasurementSet
        Every second pose for calibration, the others for validation (ch. 5.2).
    geometric : CalibrationResult
        Geometric-only calibration (3-link model, rigid).
    elasto : CalibrationResult
        Elasto-geometric calibration.
    geometric_report, elasto_report, noise_floor : AccuracyReport
        Validation errors (eq. 5.5) of the two models and of the true model.
    identifiability : IdentifiabilityReport
        Of the elasto-geometric calibration at its solution (geometry and compliances).
    load_identifiability : IdentifiabilityReport
        The same with the load free too (shows it is not separable).
    deflection : numpy.ndarray, shape (N,)
        Norm of the true gravity deflection per pose [m].
    solve_time : float
        Wall time [s].
    explanations : list of str
        Why parameters of ``load_identifiability`` are not separable.
    """

    truth: GantryTau3Stiffness
    true_model: ElastoGeometricClosure
    calibration: MeasurementSet
    validation: MeasurementSet
    geometric: CalibrationResult
    elasto: CalibrationResult
    geometric_report: AccuracyReport
    elasto_report: AccuracyReport
    noise_floor: AccuracyReport
    identifiability: IdentifiabilityReport
    load_identifiability: IdentifiabilityReport
    deflection: np.ndarray
    solve_time: float = 0.0
    explanations: list = field(default_factory=list)

    @property
    def status(self) -> str:
        """Worse status of the two calibrations."""
        return Status.worst((self.geometric.status, self.elasto.status))

    def compliance_table(self) -> list[dict[str, float]]:
        """Calibrated compliances against the truth.

        Returns
        -------
        list of dict
            ``name``, ``true``, ``calibrated``, ``std`` [m/N] and ``z = (cal - true) / std``.
        """
        true = dict(zip(self.true_model.parameter_names(), self.true_model.parameter_vector()))
        rows = []
        for n in COMPLIANCE_NAMES:
            s = self.elasto.std.get(n, 0.0)
            v = self.elasto.parameters[n]
            rows.append({"name": n, "true": float(true[n]), "calibrated": float(v), "std": float(s),
                         "z": float((v - true[n]) / s) if s and np.isfinite(s) else float("nan")})
        return rows


def elasto_geometric_study(
    truth: GantryTau3Stiffness,
    start: ThreeLinkClosure,
    q: np.typing.ArrayLike,
    noise: DeviceNoise | str = LASER_TRACKER,
    seed: int | None = 0,
    payloads_kg: Sequence[float] | None = None,
    start_compliance: str = "zero",
    free_compliance: str | Sequence[str] = ("c_l*", "c_a*"),
    solver: str = DEFAULT_SOLVER,
    align: bool = True,
    max_iter: int = MAX_ITER,
) -> ElastoGeometricStudy:
    """Calibrate a compliant robot with and without the compliance model and compare.

    Synthetic data by :func:`compliant_measurements` (eq. 1); calibration on every second
    pose, validation on the others (Dressler (2012), ch. 5.2, eq. 5.5). The true model's
    validation error on the same noisy poses is the noise floor. With ``payloads_kg`` every
    pose is measured once per payload (the known load is part of the pose); the geometric
    model sees the cart positions only.

    Parameters
    ----------
    truth : GantryTau3Stiffness
        The true robot (its ``payload_kg`` is the load without ``payloads_kg``).
    start : ThreeLinkClosure
        Start geometry (e.g. the ideal model in modified form).
    q : array_like, shape (N, 3)
        Cart positions of the poses [m].
    noise : DeviceNoise or str, optional
        Device noise.
    seed : int or None, optional
        Noise seed.
    payloads_kg : sequence of float, optional
        Payloads each pose is measured with [kg] (e.g. ``[0, 40]``); default one load.
    start_compliance : {"zero", "stated"}, optional
        Start compliances: zero (a rigid start) or the true stated values.
    free_compliance : str or sequence of str, optional
        Compliances estimated.
    solver : {"lm", "trf", "ipopt", "ipopt-gn"}, optional
        Solver.
    align : bool, optional
        Frame alignment first.
    max_iter : int, optional
        Iteration limit.

    Returns
    -------
    ElastoGeometricStudy

    Raises
    ------
    InputError
        Bad options or data.
    ModelError
        A singular calibration problem (names the non-identifiable parameters).
    """
    if start_compliance not in ("zero", "stated"):
        raise InputError(f"start_compliance: expected 'zero' or 'stated', got {start_compliance!r}")
    if not isinstance(start, ThreeLinkClosure):
        raise InputError(f"start: expected a ThreeLinkClosure, got {type(start).__name__}")
    t0 = time.perf_counter()
    qa = np.atleast_2d(np.asarray(q, dtype=float))
    per_pose = payloads_kg is not None
    if per_pose:
        loads = np.asarray(payloads_kg, dtype=float).reshape(-1)
        if loads.size == 0 or not np.all(np.isfinite(loads)) or np.any(loads < 0):
            raise InputError(f"payloads_kg: expected one or more non-negative masses [kg], got {payloads_kg!r}")
        n_l = loads.size
        rows = np.repeat(np.arange(qa.shape[0]), n_l)
        data = compliant_measurements(truth, qa[rows], noise, seed, np.tile(loads, qa.shape[0]))
        grid_index = rows
    else:
        data = compliant_measurements(truth, qa, noise, seed)
        grid_index = np.arange(qa.shape[0])
    cal = data.subset(np.flatnonzero(grid_index % 2 == 0))
    val = data.subset(np.flatnonzero(grid_index % 2 == 1))
    true_model = ElastoGeometricClosure.from_stiffness(truth, start.model, per_pose)
    geo = CalibrationProblem(start).solve(cal, solver=solver, align=align, max_iter=max_iter)
    zero = np.zeros(3)
    el_start = ElastoGeometricClosure(
        start,
        true_model.c_link if start_compliance == "stated" else zero,
        true_model.c_act if start_compliance == "stated" else zero,
        true_model.F,
        per_pose,
    )
    el = calibrate_elasto_geometric(el_start, cal, free_compliance=free_compliance, solver=solver, align=align, max_iter=max_iter)
    rep_geo = evaluate(geo.model, val, label="geometric only")
    rep_el = evaluate(el.model, val, label="elasto-geometric")
    floor = evaluate(true_model, val, label="true model (noise floor)")
    ident = el.identifiability
    load = compliance_identifiability(el.model, cal, free_compliance=free_compliance, free_load=True)
    T_rigid = np.atleast_2d(truth.kinematics.fk(data.q))
    F = data.load if per_pose else None
    dT = np.linalg.norm(np.atleast_2d(truth.deflection(T_rigid, F, limits=False)), axis=1)
    return ElastoGeometricStudy(
        truth, true_model, cal, val, geo, el, rep_geo, rep_el, floor, ident, load, dT,
        time.perf_counter() - t0, explain_identifiability(load),
    )
