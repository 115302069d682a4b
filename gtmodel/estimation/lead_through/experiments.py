"""The lead-through experiments of Dressler (2012), ch. 8.4, in simulation, with their measures.

* :func:`surface_tracking` (Figure 8.4): the operator takes contact with a compliant
  cardboard surface, pushes the tool along it, then pulls it off; with tool force control
  the contact force is held at 2 N, without it (the handle sensor alone) contact is lost
  and the force peaks;
* :func:`correction_range_study` (Figure 8.5): the same on a stiff metal plate for the
  correction ranges ``phi_L`` = 0, 5 and 10 degrees; the force oscillates at the frequency
  of the contact loop's dominant pole (:mod:`~gtmodel.estimation.lead_through.stability`),
  more strongly the larger the range (the noisy normal estimate, eq. 8.10);
* :func:`peg_in_hole` (Figures 8.6-8.9): a 3 mm peg into a 4 mm hole whose axis is
  misaligned; with zero clearance the peg is rejected (the tool force reference 0 pushes
  the tool away from every constraint it touches, the thesis' explanation).

The operator figures are assumptions of this reproduction (the thesis gives none): stated
as the defaults of :data:`SURFACE_OPERATOR` and :data:`PEG_OPERATOR`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from gtmodel.errors import InputError
from gtmodel.estimation.lead_through.contact import CARDBOARD, METAL_PLATE, PegHole, Surface
from gtmodel.estimation.lead_through.law import LeadThroughLaw
from gtmodel.estimation.lead_through.simulation import LeadThroughRun, Operator, Servo, simulate
from gtmodel.estimation.lead_through.stability import contact_loop

__all__ = [
    "tangent",
    "surface_operator",
    "SURFACE_OPERATOR",
    "PEG_OPERATOR",
    "SETTLE_S",
    "FORCE_BAND_N",
    "PEAK_LIMIT_N",
    "SurfaceTracking",
    "CorrectionRangeRow",
    "PegInHole",
    "surface_tracking",
    "correction_range_study",
    "peg_in_hole",
    "peg_law",
]

#: Time after the first contact before the force is judged [s].
SETTLE_S = 0.5
#: Largest accepted |f - f_ref| with tool force control [N] (the issue's criterion for Figure 8.4).
FORCE_BAND_N = 0.5
#: A force above this [N] is a peak (thesis: up to 7 N without tool force control).
PEAK_LIMIT_N = 5.0
#: The release command of :data:`SURFACE_OPERATOR` starts here [s].
RELEASE_AT_S = 5.0

def tangent(normal) -> np.ndarray:
    """A unit tangent of a surface: base x projected onto the plane (base y if x is the normal).

    Parameters
    ----------
    normal : array_like, shape (3,)
        Unit normal.

    Returns
    -------
    numpy.ndarray, shape (3,)
    """
    n = np.asarray(normal, dtype=float)
    for axis in np.eye(3):
        t = axis - (axis @ n) * n
        if np.linalg.norm(t) > 0.3:
            return t / np.linalg.norm(t)
    raise InputError(f"normal: expected a unit vector, got {n.tolist()}")  # pragma: no cover - a unit n has a tangent


def surface_operator(normal=(0.0, 0.0, -1.0), noise_rms: float = 0.7) -> Operator:
    """The operator of the surface experiments, in the surface's frame.

    Pushes 3 N along the normal for 0.15 s, from 1 s pushes 2 N along the tangent
    (:func:`tangent`) while keeping the tool 1 mm into the surface by sight (150 N/m along
    the normal, 0.2 s lag), a random force of ``noise_rms`` (1.5 Hz); from 5 s pulls 12 N
    off the surface for 0.3 s and aims 5 cm above it.

    Parameters
    ----------
    normal : array_like, shape (3,), optional
        Unit normal into the surface (through the origin).
    noise_rms : float, optional
        Random force [N rms].

    Returns
    -------
    Operator
    """
    n = np.asarray(normal, dtype=float)
    t = tangent(n)
    r = RELEASE_AT_S
    force = [(0.0, 3.0 * n), (0.15, 3.0 * n), (0.25, 0 * n), (1.0, 0 * n), (1.1, 2.0 * t), (r, 2.0 * t),
             (r + 0.1, -12.0 * n), (r + 0.3, -12.0 * n), (r + 0.4, 0 * n)]
    aim = [(0.0, 0.001 * n), (r, 0.001 * n), (r + 0.1, -0.05 * n)]
    return Operator(force=force, aim=aim, gain=150.0 * np.outer(n, n), lag=0.2, noise_rms=noise_rms, noise_hz=1.5)


#: Operator of the surface experiments on a horizontal surface (:func:`surface_operator`).
SURFACE_OPERATOR = surface_operator()
#: Operator of the peg-in-hole experiment: pushes down 2 N and steers the tip towards the
#: hole's mouth by sight (400 N/m laterally, 0.2 s lag), 0.3 N rms random force (1 Hz).
PEG_OPERATOR = Operator(force=[(0.0, (0, 0, -2.0))], aim=[(0.0, (0, 0, 0))], gain=(400.0, 400.0, 0.0), lag=0.2,
                        noise_rms=0.3, noise_hz=1.0)


@dataclass(frozen=True)
class SurfaceTracking:
    """Measures of one surface-tracking run (Figure 8.4).

    Parameters
    ----------
    run : LeadThroughRun
        The record.
    force_reference : float
        ``f_ref`` [N].
    first_contact_s : float
        First time the true contact force exceeds 0.5 N [s] (NaN: never).
    lost_contact_fraction : float
        Share of the judged window (first contact + :data:`SETTLE_S` to the release
        command) without contact force.
    force_min, force_max : float
        True normal force in the judged window [N].
    peak_force : float
        Largest true normal force of the run [N].
    released : bool
        Contact released (the controller's contact state and the force) by the end of the run.
    """

    run: LeadThroughRun = field(repr=False)
    force_reference: float
    first_contact_s: float
    lost_contact_fraction: float
    force_min: float
    force_max: float
    peak_force: float
    released: bool

    @property
    def force_error(self) -> float:
        """Largest ``|f - f_ref|`` in the judged window [N]."""
        return max(abs(self.force_max - self.force_reference), abs(self.force_min - self.force_reference))

    @property
    def contact_kept(self) -> bool:
        """No sample without contact force in the judged window."""
        return self.lost_contact_fraction == 0.0


def surface_tracking(law: LeadThroughLaw | None = None, surface: Surface = CARDBOARD, operator: Operator = SURFACE_OPERATOR,
                     duration: float = 6.5, servo: Servo | None = None, tool_noise: float = 0.05, seed: int = 0) -> SurfaceTracking:
    """Surface tracking on a compliant surface (Dressler (2012), Figure 8.4).

    Parameters
    ----------
    law : LeadThroughLaw, optional
        The controller (default: surface tracking, ``phi_L`` = 10 degrees, 2 N; pass
        ``tool_force_control=False`` for the handle sensor alone).
    surface : Surface, optional
        The workpiece (default the cardboard).
    operator : Operator, optional
        The operator (default :data:`SURFACE_OPERATOR`; the release command at 5 s).
    duration : float, optional
        Simulated time [s].
    servo : Servo, optional
        The robot.
    tool_noise : float, optional
        Tool sensor noise [N].
    seed : int, optional
        Noise seed.

    Returns
    -------
    SurfaceTracking

    Raises
    ------
    InputError
        A law for another task; bad simulation arguments.
    """
    law = LeadThroughLaw() if law is None else law
    if law.task != "surface_tracking":
        raise InputError(f"law: expected a surface_tracking law, got task {law.task!r}")
    start = surface.point - 0.01 * surface.normal  # 10 mm off the surface
    run = simulate(law, surface, operator, duration, servo=servo, start=start, tool_noise=tool_noise, seed=seed)
    f = run.normal_force(surface.normal)
    touched = np.flatnonzero(f > 0.5)
    if touched.size == 0:
        nan = float("nan")
        return SurfaceTracking(run, law.force_reference, nan, 1.0, nan, nan, float(f.max()), False)
    start = touched[0] + int(round(SETTLE_S / run.dt))
    stop = int(round(min(RELEASE_AT_S, duration) / run.dt))
    window = f[start:stop] if stop > start else f[start:start + 1]
    released = bool(not run.contact[-1] and f[-1] <= 0.0)
    return SurfaceTracking(run, law.force_reference, float(run.t[touched[0]]), float(np.mean(window <= 0.0)),
                           float(window.min()), float(window.max()), float(f.max()), released)


@dataclass(frozen=True)
class CorrectionRangeRow:
    """Force oscillation on the stiff surface for one correction range (Figure 8.5).

    Parameters
    ----------
    correction_range_deg : float
        ``phi_L`` [deg].
    force_std : float
        Standard deviation of the true normal force in steady contact [N].
    force_min, force_max : float
        Its extremes [N].
    lost_contact_fraction : float
        Share of steady-contact samples without contact force.
    frequency_hz : float
        Peak of the force spectrum [Hz].
    predicted_hz : float
        Oscillation frequency of the linearised contact loop [Hz].
    run : LeadThroughRun or None, optional
        The record (not a measure: left out of :meth:`measures`).
    """

    correction_range_deg: float
    force_std: float
    force_min: float
    force_max: float
    lost_contact_fraction: float
    frequency_hz: float
    predicted_hz: float
    run: LeadThroughRun | None = field(default=None, repr=False, compare=False)

    def measures(self) -> dict[str, float]:
        """The measures as a dict (every field but ``run``).

        Returns
        -------
        dict of str to float
        """
        return {k: v for k, v in vars(self).items() if k != "run"}


def correction_range_study(ranges: Sequence[float] = (0.0, 5.0, 10.0), surface: Surface = METAL_PLATE,
                           law: LeadThroughLaw | None = None, servo: Servo | None = None, duration: float = 6.0,
                           tool_noise: float = 0.1, operator_noise: float = 0.5, seed: int = 0) -> list[CorrectionRangeRow]:
    """Surface tracking on a stiff surface for several correction ranges (Dressler (2012), Figure 8.5).

    The operator pushes 3 N along the normal, then from 1 s 2 N along the tangent
    (:func:`tangent`; no visual correction); the force is judged from 2 s on (steady
    contact, moving).

    Parameters
    ----------
    ranges : sequence of float, optional
        Correction ranges ``phi_L`` [deg], each in [0, 90].
    surface : Surface, optional
        The workpiece (default the metal plate).
    law : LeadThroughLaw, optional
        The controller whose range is varied (default :class:`LeadThroughLaw`).
    servo : Servo, optional
        The robot (also used by the linearised loop).
    duration : float, optional
        Simulated time [s], above 3 s.
    tool_noise : float, optional
        Tool sensor noise [N] (the source of the normal estimate's noise).
    operator_noise : float, optional
        The operator's random force [N rms].
    seed : int, optional
        Noise seed (the same for every range).

    Returns
    -------
    list of CorrectionRangeRow
        One per range, in order.

    Raises
    ------
    InputError
        No range, a range outside [0, 90], a duration of 3 s or less.
    """
    if len(ranges) == 0:
        raise InputError("ranges: expected at least one correction range")
    if not duration > 3.0:
        raise InputError(f"duration: expected more than 3 s, got {duration!r}")
    base = LeadThroughLaw() if law is None else law
    n, t = surface.normal, tangent(surface.normal)
    operator = Operator(force=[(0.0, 3.0 * n), (1.0, 3.0 * n), (1.1, 2.0 * t)], noise_rms=operator_noise, noise_hz=1.5)
    servo = Servo() if servo is None else servo
    kn = float(surface.normal @ base.K[:3, :3] @ surface.normal)
    predicted = contact_loop(kn, surface.stiffness, surface.damping, servo, base.dt).frequency_hz
    rows = []
    for phi in ranges:
        law_phi = LeadThroughLaw(**{**_law_args(base), "correction_range_deg": phi})
        run = simulate(law_phi, surface, operator, duration, servo=servo, start=surface.point - 0.01 * n,
                       tool_noise=tool_noise, seed=seed)
        f = run.normal_force(surface.normal)[int(round(2.0 / run.dt)):]
        spectrum = np.abs(np.fft.rfft(f - f.mean()))
        freq = np.fft.rfftfreq(f.size, run.dt)
        rows.append(CorrectionRangeRow(float(phi), float(f.std()), float(f.min()), float(f.max()), float(np.mean(f <= 0.0)),
                                       float(freq[1 + np.argmax(spectrum[1:])]), predicted, run))
    return rows


def _law_args(law: LeadThroughLaw) -> dict:
    names = ("task", "M", "D", "K", "force_reference", "correction_range_deg", "nominal_normal", "contact_force",
             "release_force", "max_speed", "max_angular_speed", "dt", "tool_force_control")
    return {n: getattr(law, n) for n in names}


def peg_law(**overrides) -> LeadThroughLaw:
    """The peg-in-hole controller of Dressler (2012), eq. (8.11): force and torque reference 0.

    Parameters
    ----------
    **overrides
        Fields of :class:`LeadThroughLaw` to change (e.g. ``K``).

    Returns
    -------
    LeadThroughLaw
        ``task="peg_in_hole"``, ``force_reference=0``, ``K`` 0.005 m/(N s) and 0.5 rad/(N m s).
    """
    args = {"task": "peg_in_hole", "force_reference": 0.0, "K": [0.005] * 3 + [0.5] * 3, "correction_range_deg": 0.0}
    return LeadThroughLaw(**{**args, **overrides})


@dataclass(frozen=True)
class PegInHole:
    """Measures of a peg-in-hole run (Figures 8.6-8.9).

    Parameters
    ----------
    run : LeadThroughRun
        The record.
    hole : PegHole
        The hole.
    max_insertion : float
        Deepest tip position along the hole axis [m].
    final_insertion : float
        Tip depth at the end [m].
    max_force : float
        Largest contact force [N].
    angle_start_deg, angle_end_deg : float
        Angle between the peg and the hole axis at the start and the end [deg].
    """

    run: LeadThroughRun = field(repr=False)
    hole: PegHole
    max_insertion: float
    final_insertion: float
    max_force: float
    angle_start_deg: float
    angle_end_deg: float

    @property
    def inserted(self) -> bool:
        """The tip reached the hole's depth (within a millimetre)."""
        return self.max_insertion >= self.hole.depth - 1e-3


def peg_in_hole(hole: PegHole | None = None, law: LeadThroughLaw | None = None, operator: Operator = PEG_OPERATOR,
                duration: float = 10.0, servo: Servo | None = None, start=(0.0015, 0.0005, 0.01), tool_noise: float = 0.02,
                seed: int = 0) -> PegInHole:
    """A peg inserted into a misaligned hole by lead-through (Dressler (2012), Figures 8.6-8.9).

    Parameters
    ----------
    hole : PegHole, optional
        Peg and hole (default: 3 mm peg, 4 mm hole, 20 mm deep, 5 degrees misaligned).
    law : LeadThroughLaw, optional
        The controller (default :func:`peg_law`).
    operator : Operator, optional
        The operator (default :data:`PEG_OPERATOR`).
    duration : float, optional
        Simulated time [s].
    servo : Servo, optional
        The robot.
    start : array_like, shape (3,), optional
        Initial tip position [m] (above the block).
    tool_noise : float, optional
        Tool sensor noise [N].
    seed : int, optional
        Noise seed.

    Returns
    -------
    PegInHole

    Raises
    ------
    InputError
        A law for another task; bad simulation arguments.
    """
    hole = PegHole() if hole is None else hole
    law = peg_law() if law is None else law
    if law.task != "peg_in_hole":
        raise InputError(f"law: expected a peg_in_hole law, got task {law.task!r}")
    run = simulate(law, hole, operator, duration, servo=servo, start=start, tool_noise=tool_noise, seed=seed)
    depth = hole.insertion(run.p)
    angle = np.degrees(np.arccos(np.clip(-(run.R[:, :, 2] @ hole.axis), -1.0, 1.0)))
    return PegInHole(run, hole, float(depth.max()), float(depth[-1]), float(np.linalg.norm(run.F_contact[:, :3], axis=1).max()),
                     float(angle[0]), float(angle[-1]))

