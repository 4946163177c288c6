/* test_round.c - round curves (tubes): the double-precision tube reference
   (ref_tube.h) against Embree's round Bezier curves on the same hair and
   rays. Embree's cubic round curve is the swept circle the reference
   defines, so the two must agree on which rays hit and where, to Embree's
   own accuracy (its Newton iteration stops at a few ulps and gives up on
   some rays). The figures are printed: hit/miss disagreements (Embree's
   misses where the reference hits, its "holes", and the reverse) and
   |t - t_ref| / r. Also: a ray leaving through the tube's far sheet (the
   reference's exit hit) and the near sheet first. ref_tube.h's own checks
   (analytic cylinders and frustums, sampling, normals) are in
   test_reference.c. */
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "embree_wrap.h"
#include "ref_tube.h"
#include "scenes.h"

#include <stdlib.h>
#include <string.h>

#define SIDE 128

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Each segment's box (control points dilated by their largest radius): the
   tube lies inside it. */
typedef struct boxes {
    double *lo, *hi;
} boxes;

static void make_boxes(const hair_scene *s, boxes *b)
{
    size_t i;
    b->lo = (double *)malloc(3 * sizeof(double) * s->segment_count);
    b->hi = (double *)malloc(3 * sizeof(double) * s->segment_count);
    for (i = 0; i < s->segment_count; ++i) {
        const float *p = s->vertices + 4 * (size_t)s->indices[i];
        double r = 0.0;
        int j, k;
        for (j = 0; j < 4; ++j) r = p[4 * j + 3] > r ? p[4 * j + 3] : r;
        for (k = 0; k < 3; ++k) {
            b->lo[3 * i + k] = b->hi[3 * i + k] = p[k];
            for (j = 1; j < 4; ++j) {
                b->lo[3 * i + k] = p[4 * j + k] < b->lo[3 * i + k] ? p[4 * j + k] : b->lo[3 * i + k];
                b->hi[3 * i + k] = p[4 * j + k] > b->hi[3 * i + k] ? p[4 * j + k] : b->hi[3 * i + k];
            }
            b->lo[3 * i + k] -= r * (1.0 + 1e-9) + 1e-12;
            b->hi[3 * i + k] += r * (1.0 + 1e-9) + 1e-12;
        }
    }
}

static int box_hit(const double lo[3], const double hi[3], const double o[3], const double d[3], double tfar)
{
    double t0 = 0.0, t1 = tfar;
    int k;
    for (k = 0; k < 3; ++k) {
        if (d[k] == 0.0) {
            if (o[k] < lo[k] || o[k] > hi[k]) return 0;
            continue;
        }
        {
            double a = (lo[k] - o[k]) / d[k], b = (hi[k] - o[k]) / d[k];
            if (a > b) { double c = a; a = b; b = c; }
            t0 = a > t0 ? a : t0;
            t1 = b < t1 ? b : t1;
        }
    }
    return t0 <= t1 * (1.0 + 1e-9);
}

/* The nearest tube hit over the scene: segments whose box the ray enters,
   each tested by the reference. */
static int nearest(const hair_scene *s, const boxes *b, const float org[3], const float dir[3], ref_tube_hit *best)
{
    ref__ray ray;
    double o[3], d[3];
    size_t i;
    int found = 0, k;
    ref__ray_setup(&ray, org, dir);
    for (k = 0; k < 3; ++k) { o[k] = org[k]; d[k] = dir[k]; }
    for (i = 0; i < s->segment_count; ++i) {
        ref_tube_hit h;
        if (!box_hit(b->lo + 3 * i, b->hi + 3 * i, o, d, found ? best->t : HUGE_VAL)) continue;
        if (!ref_tube_segment_hit(&ray, s->vertices + 4 * (size_t)s->indices[i], 0.0, found ? best->t : INFINITY, &h, NULL, NULL))
            continue;
        if (found && h.t == best->t && (uint32_t)i > best->prim_id) continue;
        *best = h;
        best->prim_id = (uint32_t)i;
        found = 1;
    }
    return found;
}

