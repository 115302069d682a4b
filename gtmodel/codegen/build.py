"""Build generated C into a shared library with the system C compiler, and load it.

The compiler is ``$CC`` if set, else ``gcc`` or ``cc`` on ``PATH``. Its absence raises
:class:`~gtmodel.errors.CompilerNotFoundError` with a one-line message saying how to fix
it. Both sources (wrapper and CasADi-generated part) are compiled with ``-std=c99 -O2
-Wall -Wextra`` (optionally ``-Werror``).
"""

from __future__ import annotations

import ctypes
import logging
import sys
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from gtmodel._compiler import find_compiler
from gtmodel._compiler import run_compiler as _run
from gtmodel.codegen.writer import GeneratedCode
from gtmodel.codegen.declarations import FunctionSpec
from gtmodel.errors import CodegenError

__all__ = [
    "COMMON_FLAGS",
    "WRAPPER_WARNINGS",
    "CASADI_WARNINGS",
    "find_compiler",
    "compile_shared",
    "load_library",
    "STRICT_EXTRA",
    "load_strict",
    "CompiledFunction",
    "CompiledLibrary",
    "LoopStepRunner",
    "stack_work_bytes",
]

log = logging.getLogger("gtmodel")

#: Flags for every translation unit.
COMMON_FLAGS = ("-std=c99", "-O2", "-fPIC")
#: Warnings for the wrapper (kept warning-free; the tests add ``-Werror``).
WRAPPER_WARNINGS = ("-Wall", "-Wextra")
#: Warnings for the CasADi-generated part (the same: its unused parameters are marked ``(void)``).
CASADI_WARNINGS = ("-Wall", "-Wextra")
#: Flags :func:`load_strict` adds to :func:`compile_shared`'s ``-std=c99 -O2 -Wall -Wextra
#: -Werror``: the robot code's strict set (ISO C, no extensions).
STRICT_EXTRA = ("-pedantic",)



def compile_shared(
    generated: GeneratedCode,
    build_dir: str | Path | None = None,
    *,
    werror: bool = False,
    extra_flags: Sequence[str] = (),
) -> Path:
    """Compile generated code into a shared library.

    Parameters
    ----------
    generated : GeneratedCode
        Result of :func:`gtmodel.codegen.generate`.
    build_dir : str or pathlib.Path or None, optional
        Folder for objects and the library (created if missing); default
        ``<out_dir>/build``.
    werror : bool, optional
        Compile with ``-Werror`` (warnings become errors).
    extra_flags : sequence of str, optional
        More compiler flags for both sources (e.g. ``("-march=native",)``).

    Returns
    -------
    pathlib.Path
        The shared library, ``lib<prefix>.so`` (``.dylib`` on macOS).

    Raises
    ------
    CompilerNotFoundError
        No C compiler (see :func:`find_compiler`).
    CodegenError
        Compilation or linking failed; the message holds the command and the compiler output.
    """
    cc = find_compiler()
    build = Path(build_dir) if build_dir is not None else generated.out_dir / "build"
    build.mkdir(parents=True, exist_ok=True)
    inc = ["-I", str(generated.out_dir)] + [a for d in generated.include_dirs for a in ("-isystem", d)]
    extra = list(extra_flags)
    obj_casadi = build / f"{generated.prefix}_casadi.o"
    obj_wrap = build / f"{generated.prefix}.o"
    werr = ["-Werror"] if werror else []
    _run(
        [*cc, *COMMON_FLAGS, *CASADI_WARNINGS, *werr, *extra, *inc, "-c", str(generated.casadi_source), "-o", str(obj_casadi)],
        f"compiling {generated.casadi_source.name}",
    )
    _run(
        [*cc, *COMMON_FLAGS, *WRAPPER_WARNINGS, *werr, *extra, *inc, "-c", str(generated.source), "-o", str(obj_wrap)],
        f"compiling {generated.source.name}",
    )
    suffix = ".dylib" if sys.platform == "darwin" else ".so"
    lib = build / f"lib{generated.prefix}{suffix}"
    _run([*cc, "-shared", *extra, str(obj_casadi), str(obj_wrap), "-o", str(lib), *generated.link_flags, "-lm"], f"linking {lib.name}")
    log.info("codegen: built %s", lib)
    return lib


