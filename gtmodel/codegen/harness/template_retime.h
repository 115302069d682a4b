/*@template (stripped when filled: gtmodel.codegen.emit.fill)
 * Header part of the online re-timing function <prefix>_retime (after the limits struct).
 * Markers: @P@ the prefix, @U@ its upper case, @STACK@ the stack use [bytes].
 */

/* Work memory of @P@_retime, owned by the caller (static, global or part of a bigger
 * struct; it is too large for most stacks): sizeof(@P@_retime_work) bytes, fixed at
 * generation by @U@_RETIME_N_MAX. Nothing in it needs initialising; it holds no result
 * between calls (each call overwrites what it uses). */
typedef struct @P@_retime_work {
    double p[@U@_RETIME_N_MAX * @U@_RETIME_SIDES]; /* one-sided rows p a + r b + w sqrt(b) + e <= 0 per grid point */
    double r[@U@_RETIME_N_MAX * @U@_RETIME_SIDES];
    double w[@U@_RETIME_N_MAX * @U@_RETIME_SIDES];
    double e[@U@_RETIME_N_MAX * @U@_RETIME_SIDES];
    double p_end[@U@_RETIME_SIDES], e_end[@U@_RETIME_SIDES]; /* rows on the last interval's s_ddot at the last point */
    double s_lo[@U@_RETIME_N_MAX], s_hi[@U@_RETIME_N_MAX], hull[@U@_RETIME_N_MAX]; /* stage sets of b = s_dot^2 */
    double k_lo[@U@_RETIME_N_MAX], k_hi[@U@_RETIME_N_MAX]; /* controllable sets (backward pass) */
    double b[@U@_RETIME_N_MAX], a[@U@_RETIME_N_MAX]; /* the profile (forward pass) */
    unsigned char rest[@U@_RETIME_N_MAX];
} @P@_retime_work;

/* What a re-timing found besides the profile. */
typedef struct @P@_retime_info {
    double final_time; /* duration of the re-timed motion [s] (GT_OK; else 0) */
    int index;         /* grid point where the path fails (GT_INFEASIBLE, GT_UNREACHABLE, GT_SINGULAR,
                          GT_NUMERIC_ERROR, a bad sample: GT_BAD_ARGUMENT), else -1 */
    int uncertified;   /* grid steps where the greedy forward step is not proven optimal (0: the profile
                          is the exact optimum of the gridded problem; else feasible, possibly slower) */
    int splits;        /* stages where a viscous-friction set split in two and the part containing
                          rest was kept (an inner approximation) */
} @P@_retime_info;

/* sizeof(@P@_retime_work) in bytes (for a check of the layout from another language). */
unsigned long @P@_retime_work_bytes(void);

/* Set every limit to INFINITY (no limit), viscous_friction = 1, constrain_end = 1.
 * Returns GT_OK, or GT_BAD_ARGUMENT (limits NULL). */
int @P@_retime_limits_init(@P@_retime_limits *limits);

/*
 * Time-optimal s_dot(s) along a sampled path, from the current state to rest at the end:
 * the two-pass reachability method (Pham & Pham (2018), TOPP-RA) on the convex
 * reformulation of Verscheure et al. (2009), Dressler (2012), ch. 3.5, exactly as the
 * Python solver gtmodel.trajectory.PathConstrainedProblem.solve computes it (same grid,
 * same rows, same closed-form interval algebra: equal s_dot to rounding). With a = s_ddot
 * and b = s_dot^2 every limit is a row lo <= m a + c b + d sqrt(b) + g <= hi whose
 * coefficients come from the generated inverse dynamics and kinematics along the path
 * (eqs. 4.9, 6.5-6.8; Coulomb friction with the exact sign of q'(s), viscous friction kept
 * exactly); constraints hold at the grid points, a is constant on each interval. The
 * backward pass computes the sets of b from which the end is reachable at rest, the
 * forward pass takes the largest reachable b at every step.
 *
 * Inputs:
 *   n: number of grid points, 2 <= n <= @U@_RETIME_N_MAX (above: GT_TOO_LARGE).
 *   s[n]: the grid, strictly increasing (any range, e.g. the remaining part [s_now, 1]).
 *   T[3n], dT[3n], ddT[3n]: the path T(s), T'(s), T''(s) at the grid points [m], point k at
 *     index 3k (row-major n x 3). A corner of a polyline is a rest point (rest[k] = 1)
 *     with the outgoing tangent.
 *   rest[n] (may be NULL): 1 at interior grid points passed at rest (corners); rest[0]
 *     and rest[n-1] are ignored: the end is always at rest, the start at rest iff
 *     s_dot_start == 0.
 *   configuration: IK configuration 0-7 (as in @P@_ik).
 *   s_dot_start: s_dot at s[0] [1/s], >= 0 (0: start at rest). It must lie in the
 *     controllable set of s[0] (from it the end can be reached at rest within the limits),
 *     else GT_INFEASIBLE with index 0.
 *   limits: the limits (see @P@_retime_limits; INFINITY = none; at least one finite).
 *   work: the caller's work memory.
 * Outputs (written only when GT_OK is returned):
 *   s_dot[n]: time-optimal s_dot at the grid points [1/s] (s_dot[0] = s_dot_start).
 *   s_ddot[n] (may be NULL): s_ddot on [s_k, s_k+1) [1/s^2]; the last entry repeats the
 *     last interval's.
 *   info (may be NULL): written on every return (see @P@_retime_info).
 * Returns: GT_OK; GT_INFEASIBLE (no motion within the limits: info->index names the grid
 *   point); GT_UNREACHABLE / GT_SINGULAR (a grid point outside the workspace: an arm cannot
 *   reach it, cart travel or joint-angle limit / a singular configuration);
 *   GT_BAD_ARGUMENT (a NULL pointer, n < 2, a non-finite or non-increasing s, a non-finite
 *   sample, a limit that is NaN or not positive, no finite limit, s_dot_start negative or
 *   non-finite, viscous_friction or constrain_end not 0/1, a configuration outside 0-7);
 *   GT_TOO_LARGE (n > @U@_RETIME_N_MAX); GT_NUMERIC_ERROR (a non-finite coefficient).
 * Time: O(n) evaluations of the generated rows function and O(n) pass steps; no heap, no
 * static or global mutable state (reentrant with separate work memory). Stack use: about
 * @STACK@ bytes.
 */
int @P@_retime(int n, const double s[], const double T[], const double dT[], const double ddT[], const int rest[],
    int configuration, double s_dot_start, const @P@_retime_limits *limits, @P@_retime_work *work,
    double s_dot[], double s_ddot[], @P@_retime_info *info);
