/*@template (stripped when filled: gtmodel.codegen.emit.fill)
 * Header part of the lead-through controller step: sizes, the state struct, _init, _update.
 * Markers: @PREFIX@ the C prefix, @M@ its upper case, @REAL@ the floating-point type.
 */
/* Sizes of the lead-through controller (Dressler (2012), ch. 8): state, wrench, twist. */
#define @M@_LEAD_THROUGH_NX 8
#define @M@_LEAD_THROUGH_NW 6
/* State of the lead-through controller, owned by the caller (stack, static or in a bigger struct; no heap). */
typedef struct @PREFIX@_lead_through_state {
    @REAL@ x[8]; /* handle velocity V_h (6), contact flag, release flag */
} @PREFIX@_lead_through_state;

/*
 * Set the controller at rest, not in contact (all zeros).
 * Returns GT_OK, or GT_BAD_ARGUMENT (state NULL).
 */
int @PREFIX@_lead_through_init(@PREFIX@_lead_through_state *state);

/*
 * One 4 ms step on the state: @PREFIX@_lead_through_step(state->x, F_h, F_t, n_n, ...).
 * The state, V_tool and n are written only when GT_OK is returned. Returns GT_OK or
 * GT_BAD_ARGUMENT (a NULL pointer, a NaN/Inf wrench or state, n_n not of unit norm).
 */
int @PREFIX@_lead_through_update(@PREFIX@_lead_through_state *state, const @REAL@ F_h[6], const @REAL@ F_t[6],
                                 const @REAL@ n_n[3], @REAL@ V_tool[6], @REAL@ n[3]);
