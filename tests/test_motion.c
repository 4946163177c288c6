/* Motion blur (MOTION BLUR in hairobb.h): a moving fur patch (a rotation
   about each root, and a translation), 2 and 4 time steps, against the
   double reference at random ray times (the segment lerped in double, then
   rounded to the float control points the reference reads); the input's
   errors; time outside [0, 1]; refit and save/load of a moving BVH. */
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "test_data.h"
#include "check.h"
#include "random.h"
#include "reference.h"
#include "ref_bases.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define STRANDS 24
#define SEGS 4
#define NV (STRANDS * STRANDS * SEGS * 4)
#define NS (STRANDS * STRANDS * SEGS)

static uint32_t rng_state = 12345u;
static float rnd(void) { return lcg32_float(&rng_state); }

/* step k of T: strands on a grid, bent; rotate: each strand swept about its root's z axis; else translated along x */
static void make_step(float *v, uint32_t *idx, int k, int T, int rotate)
{
    int sx, sy, s, p, n = 0;
    double tau = T > 1 ? (double)k / (T - 1) : 0.0;
    for (sx = 0; sx < STRANDS; ++sx)
        for (sy = 0; sy < STRANDS; ++sy) {
            double rx = sx * 0.1, ry = sy * 0.1, angle = rotate ? 0.8 * tau : 0.0, shift = rotate ? 0.0 : 0.35 * tau;
            for (s = 0; s < SEGS; ++s) {
                idx[(sx * STRANDS + sy) * SEGS + s] = (uint32_t)n / 4;
                for (p = 0; p < 4; ++p) {
                    double h = (s * 3 + p) / (3.0 * SEGS), lx = 0.3 * h * h, ly = 0.05 * h;
                    double c = cos(angle), sn = sin(angle);
                    v[n++] = (float)(rx + c * lx - sn * ly + shift);
                    v[n++] = (float)(ry + sn * lx + c * ly);
                    v[n++] = (float)(h * 1.5);
                    v[n++] = (float)(0.01 * (1.0 - 0.7 * h) * (1.0 + 0.5 * tau));
                }
            }
        }
}

/* The nearest hit at time: each segment's points (of basis, 4 or 2 of
   them) lerped in double between the steps around time and rounded, as
   the header's surface definition has it; another basis then converted. */
static int ref_trace_basis(hairobb_basis basis, float *const *steps, int T, const uint32_t *idx, const float org[3],
                           const float dir[3], float time, ref_hit *best)
{
    int found = 0, points = basis == HAIROBB_BASIS_LINEAR ? 2 : 4;
    uint32_t i;
    float lerped[16], cp[16];
    static const uint32_t zero[1] = {0};
    for (i = 0; i < NS; ++i) {
        ref_hit h;
        ref_motion_points((const float *const *)steps, T, time, 4 * (size_t)idx[i], 4 * (size_t)points, lerped);
        if (basis == HAIROBB_BASIS_BEZIER) memcpy(cp, lerped, sizeof cp);
        else ref_bezier_from_basis(basis, lerped, NULL, cp);
        if (ref_intersect_segment(cp, zero, 0, org, dir, 0.0, found ? best->t : INFINITY, &h) && (!found || h.t < best->t)) {
            *best = h; best->prim_id = i; found = 1;
        }
    }
    return found;
}

static const char *basis_name(hairobb_basis basis)
{
    return basis == HAIROBB_BASIS_BEZIER ? "Bezier" : basis == HAIROBB_BASIS_BSPLINE ? "B-spline"
         : basis == HAIROBB_BASIS_CATMULL_ROM ? "Catmull-Rom" : "linear";
}

