/*
 * test_reference.c - self-test of the reference intersector (reference.h).
 *
 * Analytic cases (straight, curved, tapered, degenerate segments, interval
 * inclusivity), an independent dense-sampling cross-check of the root
 * finder, and BVH-vs-brute-force equality on random scenes near the origin
 * and translated to 1e5. Prints one line per check, then "N passed, M failed, 0 skipped".
 */
#include "check.h"
#include "random.h"
#include "reference.h"
#include "ref_tube.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* One line per check: "PASS name", or "FAIL name : detail". */
static void check(int ok, const char *name, const char *detail)
{
    check_report(ok, "%s%s%s", name, (!ok && detail) ? " : " : "", (!ok && detail) ? detail : "");
}

static int near_abs(double a, double b, double tol)
{
    return fabs(a - b) <= tol;
}

/* ------------------------------------------------------------------------ */
/* Single-segment helpers                                                   */
/* ------------------------------------------------------------------------ */

typedef struct single {
    float vertices[16];
    uint32_t index;
} single;

static void single_set(single *s, int i, double x, double y, double z, double r)
{
    s->vertices[4 * i + 0] = (float)x;
    s->vertices[4 * i + 1] = (float)y;
    s->vertices[4 * i + 2] = (float)z;
    s->vertices[4 * i + 3] = (float)r;
}

static int single_hit(const single *s, double ox, double oy, double oz, double dx, double dy, double dz,
                      double tnear, double tfar, ref_hit *hit)
{
    float org[3], dir[3];
    org[0] = (float)ox; org[1] = (float)oy; org[2] = (float)oz;
    dir[0] = (float)dx; dir[1] = (float)dy; dir[2] = (float)dz;
    hit->t = hit->u = hit->v = hit->r = -12345.0;
    return ref_intersect_segment(s->vertices, &s->index, 0, org, dir, tnear, tfar, hit);
}

/* Same ray through a one-segment BVH scene: must agree with the direct call. */
static int single_scene_hit(const single *s, double ox, double oy, double oz, double dx, double dy, double dz,
                            double tnear, double tfar, ref_hit *hit)
{
    float org[3], dir[3];
    int result;
    ref_scene *scene = ref_build(s->vertices, 4, &s->index, 1);
    org[0] = (float)ox; org[1] = (float)oy; org[2] = (float)oz;
    dir[0] = (float)dx; dir[1] = (float)dy; dir[2] = (float)dz;
    if (!scene)
        return -1;
    result = ref_intersect(scene, org, dir, tnear, tfar, hit);
    ref_free(scene);
    return result;
}

static char g_detail[512];

static const char *describe(int result, const ref_hit *h)
{
    snprintf(g_detail, sizeof g_detail, "returned %d, t=%.17g u=%.17g v=%.17g r=%.17g", result, h->t, h->u, h->v,
             h->r);
    return g_detail;
}

/* ------------------------------------------------------------------------ */
/* Analytic checks                                                          */
/* ------------------------------------------------------------------------ */

/* Straight segment along x at z = 5: P(u) = (-1.5 + 3u, 0, 5), r = 0.1.
 * Control points are exact floats so u is exactly linear in x. */
static void test_straight(void)
{
    single s;
    ref_hit h;
    int res;
    const double r = (double)0.1f;
    s.index = 0;
    single_set(&s, 0, -1.5, 0, 5, 0.1);
    single_set(&s, 1, -0.5, 0, 5, 0.1);
    single_set(&s, 2, 0.5, 0, 5, 0.1);
    single_set(&s, 3, 1.5, 0, 5, 0.1);

    res = single_hit(&s, 0, 0, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 1 && h.t == 5.0 && near_abs(h.u, 0.5, 1e-14) && near_abs(h.v, 0, 1e-14) && h.r == r,
          "straight: centre hit t=5 u=0.5 v=0 r=0.1", describe(res, &h));

    res = single_hit(&s, 0, 0, 0, 0, 0, 2, 0, HUGE_VAL, &h);
    check(res == 1 && h.t == 2.5, "straight: t scales with 1/|dir| (|dir|=2 -> t=2.5)", describe(res, &h));

    res = single_hit(&s, 0, 0.5 * r, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 1 && h.t == 5.0 && near_abs(h.v, 0.5, 1e-7), "straight: offset +0.5r -> v=+0.5",
          describe(res, &h));

    res = single_hit(&s, 0, -0.5 * r, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 1 && near_abs(h.v, -0.5, 1e-7), "straight: offset -0.5r -> v=-0.5", describe(res, &h));

    res = single_hit(&s, 0.375, 0.5 * r, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 1 && near_abs(h.u, 0.625, 1e-14) && near_abs(h.v, 0.5, 1e-7),
          "straight: sideways x=0.375 -> u=0.625, v=+0.5", describe(res, &h));

    res = single_hit(&s, 0, 0.5 * r, 10, 0, 0, -1, 0, HUGE_VAL, &h);
    check(res == 1 && h.t == 5.0 && near_abs(h.v, -0.5, 1e-7), "straight: viewed from behind, v flips to -0.5",
          describe(res, &h));

    res = single_hit(&s, 0, 0.999 * r, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 1 && near_abs(h.v, 0.999, 1e-6), "straight: offset 0.999r hits, v~0.999", describe(res, &h));

    res = single_hit(&s, 0, 1.001 * r, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 0, "straight: offset 1.001r misses", describe(res, &h));
    res = single_hit(&s, 0, -1.001 * r, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 0, "straight: offset -1.001r misses", describe(res, &h));

    /* Oblique ray through the centre line at u = 0.75, point (0.75, 0, 5) = 5 * dir. */
    res = single_hit(&s, 0, 0, 0, 0.15, 0, 1, 0, HUGE_VAL, &h);
    check(res == 1 && near_abs(h.t, 5.0, 1e-6) && near_abs(h.u, 0.75, 1e-6) && near_abs(h.v, 0, 1e-6),
          "straight: oblique ray through centre line -> t=5 u=0.75", describe(res, &h));

    res = single_scene_hit(&s, 0.375, 0.5 * r, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 1 && h.prim_id == 0 && near_abs(h.u, 0.625, 1e-14) && near_abs(h.v, 0.5, 1e-7),
          "straight: same through a one-segment scene", describe(res, &h));
}

