"""FMU export checked by an independent FMI tool: FMPy validates and simulates each FMU.

FMPy (its own CVODE for model exchange, the FMU's embedded RK4 for co-simulation) is the
independent side; gtmodel's own ``Model.simulate`` (IDAS) the reference.
"""

from __future__ import annotations

import importlib.util
import re
import zipfile

import numpy as np
import pytest

from gtmodel.errors import GtModelError, InputError, ModelError
from gtmodel.exchange import export_fmu
from gtmodel.modeling import Model

fmpy = pytest.importorskip("fmpy")
from fmpy.validation import validate_fmu  # noqa: E402

from tests.conftest import REPO  # noqa: E402


def _cart_pendulum() -> Model:
    spec = importlib.util.spec_from_file_location("cart_pendulum_model", REPO / "models" / "cart_pendulum.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.CartPendulum()


def _compare(fmu, model, names, start, inputs, stop, n=11, fmi_type="ModelExchange", step=None, rtol=1e-11):
    """Largest relative deviation of FMPy's trajectories from gtmodel's simulate()."""
    t = np.linspace(0.0, stop, n)
    flat = model.to_model() if hasattr(model, "to_model") else model
    u = None
    if inputs:
        u = np.array([inputs[k] for k in sorted(inputs)]) if len(inputs) > 1 else next(iter(inputs.values()))
    ref = flat.simulate(t, x0=start or None, u=u, rtol=rtol, atol=rtol * 0.1).to_dataframe()
    kw = dict(relative_tolerance=1e-11) if fmi_type == "ModelExchange" else dict(step_size=step)
    res = fmpy.simulate_fmu(str(fmu), stop_time=stop, output_interval=stop / (n - 1) if step is None else step,
                            start_values={**(start or {}), **inputs}, output=names, fmi_type=fmi_type, **kw)
    idx = [int(round(tk / (res["time"][1] - res["time"][0]))) for tk in t]
    return max(np.max(np.abs(res[k][idx] - ref[k].to_numpy())) / max(np.max(np.abs(ref[k].to_numpy())), 1e-12) for k in names)


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_cart_pendulum_fmu_is_valid_and_equals_gtmodel(tmp_path, version):
    model = _cart_pendulum()
    fmu = export_fmu(model, tmp_path / "cp.fmu", version=version)
    assert validate_fmu(str(fmu.path)) == []
    md = fmpy.read_model_description(str(fmu.path))
    params = {v.name: v for v in md.modelVariables if v.causality == "parameter"}
    assert params["l"].variability == "tunable" and float(params["l"].start) == 0.5
    states = {v.name: v for v in md.modelVariables if v.name == "theta"}
    assert states["theta"].initial == "exact" and states["theta"].unit == "rad"
    with zipfile.ZipFile(fmu.path) as zf:  # a source FMU with a binary for this platform
        names = zf.namelist()
    assert any(n.startswith("sources/") and n.endswith(".c") for n in names)
    assert any(n.startswith(f"binaries/{fmu.platform}/") for n in names)
    dev = _compare(fmu.path, model, ["theta", "s", "tip_x"], {"theta": 0.5}, {"F": 0.3}, 2.0)
    assert dev < 1e-6, dev
    if version == "2.0":  # the parameter is tunable: FMPy's value reaches the equations
        res = fmpy.simulate_fmu(str(fmu.path), stop_time=1.0, start_values={"theta": 0.5, "l": 1.0}, output=["theta"],
                                relative_tolerance=1e-11, output_interval=0.1)
        ref = model.simulate(np.linspace(0, 1, 11), x0={"theta": 0.5}, u=0.0, p={"l": 1.0}, rtol=1e-11, atol=1e-12)
        assert np.max(np.abs(res["theta"] - ref.x["theta"])) < 1e-6


@pytest.mark.parametrize(("version", "interfaces"), [
    ("2.0", ("CoSimulation",)),
    pytest.param("3.0", ("ModelExchange", "CoSimulation"), marks=pytest.mark.slow),  # default-run budget
])
def test_cart_pendulum_co_simulation_error_is_of_rk4_order(tmp_path, version, interfaces):
    model = _cart_pendulum()
    fmu = export_fmu(model, tmp_path / "cp_cs.fmu", version=version, interface="cs", step=2e-3)
    assert fmu.interfaces == interfaces and validate_fmu(str(fmu.path)) == []
    devs = [_compare(fmu.path, model, ["theta"], {"theta": 0.5}, {}, 1.0, fmi_type="CoSimulation", step=h)
            for h in (0.02, 0.01)]
    # embedded step min(2e-3, communication step): error h^4, well under 1e-6 at h = 2 ms
    assert devs[0] < 1e-6 and devs[1] < 1e-6


def _ball(e: float = 0.8, g: float = 9.81) -> Model:
    m = Model("ball")
    h, v = m.state("h", start=1.0, unit="m"), m.state("v", unit="m/s")
    m.equation(m.der(h), v)
    m.equation(m.der(v), -g)
    m.when(-h, reinit={v: -e * v, h: 0.0}, name="impact")
    return m


def test_bouncing_ball_events_in_model_exchange_and_co_simulation(tmp_path):
    # reference: the impact times in closed form, t1 = sqrt(2 h0 / g), then flights 2 e^k v1 / g
    fmu = export_fmu(_ball(), tmp_path / "ball.fmu", step=1e-3)
    assert validate_fmu(str(fmu.path)) == [] and fmpy.read_model_description(str(fmu.path)).numberOfEventIndicators == 1
    e, g = 0.8, 9.81
    t1, v1 = np.sqrt(2.0 / g), np.sqrt(2.0 * g)
    impacts = t1 + np.concatenate([[0.0], np.cumsum([2.0 * e**k * v1 / g for k in range(1, 4)])])

    def exact_h(t):
        k = np.searchsorted(impacts, t) - 1
        if k < 0:
            return 1.0 - 0.5 * g * t**2
        vk, tau = e ** (k + 1) * v1, t - impacts[k]
        return vk * tau - 0.5 * g * tau**2

    errors = {}
    for kind, kw in (("ModelExchange", dict(relative_tolerance=1e-10)), ("CoSimulation", {})):
        res = fmpy.simulate_fmu(str(fmu.path), stop_time=2.5, output_interval=0.01, output=["h"], fmi_type=kind, **kw)
        errors[kind] = np.max(np.abs(res["h"] - [exact_h(t) for t in res["time"]]))
    assert max(errors.values()) < 1e-6, errors


@pytest.mark.slow
@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_composed_drive_axis_fmu_equals_gtmodel(tmp_path, version):
    from gtmodel.modeling.library.drive import CompliantDriveAxis

    axis = CompliantDriveAxis()
    fmu = export_fmu(axis, tmp_path / "axis.fmu", version=version)
    assert fmu.model.algebraic > 0 and validate_fmu(str(fmu.path)) == []
    md = fmpy.read_model_description(str(fmu.path))
    kp = next(v for v in md.modelVariables if v.name == "servo.kp")
    assert kp.unit == "N.m/rad" and kp.description == "position-loop stiffness Kv*Kp"
    # gtmodel's index-reduced IDAS run fails at rtol 1e-11 (too much work): 1e-9
    dev = _compare(fmu.path, axis, ["cart.s", "servo.phi"], None, {"servo.phi_ref": 1.0}, 0.1, rtol=1e-9)
    assert dev < 1e-6, dev


@pytest.mark.slow
@pytest.mark.parametrize("robot", ["L1"])
def test_robot_dynamics_fmu_equals_gtmodel(tmp_path, robot):
    from gtmodel.robots.model import gantry_tau_model

    model = gantry_tau_model(robot, states="cart")
    fmu = export_fmu(model, tmp_path / f"{robot}.fmu", version="2.0", interface="me")
    assert validate_fmu(str(fmu.path)) == []
    tau = {"tau[0]": 100.0, "tau[1]": -50.0, "tau[2]": 20.0}
    dev = _compare(fmu.path, model, ["q[0]", "q[1]", "q_dot[2]"], None, tau, 0.2)
    assert dev < 1e-6, dev


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        (dict(version="1.0"), InputError, "version: expected one of 2.0, 3.0"),
        (dict(interface="xx"), InputError, "interface: expected one of"),
        (dict(step=0.0), InputError, "step: expected a positive"),
        (dict(out="model.zip"), InputError, r"model.zip: the file name must end in \.fmu"),
    ],
)
def test_export_bad_arguments(tmp_path, kwargs, error, match):
    out = tmp_path / kwargs.pop("out", "m.fmu")
    with pytest.raises(error, match=match):
        export_fmu(_cart_pendulum(), out, **kwargs)


