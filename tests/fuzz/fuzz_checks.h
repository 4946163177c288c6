/* fuzz_checks.h - what the fuzz targets assert of any BVH they built: a
   traced ray's hit is sane (t finite and in [tnear, tfar], u in [0,1],
   prim_id a segment, occluded1 true wherever intersect1 hits), a miss
   names no segment; and the rays they trace through a BVH's bounds. A
   failure aborts, so libFuzzer reports the input. */
#ifndef HAIROBB_TESTS_FUZZ_CHECKS_H
#define HAIROBB_TESTS_FUZZ_CHECKS_H

#include <math.h>
#include <stdlib.h>

static void fuzz_fail(const char *what)
{
    (void)what;   /* visible in the debugger and the stack trace */
    abort();
}

static void fuzz_check_ray(const hairobb_bvh *bvh, const hairobb_ray *ray, size_t segments)
{
    hairobb_hit hit;
    int hit_any = hairobb_intersect1(bvh, ray, &hit), occluded = hairobb_occluded1(bvh, ray);
    if (hit_any) {
        if (!(hit.t >= ray->tnear && hit.t <= ray->tfar) || !isfinite(hit.t)) fuzz_fail("hit outside [tnear, tfar]");
        if (!(hit.u >= 0.0f && hit.u <= 1.0f)) fuzz_fail("u outside [0,1]");
        if (hit.prim_id >= segments) fuzz_fail("prim_id past the segments");
        if (!occluded) fuzz_fail("intersect1 hits where occluded1 does not");
    } else if (hit.prim_id != HAIROBB_INVALID_ID) {
        fuzz_fail("a miss with a prim_id");
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
