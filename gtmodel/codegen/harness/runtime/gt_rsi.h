/* gt_rsi.h: KUKA RSI XML over UDP, the robot's <Rob> datagram parsed and the <Sen> reply composed.
 * Part of gtmodel's robot runtime (gtmodel.codegen.robot_runtime); no heap, no recursion.
 *
 * Robot -> sensor (every 4 ms; attribute order, whitespace and extra elements free):
 *   <Rob Type="KUKA"><RIst X=".." Y=".." Z=".." A=".." B=".." C=".."/><RSol .../>
 *   <AIPos A1=".." .. A6=".."/><ASPos .../><ELPos E1=".." ../><ESPos .../><Delay D=".."/>
 *   <IPOC>123456</IPOC></Rob>
 * Sensor -> robot:
 *   <Sen Type="ImFree"><EStr>gtmodel</EStr><RKorr X=".." .. C=".."/><AKorr A1=".." .. A6=".."/>
 *   <EKorr E1=".." .. E6=".."/><IPOC>123456</IPOC></Sen>   (only the elements the runtime writes)
 */
#ifndef GT_RSI_H
#define GT_RSI_H

#include <stddef.h>
#include <stdint.h>

/* Longest datagram accepted [bytes]; a longer one is refused (GT_RSI_TOO_LONG). */
#define GT_RSI_MAX_LEN 4096
/* Longest number text accepted [characters] (a longer one: GT_RSI_MALFORMED). */
#define GT_RSI_MAX_NUMBER 64
/* Deepest element nesting accepted (Rob is depth 1). */
#define GT_RSI_MAX_DEPTH 16

/* The measured fields of <Rob>, in this order (gtmodel.codegen.robot_runtime.RSI_INPUTS):
 * RIst.X..C 0-5, RSol.X..C 6-11, AIPos.A1..A6 12-17, ASPos.A1..A6 18-23, ELPos.E1..E6 24-29,
 * ESPos.E1..E6 30-35, Delay.D 36. */
#define GT_RSI_NFIELDS 37
/* The reply fields of <Sen>: RKorr.X..C 0-5, AKorr.A1..A6 6-11, EKorr.E1..E6 12-17. */
#define GT_RSI_NREPLY 18

/* Parse results. */
#define GT_RSI_OK 0
#define GT_RSI_MALFORMED 1  /* not a well-formed <Rob> with one IPOC: nothing to echo */
#define GT_RSI_TOO_LONG 2   /* longer than GT_RSI_MAX_LEN */
#define GT_RSI_NON_FINITE 3 /* well formed with its IPOC, but a field is NaN, infinite or overflows */

typedef struct gt_rsi_rob {
    double field[GT_RSI_NFIELDS]; /* the values (0 where absent) */
    uint64_t present;             /* bit i: field i was in the datagram */
    uint64_t ipoc;                /* the IPOC (valid unless GT_RSI_MALFORMED / GT_RSI_TOO_LONG) */
} gt_rsi_rob;

/* Parse one datagram of len bytes (need not be NUL-terminated; NUL bytes inside are refused).
 * Returns a GT_RSI_* code; *out is written in every case. */
int gt_rsi_parse(const char *buf, size_t len, gt_rsi_rob *out);

/* Compose the reply into out[cap]: sen_type (validated at generation: [A-Za-z0-9_]+), the
 * elements whose bit is set in elements (1 RKorr, 2 AKorr, 4 EKorr) with value[GT_RSI_NREPLY]
 * (%.6f; mm and degrees), the IPOC. Returns the length, or -1 when it does not fit or a value
 * is not finite. */
int gt_rsi_compose(char *out, size_t cap, const char *sen_type, unsigned elements, const double *value, uint64_t ipoc);

/* The strict number parser shared with the sensor stream: text[0..len) holds only an optional
 * sign, digits, an optional fraction and an optional exponent (or nan / inf / infinity, any case,
 * with an optional sign). Returns 0 and *value for a finite number, 1 for a non-finite one
 * (NaN, inf, overflow), -1 for anything else. */
int gt_parse_number(const char *text, size_t len, double *value);

#endif
