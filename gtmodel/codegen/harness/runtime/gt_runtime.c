/* gt_runtime.c: gtmodel's robot runtime, the 4 ms loop behind KUKA RSI or ABB EGM over UDP.
 *
 * Built by gtmodel.codegen.robot_runtime.build_runtime with the generated loop step
 * (<prefix>.c, PREFIX_step) and gt_runtime_config.h (the interface, the field maps, the limits).
 *
 *   gt_runtime --out DIR [--listen HOST:PORT] [--sensor-port PORT] [--idle-timeout S]
 *              [--max-cycles N] [--reply-deadline S] [--no-realtime] [--exit-with-parent]
 *
 * The cycle (one thread, SCHED_FIFO and mlockall where permitted): receive a datagram from the
 * robot -> parse (gt_rsi.c / gt_egm.c; bounded, no heap) -> checks (finite, IPOC/seqno strictly
 * newer, every input field present, sensor sample not older than GT_RT_STALE_CYCLES cycles)
 * -> x from the fields -> PREFIX_step -> limits (lower/upper, then the rate per cycle around
 * the last reply: nothing changes a value after them; RSI's %.6f numbers are put on the 1e-6 grid
 * by moving from the last reply towards the limited value, never past it) -> compose -> sendto.
 *
 * Safety rules: a malformed or too long datagram gets no reply (nothing to echo); a non-finite
 * field, a duplicate or older IPOC/seqno, a missing input field: the held reply (the last
 * reply again), the step is not called; stale sensor data or a failed step (a status other
 * than GT_OK, GT_MEMORY_RESET, GT_MEASUREMENT_REJECTED): the fallback, hold (the last reply)
 * or ramp (towards zero for corrections: RSI and EGM path correction; towards the start value,
 * the robot's planned position in the first datagram, for EGM joint and Cartesian guidance)
 * at the rate limit. Relative RSI corrections: the runtime keeps the limited TOTAL correction
 * and sends its increment per cycle, so a robot that sums increments holds exactly the total.
 *
 * Deadline rule: just before sendto the time since the datagram was received is measured.
 * At most the reply deadline (default 2 ms of the 4 ms period): the computed reply. Beyond it
 * but within the period: the held reply (the last one again; a relative correction sends a
 * zero increment), counted deadline_held: it still reaches the robot within its cycle, so
 * RSI does not count it late, and only the step's output of that cycle is lost. At or beyond
 * the period: no reply (counted late_dropped); RSI counts that cycle late as it would count a
 * late reply, and the robot's own limit of consecutive late cycles then stops it, the safe end.
 * The reply that is held is composed in microseconds, so only a stall of the whole process
 * longer than a period (what SCHED_FIFO and mlockall guard against) costs a cycle.
 *
 * The cycle log (DIR/cycle_log.csv) is written by a second, ordinary thread from a
 * single-producer single-consumer ring (C11 atomics, no lock); an entry that finds the ring
 * full is dropped and counted. At exit DIR/runtime_stats.json holds the counts. Exit codes:
 * 0 a normal end (idle timeout, max cycles, SIGINT/SIGTERM), 2 bad arguments, 3 a setup error
 * (socket, bind, files, threads), each with one line on stderr.
 */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <errno.h>
#include <math.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif

#include "gt_runtime_config.h"
#include "gt_egm.h"
#include "gt_rsi.h"
#include "gt_sensor_stream.h"

/* flags of a log entry */
#define F_SENT 1u
#define F_STEP 2u
#define F_HELD 4u
#define F_FALLBACK_STALE 8u
#define F_FALLBACK_STEP 16u
#define F_RAMP 32u
#define F_MALFORMED 64u
#define F_NON_FINITE 128u
#define F_DUPLICATE_OR_OLD 256u
#define F_MISSING_FIELD 512u
#define F_DEADLINE_HELD 1024u
#define F_LATE_DROPPED 2048u
#define F_CLAMPED 4096u
#define F_NO_SAFE_REPLY 8192u
#define F_TOO_LONG 16384u

#define GT_RT_RING 8192u /* entries: 32 s of cycles at 4 ms; the writer drains every 5 ms */
#define GT_RT_MAX_DATAGRAM 4096
#define GT_RT_NSTATUS 32
#define GT_RT_CYCLE_STACK (1u << 20)  /* the step's CasADi work arrays live on it */
#define GT_RT_WRITER_STACK (256u << 10)

typedef struct {
    uint64_t cycle, seq;
    double t, latency_us;
    uint32_t flags;
    int32_t status, sensor_age;
    double x[GT_RT_NX], u[GT_RT_NU], y[GT_RT_NU], sent[GT_RT_NU];
} gt_rt_entry;

static gt_rt_entry gt_ring[GT_RT_RING];
static atomic_uint_fast64_t gt_ring_head, gt_ring_tail; /* head: producer (cycle), tail: consumer (writer) */
static atomic_int gt_stop, gt_cycle_done, gt_writer_stop;
static const char *gt_cycle_end; /* set by the cycle thread before gt_cycle_done, read by main after the join */

