/* test_unit.c - white-box tests of hairobb.h: frames, hair space, bounds
   conservativeness of every node, BVH traversal against a brute-force loop
   over the same kernel, bad input and allocation failure. */
#define _POSIX_C_SOURCE 200809L
#include <stdlib.h>
#include <string.h>

/* Counting allocator that can be told to fail the N-th allocation. */
typedef struct test_allocator {
    long calls, fail_at, live;
} test_allocator;
static void *test_malloc(size_t size, void *user)
{
    test_allocator *a = (test_allocator *)user;
    void *p;
    if (!a) return malloc(size);
    if (a->calls++ == a->fail_at) return NULL;
    p = malloc(size);
    if (p) a->live++;
    return p;
}
static void test_free(void *p, void *user)
{
    test_allocator *a = (test_allocator *)user;
    if (a && p) a->live--;
    free(p);
}
#define HAIROBB_MALLOC(size, user) test_malloc(size, user)
#define HAIROBB_FREE(ptr, user) test_free(ptr, user)
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "check.h"
#include "reference.h"

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static float rnd(void)
{
    rng_state ^= rng_state << 13; rng_state ^= rng_state >> 7; rng_state ^= rng_state << 17;
    return (float)((rng_state >> 40) & 0xffffff) / 16777216.0f;
}

/* Strands of similar orientation (a combed patch) plus some random ones. */
static void make_scene(size_t n, float **vertices, uint32_t **indices)
{
    size_t i;
    int k;
    *vertices = (float *)malloc(16 * sizeof(float) * n);
    *indices = (uint32_t *)malloc(sizeof(uint32_t) * n);
    for (i = 0; i < n; ++i) {
        float base[3], d[3], bend[3];
        int random_orientation = i % 5 == 0;
        for (k = 0; k < 3; ++k) base[k] = 2.0f * rnd() - 1.0f;
        d[0] = random_orientation ? rnd() - 0.5f : 0.25f;
        d[1] = random_orientation ? rnd() - 0.5f : 0.25f + 0.05f * rnd();
        d[2] = random_orientation ? rnd() - 0.5f : 0.05f * rnd();
        for (k = 0; k < 3; ++k) bend[k] = 0.05f * (rnd() - 0.5f);
        for (k = 0; k < 4; ++k) {
            float t = (float)k / 3.0f, w = t * (1.0f - t) * 4.0f;
            float *v = *vertices + 16 * i + 4 * k;
            v[0] = base[0] + d[0] * t + bend[0] * w;
            v[1] = base[1] + d[1] * t + bend[1] * w;
            v[2] = base[2] + d[2] * t + bend[2] * w;
            v[3] = 0.004f * (1.0f - 0.6f * t);
        }
        (*indices)[i] = (uint32_t)(4 * i);
    }
}

static hairobb_ray random_ray(void)
{
    hairobb_ray ray;
    ray.org[0] = 2.0f * rnd() - 1.0f; ray.org[1] = 2.0f * rnd() - 1.0f; ray.org[2] = -4.0f;
    ray.dir[0] = 0.3f * (rnd() - 0.5f); ray.dir[1] = 0.3f * (rnd() - 0.5f); ray.dir[2] = 1.0f;
    ray.tnear = 0.0f;
    ray.tfar = INFINITY;
    return ray;
}

static void test_frames(void)
{
    int i, bad = 0;
    for (i = 0; i < 2000; ++i) {
        float n[3], f[9], len, cross[3];
        int k;
        if (i < 6) { n[0] = n[1] = n[2] = 0.0f; n[i / 2] = i % 2 ? -1.0f : 1.0f; }
        else { n[0] = rnd() - 0.5f; n[1] = rnd() - 0.5f; n[2] = rnd() - 0.5f; }
        len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (k = 0; k < 3; ++k) n[k] /= len;
        hairobb__frame_from_direction(n, f);
        cross[0] = f[1] * f[5] - f[2] * f[4];
        cross[1] = f[2] * f[3] - f[0] * f[5];
        cross[2] = f[0] * f[4] - f[1] * f[3];
        for (k = 0; k < 3; ++k) {
            if (fabsf(hairobb__dot3(f + 3 * k, f + 3 * k) - 1.0f) > 1e-5f) bad++;
            if (fabsf(cross[k] - f[6 + k]) > 1e-5f) bad++;
            if (fabsf(f[6 + k] - n[k]) > 0.0f) bad++;
        }
        if (fabsf(hairobb__dot3(f, f + 3)) > 1e-5f || fabsf(hairobb__dot3(f, f + 6)) > 1e-5f) bad++;
    }
    CHECK(bad == 0, "%d frame defects (orthonormal, right-handed, z = direction)", bad);
}

