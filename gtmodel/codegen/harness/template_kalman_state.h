/*@template (stripped when filled: gtmodel.codegen.emit.fill)
 * Header part of the stationary Kalman step of the 4 ms loop: sizes, the state struct, _init, _update.
 * Markers: @PREFIX@ the C prefix, @M@ its upper case, @REAL@ the floating-point type, @NX@ @NY@ @NZ@ the sizes.
 */
/* Sizes of the Kalman filter: state, measurements [z_kin; a_m], tool position estimate. */
#define @M@_KALMAN_NX @NX@
#define @M@_KALMAN_NY @NY@
#define @M@_KALMAN_NZ @NZ@
/* State of the Kalman filter, owned by the caller (stack, static or in a bigger struct; no heap). */
typedef struct @PREFIX@_kalman_state {
    @REAL@ x[@NX@]; /* x_k, the layout of @PREFIX@_kalman_step's x */
} @PREFIX@_kalman_state;

/*
 * Set the filter state to x0 (NULL: zeros).
 * Returns GT_OK, or GT_BAD_ARGUMENT (state NULL or x0 non-finite; state untouched).
 */
int @PREFIX@_kalman_init(@PREFIX@_kalman_state *state, const @REAL@ x0[@NX@]);

/*
 * One cycle of the Kalman filter: @PREFIX@_kalman_step(state->x, y, x_next, z_hat), then
 * state->x = x_next. On any status other than GT_OK neither the state nor z_hat is
 * written. Returns GT_OK, GT_BAD_ARGUMENT (a NULL pointer, non-finite y or state),
 * GT_NUMERIC_ERROR.
 */
int @PREFIX@_kalman_update(@PREFIX@_kalman_state *state, const @REAL@ y[@NY@], @REAL@ z_hat[@NZ@]);

