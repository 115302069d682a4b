/*@template (stripped when filled: gtmodel.codegen.emit.fill)
 * The timing program of the self-checks (gtmodel.codegen.check.run.time_program): blocks that
 * each call one generated function in a loop and print "label<TAB>ns per call[<TAB>...]".
 * Markers: @HEADER@ the generated header, @TABLES@ constant input tables (may be empty),
 * @BLOCKS@ the timed blocks.
 */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <time.h>
#include "@HEADER@"

static double now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}
@TABLES@
int main(void)
{
    volatile double sink = 0.0;
    int status = 0;
    long i, n;
    double t0, t1;
@BLOCKS@
    return status != 0;
}
