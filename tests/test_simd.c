/* test_simd.c - every SIMD path gives the same answers as the plain C path:
   the same rays traced by three builds of hairobb.h (plain C, SSE, AVX),
   compared field by field, bit for bit, on several scenes, node policies and
   intersector precisions. */
#define _POSIX_C_SOURCE 200809L
#include "simd_variant.h"
#include "check.h"
#include "scenes.h"

#include <stdlib.h>
#include <string.h>

#define SIDE 128

static int same_hit(const hairobb_hit *a, const hairobb_hit *b)
{
    if (a->prim_id != b->prim_id) return 0;
    if (a->prim_id == HAIROBB_INVALID_ID) return 1;
    return memcmp(&a->t, &b->t, sizeof a->t) == 0 && memcmp(&a->u, &b->u, sizeof a->u) == 0 &&
           memcmp(&a->v, &b->v, sizeof a->v) == 0 && memcmp(a->Ng, b->Ng, sizeof a->Ng) == 0 &&
           memcmp(a->tangent, b->tangent, sizeof a->tangent) == 0;
}

static void compare_paths(const hair_scene *s, const hairobb_build_options *options, const char *what)
{
    size_t n = (size_t)SIDE * SIDE, i, differ_sse = 0, differ_avx = 0, hits = 0;
    float *org = (float *)malloc(3 * sizeof(float) * n), *dir = (float *)malloc(3 * sizeof(float) * n);
    hairobb_ray *rays = (hairobb_ray *)malloc(sizeof(hairobb_ray) * n);
    hairobb_hit *plain = (hairobb_hit *)malloc(sizeof(hairobb_hit) * n);
    hairobb_hit *other = (hairobb_hit *)malloc(sizeof(hairobb_hit) * n);
    int *occluded_plain = (int *)malloc(sizeof(int) * n), *occluded_other = (int *)malloc(sizeof(int) * n);
    int have_avx = __builtin_cpu_supports("avx2");

    scene_camera_rays(s, SIDE, SIDE, org, dir);
    for (i = 0; i < n; ++i) {
        memcpy(rays[i].org, org + 3 * i, sizeof rays[i].org);
        memcpy(rays[i].dir, dir + 3 * i, sizeof rays[i].dir);
        rays[i].tnear = 0.0f;
        rays[i].tfar = INFINITY;
    }
    CHECK(trace_plain(s->vertices, s->vertex_count, s->indices, s->segment_count, options, rays, n, plain, occluded_plain),
          "%s %s: plain C build", s->name, what);
    for (i = 0; i < n; ++i) hits += plain[i].prim_id != HAIROBB_INVALID_ID;
    CHECK(hits > n / 20, "%s %s: %zu of %zu rays hit", s->name, what, hits, n);

    CHECK(trace_sse(s->vertices, s->vertex_count, s->indices, s->segment_count, options, rays, n, other, occluded_other),
          "%s %s: SSE build", s->name, what);
    for (i = 0; i < n; ++i) differ_sse += !same_hit(&plain[i], &other[i]) || occluded_plain[i] != occluded_other[i];
    CHECK(differ_sse == 0, "%s %s: SSE differs from plain C on %zu of %zu rays", s->name, what, differ_sse, n);

    if (have_avx) {
        CHECK(trace_avx(s->vertices, s->vertex_count, s->indices, s->segment_count, options, rays, n, other, occluded_other),
              "%s %s: AVX build", s->name, what);
        for (i = 0; i < n; ++i) differ_avx += !same_hit(&plain[i], &other[i]) || occluded_plain[i] != occluded_other[i];
        CHECK(differ_avx == 0, "%s %s: AVX differs from plain C on %zu of %zu rays", s->name, what, differ_avx, n);
    }
    printf("%-8s %-22s %5zu hits of %zu rays; SSE differs on %zu, AVX on %s%zu\n", s->name, what, hits, n, differ_sse,
           have_avx ? "" : "(no AVX2 on this CPU, skipped) ", differ_avx);
    free(org); free(dir); free(rays); free(plain); free(other); free(occluded_plain); free(occluded_other);
}

int main(void)
{
    hair_scene scenes[3];
    int k, policy;
    CHECK(scene_combed(&scenes[0], 30000, 11) == 0, "combed");
    CHECK(scene_curly(&scenes[1], 30000, 12) == 0, "curly");
    CHECK(scene_random(&scenes[2], 30000, 13) == 0, "random");
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
        }
        scene_free(&scenes[k]);
    }
    return check_summary();
}
