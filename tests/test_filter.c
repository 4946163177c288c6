/* test_filter.c - the any-hit filters (options.hit_filter and
   occluded_filter, and a call's own through hairobb_context): a filter that
   ignores every hit on the even strands (8 segments each: a joint may be
   hit on either of its segments) makes hairobb_intersect1 return the
   nearest segment of an odd strand the double-precision reference hits,
   and hairobb_occluded1 tell whether there is one (rays within 1e-4 of a
   ribbon's edge aside); every hit the filter is
   shown is within [tnear, tfar] with sane attributes, on the caller's own
   ray (a renderer keeps its data around it); occluded1 stops at the first
   hit taken; a filter that takes every hit changes nothing. A filter
   taking no hit sees each crossing once, at piece boundaries and joints
   too (rays aimed across segments at u = k/8). A per-call filter gives
   what the same filter built in gives, reaches the call's data, and with
   the BVH's own takes the nearest hit both take; an occlusion filter
   leaves intersect1 alone. On tubes a filter taking none is shown the
   crossings stepping intersect1 finds, entry and exit apart however near
   the silhouette. */
#define _POSIX_C_SOURCE 200809L
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "check.h"
#include "reference.h"
#include "scenes.h"
#include "test_data.h"

#include <stdlib.h>
#include <string.h>

/* The renderer's ray: hairobb's first, its own data after it. */
typedef struct traced_ray {
    hairobb_ray ray;
    size_t shown, taken, insane;
    int odd_only;
} traced_ray;

static int odd_strand(uint32_t prim) { return (prim / 8u) & 1u; }

static int filter(void *user, const hairobb_ray *ray, const hairobb_hit *hit)
{
    traced_ray *traced = (traced_ray *)(void *)ray;   /* the caller's ray, as documented */
    int take = !traced->odd_only || odd_strand(hit->prim_id);
    ++*(size_t *)user;
    ++traced->shown;
    if (!(hit->t >= ray->tnear && hit->t <= ray->tfar && hit->u >= 0.0f && hit->u <= 1.0f && hit->v >= -1.0f && hit->v <= 1.0f &&
          fabsf(hit->Ng[0] * hit->Ng[0] + hit->Ng[1] * hit->Ng[1] + hit->Ng[2] * hit->Ng[2] - 1.0f) < 1e-4f))
        ++traced->insane;
    traced->taken += (size_t)take;
    return take;
}

typedef struct nearest_odd {
    int found;
    ref_hit best;
} nearest_odd;

static void keep_nearest_odd(void *user, uint32_t prim, const ref_hit *hit)
{
    nearest_odd *n = (nearest_odd *)user;
    if (odd_strand(prim) && (!n->found || hit->t < n->best.t)) {
        n->best = *hit;
        n->best.prim_id = prim;
        n->found = 1;
    }
}

/* Every candidate a filter is shown, for the crossing-once check. */
#define MAX_SHOWN 256
typedef struct shown_list {
    size_t count;
    uint32_t prim[MAX_SHOWN];
    float u[MAX_SHOWN], t[MAX_SHOWN];
} shown_list;

static int record_all(void *user, const hairobb_ray *ray, const hairobb_hit *hit)
{
    shown_list *list = (shown_list *)user;
    (void)ray;
    if (list->count < MAX_SHOWN) {
        list->prim[list->count] = hit->prim_id;
        list->u[list->count] = hit->u;
        list->t[list->count] = hit->t;
        ++list->count;
    }
    return 0;   /* transparent: the ray goes on, as a transmittance product's does */
}

/* Two candidates that are one crossing: on one segment at the same u and
   t, or at a strand's joint on the two segments that meet there. */
