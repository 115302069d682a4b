"""The schema of an ``ilc`` problem file (light: validated before the kind's solvers are imported).

The kind is :mod:`gtmodel.problems.kinds.ilc`; the field reference is
``docs/problem_files.md``.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field

from gtmodel._docstrings import fill_doc
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.problems.base import KIND_DOCS
from gtmodel.problems.kinds.schemas.closed_loop import NYQUIST_HZ, RobotSection, SensorsSection, StructureSection
from gtmodel.problems.schema import MAX_LENGTH_M, Flag, NonEmptyText, ProblemSchema, Section, choice, integer, number, vector

__all__ = [
    "ILCFile",
    "MAX_ITERATIONS",
    "MIN_CUTOFF_HZ",
    "ILC_SIGNALS",
    "ILC_REQUIREMENTS",
    "ILC_Q_DESIGNS",
    "CUTOFF_READINGS",
    "KALMAN_FORMS",
    "ReferenceSection",
    "ILCSection",
    "EstimatorsSection",
    "CaseSection",
]

#: Names and defaults of :mod:`gtmodel.estimation` the file's fields list, equal to
#: theirs (checked by the tests; here so that a file is validated without the estimation):
#: the learning signals (:data:`~gtmodel.estimation.SIGNALS`), the lifted checks
#: (:data:`~gtmodel.estimation.REQUIREMENTS`), the lowest filter cut-off as a fraction of
#: the sample rate (:data:`gtmodel.estimation.filters.complementary.MIN_CUTOFF_FRACTION`)
#: and the Kalman filter's default noises [m], [m/s^3] (:mod:`gtmodel.estimation.filters.kalman`).
ILC_SIGNALS = ("actuator", "complementary", "kalman", "tool")
ILC_REQUIREMENTS = ("monotone", "stable", "none")
ILC_Q_DESIGNS = ("butterworth", "robust")
CUTOFF_READINGS = ("zero_phase_3db", "matlab")
KALMAN_FORMS = ("triple_integrator", "model")
MIN_CUTOFF_FRACTION = 1e-4
KALMAN_POSITION_NOISE = (0.000358, 0.001064)
KALMAN_JERK_NOISE = (100.0, 100.0)
#: Most ILC iterations.
MAX_ITERATIONS = 100


#: Lowest filter cut-off [Hz] (below it the Butterworth design is numerically degenerate).
MIN_CUTOFF_HZ = MIN_CUTOFF_FRACTION / LOOP_PERIOD_S


def _cutoff(description: str) -> Any:
    return number(ge=MIN_CUTOFF_HZ, lt=NYQUIST_HZ, unit="Hz", description=description,
                  what=f"a cut-off frequency in [{MIN_CUTOFF_HZ:g}, {NYQUIST_HZ:g}) Hz (below the Nyquist frequency of the 4 ms loop)")


class ReferenceSection(Section):
    """``[reference]``: the square of section 7.3.

    Parameters
    ----------
    corner : list of float, shape (3,)
        First corner [m]; the square runs +x, +y, -x, -y from it.
    side : float
        Side length [m].
    speed : float
        Nominal TCP speed [m/s] (the speed limit of the planner).
    acceleration : float
        TCP acceleration limit per axis [m/s^2].
    lead : int
        Lead-in and lead-out at rest [samples].
    grid : int
        Grid points of the path-constrained solver.
    rounds : int
        Consecutive rounds of the square (the thesis: 2).
    """

    corner: vector(3, bound=MAX_LENGTH_M, unit="m", description="first corner of the square (it runs +x, +y, -x, -y)")
    side: number(gt=0, le=1.0, unit="m", description="side of the square (the thesis: 10 mm)") = 0.010
    speed: number(gt=0, le=10.0, unit="m/s", description="nominal TCP speed (the thesis: 100 mm/s)") = 0.100
    acceleration: number(gt=0, le=1000.0, unit="m/s^2", description="TCP acceleration limit per axis") = 2.0
    lead: integer(0, 1000, description="lead-in and lead-out at rest, in samples (the thesis: 100)") = 100
    grid: integer(20, 5000, description="grid points of the path-constrained solver") = 400
    rounds: integer(1, 10, description="consecutive rounds of the square, at rest at every corner (the thesis: 2)") = 1


class ILCSection(Section):
    """``[ilc]``: the learning law (7.2) and Q's time window.

    Parameters
    ----------
    iterations : int
        Iterations after the first trial.
    gamma : float
        Learning gain.
    delta : int
        Time shift of L [samples].
    tukey_points : int
        Length of the Tukey window whose halves weight the lead-in and lead-out.
    tukey_alpha : float
        Tukey shape parameter.
    coupled_check : bool
        Also check (7.15)/(7.16) for all channels together, cross-coupling included.
    """

    iterations: integer(1, MAX_ITERATIONS, description="ILC iterations after the first trial") = 10
    gamma: number(gt=0, le=100.0, description="learning gain of L = gamma q^delta (the thesis: 0.9)") = 0.9
    delta: integer(0, 100, description="time shift of L in samples (the thesis: 5)") = 5
    tukey_points: integer(2, 2000, description="Tukey window length (the thesis: 200)") = 200
    tukey_alpha: number(ge=0, le=1.0, description="Tukey window shape (the thesis: 0.95)") = 0.95
    coupled_check: Flag = Field(default=False, description="also check (7.15)/(7.16) for all channels together, cross-coupling included")


class EstimatorsSection(Section):
    """``[estimators]``: the tool-position estimators of Cases 2A and 2B.

    Parameters
    ----------
    complementary_cutoff_hz : list of float, shape (2,)
        Complementary filter cut-offs in x and y [Hz] (7.17).
    kalman_position_noise : list of float, shape (2,)
        Kalman filter: std of the kinematic position as a tool-position measurement [m].
    kalman_jerk_noise : list of float, shape (2,)
        Kalman filter: std of the white jerk driving the model [m/s^3].
    cutoff_reading : str
        How the complementary cut-offs are read: zero_phase_3db or matlab (butter + filtfilt:
        LP and HP cross over at the cut-off).
    kalman_form : str
        The Kalman filter Case 2B learns on: triple_integrator (the tool position as a triple
        integrator measuring fk(q_m) and a_m) or model (the thesis' (7.19)-(7.22): the model
        from fk(q_m) to the tool position with fk(q_m) as input, the accelerometer measured).
        Both are computed and compared in the summary.
    """

    complementary_cutoff_hz: vector(2, positive=True, bound=NYQUIST_HZ, unit="Hz",
                                    description="complementary filter cut-offs in x and y (the thesis: 4.50, 2.63)") = Field(
        default_factory=lambda: [4.50, 2.63])
    kalman_position_noise: vector(2, positive=True, bound=1.0, unit="m",
                                  description="Kalman: std of fk(q_m) as a tool-position measurement in x, y "
                                              "(default: crossover at the complementary cut-offs)") = Field(
        default_factory=lambda: list(KALMAN_POSITION_NOISE))
    kalman_jerk_noise: vector(2, positive=True, bound=1e6, unit="m/s^3", description="Kalman: std of the white jerk of the model in x, y") = Field(
        default_factory=lambda: list(KALMAN_JERK_NOISE))
    cutoff_reading: choice(*CUTOFF_READINGS, description="reading of the complementary cut-offs: the -3 dB point of the zero-phase filter, "
                                                        "or Matlab's butter + filtfilt (the thesis: LP and HP cross over at the cut-off)") = "zero_phase_3db"
    kalman_form: choice(*KALMAN_FORMS, description="the Kalman filter of Case 2B: triple_integrator (measures fk(q_m) and a_m) or model "
                                                   "(the thesis' (7.19)-(7.22): fk(q_m) as input of the structural model, a_m measured); "
                                                   "both are compared in the summary") = "triple_integrator"


class CaseSection(Section):
    """``[[cases]]``: one ILC case.

    Parameters
    ----------
    name : str
        Label (e.g. ``"1"``, ``"2A"``).
    signal : str
        Learning signal: actuator, complementary, kalman or tool.
    q_cutoff_hz : float or None
        Cut-off of Q's zero-phase Butterworth low-pass [Hz]; omitted: no low-pass.
    q_order : int
        Butterworth order.
    require : str
        monotone (7.16), stable (7.15) or none.
    q_design : str
        butterworth, or robust (the Butterworth capped by q_margin / sigma_max(I - L T(f))).
    q_margin : float
        The robust design's bound of ``|Q| |I - L T|``.
    """

    name: NonEmptyText = Field(description="case label")
    signal: choice(*ILC_SIGNALS, description="learning signal: actuator positions (Case 1), the complementary (2A) or Kalman (2B) "
                                         "tool estimate, or the measured tool position (3)")
    q_cutoff_hz: _cutoff("cut-off of Q's zero-phase Butterworth low-pass (omit for none)") | None = None
    q_order: integer(1, 8, description="order of Q's Butterworth low-pass") = 2
    require: choice(*ILC_REQUIREMENTS, description="lifted check that must hold before the case runs: "
                                               "monotone (sigma_max < 1, 7.16), stable (rho < 1, 7.15) or none") = "monotone"
    q_design: choice(*ILC_Q_DESIGNS, description="Q design: butterworth (Case 1), or robust (Cases 2, 3: the Butterworth capped by "
                                                 "q_margin / sigma_max(I - L T(f)), learning up to the cut-off, robust at the resonances)") = "butterworth"
    q_margin: number(gt=0, lt=1.0, description="robust Q: bound of |Q| |I - L T| over the frequencies") = 0.9


@fill_doc(**KIND_DOCS)
class ILCFile(ProblemSchema):
    """An ``ilc`` problem file.

    Parameters
    ----------
    {header_fields}
    robot : RobotSection
        ``[robot]``: kinematics and actuator models.
    reference : ReferenceSection
        ``[reference]``: the square.
    structure : StructureSection, optional
        ``[structure]``: the tool structure.
    sensors : SensorsSection, optional
        ``[sensors]``: accelerometer and gauge.
    ilc : ILCSection, optional
        ``[ilc]``: the learning law.
    estimators : EstimatorsSection, optional
        ``[estimators]``: complementary and Kalman filter settings.
    cases : list of CaseSection
        ``[[cases]]``: the cases, in order.
    """

    kind: Literal["ilc"]
    robot: RobotSection
    reference: ReferenceSection
    structure: StructureSection = StructureSection()
    sensors: SensorsSection = SensorsSection()
    ilc: ILCSection = ILCSection()
    estimators: EstimatorsSection = EstimatorsSection()
    cases: list[CaseSection] = Field(min_length=1, max_length=20, description="the ILC cases")
