/* test_scenes.c - checks the test support code (tests/scenes.h and
 * tests/embree_wrap.h) before it is trusted to judge hairobb.
 *
 *   gcc -std=c99 -O2 -Wall -Wextra -pedantic tests/test_scenes.c -o build/test_scenes -lembree3 -lm
 *   build/test_scenes     (from the repository root: straight.hair found by
 *                          tests/test_data.h's rule, files written in build/)
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
#include "scratch.h"

static void info(const char *format, ...) CHECK_PRINTF_LIKE(1);

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
    check_report(result == 0 && s.segment_count == 4 && s.vertex_count == 16,
                 "catmull-rom: 3 strands (3, 1, 3 points) give 4 segments (got %zu)", s.segment_count);
    if (result != 0)
        return;
    check_report(memcmp(s.vertices, expected_a, sizeof expected_a) == 0,
                 "catmull-rom: exact control points of the 3-point strand");
    int continuous = 1;
    for (int c = 0; c < 4; c++) {
        float end_tangent = s.vertices[12 + c] - s.vertices[8 + c];  /* segment 0: P3 - P2 */
        float start_tangent = s.vertices[20 + c] - s.vertices[16 + c]; /* segment 1: P1 - P0 */
        continuous &= end_tangent == start_tangent;
    }
    check_report(continuous, "catmull-rom: C1 at the joint (P3-P2 of segment 0 == P1-P0 of segment 1)");
    check_report(s.vertices[32 + 11] == 0.0f && s.vertices[48 + 7] == 0.5f,
                 "catmull-rom: overshooting radius clamped to 0 (got %g), others kept (got %g)", s.vertices[32 + 11],
                 s.vertices[48 + 7]);
    float min_radius, max_radius;
    check_report(scene_is_sane(&s, &min_radius, &max_radius), "catmull-rom: aligned vertices, indices 4*i, radii >= 0");
    check_report(s.lower[0] == -3 && s.upper[0] == 8 && s.lower[1] == -4 && s.upper[1] == 12,
                 "catmull-rom: bounds are control points expanded by radius");
    scene_free(&s);

    const uint32_t single[] = {1, 1};
    check_report(scene_from_polylines(&s, points, single, 2, "empty") != 0 && s.vertices == NULL,
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
            check_report(0, "%s: generated", generators[g].name);
        } else {
            double ratio = (double)a.segment_count / (double)target;
            check_report(ratio > 0.9 && ratio < 1.1, "%s: %zu segments for a target of %zu", generators[g].name,
                         a.segment_count, target);
            int same = a.segment_count == b.segment_count &&
                       memcmp(a.vertices, b.vertices, 16 * a.vertex_count) == 0 &&
                       memcmp(a.indices, b.indices, 4 * a.segment_count) == 0 &&
                       memcmp(a.lower, b.lower, sizeof a.lower) == 0 &&
                       memcmp(a.upper, b.upper, sizeof a.upper) == 0 && strcmp(a.name, b.name) == 0;
            check_report(same, "%s: same seed gives identical bytes", generators[g].name);
            check_report(a.segment_count != c.segment_count || memcmp(a.vertices, c.vertices, 16 * a.vertex_count) != 0,
                         "%s: another seed gives another scene", generators[g].name);
            float min_radius, max_radius;
            check_report(scene_is_sane(&a, &min_radius, &max_radius), "%s: finite, aligned, radii >= 0",
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
        check_report(tiny_ok, "%s: tiny targets (0, 5, 10) give a non-empty scene", generators[g].name);
    }
}

/* ------------------------------------------------------------------------ */
/* Yeti-class Catmull-Rom fur */

/* Point u (x, y, z, r) of the uniform Catmull-Rom segment through p[0..3],
   from its own basis polynomials rather than a Bezier form. */
static void catmull_rom_point(const float *p, double u, double out[4])
{
    double u2 = u * u, u3 = u2 * u;
    double w[4] = {0.5 * (-u3 + 2.0 * u2 - u), 0.5 * (3.0 * u3 - 5.0 * u2 + 2.0), 0.5 * (-3.0 * u3 + 4.0 * u2 + u),
                   0.5 * (u3 - u2)};
    for (int c = 0; c < 4; c++)
        out[c] = w[0] * p[c] + w[1] * p[4 + c] + w[2] * p[8 + c] + w[3] * p[12 + c];
}