static void test_interval(void)
{
    single s;
    ref_hit h;
    int res, scene_res;
    s.index = 0;
    single_set(&s, 0, -1.5, 0, 5, 0.1);
    single_set(&s, 1, -0.5, 0, 5, 0.1);
    single_set(&s, 2, 0.5, 0, 5, 0.1);
    single_set(&s, 3, 1.5, 0, 5, 0.1);

    res = single_hit(&s, 0, 0, 0, 0, 0, 1, 5.0, HUGE_VAL, &h);
    scene_res = single_scene_hit(&s, 0, 0, 0, 0, 0, 1, 5.0, HUGE_VAL, &h);
    check(res == 1 && scene_res == 1 && h.t == 5.0, "interval: tnear == t is inclusive", describe(res, &h));
    res = single_hit(&s, 0, 0, 0, 0, 0, 1, 0.0, 5.0, &h);
    scene_res = single_scene_hit(&s, 0, 0, 0, 0, 0, 1, 0.0, 5.0, &h);
    check(res == 1 && scene_res == 1, "interval: tfar == t is inclusive", describe(res, &h));
    res = single_hit(&s, 0, 0, 0, 0, 0, 1, 5.0, 5.0, &h);
    scene_res = single_scene_hit(&s, 0, 0, 0, 0, 0, 1, 5.0, 5.0, &h);
    check(res == 1 && scene_res == 1, "interval: tnear == tfar == t hits", describe(res, &h));
    res = single_hit(&s, 0, 0, 0, 0, 0, 1, 0.0, nextafter(5.0, 0.0), &h);
    scene_res = single_scene_hit(&s, 0, 0, 0, 0, 0, 1, 0.0, nextafter(5.0, 0.0), &h);
    check(res == 0 && scene_res == 0, "interval: tfar one ulp below t excludes", describe(res, &h));
    res = single_hit(&s, 0, 0, 0, 0, 0, 1, nextafter(5.0, 10.0), HUGE_VAL, &h);
    scene_res = single_scene_hit(&s, 0, 0, 0, 0, 0, 1, nextafter(5.0, 10.0), HUGE_VAL, &h);
    check(res == 0 && scene_res == 0, "interval: tnear one ulp above t excludes", describe(res, &h));
    res = single_hit(&s, 0, 0, 10, 0, 0, 1, 0.0, HUGE_VAL, &h);
    check(res == 0, "interval: segment behind the origin is excluded for tnear=0", describe(res, &h));
    res = single_hit(&s, 0, 0, 10, 0, 0, 1, -HUGE_VAL, HUGE_VAL, &h);
    check(res == 1 && h.t == -5.0, "interval: ...and found at t=-5 for tnear=-inf", describe(res, &h));
}

/* Segment from x=0 to x=3: rays at the exact ends give roots at u=0 / u=1
 * exactly; just outside there is no root (a flat ribbon has no end caps). */
static void test_endpoints(void)
{
    single s;
    ref_hit h;
    int res;
    s.index = 0;
    single_set(&s, 0, 0, 0, 5, 0.5);
    single_set(&s, 1, 1, 0, 5, 0.5);
    single_set(&s, 2, 2, 0, 5, 0.5);
    single_set(&s, 3, 3, 0, 5, 0.5);
    res = single_hit(&s, 0, 0.1, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 1 && h.u == 0.0 && h.t == 5.0, "endpoints: root exactly at u=0", describe(res, &h));
    res = single_hit(&s, 3, 0.1, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 1 && h.u == 1.0 && h.t == 5.0, "endpoints: root exactly at u=1", describe(res, &h));
    res = single_hit(&s, -0.01, 0, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 0, "endpoints: just before u=0 misses (no end cap)", describe(res, &h));
    res = single_hit(&s, 3.01, 0, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 0, "endpoints: just after u=1 misses (no end cap)", describe(res, &h));
}

static double arch_z(double u)
{
    double w = 1.0 - u;
    return 3 * u * w * w * 1.0 + 3 * u * u * w * 3.0 + u * u * u * 4.0;
}

/* Arch in the y=0 plane: x(u) = -1 + 6u - 6u^2 crosses x=0 at
 * u = (3 -+ sqrt 3)/6 and peaks at x(0.5) = 0.5; z increases with u.
 * A ray along z in that plane meets the centre line twice. */
static void test_curved(void)
{
    single s;
    ref_hit h;
    int res;
    const double r = (double)0.1f;
    const double u1 = (3.0 - sqrt(3.0)) / 6.0, u2 = (3.0 + sqrt(3.0)) / 6.0;
    const double t1 = arch_z(u1) + 10.0, t2 = arch_z(u2) + 10.0;
    s.index = 0;
    single_set(&s, 0, -1, 0, 0, 0.1);
    single_set(&s, 1, 1, 0, 1, 0.1);
    single_set(&s, 2, 1, 0, 3, 0.1);
    single_set(&s, 3, -1, 0, 4, 0.1);

    res = single_hit(&s, 0, 0.5 * r, -10, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 1 && near_abs(h.u, u1, 1e-13) && near_abs(h.t, t1, 1e-12) && near_abs(h.v, 0.5, 1e-7),
          "curved: two crossings, nearest returned (u1, v=+0.5)", describe(res, &h));
    res = single_hit(&s, 0, 0.5 * r, -10, 0, 0, 1, t1 + 1e-6, HUGE_VAL, &h);
    check(res == 1 && near_abs(h.u, u2, 1e-13) && near_abs(h.t, t2, 1e-12) && near_abs(h.v, -0.5, 1e-7),
          "curved: tnear past the first gives the second (u2, v=-0.5), not the rejected peak", describe(res, &h));
    res = single_hit(&s, 0, 0.5 * r, 14, 0, 0, -1, 0, HUGE_VAL, &h);
    check(res == 1 && near_abs(h.u, u2, 1e-13) && near_abs(h.t, 14.0 - arch_z(u2), 1e-12) &&
              near_abs(h.v, 0.5, 1e-7),
          "curved: reversed ray returns the other crossing first", describe(res, &h));

    /* Radius 0.6 > 0.5: the peak root (local max of |P2|) is a hit too. */
    single_set(&s, 0, -1, 0, 0, 0.6);
    single_set(&s, 1, 1, 0, 1, 0.6);
    single_set(&s, 2, 1, 0, 3, 0.6);
    single_set(&s, 3, -1, 0, 4, 0.6);
    res = single_hit(&s, 0, 0, -10, 0, 0, 1, t1 + 1e-6, HUGE_VAL, &h);
    check(res == 1 && near_abs(h.u, 0.5, 1e-13) && near_abs(h.t, arch_z(0.5) + 10.0, 1e-12),
          "curved: local maximum of |P2| within r counts (u=0.5)", describe(res, &h));
}

