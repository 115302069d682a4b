"""The ranges and size limits of loop-controller files (``[mpc]``, ``[controller]``, ``[reference]``, ``[check]``).

Every number of a loop file is finite and in a declared range, checked on load before anything
is solved, built or written; the size of the reference (loop periods, numbers in the generated
C's tables) is estimated before it is sampled (:func:`loop_samples`). The readers,
:mod:`gtmodel.problems.loop_file` and the controller files, declare their fields with these
types; refusals name the file and the field.
"""

from __future__ import annotations

import math

from gtmodel.problems.base import ProblemFile
from gtmodel.problems.schema import MAX_FORCE_N, number

__all__ = ["MIN_PERIOD_S", "MAX_PERIOD_S", "MAX_WEIGHT", "MAX_MAGNITUDE", "MAX_LOOP_SAMPLES", "MAX_TABLE_NUMBERS",
           "Period", "Weights", "Bounds", "StateBounds", "loop_samples"]

#: Shortest loop period of a loop-controller file [s] (100 kHz; a shorter one is a unit slip:
#: ``period = 1e-12`` asked numpy for 2.18 TiB of reference samples).
MIN_PERIOD_S = 1e-5
#: Longest loop period [s].
MAX_PERIOD_S = 1.0
#: Largest weight of a weight table (``state_weights``, ``input_weights``, ``terminal_weights``,
#: ``integral_weights``): the shipped files' largest is 1e8 (1 mm of TCP error against 100 N);
#: 1e12 leaves four decades for other units, and keeps the QP's and the Riccati recursion's
#: products of weights and squared scales (``Q`` times ``B^T P B``) far from overflow.
MAX_WEIGHT = 1e12
#: Largest magnitude of a number in the units of the model's states and inputs in a loop file
#: (input bounds, state bounds, noise, disturbance): :data:`~gtmodel.problems.schema.MAX_FORCE_N`.
MAX_MAGNITUDE = MAX_FORCE_N
#: Most loop periods of a loop-controller file's reference (the motion sampled at the period and
#: the settling hold): each is a row of the reference the controller stores, a sample of the
#: generated C's tables and a period of the closed-loop check (400 s at the 4 ms loop, 1 s at
#: :data:`MIN_PERIOD_S`; the shipped files have 132 to 352).
MAX_LOOP_SAMPLES = 100_000
#: Most numbers in the tables the generated C holds (samples times the numbers of each: ``x*``,
#: ``u*``, a tracking controller's gains): about 25 bytes of C source each, 50 MB at the limit.
MAX_TABLE_NUMBERS = 2_000_000

#: A loop period [s] in ``MIN_PERIOD_S .. MAX_PERIOD_S``.
Period = number(ge=MIN_PERIOD_S, le=MAX_PERIOD_S, unit="s", description="loop period")
#: A weight table by variable name: finite weights in ``0 .. MAX_WEIGHT``.
Weights = dict[str, number(ge=0, le=MAX_WEIGHT, description="weight")]
#: Input bounds, one finite number of magnitude <= ``MAX_MAGNITUDE`` per input (None: the default).
Bounds = list[number(ge=-MAX_MAGNITUDE, le=MAX_MAGNITUDE)] | None
#: State bounds by state name, finite numbers of magnitude <= ``MAX_MAGNITUDE``.
StateBounds = dict[str, number(ge=-MAX_MAGNITUDE, le=MAX_MAGNITUDE)]


def loop_samples(file: ProblemFile, field: str, duration: float, settle_time: float, dt: float, per_sample: int) -> int:
    """The loop periods of a reference, refused above :data:`MAX_LOOP_SAMPLES` and :data:`MAX_TABLE_NUMBERS`.

    The estimate before anything is sampled, built or run: ``floor(duration / dt) + 1 +
    round(settle_time / dt)`` periods (the reference the controller stores, the rows of the
    generated C's tables and the periods of the closed-loop check), each with ``per_sample``
    numbers in the generated C.

    Parameters
    ----------
    file : ProblemFile
        The file (for its errors).
    field : str
        The period's field, e.g. ``"mpc.period"``.
    duration : float
        The reference motion's length [s] (0: the settling hold alone, before it is known).
    settle_time : float
        ``reference.settle_time`` [s].
    dt : float
        Loop period [s].
    per_sample : int
        Numbers of each sample in the generated C (``nx + nu``; a tracking controller's gains
        add ``nu (nx + n_integral)``).

    Returns
    -------
    int
        The number of loop periods.

    Raises
    ------
    ProblemError
        Naming the file and ``field``: more periods or table numbers than the limits (the
        estimate, the limit and the remedy in the message); a duration that is not finite.
    """
    if not (math.isfinite(duration) and duration >= 0):
        raise file.fail("reference", "a reference motion of finite length", duration)
    samples = int(math.floor(duration / dt + 1e-6)) + 1 + int(round(settle_time / dt))
    settle = f" and reference.settle_time = {settle_time:g} s" if settle_time else ""
    what = f"{duration:g} s of motion{settle} at {dt:g} s: {samples} periods"
    remedy = "a longer period, a shorter motion" + (" or settle_time" if settle_time else "")
    if samples > MAX_LOOP_SAMPLES:
        raise file.fail(field, f"a period giving at most {MAX_LOOP_SAMPLES} loop periods over the reference ({what}; each a sample "
                               f"the controller stores and the generated C holds, and a period of the closed-loop check); {remedy}", dt)
    if samples * per_sample > MAX_TABLE_NUMBERS:
        raise file.fail(field, f"a period giving at most {MAX_TABLE_NUMBERS} numbers in the generated C's tables ({what} of "
                               f"{per_sample} numbers each: {samples * per_sample}); {remedy}", dt)
    return samples
