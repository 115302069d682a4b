"""Closed-loop check of a loop controller against a plant simulated in Python.

The controller is any callable ``controller(t, x) -> (status, u)`` (the compiled C step
loaded through ctypes, see :func:`gtmodel.codegen.loop_step.load_loop_step`, or a Python
law); the plant is the fixed step of a model (:meth:`ExplicitODE.step
<gtmodel.modeling.simulation.explicit.ExplicitODE.step>`, several RK4 substeps per period)
built with parameters other than the controller's. What a real loop meets
(Dressler (2012), ch. 7.3: a 4 ms loop whose input acts one sample late, noisy sensors):

- parameter mismatch: the plant's own model (:func:`mismatched_robot` for the Gantry-Tau:
  masses and friction scaled);
- measurement noise: Gaussian, one standard deviation per state, added to what the
  controller sees;
- a step disturbance: an input offset from a given time on (a load force, a torque);
- the input delay of one sample: the input computed at ``t_k`` acts over ``[t_{k+1}, t_{k+2})``.

:class:`LoopSummary` reports the tracking error (RMS and maximum over the chosen states),
the bound violations of the applied input, the controller's status counts and its step
times (the first call apart).
"""

from __future__ import annotations

import dataclasses
import time
from collections import Counter
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import casadi as ca
import numpy as np

from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError
from gtmodel.estimation.closed_loop.plant import ToolStructure
from gtmodel.robots.parameters import RobotParameters

__all__ = ["LoopSummary", "run_controller_loop", "mismatched_robot", "compliant_plant", "BOUND_TOLERANCE", "DIVERGED"]

#: Slack of the bound-violation count (relative to ``1 + |bound|``).
BOUND_TOLERANCE = 1e-9
#: A plant state beyond this many times ``1 + max |x_ref|`` of its column has diverged (:attr:`LoopSummary.diverged`).
DIVERGED = 1e6


@dataclass
class LoopSummary:
    """The record and summary of one closed-loop run.

    Parameters
    ----------
    t : numpy.ndarray
        ``(K,)`` sample times [s].
    x : numpy.ndarray
        ``(K, nx)`` plant states at ``t`` (true, without noise).
    x_ref : numpy.ndarray
        ``(K, nx)`` reference states at ``t``.
    u : numpy.ndarray
        ``(K, nu)`` inputs applied over ``[t_k, t_{k+1})`` (after the delay, without the disturbance).
    status : numpy.ndarray
        ``(K,)`` the controller's status per call (0 = ``GT_OK``).
    step_s : numpy.ndarray
        ``(K,)`` wall time of each controller call [s].
    error_states : tuple of int
        The states whose error is summarised.
    u_lb, u_ub : numpy.ndarray
        ``(nu,)`` the input bounds checked.
    status_names : dict of int to str, optional
        Names of the status codes (for :attr:`status_counts`).
    state_names : tuple of str, optional
        Names of the states, in the order of the columns (for the summary; default none: indices).
    x_interior : numpy.ndarray, optional
        ``(K, m, nx)`` the plant's states inside each period (its step's substeps after the sample's,
        ``interior`` of :func:`run_controller_loop`; default ``(K, 0, nx)``: none recorded).
    y : numpy.ndarray, optional
        ``(K, nm)`` what the controller measured at each sample (the measured states with their noise; default None:
        not recorded).
    """

    t: np.ndarray
    x: np.ndarray
    x_ref: np.ndarray
    u: np.ndarray
    status: np.ndarray
    step_s: np.ndarray
    error_states: tuple[int, ...]
    u_lb: np.ndarray
    u_ub: np.ndarray
    status_names: dict[int, str] = field(default_factory=dict)
    state_names: tuple[str, ...] = ()
    x_interior: np.ndarray | None = None
    y: np.ndarray | None = None

    @property
    def error(self) -> np.ndarray:
        """``(K, len(error_states))`` tracking error ``x - x_ref`` of the summarised states."""
        idx = list(self.error_states)
        return self.x[:, idx] - self.x_ref[:, idx]

    @property
    def error_norm(self) -> np.ndarray:
        """``(K,)`` Euclidean norm of :attr:`error` per sample."""
        return np.linalg.norm(self.error, axis=1)

    @property
    def rms_error(self) -> float:
        """RMS over time of :attr:`error_norm`."""
        return float(np.sqrt(np.mean(self.error_norm**2)))

    @property
    def max_error(self) -> float:
        """Largest :attr:`error_norm`."""
        return float(np.max(self.error_norm))

    @property
    def diverged(self) -> bool:
        """Whether the plant ran away: a state not finite, or beyond :data:`DIVERGED` times ``1 + max |x_ref|`` of its column.

        A run whose plant diverged says nothing of the controller (an explicit plant step
        unstable on a stiff model diverges under any input); the checks refuse it.
        """
        scale = 1.0 + np.max(np.abs(self.x_ref), axis=0)
        return bool(not np.all(np.isfinite(self.x)) or np.any(np.abs(self.x) > DIVERGED * scale))

    @property
    def bound_violations(self) -> int:
        """Number of applied input entries outside ``[u_lb, u_ub]`` (beyond :data:`BOUND_TOLERANCE`)."""
        lo = self.u < self.u_lb - BOUND_TOLERANCE * (1 + np.abs(np.where(np.isfinite(self.u_lb), self.u_lb, 0)))
        hi = self.u > self.u_ub + BOUND_TOLERANCE * (1 + np.abs(np.where(np.isfinite(self.u_ub), self.u_ub, 0)))
        return int(np.sum(lo | hi) + np.sum(~np.isfinite(self.u)))

    @property
    def status_counts(self) -> dict[str, int]:
        """Calls per status name (``GT_OK``, ``GT_NOT_CONVERGED``, ...)."""
        return {self.status_names.get(int(k), str(int(k))): int(v) for k, v in sorted(Counter(self.status.tolist()).items())}

    def step_times(self) -> dict[str, float]:
        """Step time statistics [s]: ``first``, and over the other calls ``median``, ``p99``, ``max``.

        Returns
        -------
        dict of str to float
        """
        rest = self.step_s[1:] if self.step_s.size > 1 else self.step_s
        return {"first": float(self.step_s[0]), "median": float(np.median(rest)),
                "p99": float(np.percentile(rest, 99)), "max": float(np.max(rest))}

    def summary_lines(self) -> list[str]:
        """Human-readable summary, one figure per line.

        Returns
        -------
        list of str
        """
        st = self.step_times()
        states = ([self.state_names[i] for i in self.error_states] if len(self.state_names) > max(self.error_states, default=-1)
                  else list(self.error_states))
        return [f"tracking error: RMS {self.rms_error:.4g}, max {self.max_error:.4g} (states {', '.join(map(str, states))})",
                f"input bound violations: {self.bound_violations}",
                f"status counts: {self.status_counts}",
                f"step time: median {st['median'] * 1e6:.1f} us, p99 {st['p99'] * 1e6:.1f} us, max {st['max'] * 1e6:.1f} us "
                f"(first call {st['first'] * 1e6:.1f} us) over {self.step_s.size} calls"]


