/* simd_variant.h - entry points of the copies of simd_variant.c. *used is
   the path the BVH traced with; visits[0] and visits[1] count the segments
   of leaves the copy's kernels reached that were compiled without and with
   AVX2 (instrumented through HAIROBB__LEAF_VISIT), visits[2] and visits[3]
   the segments whose points were made on the fly (another basis without
   the copy, or motion) by code compiled without and with AVX2
   (HAIROBB__POINTS_MADE). *aliased_differ counts the secondary rays (a
   bounce off each hit) whose hairobb_intersect1_from with the output hit
   written over `from` differs from the same call with a separate output. */
#ifndef HAIROBB_TESTS_SIMD_VARIANT_H
#define HAIROBB_TESTS_SIMD_VARIANT_H
#include "../hairobb.h"
#define SIMD_VARIANT_SIGNATURE(name)                                                            \
    int name(const float *vertices, size_t vertex_count, const uint32_t *indices,               \
             size_t segment_count, const hairobb_build_options *options, const hairobb_ray *rays, \
             size_t ray_count, hairobb_hit *hits, int *occluded, hairobb_simd *used, size_t visits[4],   \
             size_t *aliased_differ)
SIMD_VARIANT_SIGNATURE(trace_plain);
SIMD_VARIANT_SIGNATURE(trace_sse);
SIMD_VARIANT_SIGNATURE(trace_avx);
SIMD_VARIANT_SIGNATURE(trace_dispatch);
SIMD_VARIANT_SIGNATURE(trace_neon);
#endif
