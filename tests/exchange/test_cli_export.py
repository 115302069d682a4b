"""``gtmodel export-fmu``: exit codes, messages and the FMU it writes (validated by FMPy)."""

from __future__ import annotations

import os
import re
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


def test_import_fmu_lists_and_simulates(tmp_path, capsys):
    from gtmodel.exchange import export_fmu
    from gtmodel.problems.user_model import load_user_model

    model = load_user_model(REPO / "models" / "cart_pendulum.py", "CartPendulum")
    fmu = export_fmu(model, tmp_path / "cp.fmu", interface="me").path
    csv = tmp_path / "run.csv"
    code = main(["import-fmu", str(fmu), "--stop-time", "1.0", "--points", "11", "--out", str(csv)])
    text = capsys.readouterr().out
    assert code == EXIT_OK and "states      s, v, theta, omega" in text and "directional derivatives of the FMU" in text
    rows = csv.read_text().splitlines()
    assert rows[0] == "t,s,v,theta,omega,tip_x,tip_y,energy" and len(rows) == 12
    assert abs(float(rows[-1].split(",")[6]) + 0.5) < 1e-12  # at rest hanging down: tip_y = -l


@pytest.mark.parametrize(
    ("content", "match"),
    [(None, "nothere.fmu: no such FMU file"), (b"garbage", r"bad.fmu: not an FMU \(corrupt: not a zip archive\)")],
)
def test_import_fmu_bad_file_exits_2(tmp_path, capsys, content, match):
    path = tmp_path / ("nothere.fmu" if content is None else "bad.fmu")
    if content is not None:
        path.write_bytes(content)
    assert main(["import-fmu", str(path)]) == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert re.search(match, err) and "Traceback" not in err
