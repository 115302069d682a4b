/*@template (stripped when filled: gtmodel.codegen.emit.fill)
 * The memory functions <prefix>_init and <prefix>_step of a loop controller (gtmodel.codegen.loop_step),
 * appended to the wrapper source. Markers: as template_loop_step.h, and @ULB@ @UUB@ @U0@ @W0@ the
 * C initialisers of the bounds, the first input and the inner memory, @XLO@ @XHI@ the plausible
 * measurement, @ULO@ @UHI@ @WLO@ @WHI@ the plausible memory, @CALL@ the call of the inner step
 * (arguments tt, x, mem->u_last, mem->w; outputs u_new, w_new), @RESET@ the call of the memory
 * reset at (tt, x) into mem->u_last (and mem->w), @PREDICT@ the call of the prediction from
 * (mem->u_last, mem->w) into x_hat; each a status other than GT_OK when there is none.
 */

static const @REAL@ @GP@_u_lb[@NU@] = {@ULB@};
static const @REAL@ @GP@_u_ub[@NU@] = {@UUB@};
static const @REAL@ @GP@_u_init[@NU@] = {@U0@};
static const @REAL@ @GP@_w_init[@NW1@] = {@W0@};
static const @REAL@ @GP@_x_lo[@NX@] = {@XLO@};
static const @REAL@ @GP@_x_hi[@NX@] = {@XHI@};
static const @REAL@ @GP@_u_lo[@NU@] = {@ULO@};
static const @REAL@ @GP@_u_hi[@NU@] = {@UHI@};
static const @REAL@ @GP@_w_lo[@NW1@] = {@WLO@};
static const @REAL@ @GP@_w_hi[@NW1@] = {@WHI@};

static @REAL@ @GP@_clamp(@REAL@ v, int i)
{
    if (v < @GP@_u_lb[i]) return @GP@_u_lb[i];
    if (v > @GP@_u_ub[i]) return @GP@_u_ub[i];
    return v;
}

/* 1 when every v[i] is in [lo[i], hi[i]] (NaN is not). */
static int @GP@_within(const @REAL@ *v, const @REAL@ *lo, const @REAL@ *hi, int n)
{
    int i;
    for (i = 0; i < n; ++i) {
        if (!(v[i] >= lo[i] && v[i] <= hi[i])) return 0;
    }
    return 1;
}

/* u = the last input, saturated (and kept as the last input; the first input if it is not plausible). */
static void @GP@_safe_input(@GP@_memory *mem, @REAL@ *u)
{
    int i;
    for (i = 0; i < @NU@; ++i) {
        mem->u_last[i] = @GP@_clamp(@GP@_within(&mem->u_last[i], &@GP@_u_lo[i], &@GP@_u_hi[i], 1) ? mem->u_last[i] : @GP@_u_init[i], i);
        u[i] = mem->u_last[i];
    }
}

int @GP@_init(@GP@_memory *mem)
{
    int i;
    if (mem == NULL) return GT_BAD_ARGUMENT;
    for (i = 0; i < @NU@; ++i) mem->u_last[i] = @GP@_clamp(@GP@_u_init[i], i);
    for (i = 0; i < @NW1@; ++i) mem->w[i] = @GP@_w_init[i];
    mem->steps = 0;
    mem->status = GT_OK;
    return GT_OK;
}

int @GP@_step(@GP@_memory *mem, @REAL@ t, const @REAL@ *x, @REAL@ *u)
{
    @REAL@ u_new[@NU@] = {0}, w_new[@NW1@] = {0}, tt[1], x_hat[@NX@] = {0};
    int i, reset = 0, rejected = 0, status = GT_OK;
    if (mem == NULL || u == NULL) return GT_BAD_ARGUMENT;
    mem->steps += 1;
    tt[0] = t;
    if (x == NULL || !isfinite(t)) status = GT_BAD_ARGUMENT;
    else if (!@GP@_within(x, @GP@_x_lo, @GP@_x_hi, @NX@)) rejected = 1; /* a non-finite or absurd measurement */
    if (status == GT_OK && !(@GP@_within(mem->u_last, @GP@_u_lo, @GP@_u_hi, @NU@) && @GP@_within(mem->w, @GP@_w_lo, @GP@_w_hi, @NW@))) {
        if (rejected) {
            status = GT_BAD_ARGUMENT; /* neither the measurement nor the memory: reset at the next valid measurement */
        } else { /* a non-finite or absurd memory: reset to the reference's at t (as _init at the first period) */
            reset = 1;
            if (@RESET@ != GT_OK) {
                for (i = 0; i < @NU@; ++i) mem->u_last[i] = @GP@_u_init[i];
                for (i = 0; i < @NW1@; ++i) mem->w[i] = @GP@_w_init[i];
            }
            for (i = 0; i < @NU@; ++i) mem->u_last[i] = @GP@_clamp(mem->u_last[i], i);
        }
    }
    if (status == GT_OK && rejected) { /* the state the memory predicts replaces the measurement, if there is one */
        if (@PREDICT@ == GT_OK && @GP@_within(x_hat, @GP@_x_lo, @GP@_x_hi, @NX@)) x = x_hat;
        else status = GT_BAD_ARGUMENT;
    }
    if (status == GT_OK) status = @CALL@;
    if (status == GT_OK && !rejected && !reset && !@GP@_within(w_new, @GP@_w_lo, @GP@_w_hi, @NW@)
        && @PREDICT@ == GT_OK && @GP@_within(x_hat, @GP@_x_lo, @GP@_x_hi, @NX@)) {
        /* a measurement that drives the memory absurd is absurd too: the prediction replaces it */
        rejected = 1;
        x = x_hat;
        status = @CALL@;
    }
    for (i = 0; status == GT_OK && i < @NU@; ++i) {
        if (!isfinite(u_new[i])) status = GT_NUMERIC_ERROR;
    }
    if (status != GT_OK) {
        @GP@_safe_input(mem, u);
        mem->status = status;
        return status;
    }
    for (i = 0; i < @NU@; ++i) {
        mem->u_last[i] = @GP@_clamp(u_new[i], i);
        u[i] = mem->u_last[i];
    }
    for (i = 0; i < @NW@; ++i) mem->w[i] = w_new[i];
    (void)w_new;
    status = reset ? GT_MEMORY_RESET : rejected ? GT_MEASUREMENT_REJECTED : GT_OK;
    mem->status = status;
    return status;
}
