"""Argument checks shared by the estimators of :mod:`gtmodel.estimation` (measured signals)."""

from __future__ import annotations

from typing import Any

import numpy as np

from gtmodel.errors import InputError

__all__ = ["signal_rows"]


def signal_rows(x: Any, name: str, d: int, n: int | None = None) -> np.ndarray:
    """A measured signal as a finite ``(N, d)`` array (rows are samples).

    Parameters
    ----------
    x : array_like, shape (N, d)
        The signal.
    name : str
        Argument name for messages.
    d : int
        Number of columns (directions).
    n : int, optional
        Required number of samples (the length of the first signal of a call).

    Returns
    -------
    numpy.ndarray, shape (N, d)

    Raises
    ------
    InputError
        Not numeric, another shape, another length than ``n``, or a non-finite entry (its
        sample and column named).
    """
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected an array of numbers of shape (N, {d})") from None
    if arr.ndim != 2 or arr.shape[1] != d or arr.shape[0] < 1:
        raise InputError(f"{name}: expected shape (N, {d}) with N >= 1, got {arr.shape}")
    if n is not None and arr.shape[0] != n:
        raise InputError(f"{name}: expected {n} samples (as many as z_kin), got {arr.shape[0]}")
    bad = ~np.isfinite(arr)
    if np.any(bad):
        k, j = (int(v) for v in np.argwhere(bad)[0])
        raise InputError(f"{name}: sample {k}, column {j} is not finite ({arr[k, j]!r})")
    return arr
