"""Column-pivoted QR (Businger & Golub 1965) for the dummy-derivative choice, in NumPy alone.

The dummy-derivative selection (:func:`gtmodel.modeling.structure.index_reduction.select_dummies`)
needs the pivot order and the magnitudes of ``diag(R)`` of ``G P = Q R`` for a small dense
Jacobian block (a few rows). LAPACK's ``dgeqp3`` through ``scipy.linalg.qr`` gives them, but
importing SciPy's linear algebra costs ~0.12 CPU-s (its array-API layer), more than
reducing a drive model; NumPy has no pivoted QR. Here: Householder reflections with the
column of largest remaining norm first (the norms recomputed at each step, not downdated;
ties to the first column, as LAPACK's ``idamax``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["pivoted_qr"]


def pivoted_qr(G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``|diag(R)|`` and the column permutation of the column-pivoted QR ``G[:, piv] = Q R``.

    Golub & Van Loan, *Matrix Computations* (4th ed.), algorithm 5.4.1 (Householder QR with
    column pivoting), the trailing column norms recomputed at every step.

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
    A = np.array(G, dtype=float, ndmin=2, copy=True)
    m, n = A.shape
    piv = np.arange(n)
    k_max = min(m, n)
    diag = np.zeros(k_max)
    for k in range(k_max):
        norms = np.linalg.norm(A[k:, k:], axis=0)
        j = k + int(np.argmax(norms))
        if j != k:
            A[:, [k, j]] = A[:, [j, k]]
            piv[[k, j]] = piv[[j, k]]
        x = A[k:, k]
        alpha = float(np.linalg.norm(x))
        diag[k] = alpha
        if alpha == 0.0:
            continue
        v = x.copy()
        v[0] += np.copysign(alpha, x[0] if x[0] != 0 else 1.0)
        v /= np.linalg.norm(v)
        A[k:, k:] -= 2.0 * np.outer(v, v @ A[k:, k:])
    return diag, piv
