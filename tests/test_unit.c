/* test_unit.c - white-box tests of hairobb.h: frames, hair space, clipped
   segment parts, bounds conservativeness of every node of every layout
   (compressed nodes decoded as the traversal decodes them; with spatial
   splits, every ribbon point inside the boxes of some leaf holding its
   segment), BVH traversal against a brute-force loop over the same kernel,
   bad input, allocation failure and cancellation. */
#define _POSIX_C_SOURCE 200809L
#include <stdlib.h>
#include <string.h>
#include <stdio.h>
#include <time.h>

/* the tests' allocator: it fails the N-th call, fills what it hands out
   with garbage and checks every free (builds allocate on several threads:
   it locks) */
#include "test_alloc.h"
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "check.h"
#include "reference.h"
#include "scenes.h"

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static float rnd(void) { return xorshift64_float(&rng_state); }

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

/* Half the surface area of a segment's box in a frame (rows = axes): its
   control points rotated, grown by the largest radius. */
static float frame_box_area(const float *cp, const float frame[9])
{
    float lo[3], hi[3];
    int i, k;
    for (k = 0; k < 3; ++k) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
        for (i = 0; i < 4; ++i) {
            float x = hairobb__dot3(frame + 3 * k, cp + 4 * i);
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
        lo[k] -= 0.001f;    /* the radius of these hairs */
        hi[k] += 0.001f;
    }
    return hairobb__half_area(lo, hi);
}

static void test_hair_space(void)
{
    float *vertices;
    uint32_t *indices;
    size_t i, n = 200;
    hairobb__builder b;
    hairobb__range whole;
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
    b.ranges = (float *)malloc(2 * sizeof(float) * n);
    for (i = 0; i < n; ++i) {
        b.ids[i] = (uint32_t)i;
        b.ranges[2 * i] = 0.0f;     /* whole segments */
        b.ranges[2 * i + 1] = 1.0f;
    }
    whole.begin = 0; whole.end = n; whole.cap = n;
    hairobb__identity_frame(identity);
    hairobb__choose_hair_space(&b, &whole, 1, 0, frame);
    CHECK(fabsf(hairobb__dot3(frame + 6, dir)) > 0.999f, "hair space z . hair direction = %g", hairobb__dot3(frame + 6, dir));
    for (i = 0; i < n; ++i) {
        area_hair += frame_box_area(vertices + 16 * i, frame);
        area_world += frame_box_area(vertices + 16 * i, identity);
    }
    CHECK(area_hair < 0.1f * area_world, "hair-space boxes %g vs world boxes %g", area_hair, area_world);
    free(b.ids);
    free(b.ranges);
    free(vertices);
    free(indices);
}

/* A clipped part [u0, u1] of a segment (what spatial splits make) has
   control points whose curve is the segment's on [u0, u1], radius included,
   up to the float rounding of the control points. */
static void test_clipped_parts(void)
{
    float *vertices;
    uint32_t *indices;
    hairobb__builder b;
    int trial, bad = 0, same = 1;
    double worst = 0.0;
    make_scene(1, &vertices, &indices);
    memset(&b, 0, sizeof b);
    b.vertices = vertices; b.indices = indices;
    b.ids = (uint32_t *)malloc(sizeof(uint32_t));
    b.ranges = (float *)malloc(2 * sizeof(float));
    b.ids[0] = 0;
    for (trial = 0; trial < 2000; ++trial) {
        float scratch[16], u0 = rnd(), u1 = rnd();
        const float *part;
        int k, s;
        for (k = 0; k < 16; ++k) vertices[k] = (k % 4 == 3) ? 0.01f * rnd() : 4.0f * rnd() - 2.0f;
        if (u0 > u1) { float t = u0; u0 = u1; u1 = t; }
        if (trial == 0) { u0 = 0.0f; u1 = 1.0f; }
        b.ranges[0] = u0; b.ranges[1] = u1;
        part = hairobb__ref_points(&b, 0, scratch);
        if (trial == 0) same = part == vertices;   /* a whole segment is the caller's points */
        for (s = 0; s <= 16; ++s) {
            double t = s / 16.0, u = u0 + t * ((double)u1 - u0);
            for (k = 0; k < 4; ++k) {
                double c[4], d[4], want = 0.0, got = 0.0, wt[4], wu[4];
                int j;
                wt[0] = (1 - t) * (1 - t) * (1 - t); wt[1] = 3 * t * (1 - t) * (1 - t); wt[2] = 3 * t * t * (1 - t); wt[3] = t * t * t;
                wu[0] = (1 - u) * (1 - u) * (1 - u); wu[1] = 3 * u * (1 - u) * (1 - u); wu[2] = 3 * u * u * (1 - u); wu[3] = u * u * u;
                for (j = 0; j < 4; ++j) { c[j] = vertices[4 * j + k]; d[j] = part[4 * j + k]; }
                for (j = 0; j < 4; ++j) { want += wu[j] * c[j]; got += wt[j] * d[j]; }
                /* control points rounded to float: a few ulps of the largest coordinate (2) */
                if (fabs(got - want) > 4e-7) ++bad;
                if (fabs(got - want) > worst) worst = fabs(got - want);
            }
        }
    }
    CHECK(same, "the whole segment's control points are not the caller's");
    CHECK(bad == 0, "%d clipped-part points off the segment (worst %g)", bad, worst);
    free(b.ids);
    free(b.ranges);
    free(vertices);
    free(indices);
}

/* The crossed bundles of tests/scenes.h (bent segments crossing one small
   region: spatial splits clip many, clusters by orientation pay) in arrays
   of their own. */
static void make_crossed_scene(size_t n, float **vertices, uint32_t **indices)
{
    hair_scene s;
    if (scene_crossed(&s, n, 11) != 0) { *vertices = NULL; *indices = NULL; return; }
    *vertices = (float *)malloc(16 * sizeof(float) * n);
    *indices = (uint32_t *)malloc(sizeof(uint32_t) * n);
    memcpy(*vertices, s.vertices, 16 * sizeof(float) * n);
    memcpy(*indices, s.indices, sizeof(uint32_t) * n);
    scene_free(&s);
}

/* Bounds: every sampled point of every ribbon lies inside the decoded boxes
   of all ancestors of some leaf holding its segment. Without spatial splits
   a segment is in one leaf, so that is every ancestor of its leaf; with
   them it is in the leaves of its clipped parts, and each part is bounded
   only by the boxes above its own leaf. Points: at 33 u, the ball of radius
   r(u) around P(u) in 26 directions and the ribbon's cross-section (the
   disc orthogonal to P'(u): every ray sees the ribbon's width in it) in 8.
   Checked in double on the stored boxes, decoded as the traversal does. */
#define MAX_TREE_DEPTH 128

/* A child box as the traversal sees it, decoded once: p is inside where
   lower <= m (p - centre) + offset <= upper on each axis, in double on the
   stored values. */
typedef struct decoded_box {
    double centre[3], m[9], offset[3], lower[3], upper[3];
} decoded_box;