def mismatched_robot(parameters: RobotParameters, mass_factor: float = 1.1, friction_factor: float = 1.1) -> RobotParameters:
    """A Gantry-Tau parameter set with its masses and friction coefficients scaled (a plant unlike the model).

    Parameters
    ----------
    parameters : RobotParameters
        The controller's parameter set.
    mass_factor : float, optional
        Factor on the plate, cart and link masses ``m_p``, ``m_c``, ``m_a`` (default 1.1).
    friction_factor : float, optional
        Factor on the Coulomb and viscous friction ``f_c``, ``f_v`` (default 1.1).

    Returns
    -------
    RobotParameters
        A copy with the scaled dynamic parameters (kinematics unchanged).

    Raises
    ------
    InputError
        A factor not positive and finite.
    """
    for name, v in (("mass_factor", mass_factor), ("friction_factor", friction_factor)):
        if not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
            raise InputError(f"{name}: expected a positive factor, got {v!r}")
    d = parameters.dynamics
    dyn = dataclasses.replace(d, m_p=d.m_p * mass_factor, m_c=np.asarray(d.m_c) * mass_factor, m_a=np.asarray(d.m_a) * mass_factor,
                              f_c=np.asarray(d.f_c) * friction_factor, f_v=np.asarray(d.f_v) * friction_factor)
    return dataclasses.replace(parameters, dynamics=dyn, name=f"{parameters.name}_mismatched")


