"""The algebraic variables eliminated from the collocation NLP: the same optimum, the same algebraic values.

Independent check: the same problem transcribed with ``eliminate_algebraics=False``, every
algebraic variable an NLP variable at every collocation point and the algebraic equations
constraints there (the transcription as it was). The drive is ``problems/drive_motor_gear_load.toml``
(3 states, 1 input, 29 algebraic variables) on 20 elements: the NLP with the algebraic
variables substituted is the same NLP, so the optima agree to the solver's tolerance.
"""

from __future__ import annotations

import logging

import numpy as np
import pytest

from gtmodel.modeling import Model, Optimization
from gtmodel.errors import InputError
from gtmodel.modeling.ocp.budget import MEMORY_ENV, estimate
from gtmodel.modeling.ocp.collocation import CollocationTranscription
from gtmodel.modeling.ocp.elimination import eliminable, reduced_problem
from gtmodel.problems import load_problem
from gtmodel.status import Status

from ...conftest import REPO
from .._builders import nonlinear_loop

MOTOR = REPO / "problems" / "drive_motor_gear_load.toml"
N, D = 20, 3
TAU = "gear.flange_b.tau"  # the gear's output torque (algebraic), N m: within +-1.10 N m unbounded


def _motor(tau_limit: float | None = None) -> Optimization:
    opt = load_problem(MOTOR).declaration.optimization
    if tau_limit is not None:
        dae = opt.flat()
        opt.set_bounds(dae.z[dae.z_names.index(TAU)], -tau_limit, tau_limit)
    return opt


def _solve(opt: Optimization, eliminate: bool, **kwargs):
    tr = CollocationTranscription(opt, elements=N, points=D, eliminate_algebraics=eliminate, verify=False, **kwargs)
    return tr, tr.solve()


@pytest.fixture(scope="module")
def pair():
    """The motor-gear-load's minimum time without and with the elimination."""
    opt = _motor()
    return _solve(opt, False), _solve(opt, True)


def test_reduced_nlp_carries_no_algebraic_variable(pair):
    (full, _), (reduced, res) = pair
    nz = full.dae.nz
    # independent count: the unreduced NLP has nz variables at each of the N d collocation points more
    assert (int(full.nlp.w.numel()) - int(reduced.nlp.w.numel()), res.stats["eliminated_algebraics"]) == (N * D * nz, nz)


@pytest.mark.parametrize(("eliminate", "refused"), [(False, True), (True, False)])
def test_memory_check_counts_the_algebraic_variables_the_nlp_carries(monkeypatch, eliminate, refused):
    # independent: budget.estimate of the two sizes; a limit between them refuses only the unreduced NLP
    opt = _motor()
    dae = opt.flat()
    full, reduced = estimate(N, D, dae.nx, dae.nz, dae.nu).bytes, estimate(N, D, dae.nx, 0, dae.nu).bytes
    monkeypatch.setenv(MEMORY_ENV, str((full + reduced) / 2 / 1e6))
    if refused:
        with pytest.raises(InputError, match="more than the limit"):
            CollocationTranscription(opt, elements=N, points=D, eliminate_algebraics=eliminate, verify=False)
    else:
        tr = CollocationTranscription(opt, elements=N, points=D, eliminate_algebraics=eliminate, verify=False)
        assert tr.size == estimate(N, D, dae.nx, 0, dae.nu)


@pytest.mark.parametrize("quantity", ["final_time", "objective"])
def test_reduced_optimum_equals_the_unreduced_one(pair, quantity):
    (_, full), (_, reduced) = pair
    assert (full.status, reduced.status) == (Status.OPTIMAL, Status.OPTIMAL)
    assert getattr(reduced, quantity) == pytest.approx(getattr(full, quantity), rel=1e-7)


@pytest.mark.parametrize("where", ["collocation points", "mesh", "states", "outputs"])
def test_result_values_equal_the_unreduced_ones(pair, where):
    # the algebraic variables evaluated at the solution: equal to the unreduced NLP's own values (to its tolerance)
    (_, full), (_, reduced) = pair
    get = {
        "collocation points": lambda r: r.collocation.zc,
        "mesh": lambda r: np.column_stack([r.algebraics[k] for k in full.algebraics]),
        "states": lambda r: np.column_stack([r.states[k] for k in full.states]),
        "outputs": lambda r: np.column_stack([np.ravel(r.outputs[k]) for k in full.outputs]) if full.outputs else np.zeros(1),
    }[where]
    a, b = get(full), get(reduced)
    assert a.shape == b.shape
    np.testing.assert_allclose(b, a, rtol=1e-6, atol=1e-6 * max(1.0, float(np.max(np.abs(a)))))


