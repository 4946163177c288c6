/* fuzz_load.c - libFuzzer target: arbitrary bytes as a saved BVH.
   The input's checksum is fixed up first (its last 8 bytes), so that
   mutations reach the structural checks behind it rather than stopping
   there; it is then loaded over one fixed small scene (combed fur, 48
   segments, read in the basis the header names, with fixed tangents for
   Hermite) with the hair check skipped (mutations need not fix the hair
   hash either). hairobb_load must return one of its codes, leave no BVH
   on failure and, on success, give a BVH whose traced hits are sane
   (fuzz_checks.h); ASan and UBSan see any read out of bounds, including
   the traversal stack. A saved motion-blurred BVH (time_steps 2 to 5 in
   its header) is loaded over the scene moving (swept about its roots for
   an even number of steps, translated for an odd), traced at times in
   [0, 1] and at times outside it and NaN, where every ray must miss.
   Seeds, tests/fuzz/corpus/bvh_load: the scene's BVH saved with several
   option sets, static and moving, written by this file built with
   -DFUZZ_LOAD_WRITE_SEEDS (its main writes them into the directory named). */
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#define HAIROBB_IMPLEMENTATION
#include "../../hairobb.h"
#include "fuzz_checks.h"
#include "../scenes.h"

#define FUZZ_MAX_STEPS 5

static hair_scene fuzz_scene;
static float *fuzz_tangents;
static float *fuzz_steps[FUZZ_MAX_STEPS + 1][FUZZ_MAX_STEPS];   /* [T][k]: the scene moving, T = 2.. */

static void fuzz_setup(void)
{
    size_t v;
    int k;
    if (fuzz_tangents) return;
    if (scene_combed(&fuzz_scene, 48, 1) != 0) fuzz_fail("scene");
    for (k = 2; k <= FUZZ_MAX_STEPS; ++k)
        if (scene_motion_steps(&fuzz_scene, k % 2 ? SCENE_MOTION_TRANSLATE : SCENE_MOTION_ROTATE, k % 2 ? 0.5 : 0.8, k,
                               fuzz_steps[k]) != 0)
            fuzz_fail("motion steps");
    fuzz_tangents = (float *)malloc(4 * sizeof(float) * fuzz_scene.vertex_count);
    if (!fuzz_tangents) fuzz_fail("tangents");
    for (v = 0; v < fuzz_scene.vertex_count; ++v)
        for (k = 0; k < 4; ++k)
            fuzz_tangents[4 * v + k] = v + 1 < fuzz_scene.vertex_count
                                           ? 3.0f * (fuzz_scene.vertices[4 * (v + 1) + k] - fuzz_scene.vertices[4 * v + k])
                                           : 0.0f;
}

/* Rays through the middle of the loaded bounds, and at some segments, at
   one time. */
static void trace_at(const hairobb_bvh *bvh, float time)
{
    size_t s;
    int j;
    fuzz_check_rays_through_bounds(bvh, fuzz_scene.segment_count, time);
    for (s = 0; s < fuzz_scene.segment_count; s += 6) {
        const float *cp = fuzz_scene.vertices + 4 * (size_t)fuzz_scene.indices[s];
        hairobb_ray ray;
        for (j = 0; j < 3; ++j) {
            ray.dir[j] = fuzz_directions[s % 4][j];
            ray.org[j] = 0.5f * cp[4 + j] + 0.5f * cp[8 + j] - ray.dir[j];
        }
        ray.tnear = 0.0f;
        ray.tfar = INFINITY;
        ray.time = time;
        fuzz_check_ray(bvh, &ray, fuzz_scene.segment_count);
    }
}

