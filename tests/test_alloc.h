/* test_alloc.h - the counting allocator of the tests and the bench, for
   HAIROBB_MALLOC/HAIROBB_FREE, keyed by the build's allocator_user.

   A test_allocator counts the calls, the blocks and bytes live, the bytes'
   peak and the largest request. As the tests set it up
   (test_allocator_init) it can be told to fail one call (fail_at: 0 the
   first, -1 none; failed is set when it came), and fills what it hands out
   with 0xa5, so that reading memory the library did not write shows. As the
   bench and bench/tree_hash.c set it up (test_allocator_init_meter) it fills
   nothing, so that a build's time stays its own, and can keep the sizes of
   the blocks live at the peak (snapshot); test_allocator_reset_peak starts
   the peak again from what is live, so that a build's peak transient bytes
   are peak_bytes - the bytes live before it - hairobb_memory_bytes(bvh).

   Every free is checked against the blocks it handed out: a free of anything
   else is counted in bad_frees, not done. The blocks are malloc's own (a
   table beside them, grown as needed and freed with the last live block,
   keeps their sizes), so that AddressSanitizer guards both their ends. A
   build allocates and frees on several threads: one lock guards every
   allocator.

   Included before hairobb.h, it routes HAIROBB_MALLOC/HAIROBB_FREE to it
   with allocator_user as the test_allocator (NULL: plain malloc and free,
   not counted); a program that wants another routing defines both macros
   first. Header-only, static, C99/C++ with POSIX threads. */
#ifndef HAIROBB_TESTS_TEST_ALLOC_H
#define HAIROBB_TESTS_TEST_ALLOC_H

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* sizes a snapshot keeps: the largest blocks, the rest summed as the last */
#define TEST_ALLOC_SNAPSHOT 64

typedef struct test_alloc_block {
    void *p;
    size_t size;
} test_alloc_block;

typedef struct test_allocator {
    long calls, fail_at, live;
    long bad_frees;                   /* frees of memory it did not hand out */
    int failed;                       /* the fail_at-th call came */
    int fill;                         /* fill what it hands out with 0xa5 */
    int snapshot;                     /* keep peak_sizes */
    size_t largest;                   /* the largest request, failed ones too */
    size_t bytes, peak_bytes;         /* live */
    size_t peak_blocks, peak_sizes[TEST_ALLOC_SNAPSHOT]; /* at the peak, largest first */
    test_alloc_block *blocks;         /* the live ones: live of capacity */
    size_t capacity;
} test_allocator;

static pthread_mutex_t test_allocator_lock = PTHREAD_MUTEX_INITIALIZER;

/* For the tests: nothing counted yet; the fail_at-th call fails (-1: none);
   blocks filled with 0xa5. */
static inline void test_allocator_init(test_allocator *a, long fail_at)
{
    memset(a, 0, sizeof *a);
    a->fail_at = fail_at;
    a->fill = 1;
}

/* For the bench: fails none, fills nothing; snapshot: keep the sizes of
   the blocks live at the peak. */
static inline void test_allocator_init_meter(test_allocator *a, int snapshot)
{
    test_allocator_init(a, -1);
    a->fill = 0;
    a->snapshot = snapshot;
}

/* The peak starts again from what is live now. */
static inline void test_allocator_reset_peak(test_allocator *a)
{
    pthread_mutex_lock(&test_allocator_lock);
    a->peak_bytes = a->bytes;
    a->peak_blocks = 0;
    pthread_mutex_unlock(&test_allocator_lock);
}

static inline int test_allocator_descending(const void *a, const void *b)
{
    size_t x = *(const size_t *)a, y = *(const size_t *)b;
    return x < y ? 1 : x > y ? -1 : 0;
}

/* The largest live blocks, and the rest summed as the last entry (under
   the lock). */
static inline void test_allocator_take_snapshot(test_allocator *a)
{
    enum { MOST = 4096 };
    static size_t sizes[MOST];
    size_t n = 0, i, others = 0;
    long k;
    for (k = 0; k < a->live; ++k) {
        if (n < MOST) sizes[n++] = a->blocks[k].size;
        else others += a->blocks[k].size;
    }
    qsort(sizes, n, sizeof sizes[0], test_allocator_descending);
    for (i = TEST_ALLOC_SNAPSHOT - 1; i < n; ++i) others += sizes[i];
    if (n > TEST_ALLOC_SNAPSHOT - 1) n = TEST_ALLOC_SNAPSHOT - 1;
    memcpy(a->peak_sizes, sizes, n * sizeof sizes[0]);
    if (others) a->peak_sizes[n++] = others;
    a->peak_blocks = n;
}

static inline void *test_malloc(size_t size, void *user)
{
    test_allocator *a = (test_allocator *)user;
    void *p = NULL;
    if (!a) return malloc(size);
    pthread_mutex_lock(&test_allocator_lock);
    if (size > a->largest) a->largest = size;
    if (a->calls++ == a->fail_at) {
        a->failed = 1;
    } else if ((p = malloc(size)) != NULL) {
        if ((size_t)a->live == a->capacity) {
            size_t capacity = a->capacity ? 2 * a->capacity : 64;
            test_alloc_block *blocks = (test_alloc_block *)realloc(a->blocks, capacity * sizeof *blocks);
            if (!blocks) { printf("test allocator: no memory for its table of %zu blocks\n", capacity); exit(1); }
            a->blocks = blocks;
            a->capacity = capacity;
        }
        if (a->fill) memset(p, 0xa5, size);
        a->blocks[a->live].p = p;
        a->blocks[a->live].size = size;
        a->live++;
        a->bytes += size;
        if (a->bytes > a->peak_bytes) {
            a->peak_bytes = a->bytes;
            if (a->snapshot) test_allocator_take_snapshot(a);
        }
    }
    pthread_mutex_unlock(&test_allocator_lock);
    return p;
}

static inline void test_free(void *p, void *user)
{
    test_allocator *a = (test_allocator *)user;
    long i;
    if (!p) return;
    if (!a) { free(p); return; }
    pthread_mutex_lock(&test_allocator_lock);
    /* from the table's newest end */
    for (i = a->live - 1; i >= 0 && a->blocks[i].p != p; --i) {}
    if (i < 0) {
        a->bad_frees++;
    } else {
        a->bytes -= a->blocks[i].size;
        a->blocks[i] = a->blocks[--a->live];
        if (a->live == 0) {
            free(a->blocks);
            a->blocks = NULL;
            a->capacity = 0;
        }
        free(p);
    }
    pthread_mutex_unlock(&test_allocator_lock);
}

#if !defined(HAIROBB_MALLOC) && !defined(HAIROBB_FREE)
#define HAIROBB_MALLOC(size, user) test_malloc(size, user)
#define HAIROBB_FREE(ptr, user) test_free(ptr, user)
#endif

#endif
