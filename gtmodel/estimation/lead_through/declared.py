"""A declared lead-through study: the experiments of Dressler (2012), ch. 8.4, run and checked.

:class:`LeadThroughDeclaration` holds the controller, the robot, the workpieces and what to
run; :meth:`~LeadThroughDeclaration.solve` runs the experiments and judges each against the
structure the thesis reports (:data:`CHECKS`). The result's status is ``completed`` when
every check holds and ``check_failed`` otherwise (the checks say which failed).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

from gtmodel.estimation.lead_through.contact import PegHole, Surface
from gtmodel.estimation.lead_through.experiments import (
    FORCE_BAND_N,
    PEAK_LIMIT_N,
    CorrectionRangeRow,
    PegInHole,
    SurfaceTracking,
    correction_range_study,
    peg_in_hole,
    surface_operator,
    surface_tracking,
)
from gtmodel.estimation.lead_through.law import LeadThroughLaw
from gtmodel.estimation.lead_through.simulation import Servo
from gtmodel.estimation.lead_through.stability import contact_loop, largest_stable_gain
from gtmodel.status import Status

__all__ = ["CHECKS", "PEG_FORCE_BOUND_N", "FREQUENCY_TOLERANCE", "StabilityRow", "LeadThroughDeclaration", "LeadThroughSolution"]

#: Largest accepted contact force of the peg-in-hole run [N] ("contact forces bounded").
PEG_FORCE_BOUND_N = 30.0
#: Largest accepted relative gap between the simulated and the predicted oscillation frequency.
FREQUENCY_TOLERANCE = 0.10
#: What each check asserts (the key in ``summary.json``'s ``checks``).
CHECKS = {
    "force_held": f"with tool force control: contact kept and |f - f_ref| <= {FORCE_BAND_N} N after contact (Figure 8.4)",
    "without_control_lost_or_peaks": f"without tool force control: contact lost or force above {PEAK_LIMIT_N} N (Figure 8.4)",
    "released": "the operator's pull releases the contact",
    "oscillation_grows_with_range": "force oscillation on the stiff surface grows with the correction range (Figure 8.5)",
    "frequency_predicted": f"simulated oscillation frequency within {FREQUENCY_TOLERANCE:.0%} of the linearised loop's",
    "peg_inserted": "the misaligned peg reaches the hole's depth (Figure 8.6 set-up)",
    "peg_forces_bounded": f"peg-in-hole contact force below {PEG_FORCE_BOUND_N} N",
    "zero_clearance_rejected": "with zero clearance the peg does not enter the hole",
}


@dataclass(frozen=True)
class StabilityRow:
    """The linearised contact loop at one stiffness.

    Parameters
    ----------
    stiffness : float
        Contact stiffness [N/m].
    largest_stable_gain : float
        Largest stable force gain along the normal [m/(N s)].
    spectral_radius : float
        Largest pole magnitude at the controller's gain.
    frequency_hz : float
        Oscillation frequency of the dominant pole at the controller's gain [Hz].
    damping_ratio : float
        Its damping ratio.
    """

    stiffness: float
    largest_stable_gain: float
    spectral_radius: float
    frequency_hz: float
    damping_ratio: float


@dataclass(frozen=True)
class LeadThroughSolution:
    """The runs of a lead-through study and their checks.

    Parameters
    ----------
    status : Status
        ``completed`` or ``check_failed``.
    message : str
        What failed, or a one-line summary.
    tracking : SurfaceTracking or None
        Surface tracking with tool force control.
    without_control : SurfaceTracking or None
        The same with the handle sensor alone.
    correction_ranges : list of CorrectionRangeRow
        Figure 8.5 runs.
    peg : PegInHole or None
        Peg-in-hole run.
    peg_zero_clearance : PegInHole or None
        The same with a hole as narrow as the peg.
    stability : list of StabilityRow
        The linearised loop per stiffness.
    checks : dict of str to bool
        The checks run (keys of :data:`CHECKS`).
    """

    status: Status
    message: str
    tracking: SurfaceTracking | None = None
    without_control: SurfaceTracking | None = None
    correction_ranges: list[CorrectionRangeRow] = field(default_factory=list)
    peg: PegInHole | None = None
    peg_zero_clearance: PegInHole | None = None
    stability: list[StabilityRow] = field(default_factory=list)
    checks: dict[str, bool] = field(default_factory=dict)


@dataclass(frozen=True)
class LeadThroughDeclaration:
    """What a lead-through study runs.

    Parameters
    ----------
    law : LeadThroughLaw
        The controller.
    servo : Servo
        The robot.
    surface : Surface or None
        Workpiece of surface tracking (None: not run).
    stiff_surface : Surface or None
        Workpiece of the correction-range runs (None or no ranges: not run).
    hole : PegHole or None
        Peg and hole (None: not run).
    duration : float
        Simulated time of a surface-tracking or peg run [s].
    seed : int
        Noise seed.
    tool_noise, handle_noise : float
        Sensor noise [N].
    operator_noise : float
        The operator's random force [N rms].
    compare_without_force_control : bool
        Also run surface tracking with the handle sensor alone.
    correction_ranges_deg : tuple of float
        ``phi_L`` of the correction-range runs [deg].
    zero_clearance : bool
        Also run peg-in-hole with zero clearance.
    stability_stiffness : tuple of float
        Stiffnesses of the linearised loop's table [N/m].
    """

    law: LeadThroughLaw
    servo: Servo
    surface: Surface | None = None
    stiff_surface: Surface | None = None
    hole: PegHole | None = None
    duration: float = 6.5
    seed: int = 0
    tool_noise: float = 0.05
    handle_noise: float = 0.05
    operator_noise: float = 0.7
    compare_without_force_control: bool = True
    correction_ranges_deg: tuple[float, ...] = ()
    zero_clearance: bool = True
    stability_stiffness: tuple[float, ...] = ()

    def solve(self, *, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> LeadThroughSolution:
        """Run the declared experiments and their checks.

        Parameters
        ----------
        verbose : bool, optional
            Unused (no solver output).
        previous : Any, optional
            Unused.
        warm_start : bool, optional
            Unused.

        Returns
        -------
        LeadThroughSolution
            ``completed`` when every check holds, else ``check_failed`` naming the failed checks.
        """
        out: dict[str, Any] = {"checks": {}}
        checks = out["checks"]
        common = {"servo": self.servo, "tool_noise": self.tool_noise, "seed": self.seed}
        if self.surface is not None:
            operator = surface_operator(self.surface.normal, self.operator_noise)
            r = surface_tracking(self.law, self.surface, operator, self.duration, **common)
            out["tracking"] = r
            checks["force_held"] = bool(r.contact_kept and r.force_error <= FORCE_BAND_N)
            checks["released"] = r.released
            if self.compare_without_force_control:
                w = surface_tracking(replace(self.law, tool_force_control=False), self.surface, operator, self.duration, **common)
                out["without_control"] = w
                checks["without_control_lost_or_peaks"] = bool(w.lost_contact_fraction > 0 or w.peak_force > PEAK_LIMIT_N)
        if self.stiff_surface is not None and self.correction_ranges_deg:
            rows = correction_range_study(self.correction_ranges_deg, self.stiff_surface, self.law, self.servo,
                                          duration=max(self.duration, 3.5), tool_noise=max(self.tool_noise, 1e-3),
                                          operator_noise=self.operator_noise, seed=self.seed)
            out["correction_ranges"] = rows
            ordered = sorted(rows, key=lambda row: row.correction_range_deg)
            checks["oscillation_grows_with_range"] = all(a.force_std < b.force_std for a, b in zip(ordered, ordered[1:]))
            top = ordered[-1]
            checks["frequency_predicted"] = abs(top.frequency_hz - top.predicted_hz) <= FREQUENCY_TOLERANCE * top.predicted_hz
        if self.hole is not None:
            peg = peg_in_hole(self.hole, self.law, duration=self.duration, **common)
            out["peg"] = peg
            checks["peg_inserted"] = peg.inserted
            checks["peg_forces_bounded"] = peg.max_force < PEG_FORCE_BOUND_N
            if self.zero_clearance:
                tight = peg_in_hole(replace(self.hole, hole_radius=self.hole.peg_radius), self.law, duration=self.duration, **common)
                out["peg_zero_clearance"] = tight
                checks["zero_clearance_rejected"] = tight.max_insertion < self.hole.peg_radius
        n = self.law.nominal_normal
        kn = float(n @ self.law.K[:3, :3] @ n)
        for k in self.stability_stiffness:
            damping = self.surface.damping if self.surface is not None else 0.0
            loop = contact_loop(kn, k, damping, self.servo, self.law.dt)
            out.setdefault("stability", []).append(StabilityRow(
                float(k), largest_stable_gain(k, damping, self.servo, self.law.dt), loop.spectral_radius, loop.frequency_hz,
                loop.damping_ratio))
        failed = [name for name, ok in checks.items() if not ok]
        status = Status.CHECK_FAILED if failed else Status.COMPLETED
        message = ("checks failed: " + "; ".join(f"{name} ({CHECKS[name]})" for name in failed)) if failed \
            else f"simulated; {len(checks)} checks of the thesis' structure hold"
        return LeadThroughSolution(status=status, message=message, **out)
