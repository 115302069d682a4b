"""The correction loop as Cvitanic (2021), section 5.3.5 describes its simulation: the error is the vibration only.

The thesis' loop (text of section 5.3.5, Fig. 33): every 4 ms cycle the error is "the difference
between the current measured position of the end-effector and where it was commanded to go in
the previous step"; the P controller turns it into a position correction; the correction enters
the equivalent-force model (eqs. (30)-(32)) and the model's output is the motion error, after the
52 ms controller delay. So the correction is not accumulated into the commanded path and the
error a correction causes is the structural vibration ``delta = -H(s) F_eq`` alone, without the
rigid following of the command. In :class:`~gtmodel.estimation.closed_loop.correction.OffsetResponseModel`
terms the plant from the correction to the error is ``G(z) = P(z) - 1`` (``P``: the offset-to-TCP
response, :meth:`~gtmodel.estimation.closed_loop.correction.OffsetResponseModel.response_ss`),
delayed 13 cycles, and the loop ``u_k = -K e_k`` closes ``e = -K z^-13 G(z) e``.

The project's own loop (:mod:`~gtmodel.estimation.closed_loop.correction_loop`) accumulates the
corrections (an offset stays in the path: ``K z / (z - 1)``) and executes them with DC gain 1,
which bounds every gain near ``2 sin(pi / 50) = 0.126`` whatever the mode. Here the gain limit
is set by the vibration's size at the phase crossovers of the delayed loop (every ``2 pi / 13``
rad per sample): below the resonance ``|G| ~ (M / m) (omega / omega_n)^2``, at a lightly damped
resonance ``|G| ~ (M / m) / (2 zeta)``, so the limit follows the mode's damping and frequency,
not a fixed 0.126.
"""

from __future__ import annotations

import control
import numpy as np

from gtmodel._arrays import positive_float, positive_int
from gtmodel.errors import InputError
from gtmodel.estimation.closed_loop.correction import OffsetResponseModel

__all__ = ["vibration_plant", "vibration_loop_critical_gain"]


def vibration_plant(model: OffsetResponseModel, delay_cycles: int = 13) -> control.StateSpace:
    """Plant from a (not accumulated) correction to the vibration error: ``z^-delay (P(z) - 1)``.

    Cvitanic (2021), section 5.3.5 and eqs. (30)-(32).

    Parameters
    ----------
    model : OffsetResponseModel
        Response of the direction.
    delay_cycles : int, optional
        Controller delay in cycles (default 13 = 52 ms / 4 ms).

    Returns
    -------
    control.StateSpace
        Discrete, sample time ``model.dt``.

    Raises
    ------
    InputError
        Not an OffsetResponseModel or a delay below 1.
    """
    if not isinstance(model, OffsetResponseModel):
        raise InputError(f"model: expected an OffsetResponseModel, got {type(model).__name__}")
    delay = positive_int(delay_cycles, "delay_cycles")
    shift = control.ss(np.eye(delay, k=-1), np.eye(delay, 1), np.eye(1, delay, delay - 1), [[0.0]], model.dt)
    vib = model.response_ss() - control.ss([], [], [], [[1.0]], model.dt)
    return control.series(shift, vib)


def vibration_loop_critical_gain(model: OffsetResponseModel, delay_cycles: int = 13, upper: float = 100.0, tol: float = 1e-6) -> float:
    """Smallest P gain ``K > 0`` at which the vibration loop ``e = -K z^-delay G(z) e`` becomes unstable.

    Bisection on the largest closed-loop pole modulus (:func:`control.feedback`, poles of the
    state matrix), Cvitanic (2021), section 5.3.5.

    Parameters
    ----------
    model : OffsetResponseModel
        Response of the direction.
    delay_cycles : int, optional
        Controller delay in cycles.
    upper : float, optional
        Largest gain searched; returned when the loop is stable up to it.
    tol : float, optional
        Width of the final bracket.

    Returns
    -------
    float
        The critical gain [-] (``upper`` if none below it).

    Raises
    ------
    InputError
        A bad model, delay, ``upper`` or ``tol``.
    """
    plant = vibration_plant(model, delay_cycles)
    upper = positive_float(upper, "upper")
    tol = positive_float(tol, "tol")

    def stable(K: float) -> bool:
        loop = control.feedback(plant * K, control.ss([], [], [], [[1.0]], model.dt))
        return bool(np.max(np.abs(np.linalg.eigvals(np.asarray(loop.A)))) < 1.0)

    if stable(upper):
        return upper
    lo, hi = 0.0, upper
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return hi
