"""The library under the Modelica Standard Library's class paths (issue 68, item 3; gtmodel.exchange.msl).

A drive written with MSL paths (motor, gear, compliant shaft, load) loads and solves a
minimum-time problem, agreeing with the same drive written as equations by hand; the
translational and block classes simulate as SciPy integrates their equations; a class the
shipped package does not hold is refused with the file, line and class (exit 2).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gtmodel.cli import main
from gtmodel.errors import InputError
from gtmodel.exchange.modelica import load_modelica
from gtmodel.exchange.msl import MSL_SOURCE, msl_classes, prepare
from gtmodel.exchange.optimica import OptimicaError, load_optimica
from gtmodel.problems.optimica_run import run_optimica

pytest.importorskip("pymoca")

DATA = Path(__file__).parent / "data"
MSL_DRIVE = Path(__file__).resolve().parents[2] / "problems" / "optimica" / "msl_drive_min_time.mop"

#: The classes issue 68 names, under their MSL paths.
NAMED = [
    "Modelica.Mechanics.Rotational.Components.Inertia", "Modelica.Mechanics.Rotational.Components.Spring",
    "Modelica.Mechanics.Rotational.Components.SpringDamper", "Modelica.Mechanics.Rotational.Components.IdealGear",
    "Modelica.Mechanics.Rotational.Sources.Torque", "Modelica.Electrical.Analog.Basic.Resistor",
    "Modelica.Electrical.Analog.Basic.Inductor", "Modelica.Electrical.Analog.Basic.Ground",
    "Modelica.Electrical.Analog.Sources.SignalVoltage", "Modelica.Electrical.Analog.Basic.RotationalEMF",
    "Modelica.Electrical.Analog.Basic.EMF", "Modelica.Blocks.Sources.Constant", "Modelica.Blocks.Sources.Step",
    "Modelica.Mechanics.Translational.Components.Mass", "Modelica.Blocks.Interfaces.RealInput", "Modelica.Units.SI.Torque",
    "Modelica.Mechanics.Rotational.Components.ElastoBacklash", "Modelica.Blocks.Nonlinear.Limiter", "Modelica.Blocks.Nonlinear.DeadZone",
]


def test_the_named_classes_are_shipped():
    assert set(NAMED) <= msl_classes()
    assert "Modelica.Units.SI.Time.Angle" not in msl_classes()  # a short class (type T = ...;) nests nothing


@pytest.mark.slow  # 17 s; the default run solves the same file by docs/optimica.md's block
def test_msl_drive_solves_min_time_as_the_drive_written_by_hand(tmp_path):
    msl = run_optimica(MSL_DRIVE, "MinTime", tmp_path / "msl", plots=False)
    hand = run_optimica(DATA / "drive_equations.mop", "MinTime", tmp_path / "hand", plots=False)
    a, b = msl.summary, hand.summary
    assert a["status"] == b["status"] == "optimal" and a["verification"]["passed"] and b["verification"]["passed"]
    assert a["objective"] == pytest.approx(b["objective"], rel=1e-6)  # measured 2.3e-14 relative: T = 0.100368 s
    assert 0.09 < a["objective"] < 0.11
    names = json.loads((tmp_path / "msl" / "summary.json").read_text())["model"]["states"]
    assert {"load.phi", "load.w", "inductor.i"} <= set(names)


def test_msl_drive_model_as_loaded():
    opt = load_optimica(MSL_DRIVE, "MinTime")
    model = opt.user_model
    assert list(model.variables("input")) == ["u"]  # Modelica.Blocks.Interfaces.RealInput u: an input
    assert model.units["load.phi"] == "rad" and model.units["emf.tau"] == "N.m"  # the SI types' units
    p = opt.model.flatten().p_names  # the model as reduced to index 1 (the user's has EMF, rotor and shaft angles as states)
    assert {"gear.ratio", "shaft.c", "shaft.d", "emf.k", "resistor.R", "inductor.L", "motor.J", "load.J"} <= set(p)


def test_translational_and_block_classes_simulate_as_scipy():
    model = load_modelica(DATA / "msl_translational.mo")
    t = np.linspace(0.0, 2.0, 41)
    sim = model.simulate(t, rtol=1e-10, atol=1e-12)

    def ramp(tt):
        return 0.0 if tt < 0.1 else 2.0 * min(tt - 0.1, 0.5) / 0.5

    def rhs(tt, z):  # x = s - L/2 from the wall: x'' = F - c x - d x'; T F' = ramp - F
        x, v, f = z
        return [v, f - 4.0 * x - 0.4 * v, (ramp(tt) - f) / 0.05]

    ref = solve_ivp(rhs, (0.0, 2.0), [0.0, 0.0, 0.0], t_eval=t, rtol=1e-11, atol=1e-12, max_step=0.01)
    np.testing.assert_allclose(sim.x["mass.s"] - 0.1, ref.y[0], atol=1e-5)
    np.testing.assert_allclose(sim.outputs["y_out"], ref.y[0], atol=1e-5)  # the position sensor at flange_a


def _softplus(y, eps):
    return np.maximum(y, 0.0) + eps * np.log1p(np.exp(-np.abs(y) / eps))


@pytest.fixture(scope="module")
def rattle():
    model = load_modelica(DATA / "msl_nonsmooth.mo", "Rattle")
    t = np.linspace(0.0, 1.0, 21)
    return model, t, model.simulate(t, rtol=1e-10, atol=1e-12)


def test_nonsmooth_classes_declare_their_smoothing_widths(rattle):
    assert rattle[0].smoothing == {"limiter.smoothing": 1e-4, "deadZone.smoothing": 1e-4, "gap.smoothing": 1e-4}  # continuation's


@pytest.mark.parametrize("smooth, tol", [(True, 1e-6), (False, 2e-3)], ids=["smoothed_law", "exact_law"])
def test_nonsmooth_classes_follow_their_laws(rattle, smooth, tol):
    _, t, sim = rattle
    eps, c, d, half, J = 1e-4, 100.0, 0.5, 0.01, 0.1

    def backlash(x, w):
        if not smooth:  # the exact law: a spring-damper outside the gap
            return c * (x - np.clip(x, -half, half)) + d * w * (abs(x) > half)
        contact = 0.5 * (1 + np.tanh((x - half) / (2 * eps))) + 0.5 * (1 + np.tanh((-x - half) / (2 * eps)))
        return c * (_softplus(x - half, eps) - _softplus(-x - half, eps)) + d * w * contact

    def rhs(tt, z):  # the load on the backlash; the Sine (amplitude 2, 1 Hz) limited to [-1, 1] and dead-zoned, integrated
        u = 2.0 * np.sin(2 * np.pi * tt)
        return [z[1], -backlash(z[0], z[1]) / J, np.clip(u, -1, 1), u - np.clip(u, -1, 1)]

    ref = solve_ivp(rhs, (0.0, 1.0), [0.05, 0.0, 0.0, 0.0], t_eval=t, rtol=1e-11, atol=1e-12, max_step=1e-3)
    got = np.column_stack([sim.x["load.phi"], sim.x["limited.y"], sim.x["dead.y"]])
    np.testing.assert_allclose(got, ref.y[[0, 2, 3]].T, atol=tol)


def test_electrical_classes_charge_a_capacitor_with_rc():
    path = DATA / "msl_rc.mo"
    model = load_modelica(path, "Charge")
    t = np.linspace(0.0, 0.5, 11)
    sim = model.simulate(t, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(sim.x["capacitor.v"], 2.0 * (1.0 - np.exp(-t / 0.1)), atol=1e-7)  # U (1 - e^(-t / RC))


def test_a_file_with_its_own_modelica_package_is_left_as_it_is(tmp_path):
    text = "package Modelica\n  constant Real two = 2;\nend Modelica;\nmodel M\n  Modelica.Blocks.Interfaces.RealInput u;\nend M;\n"
    assert prepare(tmp_path / "m.mo", text) == text


def test_comments_and_strings_are_not_references(tmp_path):
    text = '// uses Modelica.Mechanics.Rotational.Components.LossyGear\nmodel M "not Modelica.Thermal.X"\n  Real x;\nend M;\n'
    assert prepare(tmp_path / "m.mo", text) == text


def test_division_in_an_equation(tmp_path):
    # pymoca 0.12 divided by MX.__div__, which CasADi 3.8 no longer has: every "/" of an equation failed
    (tmp_path / "d.mo").write_text("model D\n  parameter Real T = 0.5;\n  Real x(start = 1);\nequation\n  der(x) = -x / T;\nend D;\n")
    sim = load_modelica(tmp_path / "d.mo").simulate(np.array([0.0, 1.0]), rtol=1e-10, atol=1e-12)
    assert sim.x["x"][-1] == pytest.approx(np.exp(-2.0), rel=1e-7)


UNSUPPORTED = [
    ("Modelica.Mechanics.Rotational.Components.LossyGear gear(ratio = 2);", 3, "Modelica.Mechanics.Rotational.Components.LossyGear"),
    ("Modelica.Mechanics.MultiBody.Parts.Body body(m = 1);", 3, "Modelica.Mechanics.MultiBody.Parts.Body"),
    ("Modelica.Blocks.Sources.Trapezoid profile;", 3, "Modelica.Blocks.Sources.Trapezoid"),
    ("Modelica.Electrical.Analog.Basic.Resistor r(R = 1);\n  Modelica.Thermal.HeatTransfer.Components.HeatCapacitor h;", 4,
     "Modelica.Thermal.HeatTransfer.Components.HeatCapacitor"),
]


@pytest.mark.parametrize("decl, line, name", UNSUPPORTED, ids=["lossy_gear", "multibody", "trapezoid", "thermal_second"])
def test_unsupported_msl_class_names_file_line_and_class(tmp_path, capsys, decl, line, name):
    mo = tmp_path / "plant.mo"
    mo.write_text(f"// a plant\nmodel Plant\n  {decl}\n  Real x(start = 0);\nequation\n  der(x) = 1;\nend Plant;\n")
    with pytest.raises(InputError, match=rf"plant\.mo:{line}: unsupported Modelica Standard Library class {name} "):
        load_modelica(mo, "Plant")
    mop = tmp_path / "opt.mop"
    mop.write_text(mo.read_text() + "optimization Opt (objective = x(finalTime), startTime = 0, finalTime = 1)\n  extends Plant;\nend Opt;\n")
    with pytest.raises(OptimicaError, match=rf"opt\.mop:{line}: unsupported Modelica Standard Library class {name} "):
        load_optimica(mop, "Opt")
    assert main(["solve", str(mop), "--class", "Opt", "--out", str(tmp_path / "out"), "-q"]) == 2
    assert f"opt.mop:{line}: unsupported Modelica Standard Library class {name}" in capsys.readouterr().err


@pytest.mark.parametrize("text, line, name", [
    ("  import Modelica.Mechanics.Rotational.Components;\n  Components.LossyGear gear;\n", 3,
     "Modelica.Mechanics.Rotational.Components.LossyGear"),
    ("  import R = Modelica.Mechanics.Rotational;\n  R.Components.Inertia i(J = 1);\n  R.Sources.Brake brake;\n", 4,
     "Modelica.Mechanics.Rotational.Sources.Brake"),
    ("  import Modelica.Mechanics.Rotational.Components.LossyGear;\n", 2, "Modelica.Mechanics.Rotational.Components.LossyGear"),
], ids=["package_import", "renaming_import", "class_import"])
def test_unsupported_msl_class_through_an_import(tmp_path, text, line, name):
    path = tmp_path / "m.mo"
    path.write_text(f"model M\n{text}  Real x(start = 0);\nequation\n  der(x) = 1;\nend M;\n")
    with pytest.raises(InputError, match=rf"m\.mo:{line}: unsupported Modelica Standard Library class {name} "):
        load_modelica(path, "M")


def test_imported_msl_names_load(tmp_path):
    path = tmp_path / "m.mo"
    path.write_text("model M\n  import Modelica.Blocks.Interfaces.RealInput;\n  import C = Modelica.Constants;\n  import Modelica.Units.SI;\n"
                    "  RealInput u \"a rate [rad/s]\";\n  SI.Angle phi(start = 0);\nequation\n  der(phi) = C.pi * u;\nend M;\n")
    model = load_modelica(path, "M")
    assert list(model.variables("input")) == ["u"] and model.units["phi"] == "rad"
    sim = model.simulate(np.array([0.0, 1.0]), u=2.0, rtol=1e-10, atol=1e-12)
    assert sim.x["phi"][-1] == pytest.approx(2 * np.pi, rel=1e-9)


def test_unsupported_msl_class_in_a_mo_beside_the_mop(tmp_path):
    (tmp_path / "plant.mo").write_text("model Plant\n  Modelica.Mechanics.Rotational.Components.Brake brake;\n  Real x(start = 0);\n"
                                       "equation\n  der(x) = 1;\nend Plant;\n")
    (tmp_path / "opt.mop").write_text("optimization Opt (objective = x(finalTime), startTime = 0, finalTime = 1)\n"
                                      "  extends Plant;\nend Opt;\n")
    with pytest.raises(OptimicaError, match=r"plant\.mo:2: unsupported Modelica Standard Library class .*Components\.Brake"):
        load_optimica(tmp_path / "opt.mop", "Opt")


def test_the_shipped_package_says_where_it_comes_from():
    head = MSL_SOURCE.read_text(encoding="utf-8")[:1500]
    assert "Modelica Language" in head and "not copied" in head
