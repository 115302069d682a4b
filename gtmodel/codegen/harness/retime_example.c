/* retime_example.c: online re-timing of the remaining path after a speed override.
 *
 * The TCP of the 3-link robot follows the straight line of problems/l1_path_constrained.toml
 * (from A to B, s in [0, 1]) under the actuator force limits |tau_i| <= 450 N and a TCP speed
 * limit ||T_dot|| <= override * V_MAX. A 4 ms loop plays the time-optimal motion; the
 * operator changes the speed override three times. At each change the controller calls
 * the generated <prefix>_retime on the REMAINING path, from the current state (s, s_dot),
 * with the new limits, inside the cycle, and continues on the new profile:
 *
 *   cycle   5: override 100 % -> 50 %  (still accelerating: the current state is admissible)
 *   cycle  60: override  50 % -> 100 %
 *   cycle 120: override 100 % -> 70 %  (at full speed the current state is above what the
 *              new limit allows at the current point: GT_INFEASIBLE at grid point 0; this
 *              controller keeps the profile and retries every cycle, so the override takes
 *              effect once the motion's own braking brings the state into the new
 *              controllable set. A real controller would ramp the override instead.)
 *
 * The profile between grid points: s_ddot constant per interval (exact for the re-timed
 * problem), sampled every 4 ms. Every cycle also computes the feedforward forces with the
 * generated inverse dynamics at the sampled state. The work memory of the re-timing is a
 * static struct (no heap); heap calls inside the loop are counted through the linker's
 * --wrap option (must be 0). Exit code 0 only if the first plan and every applied
 * re-timing returned GT_OK, each within the 4 ms period, s_dot is continuous at every
 * switch, the motion ends at s = 1 at rest, every inverse dynamics call is GT_OK and no heap
 * call happened.
 *
 * Build: see the Makefile (make RETIME=1000 retime-example; defines GT_HEADER, GT_PREFIX
 * and GT_MACRO, the upper-case prefix; the library generated with --retime-n-max).
 */
#define _POSIX_C_SOURCE 200112L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include GT_HEADER

#define CAT2(a, b) a##b
#define CAT(a, b) CAT2(a, b)
#define GT(fn) CAT(GT_PREFIX, CAT(_, fn))
#define GM(name) CAT(GT_MACRO, CAT(_, name))

#define N_GRID 500            /* grid points of the full path (as the shipped problem) */
#define PERIOD 0.004          /* control period [s] */
#define FORCE_LIMIT 450.0     /* N */
#define V_MAX 0.5             /* TCP speed at 100 % override [m/s] */
#define MAX_CYCLES 2000
#define N_EVENTS 3

#if N_GRID > GM(RETIME_N_MAX)
#error "retime_example.c: N_GRID exceeds the generated RETIME_N_MAX"
#endif

#include "heap_watch.h" /* heap-allocation counter (link with -Wl,--wrap=malloc,...) */

static const double A[3] = {-0.20, 2.75, -0.40}, B[3] = {0.20, 3.00, -0.60};

/* the caller-owned memory: the work struct of the re-timing and two profiles (the active one
 * and the next one, prepared by a re-timing) */
static GT(retime_work) work;
static double grid[N_GRID], Ts[3 * N_GRID], dTs[3 * N_GRID], ddTs[3 * N_GRID];
typedef struct profile {
    int n;
    double s[N_GRID], s_dot[N_GRID], s_ddot[N_GRID];
} profile;
static profile buffers[2];

/* CPU time of this thread [us]: the compute time of a call, without the preemptions of a
 * shared machine (as loop.c judges deadline misses) */
static double now_us(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec * 1e6 + (double)t.tv_nsec * 1e-3;
}

/* The remaining path from s0: s0, then the full grid's points beyond s0 + ds / 2; the line's
 * T(s) = A + s (B - A), T' = B - A, T'' = 0. Returns the number of points. */
