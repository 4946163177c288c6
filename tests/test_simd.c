/* test_simd.c - every SIMD path gives the same answers as the plain C path:
   the same rays traced by four builds of hairobb.h (plain C; SSE4.1; AVX2;
   the x86-64 baseline, forced to SSE2 and dispatched to its AVX2 kernels;
   on AArch64 two: plain C and NEON),
   compared field by field, bit for bit, on several scenes, node policies and
   intersector precisions, curve bases read with and without the Bezier
   copy, and on moving hair (motion blur: rotating and translating fur, 2
   to 4 time steps) at random ray times, and round curves (tubes), still
   and moving. */
#define _POSIX_C_SOURCE 200809L
#include "simd_variant.h"
#include "check.h"
#include "compare.h"
#include "scenes.h"

#include <stdlib.h>
#include <string.h>

/* rays a side, and segments a static scene; the AArch64 tier under qemu
   builds and traces less (tests/run_arm64.sh) */
#ifndef SIDE
#define SIDE 128
#endif
#ifndef SIMD_TEST_SEGMENTS
#define SIMD_TEST_SEGMENTS 30000
#endif

/* The copies keep hits, not what intersect1 returned: a miss is prim_id HAIROBB_INVALID_ID. */
static int same_answer(const hairobb_hit *a, const hairobb_hit *b)
{
    return same_hit(a->prim_id != HAIROBB_INVALID_ID, a, b->prim_id != HAIROBB_INVALID_ID, b);
}

typedef SIMD_VARIANT_SIGNATURE((*trace_fn));

/* the copies are static: the test names the paths itself */
static const char *path_name(hairobb_simd simd)
{
    static const char *names[] = {"auto", "plain C", "SSE2", "SSE4.1", "AVX", "AVX2", "NEON"};
    return (unsigned)simd < sizeof names / sizeof names[0] ? names[simd] : "?";
}

/* The paths compared with plain C: the copy that runs them, the path asked
   for in options.simd, and the one the BVH must report. */
typedef struct simd_path {
    const char *name;
    trace_fn trace;
    hairobb_simd request, expect;
    int needs_avx2;           /* compiled with -mavx2: runs only where the CPU has it */
} simd_path;

/* A motion-blurred BVH's ray times: random in [0, 1], every 16th ray at a
   knot k / (T - 1) (0 and 1 among them) and every 61st outside [0, 1] or
   NaN, which must miss. */
static float ray_time(size_t i, unsigned time_steps, scene_rng *rng)
{
    static const float outside[4] = {-0.25f, 1.5f, -1e-30f, NAN};
    if (i % 61 == 60) return outside[(i / 61) % 4];
    if (i % 16 == 15) return (float)((i / 16) % time_steps) / (float)(time_steps - 1);
    return scene_rng_float(rng);
}

