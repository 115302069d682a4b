/* loop.c: a 4 ms control loop calling the generated 3-link model functions.
 *
 * Every cycle reads one sample of a trajectory table (trajectory.h, written by
 * `gtmodel solve problems/l1_time_optimal.toml`), computes the feedforward of
 * Dressler (2012), ch. 3.2: cart references by the inverse kinematics (eq. 4.9), the
 * Jacobian (eq. 6.5) and the actuator forces by the inverse dynamics (eqs. 6.7, 6.8),
 * and checks its timing with clock_gettime(CLOCK_MONOTONIC).
 *
 *   loop --mode measure  --cycles 100000   cycles back to back; a deadline miss is a cycle
 *                                          whose compute time (CPU time of the thread,
 *                                          CLOCK_THREAD_CPUTIME_ID) exceeds the period;
 *                                          cycles whose wall-clock time exceeds it only
 *                                          because the OS took the CPU away are counted
 *                                          and reported separately ("stalled cycles")
 *   loop --mode realtime --cycles 250      one cycle per period, clock_nanosleep(TIMER_ABSTIME);
 *                                          a miss is a cycle finishing after its deadline
 *   --period-us 4000                       the period [us]
 *
 * As a real controller would, the program asks for real-time scheduling (SCHED_FIFO,
 * priority 80) and locks its memory (mlockall) before the loop, and says whether it got
 * them; without them (no privilege) a preemption by another process longer than the
 * period counts as a deadline miss.
 *
 * The trajectory is replayed cyclically (sample k mod N). The TCP acceleration is the
 * central difference of the tabulated TCP velocity. Exit code 0 only if every call returned
 * GT_OK, no deadline was missed, the cart references equal the table's (IK of the same
 * model) within 1e-9 m and no heap allocation happened in the loop (calls to
 * malloc/calloc/realloc/free from this program and the generated library are counted
 * through the linker's --wrap option).
 *
 * With GT_CONTROLLER defined (make CONTROLLER=controller.json: the library generated with
 * `gtmodel codegen --controller`), every cycle also runs the controller side of
 * Dressler (2012), ch. 7: the learned ILC correction u_k of the cycle (k = the sample index
 * of the trial; 0 outside the table) added to the cart references, q_cmd = q + u_k
 * (actuator-side ILC, Case 1), and one step of the stationary Kalman filter on the
 * measurements [z_kin - T0; a_m] (deviations from the first sample T0; here the table's TCP
 * position and acceleration stand in for FK(q_m) and the accelerometer), its state in a
 * caller-owned struct; z_hat + T0 estimates the tool position. The controller needs
 * ILC_D = 3, KALMAN_NY = 6 and KALMAN_NZ = 3. The program then also prints the largest
 * |u_k| and |z_hat + T0 - T| (first pass of the table; the replay then jumps back to the
 * start, a step the filter follows with a lag), and the comparison of the cart references subtracts u_k.
 *
 * Build: see the Makefile (defines GT_HEADER, GT_PREFIX, TRAJ_HEADER, TRAJ_NAME; with a
 * controller also GT_CONTROLLER and GT_MACRO, the upper-case prefix of the header's macros).
 */
#define _POSIX_C_SOURCE 200112L
#include <math.h>
#include <sched.h>
#include <stdio.h>
#include <sys/mman.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include GT_HEADER
#include TRAJ_HEADER

#define CAT2(a, b) a##b
#define CAT(a, b) CAT2(a, b)
#define GT(fn) CAT(GT_PREFIX, CAT(_, fn))
#define TR(col) CAT(TRAJ_NAME, CAT(_, col))
#define TRAJ_LEN ((long)(sizeof(TR(t)) / sizeof(TR(t)[0])))

/* cart references must equal the table's (same model) within this [m] */
#define Q_TOLERANCE 1e-9

#ifdef GT_CONTROLLER
#define GM(name) CAT(GT_MACRO, CAT(_, name))
#if GM(ILC_D) != 3 || GM(KALMAN_NY) != 6 || GM(KALMAN_NZ) != 3
#error "loop.c: the controller must have ILC_D = 3, KALMAN_NY = 6 ([z_kin; a_m]) and KALMAN_NZ = 3"
#endif
#endif

#include "heap_watch.h" /* heap-allocation counter (link with -Wl,--wrap=malloc,...) */

static double ns_of(const struct timespec *t) { return (double)t->tv_sec * 1e9 + (double)t->tv_nsec; }

