/* gt_runtime.c: gtmodel's robot runtime, the 4 ms loop behind KUKA RSI or ABB EGM over UDP.
 *
 * Built by gtmodel.codegen.robot_runtime.build_runtime with the generated loop step
 * (<prefix>.c, PREFIX_step) and gt_runtime_config.h (the interface, the field maps, the limits).
 *
 *   gt_runtime --out DIR [--listen HOST:PORT] [--sensor-port PORT] [--idle-timeout S]
 *              [--max-cycles N] [--reply-deadline S] [--robot ADDR[:PORT]] [--tracker ADDR[:PORT]]
 *              [--log-max-mb MB] [--no-realtime] [--exit-with-parent]
 *
 * One robot per session (gt_guard.c): the named --robot or the first valid datagram's source is
 * the only sender answered; any other is a stranger, never parsed, answered or logged, counted by
 * address (the sensor socket likewise, --tracker). Sequence numbers (IPOC, seqno, the tracker's
 * seq) within a window of the last accepted one reach the step; beyond it the held reply, and 5
 * consecutive consistent datagrams beyond it restart the sequence (a restarted robot). Five or
 * more cycles without the step's reply are an alarm (stderr, runtime_stats.json); gaps of more
 * than two periods are silence events (gt_runtime_report.c writes both).
 *
 * The cycle (one thread, SCHED_FIFO and mlockall where permitted): receive a datagram from the
 * robot -> parse (gt_rsi.c / gt_egm.c; bounded, no heap) -> checks (finite, IPOC/seqno strictly
 * newer, every input field present, sensor sample not older than GT_RT_STALE_CYCLES cycles)
 * -> x from the fields -> PREFIX_step -> limits (lower/upper, then the rate per cycle around
 * the last reply: nothing changes a value after them; RSI's %.6f numbers are put on the 1e-6 grid
 * by moving from the last reply towards the limited value, never past it) -> compose -> sendto.
 *
 * Safety rules: a malformed or too long datagram gets no reply (nothing to echo), counted, not
 * logged; a non-finite field, a duplicate, older or out-of-window IPOC/seqno, a missing input
 * field: the held reply (the last reply again), the step is not called; stale sensor data or a failed step (a status other
 * than GT_OK, GT_MEMORY_RESET, GT_MEASUREMENT_REJECTED): the fallback, hold (the last reply)
 * or ramp (towards zero for corrections: RSI and EGM path correction; towards the start value,
 * the robot's planned position in the first datagram, for EGM joint and Cartesian guidance)
 * at the rate limit. Relative RSI corrections: the runtime keeps the limited TOTAL correction the
 * robot applied and sends its increment per cycle, so a robot that sums increments holds exactly
 * the total; an increment the robot reports late (Delay.D grew) is taken back. EGM guidance starts
 * from the robot's measured position; no reply while that is more than a rate step outside the limits.
 *
 * Deadline rule: with the reply composed, just before sendto, the time since the datagram was received is measured.
 * At most the reply deadline (default 2 ms of the 4 ms period): the computed reply. Beyond it
 * but within the period: the held reply (the last one again; a relative correction sends a
 * zero increment), counted deadline_held: it still reaches the robot within its cycle, so
 * RSI does not count it late, and only the step's output of that cycle is lost. At or beyond
 * the period: no reply (counted late_dropped); RSI counts that cycle late as it would count a
 * late reply, and the robot's own limit of consecutive late cycles then stops it, the safe end.
 * The reply that is held is composed in microseconds, so only a stall of the whole process
 * longer than a period (what SCHED_FIFO and mlockall guard against) costs a cycle.
 *
 * The cycle log (DIR/cycle_log.csv, at most --log-max-mb) is written by a second, ordinary thread from a
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
#include "gt_guard.h"
#include "gt_rsi.h"
#include "gt_sensor_stream.h"

#include "gt_runtime_state.h"

static gt_rt_entry gt_ring[GT_RT_RING];
static atomic_uint_fast64_t gt_ring_head, gt_ring_tail; /* head: producer (cycle), tail: consumer (writer) */
static atomic_int gt_stop, gt_cycle_done, gt_writer_stop;
static const char *gt_cycle_end; /* set by the cycle thread before gt_cycle_done, read by main after the join */
gt_rt_stats gt_S;
gt_rt_event gt_events[GT_RT_MAX_EVENTS];
atomic_int gt_events_n;
gt_source gt_robot_src, gt_tracker_src;
gt_strangers gt_strangers_seen;
gt_seqwin gt_robot_seq, gt_sensor_seqw;
gt_rt_options gt_O;


static int gt_fd = -1, gt_sensor_fd = -1;
static FILE *gt_log_file;

static double gt_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void gt_fail(int code, const char *what, const char *detail)
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
        ++gt_S.log_dropped;
        return;
    }
    gt_ring[head % GT_RT_RING] = *e;
    atomic_store_explicit(&gt_ring_head, head + 1, memory_order_release);
}

