/* test_scenes.c - checks the test support code (tests/scenes.h and
 * tests/embree_wrap.h) before it is trusted to judge hairobb.
 *
 *   gcc -std=c99 -O2 -Wall -Wextra -pedantic tests/test_scenes.c -o /tmp/test_scenes -lembree3 -lm
 *   /tmp/test_scenes     (straight.hair found by tests/test_data.h's rule)
 *
 * Prints PASS/FAIL per check, SKIP for data that is absent, indented info
 * lines (counts, bounds, Embree build cost, camera hit fractions), and last
 * "N passed, M failed, K skipped"; exits nonzero on any failure. Also valid C++.
 */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "embree_wrap.h"
#include "scenes.h"

#if defined(__GNUC__) || defined(__clang__)
#define TEST_PRINTF_LIKE(format_index) __attribute__((format(printf, format_index, format_index + 1)))
#else
#define TEST_PRINTF_LIKE(format_index)
#endif

static void check(int ok, const char *format, ...) TEST_PRINTF_LIKE(2);
static void info(const char *format, ...) TEST_PRINTF_LIKE(1);

static void check(int ok, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    printf("%s ", ok ? "PASS" : "FAIL");
    vprintf(format, args);
    printf("\n");
    va_end(args);
    if (ok)
        check_passed++;
    else
        check_failed++;
}

static void info(const char *format, ...)
{
    va_list args;
    va_start(args, format);
    printf("     ");
    vprintf(format, args);
    printf("\n");
    va_end(args);
}

/* All control points finite and radii non-negative; reports the radius range. */
static int scene_is_sane(const hair_scene *s, float *min_radius, float *max_radius)
{
    *min_radius = INFINITY;
    *max_radius = -INFINITY;
    for (size_t i = 0; i < 4 * s->vertex_count; i++)
        if (!isfinite(s->vertices[i]))
            return 0;
    for (size_t i = 0; i < s->vertex_count; i++) {
        float r = s->vertices[4 * i + 3];
        if (r < 0.0f)
            return 0;
        *min_radius = fminf(*min_radius, r);
        *max_radius = fmaxf(*max_radius, r);
    }
    for (size_t i = 0; i < s->segment_count; i++)
        if (s->indices[i] != 4 * i)
            return 0;
    return ((uintptr_t)s->vertices % 16) == 0;
}

static void print_bounds(const hair_scene *s)
{
    info("%s: %zu segments, bounds x[%.3f, %.3f] y[%.3f, %.3f] z[%.3f, %.3f]", s->name, s->segment_count,
         s->lower[0], s->upper[0], s->lower[1], s->upper[1], s->lower[2], s->upper[2]);
}

/* ------------------------------------------------------------------------ */

static void test_catmull_rom(void)
{
    /* Strand A: values chosen so every division by 6 is exact in float.
       Strand B: one point, no segment. Strand C: radius 0, 0, 3 makes the
       Catmull-Rom radius dip to -0.5, which must be clamped to 0. */
    const float points[] = {
        0, 0, 0, 3,   6, 0, 0, 1.5f,   6, 12, 0, 0,   /* A */
        9, 9, 9, 1,                                   /* B */
        0, 0, 0, 0,   1, 0, 0, 0,      2, 0, 0, 3,    /* C */
    };
    const uint32_t counts[] = {3, 1, 3};
    const float expected_a[32] = {
        0, 0, 0, 3,      1, 0, 0, 2.75f,   5, -2, 0, 2,      6, 0, 0, 1.5f, /* segment 0 */
        6, 0, 0, 1.5f,   7, 2, 0, 1,       6, 10, 0, 0.25f,  6, 12, 0, 0,   /* segment 1 */
    };
    hair_scene s;
    int result = scene_from_polylines(&s, points, counts, 3, "hand-made");
    check(result == 0 && s.segment_count == 4 && s.vertex_count == 16,
          "catmull-rom: 3 strands (3, 1, 3 points) give 4 segments (got %zu)", s.segment_count);
    if (result != 0)
        return;
    check(memcmp(s.vertices, expected_a, sizeof expected_a) == 0,
          "catmull-rom: exact control points of the 3-point strand");
    int continuous = 1;
    for (int c = 0; c < 4; c++) {
        float end_tangent = s.vertices[12 + c] - s.vertices[8 + c];  /* segment 0: P3 - P2 */
        float start_tangent = s.vertices[20 + c] - s.vertices[16 + c]; /* segment 1: P1 - P0 */
        continuous &= end_tangent == start_tangent;
    }
    check(continuous, "catmull-rom: C1 at the joint (P3-P2 of segment 0 == P1-P0 of segment 1)");
    check(s.vertices[32 + 11] == 0.0f && s.vertices[48 + 7] == 0.5f,
          "catmull-rom: overshooting radius clamped to 0 (got %g), others kept (got %g)", s.vertices[32 + 11],
          s.vertices[48 + 7]);
    float min_radius, max_radius;
    check(scene_is_sane(&s, &min_radius, &max_radius), "catmull-rom: aligned vertices, indices 4*i, radii >= 0");
    check(s.lower[0] == -3 && s.upper[0] == 8 && s.lower[1] == -4 && s.upper[1] == 12,
          "catmull-rom: bounds are control points expanded by radius");
    scene_free(&s);

    const uint32_t single[] = {1, 1};
    check(scene_from_polylines(&s, points, single, 2, "empty") != 0 && s.vertices == NULL,
          "catmull-rom: strands without segments are an error");
}