@pytest.mark.parametrize("options", [{"solver": "fatrop"}, {"derivatives": "casadi"}], ids=["fatrop-stagewise", "casadi-derivatives"])
def test_reduced_optimum_is_the_same_with_other_solvers_and_derivatives(pair, options):
    (_, full), _ = pair
    _, res = _solve(_motor(), True, **options)
    assert res.status == Status.OPTIMAL
    assert res.final_time == pytest.approx(full.final_time, rel=1e-6)


def test_reduced_optimum_is_the_same_with_compiled_derivatives(pair, cache):
    (_, full), _ = pair
    _, res = _solve(_motor(), True, compile=True)
    assert res.final_time == pytest.approx(full.final_time, rel=1e-7)


@pytest.fixture(scope="module")
def bounded():
    """The gear torque bounded to +-0.8 N m (unbounded it reaches 1.10): unreduced and reduced."""
    opt = _motor(0.8)
    return _solve(opt, False)[1], _solve(opt, True)[1]


def test_algebraic_bound_binds_as_a_path_constraint(pair, bounded):
    # independent check: the unreduced NLP imposes it as a variable bound; the reduced one as a path constraint
    (_, free), (_, reduced) = pair[1], bounded
    tau = reduced.collocation.zc[:, :, reduced.dae.z_names.index(TAU)]
    assert reduced.status == Status.OPTIMAL
    assert (round(float(np.max(np.abs(tau))), 5), reduced.final_time > free.final_time * 1.05) == (0.8, True)


def test_algebraic_bound_gives_the_unreduced_optimum(bounded):
    full, reduced = bounded
    assert reduced.final_time == pytest.approx(full.final_time, rel=1e-7)


def test_algebraic_bound_is_a_path_constraint_of_the_reduced_problem():
    opt = _motor(0.8)
    red = reduced_problem(opt, opt.flat(), np.zeros(0, dtype=int))
    names = [c.name for c in red.optimization.path_constraints]
    assert (names[-1], red.dae.nz, red.eliminated) == (f"bounds of {TAU}", 0, opt.flat().nz)


def _loop() -> Optimization:
    """The nonlinear loop of :func:`nonlinear_loop`: drive x from 1 to 0 in 1 s at least effort."""
    m = nonlinear_loop()
    x, u = m.variables("state")["x"], m.variables("input")["u"]
    opt = Optimization(m, final_time=1.0)
    opt.set_objective(lagrange=u**2)
    opt.add_point_constraint(x, at="start", lb=1.0, ub=1.0)
    opt.add_point_constraint(x, at="final", lb=0.0, ub=0.0)
    return opt


def test_nonlinear_loop_keeps_its_algebraic_variables(caplog):
    opt = _loop()
    with caplog.at_level(logging.INFO, logger="gtmodel"):
        tr = CollocationTranscription(opt, elements=10, verify=False)
    res = tr.solve()
    assert (tr.reduction, res.stats["eliminated_algebraics"], res.status) == (None, 0, Status.OPTIMAL)
    assert "stay in the NLP (a nonlinear algebraic loop" in caplog.text


def _affine(jacobian_of_state: bool) -> tuple[Optimization, str]:
    """z affine in itself: x z = u (a Jacobian of the state) or 2 z = u (constant)."""
    m = Model("affine")
    x = m.state("x", start=1.0)
    z = m.algebraic("z", start=1.0)
    u = m.input("u")
    m.equation(m.der(x), z)
    m.equation((x if jacobian_of_state else 2.0) * z, u)
    return Optimization(m, final_time=1.0), "not constant" if jacobian_of_state else ""


@pytest.mark.parametrize("state_jacobian", [True, False], ids=["state-dependent-jacobian", "constant-jacobian"])
def test_only_a_constant_jacobian_is_eliminated(state_jacobian):
    opt, reason = _affine(state_jacobian)
    z, why = eliminable(opt, opt.flat(), np.zeros(0, dtype=int))
    assert ((z is None), reason in why) == (state_jacobian, True)


def test_interior_timed_value_of_an_algebraic_variable_keeps_them():
    # the NLP interpolates z through its collocation points there, which z(x(t), u(t)) would not reproduce
    opt, _ = _affine(False)
    dae = opt.flat()
    opt.timed(dae.z[0], 0.5)
    z, why = eliminable(opt, dae, np.zeros(0, dtype=int))
    assert (z, "interior time" in why) == (None, True)


def test_problem_file_switch_reaches_the_method():
    on = load_problem(MOTOR).declaration.method.eliminate_algebraics
    off = load_problem(MOTOR, settings={"collocation.eliminate_algebraics": False}).declaration.method.eliminate_algebraics
    assert (on, off) == (True, False)
