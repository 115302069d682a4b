"""Simulation of a model with zero-crossing events (declared with :mod:`gtmodel.modeling.structure.events`).

The simulation (:func:`simulate_events`) is a root-finding restart loop around SUNDIALS:

1. Integrate (IDAS or CVODES through ``casadi.integrator``, time scaled to ``[0, 1]`` so
   that one integrator serves every window with the same layout of output times) over the
   following output intervals with the same input, in one run (a restart at every output
   time would cost accuracy: 3e-6 s instead of 1e-7 s on the stick-slip test at
   ``rtol = 1e-8``), sampling the conditions at least every ``event_step``. Where the
   input changes, the algebraic variables are first made consistent with the new input
   (Newton; the grid point reports them, as :func:`~gtmodel.modeling.Model.simulate` does).
2. At the first sub-step where a condition crossed zero, find the event time with
   :func:`scipy.optimize.brentq` on the condition along the re-integrated trajectory
   (``xtol = event_tol``); its accuracy is the integration accuracy divided by the slope
   of the condition.
3. Run the actions and the event iteration, record an :class:`EventRecord`, restart the
   integrator from the post-event state.

A condition that goes positive and back within one sub-step is missed (as with SciPy's
``solve_ivp``, which checks once per step); make ``event_step`` smaller than the shortest
phase. A condition already positive at the start does not fire (edge semantics) unless
its clause is declared ``initial=True``. ``sign()`` in the equations is switched by events
too (:mod:`gtmodel.modeling.structure.discontinuities`, applied by :meth:`Model.simulate`).

A model with events that ``flatten()`` refuses (aliases, a rigid coupling, a closed chain)
is reduced once by :func:`~gtmodel.modeling.structure.index_reduction.structural_simplify` before the
loop (:func:`simulate_events_reduced`): its when-clauses are carried over and the reinit
targets kept as states. The dummy selection made at the start is not re-made between
events, so a constraint whose selection turns singular on the way (a Cartesian pendulum
passing ``x = 0``) stops with a ConvergenceError (a strict xfail in
tests/modeling/structure/test_events.py); linear couplings (rigidly joined masses) are exact.

Why not CasADi's own event support (DAE field ``"zero"`` with option ``"transition"``,
experimental in 3.8): measured in casadi 3.8.2 on ``x'' = -x``, ``x(0) = 1``, ``zero = x``
over 10 s (event times ``pi/2 + k pi``), with CVODES and IDAS alike, it stops with
``CV_ILL_INPUT`` / ``IDA_ILL_INPUT`` ("tout too far back in direction of integration")
when the 10 s are one or ten output intervals, and runs only on a fine output grid (1001
points), where it places the event at ``5 pi / 2`` 2e-8 s off at ``reltol = 1e-10``; it fires on
positive-to-negative crossings only (casadi issue #4393). The loop here, on the same
problem (``when(-x)``, CVODES, ``rtol = 1e-10``), is within 7e-10 s on 2, 11 or 1001
output points.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._arrays import positive_float, positive_int
from gtmodel._lazy import lazy_module
from gtmodel.errors import ConvergenceError, InputError
from gtmodel.modeling.dae import SimulationResult, _eval_outputs, _unpack, expand_names
from gtmodel.modeling.structure.events import EventRecord
from gtmodel.modeling.structure.index_reduction import _ident, structural_simplify
from gtmodel.modeling.simulation.integration import TIME_OPTIONS, integrator_options, simulation_inputs, time_scaled

#: SciPy's optimisers (brentq), imported on first use: a simulation without events does not need them.
optimize = lazy_module("scipy.optimize")

__all__ = ["simulate_events", "simulate_events_reduced"]

_log = logging.getLogger("gtmodel")

#: In the event iteration a condition must exceed this (in its own units) to fire: the
#: relation hysteresis of Modelica tools, so that a velocity that is zero up to the
#: integration error when a stuck friction element starts sliding does not count as a
#: crossing (it would switch the element back to stuck at once).
_HYSTERESIS = 1e-9


# ---------------------------------------------------------------------------- simulation
def _crossed(c0: np.ndarray, c1: np.ndarray, direction: np.ndarray, eps: float = 0.0) -> np.ndarray:
    """Which conditions crossed zero from ``c0`` to ``c1`` in their direction (to beyond ``eps``)."""
    rising = (c0 <= 0.0) & (c1 > eps)
    falling = (c0 >= 0.0) & (c1 < -eps)
    both = ((c0 < 0.0) & (c1 > eps)) | ((c0 > 0.0) & (c1 < -eps))
    return np.where(direction > 0, rising, np.where(direction < 0, falling, both))


class _EventSimulator:
    """The functions of one event simulation and its restart loop (internal)."""

    def __init__(self, model: Any, dae: Any, integrator: str, rtol: float, atol: float,
                 options: Mapping[str, Any] | None = None) -> None:
        self.model, self.dae, self.plugin = model, dae, integrator
        spec = model._events
        self.whens = spec.whens
        self.modes = spec.modes
        self.direction = np.array([w.direction for w in self.whens])
        args = [dae.t, dae.x, dae.z, dae.u, dae.p]
        argn = ["t", "x", "z", "u", "p"]

        def rhs(e: ca.SX) -> ca.SX:  # der() -> ODE right-hand side
            return ca.substitute(e, dae.xdot, dae.ode_expr) if dae.nx else e

        conds = ca.vertcat(*[rhs(w.condition) for w in self.whens])
        self.cond = ca.Function("event_conditions", args, [conds], argn, ["c"])
        self.actions = []
        for w in self.whens:
            xn, pn = ca.SX(dae.x), ca.SX(dae.p)
            for vname, idx, val in w.reinit:
                base = dae.x_vars[vname].start
                for k, i in enumerate(idx):
                    xn[base + i] = rhs(val[k if val.numel() > 1 else 0])
            hypo = [(dae.z[dae.z_vars[k].start], v) for k, v in w.assume.items()]
            for vname, val in w.assign:
                pn[dae.p_vars[vname].start] = ca.substitute(
                    rhs(val), ca.vertcat(*[h for h, _ in hypo]), ca.vertcat(*[v for _, v in hypo])
                ) if hypo else rhs(val)
            self.actions.append(ca.Function(f"when_action{len(self.actions)}", args, [xn, pn], argn, ["x_post", "p_post"]))
        if dae.nz:
            tz, xz, uz, pz = dae.t, dae.x, dae.u, dae.p
            gz = ca.Function("g", [dae.z, ca.vertcat(tz, xz, uz, pz)], [dae.alg_expr])
            self.zsolve = ca.rootfinder("event_zsolve", "newton", gz, {"error_on_fail": False})
        # time-scaled DAE: t = t0 + tau h, tau in [0, 1]
        tau, t0, h = ca.SX.sym("tau"), ca.SX.sym("t0"), ca.SX.sym("h")
        tt = t0 + tau * h
        self.ddict: dict[str, Any] = {
            "t": tau,
            "x": dae.x,
            "u": dae.u,
            "p": ca.vertcat(dae.p, t0, h),
            "ode": h * ca.substitute(dae.ode_expr, dae.t, tt),
        }
        if dae.nz:
            self.ddict["z"] = dae.z
            self.ddict["alg"] = ca.substitute(dae.alg_expr, dae.t, tt)
        self.opts = integrator_options(options, rtol, atol, integrator)
        self._integrators: dict[tuple[float, ...], ca.Function] = {}
        self._cond_maps: dict[int, ca.Function] = {}

    # -------------------------------------------------------------- numeric helpers
    def integrate(self, fracs: tuple[float, ...], tc: float, h: float, x: np.ndarray, z: np.ndarray, p: np.ndarray, u: np.ndarray):
        """States and algebraics at ``tc + h * fracs`` (increasing, last 1): ``(nx, k)``, ``(nz, k)``."""
        key = tuple(np.round(fracs, 13)) + ((h,) if any(k in self.opts for k in TIME_OPTIONS) else ())
        F = self._integrators.get(key)
        if F is None:  # one integrator per output layout (a uniform grid needs one), last 64 kept
            if len(self._integrators) >= 64:
                self._integrators.pop(next(iter(self._integrators)))
            opts = time_scaled(self.opts, h)  # step sizes in units of h
            F = ca.integrator("event_integrator", self.plugin, self.ddict, 0.0, list(fracs), opts)
            self._integrators[key] = F
        k = len(fracs)
        try:
            res = F(x0=x, z0=z, p=np.concatenate([p, [tc, h]]), u=u)
        except RuntimeError as exc:
            lines = [ln for ln in str(exc).splitlines() if "returned" in ln] or str(exc).splitlines()
            raise ConvergenceError(
                f"simulation of model {self.model.name!r} with {self.plugin} failed on "
                f"[{tc:.9g}, {tc + h:.9g}] s: {lines[0].strip() if lines else exc}"
            ) from exc
        xs = np.array(res["xf"]).reshape(self.dae.nx, k)
        zs = np.array(res["zf"]).reshape(self.dae.nz, k)
        if not (np.all(np.isfinite(xs)) and np.all(np.isfinite(zs))):
            raise ConvergenceError(
                f"simulation of model {self.model.name!r} produced non-finite values on [{tc:.9g}, {tc + h:.9g}] s"
            )
        return xs, zs

    def conditions(self, t: np.ndarray, xs: np.ndarray, zs: np.ndarray, u: np.ndarray, p: np.ndarray) -> np.ndarray:
        """Conditions at ``k`` samples: ``(nc, k)``."""
        k = t.size
        if k not in self._cond_maps:
            self._cond_maps[k] = self.cond.map(k)
        c = self._cond_maps[k](t.reshape(1, -1), xs, zs, np.tile(u.reshape(-1, 1), (1, k)), np.tile(p.reshape(-1, 1), (1, k)))
        return np.array(c).reshape(len(self.whens), k)

    def consistent_z(self, t: float, x: np.ndarray, z: np.ndarray, u: np.ndarray, p: np.ndarray, why: str) -> np.ndarray:
        """Algebraic variables solving ``g = 0`` at ``(t, x, u, p)`` (Newton from ``z``)."""
        if not self.dae.nz:
            return z
        zn = np.array(self.zsolve(z, np.concatenate([[t], x, u, p]))).reshape(-1)
        g = np.array(self.dae.alg(t, x, zn, u, p)).reshape(-1)
        if not (np.all(np.isfinite(zn)) and np.linalg.norm(g, np.inf) <= 1e-8 * (1.0 + np.linalg.norm(zn, np.inf))):
            raise ConvergenceError(
                f"model {self.model.name!r}: no consistent algebraic variables {self.dae.z_names} {why} "
                f"(residual {np.linalg.norm(g, np.inf):.3g})"
            )
        return zn

    def record(self, t: float, name: str, x: np.ndarray, p: np.ndarray) -> EventRecord:
        modes = {m: float(p[self.dae.p_vars[m].start]) for m in self.modes}
        states = {k: (x[s].copy() if s.stop - s.start > 1 else np.array(float(x[s.start]))) for k, s in self.dae.x_vars.items()}
        return EventRecord(t=float(t), name=name, modes=modes, x=states)

    # -------------------------------------------------------------- one event
    def locate(self, ta: float, tb: float, xa, za, p, u, ca_, i: int, tol: float) -> float:
        """Time of the zero crossing of condition ``i`` in ``(ta, tb]`` (Brent's method)."""
        sign = 1.0 if (self.direction[i] > 0 or (self.direction[i] == 0 and ca_[i] < 0)) else -1.0

        def phi(s: float) -> float:
            if s <= ta:
                return sign * ca_[i]
            xs, zs = self.integrate((1.0,), ta, s - ta, xa, za, p, u)
            return sign * float(self.conditions(np.array([s]), xs, zs, u, p)[i, 0])

        fb = phi(tb)
        if sign * ca_[i] > 0.0 or fb <= 0.0:  # crossed exactly at ta, or not seen again
            return ta if sign * ca_[i] > 0.0 else tb
        root = float(optimize.brentq(phi, ta, tb, xtol=tol, rtol=4 * np.finfo(float).eps, maxiter=200))
        step = tol
        while root < tb and phi(root) <= 0.0:  # the event is at the right limit: crossed
            root, step = min(root + step, tb), 2.0 * step
        return root

    def fire(self, t: float, x, z, p, u, fired: list[int], max_iter: int) -> tuple:
        """Run the actions of ``fired`` and the event iteration at ``t``; returns ``(x, z, p, c, records)``."""
        records = []
        for _ in range(max_iter):
            c_pre = self.conditions(np.array([t]), x.reshape(-1, 1), z.reshape(-1, 1), u, p)[:, 0]
            xn, pn = x.copy(), p.copy()
            for i in fired:  # all evaluated with the pre-event values, applied in declaration order
                xi, pi = self.actions[i](t, x, z, u, p)
                xi, pi = np.array(xi).reshape(-1), np.array(pi).reshape(-1)
                w = self.whens[i]
                for vname, idx, _ in w.reinit:
                    sl = [self.dae.x_vars[vname].start + j for j in idx]
                    xn[sl] = xi[sl]
                for vname, _ in w.assign:
                    j = self.dae.p_vars[vname].start
                    pn[j] = pi[j]
            names = [self.whens[i].name for i in fired]
            zn = self.consistent_z(t, xn, z, u, pn, f"after event {names} at t = {t:.12g} s")
            records += [self.record(t, self.whens[i].name, xn, pn) for i in fired]
            c_post = self.conditions(np.array([t]), xn.reshape(-1, 1), zn.reshape(-1, 1), u, pn)[:, 0]
            x, z, p = xn, zn, pn
            fired = [int(j) for j in np.nonzero(_crossed(c_pre, c_post, self.direction, _HYSTERESIS))[0]]
            if not fired:
                return x, z, p, c_post, records
        raise ConvergenceError(
            f"model {self.model.name!r}: the event iteration at t = {t:.12g} s did not settle in {max_iter} "
            f"rounds; clauses still firing: {[self.whens[i].name for i in fired]}"
        )


def simulate_events(
    model: Any,
    t_grid: Any,
    x0: Any = None,
    u: Any = None,
    p: Mapping[str, Any] | None = None,
    integrator: str = "idas",
    rtol: float = 1e-8,
    atol: float = 1e-10,
    z0: Any = None,
    event_step: float | None = None,
    event_tol: float = 1e-12,
    max_events: int = 10000,
    max_event_iter: int = 20,
    options: Mapping[str, Any] | None = None,
) -> SimulationResult:
    """Integrate a model with when-clauses on a time grid, stopping and restarting at events.

    :meth:`Model.simulate` calls this with the default event options when the model has
    when-clauses. The algorithm (a root-finding restart loop around SUNDIALS) and the
    semantics are in the module docstring.

    Parameters
    ----------
    model : Model
        The model, with modes and when-clauses.
    t_grid : array_like
        Strictly increasing output times, shape ``(N,)`` with ``N >= 2``, s.
    x0 : array_like or mapping, optional
        Initial state ``(nx,)`` or state name -> value; default the declared starts.
    u : float, array_like or callable, optional
        Inputs, piecewise constant on the grid, as for :meth:`Model.simulate`.
    p : mapping of str to float or array_like, optional
        Parameter overrides by name; a mode's value here is its start value.
    integrator : {"idas", "cvodes"}, optional
        SUNDIALS integrator; CVODES only without algebraic variables.
    rtol, atol : float, optional
        Relative and absolute integration tolerances.
    z0 : array_like, optional
        Guess for the algebraic variables at ``t_grid[0]``, ``(nz,)``.
    event_step : float, optional
        Longest interval between two samples of the conditions, s; default
        ``(t_grid[-1] - t_grid[0]) / 1000``. The output grid points are always samples.
    event_tol : float, optional
        Absolute tolerance of the event time in Brent's method, s; default 1e-12.
    max_events : int, optional
        Most events allowed (a guard against chattering and Zeno behaviour); default 10000.
    max_event_iter : int, optional
        Most rounds of the event iteration at one instant; default 20.
    options : mapping, optional
        Integrator options, as for :meth:`Model.simulate`
        (:func:`~gtmodel.modeling.simulation.integration.integrator_options`).

    Returns
    -------
    SimulationResult
        Trajectories on ``t_grid`` (at a grid point that is also an event time, the
        post-event values) and :attr:`SimulationResult.events` in time order.

    Raises
    ------
    InputError
        On malformed arguments.
    ModelError
        If the model cannot be flattened.
    ConvergenceError
        If the integrator fails, the algebraic variables cannot be made consistent after
        an event, the event iteration does not settle, or more than ``max_events`` events
        occur (the message names the last clauses).
    """
    dae = model.flatten()
    t, xv, zv, pv, u_int = simulation_inputs(model, dae, t_grid, x0, u, p, integrator, z0)
    span = float(t[-1] - t[0])
    step = span / 1000.0 if event_step is None else positive_float(event_step, "event_step")
    tol = positive_float(event_tol, "event_tol")
    max_events = positive_int(max_events, "max_events")
    max_event_iter = positive_int(max_event_iter, "max_event_iter")
    if model._events is None or not model._events.whens:
        raise InputError(f"model {model.name!r} declares no when-clause; use Model.simulate")
    sim = _EventSimulator(model, dae, integrator, rtol, atol, options)
    n = t.size
    xs, zs, ps = np.zeros((n, dae.nx)), np.zeros((n, dae.nz)), np.zeros((n, dae.npar))
    zv = sim.consistent_z(float(t[0]), xv, zv, u_int[0], pv, f"at the start t = {t[0]:.12g} s")
    xs[0], zs[0], ps[0] = xv, zv, pv
    c_prev = sim.conditions(t[:1], xv.reshape(-1, 1), zv.reshape(-1, 1), u_int[0], pv)[:, 0]
    events: list[EventRecord] = []
    first = [i for i, w in enumerate(sim.whens) if w.initial and c_prev[i] > _HYSTERESIS]
    if first:  # Modelica initial(): clauses already active at the start
        xv, zv, pv, c_prev, events = sim.fire(float(t[0]), xv, zv, pv, u_int[0], first, max_event_iter)
        xs[0], zs[0] = xv, zv
    j, tc = 0, float(t[0])  # grid points 0..j are stored; tc in [t[j], t[j+1])
    while j < n - 1:
        if dae.nz and j and tc == t[j] and not np.array_equal(u_int[j], u_int[j - 1]):
            # the input changes: algebraic variables consistent with the new input (the right
            # limit is reported, as by simulate_model; IDAS starts the window from them)
            zv = zs[j] = sim.consistent_z(tc, xv, zv, u_int[j], pv, f"where the input changes at t = {tc:.12g} s")
        # one window: the following grid intervals with the same input (one integrator run,
        # no restarts at the output times), conditions sampled at least every `step`
        big = j + 1
        while big < n - 1 and np.array_equal(u_int[big], u_int[j]):
            big += 1
        uj, pts, at = u_int[j], [], {}
        lo = tc
        for i in range(j + 1, big + 1):
            k = max(1, math.ceil((t[i] - lo) / step - 1e-9))
            pts.extend(lo + (t[i] - lo) * np.arange(1, k + 1) / k)
            at[i], lo = len(pts) - 1, float(t[i])
        tk, h = np.array(pts), float(t[big]) - tc
        xk, zk = sim.integrate(tuple((tk[:-1] - tc) / h) + (1.0,), tc, h, xv, zv, pv, uj)
        ck = sim.conditions(tk, xk, zk, uj, pv)
        prev = np.column_stack([c_prev, ck[:, :-1]])
        hit = _crossed(prev, ck, sim.direction[:, None])
        s = int(np.nonzero(hit.any(axis=0))[0][0]) if hit.any() else len(tk)  # first sample past a crossing
        for i, idx in at.items():
            if idx < s:
                xs[i], zs[i], ps[i] = xk[:, idx], zk[:, idx], pv
                j = i
        if s == len(tk):
            xv, zv, c_prev, tc = xk[:, -1], zk[:, -1], ck[:, -1], float(t[big])
            continue
        ta = tc if s == 0 else float(tk[s - 1])
        xa, za = (xv, zv) if s == 0 else (xk[:, s - 1], zk[:, s - 1])
        roots = {int(i): sim.locate(ta, float(tk[s]), xa, za, pv, uj, prev[:, s], int(i), tol) for i in np.nonzero(hit[:, s])[0]}
        t_ev = min(roots.values())
        fired = sorted(i for i, r in roots.items() if r <= t_ev + tol)
        if t_ev > ta:
            xe, ze = sim.integrate((1.0,), ta, t_ev - ta, xa, za, pv, uj)
            xv, zv = xe[:, 0], ze[:, 0]
        else:
            xv, zv = xa, za
        xv, zv, pv, c_prev, recs = sim.fire(t_ev, xv, zv, pv, uj, fired, max_event_iter)
        events += recs
        _log.debug("model %s: events %s at t = %.12g s", model.name, [r.name for r in recs], t_ev)
        if len(events) > max_events:
            raise ConvergenceError(
                f"model {model.name!r}: more than max_events = {max_events} events by t = {t_ev:.12g} s "
                f"(the last: {[r.name for r in events[-4:]]}); chattering or Zeno behaviour?"
            )
        tc = t_ev
        while j < n - 1 and t[j + 1] <= t_ev + tol:  # a grid point at the event: post-event values
            j += 1
            xs[j], zs[j], ps[j] = xv, zv, pv
            tc = max(tc, float(t[j]))
    us = np.vstack([u_int, u_int[-1:]])
    outs = _eval_outputs(dae, t, xs, zs, us, ps)
    _log.debug("simulated model %s with %d events on %d points", model.name, len(events), n)
    return SimulationResult(
        t=t,
        x=_unpack(dae.x_vars, xs),
        z=_unpack(dae.z_vars, zs),
        u=_unpack(dae.u_vars, us),
        outputs=outs,
        p={k: ps[0][s].copy() for k, s in dae.p_vars.items()},
        events=events,
    )


def simulate_events_reduced(
    model: Any,
    t_grid: Any,
    x0: Any = None,
    u: Any = None,
    p: Mapping[str, Any] | None = None,
    integrator: str = "idas",
    rtol: float = 1e-8,
    atol: float = 1e-10,
    consistent: bool = False,
    options: Mapping[str, Any] | None = None,
) -> SimulationResult:
    """Simulate a model with when-clauses that ``flatten()`` refuses (aliases, high index).

    :meth:`Model.simulate` calls this. The model is reduced once by
    :func:`~gtmodel.modeling.structure.index_reduction.structural_simplify` (alias elimination,
    Pantelides, dummy derivatives selected at the start values, keeping the reinit targets
    as states where the selection allows), its modes and when-clauses carried over, and
    simulated by :func:`simulate_events`; the result holds the declared states and
    algebraic variables of ``model``. Limits: the dummy selection is not re-made during
    the simulation (a constraint whose selection turns singular, e.g. a pendulum passing
    ``x = 0``, fails with a ConvergenceError; linear couplings such as rigidly joined
    masses are exact), and the states the reduction made dummies take their values from
    the constraints (:meth:`Model.simulate` solves a consistent start first when ``x0`` or a
    fixed start names one, and passes ``consistent=True``).

    Parameters
    ----------
    model : Model
        The model, with when-clauses.
    t_grid : array_like
        Strictly increasing output times, shape ``(N,)`` with ``N >= 2``, s.
    x0 : mapping of str to float or array_like, optional
        Start values of states that stay states after the reduction, by name; default the
        declared starts.
    u : float, array_like or callable, optional
        Inputs, as for :meth:`Model.simulate`.
    p : mapping of str to float or array_like, optional
        Parameter overrides by name.
    integrator : {"idas", "cvodes"}, optional
        SUNDIALS integrator.
    rtol, atol : float, optional
        Relative and absolute integration tolerances.
    consistent : bool, optional
        ``x0`` holds consistent values of all states (from
        :func:`~gtmodel.modeling.simulation.structured_simulation.consistent_start`): the dummies'
        are dropped instead of refused; default false.
    options : mapping, optional
        Integrator options, as for :meth:`Model.simulate`.

    Returns
    -------
    SimulationResult
        As :func:`simulate_events`, under the names of ``model``.

    Raises
    ------
    InputError
        If ``x0`` is not a mapping or names a state that the reduction made a dummy.
    ModelError
        If the model is structurally singular, cannot be reduced, or a reinit target cannot
        stay a state.
    ConvergenceError
        As :func:`simulate_events`.
    """
    keep = tuple(
        expand_names(vname, len(model._vars[vname].start))[i] for w in model._events.whens for vname, idx, _ in w.reinit
        for i in idx
    )
    reduced = structural_simplify(model, keep_states=keep)
    if consistent and isinstance(x0, Mapping):  # scalar states of the reduced model
        x0 = {
            nm: float(val) for k, vals in x0.items() for nm, val in zip(expand_names(k, np.size(vals)), np.ravel(vals))
            if nm in reduced._vars and reduced._vars[nm].kind == "state"
        }
    if x0 is not None:
        if not isinstance(x0, Mapping):
            raise InputError(f"model {model.name!r} is index-reduced for the event simulation: give x0 as a mapping name -> value")
        dummies = [k for k in x0 if k not in reduced._vars or reduced._vars[k].kind != "state"]
        if dummies:
            raise InputError(
                f"x0: {dummies} of model {model.name!r} are not states after index reduction (dummy derivatives: "
                f"their values follow from the constraints); states: {[v.name for v in reduced._vars.values() if v.kind == 'state']}"
            )
    res = simulate_events(reduced, t_grid, x0, u, p, integrator, rtol, atol, options=options)
    found = {**res.outputs, **res.z, **res.x}

    def column(nm: str) -> np.ndarray:
        return found[nm] if nm in found else found[_ident(nm)]

    def group(kind: str) -> dict[str, np.ndarray]:
        out = {}
        for v in model._vars.values():
            if v.kind == kind:
                cols = [column(nm) for nm in expand_names(v.name, v.size)]
                out[v.name] = cols[0] if v.size == 1 else np.column_stack(cols)
        return out

    outputs = {k: res.outputs[k] for k in model._outputs}
    return SimulationResult(t=res.t, x=group("state"), z=group("algebraic"), u=res.u, outputs=outputs, p=res.p, events=res.events)