typedef int (*scene_generator)(hair_scene *, size_t, uint64_t);

static void test_generators(void)
{
    static const struct {
        const char *name;
        scene_generator generate;
    } generators[] = {
        {"combed", scene_combed}, {"curly", scene_curly}, {"random", scene_random}, {"crossing", scene_crossing}};
    const size_t target = 100000;
    for (size_t g = 0; g < sizeof generators / sizeof generators[0]; g++) {
        hair_scene a, b, c;
        double start = scene_now();
        int result_a = generators[g].generate(&a, target, 7);
        double seconds = scene_now() - start;
        int result_b = generators[g].generate(&b, target, 7);
        int result_c = generators[g].generate(&c, target, 8);
        if (result_a || result_b || result_c) {
            check(0, "%s: generated", generators[g].name);
        } else {
            double ratio = (double)a.segment_count / (double)target;
            check(ratio > 0.9 && ratio < 1.1, "%s: %zu segments for a target of %zu", generators[g].name,
                  a.segment_count, target);
            int same = a.segment_count == b.segment_count &&
                       memcmp(a.vertices, b.vertices, 16 * a.vertex_count) == 0 &&
                       memcmp(a.indices, b.indices, 4 * a.segment_count) == 0 &&
                       memcmp(a.lower, b.lower, sizeof a.lower) == 0 &&
                       memcmp(a.upper, b.upper, sizeof a.upper) == 0 && strcmp(a.name, b.name) == 0;
            check(same, "%s: same seed gives identical bytes", generators[g].name);
            check(a.segment_count != c.segment_count || memcmp(a.vertices, c.vertices, 16 * a.vertex_count) != 0,
                  "%s: another seed gives another scene", generators[g].name);
            float min_radius, max_radius;
            check(scene_is_sane(&a, &min_radius, &max_radius), "%s: finite, aligned, radii >= 0",
                  generators[g].name);
            print_bounds(&a);
            info("%s: radius %.4f..%.4f, generated in %.3f s", a.name, min_radius, max_radius, seconds);
        }
        scene_free(&a);
        scene_free(&b);
        scene_free(&c);

        int tiny_ok = 1;
        for (size_t tiny = 0; tiny <= 10; tiny += 5) {
            tiny_ok &= generators[g].generate(&a, tiny, 1) == 0 && a.segment_count > 0;
            scene_free(&a);
        }
        check(tiny_ok, "%s: tiny targets (0, 5, 10) give a non-empty scene", generators[g].name);
    }
}

/* ------------------------------------------------------------------------ */
/* .hair loader */

static int write_file(const char *path, const unsigned char *data, size_t size)
{
    FILE *file = fopen(path, "wb");
    if (!file)
        return 0;
    int ok = fwrite(data, 1, size, file) == size;
    return (fclose(file) == 0) && ok;
}

