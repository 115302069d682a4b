"""The schema of a ``dynamic_identification`` problem file (light: validated before the kind's solvers are imported).

The kind is :mod:`gtmodel.problems.kinds.dynamic_identification`; the field reference is
``docs/problem_files.md``.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Field
from pydantic_core import PydanticCustomError

from gtmodel._docstrings import fill_doc
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.problems.base import KIND_DOCS
from gtmodel.problems.schema import MAX_FORCE_N, MAX_LENGTH_M, Flag, NonEmptyText, ProblemSchema, Section, choice, integer, number, vector

__all__ = ["DynamicIdentificationFile", "VARIANT_NAMES", "MAX_DURATION_S", "MAX_SPEED", "MAX_ACCELERATION"]

#: Names of the Table 6.3 variants, those of :data:`gtmodel.calibration.identification.VARIANTS`
#: (equal, checked by the tests; here so that a file is validated without the identification).
VARIANT_NAMES = ("model_1", "model_2", "model_3", "model_4", "full", "asymmetric")
#: Longest synthetic log or excitation period [s].
MAX_DURATION_S = 1.0e4
#: Largest cart speed or speed threshold [m/s] and acceleration [m/s^2] accepted.
MAX_SPEED = 10.0
MAX_ACCELERATION = 1.0e3


def _variants(v: Any) -> Any:
    expected = f"a non-empty list of distinct names from {', '.join(VARIANT_NAMES)}"
    if not isinstance(v, list) or not v or not all(isinstance(x, str) and x in VARIANT_NAMES for x in v) or len(set(v)) != len(v):
        raise PydanticCustomError("gtmodel", "expected {expected}", {"expected": expected})
    return v


def _stribeck(v: Any) -> Any:
    expected = f"a list of 3 finite numbers of magnitude <= {MAX_FORCE_N:g} N, or [] for no Stribeck term"
    if v == []:
        return None
    if (not isinstance(v, list) or len(v) != 3
            or not all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) and abs(x) <= MAX_FORCE_N for x in v)):
        raise PydanticCustomError("gtmodel", "expected {expected}", {"expected": expected})
    return [float(x) for x in v]


#: Names of Table 6.3 variants (``identification.variants``).
Variants = Annotated[list[str], BeforeValidator(_variants)]
#: The Stribeck amplitude: 3 forces, or ``[]`` (stored as None) for none.
Stribeck = Annotated[list[float] | None, BeforeValidator(_stribeck)]


class RobotSection(Section):
    """``[robot]``: the model's parameter set."""

    parameters: NonEmptyText = Field(description="shipped parameter set (L1, D1, L1_ideal) or a TOML path relative to the problem file: "
                                                 "kinematics, gravity, Table 6.1 friction")
    configuration: integer(0, 7, description="IK configuration") = 0


class DataSection(Section):
    """``[data]``: a measured motion log."""

    file: NonEmptyText = Field(description="log CSV (t_s,q1_m,q2_m,q3_m,tau1_N,tau2_N,tau3_N), relative to the problem file")


class TruthSection(Section):
    """``[truth]``: synthetic data from a declared true robot (say so in the file)."""

    parameters: NonEmptyText = Field(description="the true robot: shipped parameter set or a TOML path relative to the problem file")
    duration: number(gt=0, le=MAX_DURATION_S, unit="s", description="length of the log") = 30.0
    sample_time: number(gt=0, le=1.0, unit="s", description="sampling interval") = LOOP_PERIOD_S
    force_noise: number(ge=0, le=MAX_FORCE_N, unit="N", description="Gaussian force noise (std)") = 5.0
    position_noise: number(ge=0, le=1.0, unit="m", description="Gaussian position noise (std)") = 1e-6
    position_resolution: number(ge=0, le=1.0, unit="m", description="encoder quantisation (0: none)") = 1e-6
    stribeck_amplitude: Stribeck = Field(default=[40.0, 40.0, 40.0],
                                         description="f_s - f_c per actuator of a Stribeck term the model lacks [N]; [] for none")
    stribeck_velocity: number(gt=0, le=MAX_SPEED, unit="m/s", description="Stribeck velocity") = 0.02
    seed: integer(0, 2**31 - 1, description="noise seed") = 0


class ExcitationSection(Section):
    """``[excitation]``: the motion of synthetic data (a finite Fourier series)."""

    optimize: Flag = Field(default=True, description="design the coefficients by IPOPT for a well-conditioned regressor, else random")
    harmonics: integer(1, 20, description="harmonics of the Fourier series") = 4
    period: number(gt=0, le=MAX_DURATION_S, unit="s", description="period of the motion") = 10.0
    n_grid: integer(8, 1000, description="time grid of the design (at least 4 points per period of the highest harmonic)") = 60
    max_velocity: number(gt=0, le=MAX_SPEED, unit="m/s", description="cart speed bound") = 0.5
    max_acceleration: number(gt=0, le=MAX_ACCELERATION, unit="m/s^2", description="cart acceleration bound") = 3.0
    T_center: vector(3, bound=MAX_LENGTH_M, unit="m", description="TCP position at the centre of the motion") = Field(
        default_factory=lambda: [0.0, 2.9, -0.5])
    seed: integer(0, 2**31 - 1, description="seed of the initial (or random) coefficients") = 0
    max_iter: integer(1, 10000, description="IPOPT iteration limit of the design") = 150


class FilterSection(Section):
    """``[filter]``: zero-phase filtering and differentiation (:func:`gtmodel.calibration.preprocess_log`)."""

    method: choice("butter", "savgol", description="Butterworth filtfilt or Savitzky-Golay") = "butter"
    cutoff: number(gt=0, le=1e6, unit="Hz", description="cut-off frequency (below Nyquist)") = 10.0
    order: integer(1, 10, description="filter order (polynomial order >= 2 for savgol)") = 4
    decimate: integer(1, 10000, description="decimation factor (default round(fs / cutoff))") | None = None
    trim: integer(0, 10**6, description="samples trimmed at both ends (default 2 fs / cutoff)") | None = None


class IdentificationSection(Section):
    """``[identification]``: the variants and the least-squares options."""

    variants: Variants = Field(default_factory=lambda: ["model_2"], description="Table 6.3 variants to identify (the first is the main result)")
    weighting: choice("actuator", "none", description="rows weighted by 1 / residual RMS per actuator (two-step) or not") = "actuator"
    min_speed: number(ge=0, le=MAX_SPEED, unit="m/s", description="rows below this cart speed are not fitted") = 0.05


@fill_doc(**KIND_DOCS)
class DynamicIdentificationFile(ProblemSchema):
    """A ``dynamic_identification`` problem file: exactly one of ``[data]`` and ``[truth]``.

    Parameters
    ----------
    {header_fields}
    robot : RobotSection
        ``[robot]``: the model's parameter set.
    data : DataSection, optional
        ``[data]``: a measured log.
    truth : TruthSection, optional
        ``[truth]``: synthetic data.
    excitation : ExcitationSection, optional
        ``[excitation]``: the motion of synthetic data.
    filter : FilterSection, optional
        ``[filter]``: filtering and differentiation.
    identification : IdentificationSection, optional
        ``[identification]``: the variants.
    """

    kind: Literal["dynamic_identification"]
    robot: RobotSection
    data: DataSection | None = None
    truth: TruthSection | None = None
    excitation: ExcitationSection | None = None
    filter: FilterSection = FilterSection()
    identification: IdentificationSection = IdentificationSection()