static void add_ns(struct timespec *t, long ns)
{
    t->tv_nsec += ns;
    while (t->tv_nsec >= 1000000000L) {
        t->tv_nsec -= 1000000000L;
        t->tv_sec += 1;
    }
}

int main(int argc, char **argv)
{
    long cycles = 100000, period_ns = 4000000L, k, misses = 0, stalls = 0, bad_status = 0;
    int realtime = 0, i, a;
    double max_ns = 0.0, sum_ns = 0.0, max_dq = 0.0, max_late = 0.0, max_cpu_ns = 0.0;
    double sink = 0.0;
#ifdef GT_CONTROLLER
    GT(kalman_state) kf; /* the filter state: caller-owned, on the stack */
    const double T0[3] = {TR(x)[0], TR(y)[0], TR(z)[0]};
    double max_u = 0.0, max_dz = 0.0;
#endif
    struct timespec next, t0, t1, c0, c1;
    const long n = TRAJ_LEN;
    const double dt = TR(t)[1] - TR(t)[0];

    for (a = 1; a < argc; ++a) {
        if (strcmp(argv[a], "--cycles") == 0 && a + 1 < argc) cycles = atol(argv[++a]);
        else if (strcmp(argv[a], "--period-us") == 0 && a + 1 < argc) period_ns = 1000L * atol(argv[++a]);
        else if (strcmp(argv[a], "--mode") == 0 && a + 1 < argc) realtime = strcmp(argv[++a], "realtime") == 0;
        else {
            fprintf(stderr, "usage: %s [--mode measure|realtime] [--cycles N] [--period-us P]\n", argv[0]);
            return 2;
        }
    }
    if (cycles < 1 || period_ns < 1) {
        fprintf(stderr, "loop: --cycles and --period-us must be positive\n");
        return 2;
    }
    {
        struct sched_param sp;
        int fifo, locked;
        memset(&sp, 0, sizeof sp);
        sp.sched_priority = 80;
        fifo = sched_setscheduler(0, SCHED_FIFO, &sp) == 0;
        locked = mlockall(MCL_CURRENT | MCL_FUTURE) == 0;
        printf("real-time scheduling SCHED_FIFO: %s; memory locked: %s\n", fifo ? "yes" : "no (not permitted)",
               locked ? "yes" : "no (not permitted)");
    }
    printf("%s\n", GT(version)());
    printf("trajectory: %ld samples, dt = %g s; mode %s, %ld cycles, period %ld us\n", n, dt,
           realtime ? "realtime" : "measure", cycles, period_ns / 1000L);
    fflush(stdout);

    {   /* warm-up call set, untimed (first-touch page faults, instruction caches) */
        const double T[3] = {TR(x)[0], TR(y)[0], TR(z)[0]}, zero[3] = {0.0, 0.0, 0.0};
        double q[3], J[9], tau[3];
        if ((GT(ik)(T, 0, q) | GT(jacobian)(T, 0, J) | GT(inverse_dynamics)(T, zero, zero, 0, tau)) != GT_OK) {
            printf("warm-up: the first trajectory sample gives a non-OK status\n");
        }
#ifdef GT_CONTROLLER
        {
            const double y[6] = {T[0], T[1], T[2], 0.0, 0.0, 0.0};
            double u[3], z_hat[3];
            if ((GT(ilc_correction)(0, u) | GT(kalman_init)(&kf, NULL) | GT(kalman_update)(&kf, y, z_hat)) != GT_OK) {
                printf("warm-up: the controller gives a non-OK status\n");
            }
        }
        /* the filter runs on deviations from the first sample, at rest there: state zero */
        if (GT(kalman_init)(&kf, NULL) != GT_OK) printf("kalman_init: non-OK status\n");
#endif
    }
    clock_gettime(CLOCK_MONOTONIC, &next);
    heap_watch = 1;
    for (k = 0; k < cycles; ++k) {
        const long s = k % n;
        const long sp = s + 1 < n ? s + 1 : s, sm = s > 0 ? s - 1 : s;
        double T[3], T_dot[3], T_ddot[3], q[3], J[9], tau[3];
#ifdef GT_CONTROLLER
        double u[3], y[6], z_hat[3];
#endif
        int status = 0;
        if (realtime) {
            add_ns(&next, period_ns);
            clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL);
        }
        if (!realtime) clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
        clock_gettime(CLOCK_MONOTONIC, &t0);
        /* --- the cycle: read references, IK + Jacobian + inverse dynamics --- */
        T[0] = TR(x)[s];
        T[1] = TR(y)[s];
        T[2] = TR(z)[s];
        T_dot[0] = TR(xd)[s];
        T_dot[1] = TR(yd)[s];
        T_dot[2] = TR(zd)[s];
        T_ddot[0] = (TR(xd)[sp] - TR(xd)[sm]) / ((double)(sp - sm) * dt + (sp == sm));
        T_ddot[1] = (TR(yd)[sp] - TR(yd)[sm]) / ((double)(sp - sm) * dt + (sp == sm));
        T_ddot[2] = (TR(zd)[sp] - TR(zd)[sm]) / ((double)(sp - sm) * dt + (sp == sm));
        status |= GT(ik)(T, 0, q);
        status |= GT(jacobian)(T, 0, J);
        status |= GT(inverse_dynamics)(T, T_dot, T_ddot, 0, tau);
#ifdef GT_CONTROLLER
        /* --- controller: ILC correction of cycle k of the trial, Kalman step --- */
        status |= GT(ilc_correction)((int)s, u);
        for (i = 0; i < 3; ++i) q[i] += u[i]; /* q_cmd = q_ff + u_k */
        for (i = 0; i < 3; ++i) {
            y[i] = T[i] - T0[i];  /* z_kin - T0: FK(q_m) - T0 on a robot */
            y[3 + i] = T_ddot[i]; /* a_m: the accelerometer on a robot */
        }
        status |= GT(kalman_update)(&kf, y, z_hat);
#endif
        clock_gettime(CLOCK_MONOTONIC, &t1);
        if (!realtime) clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
        /* --- bookkeeping (outside the timed part) --- */
        {
            const double c = ns_of(&t1) - ns_of(&t0);
            sum_ns += c;
            if (c > max_ns) max_ns = c;
            if (realtime) {
                const double late = ns_of(&t1) - (ns_of(&next) + (double)period_ns);
                if (late > 0.0) ++misses;
                if (late > max_late) max_late = late;
            } else {
                const double cpu = ns_of(&c1) - ns_of(&c0);
                if (cpu > max_cpu_ns) max_cpu_ns = cpu;
                if (cpu > (double)period_ns) ++misses;
                else if (c > (double)period_ns) ++stalls;
            }
        }
        if (status != GT_OK) {
            ++bad_status;
            continue;
        }
        {
            const double qt[3] = {TR(q1)[s], TR(q2)[s], TR(q3)[s]};
            for (i = 0; i < 3; ++i) {
#ifdef GT_CONTROLLER
                q[i] -= u[i]; /* compare the feedforward part */
                if (fabs(u[i]) > max_u) max_u = fabs(u[i]);
                if (k < n && fabs(z_hat[i] + T0[i] - T[i]) > max_dz) max_dz = fabs(z_hat[i] + T0[i] - T[i]);
                sink += z_hat[i];
#endif
                if (fabs(q[i] - qt[i]) > max_dq) max_dq = fabs(q[i] - qt[i]);
            }
        }
        sink += tau[0] + J[0];
    }
    heap_watch = 0;
    printf("cycles %ld\n", cycles);
    printf("deadline misses %ld\n", misses);
    printf("non-OK status %ld\n", bad_status);
    printf("compute time per cycle: mean %.0f ns, max %.0f ns (period %ld ns)\n", sum_ns / (double)cycles, max_ns, period_ns);
    if (realtime) printf("largest lateness after the deadline: %.0f ns\n", max_late);
    else printf("largest CPU time of a cycle %.0f ns; stalled cycles (wall clock > period, CPU time below) %ld\n",
                max_cpu_ns, stalls);
    printf("max |q - q_table| %.3g m\n", max_dq);
#ifdef GT_CONTROLLER
    printf("controller: ILC table %d cycles, max |u_k| %.3g m; Kalman max |z_hat + T0 - T| %.3g m (first pass)\n", GM(ILC_LENGTH), max_u, max_dz);
#endif
    printf("heap allocations in the loop %ld\n", heap_calls);
    if (!isfinite(sink)) printf("non-finite feedforward\n");
    return (misses == 0 && bad_status == 0 && max_dq <= Q_TOLERANCE && heap_calls == 0 && isfinite(sink)) ? 0 : 1;
}
