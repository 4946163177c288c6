/* instructions.c - the program behind `make instructions` (bench/instructions.sh):
   hairobb's instructions a ray, counted exactly by callgrind, on one fixed
   scene and ray set: combed fur of 200k segments (tests/scenes.h, seed 1),
   128x128 camera rays (scene_camera_rays), hairobb_intersect1 on 1 thread,
   built with the Makefile's flags and no -march, as a renderer builds the
   header (the AVX2 kernels by dispatch). The quick count to decide kernel
   work from (about 20 seconds for both shapes); `make profile` splits a
   ray's instructions by phase and sets them against Embree's.
   usage: build/instructions ribbon|round [sse2]
   (sse2: options.simd = HAIROBB_SIMD_SSE2, the path of a CPU without AVX2)
   Only trace_rays runs under callgrind's --toggle-collect: the count
   leaves out the scene, the build and the rays' set-up. */
#define _POSIX_C_SOURCE 200809L
#define HAIROBB_IMPLEMENTATION
#include "hairobb.h"
#include "tests/scenes.h"
#include <stdio.h>
#include <string.h>

enum { SIDE = 128 };

#if defined(__GNUC__) || defined(__clang__)
__attribute__((noinline))
#endif
static size_t trace_rays(const hairobb_bvh *bvh, const float *org, const float *dir, size_t count)
{
    size_t i, hits = 0;
    for (i = 0; i < count; ++i) {
        hairobb_ray ray;
        hairobb_hit hit;
        memcpy(ray.org, org + 3 * i, sizeof ray.org);
        memcpy(ray.dir, dir + 3 * i, sizeof ray.dir);
        ray.tnear = 0.0f;
        ray.tfar = INFINITY;
        ray.time = 0.0f;
        hits += (size_t)hairobb_intersect1(bvh, &ray, &hit);
    }
    return hits;
}

int main(int argc, char **argv)
{
    hair_scene scene;
    hairobb_build_options options = hairobb_default_options();
    hairobb_bvh *bvh = NULL;
    float *org, *dir;
    size_t hits;
    if (argc < 2 || argc > 3 || (strcmp(argv[1], "ribbon") != 0 && strcmp(argv[1], "round") != 0) ||
        (argc == 3 && strcmp(argv[2], "sse2") != 0)) {
        fprintf(stderr, "usage: instructions ribbon|round [sse2]\n");
        return 2;
    }
    if (argc == 3) options.simd = HAIROBB_SIMD_SSE2;
    options.shape = strcmp(argv[1], "round") == 0 ? HAIROBB_SHAPE_ROUND : HAIROBB_SHAPE_RIBBON;
    org = (float *)malloc(3 * sizeof(float) * SIDE * SIDE);
    dir = (float *)malloc(3 * sizeof(float) * SIDE * SIDE);
    if (!org || !dir || scene_combed(&scene, 200000, 1) != 0) return 1;
    scene_camera_rays(&scene, SIDE, SIDE, org, dir);
    if (hairobb_build(scene.vertices, scene.vertex_count, scene.indices, scene.segment_count, &options, &bvh) != HAIROBB_OK)
        return 1;
    hits = trace_rays(bvh, org, dir, (size_t)SIDE * SIDE);
    printf("%s: %d rays, %zu hit\n", argv[1], SIDE * SIDE, hits);
    hairobb_free(bvh);
    scene_free(&scene);
    free(org);
    free(dir);
    return 0;
}
