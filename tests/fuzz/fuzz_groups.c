/* fuzz_groups.c - libFuzzer target: arbitrary bytes become 1-4 hair
   groups (points of any float, repeated points and zero-length segments
   made likely, indices past their group's points, empty groups, masks),
   the options (ribbons or tubes, end caps, back faces, basis, the copy),
   each group's shape (the options' or its own: ribbons and tubes mixed)
   and rays with ray masks. hairobb_build_groups must return one of its
   codes; where it builds, every hit must be sane (its group and segment
   in range, t in [tnear, tfar], occluded1 true where intersect1 hits),
   and where the hair and rays are of moderate size (coordinates and
   radii within 64: rounding far below the radii, where hits do not
   depend on the tree; a hit on hair thinner than rounding is rounding's,
   rounding_decided), the one the groups' own BVHs (hairobb_build on
   each group's arrays, as its shape) give together: the nearest over the groups the
   ray's mask lets through, a tie to the lower group, to the bit, with
   the group and its segment named. Then hairobb_refit_group of one group to points
   the input moves (refused with INVALID_GEOMETRY, the BVH tracing as
   before, or tracing as the moved group's own BVH does), and a save and
   hairobb_load_groups round trip tracing to the bit. Build with clang
   -fsanitize=fuzzer,address,undefined (make fuzz); seeds:
   tests/fuzz/corpus/groups. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#define HAIROBB_IMPLEMENTATION
#include "../../hairobb.h"
#include "fuzz_checks.h"
#include "fuzz_input.h"   /* rounding_decided */

#define MAX_GROUPS 4
#define MAX_POINTS 16
#define RAYS 8

typedef struct groups_reader {
    const uint8_t *data;
    size_t size, at;
} groups_reader;

static unsigned next_byte(groups_reader *r) { return r->at < r->size ? r->data[r->at++] : 0u; }

/* Mostly small numbers on a coarse grid (so points repeat), sometimes raw bits. */
static float next_float(groups_reader *r)
{
    unsigned kind = next_byte(r);
    if (kind < 200) return ((float)kind - 100.0f) / 32.0f;
    if (kind < 250) return ((float)next_byte(r) - 128.0f) / 64.0f + (float)next_byte(r) / 65536.0f;
    {
        uint32_t bits = 0;
        float f;
        int i;
        for (i = 0; i < 4; ++i) bits |= (uint32_t)next_byte(r) << (8 * i);
        memcpy(&f, &bits, sizeof f);
        return f;
    }
}

typedef struct fuzz_group_input {
    float points[MAX_POINTS * 4], tangents[MAX_POINTS * 4];
    uint32_t indices[MAX_POINTS];
} fuzz_group_input;

/* A group's points: each a new one, the one before again (zero-length
   segments), or point 0 again (loops, cusps); radii small and >= 0 but
   for raw bits. */
static void read_group(groups_reader *r, fuzz_group_input *in, hairobb_group *g, size_t points_a_segment)
{
    size_t i, n = 1 + next_byte(r) % MAX_POINTS, segments = next_byte(r) % 6;
    int k;
    for (i = 0; i < n; ++i) {
        unsigned how = next_byte(r) % 8;
        if (i > 0 && how == 0) {
            memcpy(in->points + 4 * i, in->points + 4 * (i - 1), 4 * sizeof(float));
        } else if (i > 0 && how == 1) {
            memcpy(in->points + 4 * i, in->points, 4 * sizeof(float));
        } else {
            for (k = 0; k < 3; ++k) in->points[4 * i + k] = next_float(r);
            in->points[4 * i + 3] = how == 2 ? next_float(r) : (float)(next_byte(r) % 16) / 64.0f;
        }
        for (k = 0; k < 4; ++k) in->tangents[4 * i + k] = (float)((int)next_byte(r) % 9 - 4) / 4.0f;
    }
    for (i = 0; i < segments; ++i) {
        unsigned b = next_byte(r);
        /* mostly in range; 255: one past the group's last valid first point */
        in->indices[i] = b == 255 ? (uint32_t)(n + 1 - points_a_segment) : (uint32_t)(b % (n >= points_a_segment ? n - points_a_segment + 1 : 1));
    }
    memset(g, 0, sizeof *g);
    g->vertices = in->points;
    g->vertex_count = n;
    g->indices = in->indices;
    g->segment_count = segments;
    g->mask = next_byte(r) % 4 == 0 ? 0u : next_byte(r) & 7u;
}

/* A group's shape: its own, or the options' */
static hairobb_shape group_shape(const hairobb_build_options *o, const hairobb_group *g)
{
    return g->shape == HAIROBB_GROUP_SHAPE_ROUND ? HAIROBB_SHAPE_ROUND : g->shape == HAIROBB_GROUP_SHAPE_RIBBON ? HAIROBB_SHAPE_RIBBON : o->shape;
}