def run_controller_loop(
    controller: Callable[[float, np.ndarray], tuple[int, np.ndarray]],
    plant_step: ca.Function,
    x0: Any,
    t: Any,
    x_ref: Any,
    u_lb: Any,
    u_ub: Any,
    plant_p: Any = None,
    noise_std: Any = 0.0,
    disturbance: Any = None,
    disturbance_time: float = np.inf,
    delay: int = 1,
    u_before: Any = None,
    error_states: Sequence[int] | None = None,
    seed: int = 0,
    status_names: dict[int, str] | None = None,
    clock: Callable[[], float] = time.perf_counter,
    state_names: Sequence[str] | None = None,
    interior: Callable[..., Any] | None = None,
    measured: int | None = None,
    output: Callable[[np.ndarray], np.ndarray] | None = None,
) -> LoopSummary:
    """Run a controller against a simulated plant, sample by sample.

    Parameters
    ----------
    controller : callable
        ``controller(t, x_measured) -> (status, u)``; ``u`` ``(nu,)``.
    plant_step : casadi.Function
        ``step(x, u, p) -> (x_next, ...)`` over one period of the plant's model (its own
        parameters; at least two outputs, the first the next state).
    x0 : array_like
        Initial plant state.
    t : array_like
        ``(K,)`` equally spaced sample times [s] (the loop period apart).
    x_ref : array_like
        ``(K, nx)`` reference states at ``t`` (for the error).
    u_lb, u_ub : array_like
        ``(nu,)`` input bounds whose violations are counted.
    plant_p : array_like, optional
        ``(np,)`` the plant's parameters (default none).
    noise_std : float or array_like, optional
        Standard deviation of the measurement noise per measured state (default 0).
    disturbance : array_like, optional
        ``(nu,)`` input offset added from ``disturbance_time`` on (default none).
    disturbance_time : float, optional
        Time [s] of the step disturbance.
    delay : int, optional
        Input delay in samples (default 1; 0 = acts at once).
    u_before : array_like, optional
        ``(nu,)`` input acting before the first computed one arrives (default the first computed one).
    error_states : sequence of int, optional
        States summarised by the error (default all).
    seed : int, optional
        Seed of the noise.
    status_names : dict of int to str, optional
        Names of the status codes for the counts.
    state_names : sequence of str, optional
        Names of the plant's states (for the summary; default none: indices).
    interior : callable, optional
        ``interior(x, u, p) -> (nx, m)``: the plant's states inside a period from ``x`` under ``u`` (its step's
        substeps; recorded as :attr:`LoopSummary.x_interior`, so that bounds are counted between the samples too).
        Not with ``output``.
    clock : callable, optional
        The clock of the step times [s] (default ``time.perf_counter``, wall time;
        ``time.thread_time``: the CPU time of this thread, without the preemptions of a
        shared machine).
    measured : int, optional
        The controller sees the first ``measured`` plant states (default all; a plant with
        states the controller does not model, e.g. :func:`compliant_plant`).
    output : callable, optional
        ``output(x_plant) -> (nx_ref,)``: the plant's tracked coordinates compared with
        ``x_ref`` and recorded as :attr:`LoopSummary.x` (default the plant state itself).

    Returns
    -------
    LoopSummary

    Raises
    ------
    InputError
        Mismatched shapes, fewer than two samples, a negative delay.
    """
    tt = np.asarray(t, dtype=float).reshape(-1)
    xr = np.asarray(x_ref, dtype=float)
    x = np.asarray(x0, dtype=float).reshape(-1).copy()
    nm = x.size if measured is None else int(measured)
    out = (lambda v: v) if output is None else output
    nx = np.asarray(out(x), dtype=float).size
    if tt.size < 2 or xr.shape != (tt.size, nx):
        raise InputError(f"t, x_ref: expected at least two times and an ({tt.size}, {nx}) reference, got {xr.shape}")
    if isinstance(delay, bool) or not isinstance(delay, (int, np.integer)) or delay < 0:
        raise InputError(f"delay: expected a number of samples >= 0, got {delay!r}")
    lb, ub = np.asarray(u_lb, dtype=float).reshape(-1), np.asarray(u_ub, dtype=float).reshape(-1)
    nu = lb.size
    pv = np.zeros(0) if plant_p is None else np.asarray(plant_p, dtype=float).reshape(-1)
    sigma = np.broadcast_to(np.asarray(noise_std, dtype=float), (nm,))
    dist = np.zeros(nu) if disturbance is None else np.asarray(disturbance, dtype=float).reshape(nu)
    rng = np.random.default_rng(seed)
    K = tt.size
    xs, us, status, times, ys = np.zeros((K, nx)), np.zeros((K, nu)), np.zeros(K, dtype=int), np.zeros(K), np.zeros((K, nm))
    inner: list[np.ndarray] = []
    pending: list[np.ndarray] = []
    applied = None if u_before is None else np.asarray(u_before, dtype=float).reshape(nu)
    for k in range(K):
        xs[k] = np.asarray(out(x), dtype=float).reshape(-1)
        y = x[:nm] + sigma * rng.standard_normal(nm)
        ys[k] = y
        start = clock()
        code, u = controller(float(tt[k]), y)
        times[k] = clock() - start
        status[k] = int(code)
        pending.append(np.asarray(u, dtype=float).reshape(nu).copy())
        if len(pending) > delay:
            applied = pending.pop(0)
        elif applied is None:
            applied = pending[0]
        us[k] = applied
        u_total = applied + (dist if tt[k] >= disturbance_time else 0.0)
        if interior is not None and output is None:
            inner.append(np.asarray(interior(x, u_total, pv), dtype=float).reshape(x.size, -1).T)
        x = np.asarray(plant_step(x, u_total, pv)[0]).reshape(-1)
    return LoopSummary(t=tt, x=xs, x_ref=xr, u=us, status=status, step_s=times,
                       error_states=tuple(range(nx)) if error_states is None else tuple(int(i) for i in error_states),
                       u_lb=lb, u_ub=ub, status_names=dict(status_names or {}),
                       state_names=tuple(state_names or ()), x_interior=np.stack(inner) if inner else None, y=ys)


