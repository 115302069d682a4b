"""Tests of gtmodel.robots.mapped: one-sample calls through Function.buffer and the models
evaluated through their generated C (``compiled=True``, issue 17 item 5)."""

from __future__ import annotations

import logging

import casadi as ca
import numpy as np
import pytest

from gtmodel._compiler import find_compiler
from gtmodel.errors import CompilerNotFoundError
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.mapped import MappedFunction

RNG = np.random.default_rng(17)
TOL = 1e-12  # compiled C and the CasADi interpreter evaluate the same graph: round-off only


def _compiler_available() -> bool:
    try:
        find_compiler()
    except CompilerNotFoundError:
        return False
    return True


needs_cc = pytest.mark.skipif(not _compiler_available(), reason="no C compiler")


@pytest.fixture(scope="module")
def models(tmp_path_factory):
    """L1 dynamics interpreted and compiled (into an empty cache folder), and random valid samples."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("GTMODEL_CACHE_DIR", str(tmp_path_factory.mktemp("cache")))
        mp.delenv("GTMODEL_COMPILE", raising=False)
        d, dc = GantryTau3Dynamics("L1"), GantryTau3Dynamics("L1", compiled=True)
        G = d.kinematics.workspace_grid(0.1)
        T = G[RNG.choice(len(G), 25, replace=False)]
        Td, Tdd = RNG.normal(0, 0.5, (25, 3)), RNG.normal(0, 3.0, (25, 3))
        q, tau = d.kinematics.ik(T), d.inverse_dynamics(T, Td, Tdd)
        # build every compiled Function inside the patched environment
        calls = {
            "ik": (lambda m: m.kinematics.ik, (T,)),
            "fk": (lambda m: m.kinematics.fk, (q,)),
            "jacobian": (lambda m: m.kinematics.jacobian, (T,)),
            "acceleration": (lambda m: m.kinematics.acceleration, (T, Td, Tdd)),
            "cart_motion": (lambda m: m.kinematics.cart_motion, (T, Td, Tdd)),
            "link_angles": (lambda m: m.kinematics.link_angles, (T,)),
            "inverse_dynamics": (lambda m: m.inverse_dynamics, (T, Td, Tdd)),
            "forward_dynamics": (lambda m: m.forward_dynamics, (T, Td, tau)),
        }
        for method, args in calls.values():
            method(dc)(*args)
        yield d, dc, calls


CALLS = ["ik", "fk", "jacobian", "acceleration", "cart_motion", "link_angles", "inverse_dynamics", "forward_dynamics"]


@needs_cc
@pytest.mark.parametrize("batch", [False, True], ids=["single", "batch"])
@pytest.mark.parametrize("name", CALLS)
def test_compiled_model_equals_the_interpreter(models, name, batch):
    """Checked against the interpreted CasADi Function (same graph): equal to 1e-12 on 25
    random reachable samples, one call per sample (buffer path) and one batch (map)."""
    d, dc, calls = models
    method, args = calls[name]
    if batch:
        ref, got = method(d)(*args), method(dc)(*args)
    else:
        ref = np.array([method(d)(*(a[k] for a in args)) for k in range(len(args[0]))])
        got = np.array([method(dc)(*(a[k] for a in args)) for k in range(len(args[0]))])
    np.testing.assert_allclose(got, ref, rtol=TOL, atol=TOL)


@needs_cc
def test_compiled_functions_are_externals(models):
    """The compiled option evaluates casadi.external Functions loaded from the cache."""
    _, dc, _ = models
    assert dc._inv.function is not dc._inv.f
    assert dc._inv.how.startswith("compiled C")


def test_single_sample_buffer_equals_the_function_call():
    """Checked against the Function's own call (DM conversion): matrix input and outputs of
    several shapes, through the preallocated buffer, to round-off (the same evaluation)."""
    X, y = ca.SX.sym("X", 3, 2), ca.SX.sym("y", 2)
    f = ca.Function("f", [X, y], [X @ y, ca.sin(X).T, ca.sumsqr(X)])
    m = MappedFunction(f)
    Xv, yv = RNG.normal(size=(3, 2)), RNG.normal(size=(2, 1))
    got = m(Xv, yv, n=1)
    ref = [np.asarray(o) for o in f(Xv, yv)]
    assert [g.shape for g in got] == [r.shape for r in ref] == [(3, 1), (2, 3), (1, 1)]
    np.testing.assert_allclose(np.concatenate([g.ravel() for g in got]), np.concatenate([r.ravel() for r in ref]), rtol=1e-15, atol=0)


def test_single_sample_results_are_copies():
    """A second call does not overwrite the first call's results (the buffer is reused)."""
    x = ca.SX.sym("x", 2)
    m = MappedFunction(ca.Function("f", [x], [2 * x]))
    a = m(np.array([[1.0], [2.0]]))[0]
    m(np.array([[5.0], [6.0]]))
    np.testing.assert_array_equal(a, [[2.0], [4.0]])


