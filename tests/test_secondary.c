/* test_secondary.c - secondary rays leaving a hit (shadow and bounce rays):
   hairobb_intersect1_from / hairobb_occluded1_from against the
   double-precision reference with the documented rule (the segment left and
   the segments joined to its ends are skipped within 2 * its largest radius
   / |dir| plus 8 float ulps of the origin; everything else counts from
   tnear = 0). Also: the plain functions do re-hit the ribbon they start on
   (what the rule is for), and hair in contact still shadows, where Embree's
   rule (drop every hit with t <= 2 r / |dir|) loses it.
   Built with -DTESTS_NO_EMBREE (make check), it leaves Embree's count out. */
#define _POSIX_C_SOURCE 200809L
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "check.h"
#ifndef TESTS_NO_EMBREE
#include "embree_wrap.h"
#endif
#include "reference.h"
#include "scenes.h"

#include <float.h>
#include <stdlib.h>
#include <string.h>

typedef struct scene_under_test {
    const hair_scene *s;
    const ref_scene *reference;
    const hairobb_bvh *bvh;
} scene_under_test;

static float largest_radius(const hair_scene *s, uint32_t prim)
{
    const float *cp = s->vertices + 4 * (size_t)s->indices[prim];
    return fmaxf(fmaxf(cp[3], cp[7]), fmaxf(cp[11], cp[15]));
}

/* The segment left, or one whose first control point is at the left one's
   last, or whose last is at its first. */
static int joined(const hair_scene *s, uint32_t left, uint32_t prim)
{
    const float *a = s->vertices + 4 * (size_t)s->indices[left], *b = s->vertices + 4 * (size_t)s->indices[prim];
    return prim == left || (b[0] == a[12] && b[1] == a[13] && b[2] == a[14]) || (b[12] == a[0] && b[13] == a[1] && b[14] == a[2]);
}

/* The band the rule skips, in t: documented in hairobb.h. */
static double skip_band(const hair_scene *s, uint32_t left, const float org[3], const float dir[3])
{
    double magnitude = fmax(fmax(fabs(org[0]), fabs(org[1])), fabs(org[2]));
    double length = sqrt((double)dir[0] * dir[0] + (double)dir[1] * dir[1] + (double)dir[2] * dir[2]);
    return (2.0 * largest_radius(s, left) + magnitude * 8.0 * FLT_EPSILON) / length;
}

/* The reference's nearest hit under the rule: every segment's nearest hit
   from tnear = 0, the skipped ones' from the band on. */
typedef struct nearest {
    const hair_scene *s;
    uint32_t left;
    const float *org, *dir;
    double band;
    int found, near_band;   /* near_band: the answer hangs on the band's edge */
    ref_hit best;
} nearest;

static void keep_nearest(void *user, uint32_t prim, const ref_hit *hit)
{
    nearest *n = (nearest *)user;
    ref_hit h = *hit;
    if (joined(n->s, n->left, prim)) {
        if (fabs(h.t - n->band) <= 1e-3 * n->band) n->near_band = 1;
        if (h.t < n->band && !ref_intersect_segment(n->s->vertices, n->s->indices, prim, n->org, n->dir, n->band, INFINITY, &h))
            return;
        if (fabs(h.t - n->band) <= 1e-3 * n->band) n->near_band = 1;
    }
    if (!n->found || h.t < n->best.t) {
        n->best = h;
        n->best.prim_id = prim;
        n->found = 1;
    }
}

static int reference_from(const scene_under_test *u, uint32_t left, const float org[3], const float dir[3], ref_hit *hit,
                          int *near_band)
{
    nearest n;
    memset(&n, 0, sizeof n);
    n.s = u->s;
    n.left = left;
    n.org = org;
    n.dir = dir;
    n.band = skip_band(u->s, left, org, dir);
    ref_all_hits(u->reference, org, dir, 0.0, INFINITY, keep_nearest, &n);
    *hit = n.best;
    *near_band = n.near_band;
    return n.found;
}

/* Directions a secondary ray takes from a hit: random ones (lights, diffuse
   bounces), back toward the camera, and close to the hair's tangent. */
