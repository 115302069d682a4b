"""The reference of a loop controller: a table sampled at the loop period and indexed by time.

A loop controller (the tracking controller of :mod:`gtmodel.control.tracking`, the MPC of
:mod:`gtmodel.control.mpc`) tracks a motion ``x*(t), u*(t)`` given at some times (an
optimal control result's mesh, a CSV table). :func:`sample_reference` puts it on the loop's
grid ``t_k = t_0 + k dt``: the states linearly interpolated there, each input the mean of the
reference's input over the period it is held (:func:`period_means`; a loop holds its input for
a period: an input that switches inside the period, such as a minimum-time plan's bang-bang
voltage, held at its value at ``t_k`` would act a whole period), and :func:`period_index`
is the row read at time ``t``: ``k = floor((t - t_0) / dt + eps)`` clamped to ``0 .. last``,
the same expression for a number (Python) and a CasADi expression (the generated C, where
a NaN ``t`` reads row 0 and the controller's ``ok`` flags it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError

__all__ = ["INDEX_EPS", "PERIOD_EPS", "FLOAT_PERIOD_LIMIT", "MEASUREMENT_LIMIT", "MEMORY_LIMIT", "SampledReference", "hold_input", "start_input", "delayed_start", "sampled", "period_means", "sample_reference", "period_index",
           "reference_scales", "plausible_range"]

#: Added to ``(t - t_0) / dt`` before ``floor``: a time on the grid (``k dt`` in floating
#: point) selects sample ``k``, not ``k - 1``.
INDEX_EPS = 1e-6
#: Slack, in periods, of :func:`period_index` (the row a loop controller reads at time ``t``): a
#: call up to 0.1 % of a period before a grid time reads that grid time's row. It covers clock
#: jitter and the round-off of ``(t - t_0) / dt`` in the generated C, float32 included: at
#: ``k`` periods that round-off is about ``4 k 2^-23`` periods, below this slack up to
#: :data:`FLOAT_PERIOD_LIMIT` periods (a float build of a longer reference is refused).
PERIOD_EPS = 1e-3
#: Most periods from time 0 a ``real = "float"`` loop step may index (``4 k 2^-23 <= PERIOD_EPS``).
FLOAT_PERIOD_LIMIT = int(PERIOD_EPS / (4 * 2.0 ** -23))
#: A value more than this many scales (:func:`reference_scales`) outside its reference's range is
#: absurd: a measured state (the generated step rejects it: ``GT_BAD_ARGUMENT``, the safe input,
#: its memory untouched; :mod:`gtmodel.codegen.loop_step`), an input without bounds in the memory.
MEASUREMENT_LIMIT = 1e6
#: An estimate in a loop controller's memory more than this many scales from zero is absurd (an
#: MPC's input-disturbance estimate: input scales, half the bound range; a tracking controller's
#: integrator state: state scales times the reference's duration): the generated step resets the
#: memory (``GT_MEMORY_RESET``).
MEMORY_LIMIT = 10.0


@dataclass
class SampledReference:
    """A reference sampled at the loop period: the part every loop controller shares.

    Parameters
    ----------
    dt : float
        Loop period [s].
    t0 : float
        Time of the first sample [s].
    x_ref : numpy.ndarray
        ``(N, nx)`` reference states at ``t_0 + k dt``.
    u_ref : numpy.ndarray
        ``(N, nu)`` reference inputs there.
    """

    dt: float
    t0: float
    x_ref: np.ndarray
    u_ref: np.ndarray

    @property
    def nx(self) -> int:
        """Number of states."""
        return self.x_ref.shape[1]

    @property
    def nu(self) -> int:
        """Number of inputs."""
        return self.u_ref.shape[1]

    @property
    def length(self) -> int:
        """Number of reference samples ``N``."""
        return self.x_ref.shape[0]

    def plausible_ranges(self, u_lb: np.ndarray, u_ub: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The scales and plausible ranges a generated step checks its measurement and last input against.

        Parameters
        ----------
        u_lb, u_ub : numpy.ndarray
            ``(nu,)`` the input bounds (may be infinite).

        Returns
        -------
        x_scale, u_scale : numpy.ndarray
            ``(nx,)``, ``(nu,)`` (:func:`reference_scales`).
        x, u : numpy.ndarray
            ``(2, nx)``: the reference's range widened by :data:`MEASUREMENT_LIMIT` state scales;
            ``(2, nu)``: the input bounds, where infinite the reference's range widened by
            ``MEASUREMENT_LIMIT`` input scales (:func:`plausible_range`).
        """
        x_scale, u_scale = reference_scales(self.x_ref, self.u_ref, u_lb, u_ub)
        return (x_scale, u_scale, plausible_range(self.x_ref, x_scale, MEASUREMENT_LIMIT),
                plausible_range(self.u_ref, u_scale, MEASUREMENT_LIMIT, u_lb, u_ub))


