"""Closed-loop simulation of lead-through programming in contact (Dressler (2012), ch. 8.4).

The controller step (:meth:`LeadThroughLaw.step_function`, the one graph the generated C
wraps) acts on a simulated robot every ``dt``:

* the robot is a velocity-controlled servo: each of the six TCP twist components follows
  its reference as a first-order lag of bandwidth ``bandwidth_hz`` (exact over the sample
  under a zero-order hold); ``delay_samples`` = 0 applies a reference in the sample it is
  computed in, 1 in the next. The assumed figures: 50 Hz and no delay (the thesis states
  only that the IRB 140's servo was much faster than the lead-through loop);
* the workpiece is a contact model of :mod:`gtmodel.estimation.lead_through.contact`;
* the tool sensor measures the contact wrench plus white noise, the handle sensor the
  operator's wrench plus white noise;
* the operator (:class:`Operator`) applies a planned force profile, corrects what they
  see (the tool position, perceived with a reaction lag) with a spring-like force, and
  adds a random, band-limited force (an unskilled operator's).

Plant, sensors, operator and controller make one CasADi step, run over the whole
experiment by ``Function.mapaccum``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import casadi as ca
import numpy as np
from scipy import signal

from gtmodel._arrays import finite_float
from gtmodel.errors import InputError
from gtmodel.estimation.lead_through.contact import PegHole, Surface
from gtmodel.estimation.lead_through.law import STATE_SIZE, LeadThroughLaw

__all__ = ["Servo", "Operator", "LeadThroughRun", "simulate", "rodrigues"]




@dataclass(frozen=True)
class Servo:
    """The robot as a velocity-controlled servo (assumed figures, see the module).

    Parameters
    ----------
    bandwidth_hz : float, optional
        Bandwidth of every twist component [Hz] (first-order lag).
    delay_samples : {0, 1}, optional
        Samples between computing a reference and applying it.

    Raises
    ------
    InputError
        A bandwidth that is not positive, a delay other than 0 or 1.
    """

    bandwidth_hz: float = 50.0
    delay_samples: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, "bandwidth_hz", finite_float(self.bandwidth_hz, "bandwidth_hz", "Hz", positive=True))
        if self.delay_samples not in (0, 1) or isinstance(self.delay_samples, bool):
            raise InputError(f"delay_samples: expected 0 or 1, got {self.delay_samples!r}")


def _knots(value: Any, name: str, width: int) -> tuple[np.ndarray, np.ndarray]:
    """``((t_0, v_0), (t_1, v_1), ...)`` -> times and values, times increasing."""
    try:
        rows = [(float(t), np.asarray(v, dtype=float)) for t, v in value]
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a sequence of (time [s], {width} values) pairs, got {value!r}") from None
    if not rows:
        raise InputError(f"{name}: expected at least one (time, value) pair")
    t = np.array([r[0] for r in rows])
    v = np.array([r[1] for r in rows]) if all(r[1].shape == (width,) for r in rows) else None
    if v is None or not np.all(np.isfinite(t)) or not np.all(np.isfinite(v)):
        raise InputError(f"{name}: expected finite (time, {width} values) pairs, got {value!r}")
    if np.any(np.diff(t) < 0):
        raise InputError(f"{name}: expected non-decreasing times, got {t.tolist()}")
    return t, v


def _interp(t: np.ndarray, knots: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    kt, kv = knots
    return np.column_stack([np.interp(t, kt, kv[:, j]) for j in range(kv.shape[1])])


@dataclass(frozen=True)
class Operator:
    """The operator's wrench on the handle: planned force, visual correction and a random force.

    ``f_h(t) = force(t) + gain * (aim(t) - p_seen(t)) + noise(t)``, torque zero, where
    ``p_seen`` is the tool position seen with a first-order reaction lag.

    Parameters
    ----------
    force : sequence of (float, array_like of 3)
        Planned force [N] at given times [s], linearly interpolated (held after the last).
    aim : sequence of (float, array_like of 3), optional
        Where the operator wants the tool [m], linearly interpolated; None: no correction.
    gain : array_like of 3 or array_like (3, 3), optional
        Spring-like correction [N/m]: per base axis (3 entries, 0: no correction on that
        axis) or a symmetric positive semi-definite matrix (e.g. ``k n n^T``: along ``n`` only).
    lag : float, optional
        Reaction lag [s] of the perceived position.
    noise_rms : float, optional
        Random force per axis [N rms], low-pass filtered white noise.
    noise_hz : float, optional
        Cut-off of the random force [Hz].

    Raises
    ------
    InputError
        Malformed knots, a negative gain, lag or noise.
    """

    force: Sequence[tuple[float, Any]]
    aim: Sequence[tuple[float, Any]] | None = None
    gain: Any = (0.0, 0.0, 0.0)
    lag: float = 0.2
    noise_rms: float = 0.0
    noise_hz: float = 2.0

    def __post_init__(self) -> None:
        _knots(self.force, "force", 3)
        if self.aim is not None:
            _knots(self.aim, "aim", 3)
        g = np.asarray(self.gain, dtype=float) if np.asarray(self.gain).dtype.kind in "fiu" else None
        if g is not None and g.shape == (3,):
            g = np.diag(g)
        if g is None or g.shape != (3, 3) or not np.all(np.isfinite(g)) or not np.allclose(g, g.T) \
                or np.linalg.eigvalsh(0.5 * (g + g.T)).min() < -1e-9 * max(1.0, float(np.abs(g).max())):
            raise InputError(f"gain: expected 3 non-negative gains or a symmetric positive semi-definite 3x3 matrix [N/m], got {self.gain!r}")
        object.__setattr__(self, "gain", g)
        object.__setattr__(self, "lag", finite_float(self.lag, "lag", "s", positive=True))
        object.__setattr__(self, "noise_rms", finite_float(self.noise_rms, "noise_rms", "N", nonnegative=True))
        object.__setattr__(self, "noise_hz", finite_float(self.noise_hz, "noise_hz", "Hz", positive=True))

    def planned(self, t: np.ndarray, rng: np.random.Generator, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Planned force (with the random force) and aim point per sample.

        Parameters
        ----------
        t : numpy.ndarray, shape (N,)
            Sample times [s].
        rng : numpy.random.Generator
            Source of the random force.
        dt : float
            Sample time [s].

        Returns
        -------
        tuple of numpy.ndarray
            ``(force (N, 3) [N], aim (N, 3) [m])`` (aim zeros without ``aim``).
        """
        f = _interp(t, _knots(self.force, "force", 3))
        if self.noise_rms > 0:
            b, a = signal.butter(2, min(self.noise_hz * 2 * dt, 0.99))
            raw = signal.lfilter(b, a, rng.standard_normal((t.size + 500, 3)), axis=0)[500:]
            f = f + self.noise_rms * raw / max(float(np.std(raw)), 1e-300)
        aim = np.zeros((t.size, 3)) if self.aim is None else _interp(t, _knots(self.aim, "aim", 3))
        return f, aim


