"""The plan cache of a loop-controller file's reference problem (gtmodel.problems.plan_cache): planned once, reused exactly.

References: the reference of the cart MPC fixture (tests/fixtures/user_models/cart_mpc.toml, its
cart_move.toml solved in about 0.3 s) read twice, the second time from the cache: the same
times, states, inputs, bounds, notes and model parameters, bit for bit, and no solve (a spy on
the solver the loop-controller file calls); a key that changes with each of its ingredients; an
entry damaged in each way it can be (cut, another shape, a changed number, another key, too
large) ignored with a warning and planned again; the verdict on an unverified plan the same
from the cache as from the solve (:func:`gtmodel.problems.loop_bounds.unverified_reason`).
"""

from __future__ import annotations

import json
import logging
import shutil
from types import SimpleNamespace

import numpy as np
import pytest

import gtmodel.problems.loop_file as loop_file
from gtmodel.cli import main
from gtmodel.defaults import defaults
from gtmodel.problems import plan_cache
from gtmodel.problems.loop_bounds import unverified_reason
from gtmodel.problems.loop_file import loop_inputs, read_loop_file
from gtmodel.problems.plan_cache import cache_dir, plan_key, planned

from ..conftest import REPO

FIXTURES = REPO / "tests" / "fixtures" / "user_models"
TRACKING = """name = "cart_tracking"

[controller]
model = "cart_spring.py:Cart_1"
period = 0.004
state_weights = { "cart.v" = 1.0, "sd.s_rel" = 1000.0 }
input_weights = { "push.f" = 1e-3 }

[reference]
problem = "cart_move.toml"
settle_time = 0.3

[check]
parameter_factor = 1.1
delay = 1
error_states = ["sd.s_rel"]
"""


@pytest.fixture
def cart(tmp_path, monkeypatch):
    """The cart MPC, its problem and model copied to ``tmp_path/cart``, a cache of this test's own, and a count of the solves."""
    folder = tmp_path / "cart"
    folder.mkdir()
    for name in ("cart_mpc.toml", "cart_move.toml", "cart_spring.py"):
        shutil.copy(FIXTURES / name, folder / name)
    (folder / "cart_tracking.toml").write_text(TRACKING)
    monkeypatch.setenv("GTMODEL_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv("GTMODEL_PLAN_CACHE_DIR", raising=False)  # the suite's own folder (tests/conftest.py) comes first
    solves = []
    real = loop_file.solve_problem

    def spy(problem, *args, **kwargs):
        solves.append(problem.path)
        return real(problem, *args, **kwargs)

    monkeypatch.setattr(loop_file, "solve_problem", spy)
    return SimpleNamespace(folder=folder, mpc=folder / "cart_mpc.toml", move=folder / "cart_move.toml", solves=solves)


def _reference(path, replan=False):
    """What the MPC file reads of its reference: times, states, inputs, bounds, notes and the prediction's parameters."""
    doc, file = read_loop_file(path, "mpc")
    i = loop_inputs(file, doc, "mpc", replan=replan)
    return dict(t=i.t, x=i.x_ref, u=i.u_ref, u_lb=i.u_lb, u_ub=i.u_ub, lb=i.bounds.lb, ub=i.bounds.ub, source=i.bounds.source,
                notes=i.notes, p=np.asarray(i.model.ode.p_default), plant_p=np.asarray(i.model.plant_p))


def _differences(a, b):
    """The entries of two references that differ (arrays bit for bit)."""
    return [k for k in a if not (np.array_equal(a[k], b[k]) if isinstance(a[k], np.ndarray) else a[k] == b[k])]


def _entries():
    return sorted(cache_dir().glob("*.json"))


def test_a_second_load_solves_nothing_and_reads_the_same_reference(cart, caplog):
    first = _reference(cart.mpc)
    with caplog.at_level(logging.INFO, logger="gtmodel"):
        second = _reference(cart.mpc)
    assert len(cart.solves) == 1
    assert _differences(first, second) == []
    assert len(first["t"]) > 100 and first["notes"] == second["notes"]
    (entry,) = _entries()
    assert f"is the plan cached at {entry}" in caplog.text and "--replan solves it again" in caplog.text


def test_replan_solves_again_and_refreshes_the_entry(cart, caplog):
    first = _reference(cart.mpc)
    (entry,) = _entries()
    entry.write_text(entry.read_text()[:-10])  # damaged: --replan does not read it, and replaces it
    with caplog.at_level(logging.INFO, logger="gtmodel"):
        again = _reference(cart.mpc, replan=True)
    assert len(cart.solves) == 2 and _differences(first, again) == []
    assert "solved again (--replan)" in caplog.text and "is ignored" not in caplog.text
    assert json.loads(entry.read_text())["key"] == entry.stem
    _reference(cart.mpc)
    assert len(cart.solves) == 2


def _edit(path, old, new):
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))