static void compare_paths(const hair_scene *s, const hairobb_build_options *options, const char *what)
{
    size_t n = (size_t)SIDE * SIDE, i, hits = 0, differ[4] = {0, 0, 0, 0}, outside_hits = 0;
    scene_rng rng;
    float *org = (float *)malloc(3 * sizeof(float) * n), *dir = (float *)malloc(3 * sizeof(float) * n);
    hairobb_ray *rays = (hairobb_ray *)malloc(sizeof(hairobb_ray) * n);
    hairobb_hit *plain = (hairobb_hit *)malloc(sizeof(hairobb_hit) * n);
    hairobb_hit *other = (hairobb_hit *)malloc(sizeof(hairobb_hit) * n);
    int *occluded_plain = (int *)malloc(sizeof(int) * n), *occluded_other = (int *)malloc(sizeof(int) * n);
    int k;
    hairobb_simd used = HAIROBB_SIMD_AUTO;
    size_t visits[4], aliased_differ = 0;
    /* points read where they are, or made on the fly by the path's own code */
    int made = options->time_steps >= 2 || (options->basis != HAIROBB_BASIS_BEZIER && options->bezier_copy == HAIROBB_OFF);
#if defined(__aarch64__)
    /* NEON is AArch64's baseline: asked for, and by AUTO */
    int have_avx = 0;
    simd_path paths[] = {
        {"NEON", trace_neon, HAIROBB_SIMD_NEON, HAIROBB_SIMD_NEON, 0},
        {"NEON (auto)", trace_neon, HAIROBB_SIMD_AUTO, HAIROBB_SIMD_NEON, 0},
    };
#else
    /* the x86-64 baseline copy has the AVX2 kernels too: AUTO picks them where the CPU has AVX2 */
    int have_avx = __builtin_cpu_supports("avx2");
    simd_path paths[] = {
        {"SSE4.1", trace_sse, HAIROBB_SIMD_SSE41, HAIROBB_SIMD_SSE41, 0},
        {"SSE2", trace_dispatch, HAIROBB_SIMD_SSE2, HAIROBB_SIMD_SSE2, 0},
        {"AVX2 -mavx2", trace_avx, HAIROBB_SIMD_AUTO, HAIROBB_SIMD_AVX2, 1},
        {"AVX2 dispatched", trace_dispatch, HAIROBB_SIMD_AUTO, HAIROBB_SIMD_AVX2, 0},
    };
    if (!have_avx) paths[3].expect = HAIROBB_SIMD_SSE2;
#endif
    const int path_count = (int)(sizeof paths / sizeof paths[0]);
    hairobb_build_options asked = *options;

    scene_camera_rays(s, SIDE, SIDE, org, dir);
    scene_rng_seed(&rng, 5);
    for (i = 0; i < n; ++i) {
        memcpy(rays[i].org, org + 3 * i, sizeof rays[i].org);
        memcpy(rays[i].dir, dir + 3 * i, sizeof rays[i].dir);
        rays[i].tnear = 0.0f;
        rays[i].tfar = INFINITY;
        rays[i].time = options->time_steps >= 2 ? ray_time(i, options->time_steps, &rng) : 0.0f;
    }
    CHECK(trace_plain(s->vertices, s->vertex_count, s->indices, s->segment_count, options, rays, n, plain, occluded_plain, &used, visits,
                      &aliased_differ),
          "%s %s: plain C build", s->name, what);
    CHECK(used == HAIROBB_SIMD_NONE, "%s %s: plain C build traced with %s", s->name, what, path_name(used));
    CHECK(aliased_differ == 0, "%s %s: plain C: intersect1_from with the hit written over `from` differs on %zu rays", s->name,
          what, aliased_differ);
    for (i = 0; i < n; ++i) {
        hits += plain[i].prim_id != HAIROBB_INVALID_ID;
        outside_hits += !(rays[i].time >= 0.0f && rays[i].time <= 1.0f) && (plain[i].prim_id != HAIROBB_INVALID_ID || occluded_plain[i]);
    }
    CHECK(hits > n / 20, "%s %s: %zu of %zu rays hit", s->name, what, hits, n);
    CHECK(outside_hits == 0, "%s %s: %zu rays at times outside [0, 1] hit", s->name, what, outside_hits);

    printf("%-8s %-46s %5zu hits of %zu rays; differ from plain C:", s->name, what, hits, n);
    for (k = 0; k < path_count; ++k) {
        if (paths[k].needs_avx2 && !have_avx) { printf(" %s skipped (no AVX2),", paths[k].name); continue; }
        asked.simd = paths[k].request;
        used = HAIROBB_SIMD_AUTO;
        CHECK(paths[k].trace(s->vertices, s->vertex_count, s->indices, s->segment_count, &asked, rays, n, other,
                             occluded_other, &used, visits, &aliased_differ),
              "%s %s: %s build", s->name, what, paths[k].name);
        CHECK(aliased_differ == 0, "%s %s: %s: intersect1_from with the hit written over `from` differs on %zu rays", s->name,
              what, paths[k].name, aliased_differ);
        CHECK(used == paths[k].expect, "%s %s: %s traced with %s", s->name, what, paths[k].name, path_name(used));
        /* the kernels that ran are the ones reported */
        CHECK(visits[used == HAIROBB_SIMD_AVX2] > 0 && visits[used != HAIROBB_SIMD_AVX2] == 0,
              "%s %s: %s reports %s, leaves reached by baseline/AVX2 kernels %zu/%zu", s->name, what, paths[k].name,
              path_name(used), visits[0], visits[1]);
        /* and so is the code that made points on the fly (hit attributes, baseline code, make them there too) */
        CHECK(made ? (visits[3] > 0) == (used == HAIROBB_SIMD_AVX2) && (visits[2] > 0 || used == HAIROBB_SIMD_AVX2)
                   : visits[2] + visits[3] == 0,
              "%s %s: %s reports %s, segments made on the fly by baseline/AVX2 code %zu/%zu", s->name, what, paths[k].name,
              path_name(used), visits[2], visits[3]);
        for (i = 0; i < n; ++i) differ[k] += !same_answer(&plain[i], &other[i]) || occluded_plain[i] != occluded_other[i];
        CHECK(differ[k] == 0, "%s %s: %s differs from plain C on %zu of %zu rays", s->name, what, paths[k].name, differ[k], n);
        printf(" %s (%s) %zu%s", paths[k].name, path_name(used), differ[k], k < path_count - 1 ? "," : "");
    }
    printf("\n");
    free(org); free(dir); free(rays); free(plain); free(other); free(occluded_plain); free(occluded_other);
}

