"""Column-wise evaluation of a CasADi Function on N samples (the numeric side of every model).

The models of :mod:`gtmodel.robots` build one CasADi Function per formula and evaluate it
on N samples at once with ``Function.map(N)``; :class:`MappedFunction` caches the mapped
Function per N.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

__all__ = ["MappedFunction"]


class MappedFunction:
    """Evaluate a CasADi Function column-wise on N samples, caching ``map`` per N.

    Parameters
    ----------
    f : casadi.Function
        The Function of one sample.

    Examples
    --------
    ``MappedFunction(f)(X, Y)`` with ``X`` of shape ``(n_x, N)`` and ``Y`` of shape
    ``(n_y, N)`` returns the outputs as arrays of shape ``(n_out, N)``. Matrix inputs
    (e.g. ``3 x 3``) are passed as ``(3, 3 N)`` blocks; then give ``n`` explicitly.
    """

    def __init__(self, f: ca.Function) -> None:
        self.f = f
        self._maps: dict[int, ca.Function] = {}

    def __call__(self, *args: np.ndarray, n: int | None = None) -> list[np.ndarray]:
        """Evaluate on ``n`` samples.

        Parameters
        ----------
        *args : numpy.ndarray
            Inputs, samples in columns (``(rows, N)``, or ``(rows, k N)`` for ``k``-column
            matrix inputs).
        n : int, optional
            Number of samples; default the largest number of columns of the inputs.

        Returns
        -------
        list of numpy.ndarray
            The outputs, samples in columns.
        """
        if n is None:
            n = max(a.shape[1] for a in args)
        if n == 1:
            out = self.f(*args)
        else:
            if n not in self._maps:
                self._maps[n] = self.f.map(n)
            out = self._maps[n](*args)
        if not isinstance(out, (list, tuple)):
            out = [out]
        return [np.asarray(o) for o in out]
