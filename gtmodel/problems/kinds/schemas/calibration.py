"""The schema of a ``calibration`` problem file (light: validated before the kind's solvers are imported).

The kind is :mod:`gtmodel.problems.kinds.calibration`; the field reference is
``docs/problem_files.md``.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Field
from pydantic_core import PydanticCustomError

from gtmodel._docstrings import fill_doc
from gtmodel.problems.base import KIND_DOCS
from gtmodel.problems.schema import MAX_LENGTH_M, Flag, NonEmptyText, ProblemSchema, Section, choice, integer, matrix, number, vector

__all__ = ["CalibrationFile", "MODEL_TYPES", "MAX_PERTURBATION_M", "MAX_RANDOM_POSES", "LSQ_SOLVERS", "StringList"]

#: The least-squares solvers of a kinematic calibration, those of
#: :data:`gtmodel.calibration.kinematic.SOLVERS` (equal, checked by the tests; here so that
#: a file is validated without the calibration).
LSQ_SOLVERS = ("lm", "trf", "ipopt", "ipopt-gn")
#: Model types a calibration problem can declare.
MODEL_TYPES = ("three_link", "three_link_piecewise", "six_link", "six_link_piecewise", "f1", "armwise")
#: Largest random perturbation of a parameter set [m] (built tolerances are millimetres).
MAX_PERTURBATION_M = 0.1
#: Largest number of random poses, per truth model (rejection sampling with IK or FK).
MAX_RANDOM_POSES = {"three_link": 10_000, "six_link": 2_000}
def _string_list(v: Any) -> Any:
    if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
        raise PydanticCustomError("gtmodel", "expected {expected}", {"expected": "a list of strings"})
    return v


#: A list of strings (parameter names, patterns, ties).
StringList = Annotated[list[str], BeforeValidator(_string_list)]


class DataSection(Section):
    """``[data]``: measured poses."""

    file: NonEmptyText = Field(description="measurement CSV (gtmodel.calibration.measurements), relative to the problem file")
    cart_file: NonEmptyText | None = Field(default=None, description="cart surveys CSV for piecewise-linear actuator models")


class TruthSection(Section):
    """``[truth]``: synthetic measurements of a declared true robot."""

    model: choice("three_link", "six_link", "f1", description="model of the true robot")
    parameters: NonEmptyText = Field(description="parameter set of the true robot: a shipped name or a TOML path relative to the problem file")
    perturbation: number(ge=0, le=MAX_PERTURBATION_M, unit="m", description="random change of every length/point of the true robot (built tolerances)") = 0.0
    noise: choice("laser_tracker", "stereo_vision", "none", description="measurement device (noise)") = "laser_tracker"
    actuator_errors: choice("none", "table_4_1", description="actuator errors of the data (Table 4.1)") = "none"
    cyclic_period: number(gt=0, le=MAX_LENGTH_M, unit="m", description="period of the cyclic rack-and-pinion error of table_4_1 (default 0.2 m, the pinion circumference assumed; the thesis' tooth pitch is much shorter than the 50 mm survey step)") | None = None
    cart_compliance: vector(3, nonnegative=True, bound=1e-3, unit="m/N", description="three_link/six_link D1-type truth: transverse compliance of each cart under its arm's gravity force (gtmodel.calibration.cart_compliance), a load-dependent error the error models do not hold") | None = None
    grid_step: number(gt=0, le=MAX_LENGTH_M, unit="m", description="spacing of a regular pose grid in the workspace") | None = None
    grid_step_deg: number(gt=0, le=90, unit="deg", description="orientation spacing of the F1's 6-D grid") = 10.0
    random_poses: integer(2, max(MAX_RANDOM_POSES.values()), description="number of random poses (without grid_step)") | None = None
    seed: integer(0, 2**31 - 1, description="seed of the poses and the noise") = 0
    rotary_travel_deg: matrix(2, bound=360.0, unit="deg", description="[min, max] of each rotary actuator q4.. (models with more than 3 actuators)") | None = None
    rotary_step_deg: number(gt=0, le=360, unit="deg", description="grid spacing of the rotary actuators") = 10.0


class ModelSection(Section):
    """``[[models]]``: a model to calibrate."""

    name: NonEmptyText | None = Field(default=None, description="label (default: the type)")
    type: choice(*MODEL_TYPES, description="model type")
    parametrisation: choice("ideal", "modified", description="three_link only: ideal (15) or modified (21 parameters)") = "modified"
    start: NonEmptyText = Field(default="truth", description='start parameters: a shipped name, a TOML path, or "truth"')
    perturbation: number(ge=0, le=MAX_PERTURBATION_M, unit="m", description="random start perturbation of every length/point") = 0.0
    fixed: StringList = Field(default_factory=list, description="parameter names or patterns kept at the start")
    ties: StringList = Field(default_factory=list, description='equalities, e.g. ["Abj_2b_z = Abj_2a_z"]')
    arms: StringList | None = Field(default=None, description='armwise only: for arms 1-3 the name of an earlier declared model whose calibrated arm it takes (Table 5.3 model 5), e.g. ["3", "4", "3"]')


def _model_tables(v: Any) -> Any:
    if not isinstance(v, list) or not v or not all(isinstance(m, dict) for m in v):
        raise PydanticCustomError("gtmodel", "expected {expected}", {"expected": "one or more [[models]] tables"})
    return v


class CalibrationSection(Section):
    """``[calibration]``: solver options."""

    solver: choice(*LSQ_SOLVERS, description="least-squares solver") = "lm"
    max_iter: integer(1, 10**6, description="iteration limit") = 200
    align: Flag = Field(default=True, description="move the start model into the measurement frame (eqs. 5.3-5.4)")


class PoseSelectionSection(Section):
    """``[pose_selection]``: choose poses from the candidates (eq. 5.9, or at random)."""

    n: integer(2, 10**6, description="number of poses to select")
    method: choice("condition", "random", description="greedy condition-number selection (eq. 5.9) or a random choice (seeded by truth.seed)") = "condition"
    planned: Flag = Field(default=False, description="condition only: select on the start model's FK at the candidates (poses planned before measuring: the same for every seed)")


@fill_doc(**KIND_DOCS)
class CalibrationFile(ProblemSchema):
    """A ``calibration`` problem file: exactly one of ``[data]`` and ``[truth]``.

    Parameters
    ----------
    {header_fields}
    data : DataSection, optional
        ``[data]``: measurement file(s).
    truth : TruthSection, optional
        ``[truth]``: synthetic measurements of a deviated robot.
    models : list of ModelSection
        ``[[models]]``: the models to calibrate, each with its parameter selection.
    calibration : CalibrationSection, optional
        ``[calibration]``: solver, iteration limit, alignment.
    pose_selection : PoseSelectionSection, optional
        ``[pose_selection]``: choose a subset of the poses.
    """

    kind: Literal["calibration"]
    data: DataSection | None = None
    truth: TruthSection | None = None
    models: Annotated[list[ModelSection], BeforeValidator(_model_tables), Field(min_length=1)]
    calibration: CalibrationSection = CalibrationSection()
    pose_selection: PoseSelectionSection | None = None
