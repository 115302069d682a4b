"""Building generated C: strict warnings, a C caller of the public header, missing compiler.

Independent reference: the Python evaluation of the CasADi model (``GantryTau3Kinematics``)
for the values printed by the C test program.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from gtmodel.codegen import compile_shared, find_compiler
from gtmodel.codegen.build import COMMON_FLAGS
from gtmodel.errors import CodegenError, CompilerNotFoundError
from gtmodel.robots.kinematics import GantryTau3Kinematics

from ..conftest import REPO

needs_gcc = pytest.mark.skipif(shutil.which("gcc") is None and shutil.which("cc") is None, reason="no C compiler")

#: Printed with %.17g, so the round trip through text is exact [m].
PRINT_TOLERANCE = 0.0
STRICT = ("-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-Wshadow", "-Wconversion")


@needs_gcc
def test_wrapper_compiles_with_strict_warnings_as_errors(built):
    gen, _ = built("L1")
    cc = find_compiler()
    proc = subprocess.run(
        [*cc, *STRICT, "-O2", "-I", str(gen.out_dir), "-c", str(gen.source), "-o", "/dev/null"],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr


@needs_gcc
def test_c_program_using_the_public_header(built, tmp_path):
    """A plain C caller: statuses, values, row-major layout, untouched outputs on error."""
    gen, lib = built("L1")
    k = GantryTau3Kinematics("L1")
    T = [float(x) for x in k.workspace_grid(0.1)[40]]
    prog = tmp_path / "main.c"
    prog.write_text(
        f"""
#include <stdio.h>
#include "gt_L1.h"
int main(void)
{{
    const double T[3] = {{{T[0]!r}, {T[1]!r}, {T[2]!r}}};
    const double far[3] = {{100.0, 100.0, 100.0}};
    double q[3], J[9], keep[3] = {{-7.0, -7.0, -7.0}};
    int s1 = gt_L1_ik(T, 0, q);
    int s2 = gt_L1_jacobian(T, 0, J);
    int s3 = gt_L1_ik(far, 0, keep);
    int s4 = gt_L1_ik(T, 9, keep);
    printf("%d %d %d %d\\n", s1, s2, s3, s4);
    printf("%.17g %.17g %.17g\\n", q[0], q[1], q[2]);
    printf("%.17g %.17g %.17g\\n", J[1], J[3], J[5]);
    printf("%.17g %.17g %.17g\\n", keep[0], keep[1], keep[2]);
    printf("%s\\n", gt_L1_status_string(s3));
    return 0;
}}
"""
    )
    exe = tmp_path / "main"
    cc = find_compiler()
    subprocess.run(
        [*cc, *STRICT, "-I", str(gen.out_dir), str(prog), "-L", str(lib.path.parent), "-lgt_L1",
         f"-Wl,-rpath,{lib.path.parent}", "-lm", "-o", str(exe)],
        check=True,
    )
    lines = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout.splitlines()
    assert lines[0].split() == ["0", "0", "1", "4"]
    q = np.array(lines[1].split(), dtype=float)
    np.testing.assert_allclose(q, k.ik(T, 0), rtol=0, atol=PRINT_TOLERANCE)
    J = k.jacobian(T, 0)
    np.testing.assert_allclose(np.array(lines[2].split(), dtype=float), [J[0, 1], J[1, 0], J[1, 2]], rtol=0, atol=PRINT_TOLERANCE)
    assert lines[3].split() == ["-7", "-7", "-7"]
    assert lines[4] == "GT_UNREACHABLE"


def test_missing_compiler_is_one_clear_error(monkeypatch, tmp_path):
    monkeypatch.setenv("CC", str(tmp_path / "no-such-compiler"))
    monkeypatch.setenv("PATH", "")
    with pytest.raises(CompilerNotFoundError, match=r"apt-get install gcc.*set CC") as exc:
        find_compiler()
    assert "\n" not in str(exc.value)
    monkeypatch.delenv("CC")
    with pytest.raises(CompilerNotFoundError, match=r"no C compiler found.*apt-get install gcc"):
        find_compiler()


def test_missing_compiler_stops_compile_shared(built, monkeypatch, tmp_path):
    gen, _ = built("L1")
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(CompilerNotFoundError, match="apt-get install gcc"):
        compile_shared(gen, tmp_path / "build")
    assert issubclass(CompilerNotFoundError, CodegenError)


@needs_gcc
def test_cc_environment_variable_is_honoured(monkeypatch):
    gcc = shutil.which("gcc") or shutil.which("cc")
    monkeypatch.setenv("CC", f"{gcc} -m64")
    assert find_compiler() == [gcc, "-m64"]


@needs_gcc
def test_compiler_error_is_reported(built, tmp_path):
    import dataclasses

    gen, _ = built("L1")
    broken = tmp_path / "broken.c"
    broken.write_text(gen.source.read_text() + "\nthis is not C;\n")
    gen2 = dataclasses.replace(gen, source=broken)
    with pytest.raises(CodegenError, match="compiling broken.c failed"):
        compile_shared(gen2, tmp_path / "build")
    assert "-std=c99" in COMMON_FLAGS


#: Loading a shared library or looking up its symbols: only CompiledLibrary does it (the C
#: library ``ctypes.CDLL(None)`` for prctl/errno is not a generated library).
_LIBRARY_ACCESS = re.compile(r"\.cdll\b|ctypes\.CDLL\((?!None)|ctypes\.cdll\.|LoadLibrary")
_OWNER = Path("gtmodel/codegen/build.py")
#: Modules that load a library that is not generated code (a third-party one), each with what it loads.
#: The second item: the fixed patterns by which it finds that library inside the third party's own installation.
_NOT_GENERATED = {
    Path("gtmodel/modeling/structure/pivoting.py"): ("LAPACK's dgeqp3 from the OpenBLAS NumPy's wheels ship",
                                                      ['root.parent.glob("numpy.libs/*scipy_openblas64_*")', "root = Path(np.__file__)"]),
    Path("gtmodel/_blas.py"): ("the OpenBLAS CasADi's wheel ships, to set its thread count",
                               ['importlib.util.find_spec("casadi")', 'Path(f).glob(f"{_PREFIX}*")', '_PREFIX = "libcasadi-tp-openblas"']),
}


@pytest.mark.parametrize("module", sorted(p.relative_to(REPO) for p in (REPO / "gtmodel").rglob("*.py")
                                          if p.relative_to(REPO) != _OWNER and p.relative_to(REPO) not in _NOT_GENERATED),
                         ids=str)
def test_only_compiled_library_loads_generated_code(module):
    """Source scan: every other module calls generated C through CompiledLibrary (its functions,
    loop_interface, bind), so one class owns the ctypes interface (float builds included)."""
    assert not _LIBRARY_ACCESS.findall((REPO / module).read_text())


@pytest.mark.parametrize("module", sorted(_NOT_GENERATED), ids=str)
def test_modules_loading_other_libraries_load_no_generated_code(module):
    # the exempt module finds its library by a fixed pattern inside the third party's own installation (NumPy's, CasADi's), never a path given to it
    text = (REPO / module).read_text()
    assert all(pattern in text for pattern in _NOT_GENERATED[module][1])


def test_bind_names_a_missing_symbol(built):
    generated, library = built("L1")
    with pytest.raises(CodegenError, match=f"does not export {generated.prefix}_no_such_function"):
        library.bind("no_such_function", None, [])
    assert library.bind("no_such_function", None, [], optional=True) is None