static void test_hair_space(void)
{
    float *vertices;
    uint32_t *indices;
    size_t i, n = 200;
    hairobb__builder b;
    float frame[9], dir[3] = {0.6f, 0.0f, 0.8f}, area_hair = 0.0f, area_world = 0.0f, identity[9];
    make_scene(n, &vertices, &indices);
    /* a bundle of parallel straight hairs along dir */
    for (i = 0; i < n; ++i) {
        int k;
        float base[3];
        for (k = 0; k < 3; ++k) base[k] = 0.2f * rnd();
        for (k = 0; k < 4; ++k) {
            float *v = vertices + 16 * i + 4 * k;
            v[0] = base[0] + dir[0] * (float)k / 3.0f;
            v[1] = base[1] + dir[1] * (float)k / 3.0f;
            v[2] = base[2] + dir[2] * (float)k / 3.0f;
            v[3] = 0.001f;
        }
    }
    memset(&b, 0, sizeof b);
    b.vertices = vertices; b.indices = indices; b.candidates = 4;
    b.ids = (uint32_t *)malloc(sizeof(uint32_t) * n);
    for (i = 0; i < n; ++i) b.ids[i] = (uint32_t)i;
    hairobb__identity_frame(identity);
    hairobb__choose_hair_space(&b, 0, n, 0, frame);
    CHECK(fabsf(hairobb__dot3(frame + 6, dir)) > 0.999f, "hair space z . hair direction = %g", hairobb__dot3(frame + 6, dir));
    for (i = 0; i < n; ++i) {
        float lo[3], hi[3];
        hairobb__segment_box(vertices + 16 * i, frame, NULL, lo, hi);
        area_hair += hairobb__half_area(lo, hi);
        hairobb__segment_box(vertices + 16 * i, identity, NULL, lo, hi);
        area_world += hairobb__half_area(lo, hi);
    }
    CHECK(area_hair < 0.1f * area_world, "hair-space boxes %g vs world boxes %g", area_hair, area_world);
    free(b.ids);
    free(vertices);
    free(indices);
}

/* Every sampled point of every ribbon (the ball of radius r(u) around P(u)
   contains the ribbon's cross-section for any ray) lies inside the boxes of
   its leaf's ancestors. Checked in double on the stored float boxes. */
typedef struct box_path {
    int depth;
    uint64_t refs[128];
    int lanes[128];
} box_path;

static int point_in_node(const hairobb_bvh *bvh, uint64_t ref, int lane, const double p[3])
{
    const void *node = bvh->nodes + (ref & ~(uint64_t)15);
    int k;
    if (HAIROBB__REF_TYPE(ref) == HAIROBB__REF_AABB) {
        const hairobb__aabb_node *a = (const hairobb__aabb_node *)node;
        for (k = 0; k < 3; ++k)
            if (p[k] < a->lower[k][lane] || p[k] > a->upper[k][lane]) return 0;
    } else if (HAIROBB__REF_TYPE(ref) == HAIROBB__REF_ROTATED) {
        const hairobb__rotated_node *r = (const hairobb__rotated_node *)node;
        double m[3];
        for (k = 0; k < 3; ++k) m[k] = p[k] - r->centre[k];
        for (k = 0; k < 3; ++k) {
            double q = r->rotation[3 * k] * m[0] + r->rotation[3 * k + 1] * m[1] + r->rotation[3 * k + 2] * m[2];
            if (q < r->lower[k][lane] || q > r->upper[k][lane]) return 0;
        }
    } else {
        const hairobb__obb_node *o = (const hairobb__obb_node *)node;
        double m[3];
        for (k = 0; k < 3; ++k) m[k] = p[k] - o->centre[k];
        for (k = 0; k < 3; ++k) {
            double q = o->xfm[3 * k][lane] * m[0] + o->xfm[3 * k + 1][lane] * m[1] + o->xfm[3 * k + 2][lane] * m[2] + o->xfm[9 + k][lane];
            if (q < 0.0 || q > 1.0) return 0;
        }
    }
    return 1;
}

