"""Kind ``calibration``: kinematic calibration from closure equations.

Dressler (2012), ch. 5: measured poses (a CSV file, or synthetic data from a declared
"true" robot), one or several models calibrated on every second pose and evaluated on the
others (eq. 5.5), with identifiability and parameter uncertainties::

    name = "l1_calibration"
    kind = "calibration"

    [data]                          # either a measurement file ...
    # file = "measurements.csv"     #   (format: gtmodel.calibration.measurements)
    # cart_file = "carts.csv"       #   (cart surveys, for piecewise-linear actuator models)

    [truth]                         # ... or synthetic measurements (say so in the file)
    model = "three_link"            # "three_link" | "six_link" | "f1"
    parameters = "L1"               # parameter set of the true robot
    noise = "laser_tracker"         # "laser_tracker" (10 um) | "stereo_vision" (1.7 mm) | "none"
    actuator_errors = "none"        # "none" | "table_4_1" (cyclic error, straightness, backlash)
    # cyclic_period = 0.2           # m, period of table_4_1's cyclic error (default: pinion circumference)
    # cart_compliance = [3e-6, 2e-6, 0.0]  # m/N, carts yielding across their guideways (D1-type robots)
    grid_step = 0.1153              # m, regular grid in the workspace ...
    # random_poses = 400            # ... or this many random poses
    seed = 0

    [[models]]                      # one table per model to calibrate and compare
    name = "modified"
    type = "three_link"             # "three_link" | "three_link_piecewise" | "six_link"
                                    # | "six_link_piecewise" | "f1" | "armwise"
    # arms = ["3", "4", "3"]        # armwise only: the calibrated arm i of the model named
                                    #   arms[i] (declared earlier), joined (Table 5.3 model 5)
    parametrisation = "modified"    # three_link only: "ideal" (15) | "modified" (21)
    start = "L1_ideal"              # start parameters: a set name/path, or "truth"
    perturbation = 0.0              # m, random start perturbation of every length/point
    fixed = []                      # parameter names or patterns kept at the start
    ties = []                       # e.g. ["Abj_2b_z = Abj_2a_z"]

    [calibration]                   # optional
    solver = "lm"                   # "lm" | "trf" | "ipopt" | "ipopt-gn"
    max_iter = 200
    align = true                    # move the start model into the measurement frame (5.3)-(5.4)

    [pose_selection]                # optional: choose poses from the candidates by eq. 5.9
    n = 185
    method = "condition"            # "condition" (eq. 5.9) | "random"
    planned = false                 # select on the start model's FK (before measuring)

The synthetic pose grid is bounded up front: the number of grid points a step would
examine is computed from the workspace box and the step before any pose is built, and a
step giving more than :data:`MAX_GRID_CANDIDATES` of them is an error naming the field.

The result folder holds ``summary.json`` (``status``, ``mean_error_m``, ``max_error_m``,
``rms_error_m``, ``n_calibration``, ``n_validation``, ``rank``, ``n_parameters``,
``non_identifiable``, ``iterations``, ``solve_time_s`` of the first model, and a ``models``
table for all), ``parameters.toml`` (the first model's calibrated parameters; a 3-link
result is a complete robot parameter set), ``errors.csv`` and ``error_histogram.png``.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel.calibration import (
    ActuatorErrors,
    CalibrationProblem,
    ParameterSelection,
    device_noise,
    grid_poses,
    random_poses,
    read_cart_measurements,
    read_measurements,
    synthetic_cart_measurements,
    synthetic_measurements,
)
from gtmodel.calibration.cart_compliance import cart_compliance_offsets
from gtmodel.calibration.comparison import CalibrationDeclaration, CalibrationOutcome, perturbed_model
from gtmodel.calibration.grid_count import grid_candidates
from gtmodel.errors import GtModelError, ProblemError
from gtmodel._docstrings import fill_doc
from gtmodel.problems.base import KIND_DOCS, Column, ProblemFile, ProblemKind, Written
from gtmodel.problems.kinds.calibration_results import write_calibration
from gtmodel.problems.kinds.schemas.calibration import (
    MAX_PERTURBATION_M,
    MAX_RANDOM_POSES,
    MODEL_TYPES,
    CalibrationFile,
    DataSection,
    ModelSection,
    PoseSelectionSection,
    StringList,
    TruthSection,
)
from gtmodel.robots import available_parameter_sets, load_f1, load_six_link
from gtmodel.robots.actuator import PiecewiseActuatorClosure
from gtmodel.robots.closure import ThreeLinkClosure

__all__ = [
    "CalibrationKind",
    "CalibrationFile",
    "CalibrationDeclaration",
    "CalibrationOutcome",
    "MODEL_TYPES",
    "MAX_GRID_CANDIDATES",
    "MAX_RANDOM_POSES",
    "MAX_PERTURBATION_M",
    "StringList",
    "calibration_columns",
]

_log = logging.getLogger("gtmodel")

#: Largest number of grid points a synthetic grid may examine, per truth model (each
#: costs an inverse or forward kinematics: about 10 us for the 3-link model's TCP grid,
#: 250 us for the six-link ``q`` grid, 40 us for the F1's 6-D grid; the bounds keep the
#: loading of a file within a few seconds).
MAX_GRID_CANDIDATES = {"three_link": 400_000, "six_link": 25_000, "f1": 300_000}
#: Shipped parameter files (``gtmodel/robots/data``): the names a ``parameters`` or
#: ``start`` field may give instead of a path.
_SHIPPED = tuple(sorted(
    {p.name[: -len(".toml")] for p in resources.files("gtmodel.robots").joinpath("data").iterdir() if p.name.endswith(".toml")}
    | set(available_parameter_sets())
))


def calibration_columns() -> tuple[Column, ...]:
    """Study-table columns of the calibration kinds (validation errors, eq. 5.5).

    Returns
    -------
    tuple of Column
    """
    return (
        Column("mean_error_m", "mean error [m]", "{:.3e}"),
        Column("max_error_m", "max error [m]", "{:.3e}"),
        Column("solve_time_s", "solve time [s]", "{:.3f}"),
    )


class CalibrationKind(ProblemKind):
    """Kinematic calibration of one or several closure models (Dressler (2012), ch. 5)."""

    name = "calibration"
    schema = CalibrationFile
    title = "kinematic calibration from closure equations, models compared on validation poses (Dressler (2012), ch. 5)"
    file_descriptions = {
        "parameters.toml": "the calibrated robot parameters, loadable as a robot file",
        "errors.csv": "TCP error of every validation pose per calibrated model [m]",
        "error_histogram.png": "histogram of the validation TCP errors per model",
    }
    columns = calibration_columns()
    extra_empty_fields = ("rms_error_m", "n_calibration", "n_validation", "rank", "n_parameters", "iterations")

    @fill_doc(**KIND_DOCS)
    def load(self, doc: CalibrationFile, file: ProblemFile, name: str) -> CalibrationDeclaration:
        """Validate the semantics, read or generate the data and build the start models.

        Synthetic data (seeded, so a file always gives the same data) are generated here for a
        3-link truth, and when first used (at solve time) for an F1 or six-link truth.

        Parameters
        ----------
        {load_args}

        Returns
        -------
        CalibrationDeclaration

        Raises
        ------
        ProblemError
            Both or neither of ``[data]`` and ``[truth]``; a bad parameter set; a grid
            with too many poses; a malformed measurement file (the message names its
            row); unknown fixed/tied parameters; a model that does not fit the data.
        """
        if (doc.data is None) == (doc.truth is None):
            raise ProblemError(f"{file.path}: declare exactly one of '[data]' (a measurement file) and '[truth]' (synthetic data)")
        for k, m in enumerate(doc.models):  # references first: a bad one fails before the data are built
            if m.type == "armwise":
                continue  # joins calibrated arms: no start of its own
            if m.start != "truth":
                file.reference(f"models[{k}].start", m.start, _SHIPPED)
            elif doc.truth is None:
                raise file.fail(f"models[{k}].start", "a parameter set (there is no [truth] with measured data)", m.start)
        truth = cart = noise_sigma = None
        n_sel = doc.pose_selection.n if doc.pose_selection is not None else None
        build = None
        if doc.data is not None:
            data, cart = _read_data(doc.data, file)
            source = f"measurements from {doc.data.file}"
            n_q = data.n_q
            _check_selection_size(file, n_sel, data.n_poses)
        else:
            # the cheap part now (truth model, pose count, cart surveys); the poses and the
            # measurements of an F1 or six-link truth when the problem is solved (an F1 6-D
            # workspace grid: seconds; the D1 six-link grid's forward kinematics: 0.9 CPU-s), so a
            # typo in a model's fixed parameters or ties is reported at once and every shipped
            # file loads in under a CPU second
            truth, cart, noise_sigma, build = _synthetic_setup(doc, file, n_sel)
            data, source, n_q = None, "synthetic (generated when solved)", truth.n_q
        models = [_start_model(k, m, doc, file, truth, cart, n_q) for k, m in enumerate(doc.models)]
        if build is not None and doc.truth.model == "three_link":
            data, source = build()  # a 3-link set: a fraction of a second (its too-few-poses errors at once)
            build = None
        ps = doc.pose_selection if doc.pose_selection is not None else PoseSelectionSection(n=2)
        exact = truth is not None and doc.truth.actuator_errors == "none"
        cal = doc.calibration
        return CalibrationDeclaration(data, cart, models, truth, noise_sigma, cal.solver, cal.max_iter, cal.align, source, n_sel, exact,
                                      ps.method, ps.planned, doc.truth.seed if doc.truth is not None else 0, build)

    @fill_doc(**KIND_DOCS)
    def write(self, declaration: CalibrationDeclaration, solution: CalibrationOutcome, out: Path, plots: bool, name: str) -> Written:
        """Summary fields, ``parameters.toml``, ``errors.csv`` and the error histogram.

        ``parameters.toml`` is written only when the first model converged.

        Parameters
        ----------
        declaration : CalibrationDeclaration
            The problem.
        solution : CalibrationOutcome
            Its results.
        {write_args}

        Returns
        -------
        Written
        """
        return write_calibration(declaration, solution, out, plots, name)


# ------------------------------------------------------------------ loading


def _read_data(section: DataSection, file: ProblemFile) -> tuple[Any, Any]:
    path = file.data_file("data.file", section.file)
    try:
        data = read_measurements(path)
    except GtModelError as exc:
        raise file.wrap("data.file", exc) from None
    cart = None
    if section.cart_file is not None:
        cpath = file.data_file("data.cart_file", section.cart_file)
        try:
            cart = read_cart_measurements(cpath)
        except GtModelError as exc:
            raise file.wrap("data.cart_file", exc) from None
    return data, cart


def _base_type(mtype: str) -> str:
    return "three_link" if mtype.startswith("three_link") else "six_link" if mtype.startswith("six_link") else "f1"


def _closure(base: str, ref: str, file: ProblemFile, field_name: str, parametrisation: str = "modified") -> Any:
    """A ClosureModel of a base type from a parameter-set reference (shipped name or path)."""
    target = file.reference(field_name, ref, _SHIPPED)
    try:
        if base == "three_link":
            return ThreeLinkClosure(str(target), model=parametrisation)
        if base == "six_link":
            return load_six_link(str(target))
        return load_f1(str(target))
    except GtModelError as exc:
        raise file.wrap(field_name, exc) from None


def _truth_poses(truth: Any, tkind: str, t: TruthSection, file: ProblemFile, count_only: bool = False) -> np.ndarray | int:
    """The pose grid or random poses of the truth, bounded before anything is built (``count_only``: the checks, and the
    number of candidates before the workspace filter)."""
    rotary = None if t.rotary_travel_deg is None else np.deg2rad(np.asarray(t.rotary_travel_deg, dtype=float))
    if rotary is not None and np.any(rotary[:, 0] >= rotary[:, 1]):
        raise file.fail("truth.rotary_travel_deg", "rows [min, max] with min < max", t.rotary_travel_deg)
    rot_step = float(np.deg2rad(t.rotary_step_deg))
    if t.grid_step is not None:
        if t.random_poses is not None:
            raise file.fail("truth.random_poses", "either grid_step or random_poses, not both", t.random_poses)
        cap = MAX_GRID_CANDIDATES[tkind]
        count, angular = grid_candidates(truth, tkind, t.grid_step, t.grid_step_deg, t.rotary_travel_deg, t.rotary_step_deg)
        if angular > cap:
            key = "truth.grid_step_deg" if tkind == "f1" else "truth.rotary_step_deg"
            raise file.fail(key, f"an angular step giving at most {cap} grid poses (this one gives {angular:.3g} orientations)",
                            t.grid_step_deg if tkind == "f1" else t.rotary_step_deg)
        if count > cap:
            raise file.fail("truth.grid_step", f"a grid step giving at most {cap} grid poses (this one gives {count:.3g})", t.grid_step)
        if count_only:
            return math.ceil(count)  # an upper bound of the poses the grid gives
        if tkind == "f1":
            # the F1's own 6-D workspace grid (position and orientation steps)
            _, _, q = truth.workspace_grid(step_m=t.grid_step, step_deg=t.grid_step_deg, return_q=True)
            return q
        return grid_poses(truth, t.grid_step, rotary_travel=rotary, rotary_step=rot_step)
    if tkind not in MAX_RANDOM_POSES:
        raise file.fail("truth.random_poses", f"grid_step for a truth of model {tkind} (random poses need a 3-link or six-link truth)")
    n = t.random_poses if t.random_poses is not None else 400
    if n > MAX_RANDOM_POSES[tkind]:
        raise file.fail("truth.random_poses", f"at most {MAX_RANDOM_POSES[tkind]} random poses for a {tkind} truth", n)
    if count_only:
        return int(n)
    return random_poses(truth, n, seed=t.seed, rotary_travel=rotary)


def _check_selection_size(file: ProblemFile, n_sel: int | None, n_poses: int) -> None:
    if n_sel is not None and n_sel >= n_poses:
        raise file.fail("pose_selection.n", f"fewer poses than the {n_poses} candidates", n_sel)


def _synthetic_setup(doc: CalibrationFile, file: ProblemFile, n_sel: int | None) -> tuple[Any, Any, float, Any]:
    """The truth model, the cart surveys and the noise now; a function building the poses and measurements later."""
    t = doc.truth
    truth = _closure(t.model, t.parameters, file, "truth.parameters")
    # a robot that differs from its parameter set (built tolerances): every parameter moved
    truth = perturbed_model(truth, t.perturbation, 7)
    noise = device_noise(t.noise)
    if t.cyclic_period is not None and t.actuator_errors != "table_4_1":
        raise file.fail("truth.cyclic_period", "actuator_errors = 'table_4_1' (the period belongs to its cyclic error)", t.cyclic_period)
    if t.cart_compliance is not None and t.model == "f1":
        raise file.fail("truth.cart_compliance", "a three_link or six_link truth (the F1's carts carry no such model)", t.cart_compliance)
    period = {} if t.cyclic_period is None else {"cyclic_period_m": t.cyclic_period}
    errors = ActuatorErrors.table_4_1(**period) if t.actuator_errors == "table_4_1" else None
    candidates = _truth_poses(truth, t.model, t, file, count_only=True)  # the pose set's field checks and size caps
    _check_selection_size(file, n_sel, candidates)  # at most this many poses: a selection as large is refused at once
    cart = None
    try:
        if any(m.type.endswith("_piecewise") for m in doc.models):
            cart = synthetic_cart_measurements(truth, errors, noise=noise, seed=t.seed + 1)
    except GtModelError as exc:
        raise ProblemError(f"{file.path}: field 'truth': cannot generate the synthetic data: {exc}") from None

    def build() -> tuple[Any, str]:
        try:
            q = _truth_poses(truth, t.model, t, file)
            data = synthetic_measurements(truth, q, noise=noise, actuator_errors=errors, seed=t.seed)
            if t.cart_compliance is not None:  # the carts yield across their guideways under the arms' gravity forces
                data = dataclasses.replace(data, T=data.T + cart_compliance_offsets(data.T, data.q[:, :3], t.cart_compliance,
                                                                                    t.parameters.removesuffix("_six_link")))
        except ProblemError:
            raise
        except GtModelError as exc:
            raise ProblemError(f"{file.path}: field 'truth': cannot generate the synthetic data: {exc}") from None
        _check_selection_size(file, n_sel, data.n_poses)
        source = (f"synthetic: truth {t.model} '{t.parameters}', {t.noise} noise, actuator errors {t.actuator_errors}, "
                  f"seed {t.seed}, {data.n_poses} poses"
                  + (f", cart compliance {' / '.join(f'{1e6 * c:.3g}' for c in t.cart_compliance)} um/N" if t.cart_compliance is not None else ""))
        return data, source

    return truth, cart, noise.position_sigma_m, build


def _armwise_model(k: int, m: ModelSection, doc: CalibrationFile, file: ProblemFile) -> dict[str, Any]:
    """An ``armwise`` entry: the arms of earlier declared models joined after their calibration (Table 5.3, model 5)."""
    key = f"models[{k}]"
    earlier = {(e.name if e.name is not None else e.type): e.type for e in doc.models[:k]}
    if m.arms is None or len(m.arms) != 3:
        raise file.fail(f"{key}.arms", "the names of 3 earlier declared models, one per arm", m.arms)
    for f in ("fixed", "ties"):
        if getattr(m, f):
            raise file.fail(f"{key}.{f}", "nothing for type = 'armwise' (its arms are calibrated as their models)", getattr(m, f))
    for i, a in enumerate(m.arms):
        if earlier.get(a) in (None, "armwise"):
            raise file.fail(f"{key}.arms[{i}]", f"the name of an earlier declared, calibrated model (one of {sorted(n for n, t in earlier.items() if t != 'armwise')})", a)
    return {"name": m.name if m.name is not None else "armwise", "type": "armwise", "arms": list(m.arms), "model": None, "selection": None}


def _start_model(k: int, m: ModelSection, doc: CalibrationFile, file: ProblemFile, truth: Any, cart: Any, n_q: int) -> dict[str, Any]:
    key = f"models[{k}]"
    if m.type == "armwise":
        return _armwise_model(k, m, doc, file)
    if m.arms is not None:
        raise file.fail(f"{key}.arms", "no arms (they belong to type = 'armwise')", m.arms)
    mname = m.name if m.name is not None else m.type
    base = _base_type(m.type)
    if m.start == "truth":
        if truth is None:
            raise file.fail(f"{key}.start", "a parameter set (there is no [truth] with measured data)", m.start)
        start = _closure(base, doc.truth.parameters, file, f"{key}.start", m.parametrisation)
    else:
        start = _closure(base, m.start, file, f"{key}.start", m.parametrisation)
    held = [*m.fixed, *(t.split("=")[0].strip() for t in m.ties)]
    start = perturbed_model(start, m.perturbation, 1000 + k, keep=held)
    if m.type.endswith("_piecewise"):
        if cart is None:
            raise file.fail("data.cart_file", f"cart surveys for the piecewise-linear model '{mname}'")
        try:
            start = PiecewiseActuatorClosure.from_model(start, cart, extrapolate=True)
        except GtModelError as exc:
            raise file.wrap(key, exc) from None
    try:
        selection = ParameterSelection(fixed=tuple(m.fixed), ties=tuple(m.ties))
        CalibrationProblem(start, selection)  # resolves names and ties (errors name them)
    except GtModelError as exc:
        raise file.wrap(key, exc) from None
    if start.n_q != n_q:
        raise file.fail(f"{key}.type", f"a model with {n_q} actuator values per pose (the data's)", m.type)
    return {"name": mname, "type": m.type, "model": start, "selection": selection}