class CompiledFunction:
    """One generated C function, callable from Python through ctypes.

    Parameters
    ----------
    cfunc : ctypes function pointer
        The loaded symbol ``<prefix>_<name>``.
    spec : FunctionSpec
        Its declaration.
    sizes_in : sequence of int
        Length of each array argument (0 for ``int`` arguments), in C order.
    sizes_out : sequence of int
        Length of each output array, in C order.
    real : {"double", "float"}, optional
        Floating-point type of the arrays.
    """

    def __init__(self, cfunc, spec: FunctionSpec, sizes_in: Sequence[int], sizes_out: Sequence[int], real: str = "double") -> None:
        self.cfunc = cfunc
        self.spec = spec
        self.sizes_in = tuple(sizes_in)
        self.sizes_out = tuple(sizes_out)
        self.dtype = np.float32 if real == "float" else np.float64
        self.ctype = ctypes.c_float if real == "float" else ctypes.c_double
        self.iterations = ctypes.c_int(-1)
        # the same symbol with address arguments, for the row loop of :meth:`call_rows`
        raw_types = [ctypes.c_int if n == 0 else ctypes.c_void_p for n in self.sizes_in]
        raw_types += [ctypes.c_void_p] * (len(self.sizes_out) + (spec.newton is not None))
        self._raw = ctypes.CFUNCTYPE(ctypes.c_int, *raw_types)(ctypes.cast(cfunc, ctypes.c_void_p).value)

    def call_rows(self, *args, fill: float = 0.0) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
        """Call the C function once per row of stacked inputs (a C-side loop of single calls).

        Parameters
        ----------
        *args : array_like
            The inputs in C order, one row per call: ``(N, n)`` arrays of the declared
            sizes (matrices row-major, 9 values), ``(N,)`` integers for
            configuration/solution. A row of an optional argument that is not all finite
            is passed as NULL.
        fill : float, optional
            Value the output rows hold before the call (kept where the status is not OK).

        Returns
        -------
        status : numpy.ndarray of int, shape (N,)
            The returned status codes (0 = ``GT_OK``).
        outputs : tuple of numpy.ndarray, shape (N, n)
            The outputs, one row per call.

        Raises
        ------
        CodegenError
            Wrong number of arguments, wrong array sizes or differing row counts.
        """
        if len(args) != len(self.sizes_in):
            raise CodegenError(f"{self.spec.name}: expected {len(self.sizes_in)} arguments, got {len(args)}")
        N = len(args[0])
        item = np.dtype(self.dtype).itemsize
        columns: list[list] = []
        keep = []  # the input buffers the addresses point into
        for a, n, decl in zip(args, self.sizes_in, self.spec.args):
            if n == 0:
                vals = np.asarray(a, dtype=int).reshape(-1)
                if vals.size != N:
                    raise CodegenError(f"{self.spec.name}: {decl.name}: expected {N} values, got {vals.size}")
                columns.append([int(v) for v in vals])
                continue
            arr = np.ascontiguousarray(np.reshape(a, (N, -1) if N else (0, n)), dtype=self.dtype)  # no rows: no call
            if arr.shape[1] != n:
                raise CodegenError(f"{self.spec.name}: {decl.name}: expected rows of {n} values, got {arr.shape[1]}")
            base = arr.ctypes.data
            ptrs = [base + i * n * item for i in range(N)]
            if decl.optional:
                ptrs = [p if f else None for p, f in zip(ptrs, np.all(np.isfinite(arr), axis=1))]
            columns.append(ptrs)
            keep.append(arr)
        outs = tuple(np.full((N, n), fill, dtype=self.dtype) for n in self.sizes_out)
        for o, n in zip(outs, self.sizes_out):
            columns.append([o.ctypes.data + i * n * item for i in range(N)])
        if self.spec.newton is not None:
            columns.append([ctypes.addressof(self.iterations)] * N)
        raw = self._raw
        status = np.fromiter((raw(*row) for row in zip(*columns)), dtype=int, count=N)
        del keep
        return status, outs

    def __call__(self, *args, out: Sequence[np.ndarray] | None = None) -> tuple[int, tuple[np.ndarray, ...]]:
        """Call the C function.

        Parameters
        ----------
        *args : array_like or int or None
            The inputs in C order: arrays of the declared sizes (matrices row-major, 9
            values), ``int`` for configuration/solution, None for a NULL optional pointer.
        out : sequence of numpy.ndarray or None, optional
            Output buffers (float64 or float32 as generated, C-contiguous, declared
            sizes); new zero arrays if None. A Newton function's iteration count is left
            in :attr:`iterations` (``.value``).

        Returns
        -------
        status : int
            The returned status code (0 = ``GT_OK``).
        outputs : tuple of numpy.ndarray
            The output buffers (untouched by the C code unless ``status == 0``).

        Raises
        ------
        CodegenError
            Wrong number of arguments or wrong array sizes.
        """
        if len(args) != len(self.sizes_in):
            raise CodegenError(f"{self.spec.name}: expected {len(self.sizes_in)} arguments, got {len(args)}")
        if out is None:
            out = tuple(np.zeros(n, dtype=self.dtype) for n in self.sizes_out)
        cargs = []
        keep = []
        ptr = ctypes.POINTER(self.ctype)
        for a, n in zip(args, self.sizes_in):
            if n == 0:
                cargs.append(int(a))
            elif a is None:
                cargs.append(None)
            else:
                arr = np.ascontiguousarray(a, dtype=self.dtype)
                if arr.size != n:
                    raise CodegenError(f"{self.spec.name}: expected an array of {n} values, got shape {arr.shape}")
                keep.append(arr)
                cargs.append(arr.ctypes.data_as(ptr))
        for o, n in zip(out, self.sizes_out):
            if o.dtype != self.dtype or o.size != n or not o.flags.c_contiguous:
                raise CodegenError(f"{self.spec.name}: output buffer must be a C-contiguous {np.dtype(self.dtype).name} array of {n}")
            cargs.append(o.ctypes.data_as(ptr))
        if self.spec.newton is not None:
            self.iterations.value = -1
            cargs.append(ctypes.byref(self.iterations))
        status = int(self.cfunc(*cargs))
        return status, tuple(out)


