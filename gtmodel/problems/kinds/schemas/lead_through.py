"""The schema of a ``lead_through`` problem file (light: validated before the kind's solvers are imported).

The kind is :mod:`gtmodel.problems.kinds.lead_through` (Dressler (2012), ch. 8); the field
reference is ``docs/problem_files.md``.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from gtmodel._docstrings import fill_doc
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.problems.base import KIND_DOCS
from gtmodel.problems.schema import Flag, ProblemSchema, Section, choice, integer, number, vector

__all__ = ["LeadThroughFile", "MAX_DURATION_S", "MAX_CASES"]

#: Longest simulated experiment [s].
MAX_DURATION_S = 120.0
#: Most correction ranges or stiffness values of one file.
MAX_CASES = 20


class ControllerSection(Section):
    """``[controller]``: the two-sensor lead-through law, eqs. (8.3)-(8.11).

    Parameters
    ----------
    task : str
        ``surface_tracking`` (8.8)-(8.9) or ``peg_in_hole`` (8.8), (8.11).
    mass, damping : list of float, shape (6,)
        Diagonals of the impedance's M [kg, kg m^2] and D [N s/m, N m s/rad], eq. (8.6).
    force_gain : list of float, shape (6,)
        Diagonal of the tool force gain K [m/(N s), rad/(N m s)], eq. (8.4).
    force_reference : float
        Tool force reference along the normal [N].
    correction_range_deg : float
        ``phi_L`` [deg], eq. (8.10).
    nominal_normal : list of float, shape (3,)
        Nominal normal into the workpiece (base frame).
    contact_force, release_force : float
        Contact threshold and release force [N].
    max_speed, max_angular_speed : float
        Safety saturation [m/s], [rad/s].
    loop_period : float
        Sample time [s].
    """

    task: choice("surface_tracking", "peg_in_hole", description="projections (8.8)-(8.9), or (8.8) with (8.11)") = "surface_tracking"
    mass: vector(6, nonnegative=True, bound=1e4, unit="kg, kg m^2", description="diagonal of M, eq. (8.6): x, y, z, then rotations; every entry positive (a singular M is refused)") = [2.0, 2.0, 2.0, 0.05, 0.05, 0.05]
    damping: vector(6, nonnegative=True, bound=1e6, unit="N s/m, N m s/rad", description="diagonal of D, eq. (8.6)") = [40.0, 40.0, 40.0, 1.0, 1.0, 1.0]
    force_gain: vector(6, nonnegative=True, bound=10.0, unit="m/(N s), rad/(N m s)", description="diagonal of the tool force gain K, eq. (8.4)") = [0.005, 0.005, 0.005, 0.0, 0.0, 0.0]
    force_reference: number(ge=-1e3, le=1e3, unit="N", description="tool force reference along the normal (thesis: 2 N surface tracking, 0 peg-in-hole)") = 2.0
    correction_range_deg: number(ge=0, le=90, unit="deg", description="phi_L of eq. (8.10), in [0, 90]") = 10.0
    nominal_normal: vector(3, bound=1e3, description="nominal normal n_n into the workpiece, base frame (non-zero; normalised)") = [0.0, 0.0, -1.0]
    contact_force: number(gt=0, le=1e3, unit="N", description="tool force along n_n above which contact is taken") = 0.5
    release_force: number(gt=0, le=1e4, unit="N", description="handle force away from the surface that releases contact (above contact_force)") = 10.0
    max_speed: number(gt=0, le=10.0, unit="m/s", description="safety saturation of the translational velocity") = 0.25
    max_angular_speed: number(gt=0, le=10.0, unit="rad/s", description="safety saturation of the angular velocity") = 0.5
    loop_period: number(gt=0, le=1.0, unit="s", description="controller sample time (the IRC5 loop: 4 ms)") = LOOP_PERIOD_S


class ServoSection(Section):
    """``[servo]``: the robot as a velocity-controlled servo (assumed figures).

    Parameters
    ----------
    bandwidth_hz : float
        First-order bandwidth of every twist component [Hz].
    delay_samples : int
        Samples between computing and applying a reference (0 or 1).
    """

    bandwidth_hz: number(gt=0, le=1e4, unit="Hz", description="bandwidth of the velocity servo (assumed: the thesis gives none for the IRB 140)") = 50.0
    delay_samples: integer(0, 1, description="samples between computing a reference and applying it") = 0


class SensorsSection(Section):
    """``[sensors]``: force sensor noise.

    Parameters
    ----------
    tool_noise, handle_noise : float
        Standard deviation per force component [N].
    """

    tool_noise: number(ge=0, le=100.0, unit="N", description="tool sensor noise per force component (1 sigma)") = 0.05
    handle_noise: number(ge=0, le=100.0, unit="N", description="handle sensor noise per force component (1 sigma)") = 0.05


class SurfaceSection(Section):
    """``[surface]`` / ``[stiff_surface]``: a compliant plane, normal ``controller.nominal_normal``.

    Parameters
    ----------
    stiffness : float
        Contact stiffness [N/m].
    damping : float
        Contact damping [N s/m].
    """

    stiffness: number(gt=0, le=1e9, unit="N/m", description="contact stiffness (positive)")
    damping: number(ge=0, le=1e6, unit="N s/m", description="contact damping") = 20.0


class PegSection(Section):
    """``[peg]``: peg and misaligned hole (Figure 8.6).

    Parameters
    ----------
    peg_radius, hole_radius, depth : float
        Sizes [m].
    misalignment_deg : float
        Hole axis from the vertical [deg].
    stiffness : float
        Wall stiffness [N/m].
    zero_clearance : bool
        Also run with the hole as narrow as the peg (expected: rejected).
    """

    peg_radius: number(gt=0, le=0.1, unit="m", description="peg radius (thesis: 3 mm match)") = 1.5e-3
    hole_radius: number(gt=0, le=0.1, unit="m", description="hole radius, at least peg_radius (thesis: 4 mm hole)") = 2.0e-3
    depth: number(gt=0, le=0.5, unit="m", description="hole depth") = 0.02
    misalignment_deg: number(ge=0, lt=45, unit="deg", description="hole axis from the vertical") = 5.0
    stiffness: number(gt=0, le=1e9, unit="N/m", description="wall stiffness") = 2.0e4
    zero_clearance: Flag = Field(default=True, description="also run with hole_radius = peg_radius (the thesis: then the peg is rejected)")


class ExperimentSection(Section):
    """``[experiment]``: what is simulated.

    Parameters
    ----------
    duration : float
        Simulated time of each run [s].
    seed : int
        Noise seed.
    operator_noise : float
        The operator's random force [N rms].
    compare_without_force_control : bool
        Surface tracking: also run with the handle sensor alone (Figure 8.4).
    correction_ranges_deg : list of float
        Surface tracking on ``[stiff_surface]`` for these ``phi_L`` (Figure 8.5); empty: skipped.
    stability_stiffness : list of float
        Stiffnesses [N/m] of the linearised contact loop's table.
    """

    duration: number(gt=0, le=MAX_DURATION_S, unit="s", description="simulated time of each run") = 6.5
    seed: integer(0, 2**31 - 1, description="seed of the sensor and operator noise") = 0
    operator_noise: number(ge=0, le=100.0, unit="N", description="the operator's random force (rms)") = 0.7
    compare_without_force_control: Flag = Field(default=True, description="surface tracking: also run with the handle sensor alone (Figure 8.4)")
    correction_ranges_deg: vector(None, nonnegative=True, bound=90.0, min_length=0, max_length=MAX_CASES, unit="deg",
                                  description="surface tracking on [stiff_surface] per phi_L (Figure 8.5); empty: skipped") = []
    stability_stiffness: vector(None, positive=True, bound=1e9, min_length=0, max_length=MAX_CASES, unit="N/m",
                                description="stiffnesses of the linearised contact loop's table (poles, largest stable gain)") = []


@fill_doc(**KIND_DOCS)
class LeadThroughFile(ProblemSchema):
    """A ``lead_through`` problem file.

    Parameters
    ----------
    {header_fields}
    controller : ControllerSection
        ``[controller]``: the control law.
    servo : ServoSection
        ``[servo]``: the robot.
    sensors : SensorsSection
        ``[sensors]``: force sensor noise.
    surface : SurfaceSection or None
        ``[surface]``: the workpiece of surface tracking (required for it).
    stiff_surface : SurfaceSection or None
        ``[stiff_surface]``: the workpiece of the correction-range runs.
    peg : PegSection or None
        ``[peg]``: the workpiece of peg-in-hole (required for it).
    experiment : ExperimentSection
        ``[experiment]``: what is simulated.
    """

    kind: Literal["lead_through"]
    controller: ControllerSection = ControllerSection()
    servo: ServoSection = ServoSection()
    sensors: SensorsSection = SensorsSection()
    surface: SurfaceSection | None = None
    stiff_surface: SurfaceSection | None = None
    peg: PegSection | None = None
    experiment: ExperimentSection = ExperimentSection()
