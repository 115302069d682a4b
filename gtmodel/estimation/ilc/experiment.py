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
of the plant's impulse responses linearised at the operating point (diagonal channels,
:meth:`ILCExperiment.check`) and, when asked, for all channels together with the
cross-coupling (:meth:`ILCExperiment.coupled_check`: in tool space the actuators' different
dynamics couple the directions; Case 1's actuators are independent).
The error measure (7.25) is taken over the fully corrected samples (time window 1) on the
actuator side (``r_q - q_m``) and on the tool side (``r_T - z``, the true tool position)
for every iteration.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Literal, Mapping

import numpy as np
import scipy.linalg
import scipy.sparse.linalg
from threadpoolctl import threadpool_limits

from gtmodel._arrays import as_rows, positive_int
from gtmodel.errors import InputError
from gtmodel.estimation.filters.complementary import ComplementaryFilter
from gtmodel.estimation.ilc.iteration import error_measure, run_ilc
from gtmodel.estimation.ilc.lifted import ILCStability, LearningFilter, QFilter, RobustQFilter, lifted_matrix, stability
from gtmodel.estimation.filters.kalman import StationaryKalman
from gtmodel.estimation.closed_loop.plant import TrackingPlant
from gtmodel.status import Status, StatusResult

__all__ = ["SIGNALS", "REQUIREMENTS", "Q_DESIGNS", "ILCCase", "ILCReference", "ILCCaseResult", "ILCExperiment"]

_log = logging.getLogger("gtmodel")

#: The error signals of the four cases of Dressler (2012), section 7.3.
SIGNALS = ("actuator", "complementary", "kalman", "tool")
#: What a case requires of its design before it runs: (7.15), (7.16) or nothing.
REQUIREMENTS = ("monotone", "stable", "none")
#: Designs of the Q filter: zero-phase Butterworth, or the robust shaping of Cases 2 and 3.
Q_DESIGNS = ("butterworth", "robust")
#: Points of the frequency grid of the robust design's loop gain (0 to Nyquist).
LOOP_GAIN_POINTS = 129
#: Arnoldi vectors of the coupled check's spectral radius (more than ARPACK's default 20: the largest
#: eigenvalues of a robust Q's iteration matrix cluster).
ARPACK_VECTORS = 64
#: Restarts of ARPACK before the coupled check falls back to the dense eigenvalues (a clustered spectrum
#: needs hundreds, about a minute of CPU at 3 N = 2500, where the dense eigenvalues take about 12 s).
ARPACK_ITERATIONS = 30
#: Largest coupled matrix (3 N) whose spectral radius is taken from the dense eigenvalues directly (about 12 s of
#: CPU at 2500; ARPACK rarely converges on these clustered spectra within :data:`ARPACK_ITERATIONS`).
DENSE_EIGENVALUES = 3000
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
    q_design : str, optional
        ``"butterworth"`` (:class:`QFilter`, Case 1 of the thesis) or ``"robust"``
        (:class:`RobustQFilter`: the Butterworth at ``q_cutoff_hz`` capped by
        ``q_margin / sigma_max(I - L T(f))``, Cases 2 and 3).
    q_margin : float, optional
        The robust design's bound of ``|Q| |I - L T|`` (in (0, 1)).
    """

    name: str
    signal: str
    q_cutoff_hz: float | None
    q_order: int = 2
    require: str = "monotone"
    q_design: str = "butterworth"
    q_margin: float = 0.9

    def __post_init__(self) -> None:
        if self.signal not in SIGNALS:
            raise InputError(f"signal: expected one of {', '.join(SIGNALS)}, got {self.signal!r}")
        if self.require not in REQUIREMENTS:
            raise InputError(f"require: expected one of {', '.join(REQUIREMENTS)}, got {self.require!r}")
        if self.q_design not in Q_DESIGNS:
            raise InputError(f"q_design: expected one of {', '.join(Q_DESIGNS)}, got {self.q_design!r}")
        if self.q_design == "robust" and self.q_cutoff_hz is None:
            raise InputError("q_cutoff_hz: the robust Q design needs a cut-off (the thesis: 30 Hz)")

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
    u : numpy.ndarray, shape (K+1, N, 3)
        The correction applied in every trial (actuator [m] or tool offset [m]).
    eps : numpy.ndarray, shape (K+1, N, 3)
        The learning error of every trial [m].
    coupled : ILCStability or None
        The coupled check of all channels together (:meth:`ILCExperiment.coupled_check`), when run.
    deflection : numpy.ndarray, shape (3,) or None
        Error measure (7.25) of the structural deflection ``d = z - fk(q)`` at iteration 0 [m].
    """

    case: ILCCase
    stability: dict[str, ILCStability] = field(default_factory=dict)
    actuator_error: np.ndarray | None = None
    tool_error: np.ndarray | None = None
    learning_error: np.ndarray | None = None
    tool_paths: dict[int, np.ndarray] = field(default_factory=dict)
    correction: np.ndarray | None = None
    solve_time: float = 0.0
    u: np.ndarray | None = None
    eps: np.ndarray | None = None
    coupled: ILCStability | None = None
    deflection: np.ndarray | None = None

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
    coupled : bool, optional
        Also run the coupled check (:meth:`coupled_check`) of every case (default False).

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
        coupled: bool = False,
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
        self.coupled = bool(coupled)
        self._responses: dict[str, np.ndarray] | None = None
        self._robust: dict[tuple[Any, ...], RobustQFilter] = {}
        self._coupled_T: dict[str, np.ndarray] = {}
        self._checks: dict[ILCCase, dict[str, ILCStability]] = {}
        self._estimator_lifted: dict[str, tuple[Any, Any]] = {}

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
        if case.q_design == "robust":
            key = (case.signal, case.q_cutoff_hz, case.q_order, case.q_margin)
            if key not in self._robust:
                f, g = self.loop_gain(case)
                self._robust[key] = RobustQFilter(case.q_cutoff_hz, f, g, case.q_margin, dt=self.plant.dt, order=case.q_order,
                                                  window=self.reference.window)
            return self._robust[key]
        return QFilter(case.q_cutoff_hz, dt=self.plant.dt, order=case.q_order, window=self.reference.window)

    def loop_gain(self, case: ILCCase, points: int = LOOP_GAIN_POINTS) -> tuple[np.ndarray, np.ndarray]:
        """``sigma_max(I - L T(f))`` of a case's coupled map, measured on the lifted operators.

        Each channel is driven by ``exp(i 2 pi f t)`` through ``I - kron(I_3, L) T``
        (:meth:`coupled_transfer_matrix`); the complex amplitude of every output channel is
        read over the middle half of the trial (least squares on the same exponential), which
        gives the 3 x 3 frequency response whose largest singular value is returned.

        Parameters
        ----------
        case : ILCCase
            The case.
        points : int, optional
            Grid points from 0 to the Nyquist frequency.

        Returns
        -------
        freqs_hz : numpy.ndarray, shape (points,)
        gain : numpy.ndarray, shape (points,)
        """
        n = self.reference.n
        T = self.coupled_transfer_matrix(case)
        L = self.learning.lifted(n)
        f = np.linspace(0.0, 0.5 / self.plant.dt, positive_int(points, "points"))
        t = np.arange(n) * self.plant.dt
        mid = slice(n // 4, n - n // 4)
        E = np.exp(2j * np.pi * np.outer(t, f))  # (n, F): the input of every frequency
        G = np.empty((f.size, 3, 3), dtype=complex)
        norm = np.sum(np.abs(E[mid]) ** 2, axis=0)
        for j in range(3):
            cols = T[:, j * n:(j + 1) * n]
            TE = cols @ E.real + 1j * (cols @ E.imag)  # (3 n, F), real products
            for i in range(3):
                LTE = L @ TE[i * n:(i + 1) * n].real + 1j * (L @ TE[i * n:(i + 1) * n].imag)
                Y = (E if i == j else 0.0) - LTE
                G[:, i, j] = np.sum(np.conj(E[mid]) * Y[mid], axis=0) / norm
        gain = np.linalg.norm(G, ord=2, axis=(1, 2))
        return f, np.maximum(gain, 1e-12)

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
        if case.signal == "actuator":
            return {f"q{i + 1}": lifted_matrix(h["actuator"][:, i]) for i in range(3)}
        out: dict[str, np.ndarray] = {}
        if case.signal == "tool":
            pos = h["tool_position"]
            return {a: lifted_matrix(pos[:, j]) for j, a in enumerate(_AXES)}
        F_kin, F_acc = self.estimator_matrices(case.signal)
        for j, a in enumerate(_AXES[:2]):
            out[a] = F_kin[j] @ lifted_matrix(h["kin"][:, j]) + F_acc[j] @ lifted_matrix(h["acc"][:, j])
        out["z"] = lifted_matrix(h["kin"][:, 2])
        return out

    def estimator_matrices(self, signal: str) -> tuple[Any, Any]:
        """The lifted matrices ``(F_kin, F_acc)`` of an estimator over the reference's length, built once.

        Parameters
        ----------
        signal : str
            ``"complementary"`` or ``"kalman"``.

        Returns
        -------
        tuple
            The estimator's ``lifted(N)`` (per direction ``(N, N)`` matrices).
        """
        if signal not in self._estimator_lifted:
            self._estimator_lifted[signal] = self.estimators[signal].lifted(self.reference.n)
        return self._estimator_lifted[signal]

    def coupled_transfer_matrix(self, case: ILCCase) -> np.ndarray:
        """The lifted map of all three channels together, cross-coupling included.

        Dressler (2012), eqs. 7.9 and 7.15 on the stacked trial ``[u_1; u_2; u_3]``: block
        ``(l, j)`` maps the correction of channel ``j`` to the learning signal of channel
        ``l``. Case 1: the actuators (6.11) are independent, so the matrix is block diagonal
        (the per-channel blocks of :meth:`transfer_matrices`). Tool-side cases: the chain
        tool reference -> IK -> actuators -> fk (``J diag(h) J^-1``, whose off-diagonal terms
        come from the different actuator dynamics) -> structure -> estimator, every block.

        Parameters
        ----------
        case : ILCCase
            The case.

        Returns
        -------
        numpy.ndarray, shape (3 N, 3 N)
        """
        if case.signal in self._coupled_T:
            return self._coupled_T[case.signal]
        n = self.reference.n
        T = np.zeros((3 * n, 3 * n))
        self._coupled_T[case.signal] = T
        if case.signal == "actuator":
            for i, M in enumerate(self.transfer_matrices(case).values()):
                T[i * n:(i + 1) * n, i * n:(i + 1) * n] = M
            return T
        h = self._impulses()
        if case.signal != "tool":
            F_kin, F_acc = self.estimator_matrices(case.signal)
        for j in range(3):
            for l in range(3):
                if case.signal == "tool":
                    block = lifted_matrix(h["tool_position_full"][:, l, j])
                elif l < 2:
                    block = F_kin[l] @ lifted_matrix(h["kin_full"][:, l, j]) + F_acc[l] @ lifted_matrix(h["acc_full"][:, l, j])
                else:
                    block = lifted_matrix(h["kin_full"][:, l, j])
                T[l * n:(l + 1) * n, j * n:(j + 1) * n] = block
        return T

    def coupled_matrix(self, case: ILCCase) -> np.ndarray:
        """The coupled iteration matrix ``kron(I_3, Q) (I - kron(I_3, L) T)`` of all channels.

        Dressler (2012), eqs. 7.15-7.16 on the stacked trial; built block by block,
        ``A_lj = Q (delta_lj I - L T_lj)`` with ``T`` of :meth:`coupled_transfer_matrix`
        (``L`` is a shift: ``L T_lj`` is ``gamma`` times the rows of ``T_lj`` moved up by ``delta``).

        Parameters
        ----------
        case : ILCCase
            The case.

        Returns
        -------
        numpy.ndarray, shape (3 N, 3 N)
        """
        n = self.reference.n
        Q = self.q_filter(case).lifted(n)
        T = self.coupled_transfer_matrix(case)
        A = np.empty((3 * n, 3 * n))
        with threadpool_limits(limits=1, user_api="blas"):
            for j in range(3):
                cols = slice(j * n, (j + 1) * n)
                for l in range(3):
                    rows = slice(l * n, (l + 1) * n)
                    B = -self.learning.apply(T[rows, cols])  # -L T_lj, (n, n)
                    if l == j:
                        B[np.diag_indices(n)] += 1.0
                    A[rows, cols] = Q @ B
        return A

    def coupled_check(self, case: ILCCase) -> ILCStability:
        """Stability (7.15) and monotone convergence (7.16) of all channels together.

        Dressler (2012), eqs. 7.15-7.16 with ``Q`` and ``L`` acting on every channel
        (``kron(I_3, Q)``) and the coupled map of :meth:`coupled_transfer_matrix`.
        Case 1 (``"actuator"``): the actuators are independent, the iteration matrix is block
        diagonal, and its figures are the largest of the per-channel ones (:meth:`check`),
        exactly. The tool-side cases: the dense ``(3 N, 3 N)`` matrix of :meth:`coupled_matrix`;
        ``sigma_max`` is the square root of the largest eigenvalue of ``A A^T``
        (:func:`scipy.linalg.eigh`, that eigenvalue only) and ``rho`` from the dense eigenvalues
        (:func:`scipy.linalg.eigvals`) up to ``3 N =`` :data:`DENSE_EIGENVALUES`, above it from ARPACK
        (:func:`scipy.sparse.linalg.eigs`, tolerance 1e-8, at most :data:`ARPACK_ITERATIONS`
        restarts) before the dense eigenvalues; one BLAS thread (the
        decompositions cost 10-20x more CPU with threads on a busy machine). Bounded in time:
        about 20 s of CPU per case at ``N = 834`` (two rounds of the thesis' square).

        Parameters
        ----------
        case : ILCCase
            The case.

        Returns
        -------
        ILCStability
        """
        if case.signal == "actuator":
            per = self.check(case).values()
            rho, sigma = max(c.rho for c in per), max(c.sigma_max for c in per)
            return ILCStability(rho=rho, sigma_max=sigma, stable=rho < 1.0, monotone=sigma < 1.0)
        A = self.coupled_matrix(case)
        m = A.shape[0]
        with threadpool_limits(limits=1, user_api="blas"):
            gram = A @ A.T
            sigma = math.sqrt(max(float(scipy.linalg.eigh(gram, eigvals_only=True, subset_by_index=[m - 1, m - 1])[0]), 0.0))
            rho = None
            if m > DENSE_EIGENVALUES:
                try:
                    rho = float(np.max(np.abs(scipy.sparse.linalg.eigs(A, k=1, which="LM", ncv=ARPACK_VECTORS, tol=1e-8,
                                                                       maxiter=ARPACK_ITERATIONS, return_eigenvectors=False))))
                except scipy.sparse.linalg.ArpackNoConvergence:  # a clustered spectrum: the dense decomposition
                    _log.info("ILC coupled check of case %s: ARPACK did not converge; dense eigenvalues of the (%d, %d) matrix", case.name, m, m)
            if rho is None:
                rho = float(np.max(np.abs(scipy.linalg.eigvals(A))))
        _log.debug("ILC coupled check of case %s: rho = %.6g, sigma_max = %.6g (3 N = %d)", case.name, rho, sigma, m)
        return ILCStability(rho=rho, sigma_max=sigma, stable=rho < 1.0, monotone=sigma < 1.0)

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
        if case in self._checks:  # the problem's load checks every case; its run reuses the figures
            return self._checks[case]
        n = self.reference.n
        Q = self.q_filter(case).lifted(n)
        L = self.learning.lifted(n)
        with threadpool_limits(limits=1, user_api="blas"):  # (N, N) decompositions: threads cost 10-20x CPU on a busy machine
            self._checks[case] = {ch: stability(Q, L, T) for ch, T in self.transfer_matrices(case).items()}
        return self._checks[case]

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
            u=np.asarray(result.u), eps=np.asarray(result.eps), deflection=np.asarray(error_measure(np.asarray(responses[0].d), mask)), coupled=self.coupled_check(case) if self.coupled else None,
        )