static void accuracy(int T, int rotate, hairobb_basis basis, int spatial)
{
    float *steps[4];
    uint32_t *idx = (uint32_t *)malloc(sizeof(uint32_t) * NS);
    hairobb_build_options o;
    hairobb_bvh *bvh = NULL, *loaded = NULL;
    int k, r, agree = 0, rays = 3000, both = 0;
    double max_err = 0.0;
    for (k = 0; k < T; ++k) { steps[k] = (float *)malloc(sizeof(float) * 4 * NV); make_step(steps[k], idx, k, T, rotate); }
    memset(&o, 0, sizeof o);
    o.time_steps = (unsigned)T;
    o.time_vertices = (const float *const *)steps;
    o.basis = basis;
    o.spatial_splits = spatial ? HAIROBB_ON : HAIROBB_AUTO;
    CHECK(hairobb_build(NULL, NV, idx, NS, &o, &bvh) == HAIROBB_OK, "motion build T=%d %s", T, basis_name(basis));
    if (!bvh) return;
    for (r = 0; r < rays; ++r) {
        hairobb_ray ray;
        hairobb_hit hit;
        ref_hit ref = {0.0, 0.0, 0.0, 0.0, 0};
        int ours, theirs;
        ray.org[0] = 2.6f * rnd() - 0.3f; ray.org[1] = 2.6f * rnd() - 0.3f; ray.org[2] = -3.0f;
        ray.dir[0] = 0.2f * rnd() - 0.1f; ray.dir[1] = 0.2f * rnd() - 0.1f; ray.dir[2] = 1.0f;
        ray.tnear = 0.0f; ray.tfar = INFINITY; ray.time = rnd();
        ours = hairobb_intersect1(bvh, &ray, &hit);
        theirs = ref_trace_basis(basis, steps, T, idx, ray.org, ray.dir, ray.time, &ref);
        if (ours == theirs) ++agree;
        if (ours && theirs) {
            double e = fabs(hit.t - ref.t) / ref.t;
            ++both;
            if (e > max_err) max_err = e;
        }
        CHECK(hairobb_occluded1(bvh, &ray) == ours, "occluded agrees with intersect");
    }
    printf("motion %s T=%d %s%s: %d/%d rays agree with the reference, %d hits, max rel t error %.3g\n",
           rotate ? "rotate" : "translate", T, basis_name(basis), spatial ? " spatial splits" : "", agree, rays, both, max_err);
    CHECK(agree >= rays - rays / 200, "hit/miss agreement %d/%d", agree, rays);
    CHECK(max_err < 1e-4, "t error %g", max_err);
    {   /* save/load: same hits; another T: mismatch; refit to the same steps: same hits */
        size_t size = hairobb_save_size(bvh);
        unsigned char *bytes = (unsigned char *)malloc(size);
        hairobb_build_options lo = o;
        CHECK(hairobb_save(bvh, bytes, size) == HAIROBB_OK, "save");
        CHECK(hairobb_load(bytes, size, NULL, NV, idx, NS, &lo, &loaded) == HAIROBB_OK, "load");
        lo.time_steps = 0;
        { hairobb_bvh *x = NULL; CHECK(hairobb_load(bytes, size, steps[0], NV, idx, NS, &lo, &x) == HAIROBB_ERROR_MISMATCH, "load static over MB"); hairobb_free(x); }
        lo = o;
        steps[T - 1][5] += 0.001f;
        { hairobb_bvh *x = NULL; CHECK(hairobb_load(bytes, size, NULL, NV, idx, NS, &lo, &x) == HAIROBB_ERROR_MISMATCH, "hash covers the last step"); hairobb_free(x); }
        steps[T - 1][5] -= 0.001f;
        CHECK(hairobb_refit_motion(bvh, (const float *const *)steps) == HAIROBB_OK, "refit motion");
        CHECK(hairobb_refit(bvh, steps[0]) == HAIROBB_ERROR_INVALID_ARGUMENT, "static refit of MB bvh");
        for (r = 0; r < 500 && loaded; ++r) {
            hairobb_ray ray;
            hairobb_hit a, b;
            int ha, hb;
            ray.org[0] = 2.6f * rnd() - 0.3f; ray.org[1] = 2.6f * rnd() - 0.3f; ray.org[2] = -3.0f;
            ray.dir[0] = 0.0f; ray.dir[1] = 0.0f; ray.dir[2] = 1.0f;
            ray.tnear = 0.0f; ray.tfar = INFINITY; ray.time = rnd();
            ha = hairobb_intersect1(bvh, &ray, &a);
            hb = hairobb_intersect1(loaded, &ray, &b);
            CHECK(ha == hb && (!ha || (a.t == b.t && a.prim_id == b.prim_id)), "loaded/refitted traces alike");
        }
        free(bytes);
    }
    {   /* times outside [0, 1] and NaN miss */
        hairobb_ray ray = {{1.0f, 1.0f, -3.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY, -0.01f};
        hairobb_hit hit;
        CHECK(!hairobb_intersect1(bvh, &ray, &hit) && hit.prim_id == HAIROBB_INVALID_ID, "time < 0 misses");
        ray.time = 1.01f; CHECK(!hairobb_occluded1(bvh, &ray), "time > 1 misses");
        ray.time = NAN; CHECK(!hairobb_intersect1(bvh, &ray, &hit), "NaN time misses");
    }
    hairobb_free(bvh);
    hairobb_free(loaded);
    for (k = 0; k < T; ++k) free(steps[k]);
    free(idx);
}

static void errors(void)
{
    float *a = (float *)malloc(sizeof(float) * 4 * NV), *b = (float *)malloc(sizeof(float) * 4 * NV);
    uint32_t *idx = (uint32_t *)malloc(sizeof(uint32_t) * NS);
    const float *steps[2];
    hairobb_build_options o;
    hairobb_bvh *bvh = NULL, *s1 = NULL, *s0 = NULL;
    make_step(a, idx, 0, 2, 1);
    make_step(b, idx, 1, 2, 1);
    memset(&o, 0, sizeof o);
    o.time_steps = 2;
    CHECK(hairobb_build(NULL, NV, idx, NS, &o, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT && !bvh, "time_vertices NULL");
    steps[0] = a; steps[1] = NULL; o.time_vertices = steps;
    CHECK(hairobb_build(NULL, NV, idx, NS, &o, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT && !bvh, "NULL step");
    steps[1] = b; b[42] = NAN;
    CHECK(hairobb_build(NULL, NV, idx, NS, &o, &bvh) == HAIROBB_ERROR_INVALID_GEOMETRY && !bvh, "NaN at step 1");
    b[42] = 0.5f; b[43] = -1.0f;
    CHECK(hairobb_build(NULL, NV, idx, NS, &o, &bvh) == HAIROBB_ERROR_INVALID_GEOMETRY && !bvh, "negative radius at step 1");
    make_step(b, idx, 1, 2, 1);
    o.basis = HAIROBB_BASIS_HERMITE;   /* its tangents do not move */
    o.tangents = a;
    CHECK(hairobb_build(NULL, NV, idx, NS, &o, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT && !bvh, "Hermite");
    o.basis = HAIROBB_BASIS_BEZIER;
    o.tangents = NULL;
    CHECK(hairobb_build(NULL, NV, idx, NS, &o, &bvh) == HAIROBB_OK, "good MB build");
    {
        const float *bad[2];
        bad[0] = a; bad[1] = NULL;
        CHECK(hairobb_refit_motion(bvh, bad) == HAIROBB_ERROR_INVALID_ARGUMENT, "refit NULL step");
        b[7] = INFINITY; bad[1] = b;
        CHECK(hairobb_refit_motion(bvh, bad) == HAIROBB_ERROR_INVALID_GEOMETRY, "refit Inf step");
    }
    /* T = 1 and 0: static, the same tree as no motion */
    o.time_steps = 1;
    CHECK(hairobb_build(a, NV, idx, NS, &o, &s1) == HAIROBB_OK, "T=1 build");
    CHECK(hairobb_build(a, NV, idx, NS, NULL, &s0) == HAIROBB_OK, "static build");
    if (s0 && s1) {
        size_t n0 = hairobb_save_size(s0), n1 = hairobb_save_size(s1);
        unsigned char *x = (unsigned char *)malloc(n0), *y = (unsigned char *)malloc(n1);
        hairobb_save(s0, x, n0); hairobb_save(s1, y, n1);
        CHECK(n0 == n1 && memcmp(x, y, n0) == 0, "T=1 saves the static BVH's bytes");
        CHECK(hairobb_refit_motion(s0, steps) == HAIROBB_ERROR_INVALID_ARGUMENT, "refit_motion of a static BVH");
        free(x); free(y);
    }
    hairobb_free(bvh); hairobb_free(s0); hairobb_free(s1);
    free(a); free(b); free(idx);
}

int main(void)
{
    errors();
    accuracy(2, 1, HAIROBB_BASIS_BEZIER, 0);
    accuracy(4, 1, HAIROBB_BASIS_BEZIER, 0);
    accuracy(2, 0, HAIROBB_BASIS_BEZIER, 0);
    accuracy(4, 0, HAIROBB_BASIS_BEZIER, 0);
    /* other bases move too, read without the copy */
    accuracy(2, 1, HAIROBB_BASIS_CATMULL_ROM, 0);
    accuracy(4, 0, HAIROBB_BASIS_BSPLINE, 0);
    accuracy(3, 1, HAIROBB_BASIS_LINEAR, 0);
    accuracy(3, 1, HAIROBB_BASIS_BEZIER, 1);
    accuracy(2, 1, HAIROBB_BASIS_CATMULL_ROM, 1);
    printf("%d passed, %d failed, %d skipped\n", check_passed, check_failed, check_skipped);
    return check_failed != 0;
}
