/* test_round.c - round curves (tubes, HAIROBB_SHAPE_ROUND): hairobb's tubes
   against the double-precision tube reference (ref_tube.h) on combed, curly
   and crossing fur, straight.hair and furBall_A, camera rays and secondary
   rays leaving their hits (into the fibre: its far side; out of it: never
   its own tube again); save, load and refit; refused options; and the
   reference against Embree's round Bezier curves on the same hair and
   rays. Embree's cubic round curve is the swept circle the reference
   defines, so the two must agree on which rays hit and where, to Embree's
   own accuracy (its Newton iteration stops at a few ulps and gives up on
   some rays). The figures are printed: hit/miss disagreements (Embree's
   misses where the reference hits, its "holes", and the reverse) and
   |t - t_ref| / r. Also: a ray leaving through the tube's far sheet (the
   reference's exit hit) and the near sheet first; end caps and back-face
   culling against the reference (its caps: ref_tube_cap_hit). ref_tube.h's own checks
   (analytic cylinders and frustums, sampling, normals) are in
   test_reference.c.
   The stress suite (test_stress and after it; each prints a "stress NAME"
   line): perpendicular rays grazing at r (1 - 10^-k), a taper to r = 0, a
   long thin fibre far from the origin, a short fat one, a bent one with
   rays from inside, a Bezier kink, repeated control points; then a radius
   at or above the curvature radius (a U, a hook, a tight U: the tube meets
   itself), rays through the smooth joints of B-spline and Catmull-Rom
   strands (the reference on their segments converted to Bezier: rays at
   the seam where one segment's tube ends and the next begins must hit one
   of them), very curvy segments (a zig-zag control polygon, a loop-like S,
   a wave), moving hair (time_steps 2: rays at 8 times against the
   reference on the lerped points), and secondary rays leaving hits at the
   joints of B-spline strands (into the fibre: its far side; reflected: not
   their own strand within 2 r); zero-length segments, and 16 degenerate
   strands (repeated points, cusps, zero-length segments inside and at
   the tip, zero radius, ...) in every basis, with caps and culling,
   refitted, saved and loaded (test_stress_degenerate). Rays within 1e-3 r of a silhouette (and,
   on single segments, of an open end's rim or a fold's edge) are counted
   apart; the first few failing rays are printed in hex. */
#define _POSIX_C_SOURCE 200809L
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "check.h"
#include "compare.h"
#include "embree_wrap.h"
#include "ref_tube.h"
#include "scenes.h"
#include "test_data.h"

#include <stdlib.h>
#include <string.h>

#define SIDE 128

static float dot3f(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void compare_with_embree(const char *name, hair_scene *s)
{
    size_t n = (size_t)SIDE * SIDE, i, both = 0, holes = 0, extra = 0, exits = 0, open_ends = 0;
    float *org = (float *)malloc(3 * sizeof(float) * n), *dir = (float *)malloc(3 * sizeof(float) * n);
    double *error = (double *)malloc(sizeof(double) * n), median, p99;
    ref_scene *reference_scene = ref_build(s->vertices, s->vertex_count, s->indices, s->segment_count);
    emb_scene *e = emb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, EMB_ROUND_BEZIER, 0, 0, NULL, NULL);
    CHECK(e != NULL && reference_scene != NULL, "%s: Embree builds its round curves", name);
    if (!e || !org || !dir || !error || !reference_scene) return;
    scene_camera_rays(s, SIDE, SIDE, org, dir);
    for (i = 0; i < n; ++i) {
        ref_tube_hit want;
        float t = 0.0f;
        int reference = ref_tube_intersect_scene(reference_scene, org + 3 * i, dir + 3 * i, 0.0, INFINITY, &want);
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
    median = percentile(error, both, 0.5);
    p99 = percentile(error, both, 0.99);
    printf("%s: %zu segments, %zu rays; both hit %zu; Embree misses %zu the reference hits, hits %zu it misses; "
           "|dt|/r median %.3g, p99 %.3g, max %.3g\n",
           name, s->segment_count, n, both, holes, extra, median, p99, percentile(error, both, 1.0));
    CHECK(both > n / 20, "%s: %zu rays hit both", name, both);
    /* the same surface: disagreements are Embree's rare misses and edge rays */
    CHECK(holes + extra <= n / 200, "%s: %zu + %zu of %zu rays disagree with Embree on hit or miss", name, holes, extra, n);
    CHECK(median <= 1e-4 && p99 <= 1e-2, "%s: |dt|/r against Embree: median %.3g, p99 %.3g", name, median, p99);
    printf("%s: %zu rays came in through a strand's open end and first met an exit sheet\n", name, open_ends);
    CHECK(exits == 0, "%s: %zu camera rays meet an exit sheet first away from a strand's ends", name, exits);
    emb_free(e);
    ref_free(reference_scene);
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

/* hairobb's tubes against the reference: camera rays, then from each hit
   a ray going on into the fibre (it must leave through the fibre's far
   side, the reference's exit) and one reflected outward (never its own
   tube within the band). */
static void compare_with_reference(const char *name, hair_scene *s, const hairobb_build_options *options)
{
    size_t n = (size_t)SIDE * SIDE, i, both = 0, disagree = 0, at_edge = 0, inward = 0, inward_bad = 0, outward = 0, outward_self = 0, v_bad = 0;
    float *org = (float *)malloc(3 * sizeof(float) * n), *dir = (float *)malloc(3 * sizeof(float) * n);
    double *error = (double *)malloc(sizeof(double) * n), worst_inward = 0.0, p99;
    ref_scene *reference_scene = ref_build(s->vertices, s->vertex_count, s->indices, s->segment_count);
    hairobb_bvh *bvh = NULL;
    CHECK(hairobb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, options, &bvh) == HAIROBB_OK,
          "%s: builds with round curves", name);
    if (!bvh || !org || !dir || !error || !reference_scene) return;
    scene_camera_rays(s, SIDE, SIDE, org, dir);
    for (i = 0; i < n; ++i) {
        ref_tube_hit want;
        hairobb_ray ray = {{org[3 * i], org[3 * i + 1], org[3 * i + 2]}, 0.0f, {dir[3 * i], dir[3 * i + 1], dir[3 * i + 2]}, INFINITY, 0.0f};
        hairobb_hit hit;
        int reference, got;
        reference = ref_tube_intersect_scene(reference_scene, org + 3 * i, dir + 3 * i, 0.0, INFINITY, &want);
        got = hairobb_intersect1(bvh, &ray, &hit);
        if (got != reference) {
            /* a ray through the tube within 1e-3 r of its silhouette (a
               chord under 0.09 r) is decided by the float rounding of the
               points in ray space: counted apart */
            int edge = 0;
            if (reference) {
                ref__ray rr;
                ref_tube_hit all[REF_TUBE_MAX_ROOTS], first;
                int count = 0, j;
                ref__ray_setup(&rr, ray.org, ray.dir);
                ref_tube_segment_hit(&rr, s->vertices + 4 * (size_t)s->indices[want.prim_id], 0.0, INFINITY, &first, all, &count);
                for (j = 0; j < count; ++j)
                    if (all[j].exit && all[j].t > want.t && (all[j].t - want.t) * rr.dir_len < 0.09 * want.r) edge = 1;
            }
            if (edge) {
                ++at_edge;
                continue;
            }
            if (disagree < 3) printf("  %s: ray %zu: reference %d (prim %u t %.9g), hairobb %d (prim %u t %.9g)\n", name, i, reference,
                                     want.prim_id, want.t, got, hit.prim_id, (double)hit.t);
            ++disagree;
            continue;
        }
        if (!got) continue;
        error[both++] = fabs((double)hit.t - want.t) / want.r;
        v_bad += !(fabs((double)hit.v - want.v) <= 1e-2) && !want.exit;
        if (!want.exit) {
            /* on into the fibre: from the entry, the same direction */
            hairobb_ray next;
            hairobb_hit exit_hit;
            ref__ray rr;
            ref_tube_hit all[REF_TUBE_MAX_ROOTS], first;
            int count = 0, j, k;
            double far_side = -1.0;
            for (k = 0; k < 3; ++k) {
                next.org[k] = ray.org[k] + hit.t * ray.dir[k];
                next.dir[k] = ray.dir[k];
            }
            next.tnear = 0.0f;
            next.tfar = INFINITY;
            next.time = 0.0f;
            ref__ray_setup(&rr, ray.org, ray.dir);
            ref_tube_segment_hit(&rr, s->vertices + 4 * (size_t)s->indices[want.prim_id], want.t * (1.0 + 1e-9), INFINITY, &first, all,
                                 &count);
            for (j = 0; j < count; ++j)
                if (all[j].exit && (far_side < 0.0 || all[j].t < far_side)) far_side = all[j].t;
            if (far_side > want.t + 0.01 * want.r) {   /* a chord of some length: the band must not swallow it */
                double expected = far_side - (double)hit.t;   /* from hairobb's entry, where the new ray starts */
                ++inward;
                if (!hairobb_intersect1_from(bvh, &hit, &next, &exit_hit) ||
                    (exit_hit.prim_id == hit.prim_id && fabs((double)exit_hit.t - expected) > 2e-3 * want.r)) {
                    ++inward_bad;
                } else if (exit_hit.prim_id == hit.prim_id) {
                    double e = fabs((double)exit_hit.t - expected) / want.r;
                    worst_inward = e > worst_inward ? e : worst_inward;
                }
            }
            /* reflected: out of the fibre, never its own tube nearby */
            {
                hairobb_ray out = next;
                hairobb_hit again;
                double dn = ray.dir[0] * hit.Ng[0] + ray.dir[1] * hit.Ng[1] + ray.dir[2] * hit.Ng[2];
                for (k = 0; k < 3; ++k) out.dir[k] = (float)(ray.dir[k] - 2.0 * dn * hit.Ng[k]);
                ++outward;
                if (hairobb_intersect1_from(bvh, &hit, &out, &again) && again.prim_id == hit.prim_id && again.t < 2.0f * (float)want.r) {
                    ++outward_self;
                }
            }
        }
    }
    qsort(error, both, sizeof *error, compare_doubles);
    p99 = percentile(error, both, 0.99);
    printf("%s: hairobb's tubes against the reference: %zu of %zu rays disagree on hit or miss (%zu more within 1e-3 r of a "
           "silhouette); |dt|/r median %.3g, p99 %.3g, max %.3g over %zu hits; into the fibre %zu rays, %zu without its far side "
           "(worst |dt|/r %.3g); reflected %zu, %zu back on their tube\n",
           name, disagree, n, at_edge, percentile(error, both, 0.5), p99, percentile(error, both, 1.0), both, inward, inward_bad,
           worst_inward, outward, outward_self);
    CHECK(both > n / 20, "%s: %zu hits", name, both);
    CHECK(disagree == 0 && at_edge <= n / 2000, "%s: %zu of %zu rays disagree with the tube reference (%zu at a silhouette)", name,
          disagree, n, at_edge);
    CHECK(p99 <= 2e-3, "%s: |dt|/r p99 %.3g", name, p99);
    CHECK(v_bad <= both / 1000, "%s: v off the reference's on %zu hits", name, v_bad);
    CHECK(inward > 100 && inward_bad <= inward / 1000, "%s: %zu of %zu rays into the fibre miss its far side", name, inward_bad, inward);
    CHECK(outward_self == 0, "%s: %zu reflected rays hit their own tube again", name, outward_self);
    hairobb_free(bvh);
    ref_free(reference_scene);
    free(org);
    free(dir);
    free(error);
}

/* A round BVH saved and loaded traces the same hits, bit for bit, and
   reports round curves' attributes; one refitted to the same points too. */
static void test_save_refit(hair_scene *s)
{
    hairobb_build_options o;
    hairobb_bvh *bvh = NULL, *loaded = NULL, *refitted = NULL;
    size_t n = 64 * 64, i, differ = 0, refit_differ = 0, hits = 0, size;
    float *org = (float *)malloc(3 * sizeof(float) * n), *dir = (float *)malloc(3 * sizeof(float) * n);
    void *buffer = NULL;
    memset(&o, 0, sizeof o);
    o.shape = HAIROBB_SHAPE_ROUND;
    CHECK(hairobb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, &o, &bvh) == HAIROBB_OK, "save: builds");
    CHECK(hairobb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, &o, &refitted) == HAIROBB_OK, "refit: builds");
    if (!bvh || !refitted || !org || !dir) return;
    size = hairobb_save_size(bvh);
    buffer = malloc(size);
    CHECK(buffer && hairobb_save(bvh, buffer, size) == HAIROBB_OK, "save: saves");
    CHECK(hairobb_load(buffer, size, s->vertices, s->vertex_count, s->indices, s->segment_count, NULL, &loaded) == HAIROBB_OK,
          "save: loads");
    CHECK(hairobb_refit(refitted, s->vertices) == HAIROBB_OK, "refit: refits");
    scene_camera_rays(s, 64, 64, org, dir);
    for (i = 0; loaded && i < n; ++i) {
        hairobb_ray ray = {{org[3 * i], org[3 * i + 1], org[3 * i + 2]}, 0.0f, {dir[3 * i], dir[3 * i + 1], dir[3 * i + 2]}, INFINITY, 0.0f};
        hairobb_hit a, b, c;
        int ga = hairobb_intersect1(bvh, &ray, &a), gb = hairobb_intersect1(loaded, &ray, &b), gc = hairobb_intersect1(refitted, &ray, &c);
        hits += (size_t)ga;
        differ += !same_hit(ga, &a, gb, &b);
        refit_differ += !same_hit(ga, &a, gc, &c);
    }
    CHECK(hits > n / 20 && differ == 0, "save: a loaded round BVH gives the same hits (%zu of %zu differ, %zu hits)", differ, n, hits);
    CHECK(refit_differ == 0, "refit: a refitted round BVH gives the same hits (%zu differ)", refit_differ);
    /* the shape is in the file: an unknown one is refused */
    if (buffer && size > 128) {
        unsigned char *bytes = (unsigned char *)buffer;
        hairobb_bvh *bad = NULL;
        uint32_t two = 2;
        memcpy(bytes + HAIROBB__AT_SHAPE, &two, 4);
        hairobb__put64(bytes + size - 8, hairobb__save_checksum(bytes, size));   /* a lie with its checksum fixed */
        CHECK(hairobb_load(buffer, size, s->vertices, s->vertex_count, s->indices, s->segment_count, NULL, &bad) == HAIROBB_ERROR_INVALID_FILE && !bad,
              "save: an unknown shape in the file is refused");
    }
    hairobb_free(bvh);
    hairobb_free(loaded);
    hairobb_free(refitted);
    free(buffer);
    free(org);
    free(dir);
}

