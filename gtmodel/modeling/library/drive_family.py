"""A seeded family of electric drives composed from the library, each with its optimal-control problem.

:func:`drive_family` draws ``count`` members (:class:`DriveMember`: plain numbers in SI units)
from a seeded random generator, each the same chain of library components::

    src (SignalVoltage, input src.v [V]) -- r (Resistor R) -- ind (Inductor L, current ind.i [A])
        -- emf (EMF k) -- rotor (Inertia Jm, speed rotor.w [rad/s])
        -- gear (IdealGear n) or wheel (IdealRollingWheel: ball screw lead / 2 pi, belt pulley radius)
        -- backlash (ElastoBacklash c, d, b: the transmission's compliance and gap)
        -- load (Inertia or Mass) -- friction (Friction Fc, Fs, vs, dv: to the housing)
        [-- gravity (a pendulum m g l sin(phi), or a vertical axis m g)]

The ranges (``G`` the load's displacement per motor radian: ``1/n``, ``lead/(2 pi)`` or the
pulley radius; ``F_max = k i_max / G`` the drive's peak force or torque at the load):

* motor: ``R`` 0.3 to 2.5 Ohm, ``L = R tau_e`` with ``tau_e`` 0.5 to 2.5 ms, ``k`` 0.04 to
  0.25 N m/A, rotor inertia ``Jm`` 2e-5 to 4e-4 kg m^2;
* transmission: gear (``n`` 5 to 80, torsional stiffness 1e2 to 1e5 N m/rad at the load),
  ball screw (lead 5, 10, 16 or 20 mm, axial stiffness 1e6 to 1e8 N/m), belt (pulley radius 1
  to 3 cm, stiffness 1e3 to 1e6 N/m); the stiffness clipped so that the transmission's mode
  lies between 4 and 200 Hz (a user keeps the mechanical time constants within what the
  electrical one, 0.5 to 2.5 ms, lets a controller act on); damping ratio 0.02 to 0.2; a total
  backlash of 0 (a third of the members) or 0.02 to 0.2 mm (the gear's: that arc at 0.1 m,
  in rad);
* load: inertia ``Jl`` (gear; 0.5 to 5 times the rotor's reflected ``Jm n^2``) or mass (ball
  screw 0.3 to 3, belt 1 to 10 times the rotor's reflected ``Jm / G^2``); gravity (a pendulum
  hanging at ``phi = 0`` with ``m g l`` 10 to 30 % of ``F_max``, or a vertical axis with ``m g``
  at most 35 % of ``F_max``) or none; Coulomb friction 2 to 10 % of ``F_max``, with (half of
  the members) or without a Stribeck peak ``Fs`` 20 to 60 % of ``Fc`` (Stribeck speed 5 to 15 %
  of ``v_peak``), viscous friction 1 to 5 % of ``F_max`` at ``v_peak``;
* limits: voltage 24 to 60 V (at least ``3 R i_max``), current 5 to 20 A, motor speed
  (40 % of the members) 50 to 90 % of the motion's estimated peak speed ``v_peak`` (the
  smaller of the top speed at the current limit and ``sqrt(distance F_max / m_eff)``);
* task: rest to rest over 0.5 to 1.5 rad (gear), 5 to 30 cm (ball screw) or 10 to 50 cm
  (belt) in minimum time, or at minimum copper loss ``R integral(i^2)`` [J] in a fixed time
  (1.6 times the member's estimated minimum time).

The kinds (transmission x task x gravity x Stribeck: 24 combinations) are dealt from a
seeded permutation, so any 24 consecutive members hold each once. The smoothing widths:
the backlash's 5 % of the deflection at ``F_max`` (at most a fifth of the gap), the
friction's 1 % of ``v_peak``.

Each member declares its problem the way a user would: :meth:`DriveMember.problem_toml` (kind
``optimal_control``, a model file and class, no solver settings: ``gtmodel solve``'s default
path) and :func:`write_problem` (the problem file and the model module it loads, into a folder).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError
from gtmodel.modeling.components.component import Component, Parameter, connect
from gtmodel.modeling.library import electrical as el
from gtmodel.modeling.library import rotational as rot
from gtmodel.modeling.library import translational as tr
from gtmodel.modeling.simulation.model import Model
from gtmodel.modeling.structure.index_reduction import structural_simplify

__all__ = ["DriveMember", "GravityTorque", "GravityForce", "drive_family", "write_problem", "spring_force",
           "TRANSMISSIONS", "TASKS"]

#: The transmissions of the family.
TRANSMISSIONS = ("gear", "ball_screw", "belt")
#: The tasks: rest to rest in minimum time, or at minimum copper loss in a fixed time.
TASKS = ("min_time", "min_energy")
G_ACC = 9.81  # m/s^2
#: The modes of the transmissions are kept within [F_MODE_LO, F_MODE_HI] Hz.
F_MODE_LO, F_MODE_HI = 4.0, 200.0
#: The gear's backlash is the arc of 0.02 to 0.2 mm at this radius [m].
GEAR_ARC_RADIUS = 0.1


class GravityTorque(Component):
    """Gravity on a pendulum hinged at a horizontal axis: ``flange.tau = mgl sin(flange.phi)``.

    ``phi = 0`` hangs down; the torque pulls the link back towards it.

    Parameters
    ----------
    mgl : float, optional
        Mass times gravity times hinge to centre of mass [N m], >= 0 (default 1).
    **modifiers
        Further modifiers, see :class:`~gtmodel.modeling.components.component.Component`.
    """

    mgl = Parameter(1.0, unit="N.m", description="m g l of the pendulum", lb=0.0)
    flange = rot.Flange_b("flange of the link")

    def equations(self) -> None:
        """The gravity torque on the flange."""
        self.equation(self.flange.tau, self.mgl * ca.sin(self.flange.phi), name="gravity")


class GravityForce(Component):
    """Gravity on a vertical axis (positive up): ``flange.f = mg``, pulling the flange down.

    Parameters
    ----------
    mg : float, optional
        Weight [N], >= 0 (default 1).
    **modifiers
        Further modifiers, see :class:`~gtmodel.modeling.components.component.Component`.
    """

    mg = Parameter(1.0, unit="N", description="weight of the load", lb=0.0)
    flange = tr.Flange_b("flange of the load")

    def equations(self) -> None:
        """The weight on the flange."""
        self.equation(self.flange.f, self.mg, name="gravity")


def _softplus(z: float, eps: float) -> float:
    """``eps log(1 + exp(z / eps))``, overflow-free."""
    return eps * float(np.logaddexp(0.0, z / eps))


def spring_force(x: float, c: float, b: float, smoothing: float) -> float:
    """The backlash's elastic force at rest for a deflection ``x`` (motor side ahead of the load) [N or N m].

    ``c (softplus(x - b/2) - softplus(-x - b/2))`` with ``softplus(z) = eps log(1 + exp(z / eps))``,
    ``eps = smoothing``: the smooth form of the dead zone ``c (x - sign(x) b/2)`` outside the gap.

    Parameters
    ----------
    x : float
        Deflection [m or rad].
    c : float
        Stiffness [N/m or N m/rad].
    b : float
        Total gap [m or rad].
    smoothing : float
        Smoothing width [m or rad], > 0.

    Returns
    -------
    float
        The force [N] or torque [N m] the element passes to the load.
    """
    return c * (_softplus(x - b / 2, smoothing) - _softplus(-x - b / 2, smoothing))


def _deflection(force: float, c: float, b: float, smoothing: float) -> float:
    """The deflection at which :func:`spring_force` passes ``force`` (bisection: the law is monotonic)."""
    lo, hi = -b - abs(force) / c - 50 * smoothing, b + abs(force) / c + 50 * smoothing
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if spring_force(mid, c, b, smoothing) < force:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@dataclass(frozen=True)
class DriveMember:
    """One drive of the family: plain numbers in SI units, the model and the problem they declare.

    Parameters
    ----------
    name : str
        Unique within the family, e.g. ``"drive0_07_belt_min_time"``.
    seed, index : int
        The family's seed and the member's place in it.
    transmission : str
        ``"gear"``, ``"ball_screw"`` or ``"belt"``.
    task : str
        ``"min_time"`` or ``"min_energy"``.
    R, L, k, Jm : float
        Armature resistance [Ohm], inductance [H], motor constant [N m/A], rotor inertia [kg m^2].
    ratio : float
        Gear ratio n (motor / load angle) [1], the ball screw's lead [m per turn] or the pulley's radius [m].
    c, d : float
        Transmission stiffness [N m/rad (gear, at the load) or N/m] and damping [N m s/rad or N s/m].
    backlash, backlash_smoothing : float
        Total gap and its smoothing width [rad (gear) or m].
    load : float
        Load inertia [kg m^2] (gear) or mass [kg].
    gravity : float
        ``m g l`` [N m] of the pendulum (gear) or the weight ``m g`` [N] of a vertical axis; 0 without gravity.
    Fc, Fs, vs, dv, friction_smoothing : float
        Coulomb and Stribeck friction [N m or N], Stribeck speed [rad/s or m/s], viscous coefficient
        [N m s/rad or N s/m], smoothing speed [rad/s or m/s]: ``f = (Fc + Fs exp(-(v/vs)^2)) tanh(v/smoothing) + dv v``.
    vmax, imax : float
        Voltage [V] and current [A] limits (symmetric).
    wmax : float or None
        Motor speed limit [rad/s] (symmetric), None for none.
    distance : float
        The load's displacement, rest to rest [rad (gear) or m].
    final_time : float
        The fixed time (min_energy) or the initial guess of the free one (min_time) [s].
    time_bounds : tuple of float
        Bounds of the free final time [s] (min_time).
    """

    name: str
    seed: int
    index: int
    transmission: str
    task: str
    R: float
    L: float
    k: float
    Jm: float
    ratio: float
    c: float
    d: float
    backlash: float
    backlash_smoothing: float
    load: float
    gravity: float
    Fc: float
    Fs: float
    vs: float
    dv: float
    friction_smoothing: float
    vmax: float
    imax: float
    wmax: float | None
    distance: float
    final_time: float
    time_bounds: tuple[float, float]

    @property
    def rotational(self) -> bool:
        """True for a gear (the load's coordinate an angle [rad]), False for a linear axis [m]."""
        return self.transmission == "gear"

    @property
    def G(self) -> float:  # noqa: N802 - the field's symbol
        """The load's displacement per motor radian [rad/rad or m/rad]."""
        if self.transmission == "gear":
            return 1.0 / self.ratio
        if self.transmission == "ball_screw":
            return self.ratio / (2.0 * math.pi)
        return self.ratio

    def parameters(self) -> dict[str, Any]:
        """The member's fields as plain JSON data (the reference's input).

        Returns
        -------
        dict
            Every field; ``time_bounds`` as a list.
        """
        out = dataclasses.asdict(self)
        out["time_bounds"] = list(self.time_bounds)
        return out

    def parameter_hash(self) -> str:
        """A hash of :meth:`parameters` (a cached reference of other numbers is stale).

        Returns
        -------
        str
            The first 16 hex digits of the SHA-256 of the sorted JSON.
        """
        return hashlib.sha256(json.dumps(self.parameters(), sort_keys=True).encode()).hexdigest()[:16]

    def holding_force(self, q: float) -> float:
        """The gravity force [N] or torque [N m] the transmission holds with the load at rest at ``q``.

        Parameters
        ----------
        q : float
            The load's position [rad or m].

        Returns
        -------
        float
        """
        return self.gravity * math.sin(q) if self.rotational else self.gravity

    def rest_state(self, q: float) -> dict[str, float]:
        """The state at rest with the load at ``q``: the problem's boundary values by model name.

        Parameters
        ----------
        q : float
            The load's position [rad or m].

        Returns
        -------
        dict of str to float
            ``ind.i`` [A], ``rotor.phi`` [rad], ``rotor.w``, ``load.phi``/``load.s``, ``load.w``/``load.v``:
            the current holds gravity, the transmission deflected by it (:func:`spring_force`).
        """
        force = self.holding_force(q)
        delta = _deflection(force, self.c, self.backlash, self.backlash_smoothing) if force else 0.0
        pos, vel = ("load.phi", "load.w") if self.rotational else ("load.s", "load.v")
        return {"ind.i": self.G * force / self.k, "rotor.phi": (q + delta) / self.G, "rotor.w": 0.0, pos: q, vel: 0.0}

    def component(self) -> Component:
        """The drive as a component composed from the library (a class made for this member).

        Returns
        -------
        Component
            Its sub-components as in the module's docstring.
        """
        parts: dict[str, Any] = {
            "src": el.SignalVoltage(), "gnd": el.Ground(), "r": el.Resistor(R=self.R), "ind": el.Inductor(L=self.L),
            "emf": el.EMF(k=self.k), "rotor": rot.Inertia(J=self.Jm)}
        dom = rot if self.rotational else tr
        if self.rotational:
            parts["gear"] = rot.IdealGear(ratio=self.ratio)
            parts["load"] = rot.Inertia(J=self.load)
            friction = rot.Friction(Fc=self.Fc, Fs=self.Fs, ws=self.vs, dv=self.dv, smoothing=self.friction_smoothing)
        else:
            parts["wheel"] = rot.IdealRollingWheel(radius=self.G)
            parts["load"] = tr.Mass(m=self.load)
            friction = tr.Friction(Fc=self.Fc, Fs=self.Fs, vs=self.vs, dv=self.dv, smoothing=self.friction_smoothing)
        parts["backlash"] = dom.ElastoBacklash(c=self.c, d=self.d, b=self.backlash, smoothing=self.backlash_smoothing)
        parts["friction"] = friction
        parts["fixed"] = dom.Fixed()
        if self.gravity:
            parts["gravity"] = GravityTorque(mgl=self.gravity) if self.rotational else GravityForce(mg=self.gravity)
        rotational, gravity = self.rotational, bool(self.gravity)

        def equations(comp: Component) -> None:
            connect(comp.src.p, comp.r.p)
            connect(comp.r.n, comp.ind.p)
            connect(comp.ind.n, comp.emf.p)
            connect(comp.emf.n, comp.src.n)
            connect(comp.src.n, comp.gnd.p)
            connect(comp.emf.flange, comp.rotor.flange_a)
            if rotational:
                connect(comp.rotor.flange_b, comp.gear.flange_a)
                connect(comp.gear.flange_b, comp.backlash.flange_a)
            else:
                connect(comp.rotor.flange_b, comp.wheel.flangeR)
                connect(comp.wheel.flangeT, comp.backlash.flange_a)
            connect(comp.backlash.flange_b, comp.load.flange_a)
            connect(comp.load.flange_b, comp.friction.flange_b)
            connect(comp.friction.flange_a, comp.fixed.flange)
            if gravity:
                connect(comp.load.flange_b, comp.gravity.flange)

        doc = f"Drive family member {self.name} (gtmodel.modeling.library.drive_family)."
        cls = type("DriveFamilyMember", (Component,), {**parts, "equations": equations, "__doc__": doc})
        return cls()

    def build(self) -> Model:
        """The member's model, reduced to index 1 (:func:`~gtmodel.modeling.structural_simplify`).

        Returns
        -------
        Model
            Input ``src.v`` [V]; five states (the current, the motor's angle and speed, the load's
            position and speed, under the names reduction keeps).
        """
        return structural_simplify(self.component().to_model(self.name))

    def problem(self, model_file: str | None = None) -> dict[str, Any]:
        """The optimal-control problem as a problem file's tables (``gtmodel solve``'s defaults otherwise).

        Parameters
        ----------
        model_file : str, optional
            The model module, relative to the problem file (default ``"<name>.py"``, :func:`write_problem`).

        Returns
        -------
        dict
            ``name``, ``kind``, ``description``, ``model``, ``optimization``, ``boundary``, ``bounds``.
        """
        lo, hi = self.time_bounds
        if self.task == "min_time":
            objective = "final_time"
            final_time: dict[str, Any] = {"free": True, "initial_guess": self.final_time, "bounds": [lo, hi]}
        else:
            objective = f"{self.R!r} * integral(ind_i^2)"
            final_time = {"free": False, "value": self.final_time}
        bounds: dict[str, list[float]] = {"src.v": [-self.vmax, self.vmax], "ind.i": [-self.imax, self.imax]}
        if self.wmax is not None:
            bounds["rotor.w"] = [-self.wmax, self.wmax]
        what = "minimum time" if self.task == "min_time" else "minimum copper loss in a fixed time"
        return {
            "name": self.name, "kind": "optimal_control",
            "description": f"Drive family member {self.index} (seed {self.seed}, {self.transmission}): {what}, rest to rest",
            "model": {"file": model_file or f"{self.name}.py", "class": "Member"},
            "optimization": {"objective": objective, "final_time": final_time},
            "boundary": {"start": self.rest_state(0.0), "final": self.rest_state(self.distance)},
            "bounds": bounds,
        }

    def problem_toml(self, model_file: str | None = None) -> str:
        """:meth:`problem` as the text of a TOML problem file.

        Parameters
        ----------
        model_file : str, optional
            As :meth:`problem`.

        Returns
        -------
        str
        """
        doc = self.problem(model_file)
        lines = [f"# Drive family member {self.name}: written by gtmodel.modeling.library.drive_family.write_problem",
                 f"name = {_toml(doc['name'])}", f"kind = {_toml(doc['kind'])}", f"description = {_toml(doc['description'])}", ""]
        for table in ("model", "optimization", "optimization.final_time", "boundary.start", "boundary.final", "bounds"):
            part: Any = doc
            for key in table.split("."):
                part = part[key]
            lines.append(f"[{table}]")
            lines += [f"{_toml(k) if '.' in k else k} = {_toml(v)}" for k, v in part.items() if not isinstance(v, dict)]
            lines.append("")
        return "\n".join(lines)


def _toml(value: Any) -> str:
    """A TOML value: a string, a finite number, or a list of them."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return repr(float(value))


def write_problem(member: DriveMember, folder: str | Path) -> Path:
    """Write a member's problem file and the model module it loads, ready for ``gtmodel solve``.

    Parameters
    ----------
    member : DriveMember
        The member.
    folder : str or pathlib.Path
        Where to write ``<name>.toml`` and ``<name>.py`` (created if needed).

    Returns
    -------
    pathlib.Path
        The problem file.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    fields = member.parameters()
    fields["time_bounds"] = tuple(fields["time_bounds"])
    (folder / f"{member.name}.py").write_text(
        f'"""Drive family member {member.name}: written by gtmodel.modeling.library.drive_family.write_problem."""\n\n'
        "from gtmodel.modeling.library.drive_family import DriveMember\n\n"
        f"MEMBER = DriveMember(**{fields!r})\n\n\n"
        "class Member:\n"
        '    """The member\'s model (the problem file\'s class)."""\n\n'
        "    def build(self):\n"
        '        """The reduced model."""\n'
        "        return MEMBER.build()\n", encoding="utf-8")
    path = folder / f"{member.name}.toml"
    path.write_text(member.problem_toml(), encoding="utf-8")
    return path


def _log_uniform(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def _sig(x: float, digits: int = 4) -> float:
    """``x`` rounded to ``digits`` significant digits (readable problem files)."""
    return float(f"{x:.{digits}g}")


def _member(rng: np.random.Generator, seed: int, index: int, kind: tuple[str, str, bool, bool]) -> DriveMember:
    """One member of the kind ``(transmission, task, gravity, stribeck)``, its numbers drawn from ``rng``."""
    transmission, task, gravity, stribeck = kind
    Jm = _sig(_log_uniform(rng, 2e-5, 4e-4))
    k = _sig(_log_uniform(rng, 0.04, 0.25))
    R = _sig(_log_uniform(rng, 0.3, 2.5))
    L = _sig(R * rng.uniform(0.5e-3, 2.5e-3))
    imax = _sig(rng.uniform(5.0, 20.0), 3)
    vmax = float(max(rng.choice([24.0, 36.0, 48.0, 60.0]), math.ceil(3.0 * R * imax)))
    if transmission == "gear":
        ratio = _sig(_log_uniform(rng, 5.0, 80.0), 3)
        G = 1.0 / ratio
        load = _sig(Jm / G**2 * _log_uniform(rng, 0.5, 5.0))
        c = _log_uniform(rng, 1e2, 1e5)
        backlash = rng.uniform(0.02e-3, 0.2e-3) / GEAR_ARC_RADIUS
        distance = _sig(rng.uniform(0.5, 1.5), 3)
    else:
        if transmission == "ball_screw":
            ratio = float(rng.choice([0.005, 0.01, 0.016, 0.02]))
            G = ratio / (2 * math.pi)
            load, c = Jm / G**2 * _log_uniform(rng, 0.3, 3.0), _log_uniform(rng, 1e6, 1e8)
            distance = _sig(rng.uniform(0.05, 0.3), 3)
        else:
            ratio = _sig(rng.uniform(0.01, 0.03), 3)
            G = ratio
            load, c = Jm / G**2 * _log_uniform(rng, 1.0, 10.0), _log_uniform(rng, 1e3, 1e6)
            distance = _sig(rng.uniform(0.1, 0.5), 3)
        backlash = rng.uniform(0.02e-3, 0.2e-3)
        load = _sig(load)
    f_max = k * imax / G
    if rng.uniform() < 1.0 / 3.0:
        backlash = 0.0
    m_red = 1.0 / (1.0 / load + G**2 / Jm)  # the mode's reduced mass in the load's coordinate
    c = _sig(min(max(c, (2 * math.pi * F_MODE_LO) ** 2 * m_red), (2 * math.pi * F_MODE_HI) ** 2 * m_red), 3)
    d = _sig(2.0 * rng.uniform(0.02, 0.2) * math.sqrt(c * m_red), 3)
    backlash = _sig(backlash, 3)
    eps_b = 0.05 * f_max / c
    if backlash > 0:
        eps_b = min(eps_b, backlash / 5.0)
    weight = 0.0
    if gravity:
        if transmission == "gear":
            weight = _sig(rng.uniform(0.1, 0.3) * f_max, 3)
        else:
            if load * G_ACC > 0.35 * f_max:  # a vertical axis the motor can lift briskly: a lighter load
                load = _sig(0.35 * f_max / G_ACC)
            weight = _sig(load * G_ACC, 4)
    m_eff = load + Jm / G**2  # the drive's inertia in the load's coordinate
    w_volt = (vmax - R * imax) / k  # the motor's top speed at the current limit
    v_peak = min(G * w_volt, math.sqrt(distance * (f_max - weight) / m_eff))  # the motion's peak speed, roughly
    wmax = _sig(rng.uniform(0.5, 0.9) * v_peak / G, 3) if rng.uniform() < 0.4 else None
    Fc = _sig(rng.uniform(0.02, 0.1) * f_max, 3)
    Fs = _sig(rng.uniform(0.2, 0.6) * Fc, 3) if stribeck else 0.0
    vs = _sig(rng.uniform(0.05, 0.15) * v_peak, 3)
    dv = _sig(rng.uniform(0.01, 0.05) * f_max / v_peak, 3)
    # the estimated minimum time: bang-bang at the current limit up to the speed the voltage (or wmax) allows,
    # plus one period of the transmission's mode
    accel = (f_max - Fc - Fs - weight) / m_eff
    v_lim = G * (w_volt if wmax is None else min(wmax, w_volt))
    t_est = distance / v_lim + v_lim / accel if distance >= v_lim**2 / accel else 2.0 * math.sqrt(distance / accel)
    t_est += 2 * math.pi * math.sqrt(m_red / c)
    if task == "min_time":
        final_time, bounds = _sig(1.2 * t_est, 3), (_sig(0.3 * t_est, 3), _sig(10.0 * t_est, 3))
    else:
        final_time, bounds = _sig(1.6 * t_est, 3), (0.0, 0.0)
    name = f"drive{seed}_{index:02d}_{transmission}_{task}"
    return DriveMember(
        name=name, seed=seed, index=index, transmission=transmission, task=task, R=R, L=L, k=k, Jm=Jm, ratio=ratio, c=c, d=d,
        backlash=backlash, backlash_smoothing=_sig(eps_b, 3), load=load, gravity=weight, Fc=Fc, Fs=Fs, vs=vs, dv=dv,
        friction_smoothing=_sig(0.01 * v_peak, 3), vmax=vmax, imax=imax, wmax=wmax, distance=distance,
        final_time=final_time, time_bounds=bounds)


def drive_family(count: int = 40, seed: int = 0) -> list[DriveMember]:
    """The family: ``count`` members drawn with the seed ``seed`` (the same members for the same seed).

    Parameters
    ----------
    count : int, optional
        Number of members, >= 1 (default 40).
    seed : int, optional
        Seed of NumPy's ``default_rng`` (default 0).

    Returns
    -------
    list of DriveMember
        In order of ``index``; names unique.

    Raises
    ------
    InputError
        If ``count`` < 1 or ``seed`` < 0.
    """
    if int(count) != count or count < 1:
        raise InputError(f"drive_family: count must be an integer >= 1, got {count!r}")
    if int(seed) != seed or seed < 0:
        raise InputError(f"drive_family: seed must be an integer >= 0, got {seed!r}")
    rng = np.random.default_rng(int(seed))
    kinds = [(t, task, g, s) for t in TRANSMISSIONS for task in TASKS for g in (False, True) for s in (False, True)]
    members = []
    for index in range(int(count)):
        if index % len(kinds) == 0:
            order = rng.permutation(len(kinds))
        members.append(_member(rng, int(seed), index, kinds[order[index % len(kinds)]]))
    return members
