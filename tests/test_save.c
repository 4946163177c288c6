/* test_save.c - BVHs saved and loaded (hairobb_save, hairobb_load and the
   file variants):
   - round trips of several scenes x option sets (every OBB layout, node
     policies, spatial splits, clustering, every basis, pieces precision,
     leaf sizes 1 and 15): a build on 3 threads saves to the same bytes as
     on 1; the loaded BVH has the saved one's statistics
     and memory, saves to the same bytes, and traces every ray to the same
     bits (t, u, v, Ng, tangent, prim_id; intersect1, occluded1 and a
     secondary ray from each hit) on every SIMD path this build has; on
     Bezier input its hits also agree with the double-precision reference;
   - the hit filter and SIMD path come from the load's options;
   - a too-small buffer, every truncation, every single bit flip of a small
     saved BVH (the checksum), and structural lies with the checksum fixed
     up (cycles, shared or overlapping nodes, offsets out of range or into
     a node, types the layout does not build, leaf ranges, segment ids,
     depth past the traversal stack, overflowing counts, header fields):
     each an error, never a crash;
   - other hair (vertices, indices, tangents, segment count, basis): the
     mismatch error, and loads with the check skipped where that is safe;
   - every allocation of a load failing in turn: out of memory, no leak;
   - a one-segment BVH (a leaf root, no node memory) round trips;
   - the file variants round trip; a missing file or a directory is
     HAIROBB_ERROR_IO, an empty or truncated file, or one announcing 2^40
     node bytes, HAIROBB_ERROR_INVALID_FILE before any allocation. */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE   /* madvise(MADV_HUGEPAGE), as gnu C and C++ builds have it (HAIROBB_NO_HUGE_PAGES) */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "test_alloc.h"   /* counts live blocks and fails the fail_at-th allocation */
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "check.h"
#include "compare.h"
#include "reference.h"
#include "scenes.h"
#include "scratch.h"

/* ------------------------------------------------------------------------ */
/* Rays and comparisons */

#define RAYS 2048
typedef struct ray_set { float org[3 * RAYS], dir[3 * RAYS]; } ray_set;

/* half camera rays, half random rays aimed at random segments as
   test_options.c aims them: from 0.05-1 away, within 1.5 radii, at least
   30 degrees off the segment's tangent */
static void make_rays(const hair_scene *s, ray_set *rays, uint64_t seed)
{
    scene_rng rng;
    size_t i, half = RAYS / 2;
    scene_camera_rays(s, 32, (int)(half / 32), rays->org, rays->dir);
    scene_rng_seed(&rng, seed);
    for (i = half; i < RAYS; ++i) {
        const float *cp = s->vertices + 4 * (size_t)s->indices[scene_rng_u32(&rng) % s->segment_count];
        scene_ray_near_segment(cp, &rng, rays->org + 3 * i, rays->dir + 3 * i);
    }
}

/* Rays of `rays` traced through both BVHs: how many answers differ in any bit. */
static size_t count_differences(const hairobb_bvh *a, const hairobb_bvh *b, const ray_set *rays, size_t *hits)
{
    size_t i, differ = 0;
    static const float bounce[3] = {0.36f, 0.48f, 0.8f};
    for (i = 0; i < RAYS; ++i) {
        hairobb_ray ray, next;
        hairobb_hit ha, hb, na, nb;
        int ga, gb;
        memset(&ha, 0, sizeof ha); memset(&hb, 0, sizeof hb); memset(&na, 0, sizeof na); memset(&nb, 0, sizeof nb);
        memcpy(ray.org, rays->org + 3 * i, sizeof ray.org);
        memcpy(ray.dir, rays->dir + 3 * i, sizeof ray.dir);
        ray.tnear = 0.0f;
        ray.tfar = INFINITY;
        ga = hairobb_intersect1(a, &ray, &ha);
        gb = hairobb_intersect1(b, &ray, &hb);
        if (!same_hit(ga, &ha, gb, &hb)) ++differ;
        if (hairobb_occluded1(a, &ray) != hairobb_occluded1(b, &ray)) ++differ;
        if (!ga) continue;
        ++*hits;
        /* a secondary ray leaving the hit */
        next.org[0] = ray.org[0] + ha.t * ray.dir[0];
        next.org[1] = ray.org[1] + ha.t * ray.dir[1];
        next.org[2] = ray.org[2] + ha.t * ray.dir[2];
        memcpy(next.dir, bounce, sizeof next.dir);
        next.tnear = 0.0f;
        next.tfar = INFINITY;
        ga = hairobb_intersect1_from(a, &ha, &next, &na);
        gb = hairobb_intersect1_from(b, &ha, &next, &nb);
        if (!same_hit(ga, &na, gb, &nb)) ++differ;
        if (hairobb_occluded1_from(a, &ha, &next) != hairobb_occluded1_from(b, &ha, &next)) ++differ;
    }
    return differ;
}

/* Hits of a loaded BVH against the reference on every 2nd ray aimed at a
   segment: the bar of test_options.c on such rays (<= 1 disagreement in
   10,000 rays, |dt| <= 1e-3 r). */
static void check_reference(const char *name, const hair_scene *s, const hairobb_bvh *bvh, const ray_set *rays)
{
    ref_scene *reference = ref_build(s->vertices, s->vertex_count, s->indices, s->segment_count);
    size_t i, tried = 0, disagree = 0, bad_t = 0, hits = 0;
    CHECK(reference != NULL, "%s: reference build", name);
    if (!reference) return;
    for (i = RAYS / 2; i < RAYS; i += 2) {
        hairobb_ray ray;
        hairobb_hit hit;
        ref_hit want;
        int got, expected;
        memcpy(ray.org, rays->org + 3 * i, sizeof ray.org);
        memcpy(ray.dir, rays->dir + 3 * i, sizeof ray.dir);
        ray.tnear = 0.0f;
        ray.tfar = INFINITY;
        got = hairobb_intersect1(bvh, &ray, &hit);
        expected = ref_intersect(reference, ray.org, ray.dir, 0.0, INFINITY, &want);
        ++tried;
        hits += (size_t)expected;
        if (got != expected) ++disagree;
        else if (got && !(fabs((double)hit.t - want.t) <= 1e-3 * want.r)) ++bad_t;
    }
    CHECK(disagree * 10000 <= tried && bad_t == 0 && hits > tried / 16,
          "%s: loaded BVH against the reference: %zu of %zu rays disagree, %zu far in t, %zu hits", name, disagree, tried,
          bad_t, hits);
    ref_free(reference);
}

/* ------------------------------------------------------------------------ */
/* Round trips */

typedef struct hair_input {
    hairobb_basis basis;
    const float *vertices, *tangents;
    size_t vertex_count;
    const uint32_t *indices;
    size_t segment_count;
} hair_input;

/* Tangents for Hermite input: the chord to the next control point, 3x. */
static float *make_tangents(const hair_scene *s)
{
    float *t = (float *)malloc(4 * sizeof(float) * s->vertex_count);
    size_t v, k;
    if (!t) return NULL;
    for (v = 0; v < s->vertex_count; ++v)
        for (k = 0; k < 4; ++k)
            t[4 * v + k] = v + 1 < s->vertex_count ? 3.0f * (s->vertices[4 * (v + 1) + k] - s->vertices[4 * v + k]) : 0.0f;
    return t;
}

static hair_input input_of(const hair_scene *s, hairobb_basis basis, const float *tangents)
{
    hair_input in;
    in.basis = basis;
    in.vertices = s->vertices;
    in.tangents = basis == HAIROBB_BASIS_HERMITE ? tangents : NULL;
    in.vertex_count = s->vertex_count;
    in.indices = s->indices;
    in.segment_count = s->segment_count;
    return in;
}

static unsigned char *save_of(const hairobb_bvh *bvh, size_t *size)
{
    unsigned char *blob;
    *size = hairobb_save_size(bvh);
    blob = (unsigned char *)malloc(*size);
    if (blob && hairobb_save(bvh, blob, *size) != HAIROBB_OK) { free(blob); blob = NULL; }
    return blob;
}

static hairobb_result load_of(const unsigned char *blob, size_t size, const hair_input *in, const hairobb_build_options *base,
                              hairobb_bvh **out)
{
    hairobb_build_options opt;
    if (base) opt = *base; else memset(&opt, 0, sizeof opt);
    opt.basis = in->basis;
    opt.tangents = in->tangents;
    return hairobb_load(blob, size, in->vertices, in->vertex_count, in->indices, in->segment_count, &opt, out);
}

static int same_stats(const hairobb_stats *a, const hairobb_stats *b)
{
    return a->aabb_nodes == b->aabb_nodes && a->obb_nodes == b->obb_nodes && a->leaves == b->leaves &&
           a->leaf_references == b->leaf_references && a->max_depth == b->max_depth && a->node_bytes == b->node_bytes &&
           a->leaf_bytes == b->leaf_bytes;
}

