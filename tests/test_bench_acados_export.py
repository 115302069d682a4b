"""The export of a minimum-time problem for the acados peer (benchmarks/bench_solve.py; acados itself not needed)."""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from gtmodel.problems import load_problem

from .conftest import benchmark_module

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def bench_solve():
    """benchmarks/bench_solve.py as a module (its folder on the path, for bench_ocp_suite)."""
    with benchmark_module("bench_solve") as module:
        yield module


def test_l1_export_is_the_nlp_model(bench_solve, tmp_path):
    """The L1's exported ODE is the flattened DAE's with its parameters; the guess and bounds are gtmodel's."""
    decl = load_problem(ROOT / "problems" / "l1_time_optimal.toml").declaration
    path = bench_solve.export_acados(decl, tmp_path)
    z = np.load(path)
    opt, _ = bench_solve.build_optimization(decl)
    dae = opt.flat()
    pvec = dae.parameter_vector({**opt.parameters, **decl.named_parameters})
    ode = ca.Function.load(str(tmp_path / str(z["ode_file"])))
    ref = ca.Function("ref", [dae.t, dae.x, dae.u, dae.p], [dae.ode_expr])
    x, u = z["x_guess"][7], 450.0 * z["u_guess"][7, 1]
    assert np.allclose(np.asarray(ode(x, u)).ravel(), np.asarray(ref(0.0, x, u, pvec)).ravel(), rtol=1e-12, atol=1e-12)
    assert int(z["N"]) == 50 and int(z["d"]) == 3 and np.isclose(z["tau"][-1], 1.0)
    assert np.allclose(z["u_lb"], -1.0) and np.allclose(z["u_ub"], 1.0)
    assert np.allclose(z["x_guess"][0, :3], decl.start) and np.allclose(z["x_guess"][-1, :3], decl.end)
    assert z["start_lb"].size == 9 and z["final_lb"].size == 9 and z["path_lb"].size == 6


def test_published_export(bench_solve, tmp_path):
    """The robot arm (no path constraints, finite state bounds) exports; a Lagrange term is refused."""
    decl = load_problem(ROOT / "problems" / "benchmarks" / "robot_arm.toml").declaration
    opt = decl.optimization
    z = np.load(bench_solve.export_acados_ocp(opt, decl.method, opt.parameters, np.ones(3), tmp_path))
    assert z["path_lb"].size == 0 and np.isfinite(z["x_lb"][:3]).all() and z["x_guess"].shape == (51, 6)
    opt.set_objective(mayer=opt.final_time, lagrange=ca.sumsqr(opt.flat().u))
    with pytest.raises(ValueError, match="final_time alone"):
        bench_solve.export_acados_ocp(opt, decl.method, opt.parameters, np.ones(3), tmp_path / "b")
