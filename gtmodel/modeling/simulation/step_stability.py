"""Linear stability of a fixed explicit step along a trajectory: whether the loop's step can follow the model.

A controller's prediction step and the closed-loop check's plant step are fixed steps over the loop period
(:meth:`~gtmodel.modeling.simulation.explicit.ExplicitODE.step`, explicit Euler in the MPC). An explicit step
is stable for the linearised model ``x' = J x`` only where ``|R(lambda h)| <= 1`` for each eigenvalue ``lambda``
of the Jacobian ``J = df/dx`` (``h`` the substep, ``R`` the method's stability polynomial: ``1 + z`` for
explicit Euler, ``1 + z + z^2/2 + z^3/6 + z^4/24`` for RK4; Hairer & Wanner, *Solving ODE II*, sec. IV.2).
A motor's electrical pole ``-R/L`` (a held-out drive with L/R = 0.2 ms: ``|lambda|`` 3.5e4 1/s) or a stiff
coupling (600 Hz) with 1 ms RK4 substeps gives ``|R|`` far above 1: the step's state grows by orders of
magnitude every period while the model's decays, and a controller built on it returns ``GT_OK`` on garbage
(issue 49's held-out loop trial). :func:`step_stability` evaluates the eigenvalues at the trajectory's samples
and finds the substeps that make every decaying mode decay; a growing mode of the model itself (``Re lambda
> 0``, an inverted pendulum) is the model's, not the step's, and is not counted. The implicit methods
(``"implicit_euler"``, ``"radau2"``) are A-stable and always pass.

A linear instability is confirmed by the step itself before it is reported: at the samples where the step
amplifies a mode most, a perturbation of :data:`PERTURBATION` of the states' scales along the mode's eigenvector
is stepped with the input held, beside the unperturbed state, for as many periods as the linear growth needs to
reach :data:`CONFIRMED_GROWTH`; only if the difference grows that much is the step unstable. A mode that lives in
a narrow band of the state only (the L1's smooth Coulomb friction at rest: ``tanh(v / 0.01 m/s)``, -749 1/s
under one 4 ms Euler step) stops growing where the band ends, and the MPC that predicts with that step tracks
well (``codegen/mpc/l1_mpc.toml``); a motor's electrical pole is linear and grows without end.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError

__all__ = ["StepStability", "step_stability", "STABILITY_POLYNOMIALS", "GROWTH_PER_PERIOD", "MAX_SAMPLES", "PERTURBATION",
           "CONFIRMED_GROWTH"]

#: Coefficients of the stability polynomials ``R(z)`` of the explicit methods, lowest degree first.
STABILITY_POLYNOMIALS = {"euler": (1.0, 1.0), "rk4": (1.0, 1.0, 1.0 / 2.0, 1.0 / 6.0, 1.0 / 24.0)}

#: A decaying (or neutral) mode may grow by at most this factor per period under the step: explicit Euler
#: amplifies an undamped oscillation by ``1 + (omega h)^2 / 2`` per step, harmless where it is slow.
GROWTH_PER_PERIOD = 1.01

#: Samples of the trajectory at which the Jacobian's eigenvalues are evaluated (evenly spaced).
MAX_SAMPLES = 200

#: The perturbation stepped to confirm a linear instability, relative to each state's scale ``1 + max |x|``.
PERTURBATION = 1e-3

#: The growth of the stepped perturbation that confirms a linear instability.
CONFIRMED_GROWTH = 100.0

_MAX_SUBSTEPS = 1 << 16
_CONFIRM_SAMPLES = 3
_MAX_CONFIRM_PERIODS = 200


@dataclasses.dataclass(frozen=True)
class StepStability:
    """The linear stability of a fixed explicit step along a trajectory (:func:`step_stability`).

    Parameters
    ----------
    method : str
        The step's method.
    dt : float
        The period [s] the step covers.
    substeps : int
        Equal steps of ``method`` within ``dt``.
    eigenvalue : complex
        The decaying eigenvalue of ``df/dx`` [1/s] that the step amplifies most (0 if none).
    time : float
        The trajectory's time [s] of that eigenvalue's sample.
    growth : float
        Its amplification over one period, ``|R(lambda dt / substeps)|**substeps`` (the model's own decays).
    substeps_needed : int
        The fewest substeps that keep every decaying mode within :data:`GROWTH_PER_PERIOD` per period.
    """

    method: str
    dt: float
    substeps: int
    eigenvalue: complex
    time: float
    growth: float
    substeps_needed: int

    @property
    def stable(self) -> bool:
        """No decaying mode of the model grows by more than :data:`GROWTH_PER_PERIOD` per period under the step."""
        return self.growth <= GROWTH_PER_PERIOD

    def message(self, what: str, remedy: str) -> str:
        """The refusal of an unstable step: what it is, the deciding eigenvalue and the remedy.

        Parameters
        ----------
        what : str
            The step's role and fields (``"the MPC's prediction step ([mpc] method, substeps)"``).
        remedy : str
            The field to set, formatted with ``{n}``, the substeps needed (``"substeps = {n}"``).

        Returns
        -------
        str
            One sentence.
        """
        lam = self.eigenvalue
        h = self.dt / self.substeps
        return (f"{what} is unstable for this model: {self.method} with {self.substeps} substep(s) of {h:.3g} s meets "
                f"the eigenvalue {lam.real:.4g}{lam.imag:+.4g}j 1/s of df/dx (|lambda h| = {abs(lam) * h:.3g}, at t = "
                f"{self.time:.4g} s of the reference), which it amplifies {self.growth:.3g}x per period where the model "
                f"decays; give {remedy.format(n=self.substeps_needed)} (or an implicit method, 'radau2' or "
                "'implicit_euler', A-stable but larger in C)")


def _growth(lams: np.ndarray, h: float, m: int, coefficients: tuple[float, ...]) -> np.ndarray:
    """``|R(lambda h)|**m`` per eigenvalue (``h`` the substep)."""
    z = lams * h
    r = np.zeros_like(z)
    for c in reversed(coefficients):  # Horner
        r = r * z + c
    with np.errstate(over="ignore", invalid="ignore"):
        return np.abs(r) ** m


def _explicit_step(f: ca.Function, dt: float, method: str, substeps: int) -> ca.Function:
    """The explicit step ``(x, u, p) -> x_next`` over ``dt`` (Euler or classical RK4, ``substeps`` equal steps)."""
    x, u, p = ca.SX.sym("x", f.size1_in(0)), ca.SX.sym("u", f.size1_in(1)), ca.SX.sym("p", f.size1_in(2))
    h, xn = dt / substeps, x
    for _ in range(substeps):
        if method == "euler":
            xn = xn + h * f(xn, u, p)
        else:
            k1 = f(xn, u, p)
            k2 = f(xn + h / 2 * k1, u, p)
            k3 = f(xn + h / 2 * k2, u, p)
            k4 = f(xn + h * k3, u, p)
            xn = xn + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return ca.Function("step", [x, u, p], [xn])


def _confirmed(f: ca.Function, dt: float, method: str, substeps: int, xs: np.ndarray, us: np.ndarray, p: np.ndarray,
               jacs: np.ndarray, growth: np.ndarray, scale: np.ndarray) -> bool:
    """Whether the step itself lets a perturbation along an amplified mode grow by :data:`CONFIRMED_GROWTH`
    (at the :data:`_CONFIRM_SAMPLES` samples where the linear growth is largest)."""
    step = _explicit_step(f, dt, method, substeps)
    worst = np.max(growth, axis=1)
    for k in np.argsort(-worst)[:_CONFIRM_SAMPLES]:
        if not worst[k] > GROWTH_PER_PERIOD:
            break
        lams, vecs = np.linalg.eig(jacs[k])
        j = int(np.argmax(growth[k]))
        v = np.real(vecs[:, j]) if np.any(np.abs(np.real(vecs[:, j])) > 0) else np.imag(vecs[:, j])
        v = v / np.max(np.abs(v) / scale)  # the largest component one state scale
        periods = min(_MAX_CONFIRM_PERIODS, max(1, math.ceil(math.log(CONFIRMED_GROWTH) / math.log(worst[k]))) + 1)
        nominal, perturbed = xs[k].copy(), xs[k] + PERTURBATION * v
        for _ in range(periods):
            nominal = np.asarray(step(nominal, us[k], p), dtype=float).reshape(-1)
            perturbed = np.asarray(step(perturbed, us[k], p), dtype=float).reshape(-1)
            with np.errstate(invalid="ignore", over="ignore"):
                apart = float(np.max(np.abs(perturbed - nominal) / scale))
            if not np.isfinite(apart) or apart > CONFIRMED_GROWTH * PERTURBATION:
                return True
    return False


def step_stability(f: ca.Function, dt: float, method: str, substeps: int, x: Any, u: Any, p: Any,
                   t: Any = None) -> StepStability | None:
    """The linear stability of a fixed explicit step of ``x' = f(x, u, p)`` along a trajectory.

    Parameters
    ----------
    f : casadi.Function
        The right-hand side ``f(x (nx,1), u (nu,1), p (np,1)) -> x' (nx,1)`` (first output).
    dt : float
        The period [s] one step covers.
    method : str
        ``"euler"``, ``"rk4"`` (checked) or an implicit method (A-stable: None).
    substeps : int
        Equal steps of ``method`` within ``dt``.
    x, u : array_like
        The trajectory's states ``(N, nx)`` and inputs ``(N, nu)``; at most :data:`MAX_SAMPLES` evenly spaced
        samples are evaluated.
    p : array_like
        The parameters ``(np,)``.
    t : array_like, optional
        The samples' times ``(N,)`` [s] (for the message); default the sample index times ``dt``.

    Returns
    -------
    StepStability or None
        None for an implicit method; else the worst decaying mode and the substeps it needs.

    Raises
    ------
    InputError
        ``x`` and ``u`` of different lengths or widths other than ``f``'s, or non-finite Jacobians.
    """
    if method not in STABILITY_POLYNOMIALS:
        return None
    xs, us = np.atleast_2d(np.asarray(x, dtype=float)), np.atleast_2d(np.asarray(u, dtype=float))
    nx, nu = f.size1_in(0), f.size1_in(1)
    if xs.shape[1] != nx or us.shape[1] != nu or len(xs) != len(us):
        raise InputError(f"step_stability: expected states (N, {nx}) and inputs (N, {nu}), got {xs.shape} and {us.shape}")
    times = dt * np.arange(len(xs)) if t is None else np.asarray(t, dtype=float)
    pick = np.unique(np.linspace(0, len(xs) - 1, min(len(xs), MAX_SAMPLES)).round().astype(int))
    xsym, usym, psym = ca.SX.sym("x", nx), ca.SX.sym("u", nu), ca.SX.sym("p", f.size1_in(2))
    jac = ca.Function("J", [xsym, usym, psym], [ca.jacobian(f(xsym, usym, psym), xsym)])
    jacs = np.asarray(jac.map(len(pick))(xs[pick].T, us[pick].T, np.asarray(p, dtype=float).reshape(-1, 1)))
    jacs = jacs.reshape(nx, len(pick), nx).transpose(1, 0, 2)
    if not np.all(np.isfinite(jacs)):
        raise InputError("step_stability: the model's Jacobian df/dx is not finite along the reference")
    lams = np.linalg.eigvals(jacs)  # (samples, nx)
    decaying = lams.real <= 1e-9 * np.maximum(np.abs(lams), 1.0)
    lams = np.where(decaying, lams, 0.0)
    coefficients = STABILITY_POLYNOMIALS[method]
    growth = _growth(lams, dt / substeps, substeps, coefficients)
    k, j = np.unravel_index(int(np.argmax(growth)), growth.shape)
    needed = int(substeps)
    if growth[k, j] > GROWTH_PER_PERIOD and not _confirmed(f, dt, method, substeps, xs[pick], us[pick], np.asarray(p, dtype=float),
                                                           jacs, growth, 1.0 + np.max(np.abs(xs), axis=0)):
        growth = np.minimum(growth, GROWTH_PER_PERIOD)  # a linear instability that the step's own nonlinearity bounds
    if growth[k, j] > GROWTH_PER_PERIOD:
        worst = lams[np.abs(lams) > 0]
        # |R(z)| <= 1 needs |z| below the method's reach along the real axis (2 for Euler, 2.785 for RK4): a start
        needed = max(needed, math.ceil(dt * float(np.max(np.abs(worst))) / (2.0 if method == "euler" else 2.785)))
        while needed < _MAX_SUBSTEPS and np.max(_growth(worst, dt / needed, needed, coefficients)) > GROWTH_PER_PERIOD:
            needed = max(needed + 1, math.ceil(needed * 1.1))
    return StepStability(method=method, dt=float(dt), substeps=int(substeps), eigenvalue=complex(lams[k, j]),
                         time=float(times[pick[k]]), growth=float(growth[k, j]), substeps_needed=int(needed))