class CompiledLibrary:
    """A loaded generated library: the ONE owner of its ctypes interface.

    Its functions by name (:class:`CompiledFunction`), its version string and status names,
    the real type of the build (``double`` or ``float``: every array passed through it has
    that type, so a ``--real float`` library is called as it is), the stack work of a
    function and, for a loop controller (:func:`gtmodel.codegen.loop_step.generate_loop_step`),
    the memory interface ``<prefix>_memory``, ``<prefix>_init``, ``<prefix>_step``
    (:meth:`loop_interface`, :meth:`loop_runner`) and the QP arena's figures
    (:meth:`heap_stats`). Every check of generated code calls the C through it.

    Parameters
    ----------
    generated : GeneratedCode
        What was generated (signatures are taken from it).
    path : pathlib.Path
        The shared library built by :func:`compile_shared`.
    """

    def __init__(self, generated: GeneratedCode, path: Path) -> None:
        self.generated = generated
        self.path = Path(path)
        try:
            self.cdll = ctypes.CDLL(str(self.path))
        except OSError as exc:
            raise CodegenError(f"cannot load {self.path}: {exc}") from None
        p = generated.prefix
        self._version = self.bind("version", ctypes.c_char_p, [])
        self._status_string = self.bind("status_string", ctypes.c_char_p, [ctypes.c_int])
        self.functions: dict[str, CompiledFunction] = {}
        real = getattr(generated, "real", "double")
        dptr = ctypes.POINTER(ctypes.c_float if real == "float" else ctypes.c_double)
        for spec in generated.specs:
            sizes_in, sizes_out = generated.signatures[spec.name]
            types = [ctypes.c_int if n == 0 else dptr for n in sizes_in] + [dptr] * len(sizes_out)
            if spec.newton is not None:
                types.append(ctypes.POINTER(ctypes.c_int))
            cf = self.bind(spec.name, ctypes.c_int, types)
            self.functions[spec.name] = CompiledFunction(cf, spec, sizes_in, sizes_out, real)

    def __getitem__(self, name: str) -> CompiledFunction:
        return self.functions[name]

    def version(self) -> str:
        """The version string compiled into the library.

        Returns
        -------
        str
            E.g. ``"gtmodel 0.1.0; casadi 3.8.2; parameters L1 sha256:...; friction exact"``.
        """
        return self._version().decode()

    def status_string(self, status: int) -> str:
        """Name of a status code, from the library.

        Parameters
        ----------
        status : int
            A returned status.

        Returns
        -------
        str
            E.g. ``"GT_UNREACHABLE"``.
        """
        return self._status_string(int(status)).decode()

    @property
    def real_type(self) -> type:
        """The ctypes type of the library's reals (``ctypes.c_float`` for ``real = "float"``, else ``ctypes.c_double``)."""
        return ctypes.c_float if getattr(self.generated, "real", "double") == "float" else ctypes.c_double

    def work_bytes(self, name: str) -> int:
        """Stack work arrays of one call of a generated function [bytes].

        Parameters
        ----------
        name : str
            A function of :attr:`GeneratedCode.work_sizes` (e.g. ``"control"``).

        Returns
        -------
        int
            CasADi's ``sz_arg`` + ``sz_res`` pointers, ``sz_iw`` integers (``casadi_int``,
            ``long long``) and ``sz_w`` reals of the library's real type.
        """
        return stack_work_bytes(self.generated.work_sizes[name], getattr(self.generated, "real", "double"))

    def bind(self, name: str, restype: Any, argtypes: Sequence[Any], optional: bool = False) -> Any:
        """The exported C function ``<prefix>_<name>`` with its ctypes signature set.

        The one place outside this class's constructor where a symbol of a generated library
        is looked up (the checks, the re-timing function, the loop interface).

        Parameters
        ----------
        name : str
            The function's name without the prefix, e.g. ``"kalman_update"``.
        restype : ctypes type or None
            Its return type.
        argtypes : sequence of ctypes types
            Its argument types, in C order.
        optional : bool, optional
            Return None when the library does not export it (default: raise).

        Returns
        -------
        ctypes function or None
            The bound function (None: not exported and ``optional``).

        Raises
        ------
        CodegenError
            The library does not export ``<prefix>_<name>`` (and not ``optional``).
        """
        symbol = f"{self.generated.prefix}_{name}"
        fn = getattr(self.cdll, symbol, None)
        if fn is None:
            if optional:
                return None
            raise CodegenError(f"{self.path}: the library does not export {symbol}")
        fn.restype, fn.argtypes = restype, list(argtypes)
        return fn

    def loop_interface(self) -> tuple[type, Any, Any]:
        """The memory struct type and the ``_init`` / ``_step`` functions of a loop controller's library.

        Returns
        -------
        memory : type
            A ``ctypes.Structure`` of the layout of ``<prefix>_memory`` (reals of :attr:`real_type`).
        init : callable
            ``init(ctypes.byref(mem)) -> int``.
        step : callable
            ``step(ctypes.byref(mem), t, x_ptr, u_ptr) -> int`` (``x_ptr``, ``u_ptr`` arrays of
            :attr:`real_type`, or None).

        Raises
        ------
        CodegenError
            Not a loop controller's library (no ``<prefix>_init`` / ``<prefix>_step``).
        """
        step = self.generated.parameters
        if not all(hasattr(step, a) for a in ("nx", "nu", "nw")):
            raise CodegenError(f"{self.path}: not a loop controller's library (no memory interface)")
        real = self.real_type
        memory = type("Memory", (ctypes.Structure,), {"_fields_": [
            ("u_last", real * step.nu), ("w", real * max(step.nw, 1)), ("steps", ctypes.c_long), ("status", ctypes.c_int)]})
        init = self.bind("init", ctypes.c_int, [ctypes.POINTER(memory)])
        fstep = self.bind("step", ctypes.c_int, [ctypes.POINTER(memory), real, ctypes.POINTER(real), ctypes.POINTER(real)])
        return memory, init, fstep

    def loop_runner(self) -> "LoopStepRunner":
        """The loop controller's step with its own memory, as the closed loop calls it.

        Returns
        -------
        LoopStepRunner
            ``runner(t, x) -> (status, u)``, ``runner.reset()``, ``runner.memory()``, ``runner.memory_bytes``.

        Raises
        ------
        CodegenError
            Not a loop controller's library.
        """
        return LoopStepRunner(self)

    def heap_stats(self) -> tuple[int, int, int] | None:
        """The heap arena's figures of a loop step whose QP solver allocates (``<prefix>_heap_stats``), of the calling thread.

        Returns
        -------
        tuple of int or None
            ``(peak bytes, heap calls, arena bytes)``; None when the library has no arena.
        """
        ul = ctypes.c_ulong
        fn = self.bind("heap_stats", ctypes.c_int, [ctypes.POINTER(ul)] * 3, optional=True)
        if fn is None:
            return None
        peak, calls, size = ul(), ul(), ul()
        fn(ctypes.byref(peak), ctypes.byref(calls), ctypes.byref(size))
        return int(peak.value), int(calls.value), int(size.value)