/* r(u) = 0.1 + 0.2u along P(u) = (-1.5 + 3u, 0, 5). */
static void test_taper(void)
{
    single s;
    ref_hit h;
    int res;
    s.index = 0;
    single_set(&s, 0, -1.5, 0, 5, 0.1);
    single_set(&s, 1, -0.5, 0, 5, 0.1 + 0.2 / 3.0);
    single_set(&s, 2, 0.5, 0, 5, 0.1 + 0.4 / 3.0);
    single_set(&s, 3, 1.5, 0, 5, 0.3);
    res = single_hit(&s, 0.75, 0.24, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 1 && near_abs(h.u, 0.75, 1e-14) && near_abs(h.r, 0.25, 1e-7) &&
              near_abs(h.v, (double)0.24f / h.r, 1e-12),
          "taper: u=0.75 r=0.25, offset 0.24 hits with v=0.24/r", describe(res, &h));
    res = single_hit(&s, 0.75, 0.26, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 0, "taper: offset 0.26 at u=0.75 misses", describe(res, &h));
    res = single_hit(&s, -0.75, -0.14, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 1 && near_abs(h.r, 0.15, 1e-7) && near_abs(h.v, -(double)0.14f / h.r, 1e-12),
          "taper: u=0.25 r=0.15, offset -0.14 hits with v=-0.14/r", describe(res, &h));
    res = single_hit(&s, -0.75, 0.2, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 0, "taper: offset 0.2 at u=0.25 misses (would hit at u=0.75)", describe(res, &h));
}

static void test_degenerate(void)
{
    single s;
    ref_hit h;
    int res, i;
    s.index = 0;

    for (i = 0; i < 4; ++i)
        single_set(&s, i, 1, 2, 3, 0.5);
    res = single_hit(&s, 1.2, 2, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 1 && h.u == 0.0 && h.t == 3.0, "degenerate: zero-length segment (f==0: u=0 tested)",
          describe(res, &h));
    res = single_hit(&s, 1.6, 2, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 0, "degenerate: zero-length segment, ray outside r misses", describe(res, &h));

    for (i = 0; i < 4; ++i)
        single_set(&s, i, 0, 0, 1 + i, 0.2);
    res = single_hit(&s, 0, 0, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 1 && h.t == 1.0 && h.v == 0.0, "degenerate: segment along the ray (u=0, v=0)",
          describe(res, &h));

    single_set(&s, 0, -1.5, 0, 5, 0);
    single_set(&s, 1, -0.5, 0, 5, 0);
    single_set(&s, 2, 0.5, 0, 5, 0);
    single_set(&s, 3, 1.5, 0, 5, 0);
    res = single_hit(&s, 0, 0, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 0 || (res == 1 && h.v == 0.0), "degenerate: zero radius does not crash, v=0 if hit",
          describe(res, &h));
    res = single_hit(&s, 0, 1e-3, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 0, "degenerate: zero radius, offset ray misses", describe(res, &h));

    single_set(&s, 0, -1.5, 0, 5, -0.1);
    single_set(&s, 1, -0.5, 0, 5, -0.1);
    single_set(&s, 2, 0.5, 0, 5, -0.1);
    single_set(&s, 3, 1.5, 0, 5, -0.1);
    res = single_hit(&s, 0, 0, 0, 0, 0, 1, 0, HUGE_VAL, &h);
    check(res == 0, "degenerate: negative radius never hits", describe(res, &h));

    single_set(&s, 0, -1.5, 0, 5, 0.1);
    single_set(&s, 1, -0.5, 0, 5, 0.1);
    single_set(&s, 2, 0.5, 0, 5, 0.1);
    single_set(&s, 3, 1.5, 0, 5, 0.1);
    res = single_hit(&s, 0, 0, 0, 0, 0, 0, -HUGE_VAL, HUGE_VAL, &h);
    check(res == 0, "degenerate: zero direction never hits", describe(res, &h));
    res = single_scene_hit(&s, 0, 0, 0, 0, 0, 0, -HUGE_VAL, HUGE_VAL, &h);
    check(res == 0 && h.prim_id == REF_INVALID_ID, "degenerate: zero direction through a scene misses",
          describe(res, &h));

    {
        float org[3] = {0, 0, 0}, dir[3] = {0, 0, 1};
        ref_scene *empty = ref_build(s.vertices, 0, &s.index, 0);
        int ok = empty != NULL;
        if (empty) {
            ok = ok && ref_intersect(empty, org, dir, 0, HUGE_VAL, &h) == 0 && h.prim_id == REF_INVALID_ID;
            ok = ok && ref_all_hits(empty, org, dir, 0, HUGE_VAL, NULL, NULL) == 0;
            ref_free(empty);
        }
        check(ok, "degenerate: empty scene builds and misses", NULL);
    }
    {
        /* Second segment's index is out of range: dropped, never hit. */
        uint32_t idx[2] = {0, 1};
        float org[3] = {0, 0, 0}, dir[3] = {0, 0, 1};
        ref_scene *scene = ref_build(s.vertices, 4, idx, 2);
        int ok = scene != NULL;
        if (scene) {
            ok = ok && ref_intersect(scene, org, dir, 0, HUGE_VAL, &h) == 1 && h.prim_id == 0;
            ok = ok && ref_all_hits(scene, org, dir, 0, HUGE_VAL, NULL, NULL) == 1;
            ref_free(scene);
        }
        check(ok, "degenerate: out-of-range segment index is ignored", NULL);
    }
}