/* One segment (or a few) and a set of rays: hairobb's tube against the
   reference, counting disagreements away from silhouettes. The first few
   rays that fail are printed (hex floats), with the case's name. */
typedef struct stress_count {
    const char *name;
    size_t rays, hits, disagree, edge, t_bad, printed;
    const float *rim;   /* a single segment's points: the rim rule below too (NULL: the chord rule alone) */
} stress_count;

/* Whether the reference's hit is within 1e-3 r of its tube's silhouette:
   an exit follows it within a chord of 0.09 r (on any segment: the chord
   may cross a joint; the stress scenes are small). */
static int stress_silhouette(const ref_scene *reference, const ref_tube_hit *want, const float org[3], const float dir[3])
{
    ref__ray rr;
    size_t i;
    ref__ray_setup(&rr, org, dir);
    for (i = 0; i < reference->segment_count; ++i) {
        ref_tube_hit all[REF_TUBE_MAX_ROOTS], first;
        int count = 0, j;
        ref_tube_segment_hit(&rr, reference->vertices + 4 * (size_t)reference->indices[i], 0.0, INFINITY, &first, all, &count);
        for (j = 0; j < count; ++j)
            if (all[j].exit && all[j].t > want->t && (all[j].t - want->t) * rr.dir_len < 0.09 * want->r) return 1;
    }
    return 0;
}

/* Whether the reference's answer for a single segment changes with its
   radii scaled by 1 -/+ 1e-3 (the caps test's rule, below): the ray passes
   within 1e-3 r of a silhouette, an open end's rim or the edge where a
   folded tube's sheets meet, and rounding decides. Changes: it hits or
   misses, or its first hit moves to another root (u by over 0.01). */
static int stress_rim(const float *cp, const float org[3], const float dir[3], int expected, const ref_tube_hit *want)
{
    int scale;
    for (scale = 0; scale < 2; ++scale) {
        float scaled[16];
        ref__ray rr;
        ref_tube_hit h;
        int k, got;
        for (k = 0; k < 16; ++k) scaled[k] = cp[k] * ((k & 3) == 3 ? (float)(scale ? 1.0 + 1e-3 : 1.0 - 1e-3) : 1.0f);
        ref__ray_setup(&rr, org, dir);
        got = ref_tube_segment_hit(&rr, scaled, 0.0, INFINITY, &h, NULL, NULL);
        if (got != expected || (got && fabs(h.u - want->u) > 0.01)) return 1;
    }
    return 0;
}

static void stress_print(stress_count *n, const float org[3], const float dir[3], float time, int expected, const ref_tube_hit *want,
                         int got, const hairobb_hit *hit)
{
    if (n->printed++ >= 3) return;
    printf("  stress %s: org %a %a %a dir %a %a %a time %a: reference %d (prim %u t %.9g u %.6f exit %d), hairobb %d (prim %u t %.9g u %.6f)\n",
           n->name, (double)org[0], (double)org[1], (double)org[2], (double)dir[0], (double)dir[1], (double)dir[2], (double)time, expected,
           expected ? want->prim_id : 0u, expected ? want->t : 0.0, expected ? want->u : 0.0, expected ? want->exit : 0, got,
           got ? hit->prim_id : 0u, got ? (double)hit->t : 0.0, got ? (double)hit->u : 0.0);
}

/* One ray at ray time `time` (the reference is the hair at that time). */
static void stress_ray(hairobb_bvh *bvh, const ref_scene *reference, const float org[3], const float dir[3], float time, stress_count *n)
{
    hairobb_ray ray;
    hairobb_hit hit;
    ref_tube_hit want;
    int got, expected;
    memcpy(ray.org, org, sizeof ray.org);
    memcpy(ray.dir, dir, sizeof ray.dir);
    ray.tnear = 0.0f;
    ray.tfar = INFINITY;
    ray.time = time;
    got = hairobb_intersect1(bvh, &ray, &hit);
    expected = ref_tube_intersect_scene(reference, org, dir, 0.0, INFINITY, &want);
    ++n->rays;
    n->hits += (size_t)expected;
    if (got != expected) {
        /* within 1e-3 r of a silhouette (a chord under 0.09 r) or, where
           n->rim is set, of a rim or a fold's edge: counted apart */
        if ((expected && stress_silhouette(reference, &want, org, dir)) || (n->rim && stress_rim(n->rim, org, dir, expected, &want))) {
            ++n->edge;
        } else {
            ++n->disagree;
            stress_print(n, org, dir, time, expected, &want, got, &hit);
        }
    } else if (got && fabs((double)hit.t - want.t) * sqrt((double)dir[0] * dir[0] + (double)dir[1] * dir[1] + (double)dir[2] * dir[2]) >
                          2e-3 * want.r + 1e-6 * fabs(want.t)) {
        /* hairobb passed the reference's first hit, within 1e-3 r of a
           silhouette, and hit what lies behind: the same silhouette ray
           (or the rim rule says rounding decides) */
        double length = sqrt((double)dir[0] * dir[0] + (double)dir[1] * dir[1] + (double)dir[2] * dir[2]);
        double facing = fabs(want.normal[0] * dir[0] + want.normal[1] * dir[1] + want.normal[2] * dir[2]) / length;
        if (((double)hit.t > want.t && stress_silhouette(reference, &want, org, dir)) || (n->rim && stress_rim(n->rim, org, dir, 1, &want))) {
            ++n->edge;
        } else if (hit.prim_id == want.prim_id && facing < 0.0872 &&
                   fabs((double)hit.t - want.t) * length * facing <= 2e-3 * want.r) {
            /* within 5 degrees of grazing the surface, t's error is the
               hit point's distance from the surface over the sine of the
               angle: judged by that distance (2e-3 r), counted apart */
            ++n->edge;
        } else {
            ++n->t_bad;
            stress_print(n, org, dir, time, expected, &want, got, &hit);
        }
    }
}

/* The summary line and the check: no disagreement away from a silhouette,
   every |dt| within 2e-3 r, at most 1% of the rays at a silhouette, and
   (must_hit) over a quarter of them hitting. */
static void stress_report(const stress_count *n, int must_hit)
{
    printf("stress %s: %zu rays, %zu hit the reference; %zu disagree, %zu within 1e-3 r of a silhouette, %zu with |dt| over 2e-3 r\n",
           n->name, n->rays, n->hits, n->disagree, n->edge, n->t_bad);
    CHECK(n->disagree == 0 && n->t_bad == 0 && n->edge <= n->rays / 100 && (!must_hit || n->hits > n->rays / 4),
          "stress %s: %zu disagree, %zu off in t, %zu at a silhouette, %zu hits of %zu", n->name, n->disagree, n->t_bad, n->edge, n->hits,
          n->rays);
}

static void stress_case(const char *name, const float *vertices, size_t vertex_count, const uint32_t *indices, size_t segments,
                        const float (*org)[3], const float (*dir)[3], size_t ray_count, int must_hit)
{
    hairobb_build_options o;
    hairobb_bvh *bvh = NULL;
    ref_scene *reference = ref_build(vertices, vertex_count, indices, segments);
    stress_count n;
    size_t i;
    memset(&n, 0, sizeof n);
    n.name = name;
    memset(&o, 0, sizeof o);
    o.shape = HAIROBB_SHAPE_ROUND;
    CHECK(hairobb_build(vertices, vertex_count, indices, segments, &o, &bvh) == HAIROBB_OK && reference, "stress %s: builds", name);
    if (!bvh || !reference) return;
    for (i = 0; i < ray_count; ++i) stress_ray(bvh, reference, org[i], dir[i], 0.0f, &n);
    stress_report(&n, must_hit);
    hairobb_free(bvh);
    ref_free(reference);
}

/* A straight segment along x, radii r0 at 0 and r1 at 1, shifted by offset. */
static void stress_straight(float v[16], double length, double r0, double r1, double offset)
{
    int i;
    for (i = 0; i < 4; ++i) {
        v[4 * i] = (float)(offset + length * i / 3.0);
        v[4 * i + 1] = (float)offset;
        v[4 * i + 2] = (float)offset;
        v[4 * i + 3] = (float)(r0 + (r1 - r0) * i / 3.0);
    }
}

static void test_stress(void)
{
    enum { RAYS = 2000 };
    static float org[RAYS][3], dir[RAYS][3];
    float v[64];
    uint32_t idx[4] = {0, 4, 8, 12};
    size_t i;
    int k;
    uint64_t state = 12345;
    /* perpendicular to the fibre, at offsets r (1 - 10^-k) from its axis, k = 1..6, both sides */
    stress_straight(v, 3.0, 0.25, 0.25, 0.0);
    for (i = 0; i < RAYS; ++i) {
        double e = 0.25 * (1.0 - pow(10.0, -(double)(1 + i % 6))) * (i & 1 ? 1.0 : -1.0);
        org[i][0] = (float)(0.2 + 2.6 * lcg64_double(&state)); org[i][1] = (float)e; org[i][2] = -2.0f;
        dir[i][0] = 0.0f; dir[i][1] = 0.0f; dir[i][2] = 1.0f;
    }
    stress_case("perpendicular, grazing at r (1 - 10^-k)", v, 4, idx, 1, (const float (*)[3])org, (const float (*)[3])dir, RAYS, 1);
    /* oblique rays through a tapered fibre whose radius falls to 0 */
    stress_straight(v, 3.0, 0.3, 0.0, 0.0);
    for (i = 0; i < RAYS; ++i) {
        double x = 3.0 * lcg64_double(&state), a = 6.283185307 * lcg64_double(&state);
        org[i][0] = (float)(x - 1.0); org[i][1] = (float)(2.0 * cos(a)); org[i][2] = (float)(2.0 * sin(a));
        dir[i][0] = 1.0f; dir[i][1] = (float)(-2.0 * cos(a) + 0.3 * (lcg64_double(&state) - 0.5)); dir[i][2] = (float)(-2.0 * sin(a) + 0.3 * (lcg64_double(&state) - 0.5));
    }
    stress_case("tapered to r = 0", v, 4, idx, 1, (const float (*)[3])org, (const float (*)[3])dir, RAYS, 1);
    /* a long thin fibre far from the origin (length / width 10^4, at 10^4) */
    stress_straight(v, 10.0, 5e-4, 5e-4, 1e4);
    for (i = 0; i < RAYS; ++i) {
        org[i][0] = (float)(1e4 + 0.5 + 9.0 * lcg64_double(&state)); org[i][1] = (float)(1e4 + 5e-4 * (2.0 * lcg64_double(&state) - 1.0));
        org[i][2] = (float)(1e4 - 1.0);
        dir[i][0] = (float)(0.2 * (lcg64_double(&state) - 0.5)); dir[i][1] = 0.0f; dir[i][2] = 1.0f;
    }
    stress_case("long and thin at 1e4", v, 4, idx, 1, (const float (*)[3])org, (const float (*)[3])dir, RAYS, 1);
    /* a short fat segment (length 0.2, radius 0.3), rays every way */
    stress_straight(v, 0.2, 0.3, 0.25, 0.0);
    for (i = 0; i < RAYS; ++i) {
        for (k = 0; k < 3; ++k) org[i][k] = (float)(4.0 * lcg64_double(&state) - 2.0);
        for (k = 0; k < 3; ++k) dir[i][k] = (float)((k == 0 ? 0.1 : 0.0) + 0.4 * lcg64_double(&state) - 0.2 - org[i][k]);
    }
    stress_case("short and fat", v, 4, idx, 1, (const float (*)[3])org, (const float (*)[3])dir, RAYS, 0);
    /* a strongly bent segment, and rays from inside it along its tangent */
    {
        static const float bent[16] = {0.0f, 0.0f, 0.0f, 0.15f, 1.0f, 1.2f, 0.0f, 0.15f, 0.0f, 1.4f, 0.1f, 0.15f, 1.0f, 2.0f, 0.0f, 0.15f};
        memcpy(v, bent, sizeof bent);
        for (i = 0; i < RAYS; ++i) {
            double u = 0.05 + 0.9 * lcg64_double(&state), s = 1.0 - u, c[3], d[3];
            for (k = 0; k < 3; ++k) {
                c[k] = s * s * s * bent[k] + 3 * u * s * s * bent[4 + k] + 3 * u * u * s * bent[8 + k] + u * u * u * bent[12 + k];
                d[k] = 3 * (s * s * (bent[4 + k] - bent[k]) + 2 * u * s * (bent[8 + k] - bent[4 + k]) + u * u * (bent[12 + k] - bent[8 + k]));
                org[i][k] = (float)(c[k] + 0.05 * (lcg64_double(&state) - 0.5));
                dir[i][k] = (float)(i & 1 ? d[k] : -d[k]);
            }
        }
        stress_case("bent, rays along it from inside", v, 4, idx, 1, (const float (*)[3])org, (const float (*)[3])dir, RAYS, 1);
    }
    /* a Bezier kink (two segments meeting at an angle) and repeated control points */
    {
        static const float kink[28] = {0, 0, 0, 0.1f, 0.3f, 0, 0, 0.1f, 0.6f, 0, 0, 0.1f, 1, 0, 0, 0.1f,
                                       1, 0.3f, 0, 0.1f, 1, 0.6f, 0, 0.1f, 1, 1, 0, 0.1f};
        uint32_t two[2] = {0, 3};
        for (i = 0; i < RAYS; ++i) {
            org[i][0] = (float)(0.8 + 0.4 * lcg64_double(&state)); org[i][1] = (float)(-0.2 + 0.4 * lcg64_double(&state)); org[i][2] = -3.0f;
            dir[i][0] = (float)(0.2 * (lcg64_double(&state) - 0.5)); dir[i][1] = (float)(0.2 * (lcg64_double(&state) - 0.5)); dir[i][2] = 1.0f;
        }
        stress_case("a Bezier kink", kink, 7, two, 2, (const float (*)[3])org, (const float (*)[3])dir, RAYS, 1);
        {
            static const float repeated[16] = {0, 0, 0, 0.1f, 0, 0, 0, 0.1f, 1, 0.5f, 0, 0.1f, 1, 0.5f, 0, 0.1f};
            /* oblique rays: a ray perpendicular to the segment's plane lies in
               every circle's plane, and at the repeated end, where the
               tangent vanishes, float noise decides (left open) */
            for (i = 0; i < RAYS; ++i) {
                org[i][0] = (float)(1.2 * lcg64_double(&state) - 0.1); org[i][1] = (float)(0.7 * lcg64_double(&state) - 0.1); org[i][2] = -3.0f;
                dir[i][0] = (float)(0.3 * (lcg64_double(&state) - 0.5)); dir[i][1] = (float)(0.3 * (lcg64_double(&state) - 0.5)); dir[i][2] = 1.0f;
            }
            stress_case("repeated control points", repeated, 4, idx, 1, (const float (*)[3])org, (const float (*)[3])dir, RAYS, 0);
        }
    }
}