def rodrigues(w: ca.SX) -> ca.SX:
    """Rotation matrix of the rotation vector ``w`` (Rodrigues' formula), series near zero.

    Parameters
    ----------
    w : casadi.SX, shape (3, 1)
        Rotation vector [rad].

    Returns
    -------
    casadi.SX, shape (3, 3)
    """
    th2 = ca.dot(w, w)
    th = ca.sqrt(th2 + 1e-300)
    small = th2 < 1e-12
    s = ca.if_else(small, 1.0 - th2 / 6.0, ca.sin(th) / th)
    c = ca.if_else(small, 0.5 - th2 / 24.0, (1.0 - ca.cos(th)) / (th2 + 1e-300))
    K = ca.skew(w)
    return ca.SX.eye(3) + s * K + c * ca.mtimes(K, K)


@dataclass(frozen=True)
class LeadThroughRun:
    """Record of a closed-loop lead-through simulation, one row per 4 ms sample.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Sample times [s].
    p : numpy.ndarray, shape (N, 3)
        TCP position [m].
    R : numpy.ndarray, shape (N, 3, 3)
        Tool orientation.
    F_contact : numpy.ndarray, shape (N, 6)
        True wrench of the tool on the workpiece [N, N m].
    F_t, F_h : numpy.ndarray, shape (N, 6)
        Measured tool and handle wrenches [N, N m] (the controller's inputs).
    n_n : numpy.ndarray, shape (3,)
        Nominal normal given to every step.
    x : numpy.ndarray, shape (N + 1, 8)
        Controller states ``[V_h; c; r]`` (the initial one first).
    V_tool : numpy.ndarray, shape (N, 6)
        Applied tool velocity references [m/s, rad/s].
    n : numpy.ndarray, shape (N, 3)
        Normal used by the controller, eq. (8.10).
    dt : float
        Sample time [s].
    """

    t: np.ndarray
    p: np.ndarray
    R: np.ndarray
    F_contact: np.ndarray
    F_t: np.ndarray
    F_h: np.ndarray
    n_n: np.ndarray
    x: np.ndarray
    V_tool: np.ndarray
    n: np.ndarray
    dt: float

    @property
    def contact(self) -> np.ndarray:
        """Controller contact state per sample (bool, shape (N,))."""
        return self.x[1:, 6] > 0.5

    def normal_force(self, normal: np.ndarray) -> np.ndarray:
        """True contact force along ``normal`` [N], shape (N,).

        Parameters
        ----------
        normal : array_like, shape (3,)
            Direction (into the workpiece).

        Returns
        -------
        numpy.ndarray, shape (N,)
        """
        return self.F_contact[:, :3] @ np.asarray(normal, dtype=float)


