/* fuzz_checks.h - what the fuzz targets assert of any BVH they built: a
   traced ray's hit is sane (t finite and in [tnear, tfar], u in [0,1],
   prim_id a segment, instance_id unset, group 0, occluded1 true
   wherever intersect1 hits), a miss names no segment, instance or group; and the rays they trace
   through a BVH's bounds. A failure aborts, so libFuzzer reports the
   input. */
#ifndef HAIROBB_TESTS_FUZZ_CHECKS_H
#define HAIROBB_TESTS_FUZZ_CHECKS_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static void fuzz_fail(const char *what)
{
    fprintf(stderr, "fuzz check failed: %s\n", what);   /* above libFuzzer's report */
    abort();
}

/* Whether the BVH whose hits a target checks is of tubes (1) or ribbons. */
static int fuzz_round;

/* Ng is a unit vector (HITS), up to rounding, however short the vector
   the library normalised (tests/fuzz/findings/README.md, 1: fixed). */
static int fuzz_unit_normal(const hairobb_ray *ray, const hairobb_hit *hit)
{
    double n = sqrt((double)hit->Ng[0] * hit->Ng[0] + (double)hit->Ng[1] * hit->Ng[1] + (double)hit->Ng[2] * hit->Ng[2]);
    (void)ray;
    return fabs(n - 1.0) <= 1e-5;
}

/* A hit of the ray is sane: t finite and in [tnear, tfar], u in [0,1],
   prim_id below the segment count, instance_id the one expected
   (HAIROBB_INVALID_ID from a BVH's own calls), group_id 0, Ng a unit
   vector. */
static void fuzz_check_hit(const hairobb_ray *ray, const hairobb_hit *hit, size_t segments, uint32_t instance_id)
{
    if (!(hit->t >= ray->tnear && hit->t <= ray->tfar) || !isfinite(hit->t)) fuzz_fail("hit outside [tnear, tfar]");
    if (!(hit->u >= 0.0f && hit->u <= 1.0f)) fuzz_fail("u outside [0,1]");
    if (hit->prim_id >= segments) fuzz_fail("prim_id past the segments");
    if (hit->instance_id != instance_id) fuzz_fail("instance_id not the one the manual says");
    if (hit->group_id != 0) fuzz_fail("group_id not 0 (hairobb_build's BVHs are one group)");
    if (!fuzz_unit_normal(ray, hit)) fuzz_fail("Ng not a unit vector");
}

/* A miss names nothing: prim_id, instance_id and group_id HAIROBB_INVALID_ID. */
static void fuzz_check_miss(const hairobb_hit *hit)
{
    if (hit->prim_id != HAIROBB_INVALID_ID || hit->instance_id != HAIROBB_INVALID_ID || hit->group_id != HAIROBB_INVALID_ID)
        fuzz_fail("a miss with an id");
}

static void fuzz_check_ray(const hairobb_bvh *bvh, const hairobb_ray *ray, size_t segments)
{
    hairobb_hit hit;
    int hit_any = hairobb_intersect1(bvh, ray, &hit), occluded = hairobb_occluded1(bvh, ray);
    if (hit_any) {
        fuzz_check_hit(ray, &hit, segments, HAIROBB_INVALID_ID);
        if (!occluded) fuzz_fail("intersect1 hits where occluded1 does not");
    } else {
        fuzz_check_miss(&hit);
    }
}

/* Fixed ray directions: two along axes, two oblique. */
static const float fuzz_directions[4][3] = {{0, 0, 1}, {1, 0, 0}, {0.6f, -0.8f, 0}, {0.3f, 0.4f, -0.866f}};

/* A ray from each of fuzz_directions through the middle of the bounds, at
   one time, checked. */
static void fuzz_check_rays_through_bounds(const hairobb_bvh *bvh, size_t segments, float time)
{
    float lower[3], upper[3];
    int d, j;
    hairobb_bounds(bvh, lower, upper);
    for (d = 0; d < 4; ++d) {
        hairobb_ray ray;
        for (j = 0; j < 3; ++j) {
            float middle = 0.5f * lower[j] + 0.5f * upper[j], extent = upper[j] - lower[j];
            ray.dir[j] = fuzz_directions[d][j];
            ray.org[j] = middle - fuzz_directions[d][j] * (extent + 1.0f);
        }
        ray.tnear = 0.0f;
        ray.tfar = INFINITY;
        ray.time = time;
        fuzz_check_ray(bvh, &ray, segments);
    }
}

#endif
