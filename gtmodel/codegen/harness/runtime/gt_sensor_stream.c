/* gt_sensor_stream.c: the strict GTS1 parser (see gt_sensor_stream.h). */
#include "gt_sensor_stream.h"

#include <string.h>

#include "gt_rsi.h" /* gt_parse_number */

int gt_sensor_parse(const char *s, size_t len, gt_sensor_sample *out)
{
    size_t i, tok;
    int field = 0, non_finite = 0;
    memset(out, 0, sizeof *out);
    if (s == NULL) return GT_SENSOR_MALFORMED;
    if (len > GT_SENSOR_MAX_LEN) return GT_SENSOR_TOO_LONG;
    if (len > 0 && s[len - 1] == '\n') --len;
    if (len < 5 || memcmp(s, "GTS1 ", 5) != 0) return GT_SENSOR_MALFORMED;
    i = 5;
    while (i <= len) {
        tok = i;
        while (i < len && s[i] != ' ') ++i;
        if (i == tok) return GT_SENSOR_MALFORMED; /* empty token: a double space, a trailing space */
        if (field == 0) { /* seq */
            size_t k;
            uint64_t v = 0;
            if (i - tok > 20) return GT_SENSOR_MALFORMED;
            for (k = tok; k < i; ++k) {
                unsigned d;
                if (s[k] < '0' || s[k] > '9') return GT_SENSOR_MALFORMED;
                d = (unsigned)(s[k] - '0');
                if (v > (UINT64_MAX - d) / 10u) return GT_SENSOR_MALFORMED;
                v = v * 10u + d;
            }
            out->seq = v;
        } else {
            double v = 0.0;
            int r = gt_parse_number(s + tok, i - tok, &v);
            if (r < 0) return GT_SENSOR_MALFORMED;
            if (r > 0) non_finite = 1;
            if (field == 1) {
                out->t = v;
            } else {
                if (out->n >= GT_SENSOR_MAX_VALUES) return GT_SENSOR_MALFORMED;
                out->value[out->n++] = v;
            }
        }
        ++field;
        if (i == len) break;
        ++i; /* the space */
    }
    if (out->n < 1) return GT_SENSOR_MALFORMED;
    return non_finite ? GT_SENSOR_NON_FINITE : GT_SENSOR_OK;
}
