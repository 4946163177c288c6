/* simd_variant.c - compiled once per SIMD path (plain C, SSE, AVX) with
   HAIROBB_STATIC, so the three implementations live side by side in
   test_simd and trace the same rays. VARIANT names this copy's entry point. */
#define HAIROBB_STATIC
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "simd_variant.h"

SIMD_VARIANT_SIGNATURE(VARIANT)
{
    hairobb_bvh *bvh;
    size_t i;
    if (hairobb_build(vertices, vertex_count, indices, segment_count, options, &bvh) != HAIROBB_OK) return 0;
    for (i = 0; i < ray_count; ++i) {
        hairobb_intersect1(bvh, &rays[i], &hits[i]);
        occluded[i] = hairobb_occluded1(bvh, &rays[i]);
    }
    hairobb_free(bvh);
    return 1;
}