static long check_subtree(const hairobb_bvh *bvh, uint64_t ref, box_path *path, long *seen)
{
    long outside = 0;
    if (HAIROBB__REF_TYPE(ref) == HAIROBB__REF_LEAF) {
        size_t first = (size_t)(ref >> 8), count = (size_t)((ref >> 4) & 15), i;
        for (i = first; i < first + count; ++i) {
            const float *cp = bvh->vertices + 4 * (size_t)bvh->indices[bvh->leaf_prims[i]];
            int s, e, level;
            ++*seen;
            for (s = 0; s <= 32; ++s) {
                double u = s / 32.0, w[4], c[4] = {0, 0, 0, 0};
                int k;
                w[0] = (1 - u) * (1 - u) * (1 - u); w[1] = 3 * u * (1 - u) * (1 - u); w[2] = 3 * u * u * (1 - u); w[3] = u * u * u;
                for (k = 0; k < 4; ++k) c[0] += w[k] * cp[4 * k], c[1] += w[k] * cp[4 * k + 1], c[2] += w[k] * cp[4 * k + 2], c[3] += w[k] * cp[4 * k + 3];
                for (e = 0; e < 26; ++e) {
                    double d[3], len, p[3];
                    d[0] = e % 3 - 1.0; d[1] = (e / 3) % 3 - 1.0; d[2] = e / 9 - 1.0;
                    if (e == 13) d[2] = 1.0; /* skip the zero vector */
                    len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                    for (k = 0; k < 3; ++k) p[k] = c[k] + c[3] * d[k] / len;
                    for (level = 0; level < path->depth; ++level)
                        if (!point_in_node(bvh, path->refs[level], path->lanes[level], p)) ++outside;
                }
            }
        }
        return outside;
    }
    if (HAIROBB__REF_TYPE(ref) != HAIROBB__REF_EMPTY) {
        const void *node = bvh->nodes + (ref & ~(uint64_t)15);
        const uint64_t *child = HAIROBB__REF_TYPE(ref) == HAIROBB__REF_AABB      ? ((const hairobb__aabb_node *)node)->child
                                : HAIROBB__REF_TYPE(ref) == HAIROBB__REF_ROTATED ? ((const hairobb__rotated_node *)node)->child
                                                                                 : ((const hairobb__obb_node *)node)->child;
        int lane;
        for (lane = 0; lane < HAIROBB__W; ++lane) {
            if (child[lane] == HAIROBB__REF_EMPTY) continue;
            path->refs[path->depth] = ref;
            path->lanes[path->depth] = lane;
            path->depth++;
            outside += check_subtree(bvh, child[lane], path, seen);
            path->depth--;
        }
    }
    return outside;
}

static const char *policy_name[] = {"mixed", "aabb-only", "obb-only", "mixed, shared-rotation OBBs"};