static void put_u32(unsigned char *p, uint32_t value)
{
    p[0] = (unsigned char)value;
    p[1] = (unsigned char)(value >> 8);
    p[2] = (unsigned char)(value >> 16);
    p[3] = (unsigned char)(value >> 24);
}

static void put_f32(unsigned char *p, float value)
{
    uint32_t bits;
    memcpy(&bits, &value, sizeof bits);
    put_u32(p, bits);
}

/* Writes data (optionally modified) to a temporary file and returns what the
   loader says about it. */
static int load_variant(const unsigned char *data, size_t size)
{
    char path[128];
    snprintf(path, sizeof path, "/tmp/hairobb_test_scenes_%ld.hair", (long)getpid());
    if (!write_file(path, data, size)) {
        printf("     (cannot write %s)\n", path);
        return 99;
    }
    hair_scene s;
    int result = scene_load_hair(&s, path);
    scene_free(&s);
    remove(path);
    return result;
}

static void test_hair_format(void)
{
    /* hand-made file using the segments and thickness arrays: strands of 2
       and 1 segments, thickness 0.2 (radius 0.1), plus colours to skip */
    const uint32_t point_count = 5, strand_count = 2;
    unsigned char file[128 + 2 * 2 + 5 * 12 + 5 * 4 + 5 * 12];
    memset(file, 0, sizeof file);
    memcpy(file, "HAIR", 4);
    put_u32(file + 4, strand_count);
    put_u32(file + 8, point_count);
    put_u32(file + 12, 1 | 2 | 4 | 16);
    put_u32(file + 16, 7);      /* default segments, unused: the array wins */
    put_f32(file + 20, 1.0f);   /* default thickness, unused: the array wins */
    file[128] = 2;              /* segments per strand, uint16 */
    file[130] = 1;
    for (uint32_t i = 0; i < point_count; i++) {
        put_f32(file + 132 + 12 * i, (float)i);
        put_f32(file + 132 + 12 * i + 4, 1.0f);
        put_f32(file + 132 + 12 * i + 8, 2.0f);
        put_f32(file + 132 + 60 + 4 * i, 0.2f);
    }
    char path[128];
    snprintf(path, sizeof path, "/tmp/hairobb_test_scenes_%ld_small.hair", (long)getpid());
    hair_scene s;
    int result = write_file(path, file, sizeof file) ? scene_load_hair(&s, path) : 99;
    remove(path);
    check(result == 0 && s.segment_count == 3 && s.vertices[3] == 0.1f && s.vertices[0] == 0.0f &&
              s.vertices[12] == 1.0f && s.vertices[32] == 3.0f && s.vertices[44] == 4.0f,
          "hair: segments + thickness + colour arrays (2 strands, 5 points -> 3 segments, radius 0.1)");
    if (result == 0)
        check(strncmp(s.name, "hairobb_test_scenes_", 20) == 0 && strchr(s.name, '.') == NULL, "hair: scene named after the file (%s)", s.name);
    scene_free(&s);

    check(scene_load_hair(&s, "/tmp/hairobb_no_such_file.hair") == -1, "hair: missing file reports -1 (absent)");
}

