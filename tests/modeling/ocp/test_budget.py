"""The NLP size estimate checked before a collocation NLP is built (gtmodel.modeling.ocp.budget).

Independent reference: the NLP CasADi builds (number of variables, structural nonzeros of
the constraint Jacobian ``casadi.jacobian(g, w)``), and the refusal happening before any of it
is built (a limit of 1 MB that no build could meet).
"""

from __future__ import annotations

import time

import casadi as ca
import pytest

from gtmodel.errors import InputError
from gtmodel.modeling import Model, Optimization
from gtmodel.modeling.ocp.budget import IPOPT_CPU_SHARE, MEMORY_ENV, check_memory, estimate, ipopt_left, memory_limit
from gtmodel.modeling.ocp.collocation import CollocationTranscription


def _double_integrator() -> Optimization:
    m = Model("di")
    x, v, u = m.state("x"), m.state("v"), m.input("u")
    m.equation(m.der(x), v)
    m.equation(m.der(v), u)
    opt = Optimization(m, final_time=1.0)
    opt.set_objective(lagrange=u**2)
    return opt


@pytest.mark.parametrize(("elements", "points"), [(20, 3), (10, 9), (40, 1)])
def test_the_estimate_follows_the_nlp_casadi_builds(elements, points):
    tr = CollocationTranscription(_double_integrator(), elements=elements, points=points, verify=False, derivatives="casadi")
    w, g = tr.nlp.w, tr.nlp.g
    nnz = ca.jacobian(g, w).nnz()
    assert abs(tr.size.variables - w.numel()) <= 2  # the final time's copies aside
    assert nnz <= tr.size.nonzeros <= 1.3 * nnz  # an upper bound, not far above


def test_an_nlp_beyond_the_limit_is_refused_before_it_is_built(monkeypatch):
    monkeypatch.setenv(MEMORY_ENV, "1")
    with pytest.raises(InputError, match=r"elements = 10000, points = 9: the NLP would have 290000 variables and 2340000 Jacobian nonzeros and need about "
                                          r"2602 MB, more than the limit of 1 MB \(\$GTMODEL_MAX_MEMORY_MB\); use fewer elements or points \(collocation\.elements"):
        CollocationTranscription(_double_integrator(), elements=10000, points=9, verify=False)


@pytest.mark.parametrize("value", ["0", "-5", "lots"])
def test_a_bad_limit_is_named(monkeypatch, value):
    monkeypatch.setenv(MEMORY_ENV, value)
    with pytest.raises(InputError, match="GTMODEL_MAX_MEMORY_MB: expected a positive number of megabytes"):
        memory_limit()


def test_default_limit_is_a_share_of_the_available_memory(monkeypatch):
    monkeypatch.delenv(MEMORY_ENV, raising=False)
    limit = memory_limit()
    assert limit is None or limit > 0
    assert check_memory(50, 3, 6, 0, 3) == estimate(50, 3, 6, 0, 3)  # a shipped problem's size passes


def test_ulimit_v_lowers_the_limit(tmp_path):
    """Under ``ulimit -v`` (RLIMIT_AS) the limit follows it (reference: the rlimit set in a child)."""
    import subprocess
    import sys

    code = ("import resource; resource.setrlimit(resource.RLIMIT_AS, (3_000_000_000, resource.RLIM_INFINITY)); "
            "from gtmodel.modeling.ocp.budget import memory_limit; print(memory_limit())")
    env = {k: v for k, v in __import__("os").environ.items() if k != MEMORY_ENV}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=60)
    assert out.returncode == 0, out.stderr
    assert 0 < float(out.stdout) <= 0.8 * 3_000_000_000


def test_the_shooting_estimate_counts_the_nlp_casadi_builds():
    # reference: the variables of the multiple-shooting NLP CasADi builds (states, inputs, no algebraics)
    from gtmodel.modeling.ocp.shooting import ShootingTranscription

    tr = ShootingTranscription(_double_integrator(), intervals=20, steps=4, verify=False)
    assert tr.size.variables == tr.nlp["x"].numel()
    assert ca.jacobian(tr.nlp["g"], tr.nlp["x"]).nnz() <= tr.size.nonzeros


@pytest.mark.parametrize(("intervals", "steps"), [(10000, 1000), (2000, 1000)])
def test_a_shooting_nlp_beyond_the_limit_is_refused_at_once(monkeypatch, intervals, steps):
    # the 10,000 x 1,000 (still building after 142 CPU-s, 820 MB) under a 4 GB limit: refused
    # before anything is built, naming the fields (reference: the process time of the refusal)
    import time

    from gtmodel.modeling.ocp.shooting import ShootingTranscription

    monkeypatch.setenv(MEMORY_ENV, "4000")
    start = time.process_time()
    with pytest.raises(InputError, match=rf"intervals = {intervals}, steps = {steps}: the multiple-shooting NLP would integrate "
                                         rf"{intervals * steps} steps .* more than the limit of 4000 MB .*transcription\.intervals, transcription\.steps"):
        ShootingTranscription(_double_integrator(), intervals=intervals, steps=steps)
    assert time.process_time() - start < 0.5


@pytest.mark.parametrize("limit_mb", [500, 2000, 8000])
def test_refinement_cap_is_the_largest_mesh_within_the_limit(monkeypatch, limit_mb):
    # independent check: the estimate itself, one element more exceeding the limit (the cap is where it crosses)
    from gtmodel.modeling.ocp.budget import MOST_ELEMENTS, max_elements

    monkeypatch.setenv(MEMORY_ENV, str(limit_mb))
    n = max_elements(3, 5, 20, 1)
    assert estimate(n, 3, 5, 20, 1).bytes <= limit_mb * 1e6 < estimate(n + 1, 3, 5, 20, 1).bytes or n == MOST_ELEMENTS


def test_refinement_cap_without_a_known_limit_is_the_fallback(monkeypatch):
    from gtmodel.modeling.ocp import budget

    monkeypatch.delenv(MEMORY_ENV, raising=False)
    monkeypatch.setattr(budget, "_available", lambda: None)
    assert budget.max_elements(3, 5, 20, 1) == budget.FALLBACK_ELEMENTS


@pytest.mark.parametrize(("spent", "expected"), [(0.0, IPOPT_CPU_SHARE * 100.0), (99.5, 1.0)])
def test_ipopt_is_held_to_its_share_of_the_cpu_left(spent, expected):
    # max_cpu_time = IPOPT_CPU_SHARE of (budget - spent), at least 1 s (the closed form of its definition)
    assert ipopt_left(100.0, time.process_time() - spent) == pytest.approx(expected, abs=0.05)


@pytest.mark.parametrize("history, elements, expected", [
    # the rotary table's passes (1.2 CPU-s on 144 elements the costliest per element): 20 x 1.2/144 x 146 = 24.3 s
    ([{"elements": 50, "cpu_s": 0.3}, {"elements": 144, "cpu_s": 1.2}], 146, 20.0 * 1.2 / 144 * 146),
    ([{"elements": 50, "cpu_s": 0.1}], 60, 10.0),  # the floor
    ([], 60, None),  # nothing to compare with: no cap
])
def test_stall_cap_is_a_multiple_of_the_costliest_pass_per_element(history, elements, expected):
    from gtmodel.modeling.ocp.budget import stall_cap

    assert stall_cap(history, elements) == (None if expected is None else pytest.approx(expected))
