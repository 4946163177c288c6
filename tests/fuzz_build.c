/* fuzz_build.c - libFuzzer target: arbitrary bytes become build options
   (the curve basis too), control points (any float, NaN and Inf included),
   segment indices (any value, past the end included) and rays.
   hairobb_build must return one of its codes and, on success, traced hits
   must be sane: t finite and in
   [tnear, tfar], u in [0,1], prim_id a segment, occluded1 true wherever
   intersect1 hits. Build with clang -fsanitize=fuzzer,address,undefined
   (see `make fuzz`); leaks are LeakSanitizer's to find. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "fuzz_checks.h"

typedef struct reader {
    const uint8_t *data;
    size_t size, at;
} reader;

static unsigned read_byte(reader *r) { return r->at < r->size ? r->data[r->at++] : 0u; }

static float read_float(reader *r)
{
    uint32_t bits = 0;
    int i;
    float f;
    for (i = 0; i < 4; ++i) bits |= (uint32_t)read_byte(r) << (8 * i);
    memcpy(&f, &bits, sizeof f);
    return f;
}

/* Mostly small numbers (real scenes), sometimes raw bit patterns. */
static float read_coordinate(reader *r)
{
    unsigned kind = read_byte(r);
    if (kind < 224) return ((float)kind - 112.0f) / 16.0f + (float)read_byte(r) / 4096.0f;
    return read_float(r);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    reader r;
    hairobb_build_options options;
    hairobb_bvh *bvh = NULL;
    hairobb_result result;
    size_t segments, vertex_count, i;
    float *vertices, *tangents = NULL;
    uint32_t *indices;
    unsigned rays, k;

    r.data = data; r.size = size; r.at = 0;
    memset(&options, 0, sizeof options);
    options.nodes = (hairobb_node_policy)(read_byte(&r) % 3);
    options.obb_layout = (hairobb_obb_layout)(read_byte(&r) % 5);
    options.spatial_splits = (hairobb_switch)(read_byte(&r) % 3);
    options.clustering = (hairobb_switch)(read_byte(&r) % 3);
    options.max_leaf_size = read_byte(&r) % 16;
    options.precision = (hairobb_precision)(read_byte(&r) % 2);
    options.curve_pieces = read_byte(&r) % 17;
    options.threads = 1u + read_byte(&r) % 2;
    segments = read_byte(&r) % 48;
    vertex_count = 4 * segments + read_byte(&r) % 4;
    vertices = (float *)malloc(sizeof(float) * 4 * (vertex_count + 1));
    indices = (uint32_t *)malloc(sizeof(uint32_t) * (segments + 1));
    if (!vertices || !indices) { free(vertices); free(indices); return 0; }
    for (i = 0; i < 4 * vertex_count; ++i) {
        float v = read_coordinate(&r);
        vertices[i] = (i % 4 == 3) ? (v < 0.0f && read_byte(&r) < 240 ? -v : v) * 0.05f : v;   /* radii: mostly >= 0 */
    }
    for (i = 0; i < segments; ++i) {
        unsigned pick = read_byte(&r);
        indices[i] = pick < 250 ? (uint32_t)(4 * i) : (uint32_t)(pick == 255 ? 0xfffffffeu : vertex_count - 3 + (pick - 250));
    }
    /* the curve basis from the last byte (the stream's order stays as the
       seeds were written); Hermite tangents: differences of the vertices */
    options.basis = (hairobb_basis)(size > 0 ? data[size - 1] % 5 : 0);
    if (options.basis == HAIROBB_BASIS_HERMITE) {
        tangents = (float *)malloc(sizeof(float) * 4 * (vertex_count + 1));
        if (!tangents) { free(vertices); free(indices); return 0; }
        for (i = 0; i < 4 * vertex_count; ++i) tangents[i] = vertices[(i + 4) % (4 * vertex_count)] - vertices[i];
        options.tangents = tangents;
    }

    result = hairobb_build(vertices, vertex_count, indices, segments, &options, &bvh);
    if (result != HAIROBB_OK) {
        if (bvh) fuzz_fail("a failed build returned a BVH");
        if ((unsigned)result > HAIROBB_ERROR_CANCELLED) fuzz_fail("unknown result code");
        if (!strcmp(hairobb_result_string(result), "unknown hairobb_result")) fuzz_fail("result without a message");
    } else {
        if (!bvh) fuzz_fail("a successful build returned no BVH");
        rays = 1 + read_byte(&r) % 32;
        for (k = 0; k < rays; ++k) {
            hairobb_ray ray;
            int j;
            for (j = 0; j < 3; ++j) ray.org[j] = read_coordinate(&r);
            for (j = 0; j < 3; ++j) ray.dir[j] = read_coordinate(&r);
            ray.tnear = read_byte(&r) < 200 ? 0.0f : read_coordinate(&r);
            ray.tfar = read_byte(&r) < 200 ? INFINITY : read_coordinate(&r);
            fuzz_check_ray(bvh, &ray, segments);
        }
        hairobb_free(bvh);
    }
    free(vertices);
    free(tangents);
    free(indices);
    return 0;
}
