/* test_accuracy.c - the accuracy bar: on 65,536 primary rays per scene,
   hairobb's hit/miss disagreement with the double-precision reference and its
   p99 of |t - t_ref| / r are each no worse than Embree's flat Bezier curves at
   their default tessellation rate (4), measured here on the same rays.
   Scenes: combed fur, curly, random orientations, straight.hair, furBall_A. */
#define _POSIX_C_SOURCE 200809L
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "check.h"
#include "compare.h"
#include "embree_wrap.h"
#include "reference.h"
#include "scenes.h"

#include <stdlib.h>
#include <string.h>

#define SIDE 256

typedef struct accuracy {
    accuracy_tally tally;      /* against the reference (compare.h) */
    double seconds;
} accuracy;

static void record(accuracy *a, const ref_hit *ref, int ref_hits, int hits, float t, float u, uint32_t prim)
{
    accuracy_tally_add(&a->tally, ref_hits, ref->t, ref->u, ref->prim_id, ref->r, hits, t, u, prim);
}

static void report(const char *scene, const char *who, accuracy *a, accuracy_summary *s)
{
    accuracy_summarize(&a->tally, s);
    printf("%-12s %-16s disagree %6.3f%% (%4zu)  |dt|/r median %.2e p99 %.2e max %.2e  %6.2f Mrays/s\n", scene, who,
           disagreement_percent(s), s->disagreements, s->t_median, s->t_p99, s->t_max, (double)s->rays / a->seconds * 1e-6);
}

static void check_scene(hair_scene *s)
{
    size_t n = (size_t)SIDE * SIDE, i;
    float *org = (float *)malloc(3 * sizeof(float) * n), *dir = (float *)malloc(3 * sizeof(float) * n);
    ref_hit *ref = (ref_hit *)malloc(sizeof(ref_hit) * n);
    int *ref_hits = (int *)malloc(sizeof(int) * n);
    accuracy ours, embree;
    hairobb_bvh *bvh = NULL;
    emb_scene *emb;
    ref_scene *rs;
    accuracy_summary s_ours, s_emb;
    size_t emb_bytes = 0, hit_count = 0;
    double emb_build_seconds = 0.0, t0;

    memset(&ours, 0, sizeof ours);
    memset(&embree, 0, sizeof embree);
    if (accuracy_tally_init(&ours.tally, n) != 0 || accuracy_tally_init(&embree.tally, n) != 0) {
        CHECK(0, "%s: no memory for the errors", s->name);
        return;
    }
    scene_camera_rays(s, SIDE, SIDE, org, dir);

    rs = ref_build(s->vertices, s->vertex_count, s->indices, s->segment_count);
    CHECK(rs != NULL, "%s: reference build", s->name);
    if (!rs) return;
    for (i = 0; i < n; ++i) {
        ref_hits[i] = ref_intersect(rs, org + 3 * i, dir + 3 * i, 0.0, INFINITY, &ref[i]);
        hit_count += (size_t)ref_hits[i];
    }
    ref_free(rs);
    CHECK(hit_count > n / 20, "%s: the reference hits %zu of %zu rays", s->name, hit_count, n);

    CHECK(hairobb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, NULL, &bvh) == HAIROBB_OK,
          "%s: hairobb build", s->name);
    if (!bvh) return;
    t0 = scene_now();
    for (i = 0; i < n; ++i) {
        hairobb_ray ray;
        hairobb_hit hit;
        int hits;
        memcpy(ray.org, org + 3 * i, sizeof ray.org);
        memcpy(ray.dir, dir + 3 * i, sizeof ray.dir);
        ray.tnear = 0.0f;
        ray.tfar = INFINITY;
        hits = hairobb_intersect1(bvh, &ray, &hit);
        record(&ours, &ref[i], ref_hits[i], hits, hit.t, hit.u, hit.prim_id);
    }
    ours.seconds = scene_now() - t0;

    emb = emb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, EMB_FLAT_BEZIER, 4, 1, &emb_bytes, &emb_build_seconds);
    CHECK(emb != NULL, "%s: Embree build", s->name);
    if (!emb) return;
    t0 = scene_now();
    for (i = 0; i < n; ++i) {
        float t = 0.0f, u = 0.0f, v;
        uint32_t prim = 0;
        int hits;
        hits = emb_intersect(emb, org + 3 * i, 0.0f, dir + 3 * i, INFINITY, &t, &u, &v, &prim);
        record(&embree, &ref[i], ref_hits[i], hits, t, u, prim);
    }
    embree.seconds = scene_now() - t0;
    emb_free(emb);

    printf("%-12s %zu segments, %zu of %zu rays hit; hairobb %.1f bytes/segment, Embree %.1f\n", s->name,
           s->segment_count, hit_count, n, (double)hairobb_memory_bytes(bvh) / (double)s->segment_count,
           (double)emb_bytes / (double)s->segment_count);
    report(s->name, "hairobb", &ours, &s_ours);
    report(s->name, "embree flat r4", &embree, &s_emb);
    CHECK(s_ours.disagreements <= s_emb.disagreements, "%s: hairobb disagrees on %zu rays, Embree on %zu", s->name,
          s_ours.disagreements, s_emb.disagreements);
    CHECK(s_ours.t_p99 <= s_emb.t_p99, "%s: hairobb |dt|/r p99 %g, Embree %g", s->name, s_ours.t_p99, s_emb.t_p99);
    CHECK(s_ours.t_compared > n / 20, "%s: %zu hits compared", s->name, s_ours.t_compared);

    hairobb_free(bvh);
    accuracy_tally_free(&ours.tally);
    accuracy_tally_free(&embree.tally);
    free(org);
    free(dir);
    free(ref);
    free(ref_hits);
}

int main(void)
{
    hair_scene s;
    const char *path;
    int r;

    if (scene_combed(&s, 100000, 1) == 0) { check_scene(&s); scene_free(&s); }
    else CHECK(0, "combed scene");
    if (scene_curly(&s, 100000, 2) == 0) { check_scene(&s); scene_free(&s); }
    else CHECK(0, "curly scene");
    if (scene_random(&s, 100000, 3) == 0) { check_scene(&s); scene_free(&s); }
    else CHECK(0, "random scene");
    if ((path = check_data(test_data_straight_hair)) != NULL) {
        r = scene_load_hair(&s, path);
        CHECK(r == 0, "load %s", path);
        if (r == 0) { check_scene(&s); scene_free(&s); }
    }
    if ((path = check_data(test_data_furball)) != NULL) {
        r = scene_load_furball(&s, path);
        CHECK(r == 0, "load %s", path);
        if (r == 0) { check_scene(&s); scene_free(&s); }
    }
    return check_summary();
}
