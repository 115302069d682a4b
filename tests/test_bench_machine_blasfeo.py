"""The offline fatrop solve under a preloaded BLASFEO (benchmarks/bench_solve.py, issue 46).

The machine's BLASFEO (``benchmarks/hpipm_build.sh``) needs its source and a build; here the
wheel's own ``libblasfeo`` copied to a folder stands in for it: the mechanism (the folder from
``GTMODEL_HPIPM``, the child preloading it, the mapped file checked) is what is tested, and the
copy must give the wheel's optimum bit for bit (the same code; independent of the preload).
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import casadi as ca
import pytest

from .conftest import benchmark_module

ROOT = Path(__file__).resolve().parents[1]
WHEEL_BLASFEO = Path(ca.__file__).parent / "libblasfeo.so.0"


@pytest.fixture(scope="module")
def bench_solve():
    """benchmarks/bench_solve.py as a module."""
    with benchmark_module("bench_solve") as module:
        yield module


@pytest.mark.parametrize(
    "folder, match",
    [(None, "GTMODEL_HPIPM unset"), ("", "GTMODEL_HPIPM unset"), ("empty", r"libblasfeo\.so\.0 missing")],
    ids=["unset", "empty-value", "no-library"],
)
def test_machine_blasfeo_says_why_not(bench_solve, monkeypatch, tmp_path, folder, match):
    """Without the folder or its library the benchmark gets the reason (its ``fatrop_machine_blasfeo_skipped``)."""
    if folder is None:
        monkeypatch.delenv("GTMODEL_HPIPM", raising=False)
    else:
        monkeypatch.setenv("GTMODEL_HPIPM", str(tmp_path) if folder else "")
    reason = bench_solve.machine_blasfeo()
    assert isinstance(reason, str)
    assert re.search(match, reason)


def test_machine_blasfeo_found(bench_solve, monkeypatch, tmp_path):
    (tmp_path / "libblasfeo.so.0").write_bytes(b"")
    monkeypatch.setenv("GTMODEL_HPIPM", str(tmp_path))
    assert bench_solve.machine_blasfeo() == (tmp_path / "libblasfeo.so.0").resolve()


@pytest.mark.slow
@pytest.mark.skipif(not WHEEL_BLASFEO.is_file(), reason="the casadi wheel has no libblasfeo.so.0 here")
def test_preloaded_blasfeo_is_the_one_fatrop_uses(bench_solve, tmp_path):
    """The child with the preload maps the copy (not the wheel's), the other the wheel's; the optima agree exactly."""
    lib = tmp_path / "libblasfeo.so.0"
    shutil.copyfile(WHEEL_BLASFEO.resolve(), lib)
    out = bench_solve.fatrop_blasfeo_rounds(str(ROOT / "problems" / "l1_time_optimal.toml"), lib.resolve(), rounds=1, repeat=1)
    assert isinstance(out, dict), out
    assert out["fatrop_machine_blasfeo_library"] == str(lib.resolve())
    assert out["fatrop_machine_blasfeo_final_time_rel_diff"] == 0.0
    assert out["fatrop_machine_blasfeo_iterations"] > 0 and out["fatrop_machine_blasfeo_solve_cpu_s"] > 0
