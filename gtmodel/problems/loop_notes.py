"""The notes a loop check's summary carries about how its controller was built (the plan's lead, the law's gains, its rows).

Each note says where the controller departs from the plain design a reader would assume, with its number:
the reference led by the input delay (:func:`gtmodel.control.reference.delayed_start`), the law's gains limited by
the measurement noise (:func:`gtmodel.control.tracking.limit_noise_gain`), the held end's gain designed away from
the end (:func:`gtmodel.control.lqr.rest_linearization`), an MPC's rows coarser than the check's plant.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from gtmodel.defaults import REST_NEIGHBOURHOOD

__all__ = ["controller_notes", "row_points_note"]


def controller_notes(controller: Any) -> list[str]:
    """The notes on a loop controller's reference and gains.

    Parameters
    ----------
    controller : TrackingController or MPCController
        The controller of a loop-controller file (its ``lead``, ``u_initial``, and a tracking law's ``gain_scale`` and
        ``rest`` where it has them).

    Returns
    -------
    list of str
        One sentence per departure, none for a plain design.
    """
    notes = []
    if getattr(controller, "lead", 0):  # gtmodel.control.reference.delayed_start
        u0 = np.where(np.abs(controller.u_initial) < 1e-9, 0.0, controller.u_initial)
        notes.append(f"reference: {controller.lead} period(s) at rest before the plan, held by the input {', '.join(f'{v:.4g}' for v in u0)} "
                     "(the controller's input delay: the input computed from the first measurement acts a period later); "
                     "the plan follows unchanged")
    scale = getattr(controller, "gain_scale", None)
    if scale is not None and np.any(scale < 1.0):  # gtmodel.control.tracking.limit_noise_gain
        notes.append(f"the law's gain limited in {int(np.sum(np.any(scale < 1.0, axis=1)))} of {scale.shape[0]} periods "
                     f"(the held end's included; smallest factor {float(np.min(scale)):.3g}): there a one-sigma measurement "
                     "error would have moved an input by more than noise_gain_limit of its half range")
    rest = getattr(controller, "rest", None)
    if rest is not None and rest.moved:  # gtmodel.control.lqr.rest_linearization
        notes.append(f"the held end's gain designed on the model linearised at the end with {rest.moved}: the gain of the end's own "
                     f"linearisation reaches a closed-loop spectral radius of {rest.radius_own:.3g} within {REST_NEIGHBOURHOOD:g} of "
                     f"the states' ranges around the end (a friction's or a backlash's slope at rest), this one {rest.radius:.3g}")
    return notes


def row_points_note(controller: Any, plant_substeps: int) -> list[str]:
    """A note when an MPC's constraint rows act at fewer points per period than the check counts the plant's states.

    Parameters
    ----------
    controller : MPCController or TrackingController
        The loop's controller (a tracking law has no rows: no note).
    plant_substeps : int
        The check's plant substeps per period.

    Returns
    -------
    list of str
        The note, or none.
    """
    if getattr(controller, "constraints", None) is None:
        return []
    inside = getattr(controller, "substep_states", None)
    points = 1 if inside is None else int(inside.size2_out(0))
    if points >= plant_substeps:
        return []
    return [f"the MPC's constraint rows act at {points} point(s) per period, the check counts the plant's states at {plant_substeps}: "
            f"a bound may be exceeded between the rows ([mpc] substeps = {plant_substeps} and constraint_substeps = true put them there)"]
