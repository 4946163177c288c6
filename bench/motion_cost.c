/* motion_cost.c - one motion-blurred build and one pass of primary rays at
   random times, for callgrind: the instructions a ray of the traversal of
   moving hair (docs/benchmarking.md, motion blur). Public API only, so the same file
   measures any version of the header.

     build/motion_cost SEGMENTS MOTION AMOUNT T RES [LAYOUT]
       MOTION 0: each strand rotated AMOUNT rad about its root's normal,
              1: translated by AMOUNT, 2: static (T ignored)
       LAYOUT 0: the default, 1: HAIROBB_OBB_COMPRESSED
     valgrind --tool=callgrind --toggle-collect=hairobb_intersect1_from \
         build/motion_cost 50000 1 0.05 2 64
   Instructions a ray = the Ir callgrind reports / RES^2. Prints the tree's
   node counts, bytes a segment, SAH cost and hits. */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE   /* madvise(MADV_HUGEPAGE), as gnu C and C++ builds have it (HAIROBB_NO_HUGE_PAGES) */
#define HAIROBB_IMPLEMENTATION
#include "hairobb.h"
#include "tests/scenes.h"

int main(int argc, char **argv)
{
    size_t segments = argc > 1 ? (size_t)atol(argv[1]) : 50000, hits = 0;
    int motion = argc > 2 ? atoi(argv[2]) : 0, steps = argc > 4 ? atoi(argv[4]) : 2, res = argc > 5 ? atoi(argv[5]) : 64;
    double amount = argc > 3 ? atof(argv[3]) : 0.5;
    hair_scene s;
    float *step_arrays[16], *org, *dir;
    hairobb_bvh *bvh;
    hairobb_build_options o;
    hairobb_stats stats;
    scene_rng rng;
    int i;
    if ((motion < 2 && (steps < 2 || steps > 16)) || res < 1 || scene_combed(&s, segments, 7) != 0) return 2;
    memset(&o, 0, sizeof o);
    o.threads = 1;
    if (argc > 6 && atoi(argv[6]) == 1) o.obb_layout = HAIROBB_OBB_COMPRESSED;
    if (motion < 2) {
        if (scene_motion_steps(&s, motion ? SCENE_MOTION_TRANSLATE : SCENE_MOTION_ROTATE, amount, steps, step_arrays) != 0) return 2;
        o.time_steps = (unsigned)steps;
        o.time_vertices = (const float *const *)step_arrays;
    }
    if (hairobb_build(motion < 2 ? NULL : s.vertices, s.vertex_count, s.indices, s.segment_count, &o, &bvh) != HAIROBB_OK) return 1;
    hairobb_get_stats(bvh, &stats);
    org = (float *)malloc(3 * sizeof(float) * (size_t)res * (size_t)res);
    dir = (float *)malloc(3 * sizeof(float) * (size_t)res * (size_t)res);
    if (!org || !dir) return 2;
    scene_camera_rays(&s, res, res, org, dir);
    scene_rng_seed(&rng, 99);
    for (i = 0; i < res * res; i++) {
        hairobb_ray ray;
        hairobb_hit hit;
        memset(&ray, 0, sizeof ray);
        memcpy(ray.org, org + 3 * i, sizeof ray.org);
        memcpy(ray.dir, dir + 3 * i, sizeof ray.dir);
        ray.tfar = INFINITY;
        ray.time = (float)(scene_rng_u32(&rng) >> 8) / 16777216.0f;
        hits += (size_t)hairobb_intersect1(bvh, &ray, &hit);
    }
    printf("%zu AABB and %zu OBB nodes, %.1f bytes a segment, SAH cost %.3g, %zu of %d rays hit\n", stats.aabb_nodes,
           stats.obb_nodes, (double)(stats.node_bytes + stats.leaf_bytes) / (double)s.segment_count, stats.sah_cost, hits,
           res * res);
    hairobb_free(bvh);
    if (motion < 2) scene_motion_free(step_arrays, steps);
    scene_free(&s);
    free(org);
    free(dir);
    return 0;
}
