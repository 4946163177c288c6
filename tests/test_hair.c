/* test_hair.c - the header's reader of Cem Yuksel's .hair files
   (hairobb_hair_read, hairobb_hair_load) against the tests' own reader in
   scenes.h, written separately: the same Bezier segments to the bit, the
   file's arrays as written, and an error (never a crash, a leak or a huge
   allocation) for every truncated, oversized or lying file. Then a BVH
   built from a loaded file traces what the reference traces.
   straight.hair is found by tests/test_data.h's rule. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/stat.h>

#include "test_alloc.h"   /* counts live blocks and fails the fail_at-th allocation */
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "check.h"
#include "reference.h"
#include "scenes.h"
#include "scratch.h"

/* ------------------------------------------------------------------------ */
/* Writing .hair files */


/* A file with `strands` strands of 1..6 points (or all of default_segments + 1
   points when the segments array is left out), the arrays of `flags`, and
   values that depend on seed. Returns its size; *data is malloc'd. */
typedef struct hair_spec {
    uint32_t strands, flags, default_segments;
    float default_thickness;
    uint64_t seed;
} hair_spec;

static size_t write_hair(const hair_spec *spec, unsigned char **data)
{
    scene_rng rng;
    uint32_t points = 0, k, *counts = (uint32_t *)malloc(sizeof(uint32_t) * (spec->strands + 1));
    size_t size, at, i;
    unsigned char *p;
    scene_rng_seed(&rng, spec->seed);
    for (k = 0; k < spec->strands; ++k) {
        counts[k] = (spec->flags & 1) ? 1 + scene_rng_u32(&rng) % 6 : spec->default_segments + 1;
        points += counts[k];
    }
    size = 128 + ((spec->flags & 1) ? 2 * (size_t)spec->strands : 0) + 12 * (size_t)points +
           ((spec->flags & 4) ? 4 * (size_t)points : 0) + ((spec->flags & 8) ? 4 * (size_t)points : 0) +
           ((spec->flags & 16) ? 12 * (size_t)points : 0);
    p = (unsigned char *)calloc(size, 1);
    memcpy(p, "HAIR", 4);
    scene_put_le_u32(p + 4, spec->strands);
    scene_put_le_u32(p + 8, points);
    scene_put_le_u32(p + 12, spec->flags);
    scene_put_le_u32(p + 16, spec->default_segments);
    scene_put_le_f32(p + 20, spec->default_thickness);
    scene_put_le_f32(p + 24, 0.25f);
    scene_put_le_f32(p + 28, 0.5f); scene_put_le_f32(p + 32, 0.75f); scene_put_le_f32(p + 36, 1.0f);
    strcpy((char *)p + 40, "written by test_hair");
    at = 128;
    if (spec->flags & 1)
        for (k = 0; k < spec->strands; ++k, at += 2) { p[at] = (unsigned char)(counts[k] - 1); p[at + 1] = 0; }
    for (i = 0; i < 3 * (size_t)points; ++i, at += 4) scene_put_le_f32(p + at, scene_rng_range(&rng, -10.0f, 10.0f));
    if (spec->flags & 4)
        for (i = 0; i < points; ++i, at += 4) scene_put_le_f32(p + at, scene_rng_range(&rng, 0.0f, 0.2f));
    if (spec->flags & 8)
        for (i = 0; i < points; ++i, at += 4) scene_put_le_f32(p + at, scene_rng_float(&rng));
    if (spec->flags & 16)
        for (i = 0; i < 3 * (size_t)points; ++i, at += 4) scene_put_le_f32(p + at, scene_rng_float(&rng));
    free(counts);
    *data = p;
    return size;
}

static float get_f32(const unsigned char *p) { return scene_le_f32(p); }

/* ------------------------------------------------------------------------ */
/* What a read must give */

/* The header's segments equal those of scenes.h's reader to the bit (both
   Catmull-Rom in Bezier form, written separately), the segment_point map
   names each segment's start point, and every vertex index is in range. */