/* ------------------------------------------------------------------------ */
/* Independent cross-check of the root finder by dense sampling              */
/* ------------------------------------------------------------------------ */

static uint64_t g_rng = 0x9e3779b97f4a7c15ull;

static double rnd(void) { return xorshift64_double(&g_rng); } /* [0,1) */

static double rnd_range(double lo, double hi)
{
    return lo + (hi - lo) * rnd();
}

typedef struct sample_eval {
    double f, dist2, r, t;
} sample_eval;

/* Straight from the definition with explicit Bernstein basis functions and
 * 3D perpendicular components (no ray frame), to be independent of the
 * header's evaluation path. */
static sample_eval sample_at(const float *ctrl, const double org[3], const double dir[3], double u)
{
    double w = 1.0 - u;
    double b[4], db[4];
    double p[3], dp[3], len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    double dhat[3], pz, dpz, pp[3], dpp[3];
    int i, k;
    sample_eval e;
    b[0] = w * w * w; b[1] = 3 * u * w * w; b[2] = 3 * u * u * w; b[3] = u * u * u;
    db[0] = -3 * w * w; db[1] = 3 * w * w - 6 * u * w; db[2] = 6 * u * w - 3 * u * u; db[3] = 3 * u * u;
    e.r = 0;
    for (k = 0; k < 3; ++k) {
        p[k] = dp[k] = 0;
        dhat[k] = dir[k] / len;
    }
    for (i = 0; i < 4; ++i) {
        for (k = 0; k < 3; ++k) {
            p[k] += b[i] * ((double)ctrl[4 * i + k] - org[k]);
            dp[k] += db[i] * (double)ctrl[4 * i + k];
        }
        e.r += b[i] * (double)ctrl[4 * i + 3];
    }
    pz = p[0] * dhat[0] + p[1] * dhat[1] + p[2] * dhat[2];
    dpz = dp[0] * dhat[0] + dp[1] * dhat[1] + dp[2] * dhat[2];
    for (k = 0; k < 3; ++k) {
        pp[k] = p[k] - pz * dhat[k];
        dpp[k] = dp[k] - dpz * dhat[k];
    }
    e.f = pp[0] * dpp[0] + pp[1] * dpp[1] + pp[2] * dpp[2];
    e.dist2 = pp[0] * pp[0] + pp[1] * pp[1] + pp[2] * pp[2];
    e.t = pz / len;
    return e;
}

/* Wiggly segments with several roots of f; sample f densely, bisect each sign
 * change, and compare the nearest accepted root to the reference's. Cases
 * where some root sits within 1e-6 of the radius boundary are skipped. */
static void test_sampling_cross_check(void)
{
    const int cases = 3000, samples = 4000;
    int c, compared = 0, hits = 0, mismatches = 0, multi_root_cases = 0;
    char detail[256] = "";
    for (c = 0; c < cases; ++c) {
        float ctrl[16], org_f[3], dir_f[3];
        double org[3], dir[3];
        uint32_t index = 0;
        int i, k, ambiguous = 0, sample_found = 0, ref_res, roots = 0;
        double best_t = HUGE_VAL, prev_f = 0;
        ref_hit h;
        for (i = 0; i < 4; ++i) {
            for (k = 0; k < 3; ++k)
                ctrl[4 * i + k] = (float)rnd_range(-1, 1);
            ctrl[4 * i + 3] = (float)rnd_range(0.05, 0.6);
        }
        for (k = 0; k < 3; ++k) {
            org_f[k] = (float)rnd_range(-3, 3);
            dir_f[k] = (float)rnd_range(-0.3, 0.3) - org_f[k] / 3.0f; /* roughly towards the segment */
            org[k] = org_f[k];
            dir[k] = dir_f[k];
        }
        for (i = 0; i <= samples; ++i) {
            double u = (double)i / samples;
            sample_eval e = sample_at(ctrl, org, dir, u);
            double root = -1;
            if (e.f == 0)
                root = u;
            else if (i > 0 && ((prev_f < 0) != (e.f < 0)) && prev_f != 0) {
                double lo = (double)(i - 1) / samples, hi = u;
                int it;
                for (it = 0; it < 60; ++it) {
                    double m = 0.5 * (lo + hi);
                    double fm = sample_at(ctrl, org, dir, m).f;
                    if ((fm < 0) == (prev_f < 0))
                        lo = m;
                    else
                        hi = m;
                }
                root = 0.5 * (lo + hi);
            }
            prev_f = e.f;
            if (root >= 0) {
                sample_eval er = sample_at(ctrl, org, dir, root);
                double dist = sqrt(er.dist2);
                ++roots;
                if (fabs(dist - er.r) < 1e-6)
                    ambiguous = 1;
                if (dist <= er.r && er.t >= 0 && er.t < best_t) {
                    best_t = er.t;
                    sample_found = 1;
                }
            }
        }
        if (ambiguous)
            continue;
        if (roots >= 3)
            ++multi_root_cases;
        ++compared;
        ref_res = ref_intersect_segment(ctrl, &index, 0, org_f, dir_f, 0, HUGE_VAL, &h);
        if (ref_res != sample_found || (ref_res && fabs(h.t - best_t) > 1e-9 * (1 + fabs(best_t)))) {
            if (!mismatches)
                snprintf(detail, sizeof detail, "case %d: ref %d t=%.17g, sampled %d t=%.17g", c, ref_res,
                         ref_res ? h.t : 0.0, sample_found, best_t);
            ++mismatches;
        }
        hits += ref_res;
    }
    printf("  (sampling: %d compared, %d hits, %d with >=3 roots)\n", compared, hits, multi_root_cases);
    check(mismatches == 0 && compared > cases / 2 && hits > compared / 10 && multi_root_cases > 50,
          "sampling: root finder agrees with dense sampling on wiggly segments", detail);
}

/* ------------------------------------------------------------------------ */
/* Random scenes: BVH vs brute force                                        */
/* ------------------------------------------------------------------------ */

