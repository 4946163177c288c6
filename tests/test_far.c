/* test_far.c - precision far from the origin and across scales: the combed
   scene translated to 1e3, 1e5 and 1e6 and scaled by 1e-4 and 1e4, camera
   rays from a float origin near it, against the double-precision reference
   on the same float inputs. Targets (issue "numerical stability"): hit/miss
   disagreement <= 0.05% at 1e5 and <= 0.1% at 1e6, never a NaN or Inf in a
   hit. Embree's flat curves on the same rays are printed for comparison. */
#define _POSIX_C_SOURCE 200809L
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "check.h"
#include "embree_wrap.h"
#include "reference.h"
#include "scenes.h"

#include <stdlib.h>
#include <string.h>

#define SIDE 256

static void check_placement(float offset, float scale, double max_disagreement_percent)
{
    hair_scene s;
    size_t n = (size_t)SIDE * SIDE, i, disagree = 0, embree_disagree = 0, nonfinite = 0, hits = 0;
    float *org = (float *)malloc(3 * sizeof(float) * n), *dir = (float *)malloc(3 * sizeof(float) * n);
    const float shift[3] = {offset, 0.5f * offset, -0.25f * offset};
    ref_scene *reference;
    hairobb_bvh *bvh = NULL;
    emb_scene *embree;
    double percent;
    CHECK(scene_combed(&s, 100000, 1) == 0, "combed scene");
    scene_transform(&s, shift, scale);
    scene_camera_rays(&s, SIDE, SIDE, org, dir);
    reference = ref_build(s.vertices, s.vertex_count, s.indices, s.segment_count);
    CHECK(hairobb_build(s.vertices, s.vertex_count, s.indices, s.segment_count, NULL, &bvh) == HAIROBB_OK,
          "build at offset %g scale %g", offset, scale);
    embree = emb_build(s.vertices, s.vertex_count, s.indices, s.segment_count, EMB_FLAT_BEZIER, 4, 1, NULL, NULL);
    if (!reference || !bvh || !embree) return;
    for (i = 0; i < n; ++i) {
        hairobb_ray ray;
        hairobb_hit hit;
        ref_hit ref;
        float t, u, v;
        uint32_t prim;
        int want = ref_intersect(reference, org + 3 * i, dir + 3 * i, 0.0, INFINITY, &ref), got;
        memcpy(ray.org, org + 3 * i, sizeof ray.org);
        memcpy(ray.dir, dir + 3 * i, sizeof ray.dir);
        ray.tnear = 0.0f;
        ray.tfar = INFINITY;
        got = hairobb_intersect1(bvh, &ray, &hit);
        hits += (size_t)want;
        disagree += got != want;
        if (got && !(isfinite(hit.t) && isfinite(hit.u) && isfinite(hit.v) && isfinite(hit.Ng[0]) &&
                     isfinite(hit.Ng[1]) && isfinite(hit.Ng[2]) && isfinite(hit.tangent[0])))
            ++nonfinite;
        embree_disagree += emb_intersect(embree, org + 3 * i, 0.0f, dir + 3 * i, INFINITY, &t, &u, &v, &prim) != want;
    }
    percent = 100.0 * (double)disagree / (double)n;
    printf("offset %-7g scale %-7g %5zu reference hits of %zu rays; disagreement hairobb %.3f%% (%zu), Embree flat r4 %.3f%% (%zu)\n",
           offset, scale, hits, n, percent, disagree, 100.0 * (double)embree_disagree / (double)n, embree_disagree);
    CHECK(hits > n / 20, "offset %g scale %g: %zu reference hits", offset, scale, hits);
    CHECK(percent <= max_disagreement_percent, "offset %g scale %g: disagreement %.3f%% > %.3f%%", offset, scale, percent,
          max_disagreement_percent);
    CHECK(nonfinite == 0, "offset %g scale %g: %zu hits with NaN or Inf attributes", offset, scale, nonfinite);
    emb_free(embree);
    hairobb_free(bvh);
    ref_free(reference);
    scene_free(&s);
    free(org);
    free(dir);
}

int main(void)
{
    check_placement(0.0f, 1.0f, 0.05);
    check_placement(1e3f, 1.0f, 0.05);
    check_placement(1e5f, 1.0f, 0.05);
    check_placement(1e6f, 1.0f, 0.1);
    check_placement(0.0f, 1e-4f, 0.05);
    check_placement(0.0f, 1e4f, 0.05);
    return check_summary();
}
