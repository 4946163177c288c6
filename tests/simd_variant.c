/* simd_variant.c - compiled once per SIMD path (plain C, SSE4.1, AVX2, and
   the x86-64 baseline with its AVX2 kernels for runtime dispatch; on
   AArch64 plain C and NEON) with
   HAIROBB_STATIC, so the implementations live side by side in test_simd and
   trace the same rays. VARIANT names this copy's entry point. */
#include <stddef.h>
/* HAIROBB__AVX2 is 1 in kernels compiled for AVX2: the count shows which
   copy of the kernels traced */
static size_t leaf_visits[2], points_made[2];
#define HAIROBB__LEAF_VISIT(rs, prim) ((void)(rs), (void)(prim), ++leaf_visits[HAIROBB__AVX2], 0)
#define HAIROBB__POINTS_MADE() (++points_made[HAIROBB__AVX2])
#define HAIROBB_STATIC
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "simd_variant.h"

SIMD_VARIANT_SIGNATURE(VARIANT)
{
    hairobb_bvh *bvh;
    size_t i;
    if (hairobb_build(vertices, vertex_count, indices, segment_count, options, &bvh) != HAIROBB_OK) return 0;
    *used = hairobb_get_simd(bvh);
    leaf_visits[0] = leaf_visits[1] = points_made[0] = points_made[1] = 0;
    for (i = 0; i < ray_count; ++i) {
        hairobb_intersect1(bvh, &rays[i], &hits[i]);
        occluded[i] = hairobb_occluded1(bvh, &rays[i]);
    }
    hairobb_free(bvh);
    visits[0] = leaf_visits[0];
    visits[1] = leaf_visits[1];
    visits[2] = points_made[0];
    visits[3] = points_made[1];
    return 1;
}
