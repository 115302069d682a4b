"""The seeded drive family (``gtmodel.modeling.library.drive_family``): generator, composed models, problem files.

Independent checks: the family's numbers against the documented ranges (read from the generator's
docstring, not recomputed by it); each composed model against the member's ODE written out by hand
in ``benchmarks/drive_family_reference.py`` (plain CasADi, no gtmodel code), simulated by SciPy from
the same rest state under the same voltage step; the rest states against the ODE's own equilibrium
(its right-hand side zero); the problem file through the problem layer's own loader.
"""

from __future__ import annotations

import collections
import dataclasses
import math
import tomllib

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gtmodel.errors import InputError
from gtmodel.modeling.library.drive_family import TASKS, TRANSMISSIONS, drive_family, write_problem

from ...conftest import benchmark_module

FAMILY = drive_family()
NAMES = [m.name for m in FAMILY]
#: The default run's sample: the first member of each transmission with gravity (3); the whole family is checked
#: by the slow run (about 0.5 CPU-s a member: reduction, IDAS and SciPy).
SAMPLE = [next(m for m in FAMILY if m.transmission == t and m.gravity > 0) for t in TRANSMISSIONS]
MEMBERS = [pytest.param(m, id=m.name, marks=() if m in SAMPLE else pytest.mark.slow) for m in FAMILY]
#: The reduced models' state names -> their value from the hand ODE's states x = (i, phi_m, w_m, q, v) and G.
STATES = {"ind.i": lambda x, G: x[0], "emf.phi": lambda x, G: x[1], "rotor.phi": lambda x, G: x[1],
          "rotor.w": lambda x, G: x[2], "load.phi": lambda x, G: x[3], "load.s": lambda x, G: x[3],
          "friction.phi_rel": lambda x, G: x[3], "friction.s_rel": lambda x, G: x[3], "load.w": lambda x, G: x[4],
          "load.v": lambda x, G: x[4], "backlash.phi_rel": lambda x, G: x[3] - G * x[1],
          "backlash.s_rel": lambda x, G: x[3] - G * x[1]}


@pytest.fixture(scope="module")
def ref():
    """benchmarks/drive_family_reference.py as a module."""
    with benchmark_module("drive_family_reference") as module:
        yield module


def test_family_is_deterministic_per_seed():
    # the same seed: the same members, field by field; another seed: other numbers
    assert drive_family(40, 0) == FAMILY
    assert [m.parameters() for m in drive_family(40, 1)] != [m.parameters() for m in FAMILY]


def test_family_has_forty_members_with_unique_names():
    assert len(FAMILY) >= 40 and len(set(NAMES)) == len(NAMES)


@pytest.mark.parametrize("count, seed", [(0, 0), (2.5, 0), (3, -1)])
def test_family_refuses_bad_arguments(count, seed):
    with pytest.raises(InputError):
        drive_family(count, seed)


@pytest.mark.parametrize("kind, values", [
    ("transmission", set(TRANSMISSIONS)),
    ("task", set(TASKS)),
    ("gravity", {True, False}),
    ("stribeck", {True, False}),
    ("backlash", {True, False}),
    ("speed_limit", {True, False}),
])
def test_family_covers_every_kind(kind, values):
    # each kind of element appears with and without (the 24 combinations are dealt from a permutation)
    seen = {"transmission": lambda m: m.transmission, "task": lambda m: m.task, "gravity": lambda m: m.gravity > 0,
            "stribeck": lambda m: m.Fs > 0, "backlash": lambda m: m.backlash > 0,
            "speed_limit": lambda m: m.wmax is not None}[kind]
    assert {seen(m) for m in FAMILY} == values


def test_each_transmission_and_task_pair_has_several_members():
    counts = collections.Counter((m.transmission, m.task) for m in FAMILY)
    assert len(counts) == 6 and min(counts.values()) >= 5


@pytest.mark.parametrize("field, lo, hi", [
    ("R", 0.3, 2.5), ("k", 0.04, 0.25), ("Jm", 2e-5, 4e-4), ("imax", 5.0, 20.0), ("vmax", 24.0, 60.0 * 3),
])
def test_motor_and_limits_within_the_documented_ranges(field, lo, hi):
    values = [getattr(m, field) for m in FAMILY]
    assert lo * 0.999 <= min(values) and max(values) <= hi * 1.001


def test_stiffness_spans_the_range_and_modes_stay_solvable():
    # stiffness 1e2 to 1e8 in its units: the family reaches below 1e3 and above 1e7; every transmission mode
    # (its reduced mass) between 4 and 200 Hz, the electrical time constant 0.5 to 2.5 ms
    c = np.array([m.c for m in FAMILY])
    m_red = np.array([1.0 / (1.0 / m.load + m.G**2 / m.Jm) for m in FAMILY])
    f = np.sqrt(c / m_red) / (2 * math.pi)
    tau = np.array([m.L / m.R for m in FAMILY])
    assert c.min() < 1e3 and c.max() > 1e7 and c.min() >= 1e2 and c.max() <= 1e8
    assert f.min() >= 4.0 * 0.99 and f.max() <= 200.0 * 1.01
    assert tau.min() >= 0.5e-3 * 0.99 and tau.max() <= 2.5e-3 * 1.01