static int same_crossing(const hair_scene *s, const shown_list *l, size_t a, size_t b, float dir_length)
{
    uint32_t pa = l->prim[a], pb = l->prim[b];
    const float *ca = s->vertices + 4 * (size_t)s->indices[pa], *cb = s->vertices + 4 * (size_t)s->indices[pb];
    float r = ca[3] > ca[15] ? ca[3] : ca[15], close = 1e-3f * r / dir_length;
    if (fabsf(l->t[a] - l->t[b]) > close) return 0;
    if (pa == pb) return fabsf(l->u[a] - l->u[b]) <= 1e-3f;
    if (pb + 1 == pa) {   /* b first */
        uint32_t swap = pa;
        const float *c = ca;
        pa = pb; pb = swap; ca = cb; cb = c;
        return pa + 1 == pb && !memcmp(ca + 12, cb, 12) && l->u[b] >= 1.0f - 1e-3f && l->u[a] <= 1e-3f;
    }
    return pa + 1 == pb && !memcmp(ca + 12, cb, 12) && l->u[a] >= 1.0f - 1e-3f && l->u[b] <= 1e-3f;
}

/* A filter that takes no hit sees every crossing of the ray once: at a
   piece boundary inside a segment (rays aimed across the centre line at u
   = k/8) and at a joint (aimed at the joint point), as everywhere else. */
static void test_each_crossing_once(const char *name, const hair_scene *s, const float *org, const float *dir, size_t camera_rays)
{
    size_t aimed = 4 * s->segment_count < 40000 ? 4 * s->segment_count : 40000, rays = camera_rays + aimed, i, twice = 0, shown = 0;
    hairobb_build_options options;
    hairobb_bvh *bvh = NULL;
    shown_list list;
    uint64_t state = 99;
    memset(&options, 0, sizeof options);
    options.hit_filter = record_all;
    options.hit_filter_user = &list;
    CHECK(hairobb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, &options, &bvh) == HAIROBB_OK, "%s: builds", name);
    if (!bvh) return;
    for (i = 0; i < rays; ++i) {
        hairobb_ray ray;
        hairobb_hit hit;
        size_t a, b;
        float length;
        if (i < camera_rays) {
            memcpy(ray.org, org + 3 * i, sizeof ray.org);
            memcpy(ray.dir, dir + 3 * i, sizeof ray.dir);
        } else {
            /* at P(k/8) of a segment, across its tangent there */
            size_t prim;
            double u, w, b0, b1, b2, b3, d0, d1, d2, d3, P[3], T[3], side[3], tt = 0.0, along = 0.0;
            const float *cp;
            int k;
            lcg64_next(&state);
            prim = (size_t)(state >> 33) % s->segment_count;
            u = (double)((state >> 20) % 9) / 8.0;
            cp = s->vertices + 4 * (size_t)s->indices[prim];
            w = 1.0 - u;
            b0 = w * w * w; b1 = 3 * u * w * w; b2 = 3 * u * u * w; b3 = u * u * u;
            d0 = -3 * w * w; d1 = 3 * w * w - 6 * u * w; d2 = 6 * u * w - 3 * u * u; d3 = 3 * u * u;
            for (k = 0; k < 3; ++k) {
                P[k] = b0 * cp[k] + b1 * cp[4 + k] + b2 * cp[8 + k] + b3 * cp[12 + k];
                T[k] = d0 * cp[k] + d1 * cp[4 + k] + d2 * cp[8 + k] + d3 * cp[12 + k];
                side[k] = (double)((state >> (8 + 8 * k)) & 255u) / 255.0 - 0.5;
                tt += T[k] * T[k];
            }
            for (k = 0; k < 3; ++k) along += side[k] * T[k];
            for (k = 0; k < 3; ++k) {
                side[k] -= along * T[k] / (tt > 0.0 ? tt : 1.0);   /* across the tangent */
                ray.org[k] = (float)(P[k] + 4.0 * side[k]);
                ray.dir[k] = (float)(-side[k]);
            }
        }
        ray.tnear = 0.0f;
        ray.tfar = INFINITY;
        ray.time = 0.0f;
        list.count = 0;
        hairobb_intersect1(bvh, &ray, &hit);
        shown += list.count;
        length = sqrtf(ray.dir[0] * ray.dir[0] + ray.dir[1] * ray.dir[1] + ray.dir[2] * ray.dir[2]);
        for (a = 0; a < list.count; ++a)
            for (b = a + 1; b < list.count; ++b)
                if (same_crossing(s, &list, a, b, length)) {
                    if (getenv("FILTER_VERBOSE"))
                        printf("  %s ray %zu: prim %u u %.9g t %.9g and prim %u u %.9g t %.9g\n", name, i, list.prim[a], (double)list.u[a],
                               (double)list.t[a], list.prim[b], (double)list.u[b], (double)list.t[b]);
                    ++twice;
                }
    }
    printf("%s: %zu rays (%zu aimed across a segment at u = k/8), %zu candidates shown to a filter taking none; %zu crossings shown twice\n",
           name, rays, aimed, shown, twice);
    CHECK(shown > rays / 4, "%s: %zu candidates shown", name, shown);
    CHECK(twice == 0, "%s: the filter saw %zu crossings twice", name, twice);
    hairobb_free(bvh);
}