/* A loaded BVH refits as the saved one does: both moved to sheared points
   with larger radii, then saved, give the same bytes (frames, u ranges of
   clipped parts and the caller's indices all came back). */
static void refit_both(const char *name, hairobb_bvh *built, const unsigned char *blob, size_t size, const hair_input *in)
{
    hairobb_bvh *loaded = NULL;
    hairobb_build_options lo;
    float *moved = (float *)malloc(16 * in->vertex_count);
    unsigned char *a = NULL, *b = NULL;
    size_t size_a = 0, size_b = 0, i;
    hairobb_result ra, rb;
    memset(&lo, 0, sizeof lo);
    lo.basis = in->basis;
    lo.tangents = in->tangents;
    if (!moved || load_of(blob, size, in, &lo, &loaded) != HAIROBB_OK) {
        CHECK(0, "%s: refit check: no memory or no load", name);
        free(moved);
        return;
    }
    for (i = 0; i < in->vertex_count; ++i) {
        const float *p = in->vertices + 4 * i;
        moved[4 * i] = p[0] + 0.25f * p[1];
        moved[4 * i + 1] = p[1];
        moved[4 * i + 2] = p[2] - 0.125f * p[0];
        moved[4 * i + 3] = 1.25f * p[3];
    }
    ra = hairobb_refit_tangents(built, moved, in->tangents);
    rb = hairobb_refit_tangents(loaded, moved, in->tangents);
    CHECK(ra == HAIROBB_OK && rb == HAIROBB_OK, "%s: refit %s built, %s loaded", name, hairobb_result_string(ra),
          hairobb_result_string(rb));
    a = save_of(built, &size_a);
    b = save_of(loaded, &size_b);
    CHECK(a && b && size_a == size_b && size_a > 128 && memcmp(a + 128, b + 128, size_a - 128) == 0 &&
              hairobb_memory_bytes(built) == hairobb_memory_bytes(loaded),
          "%s: the loaded BVH refits to other bytes than the built one", name);
    CHECK(a && size_a == size && memcmp(a + 128, blob + 128, size - 136) != 0, "%s: the refit changed no node", name);
    free(a);
    free(b);
    hairobb_free(loaded);
    free(moved);
}

static void round_trip(const char *name, const hair_scene *s, const hair_input *in, const hairobb_build_options *opt,
                       const ray_set *rays)
{
    static const hairobb_simd paths[] = {HAIROBB_SIMD_AUTO, HAIROBB_SIMD_NONE, HAIROBB_SIMD_SSE2, HAIROBB_SIMD_SSE41,
                                         HAIROBB_SIMD_AVX, HAIROBB_SIMD_AVX2};
    hairobb_build_options build_opt = *opt;
    hairobb_bvh *built = NULL, *loaded = NULL;
    hairobb_stats sb, sl;
    unsigned char *blob, *again;
    size_t size, size_again, p, paths_tried = 0, hits = 0;
    hairobb_result r;
    build_opt.basis = in->basis;
    build_opt.tangents = in->tangents;
    build_opt.threads = 1;
    r = hairobb_build(in->vertices, in->vertex_count, in->indices, in->segment_count, &build_opt, &built);
    CHECK(r == HAIROBB_OK, "%s: build: %s", name, hairobb_result_string(r));
    if (r != HAIROBB_OK) return;
    blob = save_of(built, &size);
    CHECK(blob != NULL, "%s: save", name);
    if (!blob) { hairobb_free(built); return; }
    {
        /* the same tree on any thread count: the same bytes */
        hairobb_bvh *threaded = NULL;
        unsigned char *threaded_blob = NULL;
        size_t threaded_size = 0;
        build_opt.threads = 3;
        r = hairobb_build(in->vertices, in->vertex_count, in->indices, in->segment_count, &build_opt, &threaded);
        if (r == HAIROBB_OK) threaded_blob = save_of(threaded, &threaded_size);
        CHECK(threaded_blob && threaded_size == size && memcmp(threaded_blob, blob, size) == 0,
              "%s: a build on 3 threads saves to other bytes", name);
        free(threaded_blob);
        hairobb_free(threaded);
    }
    {
        hairobb_build_options on;
        memset(&on, 0, sizeof on);
        on.verify_hair = HAIROBB_ON;
        r = load_of(blob, size, in, &on, &loaded);
        CHECK(r == HAIROBB_OK && loaded, "%s: load, verify_hair on: %s", name, hairobb_result_string(r));
        hairobb_free(loaded);
        loaded = NULL;
    }
    r = load_of(blob, size, in, NULL, &loaded);
    CHECK(r == HAIROBB_OK && loaded, "%s: load: %s", name, hairobb_result_string(r));
    if (r == HAIROBB_OK) {
        hairobb_get_stats(built, &sb);
        hairobb_get_stats(loaded, &sl);
        CHECK(same_stats(&sb, &sl), "%s: loaded statistics differ (nodes %zu+%zu / %zu+%zu, leaves %zu / %zu, depth %u / %u)",
              name, sb.aabb_nodes, sb.obb_nodes, sl.aabb_nodes, sl.obb_nodes, sb.leaves, sl.leaves, sb.max_depth, sl.max_depth);
        CHECK(hairobb_memory_bytes(built) == hairobb_memory_bytes(loaded), "%s: memory %zu built, %zu loaded", name,
              hairobb_memory_bytes(built), hairobb_memory_bytes(loaded));
        CHECK(hairobb_get_simd(built) == hairobb_get_simd(loaded), "%s: the default path differs", name);
        again = save_of(loaded, &size_again);
        CHECK(again && size_again == size && memcmp(again, blob, size) == 0, "%s: the loaded BVH saves to other bytes", name);
        free(again);
        hairobb_free(loaded);
        loaded = NULL;
        /* every path this build and CPU have, against the built BVH on its default path */
        for (p = 0; p < sizeof paths / sizeof paths[0]; ++p) {
            hairobb_build_options lo;
            size_t differ;
            memset(&lo, 0, sizeof lo);
            lo.simd = paths[p];
            lo.basis = in->basis;
            lo.tangents = in->tangents;
            r = load_of(blob, size, in, &lo, &loaded);
            if (r == HAIROBB_ERROR_UNSUPPORTED) {
                hairobb_bvh *probe = NULL;
                /* unsupported at load exactly where the build says so */
                hairobb_result rb = hairobb_build(in->vertices, in->vertex_count, in->indices, in->segment_count, &lo, &probe);
                if (rb != HAIROBB_ERROR_UNSUPPORTED)
                    CHECK(0, "%s: path %s: load unsupported, build %s", name, hairobb_simd_string(paths[p]), hairobb_result_string(rb));
                hairobb_free(probe);
                continue;
            }
            CHECK(r == HAIROBB_OK, "%s: load on path %s: %s", name, hairobb_simd_string(paths[p]), hairobb_result_string(r));
            if (r != HAIROBB_OK) continue;
            CHECK(paths[p] == HAIROBB_SIMD_AUTO || hairobb_get_simd(loaded) == paths[p], "%s: path %s not taken", name,
                  hairobb_simd_string(paths[p]));
            hits = 0;
            differ = count_differences(built, loaded, rays, &hits);
            CHECK(differ == 0, "%s: path %s: %zu answers differ from the saved BVH's (%zu hits)", name,
                  hairobb_simd_string(paths[p]), differ, hits);
            CHECK(hits > RAYS / 32, "%s: only %zu of %d rays hit", name, hits, RAYS);
            /* the reference takes Bezier segments; the pieces precision has a bar of its own (test_options.c) */
            if (p == 0 && in->basis == HAIROBB_BASIS_BEZIER && opt->precision == HAIROBB_PRECISION_EXACT)
                check_reference(name, s, loaded, rays);
            ++paths_tried;
            hairobb_free(loaded);
            loaded = NULL;
        }
        CHECK(paths_tried >= 2, "%s: %zu SIMD paths loaded", name, paths_tried);
        refit_both(name, built, blob, size, in);
    }
    free(blob);
    hairobb_free(built);
}

typedef struct option_set {
    const char *name;
    hairobb_node_policy nodes;
    hairobb_obb_layout layout;
    hairobb_switch spatial, clustering;
    unsigned max_leaf, pieces;
    hairobb_precision precision;
    hairobb_basis basis;
} option_set;

