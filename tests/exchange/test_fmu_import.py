"""FMU import: an exported gtmodel model comes back through CasADi's FMU loader and is
simulated, linearised, connected to a gtmodel model and optimised; each checked against the
native model (gtmodel's own simulate, linearize and collocation solve)."""

from __future__ import annotations

import importlib.util
import shutil
import zipfile

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.exchange import explicit_model, export_fmu
from gtmodel.exchange.explicit_ocp import solve_explicit_ocp
from gtmodel.exchange.explicit_ops import connect_explicit, linearize_explicit, simulate_explicit
from gtmodel.exchange.fmu_import import import_fmu
from gtmodel.modeling import Model, Optimization, solve
from gtmodel.modeling.simulation.linear import linearize

from tests.conftest import REPO


def _cart_pendulum() -> Model:
    spec = importlib.util.spec_from_file_location("cart_pendulum_model", REPO / "models" / "cart_pendulum.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.CartPendulum()


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("fmus")
    model = _cart_pendulum()
    return model, {v: export_fmu(model, folder / f"cp{v}.fmu", version=v, interface="me").path for v in ("2.0", "3.0")}


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_imported_fmu_simulates_and_linearises_like_the_native_model(fmus, version):
    model, paths = fmus
    imp = import_fmu(paths[version])
    assert imp.version == version and imp.derivatives == "directional derivatives of the FMU"
    assert imp.model.x_names == ["s", "v", "theta", "omega"] and imp.model.units["theta"] == "rad"
    t = np.linspace(0.0, 2.0, 21)
    sim = simulate_explicit(imp.model, t, x0={"theta": 0.5}, u={"F": 0.3}, p={"l": 0.7}, rtol=1e-11, atol=1e-12)
    ref = model.simulate(t, x0={"theta": 0.5}, u=0.3, p={"l": 0.7}, rtol=1e-11, atol=1e-12)
    assert np.max(np.abs(sim.x["theta"] - ref.x["theta"])) < 1e-8
    assert np.max(np.abs(sim.outputs["tip_x"] - ref.outputs["tip_x"])) < 1e-8
    lin, native = linearize_explicit(imp.model, x={"theta": 0.5}), linearize(model, x={"theta": 0.5})
    np.testing.assert_allclose(lin.A, native.A, atol=1e-12)
    np.testing.assert_allclose(lin.B, native.B, atol=1e-12)


def test_finite_differences_when_asked(fmus):
    model, paths = fmus
    imp = import_fmu(paths["2.0"], derivatives="finite_differences")
    assert imp.derivatives == "finite differences (CasADi)"
    lin, native = linearize_explicit(imp.model, x={"theta": 0.5}), linearize(model, x={"theta": 0.5})
    err = np.max(np.abs(lin.A - native.A))
    assert 0 < err < 1e-4  # inexact, as finite differences are


def test_fmu_connected_to_a_gtmodel_controller(fmus):
    model, paths = fmus
    pi = Model("pi")
    kp, ki = pi.parameter("kp", 20.0), pi.parameter("ki", 5.0)
    e_int, s_meas, ref = pi.state("e_int"), pi.input("s_meas"), pi.input("ref", start=0.2)
    pi.equation(pi.der(e_int), ref - s_meas)
    pi.output("F", kp * (ref - s_meas) + ki * e_int)
    links = [("plant.s", "ctrl.s_meas"), ("ctrl.F", "plant.F")]
    loop = connect_explicit({"plant": import_fmu(paths["2.0"]), "ctrl": pi}, links)
    assert loop.u_names == ["ctrl.ref"] and "plant.theta" in loop.x_names
    native = connect_explicit({"plant": model, "ctrl": pi}, links)  # the same loop without the FMU
    t = np.linspace(0.0, 3.0, 31)
    a, b = (simulate_explicit(m, t, rtol=1e-10, atol=1e-12) for m in (loop, native))
    assert np.max(np.abs(a.x["plant.s"] - b.x["plant.s"])) < 1e-8
    assert abs(a.x["plant.s"][-1]) > 0.01  # the controller moved the cart


@pytest.mark.parametrize("version", ["2.0", pytest.param("3.0", marks=pytest.mark.slow)])
def test_round_trip_ocp_reaches_the_native_optimum(fmus, version):
    model, paths = fmus
    final = {"s": 0.5, "v": 0.0, "theta": 0.0, "omega": 0.0}
    opt = Optimization(model, free_final_time=True, final_time=2.0, final_time_bounds=(0.1, 10.0))
    states, F = model.variables("state"), model.variables("input")["F"]
    for sym in states.values():
        opt.add_point_constraint(sym, at="start", lb=0.0, ub=0.0)
    for name, value in final.items():
        opt.add_point_constraint(states[name], at="final", lb=value, ub=value)
    opt.set_bounds(F, -5.0, 5.0)
    opt.set_objective(mayer=opt.final_time, lagrange=1e-2 * F**2)
    native = solve(opt, elements=20, points=3)
    imp = import_fmu(paths[version])
    res = solve_explicit_ocp(imp.model, final_time=2.0, free_final_time=True, final_time_bounds=(0.1, 10.0),
                             start={k: 0.0 for k in final}, final=final, input_bounds={"F": (-5.0, 5.0)},
                             lagrange=lambda v: 1e-2 * v["F"] ** 2, elements=20, derivatives=imp.derivatives,
                             # FMI 3.0 (CasADi's wrapper): its finite-difference Hessian stalls IPOPT (205 iterations,
                             # "acceptable"); quasi-Newton Hessians reach the optimum in 23
                             solver_options={"hessian_approximation": "limited-memory"} if version == "3.0" else None)
    assert native.status == "optimal" and res.status == "optimal"
    assert res.derivatives == "directional derivatives of the FMU"
    assert abs(res.final_time - native.final_time) < 1e-6 * native.final_time
    same = solve_explicit_ocp(explicit_model(model), final_time=2.0, free_final_time=True, final_time_bounds=(0.1, 10.0),
                              start={k: 0.0 for k in final}, final=final, input_bounds={"F": (-5.0, 5.0)},
                              lagrange=lambda v: 1e-2 * v["F"] ** 2, elements=20, guess=res)
    assert abs(same.objective - res.objective) < 1e-6 * res.objective  # started at the FMU optimum: stays (IPOPT tol)


def _write(path, data):
    path.write_bytes(data)
    return path


def _repack(src, dst, drop=(), edit=None):
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        for item in zin.namelist():
            if any(item.startswith(d) for d in drop):
                continue
            data = zin.read(item)
            if edit and item == "modelDescription.xml":
                data = edit(data.decode()).encode()
            zout.writestr(item, data)
    return dst


def test_source_fmu_is_built_on_import(tmp_path):
    fmu = export_fmu(_cart_pendulum(), tmp_path / "src.fmu", interface="me", binary=False)
    imp = import_fmu(fmu.path)
    assert imp.built_from_sources
    assert np.isfinite(np.array(imp.model.rhs(0, [0, 0, 0.5, 0], 0.0, imp.model.p_default)[0], dtype=float)).all()


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda p, d: d / "missing.fmu", "missing.fmu: no such FMU file"),
        (lambda p, d: _write(d / "corrupt.fmu", b"PK\x03\x04 not really"), r"corrupt.fmu: not an FMU \(corrupt"),
        (lambda p, d: _repack(p, d / "nomd.fmu", drop=("modelDescription.xml",)), "nomd.fmu: not an FMU .no modelDescription.xml"),
        (lambda p, d: _repack(p, d / "cs.fmu", edit=lambda x: x.replace("ModelExchange", "CoSimulation")),
         "cs.fmu: no model exchange interface .the FMU has CoSimulation"),
        (lambda p, d: _repack(p, d / "other.fmu", drop=("binaries/", "sources/")),
         r"other.fmu: no binary for this platform \(linux64\) and no C sources"),
        (lambda p, d: _repack(p, d / "v1.fmu", edit=lambda x: x.replace('fmiVersion="2.0"', 'fmiVersion="1.0"')),
         "v1.fmu: FMI version 1.0 is not supported"),
    ],
)
def test_bad_fmus_name_the_file(fmus, tmp_path, make, match):
    _, paths = fmus
    with pytest.raises(InputError, match=match):
        import_fmu(make(paths["2.0"], tmp_path))


def test_an_fmu_with_events_is_refused(tmp_path):
    ball = Model("ball")
    h, v = ball.state("h", start=1.0), ball.state("v")
    ball.equation(ball.der(h), v)
    ball.equation(ball.der(v), -9.81)
    ball.when(-h, reinit={v: -0.8 * v}, name="impact")
    fmu = export_fmu(ball, tmp_path / "ball.fmu", interface="me")
    with pytest.raises(InputError, match="ball.fmu: the FMU has 1 event indicator.s. .state events.; .* its events would be lost"):
        import_fmu(fmu.path)


def test_directional_derivatives_asked_of_an_fmu_without_them(fmus, tmp_path):
    _, paths = fmus
    path = _repack(paths["2.0"], tmp_path / "nodd.fmu", edit=lambda x: x.replace('providesDirectionalDerivative="true"', 'providesDirectionalDerivative="false"'))
    assert import_fmu(path).derivatives == "finite differences (CasADi)"
    with pytest.raises(InputError, match="nodd.fmu: the FMU provides no directional derivatives"):
        import_fmu(path, derivatives="directional")
    shutil.rmtree(tmp_path, ignore_errors=True)
