"""The sine path of Cvitanic (2021), section 4.2, and its closed-form true state (3-axis and 5-axis).

The sine path ``y = A sin(2 pi f x)`` (reference ``sine_path``:
``A = 76.2 mm``, ``f = 19.685 cycles/m``, i.e. a 50.8 mm wavelength) traversed with ``x`` at
the feed rate ``v_f`` (the default ``feed="x"``: the feed is the speed along ``x``, so every
derivative is closed form in ``t``; the thesis' own path is ``feed="tangential"`` below), in the
world ``xy`` plane from ``start``. The temporal frequency is ``omega = 2 pi f v_f``
(0.833 Hz at 42.33 mm/s). ``feed="tangential"`` is the thesis' own wording ("sine waves in space
with a constant tangential velocity, or 'feed rate'", Cvitanic (2021), sec. 4.2): the speed
along the arc is ``v_f``; the abscissa ``u(t)`` solves ``s(u) = v_f t`` with the arc length
``s(u) = sqrt(1 + m^2) / k E(k u | m^2 / (1 + m^2))`` (``k = 2 pi f``, ``m = A k``, ``E`` the
incomplete elliptic integral of the second kind, :func:`scipy.special.ellipeinc`), inverted by
interpolation in a table and Newton (:func:`abscissa`); every time derivative
is CasADi's of the closed form in ``u`` with ``u' = v_f / sqrt(1 + (m cos k u)^2)`` (chain
rule), so ``|v| = v_f`` exactly. Its crests come every ``s(pi / (2 k)) / v_f`` s from a zero
crossing (1.87 s at 42.33 mm/s: the thesis' "spikes around 1.8 s", Figs. 24-25). 3-axis: translation only, the orientation constant. 5-axis: the
end-effector also rotates about a FIXED BODY AXIS ``n`` by the angle
``theta(t) = theta_0 sin(omega t)`` (default ``theta_0 = 10 deg``, ``n`` tilted 30 deg from
the body z axis towards x), so ``quat(t) = quat_0 (x) exp(theta(t) n / 2)`` and, because ``n``
is invariant under that rotation, the body angular velocity and acceleration are
``w = theta'(t) n`` and ``alpha = theta''(t) n`` exactly. ``rotation_law="normal"`` is the thesis'
5-axis motion ("the tool axis is constrained to remain normal to the path", Fig. 22): ``theta(t)``
is the path's slope angle ``atan(A 2 pi f cos(omega t))`` (up to 84 deg; with ``n`` the plane's
normal the tool stays normal to the sine), turning at up to ``A (2 pi f)^2 v_f`` (49 rad/s at the
crests at 42.33 mm/s); its derivatives are CasADi's of the closed form.
:meth:`SinePath.truth` samples the closed form into the 19-D (or 9-D) state layout of
:class:`~gtmodel.estimation.filters.end_effector.EndEffectorModel`. Used by the sensors of
:mod:`gtmodel.estimation.fusion.tracker_imu` and the study of :mod:`gtmodel.estimation.fusion.study`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
from scipy.special import ellipeinc

from gtmodel._arrays import as_array, as_finite, positive_float
from gtmodel._geometry import quat_exp, quat_mul
from gtmodel.errors import InputError

__all__ = ["SINE_PATH", "FEED_RATE_M_S", "MIN_SAMPLES", "MAX_SAMPLES", "ROTATION_LAWS", "FEEDS", "Truth", "SinePath", "arc_length", "abscissa"]

#: The sine path of section 4.2 (reference ``sine_path``): amplitude [m], spatial frequency [cycles/m].
SINE_PATH = {"amplitude_m": 0.0762, "spatial_frequency_cycles_per_m": 19.685}
#: The Table 7 baseline feed rate [m/s] (42.33 mm/s).
FEED_RATE_M_S = 0.04233
#: The 5-axis rotation laws of :class:`SinePath` (module docstring).
ROTATION_LAWS = ("sine", "normal")
#: What the feed rate is the speed of (module docstring): along x, or along the arc (the thesis' wording).
FEEDS = ("x", "tangential")
#: Fewest samples of a path (the four-point regression needs 4, a table needs more).
MIN_SAMPLES = 10
#: Most samples of a path (keeps memory and run time bounded).
MAX_SAMPLES = 200_000


def _map(f: ca.Function, n: int, *args: Any) -> np.ndarray:
    """Evaluate ``f`` over ``n`` columns (``Function.map``), arguments with one column broadcast."""
    return np.asarray(f.map(n)(*args))


@dataclass(frozen=True)
class Truth:
    """The true state of a path, sampled (rows are samples).

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Times [s].
    x : numpy.ndarray, shape (N, 19) or (N, 9)
        True states in the layout of :class:`~gtmodel.estimation.filters.end_effector.EndEffectorModel`.
    jerk : numpy.ndarray, shape (N, 3)
        True jerk of the target [m/s^3] (for the process noise).
    angular_jerk : numpy.ndarray, shape (N, 3)
        True body angular jerk [rad/s^3] (zero for a 3-axis path).
    rotation : bool
        True for the 19-D layout.
    orientation : numpy.ndarray, shape (4,)
        The initial (3-axis: constant) orientation quaternion.
    """

    t: np.ndarray
    x: np.ndarray
    jerk: np.ndarray
    angular_jerk: np.ndarray
    rotation: bool
    orientation: np.ndarray

    @property
    def position(self) -> np.ndarray:
        """Target position [m], shape (N, 3)."""
        return self.x[:, 0:3]

    @property
    def velocity(self) -> np.ndarray:
        """Target velocity [m/s], shape (N, 3)."""
        return self.x[:, 3:6]

    @property
    def acceleration(self) -> np.ndarray:
        """Target acceleration [m/s^2], shape (N, 3)."""
        return self.x[:, 6:9]

    @property
    def quaternion(self) -> np.ndarray:
        """Orientation quaternions, shape (N, 4) (3-axis: the constant one repeated)."""
        return self.x[:, 9:13] if self.rotation else np.tile(self.orientation, (self.t.size, 1))

    @property
    def angular_velocity(self) -> np.ndarray:
        """Body angular velocity [rad/s], shape (N, 3) (3-axis: zero)."""
        return self.x[:, 13:16] if self.rotation else np.zeros((self.t.size, 3))

    @property
    def angular_acceleration(self) -> np.ndarray:
        """Body angular acceleration [rad/s^2], shape (N, 3) (3-axis: zero)."""
        return self.x[:, 16:19] if self.rotation else np.zeros((self.t.size, 3))


def _unit(value: Any, name: str, width: int) -> np.ndarray:
    v = as_array(value, (width,), name)
    n = float(np.linalg.norm(v))
    if not n > 1e-12:
        raise InputError(f"{name}: expected a vector of nonzero norm, got {v.tolist()}")
    return v / n


@dataclass(frozen=True)
class SinePath:
    """The sine path of section 4.2, 3-axis or 5-axis (see the module docstring).

    Parameters
    ----------
    duration : float
        Length of the record [s] (> 0).
    feed_rate : float, optional
        Speed along x, or along the arc (``feed``) [m/s] (Table 7: 42.33 mm/s).
    amplitude : float, optional
        Sine amplitude in y [m] (reference: 76.2 mm).
    spatial_frequency : float, optional
        Cycles per metre of x (reference: 19.685).
    start : array_like, shape (3,), optional
        Position of the target at ``t = 0`` [m].
    rotation : bool, optional
        True: 5-axis (the end-effector rotates); False: 3-axis.
    rotation_amplitude : float, optional
        ``theta_0`` [rad] of the 5-axis rotation ``theta = theta_0 sin(omega t)`` (default 10 deg).
    rotation_axis : array_like, shape (3,), optional
        Body axis ``n`` of the rotation (normalised; default 30 deg from z towards x).
    orientation : array_like, shape (4,), optional
        ``quat_0``, scalar-first (normalised): the initial (3-axis: constant) orientation.
    rotation_law : {"sine", "normal"}, optional
        5-axis ``theta(t)``: ``theta_0 sin(omega t)``, or the path's slope angle (the tool normal
        to the path, the thesis' motion; ``rotation_amplitude`` unused).
    feed : {"x", "tangential"}, optional
        The feed rate is the speed along x (closed form in t), or along the arc (the thesis'
        constant tangential speed; module docstring).

    Raises
    ------
    InputError
        A non-positive duration, feed rate or spatial frequency, a negative amplitude, a
        rotation axis or quaternion of zero norm, values that are not finite, an unknown rotation law or feed.
    """

    duration: float
    feed_rate: float = FEED_RATE_M_S
    amplitude: float = SINE_PATH["amplitude_m"]
    spatial_frequency: float = SINE_PATH["spatial_frequency_cycles_per_m"]
    start: Any = (1.5, 0.0, 1.0)
    rotation: bool = False
    rotation_amplitude: float = math.radians(10.0)
    rotation_axis: Any = (0.5, 0.0, math.sqrt(3.0) / 2.0)
    orientation: Any = (1.0, 0.0, 0.0, 0.0)
    rotation_law: str = "sine"
    feed: str = "x"

    def __post_init__(self) -> None:
        object.__setattr__(self, "duration", positive_float(self.duration, "duration"))
        object.__setattr__(self, "feed_rate", positive_float(self.feed_rate, "feed_rate"))
        object.__setattr__(self, "spatial_frequency", positive_float(self.spatial_frequency, "spatial_frequency"))
        object.__setattr__(self, "amplitude", float(as_finite(self.amplitude, "amplitude", nonnegative=True)))
        object.__setattr__(self, "rotation_amplitude", float(as_finite(self.rotation_amplitude, "rotation_amplitude", nonnegative=True)))
        object.__setattr__(self, "start", as_array(self.start, (3,), "start"))
        object.__setattr__(self, "rotation_axis", _unit(self.rotation_axis, "rotation_axis", 3))
        object.__setattr__(self, "orientation", _unit(self.orientation, "orientation", 4))
        if not isinstance(self.rotation, (bool, np.bool_)):
            raise InputError(f"rotation: expected True or False, got {self.rotation!r}")
        if self.rotation_law not in ROTATION_LAWS:
            raise InputError(f"rotation_law: expected one of {', '.join(ROTATION_LAWS)}, got {self.rotation_law!r}")
        if self.feed not in FEEDS:
            raise InputError(f"feed: expected one of {', '.join(FEEDS)}, got {self.feed!r}")

    @property
    def omega(self) -> float:
        """Temporal angular frequency ``2 pi f v_f`` of the sine [rad/s] (x feed; along the arc the rate of ``k u`` varies)."""
        return 2.0 * math.pi * self.spatial_frequency * self.feed_rate

    def samples(self, dt: float) -> int:
        """Number of samples ``floor(duration / dt) + 1`` at the sample time ``dt``.

        Parameters
        ----------
        dt : float
            Sample time [s].

        Returns
        -------
        int

        Raises
        ------
        InputError
            ``dt`` not positive, or fewer than :data:`MIN_SAMPLES` or more than
            :data:`MAX_SAMPLES` samples.
        """
        dt = positive_float(dt, "dt")
        n = math.floor(self.duration / dt + 1e-9) + 1
        if not MIN_SAMPLES <= n <= MAX_SAMPLES:
            raise InputError(f"dt: expected {MIN_SAMPLES} to {MAX_SAMPLES} samples over the path's {self.duration:g} s, got {n} at dt = {dt:g} s")
        return n

    def truth(self, dt: float) -> Truth:
        """The closed-form true state at ``t_k = k dt``.

        ``p = start + (v_f t, A sin(omega t), 0)``, ``v, a, jerk`` its derivatives;
        5-axis: ``quat = quat_0 (x) exp(theta n / 2)``, ``w = theta' n``, ``alpha = theta'' n``,
        ``theta = theta_0 sin(omega t)`` (module docstring); ``feed="tangential"``: the same
        in the abscissa ``u(t)`` of constant arc speed (module docstring).

        Parameters
        ----------
        dt : float
            Sample time [s].

        Returns
        -------
        Truth
            19-D states if :attr:`rotation`, else 9-D.

        Raises
        ------
        InputError
            See :meth:`samples`.
        """
        n = self.samples(dt)
        t = np.arange(n) * dt
        if self.feed == "tangential":
            return self._truth_tangential(t)
        w0, amp, vf = self.omega, self.amplitude, self.feed_rate
        s, c = np.sin(w0 * t), np.cos(w0 * t)
        zero = np.zeros(n)
        p = self.start + np.column_stack([vf * t, amp * s, zero])
        v = np.column_stack([np.full(n, vf), amp * w0 * c, zero])
        a = np.column_stack([zero, -amp * w0**2 * s, zero])
        jerk = np.column_stack([zero, -amp * w0**3 * c, zero])
        if not self.rotation:
            return Truth(t, np.hstack([p, v, a]), jerk, np.zeros((n, 3)), False, self.orientation)
        th0, axis = self.rotation_amplitude, self.rotation_axis
        if self.rotation_law == "normal":  # the slope angle and its derivatives (module docstring)
            slope = amp * 2.0 * math.pi * self.spatial_frequency
            theta, dtheta, ddtheta, dddtheta = (np.asarray(o).ravel() for o in _SLOPE_ANGLE.map(n)(t[None, :], slope, w0))
        else:
            theta, dtheta, ddtheta, dddtheta = th0 * s, th0 * w0 * c, -th0 * w0**2 * s, -th0 * w0**3 * c
        quat = _map(_ROTATE, n, self.orientation, axis, theta[None, :]).T
        return Truth(t, np.hstack([p, v, a, quat, np.outer(dtheta, axis), np.outer(ddtheta, axis)]),
                     jerk, np.outer(dddtheta, axis), True, self.orientation)

    def _truth_tangential(self, t: np.ndarray) -> Truth:
        """The true state at constant speed along the arc (module docstring)."""
        n, amp, vf = t.size, self.amplitude, self.feed_rate
        k = 2.0 * math.pi * self.spatial_frequency
        u = abscissa(vf * t, amp, k)
        p, v, a, jerk, theta, dtheta, ddtheta, dddtheta = (np.asarray(o) for o in _ARC_STATE.map(n)(u[None, :], amp, k, vf))
        zero = np.zeros((n, 1))
        pos = self.start + np.column_stack([p.T, zero])
        x = np.hstack([pos, np.column_stack([v.T, zero]), np.column_stack([a.T, zero])])
        jerk = np.column_stack([jerk.T, zero])
        if not self.rotation:
            return Truth(t, x, jerk, np.zeros((n, 3)), False, self.orientation)
        axis = self.rotation_axis
        if self.rotation_law == "normal":
            theta, dtheta, ddtheta, dddtheta = theta.ravel(), dtheta.ravel(), ddtheta.ravel(), dddtheta.ravel()
        else:  # theta_0 sin(phase), the phase k u of the sine (the x-feed law with omega t -> k u)
            theta, dtheta, ddtheta, dddtheta = (self.rotation_amplitude * np.asarray(q).ravel() for q in _ARC_SINE.map(n)(u[None, :], amp, k, vf))
        quat = _map(_ROTATE, n, self.orientation, axis, theta[None, :]).T
        return Truth(t, np.hstack([x, quat, np.outer(dtheta, axis), np.outer(ddtheta, axis)]), jerk, np.outer(dddtheta, axis), True, self.orientation)

    def jerk_rms(self, dt: float) -> tuple[float, float]:
        """RMS over the samples of ``|jerk|`` [m/s^3] and of ``|angular jerk|`` [rad/s^3].

        The process noise of the fusion study is tuned from these (a white-jerk model whose
        standard deviation is the path's RMS jerk, the same on each axis).

        Parameters
        ----------
        dt : float
            Sample time [s].

        Returns
        -------
        tuple of float
            ``(jerk_rms, angular_jerk_rms)``; the second is 0 for a 3-axis path.

        Raises
        ------
        InputError
            See :meth:`samples`.
        """
        tr = self.truth(dt)
        return (float(np.sqrt(np.mean(np.sum(tr.jerk**2, axis=1)))), float(np.sqrt(np.mean(np.sum(tr.angular_jerk**2, axis=1)))))


def _rotate_about_axis_function() -> ca.Function:
    """``quat_0 (x) exp(theta n / 2)`` for one angle, mapped over samples by the caller."""
    q0, n, th = ca.SX.sym("q0", 4), ca.SX.sym("n", 3), ca.SX.sym("theta")
    f = ca.Function("rotate_about_axis", [q0, n, th], [quat_mul(q0, quat_exp(th * n))])
    return f


_ROTATE = _rotate_about_axis_function()


def _slope_angle_function() -> ca.Function:
    """``theta = atan(m cos(omega t))`` (the slope angle of a sine of largest slope ``m``) and its first three time derivatives."""
    t, m, w = ca.SX.sym("t"), ca.SX.sym("m"), ca.SX.sym("omega")
    th = ca.atan(m * ca.cos(w * t))
    d1 = ca.jacobian(th, t)
    d2 = ca.jacobian(d1, t)
    return ca.Function("slope_angle", [t, m, w], [th, d1, d2, ca.jacobian(d2, t)])


_SLOPE_ANGLE = _slope_angle_function()


def arc_length(u: Any, amplitude: float, k: float) -> np.ndarray:
    """Arc length of ``y = A sin(k x)`` from ``x = 0`` to ``x = u`` [m] (module docstring).

    ``s(u) = sqrt(1 + m^2) / k E(k u | m^2 / (1 + m^2))``, ``m = A k``: the integral of
    ``sqrt(1 + (m cos k x)^2)`` written as an incomplete elliptic integral of the second kind.

    Parameters
    ----------
    u : array_like, shape (N,)
        Abscissae [m].
    amplitude : float
        ``A`` [m] (>= 0).
    k : float
        ``2 pi f`` [rad/m] (> 0).

    Returns
    -------
    numpy.ndarray, shape (N,)
        Arc lengths [m].
    """
    m2 = (amplitude * k) ** 2
    return math.sqrt(1.0 + m2) / k * ellipeinc(k * np.asarray(u, dtype=float), m2 / (1.0 + m2))


def abscissa(s: Any, amplitude: float, k: float) -> np.ndarray:
    """The abscissa ``u`` at which the arc length of ``y = A sin(k x)`` from 0 is ``s`` (module docstring).

    The inverse of :func:`arc_length` tabulated on a grid of 64 points per quarter wavelength
    (linear interpolation, the start), then Newton's ``u -= (s(u) - s) / sqrt(1 + (m cos k u)^2)``
    until the arc length matches to ``1e-14 m`` (at most 20 steps).

    Parameters
    ----------
    s : array_like, shape (N,)
        Arc lengths [m] (>= 0).
    amplitude : float
        ``A`` [m].
    k : float
        ``2 pi f`` [rad/m].

    Returns
    -------
    numpy.ndarray, shape (N,)
        Abscissae [m].
    """
    s = np.asarray(s, dtype=float)
    m = amplitude * k
    top = float(s.max(initial=0.0))
    grid = np.linspace(0.0, top, int(math.ceil(top * k / (math.pi / 2) * 64)) + 2)
    u = np.interp(s, arc_length(grid, amplitude, k), grid)
    for _ in range(20):
        r = arc_length(u, amplitude, k) - s
        if np.abs(r).max(initial=0.0) < 1e-14:
            break
        u = u - r / np.sqrt(1.0 + (m * np.cos(k * u)) ** 2)
    return u


def _arc_state_functions() -> tuple[ca.Function, ca.Function]:
    """Position, velocity, acceleration, jerk (x, y) and the slope angle with three derivatives, in ``u`` at constant arc speed."""
    u, amp, k, vf = ca.SX.sym("u"), ca.SX.sym("A"), ca.SX.sym("k"), ca.SX.sym("vf")
    udot = vf / ca.sqrt(1.0 + (amp * k * ca.cos(k * u)) ** 2)

    def d(h: ca.SX) -> ca.SX:  # time derivative by the chain rule
        return ca.jacobian(h, u) * udot

    p = ca.vertcat(u, amp * ca.sin(k * u))
    v = d(p)
    a = d(v)
    th = ca.atan(amp * k * ca.cos(k * u))
    d1 = d(th)
    d2 = d(d1)
    sn = ca.sin(k * u)
    s1 = d(sn)
    s2 = d(s1)
    args = [u, amp, k, vf]
    return (ca.Function("arc_state", args, [p, v, a, d(a), th, d1, d2, d(d2)]),
            ca.Function("arc_sine", args, [sn, s1, s2, d(s2)]))


_ARC_STATE, _ARC_SINE = _arc_state_functions()