class LoopStepRunner:
    """A loop controller's compiled ``<prefix>_step`` with its own memory (:meth:`CompiledLibrary.loop_runner`).

    The state and input arrays have the library's real type: a ``float`` build computes in
    float32 from the double state rounded once (relative 6e-8), and returns float32 inputs.

    Parameters
    ----------
    library : CompiledLibrary
        A loop controller's loaded library.

    Attributes
    ----------
    memory_bytes : int
        ``sizeof(<prefix>_memory)`` (the caller's static memory).
    """

    def __init__(self, library: CompiledLibrary) -> None:
        memory, self._init, self._step = library.loop_interface()
        self._mem = memory()
        self._ref = ctypes.byref(self._mem)
        step, real = library.generated.parameters, library.real_type
        self._x, self._u = (real * step.nx)(), (real * step.nu)()
        self._nw = int(step.nw)
        self.memory_bytes = ctypes.sizeof(memory)
        self.reset()

    def __call__(self, t: float, x: np.ndarray) -> tuple[int, np.ndarray]:
        """One step: ``(status, u)`` for the measured state ``x`` ``(nx,)`` at time ``t`` [s].

        Parameters
        ----------
        t : float
            Time [s].
        x : numpy.ndarray
            ``(nx,)`` measured state.

        Returns
        -------
        status : int
            The step's status code.
        u : numpy.ndarray
            ``(nu,)`` the input (float64 copy).
        """
        self._x[:] = [float(v) for v in x]
        code = self._step(self._ref, t, self._x, self._u)
        return code, np.array(self._u[:], dtype=float)

    def memory(self) -> np.ndarray:
        """The memory's ``w`` (the warm start and the estimator's state) as it is now.

        Returns
        -------
        numpy.ndarray
            ``(nw,)`` float64 copy.
        """
        return np.array(self._mem.w[:self._nw], dtype=float)

    def reset(self) -> int:
        """Call ``<prefix>_init`` on the memory.

        Returns
        -------
        int
            Its status.
        """
        return self._init(self._ref)


