/* ng_not_unit.c - a finding of the fuzzers (README.md here): hit.Ng is not
   a unit vector where the vector the library normalises is so short that
   its squared length is subnormal (below 2^-126): a ribbon hit by a ray
   within about 1e-20 of its tangent, a tube of radius under about 1e-20.
   Build from the repository root:
       cc -std=c99 -I. tests/fuzz/findings/ng_not_unit.c -o ng_not_unit -lm -pthread
   Prints |Ng| - 1 for each case; exits 1 where one is off by more than 1e-5. */
#include <math.h>
#include <stdio.h>
#define HAIROBB_IMPLEMENTATION
#include "hairobb.h"

static int report(const char *what, float value, const hairobb_bvh *bvh, const hairobb_ray *ray)
{
    hairobb_hit hit;
    double off;
    if (!hairobb_intersect1(bvh, ray, &hit)) {
        printf("%s %g: miss\n", what, value);
        return 0;
    }
    off = sqrt((double)hit.Ng[0] * hit.Ng[0] + (double)hit.Ng[1] * hit.Ng[1] + (double)hit.Ng[2] * hit.Ng[2]) - 1.0;
    printf("%s %g: t %g u %g Ng (%.9g %.9g %.9g) |Ng| - 1 = %.3g\n", what, value, hit.t, hit.u, hit.Ng[0], hit.Ng[1], hit.Ng[2], off);
    return fabs(off) > 1e-5;
}

int main(void)
{
    static const float small[] = {1e-3f, 1e-19f, 1e-20f, 1e-21f, 1e-22f};
    uint32_t index = 0;
    int k, bad = 0;
    for (k = 0; k < 5; ++k) {
        /* a straight ribbon along x rising by e, the ray along x into its end */
        float e = small[k], ribbon[16] = {0, 0, 0, 0.1f, 1.0f / 3, 0, 0, 0.1f, 2.0f / 3, 0, 0, 0.1f, 1, 0, 0, 0.1f};
        hairobb_ray ray = {{-1.0f, 0.0f, 0.0f}, 0.0f, {1.0f, 0.0f, 0.0f}, INFINITY, 0.0f};
        hairobb_bvh *bvh = NULL;
        ribbon[5] = e / 3; ribbon[9] = 2 * e / 3; ribbon[13] = e;
        if (hairobb_build(ribbon, 4, &index, 1, NULL, &bvh) != HAIROBB_OK) return 2;
        bad |= report("ribbon, the ray along its tangent within", e, bvh, &ray);
        hairobb_free(bvh);
    }
    for (k = 0; k < 5; ++k) {
        /* a straight tube of radius r along x, a ray down z through it half a radius off its axis */
        float r = small[k], tube[16] = {0, 0, 0, 0, 1.0f / 3, 0, 0, 0, 2.0f / 3, 0, 0, 0, 1, 0, 0, 0};
        hairobb_ray ray = {{0.5f, 0.0f, -1.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY, 0.0f};
        hairobb_build_options options = hairobb_default_options();
        hairobb_bvh *bvh = NULL;
        tube[3] = tube[7] = tube[11] = tube[15] = r;
        ray.org[1] = 0.5f * r;
        options.shape = HAIROBB_SHAPE_ROUND;
        if (hairobb_build(tube, 4, &index, 1, &options, &bvh) != HAIROBB_OK) return 2;
        bad |= report("tube of radius", r, bvh, &ray);
        hairobb_free(bvh);
    }
    return bad;
}
