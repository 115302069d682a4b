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

from collections.abc import Callable

import control
import numpy as np

from gtmodel._arrays import positive_float, positive_int
from gtmodel.errors import InputError
from gtmodel.estimation.closed_loop.correction import OffsetResponseModel

__all__ = ["bisect_critical_gain", "delay_line", "vibration_loop_critical_gain", "vibration_plant"]


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
    vib = model.response_ss() - control.ss([], [], [], [[1.0]], model.dt)
    return control.series(delay_line(delay, model.dt), vib)


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
        The critical gain [-] (``upper`` if none below it, 0 if unstable at ``tol``); the
        bisection of :func:`bisect_critical_gain`.

    Raises
    ------
    InputError
        A bad model, delay, ``upper`` or ``tol``.
    """
    plant = vibration_plant(model, delay_cycles)
    unity = control.ss([], [], [], [[1.0]], model.dt)
    return bisect_critical_gain(
        lambda K: float(np.max(np.abs(np.linalg.eigvals(np.asarray(control.feedback(plant * K, unity).A))))), upper, tol)


def delay_line(n: int, dt: float) -> control.StateSpace:
    """``y_k = u_{k-n}``: an exact shift register, the controller delay ``z^-n``.

    Parameters
    ----------
    n : int
        Delay in samples, >= 1.
    dt : float
        Sample time [s].

    Returns
    -------
    control.StateSpace
        Discrete, ``n`` states, strictly proper.
    """
    A = np.eye(n, k=-1)
    B = np.zeros((n, 1))
    B[0, 0] = 1.0
    C = np.zeros((1, n))
    C[0, -1] = 1.0
    return control.ss(A, B, C, [[0.0]], dt)


def bisect_critical_gain(radius: Callable[[float], float], max_gain: float, tol: float) -> float:
    """Gain at which a closed loop's spectral radius reaches 1, by bisection on ``[tol, max_gain]``.

    Cvitanic (2021), eq. (33). Assumes the loop is stable for small gains and loses
    stability once (checked on the bracket ends).

    Parameters
    ----------
    radius : callable
        ``radius(K) -> float``: largest closed-loop pole modulus at the gain ``K`` [-].
    max_gain : float
        Upper end of the bracket [-].
    tol : float
        Lower end and final width of the bracket [-].

    Returns
    -------
    float
        The critical gain [-] (``max_gain`` if the loop is stable there, 0 if unstable at ``tol``).

    Raises
    ------
    InputError
        ``max_gain`` or ``tol`` not a positive number.
    """
    lo, hi = positive_float(tol, "tol"), positive_float(max_gain, "max_gain")
    if radius(hi) < 1.0:
        return hi
    if radius(lo) >= 1.0:
        return 0.0
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if radius(mid) < 1.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)
