"""The registry's loop-controller file kinds and renamed kinds (gtmodel.problems.registry).

Independent checks: the shipped loop files validated against the declared schemas and against
their JSON Schemas by ``jsonschema`` (a second validator), the light modules' imports in a
fresh process (sys.modules), the domain's constants compared with the light copies, and the
command line's output.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tomllib

import jsonschema
import pytest

from gtmodel.errors import ProblemError
from gtmodel.problems import load_problem
from gtmodel.problems.docs import json_schema
from gtmodel.problems.registry import (KINDS, LOOP_KINDS, RENAMED, all_kinds, canonical_kind, get_kind, get_loop_kind, get_schema,
                                       kind_titles)

from ..conftest import PROBLEMS_DIR, REPO

#: Shipped loop-controller files by kind.
SHIPPED = {
    "mpc": [*sorted((REPO / "codegen" / "mpc").glob("*.toml")), *sorted((REPO / "tests" / "fixtures" / "user_models").glob("*_mpc.toml"))],
    "tracking_controller": sorted((REPO / "codegen" / "controllers").glob("*.toml")),
}


def test_every_kind_is_listed_with_a_title():
    titles = kind_titles()
    assert list(titles) == all_kinds() == [*KINDS, *LOOP_KINDS]
    assert {"mpc", "tracking_controller", "estimator_ilc", "replay"} <= set(titles) and "tracking" not in titles
    assert all(titles[name] for name in LOOP_KINDS)


def test_schema_list_on_the_command_line_names_the_loop_files():
    proc = subprocess.run([sys.executable, "-m", "gtmodel", "schema", "--list"], capture_output=True, text=True, timeout=120,
                          cwd=REPO, env=dict(os.environ, PYTHONPATH=str(REPO)))
    names = [line.split()[0] for line in proc.stdout.splitlines()]
    assert proc.returncode == 0 and names == all_kinds()


@pytest.mark.parametrize("name", list(LOOP_KINDS))
def test_loop_schema_is_light(name):
    module = LOOP_KINDS[name].schema.split(":")[0]
    script = (f"import sys, {module}\n"
              "print(sorted(m for m in ('numpy', 'casadi', 'scipy', 'control', 'matplotlib', 'pandas') if m in sys.modules))")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120,
                          env=dict(os.environ, PYTHONPATH=str(REPO)))
    assert proc.stdout.strip() == "[]", proc.stdout + proc.stderr


@pytest.mark.parametrize("name, path", [(k, p) for k, files in SHIPPED.items() for p in files], ids=lambda v: getattr(v, "name", v))
def test_shipped_loop_files_validate_against_the_declared_and_the_json_schema(name, path):
    data = tomllib.loads(path.read_text(encoding="utf-8"))
    get_schema(name).model_validate(data)
    jsonschema.Draft202012Validator(json_schema(name)).validate(data)


def test_the_light_constants_are_those_of_the_domain():
    from gtmodel.codegen.controller_file import CONTROLLER_FORMAT, CONTROLLER_KEYS
    from gtmodel.control.mpc import MPC_METHODS, MPC_SOLVERS
    from gtmodel.modeling.simulation.explicit import STEP_METHODS
    from gtmodel.problems.kinds.schemas import estimator_ilc, loop, mpc

    assert loop.STEP_METHOD_NAMES == tuple(STEP_METHODS)
    assert (mpc.MPC_METHOD_NAMES, mpc.MPC_SOLVER_NAMES) == (tuple(MPC_METHODS), tuple(MPC_SOLVERS))
    assert estimator_ilc.BUNDLE_FORMAT == CONTROLLER_FORMAT
    assert tuple(estimator_ilc.EstimatorILCFile.model_fields) == CONTROLLER_KEYS


def test_the_readers_are_the_declared_ones():
    from gtmodel.codegen.controller_file import load_controller
    from gtmodel.problems.mpc_file import MPCFile, load_mpc_file
    from gtmodel.problems.tracking_file import TrackingFile, load_tracking_file

    readers = {name: kind.reader.split(":") for name, kind in LOOP_KINDS.items()}
    loaded = {name: getattr(__import__(module, fromlist=[fn]), fn) for name, (module, fn) in readers.items()}
    assert loaded == {"mpc": load_mpc_file, "tracking_controller": load_tracking_file, "estimator_ilc": load_controller}
    assert (get_schema("mpc"), get_schema("tracking_controller")) == (MPCFile, TrackingFile)


def test_one_tracking_file_class():
    import gtmodel.problems.kinds.schemas as schemas
    from gtmodel.problems.tracking_file import TrackingFile

    modules = [p.stem for p in (REPO / "gtmodel" / "problems" / "kinds" / "schemas").glob("*.py")]
    found = {m for m in modules if getattr(__import__(f"{schemas.__name__}.{m}", fromlist=["x"]), "TrackingFile", None) is not None}
    assert found == {"tracking_controller"} and TrackingFile.__module__ == "gtmodel.problems.kinds.schemas.tracking_controller"


def test_renamed_kind_is_the_new_one_with_a_warning(caplog):
    with caplog.at_level("WARNING", logger="gtmodel"):
        assert canonical_kind("tracking", "f.toml") == "replay" and get_kind("tracking") is KINDS["replay"]
    assert RENAMED == {"tracking": "replay"}
    assert "f.toml: kind = 'tracking' is deprecated: it is now kind = 'replay'" in caplog.text
    assert canonical_kind("mpc") == "mpc" and canonical_kind(3) == 3


@pytest.mark.parametrize("call, name, match", [
    (get_kind, "mpc", r"'mpc' is a loop-controller file kind, generated and checked by code generation, not solved: gtmodel codegen --mpc"),
    (get_kind, "nope", r"unknown problem kind 'nope': expected one of point_to_point"),
    (get_schema, "nope", r"unknown kind 'nope': expected one of point_to_point.*, mpc, tracking_controller, estimator_ilc"),
    (get_loop_kind, "replay", r"unknown loop-controller file kind 'replay': expected one of mpc, tracking_controller, estimator_ilc"),
])
def test_unknown_kinds(call, name, match):
    with pytest.raises(ProblemError, match=match):
        call(name)


def test_solving_a_loop_file_names_its_route(tmp_path):
    bad = tmp_path / "m.toml"
    bad.write_text('kind = "mpc"\n')
    with pytest.raises(ProblemError, match=r"m\.toml: field 'kind': expected a problem kind \(.*\); 'mpc' names a loop-controller file "
                                           r"\(MPC file\), generated and checked by gtmodel codegen --mpc FILE\.toml"):
        load_problem(bad)


def test_docs_schemas_hold_every_kind():
    written = {p.name for p in (REPO / "docs" / "schemas").glob("*.schema.json")}
    assert written == {f"{k}.schema.json" for k in all_kinds()}
    assert json.loads((REPO / "docs" / "schemas" / "mpc.schema.json").read_text())["title"] == "gtmodel MPC file, kind mpc"


def test_a_replay_file_is_shipped():
    assert tomllib.loads((PROBLEMS_DIR / "l1_tracking.toml").read_text())["kind"] == "replay"


@pytest.mark.parametrize("name, path", [(k, p) for k, files in SHIPPED.items() for p in files if "codegen" in p.parts],
                         ids=lambda v: getattr(v, "name", v))
def test_shipped_loop_files_name_their_schema(name, path):
    # as the shipped problem files do: an editor validates them as they are typed
    first = path.read_text(encoding="utf-8").splitlines()[0]
    assert first == f"#:schema ../../docs/schemas/{name}.schema.json" and (path.parent / first.split()[1]).resolve().is_file()


def test_generated_loop_step_is_the_declared_output(tmp_path):
    # the --out contract of the loop kinds against what generate_loop_step writes (a tracking controller of the
    # dc motor, no compile): the declared files, nothing else
    import numpy as np

    from gtmodel.codegen.loop_step import generate_loop_step, tracking_step
    from gtmodel.control.tracking import tracking_controller
    from gtmodel.modeling import explicit_ode
    from gtmodel.problems.user_model import load_user_model

    ode = explicit_ode(load_user_model(REPO / "models" / "dc_motor.py", "DCMotorModel"))
    t = np.linspace(0.0, 0.1, 11)
    u = np.full((11, 1), 2.0)
    x, _ = ode.simulate_steps(ode.step(0.01, "rk4", substeps=10), u[:-1])
    generate_loop_step(tracking_step(tracking_controller(ode, t, x, u, dt=0.004), "m"), tmp_path, prefix="gt_m")
    declared = {f.format(prefix="gt_m") for f in LOOP_KINDS["tracking_controller"].output if not f.endswith("/")}
    assert {p.name for p in tmp_path.iterdir()} == declared
    assert LOOP_KINDS["mpc"].output == LOOP_KINDS["tracking_controller"].output


def test_a_saved_bundle_validates_against_its_schema(tmp_path):
    # a second validator (jsonschema) and the declared schema on what save_controller writes; load_controller reads it back
    import numpy as np

    from gtmodel.codegen import EstimatorILCBundle, load_controller, save_controller
    from gtmodel.estimation.ilc.iteration import ilc_correction_function

    table = np.array([[1e-4, -2e-4, 0.0], [3e-4, 0.0, 1e-5]])
    bundle = EstimatorILCBundle(ilc_correction=ilc_correction_function(table), ilc_table=table)
    path = save_controller(tmp_path / "c.json", bundle, description="test")
    data = json.loads(path.read_text())
    jsonschema.Draft202012Validator(json_schema("estimator_ilc")).validate(data)
    get_schema("estimator_ilc").model_validate(data)
    assert load_controller(path).ilc_table.shape == (2, 3)
