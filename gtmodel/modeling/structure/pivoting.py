"""Column-pivoted QR (Businger & Golub 1965) for the dummy-derivative choice, in NumPy alone.

The dummy-derivative selection (:func:`gtmodel.modeling.structure.index_reduction.select_dummies`)
needs the pivot order and the magnitudes of ``diag(R)`` of ``G P = Q R`` for a small dense
Jacobian block (a few rows). LAPACK's ``dgeqp3`` through ``scipy.linalg.qr`` gives them, but
importing SciPy's linear algebra costs ~0.12 CPU-s (its array-API layer), more than
reducing a drive model; NumPy has no pivoted QR. Here: Householder reflections with the
column of largest remaining norm first (the norms recomputed at each step, not downdated;
norms equal to ``TIE_RTOL`` tie, and a tie goes to the column first in ``G``'s order, so that
round-off never picks between equal candidates).
"""

from __future__ import annotations

import numpy as np

__all__ = ["pivoted_qr", "TIE_RTOL"]

#: Relative difference of two column norms below which they tie (the first column wins).
TIE_RTOL = 1e-10


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
        # a tie within round-off goes to the column first in G's own order: the reflections' rounding
        # (and the swaps so far) must not decide which of two equal candidates becomes a state
        tied = np.flatnonzero(norms >= norms.max() * (1.0 - TIE_RTOL))
        j = k + int(tied[np.argmin(piv[k:][tied])])
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