def hold_input(f: ca.Function, x: Any, u_guess: Any, p: Any, iterations: int = 10) -> np.ndarray:
    """The input that holds a state at rest: least squares ``f(x, u) = 0`` in ``u`` (Gauss-Newton from ``u_guess``).

    What a reference holds after its motion ends (its last input, mid-braking in a
    minimum-time motion, would drive the plant away; the feedforward and the MPC's input
    cost need the equilibrium input).

    Parameters
    ----------
    f : casadi.Function
        ``f(x (nx,1), u (nu,1), p (np,1)) -> xdot (nx,1)``, the explicit ODE.
    x : array_like
        ``(nx,)`` the held state.
    u_guess : array_like
        ``(nu,)`` the start (e.g. the reference's last input).
    p : array_like
        ``(np,)`` parameters.
    iterations : int, optional
        Gauss-Newton steps (one is exact for a model affine in ``u``).

    Returns
    -------
    numpy.ndarray
        ``(nu,)`` not saturated (a state no admissible input holds is the caller's to judge).
    """
    xs, us, ps = ca.SX.sym("x", f.size1_in(0)), ca.SX.sym("u", f.size1_in(1)), ca.SX.sym("p", f.size1_in(2))
    r = f(xs, us, ps)
    step = ca.Function("hold_step", [xs, us, ps], [r, ca.jacobian(r, us)])
    u = np.asarray(u_guess, dtype=float).reshape(-1).copy()
    for _ in range(iterations):
        rest, jac = (np.asarray(v, dtype=float) for v in step(x, u, p))
        du = np.linalg.lstsq(jac, rest.ravel(), rcond=None)[0]
        u = u - du
        if not np.all(np.isfinite(u)) or np.max(np.abs(du)) <= 1e-12 * (1.0 + np.max(np.abs(u))):
            break
    return u


def start_input(f: ca.Function, x0: Any, u0: Any, p: Any, rtol: float = 1e-6) -> np.ndarray:
    """The input acting before a loop's first computed input arrives: the one that holds a start at rest.

    A plant that rests at the reference's first state before the loop starts is held there
    by :func:`hold_input`, not by the plan's first input ``u*_0`` (a minimum-time plan's first
    input charges a motor's inductance within a fraction of a period: held for the whole
    period, a zero-order hold of it drives the current far beyond the plan's, issue 49).
    A start that no input holds (``max |f(x_0, u, p)|`` above ``rtol (1 + max |f(x_0, u*_0, p)|)``,
    a motion already under way) keeps ``u*_0``.

    Parameters
    ----------
    f : casadi.Function
        ``f(x (nx,1), u (nu,1), p (np,1)) -> xdot (nx,1)``, the explicit ODE.
    x0 : array_like
        ``(nx,)`` the reference's first state.
    u0 : array_like
        ``(nu,)`` the reference's first input ``u*_0`` (and the start of the least squares).
    p : array_like
        ``(np,)`` parameters.
    rtol : float, optional
        Relative residual below which ``x0`` counts as held at rest.

    Returns
    -------
    numpy.ndarray
        ``(nu,)`` not saturated.
    """
    u0 = np.asarray(u0, dtype=float).reshape(-1)
    held = hold_input(f, x0, u0, p)
    if not np.all(np.isfinite(held)):
        return u0.copy()
    rest = np.max(np.abs(np.asarray(f(x0, held, p), dtype=float)), initial=0.0)
    moving = np.max(np.abs(np.asarray(f(x0, u0, p), dtype=float)), initial=0.0)
    return held if rest <= rtol * (1.0 + moving) else u0.copy()


