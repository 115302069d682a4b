"""The controllers behind a robot's position interface (KUKA RSI, ABB EGM): corrections and streamed references.

Industrial robot controllers take position references and corrections at their
interpolation cycle (4 ms), not torques. The two controllers the theses ran through such
an interface are here, each ONE CasADi Function of the loop-step interface shared by the
loop controllers (:mod:`gtmodel.codegen.loop_step`):
``control(t, x, u_last) -> (u, ok)``, generated as C by
:func:`gtmodel.codegen.loop_step.position_step` and run behind the interface by the
robot runtime (:mod:`gtmodel.codegen.robot_runtime`, :mod:`gtmodel.control.runtime`).

- :class:`PoseCorrection`: Cvitanic (2021), section 5, eq. (33): the tracker measures the
  tool centre point ``p_k``; per Cartesian direction ``i`` the P controller adds
  ``K_i e_k`` with ``e_k = r_k - p_k`` to the total correction (RSI's relative correction:
  the offsets accumulate, ``u_k = u_{k-1} + K e_k``), saturated at the correction limits.
  The programmed pose ``r_k`` comes from the robot's packet (``RSol``: the set-point pose;
  when the robot reports it with the corrections already in, they are taken out:
  ``r_k = RSol_k - u_{k-1}``), the tracker's position from the sensor stream (metres, the
  robot's base frame after registration), scaled to the robot's unit (mm). ``u`` is the
  TOTAL correction; the runtime sends its per-cycle increment to a robot in relative mode.
- :class:`ReferenceStreaming`: a planned trajectory streamed at the loop period with the
  learned ILC correction added, Dressler (2012), eq. 7.2 and section 7.3 (the 4 ms loop
  adds the correction of the current cycle to the reference): ``u = r_k + c_k`` with
  ``k = floor(t / dt)`` held in ``0 .. N-1`` (the start before it, the end after it), saturated
  at the position bounds. The measurement ``x`` (the robot's feedback) is not used by the
  law; the runtime logs it, and the next ILC iteration learns from it
  (:func:`gtmodel.estimation.ilc.next_correction`).

Both are stateless beyond ``u_last`` (no inner memory ``w``); their plausible ranges
(:meth:`limits`) let the generated step reject an absurd measurement and reset an absurd
memory as every loop step does.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._arrays import as_per_axis, as_signal, finite_float
from gtmodel.control.reference import period_index
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError

__all__ = ["PoseCorrection", "ReferenceStreaming", "AXES", "PLAUSIBLE_SPAN_MM"]

#: The Cartesian directions of a pose correction, in order.
AXES = ("x", "y", "z")
#: Plausible positions of a programmed pose and a tracker reading [mm]: within this of the origin (a 10 m cube).
PLAUSIBLE_SPAN_MM = 1.0e4


def _period(dt: Any) -> float:
    value = finite_float(dt, "dt", "s", positive=True)
    if value > 1.0:
        raise InputError(f"dt: expected a loop period in (0, 1] s, got {dt!r}")
    return value


@dataclass(frozen=True)
class PoseCorrection:
    """Cvitanic's P correction of the tool centre point from a tracker, Cvitanic (2021), section 5, eq. (33).

    Parameters
    ----------
    gain : array_like
        ``(3,)`` the gain ``K`` per Cartesian direction x, y, z [1 per cycle]; 0 leaves a
        direction uncorrected. Table 14's largest stable gains are 0.1-0.2 (x) and 0.01-0.05
        (y) at 13 cycles of delay; a gain in ``[0, 1]``.
    limit : array_like
        ``(3,)`` the largest total correction per direction [mm] (the step saturates at
        ``+-limit``; the runtime enforces its own limits after the step as well).
    dt : float, optional
        Loop period [s] (default 4 ms).
    sensor_scale : float, optional
        The robot's length unit per sensor unit (default 1000: a tracker in metres, RSI in mm).
    reference_includes_correction : bool, optional
        The programmed pose the robot reports (``RSol``) already holds the corrections sent so
        far (then ``r = RSol - u_last``); default False.
    x_names : list of str, optional
        The measurement's fields (default ``RSol.X``, ``RSol.Y``, ``RSol.Z``, ``sensor.0`` ...
        ``sensor.2``: the programmed position, then the tracker's).
    u_names : list of str, optional
        The reply's fields (default ``RKorr.X``, ``RKorr.Y``, ``RKorr.Z``).

    Raises
    ------
    InputError
        A gain outside ``[0, 1]``, a limit that is not positive and finite, a bad period or scale.
    """

    gain: Any
    limit: Any
    dt: float = LOOP_PERIOD_S
    sensor_scale: float = 1000.0
    reference_includes_correction: bool = False
    x_names: list[str] = field(default_factory=lambda: [f"RSol.{a.upper()}" for a in AXES] + [f"sensor.{i}" for i in range(3)])
    u_names: list[str] = field(default_factory=lambda: [f"RKorr.{a.upper()}" for a in AXES])

    def __post_init__(self) -> None:
        g = as_per_axis(self.gain, 3, "gain")
        if np.any(g < 0) or np.any(g > 1):
            raise InputError(f"gain: expected gains in [0, 1] per cycle (Cvitanic (2021), Table 14: about 0.01-0.2), got {g.tolist()}")
        object.__setattr__(self, "gain", g)
        object.__setattr__(self, "limit", as_per_axis(self.limit, 3, "limit", positive=True))
        object.__setattr__(self, "dt", _period(self.dt))
        object.__setattr__(self, "sensor_scale", finite_float(self.sensor_scale, "sensor_scale", positive=True))

    @property
    def nx(self) -> int:
        """Length of the measurement: the programmed position (3) and the tracker's (3)."""
        return 6

    @property
    def nu(self) -> int:
        """Length of the correction (3)."""
        return 3

    @property
    def u_lb(self) -> np.ndarray:
        """``(3,)`` lowest correction [mm]."""
        return -self.limit

    @property
    def u_ub(self) -> np.ndarray:
        """``(3,)`` highest correction [mm]."""
        return self.limit.copy()

    @property
    def u_initial(self) -> np.ndarray:
        """``(3,)`` the correction before the first cycle: none."""
        return np.zeros(3)

    @property
    def description(self) -> str:
        """Comment lines for the generated header: the law and its source."""
        r = "RSol - u_last (RSol holds the corrections sent)" if self.reference_includes_correction else "RSol (the programmed pose)"
        return (f"Pose correction (Cvitanic (2021), sec. 5, eq. (33)): u = sat(u_last + K (r - {self.sensor_scale:g} p)),\n"
                f"r = {r}, p the tracker's TCP position (sensor.0..2), K = {self.gain.tolist()} per cycle,\n"
                f"|u| <= {self.limit.tolist()} mm; u is the total correction (the runtime sends increments in relative mode).")

    def function(self) -> ca.Function:
        """The step: ``control(t, x, u_last) -> (u, ok)``.

        Returns
        -------
        casadi.Function
            ``t`` (1,1) [s] (unused: the law is time-invariant), ``x`` (6,1): programmed
            position [mm] then tracker position [sensor unit], ``u_last`` (3,1) the last total
            correction [mm]; ``u`` (3,1) the new total correction, saturated; ``ok`` 1 when
            the error and the last correction are finite.
        """
        t, x, u_last = ca.MX.sym("t"), ca.MX.sym("x", 6), ca.MX.sym("u_last", 3)
        r = x[0:3] - (u_last if self.reference_includes_correction else 0)
        e = r - self.sensor_scale * x[3:6]
        u = ca.fmin(ca.fmax(u_last + ca.DM(self.gain) * e, ca.DM(self.u_lb)), ca.DM(self.u_ub))
        s = ca.sum1(e) + ca.sum1(u_last)
        ok = ca.if_else(ca.fabs(s) < np.inf, 1, 0)  # 0 for NaN or inf (fmin/fmax would hide a NaN error)
        return ca.Function("control", [t, x, u_last], [u, ok], ["t", "x", "u_last"], ["u", "ok"])

    def limits(self) -> dict[str, np.ndarray]:
        """The plausible measurement and memory the generated step checks.

        Returns
        -------
        dict
            ``"x"`` ``(2, 6)``: positions within :data:`PLAUSIBLE_SPAN_MM` of the origin (the
            tracker's in its own unit); ``"u_last"`` ``(2, 3)``: the correction limits.
        """
        span = np.r_[np.full(3, PLAUSIBLE_SPAN_MM), np.full(3, PLAUSIBLE_SPAN_MM / self.sensor_scale)]
        return {"x": np.vstack([-span, span]), "u_last": np.vstack([self.u_lb, self.u_ub])}

    def samples(self, n: int = 8, seed: int = 0) -> np.ndarray:
        """``(n, 6)`` measurements about which a code check samples: a TCP within 50 mm of the pose it should be at.

        Parameters
        ----------
        n : int, optional
            Number of rows.
        seed : int, optional
            Random seed.

        Returns
        -------
        numpy.ndarray
        """
        rng = np.random.default_rng(seed)
        r = rng.uniform(-1500.0, 1500.0, (n, 3))
        p = (r + rng.uniform(-50.0, 50.0, (n, 3))) / self.sensor_scale
        return np.hstack([r, p])


