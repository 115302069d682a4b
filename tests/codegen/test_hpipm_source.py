"""The fix of CasADi's generated HPIPM call (gtmodel.codegen.hpipm_source).

Reference: the text expected by construction; that the values are HPIPM's own defaults and that
the generated step needs them is checked through the step itself in tests/control/test_mpc_hpipm.py
(slow: a compile; 3-4 QP iterations with them, 50 and a failure without).
"""

from __future__ import annotations

import pytest

from gtmodel.codegen.hpipm_source import HPIPM_UNSET_OPTIONS, patch_hpipm_options

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

