"""The CasADi-generated part of a library, post-processed: work sizes read, helpers static, parameters (void).

:class:`casadi.CodeGenerator` writes ``<prefix>_casadi.c``; these functions read the stack
work-array sizes of each Function from its generated ``*_work`` function, make CasADi's
scalar helpers ``static`` (inlined) and mark the unused parameters of its function
signatures ``(void)`` so that the file compiles with ``-Wall -Wextra -Werror``. Neither
changes a single value.
"""

from __future__ import annotations

import logging
import re

import casadi as ca

__all__: list[str] = []

log = logging.getLogger("gtmodel")


def _work_sizes(casadi_c: str, cname: str, f: ca.Function) -> tuple[int, int, int, int]:
    """Work-array sizes from the generated ``<cname>_work`` function (CasADi's values as fallback)."""
    pat = re.compile(
        rf"int {re.escape(cname)}_work\(.*?\{{\s*(?:\(void\)\w+;\s*)*"
        r"if \(sz_arg\) \*sz_arg = (\d+);\s*if \(sz_res\) \*sz_res = (\d+);\s*"
        r"if \(sz_iw\) \*sz_iw = (\d+);\s*if \(sz_w\) \*sz_w = (\d+);",
        re.S,
    )
    m = pat.search(casadi_c)
    if m:
        sizes = tuple(int(g) for g in m.groups())
    else:  # pragma: no cover - depends on the CasADi version
        log.warning("codegen: could not read %s_work from the generated code; using CasADi's sizes", cname)
        sizes = (f.sz_arg(), f.sz_res(), f.sz_iw(), f.sz_w())
    return (max(sizes[0], f.n_in()), max(sizes[1], f.n_out()), sizes[2], sizes[3])


_FUNC_DEF = re.compile(r"^((?:CASADI_SYMBOL_EXPORT |static )?[A-Za-z_][\w ]*?[\s\*]+\w+)\(([^()]*)\) \{$", re.M)


_HELPER_DEF = re.compile(r"^casadi_real (casadi_\w+)\(", re.M)


def _static_helpers(text: str) -> str:
    """Give CasADi's scalar helpers (``casadi_sq``, ``casadi_fmax``, ...) internal linkage.

    Generated with external linkage, they are called through the PLT of a shared library
    (``-fPIC`` keeps them interposable) and never inlined: one call per ``x*x`` of the
    model. ``static`` lets the compiler inline them (same operations, same values).
    """
    return _HELPER_DEF.sub(lambda m: f"static casadi_real {m.group(1)}(" if text.count(m.group(1) + "(") > 1 else m.group(0), text)


def _void_unused_parameters(text: str) -> str:
    """Mark every parameter of every function definition ``(void)``: no unused-parameter warnings."""

    def add(m: re.Match) -> str:
        params = m.group(2).strip()
        if params in ("", "void"):
            return m.group(0)
        names = [re.split(r"[\s\*]+", p.strip())[-1] for p in params.split(",")]
        return m.group(0) + " " + " ".join(f"(void){n};" for n in names)

    return _FUNC_DEF.sub(add, text)
