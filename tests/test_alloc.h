/* test_alloc.h - the tests' allocator, for HAIROBB_MALLOC/HAIROBB_FREE.

   A test_allocator counts the calls, the blocks and bytes live (and the
   bytes' peak) and the largest request, and can be told to fail one call
   (fail_at: 0 the first, -1 none; failed is set when it came). What it
   hands out is filled with 0xa5, so that reading memory the library did not
   write shows. Every free is checked against the blocks it handed out: a
   free of anything else is counted in bad_frees, not done. A build
   allocates and frees on several threads: one lock guards every allocator.

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

#ifndef TEST_ALLOC_MAX_LIVE
#define TEST_ALLOC_MAX_LIVE 1024   /* blocks live at once in one allocator */
#endif

typedef struct test_allocator {
    long calls, fail_at, live;
    long bad_frees;                   /* frees of memory it did not hand out */
    int failed;                       /* the fail_at-th call came */
    size_t largest;                   /* the largest request, failed ones too */
    size_t bytes, peak_bytes;         /* live */
    void *blocks[TEST_ALLOC_MAX_LIVE];
    size_t sizes[TEST_ALLOC_MAX_LIVE];
} test_allocator;

static pthread_mutex_t test_allocator_lock = PTHREAD_MUTEX_INITIALIZER;

/* Nothing counted yet; the fail_at-th call fails (-1: none). */
static inline void test_allocator_init(test_allocator *a, long fail_at)
{
    memset(a, 0, sizeof *a);
    a->fail_at = fail_at;
}

static inline void *test_malloc(size_t size, void *user)
{
    test_allocator *a = (test_allocator *)user;
    void *p = NULL;
    int i;
    if (!a) return malloc(size);
    pthread_mutex_lock(&test_allocator_lock);
    if (size > a->largest) a->largest = size;
    if (a->calls++ == a->fail_at) {
        a->failed = 1;
    } else if ((p = malloc(size)) != NULL) {
        memset(p, 0xa5, size);
        for (i = 0; i < TEST_ALLOC_MAX_LIVE && a->blocks[i]; ++i) {}
        if (i == TEST_ALLOC_MAX_LIVE) { printf("test allocator: more than %d blocks live\n", TEST_ALLOC_MAX_LIVE); exit(1); }
        a->blocks[i] = p;
        a->sizes[i] = size;
        a->live++;
        a->bytes += size;
        if (a->bytes > a->peak_bytes) a->peak_bytes = a->bytes;
    }
    pthread_mutex_unlock(&test_allocator_lock);
    return p;
}

static inline void test_free(void *p, void *user)
{
    test_allocator *a = (test_allocator *)user;
    int i;
    if (!p) return;
    if (!a) { free(p); return; }
    pthread_mutex_lock(&test_allocator_lock);
    for (i = 0; i < TEST_ALLOC_MAX_LIVE && a->blocks[i] != p; ++i) {}
    if (i == TEST_ALLOC_MAX_LIVE) {
        a->bad_frees++;
    } else {
        a->blocks[i] = NULL;
        a->live--;
        a->bytes -= a->sizes[i];
        free(p);
    }
    pthread_mutex_unlock(&test_allocator_lock);
}

#if !defined(HAIROBB_MALLOC) && !defined(HAIROBB_FREE)
#define HAIROBB_MALLOC(size, user) test_malloc(size, user)
#define HAIROBB_FREE(ptr, user) test_free(ptr, user)
#endif

#endif
