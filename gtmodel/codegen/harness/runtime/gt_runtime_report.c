/* gt_runtime_report.c: the runtime's report: its alarms on stderr (the log writer's thread) and its counts as
 * runtime_stats.json (at exit, after the threads are joined). Part of gtmodel's robot runtime (gt_runtime.c). */
#define _GNU_SOURCE
#include <errno.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define GT_RT_CONFIG_NO_TABLES
#include "gt_runtime_config.h"
#include "gt_runtime_state.h"

static const char *const gt_event_names[] = {"silence", "hold", "resync", "sensor_resync", "lock", "sensor_lock"};

static const char *const gt_flag_names[] = {"sent", "step", "held", "fallback_stale", "fallback_step", "ramp", "malformed", "non_finite",
                                             "duplicate_or_old", "missing_field", "deadline_held", "late_dropped", "clamped", "no_safe_reply",
                                             "too_long", "out_of_window", "resync", "unapplied", "sent_late"};

static void gt_flag_text(uint32_t flags, char *out, size_t cap)
{
    size_t n = 0;
    unsigned k;
    out[0] = '\0';
    for (k = 0; k < sizeof gt_flag_names / sizeof gt_flag_names[0]; ++k)
        if ((flags & (1u << k)) && n < cap) n += (size_t)snprintf(out + n, cap - n, "%s%s", n ? ", " : "", gt_flag_names[k]);
}