def test_arguments_not_fitting_the_buffer_use_the_function_call():
    """A scalar broadcast to a vector input is not a buffer argument: the ordinary call
    (checked against the closed form 2 x)."""
    x = ca.SX.sym("x", 2)
    m = MappedFunction(ca.Function("f", [x], [2 * x]))
    np.testing.assert_array_equal(m(np.array([[3.0]]))[0], [[6.0], [6.0]])


@pytest.mark.parametrize(
    "env, value",
    [("GTMODEL_COMPILE", "0"), ("CC", "/no/such/compiler")],
    ids=["switched-off", "no-compiler"],
)
def test_compiled_falls_back_to_the_interpreter_with_a_warning(monkeypatch, tmp_path, caplog, env, value):
    """Without a compiler (or switched off) compiled=True evaluates the interpreter, logs a
    warning naming why, and gives the interpreter's forces exactly (the same Function)."""
    monkeypatch.setenv("GTMODEL_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv(env, value)
    d = GantryTau3Dynamics("L1")
    with caplog.at_level(logging.WARNING, logger="gtmodel"):
        dc = GantryTau3Dynamics("L1", compiled=True)
        T = d.kinematics.workspace_grid(0.1)[:3]
        got = dc.inverse_dynamics(T, np.zeros((3, 3)), np.ones((3, 3)))
    assert dc._inv.function is dc._inv.f
    assert any("compiled=True, but evaluated by the CasADi interpreter" in m for m in caplog.messages), caplog.messages
    np.testing.assert_array_equal(got, d.inverse_dynamics(T, np.zeros((3, 3)), np.ones((3, 3))))


def test_batch_buffer_equals_the_mapped_function_call():
    """Checked against Function.map's own call (DM conversion): 7 samples of a matrix input
    through the per-n buffer, also with a broadcast argument (one sample's value for all
    samples, as map broadcasts it), to round-off."""
    X, y = ca.SX.sym("X", 3, 2), ca.SX.sym("y", 2)
    f = ca.Function("f", [X, y], [X @ y, ca.sumsqr(X)])
    m = MappedFunction(f)
    Xv, yv = RNG.normal(size=(3, 14)), RNG.normal(size=(2, 7))
    got, got_broadcast = m(Xv, yv, n=7), m(Xv, yv[:, :1], n=7)
    ref, ref_broadcast = f.map(7)(Xv, yv), f.map(7)(Xv, yv[:, :1])
    np.testing.assert_allclose(np.concatenate([g.ravel() for g in got]), np.concatenate([np.asarray(r).ravel() for r in ref]), rtol=1e-15, atol=0)
    np.testing.assert_allclose(np.concatenate([g.ravel() for g in got_broadcast]), np.concatenate([np.asarray(r).ravel() for r in ref_broadcast]), rtol=1e-15, atol=0)
