/*@template (stripped when filled: gtmodel.codegen.emit.fill)
 * The static helpers of the wrapper source (gtmodel.codegen.emit.robot drops those no wrapper
 * calls, for -Werror). Marker: @GP@ the C prefix.
 */
/* 1 if all n values are finite. */
static int @GP@_finite(const casadi_real *x, int n)
{
    int i;
    for (i = 0; i < n; ++i) {
        if (!isfinite(x[i])) return 0;
    }
    return 1;
}

/* 1 if x[i] op t for all i (NaN fails); op 0: >=, 1: >. */
static int @GP@_all(const casadi_real *x, int n, double t, int strict)
{
    int i;
    for (i = 0; i < n; ++i) {
        if (strict ? !(x[i] > t) : !(x[i] >= t)) return 0;
    }
    return 1;
}

/* dst = src (n values). */
static void @GP@_copy(casadi_real *dst, const casadi_real *src, int n)
{
    int i;
    for (i = 0; i < n; ++i) dst[i] = src[i];
}

/* dst (column-major, CasADi) = src (row-major, API) for an r x c matrix, or back (swap r, c). */
static void @GP@_transpose(casadi_real *dst, const casadi_real *src, int r, int c)
{
    int i;
    for (i = 0; i < r * c; ++i) dst[(i % c) * r + i / c] = src[i];
}

/* IK root signs of configuration c (bit i set: +1, clear: -1); 0 if c is valid. */
static int @GP@_signs(int c, casadi_real s[3])
{
    int i;
    if (c < 0 || c > 7) return 1;
    for (i = 0; i < 3; ++i) s[i] = ((c >> i) & 1) ? 1.0 : -1.0;
    return 0;
}