/* A group alone, as its shape (the oracle's BVH for it) */
static hairobb_result build_own(const hairobb_build_options *options, const hairobb_group *g, hairobb_bvh **out)
{
    hairobb_build_options o = *options;
    o.tangents = g->tangents;
    o.shape = group_shape(options, g);
    return hairobb_build(g->vertices, g->vertex_count, g->indices, g->segment_count, &o, out);
}

static int documented(hairobb_result r)
{
    return r == HAIROBB_OK || r == HAIROBB_ERROR_INVALID_ARGUMENT || r == HAIROBB_ERROR_INDEX_OUT_OF_RANGE ||
           r == HAIROBB_ERROR_INVALID_GEOMETRY || r == HAIROBB_ERROR_TOO_LARGE;
}

/* The hit the groups' own BVHs give together for a ray of mask `mask`:
   the nearest over the groups it lets through, a tie to the lower group. */
static int groups_oracle(hairobb_bvh *const *own, const hairobb_group *g, size_t count, const hairobb_ray *ray, uint32_t mask,
                         hairobb_hit *best)
{
    size_t i;
    int found = 0;
    for (i = 0; i < count; ++i) {
        hairobb_hit h;
        uint32_t gm = g[i].mask ? g[i].mask : 0xffffffffu;
        if (!own[i] || !(gm & (mask ? mask : 0xffffffffu)) || !hairobb_intersect1(own[i], ray, &h)) continue;
        if (found && !(h.t < best->t)) continue;
        *best = h;
        best->group_id = (uint32_t)i;
        found = 1;
    }
    return found;
}

/* Whether every point a segment reads and every ray is within 64 (and finite). */
static int moderate(const hairobb_group *g, size_t count, size_t points_a_segment, const hairobb_ray *rays)
{
    size_t i, j, k;
    for (i = 0; i < count; ++i)
        for (j = 0; j < g[i].segment_count; ++j)
            for (k = 0; k < 4 * points_a_segment; ++k) {
                float x = g[i].vertices[4 * (size_t)g[i].indices[j] + k], t = g[i].tangents ? g[i].tangents[4 * (size_t)g[i].indices[j] + k] : 0.0f;
                if (!(fabsf(x) <= 64.0f) || !(fabsf(t) <= 64.0f)) return 0;
            }
    for (i = 0; i < RAYS; ++i)
        for (k = 0; k < 3; ++k)
            if (!(fabsf(rays[i].org[k]) <= 64.0f) || !(fabsf(rays[i].dir[k]) <= 64.0f)) return 0;
    return 1;
}

static void check_rays(const hairobb_bvh *bvh, hairobb_bvh *const *own, const hairobb_group *g, size_t count, const hairobb_ray *rays,
                       const uint32_t *masks, int exact)
{
    int i;
    for (i = 0; i < RAYS; ++i) {
        hairobb_context context = {NULL, NULL, masks[i]};
        hairobb_hit hit, want;
        int got = hairobb_intersect1_context(bvh, &context, NULL, &rays[i], &hit), expected = groups_oracle(own, g, count, &rays[i], masks[i], &want);
        if (got) {
            if (hit.group_id >= count || hit.prim_id >= g[hit.group_id].segment_count) fuzz_fail("a hit's group or segment out of range");
            if (!(hit.t >= rays[i].tnear && hit.t <= rays[i].tfar) || !(hit.u >= 0.0f && hit.u <= 1.0f)) fuzz_fail("t or u out of range");
            if (!((g[hit.group_id].mask ? g[hit.group_id].mask : 0xffffffffu) & (masks[i] ? masks[i] : 0xffffffffu)))
                fuzz_fail("a hit on a group the ray's mask excludes");
            if (!hairobb_occluded1_context(bvh, &context, NULL, &rays[i])) fuzz_fail("intersect1 hits where occluded1 does not");
        } else if (hit.prim_id != HAIROBB_INVALID_ID || hit.group_id != HAIROBB_INVALID_ID || hit.instance_id != HAIROBB_INVALID_ID) {
            fuzz_fail("a miss with an id");
        }
        if (!exact) continue;
        /* a hit on hair thinner than rounding (a zero radius, a ray
           starting on the strand) is rounding's, and two trees may differ
           there (fuzz_input.h) */
        if (got && rounding_decided(bvh, &rays[i], &hit)) continue;
        if (expected) {
            hairobb_hit own_hit = want;
            own_hit.group_id = 0;   /* the group's own BVH is one group */
            if (rounding_decided(own[want.group_id], &rays[i], &own_hit)) continue;
        }
        if (got != expected) fuzz_fail("a group BVH's hit or miss differs from its groups' own BVHs");
        if (got && memcmp(&hit, &want, sizeof hit) != 0) fuzz_fail("a group BVH's hit differs from its group's own BVH's");
    }
}

