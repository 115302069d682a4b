"""The measurement filter a loop-controller file gives its controller (``measurement_noise``, default ``[check] noise``).

The sensors' noise is declared once: ``[check] noise`` is what the check adds to the plant's state, and, unless the
controller's table gives its own ``measurement_noise``, what the controller's Kalman filter assumes
(:mod:`gtmodel.control.state_filter`). The plant's mismatch (``parameter_factor`` and the rest of ``[check]``) stays
unknown to the controller. Zeros or ``[]``: no filter.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from gtmodel.control.state_filter import measurement_filter
from gtmodel.errors import GtModelError
from gtmodel.problems.base import ProblemFile

__all__ = ["with_measurement_filter"]


def with_measurement_filter(file: ProblemFile, field: str, controller: Any, declared: list[float] | None,
                            check_noise: list[float] | None, ode: Any = None) -> Any:
    """The controller with the filter of its measurement (:attr:`~gtmodel.control.mpc.MPCController.state_filter`).

    Parameters
    ----------
    file : ProblemFile
        The file (for the errors).
    field : str
        The controller table's field, e.g. ``"mpc.measurement_noise"``.
    controller : MPCController or TrackingController
        The built controller.
    declared : list of float or None
        The field's value (None: not given, ``check_noise``).
    check_noise : list of float or None
        ``[check] noise`` (the default; None or empty: none).
    ode : ExplicitODE, optional
        The controller's model, at its default parameters (``ode.p_default``): ``Q``'s parameter term, each parameter
        :data:`~gtmodel.control.state_filter.PARAMETER_ERROR` off (default None: none).

    Returns
    -------
    MPCController or TrackingController
        A copy with ``state_filter`` set, or the controller itself where no state is noisy.

    Raises
    ------
    ProblemError
        Naming ``field``: not one standard deviation per state.
    """
    sigma = check_noise if declared is None else declared
    if not sigma:
        return controller
    names = list(controller.x_names)
    if len(sigma) != len(names):
        raise file.fail(field, f"{len(names)} standard deviations, one per state ({', '.join(names)})", sigma)
    try:
        f = measurement_filter(controller, sigma, None if ode is None else ode.f, None if ode is None else ode.p_default)
    except GtModelError as exc:
        raise file.wrap(field, exc) from None
    return controller if f is None else replace(controller, state_filter=f)