static const option_set option_sets[] = {
    {"default", HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_AUTO, HAIROBB_AUTO, 0, 0, HAIROBB_PRECISION_EXACT, HAIROBB_BASIS_BEZIER},
    {"per-child", HAIROBB_NODES_MIXED, HAIROBB_OBB_PER_CHILD, HAIROBB_AUTO, HAIROBB_AUTO, 0, 0, HAIROBB_PRECISION_EXACT, HAIROBB_BASIS_BEZIER},
    {"shared rotation", HAIROBB_NODES_MIXED, HAIROBB_OBB_SHARED_ROTATION, HAIROBB_AUTO, HAIROBB_AUTO, 0, 0, HAIROBB_PRECISION_EXACT, HAIROBB_BASIS_BEZIER},
    {"compressed", HAIROBB_NODES_MIXED, HAIROBB_OBB_COMPRESSED, HAIROBB_AUTO, HAIROBB_AUTO, 0, 0, HAIROBB_PRECISION_EXACT, HAIROBB_BASIS_BEZIER},
    {"aabb-only", HAIROBB_NODES_AABB_ONLY, HAIROBB_OBB_DEFAULT, HAIROBB_AUTO, HAIROBB_AUTO, 0, 0, HAIROBB_PRECISION_EXACT, HAIROBB_BASIS_BEZIER},
    {"obb-only compressed", HAIROBB_NODES_OBB_ONLY, HAIROBB_OBB_COMPRESSED, HAIROBB_AUTO, HAIROBB_AUTO, 0, 0, HAIROBB_PRECISION_EXACT, HAIROBB_BASIS_BEZIER},
    {"spatial+clusters", HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_ON, HAIROBB_ON, 0, 0, HAIROBB_PRECISION_EXACT, HAIROBB_BASIS_BEZIER},
    {"leaf 1, pieces 5", HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_AUTO, HAIROBB_AUTO, 1, 5, HAIROBB_PRECISION_PIECES, HAIROBB_BASIS_BEZIER},
    {"leaf 15, pieces 16", HAIROBB_NODES_MIXED, HAIROBB_OBB_SHARED_ROTATION, HAIROBB_ON, HAIROBB_AUTO, 15, 16, HAIROBB_PRECISION_EXACT, HAIROBB_BASIS_BEZIER},
    {"b-spline", HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_AUTO, HAIROBB_AUTO, 0, 0, HAIROBB_PRECISION_EXACT, HAIROBB_BASIS_BSPLINE},
    {"catmull-rom", HAIROBB_NODES_MIXED, HAIROBB_OBB_COMPRESSED, HAIROBB_AUTO, HAIROBB_AUTO, 0, 0, HAIROBB_PRECISION_EXACT, HAIROBB_BASIS_CATMULL_ROM},
    {"hermite", HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_ON, HAIROBB_AUTO, 0, 0, HAIROBB_PRECISION_EXACT, HAIROBB_BASIS_HERMITE},
    {"linear", HAIROBB_NODES_MIXED, HAIROBB_OBB_PER_CHILD, HAIROBB_AUTO, HAIROBB_AUTO, 0, 0, HAIROBB_PRECISION_PIECES, HAIROBB_BASIS_LINEAR},
};

/* the sanitized build (asan_test_save_w4) round-trips the first scene only */
#ifndef SAVE_SCENES
#define SAVE_SCENES 4
#endif

static void round_trips(void)
{
    hair_scene scenes[4];
    static ray_set rays;
    int k, made[4];
    size_t o;
    made[0] = scene_combed(&scenes[0], 6000, 3) == 0;
    made[1] = scene_crossed(&scenes[1], 1500, 5) == 0;
    made[2] = scene_curly(&scenes[2], 3000, 7) == 0;
    made[3] = scene_random(&scenes[3], 2000, 11) == 0;
    for (k = 0; k < 4; ++k) {
        float *tangents;
        if (k >= SAVE_SCENES) { if (made[k]) scene_free(&scenes[k]); continue; }
        CHECK(made[k], "scene %d made", k);
        if (!made[k]) continue;
        tangents = make_tangents(&scenes[k]);
        make_rays(&scenes[k], &rays, 100 + (uint64_t)k);
        for (o = 0; o < sizeof option_sets / sizeof option_sets[0]; ++o) {
            const option_set *set = &option_sets[o];
            hairobb_build_options opt;
            hair_input in = input_of(&scenes[k], set->basis, tangents);
            char name[128];
            memset(&opt, 0, sizeof opt);
            opt.nodes = set->nodes;
            opt.obb_layout = set->layout;
            opt.spatial_splits = set->spatial;
            opt.clustering = set->clustering;
            opt.max_leaf_size = set->max_leaf;
            opt.curve_pieces = set->pieces;
            opt.precision = set->precision;
            snprintf(name, sizeof name, "%s, %s", scenes[k].name, set->name);
            round_trip(name, &scenes[k], &in, &opt, &rays);
        }
        free(tangents);
        scene_free(&scenes[k]);
    }
}

/* ------------------------------------------------------------------------ */
/* Bad bytes */

static void reseal(unsigned char *blob, size_t size)
{
    hairobb__put64(blob + size - 8, hairobb__save_checksum(blob, size));
}

/* A saved BVH rebuilt from parts: the header of `model`, these nodes and
   leaf_prims (counts set, padding zero), resealed. */
static unsigned char *compose(const unsigned char *model, uint64_t root, const unsigned char *nodes, size_t node_bytes,
                              const uint32_t *leaf_prims, size_t leaf_count, size_t *size)
{
    size_t leaf_bytes = (4 * leaf_count + 7) & ~(size_t)7;
    unsigned char *blob;
    *size = HAIROBB__SAVE_HEADER + node_bytes + leaf_bytes + 8;
    blob = (unsigned char *)calloc(1, *size);
    if (!blob) return NULL;
    memcpy(blob, model, HAIROBB__SAVE_HEADER);
    hairobb__put64(blob + HAIROBB__AT_ROOT, root);
    hairobb__put64(blob + HAIROBB__AT_NODE_BYTES, node_bytes);
    hairobb__put64(blob + HAIROBB__AT_LEAF_PRIMS, leaf_count);
    if (node_bytes) memcpy(blob + HAIROBB__SAVE_HEADER, nodes, node_bytes);
    memcpy(blob + HAIROBB__SAVE_HEADER + node_bytes, leaf_prims, 4 * leaf_count);
    reseal(blob, *size);
    return blob;
}

/* The inner nodes of a saved tree in the order of the walk: offset and type. */
typedef struct node_list { size_t count; size_t offset[4096]; unsigned type[4096]; } node_list;
static void list_nodes(const unsigned char *nodes, uint64_t ref, node_list *list)
{
    unsigned type = HAIROBB__REF_TYPE(ref);
    size_t offset = (size_t)(ref & ~(uint64_t)15), i;
    if (type == HAIROBB__REF_LEAF || type == HAIROBB__REF_EMPTY || list->count == 4096) return;
    list->offset[list->count] = offset;
    list->type[list->count++] = type;
    for (i = 0; i < HAIROBB__W; ++i) {
        uint64_t child;
        memcpy(&child, nodes + offset + hairobb__node_size(type) - 8 * HAIROBB__W + 8 * i, 8);
        list_nodes(nodes, child, list);
    }
}

static uint64_t *child_slot(unsigned char *nodes, const node_list *list, size_t node, int i)
{
    return (uint64_t *)(void *)(nodes + list->offset[node] + hairobb__node_size(list->type[node]) - 8 * HAIROBB__W + 8 * (size_t)i);
}

typedef struct small_hair {
    hair_scene scene;
    hair_input in;
    hairobb_bvh *bvh;
    unsigned char *blob;
    size_t size;
} small_hair;

static int small_hair_make(small_hair *h, size_t segments, const hairobb_build_options *opt)
{
    memset(h, 0, sizeof *h);
    if (scene_combed(&h->scene, segments, 21) != 0) return 0;
    h->in = input_of(&h->scene, HAIROBB_BASIS_BEZIER, NULL);
    if (hairobb_build(h->scene.vertices, h->scene.vertex_count, h->scene.indices, h->scene.segment_count, opt, &h->bvh) != HAIROBB_OK)
        return 0;
    h->blob = save_of(h->bvh, &h->size);
    return h->blob != NULL;
}

static void small_hair_free(small_hair *h)
{
    free(h->blob);
    hairobb_free(h->bvh);
    scene_free(&h->scene);
}

static hairobb_result load_small(const small_hair *h, const unsigned char *blob, size_t size)
{
    hairobb_bvh *bvh = NULL;
    hairobb_result r = load_of(blob, size, &h->in, NULL, &bvh);
    if ((r == HAIROBB_OK) != (bvh != NULL)) { CHECK(0, "load: result %d with bvh %p", (int)r, (void *)bvh); }
    hairobb_free(bvh);
    return r;
}

