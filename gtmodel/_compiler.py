"""The system C compiler, child processes, and CasADi Functions compiled to cached shared libraries.

Base-layer utilities (no gtmodel imports above :mod:`gtmodel.errors`), used by the C code
generator (:mod:`gtmodel.codegen.build`) and by numeric code that evaluates a CasADi graph
on many samples (:mod:`gtmodel.calibration.identification`). The compiled code
is generated from the one CasADi graph by :class:`casadi.CodeGenerator`; it is never a
second model.

Every child process gtmodel starts (compilers, ``make``, the check programs) goes through
:func:`run_child`: it runs in a process group of its own under a small guard process, and
the whole group is killed when gtmodel stops it (time-out, SIGINT/SIGTERM turned into
:class:`KeyboardInterrupt`, any exception), when gtmodel exits (``atexit``) and, on Linux,
when gtmodel dies without running any clean-up (SIGKILL): the guard asks the kernel for a
signal when its parent dies (``prctl(PR_SET_PDEATHSIG)``) and then kills its group, so
that a compiler's own children (``cc1``, ``as``, ``ld``) go too.
"""

from __future__ import annotations

import atexit
import hashlib
import logging
import os
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import casadi as ca

from gtmodel.errors import CodegenError, CompilerNotFoundError

__all__ = ["find_compiler", "run_child", "run_compiler", "cache_dir", "compiled_function"]

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


#: The guard between gtmodel and a child: leader of the child's process group; kills the
#: group when gtmodel dies (Linux: parent-death signal) or when it is signalled itself.
_GUARD = r"""
import os, signal, sys
def stop(signum=None, frame=None):
    os.killpg(0, signal.SIGKILL)
for s in (signal.SIGTERM, signal.SIGHUP, signal.SIGINT):
    signal.signal(s, stop)
if sys.platform.startswith("linux"):
    import ctypes
    ctypes.CDLL(None).prctl(1, signal.SIGTERM, 0, 0, 0)  # PR_SET_PDEATHSIG
if os.getppid() != int(sys.argv[1]):  # gtmodel died before the parent-death signal was set
    stop()
try:
    pid = os.posix_spawn(sys.argv[2], sys.argv[2:], os.environ)
except OSError as e:
    sys.stderr.write("gtmodel: cannot run %r: %s\n" % (sys.argv[2], e.strerror))
    os._exit(127)
while True:
    try:
        status = os.waitpid(pid, 0)[1]
        break
    except ChildProcessError:
        os._exit(127)
code = os.waitstatus_to_exitcode(status)
os._exit(code if code >= 0 else 128 - code)
"""
#: Process groups of the children running now (killed at exit).
_GROUPS: set[int] = set()
_GROUPS_LOCK = threading.Lock()


def _kill_group(pgid: int) -> None:
    try:
        os.killpg(pgid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass


@atexit.register
def _kill_all() -> None:
    with _GROUPS_LOCK:
        groups = list(_GROUPS)
    for pgid in groups:
        _kill_group(pgid)


def run_child(cmd: list[str], timeout: float | None = None, cwd: str | os.PathLike | None = None,
              text: bool = True) -> subprocess.CompletedProcess:
    """Run a child process to its end, its output captured; nothing of it outlives the call.

    The one way gtmodel starts a child (compilers, ``make``, the check programs): the child
    runs under a guard in a process group of its own (so a signal sent to gtmodel's PID
    alone reaches gtmodel, which stops the child). The whole group (the child and whatever
    it started, e.g. ``cc1`` under ``gcc``) is killed with SIGKILL when the call ends by
    a time-out or an exception (a SIGINT/SIGTERM raised as :class:`KeyboardInterrupt` by
    :mod:`gtmodel._signals`), when the child has ended (stragglers), at gtmodel's exit, and
    on Linux when gtmodel dies without clean-up (the guard's parent-death signal).

    Parameters
    ----------
    cmd : list of str
        The command; the first word is looked up on ``PATH``.
    timeout : float, optional
        Seconds; None waits for ever.
    cwd : path-like, optional
        Working folder of the child.
    text : bool, optional
        Output as text (invalid UTF-8 replaced), else as bytes.

    Returns
    -------
    subprocess.CompletedProcess
        Exit code (128 + the signal's number when a signal ended the child), standard
        output and error.

    Raises
    ------
    FileNotFoundError
        The command's first word is no executable.
    subprocess.TimeoutExpired
        It did not end within ``timeout`` (the group is killed).
    """
    exe = shutil.which(cmd[0]) if os.sep not in cmd[0] else (cmd[0] if os.access(cmd[0], os.X_OK) and os.path.isfile(cmd[0]) else None)
    if exe is None:
        raise FileNotFoundError(f"no executable {cmd[0]!r}")
    if os.name != "posix":  # no process groups to kill: the plain way
        return subprocess.run([exe, *cmd[1:]], capture_output=True, text=text, timeout=timeout, cwd=cwd)
    # without a Python to run the guard (an embedded interpreter): the child leads its group itself
    guard = [sys.executable, "-I", "-S", "-c", _GUARD, str(os.getpid()), exe, *cmd[1:]] if sys.executable else [exe, *cmd[1:]]
    proc = subprocess.Popen(guard, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=text, errors="replace" if text else None, cwd=cwd, start_new_session=True)
    with _GROUPS_LOCK:
        _GROUPS.add(proc.pid)
    deadline = None if timeout is None else time.monotonic() + timeout
    try:
        while True:  # until the pipes close: a straggler holding them open is killed once the child ended
            try:
                out, err = proc.communicate(timeout=0.25 if deadline is None else max(0.0, min(0.25, deadline - time.monotonic())))
                break
            except subprocess.TimeoutExpired:
                if proc.poll() is not None:
                    _kill_group(proc.pid)
                elif deadline is not None and time.monotonic() >= deadline:
                    _kill_group(proc.pid)
                    proc.communicate()
                    raise subprocess.TimeoutExpired(cmd, timeout) from None
    except subprocess.TimeoutExpired:
        raise
    except BaseException:  # KeyboardInterrupt (a signal), anything: the group goes
        _kill_group(proc.pid)
        proc.communicate()
        raise
    finally:
        _kill_group(proc.pid)  # stragglers a finished child left running
        with _GROUPS_LOCK:
            _GROUPS.discard(proc.pid)
    return subprocess.CompletedProcess(cmd, proc.returncode, out, err)


def _source_size(cmd: list[str]) -> str:
    """What a compiler that timed out was given: the C sources' size, and how to make it smaller ("" without sources)."""
    size = 0
    for arg in cmd:
        path = Path(arg)
        if path.suffix == ".c" and path.is_file():
            size += path.stat().st_size
    if not size:
        return ""
    return (f" on {size / 1e6:.3g} MB of C; generated code that large comes from a large expression graph: a step "
            "unrolled over many substeps and a long horizon (the Jacobian by every input), an implicit step ('radau2', "
            "'implicit_euler') with its Newton iterations (15.9 MB for a 5-state model's radau2 step with its Jacobian, "
            "against 1.6 MB for rk4), or many SQP iterations; give fewer substeps (with an explicit method, the fewest "
            "its stability check allows), a shorter horizon or fewer input blocks, or an explicit method for an implicit one")


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
        proc = run_child(cmd, timeout=300)
    except FileNotFoundError:
        raise CompilerNotFoundError(f"no C compiler: {cmd[0]!r} cannot be run; {FIX}") from None
    except subprocess.TimeoutExpired:
        raise CodegenError(f"{what}: the compiler did not finish within 300 s{_source_size(cmd)}") from None
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