/* Per-call filters (hairobb_context): the call's data reaches the filter,
   which runs after the BVH's own and counts only where both take a hit. */
typedef struct call_data {
    size_t shown;
    int skip_even;
} call_data;

static int call_filter(void *user, const hairobb_ray *ray, const hairobb_hit *hit)
{
    call_data *data = (call_data *)user;
    (void)ray;
    ++data->shown;
    return !data->skip_even || odd_strand(hit->prim_id);
}

static int third_strands_out(void *user, const hairobb_ray *ray, const hairobb_hit *hit)
{
    (void)user; (void)ray;
    return (hit->prim_id / 8u) % 3u != 0u;
}

static int take_none(void *user, const hairobb_ray *ray, const hairobb_hit *hit)
{
    (void)ray; (void)hit;
    ++*(size_t *)user;
    return 0;
}

typedef struct nearest_both {
    int found;
    ref_hit best;
} nearest_both;

static void keep_nearest_both(void *user, uint32_t prim, const ref_hit *hit)
{
    nearest_both *n = (nearest_both *)user;
    if (odd_strand(prim) && (prim / 8u) % 3u != 0u && (!n->found || hit->t < n->best.t)) {
        n->best = *hit;
        n->best.prim_id = prim;
        n->found = 1;
    }
}

static void test_context(const hair_scene *s, const ref_scene *reference, const float *org, const float *dir, size_t rays,
                         const hairobb_bvh *with_build_filter)
{
    hairobb_build_options options;
    hairobb_bvh *plain = NULL, *third = NULL, *split = NULL;
    size_t i, differ = 0, occluded_differ = 0, both_disagree = 0, both_hits = 0, edge = 0, unseen = 0, split_wrong = 0, none_calls = 0;
    memset(&options, 0, sizeof options);
    CHECK(hairobb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, &options, &plain) == HAIROBB_OK, "context: build");
    options.hit_filter = third_strands_out;
    CHECK(hairobb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, &options, &third) == HAIROBB_OK,
          "context: build with a filter");
    options.hit_filter = NULL;
    options.occluded_filter = take_none;
    options.occluded_filter_user = &none_calls;
    CHECK(hairobb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, &options, &split) == HAIROBB_OK,
          "context: build with an occlusion filter");
    if (!plain || !third || !split) return;
    for (i = 0; i < rays; ++i) {
        traced_ray traced;
        hairobb_ray ray;
        hairobb_hit a, b;
        call_data data = {0, 1};
        hairobb_context context;
        nearest_both want;
        int ga, gb;
        memset(&traced, 0, sizeof traced);
        memcpy(traced.ray.org, org + 3 * i, sizeof traced.ray.org);
        memcpy(traced.ray.dir, dir + 3 * i, sizeof traced.ray.dir);
        traced.ray.tfar = INFINITY;
        traced.odd_only = 1;
        ray = traced.ray;
        context.filter = call_filter;
        context.user = &data;
        /* the call's filter on a plain BVH: as the same filter built in */
        ga = hairobb_intersect1(with_build_filter, &traced.ray, &a);
        gb = hairobb_intersect1_context(plain, &context, NULL, &ray, &b);
        differ += ga != gb || (ga && (a.prim_id != b.prim_id || a.t != b.t));
        occluded_differ += hairobb_occluded1(with_build_filter, &traced.ray) != hairobb_occluded1_context(plain, &context, NULL, &ray);
        unseen += gb && data.shown == 0;
        /* both filters: the nearest hit both take */
        memset(&want, 0, sizeof want);
        ref_all_hits(reference, ray.org, ray.dir, 0.0, INFINITY, keep_nearest_both, &want);
        gb = hairobb_intersect1_context(third, &context, NULL, &ray, &b);
        if ((want.found && fabs(want.best.v) > 1.0 - 1e-4) || (gb && fabsf(b.v) > 1.0f - 1e-4f)) {
            ++edge;
        } else {
            both_hits += (size_t)want.found;
            both_disagree += gb != want.found || (gb && (b.prim_id / 8u != want.best.prim_id / 8u || fabs(b.t - want.best.t) > 1e-2 * want.best.r));
            both_disagree += hairobb_occluded1_context(third, &context, NULL, &ray) != want.found;
        }
        /* a separate occlusion filter: intersect1 untouched, occluded1 through it */
        ga = hairobb_intersect1(plain, &ray, &a);
        gb = hairobb_intersect1(split, &ray, &b);
        split_wrong += ga != gb || (ga && (a.prim_id != b.prim_id || a.t != b.t)) || hairobb_occluded1(split, &ray) != 0;
    }
    printf("context: %zu rays; a per-call filter against the same filter built in: %zu differ (occluded1 %zu), %zu hits it never saw; "
           "with the BVH's filter as well: %zu of %zu nearest hits both take disagree with the reference (%zu at an edge); "
           "an occlusion-only filter taking none: %zu wrong, %zu calls\n",
           rays, differ, occluded_differ, unseen, both_disagree, both_hits, edge, split_wrong, none_calls);
    CHECK(differ == 0 && occluded_differ == 0 && unseen == 0, "context: %zu (%zu) differ from the built-in filter, %zu unseen", differ,
          occluded_differ, unseen);
    CHECK(both_disagree == 0 && both_hits > rays / 20 && edge <= rays / 1000, "context: %zu disagree with both filters (%zu hits, %zu edge)",
          both_disagree, both_hits, edge);
    CHECK(split_wrong == 0 && none_calls > rays / 10, "context: the occlusion filter: %zu wrong, %zu calls", split_wrong, none_calls);
    hairobb_free(plain);
    hairobb_free(third);
    hairobb_free(split);
}