typedef struct {
    uint64_t packets, cycles, replies, malformed, too_long, non_finite, duplicate_or_old, missing_field, held;
    uint64_t fallback_stale, fallback_step, deadline_held, late_dropped, no_safe_reply, send_errors, compose_errors;
    uint64_t clamp_lower, clamp_upper, clamp_rate, step_calls, step_status[GT_RT_NSTATUS], step_status_other;
    uint64_t sensor_accepted, sensor_malformed, sensor_non_finite, sensor_old, sensor_short;
    uint64_t log_written, log_dropped, log_write_errors, first_seq, last_seq;
    double max_latency_us;
    int realtime_fifo, realtime_mlock;
    char realtime_reason[160];
    const char *end;
} gt_rt_stats;

static gt_rt_stats S;

static struct {
    char out[3072], log_path[4096], stats_path[4096], ready_path[4096];
    struct sockaddr_in listen, sensor;
    int sensor_port_given;
    double idle_timeout, reply_deadline;
    uint64_t max_cycles;
    int realtime;
} O;

static int gt_fd = -1, gt_sensor_fd = -1;
static FILE *gt_log_file;

static double gt_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void gt_fail(int code, const char *what, const char *detail)
{
    fprintf(stderr, "gt_runtime: %s%s%s\n", what, detail ? ": " : "", detail ? detail : "");
    exit(code);
}

/* ---- the log ring: producer side (the cycle), never blocks ---- */
static void gt_log_push(const gt_rt_entry *e)
{
    uint64_t head = atomic_load_explicit(&gt_ring_head, memory_order_relaxed);
    uint64_t tail = atomic_load_explicit(&gt_ring_tail, memory_order_acquire);
    if (head - tail >= GT_RT_RING) {
        ++S.log_dropped;
        return;
    }
    gt_ring[head % GT_RT_RING] = *e;
    atomic_store_explicit(&gt_ring_head, head + 1, memory_order_release);
}

static void gt_write_row(const gt_rt_entry *e)
{
    int i, bad = 0;
    bad |= fprintf(gt_log_file, "%llu,%llu,%.17g,%u,%d,%.17g,%d", (unsigned long long)e->cycle, (unsigned long long)e->seq, e->t,
                   (unsigned)e->flags, (int)e->status, e->latency_us, (int)e->sensor_age) < 0;
    for (i = 0; i < GT_RT_NX; ++i) bad |= fprintf(gt_log_file, ",%.17g", e->x[i]) < 0;
    for (i = 0; i < GT_RT_NU; ++i) bad |= fprintf(gt_log_file, ",%.17g", e->u[i]) < 0;
    for (i = 0; i < GT_RT_NU; ++i) bad |= fprintf(gt_log_file, ",%.17g", e->y[i]) < 0;
#if GT_RT_RELATIVE
    for (i = 0; i < GT_RT_NU; ++i) bad |= fprintf(gt_log_file, ",%.17g", e->sent[i]) < 0;
#endif
    bad |= fputc('\n', gt_log_file) == EOF;
    if (bad) ++S.log_write_errors;
    else ++S.log_written;
}

/* ---- the log writer: consumer side, an ordinary thread ---- */
static void *gt_writer(void *arg)
{
    (void)arg;
    for (;;) {
        uint64_t tail = atomic_load_explicit(&gt_ring_tail, memory_order_relaxed);
        uint64_t head = atomic_load_explicit(&gt_ring_head, memory_order_acquire);
        if (tail == head) {
            struct timespec ts = {0, 5000000};
            if (atomic_load(&gt_writer_stop) && tail == atomic_load_explicit(&gt_ring_head, memory_order_acquire)) break;
            fflush(gt_log_file);
            nanosleep(&ts, NULL);
            continue;
        }
        while (tail != head) {
            gt_write_row(&gt_ring[tail % GT_RT_RING]);
            ++tail;
            atomic_store_explicit(&gt_ring_tail, tail, memory_order_release);
        }
    }
    fflush(gt_log_file);
    return NULL;
}

/* ---- limits: [lower, upper] and |y - last| <= rate (the rate first when last is outside the bounds) ---- */
static double gt_limit(double v, double last, int i, uint32_t *flags)
{
    double lo = gt_rt_lower[i], hi = gt_rt_upper[i];
    double rlo = last - gt_rt_rate[i], rhi = last + gt_rt_rate[i];
    double y = v;
    if (rlo > lo) lo = rlo;
    if (rhi < hi) hi = rhi;
    if (lo > hi) { /* last outside the bounds by more than the rate: towards them at the rate */
        lo = hi = (last < gt_rt_lower[i]) ? rhi : rlo;
    }
    if (!(y >= lo)) { /* NaN too */
        if (y < gt_rt_lower[i]) ++S.clamp_lower;
        else ++S.clamp_rate;
        y = lo;
        *flags |= F_CLAMPED;
    } else if (y > hi) {
        if (y > gt_rt_upper[i]) ++S.clamp_upper;
        else ++S.clamp_rate;
        y = hi;
        *flags |= F_CLAMPED;
    }
    return y;
}

