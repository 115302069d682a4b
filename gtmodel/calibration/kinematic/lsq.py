"""Least-squares steps of a calibration group: MINPACK's Levenberg-Marquardt through
:func:`scipy.optimize.leastsq` and the Gauss-Newton polishing step, whose pivoted QR is
kept for the identifiability report (Dressler (2012), eqs. 5.1-5.2; internal).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.optimize

from gtmodel.calibration.identifiability import RANK_TOLERANCE
from gtmodel.calibration.kinematic.residuals import _Evaluator

__all__ = ["LSQ_TOLERANCE", "POLISH_STEPS", "POLISH_MAX_STEP"]

#: Termination tolerance of least_squares: ``ftol = xtol = gtol`` (relative change of the
#: cost, relative step, scaled gradient).
LSQ_TOLERANCE = 1e-10
#: Gauss-Newton polishing steps after a converged least-squares run (see ``_polish``).
POLISH_STEPS = 1
#: Largest relative polishing step ``|dx| / (1 + |x|)``; larger steps mean the run had not
#: converged and are not taken.
POLISH_MAX_STEP = 1e-6
#: Messages of MINPACK's ``lmder`` return codes, as :func:`scipy.optimize.least_squares`
#: words them (codes 6-8, a tolerance below what rounding allows -- no better point
#: exists -- keep leastsq's words and give status "acceptable").
_MINPACK_MESSAGES = {
    0: "Improper input parameters status returned from `leastsq`",
    1: "`ftol` termination condition is satisfied.",
    2: "`xtol` termination condition is satisfied.",
    3: "Both `ftol` and `xtol` termination conditions are satisfied.",
    4: "`gtol` termination condition is satisfied.",
    5: "The maximum number of function evaluations is exceeded.",
}


class _PolishQR:
    """Column-pivoted QR of the column-scaled Jacobian at ``x`` and its Gauss-Newton step.

    ``J_s P = Q R`` with ``J_s = J / norms`` (the rows of ``mask``: poses with non-zero
    weight); ``step`` is the least-squares solution of ``J dx = -r`` (None when ``J`` is
    rank-deficient: the caller then takes the minimum-norm ``lstsq`` step). ``x_after`` is the point the
    step led to (``x`` itself until a step is taken).
    """

    def __init__(self, J: np.ndarray, r: np.ndarray, x: np.ndarray, mask: np.ndarray) -> None:
        self.x = x
        self.x_after = x
        self.r = r  # all rows (zero for zero weight)
        J, r = J[mask], r[mask]
        self.finite = bool(np.isfinite(J).all() and np.isfinite(r).all())
        self.step: np.ndarray | None = None
        m, n = J.shape
        if not self.finite or m < n:
            self.finite = False
            self.R, self.piv, self.norms = np.zeros((0, 0)), np.zeros(0, dtype=int), np.zeros(0)
            return
        # LAPACK directly (dgeqp3, dormqr, dtrtrs: the routines of scipy.linalg.qr and
        # solve_triangular, with the workspace scipy.linalg.qr queries), without the
        # ~50 us of argument handling per scipy.linalg call
        self.norms = np.sqrt(np.einsum("ij,ij->j", J, J))
        Js = J / np.where(self.norms > 0, self.norms, 1.0)
        lwork = _lwork(m, n)
        qr, jpvt, tau, _, info = scipy.linalg.lapack.dgeqp3(Js, lwork=lwork, overwrite_a=1)
        if info != 0:
            self.finite = False
            self.R, self.piv, self.norms = np.zeros((0, 0)), np.zeros(0, dtype=int), np.zeros(0)
            return
        self.R = np.triu(qr[:n])
        self.piv = jpvt - 1
        d = np.abs(np.diag(self.R))
        if d[0] > 0 and np.all(d > RANK_TOLERANCE * d[0]):
            qtr, _, info = scipy.linalg.lapack.dormqr("L", "T", qr, tau, -r[:, None], max(1, lwork))
            z, info2 = scipy.linalg.lapack.dtrtrs(self.R, qtr[:n])
            if info == 0 and info2 == 0:
                dxs = np.empty(n)
                dxs[self.piv] = z[:, 0]
                self.step = dxs / np.where(self.norms > 0, self.norms, 1.0)


_LWORK: dict[tuple[int, int], int] = {}


def _lwork(m: int, n: int) -> int:
    """Optimal LAPACK workspace of dgeqp3 (and dormqr) for an (m, n) matrix, queried once."""
    if (m, n) not in _LWORK:
        if len(_LWORK) > 64:
            _LWORK.clear()
        w1 = scipy.linalg.lapack.dgeqp3(np.zeros((m, n)), lwork=-1)[3][0]
        w2 = scipy.linalg.lapack.dormqr("L", "T", np.zeros((m, n)), np.zeros(min(m, n)), np.zeros((m, 1)), -1)[1][0]
        _LWORK[(m, n)] = int(max(w1, w2, 3 * (n + 1), 1))
    return _LWORK[(m, n)]


def _polish(ev: _Evaluator, x: np.ndarray) -> tuple[np.ndarray, int]:
    """Gauss-Newton steps with the exact Jacobian after a converged least_squares run.

    least_squares stops when the decrease of V falls below the rounding of V, which
    near the optimum is reached ~1e-11 away from it (the closure residual
    ``|A - B|^2 - L^2`` cancels ~11 digits); the Gauss-Newton step uses the gradient,
    which is not affected, and lands on the optimum to ~1e-14. Steps larger than
    :data:`POLISH_MAX_STEP` (relative) are not taken. The step comes from the
    column-pivoted QR of the column-scaled Jacobian, which is kept on the evaluator
    (``ev.polish_qr``) for the identifiability report: the report of the solution
    needs no second factorisation.
    """
    n = 0
    for _ in range(POLISH_STEPS):
        r, J = ev.residuals_jacobian(x)
        qr = _PolishQR(J, r, x, ev.mask)
        dx = qr.step if qr.step is not None else np.linalg.lstsq(J, -r, rcond=None)[0]
        scale = 1.0 + float(np.linalg.norm(x))
        ev.polish_qr = qr if qr.finite else None
        if not np.all(np.isfinite(dx)) or np.linalg.norm(dx) > POLISH_MAX_STEP * scale:
            break
        x = x + dx
        qr.x_after = x
        n += 1
        if np.linalg.norm(dx) <= 1e-15 * scale:
            break
    return x, n


def _solve_minpack(ev: _Evaluator, x0: np.ndarray, max_iter: int) -> tuple[np.ndarray, str, str, int, float]:
    """Solver "lm": MINPACK's ``lmder`` through :func:`scipy.optimize.leastsq`.

    The call ``least_squares(method="lm", x_scale="jac")`` makes (``diag=None``,
    ``factor=100``, the same tolerances and evaluation limit), so the iterates are the
    same, without its per-evaluation wrappers (~0.1 ms per group); the status and
    message are those ``least_squares`` reports (:data:`_MINPACK_MESSAGES`).
    """
    try:
        out = scipy.optimize.leastsq(
            ev.residuals_view, x0, Dfun=ev.jacobian_view, full_output=True, ftol=LSQ_TOLERANCE, xtol=LSQ_TOLERANCE,
            gtol=LSQ_TOLERANCE, maxfev=max_iter, factor=100.0, diag=None,
        )
    except (ValueError, TypeError, np.linalg.LinAlgError) as e:
        return x0, "error", f"least_squares failed: {e}", 0, 0.0
    x, info, code = out[0], out[2], int(out[-1])
    iters = int(info.get("njev", info["nfev"]))
    finite = bool(np.all(np.isfinite(x)))
    if code in (1, 2, 3, 4) and finite:
        status = "optimal"
    elif code in (6, 7, 8) and finite:  # a tolerance below the rounding: no better point exists
        status = "acceptable"
    elif code == 5:
        status = "max_iterations"
    else:
        status = "error"
    message = _MINPACK_MESSAGES.get(code, str(out[-2]).replace("\n ", ""))
    if status in ("optimal", "acceptable"):
        x, n_polish = _polish(ev, x)
        iters += n_polish
    return x, status, message, iters, 0.0