static int remaining_path(double s0)
{
    int n = 0, k, i;
    const double ds = 1.0 / (double)(N_GRID - 1);
    grid[n++] = s0;
    for (k = 1; k < N_GRID - 1; ++k) {
        const double sk = (double)k * ds;
        if (sk > s0 + 0.5 * ds) grid[n++] = sk;
    }
    grid[n++] = 1.0;
    for (k = 0; k < n; ++k) {
        for (i = 0; i < 3; ++i) {
            Ts[3 * k + i] = A[i] + grid[k] * (B[i] - A[i]);
            dTs[3 * k + i] = B[i] - A[i];
            ddTs[3 * k + i] = 0.0;
        }
    }
    return n;
}

/* Re-time the remaining path from the state (s0, sd0) at the given override into *out.
 * Returns the status; *us the CPU time of the call. */
static int retime(double s0, double sd0, double override, profile *out, double *us, GT(retime_info) *info)
{
    GT(retime_limits) limits;
    int n, status, k;
    double t0;
    GT(retime_limits_init)(&limits);
    limits.force[0] = limits.force[1] = limits.force[2] = FORCE_LIMIT;
    limits.tcp_speed = override * V_MAX;
    t0 = now_us();
    n = remaining_path(s0);
    status = GT(retime)(n, grid, Ts, dTs, ddTs, NULL, 0, sd0, &limits, &work, out->s_dot, out->s_ddot, info);
    *us = now_us() - t0;
    if (status != GT_OK) return status;
    for (k = 0; k < n; ++k) out->s[k] = grid[k];
    out->n = n;
    return status;
}

