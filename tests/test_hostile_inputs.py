"""The exit-code contract at the edges (docs/reliability.md): model names a user may write,
``codegen --out`` into a folder of the user's own files, an ``--out`` too long for the file
system, a tracking file naming a problem whose ``kind`` is a list, memory running out, and a
signal that CasADi turned into another exception.

Independent reference: the exit codes of :data:`gtmodel.status.EXIT_CODES`, the bytes of the
user's files on disk, and CasADi's own rule for Function names (``casadi.Function`` accepts
the mapped name).
"""

from __future__ import annotations

import json

import casadi as ca
import pytest

from gtmodel import _signals
from gtmodel.cli import EXIT_BAD_INPUT, EXIT_INTERRUPTED, EXIT_OK, main
from gtmodel.errors import InputError
from gtmodel.modeling import Model
from gtmodel.modeling.dae import casadi_name
from gtmodel.problems import run as run_module

from .conftest import PROBLEMS_DIR

MODEL_FILE = """
from gtmodel.modeling import Model


class Decay(Model):
    def __init__(self):
        super().__init__({name!r})
        x = self.state("x", start=1.0)
        k = self.parameter("k", 2.0)
        self.equation(self.der(x), -k * x)
        self.output("y", 3.0 * x)
"""


@pytest.mark.parametrize(("name", "mapped"), [("my-model", "my_model"), ("cart__pole", "cart_pole"), ("x.y", "x_y"),
                                               ("2dof", "m_2dof"), ("_private_", "private"), ("Größe", "Gr_e")])
def test_model_names_map_to_valid_casadi_names(name, mapped):
    assert casadi_name(name) == mapped
    x = ca.SX.sym("x")
    assert ca.Function(f"{mapped}_ode", [x], [x]).name() == f"{mapped}_ode"  # CasADi's own check accepts it


@pytest.mark.parametrize("name", ["---", "a\nb", "x" * 201, "é"])
def test_names_without_a_mapping_are_refused_at_once(name):
    with pytest.raises(InputError, match="model name .*: expected at most 200 printable characters with a letter or digit"):
        Model(name)


@pytest.mark.parametrize("name", ["my-model", "cart__pole", "x.y"])
def test_codegen_of_a_model_with_a_users_name_exits_0(tmp_path, capsys, name):
    f = tmp_path / "decay.py"
    f.write_text(MODEL_FILE.format(name=name))
    assert main(["codegen", "--model", f"{f}:Decay", "--out", str(tmp_path / "c")]) == EXIT_OK, capsys.readouterr().err
    assert (tmp_path / "c" / f"gt_{casadi_name(name)}.h").is_file()


def test_codegen_out_into_a_folder_of_the_users_files_is_refused_and_left_alone(tmp_path, capsys):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "gt_L1.h").write_text("my own notes\n")
    assert main(["codegen", "--robot", "L1", "--functions", "ik", "--out", str(mine)]) == EXIT_BAD_INPUT
    assert "--out" in capsys.readouterr().err and (mine / "gt_L1.h").read_text() == "my own notes\n"
    assert main(["codegen", "--robot", "L1", "--functions", "ik", "--out", str(tmp_path / "gen")]) == EXIT_OK
    assert main(["codegen", "--robot", "L1", "--functions", "ik", "--out", str(tmp_path / "gen")]) == EXIT_OK  # its own folder


def test_an_out_name_too_long_for_the_file_system_exits_2_naming_it(tmp_path, capsys):
    out = tmp_path / ("a" * 300)
    assert main(["solve", str(PROBLEMS_DIR / "l1_time_optimal.toml"), "--out", str(out), "--quiet", "--no-plots"]) == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert "a" * 300 in err and "internal error" not in err


def test_a_tracking_file_naming_a_problem_whose_kind_is_a_list_exits_2(tmp_path, capsys):
    (tmp_path / "l1_time_optimal.toml").write_text(
        (PROBLEMS_DIR / "l1_time_optimal.toml").read_text().replace('kind = "point_to_point"', 'kind = ["point_to_point"]'))
    track = tmp_path / "track.toml"
    track.write_text((PROBLEMS_DIR / "l1_tracking.toml").read_text())
    code = main(["solve", str(track), "--out", str(tmp_path / "out"), "--quiet", "--no-plots"])
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT and "is of kind a list, not a kind name" in err and "unhashable" not in err


def test_memory_running_out_ends_as_invalid_input_with_a_summary(tmp_path, monkeypatch, capsys):
    def exhausted(*args, **kwargs):
        raise MemoryError()

    monkeypatch.setattr(run_module, "solve_problem", exhausted)
    out = tmp_path / "out"
    code = main(["solve", str(PROBLEMS_DIR / "l1_time_optimal.toml"), "--out", str(out), "--quiet", "--no-plots"])
    summary = json.loads((out / "summary.json").read_text())
    assert (code, summary["status"]) == (EXIT_BAD_INPUT, "invalid_input")
    assert "out of memory" in summary["message"] and "Traceback" not in capsys.readouterr().err


@pytest.mark.parametrize("exc", [NotImplementedError, SystemError])
def test_a_signal_casadi_turned_into_another_exception_ends_interrupted(tmp_path, monkeypatch, exc):
    def interrupted_inside_casadi(*args, **kwargs):
        _signals._state.count += 1  # what the handler counted while CasADi held the signal
        raise exc("CasADi: interrupted")

    monkeypatch.setattr(run_module, "solve_problem", interrupted_inside_casadi)
    out = tmp_path / "out"
    code = main(["solve", str(PROBLEMS_DIR / "l1_time_optimal.toml"), "--out", str(out), "--quiet", "--no-plots"])
    assert (code, json.loads((out / "summary.json").read_text())["status"]) == (EXIT_INTERRUPTED, "interrupted")