#define GT_RT_ROW_MAX ((GT_RT_NX + 4 * GT_RT_NU + 9) * 26)

/* one row of the log, within the cap (--log-max-mb): a row past it is counted, not written */
static void gt_write_row(const gt_rt_entry *e)
{
    static char row[GT_RT_ROW_MAX];
    size_t n = 0;
    int i;
#define GT_ROW(...) n += (size_t)snprintf(row + n, n < sizeof row ? sizeof row - n : 0, __VA_ARGS__)
    GT_ROW("%llu,%llu,%.17g,%u,%d,%.17g,%d,%.17g", (unsigned long long)e->cycle, (unsigned long long)e->seq, e->t, (unsigned)e->flags,
           (int)e->status, e->latency_us, (int)e->sensor_age, e->t_monotonic);
    for (i = 0; i < GT_RT_NX; ++i) GT_ROW(",%.17g", e->x[i]);
    for (i = 0; i < GT_RT_NU; ++i) GT_ROW(",%.17g", e->u[i]);
    for (i = 0; i < GT_RT_NU; ++i) GT_ROW(",%.17g", e->y[i]);
#if GT_RT_RELATIVE
    for (i = 0; i < GT_RT_NU; ++i) GT_ROW(",%.17g", e->sent[i]);
#endif
    GT_ROW("\n");
#undef GT_ROW
    if (n >= sizeof row) {
        ++gt_S.log_write_errors;
        return;
    }
    if (gt_O.log_max_bytes > 0 && gt_S.log_bytes + n > gt_O.log_max_bytes) {
        ++gt_S.log_capped;
        return;
    }
    if (fwrite(row, 1, n, gt_log_file) != n) {
        ++gt_S.log_write_errors;
        return;
    }
    gt_S.log_bytes += n;
    ++gt_S.log_written;
}

