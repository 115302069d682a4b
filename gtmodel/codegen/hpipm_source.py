"""A fix of the HPIPM call CasADi 3.8.2 generates (the MPC's ``solver = "hpipm"``, :mod:`gtmodel.control.mpc_hpipm`).

CasADi's generated HPIPM call fills a stack copy of ``struct d_ocp_qp_ipm_arg`` field by
field, written for an older HPIPM: the fields of the casadi wheel's newer HPIPM headers
(``dual_gap_max``, ``lam0_min``, ``t0_min``, ``t0_init``, ``update_fact_exit``) stay unset.
Unset, ``dual_gap_max`` is stack garbage and every QP runs to the iteration limit and fails
(measured on the DC motor's MPC: residuals 1e-13, status 1 after 50 iterations; with the
library's defaults set, 3-4 iterations).

CasADi's call also sets up HPIPM's memory (dimensions, QP, solution, options, IPM workspace; five
``malloc``) in every QP: :func:`patch_hpipm_memory` keeps them in thread-local storage, created at a
thread's first QP, as acados creates its QP solver's memory once.

And the libraries the call links (:func:`hpipm_libraries`): the casadi wheel's ``libblasfeo`` is
built for BLASFEO's ``GENERIC`` target (plain C kernels; ``blasfeo_processor_library_string`` is
empty), acados' for ``X64_INTEL_HASWELL`` (AVX2 + FMA). HPIPM's interior point is 80 % of the L1
MPC step's instructions, its Riccati factorisation 60 % (callgrind, 2026-11-25), so the kernels
decide the step's time: the same generated L1 step linked with a Haswell BLASFEO took 0.63x the
CPU time of the wheel's (96 against 153 us median, the same inputs to 1e-13). With
:data:`HPIPM_ENV` naming a folder with ``libhpipm.a`` and ``libblasfeo.a`` (built by
``benchmarks/hpipm_build.sh``: HPIPM at the commit whose headers are the wheel's, BLASFEO for the
machine's target), the step links those statically, their symbols hidden (``--exclude-libs``): a
process that has loaded the wheel's ``libhpipm`` (CasADi's ``hpipm`` plugin, as the Python
reference does) has bound that HPIPM to the wheel's generic BLASFEO, and a step linking the
shared libraries would share that binding. The algorithm, its options and the QP are unchanged.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from gtmodel.errors import CodegenError

__all__ = ["HPIPM_ENV", "HPIPM_STATIC", "HPIPM_UNSET_OPTIONS", "hpipm_libraries", "patch_hpipm_memory", "patch_hpipm_options"]

#: The environment variable naming a folder with static HPIPM and BLASFEO libraries (position-independent)
#: that the generated HPIPM call links instead of the casadi wheel's shared ones; unset or empty: the wheel's.
HPIPM_ENV = "GTMODEL_HPIPM"
#: The static libraries in that folder, in link order.
HPIPM_STATIC = ("libhpipm.a", "libblasfeo.a")

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


def hpipm_libraries() -> tuple[Path, ...] | None:
    """The static HPIPM and BLASFEO libraries of the folder :data:`HPIPM_ENV` names, or None (the wheel's are linked).

    Returns
    -------
    tuple of pathlib.Path or None
        :data:`HPIPM_STATIC` in that folder, resolved, in link order.

    Raises
    ------
    CodegenError
        The variable names a folder without them.
    """
    name = os.environ.get(HPIPM_ENV, "").strip()
    if not name:
        return None
    folder = Path(name).expanduser().resolve()
    missing = [f for f in HPIPM_STATIC if not (folder / f).is_file()]
    if missing:
        raise CodegenError(f"{HPIPM_ENV}={name!r}: expected a folder with {', '.join(HPIPM_STATIC)} "
                           f"(benchmarks/hpipm_build.sh), missing {', '.join(missing)}")
    return tuple(folder / f for f in HPIPM_STATIC)


#: CasADi's setup of HPIPM's memory in ``casadi_hpipm_solve`` (3.8.2): the dimensions and the QP before
#: the QP's data are filled, the solution, the options and the workspace after, freed at the end.
_CREATE_QP = re.compile(r"\n[ \t]*int dim_size = d_ocp_qp_dim_memsize\(p->N\);.*?d_ocp_qp_create\(&dim, &qp, qp_mem\);", re.S)
_CREATE_REST = re.compile(r"\n[ \t]*int qp_sol_size = d_ocp_qp_sol_memsize\(&dim\);.*?"
                          r"d_ocp_qp_ipm_ws_create\(&dim, &myarg, &workspace, ipm_mem\);", re.S)
_FREES = re.compile(r"\n[ \t]*free\((?:ipm_mem|ipm_arg_mem|qp_sol_mem|qp_mem|dim_mem)\);")
_STRUCTS = re.compile(r"\n[ \t]*(struct d_ocp_qp(?:_dim|_sol|_ipm_arg|_ipm_ws)? \w+;)")


def patch_hpipm_memory(casadi_source: str | Path) -> bool:
    """Create HPIPM's memory once per thread instead of in every QP of CasADi's generated call, in place.

    The five structures (``d_ocp_qp_dim``, ``d_ocp_qp``, ``d_ocp_qp_sol``, ``d_ocp_qp_ipm_arg``,
    ``d_ocp_qp_ipm_ws``) become ``static __thread``, created (their ``malloc`` go to the step's heap
    arena) at the thread's first QP and never freed; each QP still writes all of the QP's data
    (``d_ocp_qp_set_all``) and the solution's start, and HPIPM's solve starts from them (``warm_start
    = 0``), so every QP computes what it did. Only for a file with one HPIPM call site (one conic:
    the dimensions are those of every QP).

    Parameters
    ----------
    casadi_source : str or pathlib.Path
        A CasADi-generated C file.

    Returns
    -------
    bool
        Whether the file calls HPIPM from one site (and was patched).

    Raises
    ------
    CodegenError
        The file calls HPIPM but its setup is not CasADi 3.8.2's.
    """
    path = Path(casadi_source)
    text = path.read_text()
    if "#include <hpipm_d_ocp_qp_ipm.h>" not in text or text.count("casadi_hpipm_solve(&d,") != 1:
        return False
    first, rest = _CREATE_QP.search(text), _CREATE_REST.search(text)
    if first is None or rest is None or len(_FREES.findall(text)) != 5:
        raise CodegenError(f"{path.name}: CasADi's HPIPM setup is not the one patch_hpipm_memory knows (casadi 3.8.2)")
    setup = first.group(0) + rest.group(0)
    structs = _STRUCTS.findall(setup)
    if len(structs) != 5:
        raise CodegenError(f"{path.name}: expected HPIPM's five structures in its setup, found {len(structs)}")
    body = _STRUCTS.sub("", setup).replace("\n", "\n  ")
    once = ("\n    " + " ".join(f"static __thread {s}" for s in structs) + "\n    static __thread int gt_hpipm_ready = 0;"
            "\n    if (!gt_hpipm_ready) {  /* gtmodel: HPIPM's memory created once per thread (hpipm_source.py) */"
            + body + "\n      gt_hpipm_ready = 1;\n    }")
    text = text[:rest.start()] + text[rest.end():]
    text = text[:first.start()] + once + text[first.end():]
    path.write_text(_FREES.sub("", text))
    return True
