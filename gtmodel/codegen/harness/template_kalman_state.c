/*@template (stripped when filled: gtmodel.codegen.emit.fill)
 * Wrapper source of the Kalman state functions <prefix>_kalman_init and <prefix>_kalman_update.
 * Markers: as template_kalman_state.h.
 */
int @PREFIX@_kalman_init(@PREFIX@_kalman_state *state, const @REAL@ x0[@NX@])
{
    int i;
    if (state == NULL) return GT_BAD_ARGUMENT;
    if (x0 != NULL) {
        for (i = 0; i < @NX@; ++i) {
            if (!isfinite(x0[i])) return GT_BAD_ARGUMENT;
        }
    }
    for (i = 0; i < @NX@; ++i) state->x[i] = x0 != NULL ? x0[i] : (@REAL@)0;
    return GT_OK;
}

int @PREFIX@_kalman_update(@PREFIX@_kalman_state *state, const @REAL@ y[@NY@], @REAL@ z_hat[@NZ@])
{
    @REAL@ x_next[@NX@];
    int i, status;
    if (state == NULL) return GT_BAD_ARGUMENT;
    status = @PREFIX@_kalman_step(state->x, y, x_next, z_hat);
    if (status != GT_OK) return status;
    for (i = 0; i < @NX@; ++i) state->x[i] = x_next[i];
    return GT_OK;
}