/* ---- the log writer: consumer side, an ordinary thread ---- */
static void *gt_writer(void *arg)
{
    int printed = 0;
    (void)arg;
    for (;;) {
        uint64_t tail = atomic_load_explicit(&gt_ring_tail, memory_order_relaxed);
        uint64_t head = atomic_load_explicit(&gt_ring_head, memory_order_acquire);
        gt_print_alarms(&printed);
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
    gt_print_alarms(&printed);
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
        if (y < gt_rt_lower[i]) ++gt_S.clamp_lower;
        else ++gt_S.clamp_rate;
        y = lo;
        *flags |= F_CLAMPED;
    } else if (y > hi) {
        if (y > gt_rt_upper[i]) ++gt_S.clamp_upper;
        else ++gt_S.clamp_rate;
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

/* ---- events (the cycle thread only; published for the writer's stderr lines) ---- */
static double gt_start_time;

static gt_rt_event *gt_event(int kind, uint64_t cycle, uint64_t seq, double t_rx, uint32_t reasons)
{
    int n = atomic_load_explicit(&gt_events_n, memory_order_relaxed);
    gt_rt_event *ev;
    if (n >= GT_RT_MAX_EVENTS) {
        ++gt_S.events_dropped;
        return NULL;
    }
    ev = &gt_events[n];
    memset(ev, 0, sizeof *ev);
    ev->kind = kind;
    ev->cycle = cycle;
    ev->seq = seq;
    ev->t = t_rx - gt_start_time;
    ev->reasons = reasons;
    atomic_store_explicit(&gt_events_n, n + 1, memory_order_release);
    return ev;
}

/* ---- the sensor stream (the cycle thread only): the newest valid sample of the tracker and its age in robot cycles ---- */
static gt_sensor_sample gt_latest;
static int gt_have_sensor;
static int32_t gt_sensor_age;
static double gt_sensor_rx;

static void gt_drain_sensor(int32_t age_of_new)
{
    static char sbuf[GT_SENSOR_MAX_LEN + 1];
    static gt_sensor_sample sample;
    int k;
    if (gt_sensor_fd < 0) return;
    for (k = 0; k < 256; ++k) {
        struct sockaddr_in from;
        socklen_t fromlen = sizeof from;
        ssize_t m = gt_recv(gt_sensor_fd, sbuf, sizeof sbuf, &from, &fromlen, &gt_S.kernel_dropped_sensor);
        int r;
        double now;
        if (m < 0) break;
        if (!gt_source_match(&gt_tracker_src, &from)) { /* a stranger: never parsed */
            gt_strangers_count(&gt_strangers_seen, &from, 1);
            continue;
        }
        r = gt_sensor_parse(sbuf, (size_t)m > GT_SENSOR_MAX_LEN ? GT_SENSOR_MAX_LEN + 1 : (size_t)m, &sample);
        if (r == GT_SENSOR_NON_FINITE) ++gt_S.sensor_non_finite;
        else if (r != GT_SENSOR_OK) ++gt_S.sensor_malformed;
        else if (sample.n < GT_RT_NSENSOR) ++gt_S.sensor_short;
        else {
            int q;
            now = gt_now();
            if (!gt_tracker_src.locked) {
                gt_source_lock(&gt_tracker_src, &from);
                gt_event(EV_SENSOR_LOCK, gt_S.cycles, sample.seq, now, 0);
            }
            q = gt_seq_check(&gt_sensor_seqw, sample.seq, 64,
                             (uint64_t)GT_RT_SENSOR_WINDOW + (uint64_t)(20000.0 * (gt_have_sensor ? now - gt_sensor_rx : 0.0)),
                             GT_RT_RESYNC_PACKETS);
            if (q == GT_SEQ_OLD) ++gt_S.sensor_old;
            else if (q == GT_SEQ_OUT) continue; /* counted in the window's out_of_window */
            else {
                if (q == GT_SEQ_RESYNC) gt_event(EV_SENSOR_RESYNC, gt_S.cycles, sample.seq, now, 0);
                gt_latest = sample;
                gt_have_sensor = 1;
                gt_sensor_age = age_of_new;
                gt_sensor_rx = now;
                ++gt_S.sensor_accepted;
            }
        }
    }
}

/* ---- the start of the replies ---- */
static double gt_clamp(double v, int i)
{
    return v < gt_rt_lower[i] ? gt_rt_lower[i] : v > gt_rt_upper[i] ? gt_rt_upper[i] : v;
}

/* last[] = what the robot holds before the first reply: zero corrections (RSI, EGM path correction) or, for EGM
 * guidance, the robot's MEASURED position (feedback; planned when the packet has none), so that the rate limit
 * applies from where the robot is. Returns 1, 0 when a needed field is missing, 2 when the start is more than one
 * rate step outside [lower, upper] (no reply can then keep both the limits and the rate: none is sent). */
static int gt_start(const double *field, uint64_t present_mask, double *last, double *target)
{
    int i, ok = 1;
    for (i = 0; i < GT_RT_NU; ++i) {
        int a = gt_rt_u_init[i], b = gt_rt_u_init2[i];
        double v = 0.0;
        if (a >= 0 && (present_mask & ((uint64_t)1 << a)) && isfinite(field[a])) v = field[a];
        else if (b >= 0 && (present_mask & ((uint64_t)1 << b)) && isfinite(field[b])) v = field[b];
        else if (a >= 0) ok = 0;
        if (ok && (v < gt_rt_lower[i] - gt_rt_rate[i] || v > gt_rt_upper[i] + gt_rt_rate[i])) ok = 2;
        last[i] = v;
        target[i] = gt_clamp(a >= 0 ? v : 0.0, i);
    }
    return ok;
}

/* compose the reply of y into reply[] (values: RSI relative the increments y - last; else y); the sent values in e->sent */
static int gt_compose(unsigned char *reply, const double *y, const double *last, uint64_t seq, double t_rx, int has_orient,
                      const double *orient, gt_rt_entry *e)
{
    double values[GT_RT_NREPLY];
    int i;
    for (i = 0; i < GT_RT_NREPLY; ++i) values[i] = 0.0;
    for (i = 0; i < GT_RT_NU; ++i) {
        e->sent[i] = GT_RT_RELATIVE ? y[i] - last[i] : y[i];
        values[gt_rt_u_reply[i]] = e->sent[i];
    }
#if GT_RT_INTERFACE == GT_RT_RSI
    (void)t_rx;
    (void)has_orient;
    (void)orient;
    return gt_rsi_compose((char *)reply, GT_RT_MAX_DATAGRAM, GT_RT_SEN_TYPE, GT_RT_RSI_ELEMENTS, values, seq);
#else
    return gt_egm_compose(reply, GT_RT_MAX_DATAGRAM, GT_RT_EGM_MODE, (uint32_t)seq, (uint32_t)(1000.0 * (t_rx - gt_start_time)), values,
                          GT_RT_NREPLY, has_orient ? orient : NULL,
                          (uint32_t)(gt_have_sensor && gt_sensor_age > 0 ? 1000.0 * GT_RT_PERIOD_S * gt_sensor_age : 0));
#endif
}

/* the held reply: the last one, within the limits (a start just outside them moves in at the rate) */
static void gt_held(const double *last, double *y)
{
    int i;
    uint32_t dummy = 0;
    for (i = 0; i < GT_RT_NU; ++i) {
        y[i] = gt_limit(last[i], last[i], i, &dummy);
#if GT_RT_INTERFACE == GT_RT_RSI
        y[i] = gt_rsi_grid(y[i], last[i], i);
#endif
    }
}

#define F_NOT_STEPPED (F_HELD | F_FALLBACK_STALE | F_FALLBACK_STEP | F_DEADLINE_HELD | F_LATE_DROPPED | F_NO_SAFE_REPLY)
#define F_NEVER_STEP (F_NON_FINITE | F_DUPLICATE_OR_OLD | F_OUT_OF_WINDOW | F_MISSING_FIELD)
#define GT_RSI_DELAY 36 /* Delay.D in gt_rsi.h's field order */

/* ---- the cycle ---- */
static void *gt_cycle(void *arg)
{
    static unsigned char buf[GT_RT_MAX_DATAGRAM + 1];
    static unsigned char reply[GT_RT_MAX_DATAGRAM];
    static gt_rt_memory mem;
    static gt_rt_entry e;
    static double last[GT_RT_NU], target[GT_RT_NU], y[GT_RT_NU], pending[GT_RT_NU], field[64];
    static gt_rt_real xr[GT_RT_NX], ur[GT_RT_NU];
    int have_last = 0, have_t0 = 0, have_rx = 0, have_pending = 0, have_delay = 0, hold_run = 0, repeat_run = 0;
    uint64_t seq0 = 0, cycles0 = 0, prev_seq = 0, required = 0;
    uint32_t tm0 = 0, hold_reasons = 0;
    double last_rx = 0.0, accept_rx = 0.0, prev_delay = 0.0, hold_t0 = 0.0;
    gt_rt_event *hold_ev = NULL;
    const uint64_t seq_step = GT_RT_INTERFACE == GT_RT_RSI ? (uint64_t)(llround(1000.0 * GT_RT_PERIOD_S) > 0 ? llround(1000.0 * GT_RT_PERIOD_S) : 1) : 1;
    int i;
    (void)arg;
    for (i = 0; i < GT_RT_NX; ++i)
        if (gt_rt_x_source[i] >= 0) required |= (uint64_t)1 << gt_rt_x_source[i];
#if GT_RT_RELATIVE
    required |= (uint64_t)1 << GT_RSI_DELAY; /* relative corrections: the robot's count of late replies is needed */
#endif
    gt_rt_step_init(&mem);
    while (!atomic_load(&gt_stop)) {
        struct pollfd pf[2];
        struct sockaddr_in from;
        socklen_t fromlen = sizeof from;
        ssize_t n;
        double t_rx, t = 0.0, elapsed;
        int code = 0, nfd = 1, rlen = -1, stale = 0, q, accepted;
        uint64_t seq = 0, present_mask = 0;
        uint32_t flags = 0, tm = 0;
        int has_tm = 0, has_orient = 0;
        double orient[4] = {0, 0, 0, 0};
        if (have_rx && gt_now() - last_rx > gt_O.idle_timeout) { /* the robot's silence, whatever strangers send */
            gt_cycle_end = "idle_timeout";
            break;
        }
        pf[0].fd = gt_fd;
        pf[0].events = POLLIN;
        if (gt_sensor_fd >= 0) {
            pf[1].fd = gt_sensor_fd;
            pf[1].events = POLLIN;
            nfd = 2;
        }
        if (poll(pf, (nfds_t)nfd, 20) < 0 && errno != EINTR) break;
        n = gt_recv(gt_fd, buf, sizeof buf, &from, &fromlen, &gt_S.kernel_dropped_robot);
        if (n < 0) {
            gt_drain_sensor(-1); /* a sample between robot cycles: age 0 at the next one */
            continue;
        }
        t_rx = gt_now(); /* the reply latency runs from here: the datagram in the runtime's hands */
        if (!gt_source_match(&gt_robot_src, &from)) { /* a stranger: never parsed, answered or logged; counted */
            gt_strangers_count(&gt_strangers_seen, &from, 0);
            continue;
        }
        ++gt_S.packets;
        if (gt_robot_src.locked) { /* anything the robot sends keeps the session alive; a gap of two periods is a silence */
            if (have_rx && t_rx - last_rx > 2.0 * GT_RT_PERIOD_S) {
                gt_rt_event *ev = gt_event(EV_SILENCE, gt_S.cycles + 1, 0, last_rx, 0);
                ++gt_S.silences;
                if (ev) ev->length_s = t_rx - last_rx;
                if (t_rx - last_rx > gt_S.silence_longest_s) gt_S.silence_longest_s = t_rx - last_rx;
            }
            last_rx = t_rx;
            have_rx = 1;
        }
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
        if (code == 1 || code == 2) { /* nothing to echo: no reply; counted, not logged */
            if (code == 2) ++gt_S.too_long;
            ++gt_S.malformed;
            continue;
        }
        if (!gt_robot_src.locked) { /* the session's robot: the first valid packet's source (or the named one's) */
            if (code != 0 || (present_mask & required) != required) {
                ++gt_S.before_lock;
                continue;
            }
            gt_source_lock(&gt_robot_src, &from);
            gt_event(EV_LOCK, gt_S.cycles + 1, seq, t_rx, 0);
            last_rx = t_rx;
            have_rx = 1;
        }
        /* a cycle of the robot */
        ++gt_S.cycles;
        ++gt_sensor_age;
        gt_drain_sensor(0);
        memset(&e, 0, sizeof e);
        e.cycle = gt_S.cycles;
        e.seq = seq;
        for (i = 0; i < GT_RT_NX; ++i) e.x[i] = NAN;
        for (i = 0; i < GT_RT_NU; ++i) e.u[i] = e.y[i] = e.sent[i] = NAN;
        e.status = -1;
        e.sensor_age = gt_have_sensor ? gt_sensor_age : -1;
        if (gt_S.cycles == 1) gt_S.first_seq = seq;
        gt_S.last_seq = seq;
        /* the sequence: within the window of the last accepted packet (docs/robot.md, forged and restarted sequences) */
        q = gt_seq_check(&gt_robot_seq, seq, GT_RT_INTERFACE == GT_RT_RSI ? 64 : 32,
                         seq_step * ((uint64_t)GT_RT_SEQ_WINDOW + (uint64_t)(gt_robot_seq.have ? 2.0 * (t_rx - accept_rx) / GT_RT_PERIOD_S : 0.0)),
                         GT_RT_RESYNC_PACKETS);
        accepted = q == GT_SEQ_ACCEPT || q == GT_SEQ_RESYNC;
        if (q == GT_SEQ_OLD) {
            ++gt_S.duplicate_or_old;
            flags |= F_DUPLICATE_OR_OLD;
        } else if (q == GT_SEQ_OUT) {
            flags |= F_OUT_OF_WINDOW;
        } else {
            accept_rx = t_rx;
            if (q == GT_SEQ_RESYNC) { /* a restarted robot: everything starts again from this packet */
                flags |= F_RESYNC;
                gt_event(EV_RESYNC, gt_S.cycles, seq, t_rx, 0);
                have_last = have_t0 = have_pending = have_delay = 0;
                gt_rt_step_init(&mem);
            }
#if GT_RT_RELATIVE
            /* the robot's count of late replies (Delay.D, cumulative): when it grew by the cycles since the last accepted
             * packet, the reply to that packet came late and the robot did not apply its increment */
            if ((present_mask & ((uint64_t)1 << GT_RSI_DELAY)) && isfinite(field[GT_RSI_DELAY])) {
                uint64_t gap = (seq - prev_seq + seq_step / 2) / seq_step; /* cycles since the last accepted datagram, at least 1 */
                if (gap < 1) gap = 1;
                if (have_pending && have_delay && field[GT_RSI_DELAY] - prev_delay >= (double)gap - 0.5) {
                    for (i = 0; i < GT_RT_NU; ++i) last[i] -= pending[i];
                    ++gt_S.unapplied;
                    flags |= F_UNAPPLIED;
                }
                prev_delay = field[GT_RSI_DELAY];
                have_delay = 1;
            }
            have_pending = 0;
            prev_seq = seq;
#endif
            if (code == 3) {
                ++gt_S.non_finite;
                flags |= F_NON_FINITE;
            } else if ((present_mask & required) != required) {
                ++gt_S.missing_field;
                flags |= F_MISSING_FIELD;
            }
        }
        if (accepted) /* the measurement of a packet in sequence; a held packet's is not logged */
            for (i = 0; i < GT_RT_NX; ++i) {
                int src = gt_rt_x_source[i];
                e.x[i] = src >= 0 ? field[src] : gt_have_sensor ? gt_latest.value[-1 - src] : NAN;
            }
        if (accepted && !have_t0) {
            seq0 = seq;
            tm0 = tm;
            cycles0 = gt_S.cycles;
            have_t0 = 1;
        }
#if GT_RT_INTERFACE == GT_RT_RSI
        t = (double)(int64_t)(seq - seq0) / 1000.0;
#else
        t = has_tm ? (double)(int32_t)(tm - tm0) / 1000.0 : (double)(gt_S.cycles - cycles0) * GT_RT_PERIOD_S;
#endif
        (void)has_tm;
        (void)tm0;
        (void)cycles0;
        (void)prev_seq;
        (void)seq0;
        (void)pending;
        (void)prev_delay;
        (void)have_delay;
        e.t = t;
        if (!have_last && accepted && !(flags & F_NEVER_STEP)) { /* the start, from a packet in sequence only */
            int r = gt_start(field, present_mask, last, target);
            if (r == 1) have_last = 1;
            else if (r == 2) ++gt_S.start_outside;
        }
        if (!have_last) {
            ++gt_S.no_safe_reply;
            flags |= F_NO_SAFE_REPLY;
        } else {
            if (GT_RT_NSENSOR > 0 && (!gt_have_sensor || gt_sensor_age > GT_RT_STALE_CYCLES)) stale = 1;
            if (flags & F_NEVER_STEP) { /* never the step: the held reply */
                ++gt_S.held;
                flags |= F_HELD;
                for (i = 0; i < GT_RT_NU; ++i) y[i] = last[i];
            } else if (stale) {
                ++gt_S.fallback_stale;
                flags |= F_FALLBACK_STALE;
                gt_fallback(last, target, y, &flags);
            } else {
                int st;
                for (i = 0; i < GT_RT_NX; ++i) xr[i] = (gt_rt_real)e.x[i];
                st = gt_rt_step(&mem, (gt_rt_real)t, xr, ur);
                ++gt_S.step_calls;
                flags |= F_STEP;
                e.status = st;
                if (st >= 0 && st < GT_RT_NSTATUS) ++gt_S.step_status[st];
                else ++gt_S.step_status_other;
                for (i = 0; i < GT_RT_NU; ++i) e.u[i] = (double)ur[i];
                if (st == GT_OK || st == GT_MEMORY_RESET || st == GT_MEASUREMENT_REJECTED) {
                    for (i = 0; i < GT_RT_NU; ++i) y[i] = e.u[i];
                } else {
                    ++gt_S.fallback_step;
                    flags |= F_FALLBACK_STEP;
                    gt_fallback(last, target, y, &flags);
                }
            }
            for (i = 0; i < GT_RT_NU; ++i) y[i] = gt_limit(y[i], last[i], i, &flags); /* the last change of a value */
#if GT_RT_INTERFACE == GT_RT_RSI
            for (i = 0; i < GT_RT_NU; ++i) y[i] = gt_rsi_grid(y[i], last[i], i);
#endif
            rlen = gt_compose(reply, y, last, seq, t_rx, has_orient, orient, &e);
            /* the deadline, measured with the reply composed, just before sendto */
            elapsed = gt_now() - t_rx;
            if (elapsed > gt_O.reply_deadline && elapsed < GT_RT_PERIOD_S && !(flags & F_HELD)) {
                ++gt_S.deadline_held;
                flags |= F_DEADLINE_HELD;
                gt_held(last, y);
                rlen = gt_compose(reply, y, last, seq, t_rx, has_orient, orient, &e);
                elapsed = gt_now() - t_rx;
            }
            if (elapsed >= GT_RT_PERIOD_S) {
                ++gt_S.late_dropped;
                flags |= F_LATE_DROPPED;
            } else if (rlen < 0) {
                ++gt_S.compose_errors;
            } else if (sendto(gt_fd, reply, (size_t)rlen, 0, (struct sockaddr *)&from, fromlen) != (ssize_t)rlen) {
                ++gt_S.send_errors;
            } else {
                double sent_at = gt_now();
                flags |= F_SENT;
                ++gt_S.replies;
                if (sent_at - t_rx >= GT_RT_PERIOD_S) { /* stalled inside sendto: sent, but past the period */
                    ++gt_S.sent_late;
                    flags |= F_SENT_LATE;
                }
                for (i = 0; i < GT_RT_NU; ++i) {
                    pending[i] = y[i] - last[i];
                    last[i] = y[i]; /* the robot has it */
                }
                have_pending = accepted;
            }
        }
        for (i = 0; i < GT_RT_NU; ++i) e.y[i] = (flags & F_SENT) ? y[i] : NAN;
        if (!(flags & F_SENT))
            for (i = 0; i < GT_RT_NU; ++i) e.sent[i] = NAN;
        e.latency_us = 1e6 * (gt_now() - t_rx);
        e.t_monotonic = t_rx; /* CLOCK_MONOTONIC at the datagram's arrival: other programs' logs on this machine line up with it */
        if ((flags & F_SENT) && e.latency_us > gt_S.max_latency_us) gt_S.max_latency_us = e.latency_us;
        /* a hold longer than GT_RT_HOLD_ALARM cycles: an alarm (summary.json and stderr) */
        if (!(flags & F_SENT) || (flags & F_NOT_STEPPED)) {
            if (hold_run == 0) hold_t0 = t_rx;
            hold_reasons |= flags & ~(uint32_t)(F_SENT | F_STEP | F_CLAMPED);
            if (++hold_run == GT_RT_HOLD_ALARM) {
                hold_ev = gt_event(EV_HOLD, gt_S.cycles + 1 - GT_RT_HOLD_ALARM, seq, hold_t0, hold_reasons);
                ++gt_S.holds;
            }
            if ((uint64_t)hold_run > gt_S.hold_longest) gt_S.hold_longest = (uint64_t)hold_run;
            if (hold_ev) {
                hold_ev->reasons |= hold_reasons;
                hold_ev->cycles = (uint64_t)hold_run;
                hold_ev->length_s = t_rx - hold_t0;
            }
        } else {
            hold_run = 0;
            hold_reasons = 0;
            hold_ev = NULL;
        }
        e.flags = flags;
        /* a flood of repeated or forged sequence numbers from the robot's address: its first rows logged, the rest counted */
        repeat_run = (flags & (F_DUPLICATE_OR_OLD | F_OUT_OF_WINDOW)) ? repeat_run + 1 : 0;
        if (repeat_run > GT_RT_LOG_REPEATS) ++gt_S.log_unlogged_repeats;
        else gt_log_push(&e);
        if (gt_O.max_cycles > 0 && gt_S.cycles >= gt_O.max_cycles) {
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

static int gt_udp(struct sockaddr_in *a, const char *what, uint64_t *buffer_bytes)
{
    int fd = socket(AF_INET, SOCK_DGRAM, 0); /* no SO_REUSEADDR: a second runtime on the port is a bind error */
    int one = 1, size = GT_RT_RCVBUF_BYTES;
    socklen_t len = sizeof *a, slen = sizeof size;
    char where[96];
    if (fd < 0) gt_fail(3, "cannot open a UDP socket", strerror(errno));
    /* a deeper queue than the default ~200 kB (ms of a flood; capped by net.core.rmem_max, the granted size
     * reported); SO_RXQ_OVFL: the kernel's count of datagrams dropped for a full queue (gt_recv) */
    setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &size, sizeof size);
    if (getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &size, &slen) == 0 && size > 0) *buffer_bytes = (uint64_t)size;
    setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one);
    if (bind(fd, (struct sockaddr *)a, sizeof *a) != 0) {
        char ip[INET_ADDRSTRLEN] = "?";
        inet_ntop(AF_INET, &a->sin_addr, ip, sizeof ip);
        snprintf(where, sizeof where, "cannot bind the %s socket to %s:%u", what, ip, (unsigned)ntohs(a->sin_port));
        gt_fail(3, where, strerror(errno));
    }
    getsockname(fd, (struct sockaddr *)a, &len);
    return fd;
}

static void gt_paths(const char *out)
{
    if (strlen(out) >= sizeof gt_O.out) gt_fail(2, "--out: path too long", NULL);
    strcpy(gt_O.out, out);
    snprintf(gt_O.log_path, sizeof gt_O.log_path, "%s/cycle_log.csv", gt_O.out);
    snprintf(gt_O.stats_path, sizeof gt_O.stats_path, "%s/runtime_stats.json", gt_O.out);
    snprintf(gt_O.ready_path, sizeof gt_O.ready_path, "%s/ready.json", gt_O.out);
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
    gt_O.idle_timeout = 2.0;
    gt_O.reply_deadline = GT_RT_REPLY_DEADLINE_S;
    gt_O.realtime = 1;
    gt_O.log_max_bytes = (uint64_t)1024 * 1048576u;
    gt_start_time = gt_now();
    gt_parse_address("0.0.0.0:" GT_RT_DEFAULT_PORT, &gt_O.listen);
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--no-realtime") == 0) {
            gt_O.realtime = 0;
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
                            "[--idle-timeout S] [--max-cycles N] [--reply-deadline S] [--robot ADDR[:PORT]] [--tracker ADDR[:PORT]] "
                            "[--log-max-mb MB] [--no-realtime] [--exit-with-parent])\n", a);
            return 2;
        }
        ++i;
        if (strcmp(a, "--out") == 0) gt_paths(v);
        else if (strcmp(a, "--listen") == 0) gt_parse_address(v, &gt_O.listen);
        else if (strcmp(a, "--sensor-port") == 0) {
            gt_O.sensor.sin_port = htons((uint16_t)gt_number_arg(a, v, 0, 65535));
            gt_O.sensor_port_given = 1;
        } else if (strcmp(a, "--idle-timeout") == 0) gt_O.idle_timeout = gt_number_arg(a, v, 0.001, 1e6);
        else if (strcmp(a, "--max-cycles") == 0) gt_O.max_cycles = (uint64_t)gt_number_arg(a, v, 0, 1e15);
        else if (strcmp(a, "--reply-deadline") == 0) gt_O.reply_deadline = gt_number_arg(a, v, 0.0, GT_RT_PERIOD_S);
        else if (strcmp(a, "--log-max-mb") == 0) gt_O.log_max_bytes = (uint64_t)(gt_number_arg(a, v, 0.001, 1e6) * 1048576.0);
        else if (strcmp(a, "--robot") == 0 || strcmp(a, "--tracker") == 0) {
            if (gt_source_parse(v, a[2] == 'r' ? &gt_robot_src : &gt_tracker_src) != 0) {
                fprintf(stderr, "gt_runtime: %s: expected an IPv4 address, optionally with :PORT (1..65535), got %s\n", a, v);
                return 2;
            }
        }
        else {
            fprintf(stderr, "gt_runtime: unknown argument %s\n", a);
            return 2;
        }
    }
    if (gt_O.out[0] == '\0') gt_fail(2, "--out DIR is required", NULL);
    if (gt_O.listen.sin_addr.s_addr == htonl(INADDR_ANY))
        fprintf(stderr, "gt_runtime: warning: listening on every interface (0.0.0.0): any host that reaches this one may send; "
                        "listen on the robot network's address only (docs/robot.md, the network rules)\n");
    if (!gt_robot_src.named)
        fprintf(stderr, "gt_runtime: warning: no robot address named (--robot): the first valid packet's source is the robot "
                        "for this session\n");
    gt_fd = gt_udp(&gt_O.listen, "robot", &gt_S.rcvbuf_robot);
    if (GT_RT_NSENSOR > 0) {
        uint16_t port = gt_O.sensor_port_given ? ntohs(gt_O.sensor.sin_port)
                        : (ntohs(gt_O.listen.sin_port) == 0 || ntohs(gt_O.listen.sin_port) == 65535 ? 0 : (uint16_t)(ntohs(gt_O.listen.sin_port) + 1));
        gt_O.sensor = gt_O.listen;
        gt_O.sensor.sin_port = htons(port);
        gt_sensor_fd = gt_udp(&gt_O.sensor, "sensor", &gt_S.rcvbuf_sensor);
    }
    gt_log_file = fopen(gt_O.log_path, "w");
    if (gt_log_file == NULL) gt_fail(3, "cannot open the cycle log", strerror(errno));
    setvbuf(gt_log_file, NULL, _IOFBF, 1 << 16);
    fprintf(gt_log_file, "cycle,ipoc_or_seq,t,flags,status,latency_us,sensor_age,t_monotonic");
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
    strcpy(gt_S.realtime_reason, "not asked (--no-realtime)");
    if (gt_O.realtime) {
        gt_S.realtime_reason[0] = '\0';
        if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) gt_S.realtime_mlock = 1;
        else snprintf(gt_S.realtime_reason, sizeof gt_S.realtime_reason, "mlockall: %s", strerror(errno));
    }
    /* threads with small stacks (the cycle's buffers are static): locked memory stays small */
    pthread_attr_init(&wattr);
    pthread_attr_setstacksize(&wattr, GT_RT_WRITER_STACK);
    err = pthread_create(&writer, &wattr, gt_writer, NULL);
    if (err != 0 && gt_S.realtime_mlock) { /* the locked stack over RLIMIT_MEMLOCK: on without locking */
        munlockall();
        gt_S.realtime_mlock = 0;
        snprintf(gt_S.realtime_reason, sizeof gt_S.realtime_reason, "mlockall: undone (thread stacks over the locked-memory limit)");
        err = pthread_create(&writer, &wattr, gt_writer, NULL);
    }
    if (err != 0) gt_fail(3, "cannot start the log thread", strerror(err));
    pthread_attr_init(&attr);
    pthread_attr_setstacksize(&attr, GT_RT_CYCLE_STACK);
    err = -1;
    if (gt_O.realtime) {
        struct sched_param sp;
        sp.sched_priority = 80;
        pthread_attr_setinheritsched(&attr, PTHREAD_EXPLICIT_SCHED);
        pthread_attr_setschedpolicy(&attr, SCHED_FIFO);
        pthread_attr_setschedparam(&attr, &sp);
        err = pthread_create(&cycle, &attr, gt_cycle, NULL);
        if (err == 0) gt_S.realtime_fifo = 1;
        else {
            size_t used = strlen(gt_S.realtime_reason);
            snprintf(gt_S.realtime_reason + used, sizeof gt_S.realtime_reason - used, "%sSCHED_FIFO: %s", used ? "; " : "", strerror(err));
        }
    }
    if (err != 0) {
        pthread_attr_init(&plain);
        pthread_attr_setstacksize(&plain, GT_RT_CYCLE_STACK);
        err = pthread_create(&cycle, &plain, gt_cycle, NULL);
        if (err != 0 && gt_S.realtime_mlock) {
            munlockall();
            gt_S.realtime_mlock = 0;
            err = pthread_create(&cycle, &plain, gt_cycle, NULL);
        }
        if (err != 0) gt_fail(3, "cannot start the cycle thread", strerror(err));
    }
    /* ready: the ports (0 asked: the kernel's) */
    snprintf(tmp, sizeof tmp, "%s.tmp", gt_O.ready_path);
    f = fopen(tmp, "w");
    if (f == NULL) gt_fail(3, "cannot write the ready file", strerror(errno));
    fprintf(f, "{\"listen_port\": %u, \"sensor_port\": %d, \"pid\": %ld}\n", (unsigned)ntohs(gt_O.listen.sin_port),
            gt_sensor_fd >= 0 ? (int)ntohs(gt_O.sensor.sin_port) : -1, (long)getpid());
    if (fclose(f) != 0 || rename(tmp, gt_O.ready_path) != 0) gt_fail(3, "cannot write the ready file", strerror(errno));
    while (!atomic_load(&gt_cycle_done)) {
        struct timespec ts = {0, 50000000};
        int sig = sigtimedwait(&set, NULL, &ts);
        if (sig == SIGINT || sig == SIGTERM) {
            signal_name = sig == SIGINT ? "SIGINT" : "SIGTERM";
            gt_S.end = "signal";
            atomic_store(&gt_stop, 1);
        }
    }
    pthread_join(cycle, NULL);
    if (gt_S.end == NULL) gt_S.end = gt_cycle_end;
    atomic_store(&gt_writer_stop, 1);
    pthread_join(writer, NULL);
    if (fclose(gt_log_file) != 0) ++gt_S.log_write_errors;
    if (gt_S.end == NULL) gt_S.end = "error";
    gt_write_stats(signal_name);
    close(gt_fd);
    if (gt_sensor_fd >= 0) close(gt_sensor_fd);
    return strcmp(gt_S.end, "error") == 0 ? 1 : 0;
}
