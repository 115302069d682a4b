/*@template (stripped when filled: gtmodel.codegen.emit.fill)
 * The two-pass reachability (TOPP-RA) of <prefix>_retime: the algorithm of
 * gtmodel.trajectory.path_constrained.reachability, statement by statement and in the same
 * floating-point operations, around the CasADi-generated <prefix>_cg_retime_rows.
 * Markers: @P@ the prefix, @U@ its upper case, @R@ the number of rows, @INIT_LIMITS@ and
 * @ROW_LIMITS@ the statements per limit field.
 */

/* ---- online re-timing: two-pass reachability (hand-written; the Python solver's algorithm) ---- */
#define @U@_RETIME_EMPTY_TOLERANCE 1e-12 /* relative tolerance on an empty interval (rounding) */
/* max(1, x) as Python's max(1.0, x) (1 for NaN) */
#define @U@_RETIME_AT_LEAST_1(x) ((x) > 1.0 ? (x) : 1.0)

unsigned long @P@_retime_work_bytes(void) { return (unsigned long)sizeof(@P@_retime_work); }

int @P@_retime_limits_init(@P@_retime_limits *limits)
{
    if (limits == NULL) return GT_BAD_ARGUMENT;
@INIT_LIMITS@
    limits->viscous_friction = 1;
    limits->constrain_end = 1;
    return GT_OK;
}

/* {b >= 0 : P b + Q sqrt(b) + R <= 0}, a quadratic in x = sqrt(b): [lo, hi] (lo > hi when
 * empty) and, when the set is [0, b1] u [b2, inf), b2 in split (else INFINITY); the
 * interval containing rest is returned. The scalar _interval of the Python solver. */
static inline void @P@_retime_interval(double P, double Q, double R, double *lo, double *hi, double *split)
{
    double D, sq, qq, r1, r2, x1, x2, v;
    *split = INFINITY;
    if (P == 0.0) {
        if (Q > 0.0) {
            v = -R / Q;
            if (v >= 0.0) { *lo = 0.0; *hi = v * v; } else { *lo = INFINITY; *hi = -INFINITY; }
            return;
        }
        if (Q < 0.0) {
            v = -R / Q;
            *lo = v > 0.0 ? v * v : 0.0;
            *hi = INFINITY;
            return;
        }
        if (R <= 0.0) { *lo = 0.0; *hi = INFINITY; } else { *lo = INFINITY; *hi = -INFINITY; }
        return;
    }
    D = Q * Q - 4.0 * P * R;
    if (D < 0.0) {
        if (P > 0.0) { *lo = INFINITY; *hi = -INFINITY; } else { *lo = 0.0; *hi = INFINITY; }
        return;
    }
    sq = sqrt(D);
    qq = Q >= 0.0 ? -0.5 * (Q + sq) : -0.5 * (Q - sq);
    r1 = qq / P;
    r2 = qq != 0.0 ? R / qq : 0.0;
    if (r1 <= r2) { x1 = r1; x2 = r2; } else { x1 = r2; x2 = r1; }
    if (P > 0.0) {
        if (x2 < 0.0) { *lo = INFINITY; *hi = -INFINITY; return; }
        *lo = x1 > 0.0 ? x1 * x1 : 0.0;
        *hi = x2 * x2;
        return;
    }
    if (D == 0.0 || x2 <= 0.0) { *lo = 0.0; *hi = INFINITY; return; }
    if (x1 <= 0.0) { *lo = x2 * x2; *hi = INFINITY; return; }
    *lo = 0.0;
    *hi = x1 * x1;
    *split = x2 * x2;
}

/* The set of b admitting some a at one grid point (Fourier-Motzkin on a): every row
 * without a, every pair of rows bounding a from both sides. *nsplit: split sets whose
 * upper part meets the others. */
