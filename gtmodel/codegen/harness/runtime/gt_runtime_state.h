/* gt_runtime_state.h: what the runtime's cycle (gt_runtime.c) and its report (gt_runtime_report.c) share:
 * the log entry's flags, the runtime's constants, the counts, the events, the command line. */
#ifndef GT_RUNTIME_STATE_H
#define GT_RUNTIME_STATE_H

#include <netinet/in.h>
#include <stdatomic.h>
#include <stdint.h>

#include "gt_guard.h"

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
#define F_OUT_OF_WINDOW 32768u
#define F_RESYNC 65536u
#define F_UNAPPLIED 131072u
#define F_SENT_LATE 262144u

#define GT_RT_RING 8192u /* entries: 32 s of cycles at 4 ms; the writer drains every 5 ms */
#define GT_RT_SEQ_WINDOW 250      /* cycles: a plausible jump of the robot's sequence, plus twice the cycles of a silence */
#define GT_RT_RESYNC_PACKETS 5    /* consecutive consistent packets beyond the window that restart the sequence */
#define GT_RT_SENSOR_WINDOW 10000 /* samples: a plausible jump of the tracker's seq, plus 20000 per second of silence */
#define GT_RT_HOLD_ALARM 5        /* consecutive cycles without the step's reply that raise an alarm */
#define GT_RT_MAX_EVENTS 256      /* events kept (silences, alarms, resynchronisations); more are counted */
#define GT_RT_LOG_REPEATS 100     /* consecutive duplicate / out-of-window datagrams logged row by row; more are counted */
#define GT_RT_MAX_DATAGRAM 4096
#define GT_RT_NSTATUS 32
/* GT_RT_CYCLE_STACK: gt_runtime_config.h, sized from the step's stack work arrays (robot_runtime.cycle_stack_bytes) */
#define GT_RT_WRITER_STACK (256u << 10)
#define GT_RT_RCVBUF_BYTES (1 << 20) /* asked for each socket's receive queue; the kernel caps it (net.core.rmem_max) */

typedef struct {
    uint64_t cycle, seq;
    double t, latency_us, t_monotonic;
    uint32_t flags;
    int32_t status, sensor_age;
    double x[GT_RT_NX], u[GT_RT_NU], y[GT_RT_NU], sent[GT_RT_NU];
} gt_rt_entry;


typedef struct {
    uint64_t packets, cycles, replies, malformed, too_long, non_finite, duplicate_or_old, missing_field, held;
    uint64_t fallback_stale, fallback_step, deadline_held, late_dropped, no_safe_reply, send_errors, compose_errors;
    uint64_t clamp_lower, clamp_upper, clamp_rate, step_calls, step_status[GT_RT_NSTATUS], step_status_other;
    uint64_t sensor_accepted, sensor_malformed, sensor_non_finite, sensor_old, sensor_short;
    uint64_t log_written, log_dropped, log_write_errors, log_capped, log_bytes, first_seq, last_seq;
    uint64_t before_lock, log_unlogged_repeats, unapplied, sent_late, start_outside, holds, hold_longest, silences, events_dropped;
    uint64_t rcvbuf_robot, rcvbuf_sensor, kernel_dropped_robot, kernel_dropped_sensor;
    double max_latency_us, silence_longest_s;
    int realtime_fifo, realtime_mlock;
    char realtime_reason[160];
    const char *end;
} gt_rt_stats;

extern gt_rt_stats gt_S; /* the counts */

/* events: written by the cycle thread only; the writer thread prints the alarms among those published */
#define EV_SILENCE 0
#define EV_HOLD 1
#define EV_RESYNC 2
#define EV_SENSOR_RESYNC 3
#define EV_LOCK 4
#define EV_SENSOR_LOCK 5
typedef struct {
    int kind;
    uint64_t cycle, seq, cycles;
    double t, length_s;
    uint32_t reasons;
} gt_rt_event;
extern gt_rt_event gt_events[GT_RT_MAX_EVENTS];
extern atomic_int gt_events_n;
extern gt_source gt_robot_src, gt_tracker_src;
extern gt_strangers gt_strangers_seen;
extern gt_seqwin gt_robot_seq, gt_sensor_seqw;

typedef struct {
    char out[3072], log_path[4096], stats_path[4096], ready_path[4096];
    struct sockaddr_in listen, sensor;
    int sensor_port_given;
    double idle_timeout, reply_deadline;
    uint64_t max_cycles, log_max_bytes;
    int realtime;
} gt_rt_options;
extern gt_rt_options gt_O; /* the command line */

/* the report (gt_runtime_report.c): the alarms on stderr, the counts as runtime_stats.json */
void gt_print_alarms(int *printed);
void gt_write_stats(const char *signal_name);
/* one line on stderr, then exit(code) */
void gt_fail(int code, const char *what, const char *detail);

#endif