/* Moving hair: the scene rotating or translating over time_steps steps,
   traced at random times with several option sets. */
static void compare_motion(const hair_scene *s, scene_motion motion, double amount, int time_steps)
{
    static const struct { const char *name; hairobb_node_policy nodes; hairobb_obb_layout layout; hairobb_precision precision; unsigned pieces; hairobb_shape shape; } sets[] = {
        {"mixed", HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_PRECISION_EXACT, 0, HAIROBB_SHAPE_RIBBON},
        {"aabb-only", HAIROBB_NODES_AABB_ONLY, HAIROBB_OBB_DEFAULT, HAIROBB_PRECISION_EXACT, 0, HAIROBB_SHAPE_RIBBON},
        {"obb-only, shared rotation", HAIROBB_NODES_OBB_ONLY, HAIROBB_OBB_SHARED_ROTATION, HAIROBB_PRECISION_EXACT, 0, HAIROBB_SHAPE_RIBBON},
        {"compressed, pieces=4", HAIROBB_NODES_MIXED, HAIROBB_OBB_COMPRESSED, HAIROBB_PRECISION_PIECES, 4, HAIROBB_SHAPE_RIBBON},
        {"round curves", HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_PRECISION_EXACT, 0, HAIROBB_SHAPE_ROUND},
    };
    float *steps[4];
    size_t k;
    if (scene_motion_steps(s, motion, amount, time_steps, steps) != 0) {
        CHECK(0, "%s: motion steps", s->name);
        return;
    }
    for (k = 0; k < sizeof sets / sizeof sets[0]; ++k) {
        hairobb_build_options options;
        char what[64];
        memset(&options, 0, sizeof options);
        options.nodes = sets[k].nodes;
        options.obb_layout = sets[k].layout;
        options.precision = sets[k].precision;
        options.curve_pieces = sets[k].pieces;
        options.shape = sets[k].shape;
        options.time_steps = (unsigned)time_steps;
        options.time_vertices = (const float *const *)steps;
        snprintf(what, sizeof what, "%s %.2g T=%d, %s", motion == SCENE_MOTION_ROTATE ? "rotate" : "shift", amount, time_steps,
                 sets[k].name);
        compare_paths(s, &options, what);
    }
    scene_motion_free(steps, time_steps);
}

