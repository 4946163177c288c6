/* ab.h - what bench/ab.c and the two copies of bench/ab_copy.c share. */
#ifndef HAIROBB_BENCH_AB_H
#define HAIROBB_BENCH_AB_H
#include "../tests/scenes.h"
#include <stdint.h>
#include <string.h>

typedef enum ab_kind { AB_PRIMARY, AB_SECONDARY, AB_SHADOW } ab_kind;
typedef struct ab_rays {
    ab_kind kind;
    size_t count;
    float *org, *dir;
} ab_rays;
/* a primary ray's hit, which its secondary and shadow rays leave */
typedef struct ab_hit {
    uint32_t prim_id;
    float t, Ng[3];
} ab_hit;

void *ab_base_build(const hair_scene *s);
void *ab_base_build_threads(const hair_scene *s, unsigned threads);
uint64_t ab_base_tree_hash(const void *bvh);
void ab_base_free(void *bvh);
uint64_t ab_base_trace(void *bvh, const ab_rays *r, ab_hit *hits);
void *ab_test_build(const hair_scene *s);
void *ab_test_build_threads(const hair_scene *s, unsigned threads);
uint64_t ab_test_tree_hash(const void *bvh);
void ab_test_free(void *bvh);
uint64_t ab_test_trace(void *bvh, const ab_rays *r, ab_hit *hits);
#endif