def test_backlash_within_a_fifth_of_a_millimetre():
    # linear axes: at most 0.2 mm; gears: the arc of 0.2 mm at 0.1 m (2 mrad); a third or so without any
    gap_mm = [m.backlash * (0.1 if m.rotational else 1.0) * 1e3 for m in FAMILY]
    assert max(gap_mm) <= 0.2 * 1.001 and 0.2 <= sum(g == 0 for g in gap_mm) / len(gap_mm) <= 0.5


def test_gravity_and_friction_leave_the_drive_its_force():
    # the load's weight (or m g l) at most 35 % of the peak force k imax / G, Coulomb + Stribeck below 16 %
    f_max = np.array([m.k * m.imax / m.G for m in FAMILY])
    assert np.all(np.array([m.gravity for m in FAMILY]) <= 0.35 * f_max * 1.01)
    assert np.all(np.array([m.Fc + m.Fs for m in FAMILY]) <= 0.16 * f_max * 1.01)


def test_parameter_hash_changes_with_any_number():
    m = FAMILY[0]
    assert m.parameter_hash() == FAMILY[0].parameter_hash()
    assert dataclasses.replace(m, c=m.c * 1.0001).parameter_hash() != m.parameter_hash()


@pytest.mark.parametrize("member", MEMBERS)
def test_member_builds_and_follows_its_hand_written_ode(member, ref):
    # the composed, reduced model (5 states) from the rest state at the start under the holding voltage + 2 V for
    # 2 ms, against the hand-written ODE of the reference (SciPy, DOP853, 1e-10): the same current and speeds
    model = member.build()
    names = model.flatten().x_names
    assert len(names) == 5 and set(names) <= set(STATES)
    p = member.parameters()
    x0, _ = ref.boundary(p)
    u = p["R"] * x0[0] + 2.0
    t = np.linspace(0.0, 2e-3, 5)
    # IDAS at its default tolerances (rtol 1e-8, atol 1e-10) fails at t = 0 on the ball screws; 1e-10 both works
    sim = model.simulate(t, x0={n: STATES[n](x0, member.G) for n in names}, u=np.full((t.size, 1), u), rtol=1e-10, atol=1e-10)
    f = ref.ode(p)
    hand = solve_ivp(lambda _, y: np.asarray(f(y, u)[0]).ravel(), (0.0, t[-1]), x0, method="Radau", rtol=1e-10,
                     atol=1e-10 * np.maximum(np.abs(x0), 1.0), t_eval=t)
    got = np.array([sim.x["ind.i"], sim.x["rotor.w"]])
    np.testing.assert_allclose(got, hand.y[[0, 2]], rtol=1e-5, atol=1e-6 * max(1.0, float(np.max(np.abs(hand.y[[0, 2]])))))

@pytest.mark.parametrize("member", [m for m in SAMPLE if m.gravity > 0], ids=lambda m: m.name)
def test_rest_states_are_equilibria_of_the_hand_written_ode(member, ref):
    # the problem's boundary values (the generator's bisection on the documented law) make the ODE's right-hand
    # side zero under the holding voltage R i
    p = member.parameters()
    f = ref.ode(p)
    worst = []
    for q, at in ((0.0, "start"), (member.distance, "final")):
        s = member.problem()["boundary"][at]
        x = np.array([s["ind.i"], s["rotor.phi"], s["rotor.w"], q, 0.0])
        rhs = np.asarray(f(x, p["R"] * x[0])[0]).ravel()
        peak = np.array([p["vmax"] / p["L"], 1.0, p["k"] * p["imax"] / p["Jm"], 1.0, p["k"] * p["imax"] / member.G / p["load"]])
        worst.append(float(np.max(np.abs(rhs) / peak)))
    assert max(worst) <= 1e-9  # each derivative against its peak (the drive at its current limit)


def test_problem_file_loads_as_gtmodel_solve_loads_it(tmp_path):
    # write_problem's files through the problem layer's loader: kind, bounds, boundary and the default path
    from gtmodel.problems import load_problem

    member = next(m for m in FAMILY if m.task == "min_energy" and m.wmax is not None)
    path = write_problem(member, tmp_path)
    doc = tomllib.loads(path.read_text())
    problem = load_problem(path)
    assert problem.kind == "optimal_control" and doc["bounds"]["rotor.w"] == [-member.wmax, member.wmax]
    assert "collocation" not in doc and "transcription" not in doc and doc["optimization"]["final_time"]["free"] is False
    assert problem.declaration.optimization.model.flatten().x_names[0] == "ind.i"
