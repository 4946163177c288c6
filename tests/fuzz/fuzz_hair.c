/* fuzz_hair.c - libFuzzer target: arbitrary bytes as a .hair file.
   hairobb_hair_read must return one of its codes, leave nothing behind on
   failure and, on success, give arrays that agree with each other: strand
   lengths adding up to the point count, every segment's control points
   inside the vertex array, finite coordinates and non-negative radii. A
   BVH built from them must trace sane hits (fuzz_checks.h). Seeds: small
   valid files of every array combination, tests/fuzz/corpus/hair_read. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#define HAIROBB_IMPLEMENTATION
#include "../../hairobb.h"
#include "fuzz_checks.h"

static void check_arrays(const hairobb_hair *h)
{
    uint64_t points = 0;
    size_t i;
    uint32_t k;
    for (k = 0; k < h->strand_count; ++k) points += h->strand_points[k];
    if (points != h->point_count) fuzz_fail("strand lengths do not add up to the point count");
    for (i = 0; i < h->segment_count; ++i) {
        if ((uint64_t)h->indices[i] + 3 >= h->vertex_count) fuzz_fail("a segment past the vertices");
        if ((uint64_t)h->segment_point[i] + 1 >= h->point_count) fuzz_fail("a segment past the points");
    }
    for (i = 0; i < 4 * h->vertex_count; ++i) {
        if (!isfinite(h->vertices[i])) fuzz_fail("a vertex that is not finite");
        if (i % 4 == 3 && h->vertices[i] < 0.0f) fuzz_fail("a negative radius");
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    hairobb_hair hair;
    hairobb_result result = hairobb_hair_read(data, size, NULL, &hair);
    if (result != HAIROBB_OK) {
        if (hair.allocation || hair.vertices || hair.segment_count) fuzz_fail("a failed read left arrays");
        if (result != HAIROBB_ERROR_INVALID_FILE && result != HAIROBB_ERROR_INVALID_GEOMETRY &&
            result != HAIROBB_ERROR_TOO_LARGE && result != HAIROBB_ERROR_OUT_OF_MEMORY)
            fuzz_fail("a code the reader does not return");
        return 0;
    }
    check_arrays(&hair);
    if (hair.segment_count > 0 && hair.segment_count <= 4096) {
        hairobb_build_options options;
        hairobb_bvh *bvh = NULL;
        memset(&options, 0, sizeof options);
        options.threads = 1;
        result = hairobb_build(hair.vertices, hair.vertex_count, hair.indices, hair.segment_count, &options, &bvh);
        /* Catmull-Rom control points may overshoot a coordinate near the limit */
        if (result != HAIROBB_OK && result != HAIROBB_ERROR_INVALID_GEOMETRY) fuzz_fail("a read file that does not build");
        if (bvh) {
            fuzz_check_rays_through_bounds(bvh, hair.segment_count, 0.0f);
            hairobb_free(bvh);
        }
    }
    hairobb_hair_free(&hair);
    return 0;
}