static void bezier_point(const float *b, double u, double out[4])
{
    double v = 1.0 - u, w[4] = {v * v * v, 3.0 * u * v * v, 3.0 * u * u * v, u * u * u};
    for (int c = 0; c < 4; c++)
        out[c] = w[0] * b[c] + w[1] * b[4 + c] + w[2] * b[8 + c] + w[3] * b[12 + c];
}

/* Distance from p to the capsule's axis segment (scene_yeti's body). */
static double capsule_axis_distance(const float *p)
{
    const double length = sqrt(0.8 * 0.8 + 0.3 * 0.3 + 0.5 * 0.5);
    const double axis[3] = {0.8 / length, 0.3 / length, -0.5 / length};
    double along = p[0] * axis[0] + p[1] * axis[1] + p[2] * axis[2], d2 = 0.0;
    along = along < -0.75 ? -0.75 : along > 0.75 ? 0.75 : along;
    for (int k = 0; k < 3; k++)
        d2 += (p[k] - along * axis[k]) * (p[k] - along * axis[k]);
    return sqrt(d2);
}

/* The strand layout, roots, taper and conversion of scene_yeti, and Embree's
   Catmull-Rom curves on its shared points against Embree's Bezier curves on
   scene_to_bezier's copy (the same surface). */
static void test_yeti(void)
{
    enum { SEGMENTS = SCENE_YETI_SEGMENTS, POINTS = SCENE_YETI_POINTS, BANDS = 10 };
    const size_t target = 40000;
    hair_scene a, b, c, bezier;
    double start = scene_now();
    int result = scene_yeti(&a, target, 7);
    double seconds = scene_now() - start;
    result |= scene_yeti(&b, target, 7) | scene_yeti(&c, target, 8);
    check_report(result == 0, "yeti: generated");
    if (result != 0)
        return;
    size_t strands = a.segment_count / SEGMENTS;
    check_report(a.basis == SCENE_BASIS_CATMULL_ROM && a.segment_count == target && a.vertex_count == strands * POINTS &&
                     strcmp(a.name, "yeti") == 0,
                 "yeti: Catmull-Rom, %zu segments, %zu points (%zu strands of %d points)", a.segment_count, a.vertex_count,
                 strands, POINTS);
    int indices_ok = 1, padding_ok = ((uintptr_t)a.vertices % 16) == 0;
    for (size_t k = 0; k < strands; k++)
        for (size_t j = 0; j < SEGMENTS; j++)
            indices_ok &= a.indices[SEGMENTS * k + j] == POINTS * k + j;
    for (int i = 0; i < 4; i++)
        padding_ok &= a.vertices[4 * a.vertex_count + (size_t)i] == 0.0f;
    check_report(indices_ok, "yeti: segment j of strand k starts at point 19 k + j (its 4 points shared with neighbours)");
    check_report(padding_ok, "yeti: vertices 16-byte aligned, 16 zero bytes after them");
    check_report(memcmp(a.vertices, b.vertices, 16 * a.vertex_count) == 0 &&
                     memcmp(a.indices, b.indices, 4 * a.segment_count) == 0 && memcmp(a.lower, b.lower, sizeof a.lower) == 0,
                 "yeti: same seed gives identical bytes");
    check_report(memcmp(a.vertices, c.vertices, 16 * a.vertex_count) != 0, "yeti: another seed gives another scene");

    /* each strand: finite points, root on the skin, nothing inside the
       body, 0.15-0.25 long, radius shrinking from root to tip */
    size_t bad_strands = 0, band_counts[BANDS] = {0}, diagonal = 0;
    for (size_t k = 0; k < strands; k++) {
        const float *p = a.vertices + 4 * POINTS * k;
        int ok = 1;
        double length = 0.0;
        for (size_t i = 0; i < 4 * POINTS; i++)
            ok &= isfinite(p[i]) != 0;
        ok &= fabs(capsule_axis_distance(p + 4) - 0.5) < 1e-5;
        for (int i = 1; i <= SEGMENTS + 1; i++)
            ok &= capsule_axis_distance(p + 4 * i) > 0.5 - 1e-5 && p[4 * i + 3] > 0.0f;
        for (int i = 1; i <= SEGMENTS; i++) {
            double d2 = 0.0;
            for (int axis = 0; axis < 3; axis++)
                d2 += (p[4 * (i + 1) + axis] - p[4 * i + axis]) * (p[4 * (i + 1) + axis] - p[4 * i + axis]);
            length += sqrt(d2);
            ok &= p[4 * (i + 1) + 3] < p[4 * i + 3];
        }
        ok &= length > 0.15 - 1e-4 && length < 0.25 + 1e-4;
        bad_strands += !ok;
        /* the root's place along the axis, from -1.25 to 1.25 */
        const double axis_length = sqrt(0.8 * 0.8 + 0.3 * 0.3 + 0.5 * 0.5);
        double along = (0.8 * p[4] + 0.3 * p[5] - 0.5 * p[6]) / axis_length;
        int band = (int)((along + 1.25) / 2.5 * BANDS);
        band_counts[band < 0 ? 0 : band >= BANDS ? BANDS - 1 : band]++;
        /* the middle of the strand: not along a coordinate axis */
        double mid[3], mid_length = 0.0, largest = 0.0;
        for (int axis = 0; axis < 3; axis++) {
            mid[axis] = p[4 * (SEGMENTS / 2 + 2) + axis] - p[4 * (SEGMENTS / 2 + 1) + axis];
            mid_length += mid[axis] * mid[axis];
        }
        for (int axis = 0; axis < 3; axis++)
            largest = fmax(largest, fabs(mid[axis]) / sqrt(mid_length));
        diagonal += largest < 0.9;
    }
    check_report(bad_strands == 0, "yeti: every strand finite, rooted on the capsule, outside it, 0.15-0.25 long, tapering "
                                   "(%zu not)", bad_strands);
    /* equal axial bands of a capsule have equal area (Archimedes), so an even cover puts as many roots in each */
    size_t fewest = strands, most = 0;
    for (int band = 0; band < BANDS; band++) {
        fewest = band_counts[band] < fewest ? band_counts[band] : fewest;
        most = band_counts[band] > most ? band_counts[band] : most;
    }
    check_report(fewest > strands / BANDS * 95 / 100 && most < strands / BANDS * 105 / 100,
                 "yeti: roots even along the body: %zu-%zu of %zu strands in each of %d equal-area bands", fewest, most,
                 strands, BANDS);
    /* directions uniform on the sphere have no component above 0.9 70% of the time; fur
       combed along a coordinate axis, hardly ever */
    check_report(diagonal > strands * 6 / 10, "yeti: %zu of %zu strands run diagonally to the axes mid-way (no component "
                                              "above 0.9; isotropic directions: 70%%)", diagonal, strands);

    /* the Bezier form against the Catmull-Rom polynomials, joints, bounds */
    int converted = 1, joints = 1, bounded = 1;
    double worst = 0.0;
    for (size_t i = 0; i < a.segment_count; i++) {
        float control[16], next[16];
        const float *p = a.vertices + 4 * (size_t)a.indices[i];
        scene_segment_bezier(&a, i, control);
        for (int step = 0; step <= 8; step++) {
            double want[4], got[4];
            catmull_rom_point(p, step / 8.0, want);
            bezier_point(control, step / 8.0, got);
            for (int k = 0; k < 4; k++) {
                worst = fmax(worst, fabs(got[k] - want[k]) / (k == 3 ? fabs(want[3]) : 1.0));
                if (k < 3) /* the bounds are float sums: 1e-6 of rounding */
                    bounded &= got[k] - got[3] >= a.lower[k] - 1e-6 && got[k] + got[3] <= a.upper[k] + 1e-6;
            }
        }
        converted &= control[0] == p[4] && control[12] == p[8];
        if (i % SEGMENTS != SEGMENTS - 1) {
            scene_segment_bezier(&a, i + 1, next);
            joints &= memcmp(control + 12, next, 4 * sizeof(float)) == 0;
        }
    }
    converted &= worst < 1e-6;
    check_report(converted, "yeti: Bezier form runs from point 2 to point 3 and traces the Catmull-Rom polynomials "
                            "(worst %.2g: absolute in position, relative in radius)", worst);
    check_report(joints, "yeti: along a strand each segment starts where the last ended, to the bit");
    check_report(bounded, "yeti: bounds hold the tube at 9 points of every segment");

    result = scene_to_bezier(&a, &bezier);
    check_report(result == 0 && bezier.basis == SCENE_BASIS_BEZIER && bezier.segment_count == a.segment_count &&
                     bezier.vertex_count == 4 * a.segment_count,
                 "yeti: scene_to_bezier makes %zu independent Bezier segments", bezier.segment_count);
    if (result == 0) {
        int same = 1;
        for (size_t i = 0; i < a.segment_count; i++) {
            float control[16];
            scene_segment_bezier(&a, i, control);
            same &= bezier.indices[i] == 4 * i && memcmp(bezier.vertices + 16 * i, control, sizeof control) == 0;
        }
        for (int axis = 0; axis < 3; axis++)
            same &= bezier.lower[axis] == a.lower[axis] && bezier.upper[axis] == a.upper[axis];
        check_report(same, "yeti: scene_to_bezier's segments and bounds are the scene's");

        /* Embree reads the shared points as Catmull-Rom curves: the same hits as its Bezier curves on the copy */
        const int side = 256;
        size_t rays = (size_t)side * side, hits = 0, disagree = 0, both = 0, close = 0;
        float *org = (float *)malloc(12 * rays), *dir = (float *)malloc(12 * rays);
        emb_scene *curves = emb_build_curves(a.vertices, a.vertex_count, a.indices, a.segment_count,
                                             EMB_FLAT_CATMULL_ROM, NULL, 16, 0, NULL, NULL);
        emb_scene *copy = emb_build(bezier.vertices, bezier.vertex_count, bezier.indices, bezier.segment_count,
                                    EMB_FLAT_BEZIER, 16, 0, NULL, NULL);
        check_report(curves && copy, "yeti: Embree builds flat Catmull-Rom curves on the shared points, and Bezier curves");
        if (curves && copy && org && dir) {
            scene_camera_rays(&a, side, side, org, dir);
            for (size_t i = 0; i < rays; i++) {
                float t1 = 0.0f, t2 = 0.0f;
                uint32_t prim1 = 0, prim2 = 0;
                int hit1 = emb_intersect(curves, org + 3 * i, 0.0f, dir + 3 * i, INFINITY, &t1, NULL, NULL, &prim1);
                int hit2 = emb_intersect(copy, org + 3 * i, 0.0f, dir + 3 * i, INFINITY, &t2, NULL, NULL, &prim2);
                hits += (size_t)hit1;
                disagree += hit1 != hit2;
                if (hit1 && hit2 && prim1 == prim2) {
                    both++;
                    close += fabsf(t1 - t2) <= 1e-4f * t2;
                }
            }
            info("yeti: Embree Catmull-Rom against Bezier: %zu of %zu camera rays hit, %zu disagree, t within 1e-4 "
                 "on %zu of %zu same-segment hits", hits, rays, disagree, close, both);
            check_report(hits > rays / 10, "yeti: %zu of %zu camera rays hit the fur", hits, rays);
            check_report(disagree <= rays / 1000 && close >= both - both / 1000,
                         "yeti: Embree's Catmull-Rom and Bezier curves agree: %zu hit/miss disagreements, t on %zu of %zu",
                         disagree, close, both);
        }
        emb_free(curves);
        emb_free(copy);
        free(org);
        free(dir);
    }
    print_bounds(&a);
    info("yeti: %.2f bytes a segment (16 a point, 4 an index), generated in %.3f s", 
         (16.0 * (double)a.vertex_count + 4.0 * (double)a.segment_count) / (double)a.segment_count, seconds);
    scene_free(&a);
    scene_free(&b);
    scene_free(&c);
    scene_free(&bezier);

    check_report(scene_yeti(&a, 0, 1) == 0 && a.segment_count == SEGMENTS, "yeti: a tiny target gives one strand");
    scene_free(&a);
    check_report(scene_yeti(&a, SIZE_MAX, 1) != 0 && a.vertices == NULL && a.indices == NULL &&
                     scene_yeti(&a, (size_t)UINT32_MAX, 1) != 0 && a.vertices == NULL,
                 "yeti: more points than uint32 indices reach is an error, nothing allocated");
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

/* Writes data (optionally modified) to a temporary file and returns what the
   loader says about it. */
static int load_variant(const unsigned char *data, size_t size)
{
    char path[SCRATCH_PATH_SIZE];
    scratch_path(path, sizeof path, "hairobb_test_scenes.hair");
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
    scene_put_le_u32(file + 4, strand_count);
    scene_put_le_u32(file + 8, point_count);
    scene_put_le_u32(file + 12, 1 | 2 | 4 | 16);
    scene_put_le_u32(file + 16, 7);      /* default segments, unused: the array wins */
    scene_put_le_f32(file + 20, 1.0f);   /* default thickness, unused: the array wins */
    file[128] = 2;              /* segments per strand, uint16 */
    file[130] = 1;
    for (uint32_t i = 0; i < point_count; i++) {
        scene_put_le_f32(file + 132 + 12 * i, (float)i);
        scene_put_le_f32(file + 132 + 12 * i + 4, 1.0f);
        scene_put_le_f32(file + 132 + 12 * i + 8, 2.0f);
        scene_put_le_f32(file + 132 + 60 + 4 * i, 0.2f);
    }
    char path[SCRATCH_PATH_SIZE];
    scratch_path(path, sizeof path, "hairobb_test_scenes_small.hair");
    hair_scene s;
    int result = write_file(path, file, sizeof file) ? scene_load_hair(&s, path) : 99;
    remove(path);
    check_report(result == 0 && s.segment_count == 3 && s.vertices[3] == 0.1f && s.vertices[0] == 0.0f &&
                     s.vertices[12] == 1.0f && s.vertices[32] == 3.0f && s.vertices[44] == 4.0f,
                 "hair: segments + thickness + colour arrays (2 strands, 5 points -> 3 segments, radius 0.1)");
    if (result == 0)
        check_report(strncmp(s.name, "hairobb_test_scenes_", 20) == 0 && strchr(s.name, '.') == NULL, "hair: scene named after the file (%s)", s.name);
    scene_free(&s);

    check_report(scene_load_hair(&s, scratch_path(path, sizeof path, "no_such_file.hair")) == -1,
                 "hair: missing file reports -1 (absent)");
}

static void test_straight_hair(const char *path)
{
    if (!path)
        return;
    hair_scene s;
    double start = scene_now();
    int result = scene_load_hair(&s, path);
    double seconds = scene_now() - start;
    check_report(result == 0 && s.segment_count == 150000, "straight.hair: loads with 150000 segments (got %zu)",
                 s.segment_count);
    if (result != 0)
        return;
    float min_radius, max_radius;
    check_report(scene_is_sane(&s, &min_radius, &max_radius) && min_radius == 0.05f && max_radius == 0.05f,
                 "straight.hair: radius 0.05 everywhere (default thickness 0.1 is a diameter)");
    /* README bounds of the points; control points overshoot slightly and
       add the radius */
    const float lower[3] = {-32.5f, -33.9f, -22.7f}, upper[3] = {30.9f, 24.1f, 63.7f};
    int bounds_ok = 1;
    for (int axis = 0; axis < 3; axis++)
        bounds_ok &= fabsf(s.lower[axis] - lower[axis]) < 0.6f && fabsf(s.upper[axis] - upper[axis]) < 0.6f;
    check_report(bounds_ok, "straight.hair: bounds ~x[-32.5,30.9] y[-33.9,24.1] z[-22.7,63.7]");
    print_bounds(&s);
    info("straight.hair: loaded in %.3f s", seconds);
    scene_free(&s);

    unsigned char *data = NULL;
    size_t size = 0;
    if (scene_read_file(path, &data, &size) != 0) {
        check_report(0, "straight.hair: read for corruption tests");
        return;
    }
    check_report(load_variant(data, size) == 0, "straight.hair: an unchanged copy (a scratch file) loads");
    const size_t cuts[] = {0, 3, 64, 127, 128, 128 + 12 * 80000, 128 + 12 * 160000, size - 12, size - 1};
    for (size_t k = 0; k < sizeof cuts / sizeof cuts[0]; k++)
        check_report(load_variant(data, cuts[k]) > 0, "straight.hair: truncated to %zu bytes is rejected", cuts[k]);

    unsigned char *copy = (unsigned char *)malloc(size + 4);
    memcpy(copy, data, size);
    copy[3] = 'X';
    check_report(load_variant(copy, size) > 0, "straight.hair: bad magic \"HAIX\" is rejected");
    memcpy(copy, data, size);
    scene_put_le_u32(copy + 12, scene_le_u32(data + 12) | 64);
    check_report(load_variant(copy, size) > 0, "straight.hair: reserved flag bit 64 is rejected");
    memcpy(copy, data, size);
    scene_put_le_u32(copy + 12, scene_le_u32(data + 12) & ~2u);
    check_report(load_variant(copy, size) > 0, "straight.hair: missing points array is rejected");
    memcpy(copy, data, size);
    scene_put_le_u32(copy + 4, 9999);
    check_report(load_variant(copy, size) > 0, "straight.hair: strand count inconsistent with point count is rejected");
    memcpy(copy, data, size);
    scene_put_le_u32(copy + 16, 14);
    check_report(load_variant(copy, size) > 0, "straight.hair: default segments inconsistent with point count is rejected");
    memcpy(copy, data, size);
    memset(copy + size, 0, 4);
    check_report(load_variant(copy, size + 4) > 0, "straight.hair: trailing bytes are rejected");
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
    check_report(result == 0 && s.segment_count == 455505, "furBall_A: loads with 455505 segments (got %zu)",
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
    check_report(scene_is_sane(&s, &min_radius, &max_radius) && min_end > 0.0009f && max_end <= 0.005f,
                 "furBall_A: end-point radii %.5f..%.5f within the file's 0.0009..0.005", min_end, max_end);
    print_bounds(&s);
    info("furBall_A: loaded (gunzip via popen) in %.3f s", seconds);
    scene_free(&s);
    char missing[SCRATCH_PATH_SIZE];
    check_report(scene_load_furball(&s, scratch_path(missing, sizeof missing, "no_such_furball.bin.gz")) == -1,
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
        check_report(0, "camera: scene");
        return;
    }
    const int width = 64, height = 48;
    float *org = (float *)malloc(3 * width * height * sizeof(float));
    float *dir = (float *)malloc(3 * width * height * sizeof(float));
    scene_camera_rays(&s, width, height, org, dir);
    int unit = 1;
    for (int i = 0; i < width * height; i++)
        unit &= fabsf(sqrtf(dir[3 * i] * dir[3 * i] + dir[3 * i + 1] * dir[3 * i + 1] + dir[3 * i + 2] * dir[3 * i + 2]) - 1.0f) < 1e-5f;
    check_report(unit, "camera: unit directions");
    int top_left = 0, top_right = width - 1, bottom_left = (height - 1) * width;
    check_report(dir[3 * top_left + 1] > dir[3 * bottom_left + 1] && dir[3 * top_left] < dir[3 * top_right] &&
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
        check_report(e != NULL, "embree %s %s: builds", s->name, type_name);
        if (!e)
            continue;
        info("embree %s %s: %zu segments, build %.3f s, %.1f MB (%.0f bytes/segment)", s->name, type_name,
             s->segment_count, build_seconds, (double)memory / 1e6, (double)memory / (double)s->segment_count);
        trace_stats stats = trace_camera(e, s, width, height);
        check_report(stats.hit_fraction > 0.05, "embree %s %s: %.1f%% of %dx%d camera rays hit", s->name, type_name,
                     100.0 * stats.hit_fraction, width, height);
        check_report(stats.bad_hits == 0, "embree %s %s: hits have t > 0, valid primID, u in [0,1] (%zu bad)", s->name,
                     type_name, stats.bad_hits);
        check_report(stats.disagreements == 0, "embree %s %s: emb_occluded agrees with emb_intersect (%zu disagree)",
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
            check_report(bounds_ok, "transform %s: bounds scaled by 10 about the centre and moved", s->name);
            emb_scene *moved_e = emb_build(moved.vertices, moved.vertex_count, moved.indices, moved.segment_count,
                                           type, 0, 0, NULL, NULL);
            if (moved_e) {
                trace_stats moved_stats = trace_camera(moved_e, &moved, width, height);
                check_report(fabs(moved_stats.hit_fraction - stats.hit_fraction) < 0.01,
                             "transform %s: same camera picture after moving and scaling (%.2f%% vs %.2f%% hit)",
                             s->name, 100.0 * moved_stats.hit_fraction, 100.0 * stats.hit_fraction);
                emb_free(moved_e);
            } else {
                check_report(0, "transform %s: embree build", s->name);
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
        check_report(0, "embree options: scene");
        return;
    }
    double seconds = 0.0;
    size_t memory = 0;
    emb_scene *e = emb_build(s.vertices, s.vertex_count, s.indices, s.segment_count, EMB_FLAT_BEZIER, 8, 1,
                             &memory, &seconds);
    check_report(e != NULL && memory > 0 && seconds > 0.0,
                 "embree options: threads=1 and tessellation rate 8 build (%.1f MB, %.4f s)", (double)memory / 1e6, seconds);
    emb_free(e);
    printf("     (an error message about curve type 7 is expected next)\n");
    e = emb_build(s.vertices, s.vertex_count, s.indices, s.segment_count, 7, 0, 0, &memory, &seconds);
    check_report(e == NULL, "embree options: unknown curve type gives NULL");
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
    test_yeti();
    test_hair_format();
    test_straight_hair(straight_path);
    test_furball(furball_path);
    test_camera();
    test_embree(straight_path, furball_path);
    return check_summary();
}