typedef struct tree_walk {
    const hairobb_bvh *bvh;
    int depth;                         /* the current path: boxes of its ancestors */
    size_t path[MAX_TREE_DEPTH];
    decoded_box *boxes;
    size_t box_count, box_cap;
    size_t *path_boxes;                /* every leaf's ancestors' boxes, from leaf_path[leaf] on */
    size_t path_used, path_cap;
    size_t *leaf_path, *leaf_depth;
    size_t leaf_count, leaf_cap;
    uint32_t *occ_segment;             /* each leaf reference: segment and leaf */
    size_t *occ_leaf;
    size_t occ_count, occ_cap;
    size_t node_types[16];
    unsigned max_depth;
    long bad_refs;                     /* out of range, unknown type, too deep */
} tree_walk;

static void *grow(void *p, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap) return p;
    while (*cap < need) *cap = *cap ? 2 * *cap : 1024;
    p = realloc(p, *cap * size);
    if (!p) { printf("out of memory in the test\n"); exit(1); }
    return p;
}

static const uint64_t *node_children(const hairobb_bvh *bvh, uint64_t ref)
{
    const void *node = bvh->nodes + (ref & ~(uint64_t)15);
    switch (HAIROBB__REF_TYPE(ref)) {
    case HAIROBB__REF_AABB: return ((const hairobb__aabb_node *)node)->child;
    case HAIROBB__REF_OBB: return ((const hairobb__obb_node *)node)->child;
    case HAIROBB__REF_ROTATED: return ((const hairobb__rotated_node *)node)->child;
    case HAIROBB__REF_QAABB:
    case HAIROBB__REF_QOBB: return ((const hairobb__compressed_node *)node)->child;
#ifdef HAIROBB__REF_QOBB_PER_CHILD
    case HAIROBB__REF_QOBB_PER_CHILD: return ((const hairobb__compressed_obb_node *)node)->child;
#endif
    default: return NULL;
    }
}

/* node memory a node takes (an affine OBB node is followed by the main
   directions of its children's frames, for hairobb_refit) */
static size_t node_size(unsigned type)
{
    switch (type) {
    case HAIROBB__REF_AABB: return sizeof(hairobb__aabb_node);
    case HAIROBB__REF_OBB: return sizeof(hairobb__obb_node) + HAIROBB__W * 3 * sizeof(float);
    case HAIROBB__REF_ROTATED: return sizeof(hairobb__rotated_node);
    case HAIROBB__REF_QAABB:
    case HAIROBB__REF_QOBB: return sizeof(hairobb__compressed_node);
#ifdef HAIROBB__REF_QOBB_PER_CHILD
    case HAIROBB__REF_QOBB_PER_CHILD: return sizeof(hairobb__compressed_obb_node);
#endif
    default: return 0;
    }
}

/* Child `lane` of node ref, decoded as the traversal decodes it; 0 for an
   unknown node type. */
static int decode_box(const hairobb_bvh *bvh, uint64_t ref, int lane, decoded_box *box)
{
    const void *node = bvh->nodes + (ref & ~(uint64_t)15);
    unsigned type = HAIROBB__REF_TYPE(ref);
    int k;
    memset(box, 0, sizeof *box);
    box->m[0] = box->m[4] = box->m[8] = 1.0;
    if (type == HAIROBB__REF_AABB) {
        const hairobb__aabb_node *a = (const hairobb__aabb_node *)node;
        for (k = 0; k < 3; ++k) { box->lower[k] = a->lower[k][lane]; box->upper[k] = a->upper[k][lane]; }
    } else if (type == HAIROBB__REF_ROTATED) {
        const hairobb__rotated_node *r = (const hairobb__rotated_node *)node;
        for (k = 0; k < 9; ++k) box->m[k] = r->rotation[k];
        for (k = 0; k < 3; ++k) {
            box->centre[k] = r->centre[k];
            box->lower[k] = r->lower[k][lane];
            box->upper[k] = r->upper[k][lane];
        }
    } else if (type == HAIROBB__REF_QAABB || type == HAIROBB__REF_QOBB) {
        /* the frame hairobb__decode_rotation makes of the bytes (the identity
           for an axis-aligned node) applied to p - centre; the planes
           (float)bytes * step, rounded to float */
        const hairobb__compressed_node *c = (const hairobb__compressed_node *)node;
        float frame[9];
        if (type == HAIROBB__REF_QOBB) hairobb__decode_rotation(c->rotation, frame);
        else hairobb__identity_frame(frame);
        for (k = 0; k < 9; ++k) box->m[k] = frame[k];
        for (k = 0; k < 3; ++k) {
            box->centre[k] = c->centre[k];
            box->lower[k] = (float)c->lower[k][lane] * c->step[k];
            box->upper[k] = (float)c->upper[k][lane] * c->step[k];
        }
#ifdef HAIROBB__REF_QOBB_PER_CHILD
    } else if (type == HAIROBB__REF_QOBB_PER_CHILD) {
        /* the lane's rotation bytes, converted to float, are the frame */
        const hairobb__compressed_obb_node *c = (const hairobb__compressed_obb_node *)node;
        for (k = 0; k < 9; ++k) box->m[k] = (float)c->rotation[k][lane];
        for (k = 0; k < 3; ++k) {
            box->centre[k] = c->centre[k];
            box->lower[k] = (float)c->lower[k][lane] * c->step[k];
            box->upper[k] = (float)c->upper[k][lane] * c->step[k];
        }
#endif
    } else if (type == HAIROBB__REF_OBB) {
        /* an affine map onto the unit cube */
        const hairobb__obb_node *o = (const hairobb__obb_node *)node;
        for (k = 0; k < 9; ++k) box->m[k] = o->xfm[k][lane];
        for (k = 0; k < 3; ++k) {
            box->centre[k] = o->centre[k];
            box->offset[k] = o->xfm[9 + k][lane];
            box->lower[k] = 0.0;
            box->upper[k] = 1.0;
        }
    } else {
        return 0;
    }
    return 1;
}

static int point_in_box(const decoded_box *box, const double p[3])
{
    double d[3];
    int k;
    for (k = 0; k < 3; ++k) d[k] = p[k] - box->centre[k];
    for (k = 0; k < 3; ++k) {
        double q = box->m[3 * k] * d[0] + box->m[3 * k + 1] * d[1] + box->m[3 * k + 2] * d[2] + box->offset[k];
        if (q < box->lower[k] || q > box->upper[k]) return 0;
    }
    return 1;
}