def test_export_rejects_models_it_cannot_carry(tmp_path):
    with pytest.raises(InputError, match="'ball' has when-clauses: events are exported with FMI 2.0"):
        export_fmu(_ball(), tmp_path / "b.fmu", version="3.0")
    moded = _ball()
    mode = moded.mode("stuck", 0.0)
    moded.when(moded.variables("state")["v"], assign={mode: 1.0}, name="stick")
    with pytest.raises(ModelError, match="'ball': modes and assign/initial when-clauses are not exported"):
        export_fmu(moded, tmp_path / "b.fmu")
    m = Model("static")
    m.parameter("k", 1.0)
    z = m.algebraic("z")
    m.equation(z, 1.0)
    with pytest.raises(ModelError, match="'static' has no state"):
        export_fmu(m, tmp_path / "s.fmu")
    with pytest.raises(GtModelError, match="expected a gtmodel Model or Component, got str"):
        export_fmu("not a model", tmp_path / "s.fmu")


@pytest.mark.slow
@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_source_fmu_is_rebuilt_by_fmpy(tmp_path, version):
    # a user on another platform rebuilds from the sources: FMPy's own CMake build of them
    # (its headers, not gtmodel's compiler call) gives the same trajectory
    from fmpy.build import build_platform_binary

    model = _cart_pendulum()
    fmu = export_fmu(model, tmp_path / "src.fmu", version=version, binary=False)
    assert fmu.platform == ""
    folder = tmp_path / "unzipped"
    with zipfile.ZipFile(fmu.path) as zf:
        zf.extractall(folder)
    build_platform_binary(folder)
    res = fmpy.simulate_fmu(str(folder), stop_time=1.0, start_values={"theta": 0.5}, output=["theta"],
                            fmi_type="ModelExchange", relative_tolerance=1e-11, output_interval=0.1)
    ref = model.simulate(np.linspace(0.0, 1.0, 11), x0={"theta": 0.5}, u=0.0, rtol=1e-11, atol=1e-12)
    assert np.max(np.abs(res["theta"] - ref.x["theta"])) < 1e-7


