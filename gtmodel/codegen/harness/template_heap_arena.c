/*@template (stripped when filled: gtmodel.codegen.emit.fill)
 * The heap arena of a loop controller whose QP solver allocates (DAQP: its setup mallocs its
 * work in every QP), appended to the wrapper source when the CasADi source includes it
 * (gtmodel.codegen.loop_step). The library is linked with
 * -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free, so the solver's allocator calls
 * come here: a bump allocator in a per-thread static block, reset when its last block is freed
 * (every QP frees all it allocated). Markers: @GP@ the prefix, @ARENA@ the block's bytes.
 */

#include <stddef.h>
#include <string.h>

#ifndef GT_HEAP_ARENA_BYTES
#define GT_HEAP_ARENA_BYTES @ARENA@
#endif

void *__real_malloc(size_t n);
void *__real_calloc(size_t n, size_t m);
void *__real_realloc(void *p, size_t n);
void __real_free(void *p);
void *__wrap_malloc(size_t n);
void *__wrap_calloc(size_t n, size_t m);
void *__wrap_realloc(void *p, size_t n);
void __wrap_free(void *p);

/* 16-byte aligned blocks, each after a 16-byte header holding its size */
#define GT_ARENA_ALIGN 16u
typedef union { long double ld; double d; void *p; size_t size; unsigned char b[GT_ARENA_ALIGN]; } gt_arena_cell;

static __thread gt_arena_cell gt_arena[GT_HEAP_ARENA_BYTES / sizeof(gt_arena_cell)];
static __thread size_t gt_arena_used = 0;      /* cells in use */
static __thread size_t gt_arena_live = 0;      /* blocks not freed */
static __thread size_t gt_arena_peak = 0;      /* most cells in use */
static __thread unsigned long gt_arena_heap = 0; /* allocations passed to the heap (the arena full) */

static int gt_in_arena(const void *p)
{
    return p != NULL && (const unsigned char *)p >= (const unsigned char *)gt_arena
        && (const unsigned char *)p < (const unsigned char *)(gt_arena + sizeof(gt_arena) / sizeof(gt_arena_cell));
}

void *__wrap_malloc(size_t n)
{
    size_t cells = (n + sizeof(gt_arena_cell) - 1u) / sizeof(gt_arena_cell) + 1u;
    size_t total = sizeof(gt_arena) / sizeof(gt_arena_cell);
    if (n <= GT_HEAP_ARENA_BYTES && cells <= total - gt_arena_used) {
        gt_arena_cell *head = gt_arena + gt_arena_used;
        head->size = n;
        gt_arena_used += cells;
        gt_arena_live += 1u;
        if (gt_arena_used > gt_arena_peak) gt_arena_peak = gt_arena_used;
        return head + 1;
    }
    gt_arena_heap += 1u;
    return __real_malloc(n);
}

void *__wrap_calloc(size_t n, size_t m)
{
    void *p;
    if (m != 0u && n > (size_t)-1 / m) return NULL;
    p = __wrap_malloc(n * m);
    if (p != NULL) memset(p, 0, n * m);
    return p;
}

void __wrap_free(void *p)
{
    if (!gt_in_arena(p)) {
        __real_free(p);
        return;
    }
    if (gt_arena_live > 0u && --gt_arena_live == 0u) gt_arena_used = 0u;
}

void *__wrap_realloc(void *p, size_t n)
{
    void *q;
    size_t old;
    if (!gt_in_arena(p)) {
        gt_arena_heap += 1u;
        return __real_realloc(p, n);
    }
    old = ((gt_arena_cell *)p - 1)->size;
    q = __wrap_malloc(n);
    if (q != NULL) {
        memcpy(q, p, old < n ? old : n);
        __wrap_free(p);
    }
    return q;
}

int @GP@_heap_stats(unsigned long *peak_bytes, unsigned long *heap_calls, unsigned long *arena_bytes)
{
    if (peak_bytes == NULL || heap_calls == NULL || arena_bytes == NULL) return GT_BAD_ARGUMENT;
    *peak_bytes = (unsigned long)(gt_arena_peak * sizeof(gt_arena_cell));
    *heap_calls = gt_arena_heap;
    *arena_bytes = (unsigned long)sizeof(gt_arena);
    return GT_OK;
}
