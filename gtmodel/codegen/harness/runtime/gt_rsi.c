/* gt_rsi.c: the RSI <Rob> parser and <Sen> composer (see gt_rsi.h).
 *
 * The parser is one linear pass over at most GT_RSI_MAX_LEN bytes with an explicit bounded
 * stack of open element names (GT_RSI_MAX_DEPTH): no recursion, no heap, every index checked
 * against the length before it is read. It accepts: an optional XML declaration, comments and
 * processing instructions; the root <Rob ...>; any elements inside it (closing tags must match,
 * unknown elements and attributes are skipped); the known elements (RIst, RSol, AIPos, ASPos,
 * ELPos, ESPos, Delay) as direct children of <Rob>, each at most once, their known attributes
 * at most once and as strict numbers; exactly one <IPOC> (decimal digits, unsigned 64-bit,
 * overflow refused). Anything else (a missing quote, a truncated tag, NUL bytes, text after
 * </Rob>, a number of more than GT_RSI_MAX_NUMBER characters) is GT_RSI_MALFORMED.
 */
#include "gt_rsi.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    const char *name;
    int first;             /* index of its first field */
    const char *attrs[6];  /* attribute names, NULL-terminated */
} gt_rsi_element;

static const gt_rsi_element gt_rsi_elements[] = {
    {"RIst", 0, {"X", "Y", "Z", "A", "B", "C"}},
    {"RSol", 6, {"X", "Y", "Z", "A", "B", "C"}},
    {"AIPos", 12, {"A1", "A2", "A3", "A4", "A5", "A6"}},
    {"ASPos", 18, {"A1", "A2", "A3", "A4", "A5", "A6"}},
    {"ELPos", 24, {"E1", "E2", "E3", "E4", "E5", "E6"}},
    {"ESPos", 30, {"E1", "E2", "E3", "E4", "E5", "E6"}},
    {"Delay", 36, {"D", NULL, NULL, NULL, NULL, NULL}},
};
#define GT_RSI_NELEMENTS ((int)(sizeof gt_rsi_elements / sizeof gt_rsi_elements[0]))

static int gt_eq(const char *a, size_t alen, const char *lit)
{
    size_t n = strlen(lit);
    return alen == n && memcmp(a, lit, n) == 0;
}

static int gt_ieq(const char *a, size_t alen, const char *lit)
{
    size_t i, n = strlen(lit);
    if (alen != n) return 0;
    for (i = 0; i < n; ++i) {
        char c = a[i];
        if (c >= 'A' && c <= 'Z') c = (char)(c - 'A' + 'a');
        if (c != lit[i]) return 0;
    }
    return 1;
}

int gt_parse_number(const char *text, size_t len, double *value)
{
    char tmp[GT_RSI_MAX_NUMBER + 1];
    const char *p = text;
    size_t i = 0, digits = 0;
    char *end = NULL;
    double v;
    if (text == NULL || value == NULL || len == 0 || len > GT_RSI_MAX_NUMBER) return -1;
    if (p[0] == '+' || p[0] == '-') i = 1;
    if (gt_ieq(p + i, len - i, "nan") || gt_ieq(p + i, len - i, "inf") || gt_ieq(p + i, len - i, "infinity")) {
        *value = NAN;
        return 1;
    }
    for (; i < len && p[i] >= '0' && p[i] <= '9'; ++i) ++digits;
    if (i < len && p[i] == '.') {
        for (++i; i < len && p[i] >= '0' && p[i] <= '9'; ++i) ++digits;
    }
    if (digits == 0) return -1;
    if (i < len && (p[i] == 'e' || p[i] == 'E')) {
        size_t e = 0;
        ++i;
        if (i < len && (p[i] == '+' || p[i] == '-')) ++i;
        for (; i < len && p[i] >= '0' && p[i] <= '9'; ++i) ++e;
        if (e == 0) return -1;
    }
    if (i != len) return -1;
    memcpy(tmp, text, len); /* a bounded NUL-terminated copy for strtod */
    tmp[len] = '\0';
    errno = 0;
    v = strtod(tmp, &end);
    if (end != tmp + len) return -1;
    if (!isfinite(v) || (errno == ERANGE && fabs(v) > 1.0)) { /* overflow; underflow to ~0 is a number */
        *value = NAN;
        return 1;
    }
    *value = v;
    return 0;
}

static int gt_is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

static int gt_is_name(char c)
{
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-' || c == '.' || c == ':';
}