def _closed_loop_step(law: LeadThroughLaw, contact: Surface | PegHole, servo: Servo, operator: Operator, dt: float) -> ca.Function:
    """The closed-loop step: sensors, operator, controller, servo over one sample."""
    nz = STATE_SIZE + 3 + 9 + 6 + 6 + 3
    z = ca.SX.sym("z", nz)
    u = ca.SX.sym("u", 3 + 3 + 6 + 6 + 3)  # planned force, aim, tool noise, handle noise, n_n
    x, p, R = z[:STATE_SIZE], z[STATE_SIZE:STATE_SIZE + 3], ca.reshape(z[STATE_SIZE + 3:STATE_SIZE + 12], 3, 3)
    V, V_prev, p_seen = z[STATE_SIZE + 12:STATE_SIZE + 18], z[STATE_SIZE + 18:STATE_SIZE + 24], z[STATE_SIZE + 24:]
    f_plan, aim, noise_t, noise_h, n_n = u[:3], u[3:6], u[6:12], u[12:18], u[18:21]
    W = contact.wrench(p, R, V)
    F_t = W + noise_t
    F_h = ca.vertcat(f_plan + ca.mtimes(ca.DM(operator.gain), aim - p_seen), ca.SX.zeros(3)) + noise_h
    x_next, V_tool, n, _ = law.step_function()(x, F_h, F_t, n_n)
    V_ref = V_tool if servo.delay_samples == 0 else V_prev
    ws = 2 * math.pi * servo.bandwidth_hz
    e = math.exp(-ws * dt)
    g = (1.0 - e) / ws
    V_next = V_ref + (V - V_ref) * e
    p_next = p + V_ref[:3] * dt + (V[:3] - V_ref[:3]) * g
    w_mean = V_ref[3:] * dt + (V[3:] - V_ref[3:]) * g  # integral of the angular velocity over the sample
    R_next = ca.mtimes(rodrigues(w_mean), R)
    seen_next = p_seen + (p - p_seen) * (1.0 - math.exp(-dt / operator.lag))
    z_next = ca.vertcat(x_next, p_next, ca.reshape(R_next, 9, 1), V_next, V_tool, seen_next)
    out = ca.vertcat(W, F_t, F_h, V_tool, n, p, ca.reshape(R, 9, 1))
    return ca.Function("lead_through_loop", [z, u], [z_next, out], ["z", "u"], ["z_next", "out"])