static void bad_bytes(void)
{
    small_hair h;
    hairobb_build_options opt;
    unsigned char *copy, *buffer;
    size_t cut, byte, bad_cuts = 0, bad_flips = 0, flips = 0, header_flips = 0;
    hairobb_result r;
    int bit;
    memset(&opt, 0, sizeof opt);
    opt.threads = 1;
    CHECK(small_hair_make(&h, 40, &opt), "small scene built and saved");
    if (!h.blob) { small_hair_free(&h); return; }
    printf("small saved BVH: %zu bytes, %zu segments\n", h.size, h.scene.segment_count);
    CHECK(load_small(&h, h.blob, h.size) == HAIROBB_OK, "the small BVH loads");

    /* a buffer too small: an error, nothing written */
    buffer = (unsigned char *)malloc(h.size);
    memset(buffer, 0xcd, h.size);
    r = hairobb_save(h.bvh, buffer, h.size - 1);
    for (byte = 0; byte < h.size && buffer[byte] == 0xcd; ++byte) {}
    CHECK(r == HAIROBB_ERROR_INVALID_ARGUMENT && byte == h.size, "save into %zu of %zu bytes: %s, %zu bytes untouched", h.size - 1,
          h.size, hairobb_result_string(r), byte);
    CHECK(hairobb_save(h.bvh, NULL, h.size) == HAIROBB_ERROR_INVALID_ARGUMENT && hairobb_save(NULL, buffer, h.size) ==
          HAIROBB_ERROR_INVALID_ARGUMENT && hairobb_save_size(NULL) == 0, "save of or into NULL");
    free(buffer);

    /* every truncation, and one byte more */
    for (cut = 0; cut < h.size; ++cut)
        if (load_small(&h, h.blob, cut) != HAIROBB_ERROR_INVALID_FILE) ++bad_cuts;
    copy = (unsigned char *)malloc(h.size + 1);
    memcpy(copy, h.blob, h.size);
    copy[h.size] = 0;
    CHECK(bad_cuts == 0 && load_small(&h, copy, h.size + 1) == HAIROBB_ERROR_INVALID_FILE,
          "%zu of %zu truncations (or one byte more) load or give another error than INVALID_FILE", bad_cuts, h.size);

    /* every bit of every byte flipped: version, byte order and width are
       UNSUPPORTED (but a version flipped to an older one this build reads,
       whose checksum then fails), everything else the checksum's
       INVALID_FILE */
    for (byte = 0; byte < h.size; ++byte)
        for (bit = 0; bit < 8; ++bit) {
            hairobb_result want = byte >= HAIROBB__AT_VERSION && byte < HAIROBB__AT_WIDTH + 4 ? HAIROBB_ERROR_UNSUPPORTED
                                                                                               : HAIROBB_ERROR_INVALID_FILE;
            memcpy(copy, h.blob, h.size);
            copy[byte] ^= (unsigned char)(1u << bit);
            if (byte >= HAIROBB__AT_VERSION && byte < HAIROBB__AT_VERSION + 4 && hairobb__get32(copy + HAIROBB__AT_VERSION) >= HAIROBB__SAVE_VERSION_OLDEST &&
                hairobb__get32(copy + HAIROBB__AT_VERSION) <= HAIROBB__SAVE_VERSION)
                want = HAIROBB_ERROR_INVALID_FILE;
            r = load_small(&h, copy, h.size);
            ++flips;
            if (want == HAIROBB_ERROR_UNSUPPORTED) ++header_flips;
            if (r != want) {
                if (bad_flips < 5) printf("byte %zu bit %d flipped: %s\n", byte, bit, hairobb_result_string(r));
                ++bad_flips;
            }
        }
    CHECK(bad_flips == 0, "%zu of %zu single bit flips not caught as they should be (%zu in version, byte order, width)", bad_flips,
          flips, header_flips);
    free(copy);
    small_hair_free(&h);
}

/* One structural lie: the nodes and leaves of the small BVH changed by
   `lie`, resealed, must give INVALID_FILE. */
typedef struct lie_state {
    unsigned char *nodes;
    size_t node_bytes;
    uint32_t *leaves;
    size_t leaf_count;
    uint64_t root;
    node_list list;
} lie_state;

static void lie_reset(lie_state *l, const small_hair *h)
{
    const hairobb_bvh *bvh = h->bvh;
    free(l->nodes);
    free(l->leaves);
    l->node_bytes = bvh->node_bytes;
    l->nodes = (unsigned char *)malloc(bvh->node_bytes + 64);
    memcpy(l->nodes, bvh->nodes, bvh->node_bytes);
    l->leaf_count = bvh->leaf_prim_count;
    l->leaves = (uint32_t *)malloc(4 * (bvh->leaf_prim_count + 16));
    memcpy(l->leaves, bvh->leaf_prims, 4 * bvh->leaf_prim_count);
    l->root = bvh->root;
    l->list.count = 0;
    list_nodes(l->nodes, l->root, &l->list);
}

static void expect_invalid(const char *what, const small_hair *h, const lie_state *l, const unsigned char *model)
{
    size_t size;
    unsigned char *blob = compose(model, l->root, l->nodes, l->node_bytes, l->leaves, l->leaf_count, &size);
    hairobb_result r = load_small(h, blob, size);
    CHECK(r == HAIROBB_ERROR_INVALID_FILE, "%s: %s", what, hairobb_result_string(r));
    free(blob);
}

/* the first inner child slot of node n, or -1 */
static int inner_child(lie_state *l, size_t n)
{
    int i;
    for (i = 0; i < HAIROBB__W; ++i) {
        unsigned type = HAIROBB__REF_TYPE(*child_slot(l->nodes, &l->list, n, i));
        if (type != HAIROBB__REF_LEAF && type != HAIROBB__REF_EMPTY) return i;
    }
    return -1;
}
static int leaf_child(lie_state *l, size_t n)
{
    int i;
    for (i = 0; i < HAIROBB__W; ++i)
        if (HAIROBB__REF_TYPE(*child_slot(l->nodes, &l->list, n, i)) == HAIROBB__REF_LEAF) return i;
    return -1;
}