/* A tube's entry and exit are two crossings however close: a filter that
   takes none is shown what stepping intersect1 past each hit finds (tnear
   just past it), the same count at the same t, the BVH's own filter and a
   per-call one alike. Rays along y past a straight tube along x at
   z = r (1 - 10^-k) (chords down to 0.0045 r), and shadow rays between
   random points of a scene's box, its hair as tubes. */
static size_t stepped_crossings(const hairobb_bvh *bvh, hairobb_ray ray, float *t, size_t capacity)
{
    size_t n = 0;
    hairobb_hit hit;
    while (n < capacity && hairobb_intersect1(bvh, &ray, &hit)) {
        t[n++] = hit.t;
        ray.tnear = nextafterf(hit.t, INFINITY);
    }
    return n;
}

static int compare_floats(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return x < y ? -1 : x > y;
}

static void tube_crossings(const char *name, const float *vertices, size_t vertex_count, const uint32_t *indices, size_t segments,
                           const float (*org)[3], const float (*dir)[3], size_t rays)
{
    hairobb_build_options o = hairobb_default_options();
    hairobb_bvh *filtered = NULL, *plain = NULL;
    shown_list list;
    hairobb_context context;
    size_t i, k, differ = 0, crossings = 0;
    int call;
    o.shape = HAIROBB_SHAPE_ROUND;
    CHECK(hairobb_build(vertices, vertex_count, indices, segments, &o, &plain) == HAIROBB_OK, "%s: builds", name);
    o.hit_filter = record_all;
    o.hit_filter_user = &list;
    CHECK(hairobb_build(vertices, vertex_count, indices, segments, &o, &filtered) == HAIROBB_OK, "%s: builds with a filter", name);
    if (!plain || !filtered) return;
    context.filter = record_all;
    context.user = &list;
    context.mask = 0;
    for (i = 0; i < rays; ++i) {
        hairobb_ray ray;
        hairobb_hit hit;
        float stepped[MAX_SHOWN];
        size_t n;
        memcpy(ray.org, org[i], sizeof ray.org);
        memcpy(ray.dir, dir[i], sizeof ray.dir);
        ray.tnear = 0.0f;
        ray.tfar = 1.0f;   /* a shadow ray's segment */
        ray.time = 0.0f;
        n = stepped_crossings(plain, ray, stepped, MAX_SHOWN);
        crossings += n;
        for (call = 0; call < 2; ++call) {
            int bad;
            list.count = 0;
            if (call == 0) hairobb_intersect1(filtered, &ray, &hit);
            else hairobb_intersect1_context(plain, &context, NULL, &ray, &hit);
            if (list.count == MAX_SHOWN || n == MAX_SHOWN) continue;   /* too many to compare */
            qsort(list.t, list.count, sizeof list.t[0], compare_floats);
            bad = list.count != n;
            for (k = 0; !bad && k < n; ++k) bad = list.t[k] != stepped[k];
            if (bad && differ < 3)
                printf("  %s ray %zu (%s filter): shown %zu crossings, stepping finds %zu (first t %.9g)\n", name, i,
                       call ? "per-call" : "the BVH's", list.count, n, n ? (double)stepped[0] : 0.0);
            differ += (size_t)bad;
        }
    }
    printf("%s as tubes: %zu rays, %zu crossings stepping intersect1; a filter taking none (the BVH's, per call) is shown "
           "other crossings on %zu\n", name, rays, crossings, differ);
    CHECK(differ == 0 && crossings > rays / 2, "%s tubes: the filter is shown other crossings than stepping finds on %zu rays (%zu crossings)",
          name, differ, crossings);
    hairobb_free(filtered);
    hairobb_free(plain);
}

