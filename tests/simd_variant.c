/* simd_variant.c - compiled once per SIMD path (plain C, SSE4.1, AVX2, and
   the x86-64 baseline with its AVX2 kernels for runtime dispatch; on
   AArch64 plain C and NEON) with
   HAIROBB_STATIC, so the implementations live side by side in test_simd and
   trace the same rays. VARIANT names this copy's entry point. */
#include <stddef.h>
#include <string.h>
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
    *aliased_differ = 0;
    if (hairobb_build(vertices, vertex_count, indices, segment_count, options, &bvh) != HAIROBB_OK) return 0;
    *used = hairobb_get_simd(bvh);
    leaf_visits[0] = leaf_visits[1] = points_made[0] = points_made[1] = 0;
    for (i = 0; i < ray_count; ++i) {
        hairobb_intersect1(bvh, &rays[i], &hits[i]);
        occluded[i] = hairobb_occluded1(bvh, &rays[i]);
        if (hits[i].prim_id != HAIROBB_INVALID_ID) {
            /* a mirror bounce off the hit, as a path tracer's loop makes it */
            const hairobb_hit *h = &hits[i];
            const float *d = rays[i].dir;
            float dn = d[0] * h->Ng[0] + d[1] * h->Ng[1] + d[2] * h->Ng[2];
            hairobb_ray bounce;
            hairobb_hit separate, aliased = *h;
            int k, got_separate, got_aliased;
            for (k = 0; k < 3; ++k) {
                bounce.org[k] = rays[i].org[k] + h->t * d[k];
                bounce.dir[k] = d[k] - 2.0f * dn * h->Ng[k];
            }
            bounce.tnear = 0.0f;
            bounce.tfar = INFINITY;
            bounce.time = rays[i].time;
            got_separate = hairobb_intersect1_from(bvh, h, &bounce, &separate);
            got_aliased = hairobb_intersect1_from(bvh, &aliased, &bounce, &aliased);
            *aliased_differ += got_separate != got_aliased || separate.prim_id != aliased.prim_id ||
                               (got_separate && memcmp(&separate, &aliased, sizeof separate) != 0);
        }
    }
    hairobb_free(bvh);
    visits[0] = leaf_visits[0];
    visits[1] = leaf_visits[1];
    visits[2] = points_made[0];
    visits[3] = points_made[1];
    return 1;
}