static void free_own(hairobb_bvh **own, size_t count)
{
    size_t i;
    for (i = 0; i < count; ++i) {
        hairobb_free(own[i]);
        own[i] = NULL;
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const hairobb_basis bases[5] = {HAIROBB_BASIS_BEZIER, HAIROBB_BASIS_BSPLINE, HAIROBB_BASIS_CATMULL_ROM, HAIROBB_BASIS_HERMITE,
                                           HAIROBB_BASIS_LINEAR};
    groups_reader r = {data, size, 0};
    fuzz_group_input in[MAX_GROUPS], moved;
    hairobb_group g[MAX_GROUPS];
    hairobb_bvh *bvh = NULL, *own[MAX_GROUPS] = {NULL, NULL, NULL, NULL}, *loaded = NULL;
    hairobb_build_options o = hairobb_default_options();
    hairobb_ray rays[RAYS];
    uint32_t masks[RAYS];
    hairobb_result result;
    size_t count, i, points_a_segment;
    unsigned flags = next_byte(&r);
    int k;
    o.basis = bases[next_byte(&r) % 5];
    o.shape = flags & 1 ? HAIROBB_SHAPE_ROUND : HAIROBB_SHAPE_RIBBON;
    o.end_caps = flags & 2 ? HAIROBB_ON : HAIROBB_OFF;
    o.back_faces = flags & 4 ? HAIROBB_OFF : HAIROBB_ON;
    o.bezier_copy = flags & 8 ? HAIROBB_OFF : HAIROBB_AUTO;
    o.threads = 1;
    fuzz_round = o.shape == HAIROBB_SHAPE_ROUND;
    points_a_segment = o.basis == HAIROBB_BASIS_HERMITE || o.basis == HAIROBB_BASIS_LINEAR ? 2 : 4;
    count = 1 + next_byte(&r) % MAX_GROUPS;
    for (i = 0; i < count; ++i) {
        read_group(&r, &in[i], &g[i], points_a_segment);
        if (o.basis == HAIROBB_BASIS_HERMITE) g[i].tangents = in[i].tangents;
        if (flags & 16) g[i].shape = (hairobb_group_shape)(next_byte(&r) % 3);   /* MIXED SHAPES: the options' or its own */
        fuzz_round |= group_shape(&o, &g[i]) == HAIROBB_SHAPE_ROUND;
    }
    for (i = 0; i < RAYS; ++i) {
        for (k = 0; k < 3; ++k) {
            rays[i].org[k] = next_float(&r);
            rays[i].dir[k] = next_float(&r);
        }
        rays[i].tnear = 0.0f;
        rays[i].tfar = INFINITY;
        rays[i].time = 0.0f;
        masks[i] = next_byte(&r) & 7u;
    }
    result = hairobb_build_groups(g, count, &o, &bvh);
    if (!documented(result)) fuzz_fail("hairobb_build_groups returned an undocumented code");
    if (result != HAIROBB_OK) {
        if (bvh) fuzz_fail("a failed build left a BVH");
        return 0;
    }
    for (i = 0; i < count; ++i) {   /* each group's own BVH, of its shape (an empty group: none) */
        if (!g[i].segment_count) continue;
        if (build_own(&o, &g[i], &own[i]) != HAIROBB_OK) fuzz_fail("a group builds in a group BVH but not alone");
    }
    check_rays(bvh, own, g, count, rays, masks, moderate(g, count, points_a_segment, rays));

    /* a refit of one group to moved points (maybe bad) */
    {
        size_t which = next_byte(&r) % count, n = g[which].vertex_count;
        float dx = next_float(&r);
        moved = in[which];
        for (i = 0; i < 4 * n; ++i)
            if ((i & 3) == 0) moved.points[i] += dx * (float)(i % 5);
        result = hairobb_refit_group(bvh, (uint32_t)which, moved.points, o.basis == HAIROBB_BASIS_HERMITE ? moved.tangents : NULL, NULL);
        if (result != HAIROBB_OK && result != HAIROBB_ERROR_INVALID_GEOMETRY) fuzz_fail("refit_group: an undocumented code");
        if (result == HAIROBB_OK && g[which].segment_count) {
            hairobb_free(own[which]);
            own[which] = NULL;
            g[which].vertices = moved.points;
            g[which].tangents = o.basis == HAIROBB_BASIS_HERMITE ? moved.tangents : NULL;
            if (build_own(&o, &g[which], &own[which]) != HAIROBB_OK) fuzz_fail("a group refitted that does not build alone");
        }
        check_rays(bvh, own, g, count, rays, masks, moderate(g, count, points_a_segment, rays));
    }

    /* saved and loaded over the same groups: the same hits */
    {
        size_t bytes = hairobb_save_size(bvh);
        unsigned char *saved = (unsigned char *)malloc(bytes ? bytes : 1);
        if (!saved || hairobb_save(bvh, saved, bytes) != HAIROBB_OK) fuzz_fail("save");
        result = hairobb_load_groups(saved, bytes, g, count, &o, &loaded);
        if (result != HAIROBB_OK) fuzz_fail("load_groups of what was saved");
        check_rays(loaded, own, g, count, rays, masks, moderate(g, count, points_a_segment, rays));
        free(saved);
    }
    hairobb_free(loaded);
    hairobb_free(bvh);
    free_own(own, count);
    return 0;
}