static void test_tube_crossings(const hair_scene *s)
{
    enum { GRAZING = 700, RANDOM = 4000 };
    static const float tube[16] = {-1, 0, 0, 0.1f, 0, 0, 0, 0.1f, 1, 0, 0, 0.1f, 2, 0, 0, 0.1f};
    static const uint32_t one[1] = {0};
    static float org[RANDOM][3], dir[RANDOM][3];
    uint64_t state = 31;
    size_t i;
    int k;
    for (i = 0; i < GRAZING; ++i) {
        double eps = pow(10.0, -1.0 - 6.0 * (double)i / GRAZING);
        org[i][0] = (float)(-0.5 + 2.0 * lcg64_double(&state));
        org[i][1] = -1.0f;
        org[i][2] = (float)(0.1 * (1.0 - eps)) * (i & 1 ? 1.0f : -1.0f);
        dir[i][0] = 0.0f;
        dir[i][1] = 2.0f;
        dir[i][2] = 0.0f;
    }
    tube_crossings("a straight tube grazed at r (1 - 10^-k)", tube, 4, one, 1, (const float (*)[3])org, (const float (*)[3])dir, GRAZING);
    /* shadow rays: from a point in the hair's box to another */
    for (i = 0; i < RANDOM; ++i)
        for (k = 0; k < 3; ++k) {
            float a = s->lower[k] + (s->upper[k] - s->lower[k]) * (float)lcg64_double(&state);
            float b = s->lower[k] + (s->upper[k] - s->lower[k]) * (float)lcg64_double(&state);
            org[i][k] = a;
            dir[i][k] = b - a;
        }
    tube_crossings(s->name, s->vertices, s->vertex_count, s->indices, s->segment_count, (const float (*)[3])org,
                   (const float (*)[3])dir, RANDOM);
}