static void walk_tree(tree_walk *w, uint64_t ref, unsigned depth)
{
    unsigned type = HAIROBB__REF_TYPE(ref);
    if (type == HAIROBB__REF_LEAF) {
        size_t first = (size_t)(ref >> 8), count = (size_t)((ref >> 4) & 15), i;
        if (count == 0 || first + count > w->bvh->leaf_prim_count) { ++w->bad_refs; return; }
        w->leaf_path = (size_t *)grow(w->leaf_path, &w->leaf_cap, w->leaf_count + 1, sizeof(size_t));
        w->leaf_depth = (size_t *)realloc(w->leaf_depth, w->leaf_cap * sizeof(size_t));
        if (!w->leaf_depth) exit(1);
        w->path_boxes = (size_t *)grow(w->path_boxes, &w->path_cap, w->path_used + (size_t)w->depth, sizeof(size_t));
        w->leaf_path[w->leaf_count] = w->path_used;
        w->leaf_depth[w->leaf_count] = (size_t)w->depth;
        memcpy(w->path_boxes + w->path_used, w->path, (size_t)w->depth * sizeof(size_t));
        w->path_used += (size_t)w->depth;
        for (i = first; i < first + count; ++i) {
            size_t cap = w->occ_cap;
            w->occ_segment = (uint32_t *)grow(w->occ_segment, &cap, w->occ_count + 1, sizeof(uint32_t));
            w->occ_leaf = (size_t *)grow(w->occ_leaf, &w->occ_cap, w->occ_count + 1, sizeof(size_t));
            w->occ_segment[w->occ_count] = w->bvh->leaf_prims[i];
            w->occ_leaf[w->occ_count] = w->leaf_count;
            ++w->occ_count;
        }
        ++w->leaf_count;
        if (depth > w->max_depth) w->max_depth = depth;
        return;
    }
    if (type == HAIROBB__REF_EMPTY) return;
    {
        const uint64_t *child = node_children(w->bvh, ref);
        int lane;
        if (!child || w->depth >= MAX_TREE_DEPTH || (ref & ~(uint64_t)15) + node_size(type) > w->bvh->node_bytes) {
            ++w->bad_refs;
            return;
        }
        w->node_types[type]++;
        for (lane = 0; lane < HAIROBB__W; ++lane) {
            if (child[lane] == HAIROBB__REF_EMPTY) continue;
            w->boxes = (decoded_box *)grow(w->boxes, &w->box_cap, w->box_count + 1, sizeof(decoded_box));
            if (!decode_box(w->bvh, ref, lane, &w->boxes[w->box_count])) { ++w->bad_refs; continue; }
            w->path[w->depth] = w->box_count++;
            w->depth++;
            walk_tree(w, child[lane], depth + 1);
            w->depth--;
        }
    }
}

static void free_walk(tree_walk *w)
{
    free(w->boxes); free(w->path_boxes); free(w->leaf_path); free(w->leaf_depth);
    free(w->occ_segment); free(w->occ_leaf);
}

static int point_in_leaf_path(const tree_walk *w, size_t leaf, const double p[3])
{
    size_t level, start = w->leaf_path[leaf];
    for (level = 0; level < w->leaf_depth[leaf]; ++level)
        if (!point_in_box(&w->boxes[w->path_boxes[start + level]], p)) return 0;
    return 1;
}

/* Counts sampled ribbon points outside every leaf path of their segment;
   *missing counts segments in no leaf at all. */
static long points_outside(const tree_walk *w, size_t n, long *missing, long *points)
{
    size_t *first = (size_t *)calloc(n + 1, sizeof(size_t)), *leaves = (size_t *)malloc(sizeof(size_t) * (w->occ_count + 1));
    size_t i, *fill = (size_t *)malloc(sizeof(size_t) * (n + 1));
    long outside = 0;
    if (!first || !leaves || !fill) exit(1);
    for (i = 0; i < w->occ_count; ++i)
        if (w->occ_segment[i] < n) first[w->occ_segment[i] + 1]++;
    for (i = 0; i < n; ++i) first[i + 1] += first[i];
    memcpy(fill, first, sizeof(size_t) * (n + 1));
    for (i = 0; i < w->occ_count; ++i)
        if (w->occ_segment[i] < n) leaves[fill[w->occ_segment[i]]++] = w->occ_leaf[i];
    *missing = 0;
    *points = 0;
    for (i = 0; i < n; ++i) {
        const float *cp = w->bvh->vertices + 4 * (size_t)w->bvh->indices[i];
        int s, e, k;
        if (first[i] == first[i + 1]) { ++*missing; continue; }
        for (s = 0; s <= 32; ++s) {
            double u = s / 32.0, wt[4], dw[4], c[4] = {0, 0, 0, 0}, t[3] = {0, 0, 0}, a[3], b[3], len;
            wt[0] = (1 - u) * (1 - u) * (1 - u); wt[1] = 3 * u * (1 - u) * (1 - u); wt[2] = 3 * u * u * (1 - u); wt[3] = u * u * u;
            dw[0] = -3 * (1 - u) * (1 - u); dw[1] = 3 * (1 - u) * (1 - u) - 6 * u * (1 - u); dw[2] = 6 * u * (1 - u) - 3 * u * u; dw[3] = 3 * u * u;
            for (k = 0; k < 4; ++k) {
                c[0] += wt[k] * cp[4 * k]; c[1] += wt[k] * cp[4 * k + 1]; c[2] += wt[k] * cp[4 * k + 2]; c[3] += wt[k] * cp[4 * k + 3];
                t[0] += dw[k] * cp[4 * k]; t[1] += dw[k] * cp[4 * k + 1]; t[2] += dw[k] * cp[4 * k + 2];
            }
            /* a, b: orthonormal pair spanning the plane orthogonal to the tangent */
            len = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
            if (!(len > 0.0)) { t[0] = 0.0; t[1] = 0.0; t[2] = 1.0; len = 1.0; }
            for (k = 0; k < 3; ++k) t[k] /= len;
            if (fabs(t[0]) < 0.9) { a[0] = 0.0; a[1] = t[2]; a[2] = -t[1]; } else { a[0] = -t[2]; a[1] = 0.0; a[2] = t[0]; }
            len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
            for (k = 0; k < 3; ++k) a[k] /= len;
            b[0] = t[1] * a[2] - t[2] * a[1]; b[1] = t[2] * a[0] - t[0] * a[2]; b[2] = t[0] * a[1] - t[1] * a[0];
            for (e = 0; e < 26 + 8; ++e) {
                double d[3], p[3];
                size_t j;
                int inside = 0;
                if (e < 26) {
                    d[0] = e % 3 - 1.0; d[1] = (e / 3) % 3 - 1.0; d[2] = e / 9 - 1.0;
                    if (e == 13) d[2] = 1.0; /* skip the zero vector */
                } else {
                    double angle = (e - 26) * (3.14159265358979323846 / 4.0);
                    for (k = 0; k < 3; ++k) d[k] = cos(angle) * a[k] + sin(angle) * b[k];
                }
                len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                for (k = 0; k < 3; ++k) p[k] = c[k] + c[3] * d[k] / len;
                ++*points;
                for (j = first[i]; j < first[i + 1] && !inside; ++j) inside = point_in_leaf_path(w, leaves[j], p);
                if (!inside) ++outside;
            }
        }
    }
    free(first);
    free(leaves);
    free(fill);
    return outside;
}

/* The kernels' own segment test. Under runtime dispatch the kernels' names
   stand for their AVX2 copies (the BVHs here trace with those on this CPU),
   which are always inlined and so only into code compiled for AVX2. */
#if HAIROBB__DISPATCH
__attribute__((target("avx2")))
#endif
static int segment_test(const hairobb_bvh *bvh, hairobb__ray_state *rs, uint32_t prim)
{
    float scratch[16];
    return hairobb__intersect_segment(bvh, rs, prim, hairobb__segment_points(bvh, prim, rs->line.time, scratch), 0);
}

/* Segment prim alone hits the ray first at exactly t: two segments the ray
   meets at the same t are equally first, either may be reported. */
