"""The ILC experiment of Dressler (2012), section 7.3, on the simulated closed-loop L1.

One trial replays actuator references through the closed-loop plant
(:class:`~gtmodel.estimation.closed_loop.plant.TrackingPlant`); iterative learning control
(:func:`~gtmodel.estimation.ilc.iteration.run_ilc`, eqs. 7.2-7.16) corrects the references from trial
to trial. The four cases of section 7.3 differ only in the signal the error
``eps = r - z_hat`` is formed from (:data:`SIGNALS`):

``"actuator"`` (Case 1)
    The measured actuator positions ``q_m``; the correction is added to the actuator
    references. Q: a zero-phase Butterworth low-pass (the thesis: 2nd order, 10 Hz).
``"complementary"`` (Case 2A), ``"kalman"`` (Case 2B)
    The tool position estimated from ``fk(q_m)`` and the tool accelerometer by the
    complementary filter (7.17) or the stationary Kalman filter (7.19)-(7.22); the
    correction is a tool-space offset of the reference, mapped to the actuators by IK.
``"tool"`` (Case 3)
    The tool position measured by the gauge ``z_m`` (the thesis' lower bound).

The estimators act on x and y (the structural model deflects the tool in x and y); z is
taken from the kinematic position ``fk(q_m)``. Stability (7.15) and monotone convergence
(7.16) are computed per channel (actuator or tool direction) from the lifted matrices (7.9)
of the plant's impulse responses linearised at the operating point (diagonal channels;
the cross-coupling of the actuators is left out of the check and stays in the simulation).
The error measure (7.25) is taken over the fully corrected samples (time window 1) on the
actuator side (``r_q - q_m``) and on the tool side (``r_T - z``, the true tool position)
for every iteration.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Literal, Mapping

import numpy as np

from gtmodel._arrays import as_rows, positive_int
from gtmodel.errors import InputError
from gtmodel.estimation.filters.complementary import ComplementaryFilter
from gtmodel.estimation.ilc.iteration import error_measure, run_ilc
from gtmodel.estimation.ilc.lifted import ILCStability, LearningFilter, QFilter, lifted_matrix, stability
from gtmodel.estimation.filters.kalman import StationaryKalman
from gtmodel.estimation.closed_loop.plant import TrackingPlant
from gtmodel.status import Status, StatusResult

__all__ = ["SIGNALS", "REQUIREMENTS", "ILCCase", "ILCReference", "ILCCaseResult", "ILCExperiment"]

_log = logging.getLogger("gtmodel")

#: The error signals of the four cases of Dressler (2012), section 7.3.
SIGNALS = ("actuator", "complementary", "kalman", "tool")
#: What a case requires of its design before it runs: (7.15), (7.16) or nothing.
REQUIREMENTS = ("monotone", "stable", "none")
#: Names of the three tool directions.
_AXES = ("x", "y", "z")


@dataclass(frozen=True)
class ILCCase:
    """One ILC case: the learning signal and its Q filter.

    Dressler (2012), section 7.3 (Cases 1, 2A, 2B, 3).

    Parameters
    ----------
    name : str
        Label (e.g. ``"1"``, ``"2A"``).
    signal : str
        One of :data:`SIGNALS`.
    q_cutoff_hz : float or None
        Cut-off of the zero-phase Butterworth low-pass of Q [Hz]; None: no low-pass (the
        time window only).
    q_order : int, optional
        Order of the Butterworth filter (applied forward and backward).
    require : str, optional
        One of :data:`REQUIREMENTS`: what the lifted check must show before the case runs.
    """

    name: str
    signal: str
    q_cutoff_hz: float | None
    q_order: int = 2
    require: str = "monotone"

    def __post_init__(self) -> None:
        if self.signal not in SIGNALS:
            raise InputError(f"signal: expected one of {', '.join(SIGNALS)}, got {self.signal!r}")
        if self.require not in REQUIREMENTS:
            raise InputError(f"require: expected one of {', '.join(REQUIREMENTS)}, got {self.require!r}")

    @property
    def tool_side(self) -> bool:
        """True when the correction is a tool-space offset (every case but ``"actuator"``)."""
        return self.signal != "actuator"


@dataclass(frozen=True)
class ILCReference:
    """The reference of an ILC experiment, sampled at the controller rate.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Times [s], uniform at the plant's ``dt``.
    T : numpy.ndarray, shape (N, 3)
        Tool reference [m].
    q : numpy.ndarray, shape (N, 3)
        Actuator references ``ik(T)`` [m].
    window : numpy.ndarray, shape (N,)
        Time window of Q (lead-in/lead-out weighting, 1 in the fully corrected part).
    """

    t: np.ndarray
    T: np.ndarray
    q: np.ndarray
    window: np.ndarray

    @property
    def corrected(self) -> np.ndarray:
        """Mask of the fully corrected samples (window equal to 1), shape (N,)."""
        return np.asarray(self.window) >= 1.0 - 1e-12

    @property
    def n(self) -> int:
        """Number of samples ``N``."""
        return int(np.size(self.t))


@dataclass(kw_only=True)
class ILCCaseResult(StatusResult):
    """The outcome of one ILC case.

    Parameters
    ----------
    status : Status
        ``converged``, or ``error`` when the learning error diverged.
    message : str
        What happened (iterations, final relative error measure).
    case : ILCCase
        The case.
    stability : dict of str to ILCStability
        Per channel (``"q1"``..``"q3"`` or ``"x"``, ``"y"``, ``"z"``): ``rho`` (7.15) and
        ``sigma_max`` (7.16).
    actuator_error : numpy.ndarray, shape (K+1, 3)
        Error measure (7.25) of ``r_q - q_m`` per iteration and actuator [m].
    tool_error : numpy.ndarray, shape (K+1, 3)
        Error measure (7.25) of ``r_T - z`` per iteration and direction [m].
    learning_error : numpy.ndarray, shape (K+1, 3)
        Error measure of the learning signal ``eps`` per iteration and channel.
    tool_paths : dict of int to numpy.ndarray
        True tool positions ``z`` (N, 3) at iteration 0 and at the last iteration.
    correction : numpy.ndarray, shape (N, 3)
        The learned correction for the next trial, ``Q (u_K + L eps_K)`` (actuator [m] or
        tool offset [m]).
    solve_time : float
        Wall time [s].
    """

    case: ILCCase
    stability: dict[str, ILCStability] = field(default_factory=dict)
    actuator_error: np.ndarray | None = None
    tool_error: np.ndarray | None = None
    learning_error: np.ndarray | None = None
    tool_paths: dict[int, np.ndarray] = field(default_factory=dict)
    correction: np.ndarray | None = None
    solve_time: float = 0.0

    def relative(self, side: str, first: int = 5, last: int = 10) -> np.ndarray:
        """Mean error measure over iterations ``first..last`` relative to iteration 0.

        The Table 7.2 figure of Dressler (2012): 1 is no improvement.

        Parameters
        ----------
        side : str
            ``"actuator"`` or ``"tool"``.
        first, last : int, optional
            Iteration range (inclusive; clipped to the iterations run).

        Returns
        -------
        numpy.ndarray, shape (3,)
            Per actuator or tool direction.

        Raises
        ------
        InputError
            Unknown side or a case without iterations.
        """
        if side not in ("actuator", "tool"):
            raise InputError(f"side: expected 'actuator' or 'tool', got {side!r}")
        e = self.actuator_error if side == "actuator" else self.tool_error
        if e is None or len(e) < 2:
            raise InputError(f"case {self.case.name}: no iterations to compare")
        hi = min(last, len(e) - 1)
        lo = min(first, hi)
        return np.mean(e[lo:hi + 1], axis=0) / e[0]


class ILCExperiment:
    """The ILC experiment of Dressler (2012), section 7.3, on a simulated plant.

    Parameters
    ----------
    plant : TrackingPlant
        The closed-loop plant (actuators (6.11), structure (6.14), sensors).
    reference : ILCReference
        References and time window.
    learning : LearningFilter
        ``L = gamma q^delta`` (7.2).
    iterations : int
        ILC iterations after the first trial.
    estimators : mapping of str to estimator
        ``"complementary"``: a :class:`ComplementaryFilter` and ``"kalman"``: a
        :class:`StationaryKalman`, both on the two directions x and y (needed only by the
        cases that use them).
    ik : callable
        ``ik(T (N, 3)) -> q (N, 3)``: the IK of the tool-space cases.
    operating_point : array_like, shape (3,)
        Tool position the lifted matrices are linearised at [m].

    Raises
    ------
    InputError
        Mismatched reference shapes or a non-positive iteration count.
    """

    def __init__(
        self,
        plant: TrackingPlant,
        reference: ILCReference,
        learning: LearningFilter,
        iterations: int,
        estimators: Mapping[str, Any],
        ik: Callable[[np.ndarray], np.ndarray],
        operating_point: Any,
    ) -> None:
        n = reference.n
        as_rows(reference.T, "reference.T", 3)
        as_rows(reference.q, "reference.q", 3)
        if reference.T.shape != (n, 3) or reference.q.shape != (n, 3) or np.shape(reference.window) != (n,):
            raise InputError(f"reference: expected T, q of shape ({n}, 3) and window of shape ({n},)")
        self.plant = plant
        self.reference = reference
        self.learning = learning
        self.iterations = positive_int(iterations, "iterations")
        self.estimators = dict(estimators)
        self.ik = ik
        self.operating_point = np.asarray(operating_point, dtype=float).reshape(3)
        self._responses: dict[str, np.ndarray] | None = None

    # -- the lifted check ------------------------------------------------------------------
    def q_filter(self, case: ILCCase) -> QFilter:
        """The Q filter of a case (zero-phase Butterworth, then the time window).

        Parameters
        ----------
        case : ILCCase
            The case.

        Returns
        -------
        QFilter
        """
        return QFilter(case.q_cutoff_hz, dt=self.plant.dt, order=case.q_order, window=self.reference.window)

    def _impulses(self) -> dict[str, np.ndarray]:
        if self._responses is None:
            n = self.reference.n
            tool = self.plant.tool_impulse_responses(self.operating_point, n)
            self._responses = {"actuator": self.plant.actuator_impulse_responses(n), **tool}
        return self._responses

    def transfer_matrices(self, case: ILCCase) -> dict[str, np.ndarray]:
        """The lifted map ``T = F_u + F_y T_uy`` from the correction to the learning signal.

        Dressler (2012), eqs. 7.9 and 7.15, per channel (diagonal terms).

        Parameters
        ----------
        case : ILCCase
            The case.

        Returns
        -------
        dict of str to numpy.ndarray, each (N, N)
            ``"q1"``..``"q3"`` (Case 1) or ``"x"``, ``"y"``, ``"z"``.
        """
        h = self._impulses()
        n = self.reference.n
        if case.signal == "actuator":
            return {f"q{i + 1}": lifted_matrix(h["actuator"][:, i]) for i in range(3)}
        out: dict[str, np.ndarray] = {}
        if case.signal == "tool":
            pos = h["tool_position"]
            return {a: lifted_matrix(pos[:, j]) for j, a in enumerate(_AXES)}
        F_kin, F_acc = self.estimators[case.signal].lifted(n)
        for j, a in enumerate(_AXES[:2]):
            out[a] = F_kin[j] @ lifted_matrix(h["kin"][:, j]) + F_acc[j] @ lifted_matrix(h["acc"][:, j])
        out["z"] = lifted_matrix(h["kin"][:, 2])
        return out

    def check(self, case: ILCCase) -> dict[str, ILCStability]:
        """Stability (7.15) and monotone convergence (7.16) of a case, per channel.

        Parameters
        ----------
        case : ILCCase
            The case.

        Returns
        -------
        dict of str to ILCStability
        """
        n = self.reference.n
        Q = self.q_filter(case).lifted(n)
        L = self.learning.lifted(n)
        return {ch: stability(Q, L, T) for ch, T in self.transfer_matrices(case).items()}

    # -- one trial -------------------------------------------------------------------------
    def _estimate(self, case: ILCCase, resp: Any) -> np.ndarray:
        z_kin = np.asarray(resp.T_kin)
        if case.signal == "tool":
            return np.asarray(resp.z_m)
        est = np.array(z_kin)
        est[:, :2] = self.estimators[case.signal].estimate(z_kin[:, :2], np.asarray(resp.a_m)[:, :2])
        return est

    def trial(self, case: ILCCase, u: np.ndarray, trial: int = 0) -> tuple[np.ndarray, Any]:
        """Run one trial with correction ``u`` and return the learning error and the response.

        Parameters
        ----------
        case : ILCCase
            The case.
        u : numpy.ndarray, shape (N, 3)
            Correction: actuator offsets [m] (Case 1) or tool offsets [m].
        trial : int, optional
            Trial number (each trial draws its own sensor noise).

        Returns
        -------
        eps : numpy.ndarray, shape (N, 3)
            ``r - z_hat`` of the case's signal.
        response : TrackingResponse
            The simulated trial.
        """
        ref = self.reference
        q_ref = ref.q + u if not case.tool_side else self.ik(ref.T + u)
        resp = self.plant.simulate(q_ref, trial=trial)
        if case.signal == "actuator":
            return ref.q - np.asarray(resp.q_m), resp
        return ref.T - self._estimate(case, resp), resp

    def run(self, case: ILCCase) -> ILCCaseResult:
        """The lifted check, then ``iterations`` ILC iterations of a case.

        Dressler (2012), eqs. 7.2-7.16 (``u_{k+1} = Q (u_k + L eps_k)``) and 7.25.

        Parameters
        ----------
        case : ILCCase
            The case.

        Returns
        -------
        ILCCaseResult
            Status ``converged`` when the learning error did not diverge, ``error`` when it
            did (the message says at which iteration).
        """
        t0 = time.perf_counter()
        checks = self.check(case)
        ref = self.reference
        mask = ref.corrected
        responses: list[Any] = []

        def experiment(u: np.ndarray) -> np.ndarray:
            eps, resp = self.trial(case, u, len(responses))
            responses.append(resp)
            return eps

        result = run_ilc(experiment, np.zeros((ref.n, 3)), self.q_filter(case), self.learning, self.iterations, mask=mask)
        act = np.array([error_measure(ref.q - np.asarray(r.q_m), mask) for r in responses])
        tool = np.array([error_measure(ref.T - np.asarray(r.z), mask) for r in responses])
        learn = np.asarray(result.measure)
        paths = {0: np.asarray(responses[0].z), len(responses) - 1: np.asarray(responses[-1].z)}
        _log.info("ILC case %s (%s): %s after %d trials; tool error x, y %s um", case.name, case.signal, result.status,
                  len(responses), np.round(tool[-1, :2] * 1e6, 2).tolist())
        return ILCCaseResult(
            status=Status(result.status), message=f"case {case.name}: {result.message}", case=case, stability=checks,
            actuator_error=act, tool_error=tool, learning_error=learn, tool_paths=paths,
            correction=np.asarray(result.next_u if result.next_u is not None else result.u[-1]), solve_time=time.perf_counter() - t0,
        )