/* ---- The stress suite's second part: a tube that meets itself, smooth
   joints of B-spline and Catmull-Rom strands, very curvy segments, motion,
   and secondary rays at joints. Rays are aimed near the hair from random
   directions (a random generator per check: random.h's lcg64, as above). */

/* a unit direction, uniform on the sphere */
static void stress_direction(uint64_t *state, double d[3])
{
    double z = 2.0 * lcg64_double(state) - 1.0, a = 6.283185307179586 * lcg64_double(state), s = sqrt(1.0 - z * z);
    d[0] = s * cos(a);
    d[1] = s * sin(a);
    d[2] = z;
}

/* a point uniformly in the ball of this radius about the origin */
static void stress_ball(uint64_t *state, double radius, double out[3])
{
    int k;
    do {
        for (k = 0; k < 3; ++k) out[k] = 2.0 * lcg64_double(state) - 1.0;
    } while (out[0] * out[0] + out[1] * out[1] + out[2] * out[2] > 1.0);
    for (k = 0; k < 3; ++k) out[k] *= radius;
}

/* A Bezier segment (16 floats) at u: centre, radius, first and second derivatives of the centre (either may be NULL). */
static void stress_bezier(const float *cp, double u, double centre[3], double *radius, double d1[3], double d2[3])
{
    double s = 1.0 - u;
    int k;
    for (k = 0; k < 4; ++k) {
        double value = s * s * s * cp[k] + 3.0 * u * s * s * cp[4 + k] + 3.0 * u * u * s * cp[8 + k] + u * u * u * cp[12 + k];
        if (k == 3) {
            *radius = value;
            break;
        }
        centre[k] = value;
        if (d1) d1[k] = 3.0 * (s * s * (cp[4 + k] - cp[k]) + 2.0 * u * s * (cp[8 + k] - cp[4 + k]) + u * u * (cp[12 + k] - cp[8 + k]));
        if (d2) d2[k] = 6.0 * (s * (cp[8 + k] - 2.0 * cp[4 + k] + cp[k]) + u * (cp[12 + k] - 2.0 * cp[8 + k] + cp[4 + k]));
    }
}

/* A ray through `aim` from `distance` before it, along a random direction,
   |dir| random in [0.5, 2]. */
static void stress_aimed(uint64_t *state, const double aim[3], double distance, float org[3], float dir[3])
{
    double d[3], scale = 0.5 + 1.5 * lcg64_double(state);
    int k;
    stress_direction(state, d);
    for (k = 0; k < 3; ++k) {
        org[k] = (float)(aim[k] - distance * d[k]);
        dir[k] = (float)(scale * d[k]);
    }
}

/* Rays at single Bezier segments: each aimed at a random point within
   `spread` r(u) of the centre line at u in [u0, u1], from 3 away. */
static void stress_segment_rays(hairobb_bvh *bvh, const ref_scene *reference, const float *cp, size_t rays, double u0, double u1,
                                double spread, uint64_t *state, stress_count *n)
{
    size_t i;
    for (i = 0; i < rays; ++i) {
        double u = u0 + (u1 - u0) * lcg64_double(state), aim[3], offset[3], radius;
        float org[3], dir[3];
        int k;
        stress_bezier(cp, u, aim, &radius, NULL, NULL);
        stress_ball(state, spread * radius, offset);
        for (k = 0; k < 3; ++k) aim[k] += offset[k];
        stress_aimed(state, aim, 3.0, org, dir);
        stress_ray(bvh, reference, org, dir, 0.0f, n);
    }
}

/* A single-segment scene's BVH (round) and reference. */
static int stress_single(const float *cp, hairobb_bvh **bvh, ref_scene **reference, const char *name)
{
    static const uint32_t zero[1] = {0};
    hairobb_build_options o;
    memset(&o, 0, sizeof o);
    o.shape = HAIROBB_SHAPE_ROUND;
    *bvh = NULL;
    *reference = ref_build(cp, 4, zero, 1);
    CHECK(hairobb_build(cp, 4, zero, 1, &o, bvh) == HAIROBB_OK && *reference, "stress %s: builds", name);
    if (*bvh && *reference) return 1;
    hairobb_free(*bvh);
    ref_free(*reference);
    return 0;
}

/* Rays for one shape of a stress check, kept: a longer run of the same
   random rays (about 300,000 over the shapes) found hairobb missing the
   reference's first hit on them, away from any silhouette, rim or fold
   edge (the rim rule). */
typedef struct stress_kept {
    int shape;
    float org[3], dir[3];
} stress_kept;

static void stress_kept_rays(const stress_kept *kept, size_t count, int shape, hairobb_bvh *bvh, const ref_scene *reference,
                             stress_count *n)
{
    size_t i;
    for (i = 0; i < count; ++i)
        if (kept[i].shape == shape) stress_ray(bvh, reference, kept[i].org, kept[i].dir, 0.0f, n);
}

/* 1. Radius at or above the curvature radius: the swept circles of a tight
   bend cross, and the tube meets itself (its sheets fold over). A U whose
   apex bends at radius 0.06 with r 0.15 and with r 0.0605 (about equal),
   a hook out of its plane tapering from 0.08 to 0.2 across a bend of
   radius 0.075, and a tight U out of its plane (bend radius 0.019, r 0.1,
   its legs touching).
   Each shape's smallest ratio of curvature radius to r is checked to be at
   most 1 (the premise), then rays from every direction at the whole
   segment and more at its bend, and the kept rays (stress_kept): two
   entries of one sheet close together in u (a fold), both missed. Failures
   within 1e-3 r of a silhouette, an open end's rim or a fold's edge (the
   chord or the rim rule) are counted apart. */
static void test_stress_self_meeting(void)
{
    static const float shapes[4][16] = {
        {-0.2f, 0.0f, 0.0f, 0.15f, -0.2f, 1.0f, 0.0f, 0.15f, 0.2f, 1.0f, 0.0f, 0.15f, 0.2f, 0.0f, 0.0f, 0.15f},
        {-0.2f, 0.0f, 0.0f, 0.0605f, -0.2f, 1.0f, 0.0f, 0.0605f, 0.2f, 1.0f, 0.0f, 0.0605f, 0.2f, 0.0f, 0.0f, 0.0605f},
        {0.0f, 0.0f, 0.0f, 0.08f, 0.0f, 1.2f, 0.0f, 0.12f, 0.7f, 0.9f, 0.1f, 0.16f, 0.25f, 0.5f, -0.05f, 0.2f},
        {-0.1f, 0.0f, 0.0f, 0.1f, -0.1f, 0.8f, 0.0f, 0.1f, 0.1f, 0.8f, 0.05f, 0.1f, 0.1f, 0.0f, 0.0f, 0.1f},
    };
    static const stress_kept kept[] = {
        {2, {0x1.34166p-8f, -0x1.052e66p+1f, 0x1.2c9d1ap-1f}, {0x1.ca5dcep-4f, 0x1.f383fp-1f, -0x1.93f88ep-3f}},
        {2, {-0x1.cbb58ap-3f, -0x1.738bb6p+0f, -0x1.fbdc24p+0f}, {0x1.f6533p-3f, 0x1.f2b0acp-1f, 0x1.c59c7ap-1f}},
        {2, {0x1.14b39ap-1f, -0x1.fb8026p+0f, -0x1.bf9d1ap-1f}, {-0x1.db295ep-5f, 0x1.66a594p-1f, 0x1.fc4856p-3f}},
        {3, {0x1.935bbep-3f, -0x1.39b57p+1f, -0x1.addb9ap-4f}, {-0x1.464c02p-5f, 0x1.50dffcp-1f, 0x1.6b17a6p-5f}},
        {3, {0x1.7f7832p-2f, -0x1.2a2e62p+1f, 0x1.3b2a1ap-2f}, {-0x1.1dfbe2p-3f, 0x1.3aa27p+0f, -0x1.277e06p-3f}},
    };
    stress_count n;
    uint64_t state = 3501;
    int shape;
    memset(&n, 0, sizeof n);
    n.name = "radius at or above the curvature radius";
    for (shape = 0; shape < 4; ++shape) {
        hairobb_bvh *bvh;
        ref_scene *reference;
        double ratio = INFINITY, bend_u = 0.5;
        int j;
        for (j = 0; j <= 1000; ++j) {
            double u = j / 1000.0, c[3], d1[3], d2[3], radius, cross[3], speed;
            stress_bezier(shapes[shape], u, c, &radius, d1, d2);
            ref__cross3(d1, d2, cross);
            speed = sqrt(ref__dot3(d1, d1));
            if (sqrt(ref__dot3(cross, cross)) > 0.0 && speed * speed * speed / sqrt(ref__dot3(cross, cross)) / radius < ratio) {
                ratio = speed * speed * speed / sqrt(ref__dot3(cross, cross)) / radius;
                bend_u = u;
            }
        }
        CHECK(ratio <= 1.0 + 1e-9, "stress self-meeting shape %d: the smallest curvature radius is %.3g r", shape, ratio);
        if (!stress_single(shapes[shape], &bvh, &reference, n.name)) continue;
        n.rim = shapes[shape];
        stress_segment_rays(bvh, reference, shapes[shape], 1000, 0.0, 1.0, 1.5, &state, &n);
        stress_segment_rays(bvh, reference, shapes[shape], 1000, bend_u - 0.15, bend_u + 0.15, 1.2, &state, &n);
        stress_kept_rays(kept, sizeof kept / sizeof kept[0], shape, bvh, reference, &n);
        hairobb_free(bvh);
        ref_free(reference);
    }
    stress_report(&n, 1);
}

/* 3. Very curvy segments: a zig-zag control polygon (an S whose bends reach
   curvature radius 0.06 against r 0.04), a control polygon that crosses
   itself (a loop-like S, tapered 0.05 to 0.02), and a wave out of its
   plane; random rays at them and from random points of a box around them
   at random points of it, and a kept ray (stress_kept): an entry and its
   exit 0.02 apart in u, both missed. Failures within 1e-3 r of a
   silhouette or rim are counted apart (the chord or the rim rule). */
static void test_stress_curvy(void)
{
    static const float shapes[3][16] = {
        {0.0f, 0.0f, 0.0f, 0.04f, 0.5f, 1.5f, 0.3f, 0.04f, 0.5f, -1.5f, -0.3f, 0.04f, 1.0f, 0.0f, 0.0f, 0.04f},
        {0.0f, 0.0f, 0.0f, 0.05f, 1.5f, 1.0f, 0.1f, 0.04f, -0.5f, 1.0f, -0.1f, 0.03f, 1.0f, 0.0f, 0.0f, 0.02f},
        {0.0f, 0.0f, 0.0f, 0.05f, 0.3f, 1.0f, 0.0f, 0.06f, 0.7f, -1.0f, 0.2f, 0.05f, 1.0f, 0.1f, 0.0f, 0.04f},
    };
    static const stress_kept kept[] = {
        {0, {-0x1.063e1ap+1f, -0x1.db975ep-1f, 0x1.e4b444p-2f}, {0x1.233d7ap+0f, 0x1.b25d16p-3f, -0x1.b6de7ap-3f}},
    };
    stress_count n;
    uint64_t state = 3503;
    int shape;
    memset(&n, 0, sizeof n);
    n.name = "very curvy segments (zig-zag, loop-like S, wave)";
    for (shape = 0; shape < 3; ++shape) {
        hairobb_bvh *bvh;
        ref_scene *reference;
        size_t i;
        if (!stress_single(shapes[shape], &bvh, &reference, n.name)) continue;
        n.rim = shapes[shape];
        stress_segment_rays(bvh, reference, shapes[shape], 1400, 0.0, 1.0, 1.5, &state, &n);
        for (i = 0; i < 600; ++i) {
            float org[3], dir[3];
            int k;
            for (k = 0; k < 3; ++k) {
                org[k] = (float)(3.0 * lcg64_double(&state) - 1.0);
                dir[k] = (float)(1.2 * lcg64_double(&state) - 0.1 - org[k]);
            }
            stress_ray(bvh, reference, org, dir, 0.0f, &n);
        }
        stress_kept_rays(kept, sizeof kept / sizeof kept[0], shape, bvh, reference, &n);
        hairobb_free(bvh);
        ref_free(reference);
    }
    stress_report(&n, 1);
}

/* Strands given in another basis (B-spline or Catmull-Rom): STRAND_COUNT
   strands of STRAND_POINTS points, segment j of strand s at point s *
   STRAND_POINTS + j. Every coordinate and radius is a multiple of 3 * 2^-16,
   so that the conversion to Bezier (divisions by 6 and 3) is exact in float
   as in double: the library's converted points and the reference's are the
   same floats, and consecutive segments share their joint point and
   exactly parallel tangents, so the reference's tube has no crack of its
   own at a joint (rounded points would leave one about 1e-6 r wide). */
#define STRAND_COUNT 3
#define STRAND_POINTS 8
#define STRAND_SEGMENTS (STRAND_POINTS - 3)

static float stress_on_grid(double x) { return (float)(3.0 * 0x1p-16 * floor(x / (3.0 * 0x1p-16) + 0.5)); }

static void stress_strands(float points[STRAND_COUNT * STRAND_POINTS * 4], uint32_t indices[STRAND_COUNT * STRAND_SEGMENTS])
{
    int s, j;
    for (s = 0; s < STRAND_COUNT; ++s) {
        for (j = 0; j < STRAND_POINTS; ++j) {
            float *p = points + 4 * (s * STRAND_POINTS + j);
            p[0] = stress_on_grid(0.8 * s + 0.25 * sin(0.9 * j + s));
            p[1] = stress_on_grid(0.45 * j);
            p[2] = stress_on_grid(0.2 * cos(0.7 * j + 2.0 * s));
            p[3] = stress_on_grid(0.05 + 0.015 * sin(1.7 * j + s));
        }
        for (j = 0; j < STRAND_SEGMENTS; ++j) indices[s * STRAND_SEGMENTS + j] = (uint32_t)(s * STRAND_POINTS + j);
    }
}