/* the alarms among the events published since the last call, on stderr (the writer thread) */
void gt_print_alarms(int *printed)
{
    int n = atomic_load_explicit(&gt_events_n, memory_order_acquire);
    for (; *printed < n; ++*printed) {
        const gt_rt_event *ev = &gt_events[*printed];
        if (ev->kind == EV_HOLD) {
            char why[400];
            gt_flag_text(ev->reasons, why, sizeof why);
            fprintf(stderr, "gt_runtime: alarm: no reply of the step for %d cycles from cycle %llu (t %.3f s): %s "
                            "(summary.json: loop.alarms)\n", GT_RT_HOLD_ALARM, (unsigned long long)ev->cycle, ev->t, why);
        }
        else if (ev->kind == EV_RESYNC || ev->kind == EV_SENSOR_RESYNC)
            fprintf(stderr, "gt_runtime: alarm: the %s's sequence restarted at %llu (cycle %llu, t %.3f s) after %d consecutive packets "
                            "beyond the window\n", ev->kind == EV_RESYNC ? "robot" : "tracker", (unsigned long long)ev->seq,
                    (unsigned long long)ev->cycle, ev->t, GT_RT_RESYNC_PACKETS);
    }
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

static void gt_write_source(FILE *f, const char *name, const gt_source *src)
{
    char text[64];
    fprintf(f, "\"%s\": ", name);
    if (src->locked || src->named) {
        gt_address_text(&src->addr, text, sizeof text);
        if (!src->locked && !src->named_port) *strrchr(text, ':') = '\0';
        gt_json_string(f, text);
    } else {
        fprintf(f, "null");
    }
    fprintf(f, ", \"%s_rule\": \"%s\"", name, src->named_port ? "named" : src->named ? "named_address_first_port" : "first_valid_packet");
}

/* the guard's counts: the session's sources, the strangers, the sequences, silences, alarms and the events */
static void gt_write_guard(FILE *f)
{
    int i, n = atomic_load(&gt_events_n);
    char text[64], why[400];
    fprintf(f, "  \"source\": {");
    gt_write_source(f, "robot", &gt_robot_src);
    fprintf(f, ", ");
    gt_write_source(f, "tracker", &gt_tracker_src);
    fprintf(f, ", \"before_lock\": %llu},\n", (unsigned long long)gt_S.before_lock);
    fprintf(f, "  \"strangers\": {\"datagrams\": %llu, \"other_addresses_datagrams\": %llu, \"addresses\": [",
            (unsigned long long)gt_strangers_seen.total, (unsigned long long)gt_strangers_seen.other);
    for (i = 0; i < gt_strangers_seen.n; ++i) {
        struct sockaddr_in a;
        memset(&a, 0, sizeof a);
        a.sin_family = AF_INET;
        a.sin_addr.s_addr = gt_strangers_seen.e[i].ip;
        a.sin_port = gt_strangers_seen.e[i].port;
        gt_address_text(&a, text, sizeof text);
        fprintf(f, "%s{\"address\": ", i ? ", " : "");
        gt_json_string(f, text);
        fprintf(f, ", \"socket\": \"%s\", \"datagrams\": %llu}", gt_strangers_seen.e[i].socket ? "sensor" : "robot",
                (unsigned long long)gt_strangers_seen.e[i].count);
    }
    fprintf(f, "]},\n");
    fprintf(f, "  \"receive_queue\": {\"kernel_dropped\": %llu, \"buffer_bytes\": %llu, \"sensor_kernel_dropped\": %llu, "
               "\"sensor_buffer_bytes\": %llu},\n",
            (unsigned long long)gt_S.kernel_dropped_robot, (unsigned long long)gt_S.rcvbuf_robot,
            (unsigned long long)gt_S.kernel_dropped_sensor, (unsigned long long)gt_S.rcvbuf_sensor);
    fprintf(f, "  \"sequence\": {\"out_of_window\": %llu, \"resyncs\": %llu, \"window_cycles\": %d, \"resync_packets\": %d, "
               "\"sensor_out_of_window\": %llu, \"sensor_resyncs\": %llu, \"sensor_window\": %d},\n",
            (unsigned long long)gt_robot_seq.out_of_window, (unsigned long long)gt_robot_seq.resyncs, GT_RT_SEQ_WINDOW,
            GT_RT_RESYNC_PACKETS, (unsigned long long)gt_sensor_seqw.out_of_window, (unsigned long long)gt_sensor_seqw.resyncs,
            GT_RT_SENSOR_WINDOW);
    fprintf(f, "  \"relative\": {\"unapplied\": %llu},\n  \"sent_late\": %llu,\n  \"start_outside_limits\": %llu,\n",
            (unsigned long long)gt_S.unapplied, (unsigned long long)gt_S.sent_late, (unsigned long long)gt_S.start_outside);
    fprintf(f, "  \"silences\": {\"count\": %llu, \"longest_s\": %.9g},\n", (unsigned long long)gt_S.silences, gt_S.silence_longest_s);
    fprintf(f, "  \"alarms\": {\"holds\": %llu, \"longest_hold_cycles\": %llu, \"hold_alarm_cycles\": %d},\n",
            (unsigned long long)gt_S.holds, (unsigned long long)gt_S.hold_longest, GT_RT_HOLD_ALARM);
    fprintf(f, "  \"events_dropped\": %llu,\n  \"events\": [", (unsigned long long)gt_S.events_dropped);
    for (i = 0; i < n; ++i) {
        const gt_rt_event *ev = &gt_events[i];
        fprintf(f, "%s\n    {\"kind\": \"%s\", \"cycle\": %llu, \"seq\": %llu, \"t\": %.6f", i ? "," : "", gt_event_names[ev->kind],
                (unsigned long long)ev->cycle, (unsigned long long)ev->seq, ev->t);
        if (ev->kind == EV_SILENCE || ev->kind == EV_HOLD) fprintf(f, ", \"length_s\": %.6f", ev->length_s);
        if (ev->kind == EV_HOLD) {
            gt_flag_text(ev->reasons, why, sizeof why);
            fprintf(f, ", \"cycles\": %llu, \"reasons\": ", (unsigned long long)ev->cycles);
            gt_json_string(f, why);
        }
        fprintf(f, "}");
    }
    fprintf(f, "%s],\n", n ? "\n  " : "");
}

void gt_write_stats(const char *signal_name)
{
    char tmp[4200];
    FILE *f;
    int i, first = 1;
    snprintf(tmp, sizeof tmp, "%s.tmp", gt_O.stats_path);
    f = fopen(tmp, "w");
    if (f == NULL) gt_fail(3, "cannot write the stats file", strerror(errno));
    fprintf(f, "{\n  \"format\": \"gtmodel runtime stats 1\",\n  \"interface\": \"%s\",\n", GT_RT_INTERFACE_NAME);
    fprintf(f, "  \"end\": \"%s\",\n  \"signal\": ", gt_S.end ? gt_S.end : "error");
    if (signal_name) fprintf(f, "\"%s\",\n", signal_name);
    else fprintf(f, "null,\n");
    fprintf(f, "  \"packets\": %llu,\n  \"cycles\": %llu,\n  \"replies\": %llu,\n  \"malformed\": %llu,\n  \"too_long\": %llu,\n",
            (unsigned long long)gt_S.packets, (unsigned long long)gt_S.cycles, (unsigned long long)gt_S.replies,
            (unsigned long long)gt_S.malformed, (unsigned long long)gt_S.too_long);
    fprintf(f, "  \"non_finite\": %llu,\n  \"duplicate_or_old\": %llu,\n  \"missing_field\": %llu,\n  \"held_replies\": %llu,\n",
            (unsigned long long)gt_S.non_finite, (unsigned long long)gt_S.duplicate_or_old, (unsigned long long)gt_S.missing_field,
            (unsigned long long)gt_S.held);
    fprintf(f, "  \"fallback_cycles\": {\"stale_sensor\": %llu, \"step_failed\": %llu},\n  \"fallback\": \"%s\",\n",
            (unsigned long long)gt_S.fallback_stale, (unsigned long long)gt_S.fallback_step, GT_RT_RAMP ? "ramp" : "hold");
    fprintf(f, "  \"deadline_held\": %llu,\n  \"late_dropped\": %llu,\n  \"no_safe_reply\": %llu,\n  \"send_errors\": %llu,\n  \"compose_errors\": %llu,\n",
            (unsigned long long)gt_S.deadline_held, (unsigned long long)gt_S.late_dropped, (unsigned long long)gt_S.no_safe_reply,
            (unsigned long long)gt_S.send_errors, (unsigned long long)gt_S.compose_errors);
    fprintf(f, "  \"limit_clamps\": {\"lower\": %llu, \"upper\": %llu, \"rate\": %llu},\n", (unsigned long long)gt_S.clamp_lower,
            (unsigned long long)gt_S.clamp_upper, (unsigned long long)gt_S.clamp_rate);
    fprintf(f, "  \"sensor\": {\"accepted\": %llu, \"malformed\": %llu, \"non_finite\": %llu, \"duplicate_or_old\": %llu, \"too_few_values\": %llu},\n",
            (unsigned long long)gt_S.sensor_accepted, (unsigned long long)gt_S.sensor_malformed, (unsigned long long)gt_S.sensor_non_finite,
            (unsigned long long)gt_S.sensor_old, (unsigned long long)gt_S.sensor_short);
    fprintf(f, "  \"step_calls\": %llu,\n  \"step_status\": {", (unsigned long long)gt_S.step_calls);
    for (i = 0; i < GT_RT_NSTATUS; ++i) {
        if (gt_S.step_status[i] == 0) continue;
        fprintf(f, "%s", first ? "" : ", ");
        gt_json_string(f, gt_rt_status_string(i));
        fprintf(f, ": %llu", (unsigned long long)gt_S.step_status[i]);
        first = 0;
    }
    if (gt_S.step_status_other) fprintf(f, "%s\"other\": %llu", first ? "" : ", ", (unsigned long long)gt_S.step_status_other);
    fprintf(f, "},\n  \"log\": {\"written\": %llu, \"dropped\": %llu, \"write_errors\": %llu, \"capped\": %llu, \"bytes\": %llu, "
               "\"max_bytes\": %llu, \"unlogged_repeats\": %llu},\n", (unsigned long long)gt_S.log_written, (unsigned long long)gt_S.log_dropped,
            (unsigned long long)gt_S.log_write_errors, (unsigned long long)gt_S.log_capped, (unsigned long long)gt_S.log_bytes,
            (unsigned long long)gt_O.log_max_bytes, (unsigned long long)gt_S.log_unlogged_repeats);
    gt_write_guard(f);
    fprintf(f, "  \"realtime\": {\"granted\": %s, \"sched_fifo\": %s, \"mlockall\": %s, \"reason\": ",
            gt_S.realtime_fifo && gt_S.realtime_mlock ? "true" : "false", gt_S.realtime_fifo ? "true" : "false", gt_S.realtime_mlock ? "true" : "false");
    gt_json_string(f, gt_S.realtime_reason);
    fprintf(f, "},\n  \"first_ipoc_or_seq\": %llu,\n  \"last_ipoc_or_seq\": %llu,\n  \"max_latency_us\": %.17g,\n",
            (unsigned long long)gt_S.first_seq, (unsigned long long)gt_S.last_seq, gt_S.max_latency_us);
    fprintf(f, "  \"period_s\": %.17g,\n  \"reply_deadline_s\": %.17g,\n  \"stale_cycles\": %d\n}\n", (double)GT_RT_PERIOD_S, gt_O.reply_deadline,
            (int)GT_RT_STALE_CYCLES);
    if (fclose(f) != 0 || rename(tmp, gt_O.stats_path) != 0) gt_fail(3, "cannot write the stats file", strerror(errno));
}
