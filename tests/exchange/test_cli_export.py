"""``gtmodel export-fmu``: exit codes, messages and the FMU it writes (validated by FMPy)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from gtmodel.cli import EXIT_BAD_INPUT, EXIT_OK, main

from tests.conftest import REPO

DATA = Path(__file__).parent / "data"


def test_export_a_user_model(tmp_path, capsys):
    fmpy_validation = pytest.importorskip("fmpy.validation")
    out = tmp_path / "cp.fmu"
    code = main(["export-fmu", "--model", str(REPO / "models" / "cart_pendulum.py") + ":CartPendulum", "--out", str(out)])
    text = capsys.readouterr().out
    assert code == EXIT_OK and "FMI 2.0 ModelExchange + CoSimulation" in text and "4 states, 1 inputs, 5 parameters" in text
    assert fmpy_validation.validate_fmu(str(out)) == []


@pytest.mark.slow  # default-run budget: the Modelica path is also run by tests/exchange/test_modelica.py
def test_export_a_modelica_model_as_fmi3(tmp_path, capsys):
    pytest.importorskip("pymoca")
    fmpy_validation = pytest.importorskip("fmpy.validation")
    out = tmp_path / "osc.fmu"
    code = main(["export-fmu", "--modelica", str(DATA / "oscillator.mo"), "--out", str(out), "--fmi-version", "3.0"])
    assert code == EXIT_OK and "FMI 3.0 ModelExchange + CoSimulation" in capsys.readouterr().out
    assert fmpy_validation.validate_fmu(str(out)) == []


@pytest.mark.parametrize(
    ("argv", "match"),
    [
        (["--modelica", str(DATA / "syntax_error.mo")], "syntax_error.mo:5: Modelica syntax error"),
        (["--modelica", str(DATA / "bouncing_ball_when.mo")], "bouncing_ball_when.mo:7: unsupported Modelica construct: when-clause"),
        (["--model", "nothere.py:Model"], "nothere.py: no such model file"),
        (["--robot", "L1", "--step", "-1"], "step: expected a positive number of seconds"),
    ],
)
def test_bad_input_exits_2_naming_it(tmp_path, capsys, argv, match):
    pytest.importorskip("pymoca")
    code = main(["export-fmu", *argv, "--out", str(tmp_path / "m.fmu")])
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT and match in err and "Traceback" not in err


def test_a_missing_model_file_is_reported_without_importing_casadi(tmp_path):
    script = ("import sys\nfrom gtmodel.cli import main\ncode = main(sys.argv[1:])\n"
              "print('IMPORTED', 'casadi' in sys.modules, code)\n")
    proc = subprocess.run([sys.executable, "-c", script, "export-fmu", "--model", "nope.py:M", "--out", "m.fmu"],
                          capture_output=True, text=True, cwd=tmp_path, timeout=120, env=dict(os.environ, PYTHONPATH=str(REPO)))
    assert proc.stdout.splitlines()[-1] == f"IMPORTED False {EXIT_BAD_INPUT}", proc.stdout + proc.stderr