static void secondary_direction(scene_rng *rng, int kind, const hairobb_ray *primary, const hairobb_hit *hit, float out[3])
{
    int k;
    if (kind == 0) {
        for (k = 0; k < 3; ++k) out[k] = -primary->dir[k];
    } else if (kind == 1) {
        scene_vec3 jitter = scene_random_unit_vector(rng);
        float length = sqrtf(hit->tangent[0] * hit->tangent[0] + hit->tangent[1] * hit->tangent[1] + hit->tangent[2] * hit->tangent[2]);
        out[0] = hit->tangent[0] / length + 0.2f * jitter.x;
        out[1] = hit->tangent[1] / length + 0.2f * jitter.y;
        out[2] = hit->tangent[2] / length + 0.2f * jitter.z;
    } else {
        scene_vec3 d = scene_random_unit_vector(rng);
        out[0] = d.x; out[1] = d.y; out[2] = d.z;
    }
}

static void test_scene(const char *name, hair_scene *s, int side)
{
    scene_under_test u;
    hairobb_bvh *bvh = NULL;
    ref_scene *reference = ref_build(s->vertices, s->vertex_count, s->indices, s->segment_count);
    size_t rays = (size_t)side * side, i, secondary = 0, plain_self = 0, from_self = 0, disagree = 0, occluded_disagree = 0;
    size_t blocked = 0, at_band = 0, aliased_differ = 0;
    float *org = (float *)malloc(3 * sizeof(float) * rays), *dir = (float *)malloc(3 * sizeof(float) * rays);
    scene_rng rng;
    scene_rng_seed(&rng, 99);
    CHECK(hairobb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, NULL, &bvh) == HAIROBB_OK && reference,
          "%s: builds", name);
    if (!bvh || !reference) return;
    u.s = s; u.reference = reference; u.bvh = bvh;
    scene_camera_rays(s, side, side, org, dir);
    for (i = 0; i < rays; ++i) {
        hairobb_ray primary = {{org[3 * i], org[3 * i + 1], org[3 * i + 2]}, 0.0f, {dir[3 * i], dir[3 * i + 1], dir[3 * i + 2]}, INFINITY, 0.0f};
        hairobb_hit hit;
        int kind;
        if (!hairobb_intersect1(bvh, &primary, &hit)) continue;
        for (kind = 0; kind < 4; ++kind) {
            hairobb_ray ray;
            hairobb_hit plain, from;
            ref_hit want;
            int k, expected, got, near_band;
            double band;
            for (k = 0; k < 3; ++k) ray.org[k] = primary.org[k] + hit.t * primary.dir[k];
            secondary_direction(&rng, kind, &primary, &hit, ray.dir);
            ray.tnear = 0.0f;
            ray.tfar = INFINITY;
            band = skip_band(s, hit.prim_id, ray.org, ray.dir);
            ++secondary;
            /* the plain query re-hits the ribbon it starts on */
            if (hairobb_intersect1(bvh, &ray, &plain) && joined(s, hit.prim_id, plain.prim_id) && plain.t < band) ++plain_self;
            got = hairobb_intersect1_from(bvh, &hit, &ray, &from);
            if (got && joined(s, hit.prim_id, from.prim_id) && from.t < band) ++from_self;
            {   /* the output written over `from`, as a path tracer's loop does */
                hairobb_hit aliased = hit;
                int got_aliased = hairobb_intersect1_from(bvh, &aliased, &ray, &aliased);
                aliased_differ += got_aliased != got || (got && memcmp(&aliased, &from, sizeof from) != 0);
            }
            expected = reference_from(&u, hit.prim_id, ray.org, ray.dir, &want, &near_band);
            if (near_band) { ++at_band; continue; }
            blocked += (size_t)expected;
            if (got != expected || (got && fabs(from.t - want.t) > 1e-2 * want.r + 1e-6 * want.t)) {
                if (disagree < 5)
                    printf("  %s: ray %zu kind %d from prim %u: reference %d (prim %u t %.9g), hairobb %d (prim %u t %.9g)\n", name, i,
                           kind, hit.prim_id, expected, want.prim_id, want.t, got, from.prim_id, (double)from.t);
                ++disagree;
            }
            occluded_disagree += hairobb_occluded1_from(bvh, &hit, &ray) != expected;
        }
    }
    printf("%s: %zu secondary rays (%zu blocked by the reference); the plain query re-hits the ribbon it leaves on %zu (%.1f%%), "
           "the _from query on %zu; %zu disagreements with the reference (occluded1_from %zu); %zu on the band's edge left out\n",
           name, secondary, blocked, plain_self, 100.0 * (double)plain_self / (double)secondary, from_self, disagree,
           occluded_disagree, at_band);
    CHECK(secondary > 1000 && plain_self > secondary / 20, "%s: the plain query re-hits the ribbon it leaves (%zu of %zu): the rule matters",
          name, plain_self, secondary);
    CHECK(from_self == 0, "%s: %zu secondary rays re-hit the ribbon they leave", name, from_self);
    CHECK(aliased_differ == 0, "%s: intersect1_from with the hit written over `from` differs on %zu of %zu rays", name,
          aliased_differ, secondary);
    CHECK(disagree == 0 && occluded_disagree == 0, "%s: %zu (occluded %zu) of %zu secondary rays disagree with the reference", name,
          disagree, occluded_disagree, secondary);
    CHECK(at_band <= secondary / 1000, "%s: %zu rays on the band's edge", name, at_band);
    hairobb_free(bvh);
    ref_free(reference);
    free(org);
    free(dir);
}