static int hits_at(const hairobb_bvh *bvh, const hairobb_ray *ray, uint32_t prim, float t, size_t n)
{
    hairobb__ray_state rs;
    hairobb__ray_setup(&rs, bvh, ray);
    return prim < n && segment_test(bvh, &rs, prim) && rs.line.tfar == t;
}

typedef struct unit_config {
    const char *name;
    int scene;                       /* 0: combed patch (make_scene), 1: crossed bundles */
    hairobb_node_policy nodes;
    hairobb_obb_layout layout;
    hairobb_switch spatial;
    float budget;
    hairobb_switch clustering;
    int expect_clipping, expect_clusters;
} unit_config;

static const unit_config unit_configs[] = {
    {"mixed, per-child OBBs", 0, HAIROBB_NODES_MIXED, HAIROBB_OBB_PER_CHILD, HAIROBB_OFF, 0.0f, HAIROBB_OFF, 0, 0},
    {"aabb-only, plain nodes", 0, HAIROBB_NODES_AABB_ONLY, HAIROBB_OBB_PER_CHILD, HAIROBB_OFF, 0.0f, HAIROBB_OFF, 0, 0},
    {"obb-only, per-child OBBs", 0, HAIROBB_NODES_OBB_ONLY, HAIROBB_OBB_PER_CHILD, HAIROBB_OFF, 0.0f, HAIROBB_OFF, 0, 0},
    {"mixed, shared-rotation OBBs", 0, HAIROBB_NODES_MIXED, HAIROBB_OBB_SHARED_ROTATION, HAIROBB_OFF, 0.0f, HAIROBB_OFF, 0, 0},
    {"mixed, compressed", 0, HAIROBB_NODES_MIXED, HAIROBB_OBB_COMPRESSED, HAIROBB_OFF, 0.0f, HAIROBB_OFF, 0, 0},
    {"aabb-only, compressed", 0, HAIROBB_NODES_AABB_ONLY, HAIROBB_OBB_COMPRESSED, HAIROBB_OFF, 0.0f, HAIROBB_OFF, 0, 0},
    {"obb-only, compressed", 0, HAIROBB_NODES_OBB_ONLY, HAIROBB_OBB_COMPRESSED, HAIROBB_OFF, 0.0f, HAIROBB_OFF, 0, 0},
    {"mixed, default options", 0, HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_AUTO, 0.0f, HAIROBB_AUTO, 0, 0},
    {"crossed: mixed, compressed, spatial splits", 1, HAIROBB_NODES_MIXED, HAIROBB_OBB_COMPRESSED, HAIROBB_ON, 1.0f, HAIROBB_OFF, 1, 0},
    {"crossed: mixed, per-child OBBs, spatial splits", 1, HAIROBB_NODES_MIXED, HAIROBB_OBB_PER_CHILD, HAIROBB_ON, 1.0f, HAIROBB_OFF, 1, 0},
    {"crossed: obb-only, shared-rotation, spatial splits", 1, HAIROBB_NODES_OBB_ONLY, HAIROBB_OBB_SHARED_ROTATION, HAIROBB_ON, 1.0f, HAIROBB_OFF, 1, 0},
    {"crossed: aabb-only, compressed, spatial splits", 1, HAIROBB_NODES_AABB_ONLY, HAIROBB_OBB_COMPRESSED, HAIROBB_ON, 1.0f, HAIROBB_OFF, 1, 0},
    {"crossed: obb-only, compressed, spatial splits", 1, HAIROBB_NODES_OBB_ONLY, HAIROBB_OBB_COMPRESSED, HAIROBB_ON, 1.0f, HAIROBB_OFF, 1, 0},
    {"crossed: mixed, compressed, clustering", 1, HAIROBB_NODES_MIXED, HAIROBB_OBB_COMPRESSED, HAIROBB_OFF, 0.0f, HAIROBB_ON, 0, 1},
    {"crossed: obb-only, per-child OBBs, clustering", 1, HAIROBB_NODES_OBB_ONLY, HAIROBB_OBB_PER_CHILD, HAIROBB_OFF, 0.0f, HAIROBB_ON, 0, 1},
    {"crossed: mixed, compressed, spatial splits and clustering", 1, HAIROBB_NODES_MIXED, HAIROBB_OBB_COMPRESSED, HAIROBB_ON, 1.0f, HAIROBB_ON, 0, 0},
#ifdef HAIROBB__REF_QOBB_PER_CHILD
    {"mixed, compressed per-child", 0, HAIROBB_NODES_MIXED, HAIROBB_OBB_COMPRESSED_PER_CHILD, HAIROBB_OFF, 0.0f, HAIROBB_OFF, 0, 0},
    {"crossed: obb-only, compressed per-child, spatial splits", 1, HAIROBB_NODES_OBB_ONLY, HAIROBB_OBB_COMPRESSED_PER_CHILD, HAIROBB_ON, 1.0f, HAIROBB_OFF, 1, 0},
#endif
};
#define UNIT_CONFIGS (int)(sizeof unit_configs / sizeof unit_configs[0])

