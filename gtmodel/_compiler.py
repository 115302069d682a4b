"""The system C compiler, and CasADi Functions compiled to cached shared libraries.

Base-layer utilities (no gtmodel imports above :mod:`gtmodel.errors`), used by the C code
generator (:mod:`gtmodel.codegen.build`) and by numeric code that evaluates a CasADi graph
on many samples (:mod:`gtmodel.calibration.identification`). The compiled code
is generated from the one CasADi graph by :class:`casadi.CodeGenerator`; it is never a
second model.
"""

from __future__ import annotations

import hashlib
import logging
import os
import shlex
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import casadi as ca

from gtmodel.errors import CodegenError, CompilerNotFoundError

__all__ = ["find_compiler", "run_compiler", "cache_dir", "compiled_function"]

log = logging.getLogger("gtmodel")

#: How to fix a missing compiler (appended to the error message).
FIX = "install a C compiler (e.g. `apt-get install gcc`) or set CC to one"
#: Environment variable switching compiled evaluation off (``0``).
COMPILE_ENV = "GTMODEL_COMPILE"
#: Compiled libraries loaded in this process, by path (shared by all users of one graph).
_LOADED: dict[str, ca.Function] = {}


def find_compiler() -> list[str]:
    """The C compiler command: ``$CC`` if set, else ``gcc`` or ``cc`` found on ``PATH``.

    Returns
    -------
    list of str
        The command words, the first an absolute path to the executable (``$CC`` may
        carry extra flags, e.g. ``"gcc -m64"``).

    Raises
    ------
    CompilerNotFoundError
        ``$CC`` names no executable, or neither ``gcc`` nor ``cc`` is on ``PATH``; the
        one-line message says how to fix it.
    """
    cc = os.environ.get("CC", "").strip()
    if cc:
        words = shlex.split(cc)
        exe = shutil.which(words[0])
        if exe is None:
            raise CompilerNotFoundError(f"no C compiler: CC={cc!r} is not an executable; {FIX}")
        return [exe, *words[1:]]
    for name in ("gcc", "cc"):
        exe = shutil.which(name)
        if exe is not None:
            return [exe]
    raise CompilerNotFoundError(f"no C compiler found (CC unset, no gcc or cc on PATH); {FIX}")


def run_compiler(cmd: list[str], what: str) -> str:
    """Run a compiler command; its failure is one error with the first 40 lines of output.

    Parameters
    ----------
    cmd : list of str
        The command (compiler and arguments).
    what : str
        What is being built, for the messages.

    Returns
    -------
    str
        The compiler's standard error (warnings), empty when silent.

    Raises
    ------
    CompilerNotFoundError
        The compiler cannot be run.
    CodegenError
        It fails, or does not finish within 300 s.
    """
    log.debug("codegen: %s", " ".join(shlex.quote(c) for c in cmd))
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    except FileNotFoundError:
        raise CompilerNotFoundError(f"no C compiler: {cmd[0]!r} cannot be run; {FIX}") from None
    except subprocess.TimeoutExpired:
        raise CodegenError(f"{what}: the compiler did not finish within 300 s") from None
    if proc.returncode != 0:
        msg = (proc.stderr or proc.stdout).strip()
        lines = msg.splitlines()
        if len(lines) > 40:
            msg = "\n".join(lines[:40] + [f"... ({len(lines) - 40} more lines)"])
        raise CodegenError(f"{what} failed (exit {proc.returncode}): {' '.join(cmd)}\n{msg}")
    if proc.stderr.strip():
        log.debug("codegen: %s: compiler output:\n%s", what, proc.stderr.strip())
    return proc.stderr


def cache_dir(subfolder: str) -> Path:
    """Folder of cached compiled libraries.

    Parameters
    ----------
    subfolder : str
        Subfolder per use (e.g. ``"regressor"``).

    Returns
    -------
    pathlib.Path
        ``$GTMODEL_CACHE_DIR/<subfolder>``, else ``$XDG_CACHE_HOME/gtmodel/<subfolder>``
        (default ``~/.cache/gtmodel/<subfolder>``); not created here.
    """
    env = os.environ.get("GTMODEL_CACHE_DIR", "").strip()
    if env:
        return Path(env) / subfolder
    xdg = os.environ.get("XDG_CACHE_HOME", "").strip()
    return (Path(xdg) if xdg else Path.home() / ".cache") / "gtmodel" / subfolder


def compiled_function(f: ca.Function, flags: tuple[str, ...], subfolder: str) -> tuple[ca.Function, str]:
    """``f`` as a shared library compiled from its CasADi-generated C, or ``f`` itself.

    The library is cached under :func:`cache_dir`, keyed by a hash of the generated
    source, the compiler, the flags and the CasADi version, so it is built once per graph,
    written atomically and loaded once per process. Without a compiler, with
    ``GTMODEL_COMPILE=0`` or on any build/load failure, ``f`` is returned (the CasADi
    interpreter, same results) and the reason is in the returned description.

    Parameters
    ----------
    f : casadi.Function
        An SX Function.
    flags : tuple of str
        Compiler flags (must build a shared library, e.g. ``("-O3", "-fPIC", "-shared")``).
    subfolder : str
        Cache subfolder.

    Returns
    -------
    function : casadi.Function
        The compiled Function (``casadi.external``), or ``f``.
    how : str
        Which path was taken and why (for the log).
    """
    if os.environ.get(COMPILE_ENV, "").strip() == "0":
        return f, f"CasADi interpreter ({COMPILE_ENV}=0)"
    try:
        cc = find_compiler()
    except CodegenError as e:
        return f, f"CasADi interpreter ({e})"
    cg = ca.CodeGenerator(f"{f.name()}.c", {"with_header": False})
    cg.add(f)
    key = hashlib.sha256("\0".join([cg.dump(), " ".join(cc), " ".join(flags), ca.__version__]).encode()).hexdigest()[:20]
    name = f"gtm_{f.name()}_{key}"
    folder = cache_dir(subfolder)
    lib = folder / f"{name}.so"
    if str(lib) in _LOADED:
        return _LOADED[str(lib)], f"compiled C (already loaded {lib})"
    try:
        if lib.exists():
            how = f"compiled C (cached {lib})"
        else:
            folder.mkdir(parents=True, exist_ok=True)
            # the symbol names the hash too, so that two libraries never clash in one process
            xs = f.sx_in()
            g = ca.Function(name, xs, f.call(xs), f.name_in(), f.name_out())
            cg = ca.CodeGenerator(f"{name}.c", {"with_header": False})
            cg.add(g)
            t0 = time.perf_counter()
            with tempfile.TemporaryDirectory(dir=folder) as tmp:
                c_file = Path(tmp) / f"{name}.c"
                c_file.write_text(cg.dump())
                out = Path(tmp) / lib.name
                run_compiler([*cc, *flags, str(c_file), "-o", str(out), "-lm"], f"compiling {name}")
                os.replace(out, lib)  # atomic: a concurrent process sees the whole library or none
            how = f"compiled C (built {lib} in {time.perf_counter() - t0:.2f} s)"
        _LOADED[str(lib)] = ca.external(name, str(lib))
        return _LOADED[str(lib)], how
    except (CodegenError, OSError, RuntimeError, subprocess.SubprocessError) as e:
        return f, f"CasADi interpreter (compiling failed: {e})"