#if GT_RT_INTERFACE == GT_RT_RSI
/* RSI numbers travel as %.6f: the reply moves from the last one (on the 1e-6 grid, as the robot
 * holds it) towards y by whole micro-units, never past y, so that what the robot holds is exactly
 * the reply logged, a relative robot's sum of increments never drifts, and the limits hold for
 * the printed values too. */
static double gt_rsi_grid(double y, double last, int i)
{
    long long k = llround(last * 1e6); /* the last reply, on the grid */
    double d = (y - last) * 1e6;
    long long s = (long long)(d + (d > 0 ? 1e-6 : d < 0 ? -1e-6 : 0.0)); /* towards zero; noise of whole units forgiven */
    long long r = (long long)floor(gt_rt_rate[i] * 1e6 + 1e-6);           /* the limits in whole units */
    long long hi = (long long)floor(gt_rt_upper[i] * 1e6 + 1e-6) - k;
    long long lo = (long long)ceil(gt_rt_lower[i] * 1e6 - 1e-6) - k;
    if (s > r) s = r;
    if (s < -r) s = -r;
    if (s > hi) s = hi > 0 ? hi : 0;
    if (s < lo) s = lo < 0 ? lo : 0;
    return (double)(k + s) / 1e6;
}
#endif

/* the reply of a fallback: hold the last, or one rate step towards the target */
static void gt_fallback(const double *last, const double *target, double *y, uint32_t *flags)
{
    int i;
    for (i = 0; i < GT_RT_NU; ++i) {
#if GT_RT_RAMP
        double d = target[i] - last[i], r = gt_rt_rate[i];
        y[i] = last[i] + (d > r ? r : d < -r ? -r : d);
        *flags |= F_RAMP;
#else
        (void)target;
        (void)flags;
        y[i] = last[i];
#endif
    }
}

/* ---- the sensor stream (the cycle thread only): the newest valid sample and its age in robot cycles ---- */
static gt_sensor_sample gt_latest;
static int gt_have_sensor;
static uint64_t gt_sensor_seq;
static int32_t gt_sensor_age;

static void gt_drain_sensor(int32_t age_of_new)
{
    static char sbuf[GT_SENSOR_MAX_LEN + 1];
    static gt_sensor_sample sample;
    int k;
    if (gt_sensor_fd < 0) return;
    for (k = 0; k < 256; ++k) {
        ssize_t m = recv(gt_sensor_fd, sbuf, sizeof sbuf, MSG_DONTWAIT | MSG_TRUNC);
        int r;
        if (m < 0) break;
        r = gt_sensor_parse(sbuf, (size_t)m > GT_SENSOR_MAX_LEN ? GT_SENSOR_MAX_LEN + 1 : (size_t)m, &sample);
        if (r == GT_SENSOR_NON_FINITE) ++S.sensor_non_finite;
        else if (r != GT_SENSOR_OK) ++S.sensor_malformed;
        else if (gt_have_sensor && sample.seq <= gt_sensor_seq) ++S.sensor_old;
        else if (sample.n < GT_RT_NSENSOR) ++S.sensor_short;
        else {
            gt_latest = sample;
            gt_sensor_seq = sample.seq;
            gt_have_sensor = 1;
            gt_sensor_age = age_of_new;
            ++S.sensor_accepted;
        }
    }
}