int main(void)
{
    hair_scene scenes[3];
    int k, policy;
    CHECK(scene_combed(&scenes[0], SIMD_TEST_SEGMENTS, 11) == 0, "combed");
    CHECK(scene_curly(&scenes[1], SIMD_TEST_SEGMENTS, 12) == 0, "curly");
    CHECK(scene_random(&scenes[2], SIMD_TEST_SEGMENTS, 13) == 0, "random");
    /* moving hair, 10k segments (a build bounds every step): strands swept
       by 0.8 rad about their roots, or the whole scene shifted by 0.5
       (several strand spacings) */
    {
        hair_scene moving;
        CHECK(scene_combed(&moving, 10000, 14) == 0, "combed");
        compare_motion(&moving, SCENE_MOTION_ROTATE, 0.8, 2);
        scene_free(&moving);
        CHECK(scene_curly(&moving, 10000, 15) == 0, "curly");
        compare_motion(&moving, SCENE_MOTION_TRANSLATE, 0.5, 3);
        scene_free(&moving);
        CHECK(scene_random(&moving, 10000, 16) == 0, "random");
        compare_motion(&moving, SCENE_MOTION_ROTATE, 0.8, 4);
        scene_free(&moving);
    }
    for (k = 0; k < 3; ++k) {
        for (policy = 0; policy < 3; ++policy) {
            static const char *names[] = {"mixed", "aabb-only", "obb-only"};
            hairobb_build_options options;
            memset(&options, 0, sizeof options);
            options.nodes = (hairobb_node_policy)policy;
            compare_paths(&scenes[k], &options, names[policy]);
        }
        {
            hairobb_build_options options;
            memset(&options, 0, sizeof options);
            options.precision = HAIROBB_PRECISION_PIECES;
            options.curve_pieces = 4;
            compare_paths(&scenes[k], &options, "pieces=4 (no refine)");
            options.precision = HAIROBB_PRECISION_EXACT;
            options.curve_pieces = 13;
            compare_paths(&scenes[k], &options, "exact, 13 pieces");
            options.curve_pieces = 0;
            options.obb_layout = HAIROBB_OBB_SHARED_ROTATION;
            compare_paths(&scenes[k], &options, "shared-rotation OBBs");
            options.obb_layout = HAIROBB_OBB_PER_CHILD;
            compare_paths(&scenes[k], &options, "per-child float OBBs");
            options.obb_layout = HAIROBB_OBB_COMPRESSED;
            compare_paths(&scenes[k], &options, "compressed, shared byte rotation");
            options.obb_layout = HAIROBB_OBB_DEFAULT;
            options.shape = HAIROBB_SHAPE_ROUND;
            compare_paths(&scenes[k], &options, "round curves (tubes)");
        }
        {
            /* Bezier without the copy (the caller's arrays), other bases
               through the same points, read without the copy and, for
               one, with it; Hermite takes the points as its
               tangents too */
            static const struct { const char *name; hairobb_basis basis; hairobb_switch copy; } bases[] = {
                {"Bezier, no copy", HAIROBB_BASIS_BEZIER, HAIROBB_OFF},
                {"B-spline, no copy", HAIROBB_BASIS_BSPLINE, HAIROBB_OFF},
                {"Catmull-Rom, no copy", HAIROBB_BASIS_CATMULL_ROM, HAIROBB_OFF},
                {"Catmull-Rom, copy", HAIROBB_BASIS_CATMULL_ROM, HAIROBB_ON},
                {"Hermite, no copy", HAIROBB_BASIS_HERMITE, HAIROBB_OFF},
                {"linear, no copy", HAIROBB_BASIS_LINEAR, HAIROBB_OFF},
            };
            size_t b;
            for (b = 0; b < sizeof bases / sizeof bases[0]; ++b) {
                hairobb_build_options options;
                memset(&options, 0, sizeof options);
                options.basis = bases[b].basis;
                options.bezier_copy = bases[b].copy;
                options.tangents = bases[b].basis == HAIROBB_BASIS_HERMITE ? scenes[k].vertices : NULL;
                compare_paths(&scenes[k], &options, bases[b].name);
            }
        }
        scene_free(&scenes[k]);
    }
    return check_summary();
}
