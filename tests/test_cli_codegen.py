"""``gtmodel codegen`` as sub-commands (gtmodel.cli_codegen): help, the former flat forms, progress, input errors.

References: the declared table of sub-commands (SUBCOMMANDS) against argparse's help; the
former flat forms of README/docs mapped to the same routes as the sub-commands; an error
names the option the user typed (exit 2).
"""

from __future__ import annotations

import pytest
from pathlib import Path

from gtmodel.cli import build_parser, main
from gtmodel.cli_codegen import SUBCOMMANDS, _reference_line, _route
from gtmodel.errors import GtModelError

from .conftest import REPO

MODEL = f"{REPO / 'models' / 'cart_pendulum.py'}:CartPendulum"


def test_codegen_help_lists_the_sub_commands_and_not_the_flat_options(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["codegen", "--help"])
    assert exit_.value.code == 0
    out = capsys.readouterr().out
    assert "{robot,model,tracking,mpc,controller}" in out
    assert all(name in out for name in SUBCOMMANDS)
    assert "--mismatch" not in out and "--q " not in out and "--newton-tolerance" not in out


@pytest.mark.parametrize("name", list(SUBCOMMANDS))
def test_each_sub_command_says_what_it_generates(name, capsys):
    with pytest.raises(SystemExit):
        main(["codegen", name, "--help"])
    assert SUBCOMMANDS[name].split(",")[0].split("(")[0].strip() in " ".join(capsys.readouterr().out.split())


@pytest.mark.parametrize("argv, route", [
    (["--robot", "L1"], "robot"),
    ([], "robot"),
    (["--model", MODEL], "model"),
    (["--mpc", "codegen/mpc/l1_mpc.toml"], "mpc"),
    (["--controller", "codegen/controllers/l1_tracking.toml"], "tracking"),
    (["--controller", "controller.json"], "robot"),
    (["robot", "L1"], "robot"),
    (["model", MODEL], "model"),
    (["mpc", "codegen/mpc/l1_mpc.toml"], "mpc"),
    (["tracking", "codegen/controllers/l1_tracking.toml"], "tracking"),
    (["controller", "controller.json"], "controller"),
    (["filter", "controller.json"], "controller"),
])
def test_flat_forms_and_sub_commands_take_the_same_routes(argv, route):
    args = build_parser().parse_args(["codegen", *argv, "--out", "o"])
    assert _route(args) == route


@pytest.mark.parametrize("argv", [
    ["codegen", "model", MODEL, "--period", "-0.004"],
    ["codegen", "--model", MODEL, "--period", "-0.004"],
    ["codegen", "model", MODEL, "--period", "nan"],
])
def test_a_bad_period_is_refused_naming_period(argv, tmp_path, capsys):
    assert main([*argv, "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err
    assert "--period: expected a positive loop period in seconds" in err and "dt:" not in err


def test_out_is_required(capsys):
    assert main(["codegen", "--robot", "L1"]) == 2
    assert "--out: expected the output folder" in capsys.readouterr().err


def test_each_step_says_what_it_does(tmp_path, capsys):
    assert main(["codegen", "robot", "L1", "--functions", "ik", "--out", str(tmp_path)]) == 0
    err = capsys.readouterr().err
    assert "generating kinematics and inverse dynamics of the robot L1 ..." in err


def test_quiet_says_nothing(tmp_path, capsys):
    assert main(["codegen", "robot", "L1", "--functions", "ik", "--out", str(tmp_path), "-q"]) == 0
    assert capsys.readouterr().err == ""


def test_the_re_planned_reference_is_announced():
    line = _reference_line(REPO / "codegen" / "mpc" / "l1_mpc.toml", "mpc")
    assert line.startswith("the reference is re-planned: ../../problems/l1_time_optimal.toml solved here with limits.force = [400.0, 400.0, 400.0]")
    with pytest.raises(GtModelError, match="missing.toml"):
        _reference_line(REPO / "missing.toml", "mpc")


@pytest.mark.parametrize("sub, name, field", [
    ("mpc", "codegen/mpc/dc_motor_mpc.toml", "mpc.period"),
    ("tracking", "codegen/controllers/dc_motor_tracking.toml", "controller.period"),
])
def test_a_bad_file_is_refused_before_any_progress_line(sub, name, field, tmp_path, capsys):
    """A bad period: exit 2 naming the field, and no line announcing a re-planned reference
    (nothing was planned), nothing written."""
    text = (REPO / name).read_text().replace("period = 0.004", "period = -0.004", 1).replace('"../../', f'"{REPO.as_posix()}/')
    (tmp_path / "bad.toml").write_text(text)
    assert main(["codegen", sub, str(tmp_path / "bad.toml"), "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err
    assert f"field '{field}'" in err and "re-planned" not in err and "reading" not in err
    assert not (tmp_path / "c").exists()


def _tree(folder):
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_a_failed_rerun_leaves_the_earlier_output_as_it_was(tmp_path, monkeypatch, capsys):
    # issue 67: codegen --out written into a partial folder and put in place when complete; a rerun that fails while
    # generating (here: the generator raises, as Ctrl-C would inside it) leaves the earlier C byte-identical, no partial
    out = tmp_path / "C"
    assert main(["codegen", "robot", "L1", "--functions", "ik", "--out", str(out), "-q"]) == 0
    before = _tree(out)
    import gtmodel.codegen as codegen

    def interrupted(source, out, *args, **kwargs):  # half of the files written, then Ctrl-C
        for name in before:
            (Path(out) / name).parent.mkdir(parents=True, exist_ok=True)
            (Path(out) / name).write_text("half written")
        raise KeyboardInterrupt

    monkeypatch.setattr(codegen, "generate_code", interrupted)
    code = main(["codegen", "robot", "L1", "--functions", "fk", "--out", str(out), "-q"])  # the CLI's exit for Ctrl-C
    assert (code != 0, _tree(out) == before, sorted(p.name for p in tmp_path.iterdir())) == (True, True, ["C"])


def test_a_complete_rerun_replaces_the_output_and_prints_its_paths(tmp_path, capsys):
    out = tmp_path / "C"
    assert main(["codegen", "robot", "L1", "--functions", "ik", "--out", str(out), "-q"]) == 0
    assert main(["codegen", "robot", "L1", "--functions", "fk", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    wrote = [line for line in printed.splitlines() if line.startswith("wrote ")]
    assert wrote and ".partial-" not in printed and f"{out}/" in wrote[-1]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["C"] and b"fk" in b"".join(_tree(out).values())