/* The segments' Bezier control points, converted in double (the brief's
   formulas) and stored as float; returns how many were inexact (0 on the
   grid). */
static size_t stress_to_bezier(hairobb_basis basis, const float *points, const uint32_t *indices, size_t segments, float *bezier)
{
    size_t i, inexact = 0;
    int k, j;
    for (i = 0; i < segments; ++i) {
        const float *p = points + 4 * (size_t)indices[i];
        for (k = 0; k < 4; ++k) {
            double p0 = p[k], p1 = p[4 + k], p2 = p[8 + k], p3 = p[12 + k], b[4];
            if (basis == HAIROBB_BASIS_BSPLINE) {
                b[0] = (p0 + 4.0 * p1 + p2) / 6.0;
                b[1] = (4.0 * p1 + 2.0 * p2) / 6.0;
                b[2] = (2.0 * p1 + 4.0 * p2) / 6.0;
                b[3] = (p1 + 4.0 * p2 + p3) / 6.0;
            } else {
                b[0] = p1;
                b[1] = p1 + (p2 - p0) / 6.0;
                b[2] = p2 - (p3 - p1) / 6.0;
                b[3] = p2;
            }
            for (j = 0; j < 4; ++j) {
                bezier[16 * i + 4 * j + k] = (float)b[j];
                inexact += (double)(float)b[j] != b[j];
            }
        }
    }
    return inexact;
}

/* The joint at the end of a Bezier segment (16 floats): its point, radius,
   unit tangent, and n1, n2 spanning the plane of its circle, the seam. */
static void stress_seam(const float *cp, double joint[3], double *radius, double tangent[3], double n1[3], double n2[3])
{
    double length;
    int k;
    stress_bezier(cp, 1.0, joint, radius, tangent, NULL);
    length = sqrt(ref__dot3(tangent, tangent));
    for (k = 0; k < 3; ++k) tangent[k] /= length;
    n1[0] = -tangent[1];
    n1[1] = tangent[0];
    n1[2] = 0.0;
    length = sqrt(ref__dot3(n1, n1));
    for (k = 0; k < 3; ++k) n1[k] /= length;
    ref__cross3(tangent, n1, n2);
}

/* 2. Rays through the smooth joints of B-spline and Catmull-Rom strands
   (options.basis; the reference on the segments converted to Bezier). At
   each joint (the end of one segment, the start of the next): rays aimed
   within 1.2 r of the joint point from random directions; rays aimed at the
   seam (the joint's circle, where one segment's tube ends and the next
   begins) from random directions, and at it from outside at 10-60 degrees
   to the fibre; and rays from inside on the axis out through the seam. Any
   disagreement away from a silhouette, a ray through the seam that hits
   neither segment for one of the two, is a crack. */
static void test_stress_joints(void)
{
    enum { RAYS_PER_JOINT = 240 };
    static float points[STRAND_COUNT * STRAND_POINTS * 4], bezier[STRAND_COUNT * STRAND_SEGMENTS * 16];
    static uint32_t indices[STRAND_COUNT * STRAND_SEGMENTS], bezier_indices[STRAND_COUNT * STRAND_SEGMENTS];
    const size_t segments = STRAND_COUNT * STRAND_SEGMENTS;
    int b;
    stress_strands(points, indices);
    for (b = 0; b < 2; ++b) {
        hairobb_basis basis = b ? HAIROBB_BASIS_CATMULL_ROM : HAIROBB_BASIS_BSPLINE;
        hairobb_build_options o;
        hairobb_bvh *bvh = NULL;
        ref_scene *reference;
        stress_count n;
        uint64_t state = 3502 + (uint64_t)b;
        size_t by_kind[4] = {0, 0, 0, 0}, failed;
        size_t i, inexact = stress_to_bezier(basis, points, indices, segments, bezier);
        memset(&n, 0, sizeof n);
        n.name = b ? "Catmull-Rom joints" : "B-spline joints";
        for (i = 0; i < segments; ++i) bezier_indices[i] = (uint32_t)(4 * i);
        CHECK(inexact == 0, "stress %s: %zu control points not exact in float", n.name, inexact);
        memset(&o, 0, sizeof o);
        o.shape = HAIROBB_SHAPE_ROUND;
        o.basis = basis;
        reference = ref_build(bezier, 4 * segments, bezier_indices, segments);
        CHECK(hairobb_build(points, STRAND_COUNT * STRAND_POINTS, indices, segments, &o, &bvh) == HAIROBB_OK && reference,
              "stress %s: builds", n.name);
        for (i = 0; bvh && reference && i < segments; ++i) {
            const float *cp = bezier + 16 * i, *next = cp + 16;
            double joint[3], radius, tangent[3], n1[3], n2[3];
            size_t r;
            int k;
            if (i % STRAND_SEGMENTS == STRAND_SEGMENTS - 1) continue;   /* a strand's tip, no joint */
            CHECK(memcmp(cp + 12, next, 16) == 0, "stress %s: segment %zu ends where the next begins", n.name, i);
            stress_seam(cp, joint, &radius, tangent, n1, n2);
            for (r = 0; r < RAYS_PER_JOINT; ++r) {
                double aim[3], a = 6.283185307179586 * lcg64_double(&state), outward[3], d[3];
                float org[3], dir[3];
                int kind = (int)(r % 4);
                for (k = 0; k < 3; ++k) {
                    outward[k] = cos(a) * n1[k] + sin(a) * n2[k];
                    aim[k] = joint[k] + radius * outward[k];
                }
                if (kind == 0) {   /* near the joint */
                    stress_ball(&state, 1.2 * radius, d);
                    for (k = 0; k < 3; ++k) aim[k] = joint[k] + d[k];
                    stress_aimed(&state, aim, 2.0, org, dir);
                } else if (kind == 1) {   /* at the seam, any direction */
                    stress_aimed(&state, aim, 2.0, org, dir);
                } else if (kind == 2) {   /* at the seam from outside, 10 to 60 degrees to the fibre, either way along it */
                    double angle = (10.0 + 50.0 * lcg64_double(&state)) * 3.141592653589793 / 180.0, along = r & 4 ? 1.0 : -1.0;
                    for (k = 0; k < 3; ++k) {
                        d[k] = along * cos(angle) * tangent[k] - sin(angle) * outward[k];
                        org[k] = (float)(aim[k] - 1.0 * d[k]);
                        dir[k] = (float)d[k];
                    }
                } else {   /* from the axis inside, out through the seam */
                    double back = (r & 4 ? 1.0 : -1.0) * radius * (0.2 + 1.5 * lcg64_double(&state));
                    for (k = 0; k < 3; ++k) {
                        org[k] = (float)(joint[k] + back * tangent[k]);
                        dir[k] = (float)(aim[k] - (double)org[k]);
                    }
                }
                failed = n.disagree + n.t_bad;
                stress_ray(bvh, reference, org, dir, 0.0f, &n);
                by_kind[kind] += n.disagree + n.t_bad - failed;
            }
        }
        stress_report(&n, 1);
        if (n.disagree + n.t_bad)
            printf("  stress %s: failures by ray: near the joint %zu; at the seam: from any direction %zu, at 10-60 degrees %zu, "
                   "from inside %zu\n", n.name, by_kind[0], by_kind[1], by_kind[2], by_kind[3]);
        hairobb_free(bvh);
        ref_free(reference);
    }
}

/* 4. Motion: a round BVH of moving hair (time_steps 2): MOTION_STRANDS
   strands of MOTION_SEGMENTS Bezier segments (sharing their joint points),
   which move by several radii, bend and thicken between times 0 and 1.
   At each of several ray times, rays aimed at the hair as it is then,
   against the reference on the control points lerped to that time
   (ref_motion_points). The hair at time 0 is traced too, against the same
   rays, to show the rays tell the times apart. */
#define MOTION_STRANDS 6
#define MOTION_SEGMENTS 3
#define MOTION_POINTS (3 * MOTION_SEGMENTS + 1)

static void test_stress_motion(void)
{
    enum { TIMES = 8, RAYS_PER_TIME = 100 };
    static const float times[TIMES] = {0.0f, 1.0f, 0.5f, 0.25f, 0.8125f, 0.1f, 0.637f, 0.999f};
    static float steps[2][MOTION_STRANDS * MOTION_POINTS * 4], lerped[MOTION_STRANDS * MOTION_POINTS * 4];
    static uint32_t indices[MOTION_STRANDS * MOTION_SEGMENTS];
    const size_t segments = MOTION_STRANDS * MOTION_SEGMENTS, vertex_count = MOTION_STRANDS * MOTION_POINTS;
    const float *step_pointers[2];
    hairobb_build_options o;
    hairobb_bvh *bvh = NULL;
    ref_scene *at_zero;
    stress_count n;
    uint64_t state = 3504;
    size_t i, differ_from_zero = 0;
    int s, j, t;
    memset(&n, 0, sizeof n);
    n.name = "motion (time_steps 2, rays at 8 times)";
    for (s = 0; s < MOTION_STRANDS; ++s) {
        for (j = 0; j < MOTION_POINTS; ++j) {
            double y = 0.12 * j, a = 0.7 * j + s;
            float *p0 = steps[0] + 4 * (s * MOTION_POINTS + j), *p1 = steps[1] + 4 * (s * MOTION_POINTS + j);
            p0[0] = (float)(0.4 * s + 0.08 * sin(a));
            p0[1] = (float)y;
            p0[2] = (float)(0.08 * cos(a));
            p0[3] = (float)(0.03 - 0.0015 * j);
            /* time 1: swept sideways by up to 0.3 (10 radii) with the height, turned, and thicker */
            p1[0] = (float)(0.4 * s + 0.3 * y * y + 0.1 * sin(a + 1.0));
            p1[1] = (float)(y - 0.05 * y * y);
            p1[2] = (float)(0.1 * cos(a + 1.0) - 0.15 * y);
            p1[3] = (float)(0.045 - 0.002 * j);
        }
        for (j = 0; j < MOTION_SEGMENTS; ++j) indices[s * MOTION_SEGMENTS + j] = (uint32_t)(s * MOTION_POINTS + 3 * j);
    }
    step_pointers[0] = steps[0];
    step_pointers[1] = steps[1];
    memset(&o, 0, sizeof o);
    o.shape = HAIROBB_SHAPE_ROUND;
    o.time_steps = 2;
    o.time_vertices = step_pointers;
    at_zero = ref_build(steps[0], vertex_count, indices, segments);
    CHECK(hairobb_build(NULL, vertex_count, indices, segments, &o, &bvh) == HAIROBB_OK && at_zero, "stress %s: builds", n.name);
    for (t = 0; bvh && at_zero && t < TIMES; ++t) {
        ref_scene *reference;
        ref_motion_points(step_pointers, 2, times[t], 0, 4 * vertex_count, lerped);
        reference = ref_build(lerped, vertex_count, indices, segments);
        CHECK(reference != NULL, "stress %s: the reference at time %g builds", n.name, (double)times[t]);
        for (i = 0; reference && i < RAYS_PER_TIME; ++i) {
            size_t prim = (size_t)(lcg64_double(&state) * (double)segments);
            double u = lcg64_double(&state), aim[3], offset[3], radius;
            float org[3], dir[3];
            ref_tube_hit now, then;
            int k, hit_now, hit_then;
            stress_bezier(lerped + 4 * (size_t)indices[prim], u, aim, &radius, NULL, NULL);
            stress_ball(&state, 1.5 * radius, offset);
            for (k = 0; k < 3; ++k) aim[k] += offset[k];
            stress_aimed(&state, aim, 3.0, org, dir);
            stress_ray(bvh, reference, org, dir, times[t], &n);
            hit_now = ref_tube_intersect_scene(reference, org, dir, 0.0, INFINITY, &now);
            hit_then = ref_tube_intersect_scene(at_zero, org, dir, 0.0, INFINITY, &then);
            differ_from_zero += hit_now != hit_then || (hit_now && fabs(now.t - then.t) > 1e-2 * now.r);
        }
        ref_free(reference);
    }
    stress_report(&n, 1);
    printf("stress %s: the hair at time 0 would answer %zu of the %zu rays otherwise\n", n.name, differ_from_zero, n.rays);
    CHECK(differ_from_zero > n.rays / 2, "stress %s: only %zu of %zu rays tell the times apart", n.name, differ_from_zero, n.rays);
    hairobb_free(bvh);
    ref_free(at_zero);
}

/* 5. Secondary rays from the surface at the joints of B-spline strands
   (hairobb_intersect1_from with the hit they leave): rays aimed within 0.8 r
   of a joint point from random directions; from each entry hit, a ray on
   into the fibre must find its far side (the reference's first exit after
   the entry, on any segment of the strand) and occluded1_from must see it;
   a ray reflected outward must not hit its own strand within 2 r, unless
   the reference has it re-entering there too (a grazing ray on the inside
   of a bend). Rays whose chord is under 0.09 r (within 1e-3 r of a
   silhouette) are counted apart. */