@pytest.mark.parametrize("change", ["a number of the problem file", "a comment of the problem file", "the model's source",
                                    "the overrides", "a value of an override", "a default of the solver"])
def test_the_key_changes_with_each_ingredient(change, cart, monkeypatch):
    overrides = {"collocation.elements": 40}
    before = plan_key(cart.move, overrides)
    assert plan_key(cart.move, dict(overrides)) == before  # the same inputs: the same key
    if change == "a number of the problem file":
        _edit(cart.move, "elements = 40", "elements = 41")
    elif change == "a comment of the problem file":
        _edit(cart.move, "[collocation]", "# planned again\n[collocation]")
    elif change == "the model's source":
        _edit(cart.folder / "cart_spring.py", "\n", "\n# edited\n")
    elif change == "a default of the solver":
        monkeypatch.setitem(defaults, "ocp.verification_tolerance", 0.5 * defaults["ocp.verification_tolerance"])
    if change == "the overrides":
        overrides = {}
    elif change == "a value of an override":
        overrides = {"collocation.elements": 41}
    assert plan_key(cart.move, overrides) != before


def test_the_key_is_of_the_contents_not_of_the_folder(cart, tmp_path):
    other = tmp_path / "elsewhere"
    shutil.copytree(cart.folder, other)
    assert plan_key(other / "cart_move.toml", {"w": 1}) == plan_key(cart.move, {"w": 1})
    assert len(plan_key(cart.move)) == 64


@pytest.mark.parametrize("reference", ["guess.csv", "./guess.csv", "guess.csv:Column"])
def test_the_key_covers_a_data_file_the_problem_names(reference, tmp_path):
    problem = tmp_path / "p.toml"
    problem.write_text(f'kind = "optimal_control"\n[initial_guess]\nmethod = "file"\nfile = "{reference}"\n')
    (tmp_path / "guess.csv").write_text("t,x\n0,0\n")
    before = plan_key(problem)
    (tmp_path / "guess.csv").write_text("t,x\n0,1\n")
    assert plan_key(problem) != before


def _rewrite(entry, change):
    """An entry with ``change(payload)`` applied and its checksum made to match (a consistent file, wrong inside)."""
    data = json.loads(entry.read_text())
    change(data["payload"])
    data["checksum"] = plan_cache.hashlib.sha256(plan_cache._canonical(data["payload"]).encode()).hexdigest()
    entry.write_text(json.dumps(data))


def _shorter_state(payload):
    name = next(iter(payload["states"]))
    payload["states"][name] = payload["states"][name][:-1]


