/*@template (stripped when filled: gtmodel.codegen.emit.fill)
 * Wrapper source of the lead-through state functions <prefix>_lead_through_init and _update.
 * Markers: as template_lead_through_state.h.
 */
int @PREFIX@_lead_through_init(@PREFIX@_lead_through_state *state)
{
    int i;
    if (state == NULL) return GT_BAD_ARGUMENT;
    for (i = 0; i < 8; ++i) state->x[i] = (@REAL@)0;
    return GT_OK;
}

int @PREFIX@_lead_through_update(@PREFIX@_lead_through_state *state, const @REAL@ F_h[6], const @REAL@ F_t[6],
                                 const @REAL@ n_n[3], @REAL@ V_tool[6], @REAL@ n[3])
{
    if (state == NULL) return GT_BAD_ARGUMENT;
    /* the step writes its outputs only on GT_OK (computed in its own work arrays first) */
    return @PREFIX@_lead_through_step(state->x, F_h, F_t, n_n, state->x, V_tool, n);
}
