"""A fine collocation mesh starts from a coarse solve interpolated onto it (:data:`gtmodel.trajectory.model_ocp.COARSE_START_MIN_ELEMENTS`).

Reference: the same problem solved cold (from the declared linear guess) on the same mesh,
a second path to the same NLP optimum (to 1e-6), and the published optimum of Bryson and
Ho's orbit raising (``problems/benchmarks/orbit_raising.toml``).
"""

from __future__ import annotations

import dataclasses

import pytest

from gtmodel.problems import load_problem
from gtmodel.trajectory import model_ocp

from ..conftest import PROBLEMS_DIR

ORBIT = PROBLEMS_DIR / "benchmarks" / "orbit_raising.toml"


def _orbit(elements: int):
    decl = load_problem(ORBIT).declaration
    return dataclasses.replace(decl, method=dataclasses.replace(decl.method, elements=elements))


def test_fine_mesh_starts_from_the_coarse_solve(monkeypatch):
    cold = _orbit(16).solve()
    assert "coarse_start" not in cold.stats  # below the threshold: the declared guess
    monkeypatch.setattr(model_ocp, "COARSE_START_MIN_ELEMENTS", 16)
    monkeypatch.setattr(model_ocp, "COARSE_START_ELEMENTS", 8)
    res = _orbit(16).solve()
    assert (cold.status, res.status) == ("optimal", "optimal")
    # on 16 elements the cold and the coarse-started solves end 1.3e-5 apart (the start's input bounds,
    # imposed since the consistent-start change, leave neighbouring optima of a coarse mesh)
    assert res.objective == pytest.approx(cold.objective, rel=3e-5)
    coarse = res.stats["coarse_start"]
    assert coarse["used"] and coarse["elements"] == 8 and coarse["status"] == "optimal"
    assert res.solve_time >= coarse["solve_time"]  # the coarse pass is counted in the solve
    # (iterations are not compared here: on 16 elements the coarse start saves none, 37 against 31; at
    # 400 elements it does, 19 against 51: benchmarks/bench_large_mesh.py and docs/verification.md)
    # the published r(tf) = 1.525 (Bryson and Ho's three digits) to the 3.3e-4 of test_benchmarks.PUBLISHED_RTOL
    assert res.objective == pytest.approx(load_problem(ORBIT).declaration.benchmark["published"], rel=3.3e-4)


@pytest.mark.parametrize(
    "file, expected",
    [("dc_motor_min_energy.toml", True), ("orbit_raising.toml", False)],
    ids=["linear-motor-energy", "orbit-raising"],
)
def test_linear_quadratic_problems_skip_the_coarse_start(file, expected):
    """A linear model with a quadratic objective is a QP (no coarse pass); orbit raising is not (CasADi's
    is_linear/is_quadratic, checked against the problems' closed forms: x' = A x + B v and integral(v^2))."""
    from gtmodel.modeling.ocp.coarse_start import linear_quadratic

    decl = load_problem(PROBLEMS_DIR / "benchmarks" / file).declaration
    assert linear_quadratic(decl.optimization, decl.optimization.flat()) is expected


def test_a_linear_quadratic_fine_mesh_solves_without_a_coarse_pass():
    """dc_motor_min_energy on 200 elements: no coarse pass, the closed-form optimum 0.2667243572 to 1e-4."""
    res = load_problem(PROBLEMS_DIR / "benchmarks" / "dc_motor_min_energy.toml").declaration.solve()
    assert res.status == "optimal" and "coarse_start" not in res.stats
    assert res.objective == pytest.approx(0.2667243572, rel=1e-4)