/* ---- the cycle ---- */
static void *gt_cycle(void *arg)
{
    static unsigned char buf[GT_RT_MAX_DATAGRAM + 1];
    static unsigned char reply[GT_RT_MAX_DATAGRAM];
    static gt_rt_memory mem;
    static gt_rt_entry e;
    static double last[GT_RT_NU], target[GT_RT_NU], y[GT_RT_NU], field[64];
    static gt_rt_real xr[GT_RT_NX], ur[GT_RT_NU];
    int have_last = 0, have_seq = 0, have_t0 = 0;
    uint64_t last_seq = 0, seq0 = 0, cycles0 = 0;
    uint32_t tm0 = 0;
    double last_rx = 0.0, start = gt_now();
    (void)arg;
    gt_rt_step_init(&mem);
    while (!atomic_load(&gt_stop)) {
        struct pollfd pf[2];
        struct sockaddr_in from;
        socklen_t fromlen = sizeof from;
        ssize_t n;
        double t_rx, t = 0.0, elapsed;
        int i, code = 0, nfd = 1, present = 1, rlen = -1, stale = 0;
        uint64_t seq = 0, present_mask = 0;
        uint32_t flags = 0;
        uint32_t tm = 0;
        int has_tm = 0, has_orient = 0;
        double orient[4] = {0, 0, 0, 0};
        pf[0].fd = gt_fd;
        pf[0].events = POLLIN;
        if (gt_sensor_fd >= 0) {
            pf[1].fd = gt_sensor_fd;
            pf[1].events = POLLIN;
            nfd = 2;
        }
        if (poll(pf, (nfds_t)nfd, 20) < 0 && errno != EINTR) break;
        n = recvfrom(gt_fd, buf, sizeof buf, MSG_DONTWAIT | MSG_TRUNC, (struct sockaddr *)&from, &fromlen);
        if (n < 0) {
            gt_drain_sensor(-1); /* a sample between robot cycles: age 0 at the next one */
            if (have_seq && gt_now() - last_rx > O.idle_timeout) {
                gt_cycle_end = "idle_timeout";
                break;
            }
            continue;
        }
        t_rx = gt_now(); /* the reply latency runs from here: the datagram in the runtime's hands */
        last_rx = t_rx;
        ++S.packets;
        ++gt_sensor_age;
        gt_drain_sensor(0);
        memset(&e, 0, sizeof e);
        e.cycle = S.packets;
        for (i = 0; i < GT_RT_NX; ++i) e.x[i] = NAN;
        for (i = 0; i < GT_RT_NU; ++i) e.u[i] = e.y[i] = e.sent[i] = NAN;
        e.status = -1;
        e.sensor_age = gt_have_sensor ? gt_sensor_age : -1;
#if GT_RT_INTERFACE == GT_RT_RSI
        {
            static gt_rsi_rob rob;
            code = gt_rsi_parse((const char *)buf, (size_t)n > GT_RSI_MAX_LEN ? GT_RSI_MAX_LEN + 1 : (size_t)n, &rob);
            code = code == GT_RSI_OK ? 0 : code == GT_RSI_NON_FINITE ? 3 : code == GT_RSI_TOO_LONG ? 2 : 1;
            seq = rob.ipoc;
            present_mask = rob.present;
            memcpy(field, rob.field, sizeof rob.field);
        }
#else
        {
            static gt_egm_robot rob;
            code = gt_egm_parse(buf, (size_t)n > GT_EGM_MAX_LEN ? GT_EGM_MAX_LEN + 1 : (size_t)n, &rob);
            code = code == GT_EGM_OK ? 0 : code == GT_EGM_NON_FINITE ? 3 : code == GT_EGM_TOO_LONG ? 2 : 1;
            seq = rob.seqno;
            has_tm = rob.has_tm;
            tm = rob.tm;
            present_mask = rob.present;
            memcpy(field, rob.field, sizeof rob.field);
            has_orient = rob.has_orient;
            memcpy(orient, rob.orient, sizeof orient);
        }
#endif
        if (code == 1 || code == 2) { /* nothing to echo: no reply */
            if (code == 2) {
                ++S.too_long;
                flags |= F_TOO_LONG;
            }
            ++S.malformed;
            e.flags = flags | F_MALFORMED;
            e.latency_us = 1e6 * (gt_now() - t_rx);
            gt_log_push(&e);
            continue;
        }
        ++S.cycles;
        e.seq = seq;
        if (!have_seq) S.first_seq = seq;
        S.last_seq = seq;
        for (i = 0; i < GT_RT_NX; ++i) {
            int src = gt_rt_x_source[i];
            if (src >= 0) {
                if (!(present_mask & ((uint64_t)1 << src))) present = 0;
                e.x[i] = field[src];
            } else {
                e.x[i] = gt_have_sensor ? gt_latest.value[-1 - src] : NAN;
            }
        }
        if (code == 3) {
            ++S.non_finite;
            flags |= F_NON_FINITE;
        } else if (have_seq &&
#if GT_RT_INTERFACE == GT_RT_RSI
                   !(seq > last_seq)
#else
                   !((int32_t)((uint32_t)seq - (uint32_t)last_seq) > 0)
#endif
        ) {
            ++S.duplicate_or_old;
            flags |= F_DUPLICATE_OR_OLD;
        } else if (!present) {
            ++S.missing_field;
            flags |= F_MISSING_FIELD;
        }
        if (!have_seq || !(flags & F_DUPLICATE_OR_OLD)) {
            last_seq = seq;
            have_seq = 1;
        }
        if (!have_t0) {
            seq0 = seq;
            tm0 = tm;
            cycles0 = S.cycles;
            have_t0 = 1;
        }
#if GT_RT_INTERFACE == GT_RT_RSI
        t = (double)(int64_t)(seq - seq0) / 1000.0;
#else
        t = has_tm ? (double)(int32_t)(tm - tm0) / 1000.0 : (double)(S.cycles - cycles0) * GT_RT_PERIOD_S;
#endif
        (void)seq0; /* each interface uses some of these */
        (void)has_tm;
        (void)tm0;
        (void)cycles0;
        (void)start;
        e.t = t;
        if (!have_last) { /* the start: zero corrections, or the robot's planned position */
            int ok = 1;
            for (i = 0; i < GT_RT_NU; ++i) {
                int a = gt_rt_u_init[i], b = gt_rt_u_init2[i];
                double v = 0.0;
                if (a >= 0 && (present_mask & ((uint64_t)1 << a)) && isfinite(field[a])) v = field[a];
                else if (b >= 0 && (present_mask & ((uint64_t)1 << b)) && isfinite(field[b])) v = field[b];
                else if (a >= 0) ok = 0;
                last[i] = v;
                target[i] = gt_rt_u_init[i] >= 0 ? v : (0.0 < gt_rt_lower[i] ? gt_rt_lower[i] : 0.0 > gt_rt_upper[i] ? gt_rt_upper[i] : 0.0);
            }
            if (ok) {
                uint32_t dummy = 0;
                for (i = 0; i < GT_RT_NU; ++i) last[i] = target[i] = gt_limit(last[i], last[i], i, &dummy);
                have_last = 1;
            }
        }
        if (!have_last) {
            ++S.no_safe_reply;
            e.flags = flags | F_NO_SAFE_REPLY;
            e.latency_us = 1e6 * (gt_now() - t_rx);
            gt_log_push(&e);
            continue;
        }
        if (GT_RT_NSENSOR > 0 && (!gt_have_sensor || gt_sensor_age > GT_RT_STALE_CYCLES)) stale = 1;
        if (flags & (F_NON_FINITE | F_DUPLICATE_OR_OLD | F_MISSING_FIELD)) { /* never the step: the held reply */
            ++S.held;
            flags |= F_HELD;
            for (i = 0; i < GT_RT_NU; ++i) y[i] = last[i];
        } else if (stale) {
            ++S.fallback_stale;
            flags |= F_FALLBACK_STALE;
            gt_fallback(last, target, y, &flags);
        } else {
            int st;
            for (i = 0; i < GT_RT_NX; ++i) xr[i] = (gt_rt_real)e.x[i];
            st = gt_rt_step(&mem, (gt_rt_real)t, xr, ur);
            ++S.step_calls;
            flags |= F_STEP;
            e.status = st;
            if (st >= 0 && st < GT_RT_NSTATUS) ++S.step_status[st];
            else ++S.step_status_other;
            for (i = 0; i < GT_RT_NU; ++i) e.u[i] = (double)ur[i];
            if (st == GT_OK || st == GT_MEMORY_RESET || st == GT_MEASUREMENT_REJECTED) {
                for (i = 0; i < GT_RT_NU; ++i) y[i] = e.u[i];
            } else {
                ++S.fallback_step;
                flags |= F_FALLBACK_STEP;
                gt_fallback(last, target, y, &flags);
            }
        }
        for (i = 0; i < GT_RT_NU; ++i) y[i] = gt_limit(y[i], last[i], i, &flags); /* the last change of a value */
        elapsed = gt_now() - t_rx;
        if (elapsed >= GT_RT_PERIOD_S) {
            ++S.late_dropped;
            flags |= F_LATE_DROPPED;
        } else {
            double values[GT_RT_NREPLY];
            if (elapsed > O.reply_deadline && !(flags & F_HELD)) {
                ++S.deadline_held;
                flags |= F_DEADLINE_HELD;
                for (i = 0; i < GT_RT_NU; ++i) y[i] = last[i];
            }
#if GT_RT_INTERFACE == GT_RT_RSI
            for (i = 0; i < GT_RT_NU; ++i) y[i] = gt_rsi_grid(y[i], last[i], i);
#endif
            for (i = 0; i < GT_RT_NREPLY; ++i) values[i] = 0.0;
            for (i = 0; i < GT_RT_NU; ++i) {
                e.sent[i] = GT_RT_RELATIVE ? y[i] - last[i] : y[i];
                values[gt_rt_u_reply[i]] = e.sent[i];
            }
#if GT_RT_INTERFACE == GT_RT_RSI
            rlen = gt_rsi_compose((char *)reply, sizeof reply, GT_RT_SEN_TYPE, GT_RT_RSI_ELEMENTS, values, seq);
            (void)has_orient;
            (void)orient;
#else
            rlen = gt_egm_compose(reply, sizeof reply, GT_RT_EGM_MODE, (uint32_t)seq, (uint32_t)(1000.0 * (t_rx - start)), values,
                                  GT_RT_NREPLY, has_orient ? orient : NULL,
                                  (uint32_t)(gt_have_sensor && gt_sensor_age > 0 ? 1000.0 * GT_RT_PERIOD_S * gt_sensor_age : 0));
#endif
            if (rlen < 0) {
                ++S.compose_errors;
            } else if (sendto(gt_fd, reply, (size_t)rlen, 0, (struct sockaddr *)&from, fromlen) != (ssize_t)rlen) {
                ++S.send_errors;
            } else {
                flags |= F_SENT;
                ++S.replies;
                for (i = 0; i < GT_RT_NU; ++i) last[i] = y[i]; /* the robot has it */
            }
        }
        for (i = 0; i < GT_RT_NU; ++i) e.y[i] = (flags & F_SENT) ? y[i] : NAN;
        e.latency_us = 1e6 * (gt_now() - t_rx);
        if ((flags & F_SENT) && e.latency_us > S.max_latency_us) S.max_latency_us = e.latency_us;
        e.flags = flags;
        gt_log_push(&e);
        if (O.max_cycles > 0 && S.cycles >= O.max_cycles) {
            gt_cycle_end = "max_cycles";
            break;
        }
    }
    atomic_store(&gt_cycle_done, 1);
    return NULL;
}

