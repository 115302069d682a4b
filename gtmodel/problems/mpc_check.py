"""Former path of the MPC's closed-loop check: :mod:`gtmodel.codegen.check.mpc`.

Kept so that ``from gtmodel.problems.mpc_check import build_mpc, closed_loop_check`` (and the
other names) works as before; the check lives in the codegen check harness.
"""

from __future__ import annotations

from gtmodel.codegen.check.mpc import STATUS_NAMES, MPCCheck, build_mpc, closed_loop_check, compiled_step, ipopt_agreement

__all__ = ["MPCCheck", "STATUS_NAMES", "build_mpc", "compiled_step", "closed_loop_check", "ipopt_agreement"]