static int same_as_scene_reader(const hairobb_hair *h, const unsigned char *data, size_t size)
{
    hair_scene s;
    size_t i;
    int same;
    if (scene_parse_hair(&s, data, size, "test") != 0) return h->segment_count == 0;
    same = s.segment_count == h->segment_count;
    for (i = 0; same && i < h->segment_count; ++i) {
        const float *ours = h->vertices + 4 * (size_t)h->indices[i];
        same = h->indices[i] + 3 < h->vertex_count && memcmp(ours, s.vertices + 4 * (size_t)s.indices[i], 16 * sizeof(float)) == 0 &&
               memcmp(ours, h->points + 4 * (size_t)h->segment_point[i], 4 * sizeof(float)) == 0 &&
               memcmp(ours + 12, h->points + 4 * ((size_t)h->segment_point[i] + 1), 4 * sizeof(float)) == 0;
    }
    scene_free(&s);
    return same;
}

/* The file's own arrays, read back as written. */
static int arrays_as_written(const hairobb_hair *h, const hair_spec *spec, const unsigned char *data)
{
    size_t at = 128 + ((spec->flags & 1) ? 2 * (size_t)spec->strands : 0), points = h->point_count, i, total = 0;
    uint32_t k;
    int ok = h->strand_count == spec->strands && strcmp(h->info, "written by test_hair") == 0 &&
             h->default_transparency == 0.25f && h->default_color[2] == 1.0f;
    for (k = 0; k < h->strand_count; ++k) total += h->strand_points[k];
    ok &= total == points;
    for (i = 0; ok && i < points; ++i) {
        float thickness = (spec->flags & 4) ? get_f32(data + at + 12 * points + 4 * i) : spec->default_thickness;
        ok = h->points[4 * i] == get_f32(data + at + 12 * i) && h->points[4 * i + 2] == get_f32(data + at + 12 * i + 8) &&
             h->points[4 * i + 3] == 0.5f * thickness;
    }
    at += 12 * points + ((spec->flags & 4) ? 4 * points : 0);
    ok &= ((spec->flags & 8) != 0) == (h->transparency != NULL) && ((spec->flags & 16) != 0) == (h->colors != NULL);
    if (ok && h->transparency) {
        ok = h->transparency[0] == get_f32(data + at) && h->transparency[points - 1] == get_f32(data + at + 4 * (points - 1));
        at += 4 * points;
    }
    if (ok && h->colors)
        ok = h->colors[0] == get_f32(data + at) && h->colors[3 * points - 1] == get_f32(data + at + 12 * (points - 1) + 8);
    return ok;
}

static hairobb_result read_counted(const unsigned char *data, size_t size, test_allocator *a, hairobb_hair *h)
{
    test_allocator_init(a, -1);
    return hairobb_hair_read(data, size, a, h);
}

/* ------------------------------------------------------------------------ */
/* Tests */

/* Every combination of optional arrays, segment arrays or defaults. */
static void test_layouts(void)
{
    uint32_t flags;
    for (flags = 0; flags < 32; ++flags) {
        hair_spec spec = {40, 0, 3, 0.05f, 0};
        unsigned char *data;
        size_t size;
        hairobb_hair h;
        test_allocator a;
        hairobb_result r;
        if (!(flags & 2)) continue;
        spec.flags = flags;
        spec.seed = flags;
        size = write_hair(&spec, &data);
        r = read_counted(data, size, &a, &h);
        CHECK(r == HAIROBB_OK, "flags %u: %s", flags, hairobb_result_string(r));
        CHECK(r == HAIROBB_OK && arrays_as_written(&h, &spec, data), "flags %u: the file's arrays as written", flags);
        CHECK(r == HAIROBB_OK && same_as_scene_reader(&h, data, size),
              "flags %u: %zu segments equal scenes.h's reader to the bit", flags, h.segment_count);
        CHECK(((uintptr_t)h.vertices & 15) == 0, "flags %u: vertices 16-byte aligned", flags);
        hairobb_hair_free(&h);
        CHECK(a.live == 0 && h.allocation == NULL, "flags %u: free leaves %ld blocks", flags, a.live);
        free(data);
    }
}

/* Strands of one point have no segment; a file of only those reads, with
   no segments to build. */