/* ---- set-up ---- */
static void gt_parse_address(const char *text, struct sockaddr_in *a)
{
    char host[64];
    const char *colon = strrchr(text, ':');
    char *end = NULL;
    long port;
    if (colon == NULL || (size_t)(colon - text) >= sizeof host) gt_fail(2, "--listen: expected HOST:PORT (IPv4)", NULL);
    memcpy(host, text, (size_t)(colon - text));
    host[colon - text] = '\0';
    port = strtol(colon + 1, &end, 10);
    if (*(colon + 1) == '\0' || *end != '\0' || port < 0 || port > 65535) gt_fail(2, "--listen: expected a port 0..65535", NULL);
    memset(a, 0, sizeof *a);
    a->sin_family = AF_INET;
    a->sin_port = htons((uint16_t)port);
    if (inet_pton(AF_INET, host, &a->sin_addr) != 1) gt_fail(2, "--listen: expected an IPv4 address", NULL);
}

static double gt_number_arg(const char *name, const char *text, double lo, double hi)
{
    char *end = NULL;
    double v = strtod(text, &end);
    if (end == text || *end != '\0' || !(v >= lo && v <= hi)) {
        fprintf(stderr, "gt_runtime: %s: expected a number in [%g, %g]\n", name, lo, hi);
        exit(2);
    }
    return v;
}