static void test_straight_hair(const char *path)
{
    if (!path)
        return;
    hair_scene s;
    double start = scene_now();
    int result = scene_load_hair(&s, path);
    double seconds = scene_now() - start;
    check(result == 0 && s.segment_count == 150000, "straight.hair: loads with 150000 segments (got %zu)",
          s.segment_count);
    if (result != 0)
        return;
    float min_radius, max_radius;
    check(scene_is_sane(&s, &min_radius, &max_radius) && min_radius == 0.05f && max_radius == 0.05f,
          "straight.hair: radius 0.05 everywhere (default thickness 0.1 is a diameter)");
    /* README bounds of the points; control points overshoot slightly and
       add the radius */
    const float lower[3] = {-32.5f, -33.9f, -22.7f}, upper[3] = {30.9f, 24.1f, 63.7f};
    int bounds_ok = 1;
    for (int axis = 0; axis < 3; axis++)
        bounds_ok &= fabsf(s.lower[axis] - lower[axis]) < 0.6f && fabsf(s.upper[axis] - upper[axis]) < 0.6f;
    check(bounds_ok, "straight.hair: bounds ~x[-32.5,30.9] y[-33.9,24.1] z[-22.7,63.7]");
    print_bounds(&s);
    info("straight.hair: loaded in %.3f s", seconds);
    scene_free(&s);

    unsigned char *data = NULL;
    size_t size = 0;
    if (scene_read_file(path, &data, &size) != 0) {
        check(0, "straight.hair: read for corruption tests");
        return;
    }
    check(load_variant(data, size) == 0, "straight.hair: an unchanged copy in /tmp loads");
    const size_t cuts[] = {0, 3, 64, 127, 128, 128 + 12 * 80000, 128 + 12 * 160000, size - 12, size - 1};
    for (size_t k = 0; k < sizeof cuts / sizeof cuts[0]; k++)
        check(load_variant(data, cuts[k]) > 0, "straight.hair: truncated to %zu bytes is rejected", cuts[k]);

    unsigned char *copy = (unsigned char *)malloc(size + 4);
    memcpy(copy, data, size);
    copy[3] = 'X';
    check(load_variant(copy, size) > 0, "straight.hair: bad magic \"HAIX\" is rejected");
    memcpy(copy, data, size);
    put_u32(copy + 12, scene_le_u32(data + 12) | 64);
    check(load_variant(copy, size) > 0, "straight.hair: reserved flag bit 64 is rejected");
    memcpy(copy, data, size);
    put_u32(copy + 12, scene_le_u32(data + 12) & ~2u);
    check(load_variant(copy, size) > 0, "straight.hair: missing points array is rejected");
    memcpy(copy, data, size);
    put_u32(copy + 4, 9999);
    check(load_variant(copy, size) > 0, "straight.hair: strand count inconsistent with point count is rejected");
    memcpy(copy, data, size);
    put_u32(copy + 16, 14);
    check(load_variant(copy, size) > 0, "straight.hair: default segments inconsistent with point count is rejected");
    memcpy(copy, data, size);
    memset(copy + size, 0, 4);
    check(load_variant(copy, size + 4) > 0, "straight.hair: trailing bytes are rejected");
    free(copy);
    free(data);
}

static void test_furball(const char *path)
{
    if (!path)
        return;
    hair_scene s;
    double start = scene_now();
    int result = scene_load_furball(&s, path);
    double seconds = scene_now() - start;
    check(result == 0 && s.segment_count == 455505, "furBall_A: loads with 455505 segments (got %zu)",
          s.segment_count);
    if (result != 0)
        return;
    /* the file's radii are 0.0009375..0.005; the segment end points carry them */
    float min_end = INFINITY, max_end = -INFINITY, min_radius, max_radius;
    for (size_t i = 0; i < s.segment_count; i++) {
        for (int j = 0; j < 4; j += 3) {
            float r = s.vertices[16 * i + 4 * j + 3];
            min_end = fminf(min_end, r);
            max_end = fmaxf(max_end, r);
        }
    }
    check(scene_is_sane(&s, &min_radius, &max_radius) && min_end > 0.0009f && max_end <= 0.005f,
          "furBall_A: end-point radii %.5f..%.5f within the file's 0.0009..0.005", min_end, max_end);
    print_bounds(&s);
    info("furBall_A: loaded (gunzip via popen) in %.3f s", seconds);
    scene_free(&s);
    check(scene_load_furball(&s, "/tmp/hairobb_no_such_furball.bin.gz") == -1,
          "furBall_A: missing file reports -1 (absent)");
}

/* ------------------------------------------------------------------------ */
/* Camera and Embree */

typedef struct trace_stats {
    double hit_fraction, seconds;
    size_t disagreements, bad_hits;
} trace_stats;

/* Traces the framing camera's rays; checks every ray's occlusion agrees with
   its closest hit (any hit up to infinity; nothing up to 0.99 t), and that
   hits are plausible. */
