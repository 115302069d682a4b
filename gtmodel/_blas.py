"""CasADi's bundled OpenBLAS held to one thread unless the user sets its thread count.

CasADi's wheel ships its own OpenBLAS (``libcasadi-tp-openblas``) under IPOPT's MUMPS and
the LAPACK linear solvers. Left alone it starts one thread per core, and on gtmodel's
sparse NLPs those threads only spin: the L1 minimum-time solve on 400 elements took 7.57
CPU-s for 3.81 s of wall time with them and 3.73 CPU-s for 3.74 s without, the same 99
iterations and the same optimum to the last digit (casadi 3.8.2, 2 cores; at 50 elements 0.294
against 0.194 CPU-s). A study runs such solves in parallel processes, one per core, where
the threads only compete with the other solves. So gtmodel sets that library to one
thread when it is imported, as ``OPENBLAS_NUM_THREADS=1`` would, unless one of the
variables OpenBLAS reads (:data:`THREAD_VARIABLES`) is set: then the user's count stands.
numpy's and SciPy's own OpenBLAS are not touched.

:func:`threadpoolctl.threadpool_info` does not list CasADi's copy (its file name is not
one threadpoolctl knows); :func:`casadi_blas_threads` reads its thread count.
"""

from __future__ import annotations

import ctypes
import importlib.util
import os
from pathlib import Path

from gtmodel.errors import InputError

__all__ = ["THREAD_VARIABLES", "CASADI_BLAS_THREADS", "casadi_blas_library", "casadi_blas_threads", "limit_casadi_blas"]

#: Environment variables from which OpenBLAS takes its thread count, in its order of precedence.
THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS")
#: Threads of CasADi's OpenBLAS when none of :data:`THREAD_VARIABLES` is set.
CASADI_BLAS_THREADS = 1
#: File name prefix of CasADi's bundled OpenBLAS (Linux ``.so``, macOS ``.dylib``, Windows ``.dll``).
_PREFIX = "libcasadi-tp-openblas"

_library: ctypes.CDLL | None = None


def casadi_blas_library() -> ctypes.CDLL | None:
    """CasADi's bundled OpenBLAS, loaded (the same copy CasADi's plugins then bind to), or ``None``.

    Returns
    -------
    ctypes.CDLL or None
        The library, or ``None`` where CasADi is not installed or its wheel ships no
        OpenBLAS of its own (another platform's build) or the file does not load.
    """
    global _library
    if _library is not None:
        return _library
    spec = importlib.util.find_spec("casadi")  # the package's folder, without importing CasADi
    folders = list(spec.submodule_search_locations or []) if spec is not None else []
    files = sorted(p for f in folders for p in Path(f).glob(f"{_PREFIX}*") if p.is_file())
    # the name CasADi's plugins ask for first (their DT_NEEDED; the wheel holds copies, not links, under three names:
    # the dynamic loader then hands the plugins this copy by its soname, checked in tests/test_blas.py)
    for path in sorted(files, key=lambda p: (p.name != f"{_PREFIX}.so.0", len(p.name))):
        try:
            lib = ctypes.CDLL(str(path))
        except OSError:
            continue
        if hasattr(lib, "openblas_set_num_threads") and hasattr(lib, "openblas_get_num_threads"):
            lib.openblas_get_num_threads.restype = ctypes.c_int
            lib.openblas_set_num_threads.argtypes = [ctypes.c_int]
            _library = lib
            return lib
    return None


def casadi_blas_threads() -> int | None:
    """The thread count of CasADi's bundled OpenBLAS (loading it), or ``None`` where there is none.

    Returns
    -------
    int or None
        ``openblas_get_num_threads()`` of the library :func:`casadi_blas_library` loads.
    """
    lib = casadi_blas_library()
    return None if lib is None else int(lib.openblas_get_num_threads())


def limit_casadi_blas(threads: int = CASADI_BLAS_THREADS) -> int | None:
    """Set CasADi's bundled OpenBLAS to ``threads`` threads unless the environment sets its count.

    Called once when :mod:`gtmodel` is imported (cost: loading the library, about 2 ms).

    Parameters
    ----------
    threads : int, optional
        Threads to use, at least 1 (default :data:`CASADI_BLAS_THREADS`).

    Returns
    -------
    int or None
        The library's thread count afterwards; ``None`` where the wheel has no OpenBLAS of
        its own. Where one of :data:`THREAD_VARIABLES` is set (non-empty) the count is left
        as OpenBLAS read it from there.

    Raises
    ------
    gtmodel.errors.InputError
        If ``threads`` is not an integer of at least 1.
    """
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise InputError(f"threads: expected an integer >= 1, got {threads!r}")
    lib = casadi_blas_library()
    if lib is None:
        return None
    if not any(os.environ.get(v, "").strip() for v in THREAD_VARIABLES):
        lib.openblas_set_num_threads(threads)
    return int(lib.openblas_get_num_threads())
