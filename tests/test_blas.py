"""gtmodel._blas: CasADi's bundled OpenBLAS held to one thread unless the environment sets its count.

Independent check: not the library's own ``openblas_get_num_threads`` alone but the kernel's
per-thread CPU counters (``/proc/self/task/*/stat``) around a dense LU in CasADi's LAPACK
plugin (``lapacklu``, which calls CasADi's OpenBLAS): held to one thread, no other thread of
the process does any of the work; with ``OPENBLAS_NUM_THREADS=2`` (the control) another one does.
Each case runs in a fresh child process, as OpenBLAS reads the environment when it loads.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from gtmodel import _blas
from gtmodel._blas import THREAD_VARIABLES, limit_casadi_blas
from gtmodel.errors import InputError

#: The child: gtmodel imported, then a 1500 x 1500 LU by CasADi's lapacklu; prints the library's thread count
#: and the CPU ticks of the calling thread and of all other threads during the LU.
CHILD = r"""
import json, os, threading
import numpy as np
import gtmodel
import casadi as ca
from gtmodel._blas import casadi_blas_threads

def ticks():
    out = {}
    for t in os.listdir("/proc/self/task"):
        f = open(f"/proc/self/task/{t}/stat").read().rsplit(")", 1)[1].split()
        out[int(t)] = int(f[11]) + int(f[12])  # utime + stime
    return out

n = 1500
A = ca.DM(np.random.default_rng(0).standard_normal((n, n)) + n * np.eye(n))
b = ca.DM.ones(n)
before = ticks()
x = ca.solve(A, b, "lapacklu")
after = ticks()
me = threading.get_native_id()
delta = {t: after[t] - before.get(t, 0) for t in after}
assert float(ca.norm_inf(ca.mtimes(A, x) - b)) < 1e-9
print(json.dumps({"threads": casadi_blas_threads(), "caller": delta.pop(me), "others": sum(delta.values())}))
"""


def _child(**env_extra: str) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES}
    env.update(env_extra)
    run = subprocess.run([sys.executable, "-P", "-c", CHILD], env=env, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]
    return json.loads(run.stdout.strip().splitlines()[-1])


needs_proc = pytest.mark.skipif(not Path("/proc/self/task").is_dir() or _blas.casadi_blas_library() is None,
                                reason="needs Linux's /proc and a CasADi wheel with its own OpenBLAS")


@needs_proc
def test_casadi_blas_does_its_work_on_the_calling_thread_only():
    r = _child()
    assert r["threads"] == 1
    assert r["caller"] >= 1  # the LU took CPU time on the caller (ticks of 10 ms)
    assert r["others"] <= max(1, r["caller"] // 10)  # no worker thread shared it


@needs_proc
@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="a second thread needs a second core to be started by OpenBLAS")
def test_a_thread_count_set_in_the_environment_stands():
    r = _child(OPENBLAS_NUM_THREADS="2")
    assert r["threads"] == 2
    assert r["others"] >= 1  # the control: with two threads a second one does part of the LU


@needs_proc
def test_the_library_is_the_copy_casadi_plugins_bind_to():
    """One copy of CasADi's OpenBLAS in the process after an IPOPT solve (the one gtmodel loaded and set)."""
    import casadi as ca

    x = ca.MX.sym("x")
    ca.nlpsol("s", "ipopt", {"x": x, "f": (x - 1) ** 2}, {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes"})(x0=0)
    maps = {line.split()[-1] for line in Path("/proc/self/maps").read_text().splitlines() if "libcasadi-tp-openblas" in line}
    assert len({Path(m).resolve() for m in maps}) == 1
    if not any(os.environ.get(v, "").strip() for v in THREAD_VARIABLES):  # else the user's count stands (the test above)
        assert _blas.casadi_blas_threads() == 1


@pytest.mark.parametrize("threads", [0, -1, 1.5, True, "2", None])
def test_a_bad_thread_count_is_refused(threads):
    with pytest.raises(InputError, match=r"threads: expected an integer >= 1"):
        limit_casadi_blas(threads)
