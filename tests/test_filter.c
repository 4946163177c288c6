/* test_filter.c - the any-hit filter (options.hit_filter): a filter that
   ignores every hit on the even strands (8 segments each: a joint may be
   hit on either of its segments) makes hairobb_intersect1 return the
   nearest segment of an odd strand the double-precision reference hits,
   and hairobb_occluded1 tell whether there is one (rays within 1e-4 of a
   ribbon's edge aside); every hit the filter is
   shown is within [tnear, tfar] with sane attributes, on the caller's own
   ray (a renderer keeps its data around it); occluded1 stops at the first
   hit taken; a filter that takes every hit changes nothing. */
#define _POSIX_C_SOURCE 200809L
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "check.h"
#include "reference.h"
#include "scenes.h"

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
    hairobb_free(bvh);
    hairobb_free(plain);
    ref_free(reference);
    scene_free(&s);
    free(org);
    free(dir);
    return check_summary();
}