static void test_bounds_and_traversal(void)
{
    size_t n = 6000;
    float *vertices;
    uint32_t *indices;
    int policy;
    make_scene(n, &vertices, &indices);
    for (policy = 0; policy < 4; ++policy) {
        hairobb_build_options opt;
        hairobb_bvh *bvh = NULL;
        hairobb_stats stats;
        box_path path;
        long seen = 0, outside, mismatches = 0, occluded_mismatches = 0, hits = 0;
        int r;
        memset(&opt, 0, sizeof opt);
        opt.nodes = policy == 3 ? HAIROBB_NODES_MIXED : (hairobb_node_policy)policy;
        opt.obb_layout = policy == 3 ? HAIROBB_OBB_SHARED_ROTATION : HAIROBB_OBB_PER_CHILD;
        CHECK(hairobb_build(vertices, 4 * n, indices, n, &opt, &bvh) == HAIROBB_OK, "build %s", policy_name[policy]);
        if (!bvh) continue;
        hairobb_get_stats(bvh, &stats);
        CHECK(stats.leaf_references == n, "%s: %zu leaf references for %zu segments", policy_name[policy], stats.leaf_references, n);
        CHECK(policy != HAIROBB_NODES_AABB_ONLY || stats.obb_nodes == 0, "aabb-only built %zu OBB nodes", stats.obb_nodes);
        CHECK(policy != HAIROBB_NODES_OBB_ONLY || stats.aabb_nodes == 0, "obb-only built %zu AABB nodes", stats.aabb_nodes);
        CHECK((policy != HAIROBB_NODES_MIXED && policy != 3) || (stats.obb_nodes > 0 && stats.aabb_nodes > 0),
              "mixed built %zu AABB and %zu OBB nodes", stats.aabb_nodes, stats.obb_nodes);
        CHECK(hairobb_memory_bytes(bvh) >= stats.node_bytes + stats.leaf_bytes, "memory_bytes %zu", hairobb_memory_bytes(bvh));
        path.depth = 0;
        outside = check_subtree(bvh, bvh->root, &path, &seen);
        CHECK(seen == (long)n, "%s: walked %ld segments of %zu", policy_name[policy], seen, n);
        CHECK(outside == 0, "%s: %ld ribbon samples outside an ancestor box", policy_name[policy], outside);

        /* the BVH finds exactly what a loop over all segments with the same kernel finds */
        for (r = 0; r < 3000; ++r) {
            hairobb_ray ray = random_ray();
            hairobb_hit hit;
            hairobb__ray_state rs;
            uint32_t p;
            int brute = 0, got = hairobb_intersect1(bvh, &ray, &hit);
            hairobb__ray_setup(&rs, &ray);
            for (p = 0; p < n; ++p) brute |= hairobb__intersect_segment(bvh, &rs, p, 0);
            if (brute != got || (got && (hit.prim_id != rs.hit_prim || hit.t != rs.tfar))) ++mismatches;
            if (hairobb_occluded1(bvh, &ray) != got) ++occluded_mismatches;
            if (got && !(hit.t >= ray.tnear && hit.u >= 0.0f && hit.u <= 1.0f && hit.v >= -1.0f && hit.v <= 1.0f)) ++mismatches;
            if (!got && hit.prim_id != HAIROBB_INVALID_ID) ++mismatches;
            hits += got;
        }
        CHECK(hits > 300, "%s: only %ld of 3000 rays hit", policy_name[policy], hits);
        CHECK(mismatches == 0, "%s: %ld rays where BVH and brute force differ", policy_name[policy], mismatches);
        CHECK(occluded_mismatches == 0, "%s: %ld rays where occluded1 and intersect1 disagree", policy_name[policy], occluded_mismatches);
        hairobb_free(bvh);
    }
    free(vertices);
    free(indices);
}

