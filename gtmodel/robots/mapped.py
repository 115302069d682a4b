"""Column-wise evaluation of a CasADi Function on N samples (the numeric side of every model).

The models of :mod:`gtmodel.robots` build one CasADi Function per formula and evaluate it
on N samples at once with ``Function.map(N)``; :class:`MappedFunction` caches the mapped
Function per N.

Fast calls (issue 17, item 5). A call of a CasADi Function with NumPy arrays converts every
argument to a ``casadi.DM`` and every result back (about 10 us each): 55 us of the L1
inverse dynamics' call, against 1.4 us for the evaluation itself. A single sample
therefore goes through :meth:`casadi.Function.buffer` with preallocated NumPy inputs and
outputs (no conversion), and with ``compiled=True`` the Function is evaluated by its own
CasADi-generated C, compiled once to a cached shared library and loaded as a
``casadi.external`` (:func:`gtmodel._compiler.compiled_function`), single samples and
``map`` batches alike. The generated C is the same graph, never a second model. Batches
go through a call buffer per N as well. Figures: ``python benchmarks/bench_model_calls.py``
(L1 inverse dynamics, one call: 61 us -> 7 us with the buffer, 6 us compiled; the public
method with its checks ~20 us either way; batch of 1000: 2.2 -> 0.6 us per sample compiled).
"""

from __future__ import annotations

import logging

import casadi as ca
import numpy as np

from gtmodel._compiler import compiled_function

__all__ = ["MappedFunction"]

log = logging.getLogger("gtmodel")

#: Compiler flags of the model libraries (the generated code is small: -O2 builds in ~0.1 s).
_COMPILE_FLAGS = ("-O2", "-fPIC", "-shared")


class MappedFunction:
    """Evaluate a CasADi Function column-wise on N samples, caching ``map`` per N.

    Parameters
    ----------
    f : casadi.Function
        The Function of one sample.
    compiled : bool, optional
        Evaluate ``f`` through its generated C, compiled once to a cached shared library
        and loaded as ``casadi.external`` (default False). Results equal the interpreter's
        (tests: to 1e-12). Without a C compiler, with ``GTMODEL_COMPILE=0`` or when the
        build fails, the CasADi interpreter is used and a warning is logged (as the
        filters' and the regressor's ``compiled`` option do).

    Attributes
    ----------
    function : casadi.Function
        The Function evaluated: ``f`` or its compiled external.
    how : str
        How it is evaluated (``"CasADi interpreter"`` or the compiled library and why).

    Notes
    -----
    Dense inputs of the Function's sizes (one sample, or ``n`` samples of the mapped
    Function) are evaluated through :meth:`casadi.Function.buffer` with preallocated NumPy
    arrays per ``n``, without conversion to ``casadi.DM``; this shares state, so one
    instance must not be called from two threads at once.

    Examples
    --------
    ``MappedFunction(f)(X, Y)`` with ``X`` of shape ``(n_x, N)`` and ``Y`` of shape
    ``(n_y, N)`` returns the outputs as arrays of shape ``(n_out, N)``. Matrix inputs
    (e.g. ``3 x 3``) are passed as ``(3, 3 N)`` blocks; then give ``n`` explicitly.
    """

    def __init__(self, f: ca.Function, compiled: bool = False) -> None:
        self.f = f
        self.compiled = bool(compiled)
        self.function, self.how = f, "CasADi interpreter"
        if self.compiled:
            self.function, self.how = compiled_function(f, _COMPILE_FLAGS, "models")
            if self.function is f:
                log.warning("%s: compiled=True, but evaluated by the %s", f.name(), self.how)
            else:
                log.info("%s: %s", f.name(), self.how)
        self._maps: dict[int, ca.Function] = {}
        self._buffers: dict[int, tuple] = {}
        dense = all(f.sparsity_in(i).is_dense() for i in range(f.n_in())) and all(f.sparsity_out(i).is_dense() for i in range(f.n_out()))
        if dense:
            self._sizes_in = [f.nnz_in(i) for i in range(f.n_in())]
            self._shapes_out = [f.size_out(i) for i in range(f.n_out())]

    def _buffer_of(self, n: int):
        """The call buffer of ``f`` (``n == 1``) or of its map over ``n``, its NumPy input and
        output arrays (column-major data) and its trigger (built once per ``n``)."""
        entry = self._buffers.get(n)
        if entry is None:
            fn = self.function if n == 1 else self._mapped(n)
            buf, trigger = fn.buffer()
            ins = [np.zeros(k * n) for k in self._sizes_in]
            outs = [np.zeros(r * c * n) for r, c in self._shapes_out]
            for i, a in enumerate(ins):
                buf.set_arg(i, memoryview(a))
            for i, a in enumerate(outs):
                buf.set_res(i, memoryview(a))
            entry = self._buffers[n] = (buf, ins, outs, trigger)  # buf keeps the pointers: hold every array
        return entry

    def _call_buffer(self, args, n: int) -> list[np.ndarray] | None:
        """``n`` samples through the call buffer, or None if an argument does not fit it."""
        if not hasattr(self, "_sizes_in") or len(args) != len(self._sizes_in):
            return None
        _, ins, outs, trigger = self._buffer_of(n)
        for dst, a, k in zip(ins, args, self._sizes_in):  # copying before every argument is checked is harmless
            if type(a) is not np.ndarray:
                return None
            if a.size == dst.size:
                dst[:] = a.ravel(order="F")
            elif a.size == k:  # one sample's value for all n (as map broadcasts it)
                dst.reshape(n, k)[:] = a.ravel(order="F")
            else:
                return None
        trigger()
        return [o[:, None].copy() if c * n == 1 else o.reshape((c * n, r)).T.copy() for o, (r, c) in zip(outs, self._shapes_out)]

    def _mapped(self, n: int) -> ca.Function:
        if n not in self._maps:
            self._maps[n] = self.function.map(n)
        return self._maps[n]

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
        fast = self._call_buffer(args, n)
        if fast is not None:
            return fast
        out = self.function(*args) if n == 1 else self._mapped(n)(*args)
        if not isinstance(out, (list, tuple)):
            out = [out]
        return [np.asarray(o) for o in out]