static void @P@_retime_stage(const double *p, const double *r, const double *w, const double *e, int M,
    double *s_lo, double *s_hi, double *hull, int *nsplit)
{
    int i, j, count = 0;
    double lo = 0.0, hi = INFINITY, h = INFINITY, l2, h2, b2;
    double splits[@U@_RETIME_SIDES * @U@_RETIME_SIDES + @U@_RETIME_SIDES];
    for (i = 0; i < M; ++i) {
        if (p[i] != 0.0) continue;
        @P@_retime_interval(r[i], w[i], e[i], &l2, &h2, &b2);
        if (l2 > lo) lo = l2;
        if (h2 < hi) hi = h2;
        if (b2 < INFINITY) splits[count++] = b2;
        else if (h2 < h) h = h2;
    }
    for (i = 0; i < M; ++i) {
        if (!(p[i] > 0.0)) continue;
        for (j = 0; j < M; ++j) {
            if (!(p[j] < 0.0)) continue;
            @P@_retime_interval(p[i] * r[j] - p[j] * r[i], p[i] * w[j] - p[j] * w[i], p[i] * e[j] - p[j] * e[i], &l2, &h2, &b2);
            if (l2 > lo) lo = l2;
            if (h2 < hi) hi = h2;
            if (b2 < INFINITY) splits[count++] = b2;
            else if (h2 < h) h = h2;
        }
    }
    *s_lo = lo;
    *s_hi = hi;
    *hull = h;
    *nsplit = 0;
    for (i = 0; i < count; ++i) *nsplit += splits[i] <= h;
}

/* 1 if the greedy step k is proven to dominate every feasible profile (the Python
 * solver's _uncertified_stages, per stage). For the rows with p > 0 the forward pass left
 * r / p, w / p, e / p in r, w, e. */
static int @P@_retime_certified(const @P@_retime_work *wk, int k, int M, double td)
{
    const double *p = wk->p + (long)k * M, *r = wk->r + (long)k * M, *w = wk->w + (long)k * M, *e = wk->e + (long)k * M;
    const double bk = wk->b[k], lo = wk->k_lo[k];
    const double tol = 1e-12 * @U@_RETIME_AT_LEAST_1(fabs(wk->k_hi[k + 1]));
    double x, vmin = INFINITY, val, rp, wp, ep, slope, val_lo, vals[@U@_RETIME_SIDES];
    int i;
    if (wk->b[k + 1] >= wk->k_hi[k + 1] - tol) return 1; /* capped by the controllable set */
    if (bk <= lo + 1e-12 * @U@_RETIME_AT_LEAST_1(bk)) return 1; /* pinned at its lowest value */
    x = sqrt(bk);
    for (i = 0; i < M; ++i) {
        if (!(p[i] > 0.0)) continue;
        vals[i] = bk - td * (r[i] * bk + w[i] * x + e[i]);
        if (vals[i] < vmin) vmin = vals[i];
    }
    for (i = 0; i < M; ++i) {
        if (!(p[i] > 0.0)) continue;
        rp = r[i];
        wp = w[i];
        ep = e[i];
        val = vals[i];
        if (!(val <= vmin + tol)) continue; /* not active */
        if (wp > 0.0) {
            val_lo = lo - td * (rp * lo + wp * sqrt(lo) + ep);
            if (val_lo <= val + tol) return 1;
        } else {
            slope = x > 0.0 ? (1.0 - td * rp) - td * wp / (2.0 * x) : (wp < 0.0 ? INFINITY : 1.0 - td * rp);
            if (slope >= -1e-12) return 1;
        }
    }
    return vmin == INFINITY; /* no row: the step is capped */
}

