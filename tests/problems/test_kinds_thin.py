"""The problem kinds are thin: defaults from ProblemKind, declarations in the domain, honest statuses."""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib

import pytest

from gtmodel.errors import InputError
from gtmodel.problems.base import ProblemKind
from gtmodel.problems.registry import _SCHEMAS, KINDS, get_schema
from gtmodel.problems.run import load_problem
from gtmodel.status import Status
from gtmodel.trajectory import PointToPoint
from gtmodel.modeling.ocp.methods import Collocation, SolverSettings

from ..conftest import PROBLEMS_DIR

#: Kinds that simulate (or filter) and optimise nothing: their success is ``completed``.
SIMULATION_KINDS = ("replay", "state_estimation", "correction_stability")


@pytest.mark.parametrize("name", list(KINDS))
def test_empty_fields_start_with_the_column_keys(name):
    kind = KINDS[name]
    keys = [c.key for c in kind.columns]
    assert list(kind.empty_fields[: len(keys)]) == keys
    assert len(set(kind.empty_fields)) == len(kind.empty_fields)


@pytest.mark.parametrize("name", [n for n in KINDS if n != "replay"])
def test_kinds_solve_through_the_declaration(name):
    # no pass-through solve in the kinds: ProblemKind.solve calls the declaration's own
    assert type(KINDS[name]).solve is ProblemKind.solve


def test_default_solve_passes_the_arguments_on():
    class Declaration:
        def solve(self, *, verbose=False, previous=None, warm_start=False):
            return (verbose, previous, warm_start)

    assert KINDS["calibration"].solve(Declaration(), verbose=True, previous=1, warm_start=True) == (True, 1, True)


@pytest.mark.parametrize("name", list(KINDS))
def test_declarations_live_in_the_domain_packages(name):
    # the one exception: replay's declaration holds another problem file's kind
    # robot_loop's shipped files serve a robot: they live in loops/ (gtmodel loop), not problems/
    # an optimica file lives beside its .mop (problems/optimica/)
    files = [p for p in sorted(PROBLEMS_DIR.glob("*.toml")) + sorted((PROBLEMS_DIR.parent / "loops").glob("*.toml"))
             + sorted((PROBLEMS_DIR / "optimica").glob("*.toml"))
             if tomllib.loads(p.read_text())["kind"] == name]
    decl = load_problem(files[0]).declaration
    module = type(decl).__module__
    assert module.startswith("gtmodel.problems.kinds.replay") if name == "replay" else not module.startswith("gtmodel.problems")


def test_simulation_statuses_are_completed_not_optimal():
    # defect (c): a simulation is not an optimisation
    assert Status.COMPLETED.success and Status.COMPLETED.exit_code == 0
    assert Status.worst(["optimal", "completed"]) == "completed"
    assert set(SIMULATION_KINDS) <= set(KINDS)


def test_point_to_point_method_and_solver_settings_are_objects():
    p = PointToPoint("L1", start=[-0.2, 2.75, -0.4], end=[0.2, 3.0, -0.6], force_limit=[450, 450, 450], elements=12, max_iter=50)
    assert p.method == Collocation(12, 3, "radau") and p.solver == SolverSettings(max_iter=50)
    assert (p.elements, p.max_iter, p.jit) == (12, 50, True)  # read under the former names


@pytest.mark.parametrize("build, match", [
    (lambda: Collocation(elements=0), "elements: expected a positive integer"),
    (lambda: Collocation(points=10), "points: expected an integer in 1..9"),
    (lambda: Collocation(scheme="euler"), "scheme: expected one of radau, legendre"),
    (lambda: SolverSettings(name="snopt"), "name: expected one of ipopt, fatrop"),
    (lambda: SolverSettings(tol=0.0), "tol: expected a positive finite number"),
])
def test_settings_name_the_bad_value(build, match):
    with pytest.raises(InputError, match=match):
        build()