/* Hit attributes against the reference on single segments. */
static void test_hit_attributes(void)
{
    float *vertices;
    uint32_t *indices;
    size_t n = 1;
    hairobb_bvh *bvh;
    int r, compared = 0, bad_t = 0, bad_v = 0, bad_ng = 0, disagree = 0;
    make_scene(n, &vertices, &indices);
    /* a curved, tapered segment */
    {
        const float cp[16] = {0, 0, 0, 0.05f, 0.3f, 0.4f, 0.1f, 0.04f, 0.7f, -0.1f, 0.0f, 0.03f, 1.0f, 0.2f, 0.2f, 0.01f};
        memcpy(vertices, cp, sizeof cp);
    }
    CHECK(hairobb_build(vertices, 4, indices, 1, NULL, &bvh) == HAIROBB_OK, "build one segment");
    for (r = 0; r < 20000; ++r) {
        hairobb_ray ray;
        hairobb_hit hit;
        ref_hit ref;
        int got, want;
        /* aim near a random curve point, within 1.5 radii, so edges are tested often */
        float u = rnd(), target[3];
        int k;
        for (k = 0; k < 3; ++k) {
            float c[4] = {vertices[k], vertices[4 + k], vertices[8 + k], vertices[12 + k]};
            target[k] = hairobb__bezier(c, u, NULL, NULL) + 0.15f * (rnd() - 0.5f);
        }
        ray.dir[0] = 0.4f * (rnd() - 0.5f); ray.dir[1] = 0.4f * (rnd() - 0.5f); ray.dir[2] = 0.5f + rnd();
        for (k = 0; k < 3; ++k) ray.org[k] = target[k] - 2.0f * ray.dir[k];
        ray.tnear = 0.0f; ray.tfar = INFINITY;
        got = hairobb_intersect1(bvh, &ray, &hit);
        want = ref_intersect_segment(vertices, indices, 0, ray.org, ray.dir, 0.0, INFINITY, &ref);
        if (got != want) { ++disagree; continue; }
        if (!got) continue;
        ++compared;
        if (fabs(hit.t - ref.t) > 1e-3 * ref.r) ++bad_t;
        if (fabs(hit.v - ref.v) > 1e-3) ++bad_v;
        {
            /* Ng: unit, facing the ray, orthogonal to the tangent */
            float len = sqrtf(hairobb__dot3(hit.Ng, hit.Ng));
            float facing = hairobb__dot3(hit.Ng, ray.dir);
            float tl = sqrtf(hairobb__dot3(hit.tangent, hit.tangent));
            if (fabsf(len - 1.0f) > 1e-4f || facing > 0.0f || fabsf(hairobb__dot3(hit.Ng, hit.tangent)) > 1e-4f * tl) ++bad_ng;
        }
    }
    printf("single segment: %d hits compared, %d hit/miss disagreements of 20000\n", compared, disagree);
    CHECK(compared > 2000, "only %d hits compared", compared);
    CHECK(disagree <= 2, "%d hit/miss disagreements with the reference of 20000", disagree);
    CHECK(bad_t == 0, "%d hits with |t - t_ref| > 1e-3 r", bad_t);
    CHECK(bad_v == 0, "%d hits with |v - v_ref| > 1e-3", bad_v);
    CHECK(bad_ng == 0, "%d hits with a bad Ng", bad_ng);
    /* tnear / tfar are honoured; an empty interval and a zero direction miss */
    {
        hairobb_ray ray = {{0.5f, 0.0f, -2.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY};
        hairobb_hit hit;
        ref_hit ref;
        float lo[3], hi[3];
        hairobb_bounds(bvh, lo, hi);
        ray.org[1] = (float)(hairobb__bezier((const float[]){0, 0.4f, -0.1f, 0.2f}, 0.5f, NULL, NULL));
        if (ref_intersect_segment(vertices, indices, 0, ray.org, ray.dir, 0.0, INFINITY, &ref)) {
            CHECK(hairobb_intersect1(bvh, &ray, &hit), "hit expected");
            ray.tfar = (float)ref.t * 0.999f;
            CHECK(!hairobb_intersect1(bvh, &ray, &hit) && hit.prim_id == HAIROBB_INVALID_ID, "tfar before the hit");
            CHECK(!hairobb_occluded1(bvh, &ray), "occluded with tfar before the hit");
            ray.tfar = INFINITY;
            ray.tnear = (float)ref.t * 1.001f;
            CHECK(!hairobb_intersect1(bvh, &ray, &hit), "tnear past the hit");
            ray.tnear = 1.0f; ray.tfar = 0.5f;
            CHECK(!hairobb_intersect1(bvh, &ray, &hit), "tnear > tfar");
            ray.tnear = 0.0f; ray.tfar = INFINITY;
            ray.dir[2] = 0.0f;
            CHECK(!hairobb_intersect1(bvh, &ray, &hit), "zero direction");
        }
        CHECK(lo[0] <= -0.05f && hi[0] >= 1.01f, "bounds x [%g, %g]", lo[0], hi[0]);
    }
    hairobb_free(bvh);
    free(vertices);
    free(indices);
}

/* A wiggle seen almost end-on: f = dot(P2, P2') has three roots, two of
   them inside one linear piece with f of equal sign at both its ends. The
   nearest is the first root; found by the reference, it must be found here. */
static void test_roots_hidden_in_one_piece(void)
{
    static const float cp[16] = {
        -0.00720855594f, 0.0268633962f, 1.75773466f, 0.00097127f,
        0.00180314481f, 0.00120264292f, 1.76457095f, 0.000937457f,
        0.00125399232f, -0.00672522187f, 1.78056204f, 0.000903643f,
        -0.00104784966f, 0.00540038943f, 1.80574322f, 0.000869829f};
    static const uint32_t index = 0;
    hairobb_bvh *bvh;
    hairobb_ray ray = {{0.0f, 0.0f, 0.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY};
    hairobb_hit hit;
    ref_hit ref;
    memset(&ref, 0, sizeof ref);
    CHECK(hairobb_build(cp, 4, &index, 1, NULL, &bvh) == HAIROBB_OK, "build");
    CHECK(ref_intersect_segment(cp, &index, 0, ray.org, ray.dir, 0.0, INFINITY, &ref), "the reference hits");
    CHECK(hairobb_intersect1(bvh, &ray, &hit) && fabs(hit.t - ref.t) < 1e-3 * ref.r,
          "nearest of three roots: t %.7f u %.5f, reference t %.7f u %.5f", hit.t, hit.u, ref.t, ref.u);
    hairobb_free(bvh);
}

/* Inputs that defeat the SAH: identical segments (no split separates them)
   and segments at exponentially growing distances (every split peels off
   one). Depth must stay bounded, leaves small, and hits those of a loop
   over all segments. */
static void test_degenerate_trees(void)
{
    size_t n = 3000, i;
    int scene;
    for (scene = 0; scene < 2; ++scene) {
        float *vertices = (float *)malloc(16 * sizeof(float) * n);
        uint32_t *indices = (uint32_t *)malloc(sizeof(uint32_t) * n);
        hairobb_bvh *bvh = NULL;
        hairobb_stats stats;
        long mismatches = 0, hits = 0;
        int r, k;
        for (i = 0; i < n; ++i) {
            float x = scene == 0 ? 0.0f : (float)pow(1.01, (double)i) - 1.0f;
            for (k = 0; k < 4; ++k) {
                float *v = vertices + 16 * i + 4 * k;
                v[0] = x; v[1] = 0.3f * (float)k; v[2] = 0.05f * (float)(k * (3 - k)); v[3] = 0.01f;
            }
            indices[i] = (uint32_t)(4 * i);
        }
        CHECK(hairobb_build(vertices, 4 * n, indices, n, NULL, &bvh) == HAIROBB_OK, "degenerate scene %d builds", scene);
        if (!bvh) continue;
        hairobb_get_stats(bvh, &stats);
        printf("degenerate scene %d: depth %u, %zu leaves\n", scene, stats.max_depth, stats.leaves);
        CHECK(stats.max_depth <= 80, "degenerate scene %d: depth %u", scene, stats.max_depth);
        CHECK(stats.leaf_references == n && stats.leaves * 4 >= n, "degenerate scene %d: %zu leaves for %zu segments", scene, stats.leaves, n);
        for (r = 0; r < 400; ++r) {
            hairobb_ray ray = {{0.0f, 0.0f, -3.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY};
            hairobb_hit hit;
            hairobb__ray_state rs;
            uint32_t p;
            int brute = 0, got;
            ray.org[0] = scene == 0 ? 0.02f * (rnd() - 0.5f) : 20.0f * rnd();
            ray.org[1] = 0.9f * rnd();
            got = hairobb_intersect1(bvh, &ray, &hit);
            hairobb__ray_setup(&rs, &ray);
            for (p = 0; p < n; ++p) brute |= hairobb__intersect_segment(bvh, &rs, p, 0);
            if (brute != got || (got && hit.t != rs.tfar) || hairobb_occluded1(bvh, &ray) != got) ++mismatches;
            hits += got;
        }
        CHECK(hits > 40, "degenerate scene %d: %ld hits of 400 rays", scene, hits);
        CHECK(mismatches == 0, "degenerate scene %d: %ld rays where BVH and brute force differ", scene, mismatches);
        hairobb_free(bvh);
        free(vertices);
        free(indices);
    }
}

/* Rays with NaN or infinite components miss cleanly (no crash, no hang, no
   hit with garbage attributes); infinite tfar and tnear = -inf are valid. */
static void test_bad_rays(void)
{
    size_t n = 2000;
    float *vertices;
    uint32_t *indices;
    hairobb_bvh *bvh;
    hairobb_ray base;
    hairobb_hit hit;
    int found = 0, tries, component, bad = 0;
    make_scene(n, &vertices, &indices);
    CHECK(hairobb_build(vertices, 4 * n, indices, n, NULL, &bvh) == HAIROBB_OK, "build");
    for (tries = 0; tries < 1000 && !found; ++tries) {
        base = random_ray();
        found = hairobb_intersect1(bvh, &base, &hit);
    }
    CHECK(found, "a ray that hits");
    for (component = 0; component < 8; ++component) {
        int value;
        for (value = 0; value < 3; ++value) {
            static const float values[3] = {NAN, INFINITY, -INFINITY};
            hairobb_ray ray = base;
            float *f = component < 3 ? &ray.org[component] : component == 3 ? &ray.tnear
                     : component < 7 ? &ray.dir[component - 4] : &ray.tfar;
            int got, occluded, valid;
            *f = values[value];
            /* still a valid ray: tnear = -inf, tfar = +inf */
            valid = (component == 3 && value == 2) || (component == 7 && value == 1);
            got = hairobb_intersect1(bvh, &ray, &hit);
            occluded = hairobb_occluded1(bvh, &ray);
            if (valid ? !(got && occluded && isfinite(hit.t)) : (got || occluded || hit.prim_id != HAIROBB_INVALID_ID)) {
                ++bad;
                printf("component %d value %g: hit %d occluded %d\n", component, values[value], got, occluded);
            }
        }
    }
    CHECK(bad == 0, "%d bad-ray cases misbehaved", bad);
    hairobb_free(bvh);
    free(vertices);
    free(indices);
}

static void test_bad_input(void)
{
    float *vertices;
    uint32_t *indices;
    size_t n = 8;
    hairobb_bvh *bvh = (hairobb_bvh *)&n; /* must be reset to NULL on failure */
    hairobb_build_options opt;
    make_scene(n, &vertices, &indices);
    CHECK(hairobb_build(NULL, 32, indices, n, NULL, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT && bvh == NULL, "NULL vertices");
    CHECK(hairobb_build(vertices, 32, NULL, n, NULL, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT, "NULL indices");
    CHECK(hairobb_build(vertices, 32, indices, n, NULL, NULL) == HAIROBB_ERROR_INVALID_ARGUMENT, "NULL out");
    CHECK(hairobb_build(vertices, 32, indices, 0, NULL, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT, "zero segments");
    CHECK(hairobb_build(vertices, 31, indices, n, NULL, &bvh) == HAIROBB_ERROR_INDEX_OUT_OF_RANGE, "last index + 3 past the end");
    CHECK(hairobb_build(vertices, 3, indices, 1, NULL, &bvh) == HAIROBB_ERROR_INDEX_OUT_OF_RANGE, "fewer than 4 vertices");
    indices[3] = 0xffffffffu;
    CHECK(hairobb_build(vertices, 32, indices, n, NULL, &bvh) == HAIROBB_ERROR_INDEX_OUT_OF_RANGE && bvh == NULL, "index 2^32-1");
    indices[3] = 0xfffffffeu;
    CHECK(hairobb_build(vertices, (size_t)0xffffffffu, indices, 1, NULL, &bvh) == HAIROBB_OK, "index + 3 = vertex_count - 1 is valid in arithmetic");
    hairobb_free(bvh);
    indices[3] = 12;
    CHECK(hairobb_build(vertices, 32, indices, (size_t)1 << 33, NULL, &bvh) == HAIROBB_ERROR_TOO_LARGE, "more than 2^32-1 segments");
    CHECK(hairobb_build(vertices, (size_t)-1 / 8, indices, n, NULL, &bvh) == HAIROBB_ERROR_TOO_LARGE, "vertex bytes overflow");
    vertices[21] = NAN;
    CHECK(hairobb_build(vertices, 32, indices, n, NULL, &bvh) == HAIROBB_ERROR_INVALID_GEOMETRY, "NaN coordinate");
    vertices[21] = INFINITY;
    CHECK(hairobb_build(vertices, 32, indices, n, NULL, &bvh) == HAIROBB_ERROR_INVALID_GEOMETRY, "Inf coordinate");
    vertices[21] = 1e30f;
    CHECK(hairobb_build(vertices, 32, indices, n, NULL, &bvh) == HAIROBB_ERROR_INVALID_GEOMETRY, "huge coordinate");
    vertices[21] = 0.0f;
    vertices[23] = -0.001f;
    CHECK(hairobb_build(vertices, 32, indices, n, NULL, &bvh) == HAIROBB_ERROR_INVALID_GEOMETRY, "negative radius");
    vertices[23] = NAN;
    CHECK(hairobb_build(vertices, 32, indices, n, NULL, &bvh) == HAIROBB_ERROR_INVALID_GEOMETRY, "NaN radius");
    vertices[23] = 0.001f;
    memset(&opt, 0, sizeof opt);
    opt.max_leaf_size = 16;
    CHECK(hairobb_build(vertices, 32, indices, n, &opt, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT, "max_leaf_size 16");
    memset(&opt, 0, sizeof opt);
    opt.nodes = (hairobb_node_policy)7;
    CHECK(hairobb_build(vertices, 32, indices, n, &opt, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT, "bad node policy");
    memset(&opt, 0, sizeof opt);
    opt.obb_layout = (hairobb_obb_layout)2;
    CHECK(hairobb_build(vertices, 32, indices, n, &opt, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT, "bad OBB layout");
    memset(&opt, 0, sizeof opt);
    opt.curve_pieces = 17;
    CHECK(hairobb_build(vertices, 32, indices, n, &opt, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT, "17 pieces");
    CHECK(hairobb_build(vertices, 32, indices, n, NULL, &bvh) == HAIROBB_OK, "valid again");
    CHECK(!hairobb_intersect1(bvh, NULL, NULL) && !hairobb_occluded1(NULL, NULL), "NULL to the tracers");
    hairobb_free(bvh);
    hairobb_free(NULL);
    CHECK(strcmp(hairobb_result_string((hairobb_result)99), "unknown hairobb_result") == 0, "unknown result string");
    free(vertices);
    free(indices);
}

static void test_allocation_failure(void)
{
    float *vertices;
    uint32_t *indices;
    size_t n = 3000;
    long fail_at, allocations;
    int failures_right = 1;
    test_allocator counter = {0, -1, 0};
    hairobb_build_options opt;
    hairobb_bvh *bvh;
    make_scene(n, &vertices, &indices);
    memset(&opt, 0, sizeof opt);
    opt.allocator_user = &counter;
    CHECK(hairobb_build(vertices, 4 * n, indices, n, &opt, &bvh) == HAIROBB_OK, "counting build");
    allocations = counter.calls;
    hairobb_free(bvh);
    CHECK(counter.live == 0, "%ld allocations live after free", counter.live);
    CHECK(allocations >= 4, "only %ld allocations", allocations);
    for (fail_at = 0; fail_at < allocations; ++fail_at) {
        test_allocator a = {0, 0, 0};
        hairobb_result r;
        a.fail_at = fail_at;
        opt.allocator_user = &a;
        r = hairobb_build(vertices, 4 * n, indices, n, &opt, &bvh);
        if (r != HAIROBB_ERROR_OUT_OF_MEMORY || bvh != NULL || a.live != 0) {
            failures_right = 0;
            printf("allocation %ld failing: result %d, %ld live\n", fail_at, (int)r, a.live);
        }
    }
    CHECK(failures_right, "each of %ld failing allocations gives OUT_OF_MEMORY, no BVH and no leak", allocations);
    free(vertices);
    free(indices);
}

int main(void)
{
    test_frames();
    test_hair_space();
    test_bounds_and_traversal();
    test_hit_attributes();
    test_roots_hidden_in_one_piece();
    test_degenerate_trees();
    test_bad_rays();
    test_bad_input();
    test_allocation_failure();
    return check_summary();
}