def load_library(generated: GeneratedCode, path: str | Path) -> CompiledLibrary:
    """Load a compiled library with ctypes and declare its function signatures.

    Parameters
    ----------
    generated : GeneratedCode
        What was generated.
    path : str or pathlib.Path
        Shared library from :func:`compile_shared`.

    Returns
    -------
    CompiledLibrary
        Callable functions by name (``lib["ik"](T, 0)`` -> ``(status, (q,))``).

    Raises
    ------
    CodegenError
        The library cannot be loaded.
    """
    return CompiledLibrary(generated, Path(path))


def load_strict(generated: GeneratedCode, build_dir: str | Path | None = None) -> CompiledLibrary:
    """Compile generated code under the strict flags (``-Werror`` and :data:`STRICT_EXTRA`) and load it.

    The build of the self-checks of a user model's and a loop controller's code
    (:func:`~gtmodel.codegen.model_code.check_model`,
    :func:`~gtmodel.codegen.loop_step.check_loop_step`).

    Parameters
    ----------
    generated : GeneratedCode
        What was generated.
    build_dir : str or pathlib.Path or None, optional
        Folder for objects and the library; default ``<out_dir>/build``.

    Returns
    -------
    CompiledLibrary
        The loaded library.

    Raises
    ------
    CompilerNotFoundError
        No C compiler.
    CodegenError
        Compilation (a warning included) or loading failed.
    """
    return load_library(generated, compile_shared(generated, build_dir, werror=True, extra_flags=STRICT_EXTRA))


def stack_work_bytes(sizes: Sequence[int], real: str = "double") -> int:
    """Stack work arrays of one call of a generated function [bytes].

    Parameters
    ----------
    sizes : sequence of int
        CasADi's ``(sz_arg, sz_res, sz_iw, sz_w)`` (:attr:`GeneratedCode.work_sizes`).
    real : {"double", "float"}, optional
        The generated code's real type.

    Returns
    -------
    int
        ``sz_arg`` + ``sz_res`` pointers, ``sz_iw`` integers (``casadi_int``, ``long long``) and
        ``sz_w`` reals, the arrays the generated wrapper declares on the stack.
    """
    sz = [int(v) for v in sizes]
    return (ctypes.sizeof(ctypes.c_void_p) * (sz[0] + sz[1]) + ctypes.sizeof(ctypes.c_longlong) * sz[2]
            + ctypes.sizeof(ctypes.c_float if real == "float" else ctypes.c_double) * sz[3])