int main(void)
{
    const int event_cycle[N_EVENTS] = {5, 60, 120};
    const double event_override[N_EVENTS] = {0.5, 1.0, 0.7};
    GT(retime_info) info;
    profile *active = &buffers[0], *next = &buffers[1], *swap;
    int status, cycle, j = 0, e = 0, pending = 0, next_at = -1, retimes = 0, infeasible = 0, failures = 0, bad_tau = 0, finished = 0;
    double us, max_us = 0.0, sum_us = 0.0, h = 0.0, s = 0.0, sd = 0.0, sdd = 0.0, max_jump = 0.0, max_tau = 0.0;
    double override = 1.0, pending_override = 1.0;

    printf("%s\n", GT(version)());
    printf("retime: N_MAX %d, grid %d points, work %lu bytes (static)\n", GM(RETIME_N_MAX), N_GRID, GT(retime_work_bytes)());
    status = retime(0.0, 0.0, override, active, &us, &info);
    printf("plan: override 100 %%: %s, %d points, duration %.4f s, %.0f us\n", GT(status_string)(status), active->n, info.final_time, us);
    if (status != GT_OK) return 1;
    heap_watch = 1;
    for (cycle = 1; cycle <= MAX_CYCLES && !finished; ++cycle) {
        double T[3], T_dot[3], T_ddot[3], tau[3];
        int i;
        /* advance the active profile by one period: interval j, time h into it; at the grid
         * point where a prepared profile starts, switch to it */
        h += PERIOD;
        for (;;) {
            const double dt = 2.0 * (active->s[j + 1] - active->s[j]) / (active->s_dot[j] + active->s_dot[j + 1]);
            if (h < dt) break;
            h -= dt;
            ++j;
            if (j == next_at) {
                if (fabs(next->s_dot[0] - active->s_dot[j]) > max_jump) max_jump = fabs(next->s_dot[0] - active->s_dot[j]);
                swap = active;
                active = next;
                next = swap;
                j = 0;
                next_at = -1;
            }
            if (j >= active->n - 1) {
                finished = 1;
                break;
            }
        }
        if (finished) {
            s = active->s[active->n - 1];
            sd = active->s_dot[active->n - 1];
            sdd = 0.0;
        } else {
            s = active->s[j] + active->s_dot[j] * h + 0.5 * active->s_ddot[j] * h * h;
            sd = active->s_dot[j] + active->s_ddot[j] * h;
            sdd = active->s_ddot[j];
            if (s > active->s[j + 1]) s = active->s[j + 1];
            if (sd < 0.0) sd = 0.0;
        }
        /* the speed override of the operator: re-time the remaining path from the next grid
         * point of the active profile (reached within the cycle or the next ones), so that
         * the new profile starts from a state the active one passes exactly */
        if (e < N_EVENTS && cycle == event_cycle[e]) {
            pending = 1;
            pending_override = event_override[e++];
            next_at = -1; /* a prepared, not yet started profile is superseded */
        }
        if (pending && !finished && j + 1 < active->n - 1) {
            status = retime(active->s[j + 1], active->s_dot[j + 1], pending_override, next, &us, &info);
            sum_us += us;
            if (us > max_us) max_us = us;
            if (status == GT_OK) {
                printf("cycle %d (t = %.3f s): override %.0f %% -> %.0f %%: GT_OK from s = %.4f, s_dot = %.4f 1/s, %d points, "
                       "remaining %.4f s, %.0f us%s\n", cycle, cycle * PERIOD, 100.0 * override, 100.0 * pending_override,
                       next->s[0], next->s_dot[0], next->n, info.final_time, us, pending > 1 ? " (after retrying every cycle)" : "");
                ++retimes;
                override = pending_override;
                pending = 0;
                next_at = j + 1;
            } else if (status == GT_INFEASIBLE) {
                if (pending == 1) {
                    printf("cycle %d (t = %.3f s): override %.0f %% -> %.0f %%: GT_INFEASIBLE at grid point %d from s = %.4f, "
                           "s_dot = %.4f 1/s (the speed is above what the new limits allow); profile kept, retrying every cycle\n",
                           cycle, cycle * PERIOD, 100.0 * override, 100.0 * pending_override, info.index, active->s[j + 1],
                           active->s_dot[j + 1]);
                }
                ++infeasible;
                pending = 2;
            } else {
                printf("cycle %d: re-timing failed: %s\n", cycle, GT(status_string)(status));
                ++failures;
                pending = 0;
            }
        }
        /* the feedforward of the cycle at the sampled state */
        for (i = 0; i < 3; ++i) {
            T[i] = A[i] + s * (B[i] - A[i]);
            T_dot[i] = (B[i] - A[i]) * sd;
            T_ddot[i] = (B[i] - A[i]) * sdd;
        }
        if (GT(inverse_dynamics)(T, T_dot, T_ddot, 0, tau) != GT_OK) {
            ++bad_tau;
            continue;
        }
        for (i = 0; i < 3; ++i) {
            if (fabs(tau[i]) > max_tau) max_tau = fabs(tau[i]);
        }
    }
    heap_watch = 0;
    printf("finished: %s at cycle %d (t = %.3f s), s = %.6f, s_dot = %.3g 1/s\n", finished ? "yes" : "no", cycle - 1,
           (cycle - 1) * PERIOD, s, sd);
    printf("re-timings applied %d, GT_INFEASIBLE %d, failed %d; CPU time max %.0f us, mean %.0f us per call (period %.0f us)\n",
           retimes, infeasible, failures, max_us, retimes + infeasible > 0 ? sum_us / (retimes + infeasible) : 0.0, PERIOD * 1e6);
    printf("largest s_dot jump at a switch %.3g 1/s\n", max_jump);
    printf("largest |tau| sampled every 4 ms %.1f N (limit %.0f N at the grid points)\n", max_tau, FORCE_LIMIT);
    printf("non-OK inverse dynamics %d\n", bad_tau);
    printf("heap allocations in the loop %ld\n", heap_calls);
    return (finished && fabs(s - 1.0) < 1e-12 && sd == 0.0 && retimes == N_EVENTS && failures == 0 && bad_tau == 0 && heap_calls == 0
            && max_us < PERIOD * 1e6 && max_jump == 0.0) ? 0 : 1;
}
