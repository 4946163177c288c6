/* simd_variant.h - entry points of the three copies of simd_variant.c. */
#ifndef HAIROBB_TESTS_SIMD_VARIANT_H
#define HAIROBB_TESTS_SIMD_VARIANT_H
#include "../hairobb.h"
#define SIMD_VARIANT_SIGNATURE(name)                                                            \
    int name(const float *vertices, size_t vertex_count, const uint32_t *indices,               \
             size_t segment_count, const hairobb_build_options *options, const hairobb_ray *rays, \
             size_t ray_count, hairobb_hit *hits, int *occluded)
SIMD_VARIANT_SIGNATURE(trace_plain);
SIMD_VARIANT_SIGNATURE(trace_sse);
SIMD_VARIANT_SIGNATURE(trace_avx);
#endif
