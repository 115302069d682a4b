/*@template (stripped when filled: gtmodel.codegen.emit.fill)
 * The public header <prefix>.h of a loop controller (gtmodel.codegen.loop_step): the ONE step
 * interface of the controllers of the loop (tracking controller, MPC): a caller-owned memory
 * struct of static size, <prefix>_init and <prefix>_step.
 * Markers: @GP@ the C prefix, @P@ its upper case, @NAME@ the controller, @VERSION@, @REAL@,
 * @NX@ @NU@ the sizes, @NW@ the inner memory length (0: none), @NW1@ its array length (>= 1),
 * @DT@ the period; blocks: @DESCRIPTION@ (comment lines), @OPEN@ and @CLOSE@ (template_header_guard.h), @PROTOTYPES@.
 */
/* @GP@.h: C API of the loop controller @NAME@.
 *
@DESCRIPTION@
 * @VERSION@
 * Floating-point type: @REAL@
 *
 * Every function returns a status code (GT_OK = 0). No heap, no global state: the
 * controller's memory is the caller's @GP@_memory.
 */
@OPEN@

#define @P@_VERSION "@VERSION@"
#define @P@_NX @NX@
#define @P@_NU @NU@
#define @P@_NW @NW@
#define @P@_DT @DT@
typedef @REAL@ @GP@_real;

/* Version string: gtmodel and CasADi versions and the controller's hash. */
const char *@GP@_version(void);

/* Name of a status code, e.g. "GT_BAD_ARGUMENT" ("unknown" for others). */
const char *@GP@_status_string(int status);

/* Memory of the controller, owned by the caller (static size: stack, static or part of a
 * bigger struct; no heap). Set by @GP@_init, updated by @GP@_step. */
typedef struct @GP@_memory {
    @REAL@ u_last[@NU@]; /* the input of the last step, saturated: the safe input on failure */
    @REAL@ w[@NW1@];     /* the inner step's memory (e.g. an MPC's shifted warm start; unused if @P@_NW is 0) */
    long steps;          /* calls of @GP@_step since @GP@_init */
    int status;          /* status of the last @GP@_step */
} @GP@_memory;

/*
 * Reset the memory: u_last = the first input (saturated), w = its initial value.
 * Returns GT_OK, or GT_BAD_ARGUMENT (mem NULL).
 */
int @GP@_init(@GP@_memory *mem);

/*
 * One period of the loop: the input u[@P@_NU] at time t [s] from the measured state
 * x[@P@_NX], saturated at the input bounds. Returns GT_OK with u written; on any other
 * status u holds the safe input (the last input, saturated) unless u or mem is NULL:
 * GT_BAD_ARGUMENT (a NULL pointer, a non-finite t or x), GT_NUMERIC_ERROR (a non-finite
 * result), or the inner step's failure status (e.g. GT_NOT_CONVERGED).
 */
int @GP@_step(@GP@_memory *mem, @REAL@ t, const @REAL@ *x, @REAL@ *u);

@PROTOTYPES@
@CLOSE@