static void structural_lies(void)
{
    small_hair h;
    hairobb_build_options opt;
    lie_state l;
    size_t n, size;
    int i, j;
    unsigned char *model;
    memset(&opt, 0, sizeof opt);
    memset(&l, 0, sizeof l);
    opt.threads = 1;
    opt.max_leaf_size = 4;
    CHECK(small_hair_make(&h, 600, &opt), "small scene built and saved");
    if (!h.blob) { small_hair_free(&h); return; }
    model = h.blob;
    lie_reset(&l, &h);
    CHECK(l.list.count >= 3 && l.list.count < 4096, "%zu inner nodes", l.list.count);
    {
        unsigned char *blob = compose(model, l.root, l.nodes, l.node_bytes, l.leaves, l.leaf_count, &size);
        CHECK(size == h.size && memcmp(blob, h.blob, size) == 0, "compose rebuilds the saved bytes");
        free(blob);
    }

    /* a cycle: a child pointing back at the root, and a node at itself */
    *child_slot(l.nodes, &l.list, 1, 0) = l.root;
    expect_invalid("a child pointing at the root", &h, &l, model);
    lie_reset(&l, &h);
    i = inner_child(&l, 0);
    *child_slot(l.nodes, &l.list, 0, i) = l.root;
    expect_invalid("the root its own child", &h, &l, model);
    /* a shared child: two slots naming one node */
    lie_reset(&l, &h);
    for (n = 0; n < l.list.count && inner_child(&l, n) < 0; ++n) {}
    i = inner_child(&l, n);
    j = i == 0 ? 1 : 0;
    *child_slot(l.nodes, &l.list, n, j) = *child_slot(l.nodes, &l.list, n, i);
    expect_invalid("two children naming one node", &h, &l, model);
    /* offsets out of range, into the middle of a node, of a type of another size */
    lie_reset(&l, &h);
    *child_slot(l.nodes, &l.list, 0, i = inner_child(&l, 0)) = (uint64_t)l.node_bytes | l.list.type[1];
    expect_invalid("a child at the end of the node memory", &h, &l, model);
    lie_reset(&l, &h);
    *child_slot(l.nodes, &l.list, 0, i) = ((uint64_t)1 << 60) | l.list.type[1];
    expect_invalid("a child 2^60 bytes on", &h, &l, model);
    lie_reset(&l, &h);
    *child_slot(l.nodes, &l.list, 0, i) += 16;
    expect_invalid("a child 16 bytes into a node", &h, &l, model);
    lie_reset(&l, &h);
    l.root = (l.root & ~(uint64_t)15) | HAIROBB__REF_AABB;   /* a 256-/128-byte type over the per-child compressed one */
    if (HAIROBB__REF_TYPE(h.bvh->root) == HAIROBB__REF_AABB) l.root = (l.root & ~(uint64_t)15) | HAIROBB__REF_OBB;
    expect_invalid("the root read as a node of another size", &h, &l, model);
    /* types the traversal cannot trace, or the layout does not build */
    for (j = 0; j < 16; ++j) {
        char what[96];
        if (j == HAIROBB__REF_AABB || j == HAIROBB__REF_OBB || j == HAIROBB__REF_QOBB_PER_CHILD || j == HAIROBB__REF_LEAF) continue;
        lie_reset(&l, &h);
        i = inner_child(&l, 0);
        *child_slot(l.nodes, &l.list, 0, i) = (*child_slot(l.nodes, &l.list, 0, i) & ~(uint64_t)15) | (uint64_t)j;
        snprintf(what, sizeof what, "a child of type %d in the default layout", j);
        expect_invalid(what, &h, &l, model);
    }
    lie_reset(&l, &h);
    l.root = HAIROBB__REF_EMPTY;
    expect_invalid("an empty root", &h, &l, model);
    lie_reset(&l, &h);
    l.root = HAIROBB__REF_TASK;
    expect_invalid("a task root", &h, &l, model);
    lie_reset(&l, &h);
    *child_slot(l.nodes, &l.list, 0, HAIROBB__W - 1) = HAIROBB__REF_EMPTY | 16u;
    if (HAIROBB__REF_TYPE(*child_slot(l.nodes, &l.list, 0, HAIROBB__W - 1)) == HAIROBB__REF_EMPTY)
        expect_invalid("an empty child with offset bits", &h, &l, model);
    /* children: fewer than two, an empty lane before a full one */
    lie_reset(&l, &h);
    for (n = 0; n < l.list.count; ++n) {
        for (i = 1; i < HAIROBB__W; ++i) *child_slot(l.nodes, &l.list, n, i) = HAIROBB__REF_EMPTY;
    }
    expect_invalid("nodes of one child", &h, &l, model);
    lie_reset(&l, &h);
    *child_slot(l.nodes, &l.list, 0, 0) = HAIROBB__REF_EMPTY;
    expect_invalid("an empty lane before a full one", &h, &l, model);
    /* leaves: past the end, overlapping, out of order, of 0 or too many segments */
    lie_reset(&l, &h);
    for (n = 0; n < l.list.count && leaf_child(&l, n) < 0; ++n) {}
    {
        uint64_t *slot = child_slot(l.nodes, &l.list, n, leaf_child(&l, n)), leaf = *slot;
        size_t first = (size_t)(leaf >> 8), count = (size_t)((leaf >> 4) & 15u);
        *slot = ((uint64_t)(l.leaf_count - 1) << 8) | (4u << 4) | HAIROBB__REF_LEAF;
        expect_invalid("a leaf past the end of leaf_prims", &h, &l, model);
        *slot = ((uint64_t)first << 8) | ((uint64_t)(count + 1) << 4) | HAIROBB__REF_LEAF;
        expect_invalid("a leaf overlapping the next", &h, &l, model);
        *slot = ((uint64_t)first << 8) | HAIROBB__REF_LEAF;
        expect_invalid("a leaf of no segments", &h, &l, model);
        *slot = ((uint64_t)(first + 1) << 8) | ((uint64_t)count << 4) | HAIROBB__REF_LEAF;
        expect_invalid("a leaf out of tree order", &h, &l, model);
        *slot = ((uint64_t)first << 8) | (5u << 4) | HAIROBB__REF_LEAF;
        if (count != 5) expect_invalid("a leaf over max_leaf_size", &h, &l, model);
    }
    lie_reset(&l, &h);
    l.leaves[l.leaf_count / 2] = (uint32_t)h.scene.segment_count;
    expect_invalid("a segment id = segment_count", &h, &l, model);
    l.leaves[l.leaf_count / 2] = 0xffffffffu;
    expect_invalid("a segment id 2^32-1", &h, &l, model);
    lie_reset(&l, &h);
    l.leaf_count += 1;
    l.leaves[l.leaf_count - 1] = 0;
    expect_invalid("a leaf_prims entry no leaf names", &h, &l, model);
    lie_reset(&l, &h);
    if (l.leaves[0] != l.leaves[1]) {
        l.leaves[0] = l.leaves[1];   /* one segment twice, another nowhere */
        expect_invalid("a segment no leaf names", &h, &l, model);
    }
    lie_reset(&l, &h);
    l.node_bytes += 16;
    memset(l.nodes + l.node_bytes - 16, 0, 16);
    expect_invalid("16 bytes of node memory no reference reaches", &h, &l, model);
    lie_reset(&l, &h);
    l.root = (l.root & 15u) | (uint64_t)l.list.offset[1];
    expect_invalid("the root at another node (parts unreached)", &h, &l, model);

    /* header fields (resealed): counts that overflow or disagree, values out of range */
    {
        static const struct { size_t at; int wide; uint64_t value; const char *what; } fields[] = {
            {HAIROBB__AT_NODE_BYTES, 1, ~(uint64_t)15, "node_bytes 2^64-16"},
            {HAIROBB__AT_NODE_BYTES, 1, (uint64_t)1 << 62, "node_bytes 2^62"},
            {HAIROBB__AT_LEAF_PRIMS, 1, ~(uint64_t)0, "leaf_prims 2^64-1"},
            {HAIROBB__AT_LEAF_PRIMS, 1, (uint64_t)1 << 62, "leaf_prims 2^62"},
            {HAIROBB__AT_LEAF_PRIMS, 1, 0, "no leaf_prims"},
            {HAIROBB__AT_BASIS, 0, 9, "basis 9"},
            {HAIROBB__AT_PRECISION, 0, 2, "precision 2"},
            {HAIROBB__AT_PIECES, 0, 0, "0 pieces"},
            {HAIROBB__AT_PIECES, 0, 17, "17 pieces"},
            {HAIROBB__AT_LAYOUT, 0, 0, "layout 0"},
            {HAIROBB__AT_LAYOUT, 0, 5, "layout 5"},
            {HAIROBB__AT_LAYOUT, 0, HAIROBB_OBB_COMPRESSED, "the compressed layout (other node types)"},
            {HAIROBB__AT_MAX_LEAF, 0, 0, "max leaf 0"},
            {HAIROBB__AT_MAX_LEAF, 0, 16, "max leaf 16"},
            {HAIROBB__AT_MAX_LEAF, 0, 1, "max leaf 1 (leaves of 4 in the tree)"},
            {HAIROBB__AT_POLICY, 0, 3, "policy 3"},
            {HAIROBB__AT_POLICY, 0, HAIROBB_NODES_AABB_ONLY, "AABB-only (OBB nodes in the tree)"},
            {44, 0, 1, "reserved word"},
            {120, 1, 1, "reserved bytes"},
            {HAIROBB__AT_BOUNDS, 0, 0x7fc00000u, "a NaN bound"},
            {HAIROBB__AT_BOUNDS + 12, 0, 0xff800000u, "upper bound -inf"},
        };
        size_t f;
        for (f = 0; f < sizeof fields / sizeof fields[0]; ++f) {
            unsigned char *copy = (unsigned char *)malloc(h.size);
            hairobb_result r;
            memcpy(copy, h.blob, h.size);
            if (fields[f].wide) hairobb__put64(copy + fields[f].at, fields[f].value);
            else hairobb__put32(copy + fields[f].at, (uint32_t)fields[f].value);
            reseal(copy, h.size);
            r = load_small(&h, copy, h.size);
            CHECK(r == HAIROBB_ERROR_INVALID_FILE, "%s: %s", fields[f].what, hairobb_result_string(r));
            free(copy);
        }
    }
    /* leaf padding not zero (an odd leaf count pads 4 bytes) */
    {
        unsigned char *blob = compose(model, h.bvh->root, h.bvh->nodes, h.bvh->node_bytes, h.bvh->leaf_prims, h.bvh->leaf_prim_count, &size);
        if (h.bvh->leaf_prim_count % 2 == 1) {
            blob[size - 9] = 1;
            reseal(blob, size);
            CHECK(load_small(&h, blob, size) == HAIROBB_ERROR_INVALID_FILE, "leaf padding not zero");
        }
        free(blob);
    }
    /* other versions, byte order, node width: unsupported */
    {
        static const struct { size_t at; uint32_t value; const char *what; } fields[] = {
            {HAIROBB__AT_VERSION, HAIROBB__SAVE_VERSION + 1, "a newer format version"},
            {HAIROBB__AT_BYTE_ORDER, 0x04030201u, "the other byte order"},
            {HAIROBB__AT_WIDTH, HAIROBB__W == 8 ? 4 : 8, "the other node width"},
        };
        size_t f;
        for (f = 0; f < sizeof fields / sizeof fields[0]; ++f) {
            unsigned char *copy = (unsigned char *)malloc(h.size);
            hairobb_result r;
            memcpy(copy, h.blob, h.size);
            hairobb__put32(copy + fields[f].at, fields[f].value);
            reseal(copy, h.size);
            r = load_small(&h, copy, h.size);
            CHECK(r == HAIROBB_ERROR_UNSUPPORTED, "%s: %s", fields[f].what, hairobb_result_string(r));
            free(copy);
        }
    }
    free(l.nodes);
    free(l.leaves);
    small_hair_free(&h);
}

/* A chain of full AABB nodes around everything, W - 1 one-segment leaves
   and the next node in each: a ray pushes W - 1 entries a level. The
   deepest the loader takes is the deepest the traversal stack holds
   ((W - 1) d + W <= HAIROBB__STACK for the deepest inner node d); one
   level more is INVALID_FILE. Traced here at the limit (ASan would see an
   overflow in the sanitized builds of the fuzzer). */
