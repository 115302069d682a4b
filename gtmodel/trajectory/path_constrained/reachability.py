"""Two-pass reachability solve of the gridded problem (TOPP-RA, Pham & Pham 2018), exact interval algebra.

The one-step problems in ``(a, b)`` are solved in closed form: ``a`` is eliminated
(Fourier-Motzkin), leaving conditions ``P x^2 + Q x + R <= 0`` in ``x = sqrt(b)``; see the
package docstring for the viscous-friction case and the optimality certificate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__: list[str] = []

#: Relative tolerance on the emptiness of an interval (rounding of the closed forms).
_EMPTY_TOLERANCE = 1e-12
_INF = math.inf


def _intervals(P: np.ndarray, Q: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``{b >= 0 : P b + Q sqrt(b) + R <= 0}`` elementwise, a quadratic in ``x = sqrt(b)``.

    Returns the lower and upper ends (``lo > hi`` when empty) and, where the set is two
    intervals ``[0, b1] u [b2, inf)`` (concave quadratic with two positive roots), ``b2``
    (else ``inf``); the first interval, which contains rest, is returned as ``lo, hi``.
    """
    shape = np.shape(P)
    lo = np.zeros(shape)
    hi = np.full(shape, _INF)
    split = np.full(shape, _INF)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # P == 0: Q x + R <= 0
        z = P == 0
        v = -R / Q
        m = z & (Q > 0)
        hi[m] = np.where(v[m] >= 0, v[m] ** 2, -_INF)
        m = z & (Q < 0)
        lo[m] = np.maximum(v[m], 0.0) ** 2
        m = z & (Q == 0) & (R > 0)
        lo[m], hi[m] = _INF, -_INF
        # P != 0: roots of P x^2 + Q x + R (stable form)
        D = Q * Q - 4.0 * P * R
        sq = np.sqrt(np.maximum(D, 0.0))
        qq = -0.5 * (Q + np.where(Q >= 0, sq, -sq))
        r1 = qq / P
        r2 = np.where(qq != 0, R / qq, 0.0)
        x1 = np.minimum(r1, r2)
        x2 = np.maximum(r1, r2)
        # convex: [x1, x2]
        m = (P > 0) & (D >= 0)
        lo[m] = np.maximum(x1[m], 0.0) ** 2
        hi[m] = np.where(x2[m] >= 0, x2[m] ** 2, -_INF)
        m = (P > 0) & (D < 0)
        lo[m], hi[m] = _INF, -_INF
        # concave: outside (x1, x2)
        c = (P < 0) & (D > 0)
        m = c & (x2 > 0) & (x1 <= 0)
        lo[m] = x2[m] ** 2
        m = c & (x1 > 0)
        hi[m] = x1[m] ** 2
        split[m] = x2[m] ** 2
    return lo, hi, split


def _interval(P: float, Q: float, R: float) -> tuple[float, float, float]:
    """Scalar :func:`_intervals`."""
    if P == 0.0:
        if Q > 0.0:
            v = -R / Q
            return (0.0, v * v, _INF) if v >= 0.0 else (_INF, -_INF, _INF)
        if Q < 0.0:
            v = -R / Q
            return ((v * v if v > 0.0 else 0.0), _INF, _INF)
        return (0.0, _INF, _INF) if R <= 0.0 else (_INF, -_INF, _INF)
    D = Q * Q - 4.0 * P * R
    if D < 0.0:
        return (_INF, -_INF, _INF) if P > 0.0 else (0.0, _INF, _INF)
    sq = math.sqrt(D)
    qq = -0.5 * (Q + sq) if Q >= 0.0 else -0.5 * (Q - sq)
    r1 = qq / P
    r2 = R / qq if qq != 0.0 else 0.0
    x1, x2 = (r1, r2) if r1 <= r2 else (r2, r1)
    if P > 0.0:
        if x2 < 0.0:
            return (_INF, -_INF, _INF)
        return ((x1 * x1 if x1 > 0.0 else 0.0), x2 * x2, _INF)
    if D == 0.0 or x2 <= 0.0:
        return (0.0, _INF, _INF)
    if x1 <= 0.0:
        return (x2 * x2, _INF, _INF)
    return (0.0, x1 * x1, x2 * x2)


