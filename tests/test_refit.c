/* test_refit.c - hairobb_refit: a tree built on pose A refitted to pose B
   (combed fur swayed about its roots, rotated and translated, scaled,
   radii changed, a large deformation) traces every ray to the same hit,
   bit for bit, as a fresh build on B (the nearest hit does not depend on
   the tree: t, then the smallest index), agrees with the double-precision
   reference, and stays conservative (the header built instrumented, as in
   test_conservative.c: every segment the reference hits is reached), for
   every node layout and option set. Refitted back to A it has the build's
   bytes exactly; 1, 2 and 4 threads and a user's parallel_for write the
   same bytes; bad input leaves the BVH as it was; the SAH cost equals the
   build's at the build's pose and grows with a deformation; other curve
   bases refit (Hermite with new tangents). Built 8- and 4-wide. */
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <string.h>

/* instrumented while `instrument` is set: segments reached, none intersected */
static unsigned char *reached;
static int instrument;
#define HAIROBB__LEAF_VISIT(rs, prim) (instrument ? (reached[prim] = 1, (void)(rs), 1) : 0)

#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "check.h"
#include "compare.h"
#include "reference.h"
#include "scenes.h"

enum { SIDE = 48, CAMERA_RAYS = SIDE * SIDE, RAYS = 2 * CAMERA_RAYS };
enum { POSE_A, POSE_SWAY, POSE_ROTATED, POSE_SCALED, POSE_RADII, POSE_DEFORMED, POSES };
static const char *pose_names[POSES] = {"pose A", "swayed", "rotated and translated", "scaled 1.8", "radii changed", "large deformation"};

/* Rotation of p about the y axis by angle. */
static void rotate_y(float *p, float angle)
{
    float c = cosf(angle), s = sinf(angle), x = p[0], z = p[2];
    p[0] = c * x + s * z;
    p[2] = -s * x + c * z;
}

/* Pose `kind` of the combed fur (roots on the unit sphere): the control
   points moved by a smooth map, so strands stay strands. */