def simulate(
    law: LeadThroughLaw,
    contact: Surface | PegHole,
    operator: Operator,
    duration: float,
    *,
    servo: Servo | None = None,
    start: Any = (0.0, 0.0, 0.01),
    tool_noise: float = 0.05,
    handle_noise: float = 0.05,
    seed: int = 0,
) -> LeadThroughRun:
    """Simulate the lead-through controller in closed loop with a workpiece and an operator.

    Parameters
    ----------
    law : LeadThroughLaw
        The controller (its ``dt`` is the sample time).
    contact : Surface or PegHole
        The workpiece.
    operator : Operator
        The operator's wrench on the handle.
    duration : float
        Simulated time [s], positive, at most 600 s.
    servo : Servo, optional
        The robot (default: :class:`Servo` with the assumed figures).
    start : array_like, shape (3,), optional
        Initial TCP position [m] (at rest, tool z axis vertical up, no contact).
    tool_noise, handle_noise : float, optional
        Standard deviation of the tool and handle force sensors' noise [N] per force
        component (torques: the same figure in N m times 0.01 m).
    seed : int, optional
        Seed of the sensor and operator noise.

    Returns
    -------
    LeadThroughRun

    Raises
    ------
    InputError
        A bad argument (named), a duration outside (0, 600] s.
    """
    if not isinstance(law, LeadThroughLaw):
        raise InputError(f"law: expected a LeadThroughLaw, got {type(law).__name__}")
    if not isinstance(contact, (Surface, PegHole)):
        raise InputError(f"contact: expected a Surface or a PegHole, got {type(contact).__name__}")
    if not isinstance(operator, Operator):
        raise InputError(f"operator: expected an Operator, got {type(operator).__name__}")
    duration = finite_float(duration, "duration", "s", positive=True)
    if duration > 600:
        raise InputError(f"duration: expected at most 600 s, got {duration}")
    servo = Servo() if servo is None else servo
    tool_noise, handle_noise = finite_float(tool_noise, "tool_noise", "N", nonnegative=True), finite_float(handle_noise, "handle_noise", "N", nonnegative=True)
    p0 = np.asarray(start, dtype=float) if np.asarray(start).dtype.kind in "fiu" else None
    if p0 is None or p0.shape != (3,) or not np.all(np.isfinite(p0)):
        raise InputError(f"start: expected 3 finite numbers [m], got {start!r}")
    dt = law.dt
    n_steps = int(round(duration / dt))
    t = np.arange(n_steps) * dt
    rng = np.random.default_rng(seed)
    f_plan, aim = operator.planned(t, rng, dt)
    scale = np.array([1, 1, 1, 0.01, 0.01, 0.01])
    noise_t = tool_noise * scale * rng.standard_normal((n_steps, 6))
    noise_h = handle_noise * scale * rng.standard_normal((n_steps, 6))
    n_n = law.nominal_normal
    u = np.hstack([f_plan, aim, noise_t, noise_h, np.tile(n_n, (n_steps, 1))])
    z0 = np.concatenate([np.zeros(STATE_SIZE), p0, np.eye(3).ravel(order="F"), np.zeros(12), p0])
    step = _closed_loop_step(law, contact, servo, operator, dt)
    z, out = step.mapaccum(n_steps)(z0, u.T)
    z, out = np.asarray(z).T, np.asarray(out).T
    x = np.vstack([z0[:STATE_SIZE], z[:, :STATE_SIZE]])
    R = out[:, 30:39].reshape(n_steps, 3, 3, order="F")
    return LeadThroughRun(t=t, p=out[:, 27:30], R=R, F_contact=out[:, :6], F_t=out[:, 6:12], F_h=out[:, 12:18],
                          n_n=n_n.copy(), x=x, V_tool=out[:, 18:24], n=out[:, 24:27], dt=dt)
