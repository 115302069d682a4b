"""Column-pivoted QR (Businger & Golub 1965) for the dummy-derivative choice.

The dummy-derivative selection (:func:`gtmodel.modeling.structure.index_reduction.select_dummies`)
needs the pivot order and the magnitudes of ``diag(R)`` of ``G P = Q R`` for a small dense
Jacobian block (a few rows). Both come from LAPACK's ``dgeqp3``. A NumPy re-implementation was
tried and dropped: these blocks hold columns whose norms tie but for round-off (e.g. the
two-mass drive's, 0.577109856824761 against ...7612 at the fourth step), and which of them
becomes a state then depends on the rounding of the norm updates; a re-implementation picked
other states than LAPACK for three shipped models, and a user's files name their states
(``error_states`` of an MPC file).

Where ``dgeqp3`` comes from: NumPy's wheels ship OpenBLAS with its LAPACK (``scipy-openblas64``,
loaded by every NumPy process for :mod:`numpy.linalg`), whose ``dgeqp3`` is called here through
:mod:`ctypes`; elsewhere (a NumPy built on another LAPACK) :func:`scipy.linalg.qr`, imported on
first use. SciPy's linear algebra costs 0.15-0.2 CPU-s to import (its array-API layer clones
NumPy's namespace, ``numpy.f2py`` included), as much as the solve of a small problem
(``dc_motor_min_energy``, issue 49). Both are LAPACK's reference ``dgeqp3`` on OpenBLAS's BLAS;
``tests/modeling/structure/test_pivoting.py`` checks that they agree, ties included.
"""

from __future__ import annotations

import ctypes
from pathlib import Path
from typing import Any, Callable

import numpy as np

from gtmodel._lazy import lazy_module

__all__ = ["pivoted_qr", "numpy_dgeqp3"]

#: Imported on first use (PEP 562 lazy module), and only when NumPy has no OpenBLAS of its own.
sla = lazy_module("scipy.linalg")

_INT = ctypes.c_int64
_UNSET: Any = object()
_DGEQP3: Any = _UNSET


def _numpy_openblas() -> Callable[..., Any] | None:
    """``dgeqp3`` of the OpenBLAS NumPy ships (ILP64, ``scipy_`` prefixed symbols), or None."""
    try:
        lapack = np.__config__.CONFIG["Build Dependencies"]["lapack"]
    except (AttributeError, KeyError, TypeError):
        return None
    if lapack.get("name") != "scipy-openblas" or "USE64BITINT" not in str(lapack.get("openblas configuration", "")):
        return None
    root = Path(np.__file__).resolve().parent
    for path in sorted([*root.parent.glob("numpy.libs/*scipy_openblas64_*"), *(root / ".dylibs").glob("*scipy_openblas64_*")]):
        try:
            fn = getattr(ctypes.CDLL(str(path)), "scipy_dgeqp3_64_")
        except (OSError, AttributeError):
            continue
        fn.restype = None
        fn.argtypes = [ctypes.POINTER(_INT), ctypes.POINTER(_INT), ctypes.c_void_p, ctypes.POINTER(_INT),
                       ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.POINTER(_INT), ctypes.POINTER(_INT)]
        return fn
    return None


def numpy_dgeqp3() -> Callable[..., Any] | None:
    """LAPACK's ``dgeqp3`` from NumPy's own OpenBLAS (looked up once), or None without one.

    Returns
    -------
    callable or None
        The Fortran routine (:mod:`ctypes`; 64-bit integers), None when NumPy is built on
        another LAPACK (then :func:`pivoted_qr` uses :func:`scipy.linalg.qr`).
    """
    global _DGEQP3
    if _DGEQP3 is _UNSET:
        _DGEQP3 = _numpy_openblas()
    return _DGEQP3


def _dgeqp3(fn: Callable[..., Any], A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(R's upper part in A, 0-based pivots)`` of ``dgeqp3`` on a copy of ``A`` (column-major)."""
    m, n = A.shape
    a = np.array(A, dtype=np.float64, order="F")
    jpvt = np.zeros(n, dtype=np.int64)  # zeros: every column is free to move
    tau = np.zeros(max(1, min(m, n)))
    M, N, lda, info = _INT(m), _INT(n), _INT(max(1, m)), _INT(0)
    query = np.zeros(1)
    fn(M, N, a.ctypes.data, lda, jpvt.ctypes.data, tau.ctypes.data, query.ctypes.data, _INT(-1), info)
    work = np.zeros(max(1, int(query[0]), 3 * n + 1))
    fn(M, N, a.ctypes.data, lda, jpvt.ctypes.data, tau.ctypes.data, work.ctypes.data, _INT(work.size), info)
    if info.value != 0:
        raise RuntimeError(f"LAPACK dgeqp3 returned info = {info.value}")
    return a, jpvt - 1


def pivoted_qr(G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``|diag(R)|`` and the column permutation of the column-pivoted QR ``G[:, piv] = Q R``.

    Golub & Van Loan, *Matrix Computations* (4th ed.), algorithm 5.4.1, as LAPACK's ``dgeqp3``
    (NumPy's OpenBLAS, else :func:`scipy.linalg.qr`).

    Parameters
    ----------
    G : array_like
        ``(m, n)`` matrix.

    Returns
    -------
    r_diag : numpy.ndarray
        ``(min(m, n),)`` magnitudes of the diagonal of ``R``, non-increasing.
    piv : numpy.ndarray
        ``(n,)`` int column order: the first ``min(m, n)`` are the pivot columns in order.
    """
    A = np.array(G, dtype=float, ndmin=2)
    fn = numpy_dgeqp3()
    if fn is not None and A.size:
        R, piv = _dgeqp3(fn, A)
        k = min(A.shape)
        return np.abs(np.diag(R[:k, :k])).copy(), np.asarray(piv, dtype=int)
    _, R, piv = sla.qr(A, pivoting=True, mode="economic")
    return np.abs(np.diag(R)), np.asarray(piv, dtype=int)