static void make_pose(const hair_scene *a, int kind, float *out)
{
    size_t i;
    memcpy(out, a->vertices, 16 * a->vertex_count);
    for (i = 0; i < a->vertex_count; ++i) {
        float *p = out + 4 * i;
        float along = (sqrtf(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 1.0f) / 0.5f;   /* 0 at the root, ~1 at the tip */
        if (kind == POSE_SWAY) {
            rotate_y(p, 0.4f * along);
        } else if (kind == POSE_ROTATED) {
            float c = cosf(0.7f), s = sinf(0.7f), y = p[1], z = p[2];
            p[1] = c * y - s * z;
            p[2] = s * y + c * z;
            p[0] += 2.0f; p[1] -= 1.0f; p[2] += 0.5f;
        } else if (kind == POSE_SCALED) {
            p[0] *= 1.8f; p[1] *= 1.8f; p[2] *= 1.8f; p[3] *= 1.8f;
        } else if (kind == POSE_RADII) {
            p[3] *= 0.3f + 2.2f * (float)((i * 2654435761u) % 1000u) / 1000.0f;
        } else if (kind == POSE_DEFORMED) {
            /* tips swung by up to 2.5 radians and stretched, twisted along y */
            rotate_y(p, 2.5f * along * along + 1.5f * p[1]);
            p[0] *= 1.0f + 0.8f * along; p[1] += 0.6f * along * sinf(3.0f * p[0]);
        }
    }
}

/* Camera rays towards the pose, and random rays through its bounds. */
static void make_rays(const hair_scene *pose, float *org, float *dir)
{
    scene_rng rng;
    int i, k;
    scene_camera_rays(pose, SIDE, SIDE, org, dir);
    scene_rng_seed(&rng, 99);
    for (i = CAMERA_RAYS; i < RAYS; ++i) {
        scene_vec3 d = scene_random_unit_vector(&rng);
        float size = pose->upper[0] - pose->lower[0];
        for (k = 0; k < 3; ++k) org[3 * i + k] = pose->lower[k] + (pose->upper[k] - pose->lower[k]) * scene_rng_float(&rng);
        org[3 * i] -= 2.0f * size * d.x; org[3 * i + 1] -= 2.0f * size * d.y; org[3 * i + 2] -= 2.0f * size * d.z;
        dir[3 * i] = d.x; dir[3 * i + 1] = d.y; dir[3 * i + 2] = d.z;
    }
}

static hairobb_ray ray_at(const float *org, const float *dir, int i)
{
    hairobb_ray ray;
    memcpy(ray.org, org + 3 * i, sizeof ray.org);
    memcpy(ray.dir, dir + 3 * i, sizeof ray.dir);
    ray.tnear = 0.0f;
    ray.tfar = INFINITY;
    return ray;
}

/* Rays whose hits (intersect1, to the bit, and occluded1) differ. */
static int differing_hits(const hairobb_bvh *a, const hairobb_bvh *b, const float *org, const float *dir, int *hits)
{
    int i, differ = 0;
    *hits = 0;
    for (i = 0; i < RAYS; ++i) {
        hairobb_ray ray = ray_at(org, dir, i);
        hairobb_hit ha, hb;
        int got_a = hairobb_intersect1(a, &ray, &ha), got_b = hairobb_intersect1(b, &ray, &hb);
        *hits += got_a;
        differ += !same_hit(got_a, &ha, got_b, &hb) || hairobb_occluded1(a, &ray) != hairobb_occluded1(b, &ray);
    }
    return differ;
}

/* The bytes a tree is: nodes, leaves, clipped ranges, root and bounds. */
static int same_tree(const hairobb_bvh *a, const hairobb_bvh *b)
{
    return a->node_bytes == b->node_bytes && memcmp(a->nodes, b->nodes, a->node_bytes) == 0 && a->root == b->root &&
           a->leaf_prim_count == b->leaf_prim_count && memcmp(a->leaf_prims, b->leaf_prims, 4 * a->leaf_prim_count) == 0 &&
           (a->leaf_ranges == NULL) == (b->leaf_ranges == NULL) &&
           (!a->leaf_ranges || memcmp(a->leaf_ranges, b->leaf_ranges, 8 * a->leaf_prim_count) == 0) &&
           memcmp(a->lower, b->lower, sizeof a->lower) == 0 && memcmp(a->upper, b->upper, sizeof a->upper) == 0;
}

/* A copy of the node memory and bounds, to compare with later. */
typedef struct tree_copy {
    unsigned char *nodes;
    size_t node_bytes;
    float lower[3], upper[3];
    const float *vertices;
} tree_copy;

static void copy_tree(const hairobb_bvh *bvh, tree_copy *c)
{
    c->nodes = (unsigned char *)malloc(bvh->node_bytes + 1);
    memcpy(c->nodes, bvh->nodes, bvh->node_bytes);
    c->node_bytes = bvh->node_bytes;
    memcpy(c->lower, bvh->lower, sizeof c->lower);
    memcpy(c->upper, bvh->upper, sizeof c->upper);
    c->vertices = bvh->vertices;
}

static int unchanged(const hairobb_bvh *bvh, const tree_copy *c)
{
    return bvh->node_bytes == c->node_bytes && memcmp(bvh->nodes, c->nodes, c->node_bytes) == 0 &&
           memcmp(bvh->lower, c->lower, sizeof c->lower) == 0 && memcmp(bvh->upper, c->upper, sizeof c->upper) == 0 &&
           bvh->vertices == c->vertices;
}

typedef struct counter {
    const unsigned char *reached;
    size_t hits, missed;
} counter;

static void count_missed(void *user, uint32_t prim, const ref_hit *hit)
{
    counter *m = (counter *)user;
    (void)hit;
    ++m->hits;
    m->missed += !m->reached[prim];
}

static size_t reference_rays, reference_disagree;

/* Against the reference on the pose: hit or miss (counted; the bar of
   test_options over all the rays: at most one disagreement per 10,000), |dt| <= 1e-3 r plus 32 float
   ulps of t (the random rays start two scene sizes away, t ~ 6-8, where
   1e-3 r is under 4 ulps of t; a fresh build has the same t, to the bit:
   measured 5-17 ulps); and, the header instrumented, every segment the
   reference hits is reached. */
static void check_reference(const char *name, const hairobb_bvh *bvh, const hair_scene *pose, const float *org, const float *dir)
{
    ref_scene *reference = ref_build(pose->vertices, pose->vertex_count, pose->indices, pose->segment_count);
    size_t disagree = 0, bad_t = 0, reached_total = 0;
    counter m = {NULL, 0, 0};
    int i;
    CHECK(reference != NULL, "%s: reference", name);
    if (!reference) return;
    for (i = 0; i < RAYS; ++i) {
        hairobb_ray ray = ray_at(org, dir, i);
        hairobb_hit hit;
        ref_hit expected;
        int got = hairobb_intersect1(bvh, &ray, &hit), want = ref_intersect(reference, ray.org, ray.dir, 0.0, INFINITY, &expected);
        if (got != want) ++disagree;
        else if (got && fabs((double)hit.t - expected.t) > 1e-3 * expected.r + 32.0 * FLT_EPSILON * expected.t) ++bad_t;
    }
    reached = (unsigned char *)calloc(pose->segment_count, 1);
    m.reached = reached;
    instrument = 1;
    for (i = 0; i < RAYS; ++i) {
        hairobb_ray ray = ray_at(org, dir, i);
        hairobb_hit hit;
        size_t k;
        memset(reached, 0, pose->segment_count);
        hairobb_intersect1(bvh, &ray, &hit);
        ref_all_hits(reference, ray.org, ray.dir, 0.0, INFINITY, count_missed, &m);
        for (k = 0; k < pose->segment_count; ++k) reached_total += reached[k];
    }
    instrument = 0;
    reference_rays += RAYS;
    reference_disagree += disagree;
    CHECK(bad_t == 0, "%s: %zu rays with |dt| > 1e-3 r (and %zu hit/miss disagreements)", name, bad_t, disagree);
    CHECK(m.hits > RAYS / 10 && m.missed == 0, "%s: %zu of %zu segments the reference hits not reached", name, m.missed, m.hits);
    CHECK((double)reached_total / RAYS < 0.25 * (double)pose->segment_count, "%s: %.1f segments reached per ray: not selective",
          name, (double)reached_total / RAYS);
    free(reached);
    reached = NULL;
    ref_free(reference);
}

typedef struct option_set {
    const char *name;
    hairobb_node_policy nodes;
    hairobb_obb_layout layout;
    hairobb_switch spatial, clustering;
    unsigned max_leaf;
} option_set;

static const option_set option_sets[] = {
    {"defaults", HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_AUTO, HAIROBB_AUTO, 0},
    {"per-child affine", HAIROBB_NODES_MIXED, HAIROBB_OBB_PER_CHILD, HAIROBB_AUTO, HAIROBB_AUTO, 0},
    {"shared rotation", HAIROBB_NODES_MIXED, HAIROBB_OBB_SHARED_ROTATION, HAIROBB_AUTO, HAIROBB_AUTO, 0},
    {"compressed (paper)", HAIROBB_NODES_MIXED, HAIROBB_OBB_COMPRESSED, HAIROBB_AUTO, HAIROBB_AUTO, 0},
    {"AABB only, compressed", HAIROBB_NODES_AABB_ONLY, HAIROBB_OBB_COMPRESSED, HAIROBB_AUTO, HAIROBB_AUTO, 0},
    {"OBB only, per-child affine", HAIROBB_NODES_OBB_ONLY, HAIROBB_OBB_PER_CHILD, HAIROBB_AUTO, HAIROBB_AUTO, 0},
    {"OBB only, leaves of 1", HAIROBB_NODES_OBB_ONLY, HAIROBB_OBB_DEFAULT, HAIROBB_AUTO, HAIROBB_AUTO, 1},
    {"AABB only, leaves of 15", HAIROBB_NODES_AABB_ONLY, HAIROBB_OBB_PER_CHILD, HAIROBB_AUTO, HAIROBB_AUTO, 15},
    {"spatial splits", HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_ON, HAIROBB_AUTO, 0},
    {"spatial splits, per-child affine", HAIROBB_NODES_MIXED, HAIROBB_OBB_PER_CHILD, HAIROBB_ON, HAIROBB_AUTO, 0},
    {"clustering, spatial splits, compressed", HAIROBB_NODES_MIXED, HAIROBB_OBB_COMPRESSED, HAIROBB_ON, HAIROBB_ON, 0},
};
#define OPTION_SETS (int)(sizeof option_sets / sizeof option_sets[0])

static void set_options(const option_set *o, hairobb_build_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->nodes = o->nodes;
    opt->obb_layout = o->layout;
    opt->spatial_splits = o->spatial;
    opt->spatial_split_budget = 1.0f;
    opt->clustering = o->clustering;
    opt->max_leaf_size = o->max_leaf;
}

/* Every pose, one option set: refit from A to each pose against a fresh
   build there, then back to A. */
static void check_option_set(const option_set *o, const hair_scene *a, float *const poses[POSES], float *const *orgs,
                             float *const *dirs, const hair_scene *posed)
{
    hairobb_build_options opt;
    hairobb_bvh *bvh = NULL, *original = NULL;
    hairobb_stats stats;
    int p;
    set_options(o, &opt);
    CHECK(hairobb_build(a->vertices, a->vertex_count, a->indices, a->segment_count, &opt, &bvh) == HAIROBB_OK &&
          hairobb_build(a->vertices, a->vertex_count, a->indices, a->segment_count, &opt, &original) == HAIROBB_OK,
          "%s: build", o->name);
    if (!bvh || !original) return;
    if (o->spatial == HAIROBB_ON) CHECK(bvh->leaf_ranges != NULL, "%s: no reference was clipped", o->name);
    for (p = POSE_SWAY; p < POSES; ++p) {
        hairobb_bvh *fresh = NULL;
        hairobb_stats fresh_stats;
        char name[160];
        int differ, hits;
        snprintf(name, sizeof name, "%s, %s", o->name, pose_names[p]);
        CHECK(hairobb_refit(bvh, poses[p]) == HAIROBB_OK && bvh->vertices == poses[p], "%s: refit", name);
        CHECK(hairobb_build(poses[p], a->vertex_count, a->indices, a->segment_count, &opt, &fresh) == HAIROBB_OK, "%s: fresh build", name);
        if (!fresh) continue;
        differ = differing_hits(bvh, fresh, orgs[p], dirs[p], &hits);
        CHECK(differ == 0 && hits > RAYS / 10, "%s: %d of %d rays hit otherwise than after a fresh build (%d hits)", name, differ, RAYS, hits);
        /* the reference and the instrumented traversal: every set on the large deformation, the defaults on every pose */
        if (p == POSE_DEFORMED || o == &option_sets[0]) check_reference(name, bvh, &posed[p], orgs[p], dirs[p]);
        hairobb_get_stats(bvh, &stats);
        hairobb_get_stats(fresh, &fresh_stats);
        if (p == POSE_DEFORMED)
            CHECK(stats.sah_cost > 1.2 * stats.build_sah_cost && stats.sah_cost > fresh_stats.sah_cost,
                  "%s: SAH cost %.2f after the refit, %.2f as built, %.2f rebuilt", name, stats.sah_cost, stats.build_sah_cost,
                  fresh_stats.sah_cost);
        if (p == POSE_SCALED)   /* areas scale as the bounds' area does: the cost stays within rounding */
            CHECK(fabs(stats.sah_cost / stats.build_sah_cost - 1.0) < 0.05, "%s: SAH cost %.3f, as built %.3f", name,
                  stats.sah_cost, stats.build_sah_cost);
        hairobb_free(fresh);
    }
    CHECK(hairobb_refit(bvh, a->vertices) == HAIROBB_OK, "%s: refit back", o->name);
    CHECK(same_tree(bvh, original), "%s: refitted back to pose A, the tree is not the build's to the byte", o->name);
    hairobb_get_stats(bvh, &stats);
    CHECK(stats.sah_cost == stats.build_sah_cost, "%s: SAH cost %.17g back at pose A, %.17g as built", o->name, stats.sah_cost,
          stats.build_sah_cost);
    hairobb_free(bvh);
    hairobb_free(original);
}

/* A user's task system: every index, last first; or every other one (the
   refit runs the ones skipped itself). */
static void for_backwards(void *user, unsigned count, hairobb_task_fn run, void *context)
{
    unsigned i;
    *(unsigned *)user = count;
    for (i = count; i-- > 0;) run(context, i);
}

static int skipping;     /* set for the refits: the build's parallel_for must run every task */
static void for_every_other(void *user, unsigned count, hairobb_task_fn run, void *context)
{
    unsigned i;
    *(unsigned *)user = count;
    for (i = 0; i < count; i += skipping ? 2 : 1) run(context, i);
}

static void check_threads(const hair_scene *a, const float *pose)
{
    hairobb_bvh *bvh[5] = {NULL, NULL, NULL, NULL, NULL};
    unsigned threads[3] = {1, 2, 4}, tasks[2] = {0, 0};
    int k;
    for (k = 0; k < 5; ++k) {
        hairobb_build_options opt;
        memset(&opt, 0, sizeof opt);
        if (k < 3) opt.threads = threads[k];
        else { opt.parallel_for = k == 3 ? for_backwards : for_every_other; opt.parallel_for_user = &tasks[k - 3]; }
        CHECK(hairobb_build(a->vertices, a->vertex_count, a->indices, a->segment_count, &opt, &bvh[k]) == HAIROBB_OK, "build %d", k);
        if (!bvh[k]) return;
    }
    skipping = 1;
    for (k = 0; k < 5; ++k) {
        tasks[0] = tasks[1] = 0;
        CHECK(hairobb_refit(bvh[k], pose) == HAIROBB_OK, "refit %d", k);
        if (k >= 3) CHECK(tasks[k - 3] > 1, "the refit handed %u tasks to parallel_for", tasks[k - 3]);
    }
    skipping = 0;
    for (k = 1; k < 5; ++k)
        CHECK(same_tree(bvh[k], bvh[0]), "refit %s: not the bytes of the refit on 1 thread",
              k == 1 ? "on 2 threads" : k == 2 ? "on 4 threads" : k == 3 ? "through a parallel_for running backwards"
                                                                       : "through a parallel_for skipping every other task");
    for (k = 0; k < 5; ++k) hairobb_free(bvh[k]);
}

/* Bad input: an error, and the BVH as it was (and tracing the old pose). */
static void check_bad_input(const hair_scene *a, const float *pose)
{
    hairobb_bvh *bvh = NULL, *reference = NULL;
    float *bad = (float *)malloc(16 * a->vertex_count);
    size_t last = 4 * (size_t)a->indices[a->segment_count - 1];
    tree_copy before;
    int k, differ, hits;
    float org[3 * RAYS], dir[3 * RAYS];
    static const struct { const char *what; size_t offset; float value; } cases[] = {
        {"NaN x", 0, NAN}, {"Inf y", 1, INFINITY}, {"-Inf z", 2, -INFINITY}, {"|x| > 1e18", 0, 2e18f},
        {"negative radius", 3, -1e-6f}, {"NaN radius", 3, NAN},
    };
    CHECK(hairobb_build(a->vertices, a->vertex_count, a->indices, a->segment_count, NULL, &bvh) == HAIROBB_OK &&
          hairobb_build(a->vertices, a->vertex_count, a->indices, a->segment_count, NULL, &reference) == HAIROBB_OK, "build");
    if (!bvh || !reference) return;
    copy_tree(bvh, &before);
    CHECK(hairobb_refit(NULL, pose) == HAIROBB_ERROR_INVALID_ARGUMENT, "refit of NULL");
    CHECK(hairobb_refit(bvh, NULL) == HAIROBB_ERROR_INVALID_ARGUMENT && unchanged(bvh, &before), "refit to NULL vertices");
    CHECK(hairobb_refit_tangents(bvh, pose, pose) == HAIROBB_ERROR_INVALID_ARGUMENT && unchanged(bvh, &before),
          "tangents for a Bezier BVH");
    for (k = 0; k < (int)(sizeof cases / sizeof cases[0]); ++k) {
        /* in the last segment's last control point: found after every other one was read */
        memcpy(bad, pose, 16 * a->vertex_count);
        bad[last + 12 + cases[k].offset] = cases[k].value;
        CHECK(hairobb_refit(bvh, bad) == HAIROBB_ERROR_INVALID_GEOMETRY && unchanged(bvh, &before), "%s: error, or the BVH changed",
              cases[k].what);
    }
    /* -0 is a radius of 0, not negative */
    memcpy(bad, pose, 16 * a->vertex_count);
    bad[last + 15] = -0.0f;
    CHECK(hairobb_refit(bvh, bad) == HAIROBB_OK, "radius -0");
    CHECK(hairobb_refit(bvh, a->vertices) == HAIROBB_OK && unchanged(bvh, &before), "back to pose A");
    make_rays(a, org, dir);
    differ = differing_hits(bvh, reference, org, dir, &hits);
    CHECK(differ == 0 && hits > RAYS / 10, "after the errors %d rays hit otherwise than the build", differ);
    free(before.nodes);
    free(bad);
    hairobb_free(bvh);
    hairobb_free(reference);
}

/* With the copy (the default) each refit writes the copy's points again,
   converted from other bases, and tracing reads no caller's array: the
   vertices may go after the refit. Other bases keep a copy of the caller's
   indices too. Hermite takes new tangents (hairobb_refit_tangents). */
static void check_bases(const hair_scene *a, const float *pose)
{
    static const hairobb_basis bases[] = {HAIROBB_BASIS_BSPLINE, HAIROBB_BASIS_CATMULL_ROM, HAIROBB_BASIS_HERMITE, HAIROBB_BASIS_LINEAR,
                                          HAIROBB_BASIS_BEZIER};
    static const char *names[] = {"B-spline", "Catmull-Rom", "Hermite", "linear", "Bezier"};
    size_t bytes = 16 * a->vertex_count;
    float *tangents_a = (float *)malloc(bytes), *tangents_b = (float *)malloc(bytes), *moved = (float *)malloc(bytes);
    float org[3 * RAYS], dir[3 * RAYS];
    hair_scene posed = *a;
    size_t i;
    int b, k;
    /* tangents: a tenth of the offset to the next point, radius derivative 0 */
    for (i = 0; i < a->vertex_count; ++i)
        for (k = 0; k < 4; ++k) {
            size_t next = i + 1 < a->vertex_count ? i + 1 : i;
            tangents_a[4 * i + k] = k < 3 ? 0.1f * (a->vertices[4 * next + k] - a->vertices[4 * i + k]) : 0.0f;
            tangents_b[4 * i + k] = k < 3 ? 0.1f * (pose[4 * next + k] - pose[4 * i + k]) : 0.0f;
        }
    posed.vertices = (float *)pose;
    scene_update_bounds(&posed);
    make_rays(&posed, org, dir);
    for (b = 0; b < 5; ++b) {
        hairobb_build_options opt;
        hairobb_bvh *bvh = NULL, *fresh = NULL, *original = NULL;
        size_t indices_copy = bases[b] == HAIROBB_BASIS_BEZIER ? 0 : 4;
        int hermite = bases[b] == HAIROBB_BASIS_HERMITE, differ, hits;
        memset(&opt, 0, sizeof opt);
        opt.basis = bases[b];
        opt.tangents = hermite ? tangents_a : NULL;
        CHECK(hairobb_build(a->vertices, a->vertex_count, a->indices, a->segment_count, &opt, &bvh) == HAIROBB_OK &&
              hairobb_build(a->vertices, a->vertex_count, a->indices, a->segment_count, &opt, &original) == HAIROBB_OK, "%s: build", names[b]);
        opt.tangents = hermite ? tangents_b : NULL;
        CHECK(hairobb_build(pose, a->vertex_count, a->indices, a->segment_count, &opt, &fresh) == HAIROBB_OK, "%s: fresh build", names[b]);
        if (!bvh || !fresh || !original) continue;
        /* nodes, leaf_prims, the copy (64 bytes a reference, point_refs, its alignment) and the caller's indices */
        CHECK(hairobb_memory_bytes(bvh) == sizeof(hairobb_bvh) + bvh->node_bytes + 64 + 4 * bvh->leaf_prim_count +
                                               64 * bvh->leaf_prim_count + 64 + (4 + indices_copy) * a->segment_count,
              "%s: memory %zu", names[b], hairobb_memory_bytes(bvh));
        if (hermite) CHECK(hairobb_refit(bvh, pose) == HAIROBB_ERROR_INVALID_ARGUMENT, "Hermite refit without tangents");
        memcpy(moved, pose, bytes);
        CHECK(hairobb_refit_tangents(bvh, moved, hermite ? tangents_b : NULL) == HAIROBB_OK, "%s: refit", names[b]);
        memset(moved, 0xff, bytes);       /* NaN: the BVH must not read the caller's array */
        differ = differing_hits(bvh, fresh, org, dir, &hits);
        CHECK(differ == 0 && hits > RAYS / 10, "%s: %d rays hit otherwise than after a fresh build", names[b], differ);
        CHECK(hairobb_refit_tangents(bvh, a->vertices, hermite ? tangents_a : NULL) == HAIROBB_OK && same_tree(bvh, original),
              "%s: refitted back, not the build's bytes", names[b]);
        hairobb_free(bvh);
        hairobb_free(fresh);
        hairobb_free(original);
    }
    free(tangents_a);
    free(tangents_b);
    free(moved);
}

int main(void)
{
    hair_scene a, posed[POSES];
    float *poses[POSES], *orgs[POSES], *dirs[POSES];
    int p, o;
    CHECK(scene_combed(&a, 20000, 41) == 0, "combed");
    for (p = 0; p < POSES; ++p) {
        poses[p] = (float *)malloc(16 * a.vertex_count + 16);
        orgs[p] = (float *)malloc(3 * sizeof(float) * RAYS);
        dirs[p] = (float *)malloc(3 * sizeof(float) * RAYS);
        make_pose(&a, p, poses[p]);
        posed[p] = a;
        posed[p].vertices = poses[p];
        scene_update_bounds(&posed[p]);
        make_rays(&posed[p], orgs[p], dirs[p]);
    }
    printf("combed %zu segments, %d rays a pose, %d-wide nodes\n", a.segment_count, RAYS, HAIROBB__W);
    for (o = 0; o < OPTION_SETS; ++o) check_option_set(&option_sets[o], &a, poses, orgs, dirs, posed);
    CHECK(reference_disagree * 10000 <= reference_rays, "%zu of %zu rays disagree with the reference on hit or miss",
          reference_disagree, reference_rays);
    printf("%zu of %zu rays disagree with the reference on hit or miss\n", reference_disagree, reference_rays);
    check_threads(&a, poses[POSE_SWAY]);
    check_bad_input(&a, poses[POSE_SWAY]);
    check_bases(&a, poses[POSE_SWAY]);
    for (p = 0; p < POSES; ++p) { free(poses[p]); free(orgs[p]); free(dirs[p]); }
    scene_free(&a);
    return check_summary();
}
