"""The lead-through controller step as generated C (issue 29, item 5).

Independent references: the very CasADi step Function of gtmodel.estimation.lead_through
evaluated from Python over the same record (``mapaccum``) — a scripted session and a
simulated surface-tracking run; a step of another law must fail the check; the stand-alone
program (strict flags, heap calls counted by ``-Wl,--wrap``) under valgrind's memcheck.
"""

from __future__ import annotations

import contextlib
import io
import shutil

import numpy as np
import pytest

from gtmodel.cli import main
from gtmodel.codegen import Controller, check_controller, compile_shared, generate, load_controller, load_library, save_controller
from gtmodel.codegen.check.lead_through import (
    build_lead_through_program,
    lead_through_record,
    python_lead_through_run,
    run_lead_through_program,
)
from gtmodel.errors import InputError
from gtmodel.estimation.lead_through import LeadThroughLaw
from gtmodel.estimation.lead_through.experiments import surface_tracking

needs_valgrind = pytest.mark.skipif(shutil.which("valgrind") is None, reason="valgrind not on PATH")


@pytest.fixture(scope="module")
def law():
    return LeadThroughLaw()


@pytest.fixture(scope="module")
def built(tmp_path_factory, law):
    root = tmp_path_factory.mktemp("lead_through")
    gen = generate("L1", root / "src", functions=(), prefix="gt", controller=Controller(lead_through_step=law.step_function()))
    lib = load_library(gen, compile_shared(gen, root / "build", werror=True, extra_flags=("-pedantic",)))
    return gen, lib, root / "build"


def _record_of(run):
    return {"F_h": run.F_h, "F_t": run.F_t, "n_n": np.tile(run.n_n, (len(run.t), 1)), "x0": np.zeros(8)}


def test_check_over_the_scripted_session_passes(built):
    gen, lib, _ = built
    report = check_controller(gen, library=lib)
    assert report.passed, "\n".join(report.summary_lines())
    names = {f.name: f for f in report.functions}
    assert names["lead_through_update"].max_abs_diff <= 1e-12 and names["lead_through_step"].max_abs_diff <= 1e-12
    assert all(p.passed for p in report.probes) and len(report.probes) >= 19


def test_check_over_a_simulated_run_equals_python(built):
    # the whole recorded run of the Figure 8.4 experiment, C against the Python step to 1e-12
    gen, lib, _ = built
    run = surface_tracking().run
    report = check_controller(gen, library=lib, records={"lead_through_step": _record_of(run)})
    assert report.passed and report.n == len(run.t)
    # and the Python step over the record is the simulation's controller (same graph)
    ref = python_lead_through_run(LeadThroughLaw().step_function(), _record_of(run))
    np.testing.assert_array_equal(ref["V_tool"], run.V_tool)


def test_a_step_of_another_law_fails_the_check(built):
    gen, lib, _ = built
    other = Controller(lead_through_step=LeadThroughLaw(K=0.006).step_function())
    gen_other = gen.__class__(**{**gen.__dict__, "controller": other})
    report = check_controller(gen_other, library=lib)
    assert not report.passed


@pytest.mark.slow
@needs_valgrind
def test_stand_alone_run_is_valgrind_clean_and_heap_free(built, tmp_path):
    gen, _, build = built
    record = lead_through_record(cycles=200)
    program = build_lead_through_program(gen, record, tmp_path)
    proc, rows = run_lead_through_program(program, tmp_path / "run.bin", valgrind=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "heap calls in the controller 0" in proc.stdout and "ERROR SUMMARY: 0 errors" in proc.stderr
    ref = python_lead_through_run(LeadThroughLaw().step_function(), record)
    np.testing.assert_allclose(rows[:, 9:15], ref["V_tool"], atol=1e-12)


def test_cli_codegen_from_a_controller_file(tmp_path, law):
    save_controller(tmp_path / "controller.json", Controller(lead_through_step=law.step_function()))
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = main(["codegen", "--controller", str(tmp_path / "controller.json"), "--out", str(tmp_path / "c"), "--check"])
    assert code == 0, buf.getvalue()
    header = (tmp_path / "c" / "gt.h").read_text()
    assert "PASSED" in buf.getvalue()
    assert all(f"{name}(" in header for name in ("gt_lead_through_step", "gt_lead_through_init", "gt_lead_through_update"))


def test_controller_file_round_trip(tmp_path, law):
    save_controller(tmp_path / "c.json", Controller(lead_through_step=law.step_function()))
    back = load_controller(tmp_path / "c.json")
    assert back.functions == ("lead_through_step",)


@pytest.mark.parametrize("bad, match", [
    ("not a function", r"lead_through_step: expected a casadi.Function"),
    ("kalman", r"lead_through_step: expected a casadi.Function \(x, F_h, F_t, n_n\)"),
])
def test_bad_step_functions_are_refused(bad, match):
    import casadi as ca

    x = ca.SX.sym("x")
    value = bad if bad == "not a function" else ca.Function("f", [x], [2 * x], ["x"], ["y"])
    with pytest.raises(InputError, match=match):
        Controller(lead_through_step=value)


def test_record_with_a_non_unit_normal_is_refused(built):
    gen, lib, _ = built
    record = lead_through_record(cycles=20)
    record["n_n"] = record["n_n"] * 2
    with pytest.raises(InputError, match=r"records\['lead_through_step'\]: record\['n_n'\]: expected unit normals"):
        check_controller(gen, library=lib, records={"lead_through_step": record})