def compliant_plant(ode: Any, structure: ToolStructure | None = None, dt: float = LOOP_PERIOD_S, substeps: int = 4) -> tuple[ca.Function, Callable, int]:
    """A TCP-state robot model with the tool structure of Dressler (2012), eq. 6.14, as a plant.

    States ``[T (3), T_dot (3), d (2), d_dot (2)]``: the rigid body ``T_ddot = f(T, T_dot, tau)``
    of ``ode`` (TCP states), and one structural mode per direction x, y driven by the
    kinematic acceleration, ``M d'' + D d' + K d = B a_kin`` (:class:`ToolStructure`). The
    controller measures ``T``, ``T_dot`` (encoders, forward kinematics); the tool is at
    ``T + (d, 0)``.

    Parameters
    ----------
    ode : ExplicitODE
        The rigid-body model in TCP states (``gantry_tau_model(..., states="tcp")``), the plant's
        own parameters.
    structure : ToolStructure, optional
        The modes (default the ILC operating point of ch. 7.3: 7.4 / 11.5 Hz).
    dt : float, optional
        Loop period [s].
    substeps : int, optional
        RK4 steps per period.

    Returns
    -------
    step : casadi.Function
        ``step(x (10,1), u (3,1), p) -> (x_next, converged)`` (the interface of
        :meth:`ExplicitODE.step <gtmodel.modeling.simulation.explicit.ExplicitODE.step>`; ``converged`` 1).
    output : callable
        ``output(x) -> (6,)``: tool position ``T + (d, 0)`` and velocity ``T_dot + (d_dot, 0)``.
    measured : int
        6 (the states the controller sees).

    Raises
    ------
    InputError
        A model that is not in TCP states (6 states, 3 inputs).
    """
    if ode.nx != 6 or ode.nu != 3:
        raise InputError(f"ode: expected a TCP-state robot model (6 states, 3 inputs), got {ode.nx} states and {ode.nu} inputs")
    pm = (structure or ToolStructure()).physical_model()
    M, D, K, B = (np.asarray(getattr(pm, n), dtype=float) for n in ("M", "D", "K", "B"))
    Minv = np.linalg.inv(M)
    x, u, p = ca.SX.sym("x", 10), ca.SX.sym("u", 3), ca.SX.sym("p", ode.np)

    def rhs(v):
        rigid = ode.f(v[:6], u, p)
        a_kin = rigid[3:5]
        d, d_dot = v[6:8], v[8:10]
        d_ddot = ca.mtimes(ca.DM(Minv), ca.mtimes(ca.DM(B), a_kin) - ca.mtimes(ca.DM(D), d_dot) - ca.mtimes(ca.DM(K), d))
        return ca.vertcat(rigid, d_dot, d_ddot)

    h, xn = dt / substeps, x
    for _ in range(substeps):
        k1 = rhs(xn)
        k2 = rhs(xn + h / 2 * k1)
        k3 = rhs(xn + h / 2 * k2)
        k4 = rhs(xn + h * k3)
        xn = xn + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    step = ca.Function("compliant_step", [x, u, p], [xn, ca.DM(1.0)], ["x", "u", "p"], ["x_next", "converged"])

    def output(v: np.ndarray) -> np.ndarray:
        v = np.asarray(v, dtype=float).reshape(-1)
        return np.r_[v[:2] + v[6:8], v[2], v[3:5] + v[8:10], v[5]]

    return step, output, 6
