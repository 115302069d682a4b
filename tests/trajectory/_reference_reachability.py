"""Today's (pre issue 17) reachability pass, kept verbatim as the reference of the per-step rewrite.

The pure-Python loops over ``.tolist()`` tables of the whole grid, as they were before the
rewrite of :func:`gtmodel.trajectory.path_constrained.reachability._reachability`
(and the stage sets before their one-call ``_intervals``); the
test compares the two bit for bit (to 1e-12 relative) on random feasible instances.
"""

from __future__ import annotations

import math

import numpy as np

from gtmodel.trajectory.path_constrained.reachability import (
    _EMPTY_TOLERANCE,
    _INF,
    _Pass,
    _empty_message,
    _interval,
    _intervals,
    _rows_of,
    _uncertified_stages,
)


def _old_stage_sets(p: np.ndarray, r: np.ndarray, w: np.ndarray, e: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Sets of ``b`` admitting some ``a`` at every grid point (Fourier-Motzkin on ``a``).

    Returns ``lo, hi`` (N + 1,), the codes of the one-sided rows (``j < M``) or pairs
    (``M + i M + j``) that set each end, the upper end ignoring the upper bounds of split
    sets (N + 1,), and the number of split sets whose upper part meets the others.
    """
    n, M = p.shape
    zero = p == 0
    lo1, hi1, sp1 = _intervals(np.where(zero, r, 0.0), np.where(zero, w, 0.0), np.where(zero, e, -1.0))
    # pairs (i: p > 0, j: p < 0): p_i row_j - p_j row_i eliminates a
    ci = np.flatnonzero(np.any(p > 0, axis=0))
    cj = np.flatnonzero(np.any(p < 0, axis=0))
    pi, pj = p[:, ci, None], p[:, None, cj]
    valid = (pi > 0) & (pj < 0)
    P = np.where(valid, pi * r[:, None, cj] - pj * r[:, ci, None], 0.0)
    Q = np.where(valid, pi * w[:, None, cj] - pj * w[:, ci, None], 0.0)
    R = np.where(valid, pi * e[:, None, cj] - pj * e[:, ci, None], -1.0)
    lo2, hi2, sp2 = _intervals(P, Q, R)
    codes = M + (ci[:, None] * M + cj[None, :]).ravel()
    lo_all = np.concatenate([lo1, lo2.reshape(n, -1)], axis=1)
    hi_all = np.concatenate([hi1, hi2.reshape(n, -1)], axis=1)
    code_all = np.concatenate([np.arange(M), codes])
    arg_lo = np.argmax(lo_all, axis=1)
    arg_hi = np.argmin(hi_all, axis=1)
    idx = np.arange(n)
    split_all = np.concatenate([sp1, sp2.reshape(n, -1)], axis=1)
    hull_hi = np.min(np.where(np.isfinite(split_all), _INF, hi_all), axis=1)
    nsplit = np.sum(np.isfinite(split_all) & (split_all <= hull_hi[:, None]), axis=1)
    return lo_all[idx, arg_lo], hi_all[idx, arg_hi], code_all[arg_lo], code_all[arg_hi], hull_hi, nsplit


def reference_reachability(
    s: np.ndarray, rest: np.ndarray, p: np.ndarray, r: np.ndarray, w: np.ndarray, e: np.ndarray, names: list[str],
    p_end: np.ndarray | None = None, e_end: np.ndarray | None = None,
) -> _Pass:
    """Two-pass reachability solve of the gridded problem ``p a + r b + w sqrt(b) + e <= 0``.

    ``p_end a_{N-1} + e_end <= 0`` are rows at the last grid point (where ``b_N = 0``).
    """
    N = s.size - 1
    M = p.shape[1]
    S_lo, S_hi, arg_lo, arg_hi, S_hull, nsplit = _old_stage_sets(p, r, w, e)
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
    table = np.stack([code, alpha, beta, Pb, Qb, Eb, pa], axis=2).tolist()
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
        for cd, al, be, P, Q, E, pp in table[k]:
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
    ftable = (np.stack([rp, wp, ep], axis=2) if viscous else np.stack([rp, ep], axis=2)).tolist()
    for k in range(N):
        amax = _INF
        if viscous:
            x = sqrt(bk)
            for rr, ww, ee in ftable[k]:
                v = -(rr * bk + ww * x + ee)
                if v < amax:
                    amax = v
        else:
            for rr, ee in ftable[k]:
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