static int gt_udp(struct sockaddr_in *a, const char *what)
{
    int fd = socket(AF_INET, SOCK_DGRAM, 0); /* no SO_REUSEADDR: a second runtime on the port is a bind error */
    socklen_t len = sizeof *a;
    char where[96];
    if (fd < 0) gt_fail(3, "cannot open a UDP socket", strerror(errno));
    if (bind(fd, (struct sockaddr *)a, sizeof *a) != 0) {
        char ip[INET_ADDRSTRLEN] = "?";
        inet_ntop(AF_INET, &a->sin_addr, ip, sizeof ip);
        snprintf(where, sizeof where, "cannot bind the %s socket to %s:%u", what, ip, (unsigned)ntohs(a->sin_port));
        gt_fail(3, where, strerror(errno));
    }
    getsockname(fd, (struct sockaddr *)a, &len);
    return fd;
}

static void gt_json_string(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; ++s) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\') fprintf(f, "\\%c", c);
        else if (c < 0x20 || c >= 0x7f) fprintf(f, "\\u%04x", c);
        else fputc(c, f);
    }
    fputc('"', f);
}

static void gt_write_stats(const char *signal_name)
{
    char tmp[4200];
    FILE *f;
    int i, first = 1;
    snprintf(tmp, sizeof tmp, "%s.tmp", O.stats_path);
    f = fopen(tmp, "w");
    if (f == NULL) gt_fail(3, "cannot write the stats file", strerror(errno));
    fprintf(f, "{\n  \"format\": \"gtmodel runtime stats 1\",\n  \"interface\": \"%s\",\n", GT_RT_INTERFACE_NAME);
    fprintf(f, "  \"end\": \"%s\",\n  \"signal\": ", S.end ? S.end : "error");
    if (signal_name) fprintf(f, "\"%s\",\n", signal_name);
    else fprintf(f, "null,\n");
    fprintf(f, "  \"packets\": %llu,\n  \"cycles\": %llu,\n  \"replies\": %llu,\n  \"malformed\": %llu,\n  \"too_long\": %llu,\n",
            (unsigned long long)S.packets, (unsigned long long)S.cycles, (unsigned long long)S.replies,
            (unsigned long long)S.malformed, (unsigned long long)S.too_long);
    fprintf(f, "  \"non_finite\": %llu,\n  \"duplicate_or_old\": %llu,\n  \"missing_field\": %llu,\n  \"held_replies\": %llu,\n",
            (unsigned long long)S.non_finite, (unsigned long long)S.duplicate_or_old, (unsigned long long)S.missing_field,
            (unsigned long long)S.held);
    fprintf(f, "  \"fallback_cycles\": {\"stale_sensor\": %llu, \"step_failed\": %llu},\n  \"fallback\": \"%s\",\n",
            (unsigned long long)S.fallback_stale, (unsigned long long)S.fallback_step, GT_RT_RAMP ? "ramp" : "hold");
    fprintf(f, "  \"deadline_held\": %llu,\n  \"late_dropped\": %llu,\n  \"no_safe_reply\": %llu,\n  \"send_errors\": %llu,\n  \"compose_errors\": %llu,\n",
            (unsigned long long)S.deadline_held, (unsigned long long)S.late_dropped, (unsigned long long)S.no_safe_reply,
            (unsigned long long)S.send_errors, (unsigned long long)S.compose_errors);
    fprintf(f, "  \"limit_clamps\": {\"lower\": %llu, \"upper\": %llu, \"rate\": %llu},\n", (unsigned long long)S.clamp_lower,
            (unsigned long long)S.clamp_upper, (unsigned long long)S.clamp_rate);
    fprintf(f, "  \"sensor\": {\"accepted\": %llu, \"malformed\": %llu, \"non_finite\": %llu, \"duplicate_or_old\": %llu, \"too_few_values\": %llu},\n",
            (unsigned long long)S.sensor_accepted, (unsigned long long)S.sensor_malformed, (unsigned long long)S.sensor_non_finite,
            (unsigned long long)S.sensor_old, (unsigned long long)S.sensor_short);
    fprintf(f, "  \"step_calls\": %llu,\n  \"step_status\": {", (unsigned long long)S.step_calls);
    for (i = 0; i < GT_RT_NSTATUS; ++i) {
        if (S.step_status[i] == 0) continue;
        fprintf(f, "%s", first ? "" : ", ");
        gt_json_string(f, gt_rt_status_string(i));
        fprintf(f, ": %llu", (unsigned long long)S.step_status[i]);
        first = 0;
    }
    if (S.step_status_other) fprintf(f, "%s\"other\": %llu", first ? "" : ", ", (unsigned long long)S.step_status_other);
    fprintf(f, "},\n  \"log\": {\"written\": %llu, \"dropped\": %llu, \"write_errors\": %llu},\n", (unsigned long long)S.log_written,
            (unsigned long long)S.log_dropped, (unsigned long long)S.log_write_errors);
    fprintf(f, "  \"realtime\": {\"granted\": %s, \"sched_fifo\": %s, \"mlockall\": %s, \"reason\": ",
            S.realtime_fifo && S.realtime_mlock ? "true" : "false", S.realtime_fifo ? "true" : "false", S.realtime_mlock ? "true" : "false");
    gt_json_string(f, S.realtime_reason);
    fprintf(f, "},\n  \"first_ipoc_or_seq\": %llu,\n  \"last_ipoc_or_seq\": %llu,\n  \"max_latency_us\": %.17g,\n",
            (unsigned long long)S.first_seq, (unsigned long long)S.last_seq, S.max_latency_us);
    fprintf(f, "  \"period_s\": %.17g,\n  \"reply_deadline_s\": %.17g,\n  \"stale_cycles\": %d\n}\n", (double)GT_RT_PERIOD_S, O.reply_deadline,
            (int)GT_RT_STALE_CYCLES);
    if (fclose(f) != 0 || rename(tmp, O.stats_path) != 0) gt_fail(3, "cannot write the stats file", strerror(errno));
}

