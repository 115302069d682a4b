"""The 4 ms Kalman step (Dressler (2012), eqs. 7.19-7.22) as a discrete-time co-simulation FMU,
run by FMPy against the filter's own run in Python (StationaryKalman.run)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.cli import EXIT_BAD_INPUT, EXIT_OK, main
from gtmodel.errors import InputError
from gtmodel.estimation import StationaryKalman
from gtmodel.estimation.filters.kalman import DEFAULT_JERK_NOISE, DEFAULT_POSITION_NOISE
from gtmodel.exchange import export_step_fmu

fmpy = pytest.importorskip("fmpy")
from fmpy.validation import validate_fmu  # noqa: E402

DT = 0.004


@pytest.fixture(scope="module")
def kf():
    return StationaryKalman(dt=DT, position_noise=DEFAULT_POSITION_NOISE[0], jerk_noise=DEFAULT_JERK_NOISE[0], d=1)


def test_kalman_step_fmu_equals_the_python_filter(kf, tmp_path):
    fmu = export_step_fmu(kf.step_function(), tmp_path / "kalman.fmu", dt=DT)
    assert validate_fmu(str(fmu.path)) == []
    assert fmu.x_names == ["x[0]", "x[1]", "x[2]"] and fmu.u_names == ["y[0]", "y[1]"] and fmu.y_names == ["z_hat"]
    rng = np.random.default_rng(1)
    n = 60
    zk, am = 1e-3 * rng.normal(size=(n, 1)), rng.normal(size=(n, 1))
    signals = np.array([(k * DT, zk[k, 0], am[k, 0]) for k in range(n)], dtype=[("time", float), ("y[0]", float), ("y[1]", float)])
    res = fmpy.simulate_fmu(str(fmu.path), stop_time=(n - 1) * DT, output_interval=DT, input=signals,
                            output=["z_hat"], fmi_type="CoSimulation")
    z_hat, _ = kf.run(zk, am, x0=np.zeros(3))  # the filter's own loop (mapaccum of the same step)
    # the FMU's output after the step at t_k is the estimate of sample k - 1
    np.testing.assert_allclose(res["z_hat"][1:], np.asarray(z_hat).reshape(-1)[: n - 1], rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    ("step", "kwargs", "match"),
    [
        ("one-in", {}, r"expected a casadi.Function \(x, u\) -> \(x_next, y\)"),
        (None, {"dt": 0.0}, "dt: expected a positive sample period"),
        (None, {"x_start": [1.0]}, "x_start: expected 3 values, got 1"),
        (None, {"out": "k.zip"}, r"k.zip: the file name must end in \.fmu"),
    ],
)
def test_bad_step_exports(kf, tmp_path, step, kwargs, match):
    kwargs = {"dt": DT, **kwargs}
    out = tmp_path / kwargs.pop("out", "k.fmu")
    if step == "one-in":
        x = ca.SX.sym("x")
        step = ca.Function("f", [x], [2 * x])
    with pytest.raises(InputError, match=match):
        export_step_fmu(step if step is not None else kf.step_function(), out, **kwargs)


def test_cli_exports_a_controller_files_kalman_step(kf, tmp_path, capsys):
    from gtmodel.codegen import Controller, save_controller

    path = save_controller(tmp_path / "controller.json", Controller(kalman_step=kf.step_function(), dt=DT))
    code = main(["export-fmu", "--controller", str(path), "--out", str(tmp_path / "c.fmu")])
    assert code == EXIT_OK and "discrete step every 0.004 s" in capsys.readouterr().out
    assert validate_fmu(str(tmp_path / "c.fmu")) == []
    code = main(["export-fmu", "--controller", str(path), "--out", str(tmp_path / "c3.fmu"), "--fmi-version", "3.0"])
    assert code == EXIT_BAD_INPUT and "FMI 2.0 co-simulation only" in capsys.readouterr().err