static trace_stats trace_camera(const emb_scene *e, const hair_scene *s, int width, int height)
{
    trace_stats stats;
    memset(&stats, 0, sizeof stats);
    size_t ray_count = (size_t)width * (size_t)height;
    float *org = (float *)malloc(3 * ray_count * sizeof(float));
    float *dir = (float *)malloc(3 * ray_count * sizeof(float));
    unsigned char *hit = (unsigned char *)malloc(ray_count);
    float *hit_t = (float *)malloc(ray_count * sizeof(float));
    scene_camera_rays(s, width, height, org, dir);

    size_t hits = 0;
    double start = scene_now();
    for (size_t i = 0; i < ray_count; i++) {
        float t = 0.0f, u = 0.0f, v = 0.0f;
        uint32_t prim = 0;
        hit[i] = (unsigned char)emb_intersect(e, org + 3 * i, 0.0f, dir + 3 * i, INFINITY, &t, &u, &v, &prim);
        hit_t[i] = t;
        if (hit[i]) {
            hits++;
            if (!(t > 0.0f) || prim >= s->segment_count || !(u >= 0.0f && u <= 1.0f))
                stats.bad_hits++;
        }
    }
    stats.seconds = scene_now() - start;
    for (size_t i = 0; i < ray_count; i++) {
        int occluded = emb_occluded(e, org + 3 * i, 0.0f, dir + 3 * i, INFINITY);
        if (occluded != hit[i] || (hit[i] && emb_occluded(e, org + 3 * i, 0.0f, dir + 3 * i, 0.99f * hit_t[i])))
            stats.disagreements++;
    }
    stats.hit_fraction = (double)hits / (double)ray_count;
    free(org);
    free(dir);
    free(hit);
    free(hit_t);
    return stats;
}

static void test_camera(void)
{
    hair_scene s;
    if (scene_combed(&s, 1000, 1) != 0) {
        check(0, "camera: scene");
        return;
    }
    const int width = 64, height = 48;
    float *org = (float *)malloc(3 * width * height * sizeof(float));
    float *dir = (float *)malloc(3 * width * height * sizeof(float));
    scene_camera_rays(&s, width, height, org, dir);
    int unit = 1;
    for (int i = 0; i < width * height; i++)
        unit &= fabsf(sqrtf(dir[3 * i] * dir[3 * i] + dir[3 * i + 1] * dir[3 * i + 1] + dir[3 * i + 2] * dir[3 * i + 2]) - 1.0f) < 1e-5f;
    check(unit, "camera: unit directions");
    int top_left = 0, top_right = width - 1, bottom_left = (height - 1) * width;
    check(dir[3 * top_left + 1] > dir[3 * bottom_left + 1] && dir[3 * top_left] < dir[3 * top_right] &&
              dir[3 * top_left + 2] < 0.0f && org[2] > s.upper[2] && org[1] > 0.5f * (s.lower[1] + s.upper[1]),
          "camera: row-major from the top-left, looking from +z and above");
    free(org);
    free(dir);
    scene_free(&s);
}

