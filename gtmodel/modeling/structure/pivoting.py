"""Column-pivoted QR (Businger & Golub 1965) for the dummy-derivative choice.

The dummy-derivative selection (:func:`gtmodel.modeling.structure.index_reduction.select_dummies`)
needs the pivot order and the magnitudes of ``diag(R)`` of ``G P = Q R`` for a small dense
Jacobian block (a few rows). Both come from LAPACK's ``dgeqp3`` (``scipy.linalg.qr``),
imported on first use. A NumPy re-implementation was tried and dropped: these blocks hold
columns whose norms tie but for round-off (e.g. the two-mass drive's, 0.577109856824761 against
...7612 at the fourth step), and which of them becomes a state then depends on the rounding of
the norm updates; a re-implementation picked other states than LAPACK for three shipped models,
and a user's files name their states (``error_states`` of an MPC file).
"""

from __future__ import annotations

import numpy as np

from gtmodel._lazy import lazy_module

__all__ = ["pivoted_qr"]

#: Imported on first use (PEP 562 lazy module): a model without dummy derivatives need not pay for it.
sla = lazy_module("scipy.linalg")


def pivoted_qr(G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``|diag(R)|`` and the column permutation of the column-pivoted QR ``G[:, piv] = Q R``.

    Golub & Van Loan, *Matrix Computations* (4th ed.), algorithm 5.4.1, as LAPACK's ``dgeqp3``.

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
    _, R, piv = sla.qr(A, pivoting=True, mode="economic")
    return np.abs(np.diag(R)), np.asarray(piv, dtype=int)
