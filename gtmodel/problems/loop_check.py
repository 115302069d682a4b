"""Former path of the closed-loop check of a loop controller's generated C: :mod:`gtmodel.codegen.check.closed_loop`.

Kept so that ``from gtmodel.problems.loop_check import closed_loop_check`` (and the other names)
works as before; the check lives in the codegen check harness.
"""

from __future__ import annotations

from gtmodel.codegen.check.closed_loop import (AUTHORITY_WARNING, STATUS_NAMES, LoopCheck, closed_loop_check, compiled_step,
                                               feedforward_law, heap_stats, plant_bounds, reference_at_bounds)
from gtmodel.codegen.loop_step import build_step

__all__ = ["AUTHORITY_WARNING", "STATUS_NAMES", "LoopCheck", "plant_bounds", "reference_at_bounds", "build_step", "compiled_step",
           "heap_stats", "closed_loop_check", "feedforward_law"]