/* Two parallel strands whose ribbons overlap (axes 1.5 r apart): a ray from
   one toward the other hits it at t < 2 r / |dir|. Hairobb keeps that
   shadow; Embree's rule drops it. */
static void test_contact_shadows(void)
{
    const float r = 0.01f, gap = 1.5f * r;
    float vertices[2 * 16];
    uint32_t indices[2] = {0, 4};
    hairobb_bvh *bvh = NULL;
    int k, i, hairobb_blocked = 0, reference_blocked = 0, n = 200;
    scene_rng rng;
    for (k = 0; k < 4; ++k) {
        float *a = vertices + 4 * k, *b = vertices + 16 + 4 * k;
        a[0] = b[0] = (float)k / 3.0f;
        a[1] = 0.0f; b[1] = gap;
        a[2] = b[2] = 0.0f;
        a[3] = b[3] = r;
    }
    CHECK(hairobb_build(vertices, 8, indices, 2, NULL, &bvh) == HAIROBB_OK, "contact: builds");
#ifndef TESTS_NO_EMBREE
    int embree_blocked = 0;
    emb_scene *embree = emb_build(vertices, 8, indices, 2, EMB_FLAT_BEZIER, 16, 1, NULL, NULL);
    CHECK(embree != NULL, "contact: Embree builds");
#endif
    scene_rng_seed(&rng, 5);
    for (i = 0; bvh && i < n; ++i) {
        /* a camera ray down onto strand A, then a shadow ray toward B */
        hairobb_ray primary = {{0.2f + 0.6f * scene_rng_float(&rng), -0.2f * r, 1.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY, 0.0f};
        hairobb_ray shadow;
        hairobb_hit hit;
        ref_hit want;
        if (!hairobb_intersect1(bvh, &primary, &hit) || hit.prim_id != 0) continue;
        for (k = 0; k < 3; ++k) shadow.org[k] = primary.org[k] + hit.t * primary.dir[k];
        shadow.dir[0] = 0.0f; shadow.dir[1] = 1.0f; shadow.dir[2] = 0.1f * (scene_rng_float(&rng) - 0.5f);
        shadow.tnear = 0.0f;
        shadow.tfar = INFINITY;
        reference_blocked += ref_intersect_segment(vertices, indices, 1, shadow.org, shadow.dir, 0.0, INFINITY, &want);
        hairobb_blocked += hairobb_occluded1_from(bvh, &hit, &shadow);
#ifndef TESTS_NO_EMBREE
        if (embree) embree_blocked += emb_occluded(embree, shadow.org, 0.0f, shadow.dir, INFINITY);
#endif
    }
    printf("contact shadows (axes 1.5 r apart), %d shadow rays toward the other strand: reference %d blocked, hairobb %d\n",
           n, reference_blocked, hairobb_blocked);
#ifndef TESTS_NO_EMBREE
    printf("  the same rays through Embree flat r16 (its rule drops t <= 2 r / |dir|): %d blocked\n", embree_blocked);
    emb_free(embree);
#else
    check_skip("contact shadows through Embree: built without Embree (make check)");
#endif
    CHECK(reference_blocked > n / 2 && hairobb_blocked == reference_blocked, "contact: hairobb %d of %d reference shadows",
          hairobb_blocked, reference_blocked);
    hairobb_free(bvh);
}

int main(void)
{
    hair_scene s;
    const float far[3] = {1e5f, -5e4f, 2.5e4f};
    CHECK(scene_combed(&s, 30000, 3) == 0, "combed scene");
    test_scene("combed 30k", &s, 128);
    scene_transform(&s, far, 1.0f);
    test_scene("combed 30k at 1e5", &s, 128);
    scene_free(&s);
    CHECK(scene_curly(&s, 30000, 4) == 0, "curly scene");
    test_scene("curly 30k", &s, 128);
    scene_free(&s);
    test_contact_shadows();
    return check_summary();
}
