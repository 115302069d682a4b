/*@template (stripped when filled: gtmodel.codegen.emit.fill)
 * Wrapper source of one KF/EKF step: <prefix>_<stem>_init and <prefix>_<stem>_update.
 * Markers: as template_filter_state.h.
 */
int @PREFIX@_@STEM@_init(@ST@ *state, const @REAL@ x0[@NX@], const @REAL@ P0[@NX2@])
{
    int i;
    if (state == NULL || x0 == NULL || P0 == NULL) return GT_BAD_ARGUMENT;
    for (i = 0; i < @NX@; ++i) {
        if (!isfinite(x0[i])) return GT_BAD_ARGUMENT;
    }
    for (i = 0; i < @NX2@; ++i) {
        if (!isfinite(P0[i])) return GT_BAD_ARGUMENT;
    }
    for (i = 0; i < @NX@; ++i) state->x[i] = x0[i];
    for (i = 0; i < @NX2@; ++i) state->P[i] = P0[i];
    return GT_OK;
}

int @PREFIX@_@STEM@_update(@ST@ *state, const @REAL@ z[@NZ@])
{
    if (state == NULL) return GT_BAD_ARGUMENT;
    /* the step writes its outputs only on GT_OK (computed in its own work arrays first) */
    return @PREFIX@_@NAME@(state->x, state->P, z, state->x, state->P);
}

