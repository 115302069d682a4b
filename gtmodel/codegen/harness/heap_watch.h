/* Heap-allocation counter of the harness programs (loop.c, retime_example.c, the filter
 * check's stand-alone run): link with -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free.
 * Every allocator call made while heap_watch is non-zero adds one to heap_calls; the
 * real-time parts of a cycle must leave it at 0. Include it in one file of a program. */
#ifndef GT_HEAP_WATCH_H
#define GT_HEAP_WATCH_H

#include <stddef.h>

static long heap_calls = 0; /* counts calls made while heap_watch is set */
static int heap_watch = 0;
void *__real_malloc(size_t n);
void *__real_calloc(size_t n, size_t m);
void *__real_realloc(void *p, size_t n);
void __real_free(void *p);
void *__wrap_malloc(size_t n);
void *__wrap_calloc(size_t n, size_t m);
void *__wrap_realloc(void *p, size_t n);
void __wrap_free(void *p);
void *__wrap_malloc(size_t n) { heap_calls += heap_watch; return __real_malloc(n); }
void *__wrap_calloc(size_t n, size_t m) { heap_calls += heap_watch; return __real_calloc(n, m); }
void *__wrap_realloc(void *p, size_t n) { heap_calls += heap_watch; return __real_realloc(p, n); }
void __wrap_free(void *p) { heap_calls += heap_watch; __real_free(p); }

#endif