static void deep_chains(void)
{
    small_hair h;
    hairobb_build_options opt;
    int deepest = (HAIROBB__STACK - HAIROBB__W) / (HAIROBB__W - 1), extra;
    memset(&opt, 0, sizeof opt);
    opt.threads = 1;
    opt.obb_layout = HAIROBB_OBB_PER_CHILD;
    opt.max_leaf_size = 1;
    CHECK(small_hair_make(&h, 40, &opt), "small scene built and saved");
    if (!h.blob) { small_hair_free(&h); return; }
    for (extra = 0; extra < 2; ++extra) {
        int nodes = deepest + 1 + extra, d, i, k;
        size_t leaf_count = (size_t)nodes * (HAIROBB__W - 1) + 1, leaf = 0, size;
        unsigned char *memory = (unsigned char *)calloc((size_t)nodes, sizeof(hairobb__aabb_node)), *blob;
        uint32_t *leaves = (uint32_t *)calloc(leaf_count, 4);
        hairobb_bvh *bvh = NULL;
        hairobb_result r;
        for (d = 0; d < nodes; ++d) {
            hairobb__aabb_node node;
            for (k = 0; k < 3; ++k)
                for (i = 0; i < HAIROBB__W; ++i) { node.lower[k][i] = -1e30f; node.upper[k][i] = 1e30f; }
            for (i = 0; i < HAIROBB__W; ++i) {
                int last = i == HAIROBB__W - 1;
                if (last && d + 1 < nodes) {
                    node.child[i] = (uint64_t)(d + 1) * sizeof(hairobb__aabb_node) | HAIROBB__REF_AABB;
                } else {
                    leaves[leaf] = (uint32_t)(leaf % h.scene.segment_count);
                    node.child[i] = ((uint64_t)leaf << 8) | (1u << 4) | HAIROBB__REF_LEAF;
                    ++leaf;
                }
            }
            memcpy(memory + (size_t)d * sizeof node, &node, sizeof node);
        }
        blob = compose(h.blob, HAIROBB__REF_AABB, memory, (size_t)nodes * sizeof(hairobb__aabb_node), leaves, leaf, &size);
        r = load_of(blob, size, &h.in, NULL, &bvh);
        if (extra == 0) {
            hairobb_stats st;
            CHECK(r == HAIROBB_OK, "a chain of %d full nodes (deepest inner node %d) loads: %s", nodes, deepest, hairobb_result_string(r));
            if (bvh) {
                hairobb_ray ray = {{0.0f, 0.0f, -5.0f}, 0.0f, {0.05f, 0.02f, 1.0f}, INFINITY, 0.0f};
                hairobb_hit hit;
                hairobb_get_stats(bvh, &st);
                CHECK(st.max_depth == (unsigned)nodes && st.aabb_nodes == (size_t)nodes && st.leaves == leaf,
                      "chain statistics: depth %u, %zu nodes, %zu leaves", st.max_depth, st.aabb_nodes, st.leaves);
                (void)hairobb_intersect1(bvh, &ray, &hit);
                (void)hairobb_occluded1(bvh, &ray);
            }
        } else {
            CHECK(r == HAIROBB_ERROR_INVALID_FILE, "a chain of %d full nodes (one level past the stack): %s", nodes,
                  hairobb_result_string(r));
        }
        hairobb_free(bvh);
        free(blob);
        free(memory);
        free(leaves);
    }
    small_hair_free(&h);
}

/* ------------------------------------------------------------------------ */
/* Other hair */

static void other_hair(void)
{
    hair_scene s;
    float *tangents, *moved;
    uint32_t *indices;
    hairobb_build_options opt, skip;
    hairobb_bvh *bvh = NULL, *loaded = NULL;
    unsigned char *blob;
    size_t size;
    hairobb_result r;
    hair_input in;
    int b;
    CHECK(scene_combed(&s, 400, 31) == 0, "scene");
    tangents = make_tangents(&s);
    moved = (float *)malloc(4 * sizeof(float) * s.vertex_count);
    indices = (uint32_t *)malloc(4 * s.segment_count);
    memset(&skip, 0, sizeof skip);
    skip.verify_hair = HAIROBB_OFF;
    for (b = 0; b <= HAIROBB_BASIS_LINEAR; ++b) {
        const char *basis_name[] = {"bezier", "b-spline", "catmull-rom", "hermite", "linear"};
        hair_input other;
        in = input_of(&s, (hairobb_basis)b, tangents);
        memset(&opt, 0, sizeof opt);
        opt.basis = in.basis;
        opt.tangents = in.tangents;
        opt.threads = 1;
        r = hairobb_build(in.vertices, in.vertex_count, in.indices, in.segment_count, &opt, &bvh);
        CHECK(r == HAIROBB_OK, "%s: build", basis_name[b]);
        if (r != HAIROBB_OK) continue;
        blob = save_of(bvh, &size);
        /* one coordinate moved by an ulp, in a vertex segment 0 reads */
        memcpy(moved, s.vertices, 4 * sizeof(float) * s.vertex_count);
        moved[4 * s.indices[0] + 4] = nextafterf(moved[4 * s.indices[0] + 4], INFINITY);
        other = in;
        other.vertices = moved;
        CHECK(load_of(blob, size, &other, NULL, &loaded) == HAIROBB_ERROR_MISMATCH && !loaded, "%s: a vertex moved: mismatch",
              basis_name[b]);
        r = load_of(blob, size, &other, &skip, &loaded);
        CHECK(r == HAIROBB_OK && loaded, "%s: a vertex moved, check skipped: loads (%s)", basis_name[b], hairobb_result_string(r));
        hairobb_free(loaded);
        loaded = NULL;
        /* the indices of segments 0 and 1 swapped */
        memcpy(indices, s.indices, 4 * s.segment_count);
        indices[0] = s.indices[1];
        indices[1] = s.indices[0];
        other = in;
        other.indices = indices;
        CHECK(load_of(blob, size, &other, NULL, &loaded) == HAIROBB_ERROR_MISMATCH, "%s: indices swapped: mismatch", basis_name[b]);
        /* fewer segments, more vertices: mismatch even unchecked for segments */
        other = in;
        other.segment_count -= 1;
        CHECK(load_of(blob, size, &other, NULL, &loaded) == HAIROBB_ERROR_MISMATCH &&
              load_of(blob, size, &other, &skip, &loaded) == HAIROBB_ERROR_MISMATCH, "%s: one segment less: mismatch", basis_name[b]);
        /* one vertex more (the scene's padding): the Bezier hash covers the
           caller's whole array, other bases' the converted curves */
        other = in;
        other.vertex_count += 1;
        r = load_of(blob, size, &other, NULL, &loaded);
        CHECK(r == (b == HAIROBB_BASIS_BEZIER ? HAIROBB_ERROR_MISMATCH : HAIROBB_OK), "%s: one vertex more: %s", basis_name[b],
              hairobb_result_string(r));
        hairobb_free(loaded);
        loaded = NULL;
        /* another basis */
        other = input_of(&s, (hairobb_basis)(b == HAIROBB_BASIS_BEZIER ? HAIROBB_BASIS_BSPLINE : HAIROBB_BASIS_BEZIER), tangents);
        CHECK(load_of(blob, size, &other, &skip, &loaded) == HAIROBB_ERROR_MISMATCH, "%s: loaded as another basis: mismatch",
              basis_name[b]);
        if (b == HAIROBB_BASIS_HERMITE) {
            float *t2 = (float *)malloc(4 * sizeof(float) * s.vertex_count);
            memcpy(t2, tangents, 4 * sizeof(float) * s.vertex_count);
            t2[4 * s.indices[0]] += 0.25f;
            other = in;
            other.tangents = t2;
            CHECK(load_of(blob, size, &other, NULL, &loaded) == HAIROBB_ERROR_MISMATCH, "hermite: a tangent changed: mismatch");
            free(t2);
        }
        /* bad arrays are the build's errors */
        memcpy(moved, s.vertices, 4 * sizeof(float) * s.vertex_count);
        moved[4 * s.indices[0]] = NAN;
        other = in;
        other.vertices = moved;
        CHECK(load_of(blob, size, &other, &skip, &loaded) == HAIROBB_ERROR_INVALID_GEOMETRY, "%s: a NaN vertex", basis_name[b]);
        memcpy(indices, s.indices, 4 * s.segment_count);
        indices[3] = (uint32_t)s.vertex_count;
        other = in;
        other.indices = indices;
        CHECK(load_of(blob, size, &other, &skip, &loaded) == HAIROBB_ERROR_INDEX_OUT_OF_RANGE, "%s: an index past the vertices",
              basis_name[b]);
        free(blob);
        hairobb_free(bvh);
        bvh = NULL;
    }
    /* arguments */
    in = input_of(&s, HAIROBB_BASIS_BEZIER, NULL);
    r = hairobb_build(in.vertices, in.vertex_count, in.indices, in.segment_count, NULL, &bvh);
    blob = save_of(bvh, &size);
    CHECK(hairobb_load(blob, size, NULL, s.vertex_count, s.indices, s.segment_count, NULL, &loaded) == HAIROBB_ERROR_INVALID_ARGUMENT &&
          hairobb_load(NULL, size, s.vertices, s.vertex_count, s.indices, s.segment_count, NULL, &loaded) == HAIROBB_ERROR_INVALID_ARGUMENT &&
          hairobb_load(blob, size, s.vertices, s.vertex_count, s.indices, s.segment_count, NULL, NULL) == HAIROBB_ERROR_INVALID_ARGUMENT,
          "NULL arguments");
    memset(&opt, 0, sizeof opt);
    opt.verify_hair = (hairobb_switch)3;
    CHECK(hairobb_load(blob, size, s.vertices, s.vertex_count, s.indices, s.segment_count, &opt, &loaded) == HAIROBB_ERROR_INVALID_ARGUMENT,
          "verify_hair 3");
    memset(&opt, 0, sizeof opt);
    opt.bezier_copy = (hairobb_switch)3;
    CHECK(hairobb_load(blob, size, s.vertices, s.vertex_count, s.indices, s.segment_count, &opt, &loaded) == HAIROBB_ERROR_INVALID_ARGUMENT &&
              loaded == NULL,
          "bezier_copy 3");
    memset(&opt, 0, sizeof opt);
    opt.tangents = tangents;
    CHECK(hairobb_load(blob, size, s.vertices, s.vertex_count, s.indices, s.segment_count, &opt, &loaded) == HAIROBB_ERROR_INVALID_ARGUMENT,
          "tangents without Hermite");
    free(blob);
    hairobb_free(bvh);
    free(moved);
    free(indices);
    free(tangents);
    scene_free(&s);
}

