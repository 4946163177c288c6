/* alloc_meter.h - a counting allocator for HAIROBB_MALLOC/HAIROBB_FREE,
   keyed by the build's allocator_user, for the bench and bench/tree_hash.c.

   Include it before the implementation of hairobb.h. A build given an
   alloc_meter as options.allocator_user counts what it holds at once
   (current) and the most it held (peak), in the bytes it asked for; a NULL
   user is not counted. The build allocates and frees on several threads:
   one lock per meter. With `snapshot` set, the meter also keeps the sizes
   of the blocks live at the peak (what holds it), largest first.

   Peak transient bytes of a build = peak - hairobb_memory_bytes(bvh): what
   it needed beyond the BVH it returned. Header-only, for C99 programs. */
#ifndef HAIROBB_BENCH_ALLOC_METER_H
#define HAIROBB_BENCH_ALLOC_METER_H

#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define ALLOC_METER_SNAPSHOT 64

typedef struct alloc_block {
    size_t size;
    struct alloc_block *prev, *next; /* live blocks of a snapshotting meter */
    size_t pad;                      /* 32 bytes: what follows stays 16-byte aligned */
} alloc_block;

typedef struct alloc_meter {
    pthread_mutex_t lock;
    size_t current, peak, allocations;
    int snapshot;
    alloc_block live;                /* list head */
    size_t peak_blocks, peak_sizes[ALLOC_METER_SNAPSHOT];
} alloc_meter;

static inline void alloc_meter_init(alloc_meter *m, int snapshot)
{
    memset(m, 0, sizeof *m);
    pthread_mutex_init(&m->lock, NULL);
    m->snapshot = snapshot;
    m->live.prev = m->live.next = &m->live;
}

static inline void alloc_meter_destroy(alloc_meter *m) { pthread_mutex_destroy(&m->lock); }

/* counting starts again from what is live now */
static inline void alloc_meter_reset_peak(alloc_meter *m)
{
    pthread_mutex_lock(&m->lock);
    m->peak = m->current;
    m->peak_blocks = 0;
    pthread_mutex_unlock(&m->lock);
}

static int alloc_meter_descending(const void *a, const void *b)
{
    size_t x = *(const size_t *)a, y = *(const size_t *)b;
    return x < y ? 1 : x > y ? -1 : 0;
}

/* the largest live blocks, and the rest summed as the last entry */
static inline void alloc_meter_take_snapshot(alloc_meter *m)
{
    enum { MOST = 4096 };
    static size_t sizes[MOST]; /* under m->lock */
    const alloc_block *k;
    size_t n = 0, i, others = 0;
    for (k = m->live.next; k != &m->live; k = k->next) {
        if (n < MOST) sizes[n++] = k->size;
        else others += k->size;
    }
    qsort(sizes, n, sizeof sizes[0], alloc_meter_descending);
    for (i = ALLOC_METER_SNAPSHOT - 1; i < n; ++i) others += sizes[i];
    if (n > ALLOC_METER_SNAPSHOT - 1) n = ALLOC_METER_SNAPSHOT - 1;
    memcpy(m->peak_sizes, sizes, n * sizeof sizes[0]);
    if (others) m->peak_sizes[n++] = others;
    m->peak_blocks = n;
}

static inline void *alloc_meter_malloc(size_t size, void *user)
{
    alloc_meter *m = (alloc_meter *)user;
    alloc_block *block;
    if (size > SIZE_MAX - sizeof *block) return NULL;
    block = (alloc_block *)malloc(sizeof *block + size);
    if (!block) return NULL;
    block->size = size;
    block->prev = block->next = NULL;
    if (m) {
        pthread_mutex_lock(&m->lock);
        m->current += size;
        m->allocations++;
        if (m->snapshot) {
            block->next = m->live.next;
            block->prev = &m->live;
            m->live.next->prev = block;
            m->live.next = block;
        }
        if (m->current > m->peak) {
            m->peak = m->current;
            if (m->snapshot) alloc_meter_take_snapshot(m);
        }
        pthread_mutex_unlock(&m->lock);
    }
    return block + 1;
}

static inline void alloc_meter_free(void *p, void *user)
{
    alloc_meter *m = (alloc_meter *)user;
    alloc_block *block;
    if (!p) return;
    block = (alloc_block *)p - 1;
    if (m) {
        pthread_mutex_lock(&m->lock);
        m->current -= block->size;
        if (block->next) {
            block->prev->next = block->next;
            block->next->prev = block->prev;
        }
        pthread_mutex_unlock(&m->lock);
    }
    free(block);
}

#define HAIROBB_MALLOC(size, user) alloc_meter_malloc(size, user)
#define HAIROBB_FREE(ptr, user) alloc_meter_free(ptr, user)

#endif