static void compare_with_embree(const char *name, hair_scene *s)
{
    size_t n = (size_t)SIDE * SIDE, i, both = 0, holes = 0, extra = 0, exits = 0, open_ends = 0;
    float *org = (float *)malloc(3 * sizeof(float) * n), *dir = (float *)malloc(3 * sizeof(float) * n);
    double *error = (double *)malloc(sizeof(double) * n);
    boxes b;
    emb_scene *e = emb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, EMB_ROUND_BEZIER, 0, 0, NULL, NULL);
    CHECK(e != NULL, "%s: Embree builds its round curves", name);
    if (!e || !org || !dir || !error) return;
    make_boxes(s, &b);
    scene_camera_rays(s, SIDE, SIDE, org, dir);
    for (i = 0; i < n; ++i) {
        ref_tube_hit want;
        float t = 0.0f;
        want.prim_id = REF_INVALID_ID;
        int reference = nearest(s, &b, org + 3 * i, dir + 3 * i, &want);
        int embree = emb_intersect(e, org + 3 * i, 0.0f, dir + 3 * i, INFINITY, &t, NULL, NULL, NULL);
        if (reference && embree) error[both++] = fabs((double)t - want.t) / want.r;
        holes += reference && !embree;
        extra += embree && !reference;
        /* camera rays start outside every tube: one meets an exit first
           only where it came in through an open end, at a strand's first
           or last segment */
        if (reference && want.exit) {
            size_t p = want.prim_id;
            int first = p == 0 || memcmp(s->vertices + 4 * (size_t)s->indices[p - 1] + 12, s->vertices + 4 * (size_t)s->indices[p], 12),
                last = p + 1 == s->segment_count ||
                       memcmp(s->vertices + 4 * (size_t)s->indices[p] + 12, s->vertices + 4 * (size_t)s->indices[p + 1], 12);
            exits += !(first || last);
            open_ends += first || last;
        }
    }
    qsort(error, both, sizeof *error, compare_doubles);
    printf("%s: %zu segments, %zu rays; both hit %zu; Embree misses %zu the reference hits, hits %zu it misses; "
           "|dt|/r median %.3g, p99 %.3g, max %.3g\n",
           name, s->segment_count, n, both, holes, extra, both ? error[both / 2] : 0.0,
           both ? error[(size_t)(0.99 * (double)(both - 1))] : 0.0, both ? error[both - 1] : 0.0);
    CHECK(both > n / 20, "%s: %zu rays hit both", name, both);
    /* the same surface: disagreements are Embree's rare misses and edge rays */
    CHECK(holes + extra <= n / 200, "%s: %zu + %zu of %zu rays disagree with Embree on hit or miss", name, holes, extra, n);
    CHECK(both && error[both / 2] <= 1e-4 && error[(size_t)(0.99 * (double)(both - 1))] <= 1e-2,
          "%s: |dt|/r against Embree: median %.3g, p99 %.3g", name, both ? error[both / 2] : 0.0,
          both ? error[(size_t)(0.99 * (double)(both - 1))] : 0.0);
    printf("%s: %zu rays came in through a strand's open end and first met an exit sheet\n", name, open_ends);
    CHECK(exits == 0, "%s: %zu camera rays meet an exit sheet first away from a strand's ends", name, exits);
    emb_free(e);
    free(b.lo);
    free(b.hi);
    free(org);
    free(dir);
    free(error);
}

/* A ray starting on the axis of a curved tube leaves it through one sheet:
   the reference's first hit from there is an exit, and the ray entering
   from outside meets the entry first, then the exit. */
static void test_sheets(void)
{
    static const float ctrl[16] = {0.0f, 0.0f, 0.0f, 0.2f, 0.5f, 0.3f, 0.0f, 0.25f, 1.0f, 0.3f, 0.1f, 0.2f, 1.5f, 0.0f, 0.0f, 0.15f};
    const float org_in[3] = {0.75f, 0.22f, 0.04f}, dir_in[3] = {0.1f, 0.3f, 1.0f};
    const float org_out[3] = {0.75f, 0.22f, -3.0f}, dir_out[3] = {0.0f, 0.0f, 1.0f};
    ref__ray ray;
    ref_tube_hit first, all[REF_TUBE_MAX_ROOTS];
    int count = 0, got;
    ref__ray_setup(&ray, org_in, dir_in);
    got = ref_tube_segment_hit(&ray, ctrl, 0.0, INFINITY, &first, NULL, NULL);
    CHECK(got && first.exit, "sheets: a ray from inside the tube first meets an exit (hit %d, exit %d)", got, got ? first.exit : -1);
    ref__ray_setup(&ray, org_out, dir_out);
    got = ref_tube_segment_hit(&ray, ctrl, 0.0, INFINITY, &first, all, &count);
    CHECK(got && !first.exit && count == 2 && all[0].exit != all[1].exit,
          "sheets: a ray through the tube meets an entry, then an exit (%d hits, first exit %d)", count, got ? first.exit : -1);
}

int main(void)
{
    hair_scene s;
    test_sheets();
    if (scene_combed(&s, 20000, 1) == 0) {
        compare_with_embree("combed", &s);
        scene_free(&s);
    }
    if (scene_curly(&s, 20000, 2) == 0) {
        compare_with_embree("curly", &s);
        scene_free(&s);
    }
    return check_summary();
}