def _stage_sets(p: np.ndarray, r: np.ndarray, w: np.ndarray, e: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Sets of ``b`` admitting some ``a`` at every grid point (Fourier-Motzkin on ``a``).

    Returns ``lo, hi`` (N + 1,), the codes of the one-sided rows (``j < M``) or pairs
    (``M + i M + j``) that set each end, the upper end ignoring the upper bounds of split
    sets (N + 1,), and the number of split sets whose upper part meets the others.
    """
    n, M = p.shape
    zero = p == 0
    # pairs (i: p > 0, j: p < 0): p_i row_j - p_j row_i eliminates a
    ci = np.flatnonzero(np.any(p > 0, axis=0))
    cj = np.flatnonzero(np.any(p < 0, axis=0))
    pi, pj = p[:, ci, None], p[:, None, cj]
    valid = (pi > 0) & (pj < 0)
    P = np.where(valid, pi * r[:, None, cj] - pj * r[:, ci, None], 0.0)
    Q = np.where(valid, pi * w[:, None, cj] - pj * w[:, ci, None], 0.0)
    R = np.where(valid, pi * e[:, None, cj] - pj * e[:, ci, None], -1.0)
    # the one-sided rows without a (p == 0) and the pairs, in one elementwise call
    lo_all, hi_all, split_all = _intervals(
        np.concatenate([np.where(zero, r, 0.0), P.reshape(n, -1)], axis=1),
        np.concatenate([np.where(zero, w, 0.0), Q.reshape(n, -1)], axis=1),
        np.concatenate([np.where(zero, e, -1.0), R.reshape(n, -1)], axis=1),
    )
    codes = M + (ci[:, None] * M + cj[None, :]).ravel()
    code_all = np.concatenate([np.arange(M), codes])
    arg_lo = np.argmax(lo_all, axis=1)
    arg_hi = np.argmin(hi_all, axis=1)
    idx = np.arange(n)
    hull_hi = np.min(np.where(np.isfinite(split_all), _INF, hi_all), axis=1)
    nsplit = np.sum(np.isfinite(split_all) & (split_all <= hull_hi[:, None]), axis=1)
    return lo_all[idx, arg_lo], hi_all[idx, arg_hi], code_all[arg_lo], code_all[arg_hi], hull_hi, nsplit


def _rows_of(code: int, M: int) -> list[int]:
    """One-sided rows behind a stage-set code (a row ``j < M`` or a pair ``M + i M + j``)."""
    if code < M:
        return [code]
    i, j = divmod(code - M, M)
    return [i, j]


def _empty_message(k: int, s: np.ndarray, rest: np.ndarray, p: np.ndarray, e: np.ndarray, names: list[str], klo: float, khi: float) -> str:
    """Why the controllable set at grid point k is empty (backward pass)."""
    where = f"grid point {k} (s = {s[k]:.6g})"
    head = f"infeasible: the controllable set becomes empty at {where}"
    if rest[k]:
        pos = np.flatnonzero(p[k] > 0)
        if pos.size:
            amax = -e[k, pos] / p[k, pos]
            i = int(pos[np.argmin(amax)])
            if np.min(amax) <= 0:
                return (
                    f"{head}, which is passed at rest: there constraint '{names[i]}' allows s_ddot <= {np.min(amax):.6g} "
                    "1/s^2, no acceleration from rest (e.g. a force limit below gravity plus Coulomb friction)"
                )
        return f"{head}, which is passed at rest: from rest there the motion cannot reach s_dot^2 in [{klo:.6g}, {khi:.6g}] 1/s^2 at s = {s[k + 1]:.6g} and still end at rest"
    return f"{head}: from no admissible s_dot there can the motion reach s_dot^2 in [{klo:.6g}, {khi:.6g}] 1/s^2 at s = {s[k + 1]:.6g} and still end at rest"


@dataclass
class _Pass:
    """Result of one reachability solve (internal)."""

    ok: bool
    b: np.ndarray | None = None
    a: np.ndarray | None = None
    message: str = ""
    index: int = -1
    splits: int = 0
    uncertified: np.ndarray | None = None


def _reachability(
    s: np.ndarray, rest: np.ndarray, p: np.ndarray, r: np.ndarray, w: np.ndarray, e: np.ndarray, names: list[str],
    p_end: np.ndarray | None = None, e_end: np.ndarray | None = None,
) -> _Pass:
    """Two-pass reachability solve of the gridded problem ``p a + r b + w sqrt(b) + e <= 0``.

    ``p_end a_{N-1} + e_end <= 0`` are rows at the last grid point (where ``b_N = 0``).
    """
    N = s.size - 1
    M = p.shape[1]
    S_lo, S_hi, arg_lo, arg_hi, S_hull, nsplit = _stage_sets(p, r, w, e)
    splits = int(nsplit.sum())
    tol = _EMPTY_TOLERANCE * np.maximum(1.0, np.where(np.isfinite(S_hi), np.abs(S_hi), 0.0))
    bad = S_lo > S_hi + tol
    bad |= rest & (S_lo > tol)
    if np.any(bad):
        k = int(np.argmax(bad))
        if S_lo[k] > S_hi[k] + tol[k]:
            rows = list(dict.fromkeys(_rows_of(int(arg_lo[k]), M) + _rows_of(int(arg_hi[k]), M)))
            why = f"constraints {', '.join(repr(names[i]) for i in rows)} admit no (s_ddot, s_dot^2) together"
        else:
            rows = _rows_of(int(arg_lo[k]), M)
            why = f"constraints {', '.join(repr(names[i]) for i in rows)} cannot hold at rest (they need s_dot^2 >= {S_lo[k]:.6g} 1/s^2)"
        return _Pass(False, message=f"infeasible at grid point {k} (s = {s[k]:.6g}): {why}", index=k)
    # leaving rest (start, corners) needs s_ddot > 0 there
    for k in np.flatnonzero(rest[:-1]):
        pos = np.flatnonzero(p[k] > 0)
        if pos.size and np.min(-e[k, pos] / p[k, pos]) <= 0:
            return _Pass(False, message=_empty_message(int(k), s, rest, p, e, names, 0.0, 0.0), index=int(k))
    S_lo = np.maximum(S_lo, 0.0)
    S_hi = np.where(rest, 0.0, S_hi)
    S_lo = np.minimum(S_lo, S_hi)
    two_d = 2.0 * np.diff(s)
    # backward pass. Row i at stage k with the reach constraint klo <= b + 2 ds a (p > 0) or
    # b + 2 ds a <= khi (p < 0), a eliminated: P b + Q sqrt(b) + R <= 0 with P = 2 ds r - p,
    # Q = 2 ds w, R = 2 ds e + p klo (p > 0) or 2 ds e + p khi (p < 0).
    pa = p[:-1]
    cols = np.flatnonzero(np.any(pa != 0, axis=0))
    pa = pa[:, cols]
    Pb = two_d[:, None] * r[:-1, cols] - pa
    Qb = two_d[:, None] * w[:-1, cols]
    Eb = two_d[:, None] * e[:-1, cols]
    with np.errstate(divide="ignore", invalid="ignore"):
        alpha = np.where(Pb != 0, -Eb / Pb, 0.0)
        beta = np.where(Pb != 0, -pa / Pb, 0.0)
    # codes: 0/1 lower/upper bound alpha + beta klo; 2/3 the same with khi; 4 no a;
    # 5 P == 0 (a condition on klo/khi); 6 quadratic (Q != 0)
    code = np.where(pa > 0, 0, 2) + np.where(Pb > 0, 1, 0)
    code = np.where(Pb == 0, 5, code)
    code = np.where(Qb != 0, 6, code)
    code = np.where(pa == 0, 4, code)
    # one (N, M', 7) array; each step converts only its own rows to Python floats, so no
    # grid-sized tree of Python lists lives through the loop (it made the garbage collector's
    # full collections, and so the time per grid point, grow with N)
    table = np.stack([code, alpha, beta, Pb, Qb, Eb, pa], axis=2)
    K_lo = [0.0] * (N + 1)
    K_hi = [0.0] * (N + 1)
    slo, shi, shull = S_lo.tolist(), S_hi.tolist(), S_hull.tolist()
    interval = _interval
    end_rows = [] if p_end is None else [(float(pe), float(ee)) for pe, ee in zip(p_end, e_end) if pe != 0.0]
    td_last = float(two_d[-1])
    for k in range(N - 1, -1, -1):
        klo, khi = K_lo[k + 1], K_hi[k + 1]
        lo, hi = slo[k], shi[k]
        hull = shull[k]
        upper = None
        for cd, al, be, P, Q, E, pp in table[k].tolist():
            if cd == 1.0:
                v = al + be * klo
                if v < hi:
                    hi = v
            elif cd == 3.0:
                v = al + be * khi
                if v < hi:
                    hi = v
            elif cd == 0.0:
                v = al + be * klo
                if v > lo:
                    lo = v
            elif cd == 2.0:
                v = al + be * khi
                if v > lo:
                    lo = v
            elif cd == 6.0:
                l2, h2, b2 = interval(P, Q, E + pp * (klo if pp > 0.0 else khi))
                if l2 > lo:
                    lo = l2
                if h2 < hi:
                    hi = h2
                if b2 < _INF:
                    upper = [b2] if upper is None else upper + [b2]
                elif h2 < hull:
                    hull = h2
            elif cd == 5.0 and E + pp * (klo if pp > 0.0 else khi) > 0.0:
                lo, hi = _INF, -_INF
        if upper is not None:
            splits += sum(1 for b2 in upper if b2 <= min(hull, hi if hi < _INF else hull))
        if k == N - 1 and end_rows:
            # rows at the last grid point on a_{N-1} = (b_N - b_{N-1}) / (2 ds), b_N = 0
            for pe, ee in end_rows:
                v = td_last * ee / pe
                if pe > 0.0:
                    if v > lo:
                        lo = v
                elif v < hi:
                    hi = v
        if lo > hi:
            if lo > hi + _EMPTY_TOLERANCE * max(1.0, abs(hi)):
                return _Pass(False, message=_empty_message(k, s, rest, p, e, names, klo, khi), index=k)
            lo = hi
        K_lo[k], K_hi[k] = lo, hi
    # forward pass: the largest b_{k+1} in K_{k+1} reachable with a <= -(r b + w sqrt(b) + e) / p
    pcols = np.flatnonzero(np.any(p[:-1] > 0, axis=0))
    pp_ = p[:-1, pcols]
    pos = pp_ > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        rp = np.where(pos, r[:-1, pcols] / pp_, 0.0)
        wp = np.where(pos, w[:-1, pcols] / pp_, 0.0)
        ep = np.where(pos, e[:-1, pcols] / pp_, -_INF)
    b = [0.0] * (N + 1)
    a = [0.0] * N
    td = two_d.tolist()
    bk = 0.0
    sqrt = math.sqrt
    viscous = bool(np.any(wp != 0))
    ftable = np.stack([rp, wp, ep], axis=2) if viscous else np.stack([rp, ep], axis=2)
    for k in range(N):
        amax = _INF
        if viscous:
            x = sqrt(bk)
            for rr, ww, ee in ftable[k].tolist():
                v = -(rr * bk + ww * x + ee)
                if v < amax:
                    amax = v
        else:
            for rr, ee in ftable[k].tolist():
                v = -(rr * bk + ee)
                if v < amax:
                    amax = v
        bn = bk + td[k] * amax
        if bn > K_hi[k + 1]:
            bn = K_hi[k + 1]
        if bn < K_lo[k + 1]:
            bn = K_lo[k + 1]
        a[k] = (bn - bk) / td[k]
        b[k + 1] = bn
        bk = bn
    b_arr = np.array(b)
    uncertified = _uncertified_stages(b_arr, np.array(K_lo), np.array(K_hi), two_d, rp, wp, ep)
    return _Pass(True, b=b_arr, a=np.array(a), splits=splits, uncertified=uncertified)


def _uncertified_stages(b: np.ndarray, K_lo: np.ndarray, K_hi: np.ndarray, two_d: np.ndarray, rp: np.ndarray, wp: np.ndarray, ep: np.ndarray) -> np.ndarray:
    """Stages where the greedy forward step is not proven to dominate every feasible profile.

    Step k maps ``b_k`` to ``u_k(b_k) = min(K_hi[k+1], min_j l_j(b_k))`` with
    ``l_j(b) = b - 2 ds (rp_j b + wp_j sqrt(b) + ep_j)``. If some piece active at the greedy
    ``b_k`` (the cap, or a row) is nowhere above its value at ``b_k`` on ``[K_lo[k], b_k]``,
    then ``u_k(b) <= u_k(b_k)`` for every smaller ``b``: by induction every feasible profile
    stays below the greedy one, which is then the optimum (the duration decreases in every
    ``b_k``). Checked per piece: affine with slope >= 0, concave (``wp < 0``) with slope >= 0
    at ``b_k``, convex (``wp > 0``) with ``l_j(K_lo[k]) <= l_j(b_k)``.
    """
    bk = b[:-1]
    tol = 1e-12 * np.maximum(1.0, np.abs(K_hi[1:]))
    capped = b[1:] >= K_hi[1:] - tol
    pinned = bk <= K_lo[:-1] + 1e-12 * np.maximum(1.0, bk)
    x = np.sqrt(bk)[:, None]
    td = two_d[:, None]
    with np.errstate(invalid="ignore", divide="ignore"):
        val = bk[:, None] - td * (rp * bk[:, None] + wp * x + ep)
        val = np.where(np.isfinite(ep), val, _INF)
        active = val <= np.min(val, axis=1, keepdims=True) + tol[:, None]
        slope_lin = 1.0 - td * rp
        slope = np.where(x > 0, slope_lin - td * wp / (2.0 * x), np.where(wp < 0, _INF, np.where(wp > 0, -_INF, slope_lin)))
        lo = K_lo[:-1, None]
        val_lo = lo - td * (rp * lo + wp * np.sqrt(lo) + ep)
    ok_piece = np.where(wp > 0, val_lo <= val + tol[:, None], slope >= -1e-12)
    certified = capped | pinned | np.any(active & ok_piece, axis=1)
    return np.flatnonzero(~certified)