def delayed_start(f: ca.Function, t: Any, x_ref: Any, u_ref: Any, p: Any, dt: float, delay: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """A reference that starts at rest for the periods an input delay holds the plant there.

    With an input delay of ``delay`` periods, the input a loop computes from its first
    measurement acts ``delay`` periods later; until then the plant gets the input acting
    before the loop (:func:`start_input`: the one that holds a start at rest). A plan whose
    first input ``u*_0`` differs from it is one the plant cannot follow in those periods: the
    loop starts ``delay`` periods behind and catches up against its bounds (held-out ball-screw
    drives' TV-LQR and MPC beyond their current bound in the second period: the lead's effect
    is measured in ``docs/model_in_the_loop.md``). The rule: the reference gets ``delay``
    periods at rest before the plan, ``x*_0`` held by that input, and the plan follows
    unchanged (its end ``delay`` periods later in the loop's time). A start that no input
    holds (a motion under way), a plan whose first input is that input, or no delay: the
    reference as given.

    Parameters
    ----------
    f : casadi.Function
        ``f(x (nx,1), u (nu,1), p (np,1)) -> xdot (nx,1)``, the explicit ODE.
    t : array_like
        ``(M,)`` increasing reference times [s].
    x_ref, u_ref : array_like
        ``(M, nx)``, ``(M, nu)`` the reference's states and inputs.
    p : array_like
        ``(np,)`` parameters.
    dt : float
        Loop period [s], > 0.
    delay : int
        Periods of input delay, >= 0.

    Returns
    -------
    t, x_ref, u_ref : numpy.ndarray
        ``(M', )``, ``(M', nx)``, ``(M', nu)`` the reference led by the rest: rows at
        ``t_0 - delay dt`` and just before ``t_0`` (``t_0 - 1e-9 dt``, so that the
        first period's input mean is the rest's, :func:`period_means`) with ``x*_0`` and
        the resting input, then the given rows; ``M' = M`` without a lead.
    lead : int
        The periods led: ``delay`` or 0.

    Raises
    ------
    InputError
        ``delay`` not an integer >= 0.
    """
    if isinstance(delay, bool) or not isinstance(delay, (int, np.integer)) or delay < 0:
        raise InputError(f"delay: expected a number of periods >= 0, got {delay!r}")
    tt = np.asarray(t, dtype=float).reshape(-1)
    xs = np.asarray(x_ref, dtype=float).reshape(tt.size, -1)
    us = np.asarray(u_ref, dtype=float).reshape(tt.size, -1)
    if not delay or tt.size == 0:
        return tt, xs, us, 0
    rest = start_input(f, xs[0], us[0], p)
    if np.allclose(rest, us[0], rtol=1e-9, atol=1e-12):
        return tt, xs, us, 0
    before = np.array([tt[0] - delay * dt, tt[0] - 1e-9 * dt])
    return (np.r_[before, tt], np.vstack([np.tile(xs[0], (2, 1)), xs]),
            np.vstack([np.tile(rest, (2, 1)), us]), int(delay))


def sampled(t: np.ndarray, values: np.ndarray, grid: np.ndarray, name: str) -> np.ndarray:
    """The columns of a table linearly interpolated on a time grid.

    Parameters
    ----------
    t : numpy.ndarray
        ``(M,)`` increasing times of the rows [s].
    values : numpy.ndarray
        ``(M, n)`` finite values, one row per time.
    grid : numpy.ndarray
        ``(N,)`` times to sample [s] (outside ``t``: the first or last row).
    name : str
        Name of ``values`` in the error message.

    Returns
    -------
    numpy.ndarray
        ``(N, n)``.

    Raises
    ------
    InputError
        ``values`` not a finite ``(M, n)`` array.
    """
    if values.ndim != 2 or values.shape[0] != t.size or not np.all(np.isfinite(values)):
        raise InputError(f"{name}: expected a finite ({t.size}, n) array (one row per reference time), got shape {values.shape}")
    return np.column_stack([np.interp(grid, t, values[:, j]) for j in range(values.shape[1])]) if values.shape[1] else np.zeros((grid.size, 0))


def period_means(t: np.ndarray, values: np.ndarray, grid: np.ndarray, dt: float) -> np.ndarray:
    """The mean of each column over the periods ``[g, g + dt]`` of a grid: what a zero-order hold applies.

    The columns are linearly interpolated between the rows and held at the first or last
    row outside ``t``; the means are exact for that interpolation (the trapezoidal integral
    on the rows' times merged with the periods' edges). The input a loop holds for a period
    then has the reference input's integral over it (the same volt-seconds of a voltage), not
    its value at the period's start.

    Parameters
    ----------
    t : numpy.ndarray
        ``(M,)`` increasing times of the rows [s].
    values : numpy.ndarray
        ``(M, n)`` finite values, one row per time.
    grid : numpy.ndarray
        ``(N,)`` increasing start times of the periods [s].
    dt : float
        Period [s], > 0.

    Returns
    -------
    numpy.ndarray
        ``(N, n)``.

    Raises
    ------
    InputError
        ``values`` not a finite ``(M, n)`` array.
    """
    edges = np.union1d(t, np.r_[grid, grid + dt])
    merged = sampled(t, values, edges, "u_ref")  # checks values
    area = np.vstack([np.zeros((1, values.shape[1])), np.cumsum(0.5 * np.diff(edges)[:, None] * (merged[1:] + merged[:-1]), axis=0)])
    start, end = np.searchsorted(edges, grid), np.searchsorted(edges, grid + dt)
    return (area[end] - area[start]) / dt


def sample_reference(t: Any, x_ref: Any, u_ref: Any, dt: float, min_samples: int = 1, eps: float = INDEX_EPS) -> tuple[float, np.ndarray, np.ndarray]:
    """A reference motion sampled at the loop period from its first time to its last.

    Parameters
    ----------
    t : array_like
        ``(M,)`` increasing finite times [s], ``M >= 2``.
    x_ref : array_like
        ``(M, nx)`` states (or ``(M * nx,)``).
    u_ref : array_like
        ``(M, nu)`` inputs.
    dt : float
        Loop period [s], > 0.
    min_samples : int, optional
        Fewest samples ``N`` of the grid accepted (default 1).
    eps : float, optional
        Slack of the last grid point (default :data:`INDEX_EPS`).

    Returns
    -------
    t0 : float
        Time of the first sample [s].
    x : numpy.ndarray
        ``(N, nx)`` states at ``t_0 + k dt``, ``N = floor((t_M - t_0) / dt + eps) + 1``.
    u : numpy.ndarray
        ``(N, nu)`` inputs held from ``t_0 + k dt`` for a period: the given inputs' means over
        it (:func:`period_means`; after the last time the last input counts).

    Raises
    ------
    InputError
        ``dt`` not positive, times not increasing, a reference shorter than
        ``min_samples - 1`` periods, non-finite values.
    """
    if isinstance(dt, bool) or not isinstance(dt, (int, float, np.floating)) or not math.isfinite(dt) or dt <= 0:
        raise InputError(f"dt: expected a positive loop period in seconds, got {dt!r}")
    tt = np.asarray(t, dtype=float).reshape(-1)
    if tt.size < 2 or not np.all(np.isfinite(tt)) or np.any(np.diff(tt) <= 0):
        raise InputError("t: expected at least two increasing finite reference times")
    n = int(math.floor((tt[-1] - tt[0]) / dt + eps)) + 1
    if n < min_samples:
        span = "one period" if min_samples == 2 else f"{min_samples - 1} periods"
        raise InputError(f"t: the reference ({tt[-1] - tt[0]:g} s) is shorter than {span} ({dt:g} s)")
    grid = tt[0] + dt * np.arange(n)
    xs = sampled(tt, np.asarray(x_ref, dtype=float).reshape(tt.size, -1), grid, "x_ref")
    us = period_means(tt, np.asarray(u_ref, dtype=float).reshape(tt.size, -1), grid, dt)
    return float(tt[0]), xs, us


def period_index(t: Any, t0: float, dt: float, last: int, eps: float = PERIOD_EPS) -> Any:
    """The row of a sampled reference read at time ``t``: ``floor((t - t_0) / dt + eps)`` clamped to ``0 .. last``.

    Parameters
    ----------
    t : float or casadi.MX or casadi.SX
        Time [s].
    t0 : float
        Time of row 0 [s].
    dt : float
        Loop period [s].
    last : int
        Largest row (``N - 1``, or ``N`` with a row after the reference such as a held end).
    eps : float, optional
        Slack in periods (default :data:`PERIOD_EPS`; float32 round-off needs it).

    Returns
    -------
    int or casadi expression
        The row; for a CasADi expression a NaN ``t`` gives row 0 (a number raises).

    Raises
    ------
    InputError
        A numeric ``t`` that is not finite.
    """
    if isinstance(t, (ca.MX, ca.SX)):
        k = ca.fmin(ca.fmax(ca.floor((t - t0) / dt + eps), 0), last)
        return ca.if_else(t == t, k, 0)
    if not math.isfinite(float(t)):
        raise InputError(f"t: expected a finite time, got {t!r}")
    return int(min(max(math.floor((float(t) - t0) / dt + eps), 0), last))


def reference_scales(x_ref: np.ndarray, u_ref: np.ndarray, u_lb: np.ndarray, u_ub: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The scales of a loop controller's states and inputs (its default weights, Bryson's rule, and its memory's limits).

    Parameters
    ----------
    x_ref, u_ref : numpy.ndarray
        ``(N, nx)``, ``(N, nu)`` the sampled reference.
    u_lb, u_ub : numpy.ndarray
        ``(nu,)`` input bounds (``-inf``/``inf``: none).

    Returns
    -------
    x_scale : numpy.ndarray
        ``(nx,)`` the reference's range of each state, at least ``1e-3 (1 + max |x*|)``.
    u_scale : numpy.ndarray
        ``(nu,)`` half the bound range where both bounds are finite, else as ``x_scale`` of ``u*``.
    """
    xs, us = np.asarray(x_ref, dtype=float), np.asarray(u_ref, dtype=float)
    lb, ub = np.asarray(u_lb, dtype=float), np.asarray(u_ub, dtype=float)
    x_scale = np.maximum(np.ptp(xs, axis=0), 1e-3 * (1.0 + np.max(np.abs(xs), axis=0)))
    finite = np.isfinite(lb) & np.isfinite(ub)
    u_scale = np.where(finite, 0.5 * (np.where(finite, ub, 0) - np.where(finite, lb, 0)),
                       np.maximum(np.ptp(us, axis=0), 1e-3 * (1 + np.max(np.abs(us), axis=0))))
    return x_scale, u_scale


def plausible_range(values: np.ndarray, scale: np.ndarray, factor: float, lb: Any = None, ub: Any = None) -> np.ndarray:
    """The plausible range of a loop controller's quantity: its reference's range widened by ``factor`` scales.

    Parameters
    ----------
    values : numpy.ndarray
        ``(N, n)`` the reference's values (states or inputs).
    scale : numpy.ndarray
        ``(n,)`` their scales (:func:`reference_scales`).
    factor : float
        Scales beyond the range (e.g. :data:`MEASUREMENT_LIMIT`).
    lb, ub : array_like, optional
        ``(n,)`` bounds that replace the widened range where finite (an input's).

    Returns
    -------
    numpy.ndarray
        ``(2, n)``: the lowest and the highest plausible value.
    """
    v = np.asarray(values, dtype=float)
    width = factor * np.asarray(scale, dtype=float)
    lo, hi = np.min(v, axis=0) - width, np.max(v, axis=0) + width
    if lb is not None:
        lo = np.where(np.isfinite(lb), lb, lo)
    if ub is not None:
        hi = np.where(np.isfinite(ub), ub, hi)
    return np.vstack([lo, hi])