@dataclass(frozen=True)
class ReferenceStreaming:
    """A planned trajectory streamed at the loop period, with the learned ILC correction added (Dressler (2012), eq. 7.2).

    Parameters
    ----------
    reference : array_like
        ``(N, n)`` the planned positions, one row per period from ``t = 0`` (the robot's
        units: mm for linear axes, degrees for revolute ones).
    correction : array_like, optional
        ``(N, n)`` the learned correction added to the reference (default zeros: the first
        iteration); the time window is already inside it.
    lower, upper : array_like, optional
        ``(n,)`` the position bounds the step saturates at (default: the reference's range
        widened by :attr:`margin` on each side).
    dt : float, optional
        Loop period [s] (default 4 ms).
    names : list of str, optional
        The reply fields (default ``planned.joints.0`` ...).
    feedback_names : list of str, optional
        The measurement's fields (default ``feedback.joints.0`` ...).
    margin : float, optional
        The default bounds' widening [robot units] (default 10).

    Raises
    ------
    InputError
        Tables that are not finite, of other shapes, or leave the bounds; a bad period.
    """

    reference: Any
    correction: Any = None
    lower: Any = None
    upper: Any = None
    dt: float = LOOP_PERIOD_S
    names: list[str] | None = None
    feedback_names: list[str] | None = None
    margin: float = 10.0

    def __post_init__(self) -> None:
        ref = as_signal(self.reference, "reference", vector=True)
        n, d = ref.shape
        corr = np.zeros_like(ref) if self.correction is None else as_signal(self.correction, "correction", vector=True)
        if corr.shape != ref.shape:
            raise InputError(f"correction: expected the reference's shape {ref.shape}, got {corr.shape}")
        lo = ref.min(axis=0) - self.margin if self.lower is None else as_per_axis(self.lower, d, "lower")
        hi = ref.max(axis=0) + self.margin if self.upper is None else as_per_axis(self.upper, d, "upper")
        if np.any(lo > hi):
            raise InputError(f"lower, upper: expected lower <= upper, got {lo.tolist()} and {hi.tolist()}")
        if np.any(ref < lo) or np.any(ref > hi):
            raise InputError("reference: expected every row within the bounds lower, upper")
        object.__setattr__(self, "reference", ref)
        object.__setattr__(self, "correction", corr)
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)
        object.__setattr__(self, "dt", _period(self.dt))
        object.__setattr__(self, "names", list(self.names or [f"planned.joints.{i}" for i in range(d)]))
        object.__setattr__(self, "feedback_names", list(self.feedback_names or [f"feedback.joints.{i}" for i in range(d)]))
        if len(self.names) != d or len(self.feedback_names) != d:
            raise InputError(f"names, feedback_names: expected {d} names each")

    @property
    def length(self) -> int:
        """Rows of the reference (``N``)."""
        return int(self.reference.shape[0])

    @property
    def nx(self) -> int:
        """Length of the measurement (the axes' feedback)."""
        return int(self.reference.shape[1])

    @property
    def nu(self) -> int:
        """Length of the streamed position."""
        return int(self.reference.shape[1])

    @property
    def x_names(self) -> list[str]:
        """The measurement's field names."""
        return list(self.feedback_names)

    @property
    def u_names(self) -> list[str]:
        """The reply's field names."""
        return list(self.names)

    @property
    def u_lb(self) -> np.ndarray:
        """``(n,)`` lowest streamed position."""
        return self.lower.copy()

    @property
    def u_ub(self) -> np.ndarray:
        """``(n,)`` highest streamed position."""
        return self.upper.copy()

    @property
    def streamed(self) -> np.ndarray:
        """``(N, n)`` what is sent per cycle: reference plus correction, saturated at the bounds."""
        return np.clip(self.reference + self.correction, self.lower, self.upper)

    @property
    def u_initial(self) -> np.ndarray:
        """``(n,)`` the position before the first cycle: the first streamed row."""
        return self.streamed[0].copy()

    @property
    def description(self) -> str:
        """Comment lines for the generated header: the law and its source."""
        learned = "a learned correction c" if np.any(self.correction) else "no correction yet (c = 0)"
        return (f"Reference streaming with ILC (Dressler (2012), eq. 7.2, sec. 7.3): u = sat(r_k + c_k),\n"
                f"k = floor(t / {self.dt!r}) held in 0..{self.length - 1}; {self.length} rows, {learned}.")

    def function(self) -> ca.Function:
        """The step: ``control(t, x, u_last) -> (u, ok)``.

        Returns
        -------
        casadi.Function
            ``t`` (1,1) [s] since the first cycle, ``x`` (n,1) the feedback (not used by the
            law), ``u_last`` (n,1); ``u`` (n,1) the streamed position of row
            ``k = floor(t / dt)`` (:func:`~gtmodel.control.reference.period_index`), ``ok``
            0 for a NaN ``t``.
        """
        d = self.nu
        t, x, u_last = ca.MX.sym("t"), ca.MX.sym("x", d), ca.MX.sym("u_last", d)
        k = period_index(t, 0.0, self.dt, self.length - 1)
        values = ca.MX(ca.DM(self.streamed.reshape(-1)))
        u = ca.vertcat(*[values[d * k + j] for j in range(d)])
        ok = ca.if_else(ca.fabs(t) < np.inf, 1, 0)  # 0 for a NaN t (CasADi folds t == t to 1)
        return ca.Function("control", [t, x, u_last], [u, ok], ["t", "x", "u_last"], ["u", "ok"])

    def limits(self) -> dict[str, np.ndarray]:
        """The plausible measurement and memory the generated step checks.

        Returns
        -------
        dict
            ``"x"`` ``(2, n)``: the bounds widened by ten times their span (feedback far
            outside them is absurd); ``"u_last"`` ``(2, n)``: the bounds.
        """
        span = 10.0 * np.maximum(self.upper - self.lower, 1.0)
        return {"x": np.vstack([self.lower - span, self.upper + span]), "u_last": np.vstack([self.lower, self.upper])}

    def samples(self, n: int = 8, seed: int = 0) -> np.ndarray:
        """``(n, nx)`` measurements about which a code check samples: rows of the reference.

        Parameters
        ----------
        n : int, optional
            Number of rows.
        seed : int, optional
            Random seed.

        Returns
        -------
        numpy.ndarray
        """
        rng = np.random.default_rng(seed)
        return self.reference[rng.integers(0, self.length, n)]