typedef struct scene_data {
    float *vertices;
    uint32_t *indices;
    size_t vertex_count, segment_count;
} scene_data;

/* Strands of segments sharing end points (Embree bezier layout: segment j of
 * a strand starts at vertex 3j), random walks inside [0,10]^3. */
static scene_data make_scene(size_t strands, size_t segs_per_strand, double offset)
{
    scene_data d;
    size_t s, j, v = 0, seg = 0, verts_per_strand = 3 * segs_per_strand + 1;
    d.vertex_count = strands * verts_per_strand;
    d.segment_count = strands * segs_per_strand;
    d.vertices = (float *)malloc(4 * d.vertex_count * sizeof(float));
    d.indices = (uint32_t *)malloc(d.segment_count * sizeof(uint32_t));
    for (s = 0; s < strands; ++s) {
        double p[3];
        int k;
        for (k = 0; k < 3; ++k)
            p[k] = rnd_range(0, 10);
        for (j = 0; j < verts_per_strand; ++j, ++v) {
            for (k = 0; k < 3; ++k) {
                p[k] += rnd_range(-0.3, 0.3);
                d.vertices[4 * v + k] = (float)(p[k] + offset);
            }
            d.vertices[4 * v + 3] = (float)rnd_range(0.02, 0.15);
        }
        for (j = 0; j < segs_per_strand; ++j)
            d.indices[seg++] = (uint32_t)(s * verts_per_strand + 3 * j);
    }
    return d;
}

static void free_scene(scene_data *d)
{
    free(d->vertices);
    free(d->indices);
}

typedef struct ray_data {
    float org[3], dir[3];
    double tnear, tfar;
} ray_data;

/* Rays aimed at random points near random segments so many of them hit;
 * some with zero direction components, various [tnear, tfar]. */
static ray_data make_ray(const scene_data *d, double offset, int kind)
{
    ray_data ray;
    uint32_t prim = (uint32_t)(rnd() * (double)d->segment_count);
    const float *ctrl = d->vertices + 4 * (size_t)d->indices[prim];
    double u = rnd(), w = 1 - u, target[3], origin[3];
    int k;
    for (k = 0; k < 3; ++k) {
        target[k] = w * w * w * ctrl[k] + 3 * u * w * w * ctrl[4 + k] + 3 * u * u * w * ctrl[8 + k] +
                    u * u * u * ctrl[12 + k] + rnd_range(-0.15, 0.15);
        origin[k] = offset + rnd_range(-5, 15);
    }
    if (kind % 7 == 3)
        origin[kind % 3] = target[kind % 3]; /* one zero direction component */
    if (kind % 11 == 5) {
        origin[0] = target[0];
        origin[1] = target[1]; /* axis-aligned along z */
    }
    for (k = 0; k < 3; ++k) {
        ray.org[k] = (float)origin[k];
        ray.dir[k] = (float)((target[k] - origin[k]) * (kind % 2 ? 0.37 : 1.0)); /* non-unit lengths */
        if (kind % 7 == 3 && k == kind % 3)
            ray.dir[k] = 0.0f;
        if (kind % 11 == 5 && k < 2)
            ray.dir[k] = 0.0f;
    }
    switch (kind % 4) {
    case 0: ray.tnear = 0; ray.tfar = HUGE_VAL; break;
    case 1: ray.tnear = 0.5; ray.tfar = HUGE_VAL; break;
    case 2: ray.tnear = 0; ray.tfar = rnd_range(0.5, 3.0); break;
    default: ray.tnear = -HUGE_VAL; ray.tfar = HUGE_VAL; break;
    }
    return ray;
}

static int brute_nearest(const scene_data *d, const ray_data *ray, ref_hit *best)
{
    size_t i;
    int found = 0;
    for (i = 0; i < d->segment_count; ++i) {
        ref_hit h;
        if (ref_intersect_segment(d->vertices, d->indices, (uint32_t)i, ray->org, ray->dir, ray->tnear, ray->tfar,
                                  &h) &&
            (!found || h.t < best->t)) {
            *best = h;
            found = 1;
        }
    }
    return found;
}

/* Every hit satisfies the definition, checked in world space: the ray point
 * X is within r of C = P(u), and X - C is perpendicular to the tangent. */
static int hit_is_consistent(const scene_data *d, const ray_data *ray, const ref_hit *h)
{
    const float *ctrl = d->vertices + 4 * (size_t)d->indices[h->prim_id];
    double org[3], dir[3];
    sample_eval e;
    int k;
    for (k = 0; k < 3; ++k) {
        org[k] = ray->org[k];
        dir[k] = ray->dir[k];
    }
    e = sample_at(ctrl, org, dir, h->u);
    return sqrt(e.dist2) <= e.r * (1 + 1e-9) + 1e-12 && fabs(e.t - h->t) <= 1e-9 * (1 + fabs(h->t)) &&
           fabs(e.r - h->r) <= 1e-9 && fabs(h->v) <= 1 + 1e-9;
}

static void compare_nearest(const char *label, double offset)
{
    const int rays = 2000;
    scene_data d = make_scene(100, 20, offset);
    ref_scene *scene = ref_build(d.vertices, d.vertex_count, d.indices, d.segment_count);
    int i, hits = 0, mismatches = 0, inconsistent = 0;
    char name[128], detail[256] = "";
    if (!scene) {
        snprintf(name, sizeof name, "%s: ref_build", label);
        check(0, name, "returned NULL");
        free_scene(&d);
        return;
    }
    for (i = 0; i < rays; ++i) {
        ray_data ray = make_ray(&d, offset, i);
        ref_hit brute, fast;
        int brute_res;
        memset(&brute, 0, sizeof brute);
        brute_res = brute_nearest(&d, &ray, &brute);
        int fast_res = ref_intersect(scene, ray.org, ray.dir, ray.tnear, ray.tfar, &fast);
        if (brute_res != fast_res ||
            (brute_res && (brute.prim_id != fast.prim_id || brute.t != fast.t || brute.u != fast.u ||
                           brute.v != fast.v || brute.r != fast.r)) ||
            (!fast_res && fast.prim_id != REF_INVALID_ID)) {
            if (!mismatches)
                snprintf(detail, sizeof detail, "ray %d: brute %d prim %u t=%.17g, bvh %d prim %u t=%.17g", i,
                         brute_res, (unsigned)brute.prim_id, brute_res ? brute.t : 0.0, fast_res,
                         (unsigned)fast.prim_id, fast_res ? fast.t : 0.0);
            ++mismatches;
        }
        if (fast_res) {
            ++hits;
            inconsistent += !hit_is_consistent(&d, &ray, &fast);
        }
    }
    printf("  (%s: %d of %d rays hit)\n", label, hits, rays);
    snprintf(name, sizeof name, "%s: ref_intersect == brute force (prim, t, u, v, r)", label);
    check(mismatches == 0 && hits > rays / 4, name, detail);
    snprintf(name, sizeof name, "%s: every hit satisfies the definition in world space", label);
    check(inconsistent == 0, name, NULL);
    ref_free(scene);
    free_scene(&d);
}