static void gt_paths(const char *out)
{
    if (strlen(out) >= sizeof O.out) gt_fail(2, "--out: path too long", NULL);
    strcpy(O.out, out);
    snprintf(O.log_path, sizeof O.log_path, "%s/cycle_log.csv", O.out);
    snprintf(O.stats_path, sizeof O.stats_path, "%s/runtime_stats.json", O.out);
    snprintf(O.ready_path, sizeof O.ready_path, "%s/ready.json", O.out);
}

int main(int argc, char **argv)
{
    pthread_t cycle, writer;
    pthread_attr_t attr, wattr, plain;
    sigset_t set;
    const char *signal_name = NULL;
    char tmp[4200];
    FILE *f;
    int i, err;
    O.idle_timeout = 2.0;
    O.reply_deadline = GT_RT_REPLY_DEADLINE_S;
    O.realtime = 1;
    gt_parse_address("0.0.0.0:" GT_RT_DEFAULT_PORT, &O.listen);
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--no-realtime") == 0) {
            O.realtime = 0;
            continue;
        }
        if (strcmp(a, "--exit-with-parent") == 0) { /* SIGTERM (a clean end) when the starting process dies */
#ifdef __linux__
            pid_t parent = getppid();
            if (prctl(PR_SET_PDEATHSIG, SIGTERM) != 0 || getppid() != parent) gt_fail(3, "--exit-with-parent", "the parent is gone");
#endif
            continue;
        }
        if (v == NULL) {
            fprintf(stderr, "gt_runtime: %s: expected a value (usage: gt_runtime --out DIR [--listen HOST:PORT] [--sensor-port PORT] "
                            "[--idle-timeout S] [--max-cycles N] [--reply-deadline S] [--no-realtime] [--exit-with-parent])\n", a);
            return 2;
        }
        ++i;
        if (strcmp(a, "--out") == 0) gt_paths(v);
        else if (strcmp(a, "--listen") == 0) gt_parse_address(v, &O.listen);
        else if (strcmp(a, "--sensor-port") == 0) {
            O.sensor.sin_port = htons((uint16_t)gt_number_arg(a, v, 0, 65535));
            O.sensor_port_given = 1;
        } else if (strcmp(a, "--idle-timeout") == 0) O.idle_timeout = gt_number_arg(a, v, 0.001, 1e6);
        else if (strcmp(a, "--max-cycles") == 0) O.max_cycles = (uint64_t)gt_number_arg(a, v, 0, 1e15);
        else if (strcmp(a, "--reply-deadline") == 0) O.reply_deadline = gt_number_arg(a, v, 0.0, GT_RT_PERIOD_S);
        else {
            fprintf(stderr, "gt_runtime: unknown argument %s\n", a);
            return 2;
        }
    }
    if (O.out[0] == '\0') gt_fail(2, "--out DIR is required", NULL);
    gt_fd = gt_udp(&O.listen, "robot");
    if (GT_RT_NSENSOR > 0) {
        uint16_t port = O.sensor_port_given ? ntohs(O.sensor.sin_port)
                        : (ntohs(O.listen.sin_port) == 0 || ntohs(O.listen.sin_port) == 65535 ? 0 : (uint16_t)(ntohs(O.listen.sin_port) + 1));
        O.sensor = O.listen;
        O.sensor.sin_port = htons(port);
        gt_sensor_fd = gt_udp(&O.sensor, "sensor");
    }
    gt_log_file = fopen(O.log_path, "w");
    if (gt_log_file == NULL) gt_fail(3, "cannot open the cycle log", strerror(errno));
    setvbuf(gt_log_file, NULL, _IOFBF, 1 << 16);
    fprintf(gt_log_file, "cycle,ipoc_or_seq,t,flags,status,latency_us,sensor_age");
    for (i = 0; i < GT_RT_NX; ++i) fprintf(gt_log_file, ",x:%s", gt_rt_x_names[i]);
    for (i = 0; i < GT_RT_NU; ++i) fprintf(gt_log_file, ",u:%s", gt_rt_u_names[i]);
    for (i = 0; i < GT_RT_NU; ++i) fprintf(gt_log_file, ",reply:%s", gt_rt_u_names[i]);
