/*@template (stripped when filled: gtmodel.codegen.emit.fill)
 * The memory functions <prefix>_init and <prefix>_step of a loop controller (gtmodel.codegen.loop_step),
 * appended to the wrapper source. Markers: as template_loop_step.h, and @ULB@ @UUB@ @U0@ @W0@ the
 * C initialisers of the bounds, the first input and the inner memory, @CALL@ the call of the inner
 * step (arguments tt, x, mem->u_last, mem->w; outputs u_new, w_new).
 */

static const @REAL@ @GP@_u_lb[@NU@] = {@ULB@};
static const @REAL@ @GP@_u_ub[@NU@] = {@UUB@};
static const @REAL@ @GP@_u_init[@NU@] = {@U0@};
static const @REAL@ @GP@_w_init[@NW1@] = {@W0@};

static @REAL@ @GP@_clamp(@REAL@ v, int i)
{
    if (v < @GP@_u_lb[i]) return @GP@_u_lb[i];
    if (v > @GP@_u_ub[i]) return @GP@_u_ub[i];
    return v;
}

/* u = the last input, saturated (and kept as the last input). */
static void @GP@_safe_input(@GP@_memory *mem, @REAL@ *u)
{
    int i;
    for (i = 0; i < @NU@; ++i) {
        mem->u_last[i] = @GP@_clamp(isfinite(mem->u_last[i]) ? mem->u_last[i] : @GP@_clamp(@GP@_u_init[i], i), i);
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
    @REAL@ u_new[@NU@] = {0}, w_new[@NW1@] = {0}, tt[1];
    int i, status = GT_OK;
    if (mem == NULL || u == NULL) return GT_BAD_ARGUMENT;
    mem->steps += 1;
    if (x == NULL || !isfinite(t)) status = GT_BAD_ARGUMENT;
    for (i = 0; status == GT_OK && i < @NX@; ++i) {
        if (!isfinite(x[i])) status = GT_BAD_ARGUMENT;
    }
    if (status == GT_OK) {
        tt[0] = t;
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
    mem->status = GT_OK;
    return GT_OK;
}