typedef struct collected {
    double *t;     /* per prim, NaN if not reported */
    size_t calls, duplicates;
} collected;

static void collect_hit(void *user, uint32_t prim, const ref_hit *hit)
{
    collected *c = (collected *)user;
    if (c->t[prim] == c->t[prim])
        ++c->duplicates;
    c->t[prim] = hit->t;
    if (hit->prim_id != prim)
        ++c->duplicates; /* count as an error too */
    ++c->calls;
}

static void compare_all_hits(const char *label, double offset)
{
    const int rays = 500;
    scene_data d = make_scene(100, 20, offset);
    ref_scene *scene = ref_build(d.vertices, d.vertex_count, d.indices, d.segment_count);
    collected c;
    int i, mismatches = 0, multi = 0;
    size_t total = 0;
    char name[128], detail[256] = "";
    c.t = (double *)malloc(d.segment_count * sizeof(double));
    if (!scene || !c.t) {
        snprintf(name, sizeof name, "%s: ref_build", label);
        check(0, name, "allocation failed");
        free(c.t);
        ref_free(scene);
        free_scene(&d);
        return;
    }
    for (i = 0; i < rays; ++i) {
        ray_data ray = make_ray(&d, offset, i);
        size_t p, count, brute_count = 0;
        ref_hit nearest;
        double min_t = HUGE_VAL;
        int nearest_res;
        /* Long rays through the whole cloud so most see several segments. */
        if (i % 2 == 0) {
            ray.tnear = -HUGE_VAL;
            ray.tfar = HUGE_VAL;
        }
        for (p = 0; p < d.segment_count; ++p)
            c.t[p] = NAN;
        c.calls = c.duplicates = 0;
        count = ref_all_hits(scene, ray.org, ray.dir, ray.tnear, ray.tfar, collect_hit, &c);
        for (p = 0; p < d.segment_count; ++p) {
            ref_hit h;
            int res = ref_intersect_segment(d.vertices, d.indices, (uint32_t)p, ray.org, ray.dir, ray.tnear,
                                            ray.tfar, &h);
            brute_count += (size_t)res;
            if (res != (c.t[p] == c.t[p]) || (res && h.t != c.t[p])) {
                if (!mismatches)
                    snprintf(detail, sizeof detail, "ray %d prim %u: brute %d t=%.17g, all_hits t=%.17g", i,
                             (unsigned)p, res, res ? h.t : 0.0, c.t[p]);
                ++mismatches;
            }
            if (res && h.t < min_t)
                min_t = h.t;
        }
        nearest_res = ref_intersect(scene, ray.org, ray.dir, ray.tnear, ray.tfar, &nearest);
        if (count != brute_count || c.calls != count || c.duplicates != 0 ||
            nearest_res != (brute_count > 0) || (nearest_res && nearest.t != min_t)) {
            if (!mismatches)
                snprintf(detail, sizeof detail, "ray %d: count %lu, calls %lu, brute %lu, duplicates %lu", i,
                         (unsigned long)count, (unsigned long)c.calls, (unsigned long)brute_count,
                         (unsigned long)c.duplicates);
            ++mismatches;
        }
        multi += brute_count >= 2;
        total += brute_count;
    }
    printf("  (%s: %lu hits over %d rays, %d rays with >= 2)\n", label, (unsigned long)total, rays, multi);
    snprintf(name, sizeof name, "%s: ref_all_hits == brute-force set (and its min == ref_intersect)", label);
    check(mismatches == 0 && multi > rays / 10, name, detail);
    free(c.t);
    ref_free(scene);
    free_scene(&d);
}

/* ------------------------------------------------------------------------ */
/* The tube reference (ref_tube.h)                                          */
/* ------------------------------------------------------------------------ */

/* A straight segment along x from x0 to x1 with radii r0, r1 at its ends
   (control points at thirds: c(u) linear, r(u) linear). */
static void tube_straight(float ctrl[16], double x0, double x1, double r0, double r1)
{
    int i;
    for (i = 0; i < 4; ++i) {
        ctrl[4 * i + 0] = (float)(x0 + (x1 - x0) * i / 3.0);
        ctrl[4 * i + 1] = 0.0f;
        ctrl[4 * i + 2] = 0.0f;
        ctrl[4 * i + 3] = (float)(r0 + (r1 - r0) * i / 3.0);
    }
}

/* Straight segments: the swept circle is the cylinder or, tapered, the cone
   frustum y^2 + z^2 = r(x)^2, x in [x0, x1]. Its hits solve a quadratic in
   t; both roots (entry and exit) must be the reference's, to 1e-9. */
