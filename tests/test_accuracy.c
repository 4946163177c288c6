/* test_accuracy.c - the accuracy bar: on 65,536 primary rays per scene,
   hairobb's hit/miss disagreement with the double-precision reference and its
   p99 of |t - t_ref| / r are each no worse than Embree's flat Bezier curves at
   their default tessellation rate (4), measured here on the same rays.
   Scenes: combed fur, curly, random orientations, straight.hair, furBall_A. */
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

typedef struct accuracy {
    size_t rays, disagreements, compared;
    double *relative_errors;   /* |t - t_ref| / r_ref where both hit */
    double seconds;
} accuracy;

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double percentile(double *sorted, size_t n, double p)
{
    size_t i;
    if (n == 0) return 0.0;
    i = (size_t)(p * (double)(n - 1) + 0.5);
    return sorted[i];
}

static void record(accuracy *a, const ref_hit *ref, int ref_hits, int hits, float t)
{
    if (ref_hits != hits) a->disagreements++;
    else if (hits && ref->r > 0.0) a->relative_errors[a->compared++] = fabs((double)t - ref->t) / ref->r;
}

static void report(const char *scene, const char *who, accuracy *a, double *median, double *p99)
{
    qsort(a->relative_errors, a->compared, sizeof(double), compare_doubles);
    *median = percentile(a->relative_errors, a->compared, 0.5);
    *p99 = percentile(a->relative_errors, a->compared, 0.99);
    printf("%-12s %-16s disagree %6.3f%% (%4zu)  |dt|/r median %.2e p99 %.2e max %.2e  %6.2f Mrays/s\n", scene, who,
           100.0 * (double)a->disagreements / (double)a->rays, a->disagreements, *median, *p99,
           percentile(a->relative_errors, a->compared, 1.0), (double)a->rays / a->seconds * 1e-6);
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
    size_t emb_bytes = 0, hit_count = 0;
    double emb_build_seconds = 0.0, t0, m_ours, p_ours, m_emb, p_emb;

    memset(&ours, 0, sizeof ours);
    memset(&embree, 0, sizeof embree);
    ours.rays = embree.rays = n;
    ours.relative_errors = (double *)malloc(sizeof(double) * n);
    embree.relative_errors = (double *)malloc(sizeof(double) * n);
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
        record(&ours, &ref[i], ref_hits[i], hits, hit.t);
    }
    ours.seconds = scene_now() - t0;

    emb = emb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, EMB_FLAT_BEZIER, 4, 1, &emb_bytes, &emb_build_seconds);
    CHECK(emb != NULL, "%s: Embree build", s->name);
    if (!emb) return;
    t0 = scene_now();
    for (i = 0; i < n; ++i) {
        float t = 0.0f, u, v;
        uint32_t prim;
        int hits;
        hits = emb_intersect(emb, org + 3 * i, 0.0f, dir + 3 * i, INFINITY, &t, &u, &v, &prim);
        record(&embree, &ref[i], ref_hits[i], hits, t);
    }
    embree.seconds = scene_now() - t0;
    emb_free(emb);

    printf("%-12s %zu segments, %zu of %zu rays hit; hairobb %.1f bytes/segment, Embree %.1f\n", s->name,
           s->segment_count, hit_count, n, (double)hairobb_memory_bytes(bvh) / (double)s->segment_count,
           (double)emb_bytes / (double)s->segment_count);
    report(s->name, "hairobb", &ours, &m_ours, &p_ours);
    report(s->name, "embree flat r4", &embree, &m_emb, &p_emb);
    CHECK(ours.disagreements <= embree.disagreements, "%s: hairobb disagrees on %zu rays, Embree on %zu", s->name,
          ours.disagreements, embree.disagreements);
    CHECK(p_ours <= p_emb, "%s: hairobb |dt|/r p99 %g, Embree %g", s->name, p_ours, p_emb);
    CHECK(ours.compared > n / 20, "%s: %zu hits compared", s->name, ours.compared);

    hairobb_free(bvh);
    free(ours.relative_errors);
    free(embree.relative_errors);
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