def test_a_flattened_component_exports_the_units_descriptions_and_parameters_of_the_component(tmp_path):
    """``export_fmu(C().to_model())`` states what ``export_fmu(C())`` states (reference: the
    component's own export and its ``describe()`` table)."""
    from gtmodel.modeling.library.drive import CompliantDriveAxis

    axis = CompliantDriveAxis()
    texts = [zipfile.ZipFile(export_fmu(source, tmp_path / f"{i}.fmu", interface="me", binary=False).path)
             .read("modelDescription.xml").decode() for i, source in enumerate((axis, axis.to_model("CompliantDriveAxis")))]
    strip = [re.sub(r'guid="[^"]*"', "", t) for t in texts]
    assert strip[0] == strip[1]
    assert 'name="servo.kp"' in strip[1] and 'unit="N.m/rad"' in strip[1] and "position-loop stiffness Kv*Kp" in strip[1]


@pytest.mark.parametrize(("name", "version"), [("cart__pole", "3.0"), ('a"<b>&c', "2.0"), ("my-model", "2.0")])
def test_a_hostile_model_name_exports_and_imports(tmp_path, name, version):
    """CasADi refuses ``cart__pole`` as a Function name; the FMU's identifier is the one mapping
    (``casadi_name``), the XML quotes the name. Reference: x = exp(-t) after the round trip."""
    from gtmodel.exchange import import_fmu, simulate_explicit
    from gtmodel.modeling import Model

    m = Model(name)
    x = m.state("x", start=1.0)
    m.equation(m.der(x), -x)
    imported = import_fmu(export_fmu(m, tmp_path / "n.fmu", version=version, interface="me").path)
    assert imported.model.name == name
    sim = simulate_explicit(imported.model, np.linspace(0.0, 1.0, 3), rtol=1e-11, atol=1e-13)
    np.testing.assert_allclose(sim.x["x"], np.exp(-np.linspace(0.0, 1.0, 3)), rtol=1e-8)


HOSTILE_NAME = ('p"; } int system(const char *); __attribute__((constructor)) static void pwn(void) '
                '{ system("touch PWNED"); } const char *gt_q(void) { return "')
HOSTILE_UNIT = "m\"/><x a='1'/>]]>\x01\t&amp;\u2028"


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_hostile_names_and_units_are_xml_text(tmp_path, version):
    """The issue's model name and a unit holding markup and a control character: the description
    parses (fmpy, expat) with the name and unit as given, the control character as U+FFFD."""
    m = Model(HOSTILE_NAME)
    x = m.state("x", start=1.0, unit=HOSTILE_UNIT)
    m.equation(m.der(x), -x)
    fmu = export_fmu(m, tmp_path / "n.fmu", version=version, interface="me", binary=False)
    md = fmpy.read_model_description(str(fmu.path))
    assert md.modelName == HOSTILE_NAME
    shown = HOSTILE_UNIT.replace("\x01", "\ufffd")
    assert {u.name for u in md.unitDefinitions} == {shown, f"{shown}/s"}  # the state's and its derivative's
    assert re.fullmatch(r"[A-Za-z0-9_]+", md.coSimulation.modelIdentifier if md.coSimulation else md.modelExchange.modelIdentifier)