static void test_tube_analytic(void)
{
    int ray_index, mismatches = 0, hits = 0, exits = 0, v_bad = 0;
    char detail[256] = "";
    for (ray_index = 0; ray_index < 4000; ++ray_index) {
        int tapered = ray_index & 1, n_expected = 0, n_found = 0, k, j;
        float ctrl[16], org[3], dir[3];
        /* exact in float at the thirds too: c(u) and r(u) are exactly linear */
        double x0 = -1.5, x1 = 1.5, r0 = 0.375, r1 = tapered ? 0.1875 : 0.375, slope = (r1 - r0) / (x1 - x0);
        double o[3], d[3], qa, qb, qc, disc, expected[2];
        ref__ray ray;
        ref_tube_hit all[REF_TUBE_MAX_ROOTS], h;
        tube_straight(ctrl, x0, x1, r0, r1);
        for (k = 0; k < 3; ++k) {
            o[k] = rnd_range(-3.0, 3.0);
            d[k] = rnd_range(-1.0, 1.0);
        }
        o[2] = rnd_range(2.0, 4.0) * (rnd() < 0.5 ? -1.0 : 1.0);   /* away from the axis, */
        d[1] += -0.3 * o[1];                                        /* aimed at it */
        d[2] = -o[2] * rnd_range(0.2, 0.5);
        for (k = 0; k < 3; ++k) {
            org[k] = (float)o[k];
            dir[k] = (float)d[k];
            o[k] = org[k];
            d[k] = dir[k];
        }
        /* (oy + t dy)^2 + (oz + t dz)^2 = (r0 + slope (ox + t dx - x0))^2 */
        {
            double e = r0 + slope * (o[0] - x0), f = slope * d[0];
            qa = d[1] * d[1] + d[2] * d[2] - f * f;
            qb = 2.0 * (o[1] * d[1] + o[2] * d[2] - e * f);
            qc = o[1] * o[1] + o[2] * o[2] - e * e;
        }
        disc = qb * qb - 4.0 * qa * qc;
        if (disc > 0.0 && qa != 0.0) {
            double root[2];
            root[0] = (-qb - sqrt(disc)) / (2.0 * qa);
            root[1] = (-qb + sqrt(disc)) / (2.0 * qa);
            for (j = 0; j < 2; ++j) {
                double x = o[0] + root[j] * d[0], radius = r0 + slope * (x - x0);
                /* on the frustum's sheet (not its mirror cone), inside the ends, ahead */
                if (root[j] >= 0.0 && x > x0 && x < x1 && radius > 0.0) expected[n_expected++] = root[j];
            }
        }
        ref__ray_setup(&ray, org, dir);
        ref_tube_segment_hit(&ray, ctrl, 0.0, INFINITY, &h, all, &n_found);
        if (n_found != n_expected) {
            if (!mismatches) snprintf(detail, sizeof detail, "ray %d: %d hits, expected %d", ray_index, n_found, n_expected);
            ++mismatches;
            continue;
        }
        for (j = 0; j < n_found; ++j) {
            int matched = 0, m;
            for (m = 0; m < n_expected; ++m) matched |= fabs(all[j].t - expected[m]) <= 1e-9 * (1.0 + expected[m]);
            if (!matched) {
                if (!mismatches) snprintf(detail, sizeof detail, "ray %d: t %.17g not among the quadratic's roots", ray_index, all[j].t);
                ++mismatches;
            }
            /* the cone's outward normal is (-slope, y, z)/|.| at the hit */
            {
                double X[3], nn[3], len;
                for (k = 0; k < 3; ++k) X[k] = o[k] + all[j].t * d[k];
                nn[0] = -slope * sqrt(X[1] * X[1] + X[2] * X[2]);
                nn[1] = X[1];
                nn[2] = X[2];
                len = sqrt(ref__dot3(nn, nn));
                if (fabs(ref__dot3(nn, all[j].normal) / len - 1.0) > 1e-9) {
                    if (!mismatches) snprintf(detail, sizeof detail, "ray %d: normal off the cone's", ray_index);
                    ++mismatches;
                }
            }
            exits += all[j].exit;
            v_bad += !(all[j].v >= -1.0 && all[j].v <= 1.0);
        }
        hits += n_found;
    }
    printf("  (tube, straight and tapered: %d hits over 4000 rays, %d of them exits)\n", hits, exits);
    check(mismatches == 0 && hits > 200 && exits > hits / 3 && v_bad == 0,
          "tube: straight and tapered segments hit where the cylinder's and the frustum's quadratics say, normals included", detail);
}

/* g(u) = |X(u) - c(u)|^2 - r(u)^2 where X(u) is the ray's point in the plane
   normal to c'(u) through c(u): computed in world space from the control
   points, without ref_tube.h's polynomial, ray frame or Bernstein forms. */
static double tube_g(const float *ctrl, const double o[3], const double d[3], double u, double *t_out)
{
    double c[3], dc[3], X[3], radius, s = 1.0 - u, denominator, t, g;
    int k;
    for (k = 0; k < 3; ++k) {
        double p0 = ctrl[k], p1 = ctrl[4 + k], p2 = ctrl[8 + k], p3 = ctrl[12 + k];
        c[k] = s * s * s * p0 + 3 * u * s * s * p1 + 3 * u * u * s * p2 + u * u * u * p3;
        dc[k] = 3 * (s * s * (p1 - p0) + 2 * u * s * (p2 - p1) + u * u * (p3 - p2));
    }
    radius = s * s * s * ctrl[3] + 3 * u * s * s * ctrl[7] + 3 * u * u * s * ctrl[11] + u * u * u * ctrl[15];
    denominator = ref__dot3(d, dc);
    {
        double oc[3];
        for (k = 0; k < 3; ++k) oc[k] = c[k] - o[k];
        t = ref__dot3(oc, dc) / denominator;
    }
    for (k = 0; k < 3; ++k) X[k] = o[k] + t * d[k] - c[k];
    g = ref__dot3(X, X) - radius * radius;
    *t_out = t;
    return g;
}

/* Curved, tapered segments: every hit the reference finds is a sign change
   of g on a grid of 8,000 steps refined by bisection, and the reverse;
   the normals are the gradient of |X - c(u(X))|^2 - r(u(X))^2 taken by
   central differences. */