int main(void)
{
    hair_scene s;
    size_t side = 128, rays = side * side, i, calls = 0, disagree = 0, occluded_disagree = 0, insane = 0, hits = 0;
    size_t plain_differs = 0, occluded_extra = 0, edge = 0;
    float *org = (float *)malloc(12 * rays), *dir = (float *)malloc(12 * rays);
    hairobb_build_options options;
    hairobb_bvh *bvh = NULL, *plain = NULL;
    ref_scene *reference;
    CHECK(scene_combed(&s, 50000, 8) == 0, "combed scene");
    reference = ref_build(s.vertices, s.vertex_count, s.indices, s.segment_count);
    memset(&options, 0, sizeof options);
    CHECK(hairobb_build(s.vertices, s.vertex_count, s.indices, s.segment_count, &options, &plain) == HAIROBB_OK, "build");
    options.hit_filter = filter;
    options.hit_filter_user = &calls;
    CHECK(hairobb_build(s.vertices, s.vertex_count, s.indices, s.segment_count, &options, &bvh) == HAIROBB_OK,
          "build with a filter");
    if (!bvh || !plain || !reference) return check_summary();
    scene_camera_rays(&s, (int)side, (int)side, org, dir);
    for (i = 0; i < rays; ++i) {
        traced_ray traced;
        hairobb_hit hit, plain_hit;
        nearest_odd want;
        int got, occluded, plain_got;
        memset(&traced, 0, sizeof traced);
        memcpy(traced.ray.org, org + 3 * i, sizeof traced.ray.org);
        memcpy(traced.ray.dir, dir + 3 * i, sizeof traced.ray.dir);
        traced.ray.tfar = INFINITY;
        memset(&want, 0, sizeof want);
        ref_all_hits(reference, traced.ray.org, traced.ray.dir, 0.0, INFINITY, keep_nearest_odd, &want);

        traced.odd_only = 1;
        got = hairobb_intersect1(bvh, &traced.ray, &hit);
        if ((want.found && fabs(want.best.v) > 1.0 - 1e-4) || (got && fabsf(hit.v) > 1.0f - 1e-4f)) {
            ++edge;
            continue;
        }
        hits += (size_t)want.found;
        /* at a joint either segment of the strand may be named */
        if (got != want.found ||
            (got && (hit.prim_id / 8u != want.best.prim_id / 8u || fabs(hit.t - want.best.t) > 1e-2 * want.best.r))) {
            if (getenv("FILTER_VERBOSE"))
                printf("  ray %zu: reference %d prim %u t %.9g v %.6f | hairobb %d prim %u t %.9g v %.6f\n", i, want.found,
                       want.best.prim_id, want.best.t, want.best.v, got, hit.prim_id, (double)hit.t, (double)hit.v);
            ++disagree;
        }
        traced.taken = 0;
        occluded = hairobb_occluded1(bvh, &traced.ray);
        occluded_disagree += occluded != want.found;
        occluded_extra += traced.taken > 1;   /* it must stop at the first hit taken */
        insane += traced.insane;

        /* a filter that takes everything: the plain answer */
        traced.odd_only = 0;
        got = hairobb_intersect1(bvh, &traced.ray, &hit);
        plain_got = hairobb_intersect1(plain, &traced.ray, &plain_hit);
        plain_differs += got != plain_got || (got && (hit.t != plain_hit.t || hit.prim_id != plain_hit.prim_id));
    }
    printf("combed 50k, %zu rays, %zu with an odd strand hit: filter ignoring even strands: %zu disagreements with the reference, "
           "occluded1 %zu (%zu went past a hit taken), %zu at an edge left out, %zu filter calls, %zu insane hits shown; "
           "a filter taking all: %zu differ\n",
           rays, hits, disagree, occluded_disagree, occluded_extra, edge, calls, insane, plain_differs);
    CHECK(edge <= rays / 1000, "%zu rays at an edge", edge);
    CHECK(hits > rays / 10, "%zu odd hits", hits);
    CHECK(disagree == 0 && occluded_disagree == 0, "%zu (occluded %zu) disagreements", disagree, occluded_disagree);
    CHECK(occluded_extra == 0 && insane == 0, "%zu occluded rays went on, %zu insane hits", occluded_extra, insane);
    CHECK(calls > hits, "the filter was called (%zu)", calls);
    CHECK(plain_differs == 0, "a filter taking every hit changed %zu rays", plain_differs);
    test_each_crossing_once("combed 50k", &s, org, dir, rays);
    test_tube_crossings(&s);
    test_context(&s, reference, org, dir, rays, bvh);
    hairobb_free(bvh);
    hairobb_free(plain);
    ref_free(reference);
    scene_free(&s);
    {
        const char *path = check_data(test_data_straight_hair);
        if (path) {
            CHECK(scene_load_hair(&s, path) == 0, "load %s", path);
            scene_camera_rays(&s, (int)side, (int)side, org, dir);
            test_each_crossing_once("straight.hair", &s, org, dir, rays);
            test_tube_crossings(&s);
            scene_free(&s);
        }
    }
    free(org);
    free(dir);
    return check_summary();
}