static void test_stress_secondary_at_joints(void)
{
    enum { RAYS_PER_JOINT = 240 };
    static float points[STRAND_COUNT * STRAND_POINTS * 4], bezier[STRAND_COUNT * STRAND_SEGMENTS * 16];
    static uint32_t indices[STRAND_COUNT * STRAND_SEGMENTS], bezier_indices[STRAND_COUNT * STRAND_SEGMENTS];
    const size_t segments = STRAND_COUNT * STRAND_SEGMENTS;
    const char *name = "secondary rays at B-spline joints";
    hairobb_build_options o;
    hairobb_bvh *bvh = NULL;
    ref_scene *reference;
    uint64_t state = 3505;
    size_t i, rays = 0, primary_bad = 0, seam_missed = 0, edge = 0, inward = 0, inward_bad = 0, outward = 0, outward_self = 0, reentries = 0, printed = 0;
    double worst_inward = 0.0;
    stress_strands(points, indices);
    CHECK(stress_to_bezier(HAIROBB_BASIS_BSPLINE, points, indices, segments, bezier) == 0, "stress %s: exact control points", name);
    for (i = 0; i < segments; ++i) bezier_indices[i] = (uint32_t)(4 * i);
    memset(&o, 0, sizeof o);
    o.shape = HAIROBB_SHAPE_ROUND;
    o.basis = HAIROBB_BASIS_BSPLINE;
    reference = ref_build(bezier, 4 * segments, bezier_indices, segments);
    CHECK(hairobb_build(points, STRAND_COUNT * STRAND_POINTS, indices, segments, &o, &bvh) == HAIROBB_OK && reference, "stress %s: builds",
          name);
    for (i = 0; bvh && reference && i < segments; ++i) {
        double joint[3], radius, tangent[3], n1[3], n2[3];
        size_t r;
        if (i % STRAND_SEGMENTS == STRAND_SEGMENTS - 1) continue;
        stress_seam(bezier + 16 * i, joint, &radius, tangent, n1, n2);
        for (r = 0; r < RAYS_PER_JOINT; ++r) {
            double aim[3], offset[3], dir_length, far_side = -1.0;
            hairobb_ray ray, next, out;
            hairobb_hit hit, exit_hit, again;
            ref_tube_hit want;
            ref__ray rr;
            int k, got, expected;
            size_t j, strand;
            if (r % 3 == 0) {   /* within 0.8 r of the joint point */
                stress_ball(&state, 0.8 * radius, offset);
                for (k = 0; k < 3; ++k) aim[k] = joint[k] + offset[k];
                stress_aimed(&state, aim, 2.0, ray.org, ray.dir);
            } else if (r % 3 == 1) {   /* shallow: at 5-30 degrees to the fibre, passing r (1 - delta) from its axis */
                double a = 6.283185307179586 * lcg64_double(&state), e[3], f[3], closest[3];
                double angle = (5.0 + 25.0 * lcg64_double(&state)) * 3.141592653589793 / 180.0;
                double delta = 2e-3 * pow(25.0, lcg64_double(&state)), along = (lcg64_double(&state) - 0.5) * radius;
                double sense = lcg64_double(&state) < 0.5 ? -1.0 : 1.0;
                for (k = 0; k < 3; ++k) e[k] = cos(a) * n1[k] + sin(a) * n2[k];
                ref__cross3(tangent, e, f);
                for (k = 0; k < 3; ++k) {
                    double d = sense * cos(angle) * tangent[k] + sin(angle) * f[k];
                    closest[k] = joint[k] + along * tangent[k] + radius * (1.0 - delta) * e[k];
                    ray.org[k] = (float)(closest[k] - d);
                    ray.dir[k] = (float)d;
                }
            } else {   /* into the seam from outside */
                double a = 6.283185307179586 * lcg64_double(&state), outward[3], d[3], scale = 0.5 + 1.5 * lcg64_double(&state), flip;
                for (k = 0; k < 3; ++k) outward[k] = cos(a) * n1[k] + sin(a) * n2[k];
                do stress_direction(&state, d); while (fabs(ref__dot3(d, outward)) < 0.03);   /* not within 1.7 degrees of grazing */
                flip = ref__dot3(d, outward) > 0.0 ? -1.0 : 1.0;
                for (k = 0; k < 3; ++k) {
                    ray.org[k] = (float)(joint[k] + radius * outward[k] - 2.0 * flip * d[k]);
                    ray.dir[k] = (float)(scale * flip * d[k]);
                }
            }
            ray.tnear = 0.0f;
            ray.tfar = INFINITY;
            ray.time = 0.0f;
            ++rays;
            got = hairobb_intersect1(bvh, &ray, &hit);
            expected = ref_tube_intersect_scene(reference, ray.org, ray.dir, 0.0, INFINITY, &want);
            dir_length = sqrt((double)ray.dir[0] * ray.dir[0] + (double)ray.dir[1] * ray.dir[1] + (double)ray.dir[2] * ray.dir[2]);
            if (expected && stress_silhouette(reference, &want, ray.org, ray.dir)) {
                ++edge;
                continue;
            }
            if (got != expected || (got && fabs((double)hit.t - want.t) * dir_length > 2e-3 * want.r + 1e-6 * want.t)) {
                /* the reference's first hit on the seam (u 0 or 1) that hairobb misses: a crack, the joints check's (2) */
                if (expected && (want.u <= 1e-6 || want.u >= 1.0 - 1e-6)) {
                    ++seam_missed;
                } else if (primary_bad++ < 3) {
                    printf("  stress %s: org %a %a %a dir %a %a %a: reference %d (prim %u t %.9g u %.6f exit %d), hairobb %d (prim %u t "
                           "%.9g u %.6f)\n", name, (double)ray.org[0], (double)ray.org[1], (double)ray.org[2], (double)ray.dir[0],
                           (double)ray.dir[1], (double)ray.dir[2], expected, expected ? want.prim_id : 0u, expected ? want.t : 0.0,
                           expected ? want.u : 0.0, expected ? want.exit : 0, got, got ? hit.prim_id : 0u, got ? (double)hit.t : 0.0,
                           got ? (double)hit.u : 0.0);
                }
                continue;
            }
            if (!got || want.exit) continue;
            strand = want.prim_id / STRAND_SEGMENTS;   /* (the ray may meet another strand first) */
            /* the reference's far side: the first exit after the entry, on the strand's segments */
            ref__ray_setup(&rr, ray.org, ray.dir);
            for (j = strand * STRAND_SEGMENTS; j < (strand + 1) * STRAND_SEGMENTS; ++j) {
                ref_tube_hit all[REF_TUBE_MAX_ROOTS], first;
                int count = 0, m;
                ref_tube_segment_hit(&rr, bezier + 16 * j, 0.0, INFINITY, &first, all, &count);
                for (m = 0; m < count; ++m)
                    if (all[m].exit && all[m].t > want.t && (far_side < 0.0 || all[m].t < far_side)) far_side = all[m].t;
            }
            for (k = 0; k < 3; ++k) {
                next.org[k] = ray.org[k] + hit.t * ray.dir[k];
                next.dir[k] = ray.dir[k];
            }
            next.tnear = 0.0f;
            next.tfar = INFINITY;
            next.time = 0.0f;
            if (far_side < 0.0 || (far_side - want.t) * dir_length < 0.09 * want.r) {
                ++edge;   /* the chord of a ray within 1e-3 r of the silhouette */
            } else {
                double expected_t = far_side - (double)hit.t;   /* from hairobb's entry, where the new ray starts */
                int found = hairobb_intersect1_from(bvh, &hit, &next, &exit_hit), sees = hairobb_occluded1_from(bvh, &hit, &next);
                ++inward;
                if (!found || !sees || dot3f(exit_hit.Ng, next.dir) <= 0.0f ||
                    fabs((double)exit_hit.t - expected_t) * dir_length > 2e-3 * want.r + 1e-6 * far_side) {
                    ++inward_bad;
                    if (printed++ < 3)
                        printf("  stress %s: into the fibre from the hit of org %a %a %a dir %a %a %a (prim %u t %.9g): found %d "
                               "(prim %u t %.9g, exit %d), occluded %d; the reference's far side at t %.9g from the entry\n",
                               name, (double)ray.org[0], (double)ray.org[1], (double)ray.org[2], (double)ray.dir[0], (double)ray.dir[1],
                               (double)ray.dir[2], hit.prim_id, (double)hit.t, found, found ? exit_hit.prim_id : 0u,
                               found ? (double)exit_hit.t : 0.0, found ? dot3f(exit_hit.Ng, next.dir) > 0.0f : 0, sees, expected_t);
                } else {
                    double e = fabs((double)exit_hit.t - expected_t) * dir_length / want.r;
                    worst_inward = e > worst_inward ? e : worst_inward;
                }
            }
            /* reflected outward */
            out = next;
            {
                double dn = ray.dir[0] * hit.Ng[0] + ray.dir[1] * hit.Ng[1] + ray.dir[2] * hit.Ng[2], out_length;
                for (k = 0; k < 3; ++k) out.dir[k] = (float)(ray.dir[k] - 2.0 * dn * hit.Ng[k]);
                out_length = sqrt((double)out.dir[0] * out.dir[0] + (double)out.dir[1] * out.dir[1] + (double)out.dir[2] * out.dir[2]);
                ++outward;
                if (hairobb_intersect1_from(bvh, &hit, &out, &again) && again.prim_id / STRAND_SEGMENTS == strand &&
                    (double)again.t * out_length < 2.0 * want.r) {
                    /* the reference: an entry there on the strand, past the start */
                    int confirmed = 0;
                    ref__ray_setup(&rr, out.org, out.dir);
                    for (j = strand * STRAND_SEGMENTS; j < (strand + 1) * STRAND_SEGMENTS; ++j) {
                        ref_tube_hit all[REF_TUBE_MAX_ROOTS], first;
                        int count = 0, m;
                        ref_tube_segment_hit(&rr, bezier + 16 * j, 0.0, INFINITY, &first, all, &count);
                        for (m = 0; m < count; ++m)
                            confirmed |= !all[m].exit && all[m].t * out_length > 1e-2 * want.r &&
                                         fabs(all[m].t - (double)again.t) * out_length <= 2e-3 * want.r + 1e-6 * all[m].t;
                    }
                    if (confirmed) {
                        ++reentries;
                    } else {
                        ++outward_self;
                        if (printed++ < 3)
                            printf("  stress %s: reflected from the hit of org %a %a %a dir %a %a %a (prim %u t %.9g): hits prim %u at "
                                   "t %.9g\n", name, (double)ray.org[0], (double)ray.org[1], (double)ray.org[2], (double)ray.dir[0],
                                   (double)ray.dir[1], (double)ray.dir[2], hit.prim_id, (double)hit.t, again.prim_id, (double)again.t);
                    }
                }
            }
        }
    }
    printf("stress %s: %zu rays, %zu disagree with the reference (%zu more miss its hit on a seam, left to the joints check), %zu within "
           "1e-3 r of a silhouette; into the fibre %zu, %zu without its far side (worst |dt|/r %.3g); reflected %zu, %zu back on their "
           "strand within 2 r (%zu re-entering as the reference does)\n",
           name, rays, primary_bad, seam_missed, edge, inward, inward_bad, worst_inward, outward, outward_self, reentries);
    CHECK(primary_bad == 0 && edge <= rays / 100 && inward > rays / 2 && inward_bad == 0 && outward_self == 0,
          "stress %s: %zu disagree, %zu at a silhouette, %zu of %zu into the fibre miss its far side, %zu of %zu reflected hit their strand",
          name, primary_bad, edge, inward_bad, inward, outward_self, outward);
    hairobb_free(bvh);
    ref_free(reference);
}

/* End caps (end_caps ON) and back-face culling (back_faces OFF) against the
   reference: 3 strands of 4 smooth Bezier segments (shared joint points,
   matching tangents), tapered; rays into each free end from outside, out
   of it from inside, and oblique rays near it. The reference takes every
   sheet hit of every segment and a cap at each strand's two free ends
   (never at the joints); culling keeps entries only. A ray whose hit or
   miss changes with r scaled by 1 -/+ 1e-3 is a silhouette or rim ray,
   decided by rounding, and is counted apart. */
#define CAP_STRANDS 3
#define CAP_SEGMENTS 4

static int cap_reference(const float *v, size_t segments, const float org[3], const float dir[3], int caps, int cull,
                         ref_tube_hit *best)
{
    ref__ray ray;
    size_t i;
    int found = 0, j, count, end;
    ref__ray_setup(&ray, org, dir);
    for (i = 0; i < segments; ++i) {
        ref_tube_hit all[REF_TUBE_MAX_ROOTS + 2], first;
        ref_tube_segment_hit(&ray, v + 16 * i, 0.0, INFINITY, &first, all, &count);
        for (end = 0; end < 2 && caps; ++end)
            if ((end == 0 && i % CAP_SEGMENTS == 0) || (end == 1 && i % CAP_SEGMENTS == CAP_SEGMENTS - 1))
                count += ref_tube_cap_hit(&ray, v + 16 * i, end, 0.0, INFINITY, &all[count]);
        for (j = 0; j < count; ++j) {
            if (cull && all[j].exit) continue;
            if (found && !(all[j].t < best->t)) continue;
            *best = all[j];
            best->prim_id = (uint32_t)i;
            found = 1;
        }
    }
    return found;
}

