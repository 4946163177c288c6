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
   test_reference.c. */
#define _POSIX_C_SOURCE 200809L
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "check.h"
#include "embree_wrap.h"
#include "ref_tube.h"
#include "scenes.h"
#include "test_data.h"

#include <stdlib.h>
#include <string.h>

#define SIDE 128

static float dot3f(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static void compare_with_embree(const char *name, hair_scene *s)
{
    size_t n = (size_t)SIDE * SIDE, i, both = 0, holes = 0, extra = 0, exits = 0, open_ends = 0;
    float *org = (float *)malloc(3 * sizeof(float) * n), *dir = (float *)malloc(3 * sizeof(float) * n);
    double *error = (double *)malloc(sizeof(double) * n);
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
    double *error = (double *)malloc(sizeof(double) * n), worst_inward = 0.0;
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
    printf("%s: hairobb's tubes against the reference: %zu of %zu rays disagree on hit or miss (%zu more within 1e-3 r of a "
           "silhouette); |dt|/r median %.3g, p99 %.3g, max %.3g over %zu hits; into the fibre %zu rays, %zu without its far side "
           "(worst |dt|/r %.3g); reflected %zu, %zu back on their tube\n",
           name, disagree, n, at_edge, both ? error[both / 2] : 0.0, both ? error[(size_t)(0.99 * (double)(both - 1))] : 0.0,
           both ? error[both - 1] : 0.0, both, inward, inward_bad, worst_inward, outward, outward_self);
    CHECK(both > n / 20, "%s: %zu hits", name, both);
    CHECK(disagree == 0 && at_edge <= n / 2000, "%s: %zu of %zu rays disagree with the tube reference (%zu at a silhouette)", name,
          disagree, n, at_edge);
    CHECK(both && error[(size_t)(0.99 * (double)(both - 1))] <= 2e-3, "%s: |dt|/r p99 %.3g", name,
          both ? error[(size_t)(0.99 * (double)(both - 1))] : 0.0);
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
        differ += ga != gb || (ga && memcmp(&a, &b, sizeof a) != 0);
        refit_differ += ga != gc || (ga && memcmp(&a, &c, sizeof a) != 0);
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
   reference, counting disagreements away from silhouettes. */
typedef struct stress_count {
    size_t rays, hits, disagree, edge, t_bad;
} stress_count;

static void stress_ray(const float *vertices, size_t vertex_count, const uint32_t *indices, size_t segments, hairobb_bvh *bvh,
                       ref_scene *reference, const float org[3], const float dir[3], stress_count *n)
{
    hairobb_ray ray;
    hairobb_hit hit;
    ref_tube_hit want;
    int got, expected;
    (void)vertices; (void)vertex_count; (void)indices; (void)segments;
    memcpy(ray.org, org, sizeof ray.org);
    memcpy(ray.dir, dir, sizeof ray.dir);
    ray.tnear = 0.0f;
    ray.tfar = INFINITY;
    ray.time = 0.0f;
    got = hairobb_intersect1(bvh, &ray, &hit);
    expected = ref_tube_intersect_scene(reference, org, dir, 0.0, INFINITY, &want);
    ++n->rays;
    n->hits += (size_t)expected;
    if (got != expected) {
        int edge = 0;
        if (expected) {   /* a chord under 0.09 r: within 1e-3 r of the silhouette */
            ref__ray rr;
            ref_tube_hit all[REF_TUBE_MAX_ROOTS], first;
            int count = 0, j;
            ref__ray_setup(&rr, org, dir);
            ref_tube_segment_hit(&rr, reference->vertices + 4 * (size_t)reference->indices[want.prim_id], 0.0, INFINITY, &first, all,
                                 &count);
            for (j = 0; j < count; ++j)
                if (all[j].exit && all[j].t > want.t && (all[j].t - want.t) * rr.dir_len < 0.09 * want.r) edge = 1;
        }
        if (edge) ++n->edge; else ++n->disagree;
    } else if (got && fabs((double)hit.t - want.t) * sqrt((double)dir[0] * dir[0] + (double)dir[1] * dir[1] + (double)dir[2] * dir[2]) >
                          2e-3 * want.r + 1e-6 * fabs(want.t)) {
        ++n->t_bad;
    }
}

static void stress_case(const char *name, const float *vertices, size_t vertex_count, const uint32_t *indices, size_t segments,
                        const float (*org)[3], const float (*dir)[3], size_t ray_count, int must_hit)
{
    hairobb_build_options o;
    hairobb_bvh *bvh = NULL;
    ref_scene *reference = ref_build(vertices, vertex_count, indices, segments);
    stress_count n = {0, 0, 0, 0, 0};
    size_t i;
    memset(&o, 0, sizeof o);
    o.shape = HAIROBB_SHAPE_ROUND;
    CHECK(hairobb_build(vertices, vertex_count, indices, segments, &o, &bvh) == HAIROBB_OK && reference, "stress %s: builds", name);
    if (!bvh || !reference) return;
    for (i = 0; i < ray_count; ++i) stress_ray(vertices, vertex_count, indices, segments, bvh, reference, org[i], dir[i], &n);
    printf("stress %s: %zu rays, %zu hit the reference; %zu disagree, %zu within 1e-3 r of a silhouette, %zu with |dt| over 2e-3 r\n",
           name, n.rays, n.hits, n.disagree, n.edge, n.t_bad);
    CHECK(n.disagree == 0 && n.t_bad == 0 && n.edge <= n.rays / 100 && (!must_hit || n.hits > n.rays / 4),
          "stress %s: %zu disagree, %zu off in t, %zu at a silhouette, %zu hits of %zu", name, n.disagree, n.t_bad, n.edge, n.hits, n.rays);
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
#define STRESS_RANDOM() ((double)((state = state * 6364136223846793005ull + 1442695040888963407ull) >> 11) * 0x1p-53)
    /* perpendicular to the fibre, at offsets r (1 - 10^-k) from its axis, k = 1..6, both sides */
    stress_straight(v, 3.0, 0.25, 0.25, 0.0);
    for (i = 0; i < RAYS; ++i) {
        double e = 0.25 * (1.0 - pow(10.0, -(double)(1 + i % 6))) * (i & 1 ? 1.0 : -1.0);
        org[i][0] = (float)(0.2 + 2.6 * STRESS_RANDOM()); org[i][1] = (float)e; org[i][2] = -2.0f;
        dir[i][0] = 0.0f; dir[i][1] = 0.0f; dir[i][2] = 1.0f;
    }
    stress_case("perpendicular, grazing at r (1 - 10^-k)", v, 4, idx, 1, (const float (*)[3])org, (const float (*)[3])dir, RAYS, 1);
    /* oblique rays through a tapered fibre whose radius falls to 0 */
    stress_straight(v, 3.0, 0.3, 0.0, 0.0);
    for (i = 0; i < RAYS; ++i) {
        double x = 3.0 * STRESS_RANDOM(), a = 6.283185307 * STRESS_RANDOM();
        org[i][0] = (float)(x - 1.0); org[i][1] = (float)(2.0 * cos(a)); org[i][2] = (float)(2.0 * sin(a));
        dir[i][0] = 1.0f; dir[i][1] = (float)(-2.0 * cos(a) + 0.3 * (STRESS_RANDOM() - 0.5)); dir[i][2] = (float)(-2.0 * sin(a) + 0.3 * (STRESS_RANDOM() - 0.5));
    }
    stress_case("tapered to r = 0", v, 4, idx, 1, (const float (*)[3])org, (const float (*)[3])dir, RAYS, 1);
    /* a long thin fibre far from the origin (length / width 10^4, at 10^4) */
    stress_straight(v, 10.0, 5e-4, 5e-4, 1e4);
    for (i = 0; i < RAYS; ++i) {
        org[i][0] = (float)(1e4 + 0.5 + 9.0 * STRESS_RANDOM()); org[i][1] = (float)(1e4 + 5e-4 * (2.0 * STRESS_RANDOM() - 1.0));
        org[i][2] = (float)(1e4 - 1.0);
        dir[i][0] = (float)(0.2 * (STRESS_RANDOM() - 0.5)); dir[i][1] = 0.0f; dir[i][2] = 1.0f;
    }
    stress_case("long and thin at 1e4", v, 4, idx, 1, (const float (*)[3])org, (const float (*)[3])dir, RAYS, 1);
    /* a short fat segment (length 0.2, radius 0.3), rays every way */
    stress_straight(v, 0.2, 0.3, 0.25, 0.0);
    for (i = 0; i < RAYS; ++i) {
        for (k = 0; k < 3; ++k) org[i][k] = (float)(4.0 * STRESS_RANDOM() - 2.0);
        for (k = 0; k < 3; ++k) dir[i][k] = (float)((k == 0 ? 0.1 : 0.0) + 0.4 * STRESS_RANDOM() - 0.2 - org[i][k]);
    }
    stress_case("short and fat", v, 4, idx, 1, (const float (*)[3])org, (const float (*)[3])dir, RAYS, 0);
    /* a strongly bent segment, and rays from inside it along its tangent */
    {
        static const float bent[16] = {0.0f, 0.0f, 0.0f, 0.15f, 1.0f, 1.2f, 0.0f, 0.15f, 0.0f, 1.4f, 0.1f, 0.15f, 1.0f, 2.0f, 0.0f, 0.15f};
        memcpy(v, bent, sizeof bent);
        for (i = 0; i < RAYS; ++i) {
            double u = 0.05 + 0.9 * STRESS_RANDOM(), s = 1.0 - u, c[3], d[3];
            for (k = 0; k < 3; ++k) {
                c[k] = s * s * s * bent[k] + 3 * u * s * s * bent[4 + k] + 3 * u * u * s * bent[8 + k] + u * u * u * bent[12 + k];
                d[k] = 3 * (s * s * (bent[4 + k] - bent[k]) + 2 * u * s * (bent[8 + k] - bent[4 + k]) + u * u * (bent[12 + k] - bent[8 + k]));
                org[i][k] = (float)(c[k] + 0.05 * (STRESS_RANDOM() - 0.5));
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
            org[i][0] = (float)(0.8 + 0.4 * STRESS_RANDOM()); org[i][1] = (float)(-0.2 + 0.4 * STRESS_RANDOM()); org[i][2] = -3.0f;
            dir[i][0] = (float)(0.2 * (STRESS_RANDOM() - 0.5)); dir[i][1] = (float)(0.2 * (STRESS_RANDOM() - 0.5)); dir[i][2] = 1.0f;
        }
        stress_case("a Bezier kink", kink, 7, two, 2, (const float (*)[3])org, (const float (*)[3])dir, RAYS, 1);
        {
            static const float repeated[16] = {0, 0, 0, 0.1f, 0, 0, 0, 0.1f, 1, 0.5f, 0, 0.1f, 1, 0.5f, 0, 0.1f};
            /* oblique rays: a ray perpendicular to the segment's plane lies in
               every circle's plane, and at the repeated end, where the
               tangent vanishes, float noise decides (left open) */
            for (i = 0; i < RAYS; ++i) {
                org[i][0] = (float)(1.2 * STRESS_RANDOM() - 0.1); org[i][1] = (float)(0.7 * STRESS_RANDOM() - 0.1); org[i][2] = -3.0f;
                dir[i][0] = (float)(0.3 * (STRESS_RANDOM() - 0.5)); dir[i][1] = (float)(0.3 * (STRESS_RANDOM() - 0.5)); dir[i][2] = 1.0f;
            }
            stress_case("repeated control points", repeated, 4, idx, 1, (const float (*)[3])org, (const float (*)[3])dir, RAYS, 0);
        }
    }
#undef STRESS_RANDOM
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
#define CAP_RANDOM() ((double)((state = state * 6364136223846793005ull + 1442695040888963407ull) >> 11) * 0x1p-53)
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
                        double jitter = 2.0 * CAP_RANDOM() - 1.0, wobble = 2.0 * CAP_RANDOM() - 1.0;
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
                    double aim = (k == 0 ? 1.2 : k == 1 ? 2.0 : 0.0) * CAP_RANDOM();
                    ray.org[k] = (float)(4.0 * CAP_RANDOM() - 2.0 + (k == 1 ? 1.0 : 0.0));
                    ray.dir[k] = (float)(aim - ray.org[k]);
                }
                ray.tnear = 0.0f;
                ray.tfar = INFINITY;
                ray.time = 0.0f;
                ga = hairobb_intersect1(bvh, &ray, &a);
                gb = hairobb_intersect1(loaded, &ray, &b);
                differ += ga != gb || (ga && memcmp(&a, &b, sizeof a) != 0);
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
            double s = 0.05 + 5.9 * CAP_RANDOM(), u = s - floor(s), b[4], c[3] = {0, 0, 0}, d[3] = {0, 0, 0};
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
#undef CAP_RANDOM
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
    test_caps_and_back_faces();
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