static void test_single_point_strands(void)
{
    hair_spec spec = {5, 2, 0, 0.1f, 7};
    unsigned char *data;
    size_t size = write_hair(&spec, &data);
    hairobb_hair h;
    test_allocator a;
    hairobb_bvh *bvh = NULL;
    hairobb_result r = read_counted(data, size, &a, &h);
    CHECK(r == HAIROBB_OK && h.segment_count == 0 && h.vertex_count == 0 && h.point_count == 5 && h.strand_points[4] == 1,
          "strands of one point: read, no segments (%s, %zu)", hairobb_result_string(r), h.segment_count);
    CHECK(hairobb_build(h.vertices, h.vertex_count, h.indices, h.segment_count, NULL, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT &&
          !bvh, "no segments: the build says so");
    hairobb_hair_free(&h);
    free(data);
}

/* Every shorter prefix and every longer file is an error; so is each lie
   in the header. Nothing is allocated past the file's own size. */
static void expect_error(const unsigned char *data, size_t size, hairobb_result want, const char *what)
{
    hairobb_hair h;
    test_allocator a;
    hairobb_result r = read_counted(data, size, &a, &h);
    int cleared = r == HAIROBB_OK || (h.segment_count == 0 && h.vertices == NULL);
    if (r == HAIROBB_OK) hairobb_hair_free(&h);
    CHECK(r == want && cleared && a.live == 0 && a.largest <= 64 * size + 4096,
          "%s: %s (want %s), %ld blocks live, largest allocation %zu", what, hairobb_result_string(r),
          hairobb_result_string(want), a.live, a.largest);
}

static void test_truncated_and_oversized(void)
{
    hair_spec spec = {6, 1 | 2 | 4 | 8 | 16, 0, 0.1f, 3};
    unsigned char *data, *longer;
    size_t size = write_hair(&spec, &data), cut, extra;
    int all_rejected = 1;
    for (cut = 0; cut < size; ++cut) {
        hairobb_hair h;
        test_allocator a;
        hairobb_result r = read_counted(data, cut, &a, &h);
        if (r != HAIROBB_ERROR_INVALID_FILE || a.live != 0) {
            all_rejected = 0;
            printf("truncated to %zu of %zu bytes: %s\n", cut, size, hairobb_result_string(r));
        }
        if (r == HAIROBB_OK) hairobb_hair_free(&h);
    }
    CHECK(all_rejected, "each of the %zu truncations of a %zu-byte file: invalid file", size, size);
    longer = (unsigned char *)calloc(size + 64, 1);
    memcpy(longer, data, size);
    for (extra = 1; extra <= 64; extra *= 2) expect_error(longer, size + extra, HAIROBB_ERROR_INVALID_FILE, "bytes past the arrays");
    free(longer);
    free(data);
}

static void test_lying_headers(void)
{
    hair_spec spec = {6, 1 | 2 | 4, 0, 0.1f, 5}, defaults = {8, 2 | 16, 4, 0.1f, 6};
    unsigned char *data, *copy, *plain;
    size_t size = write_hair(&spec, &data), plain_size = write_hair(&defaults, &plain);
    uint32_t bit, points = scene_le_u32(data + 8);
    static const uint32_t huge_counts[] = {0xffffffffu, 0x80000000u, 0x15555556u};
    size_t i;
    copy = (unsigned char *)malloc(size > plain_size ? size : plain_size);

#define MUTATE(source, source_size, statement, want, what) \
    do { memcpy(copy, source, source_size); statement; expect_error(copy, source_size, want, what); } while (0)
    MUTATE(data, size, copy[0] = 'h', HAIROBB_ERROR_INVALID_FILE, "bad magic");
    for (bit = 5; bit < 32; ++bit)
        MUTATE(data, size, scene_put_le_u32(copy + 12, scene_le_u32(copy + 12) | 1u << bit), HAIROBB_ERROR_INVALID_FILE, "a reserved flag bit");
    MUTATE(data, size, scene_put_le_u32(copy + 12, 1 | 4), HAIROBB_ERROR_INVALID_FILE, "no points array");
    MUTATE(data, size, scene_put_le_u32(copy + 12, 1 | 2 | 4 | 8), HAIROBB_ERROR_INVALID_FILE, "a flag for an array that is not there");
    MUTATE(data, size, scene_put_le_u32(copy + 12, 1 | 2), HAIROBB_ERROR_INVALID_FILE, "an array not flagged");
    MUTATE(data, size, scene_put_le_u32(copy + 4, 7), HAIROBB_ERROR_INVALID_FILE, "one strand more than the file holds");
    MUTATE(data, size, scene_put_le_u32(copy + 8, points + 1), HAIROBB_ERROR_INVALID_FILE, "one point more than the file holds");
    MUTATE(data, size, copy[128] = (unsigned char)(copy[128] + 1), HAIROBB_ERROR_INVALID_FILE, "strand lengths that add up to more points");
    MUTATE(data, size, copy[128] = (unsigned char)(copy[128] - 1), HAIROBB_ERROR_INVALID_FILE, "strand lengths that add up to fewer points");
    MUTATE(data, size, copy[129] = 0xff, HAIROBB_ERROR_INVALID_FILE, "a strand of 65000 segments");
    for (i = 0; i < sizeof huge_counts / sizeof huge_counts[0]; ++i) {
        MUTATE(data, size, scene_put_le_u32(copy + 4, huge_counts[i]), HAIROBB_ERROR_INVALID_FILE, "a huge strand count");
        MUTATE(data, size, scene_put_le_u32(copy + 8, huge_counts[i]), HAIROBB_ERROR_INVALID_FILE, "a huge point count");
        MUTATE(plain, plain_size, scene_put_le_u32(copy + 4, huge_counts[i]), HAIROBB_ERROR_INVALID_FILE,
               "a huge strand count, default segments");
        MUTATE(plain, plain_size, scene_put_le_u32(copy + 16, huge_counts[i]), HAIROBB_ERROR_INVALID_FILE, "huge default segments");
    }
    MUTATE(plain, plain_size, scene_put_le_u32(copy + 16, 3), HAIROBB_ERROR_INVALID_FILE, "default segments that disagree with the points");
    MUTATE(plain, plain_size, scene_put_le_u32(copy + 4, 0), HAIROBB_ERROR_INVALID_FILE, "no strands but points");
    MUTATE(plain, plain_size, scene_put_le_f32(copy + 20, -0.1f), HAIROBB_ERROR_INVALID_GEOMETRY, "a negative default thickness");
    MUTATE(plain, plain_size, scene_put_le_f32(copy + 20, NAN), HAIROBB_ERROR_INVALID_GEOMETRY, "a NaN default thickness");
    MUTATE(data, size, scene_put_le_f32(copy + 20, NAN), HAIROBB_OK, "a NaN default thickness the thickness array overrides");
    MUTATE(data, size, scene_put_le_f32(copy + 128 + 12 + 4, INFINITY), HAIROBB_ERROR_INVALID_GEOMETRY, "an infinite coordinate");
    MUTATE(data, size, scene_put_le_f32(copy + 128 + 12 + 8, NAN), HAIROBB_ERROR_INVALID_GEOMETRY, "a NaN coordinate");
    MUTATE(data, size, scene_put_le_f32(copy + 128 + 12, 1e30f), HAIROBB_ERROR_INVALID_GEOMETRY, "a coordinate beyond 1e18");
    MUTATE(data, size, scene_put_le_f32(copy + size - 4, -1.0f), HAIROBB_ERROR_INVALID_GEOMETRY, "a negative thickness");
    MUTATE(data, size, scene_put_le_f32(copy + size - 4, NAN), HAIROBB_ERROR_INVALID_GEOMETRY, "a NaN thickness");
    MUTATE(plain, plain_size, scene_put_le_f32(copy + plain_size - 4, INFINITY), HAIROBB_ERROR_INVALID_FILE, "an infinite colour");
#undef MUTATE
    expect_error(NULL, 0, HAIROBB_ERROR_INVALID_ARGUMENT, "no data");
    CHECK(hairobb_hair_read(data, size, NULL, NULL) == HAIROBB_ERROR_INVALID_ARGUMENT, "no hairobb_hair");
    hairobb_hair_free(NULL);
    free(copy);
    free(plain);
    free(data);
}

/* Each allocation failing in turn: out of memory, nothing left. */
static void test_allocation_failure(void)
{
    hair_spec spec = {10, 1 | 2 | 16, 0, 0.1f, 9};
    unsigned char *data;
    size_t size = write_hair(&spec, &data);
    long fail_at, calls;
    int right = 1;
    char path[SCRATCH_PATH_SIZE];
    FILE *file;
    hairobb_hair h;
    test_allocator a;
    CHECK(read_counted(data, size, &a, &h) == HAIROBB_OK, "allocation count run");
    hairobb_hair_free(&h);
    calls = a.calls;
    scratch_path(path, sizeof path, "allocation_failure.hair");
    file = fopen(path, "wb");
    fwrite(data, 1, size, file);
    fclose(file);
    for (fail_at = 0; fail_at < calls + 1; ++fail_at) {
        hairobb_result r, from_file;
        test_allocator_init(&a, fail_at);
        if (fail_at < calls) {
            r = hairobb_hair_read(data, size, &a, &h);
            if (r != HAIROBB_ERROR_OUT_OF_MEMORY || a.live != 0 || h.vertices) right = 0;
        }
        test_allocator_init(&a, fail_at);
        from_file = hairobb_hair_load(path, &a, &h);   /* one allocation more: the file's bytes */
        if (from_file != HAIROBB_ERROR_OUT_OF_MEMORY || a.live != 0 || h.vertices) right = 0;
    }
    CHECK(right, "each of %ld allocations failing (and %ld loading from a file): out of memory, nothing leaked", calls, calls + 1);
    remove(path);
    free(data);
}

/* Files: missing, a directory, truncated on disk, lying about its size. */
static void test_files(void)
{
    hair_spec spec = {12, 1 | 2 | 4 | 8 | 16, 0, 0.1f, 11};
    unsigned char *data;
    size_t size = write_hair(&spec, &data);
    char path[SCRATCH_PATH_SIZE], dir[SCRATCH_PATH_SIZE];
    FILE *file;
    hairobb_hair h, from_memory;
    test_allocator a, b;
    hairobb_result r;
    scratch_path(path, sizeof path, "files.hair");
    scratch_path(dir, sizeof dir, "files.dir");
    file = fopen(path, "wb");
    fwrite(data, 1, size, file);
    fclose(file);
    test_allocator_init(&a, -1);
    r = hairobb_hair_load(path, &a, &h);
    CHECK(r == HAIROBB_OK && read_counted(data, size, &b, &from_memory) == HAIROBB_OK &&
          h.vertex_count == from_memory.vertex_count && h.segment_count == from_memory.segment_count &&
          memcmp(h.vertices, from_memory.vertices, 16 * h.vertex_count) == 0 &&
          memcmp(h.indices, from_memory.indices, 4 * h.segment_count) == 0 && memcmp(h.colors, from_memory.colors, 12 * h.point_count) == 0,
          "a file loads as its bytes read from memory (%s)", hairobb_result_string(r));
    hairobb_hair_free(&h);
    hairobb_hair_free(&from_memory);
    CHECK(a.live == 0 && b.live == 0, "nothing left after freeing both");

    CHECK(truncate(path, (off_t)size - 1) == 0 && hairobb_hair_load(path, NULL, &h) == HAIROBB_ERROR_INVALID_FILE && !h.vertices,
          "a file one byte short");
    CHECK(truncate(path, 100) == 0 && hairobb_hair_load(path, NULL, &h) == HAIROBB_ERROR_INVALID_FILE, "a file shorter than its header");
    /* a header announcing 2^32-1 points in a file of 128 bytes: an error
       before anything that large is allocated */
    scene_put_le_u32(data + 8, 0xffffffffu);
    file = fopen(path, "wb");
    fwrite(data, 1, 128, file);
    fclose(file);
    test_allocator_init(&a, -1);
    r = hairobb_hair_load(path, &a, &h);
    CHECK(r == HAIROBB_ERROR_INVALID_FILE && a.largest == 0, "a header announcing 4G points in 128 bytes: %s, largest allocation %zu",
          hairobb_result_string(r), a.largest);
    remove(path);
    CHECK(hairobb_hair_load(path, NULL, &h) == HAIROBB_ERROR_IO && !h.vertices, "a missing file: I/O error");
    CHECK(mkdir(dir, 0700) == 0 && hairobb_hair_load(dir, NULL, &h) == HAIROBB_ERROR_IO, "a directory: I/O error");
    rmdir(dir);
    CHECK(hairobb_hair_load(NULL, NULL, &h) == HAIROBB_ERROR_INVALID_ARGUMENT, "no path");
    free(data);
}

/* straight.hair: the header's reader against scenes.h's, then the BVH built
   from it against the double-precision reference on camera rays. */
static void test_straight_hair(const char *path)
{
    unsigned char *data = NULL;
    size_t size = 0, rays = 64 * 64, i, disagree = 0, hits = 0;
    hairobb_hair h;
    hairobb_bvh *bvh = NULL;
    hair_scene framing;
    ref_scene *reference;
    float *org, *dir;
    hairobb_result r;
    if (!path) return;
    CHECK(scene_read_file(path, &data, &size) == 0, "read %s", path);
    if (!data) return;
    r = hairobb_hair_load(path, NULL, &h);
    CHECK(r == HAIROBB_OK && h.strand_count == 10000 && h.point_count == 160000 && h.segment_count == 150000 &&
          h.vertex_count == 10000 * 46 && h.colors && !h.transparency && h.points[3] == 0.05f,
          "straight.hair: %s, %u strands, %u points, %zu segments", hairobb_result_string(r), h.strand_count, h.point_count,
          h.segment_count);
    if (r != HAIROBB_OK) { free(data); return; }
    CHECK(same_as_scene_reader(&h, data, size), "straight.hair: segments equal scenes.h's reader to the bit");
    CHECK(strncmp(h.info, "Hair model file generated by Cem Yuksel", 39) == 0, "straight.hair: info '%s'", h.info);

    r = hairobb_build(h.vertices, h.vertex_count, h.indices, h.segment_count, NULL, &bvh);
    CHECK(r == HAIROBB_OK, "straight.hair: build from the loaded buffers: %s", hairobb_result_string(r));
    reference = ref_build(h.vertices, h.vertex_count, h.indices, h.segment_count);
    CHECK(scene_parse_hair(&framing, data, size, "straight") == 0, "framing");
    org = (float *)malloc(3 * sizeof(float) * rays);
    dir = (float *)malloc(3 * sizeof(float) * rays);
    scene_camera_rays(&framing, 64, 64, org, dir);
    for (i = 0; bvh && reference && i < rays; ++i) {
        hairobb_ray ray = {{org[3 * i], org[3 * i + 1], org[3 * i + 2]}, 0.0f, {dir[3 * i], dir[3 * i + 1], dir[3 * i + 2]}, INFINITY, 0.0f};
        hairobb_hit hit;
        ref_hit want;
        int expected = ref_intersect(reference, org + 3 * i, dir + 3 * i, 0.0, INFINITY, &want);
        int got = hairobb_intersect1(bvh, &ray, &hit);
        hits += (size_t)expected;
        disagree += got != expected || (got && fabs(hit.t - want.t) > 1e-2 * want.r);
    }
    printf("straight.hair from hairobb_hair_load: %zu rays, %zu reference hits, %zu disagreements\n", rays, hits, disagree);
    CHECK(hits > rays / 10 && disagree == 0, "straight.hair: %zu of %zu rays disagree with the reference", disagree, hits);
    free(org);
    free(dir);
    ref_free(reference);
    scene_free(&framing);
    hairobb_free(bvh);
    hairobb_hair_free(&h);
    free(data);
}

int main(void)
{
    test_layouts();
    test_single_point_strands();
    test_truncated_and_oversized();
    test_lying_headers();
    test_allocation_failure();
    test_files();
    test_straight_hair(check_data(test_data_straight_hair));
    return check_summary();
}