static void test_caps_and_back_faces(void)
{
    enum { RAYS_PER_END = 2000 };
    static float v[CAP_STRANDS * CAP_SEGMENTS * 16], scaled[2][CAP_STRANDS * CAP_SEGMENTS * 16];
    static uint32_t idx[CAP_STRANDS * CAP_SEGMENTS];
    size_t segments = CAP_STRANDS * CAP_SEGMENTS, i;
    int strand, k, mode;
    uint64_t state = 777;
    for (strand = 0; strand < CAP_STRANDS; ++strand) {
        float joint[CAP_SEGMENTS + 1][4], handle[CAP_SEGMENTS + 1][3];
        int j;
        for (j = 0; j <= CAP_SEGMENTS; ++j) {
            double a = 0.9 * j + strand;
            joint[j][0] = (float)(0.6 * strand + 0.15 * sin(a));
            joint[j][1] = (float)(0.5 * j);
            joint[j][2] = (float)(0.15 * cos(1.3 * a));
            joint[j][3] = (float)(0.06 - 0.0075 * j);
            handle[j][0] = (float)(0.05 * cos(a));
            handle[j][1] = 0.17f;
            handle[j][2] = (float)(-0.06 * sin(1.3 * a));
        }
        for (j = 0; j < CAP_SEGMENTS; ++j) {
            float *p = v + 16 * (size_t)(strand * CAP_SEGMENTS + j);
            for (k = 0; k < 3; ++k) {
                p[k] = joint[j][k];
                p[4 + k] = joint[j][k] + handle[j][k];
                p[8 + k] = joint[j + 1][k] - handle[j + 1][k];
                p[12 + k] = joint[j + 1][k];
            }
            p[3] = joint[j][3];
            p[7] = (2.0f * joint[j][3] + joint[j + 1][3]) / 3.0f;
            p[11] = (joint[j][3] + 2.0f * joint[j + 1][3]) / 3.0f;
            p[15] = joint[j + 1][3];
        }
    }
    for (i = 0; i < segments; ++i) idx[i] = (uint32_t)(4 * i);
    for (i = 0; i < 16 * segments; ++i) {
        scaled[0][i] = v[i] * ((i & 3) == 3 ? (float)(1.0 - 1e-3) : 1.0f);
        scaled[1][i] = v[i] * ((i & 3) == 3 ? (float)(1.0 + 1e-3) : 1.0f);
    }
    /* mode 0: caps; 1: caps, back faces culled; 2: open ends, back faces culled */
    for (mode = 0; mode < 3; ++mode) {
        hairobb_build_options o;
        hairobb_bvh *bvh = NULL;
        size_t rays = 0, hits = 0, cap_hits = 0, disagree = 0, edge = 0, t_bad = 0, attr_bad = 0, exits_seen = 0;
        int caps = mode < 2, cull = mode > 0;
        memset(&o, 0, sizeof o);
        o.shape = HAIROBB_SHAPE_ROUND;
        o.end_caps = caps ? HAIROBB_ON : HAIROBB_AUTO;
        o.back_faces = cull ? HAIROBB_OFF : HAIROBB_AUTO;
        CHECK(hairobb_build(v, 4 * segments, idx, segments, &o, &bvh) == HAIROBB_OK, "caps %d: builds", mode);
        if (!bvh) continue;
        for (strand = 0; strand < CAP_STRANDS; ++strand) {
            int end;
            for (end = 0; end < 2; ++end) {
                const float *p = v + 16 * (size_t)(strand * CAP_SEGMENTS + (end ? CAP_SEGMENTS - 1 : 0));
                double E[3], T[3], len = 0.0, r = p[12 * end + 3];
                for (k = 0; k < 3; ++k) {
                    E[k] = p[12 * end + k];
                    T[k] = end ? p[12 + k] - p[8 + k] : p[k] - p[4 + k];   /* outward */
                    len += T[k] * T[k];
                }
                len = sqrt(len);
                for (k = 0; k < 3; ++k) T[k] /= len;
                for (i = 0; i < RAYS_PER_END; ++i) {
                    float org[3], dir[3];
                    int kind = (int)(i % 3), got, want, lo, hi;
                    ref_tube_hit expected, thin, fat;
                    hairobb_ray ray;
                    double dir_length;
                    hairobb_hit hit;
                    for (k = 0; k < 3; ++k) {
                        double jitter = 2.0 * lcg64_double(&state) - 1.0, wobble = 2.0 * lcg64_double(&state) - 1.0;
                        if (kind == 0) {          /* into the end from outside, nearly along the strand */
                            org[k] = (float)(E[k] + 0.5 * T[k] + 1.3 * r * jitter);
                            dir[k] = (float)(-T[k] + 0.25 * wobble);
                        } else if (kind == 1) {   /* out through it from inside */
                            org[k] = (float)(E[k] - 2.0 * r * T[k] + 0.4 * r * jitter);
                            dir[k] = (float)(T[k] + 0.3 * wobble);
                        } else {                  /* oblique, near the end */
                            org[k] = (float)(E[k] + 1.5 * jitter);
                            dir[k] = (float)(E[k] + 1.5 * r * wobble - org[k]);
                        }
                    }
                    memcpy(ray.org, org, sizeof ray.org);
                    memcpy(ray.dir, dir, sizeof ray.dir);
                    ray.tnear = 0.0f;
                    ray.tfar = INFINITY;
                    ray.time = 0.0f;
                    got = hairobb_intersect1(bvh, &ray, &hit);
                    lo = cap_reference(scaled[0], segments, org, dir, caps, cull, &thin);
                    hi = cap_reference(scaled[1], segments, org, dir, caps, cull, &fat);
                    want = cap_reference(v, segments, org, dir, caps, cull, &expected);
                    dir_length = sqrt((double)dir[0] * dir[0] + (double)dir[1] * dir[1] + (double)dir[2] * dir[2]);
                    /* the thin and the fat hair disagree: the ray passes within 1e-3 r of an edge */
                    if (lo && hi && fabs(thin.t - fat.t) * dir_length > 2e-3 * thin.r) hi = 0;
                    ++rays;
                    hits += (size_t)want;
                    CHECK(hairobb_occluded1(bvh, &ray) == want || lo != hi, "caps %d: occluded1 agrees with the reference", mode);
                    if (got != want) {
                        if (lo != hi) ++edge; else ++disagree;
                        continue;
                    }
                    if (!got) continue;
                    if (fabs((double)hit.t - expected.t) * dir_length > 2e-3 * expected.r + 1e-6 * fabs(expected.t)) {
                        if (lo != hi) ++edge; else ++t_bad;
                        continue;
                    }
                    exits_seen += (size_t)expected.exit;
                    if (expected.u == 0.0 || expected.u == 1.0) {
                        double n_dot = 0.0;
                        int cap_hit = hit.prim_id == expected.prim_id && hit.u == (float)expected.u;
                        for (k = 0; k < 3; ++k) n_dot += hit.Ng[k] * expected.normal[k];
                        cap_hits += (size_t)cap_hit;
                        attr_bad += !cap_hit || !(n_dot > 0.999);
                    }
                }
            }
        }
        printf("caps %d (end caps %s, back faces %s): %zu rays, %zu hit the reference (%zu on caps, %zu exits); %zu disagree, "
               "%zu at a silhouette or rim, %zu with |dt| over 2e-3 r, %zu cap hits with another u or normal\n",
               mode, caps ? "on" : "off", cull ? "culled" : "kept", rays, hits, cap_hits, exits_seen, disagree, edge, t_bad, attr_bad);
        CHECK(disagree == 0 && t_bad == 0 && attr_bad == 0 && edge <= rays / 50 && hits > rays / (cull ? 8 : 3),
              "caps %d: %zu disagree, %zu off in t, %zu bad attributes, %zu at an edge, %zu hits of %zu", mode, disagree, t_bad, attr_bad,
              edge, hits, rays);
        CHECK(caps ? cap_hits > rays / (cull ? 20 : 10) : cap_hits == 0, "caps %d: %zu hits on caps", mode, cap_hits);
        CHECK(cull ? exits_seen == 0 : exits_seen > rays / 20, "caps %d: %zu exits taken", mode, exits_seen);
        /* the options are in the saved file */
        {
            size_t size = hairobb_save_size(bvh), differ = 0;
            void *buffer = malloc(size);
            hairobb_bvh *loaded = NULL;
            CHECK(buffer && hairobb_save(bvh, buffer, size) == HAIROBB_OK &&
                  hairobb_load(buffer, size, v, 4 * segments, idx, segments, NULL, &loaded) == HAIROBB_OK,
                  "caps %d: saves and loads", mode);
            for (i = 0; loaded && i < 4000; ++i) {
                hairobb_ray ray;
                hairobb_hit a, b;
                int ga, gb;
                for (k = 0; k < 3; ++k) {
                    double aim = (k == 0 ? 1.2 : k == 1 ? 2.0 : 0.0) * lcg64_double(&state);
                    ray.org[k] = (float)(4.0 * lcg64_double(&state) - 2.0 + (k == 1 ? 1.0 : 0.0));
                    ray.dir[k] = (float)(aim - ray.org[k]);
                }
                ray.tnear = 0.0f;
                ray.tfar = INFINITY;
                ray.time = 0.0f;
                ga = hairobb_intersect1(bvh, &ray, &a);
                gb = hairobb_intersect1(loaded, &ray, &b);
                differ += !same_hit(ga, &a, gb, &b);
            }
            CHECK(loaded && differ == 0, "caps %d: the loaded BVH gives the same hits (%zu differ)", mode, differ);
            hairobb_free(loaded);
            free(buffer);
        }
        hairobb_free(bvh);
    }
    /* a B-spline strand (its joints are the converted segments' shared
       ends): a ray along the axis from inside, toward either end, meets
       only that end's cap, never one at a joint */
    {
        static float bs[9 * 4];
        static uint32_t bidx[6];
        hairobb_build_options o;
        hairobb_bvh *bvh = NULL;
        size_t wrong = 0, tried = 0;
        for (i = 0; i < 9; ++i) {
            bs[4 * i] = (float)(0.2 * sin(0.7 * (double)i));
            bs[4 * i + 1] = (float)(0.5 * (double)i);
            bs[4 * i + 2] = (float)(0.1 * cos(0.5 * (double)i));
            bs[4 * i + 3] = 0.05f;
        }
        for (i = 0; i < 6; ++i) bidx[i] = (uint32_t)i;
        memset(&o, 0, sizeof o);
        o.shape = HAIROBB_SHAPE_ROUND;
        o.basis = HAIROBB_BASIS_BSPLINE;
        o.end_caps = HAIROBB_ON;
        CHECK(hairobb_build(bs, 9, bidx, 6, &o, &bvh) == HAIROBB_OK, "caps: a B-spline strand builds");
        for (i = 0; bvh && i < 200; ++i) {
            /* the strand's point at knot 1 + s (a joint of segments, or between), and the chord's direction */
            double s = 0.05 + 5.9 * lcg64_double(&state), u = s - floor(s), b[4], c[3] = {0, 0, 0}, d[3] = {0, 0, 0};
            size_t first = (size_t)s;
            hairobb_ray ray;
            hairobb_hit hit;
            int toward_tip = (int)(i & 1);
            b[0] = (1 - u) * (1 - u) * (1 - u) / 6.0;
            b[1] = (3 * u * u * u - 6 * u * u + 4) / 6.0;
            b[2] = (-3 * u * u * u + 3 * u * u + 3 * u + 1) / 6.0;
            b[3] = u * u * u / 6.0;
            for (k = 0; k < 3; ++k) {
                int j;
                for (j = 0; j < 4; ++j) c[k] += b[j] * bs[4 * (first + (size_t)j) + k];
                d[k] = bs[4 * (first + 2) + k] - bs[4 * (first + 1) + k];
                ray.org[k] = (float)c[k];
                ray.dir[k] = (float)(toward_tip ? d[k] : -d[k]);
            }
            ray.tnear = 0.0f;
            ray.tfar = INFINITY;
            ray.time = 0.0f;
            ++tried;
            /* the hit may be a sheet where the strand bends out of the ray's
               way; a cap hit must be the strand's own end */
            if (hairobb_intersect1(bvh, &ray, &hit) && (hit.u == 0.0f || hit.u == 1.0f) &&
                dot3f(hit.Ng, ray.dir) > 0.0f && !(toward_tip ? hit.prim_id == 5 && hit.u == 1.0f : hit.prim_id == 0 && hit.u == 0.0f))
                ++wrong;
        }
        CHECK(tried == 200 && wrong == 0, "caps: rays along a B-spline strand from inside meet no cap at a joint (%zu of %zu did)", wrong,
              tried);
        hairobb_free(bvh);
    }
}

/* A zero-length segment (every control point equal; in the linear basis,
   two equal points) has no circle anywhere: rays through it, on the AVX2
   (where this CPU has it) and SSE2 paths, miss it. A read past a stack array of 8 floats (the inside
   samples' lane 8) once followed the zero g there: make test runs this
   under ASan and UBSan (asan_test_round). */
