/* gt_sensor_stream.h: the GTS1 sensor datagrams (laser tracker, IMU) into gtmodel's robot runtime.
 *
 * One sample per UDP datagram, ASCII: "GTS1 <seq> <t_s> <v1> ... <vn>\n" with single spaces,
 * seq a decimal unsigned 64-bit integer, t_s the sender's clock [s], 1 <= n <= 16 values, all
 * strict finite decimal numbers (gt_parse_number), the final newline optional. No heap.
 */
#ifndef GT_SENSOR_STREAM_H
#define GT_SENSOR_STREAM_H

#include <stddef.h>
#include <stdint.h>

#define GT_SENSOR_MAX_VALUES 16
#define GT_SENSOR_MAX_LEN 1024

#define GT_SENSOR_OK 0
#define GT_SENSOR_MALFORMED 1
#define GT_SENSOR_TOO_LONG 2
#define GT_SENSOR_NON_FINITE 3

typedef struct gt_sensor_sample {
    uint64_t seq;
    double t;
    int n;                                /* number of values */
    double value[GT_SENSOR_MAX_VALUES];
} gt_sensor_sample;

/* Parse one datagram of len bytes. Returns a GT_SENSOR_* code; *out is written in every case. */
int gt_sensor_parse(const char *buf, size_t len, gt_sensor_sample *out);

#endif
