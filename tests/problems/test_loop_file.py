"""Loop-controller files (``[mpc]``, ``[controller]``, ``[reference]``, ``[check]``) checked at load.

Every number finite and in its declared range, ``name`` a C identifier, ``overrides`` only with
a reference problem, and the size estimates (:func:`gtmodel.problems.loop_file.loop_samples`,
:func:`gtmodel.problems.mpc_file.qp_entries`) refused before anything is solved, built or
written: each refusal names the file and the field, and ``gtmodel codegen`` exits 2 without
an output folder.

References: the declared ranges of :mod:`gtmodel.problems.loop_file` (independent of the
code paths: the hostile values of issue 44, NaN, inf, 1e300, 1e-12 s, non-identifier names);
the "before anything is solved" claim is checked by a second method, the reference solvers
replaced by a function that fails the test; the size estimates against hand-counted sizes.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from gtmodel._tables import write_table
from gtmodel.cli import main
from gtmodel.errors import ProblemError
from gtmodel.problems import loop_file, mpc_file
from gtmodel.problems.loop_file import MAX_LOOP_SAMPLES, MAX_TABLE_NUMBERS, loop_samples
from gtmodel.problems.base import ProblemFile
from gtmodel.control.problem import substep_states
from gtmodel.problems.loop_file import loop_inputs, read_loop_file
from gtmodel.problems.mpc_file import MAX_CODE_BYTES, MAX_QP_ENTRIES, code_bytes, load_mpc_file, qp_entries
from gtmodel.problems.registry import LOOP_KINDS

from ..conftest import REPO

MPC_L1 = (REPO / "codegen" / "mpc" / "l1_mpc.toml").read_text()
MPC_MOTOR = (REPO / "codegen" / "mpc" / "dc_motor_mpc.toml").read_text()
TRK_L1 = (REPO / "codegen" / "controllers" / "l1_tracking.toml").read_text()
TRK_MOTOR = (REPO / "codegen" / "controllers" / "dc_motor_tracking.toml").read_text()
_TABLE_REFERENCE = 'file = "ref.csv"'

#: (case, loader, file text, original, replacement, field named in the error)
BAD = [
    # [check]: NaN, inf and negative magnitudes (issue 44: built for 78 s, then GT_BAD_ARGUMENT)
    ("noise nan", "mpc", MPC_MOTOR, "noise = [1e-3, 1e-3, 1e-2]", "noise = [nan, 0.0, 0.0]", "check.noise[0]"),
    ("noise inf", "tracking_controller", TRK_MOTOR, "noise = [1e-3, 1e-3, 1e-2]", "noise = [1e-3, inf, 1e-2]", "check.noise[1]"),
    ("noise negative", "mpc", MPC_L1, "noise = [1e-6,", "noise = [-1e-6,", "check.noise[0]"),
    ("noise huge", "tracking_controller", TRK_L1, "noise = [1e-6,", "noise = [1e300,", "check.noise[0]"),
    ("noise not a list", "mpc", MPC_MOTOR, "noise = [1e-3, 1e-3, 1e-2]", 'noise = "high"', "check.noise"),
    ("noise of another length", "mpc", MPC_MOTOR, "noise = [1e-3, 1e-3, 1e-2]", "noise = [1e-3]", "check.noise"),
    ("disturbance nan", "mpc", MPC_MOTOR, "disturbance = [-1.0]", "disturbance = [nan]", "check.disturbance[0]"),
    ("disturbance -inf", "tracking_controller", TRK_L1, "disturbance = [20.0,", "disturbance = [-inf,", "check.disturbance[0]"),
    ("disturbance huge", "mpc", MPC_L1, "disturbance = [20.0,", "disturbance = [1e300,", "check.disturbance[0]"),
    ("disturbance of another length", "tracking_controller", TRK_MOTOR, "disturbance = [-1.0]", "disturbance = [-1.0, 2.0]", "check.disturbance"),
    ("disturbance time nan", "mpc", MPC_MOTOR, "disturbance_time = 0.1", "disturbance_time = nan", "check.disturbance_time"),
    ("mass factor inf", "mpc", MPC_L1, "mass_factor = 1.1", "mass_factor = inf", "check.mass_factor"),
    ("parameter factor nan", "tracking_controller", TRK_MOTOR, "parameter_factor = 1.1", 'parameter_factor = 1.1\nparameter_factors = { "r.R" = nan }',
     "check.parameter_factors.r.R"),
    ("parameter factor huge", "mpc", MPC_MOTOR, "parameter_factor = 1.1", 'parameter_factor = 1.1\nparameter_factors = { "r.R" = 1e300 }',
     "check.parameter_factors.r.R"),
    ("max_step_time inf", "mpc", MPC_MOTOR, "max_ratio = 0.5", "max_ratio = 0.5\nmax_step_time = inf", "check.max_step_time"),
    ("unknown error state", "tracking_controller", TRK_L1, 'error_states = ["T[0]"', 'error_states = ["T[7]"', "check.error_states.T[7]"),
    ("compliance of a user model", "mpc", MPC_MOTOR, "\ndelay = 1", "\ndelay = 1\ncompliance = true", "check.compliance"),
    # weights: finite, >= 0, <= 1e12
    ("state weight 1e300", "mpc", MPC_L1, '"T[0]" = 1e8', '"T[0]" = 1e300', "mpc.state_weights.T[0]"),
    ("state weight above 1e12", "tracking_controller", TRK_L1, '"T[1]" = 1e8', '"T[1]" = 2e12', "controller.state_weights.T[1]"),
    ("input weight nan", "mpc", MPC_MOTOR, '"src.v" = 1e-3', '"src.v" = nan', "mpc.input_weights.src.v"),
    ("input weight inf", "tracking_controller", TRK_MOTOR, '"src.v" = 1e-3', '"src.v" = inf', "controller.input_weights.src.v"),
    ("terminal weight negative", "mpc", MPC_MOTOR, "input_weights =", 'terminal_weights = { "emf.phi" = -1.0 }\ninput_weights =',
     "mpc.terminal_weights.emf.phi"),
    ("weight not a number", "mpc", MPC_MOTOR, '"src.v" = 1e-3', '"src.v" = "high"', "mpc.input_weights.src.v"),
    ("integral weight 1e300", "tracking_controller", TRK_MOTOR, '"emf.phi" = 1e4 }', '"emf.phi" = 1e300 }', "controller.integral_weights.emf.phi"),
    ("integral weight nan", "tracking_controller", TRK_MOTOR, '"emf.phi" = 1e4 }', '"emf.phi" = nan }', "controller.integral_weights.emf.phi"),
    ("integral of an unknown state", "tracking_controller", TRK_MOTOR, '"emf.phi" = 1e4 }', '"phi" = 1e4 }', "controller.integral_weights.phi"),
    ("constraint weight nan", "mpc", MPC_L1, "constraint_every = 4", "constraint_every = 4\nconstraint_weight = nan", "mpc.constraint_weight"),
    # the period: 1e-5 .. 1 s (issue 44: 1e-12 s ended in "out of memory", 2.18 TiB)
    ("period 1e-12", "mpc", MPC_L1, "period = 0.004 ", "period = 1e-12 ", "mpc.period"),
    ("period below 1e-5", "tracking_controller", TRK_MOTOR, "period = 0.004", "period = 9e-6", "controller.period"),
    ("period nan", "mpc", MPC_MOTOR, "period = 0.004", "period = nan", "mpc.period"),
    ("period inf", "tracking_controller", TRK_L1, "period = 0.004 ", "period = inf ", "controller.period"),
    ("period above 1 s", "mpc", MPC_MOTOR, "period = 0.004", "period = 2.0", "mpc.period"),
    # the horizon: 1 .. 1000, blocks too, and the horizon problem's size estimate
    ("horizon 1e6", "mpc", MPC_L1, "horizon = 20 ", "horizon = 1000000 ", "mpc.horizon"),
    ("horizon a float", "mpc", MPC_L1, "horizon = 20 ", "horizon = 20.0 ", "mpc.horizon"),
    ("blocks above 1000", "mpc", MPC_L1, "blocks = 5 ", "blocks = 2000 ", "mpc.blocks"),
    # 300 x 4 x 300 + 300^2 = 450,000 entries (about 26 MB of C) > MAX_QP_ENTRIES
    ("horizon problem too large, one block per period", "mpc", MPC_MOTOR, "horizon = 20", "horizon = 300", "mpc.horizon"),
    # the generated C estimated before building (issue 67: 100 substeps with hard rows compiled for 437 s): about 18 MB > 16 MB
    ("generated C too large, 100 substeps with hard rows", "mpc", MPC_MOTOR, "substeps = 2", "substeps = 100\nhard_constraints = true",
     "mpc.substeps"),
    ("generated C too large, 60 radau2 substeps", "mpc", MPC_MOTOR, 'method = "rk4"\nsubsteps = 2', 'method = "radau2"\nsubsteps = 60',
     "mpc.substeps"),
    # the number of loop periods: the settling hold alone is too long at 10 us
    ("settling hold of 6 million periods", "mpc", MPC_MOTOR, "period = 0.004", "period = 1e-5",
     "mpc.period"),  # with settle_time 60 s below
    # bounds: finite, |.| <= 1e7
    ("u_lb nan", "mpc", MPC_MOTOR, "period = 0.004", "period = 0.004\nu_lb = [nan]\nu_ub = [24.0]", "mpc.u_lb[0]"),
    ("u_ub 1e300", "tracking_controller", TRK_MOTOR, "period = 0.004", "period = 0.004\nu_lb = [-24.0]\nu_ub = [1e300]", "controller.u_ub[0]"),
    ("u_ub -inf", "mpc", MPC_L1, "period = 0.004 ", "period = 0.004\nu_ub = [450.0, -inf, 450.0] ", "mpc.u_ub[1]"),
    ("u_lb of another length", "tracking_controller", TRK_L1, "period = 0.004 ", "period = 0.004\nu_lb = [-1.0, -1.0] ", "controller.u_lb"),
    ("u_lb above the model's upper bound", "mpc", MPC_MOTOR, "period = 0.004", "period = 0.004\nu_lb = [5.0]\nu_ub = [-5.0]", "mpc.u_lb[0]"),
    ("state bound nan", "mpc", MPC_MOTOR, "input_weights =", 'state_ub = { "rotor.w" = nan }\ninput_weights =', "mpc.state_ub.rotor.w"),
    ("state bound 1e300", "mpc", MPC_MOTOR, "input_weights =", 'state_lb = { "rotor.w" = -1e300 }\ninput_weights =', "mpc.state_lb.rotor.w"),
    # names: C identifiers of at most 40 characters
    ("name with a hyphen", "mpc", MPC_L1, 'name = "l1_mpc"', 'name = "l1-mpc"', "name"),
    ("name that is C code", "tracking_controller", TRK_L1, 'name = "l1_tracking"', 'name = "p\\"; } int system(const char *); /*"', "name"),
    ("name with a newline", "mpc", MPC_MOTOR, 'name = "dc_motor_mpc"', 'name = "dc_motor_mpc\\n"', "name"),
    ("name starting with a digit", "tracking_controller", TRK_MOTOR, 'name = "dc_motor_tracking"', 'name = "2motor"', "name"),
    ("name of 41 characters", "mpc", MPC_MOTOR, 'name = "dc_motor_mpc"', f'name = "{"a" * 41}"', "name"),
    ("name empty", "mpc", MPC_MOTOR, 'name = "dc_motor_mpc"', 'name = ""', "name"),
    ("name not a string", "tracking_controller", TRK_MOTOR, 'name = "dc_motor_tracking"', "name = 3", "name"),
    # overrides only with a reference problem
    ("overrides with a table", "mpc", MPC_MOTOR, 'problem = "../../problems/dc_motor_move.toml"', _TABLE_REFERENCE, "reference.overrides"),
    ("overrides with a table (tracking)", "tracking_controller", TRK_L1, 'problem = "../../problems/l1_time_optimal.toml"', _TABLE_REFERENCE,
     "reference.overrides"),
    ("both problem and file", "tracking_controller", TRK_MOTOR, 'problem = "../../problems/dc_motor_move.toml"',
     'problem = "../../problems/dc_motor_move.toml"\n' + _TABLE_REFERENCE, "reference"),
]

#: The declared kinds' readers (gtmodel.problems.registry.LOOP_KINDS), the ones gtmodel codegen calls.
LOADERS = {name: LOOP_KINDS[name].read for name in ("mpc", "tracking_controller")}


def _text(text: str, old: str, new: str) -> str:
    assert old in text
    text = text.replace(old, new, 1).replace('"../../', f'"{REPO}/')  # written elsewhere: the shipped references by absolute path
    if old == "period = 0.004" and new == "period = 1e-5":
        text = text.replace("settle_time = 0.3", "settle_time = 60.0")
    return text


@pytest.fixture
def no_solve(monkeypatch):
    """The reference solvers replaced: a refusal at load never reaches them."""

    def fail(*args, **kwargs):
        raise AssertionError("the reference was solved before the file was refused")

    monkeypatch.setattr(loop_file, "solve_problem", fail)
    monkeypatch.setattr(loop_file, "solve_point_to_point", fail)


@pytest.mark.parametrize("case, kind, text, old, new, field", BAD, ids=[b[0] for b in BAD])
def test_bad_loop_file_is_refused_at_load_naming_file_and_field(tmp_path, no_solve, case, kind, text, old, new, field):
    path = tmp_path / "controller.toml"
    path.write_text(_text(text, old, new))
    with pytest.raises(ProblemError, match=re.escape(f"{path}: field '{field}'")):
        LOADERS[kind](path)


@pytest.mark.parametrize("route, kind, text, old, new", [
    ("--mpc", "mpc", MPC_MOTOR, "noise = [1e-3, 1e-3, 1e-2]", "noise = [nan, 0.0, 0.0]"),
    ("--controller", "tracking_controller", TRK_L1, "period = 0.004 ", "period = 1e-12 "),
    ("--mpc", "mpc", MPC_L1, '"T[0]" = 1e8', '"T[0]" = 1e300'),
], ids=["mpc noise nan", "tracking period 1e-12", "mpc weight 1e300"])
def test_bad_loop_file_exits_2_and_writes_nothing(tmp_path, capsys, no_solve, route, kind, text, old, new):
    path = tmp_path / "controller.toml"
    path.write_text(_text(text, old, new))
    out = tmp_path / "out"
    code = main(["codegen", route, str(path), "--out", str(out), "--check"])
    err = capsys.readouterr().err
    assert code == 2
    assert str(path) in err and "field '" in err
    assert not out.exists()


def _motor_table(tmp_path, duration: float) -> None:
    t = np.linspace(0.0, duration, 11)
    write_table(tmp_path / "ref.csv", ["t", "ind.i", "emf.phi", "rotor.w", "src.v"], np.column_stack([t, 0 * t, t, 1 + 0 * t, 2 + 0 * t]))


def _table_file(tmp_path, text: str, period: str) -> str:
    text = text.replace('problem = "../../problems/dc_motor_move.toml"', _TABLE_REFERENCE).replace("period = 0.004", f"period = {period}")
    return "\n".join(line for line in text.splitlines() if not line.startswith("overrides")).replace('"../../', f'"{REPO}/') + "\n"


def test_a_long_table_at_a_short_period_is_refused_before_it_is_sampled(tmp_path, no_solve, monkeypatch):
    # 10 s of motion at 10 us: 1,000,001 periods + the 0.3 s hold, more than MAX_LOOP_SAMPLES (the hold alone: 30,000, accepted)
    _motor_table(tmp_path, 10.0)
    (tmp_path / "m.toml").write_text(_table_file(tmp_path, MPC_MOTOR, "1e-5"))
    monkeypatch.setattr(loop_file, "hold_input", lambda *a: pytest.fail("the reference was sampled and held"))
    with pytest.raises(ProblemError, match=re.escape(f"{tmp_path / 'm.toml'}: field 'mpc.period'") + r".*1030001 periods"):
        load_mpc_file(tmp_path / "m.toml")


def test_a_table_within_the_limits_is_accepted(tmp_path):
    # the same motor file with a 0.2 s table at the 4 ms loop (the limits leave the usual files alone)
    _motor_table(tmp_path, 0.2)
    (tmp_path / "m.toml").write_text(_table_file(tmp_path, MPC_MOTOR, "0.004"))
    assert load_mpc_file(tmp_path / "m.toml").controller.length == 51 + 75


def test_crossed_input_bounds_are_refused(tmp_path):
    _motor_table(tmp_path, 0.2)
    text = _table_file(tmp_path, MPC_MOTOR, "0.004").replace("substeps = 2", "substeps = 2\nu_lb = [5.0]\nu_ub = [-5.0]")
    (tmp_path / "m.toml").write_text(text)
    with pytest.raises(ProblemError, match=re.escape(f"{tmp_path / 'm.toml'}: field 'mpc.u_lb[0]'")):
        load_mpc_file(tmp_path / "m.toml")


@pytest.mark.parametrize("duration, settle, dt, per_sample, expected", [
    (0.0, 0.5, 0.004, 9, 126),        # the hold: 125 periods after the first sample
    (0.68, 0.5, 0.004, 9, 296),       # 170 + 1 + 125 (floor(0.68 / 0.004) = 170)
    (0.999, 0.0, 1e-5, 1, 99_901),    # just within MAX_LOOP_SAMPLES
    (0.5, 0.0, 1e-5, 27, 50_001),     # the L1 tracking's x*, u*, K: 1,350,027 numbers, within MAX_TABLE_NUMBERS
], ids=["hold", "l1 motion", "1 s at 10 us", "tables at 0.5 s"])
def test_loop_samples_counts_the_periods(tmp_path, duration, settle, dt, per_sample, expected):
    # hand-counted: floor(duration / dt) + 1 + round(settle / dt)
    assert loop_samples(ProblemFile(tmp_path / "f.toml"), "mpc.period", duration, settle, dt, per_sample) == expected


@pytest.mark.parametrize("duration, per_sample, what", [
    (1.0, 1, f"a period giving at most {MAX_LOOP_SAMPLES} loop periods"),               # 100,001 periods
    (0.9, 27, f"a period giving at most {MAX_TABLE_NUMBERS} numbers"),                 # 90,001 x 27 = 2,430,027
    (float("nan"), 1, "a reference motion of finite length"),
], ids=["periods", "tables at 0.9 s", "nan"])
def test_loop_samples_refuses_above_its_limits(tmp_path, duration, per_sample, what):
    with pytest.raises(ProblemError, match=re.escape(f"expected {what}")):
        loop_samples(ProblemFile(tmp_path / "f.toml"), "controller.period", duration, 0.0, 1e-5, per_sample)


@pytest.mark.parametrize("horizon, blocks, nx, nu, solver, expected", [
    (20, 5, 6, 3, "sqpmethod", 20 * 9 * 15 + 15 * 15),     # the shipped L1 MPC: 2,925
    (20, 20, 3, 1, "sqpmethod", 20 * 4 * 20 + 20 * 20),    # the shipped motor MPC: 2,000
    (1000, 1000, 6, 3, "sqpmethod", 1000 * 9 * 3000 + 3000 ** 2),
    (1000, 1000, 6, 3, "fatrop", 1000 * 81),
], ids=["l1", "motor", "l1 1000", "fatrop 1000"])
def test_qp_entries_hand_counted(horizon, blocks, nx, nu, solver, expected):
    assert qp_entries(horizon, blocks, nx, nu, solver) == expected


#: The motor's generated C measured (MB of the .c files, generated without the load-time refusal) against code_bytes:
#: (horizon, substeps, operations, MB). Horizons 20 to 200 at 2 substeps (the shipped file's), 10 and 20 substeps with hard
#: rows; measured 2026-11-29 on the step whose Jacobians are the chain rule of the stages' (2026-11-26, CasADi's
#: jacobian() of the whole prediction: 0.73, 4.07, 12.8 MB at horizons 20, 100, 200 and 1.80, 3.60 MB at 10, 20 substeps).
MEASURED_C = [(20, 2, 2328, 0.42), (50, 2, 2328, 0.96), (100, 2, 2328, 1.53), (150, 2, 2328, 2.65), (200, 2, 2328, 4.11),
              (20, 10, 11544, 1.66), (20, 20, 23064, 3.02)]


@pytest.mark.parametrize("horizon, substeps, ops, mb", MEASURED_C, ids=[f"h{h} s{s}" for h, s, _, _ in MEASURED_C])
def test_the_code_size_estimate_bounds_the_measured_c(horizon, substeps, ops, mb):
    # fitted on jacobian()'s code (within 20 % there), the estimate is now an upper bound on the motor's, at most 5x
    # (a refusal on the safe side; long horizons are the most overestimated)
    assert 1.0 < code_bytes(ops, horizon, horizon, 3, 1, "sqpmethod") / (mb * 1e6) < 5.0


@pytest.mark.parametrize("path", sorted((REPO / "codegen" / "mpc").glob("*.toml")), ids=lambda p: p.stem)
def test_the_shipped_mpc_files_are_far_below_the_code_size_limit(path):
    doc, file = read_loop_file(path, "mpc")
    m, seen = doc.mpc, []

    def size(model):
        ops = substep_states(model.ode, m.period, m.method, m.substeps).n_instructions()
        seen.append(code_bytes(ops, m.horizon, m.blocks or m.horizon, model.ode.nx, model.ode.nu, m.solver))
        raise _Stop

    with pytest.raises(_Stop):
        loop_inputs(file, doc, "mpc", before_reference=size)
    assert seen[0] < MAX_CODE_BYTES / 10


class _Stop(Exception):
    """Ends a load before the reference is solved."""


def test_the_shipped_horizons_are_far_below_the_limit():
    assert qp_entries(20, 5, 6, 3, "sqpmethod") < MAX_QP_ENTRIES / 50


def _doc(x: float) -> str:
    """A number as the page writes it (1e-5, 1e12)."""
    return f"{x:g}".replace("e-0", "e-").replace("e+0", "e").replace("e+", "e")


@pytest.mark.parametrize("text", [
    f"| `period` | {_doc(loop_file.MIN_PERIOD_S)} .. {_doc(loop_file.MAX_PERIOD_S)} s |",
    f"| `state_weights`, `input_weights`, `terminal_weights` | 0 .. {_doc(loop_file.MAX_WEIGHT)} each |",
    f"magnitude <= {_doc(loop_file.MAX_MAGNITUDE)}",
    f"at most {MAX_LOOP_SAMPLES:,}",
    f"at most {MAX_TABLE_NUMBERS:,}",
    f"at most {MAX_QP_ENTRIES:,}",
    f"generated C at most {MAX_CODE_BYTES // 1_000_000} MB",
    f"`0.3 MB + horizon ops ({mpc_file.CODE_PER_OPERATION:g} + {mpc_file.CODE_PER_DIRECTION:g} directions)`",
], ids=["period", "weights", "magnitude", "periods", "tables", "qp", "code", "code formula"])
def test_the_documented_ranges_are_the_declared_ones(text):
    # docs/model_in_the_loop.md's table against the constants the schema declares
    assert text in (REPO / "docs" / "model_in_the_loop.md").read_text()