/* The hit filter is the load's: one that takes nothing leaves every ray a miss. */
static int take_nothing(void *user, const hairobb_ray *ray, const hairobb_hit *hit)
{
    (void)ray; (void)hit;
    ++*(size_t *)user;
    return 0;
}

static void filter_from_load(void)
{
    hair_scene s;
    static ray_set rays;
    hairobb_bvh *bvh = NULL, *loaded = NULL;
    hairobb_build_options opt;
    unsigned char *blob;
    size_t size, i, shown = 0, hits = 0;
    CHECK(scene_combed(&s, 2000, 41) == 0, "scene");
    make_rays(&s, &rays, 43);
    CHECK(hairobb_build(s.vertices, s.vertex_count, s.indices, s.segment_count, NULL, &bvh) == HAIROBB_OK, "build");
    blob = save_of(bvh, &size);
    memset(&opt, 0, sizeof opt);
    opt.hit_filter = take_nothing;
    opt.hit_filter_user = &shown;
    CHECK(hairobb_load(blob, size, s.vertices, s.vertex_count, s.indices, s.segment_count, &opt, &loaded) == HAIROBB_OK, "load");
    for (i = 0; loaded && i < RAYS; ++i) {
        hairobb_ray ray;
        hairobb_hit hit;
        memcpy(ray.org, rays.org + 3 * i, sizeof ray.org);
        memcpy(ray.dir, rays.dir + 3 * i, sizeof ray.dir);
        ray.tnear = 0.0f;
        ray.tfar = INFINITY;
        hits += (size_t)hairobb_intersect1(loaded, &ray, &hit);
        hits += (size_t)hairobb_occluded1(loaded, &ray);
    }
    CHECK(hits == 0 && shown > RAYS / 8, "a filter given at load: %zu hits taken, %zu shown", hits, shown);
    free(blob);
    hairobb_free(loaded);
    hairobb_free(bvh);
    scene_free(&s);
}

/* ------------------------------------------------------------------------ */
/* Allocation failure, files */

static void failing_allocations(void)
{
    hair_scene s;
    float *tangents;
    int b;
    CHECK(scene_combed(&s, 300, 51) == 0, "scene");
    tangents = make_tangents(&s);
    for (b = HAIROBB_BASIS_BEZIER; b <= HAIROBB_BASIS_HERMITE; b += HAIROBB_BASIS_HERMITE) {
        hair_input in = input_of(&s, (hairobb_basis)b, tangents);
        hairobb_build_options opt;
        test_allocator a;
        hairobb_bvh *bvh = NULL, *loaded = NULL;
        unsigned char *blob;
        size_t size;
        long fail_at, allocations, bad = 0;
        int copy;
        memset(&opt, 0, sizeof opt);
        opt.basis = in.basis;
        opt.tangents = in.tangents;
        opt.threads = 1;
        CHECK(hairobb_build(in.vertices, in.vertex_count, in.indices, in.segment_count, &opt, &bvh) == HAIROBB_OK, "build");
        blob = save_of(bvh, &size);
        opt.allocator_user = &a;
        /* loads with the copy (the default) and without it (its vertex offsets) */
        for (copy = 1; copy >= 0; --copy) {
            opt.bezier_copy = copy ? HAIROBB_AUTO : HAIROBB_OFF;
            test_allocator_init(&a, -1);
            CHECK(load_of(blob, size, &in, &opt, &loaded) == HAIROBB_OK, "counting load");
            hairobb_free(loaded);
            allocations = a.calls;
            CHECK(a.live == 0 && allocations >= 3, "a load makes %ld allocations, %ld live after free", allocations, a.live);
            for (bad = 0, fail_at = 0; fail_at < allocations; ++fail_at) {
                hairobb_result r;
                test_allocator_init(&a, fail_at);
                loaded = NULL;
                r = load_of(blob, size, &in, &opt, &loaded);
                if (r != HAIROBB_ERROR_OUT_OF_MEMORY || loaded || a.live != 0) {
                    printf("allocation %ld failing: %s, %ld live\n", fail_at, hairobb_result_string(r), a.live);
                    ++bad;
                }
                hairobb_free(loaded);
            }
            CHECK(bad == 0, "%s, copy %s: %ld of %ld failing allocations not out of memory without a leak", b ? "hermite" : "bezier",
                  copy ? "on" : "off", bad, allocations);
        }
        /* save_file's one allocation */
        {
            char path[SCRATCH_PATH_SIZE];
            hairobb_bvh *counted = NULL;
            test_allocator_init(&a, -1);
            CHECK(load_of(blob, size, &in, &opt, &counted) == HAIROBB_OK, "counting load");
            scratch_path(path, sizeof path, "never_written.bvh");
            a.calls = 0;
            a.fail_at = 0;
            CHECK(hairobb_save_file(counted, path) == HAIROBB_ERROR_OUT_OF_MEMORY, "save_file out of memory");
            a.fail_at = -1;
            hairobb_free(counted);
            CHECK(a.live == 0, "%ld blocks live", a.live);
        }
        free(blob);
        hairobb_free(bvh);
    }
    free(tangents);
    scene_free(&s);
}

/* One segment: the root a leaf, no node memory. */
/* Format 2 hashes each segment where the BVH reads it (the copy): Bezier
   arrays freed after a build save the same bytes; a format-1 file (0.1.x:
   the caller's arrays hashed) still loads, and its version picks its
   hash. */