DAMAGE = {
    "cut short": lambda entry, mp: entry.write_text(entry.read_text()[: entry.stat().st_size // 2]),
    "not text": lambda entry, mp: entry.write_bytes(b"\xff\xfe\x00garbage"),
    "a list, not an entry": lambda entry, mp: entry.write_text("[1, 2, 3]"),
    "a state one row short": lambda entry, mp: _rewrite(entry, _shorter_state),
    "times a table": lambda entry, mp: _rewrite(entry, lambda p: p.update(t=[[0.0, 1.0], [2.0, 3.0]])),
    "a state missing": lambda entry, mp: _rewrite(entry, lambda p: p["states"].pop(next(iter(p["states"])))),
    "a state of text": lambda entry, mp: _rewrite(entry, lambda p: p["states"].update({k: ["a"] * len(p["t"]) for k in p["states"]})),
    "another status": lambda entry, mp: _rewrite(entry, lambda p: p.update(status="infeasible")),
    "a number changed, not its checksum": lambda entry, mp: entry.write_text(entry.read_text().replace('"t":[0.0,', '"t":[1e-3,', 1)),
    "another key": lambda entry, mp: entry.write_text(entry.read_text().replace(entry.stem, "0" * 64)),
    "too large": lambda entry, mp: mp.setattr(plan_cache, "MAX_ENTRY_BYTES", 100),
}


@pytest.mark.parametrize("damage", list(DAMAGE))
def test_a_damaged_entry_is_ignored_with_a_warning_and_planned_again(damage, cart, caplog, monkeypatch):
    first = _reference(cart.mpc)
    (entry,) = _entries()
    before = entry.read_bytes()
    DAMAGE[damage](entry, monkeypatch)
    assert damage == "too large" or entry.read_bytes() != before
    with caplog.at_level(logging.INFO, logger="gtmodel"):
        again = _reference(cart.mpc)
    assert len(cart.solves) == 2 and _differences(first, again) == []
    ignored = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING and "is ignored" in r.getMessage()]
    assert len(ignored) == 1 and f"the plan cached at {entry} is ignored" in ignored[0] and "solved again" in ignored[0]


def test_a_cache_that_cannot_be_written_plans_and_goes_on(cart, tmp_path, monkeypatch, caplog):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("GTMODEL_CACHE_DIR", str(blocker))  # its plans/ cannot be created
    monkeypatch.delenv("GTMODEL_PLAN_CACHE_DIR", raising=False)  # the suite's own folder (tests/conftest.py) comes first
    with caplog.at_level(logging.INFO, logger="gtmodel"):
        first = _reference(cart.mpc)
        second = _reference(cart.mpc)
    assert len(cart.solves) == 2 and _differences(first, second) == []
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 2 and all("cannot be written" in w and "going on without it" in w for w in warnings)


def _verification(passed, message):
    return SimpleNamespace(passed=passed, message=message, status="whatever")  # as a Verification: passed, message


@pytest.mark.parametrize("status, verification", [
    ("optimal", _verification(True, "")),
    ("check_failed", _verification(False, "state 'cart.v' deviates 3e-2")),
    ("check_failed", _verification(False, "")),
    ("optimal", _verification(np.True_, "")),  # read as `passed is not True`: not verified, from the cache too
    ("acceptable", _verification(None, "")),
    ("optimal", None),
    ("optimal", {"passed": False, "status": "failed"}),
    ("optimal", {"passed": True, "message": ""}),
])
def test_the_verdict_on_a_cached_plan_is_the_solve_s(status, verification, tmp_path, monkeypatch):
    monkeypatch.setenv("GTMODEL_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv("GTMODEL_PLAN_CACHE_DIR", raising=False)  # the suite's own folder (tests/conftest.py) comes first
    path = tmp_path / "p.toml"
    path.write_text('kind = "optimal_control"\n')
    problem = SimpleNamespace(path=path, overrides={"w": 1})
    t = np.linspace(0.0, 1.0, 7) ** 2
    solution = SimpleNamespace(status=status, verification=verification, t=t, states={"x": np.sin(t), "v": np.cos(t) / 3},
                               inputs={"u": np.exp(t)}, parameters={"m": np.array(0.1), "k": np.array([1.0, 2.0 / 3])})
    solves = []

    def solve():
        solves.append(1)
        return solution

    assert planned(problem, solve, names=["x", "v", "u"]) is solution
    cached = planned(problem, solve, names=["x", "v", "u"])
    assert solves == [1] and cached is not solution
    assert unverified_reason(cached.status, cached.verification) == unverified_reason(status, verification)
    assert np.array_equal(cached.t, t) and np.array_equal(cached.states["v"], solution.states["v"])
    assert np.array_equal(cached.inputs["u"], solution.inputs["u"]) and cached.parameters["k"].tolist() == [1.0, 2.0 / 3]
    assert cached.parameters["m"].shape == ()


@pytest.mark.parametrize("status", ["infeasible", "max_iterations", "error"])
def test_a_solve_without_a_solution_is_not_cached(status, tmp_path, monkeypatch):
    monkeypatch.setenv("GTMODEL_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv("GTMODEL_PLAN_CACHE_DIR", raising=False)  # the suite's own folder (tests/conftest.py) comes first
    path = tmp_path / "p.toml"
    path.write_text('kind = "optimal_control"\n')
    problem = SimpleNamespace(path=path, overrides={})
    solution = SimpleNamespace(status=status, verification=None, t=np.zeros(2), states={}, inputs={}, parameters={})
    solves = []
    planned(problem, lambda: solves.append(1) or solution)
    planned(problem, lambda: solves.append(1) or solution)
    assert solves == [1, 1] and not (tmp_path / "cache").exists()


def test_codegen_mpc_and_tracking_take_replan(cart, tmp_path, capsys):
    """Cold with --replan, then warm: the line before the solve says which (the log, stderr)."""
    assert main(["codegen", "mpc", str(cart.mpc), "--out", str(tmp_path / "mpc"), "--replan"]) == 0
    cold = capsys.readouterr().err
    assert main(["codegen", "tracking", str(cart.folder / "cart_tracking.toml"), "--out", str(tmp_path / "trk")]) == 0
    warm = capsys.readouterr().err
    assert main(["codegen", "tracking", str(cart.folder / "cart_tracking.toml"), "--out", str(tmp_path / "trk"), "--replan", "-q"]) == 0
    assert len(cart.solves) == 2
    assert "the reference is re-planned: cart_move.toml solved here" in cold and "solved again (--replan)" in cold
    assert "the reference cart_move.toml is not solved here: its plan is read from the plan cache" in warm
    assert "is the plan cached at" in warm and "re-planned:" not in warm


@pytest.mark.parametrize("argv", [["codegen", "--robot", "L1", "--functions", "ik"], ["codegen", "--model", f"{FIXTURES / 'cart_spring.py'}:Cart_1"]])
def test_replan_is_refused_where_nothing_is_planned(argv, tmp_path, capsys):
    assert main([*argv, "--replan", "--out", str(tmp_path / "c")]) == 2
    assert "--replan applies to an MPC or tracking-controller file" in capsys.readouterr().err


def test_the_plans_own_folder_comes_before_gtmodels_cache(tmp_path, monkeypatch):
    """``GTMODEL_PLAN_CACHE_DIR`` (the test suite's) over ``GTMODEL_CACHE_DIR/plans`` (the compiled libraries' root)."""
    from gtmodel.problems.plan_cache import cache_dir

    monkeypatch.setenv("GTMODEL_CACHE_DIR", str(tmp_path / "root"))
    monkeypatch.setenv("GTMODEL_PLAN_CACHE_DIR", str(tmp_path / "own"))
    assert cache_dir() == tmp_path / "own"
    monkeypatch.delenv("GTMODEL_PLAN_CACHE_DIR")
    assert cache_dir() == tmp_path / "root" / "plans"


def test_the_key_reads_no_file_outside_the_problems_folder(tmp_path, monkeypatch):
    """A string of someone else's problem file naming a file elsewhere is not read for the key; one inside its folder is."""
    import builtins

    from gtmodel.problems.plan_cache import plan_key

    outside = tmp_path / "secret.txt"
    outside.write_text("not yours")
    folder = tmp_path / "p"
    folder.mkdir()
    (folder / "table.csv").write_text("t\n0\n")
    problem = folder / "x.toml"
    problem.write_text(f'name = "x"\nkind = "optimal_control"\ndescription = "{outside}"\nnote = "../secret.txt"\ndata = "table.csv"\n')
    opened = []
    real_open = builtins.open
    monkeypatch.setattr(builtins, "open", lambda f, *a, **k: (opened.append(str(f)), real_open(f, *a, **k))[1])
    plan_key(problem)
    assert str(outside) not in opened and str((folder / "table.csv").resolve()) in opened