static void test_tube_sampling(void)
{
    int segment, mismatches = 0, hits = 0, normal_bad = 0;
    double worst_normal = 0.0;
    char detail[256] = "";
    for (segment = 0; segment < 30; ++segment) {
        float ctrl[16];
        int i, k, ray_index;
        for (i = 0; i < 4; ++i) {
            ctrl[4 * i + 0] = (float)(i * 0.5 + rnd_range(-0.4, 0.4));
            ctrl[4 * i + 1] = (float)rnd_range(-0.5, 0.5);
            ctrl[4 * i + 2] = (float)rnd_range(-0.5, 0.5);
            ctrl[4 * i + 3] = (float)rnd_range(0.05, 0.2);
        }
        for (ray_index = 0; ray_index < 30; ++ray_index) {
            float org[3], dir[3];
            double o[3], d[3], sampled[64];
            int n_sampled = 0, n_found = 0, j, step;
            const int steps = 8000;
            double previous_g = 0.0, previous_t = 0.0;
            ref__ray ray;
            ref_tube_hit all[REF_TUBE_MAX_ROOTS], h;
            for (k = 0; k < 3; ++k) {
                double target = (k == 0 ? 0.75 : 0.0) + rnd_range(-0.6, 0.6);
                o[k] = rnd_range(-4.0, 4.0);
                org[k] = (float)o[k];
                dir[k] = (float)(target - o[k]);
                o[k] = org[k];
                d[k] = dir[k];
            }
            for (step = 0; step <= steps; ++step) {
                double u = (double)step / steps, t, g = tube_g(ctrl, o, d, u, &t);
                if (step > 0 && (g < 0.0) != (previous_g < 0.0) && fabs(t - previous_t) < 0.5) {
                    double a = (double)(step - 1) / steps, b = u, ta = 0.0;
                    int sign_a = previous_g < 0.0, it;
                    for (it = 0; it < 60; ++it) {
                        double m = 0.5 * (a + b), gm = tube_g(ctrl, o, d, m, &ta);
                        if ((gm < 0.0) == sign_a) a = m; else b = m;
                    }
                    tube_g(ctrl, o, d, 0.5 * (a + b), &ta);
                    if (ta >= 0.0 && n_sampled < 64) sampled[n_sampled++] = ta;
                }
                previous_g = g;
                previous_t = t;
            }
            ref__ray_setup(&ray, org, dir);
            ref_tube_segment_hit(&ray, ctrl, 0.0, INFINITY, &h, all, &n_found);
            for (j = 0; j < n_found; ++j) {
                int m, matched = 0;
                for (m = 0; m < n_sampled; ++m) matched |= fabs(all[j].t - sampled[m]) <= 1e-8 * (1.0 + fabs(sampled[m]));
                if (!matched) {
                    if (!mismatches) snprintf(detail, sizeof detail, "segment %d ray %d: reference t %.17g not sampled", segment, ray_index, all[j].t);
                    ++mismatches;
                }
            }
            for (j = 0; j < n_sampled; ++j) {
                int m, matched = 0;
                for (m = 0; m < n_found; ++m) matched |= fabs(all[m].t - sampled[j]) <= 1e-8 * (1.0 + fabs(sampled[j]));
                if (!matched) {
                    if (!mismatches) snprintf(detail, sizeof detail, "segment %d ray %d: sampled t %.17g missed", segment, ray_index, sampled[j]);
                    ++mismatches;
                }
            }
            /* normals: F(X) = |X - c(u)|^2 - r(u)^2 at the u whose plane holds X */
            for (j = 0; j < n_found; ++j) {
                double X[3], grad[3], len, cosine, hstep = 1e-6;
                for (k = 0; k < 3; ++k) X[k] = o[k] + all[j].t * d[k];
                for (k = 0; k < 3; ++k) {
                    double F[2];
                    int side;
                    for (side = 0; side < 2; ++side) {
                        double Y[3], u = all[j].u, c[3], dc[3], d2[3], radius, dr, d2r, e[3];
                        int it, q;
                        for (q = 0; q < 3; ++q) Y[q] = X[q];
                        Y[k] += side ? hstep : -hstep;
                        for (it = 0; it < 50; ++it) {   /* Newton on (Y - c(u)).c'(u) = 0 */
                            double f, df;
                            for (q = 0; q < 3; ++q) {
                                double cp[4] = {ctrl[q], ctrl[4 + q], ctrl[8 + q], ctrl[12 + q]};
                                ref_tube__cubic(cp, u, &c[q], &dc[q], &d2[q]);
                                e[q] = Y[q] - c[q];
                            }
                            f = ref__dot3(e, dc);
                            df = ref__dot3(e, d2) - ref__dot3(dc, dc);
                            u -= f / df;
                        }
                        {
                            double rp[4] = {ctrl[3], ctrl[7], ctrl[11], ctrl[15]};
                            ref_tube__cubic(rp, u, &radius, &dr, &d2r);
                            for (q = 0; q < 3; ++q) {
                                double cp[4] = {ctrl[q], ctrl[4 + q], ctrl[8 + q], ctrl[12 + q]};
                                ref_tube__cubic(cp, u, &c[q], &dc[q], &d2[q]);
                                e[q] = Y[q] - c[q];
                            }
                        }
                        F[side] = ref__dot3(e, e) - radius * radius;
                    }
                    grad[k] = (F[1] - F[0]) / (2 * hstep);
                }
                len = sqrt(ref__dot3(grad, grad));
                cosine = ref__dot3(grad, all[j].normal) / len;
                if (1.0 - cosine > worst_normal) worst_normal = 1.0 - cosine;
                normal_bad += !(cosine > 1.0 - 1e-6);
            }
            hits += n_found;
        }
    }
    printf("  (tube, curved and tapered: %d hits of 30 segments x 30 rays; normals within %.2g of the gradient)\n", hits,
           worst_normal);
    check(mismatches == 0 && hits > 200, "tube: curved segments' hits are g's sign changes on a fine grid, and only those",
          detail);
    check(normal_bad == 0, "tube: normals (with the curvature term) are the gradient of the implicit function", NULL);
}

int main(void)
{
    test_straight();
    test_interval();
    test_endpoints();
    test_curved();
    test_taper();
    test_degenerate();
    test_sampling_cross_check();
    compare_nearest("random scene", 0.0);
    compare_nearest("random scene at 1e5", 1e5);
    compare_all_hits("random scene", 0.0);
    compare_all_hits("random scene at 1e5", 1e5);
    test_tube_analytic();
    test_tube_sampling();
    return check_summary();
}