/* The position of the literal lit at or after i, or len. */
static size_t gt_find(const char *s, size_t len, size_t i, const char *lit)
{
    size_t n = strlen(lit);
    for (; i + n <= len; ++i) {
        if (memcmp(s + i, lit, n) == 0) return i;
    }
    return len;
}

static int gt_rsi_ipoc(const char *s, size_t len, uint64_t *ipoc)
{
    size_t a = 0, b = len, i;
    uint64_t v = 0;
    while (a < b && gt_is_space(s[a])) ++a;
    while (b > a && gt_is_space(s[b - 1])) --b;
    if (a == b || b - a > 20) return -1;
    for (i = a; i < b; ++i) {
        unsigned d;
        if (s[i] < '0' || s[i] > '9') return -1;
        d = (unsigned)(s[i] - '0');
        if (v > (UINT64_MAX - d) / 10u) return -1; /* overflow */
        v = v * 10u + d;
    }
    *ipoc = v;
    return 0;
}

int gt_rsi_parse(const char *s, size_t len, gt_rsi_rob *out)
{
    const char *stack[GT_RSI_MAX_DEPTH];
    size_t stack_len[GT_RSI_MAX_DEPTH];
    int depth = 0, seen_root = 0, closed_root = 0, n_ipoc = 0, non_finite = 0;
    size_t i = 0, ipoc_text = 0;
    int in_ipoc = 0;
    memset(out, 0, sizeof *out);
    if (s == NULL) return GT_RSI_MALFORMED;
    if (len > GT_RSI_MAX_LEN) return GT_RSI_TOO_LONG;
    if (memchr(s, '\0', len) != NULL) return GT_RSI_MALFORMED;
    while (i < len) {
        size_t name, name_len, j;
        int closing = 0, empty = 0, known = -1;
        if (s[i] != '<') { /* text: only inside the root; whitespace outside */
            size_t lt = i;
            while (lt < len && s[lt] != '<') ++lt;
            if (depth == 0) {
                for (j = i; j < lt; ++j) {
                    if (!gt_is_space(s[j])) return GT_RSI_MALFORMED;
                }
            }
            i = lt;
            continue;
        }
        if (i + 1 >= len) return GT_RSI_MALFORMED;
        if (s[i + 1] == '?' || (i + 3 < len && s[i + 1] == '!' && s[i + 2] == '-' && s[i + 3] == '-')) { /* PI, comment */
            size_t e = s[i + 1] == '?' ? gt_find(s, len, i + 2, "?>") : gt_find(s, len, i + 4, "-->");
            if (e >= len) return GT_RSI_MALFORMED;
            i = e + (s[i + 1] == '?' ? 2 : 3);
            continue;
        }
        if (closed_root) return GT_RSI_MALFORMED; /* a second element after </Rob> */
        ++i;
        if (s[i] == '/') {
            closing = 1;
            ++i;
        }
        name = i;
        while (i < len && gt_is_name(s[i])) ++i;
        name_len = i - name;
        if (name_len == 0 || i >= len) return GT_RSI_MALFORMED;
        if (closing) {
            while (i < len && gt_is_space(s[i])) ++i;
            if (i >= len || s[i] != '>' || depth == 0) return GT_RSI_MALFORMED;
            if (stack_len[depth - 1] != name_len || memcmp(stack[depth - 1], s + name, name_len) != 0) return GT_RSI_MALFORMED;
            if (in_ipoc && depth == 2) {
                if (gt_rsi_ipoc(s + ipoc_text, name - 2 - ipoc_text, &out->ipoc) != 0) return GT_RSI_MALFORMED;
                in_ipoc = 0;
            }
            --depth;
            if (depth == 0) closed_root = 1;
            ++i;
            continue;
        }
        if (depth == 0) {
            if (seen_root || !gt_eq(s + name, name_len, "Rob")) return GT_RSI_MALFORMED;
            seen_root = 1;
        } else if (depth == 1) {
            int k;
            for (k = 0; k < GT_RSI_NELEMENTS; ++k) {
                if (gt_eq(s + name, name_len, gt_rsi_elements[k].name)) known = k;
            }
        }
        if (in_ipoc) return GT_RSI_MALFORMED; /* an element inside IPOC */
        /* attributes */
        for (;;) {
            size_t an, an_len, vs, ve;
            char q;
            int had_space = 0;
            while (i < len && gt_is_space(s[i])) {
                ++i;
                had_space = 1;
            }
            if (i >= len) return GT_RSI_MALFORMED;
            if (s[i] == '>') {
                ++i;
                break;
            }
            if (s[i] == '/') {
                if (i + 1 >= len || s[i + 1] != '>') return GT_RSI_MALFORMED;
                empty = 1;
                i += 2;
                break;
            }
            if (!had_space) return GT_RSI_MALFORMED;
            an = i;
            while (i < len && gt_is_name(s[i])) ++i;
            an_len = i - an;
            if (an_len == 0) return GT_RSI_MALFORMED;
            while (i < len && gt_is_space(s[i])) ++i;
            if (i >= len || s[i] != '=') return GT_RSI_MALFORMED;
            ++i;
            while (i < len && gt_is_space(s[i])) ++i;
            if (i >= len || (s[i] != '"' && s[i] != '\'')) return GT_RSI_MALFORMED;
            q = s[i++];
            vs = i;
            while (i < len && s[i] != q && s[i] != '<') ++i;
            if (i >= len || s[i] != q) return GT_RSI_MALFORMED;
            ve = i++;
            if (known >= 0) {
                int a;
                for (a = 0; a < 6 && gt_rsi_elements[known].attrs[a] != NULL; ++a) {
                    if (gt_eq(s + an, an_len, gt_rsi_elements[known].attrs[a])) {
                        int f = gt_rsi_elements[known].first + a, r;
                        size_t b = vs, e = ve;
                        double v = 0.0;
                        if (out->present & ((uint64_t)1 << f)) return GT_RSI_MALFORMED; /* the same field twice */
                        while (b < e && gt_is_space(s[b])) ++b;
                        while (e > b && gt_is_space(s[e - 1])) --e;
                        r = gt_parse_number(s + b, e - b, &v);
                        if (r < 0) return GT_RSI_MALFORMED;
                        if (r > 0) non_finite = 1;
                        out->field[f] = v;
                        out->present |= (uint64_t)1 << f;
                    }
                }
            }
        }
        if (depth == 1 && gt_eq(s + name, name_len, "IPOC")) {
            if (empty || n_ipoc++ > 0) return GT_RSI_MALFORMED;
            in_ipoc = 1;
            ipoc_text = i;
        }
        if (!empty) {
            if (depth >= GT_RSI_MAX_DEPTH) return GT_RSI_MALFORMED;
            stack[depth] = s + name;
            stack_len[depth] = name_len;
            ++depth;
        } else if (depth == 0) {
            return GT_RSI_MALFORMED; /* <Rob/> */
        }
    }
    if (!closed_root || n_ipoc != 1 || in_ipoc) return GT_RSI_MALFORMED;
    return non_finite ? GT_RSI_NON_FINITE : GT_RSI_OK;
}