/* A moving BVH's rays miss at times outside [0, 1] and NaN. */
static void check_misses_at(const hairobb_bvh *bvh, float time)
{
    hairobb_ray ray = {{0.0f, 0.0f, -3.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY, 0.0f};
    hairobb_hit hit;
    size_t s;
    int j;
    ray.time = time;
    for (s = 0; s < fuzz_scene.segment_count; s += 3) {
        const float *cp = fuzz_scene.vertices + 4 * (size_t)fuzz_scene.indices[s];
        for (j = 0; j < 2; ++j) ray.org[j] = cp[4 + j];
        if (hairobb_intersect1(bvh, &ray, &hit) || hit.prim_id != HAIROBB_INVALID_ID || hairobb_occluded1(bvh, &ray))
            fuzz_fail("a ray at a time outside [0, 1] hit");
    }
}

static void trace(const hairobb_bvh *bvh, unsigned time_steps)
{
    static const float inside[4] = {0.0f, 0.37f, 0.5f, 1.0f}, outside[4] = {-0.5f, -1e-30f, 1.0000001f, NAN};
    int k;
    if (time_steps < 2) {
        trace_at(bvh, 0.0f);
        return;
    }
    for (k = 0; k < 4; ++k) trace_at(bvh, inside[k]);
    for (k = 0; k < 4; ++k) check_misses_at(bvh, outside[k]);
}

/* time_steps in a saved header (0 for a static BVH or too short a file) */
static unsigned saved_time_steps(const uint8_t *data, size_t size)
{
    return size >= HAIROBB__SAVE_HEADER ? hairobb__get32(data + HAIROBB__AT_TIME_STEPS) : 0u;
}

static hairobb_result fuzz_load(const uint8_t *data, size_t size, hairobb_bvh **bvh)
{
    hairobb_build_options options;
    uint32_t basis = size >= HAIROBB__SAVE_HEADER ? hairobb__get32(data + HAIROBB__AT_BASIS) : 0;
    memset(&options, 0, sizeof options);
    options.verify_hair = HAIROBB_OFF;
    options.basis = basis <= HAIROBB_BASIS_LINEAR ? (hairobb_basis)basis : HAIROBB_BASIS_BEZIER;
    options.tangents = options.basis == HAIROBB_BASIS_HERMITE ? fuzz_tangents : NULL;
    /* moving: the steps of the count saved (another count loads as static: a mismatch);
       never with Hermite, options a caller cannot give (INVALID_ARGUMENT before the file is read) */
    if (saved_time_steps(data, size) >= 2 && saved_time_steps(data, size) <= FUZZ_MAX_STEPS && options.basis != HAIROBB_BASIS_HERMITE) {
        options.time_steps = saved_time_steps(data, size);
        options.time_vertices = (const float *const *)fuzz_steps[options.time_steps];
    }
    return hairobb_load(data, size, fuzz_scene.vertices, fuzz_scene.vertex_count, fuzz_scene.indices,
                        fuzz_scene.segment_count, &options, bvh);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    hairobb_bvh *bvh = (hairobb_bvh *)(uintptr_t)1;
    hairobb_result result;
    uint8_t *copy;
    unsigned time_steps;
    fuzz_setup();
    copy = (uint8_t *)malloc(size ? size : 1);
    if (!copy) return 0;
    if (size) memcpy(copy, data, size);
    if (size >= 8) hairobb__put64(copy + size - 8, hairobb__save_checksum(copy, size));
    result = fuzz_load(copy, size, &bvh);
    time_steps = saved_time_steps(copy, size);
    free(copy);   /* nothing of the bytes is kept */
    if (result != HAIROBB_OK) {
        if (bvh) fuzz_fail("a failed load left a BVH");
        if (result != HAIROBB_ERROR_INVALID_FILE && result != HAIROBB_ERROR_UNSUPPORTED && result != HAIROBB_ERROR_MISMATCH &&
            result != HAIROBB_ERROR_OUT_OF_MEMORY)
            fuzz_fail("a code the loader does not return for these arrays");
        return 0;
    }
    if (!bvh) fuzz_fail("a load without a BVH");
    trace(bvh, time_steps);
    hairobb_free(bvh);
    return 0;
}

#ifdef FUZZ_LOAD_WRITE_SEEDS
#include <stdio.h>
int main(int argc, char **argv)
{
    static const struct { hairobb_obb_layout layout; hairobb_basis basis; unsigned leaf; hairobb_switch spatial; unsigned time_steps; } seeds[] = {
        {HAIROBB_OBB_DEFAULT, HAIROBB_BASIS_BEZIER, 0, HAIROBB_AUTO, 0},
        {HAIROBB_OBB_PER_CHILD, HAIROBB_BASIS_BEZIER, 1, HAIROBB_AUTO, 0},
        {HAIROBB_OBB_SHARED_ROTATION, HAIROBB_BASIS_CATMULL_ROM, 2, HAIROBB_ON, 0},
        {HAIROBB_OBB_COMPRESSED, HAIROBB_BASIS_HERMITE, 0, HAIROBB_AUTO, 0},
        {HAIROBB_OBB_COMPRESSED_PER_CHILD, HAIROBB_BASIS_BSPLINE, 3, HAIROBB_ON, 0},
        {HAIROBB_OBB_DEFAULT, HAIROBB_BASIS_LINEAR, 15, HAIROBB_AUTO, 0},
        /* moving (Bezier only) */
        {HAIROBB_OBB_DEFAULT, HAIROBB_BASIS_BEZIER, 0, HAIROBB_AUTO, 2},
        {HAIROBB_OBB_PER_CHILD, HAIROBB_BASIS_BEZIER, 1, HAIROBB_ON, 3},
        {HAIROBB_OBB_SHARED_ROTATION, HAIROBB_BASIS_BEZIER, 2, HAIROBB_AUTO, 4},
        {HAIROBB_OBB_COMPRESSED, HAIROBB_BASIS_BEZIER, 0, HAIROBB_ON, 5},
        {HAIROBB_OBB_COMPRESSED_PER_CHILD, HAIROBB_BASIS_BEZIER, 3, HAIROBB_AUTO, 2},
    };
    size_t k;
    if (argc != 2) { fprintf(stderr, "usage: %s DIRECTORY\n", argv[0]); return 2; }
    fuzz_setup();
    for (k = 0; k < sizeof seeds / sizeof seeds[0]; ++k) {
        hairobb_build_options options;
        hairobb_bvh *bvh = NULL, *loaded = NULL;
        char path[4096];
        memset(&options, 0, sizeof options);
        options.obb_layout = seeds[k].layout;
        options.basis = seeds[k].basis;
        options.tangents = seeds[k].basis == HAIROBB_BASIS_HERMITE ? fuzz_tangents : NULL;
        options.max_leaf_size = seeds[k].leaf;
        options.spatial_splits = seeds[k].spatial;
        options.threads = 1;
        if (seeds[k].time_steps) {
            options.time_steps = seeds[k].time_steps;
            options.time_vertices = (const float *const *)fuzz_steps[seeds[k].time_steps];
        }
        snprintf(path, sizeof path, "%s/seed%zu.bvh", argv[1], k);
        if (hairobb_build(fuzz_scene.vertices, fuzz_scene.vertex_count, fuzz_scene.indices, fuzz_scene.segment_count, &options,
                          &bvh) != HAIROBB_OK ||
            hairobb_save_file(bvh, path) != HAIROBB_OK ||
            hairobb_load_file(path, fuzz_scene.vertices, fuzz_scene.vertex_count, fuzz_scene.indices,
                              fuzz_scene.segment_count, &options, &loaded) != HAIROBB_OK) {
            fprintf(stderr, "seed %zu failed\n", k);
            return 1;
        }
        trace(loaded, seeds[k].time_steps);
        printf("%s: %zu bytes\n", path, hairobb_save_size(bvh));
        hairobb_free(loaded);
        hairobb_free(bvh);
    }
    return 0;
}
#endif