static void test_embree_scene(hair_scene *s, int check_transform)
{
    const int width = 512, height = 512;
    for (int type = EMB_FLAT_BEZIER; type <= EMB_ROUND_BEZIER; type++) {
        const char *type_name = type == EMB_FLAT_BEZIER ? "flat" : "round";
        size_t memory = 0;
        double build_seconds = 0.0;
        emb_scene *e = emb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, type, 0, 0, &memory,
                                 &build_seconds);
        check(e != NULL, "embree %s %s: builds", s->name, type_name);
        if (!e)
            continue;
        info("embree %s %s: %zu segments, build %.3f s, %.1f MB (%.0f bytes/segment)", s->name, type_name,
             s->segment_count, build_seconds, (double)memory / 1e6, (double)memory / (double)s->segment_count);
        trace_stats stats = trace_camera(e, s, width, height);
        check(stats.hit_fraction > 0.05, "embree %s %s: %.1f%% of %dx%d camera rays hit", s->name, type_name,
              100.0 * stats.hit_fraction, width, height);
        check(stats.bad_hits == 0, "embree %s %s: hits have t > 0, valid primID, u in [0,1] (%zu bad)", s->name,
              type_name, stats.bad_hits);
        check(stats.disagreements == 0, "embree %s %s: emb_occluded agrees with emb_intersect (%zu disagree)",
              s->name, type_name, stats.disagreements);
        info("embree %s %s: %.2f Mrays/s closest hit, 1 thread", s->name, type_name,
             (double)width * height / stats.seconds / 1e6);

        if (check_transform && type == EMB_ROUND_BEZIER) {
            /* The camera frames the bounds, so the same picture must come out
               far from the origin and 10x larger. */
            hair_scene moved;
            memcpy(&moved, s, sizeof moved);
            void *vertices = NULL;
            if (posix_memalign(&vertices, 16, 16 * s->vertex_count + 16) != 0)
                continue;
            moved.vertices = (float *)memcpy(vertices, s->vertices, 16 * s->vertex_count + 16);
            const float offset[3] = {100.0f, -50.0f, 25.0f};
            scene_transform(&moved, offset, 10.0f);
            int bounds_ok = 1;
            for (int axis = 0; axis < 3; axis++) {
                float centre = 0.5f * (s->lower[axis] + s->upper[axis]);
                float expected_lower = centre + 10.0f * (s->lower[axis] - centre) + offset[axis];
                float expected_upper = centre + 10.0f * (s->upper[axis] - centre) + offset[axis];
                bounds_ok &= fabsf(moved.lower[axis] - expected_lower) < 1e-3f &&
                             fabsf(moved.upper[axis] - expected_upper) < 1e-3f;
            }
            check(bounds_ok, "transform %s: bounds scaled by 10 about the centre and moved", s->name);
            emb_scene *moved_e = emb_build(moved.vertices, moved.vertex_count, moved.indices, moved.segment_count,
                                           type, 0, 0, NULL, NULL);
            if (moved_e) {
                trace_stats moved_stats = trace_camera(moved_e, &moved, width, height);
                check(fabs(moved_stats.hit_fraction - stats.hit_fraction) < 0.01,
                      "transform %s: same camera picture after moving and scaling (%.2f%% vs %.2f%% hit)",
                      s->name, 100.0 * moved_stats.hit_fraction, 100.0 * stats.hit_fraction);
                emb_free(moved_e);
            } else {
                check(0, "transform %s: embree build", s->name);
            }
            free(moved.vertices);
        }
        emb_free(e);
    }
}

static void test_embree_options(void)
{
    hair_scene s;
    if (scene_combed(&s, 10000, 3) != 0) {
        check(0, "embree options: scene");
        return;
    }
    double seconds = 0.0;
    size_t memory = 0;
    emb_scene *e = emb_build(s.vertices, s.vertex_count, s.indices, s.segment_count, EMB_FLAT_BEZIER, 8, 1,
                             &memory, &seconds);
    check(e != NULL && memory > 0 && seconds > 0.0,
          "embree options: threads=1 and tessellation rate 8 build (%.1f MB, %.4f s)", (double)memory / 1e6, seconds);
    emb_free(e);
    printf("     (an error message about curve type 7 is expected next)\n");
    e = emb_build(s.vertices, s.vertex_count, s.indices, s.segment_count, 7, 0, 0, &memory, &seconds);
    check(e == NULL, "embree options: unknown curve type gives NULL");
    emb_free(e);
    scene_free(&s);
}

static void test_embree(const char *straight_path, const char *furball_path)
{
    test_embree_options();
    scene_generator generators[] = {scene_combed, scene_curly, scene_random, scene_crossing};
    for (size_t g = 0; g < sizeof generators / sizeof generators[0]; g++) {
        hair_scene s;
        if (generators[g](&s, 100000, 7) == 0) {
            test_embree_scene(&s, g == 0);
            scene_free(&s);
        }
    }
    hair_scene s;
    if (straight_path && scene_load_hair(&s, straight_path) == 0) {
        test_embree_scene(&s, 0);
        scene_free(&s);
    }
    if (furball_path && scene_load_furball(&s, furball_path) == 0) {
        test_embree_scene(&s, 0);
        scene_free(&s);
    }
}

int main(void)
{
    /* the data files, found by tests/test_data.h's rule (each reported once) */
    const char *straight_path = check_data(test_data_straight_hair);
    const char *furball_path = check_data(test_data_furball);

    test_catmull_rom();
    test_generators();
    test_hair_format();
    test_straight_hair(straight_path);
    test_furball(furball_path);
    test_camera();
    test_embree(straight_path, furball_path);
    return check_summary();
}
