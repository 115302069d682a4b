"""``gtmodel robot-sim``'s parser and command (built here: the lead wires it into gtmodel/cli.py)."""

from __future__ import annotations

import argparse
import json

import pytest

from gtmodel.robot_sim.cli import add_robot_sim_parser, robot_sim_command

from .peers import RsiPeer


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="gtmodel")
    add_robot_sim_parser(p.add_subparsers(dest="command"))
    return p


def test_parser_defaults():
    a = _parser().parse_args(["robot-sim", "--interface", "egm", "--out", "x"])
    assert (a.plant, a.to, a.duration, a.correction, a.seed, a.faults) == (None, None, 60.0, "relative", 0, None)


@pytest.mark.parametrize("bad", ["localhost", ":80", "host:0", "host:70000", "host:port", "127.0.0.1:\u0664\u0669\u0661\u0665\u0662"])
def test_bad_address_is_refused(bad, capsys):
    with pytest.raises(SystemExit):
        _parser().parse_args(["robot-sim", "--interface", "rsi", "--to", bad, "--out", "x"])


def test_a_run_writes_record_and_summary_and_may_repeat_into_its_folder(tmp_path):
    out = tmp_path / "sim"
    with RsiPeer() as peer:
        host, port = peer.target
        shost, sport = peer.sensor_target
        argv = ["robot-sim", "--interface", "rsi", "--to", f"{host}:{port}", "--sensor-to", f"{shost}:{sport}", "--duration", "0.2",
                "--faults", "loss:at=3", "--out", str(out), "-q"]
        codes = [robot_sim_command(_parser().parse_args(argv)) for _ in range(2)]
    summary = json.loads((out / "sim_summary.json").read_text())
    header = (out / "sim_record.csv").read_text().splitlines()[0].split(",")
    assert (codes, summary["cycles_sent"], summary["faults_injected"]["loss"], header[:5]) == ([0, 0], 50, 1, ["cycle", "t_s", "seq", "sent", "late"])


def test_a_folder_of_other_files_is_refused(tmp_path, capsys):
    (tmp_path / "mine.txt").write_text("keep me")
    code = robot_sim_command(_parser().parse_args(["robot-sim", "--interface", "rsi", "--to", "127.0.0.1:9", "--duration", "0.1",
                                                   "--out", str(tmp_path)]))
    assert (code, (tmp_path / "mine.txt").read_text()) == (2, "keep me") and "mine.txt" in capsys.readouterr().err


def test_a_bad_fault_spec_is_an_input_error(tmp_path, capsys):
    code = robot_sim_command(_parser().parse_args(["robot-sim", "--interface", "rsi", "--to", "127.0.0.1:9", "--faults", "boom:at=1",
                                                   "--out", str(tmp_path / "o")]))
    assert code == 2 and "boom" in capsys.readouterr().err
