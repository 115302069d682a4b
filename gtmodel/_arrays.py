"""Up-front argument checks for NumPy inputs (shapes, finiteness, rotations), in one place.

Every check raises :class:`~gtmodel.errors.InputError` with a message naming the argument,
what was expected and what was given (the SciPy style of argument checking). Library
functions call these instead of writing their own ``np.asarray`` + shape tests.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from gtmodel.errors import InputError

__all__ = ["as_rows", "as_signal", "as_times", "as_vector", "as_per_axis", "as_array", "as_finite", "as_rotation", "as_rotations", "positive_int", "positive_float", "finite_float"]


def as_rows(x: Any, name: str, width: int) -> tuple[np.ndarray, bool]:
    """An ``(N, width)`` finite float array, and whether ``x`` was a single ``(width,)`` row.

    Parameters
    ----------
    x : array_like, shape (width,) or (N, width)
        The input (rows are samples).
    name : str
        Argument name for messages.
    width : int
        Number of columns.

    Returns
    -------
    numpy.ndarray, shape (N, width)
        The rows (N >= 1).
    bool
        True when ``x`` was one row of shape ``(width,)``.

    Raises
    ------
    InputError
        Not numeric, another shape, no rows, or a row that is not finite (named).
    """
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected an array of shape ({width},) or (N, {width}), got {x!r}") from None
    single = arr.ndim == 1
    arr = arr[None, :] if single else arr
    if arr.ndim != 2 or arr.shape[1] != width or arr.shape[0] == 0:
        raise InputError(f"{name}: expected shape ({width},) or (N, {width}), got {np.shape(x)}")
    if np.isfinite(arr).all():  # the fast path (a call of a model is ~us: keep numpy's wrappers out)
        return arr, single
    k = int(np.argmax(~np.all(np.isfinite(arr), axis=1)))
    raise InputError(f"{name}: row {k} is not finite: {arr[k].tolist()}")


def as_signal(
    x: Any, name: str, width: int | None = None, n: int | None = None, like: str | None = None, vector: bool = False, min_samples: int = 1
) -> np.ndarray:
    """A sampled signal as a finite ``(N, width)`` float array (rows are samples, columns channels).

    The one check of measured or logged signals (estimators, identification): unlike
    :func:`as_rows` a single ``(width,)`` row is not accepted (a signal has a time axis),
    and a non-finite entry is named by its sample and column (both 0-based, as in ``x[k, j]``).

    Parameters
    ----------
    x : array_like, shape (N, width), or (N,) with ``vector``
        The signal.
    name : str
        Argument name for messages.
    width : int, optional
        Number of columns (channels); None accepts any number >= 1.
    n : int, optional
        Required number of samples (the length of the signal that sets it).
    like : str, optional
        Name of what sets ``n`` (for messages, e.g. ``"t"``).
    vector : bool, optional
        Also accept a 1-D ``(N,)`` signal, returned as one column ``(N, 1)``.
    min_samples : int, optional
        Smallest number of samples N (default 1).

    Returns
    -------
    numpy.ndarray, shape (N, width)
        A float array (a view of ``x`` where no conversion was needed).

    Raises
    ------
    InputError
        Not numeric, another shape, fewer than ``min_samples`` samples, another length than
        ``n``, or a non-finite entry (its sample and column named).
    """
    cols = "d" if width is None else str(width)
    shapes = f"(N,) or (N, {cols})" if vector else f"(N, {cols})"
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected an array of numbers of shape {shapes}") from None
    if vector and arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or (width is not None and arr.shape[1] != width) or arr.shape[1] < 1 or arr.shape[0] < min_samples:
        raise InputError(f"{name}: expected shape {shapes} with N >= {min_samples}, got {np.shape(x)}")
    if n is not None and arr.shape[0] != n:
        raise InputError(f"{name}: expected {n} samples{f' like {like}' if like else ''}, got {arr.shape[0]}")
    bad = ~np.isfinite(arr)
    if np.any(bad):
        k, j = (int(v) for v in np.argwhere(bad)[0])
        raise InputError(f"{name}: sample {k}, column {j} is not finite ({arr[k, j]!r})")
    return arr


def as_times(t: Any, name: str = "t", min_samples: int = 2) -> np.ndarray:
    """Sample times: a finite, strictly increasing 1-D float array [s] (the time axis of a signal).

    Parameters
    ----------
    t : array_like, shape (N,)
        Times [s].
    name : str, optional
        Argument name for messages (default ``"t"``).
    min_samples : int, optional
        Smallest number of samples N (default 2).

    Returns
    -------
    numpy.ndarray, shape (N,)

    Raises
    ------
    InputError
        Not numeric, not 1-D, fewer than ``min_samples`` samples, a sample that is not
        finite, or a time not above the one before it (the sample named, 0-based).
    """
    try:
        arr = np.asarray(t, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a 1-D array of times in s, got {t!r}") from None
    if arr.ndim != 1:
        raise InputError(f"{name}: expected a 1-D array of times in s, got shape {arr.shape}")
    if arr.size < min_samples:
        raise InputError(f"{name}: expected at least {min_samples} samples, got {arr.size}")
    bad = ~np.isfinite(arr)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise InputError(f"{name}: sample {k} is not finite ({float(arr[k])!r})")
    back = np.diff(arr) <= 0
    if np.any(back):
        k = int(np.argmax(back)) + 1
        raise InputError(
            f"{name}: times must increase strictly, but sample {k} does not (t[{k}] = {float(arr[k])!r} s <= t[{k - 1}] = {float(arr[k - 1])!r} s)"
        )
    return arr


def as_vector(x: Any, name: str, min_size: int = 1, what: str = "values", nonnegative: bool = False) -> np.ndarray:
    """A finite 1-D float array of at least ``min_size`` entries (any length otherwise).

    Parameters
    ----------
    x : array_like, shape (n,)
        The input.
    name : str
        Argument name for messages.
    min_size : int, optional
        Smallest accepted length n (default 1).
    what : str, optional
        What the entries are, for messages (e.g. ``"frequencies"``).
    nonnegative : bool, optional
        Also require every entry >= 0.

    Returns
    -------
    numpy.ndarray, shape (n,)

    Raises
    ------
    InputError
        Not numeric, not 1-D, shorter than ``min_size``, or an entry that is not finite
        (or negative with ``nonnegative``), named by its index.
    """
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a 1-D array of {what}, got {x!r}") from None
    if arr.ndim != 1 or arr.size < min_size:
        raise InputError(f"{name}: expected a 1-D array of at least {min_size} {what}, got shape {arr.shape}")
    for bad, kind in ((~np.isfinite(arr), "finite"), ((arr < 0) if nonnegative else None, "non-negative")):
        if bad is not None and np.any(bad):
            k = int(np.argmax(bad))
            raise InputError(f"{name}: expected {kind} {what}, got entry {k} = {float(arr[k])!r}")
    return arr


def as_per_axis(value: Any, n: int, name: str, positive: bool = False, nonnegative: bool = False) -> np.ndarray:
    """One finite number per axis: a scalar (used for every axis) or an ``(n,)`` array.

    Parameters
    ----------
    value : float or array_like, shape (n,)
        The input.
    n : int
        Number of axes (directions).
    name : str
        Argument name for messages.
    positive, nonnegative : bool, optional
        Also require every entry > 0 (or >= 0).

    Returns
    -------
    numpy.ndarray, shape (n,)
        A new array.

    Raises
    ------
    InputError
        Not numeric, not finite, another shape, or of the wrong sign.
    """
    arr = as_finite(value, name)
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,):
        raise InputError(f"{name}: expected a number or shape ({n},) (one per axis), got shape {arr.shape}")
    if (positive and not np.all(arr > 0)) or (nonnegative and not np.all(arr >= 0)):
        raise InputError(f"{name}: expected values {'>' if positive else '>='} 0 (one per axis), got {arr.tolist()}")
    return arr.copy()


def as_array(x: Any, shape: tuple[int, ...], name: str) -> np.ndarray:
    """A finite float array of exactly ``shape``.

    Parameters
    ----------
    x : array_like
        The input.
    shape : tuple of int
        Required shape.
    name : str
        Argument name for messages.

    Returns
    -------
    numpy.ndarray
        A new array (a copy of ``x``).

    Raises
    ------
    InputError
        Not numeric, another shape, or not finite.
    """
    try:
        arr = np.array(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a numeric array of shape {shape}, got {x!r}") from None
    if arr.shape != tuple(shape):
        raise InputError(f"{name}: expected shape {tuple(shape)}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name}: expected finite values, got {arr.tolist()}")
    return arr


def as_finite(x: Any, name: str, positive: bool = False, nonnegative: bool = False) -> np.ndarray:
    """A finite float array of any shape (a scalar gives a 0-d array).

    Parameters
    ----------
    x : array_like
        The input.
    name : str
        Argument name for messages.
    positive, nonnegative : bool, optional
        Also require every entry > 0 (or >= 0).

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    InputError
        Not numeric, not finite, or of the wrong sign.
    """
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected numbers, got {x!r}") from None
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name}: expected finite values, got {arr.tolist()}")
    if positive and not np.all(arr > 0):
        raise InputError(f"{name}: expected positive values, got {arr.tolist()}")
    if nonnegative and not np.all(arr >= 0):
        raise InputError(f"{name}: expected non-negative values, got {arr.tolist()}")
    return arr


def as_rotation(R: Any, name: str, tolerance: float) -> np.ndarray:
    """One rotation matrix: ``R^T R = I`` within ``tolerance`` and ``det R = +1``.

    Parameters
    ----------
    R : array_like, shape (3, 3)
        The matrix.
    name : str
        Argument name for messages.
    tolerance : float
        Largest allowed entry of ``|R^T R - I|``.

    Returns
    -------
    numpy.ndarray, shape (3, 3)

    Raises
    ------
    InputError
        Another shape, not finite, or not a rotation.
    """
    try:
        Rm = np.asarray(R, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a 3x3 rotation matrix, got {R!r}") from None
    if Rm.shape != (3, 3) or not np.all(np.isfinite(Rm)):
        raise InputError(f"{name}: expected a finite 3x3 rotation matrix, got shape {Rm.shape}")
    err = np.abs(Rm.T @ Rm - np.eye(3)).max()
    if err > tolerance or np.linalg.det(Rm) < 0:
        raise InputError(
            f"{name}: expected a rotation matrix (R^T R = I within {tolerance}, det = +1), "
            f"got max |R^T R - I| = {err:.3g}, det = {np.linalg.det(Rm):.6g}"
        )
    return Rm


def as_rotations(R: Any, n: int, name: str, tolerance: float) -> np.ndarray:
    """``n`` rotation matrices (one ``(3, 3)`` matrix is repeated ``n`` times).

    Parameters
    ----------
    R : array_like, shape (3, 3) or (n, 3, 3)
        The matrices.
    n : int
        How many are needed (e.g. the number of positions they go with).
    name : str
        Argument name for messages.
    tolerance : float
        Largest allowed entry of ``|R^T R - I|``.

    Returns
    -------
    numpy.ndarray, shape (n, 3, 3)

    Raises
    ------
    InputError
        Another shape, a matrix that is not finite or not a rotation (named by index).
    """
    try:
        arr = np.asarray(R, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected rotation matrices of shape (3, 3) or (N, 3, 3), got {R!r}") from None
    if arr.shape == (3, 3):
        arr = np.broadcast_to(arr, (n, 3, 3))
    if arr.shape != (n, 3, 3):
        raise InputError(f"{name}: expected shape (3, 3) or ({n}, 3, 3) to match the positions, got {np.shape(R)}")
    if not np.all(np.isfinite(arr)):
        k = int(np.argmax(~np.all(np.isfinite(arr.reshape(n, 9)), axis=1)))
        raise InputError(f"{name}: matrix {k} is not finite")
    dev = np.abs(np.einsum("nji,njk->nik", arr, arr) - np.eye(3)).reshape(n, 9).max(axis=1)
    det = np.linalg.det(arr)
    bad = (dev > tolerance) | (det <= 0)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise InputError(f"{name}: matrix {k} is not a rotation (max |R^T R - I| = {dev[k]:.3g}, det = {det[k]:.6g})")
    return arr


def positive_int(value: Any, name: str) -> int:
    """A positive integer (``bool`` is refused).

    Parameters
    ----------
    value : Any
        The input.
    name : str
        Argument name for messages.

    Returns
    -------
    int

    Raises
    ------
    InputError
        Not an integer, or below 1.
    """
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise InputError(f"{name}: expected a positive integer, got {value!r}")
    return int(value)


def positive_float(value: Any, name: str) -> float:
    """A finite number > 0, as a ``float``.

    Parameters
    ----------
    value : Any
        The input (a scalar).
    name : str
        Argument name for messages.

    Returns
    -------
    float

    Raises
    ------
    InputError
        Not a number, not finite, or not above 0.
    """
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a number > 0, got {value!r}") from None
    if not np.isfinite(v) or v <= 0:
        raise InputError(f"{name}: expected a finite number > 0, got {value!r}")
    return v


def finite_float(value: Any, name: str, unit: str = "", *, positive: bool = False, nonnegative: bool = False) -> float:
    """A finite real number (not a bool), optionally > 0 or >= 0, as a ``float``.

    Parameters
    ----------
    value : Any
        The input (a scalar).
    name : str
        Argument name for messages.
    unit : str, optional
        Unit named in the message (e.g. ``"N/m"``).
    positive, nonnegative : bool, optional
        Require ``value > 0`` or ``value >= 0``.

    Returns
    -------
    float

    Raises
    ------
    InputError
        Not a number (a bool is not one), not finite, or of the wrong sign; the message
        reads ``"<name>: expected a finite positive value [<unit>], got <value>"``.
    """
    what = "positive " if positive else "non-negative " if nonnegative else ""
    expected = f"{name}: expected a finite {what}value" + (f" [{unit}]" if unit else "")
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputError(f"{expected}, got {value!r}")
    v = float(value)
    if not np.isfinite(v) or (positive and v <= 0) or (nonnegative and v < 0):
        raise InputError(f"{expected}, got {value!r}")
    return v