int @P@_retime(int n, const double s[], const double T[], const double dT[], const double ddT[], const int rest[],
    int configuration, double s_dot_start, const @P@_retime_limits *limits, @P@_retime_work *work,
    double s_dot[], double s_ddot[], @P@_retime_info *info)
{
    const casadi_real *arg[@U@_RETIME_SZ_ARG];
    casadi_real *res[@U@_RETIME_SZ_RES];
    casadi_int iw[@U@_RETIME_SZ_IW];
    casadi_real w[@U@_RETIME_SZ_W];
    casadi_real sg[3], cm[@R@], cc[@R@], cd[@R@], cg[@R@], q[3], disc[3], cs[3];
    double lim[@R@];
    double bound_hi[@R@], bound_lo[@R@], nonfinite, b0, bk, bn, amax, x, v, klo, khi, lo, hi, hull, l2, h2, b2, td, t;
    int hi_rows[@R@], lo_rows[@R@], nhi = 0, nlo = 0, M, N, i, j, k, flag, nsplit, splits = 0, uncertified = 0, finite_limits = 0;
    if (info != NULL) {
        info->final_time = 0.0;
        info->index = -1;
        info->uncertified = 0;
        info->splits = 0;
    }
    if (s == NULL || T == NULL || dT == NULL || ddT == NULL || limits == NULL || work == NULL || s_dot == NULL) return GT_BAD_ARGUMENT;
    if (n < 2) return GT_BAD_ARGUMENT;
    if (n > @U@_RETIME_N_MAX) return GT_TOO_LARGE;
    if (configuration < 0 || configuration > 7) return GT_BAD_ARGUMENT;
    for (i = 0; i < 3; ++i) sg[i] = ((configuration >> i) & 1) ? 1.0 : -1.0;
    if (!isfinite(s_dot_start) || !(s_dot_start >= 0.0)) return GT_BAD_ARGUMENT;
    if ((limits->viscous_friction != 0 && limits->viscous_friction != 1) || (limits->constrain_end != 0 && limits->constrain_end != 1)) {
        return GT_BAD_ARGUMENT;
    }
    /* the rows' bounds: |x| <= v for forces and accelerations (two one-sided rows), c b <= v^2
     * for velocities; INFINITY: no row (PathConstraints.bounds of the Python solver) */
@ROW_LIMITS@
    for (j = 0; j < @R@; ++j) {
        if (isnan(lim[j]) || !(lim[j] > 0.0)) return GT_BAD_ARGUMENT;
        if (!isfinite(lim[j])) continue;
        ++finite_limits;
        hi_rows[nhi++] = j;
        bound_hi[j] = @P@_retime_squared[j] ? lim[j] * lim[j] : lim[j];
        bound_lo[j] = -lim[j];
    }
    if (finite_limits == 0) return GT_BAD_ARGUMENT;
    for (i = 0; i < nhi; ++i) {
        if (!@P@_retime_squared[hi_rows[i]]) lo_rows[nlo++] = hi_rows[i];
    }
    M = nhi + nlo;
    N = n - 1;
    for (k = 0; k < n; ++k) {
        if (!isfinite(s[k]) || (k > 0 && !(s[k] > s[k - 1]))) {
            if (info != NULL) info->index = k;
            return GT_BAD_ARGUMENT;
        }
        nonfinite = 0.0;
        for (i = 0; i < 3; ++i) nonfinite += 0.0 * T[3 * k + i] + 0.0 * dT[3 * k + i] + 0.0 * ddT[3 * k + i];
        if (nonfinite != 0.0) {
            if (info != NULL) info->index = k;
            return GT_BAD_ARGUMENT;
        }
    }
    /* the rows at every grid point, from the generated coefficients; the stage sets */
    for (k = 0; k < n; ++k) {
        double *pk = work->p + (long)k * M, *rk = work->r + (long)k * M, *wk = work->w + (long)k * M, *ek = work->e + (long)k * M;
        for (i = 0; i < @U@_RETIME_SZ_ARG; ++i) arg[i] = NULL;
        for (i = 0; i < @U@_RETIME_SZ_RES; ++i) res[i] = NULL;
        arg[0] = T + 3 * k;
        arg[1] = dT + 3 * k;
        arg[2] = ddT + 3 * k;
        arg[3] = sg;
        res[0] = cm;
        res[1] = cc;
        res[2] = cd;
        res[3] = cg;
        res[4] = q;
        res[5] = disc;
        res[6] = cs;
        flag = @P@_cg_retime_rows(arg, res, iw, w, 0);
        if (flag != 0) {
            if (info != NULL) info->index = k;
            return GT_NUMERIC_ERROR;
        }
        for (i = 0; i < 3; ++i) { /* the workspace (PathConstrainedProblem._check_reach) */
            if (!(disc[i] >= 0.0) || !(q[i] >= @P@_retime_travel[i][0]) || !(q[i] <= @P@_retime_travel[i][1])
                || !(fabs(cs[i]) >= @U@_RETIME_COS_JOINT_MAX)) {
                if (info != NULL) info->index = k;
                return GT_UNREACHABLE;
            }
        }
        for (i = 0; i < 3; ++i) {
            if (!(fabs(cs[i]) >= @U@_SINGULARITY_TOLERANCE)) {
                if (info != NULL) info->index = k;
                return GT_SINGULAR;
            }
        }
        nonfinite = 0.0; /* 0 * x is 0 for a finite x, NaN for an infinite or NaN one */
        for (j = 0; j < @R@; ++j) nonfinite += 0.0 * cm[j] + 0.0 * cc[j] + 0.0 * cd[j] + 0.0 * cg[j];
        if (nonfinite != 0.0) {
            if (info != NULL) info->index = k;
            return GT_NUMERIC_ERROR;
        }
        if (!limits->viscous_friction) {
            for (j = 0; j < @R@; ++j) cd[j] = 0.0;
        }
        for (i = 0; i < nhi; ++i) { /* m a + c b + d sqrt(b) + g - hi <= 0 */
            j = hi_rows[i];
            pk[i] = cm[j];
            rk[i] = cc[j];
            wk[i] = cd[j];
            ek[i] = cg[j] - bound_hi[j];
        }
        for (i = 0; i < nlo; ++i) { /* lo - (m a + c b + d sqrt(b) + g) <= 0 */
            j = lo_rows[i];
            pk[nhi + i] = -cm[j];
            rk[nhi + i] = -cc[j];
            wk[nhi + i] = -cd[j];
            ek[nhi + i] = bound_lo[j] - cg[j];
        }
        if (k == N) { /* rows with a: at the last point on a_{N-1} with b_N = 0 (constrain_end), else dropped */
            for (i = 0; i < M; ++i) {
                work->p_end[i] = 0.0;
                work->e_end[i] = -1.0;
                if (pk[i] != 0.0) {
                    if (limits->constrain_end) {
                        work->p_end[i] = pk[i];
                        work->e_end[i] = ek[i];
                    }
                    pk[i] = 0.0;
                    rk[i] = 0.0;
                    wk[i] = 0.0;
                    ek[i] = -1.0;
                }
            }
        }
        work->rest[k] = (unsigned char)(k == N || (k == 0 && s_dot_start == 0.0) || (k > 0 && rest != NULL && rest[k] != 0));
        @P@_retime_stage(pk, rk, wk, ek, M, &work->s_lo[k], &work->s_hi[k], &work->hull[k], &nsplit);
        splits += nsplit;
    }
    /* empty stage sets, rest points that need s_dot > 0 */
    for (k = 0; k < n; ++k) {
        const double tol = @U@_RETIME_EMPTY_TOLERANCE * @U@_RETIME_AT_LEAST_1(isfinite(work->s_hi[k]) ? fabs(work->s_hi[k]) : 0.0);
        if (work->s_lo[k] > work->s_hi[k] + tol || (work->rest[k] && work->s_lo[k] > tol)) {
            if (info != NULL) info->index = k;
            return GT_INFEASIBLE;
        }
    }
    for (k = 0; k < N; ++k) { /* leaving rest needs s_ddot > 0 there */
        const double *pk = work->p + (long)k * M, *ek = work->e + (long)k * M;
        int any = 0;
        double amin = INFINITY;
        if (!work->rest[k]) continue;
        for (i = 0; i < M; ++i) {
            if (!(pk[i] > 0.0)) continue;
            v = -ek[i] / pk[i];
            if (!any || v < amin) amin = v;
            any = 1;
        }
        if (any && amin <= 0.0) {
            if (info != NULL) info->index = k;
            return GT_INFEASIBLE;
        }
    }
    for (k = 0; k < n; ++k) {
        if (work->s_lo[k] < 0.0) work->s_lo[k] = 0.0;
        if (work->rest[k]) work->s_hi[k] = 0.0;
        if (work->s_hi[k] < work->s_lo[k]) work->s_lo[k] = work->s_hi[k];
    }
    /* backward pass: K_k from K_{k+1}; row i with the reach constraint klo <= b + 2 ds a (p > 0)
     * or b + 2 ds a <= khi (p < 0), a eliminated: P b + Q sqrt(b) + R <= 0 */
    work->k_lo[N] = 0.0;
    work->k_hi[N] = 0.0;
    for (k = N - 1; k >= 0; --k) {
        const double *pk = work->p + (long)k * M, *rk = work->r + (long)k * M, *wk = work->w + (long)k * M, *ek = work->e + (long)k * M;
        int upper = 0;
        double ups[@U@_RETIME_SIDES];
        td = 2.0 * (s[k + 1] - s[k]);
        klo = work->k_lo[k + 1];
        khi = work->k_hi[k + 1];
        lo = work->s_lo[k];
        hi = work->s_hi[k];
        hull = work->hull[k];
        for (i = 0; i < M; ++i) {
            const double pa = pk[i];
            double Pb, Qb, Eb, al, be;
            if (pa == 0.0) continue;
            Pb = td * rk[i] - pa;
            Qb = td * wk[i];
            Eb = td * ek[i];
            if (Qb != 0.0) { /* quadratic in sqrt(b) */
                @P@_retime_interval(Pb, Qb, Eb + pa * (pa > 0.0 ? klo : khi), &l2, &h2, &b2);
                if (l2 > lo) lo = l2;
                if (h2 < hi) hi = h2;
                if (b2 < INFINITY) ups[upper++] = b2;
                else if (h2 < hull) hull = h2;
            } else if (Pb == 0.0) {
                if (Eb + pa * (pa > 0.0 ? klo : khi) > 0.0) {
                    lo = INFINITY;
                    hi = -INFINITY;
                }
            } else {
                al = -Eb / Pb;
                be = -pa / Pb;
                v = al + be * (pa > 0.0 ? klo : khi);
                if (Pb > 0.0) {
                    if (v < hi) hi = v;
                } else if (v > lo) {
                    lo = v;
                }
            }
        }
        for (i = 0; i < upper; ++i) splits += ups[i] <= fmin(hull, hi < INFINITY ? hi : hull);
        if (k == N - 1) { /* rows at the last grid point on a_{N-1} = (b_N - b_{N-1}) / (2 ds), b_N = 0 */
            for (i = 0; i < M; ++i) {
                if (work->p_end[i] == 0.0) continue;
                v = td * work->e_end[i] / work->p_end[i];
                if (work->p_end[i] > 0.0) {
                    if (v > lo) lo = v;
                } else if (v < hi) {
                    hi = v;
                }
            }
        }
        if (lo > hi) {
            if (lo > hi + @U@_RETIME_EMPTY_TOLERANCE * @U@_RETIME_AT_LEAST_1(fabs(hi))) {
                if (info != NULL) info->index = k;
                return GT_INFEASIBLE;
            }
            lo = hi;
        }
        work->k_lo[k] = lo;
        work->k_hi[k] = hi;
    }
    /* the start state must be controllable */
    b0 = s_dot_start * s_dot_start;
    if (b0 > work->k_hi[0] + @U@_RETIME_EMPTY_TOLERANCE * @U@_RETIME_AT_LEAST_1(fabs(work->k_hi[0])) || b0 < work->k_lo[0] - @U@_RETIME_EMPTY_TOLERANCE * @U@_RETIME_AT_LEAST_1(fabs(work->k_lo[0]))) {
        if (info != NULL) info->index = 0;
        return GT_INFEASIBLE;
    }
    /* forward pass: the largest b_{k+1} in K_{k+1} reachable with a <= -(r b + w sqrt(b) + e) / p */
    bk = b0;
    work->b[0] = b0;
    for (k = 0; k < N; ++k) {
        const double *pk = work->p + (long)k * M;
        double *rk = work->r + (long)k * M, *wk = work->w + (long)k * M, *ek = work->e + (long)k * M;
        td = 2.0 * (s[k + 1] - s[k]);
        amax = INFINITY;
        x = sqrt(bk);
        for (i = 0; i < M; ++i) {
            if (!(pk[i] > 0.0)) continue;
            rk[i] /= pk[i]; /* kept for the certificate */
            wk[i] /= pk[i];
            ek[i] /= pk[i];
            v = -(rk[i] * bk + wk[i] * x + ek[i]);
            if (v < amax) amax = v;
        }
        bn = bk + td * amax;
        if (bn > work->k_hi[k + 1]) bn = work->k_hi[k + 1];
        if (bn < work->k_lo[k + 1]) bn = work->k_lo[k + 1];
        work->a[k] = (bn - bk) / td;
        work->b[k + 1] = bn;
        bk = bn;
    }
    /* the duration (b piecewise linear: dt = 2 ds / (s_dot_k + s_dot_k+1)) */
    for (k = 0; k < n; ++k) work->s_lo[k] = sqrt(work->b[k] > 0.0 ? work->b[k] : 0.0); /* s_dot (s_lo is free now) */
    t = 0.0;
    for (k = 0; k < N; ++k) {
        const double dt = 2.0 * (s[k + 1] - s[k]) / (work->s_lo[k] + work->s_lo[k + 1]);
        if (!isfinite(dt) || !isfinite(work->a[k])) { /* s_dot zero at both ends of an interval */
            if (info != NULL) info->index = k;
            return GT_INFEASIBLE;
        }
        t += dt;
    }
    for (k = 0; k < N; ++k) uncertified += !@P@_retime_certified(work, k, M, 2.0 * (s[k + 1] - s[k]));
    for (k = 0; k < n; ++k) s_dot[k] = work->s_lo[k];
    if (s_dot_start > 0.0) s_dot[0] = s_dot_start;
    if (s_ddot != NULL) {
        for (k = 0; k < N; ++k) s_ddot[k] = work->a[k];
        s_ddot[N] = work->a[N - 1];
    }
    if (info != NULL) {
        info->final_time = t;
        info->uncertified = uncertified;
        info->splits = splits;
    }
    return GT_OK;
}
