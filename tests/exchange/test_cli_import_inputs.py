"""``gtmodel import-fmu`` with start values and an input table, and ``export-fmu --interface`` obeyed (issue 67, item 6).

Checked against closed forms: with ``m_pole = 0`` the cart-pendulum's cart is a free mass
``m_cart = 1 kg`` pushed by ``F``, so a force of 1 N held for 0.5 s then 0 from ``v(0) = 2``
gives ``v(1) = 2.5 m/s`` and ``s(1) = 2 + 0.125 + 0.25 = 2.375 m``.
"""

from __future__ import annotations

import pytest

from gtmodel.cli import EXIT_BAD_INPUT, EXIT_OK, main

from tests.conftest import REPO


@pytest.fixture(scope="module")
def fmu(tmp_path_factory):
    from gtmodel.exchange import export_fmu
    from gtmodel.problems.user_model import load_user_model

    model = load_user_model(REPO / "models" / "cart_pendulum.py", "CartPendulum")
    return export_fmu(model, tmp_path_factory.mktemp("fmu") / "cp.fmu", interface="me").path


def _last_row(csv) -> dict[str, float]:
    rows = csv.read_text().splitlines()
    return dict(zip(rows[0].split(","), map(float, rows[-1].split(","))))


def test_start_values_and_an_input_table_drive_the_simulation(fmu, tmp_path, capsys):
    table = tmp_path / "force.csv"
    table.write_text("t,F\n0,1\n0.5,0\n")
    csv = tmp_path / "run.csv"
    code = main(["import-fmu", str(fmu), "--stop-time", "1", "--points", "5", "--start", "m_pole=0", "--start", "v=2",
                 "--input", str(table), "--out", str(csv)])
    assert code == EXIT_OK, capsys.readouterr().err
    end = _last_row(csv)
    assert (end["t"], round(end["v"], 6), round(end["s"], 6)) == (1.0, 2.5, 2.375)


def test_the_table_times_join_the_grid(fmu, tmp_path):
    table = tmp_path / "force.csv"
    table.write_text("# a step at 0.3 s\nt [s],F [N]\n0,0\n0.3,2\n")
    csv = tmp_path / "run.csv"
    assert main(["import-fmu", str(fmu), "--stop-time", "1", "--points", "3", "--start", "m_pole=0",
                 "--input", str(table), "--out", str(csv)]) == EXIT_OK
    times = [float(row.split(",")[0]) for row in csv.read_text().splitlines()[1:]]
    end = _last_row(csv)
    assert times == [0.0, 0.3, 0.5, 1.0] and (round(end["v"], 6), round(end["s"], 6)) == (1.4, 0.49)


SECRET = "API_KEY=hunter2-very-secret"

BAD = {
    "unknown name": (["--start", "mass=1"], None, "--start mass: model 'cart_pendulum' has no state, parameter or input of that name"),
    "not a number": (["--start", "theta=abc"], None, "--start theta: expected a finite number, got 'abc'"),
    "not finite": (["--start", "theta=inf"], None, "--start theta: expected a finite number"),
    "no equals sign": (["--start", "theta"], None, "--start theta: expected NAME=VALUE"),
    "no time column": ([], "F,G\n1,2\n", "line 1: expected a column t (time [s]) and one per input (F)"),
    "not an input": ([], "t,G\n0,1\n", "line 1, column 'G': not an input of model 'cart_pendulum' (inputs: F)"),
    "times fall": ([], "t,F\n0,1\n0.5,1\n0.2,1\n", "line 4, column 't': expected times that increase row by row"),
    "a secret file": ([], SECRET + "\n", "expected a column t"),
    "a text value": ([], "t,F\n0,high\n", "line 2"),
}


@pytest.mark.parametrize(("options", "table", "match"), list(BAD.values()), ids=list(BAD))
def test_bad_start_values_and_tables_exit_2_naming_the_field(fmu, tmp_path, capsys, options, table, match):
    argv = ["import-fmu", str(fmu), "--stop-time", "1", *options]
    if table is not None:
        (tmp_path / "in.csv").write_text(table)
        argv += ["--input", str(tmp_path / "in.csv")]
    code = main(argv)
    err = capsys.readouterr().err
    assert (code, match in err, "Traceback" in err, "hunter2" in err) == (EXIT_BAD_INPUT, True, False, False), err


def test_start_values_without_a_stop_time_are_refused(fmu, capsys):
    assert main(["import-fmu", str(fmu), "--start", "v=1"]) == EXIT_BAD_INPUT
    assert "--start and --input set up a simulation: give --stop-time too" in capsys.readouterr().err


def test_export_fmi3_co_simulation_only_is_refused_not_widened(tmp_path, capsys):
    """FMI 3.0 export always carries model exchange: ``--interface cs`` is refused before any model is loaded."""
    out = tmp_path / "cp3.fmu"
    code = main(["export-fmu", "--model", str(REPO / "models" / "cart_pendulum.py") + ":CartPendulum", "--out", str(out),
                 "--fmi-version", "3.0", "--interface", "cs"])
    err = capsys.readouterr().err
    assert (code, out.exists()) == (EXIT_BAD_INPUT, False)
    assert "--interface cs: an FMI 3.0 FMU of gtmodel always carries model exchange too" in err and "--interface both" in err