#if GT_RT_RELATIVE
    for (i = 0; i < GT_RT_NU; ++i) fprintf(gt_log_file, ",sent:%s", gt_rt_u_names[i]);
#endif
    fputc('\n', gt_log_file);
    /* signals: blocked in every thread, taken by sigtimedwait in this one */
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set, NULL);
    strcpy(S.realtime_reason, "not asked (--no-realtime)");
    if (O.realtime) {
        S.realtime_reason[0] = '\0';
        if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) S.realtime_mlock = 1;
        else snprintf(S.realtime_reason, sizeof S.realtime_reason, "mlockall: %s", strerror(errno));
    }
    /* threads with small stacks (the cycle's buffers are static): locked memory stays small */
    pthread_attr_init(&wattr);
    pthread_attr_setstacksize(&wattr, GT_RT_WRITER_STACK);
    err = pthread_create(&writer, &wattr, gt_writer, NULL);
    if (err != 0 && S.realtime_mlock) { /* the locked stack over RLIMIT_MEMLOCK: on without locking */
        munlockall();
        S.realtime_mlock = 0;
        snprintf(S.realtime_reason, sizeof S.realtime_reason, "mlockall: undone (thread stacks over the locked-memory limit)");
        err = pthread_create(&writer, &wattr, gt_writer, NULL);
    }
    if (err != 0) gt_fail(3, "cannot start the log thread", strerror(err));
    pthread_attr_init(&attr);
    pthread_attr_setstacksize(&attr, GT_RT_CYCLE_STACK);
    err = -1;
    if (O.realtime) {
        struct sched_param sp;
        sp.sched_priority = 80;
        pthread_attr_setinheritsched(&attr, PTHREAD_EXPLICIT_SCHED);
        pthread_attr_setschedpolicy(&attr, SCHED_FIFO);
        pthread_attr_setschedparam(&attr, &sp);
        err = pthread_create(&cycle, &attr, gt_cycle, NULL);
        if (err == 0) S.realtime_fifo = 1;
        else {
            size_t used = strlen(S.realtime_reason);
            snprintf(S.realtime_reason + used, sizeof S.realtime_reason - used, "%sSCHED_FIFO: %s", used ? "; " : "", strerror(err));
        }
    }
    if (err != 0) {
        pthread_attr_init(&plain);
        pthread_attr_setstacksize(&plain, GT_RT_CYCLE_STACK);
        err = pthread_create(&cycle, &plain, gt_cycle, NULL);
        if (err != 0 && S.realtime_mlock) {
            munlockall();
            S.realtime_mlock = 0;
            err = pthread_create(&cycle, &plain, gt_cycle, NULL);
        }
        if (err != 0) gt_fail(3, "cannot start the cycle thread", strerror(err));
    }
    /* ready: the ports (0 asked: the kernel's) */
    snprintf(tmp, sizeof tmp, "%s.tmp", O.ready_path);
    f = fopen(tmp, "w");
    if (f == NULL) gt_fail(3, "cannot write the ready file", strerror(errno));
    fprintf(f, "{\"listen_port\": %u, \"sensor_port\": %d, \"pid\": %ld}\n", (unsigned)ntohs(O.listen.sin_port),
            gt_sensor_fd >= 0 ? (int)ntohs(O.sensor.sin_port) : -1, (long)getpid());
    if (fclose(f) != 0 || rename(tmp, O.ready_path) != 0) gt_fail(3, "cannot write the ready file", strerror(errno));
    while (!atomic_load(&gt_cycle_done)) {
        struct timespec ts = {0, 50000000};
        int sig = sigtimedwait(&set, NULL, &ts);
        if (sig == SIGINT || sig == SIGTERM) {
            signal_name = sig == SIGINT ? "SIGINT" : "SIGTERM";
            S.end = "signal";
            atomic_store(&gt_stop, 1);
        }
    }
    pthread_join(cycle, NULL);
    if (S.end == NULL) S.end = gt_cycle_end;
    atomic_store(&gt_writer_stop, 1);
    pthread_join(writer, NULL);
    if (fclose(gt_log_file) != 0) ++S.log_write_errors;
    if (S.end == NULL) S.end = "error";
    gt_write_stats(signal_name);
    close(gt_fd);
    if (gt_sensor_fd >= 0) close(gt_sensor_fd);
    return strcmp(S.end, "error") == 0 ? 1 : 0;
}