static void format_versions(void)
{
    hair_scene s;
    hair_input in;
    ray_set *rays = (ray_set *)malloc(sizeof *rays);
    hairobb_bvh *bvh = NULL, *loaded = NULL, *old = NULL;
    unsigned char *before = NULL, *after = NULL, *v1 = NULL;
    size_t size_before = 0, size_after = 0, hits = 0;
    float *vertices, *extended = NULL;
    uint32_t *indices;
    hairobb_result r;
    if (scene_combed(&s, 5000, 17) != 0 || !rays) {
        check_skip("format versions: no scene");
        free(rays);
        return;
    }
    make_rays(&s, rays, 18);
    /* 4 points past the last segment's: format 1 hashed them (the whole
       array), format 2 does not (where every segment has 4 points of its
       own in index order, as the tests' scenes, the two hashes agree) */
    vertices = (float *)calloc(4 * (s.vertex_count + 4), sizeof(float));
    indices = (uint32_t *)malloc(sizeof(uint32_t) * s.segment_count);
    memcpy(vertices, s.vertices, 4 * sizeof(float) * s.vertex_count);
    memcpy(indices, s.indices, sizeof(uint32_t) * s.segment_count);
    CHECK(hairobb_build(vertices, s.vertex_count + 4, indices, s.segment_count, NULL, &bvh) == HAIROBB_OK, "format versions: build");
    memcpy(s.vertices, vertices, 4 * sizeof(float) * s.vertex_count);
    in = input_of(&s, HAIROBB_BASIS_BEZIER, NULL);
    in.vertices = extended = (float *)calloc(4 * (s.vertex_count + 4), sizeof(float));
    memcpy(extended, s.vertices, 4 * sizeof(float) * s.vertex_count);
    in.vertex_count = s.vertex_count + 4;
    if (bvh) before = save_of(bvh, &size_before);
    /* the caller's arrays overwritten and freed (ASan sees a read of them) */
    memset(vertices, 0xff, 4 * sizeof(float) * s.vertex_count);
    memset(indices, 0xff, sizeof(uint32_t) * s.segment_count);
    free(vertices);
    free(indices);
    if (bvh) after = save_of(bvh, &size_after);
    CHECK(before && after && size_before == size_after && memcmp(before, after, size_before) == 0 &&
              hairobb__get32(after + HAIROBB__AT_VERSION) == HAIROBB_SAVE_FORMAT_VERSION,
          "format versions: the same bytes saved after the arrays were freed");
    r = after ? load_of(after, size_after, &in, NULL, &loaded) : HAIROBB_ERROR_INVALID_ARGUMENT;
    CHECK(r == HAIROBB_OK && count_differences(bvh, loaded, rays, &hits) == 0, "format versions: loads and traces as built: %s",
          hairobb_result_string(r));
    if (loaded) {
        v1 = (unsigned char *)malloc(size_after);
        memcpy(v1, after, size_after);
        hairobb__put32(v1 + HAIROBB__AT_VERSION, 1u);
        reseal(v1, size_after);
        r = load_of(v1, size_after, &in, NULL, &old);
        CHECK(r == HAIROBB_ERROR_MISMATCH && !old, "format 1 with format 2's hash: %s", hairobb_result_string(r));
        hairobb_free(old);
        old = NULL;
        hairobb__put64(v1 + HAIROBB__AT_HAIR_HASH, hairobb__traced_hash(loaded, 1u));
        reseal(v1, size_after);
        r = load_of(v1, size_after, &in, NULL, &old);
        CHECK(r == HAIROBB_OK && count_differences(bvh, old, rays, &hits) == 0, "format 1 (0.1.x's hash) loads: %s",
              hairobb_result_string(r));
        hairobb__put32(v1 + HAIROBB__AT_VERSION, 0u);
        reseal(v1, size_after);
        hairobb_free(old);
        old = NULL;
        r = load_of(v1, size_after, &in, NULL, &old);
        CHECK(r == HAIROBB_ERROR_UNSUPPORTED && !old, "format 0: %s", hairobb_result_string(r));
    }
    CHECK(hits > 0, "format versions: rays hit");
    hairobb_free(old);
    hairobb_free(loaded);
    hairobb_free(bvh);
    free(before);
    free(after);
    free(v1);
    free(rays);
    free(extended);
    scene_free(&s);
}

static void one_segment(void)
{
    static const float v[20] = {0, 0, 0, 0.1f, 1, 0.2f, 0, 0.1f, 2, -0.2f, 0, 0.1f, 3, 0, 0, 0.1f, 0, 0, 0, 0};
    static const uint32_t ix[1] = {0};
    hairobb_bvh *bvh = NULL, *loaded = NULL;
    unsigned char *blob;
    size_t size;
    hairobb_result r;
    CHECK(hairobb_build(v, 4, ix, 1, NULL, &bvh) == HAIROBB_OK && HAIROBB__REF_TYPE(bvh->root) == HAIROBB__REF_LEAF &&
          bvh->node_bytes == 0, "one segment: a leaf root");
    blob = save_of(bvh, &size);
    r = hairobb_load(blob, size, v, 4, ix, 1, NULL, &loaded);
    CHECK(r == HAIROBB_OK && size == HAIROBB__SAVE_HEADER + 8 + 8, "one segment: %zu bytes, %s", size, hairobb_result_string(r));
    if (loaded) {
        hairobb_ray ray = {{1.0f, 0.0f, -5.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY, 0.0f};
        hairobb_hit a, b;
        memset(&a, 0, sizeof a);
        memset(&b, 0, sizeof b);
        CHECK(hairobb_intersect1(bvh, &ray, &a) == 1 && hairobb_intersect1(loaded, &ray, &b) == 1 && memcmp(&a, &b, sizeof a) == 0,
              "one segment: the same hit");
    }
    hairobb_free(loaded);
    free(blob);
    hairobb_free(bvh);
}

static void files(void)
{
    hair_scene s;
    hairobb_bvh *bvh = NULL, *loaded = NULL;
    unsigned char *blob, *read_back;
    size_t size, got;
    char path[SCRATCH_PATH_SIZE];
    FILE *f;
    hairobb_result r;
    CHECK(scene_combed(&s, 500, 61) == 0, "scene");
    scratch_path(path, sizeof path, "files.bvh");
    CHECK(hairobb_build(s.vertices, s.vertex_count, s.indices, s.segment_count, NULL, &bvh) == HAIROBB_OK, "build");
    blob = save_of(bvh, &size);
    r = hairobb_save_file(bvh, path);
    CHECK(r == HAIROBB_OK, "save_file: %s", hairobb_result_string(r));
    read_back = (unsigned char *)malloc(size + 1);
    f = fopen(path, "rb");
    got = f ? fread(read_back, 1, size + 1, f) : 0;
    if (f) fclose(f);
    CHECK(got == size && memcmp(read_back, blob, size) == 0, "the file holds the saved bytes (%zu of %zu)", got, size);
    r = hairobb_load_file(path, s.vertices, s.vertex_count, s.indices, s.segment_count, NULL, &loaded);
    CHECK(r == HAIROBB_OK && loaded, "load_file: %s", hairobb_result_string(r));
    if (loaded) {
        unsigned char *again;
        size_t size_again;
        again = save_of(loaded, &size_again);
        CHECK(again && size_again == size && memcmp(again, blob, size) == 0, "load_file's BVH saves to the same bytes");
        free(again);
        hairobb_free(loaded);
        loaded = NULL;
    }
    /* a truncated file */
    f = fopen(path, "wb");
    if (f) { fwrite(blob, 1, size / 2, f); fclose(f); }
    r = hairobb_load_file(path, s.vertices, s.vertex_count, s.indices, s.segment_count, NULL, &loaded);
    CHECK(r == HAIROBB_ERROR_INVALID_FILE && !loaded, "a truncated file: %s", hairobb_result_string(r));
    remove(path);
    r = hairobb_load_file(path, s.vertices, s.vertex_count, s.indices, s.segment_count, NULL, &loaded);
    CHECK(r == HAIROBB_ERROR_IO && !loaded, "a missing file: %s", hairobb_result_string(r));
    r = hairobb_load_file(scratch_dir(), s.vertices, s.vertex_count, s.indices, s.segment_count, NULL, &loaded);
    CHECK(r == HAIROBB_ERROR_IO && !loaded, "a directory: %s", hairobb_result_string(r));
    r = hairobb_load_file("/dev/null", s.vertices, s.vertex_count, s.indices, s.segment_count, NULL, &loaded);
    CHECK(r == HAIROBB_ERROR_INVALID_FILE && !loaded, "an empty file: %s", hairobb_result_string(r));
    /* a header announcing 2^40 node bytes: an error before any large allocation */
    {
        test_allocator a;
        hairobb_build_options counted;
        unsigned char *lying = (unsigned char *)malloc(size);
        memcpy(lying, blob, size);
        hairobb__put64(lying + HAIROBB__AT_NODE_BYTES, (uint64_t)1 << 40);
        reseal(lying, size);
        f = fopen(path, "wb");
        if (f) { fwrite(lying, 1, size, f); fclose(f); }
        test_allocator_init(&a, -1);
        memset(&counted, 0, sizeof counted);
        counted.allocator_user = &a;
        r = hairobb_load_file(path, s.vertices, s.vertex_count, s.indices, s.segment_count, &counted, &loaded);
        CHECK(r == HAIROBB_ERROR_INVALID_FILE && !loaded && a.largest == 0 && a.live == 0,
              "a file announcing 2^40 node bytes: %s, largest allocation %zu", hairobb_result_string(r), a.largest);
        free(lying);
        remove(path);
    }
    r = hairobb_save_file(bvh, "/nonexistent-directory/hairobb.bvh");
    CHECK(r == HAIROBB_ERROR_IO, "a file that cannot be created: %s", hairobb_result_string(r));
    CHECK(hairobb_save_file(NULL, path) == HAIROBB_ERROR_INVALID_ARGUMENT && hairobb_save_file(bvh, NULL) == HAIROBB_ERROR_INVALID_ARGUMENT,
          "save_file of NULL");
    free(read_back);
    free(blob);
    hairobb_free(bvh);
    scene_free(&s);
}

int main(void)
{
    double t0 = scene_now();
    round_trips();
    printf("round trips: %.1f s\n", scene_now() - t0);
    bad_bytes();
    structural_lies();
    deep_chains();
    other_hair();
    filter_from_load();
    failing_allocations();
    one_segment();
    format_versions();
    files();
    printf("test_save: %.1f s\n", scene_now() - t0);
    return check_summary();
}
