/*@template (stripped when filled: gtmodel.codegen.emit.fill)
 * Header part of one KF/EKF step of the tracker + IMU fusion: sizes, the state struct, _init, _update.
 * Markers: @PREFIX@ the C prefix, @NAME@ the step (kf_step, ekf_step), @STEM@ its stem (kf, ekf),
 * @STEM_U@ the stem in upper case, @M@ the macro prefix <PREFIX>_<STEM>, @ST@ the state struct,
 * @REAL@ the floating-point type, @NX@ @NZ@ @NX2@ @NPIVOTS@ the sizes.
 */
/* Sizes of the @STEM_U@ (Cvitanic (2021), ch. 4): state, measurement, pivots (S then P_next). */
#define @M@_NX @NX@
#define @M@_NZ @NZ@
#define @M@_NPIVOTS @NPIVOTS@
/* State of the @STEM_U@, owned by the caller (stack, static or in a bigger struct; no heap). */
typedef struct @ST@ {
    @REAL@ x[@NX@];  /* posterior mean x_{k|k} */
    @REAL@ P[@NX2@]; /* posterior covariance P_{k|k}, row-major @NX@x@NX@ */
} @ST@;

/*
 * Set the prior (x0, P0 row-major). Returns GT_OK, or GT_BAD_ARGUMENT (a NULL pointer,
 * a non-finite value; state untouched). A P0 that is not positive definite is reported
 * by the first update (GT_NUMERIC_ERROR).
 */
int @PREFIX@_@STEM@_init(@ST@ *state, const @REAL@ x0[@NX@], const @REAL@ P0[@NX2@]);

/*
 * One filter step on the state: @PREFIX@_@NAME@(state->x, state->P, z, ...). The state is
 * replaced only when GT_OK is returned. Returns GT_OK, GT_BAD_ARGUMENT (NULL pointer,
 * non-finite z or state), GT_NUMERIC_ERROR (covariance not positive definite or a
 * non-finite result).
 */
int @PREFIX@_@STEM@_update(@ST@ *state, const @REAL@ z[@NZ@]);