int gt_rsi_compose(char *out, size_t cap, const char *sen_type, unsigned elements, const double *value, uint64_t ipoc)
{
    static const char *const names[3] = {"RKorr", "AKorr", "EKorr"};
    static const char *const attrs[3][6] = {{"X", "Y", "Z", "A", "B", "C"}, {"A1", "A2", "A3", "A4", "A5", "A6"}, {"E1", "E2", "E3", "E4", "E5", "E6"}};
    size_t n = 0;
    int k, a, w;
    if (out == NULL || cap == 0 || sen_type == NULL || value == NULL) return -1;
    w = snprintf(out, cap, "<Sen Type=\"%s\"><EStr>gtmodel</EStr>", sen_type);
    if (w < 0 || (size_t)w >= cap) return -1;
    n = (size_t)w;
    for (k = 0; k < 3; ++k) {
        if (!(elements & (1u << k))) continue;
        w = snprintf(out + n, cap - n, "<%s", names[k]);
        if (w < 0 || (size_t)w >= cap - n) return -1;
        n += (size_t)w;
        for (a = 0; a < 6; ++a) {
            double v = value[6 * k + a];
            if (!isfinite(v) || fabs(v) > 1e9) return -1;
            w = snprintf(out + n, cap - n, " %s=\"%.6f\"", attrs[k][a], v);
            if (w < 0 || (size_t)w >= cap - n) return -1;
            n += (size_t)w;
        }
        w = snprintf(out + n, cap - n, "/>");
        if (w < 0 || (size_t)w >= cap - n) return -1;
        n += (size_t)w;
    }
    w = snprintf(out + n, cap - n, "<IPOC>%llu</IPOC></Sen>", (unsigned long long)ipoc);
    if (w < 0 || (size_t)w >= cap - n) return -1;
    return (int)(n + (size_t)w);
}