static void test_bounds_and_traversal(void)
{
    size_t counts[2] = {6000, 2000};
    float *vertices[2];
    uint32_t *indices[2];
    int c;
    make_scene(counts[0], &vertices[0], &indices[0]);
    make_crossed_scene(counts[1], &vertices[1], &indices[1]);
    for (c = 0; c < UNIT_CONFIGS; ++c) {
        const unit_config *config = &unit_configs[c];
        const char *name = config->name;
        size_t n = counts[config->scene], expected_bytes = 0;
        const float *v = vertices[config->scene];
        const uint32_t *ix = indices[config->scene];
        hairobb_build_options opt;
        hairobb_bvh *bvh = NULL;
        hairobb_stats stats;
        tree_walk w;
        long outside, missing, points, mismatches = 0, occluded_mismatches = 0, hits = 0;
        size_t aabb_types, obb_types, type;
        unsigned layout;
        int r;
        double t0 = (double)clock();
        memset(&opt, 0, sizeof opt);
        opt.nodes = config->nodes;
        opt.obb_layout = config->layout;
        opt.spatial_splits = config->spatial;
        opt.spatial_split_budget = config->budget;
        opt.clustering = config->clustering;
        CHECK(hairobb_build(v, 4 * n, ix, n, &opt, &bvh) == HAIROBB_OK, "build %s", name);
        if (!bvh) continue;
        hairobb_get_stats(bvh, &stats);

        memset(&w, 0, sizeof w);
        w.bvh = bvh;
        walk_tree(&w, bvh->root, 0);
        CHECK(w.bad_refs == 0, "%s: %ld bad node or leaf references", name, w.bad_refs);
        /* stats describe the tree that is there */
        for (type = 0; type < 16; ++type) expected_bytes += w.node_types[type] * node_size((unsigned)type);
        aabb_types = w.node_types[HAIROBB__REF_AABB] + w.node_types[HAIROBB__REF_QAABB];
        obb_types = w.node_types[HAIROBB__REF_OBB] + w.node_types[HAIROBB__REF_ROTATED] + w.node_types[HAIROBB__REF_QOBB];
#ifdef HAIROBB__REF_QOBB_PER_CHILD
        obb_types += w.node_types[HAIROBB__REF_QOBB_PER_CHILD];
#endif
        CHECK(stats.aabb_nodes == aabb_types && stats.obb_nodes == obb_types, "%s: stats %zu AABB %zu OBB nodes, tree %zu and %zu",
              name, stats.aabb_nodes, stats.obb_nodes, aabb_types, obb_types);
        CHECK(stats.leaves == w.leaf_count && stats.leaf_references == w.occ_count && bvh->leaf_prim_count == w.occ_count,
              "%s: stats %zu leaves %zu references, tree %zu and %zu", name, stats.leaves, stats.leaf_references, w.leaf_count, w.occ_count);
        CHECK(stats.max_depth == w.max_depth, "%s: stats depth %u, tree %u", name, stats.max_depth, w.max_depth);
        CHECK(stats.node_bytes == expected_bytes && bvh->node_bytes == expected_bytes, "%s: %zu node bytes for nodes of %zu", name,
              stats.node_bytes, expected_bytes);
        CHECK(hairobb_memory_bytes(bvh) >= stats.node_bytes + stats.leaf_bytes, "%s: memory_bytes %zu", name, hairobb_memory_bytes(bvh));
        /* the node types the options allow; the default layout is one of the others */
        layout = config->layout;
        if (layout == HAIROBB_OBB_DEFAULT) {
            unsigned other, last = HAIROBB_OBB_COMPRESSED;
#ifdef HAIROBB__REF_QOBB_PER_CHILD
            last = HAIROBB_OBB_COMPRESSED_PER_CHILD;
#endif
            for (other = 1; other <= last && layout == HAIROBB_OBB_DEFAULT; ++other) {
                hairobb_bvh *explicit_layout = NULL;
                hairobb_stats explicit_stats;
                opt.obb_layout = (hairobb_obb_layout)other;
                if (hairobb_build(v, 4 * n, ix, n, &opt, &explicit_layout) != HAIROBB_OK) continue;
                hairobb_get_stats(explicit_layout, &explicit_stats);
                if (memcmp(&explicit_stats, &stats, sizeof stats) == 0 && explicit_layout->node_bytes == bvh->node_bytes &&
                    memcmp(explicit_layout->nodes, bvh->nodes, bvh->node_bytes) == 0)
                    layout = other;
                hairobb_free(explicit_layout);
            }
            opt.obb_layout = config->layout;
            CHECK(layout != HAIROBB_OBB_DEFAULT, "%s: the default layout builds the tree of no explicit layout", name);
        }
        for (type = 0; type < 16; ++type) {
            int allowed;
            if (!w.node_types[type]) continue;
            if (layout == HAIROBB_OBB_DEFAULT) allowed = 1;     /* reported above */
            else if (layout == HAIROBB_OBB_COMPRESSED) allowed = type == HAIROBB__REF_QAABB || type == HAIROBB__REF_QOBB;
#ifdef HAIROBB__REF_QOBB_PER_CHILD
            else if (layout == HAIROBB_OBB_COMPRESSED_PER_CHILD)   /* float AABB nodes, float OBBs near the root */
                allowed = type == HAIROBB__REF_AABB || type == HAIROBB__REF_OBB || type == HAIROBB__REF_QOBB_PER_CHILD;
#endif
            else if (layout == HAIROBB_OBB_PER_CHILD) allowed = type == HAIROBB__REF_AABB || type == HAIROBB__REF_OBB;
            else allowed = type == HAIROBB__REF_AABB || type == HAIROBB__REF_ROTATED;
            CHECK(allowed, "%s: %zu nodes of type %zu", name, w.node_types[type], type);
        }
        CHECK(config->nodes != HAIROBB_NODES_AABB_ONLY || stats.obb_nodes == 0, "%s: %zu OBB nodes", name, stats.obb_nodes);
        CHECK(config->nodes != HAIROBB_NODES_OBB_ONLY || stats.aabb_nodes == 0, "%s: %zu AABB nodes", name, stats.aabb_nodes);
        CHECK(config->nodes != HAIROBB_NODES_MIXED || config->scene != 0 || (stats.obb_nodes > 0 && stats.aabb_nodes > 0),
              "%s: %zu AABB and %zu OBB nodes", name, stats.aabb_nodes, stats.obb_nodes);
        /* references: one per segment, or up to the budget more with spatial splits */
        if (config->spatial == HAIROBB_ON) {
            size_t budget = (size_t)((double)n * (config->budget > 0.0f ? config->budget : 0.25f));
            CHECK(stats.leaf_references >= n && stats.leaf_references <= n + budget, "%s: %zu references for %zu segments, budget %zu",
                  name, stats.leaf_references, n, budget);
            CHECK(!config->expect_clipping || stats.leaf_references > n, "%s: spatial splits clipped nothing (%zu references)", name,
                  stats.leaf_references);
        } else {
            CHECK(stats.leaf_references == n, "%s: %zu leaf references for %zu segments", name, stats.leaf_references, n);
        }
        if (config->expect_clusters) {
            /* the scene is built for clusters: they must change the tree */
            hairobb_bvh *plain = NULL;
            hairobb_stats plain_stats;
            opt.clustering = HAIROBB_OFF;
            CHECK(hairobb_build(v, 4 * n, ix, n, &opt, &plain) == HAIROBB_OK, "%s: build without clustering", name);
            hairobb_get_stats(plain, &plain_stats);
            CHECK(memcmp(&plain_stats, &stats, sizeof stats) != 0, "%s: clustering changed nothing", name);
            hairobb_free(plain);
        }
        outside = points_outside(&w, n, &missing, &points);
        CHECK(missing == 0, "%s: %ld segments in no leaf", name, missing);
        CHECK(outside == 0, "%s: %ld of %ld ribbon samples outside the boxes of every leaf path of their segment", name, outside, points);
        printf("%s: %zu AABB + %zu OBB nodes, %zu leaves, %zu references for %zu segments, depth %u\n", name, stats.aabb_nodes,
               stats.obb_nodes, stats.leaves, stats.leaf_references, n, stats.max_depth);
        free_walk(&w);

        /* the BVH finds exactly what a loop over all segments with the same kernel finds */
        for (r = 0; r < 3000; ++r) {
            hairobb_ray ray = random_ray();
            hairobb_hit hit;
            hairobb__ray_state rs;
            uint32_t p;
            int brute = 0, got = hairobb_intersect1(bvh, &ray, &hit);
            hairobb__ray_setup(&rs, bvh, &ray);
            for (p = 0; p < n; ++p) brute |= segment_test(bvh, &rs, p);
            if (brute != got || (got && (hit.t != rs.line.tfar || (hit.prim_id != rs.best.prim && !hits_at(bvh, &ray, hit.prim_id, hit.t, n)))))
                ++mismatches;
            if (hairobb_occluded1(bvh, &ray) != got) ++occluded_mismatches;
            if (got && !(hit.t >= ray.tnear && hit.u >= 0.0f && hit.u <= 1.0f && hit.v >= -1.0f && hit.v <= 1.0f)) ++mismatches;
            if (!got && hit.prim_id != HAIROBB_INVALID_ID) ++mismatches;
            hits += got;
        }
        CHECK(hits > 300, "%s: only %ld of 3000 rays hit", name, hits);
        CHECK(mismatches == 0, "%s: %ld rays where BVH and brute force differ", name, mismatches);
        CHECK(occluded_mismatches == 0, "%s: %ld rays where occluded1 and intersect1 disagree", name, occluded_mismatches);
        hairobb_free(bvh);
        printf("%s: checked in %.2f s\n", name, ((double)clock() - t0) / CLOCKS_PER_SEC);
    }
    free(vertices[0]);
    free(indices[0]);
    free(vertices[1]);
    free(indices[1]);
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
        hairobb_ray ray = {{0.5f, 0.0f, -2.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY, 0.0f};
        hairobb_hit hit;
        ref_hit ref;
        float lo[3], hi[3];
        hairobb_bounds(bvh, lo, hi);
        ray.org[1] = (float)(hairobb__bezier((const float[]){0, 0.4f, -0.1f, 0.2f}, 0.5f, NULL, NULL));
        if (ref_intersect_segment(vertices, indices, 0, ray.org, ray.dir, 0.0, INFINITY, &ref)) {
            CHECK(hairobb_intersect1(bvh, &ray, &hit), "hit expected");
            ray.tfar = (float)ref.t * 0.999f;
            hit.instance_id = 7u;   /* a miss writes both ids, whatever the hit held */
            CHECK(!hairobb_intersect1(bvh, &ray, &hit) && hit.prim_id == HAIROBB_INVALID_ID && hit.instance_id == HAIROBB_INVALID_ID,
                  "tfar before the hit: a miss, both ids HAIROBB_INVALID_ID");
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
    hairobb_ray ray = {{0.0f, 0.0f, 0.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY, 0.0f};
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
    /* 0: all on one line; 1: exponential spacing; 2: zero radius, spread
       over 3e-38, so bins of the centroids would be 1e-39 wide (an
       overflowing bin scale, undefined conversion to int, found by the .hair
       fuzzer); the ribbons are too thin to hit, the rays must still agree */
    for (scene = 0; scene < 3; ++scene) {
        float *vertices = (float *)malloc(16 * sizeof(float) * n);
        uint32_t *indices = (uint32_t *)malloc(sizeof(uint32_t) * n);
        hairobb_bvh *bvh = NULL;
        hairobb_stats stats;
        long mismatches = 0, hits = 0;
        int r, k;
        for (i = 0; i < n; ++i) {
            float x = scene == 0 ? 0.0f : scene == 1 ? (float)pow(1.01, (double)i) - 1.0f : (float)i * 1e-41f;
            for (k = 0; k < 4; ++k) {
                float *v = vertices + 16 * i + 4 * k;
                v[0] = x; v[1] = 0.3f * (float)k; v[2] = 0.05f * (float)(k * (3 - k)); v[3] = scene == 2 ? 0.0f : 0.01f;
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
            hairobb_ray ray = {{0.0f, 0.0f, -3.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY, 0.0f};
            hairobb_hit hit;
            hairobb__ray_state rs;
            uint32_t p;
            int brute = 0, got;
            ray.org[0] = scene != 1 ? 0.02f * (rnd() - 0.5f) : 20.0f * rnd();
            ray.org[1] = 0.9f * rnd();
            got = hairobb_intersect1(bvh, &ray, &hit);
            hairobb__ray_setup(&rs, bvh, &ray);
            for (p = 0; p < n; ++p) brute |= segment_test(bvh, &rs, p);
            if (brute != got || (got && hit.t != rs.line.tfar) || hairobb_occluded1(bvh, &ray) != got) ++mismatches;
            hits += got;
        }
        CHECK(scene == 2 || hits > 40, "degenerate scene %d: %ld hits of 400 rays", scene, hits);
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
    opt.obb_layout = (hairobb_obb_layout)9;
    CHECK(hairobb_build(vertices, 32, indices, n, &opt, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT && bvh == NULL, "bad OBB layout");
    memset(&opt, 0, sizeof opt);
    opt.spatial_splits = (hairobb_switch)7;
    CHECK(hairobb_build(vertices, 32, indices, n, &opt, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT && bvh == NULL, "bad spatial_splits");
    memset(&opt, 0, sizeof opt);
    opt.clustering = (hairobb_switch)7;
    CHECK(hairobb_build(vertices, 32, indices, n, &opt, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT && bvh == NULL, "bad clustering");
    {
        static const float bad_budgets[] = {-1.0f, NAN, 5.0f};
        int i;
        for (i = 0; i < 3; ++i) {
            memset(&opt, 0, sizeof opt);
            opt.spatial_splits = HAIROBB_ON;
            opt.spatial_split_budget = bad_budgets[i];
            CHECK(hairobb_build(vertices, 32, indices, n, &opt, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT && bvh == NULL,
                  "spatial_split_budget %g", (double)bad_budgets[i]);
        }
    }
    memset(&opt, 0, sizeof opt);
    opt.curve_pieces = 17;
    CHECK(hairobb_build(vertices, 32, indices, n, &opt, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT, "17 pieces");
    CHECK(hairobb_build(vertices, 32, indices, n, NULL, &bvh) == HAIROBB_OK, "valid again");
    CHECK(!hairobb_intersect1(bvh, NULL, NULL) && !hairobb_occluded1(NULL, NULL), "NULL to the tracers");
    hairobb_free(bvh);
    hairobb_free(NULL);
    CHECK(strcmp(hairobb_result_string((hairobb_result)99), "unknown hairobb_result") == 0, "unknown result string");

    /* options.simd: the compiler's baseline path, or AVX2 where the CPU has
       it (dispatched where the baseline lacks it); any other is UNSUPPORTED */
    {
#if defined(__x86_64__) || defined(__i386__)
        int have_avx2 = __builtin_cpu_supports("avx2") != 0, k;
#else
        int have_avx2 = 0, k;
#endif
        hairobb_simd baseline =
#if defined(__aarch64__)
            HAIROBB_SIMD_NEON;
#elif defined(__AVX2__)
            HAIROBB_SIMD_AVX2;
#elif defined(__AVX__)
            HAIROBB_SIMD_AVX;
#elif defined(__SSE4_1__)
            HAIROBB_SIMD_SSE41;
#else
            HAIROBB_SIMD_SSE2;
#endif
        for (k = HAIROBB_SIMD_AUTO; k <= HAIROBB_SIMD_NEON; ++k) {
            hairobb_simd asked = (hairobb_simd)k;
            hairobb_simd expect = asked == HAIROBB_SIMD_AUTO ? (have_avx2 ? HAIROBB_SIMD_AVX2 : baseline) : asked;
            int runs = asked == HAIROBB_SIMD_AUTO || asked == baseline || (asked == HAIROBB_SIMD_AVX2 && have_avx2);
            hairobb_result r;
            memset(&opt, 0, sizeof opt);
            opt.simd = asked;
            r = hairobb_build(vertices, 32, indices, n, &opt, &bvh);
            if (runs) {
                CHECK(r == HAIROBB_OK && hairobb_get_simd(bvh) == expect, "simd %s: %s, traces with %s",
                      hairobb_simd_string(asked), hairobb_result_string(r), bvh ? hairobb_simd_string(hairobb_get_simd(bvh)) : "-");
                hairobb_free(bvh);
            } else {
                CHECK(r == HAIROBB_ERROR_UNSUPPORTED && bvh == NULL, "simd %s: %s", hairobb_simd_string(asked),
                      hairobb_result_string(r));
            }
        }
        opt.simd = (hairobb_simd)(HAIROBB_SIMD_NEON + 1);
        CHECK(hairobb_build(vertices, 32, indices, n, &opt, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT && bvh == NULL,
              "simd out of range");
        CHECK(hairobb_get_simd(NULL) == HAIROBB_SIMD_NONE, "simd of a NULL BVH");
        CHECK(strcmp(hairobb_simd_string(HAIROBB_SIMD_SSE41), "SSE4.1") == 0 &&
              strcmp(hairobb_simd_string(HAIROBB_SIMD_NEON), "NEON") == 0 &&
              strcmp(hairobb_simd_string((hairobb_simd)99), "unknown hairobb_simd") == 0, "simd names");
    }
    free(vertices);
    free(indices);
}

/* Progress callback for the allocation tests: counts calls; cancels at
   the first call (when = 0), at the first fraction of at least 1/2 (1) or
   at the first fraction of 1 (2; the closing call has 1), or never (-1).
   How many calls a build makes may depend on its threads; these three
   come in every build. */
typedef struct cancel_log {
    int when, calls, cancelled_at;   /* cancelled_at: the call that cancelled, -1 */
    int monotone;
    float last;
} cancel_log;

static void cancel_log_init(cancel_log *log, int when)
{
    memset(log, 0, sizeof *log);
    log->when = when;
    log->cancelled_at = -1;
    log->monotone = 1;
}

static int cancel_progress(void *user, float fraction)
{
    cancel_log *log = (cancel_log *)user;
    int cancel = log->when == 0 || (log->when == 1 && fraction >= 0.5f) || (log->when == 2 && fraction == 1.0f);
    if (log->calls > 0 && !(fraction >= log->last)) log->monotone = 0;
    log->last = fraction;
    if (cancel && log->cancelled_at < 0) log->cancelled_at = log->calls;
    ++log->calls;
    return cancel;
}

/* Every allocation of a build failing in turn gives OUT_OF_MEMORY, no BVH
   and no leak: default options, spatial splits (on a scene they clip),
   clustering, and without the copy (its vertex offsets). Cancelling from
   the progress callback at the first, a middle and the closing call
   gives CANCELLED, no BVH, no leak and no call after
   the cancelling one; with both a cancel and a failing allocation, the
   result is that of the one that came (either, if both did). */
/* A user's parallel_for: the tasks on the calling thread, last first, or
   (skip_first) all but task 0, which breaks its contract. */
static int skip_first;
static unsigned parallel_for_calls;
static void for_backwards(void *user, unsigned count, hairobb_task_fn run, void *context)
{
    unsigned i;
    (void)user;
    parallel_for_calls++;
    for (i = count; i > (skip_first ? 1u : 0u); --i) run(context, i - 1);
}

static void test_allocation_failure(void)
{
    static const struct {
        const char *name;
        int scene;
        hairobb_obb_layout layout;
        hairobb_switch spatial, clustering;
        int parallel_for;
        hairobb_switch copy;
    } configs[] = {
        {"default options", 0, HAIROBB_OBB_DEFAULT, HAIROBB_AUTO, HAIROBB_AUTO, 0, HAIROBB_AUTO},
        {"spatial splits", 1, HAIROBB_OBB_COMPRESSED, HAIROBB_ON, HAIROBB_OFF, 0, HAIROBB_AUTO},
        {"spatial splits and clustering, per-child OBBs", 1, HAIROBB_OBB_PER_CHILD, HAIROBB_ON, HAIROBB_ON, 0, HAIROBB_AUTO},
        {"default options through a parallel_for", 0, HAIROBB_OBB_DEFAULT, HAIROBB_AUTO, HAIROBB_AUTO, 1, HAIROBB_AUTO},
        {"without the copy, through a parallel_for", 0, HAIROBB_OBB_DEFAULT, HAIROBB_AUTO, HAIROBB_AUTO, 1, HAIROBB_OFF},
    };
    static const char *when_names[] = {"the first call", "the first call past 1/2", "the call with 1"};
    float *vertices[2];
    uint32_t *indices[2];
    size_t counts[2] = {3000, 1500};
    int c;
    make_scene(counts[0], &vertices[0], &indices[0]);
    make_crossed_scene(counts[1], &vertices[1], &indices[1]);
    for (c = 0; c < (int)(sizeof configs / sizeof configs[0]); ++c) {
        const char *name = configs[c].name;
        size_t n = counts[configs[c].scene];
        const float *v = vertices[configs[c].scene];
        const uint32_t *ix = indices[configs[c].scene];
        long fail_at, allocations;
        int failures_right = 1, both_right = 1, when;
        test_allocator counter;
        hairobb_build_options opt;
        hairobb_bvh *bvh;
        hairobb_stats stats;
        cancel_log log;
        test_allocator_init(&counter, -1);
        memset(&opt, 0, sizeof opt);
        opt.obb_layout = configs[c].layout;
        opt.spatial_splits = configs[c].spatial;
        opt.spatial_split_budget = 1.0f;
        opt.clustering = configs[c].clustering;
        opt.bezier_copy = configs[c].copy;
        opt.allocator_user = &counter;
        opt.parallel_for = configs[c].parallel_for ? for_backwards : NULL;
        parallel_for_calls = 0;
        CHECK(hairobb_build(v, 4 * n, ix, n, &opt, &bvh) == HAIROBB_OK, "%s: counting build", name);
        /* the tasks, and the last pass's parts (the world boxes' too above 32k segments) */
        CHECK(configs[c].parallel_for ? parallel_for_calls >= 1 : parallel_for_calls == 0, "%s: parallel_for called %u times", name,
              parallel_for_calls);
        allocations = counter.calls;
        hairobb_get_stats(bvh, &stats);
        hairobb_free(bvh);
        CHECK(counter.live == 0 && counter.bad_frees == 0, "%s: %ld allocations live after free, %ld bad frees", name, counter.live,
              counter.bad_frees);
        CHECK(allocations >= 4, "%s: only %ld allocations", name, allocations);
        CHECK(configs[c].spatial != HAIROBB_ON || configs[c].clustering == HAIROBB_ON || stats.leaf_references > n,
              "%s: nothing clipped (%zu references for %zu segments)", name, stats.leaf_references, n);
        for (fail_at = 0; fail_at < allocations; ++fail_at) {
            test_allocator a;
            hairobb_result r;
            test_allocator_init(&a, fail_at);
            opt.allocator_user = &a;
            bvh = (hairobb_bvh *)&a;
            r = hairobb_build(v, 4 * n, ix, n, &opt, &bvh);
            if (r != HAIROBB_ERROR_OUT_OF_MEMORY || !a.failed || bvh != NULL || a.live != 0 || a.bad_frees != 0) {
                failures_right = 0;
                printf("%s: allocation %ld failing: result %d, %ld live, %ld frees of memory not allocated\n", name, fail_at, (int)r,
                       a.live, a.bad_frees);
            }
            if (r == HAIROBB_OK) hairobb_free(bvh);
        }
        CHECK(failures_right, "%s: each of %ld failing allocations gives OUT_OF_MEMORY, no BVH and no leak", name, allocations);

        /* cancelling */
        opt.progress = cancel_progress;
        opt.progress_user = &log;
        for (when = -1; when < 3; ++when) {
            test_allocator a;
            hairobb_result r;
            test_allocator_init(&a, -1);
            cancel_log_init(&log, when);
            opt.allocator_user = &a;
            bvh = (hairobb_bvh *)&a;
            r = hairobb_build(v, 4 * n, ix, n, &opt, &bvh);
            if (when < 0) {
                CHECK(r == HAIROBB_OK && bvh != NULL && log.calls >= 1 && log.last == 1.0f && log.monotone,
                      "%s: a build with a progress callback: %s, %d calls, last %g", name, hairobb_result_string(r), log.calls,
                      (double)log.last);
                if (r == HAIROBB_OK) hairobb_free(bvh);
            } else {
                CHECK(r == HAIROBB_ERROR_CANCELLED && bvh == NULL && log.cancelled_at + 1 == log.calls,
                      "%s: cancel at %s: %s, %d calls, cancelled at call %d", name, when_names[when], hairobb_result_string(r),
                      log.calls, log.cancelled_at);
                if (r == HAIROBB_OK) hairobb_free(bvh);
            }
            CHECK(a.live == 0 && a.bad_frees == 0, "%s: cancel at %s: %ld allocations leaked, %ld bad frees", name,
                  when < 0 ? "no call" : when_names[when], a.live, a.bad_frees);
        }

        /* a cancel at the first call past 1/2 and each allocation failing in turn */
        for (fail_at = 0; fail_at < allocations; ++fail_at) {
            test_allocator f;
            hairobb_result r;
            int cancelled;
            test_allocator_init(&f, fail_at);
            cancel_log_init(&log, 1);
            opt.allocator_user = &f;
            bvh = (hairobb_bvh *)&f;
            r = hairobb_build(v, 4 * n, ix, n, &opt, &bvh);
            cancelled = log.cancelled_at >= 0;
            if (!(f.failed || cancelled) || (f.failed && !cancelled && r != HAIROBB_ERROR_OUT_OF_MEMORY) ||
                (cancelled && !f.failed && r != HAIROBB_ERROR_CANCELLED) ||
                (r != HAIROBB_ERROR_OUT_OF_MEMORY && r != HAIROBB_ERROR_CANCELLED) || bvh != NULL || f.live != 0 || f.bad_frees != 0) {
                both_right = 0;
                printf("%s: allocation %ld failing (%s), cancel past 1/2 (%s): result %d, %ld live, %ld bad frees\n", name, fail_at,
                       f.failed ? "came" : "did not come", cancelled ? "came" : "did not come", (int)r, f.live, f.bad_frees);
            }
            if (r == HAIROBB_OK) hairobb_free(bvh);
        }
        CHECK(both_right, "%s: a failing allocation and a cancel: the result of the one that came, no BVH, no leak", name);
    }
    /* a parallel_for that skips a task: an error, not a tree with a hole */
    {
        test_allocator a;
        hairobb_build_options opt;
        hairobb_bvh *bvh = (hairobb_bvh *)&a;
        hairobb_result r;
        test_allocator_init(&a, -1);
        memset(&opt, 0, sizeof opt);
        opt.allocator_user = &a;
        opt.parallel_for = for_backwards;
        skip_first = 1;
        r = hairobb_build(vertices[0], 4 * counts[0], indices[0], counts[0], &opt, &bvh);
        skip_first = 0;
        CHECK(r == HAIROBB_ERROR_INVALID_ARGUMENT && bvh == NULL && a.live == 0 && a.bad_frees == 0,
              "parallel_for skipping a task: %s, %ld blocks live", hairobb_result_string(r), a.live);
    }
    free(vertices[0]);
    free(indices[0]);
    free(vertices[1]);
    free(indices[1]);
}

/* What a build holds beyond the BVH it returns (the peak of its
   allocations minus hairobb_memory_bytes): at most 48 bytes a segment on
   combed fur with the default options, on 1 and 2 threads; with spatial
   splits (budget 0.25: 1.25 positions a segment, 36 bytes each) as well.
   The bound holds while node bytes stay under 48 a segment (the tasks'
   nodes and the BVH's are live at once, as they are copied). */
static void test_build_memory(void)
{
    static const struct { const char *name; hairobb_switch spatial; unsigned threads; hairobb_switch copy; } configs[] = {
        {"default options, 1 thread", HAIROBB_AUTO, 1, HAIROBB_AUTO},
        {"default options, 2 threads", HAIROBB_AUTO, 2, HAIROBB_AUTO},
        {"spatial splits, 2 threads", HAIROBB_ON, 2, HAIROBB_AUTO},
        {"without the copy, 2 threads", HAIROBB_AUTO, 2, HAIROBB_OFF},
    };
    hair_scene s;
    size_t c;
    if (scene_combed(&s, 50000, 1) != 0) { CHECK(0, "combed fur for the memory test"); return; }
    for (c = 0; c < sizeof configs / sizeof configs[0]; ++c) {
        test_allocator a;
        hairobb_build_options opt;
        hairobb_bvh *bvh = NULL;
        hairobb_result r;
        test_allocator_init(&a, -1);
        memset(&opt, 0, sizeof opt);
        opt.allocator_user = &a;
        opt.spatial_splits = configs[c].spatial;
        opt.threads = configs[c].threads;
        opt.bezier_copy = configs[c].copy;
        r = hairobb_build(s.vertices, s.vertex_count, s.indices, s.segment_count, &opt, &bvh);
        CHECK(r == HAIROBB_OK, "%s: build: %s", configs[c].name, hairobb_result_string(r));
        if (r != HAIROBB_OK) continue;
        CHECK(a.bytes == hairobb_memory_bytes(bvh), "%s: %zu bytes live after the build, memory_bytes %zu", configs[c].name,
              a.bytes, hairobb_memory_bytes(bvh));
        CHECK(a.peak_bytes - hairobb_memory_bytes(bvh) <= 48 * s.segment_count,
              "%s: peak transient %.1f bytes a segment (at most 48), BVH %.1f", configs[c].name,
              (double)(a.peak_bytes - hairobb_memory_bytes(bvh)) / (double)s.segment_count,
              (double)hairobb_memory_bytes(bvh) / (double)s.segment_count);
        hairobb_free(bvh);
        CHECK(a.live == 0 && a.bytes == 0, "%s: %ld blocks live after hairobb_free", configs[c].name, a.live);
    }
    scene_free(&s);
}

int main(void)
{
    test_frames();
    test_hair_space();
    test_clipped_parts();
    test_bounds_and_traversal();
    test_hit_attributes();
    test_roots_hidden_in_one_piece();
    test_degenerate_trees();
    test_bad_rays();
    test_bad_input();
    test_allocation_failure();
    test_build_memory();
    return check_summary();
}