def test_point_to_point_checks_its_invariants_once_at_construction():
    with pytest.raises(InputError, match="force_limit: .* cannot hold the robot at rest at the start pose"):
        PointToPoint("L1", start=[-0.2, 2.75, -0.4], end=[0.2, 3.0, -0.6], force_limit=[100, 100, 100])


@pytest.mark.parametrize("name", list(KINDS))
def test_the_light_schema_of_a_kind_is_its_schema(name):
    """The registry validates a file against the kind's schema without importing the kind
    (issue 24, item 7): the light module's class is the kind's ``schema``, and it imports
    no solver (checked on sys.modules in a fresh process)."""
    assert get_schema(name) is KINDS[name].schema
    target = _SCHEMAS.get(name)
    if target is None:
        return
    module = target.split(":")[0]
    script = (f"import sys, {module}\n"
              "print(sorted(m for m in ('numpy', 'casadi', 'scipy', 'control', 'matplotlib', 'pandas') if m in sys.modules))")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120,
                          env=dict(os.environ, PYTHONPATH=str(PROBLEMS_DIR.parent)))
    assert proc.stdout.strip() == "[]", proc.stdout + proc.stderr


def test_the_light_constants_are_those_of_the_domain():
    """Constants the light schemas name, equal to the domain's (gtmodel.defaults)."""
    from gtmodel import defaults
    from gtmodel.robots import friction

    from gtmodel.estimation.closed_loop import plant

    assert (defaults.FRICTION_FORMS, defaults.DEFAULT_FRICTION_WIDTH) == (friction.FRICTION_FORMS, friction.DEFAULT_FRICTION_WIDTH)
    assert (defaults.STANDARD_GRAVITY, defaults.LOOP_PERIOD_S) == (plant.STANDARD_GRAVITY, plant.DT)
    from gtmodel.calibration.identification import VARIANTS
    from gtmodel.problems.kinds.schemas.dynamic_identification import VARIANT_NAMES

    assert VARIANT_NAMES == tuple(VARIANTS)
    from gtmodel.calibration.kinematic import SOLVERS
    from gtmodel.problems.kinds.schemas.calibration import LSQ_SOLVERS

    assert LSQ_SOLVERS == tuple(SOLVERS)
    from gtmodel.calibration.elasto_geometric import COMPLIANCE_NAMES
    from gtmodel.problems.kinds.schemas.elasto_geometric_calibration import COMPLIANCE_NAME_LIST

    assert COMPLIANCE_NAME_LIST == tuple(COMPLIANCE_NAMES)
    from gtmodel.calibration import joint_stiffness
    from gtmodel.problems.kinds.schemas import joint_stiffness_calibration as js

    assert list(js.TABLE_2_DPP_K_THETA) == joint_stiffness.TABLE_2_K_THETA["DPP"].tolist()
    assert js.TABLE_2_ROTATION_ONLY_STIFFNESS == joint_stiffness.TABLE_2_SCENARIO_ROTATION_ONLY_STIFFNESS
    from gtmodel import estimation
    from gtmodel.estimation.filters import complementary, kalman
    from gtmodel.problems.kinds.schemas import ilc

    assert (ilc.ILC_SIGNALS, ilc.ILC_REQUIREMENTS) == (tuple(estimation.SIGNALS), tuple(estimation.REQUIREMENTS))
    from gtmodel.estimation.ilc.experiment import Q_DESIGNS

    assert (ilc.ILC_Q_DESIGNS, ilc.CUTOFF_READINGS) == (Q_DESIGNS, complementary.CUTOFF_READINGS)
    assert (ilc.MIN_CUTOFF_FRACTION, ilc.KALMAN_POSITION_NOISE, ilc.KALMAN_JERK_NOISE) == (
        complementary.MIN_CUTOFF_FRACTION, tuple(kalman.DEFAULT_POSITION_NOISE), tuple(kalman.DEFAULT_JERK_NOISE))
