"""The fix of CasADi's generated HPIPM call (gtmodel.codegen.hpipm_source).

Reference: the text expected by construction; that the values are HPIPM's own defaults and that
the generated step needs them is checked through the step itself in tests/control/test_mpc_hpipm.py
(slow: a compile; 3-4 QP iterations with them, 50 and a failure without). The memory patch and
the library selection: the text and the linker arguments expected by construction (CasADi 3.8.2's
setup, abridged); that the patched step computes what the Python reference does is checked by the
codegen checks of the hpipm MPC (tests/control/test_mpc_hpipm.py, tests/codegen/test_loop_step_solvers.py).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from gtmodel.codegen.hpipm_source import HPIPM_ENV, HPIPM_STATIC, HPIPM_UNSET_OPTIONS, hpipm_libraries, patch_hpipm_memory, patch_hpipm_options
from gtmodel.codegen.loop_step import solver_libraries
from gtmodel.errors import CodegenError

CALL = "#include <hpipm_d_ocp_qp_ipm.h>\n  p.hpipm_options.iter_max = 50;\n  p.hpipm_options.mode = 1;\n"


@pytest.mark.parametrize("text, patched", [(CALL, True), (CALL.replace("hpipm_d_ocp_qp_ipm", "daqp/api"), False)],
                         ids=["hpipm", "other solver"])
def test_unset_options_are_set_after_the_mode(tmp_path, text, patched):
    path = tmp_path / "x_casadi.c"
    path.write_text(text)
    assert patch_hpipm_options(path) == patched
    out = path.read_text()
    want = text.replace("mode = 1;", "mode = 1;" + "".join(f" p.hpipm_options.{k} = {v};" for k, v in HPIPM_UNSET_OPTIONS.items())) if patched else text
    assert out == want



# CasADi 3.8.2's setup of HPIPM's memory in casadi_hpipm_solve, as generated (abridged: the QP's data between)
SETUP = """#include <hpipm_d_ocp_qp_ipm.h>
int casadi_hpipm_solve(struct casadi_hpipm_data* d) {
    int dim_size = d_ocp_qp_dim_memsize(p->N);
\t  void *dim_mem = malloc(dim_size);
    struct d_ocp_qp_dim dim;
\t  d_ocp_qp_dim_create(p->N, &dim, dim_mem);
    int qp_size = d_ocp_qp_memsize(&dim);
    void *qp_mem = malloc(qp_size);
    struct d_ocp_qp qp;
    d_ocp_qp_create(&dim, &qp, qp_mem);
    d_ocp_qp_set_all(&qp);
    int qp_sol_size = d_ocp_qp_sol_memsize(&dim);
    void *qp_sol_mem = malloc(qp_sol_size);
    struct d_ocp_qp_sol qp_sol;
    d_ocp_qp_sol_create(&dim, &qp_sol, qp_sol_mem);
    int ipm_arg_size = d_ocp_qp_ipm_arg_memsize(&dim);
    void *ipm_arg_mem = malloc(ipm_arg_size);
    struct d_ocp_qp_ipm_arg myarg;
    d_ocp_qp_ipm_arg_create(&dim, &myarg, ipm_arg_mem);
    memcpy(&myarg, &p->hpipm_options, sizeof(struct d_ocp_qp_ipm_arg));
    int ipm_size = d_ocp_qp_ipm_ws_memsize(&dim, &myarg);
    void *ipm_mem = malloc(ipm_size);
    struct d_ocp_qp_ipm_ws workspace;
    d_ocp_qp_ipm_ws_create(&dim, &myarg, &workspace, ipm_mem);
    d_ocp_qp_ipm_solve(&qp, &qp_sol, &myarg, &workspace);
    free(ipm_mem);
    free(ipm_arg_mem);
    free(qp_sol_mem);
    free(qp_mem);
    free(dim_mem);
}
void call(void) { casadi_hpipm_solve(&d, arg, res, iw, w); }
"""


def test_memory_is_created_once_per_thread(tmp_path):
    path = tmp_path / "x_casadi.c"
    path.write_text(SETUP)
    assert patch_hpipm_memory(path)
    out = path.read_text()
    guard, solve = out.index("if (!gt_hpipm_ready) {"), out.index("d_ocp_qp_ipm_solve(")
    # every structure thread-local, every malloc and create inside the guard, before the data and the solve; no free
    assert all(f"static __thread struct {s};" in out for s in ("d_ocp_qp_dim dim", "d_ocp_qp qp", "d_ocp_qp_sol qp_sol",
                                                               "d_ocp_qp_ipm_arg myarg", "d_ocp_qp_ipm_ws workspace"))
    assert [m.start() > guard for m in re.finditer(r"malloc\(|_create\(|memcpy\(", out)] == [True] * 11
    assert out.index("gt_hpipm_ready = 1;") < out.index("d_ocp_qp_set_all(") < solve
    assert "free(" not in out


@pytest.mark.parametrize("text, result", [(SETUP.replace("hpipm_d_ocp_qp_ipm", "daqp/api"), False),
                                          (SETUP + "void again(void) { casadi_hpipm_solve(&d, arg, res, iw, w); }\n", False),
                                          (SETUP.replace("    free(qp_mem);\n", ""), CodegenError)],
                         ids=["other solver", "two conics", "another setup"])
def test_memory_patch_only_on_the_known_setup(tmp_path, text, result):
    path = tmp_path / "x_casadi.c"
    path.write_text(text)
    if result is CodegenError:
        with pytest.raises(CodegenError, match="HPIPM setup"):
            patch_hpipm_memory(path)
    else:
        assert patch_hpipm_memory(path) is result
        assert path.read_text() == text


@pytest.mark.parametrize("header, named, expected", [
    ("hpipm_d_ocp_qp_ipm.h", True, ["libhpipm.a", "libblasfeo.a", "-Wl,--exclude-libs,ALL"]),
    ("hpipm_d_ocp_qp_ipm.h", False, ["-L", "-lhpipm", "-lblasfeo", "-Wl,-rpath,"]),
    ("fatrop/ocp/OCPCInterface.h", True, ["-L", "-lfatrop", "-lblasfeo", "-Wl,-rpath,"])],
    ids=["hpipm named", "hpipm unset", "fatrop (the wheel's)"])
def test_named_hpipm_is_linked_statically(tmp_path, monkeypatch, header, named, expected):
    for name in HPIPM_STATIC:
        (tmp_path / name).write_bytes(b"")
    monkeypatch.setenv(HPIPM_ENV, str(tmp_path) if named else "")
    src = tmp_path / "x_casadi.c"
    src.write_text(f"#include <{header}>\n")
    _, flags = solver_libraries(src)
    # the expected arguments by construction: the folder's static libraries by path, else the wheel's (their prefixes)
    names = [Path(f).name if f.endswith(".a") else f for f in flags]
    assert [next((e for e in expected if n.startswith(e)), n) for n in names] == expected
    assert all(Path(f).parent == tmp_path for f in flags if f.endswith(".a"))


@pytest.mark.parametrize("value", ["", "   "], ids=["empty", "blank"])
def test_unset_hpipm_is_the_wheels(monkeypatch, value):
    monkeypatch.setenv(HPIPM_ENV, value)
    assert hpipm_libraries() is None


def test_hpipm_folder_without_the_libraries_is_refused(tmp_path, monkeypatch):
    (tmp_path / "libhpipm.a").write_bytes(b"")
    monkeypatch.setenv(HPIPM_ENV, str(tmp_path))
    with pytest.raises(CodegenError, match="missing libblasfeo.a"):
        hpipm_libraries()
