"""A fix of the HPIPM call CasADi 3.8.2 generates (the MPC's ``solver = "hpipm"``, :mod:`gtmodel.control.mpc_hpipm`).

CasADi's generated HPIPM call fills a stack copy of ``struct d_ocp_qp_ipm_arg`` field by
field, written for an older HPIPM: the fields of the casadi wheel's newer HPIPM headers
(``dual_gap_max``, ``lam0_min``, ``t0_min``, ``t0_init``, ``update_fact_exit``) stay unset.
Unset, ``dual_gap_max`` is stack garbage and every QP runs to the iteration limit and fails
(measured on the DC motor's MPC: residuals 1e-13, status 1 after 50 iterations; with the
library's defaults set, 3-4 iterations).
"""

from __future__ import annotations

import re
from pathlib import Path

__all__ = ["HPIPM_UNSET_OPTIONS", "patch_hpipm_options"]

#: The options left unset, with the library's defaults (``d_ocp_qp_ipm_arg_set_default``, every mode).
HPIPM_UNSET_OPTIONS = {"dual_gap_max": "1e15", "lam0_min": "1e-9", "t0_min": "1e-9", "t0_init": "2", "update_fact_exit": "1"}


def patch_hpipm_options(casadi_source: str | Path) -> bool:
    """Set the HPIPM options CasADi's generated C leaves unset (:data:`HPIPM_UNSET_OPTIONS`), in place.

    Parameters
    ----------
    casadi_source : str or pathlib.Path
        A CasADi-generated C file.

    Returns
    -------
    bool
        Whether the file calls HPIPM (and was patched).
    """
    path = Path(casadi_source)
    text = path.read_text()
    if "#include <hpipm_d_ocp_qp_ipm.h>" not in text:
        return False
    extra = "".join(f" p.hpipm_options.{k} = {v};" for k, v in HPIPM_UNSET_OPTIONS.items())
    path.write_text(re.sub(r"(p\.hpipm_options\.mode = \d+;)", lambda m: m.group(1) + extra, text))
    return True