static void test_zero_length(void)
{
    static const float v[16] = {5, 5, 5, 0.05f, 5, 5, 5, 0.05f, 5, 5, 5, 0.05f, 5, 5, 5, 0.05f};
    static const uint32_t idx[1] = {0};
    static const hairobb_basis bases[2] = {HAIROBB_BASIS_BEZIER, HAIROBB_BASIS_LINEAR};
    static const hairobb_simd paths[2] = {HAIROBB_SIMD_AUTO, HAIROBB_SIMD_SSE2};
    size_t rays = 0, differ = 0, malformed = 0, hits = 0;
    int b, caps, p, i;
    for (b = 0; b < 2; ++b)
        for (caps = 0; caps < 2; ++caps) {
            hairobb_bvh *bvh[2] = {NULL, NULL};
            hairobb_build_options o = hairobb_default_options();
            o.shape = HAIROBB_SHAPE_ROUND;
            o.basis = bases[b];
            o.end_caps = caps ? HAIROBB_ON : HAIROBB_OFF;
            for (p = 0; p < 2; ++p) {
                o.simd = paths[p];
                CHECK(hairobb_build(v, 4, idx, 1, &o, &bvh[p]) == HAIROBB_OK, "zero length, basis %d, caps %d: builds", b, caps);
            }
            for (i = 0; bvh[0] && bvh[1] && i < 400; ++i) {
                /* the issue's ray (0.01 off the point, along z), then others within r of it every way */
                double a = 0.0157 * i, c = cos(a), s = sin(a), off = 0.0001 * (i % 97);
                hairobb_ray ray = {{5.01f, 5.0f, 0.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY, 0.0f};
                hairobb_hit hit[2];
                int got[2];
                if (i > 0) {
                    ray.dir[0] = (float)(c * s);
                    ray.dir[1] = (float)(s * s);
                    ray.dir[2] = (float)c;
                    ray.org[0] = (float)(5.0 + off - 2.0 * ray.dir[0]);
                    ray.org[1] = (float)(5.0 - off - 2.0 * ray.dir[1]);
                    ray.org[2] = (float)(5.0 - 2.0 * ray.dir[2]);
                }
                for (p = 0; p < 2; ++p) got[p] = hairobb_intersect1(bvh[p], &ray, &hit[p]);
                ++rays;
                differ += !same_hit(got[0], &hit[0], got[1], &hit[1]);
                malformed += got[0] && !(isfinite(hit[0].t) && hit[0].t >= 0.0f && hit[0].u >= 0.0f && hit[0].u <= 1.0f);
                hits += (size_t)got[0];
            }
            for (p = 0; p < 2; ++p) hairobb_free(bvh[p]);
        }
    printf("zero-length segments: %zu rays, %zu hits, %zu malformed, %zu differ between AVX2 and SSE2\n", rays, hits, malformed, differ);
    CHECK(rays == 1600 && hits == 0 && malformed == 0 && differ == 0, "zero-length segments: %zu hits, %zu malformed, %zu differ", hits,
          malformed, differ);
}

/* ---- Degenerate tubes: 16 strand shapes (repeated points, cusps,
   zero-length segments inside a strand and at its tip, zero radius, a
   radius larger than the segment, ...) in each of the 5 bases, with end
   caps and back-face culling on and off, traced on the AVX2 (where this CPU
   has it) and SSE2 paths, built anew and refitted onto the shape from a
   regular pose, and saved and loaded. Every path, the refit and the loaded
   BVH must give the same hits bit for bit; hits must be finite with t in
   [tnear, tfar], u in [0, 1] and a unit normal; occluded1 must agree with
   intersect1; with open ends and both sheets, the hits must agree with the
   tube reference on the segments converted to Bezier (as stress_ray
   judges). make test runs this under ASan and UBSan too (asan_test_round):
   a zero-length segment once read past a stack array of 8 floats. */
#define DEGENERATE_POINTS 10
typedef struct degenerate_shape {
    const char *name;
    float p[DEGENERATE_POINTS][4];
} degenerate_shape;

static const degenerate_shape degenerate_shapes[] = {
    {"every point equal", {{5, 5, 5, 0.05f}, {5, 5, 5, 0.05f}, {5, 5, 5, 0.05f}, {5, 5, 5, 0.05f}, {5, 5, 5, 0.05f},
                           {5, 5, 5, 0.05f}, {5, 5, 5, 0.05f}, {5, 5, 5, 0.05f}, {5, 5, 5, 0.05f}, {5, 5, 5, 0.05f}}},
    {"p1 = p2 = p3", {{0, 0, 0, 0.05f}, {0.3f, 0.1f, 0, 0.05f}, {0.3f, 0.1f, 0, 0.05f}, {0.3f, 0.1f, 0, 0.05f}, {0.6f, 0.3f, 0.1f, 0.05f},
                      {0.9f, 0.4f, 0.1f, 0.05f}, {1.2f, 0.4f, 0, 0.05f}, {1.5f, 0.5f, 0, 0.05f}, {1.8f, 0.5f, 0, 0.05f}, {2.1f, 0.6f, 0, 0.05f}}},
    {"cusp, P0 = P3, P1 = P2", {{0, 0, 0, 0.04f}, {1, 0.5f, 0, 0.04f}, {1, 0.5f, 0, 0.04f}, {0, 0, 0, 0.04f}, {-0.3f, 0.2f, 0, 0.04f},
                                {-0.6f, 0.2f, 0.1f, 0.04f}, {-0.9f, 0.3f, 0.1f, 0.04f}, {-1.2f, 0.3f, 0, 0.04f}, {-1.5f, 0.4f, 0, 0.04f},
                                {-1.8f, 0.4f, 0, 0.04f}}},
    {"zero length at the tip", {{0, 0, 0, 0.05f}, {0.3f, 0.1f, 0, 0.05f}, {0.6f, 0.1f, 0.1f, 0.05f}, {0.9f, 0.2f, 0.1f, 0.05f},
                                {1.2f, 0.2f, 0, 0.05f}, {1.5f, 0.3f, 0, 0.05f}, {1.8f, 0.3f, 0, 0.05f}, {1.8f, 0.3f, 0, 0.05f},
                                {1.8f, 0.3f, 0, 0.05f}, {1.8f, 0.3f, 0, 0.05f}}},
    {"zero length inside", {{0, 0, 0, 0.05f}, {0.3f, 0.1f, 0, 0.05f}, {0.6f, 0.1f, 0.1f, 0.05f}, {0.9f, 0.2f, 0.1f, 0.05f},
                            {0.9f, 0.2f, 0.1f, 0.05f}, {0.9f, 0.2f, 0.1f, 0.05f}, {0.9f, 0.2f, 0.1f, 0.05f}, {1.2f, 0.2f, 0, 0.05f},
                            {1.5f, 0.3f, 0, 0.05f}, {1.8f, 0.3f, 0, 0.05f}}},
    {"P0 = P1, P2 = P3", {{0, 0, 0, 0.05f}, {0, 0, 0, 0.05f}, {0.6f, 0.2f, 0.1f, 0.05f}, {0.6f, 0.2f, 0.1f, 0.05f}, {0.9f, 0.3f, 0, 0.05f},
                          {0.9f, 0.3f, 0, 0.05f}, {1.5f, 0.3f, 0.1f, 0.05f}, {1.5f, 0.3f, 0.1f, 0.05f}, {1.8f, 0.4f, 0, 0.05f},
                          {1.8f, 0.4f, 0, 0.05f}}},
    {"zero radius", {{0, 0, 0, 0}, {0.3f, 0.1f, 0, 0}, {0.6f, 0.1f, 0.1f, 0}, {0.9f, 0.2f, 0.1f, 0}, {1.2f, 0.2f, 0, 0}, {1.5f, 0.3f, 0, 0},
                     {1.8f, 0.3f, 0, 0}, {2.1f, 0.4f, 0, 0}, {2.4f, 0.4f, 0, 0}, {2.7f, 0.5f, 0, 0}}},
    {"radius 50x the segment", {{0, 0, 0, 0.5f}, {0.003f, 0.001f, 0, 0.5f}, {0.006f, 0.001f, 0.001f, 0.5f}, {0.009f, 0.002f, 0.001f, 0.5f},
                                {0.012f, 0.002f, 0, 0.5f}, {0.015f, 0.003f, 0, 0.5f}, {0.018f, 0.003f, 0, 0.5f}, {0.021f, 0.004f, 0, 0.5f},
                                {0.024f, 0.004f, 0, 0.5f}, {0.027f, 0.005f, 0, 0.5f}}},
    {"collinear, doubling back", {{0, 0, 0, 0.04f}, {1, 0.5f, 0, 0.04f}, {-0.5f, -0.25f, 0, 0.04f}, {0.5f, 0.25f, 0, 0.04f},
                                  {1.5f, 0.75f, 0, 0.04f}, {0.2f, 0.1f, 0, 0.04f}, {0.9f, 0.45f, 0, 0.04f}, {1.2f, 0.6f, 0, 0.04f},
                                  {0.4f, 0.2f, 0, 0.04f}, {0.8f, 0.4f, 0, 0.04f}}},
    {"taper to 0 at repeated tip", {{0, 0, 0, 0.06f}, {0.3f, 0.1f, 0, 0.05f}, {0.6f, 0.1f, 0.1f, 0.04f}, {0.9f, 0.2f, 0.1f, 0.03f},
                                    {1.2f, 0.2f, 0, 0.02f}, {1.5f, 0.3f, 0, 0.01f}, {1.8f, 0.3f, 0, 0}, {1.8f, 0.3f, 0, 0},
                                    {1.8f, 0.3f, 0, 0}, {1.8f, 0.3f, 0, 0}}},
    {"loop, P0 = P3", {{0, 0, 0, 0.03f}, {0.5f, 0.5f, 0.1f, 0.03f}, {-0.5f, 0.5f, -0.1f, 0.03f}, {0, 0, 0, 0.03f}, {0.3f, -0.2f, 0, 0.03f},
                       {0.6f, -0.2f, 0.1f, 0.03f}, {0.6f, -0.5f, 0.1f, 0.03f}, {0.3f, -0.5f, 0, 0.03f}, {0, -0.3f, 0, 0.03f},
                       {0, 0, 0, 0.03f}}},
    {"length 1e-4, radius 0.05", {{1, 1, 1, 0.05f}, {1.0001f, 1, 1, 0.05f}, {1.0002f, 1, 1, 0.05f}, {1.0003f, 1, 1, 0.05f},
                                  {1.0004f, 1, 1, 0.05f}, {1.0005f, 1, 1, 0.05f}, {1.0006f, 1, 1, 0.05f}, {1.0007f, 1, 1, 0.05f},
                                  {1.0008f, 1, 1, 0.05f}, {1.0009f, 1, 1, 0.05f}}},
    {"repeated points far out", {{1e5f, 1e5f, 1e5f, 0.5f}, {1e5f, 1e5f, 1e5f, 0.5f}, {1e5f, 1e5f, 1e5f, 0.5f}, {1e5f + 3, 1e5f, 1e5f, 0.5f},
                                 {1e5f + 3, 1e5f, 1e5f, 0.5f}, {1e5f + 3, 1e5f, 1e5f, 0.5f}, {1e5f + 6, 1e5f + 1, 1e5f, 0.5f},
                                 {1e5f + 6, 1e5f + 1, 1e5f, 0.5f}, {1e5f + 6, 1e5f + 1, 1e5f, 0.5f}, {1e5f + 6, 1e5f + 1, 1e5f, 0.5f}}},
    {"a kink at a repeated joint", {{0, 0, 0, 0.05f}, {0.3f, 0, 0, 0.05f}, {0.6f, 0, 0, 0.05f}, {0.9f, 0, 0, 0.05f}, {0.9f, 0, 0, 0.05f},
                                    {0.9f, 0.3f, 0, 0.05f}, {0.9f, 0.6f, 0, 0.05f}, {0.9f, 0.9f, 0, 0.05f}, {0.9f, 0.9f, 0, 0.05f},
                                    {0.9f, 0.9f, 0.3f, 0.05f}}},
    {"zero radius at a cusp", {{0, 0, 0, 0.05f}, {1, 0.5f, 0, 0}, {1, 0.5f, 0, 0}, {0, 0, 0, 0.05f}, {0, 0, 0, 0.05f}, {1, 0.5f, 0, 0},
                               {1, 0.5f, 0, 0}, {0, 0, 0, 0.05f}, {0, 0, 0, 0.05f}, {0, 0, 0, 0.05f}}},
    {"two points alternating", {{0, 0, 0, 0.05f}, {0.5f, 0, 0, 0.05f}, {0, 0, 0, 0.05f}, {0.5f, 0, 0, 0.05f}, {0, 0, 0, 0.05f},
                                {0.5f, 0, 0, 0.05f}, {0, 0, 0, 0.05f}, {0.5f, 0, 0, 0.05f}, {0, 0, 0, 0.05f}, {0.5f, 0, 0, 0.05f}}},
};
#define DEGENERATE_SHAPES (sizeof degenerate_shapes / sizeof degenerate_shapes[0])

/* A basis's segments over the shape's points (Bezier: 0, 3, 6; B-spline and
   Catmull-Rom: every 4 in a row; Hermite and linear: every 2 in a row, the
   Hermite tangents the differences of the neighbours), and the same
   segments as Bezier control points (16 floats each) for the reference. */
static size_t degenerate_segments(hairobb_basis basis, const float *points, float *tangents, uint32_t *indices, float *bezier)
{
    size_t n = 0, i;
    int k, j;
    for (i = 0; i < DEGENERATE_POINTS; ++i)
        for (k = 0; k < 4; ++k) {
            size_t a = i == 0 ? 0 : i - 1, b = i + 1 == DEGENERATE_POINTS ? i : i + 1;
            tangents[4 * i + k] = (points[4 * b + k] - points[4 * a + k]) * (b - a == 2 ? 0.5f : 1.0f);
        }
    if (basis == HAIROBB_BASIS_BEZIER)
        for (i = 0; i + 3 < DEGENERATE_POINTS; i += 3) indices[n++] = (uint32_t)i;
    else if (basis == HAIROBB_BASIS_BSPLINE || basis == HAIROBB_BASIS_CATMULL_ROM)
        for (i = 0; i + 3 < DEGENERATE_POINTS; ++i) indices[n++] = (uint32_t)i;
    else
        for (i = 0; i + 1 < DEGENERATE_POINTS; ++i) indices[n++] = (uint32_t)i;
    for (i = 0; i < n; ++i) {
        const float *p = points + 4 * (size_t)indices[i], *d = tangents + 4 * (size_t)indices[i];
        for (k = 0; k < 4; ++k) {
            double c[4];
            if (basis == HAIROBB_BASIS_BEZIER) {
                for (j = 0; j < 4; ++j) c[j] = p[4 * j + k];
            } else if (basis == HAIROBB_BASIS_BSPLINE) {
                c[0] = (p[k] + 4.0 * p[4 + k] + p[8 + k]) / 6.0;
                c[1] = (4.0 * p[4 + k] + 2.0 * p[8 + k]) / 6.0;
                c[2] = (2.0 * p[4 + k] + 4.0 * p[8 + k]) / 6.0;
                c[3] = (p[4 + k] + 4.0 * p[8 + k] + p[12 + k]) / 6.0;
            } else if (basis == HAIROBB_BASIS_CATMULL_ROM) {
                c[0] = p[4 + k];
                c[1] = p[4 + k] + (p[8 + k] - (double)p[k]) / 6.0;
                c[2] = p[8 + k] - (p[12 + k] - (double)p[4 + k]) / 6.0;
                c[3] = p[8 + k];
            } else if (basis == HAIROBB_BASIS_HERMITE) {
                c[0] = p[k];
                c[1] = p[k] + d[k] / 3.0;
                c[2] = p[4 + k] - d[4 + k] / 3.0;
                c[3] = p[4 + k];
            } else {
                for (j = 0; j < 4; ++j) c[j] = p[k] + (p[4 + k] - (double)p[k]) * j / 3.0;
            }
            for (j = 0; j < 4; ++j) bezier[16 * i + 4 * j + k] = (float)c[j];
        }
    }
    return n;
}

/* Whether a hit is well formed: finite fields, t in [tnear, tfar], u in
   [0, 1], a unit normal, a prim id below the segment count. */
static int degenerate_hit_ok(const hairobb_hit *h, const hairobb_ray *ray, size_t segments)
{
    double n2 = (double)h->Ng[0] * h->Ng[0] + (double)h->Ng[1] * h->Ng[1] + (double)h->Ng[2] * h->Ng[2];
    int k, finite = isfinite(h->t) && isfinite(h->u) && isfinite(h->v);
    for (k = 0; k < 3; ++k) finite = finite && isfinite(h->Ng[k]) && isfinite(h->tangent[k]);
    return finite && h->t >= ray->tnear && h->t <= ray->tfar && h->u >= 0.0f && h->u <= 1.0f && h->v >= -1.0f && h->v <= 1.0f &&
           fabs(n2 - 1.0) < 1e-3 && h->prim_id < segments;
}

static void test_stress_degenerate(void)
{
    enum { RAYS = 160 };
    static const hairobb_basis bases[5] = {HAIROBB_BASIS_BEZIER, HAIROBB_BASIS_BSPLINE, HAIROBB_BASIS_CATMULL_ROM, HAIROBB_BASIS_HERMITE,
                                           HAIROBB_BASIS_LINEAR};
    static const hairobb_simd paths[2] = {HAIROBB_SIMD_AUTO, HAIROBB_SIMD_SSE2};
    size_t shape, rays = 0, bad = 0, differ = 0, occluded_differ = 0, built = 0;
    stress_count n;
    uint64_t state = 4242;
    memset(&n, 0, sizeof n);
    n.name = "degenerate tubes";
    for (shape = 0; shape < DEGENERATE_SHAPES; ++shape) {
        const float *points = &degenerate_shapes[shape].p[0][0];
        float regular[DEGENERATE_POINTS * 4], tangents[DEGENERATE_POINTS * 4], regular_tangents[DEGENERATE_POINTS * 4];
        float bezier[DEGENERATE_POINTS * 16], regular_bezier[DEGENERATE_POINTS * 16], lo[3], hi[3], rmax = 0.0f, rmin = INFINITY;
        float coordinates = 0.0f;
        uint32_t indices[DEGENERATE_POINTS], bezier_indices[DEGENERATE_POINTS];
        int b, k, mode;
        size_t i;
        for (k = 0; k < 3; ++k) lo[k] = hi[k] = points[k];
        for (i = 0; i < DEGENERATE_POINTS; ++i) {
            for (k = 0; k < 3; ++k) {
                lo[k] = fminf(lo[k], points[4 * i + k]);
                hi[k] = fmaxf(hi[k], points[4 * i + k]);
                /* a regular pose to refit from: a gentle arc beside it */
                regular[4 * i + k] = points[k] + (k == 0 ? 0.2f * (float)i : k == 1 ? 0.02f * (float)(i * i) : 0.0f);
            }
            rmax = fmaxf(rmax, points[4 * i + 3]);
            rmin = fminf(rmin, points[4 * i + 3]);
            for (k = 0; k < 3; ++k) coordinates = fmaxf(coordinates, fabsf(points[4 * i + k]));
            regular[4 * i + 3] = 0.05f;
        }
        for (b = 0; b < 5; ++b) {
            size_t segments = degenerate_segments(bases[b], points, tangents, indices, bezier);
            ref_scene *reference;
            degenerate_segments(bases[b], regular, regular_tangents, indices, regular_bezier);
            for (i = 0; i < segments; ++i) bezier_indices[i] = (uint32_t)(4 * i);
            reference = ref_build(bezier, 4 * segments, bezier_indices, segments);
            /* mode bit 0: end caps; bit 1: back faces culled */
            for (mode = 0; mode < 4; ++mode) {
                hairobb_bvh *bvh[2] = {NULL, NULL}, *refitted = NULL, *loaded = NULL, *moving = NULL;
                const float *steps[2] = {regular, points};
                hairobb_build_options o = hairobb_default_options();
                unsigned char *saved = NULL;
                size_t saved_size = 0;
                int p, ok = 1;
                o.shape = HAIROBB_SHAPE_ROUND;
                o.basis = bases[b];
                o.tangents = bases[b] == HAIROBB_BASIS_HERMITE ? tangents : NULL;
                o.end_caps = mode & 1 ? HAIROBB_ON : HAIROBB_OFF;
                o.back_faces = mode & 2 ? HAIROBB_OFF : HAIROBB_ON;
                for (p = 0; p < 2; ++p) {
                    o.simd = paths[p];
                    ok &= hairobb_build(points, DEGENERATE_POINTS, indices, segments, &o, &bvh[p]) == HAIROBB_OK;
                }
                o.simd = HAIROBB_SIMD_AUTO;
                o.tangents = bases[b] == HAIROBB_BASIS_HERMITE ? regular_tangents : NULL;
                ok &= hairobb_build(regular, DEGENERATE_POINTS, indices, segments, &o, &refitted) == HAIROBB_OK &&
                      hairobb_refit_tangents(refitted, points, bases[b] == HAIROBB_BASIS_HERMITE ? tangents : NULL) == HAIROBB_OK;
                o.tangents = bases[b] == HAIROBB_BASIS_HERMITE ? tangents : NULL;
                if (ok) {
                    saved_size = hairobb_save_size(bvh[0]);
                    saved = (unsigned char *)malloc(saved_size);
                    ok &= saved && hairobb_save(bvh[0], saved, saved_size) == HAIROBB_OK &&
                          hairobb_load(saved, saved_size, points, DEGENERATE_POINTS, indices, segments, &o, &loaded) == HAIROBB_OK;
                }
                if (ok && bases[b] != HAIROBB_BASIS_HERMITE) {   /* moving into the shape (no moving Hermite tangents) */
                    hairobb_build_options m = o;
                    m.time_steps = 2;
                    m.time_vertices = steps;
                    ok &= hairobb_build(NULL, DEGENERATE_POINTS, indices, segments, &m, &moving) == HAIROBB_OK;
                }
                CHECK(ok && reference, "degenerate %s, basis %d, mode %d: builds, refits, saves and loads", degenerate_shapes[shape].name,
                      b, mode);
                built += (size_t)ok;
                for (i = 0; ok && i < RAYS; ++i) {
                    hairobb_ray ray;
                    hairobb_hit hit[4];
                    int got[4], occluded;
                    for (k = 0; k < 3; ++k) {
                        double target = lo[k] - rmax + (hi[k] - lo[k] + 2.0 * rmax) * lcg64_double(&state);
                        /* a third of the rays at a control point itself */
                        if (i % 3 == 0) target = points[4 * (i / 3 % DEGENERATE_POINTS) + k] + rmax * (lcg64_double(&state) - 0.5);
                        ray.dir[k] = (float)(2.0 * lcg64_double(&state) - 1.0);
                        ray.org[k] = (float)(target - 3.0 * ray.dir[k]);
                    }
                    ray.tnear = 0.0f;
                    ray.tfar = INFINITY;
                    ray.time = 0.0f;
                    for (p = 0; p < 2; ++p) got[p] = hairobb_intersect1(bvh[p], &ray, &hit[p]);
                    got[2] = hairobb_intersect1(refitted, &ray, &hit[2]);
                    got[3] = hairobb_intersect1(loaded, &ray, &hit[3]);
                    occluded = hairobb_occluded1(bvh[0], &ray);
                    ++rays;
                    bad += got[0] && !degenerate_hit_ok(&hit[0], &ray, segments);
                    differ += !same_hit(got[0], &hit[0], got[1], &hit[1]) + !same_hit(got[0], &hit[0], got[2], &hit[2]) +
                              !same_hit(got[0], &hit[0], got[3], &hit[3]);
                    occluded_differ += occluded != got[0];
                    if (moving) {   /* on the way into the shape, and in it */
                        ray.time = i & 1 ? 1.0f : 0.5f;
                        got[2] = hairobb_intersect1(moving, &ray, &hit[2]);
                        bad += got[2] && !degenerate_hit_ok(&hit[2], &ray, segments);
                        occluded_differ += hairobb_occluded1(moving, &ray) != got[2];
                        ray.time = 0.0f;
                    }
                    if (got[0]) {   /* a path of 8 bounces from the hit, reflected about Ng */
                        hairobb_hit from = hit[0], next;
                        hairobb_ray bounce = ray;
                        int depth;
                        for (depth = 0; depth < 8; ++depth) {
                            float along = 2.0f * (bounce.dir[0] * from.Ng[0] + bounce.dir[1] * from.Ng[1] + bounce.dir[2] * from.Ng[2]);
                            int hit_again;
                            for (k = 0; k < 3; ++k) {
                                bounce.org[k] = bounce.org[k] + from.t * bounce.dir[k];
                                bounce.dir[k] -= along * from.Ng[k];
                            }
                            bounce.tnear = 0.0f;
                            bounce.tfar = INFINITY;
                            hit_again = hairobb_intersect1_from(bvh[0], &from, &bounce, &next);
                            bad += hit_again && !degenerate_hit_ok(&next, &bounce, segments);
                            occluded_differ += hairobb_occluded1_from(bvh[0], &from, &bounce) != hit_again;
                            if (!hit_again) break;
                            from = next;
                        }
                    }
                    /* the reference on the Bezier form, converted in double
                       where the basis is another: hairobb's float conversion
                       rounds the points by a few ulps of the coordinates,
                       which on the shape at 1e5 is over 1e-3 r (left out) */
                    if (mode == 0 && reference && (bases[b] == HAIROBB_BASIS_BEZIER || 8.0 * FLT_EPSILON * coordinates <= 1e-3 * rmin))
                        stress_ray(bvh[0], reference, ray.org, ray.dir, 0.0f, &n);
                }
                free(saved);
                hairobb_free(moving);
                hairobb_free(loaded);
                hairobb_free(refitted);
                for (p = 0; p < 2; ++p) hairobb_free(bvh[p]);
            }
            ref_free(reference);
        }
    }
    printf("stress degenerate tubes: %zu shapes x 5 bases x caps and culling on/off, %zu BVHs, %zu rays (and 8 bounces from each "
           "hit, and moving into the shape): %zu malformed hits, "
           "%zu differ between AVX2/SSE2, refit and load, %zu occluded1 against intersect1; reference (open ends, "
           "both sheets): %zu rays, %zu hits, %zu disagree, %zu at a silhouette, %zu off in t\n",
           DEGENERATE_SHAPES, built, rays, bad, differ, occluded_differ, n.rays, n.hits, n.disagree, n.edge, n.t_bad);
    CHECK(built == DEGENERATE_SHAPES * 5 * 4, "degenerate tubes: %zu of %zu BVHs", built, DEGENERATE_SHAPES * 5 * 4);
    CHECK(bad == 0 && differ == 0 && occluded_differ == 0, "degenerate tubes: %zu malformed, %zu differ, %zu occluded", bad, differ,
          occluded_differ);
    CHECK(n.disagree == 0 && n.t_bad == 0 && n.edge <= n.rays / 100 && n.hits > n.rays / 10,
          "degenerate tubes: %zu disagree, %zu off in t, %zu at a silhouette, %zu hits of %zu", n.disagree, n.t_bad, n.edge, n.hits,
          n.rays);
}

/* Options a round BVH must refuse or keep. */
static void test_options(void)
{
    static const float v[16] = {0, 0, 0, 0.1f, 1, 0, 0, 0.1f, 2, 0, 0, 0.1f, 3, 0, 0, 0.1f};
    static const uint32_t idx[1] = {0};
    hairobb_build_options o;
    hairobb_bvh *bvh = NULL;
    memset(&o, 0, sizeof o);
    o.shape = (hairobb_shape)2;
    CHECK(hairobb_build(v, 4, idx, 1, &o, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT && !bvh, "options: an unknown shape is refused");
    o.shape = HAIROBB_SHAPE_ROUND;
    o.precision = HAIROBB_PRECISION_PIECES;
    CHECK(hairobb_build(v, 4, idx, 1, &o, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT && !bvh,
          "options: round curves with the pieces precision are refused");
    o.precision = HAIROBB_PRECISION_EXACT;
    o.end_caps = (hairobb_switch)3;
    CHECK(hairobb_build(v, 4, idx, 1, &o, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT && !bvh, "options: end_caps out of range is refused");
    o.end_caps = HAIROBB_ON;
    o.back_faces = (hairobb_switch)7;
    CHECK(hairobb_build(v, 4, idx, 1, &o, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT && !bvh, "options: back_faces out of range is refused");
    /* ribbons ignore both; a ribbon file that says it has caps is a lie */
    o.shape = HAIROBB_SHAPE_RIBBON;
    o.back_faces = HAIROBB_OFF;
    CHECK(hairobb_build(v, 4, idx, 1, &o, &bvh) == HAIROBB_OK && bvh, "options: ribbons build with end_caps and back_faces set");
    if (bvh) {
        size_t size = hairobb_save_size(bvh);
        unsigned char *bytes = (unsigned char *)malloc(size);
        hairobb_bvh *bad = NULL;
        uint32_t word;
        CHECK(bytes && hairobb_save(bvh, bytes, size) == HAIROBB_OK, "options: the ribbon BVH saves");
        if (bytes) {
            memcpy(&word, bytes + HAIROBB__AT_SHAPE, 4);
            CHECK(word == HAIROBB_SHAPE_RIBBON, "options: a ribbon's file records no caps or culling (%u)", (unsigned)word);
            word = HAIROBB_SHAPE_RIBBON | HAIROBB__SAVE_CAPS;
            memcpy(bytes + HAIROBB__AT_SHAPE, &word, 4);
            hairobb__put64(bytes + size - 8, hairobb__save_checksum(bytes, size));
            CHECK(hairobb_load(bytes, size, v, 4, idx, 1, NULL, &bad) == HAIROBB_ERROR_INVALID_FILE && !bad,
                  "options: a ribbon file with the caps bit is refused");
            word = HAIROBB_SHAPE_ROUND | 0x400u;
            memcpy(bytes + HAIROBB__AT_SHAPE, &word, 4);
            hairobb__put64(bytes + size - 8, hairobb__save_checksum(bytes, size));
            CHECK(hairobb_load(bytes, size, v, 4, idx, 1, NULL, &bad) == HAIROBB_ERROR_INVALID_FILE && !bad,
                  "options: an unknown shape bit is refused");
        }
        free(bytes);
        hairobb_free(bvh);
        bvh = NULL;
    }
}

int main(void)
{
    hair_scene s;
    hairobb_build_options round;
    memset(&round, 0, sizeof round);
    round.shape = HAIROBB_SHAPE_ROUND;
    test_sheets();
    test_options();
    test_stress();
    test_stress_self_meeting();
    test_stress_joints();
    test_stress_curvy();
    test_stress_motion();
    test_stress_secondary_at_joints();
    test_caps_and_back_faces();
    test_zero_length();
    test_stress_degenerate();
    if (scene_combed(&s, 20000, 1) == 0) {
        test_save_refit(&s);
        compare_with_reference("combed", &s, &round);
        scene_free(&s);
    }
    if (scene_curly(&s, 20000, 2) == 0) {
        compare_with_reference("curly", &s, &round);
        scene_free(&s);
    }
    if (scene_crossing(&s, 20000, 3) == 0) {
        compare_with_reference("crossing", &s, &round);
        scene_free(&s);
    }
    {
        const char *path;
        if ((path = check_data(test_data_straight_hair)) != NULL) {
            CHECK(scene_load_hair(&s, path) == 0, "load %s", path);
            compare_with_reference("straight.hair", &s, &round);
            scene_free(&s);
        }
        if ((path = check_data(test_data_furball)) != NULL) {
            CHECK(scene_load_furball(&s, path) == 0, "load %s", path);
            compare_with_reference("furBall_A", &s, &round);
            scene_free(&s);
        }
    }
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
