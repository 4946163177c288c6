/* fuzz_scene.c - libFuzzer target: arbitrary bytes become 1 to 4 BVHs
   (ribbons or tubes, caps and culling, any basis, points as read_point
   makes them: repeated, collinear, cusped, poisoned; fuzz_input.h) and a
   scene (SCENES in hairobb.h) over 0 to 8 instances of them, each with a
   mask and an affine map: the identity, a diagonal of powers of 2 with a
   translation (inverses exact), a similarity, 12 raw floats, a nearly
   singular map, a singular one, one entry NaN, Inf, beyond 1e18 or at
   the limits, a huge or tiny scale; an instance may name a BVH whose
   build failed (none). hairobb_scene_build must refuse with
   INVALID_ARGUMENT an instance without a BVH or with a map not finite,
   beyond 1e18 or singular, accept the identity and the exact maps, and
   return nothing else. Rays, each with a mask (hairobb_context.mask):
   - hits sane: instance_id below the count, of an instance the mask
     lets through, prim_id within that instance's BVH, group_id 0, t
     finite in [tnear, tfar], u in [0, 1], Ng unit; hairobb_scene_user
     gives back the instance's pointer; occluded1 true where intersect1
     hits; a miss names nothing;
   - where every instance the ray's mask lets through has an exact map:
     the nearest of each instance's BVH hits of the ray mapped into it (in
     double, rounded once), ties to the lower instance; occluded1 the
     BVHs' occluded1 (to the bit; hair and rays of moderate size,
     moderate_hair);
   - a path of 8 bounces from each hit (`from` a scene hit; `hit` the same
     as `from` or not, which must agree), each sane, occluded where
     intersect1 hits;
   - a per-call filter (fuzz_input.h) shown only hits of instances the
     mask lets through, with instance_id set: the hit returned one it
     took, occluded1 where it took one, taking all changes nothing;
   - each BVH alone under the identity map: the BVH's own hit of the ray
     (and along a path of bounces from it), bit for bit but instance_id
     and Ng, which is made unit again (within 1e-6).
   Then hairobb_scene_update to 0 to 8 instances (some kept, some with a
   new map, mask or BVH, some added or removed): refused as a build would
   be, then tracing as before (to the bit), or accepted and checked as
   above; hairobb_scene_count the instances'. Build with clang -fsanitize=fuzzer,address,undefined (see `make
   fuzz`). Seeds: tests/fuzz/corpus/scene, written by this file built
   with -DFUZZ_SCENE_WRITE_SEEDS. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#define HAIROBB_IMPLEMENTATION
#include "../../hairobb.h"
#include "fuzz_checks.h"
#include "fuzz_input.h"

#define MAX_HAIRS 4
#define MAX_SEGMENTS 16
#define MAX_INSTANCES 8
#define MAX_RAYS 16
#define PATH_BOUNCES 8

/* a switch from 2 bits: AUTO, ON, OFF, and the setting that differs from the default again */
static const hairobb_switch then_on[4] = {HAIROBB_AUTO, HAIROBB_ON, HAIROBB_OFF, HAIROBB_ON};
static const hairobb_switch then_off[4] = {HAIROBB_AUTO, HAIROBB_ON, HAIROBB_OFF, HAIROBB_OFF};

/* One BVH's hair, and the BVH (NULL where its build failed). */
typedef struct fuzz_hair {
    float *vertices, *tangents;
    uint32_t *indices;
    size_t segments, vertex_count;
    unsigned points;   /* a segment's control points */
    int round;
    hairobb_bvh *bvh;
} fuzz_hair;

/* What the input made of an instance's map: whether a build must refuse
   it, whether its inverse is known exactly (diagonal, powers of 2) and
   the inverse then. */
typedef struct map_info {
    int refused, exact;
    float inverse[12];
} map_info;

typedef struct scene_input {
    fuzz_hair hairs[MAX_HAIRS];
    unsigned hair_count;
    hairobb_instance instances[MAX_INSTANCES];
    unsigned hair_of[MAX_INSTANCES];
    map_info maps[MAX_INSTANCES];
    size_t count;
    int users[MAX_INSTANCES];
    uint32_t masks[MAX_INSTANCES];    /* for the filter */
    size_t segments[MAX_INSTANCES];
} scene_input;

/* A ray and the bytes of its checks, read before any is traced (so that
   the bytes an input takes do not depend on its hits). */
typedef struct scene_ray {
    hairobb_ray ray;
    uint32_t mask;
    unsigned path, path_flags, filter_choice;
    uint32_t pattern;
    float given[PATH_BOUNCES][3], bounce_tfar;
} scene_ray;

/* A mask: 0 (every bit) often, one of 4 bits mostly (so that masks meet
   and miss), any 32 bits sometimes. */
static uint32_t read_mask(reader *r)
{
    unsigned b = read_byte(r);
    if (b < 96) return 0u;
    if (b < 224) return 1u << (b & 3);
    return read_u32(r);
}

static int masks_meet(uint32_t a, uint32_t b) { return ((a ? a : 0xffffffffu) & (b ? b : 0xffffffffu)) != 0; }

/* The result a static build of this hair may return: each error it has
   (no segments; an index past the vertices; a bad point or tangent a
   segment reads), or success where it has none. */
static int build_result_allowed(hairobb_result result, const fuzz_hair *h)
{
    unsigned points = h->points, j;
    int index = 0, geometry = 0;
    size_t i;
    for (i = 0; i < h->segments; ++i) {
        if ((size_t)h->indices[i] + points > h->vertex_count) { index = 1; continue; }
        for (j = 0; j < points; ++j) {
            geometry |= bad_point(h->vertices + 4 * ((size_t)h->indices[i] + j));
            if (h->tangents) geometry |= bad_tangent(h->tangents + 4 * ((size_t)h->indices[i] + j));
        }
    }
    if (result == HAIROBB_ERROR_INVALID_ARGUMENT) return h->segments == 0;
    if (result == HAIROBB_ERROR_INDEX_OUT_OF_RANGE) return index;
    if (result == HAIROBB_ERROR_INVALID_GEOMETRY) return geometry;
    if (result == HAIROBB_OK || result == HAIROBB_ERROR_OUT_OF_MEMORY) return h->segments && !index && !geometry;
    return 0;
}

/* A BVH from the input: shape, caps, culling, strands, bezier_copy, basis,
   layout, node policy, leaf size, spatial splits, then the points and
   indices. Returns 0 where memory ran out. */
static int read_hair(reader *r, fuzz_hair *h)
{
    hairobb_build_options options;
    unsigned shape = read_byte(r), how = read_byte(r), sizes = read_byte(r);
    hairobb_result result;
    size_t i;
    memset(&options, 0, sizeof options);
    options.shape = shape & 1 ? HAIROBB_SHAPE_ROUND : HAIROBB_SHAPE_RIBBON;
    h->round = shape & 1;
    options.end_caps = then_on[shape >> 1 & 3];
    options.back_faces = then_off[shape >> 3 & 3];
    options.bezier_copy = then_off[shape >> 6 & 3];
    options.basis = (hairobb_basis)(how % 5);
    h->points = options.basis == HAIROBB_BASIS_LINEAR || options.basis == HAIROBB_BASIS_HERMITE ? 2u : 4u;
    options.obb_layout = (hairobb_obb_layout)(how / 5 % 5);
    options.nodes = (hairobb_node_policy)(how / 25 % 3);
    options.max_leaf_size = sizes % 16;
    options.spatial_splits = sizes & 16 ? HAIROBB_ON : HAIROBB_AUTO;
    options.threads = 1;
    h->segments = read_byte(r) % (MAX_SEGMENTS + 1);
    h->vertex_count = 4 * h->segments + 3;
    h->vertices = (float *)malloc(sizeof(float) * 4 * h->vertex_count);
    h->indices = (uint32_t *)malloc(sizeof(uint32_t) * (h->segments + 1));
    if (!h->vertices || !h->indices) return 0;
    for (i = 0; i < h->vertex_count; ++i) read_point(r, h->vertices, i);
    read_indices(r, h->indices, h->segments, h->vertex_count, shape >> 5 & 1, options.basis);
    if (options.basis == HAIROBB_BASIS_HERMITE) {
        h->tangents = (float *)malloc(sizeof(float) * 4 * h->vertex_count);
        if (!h->tangents) return 0;
        difference_tangents(h->vertices, h->vertex_count, h->tangents);
        options.tangents = h->tangents;
    }
    result = hairobb_build(h->vertices, h->vertex_count, h->indices, h->segments, &options, &h->bvh);
    if (!build_result_allowed(result, h)) fuzz_fail("a build's result is not one its input's errors allow");
    if ((result == HAIROBB_OK) != (h->bvh != NULL)) fuzz_fail("a build's BVH and its result disagree");
    if (h->bvh) {
        fuzz_round = h->round;
        fuzz_check_rays_through_bounds(h->bvh, h->segments, 0.0f);
        fuzz_round = 0;   /* scene hits: made unit again */
    }
    return 1;
}

static void free_hair(fuzz_hair *h)
{
    hairobb_free(h->bvh);
    free(h->vertices);
    free(h->tangents);
    free(h->indices);
}

/* A rotation (unit quaternion from the input; the identity for a zero
   one) times a uniform scale, and a translation from the input. */
static void similarity(reader *r, float m[12], float scale)
{
    float q[4], n = 0.0f;
    int i;
    for (i = 0; i < 4; ++i) {
        q[i] = read_coordinate(r);
        if (!isfinite(q[i])) q[i] = 0.0f;
        n += q[i] * q[i];
    }
    if (!(n > 1e-12f && n < 1e30f)) { q[0] = 1.0f; q[1] = q[2] = q[3] = 0.0f; n = 1.0f; }
    n = 1.0f / sqrtf(n);
    for (i = 0; i < 4; ++i) q[i] *= n;
    m[0] = scale * (1 - 2 * (q[2] * q[2] + q[3] * q[3])); m[1] = scale * 2 * (q[1] * q[2] - q[0] * q[3]); m[2] = scale * 2 * (q[1] * q[3] + q[0] * q[2]);
    m[4] = scale * 2 * (q[1] * q[2] + q[0] * q[3]); m[5] = scale * (1 - 2 * (q[1] * q[1] + q[3] * q[3])); m[6] = scale * 2 * (q[2] * q[3] - q[0] * q[1]);
    m[8] = scale * 2 * (q[1] * q[3] - q[0] * q[2]); m[9] = scale * 2 * (q[2] * q[3] + q[0] * q[1]); m[10] = scale * (1 - 2 * (q[1] * q[1] + q[2] * q[2]));
    for (i = 0; i < 3; ++i) m[4 * i + 3] = read_coordinate(r);
}

/* A diagonal of powers of 2 (signs too, 2^-8 to 2^8) and a translation:
   its inverse is exact (1 / s on the diagonal, -t / s rounded once). */
static void diagonal(reader *r, float m[12], map_info *info)
{
    int i;
    memset(m, 0, 12 * sizeof(float));
    for (i = 0; i < 3; ++i) {
        unsigned e = read_byte(r);
        m[5 * i] = ldexpf(e & 128 ? -1.0f : 1.0f, (int)(e % 17) - 8);
    }
    for (i = 0; i < 3; ++i) m[4 * i + 3] = read_coordinate(r);
    memset(info->inverse, 0, sizeof info->inverse);
    for (i = 0; i < 3; ++i) {
        info->inverse[5 * i] = 1.0f / m[5 * i];
        info->inverse[4 * i + 3] = (float)-((double)info->inverse[5 * i] * m[4 * i + 3]);
    }
    info->exact = 1;
}

/* An instance's map from the input (kinds above), and what a build must
   do with it. */
static void read_map(reader *r, float m[12], map_info *info)
{
    unsigned kind = read_byte(r) % 8, b, i, j;
    memset(m, 0, 12 * sizeof(float));
    memset(info, 0, sizeof *info);
    switch (kind) {
    case 0:   /* the identity */
        m[0] = m[5] = m[10] = 1.0f;
        info->inverse[0] = info->inverse[5] = info->inverse[10] = 1.0f;
        info->exact = 1;
        break;
    case 1: diagonal(r, m, info); break;
    case 2:
        b = read_byte(r);
        similarity(r, m, ldexpf(1.0f + (float)(b & 15) / 16.0f, (int)(b >> 4) - 8));
        break;
    case 3:
        for (i = 0; i < 12; ++i) m[i] = read_coordinate(r);
        break;
    case 4: {   /* nearly singular: column 2 nearly a combination of the others */
        float a = read_coordinate(r), c = read_coordinate(r), eps = ldexpf(1.0f, -(int)(read_byte(r) % 48));
        similarity(r, m, 1.0f);
        for (i = 0; i < 3; ++i) m[4 * i + 2] = a * m[4 * i] + c * m[4 * i + 1] + eps * m[4 * i + 2];
        break;
    }
    case 5:   /* singular: a row or column zero, or a multiple of another */
        diagonal(r, m, info);
        b = read_byte(r);
        i = b % 3;
        j = (i + 1 + (b >> 2) % 2) % 3;
        switch (b >> 3 & 3) {
        case 0: m[4 * i] = m[4 * i + 1] = m[4 * i + 2] = 0.0f; break;
        case 1: m[i] = m[4 + i] = m[8 + i] = 0.0f; break;
        case 2: m[4 * i] = m[4 * j]; m[4 * i + 1] = m[4 * j + 1]; m[4 * i + 2] = m[4 * j + 2]; break;
        default: m[i] = 2.0f * m[j]; m[4 + i] = 2.0f * m[4 + j]; m[8 + i] = 2.0f * m[8 + j]; break;
        }
        info->exact = 0;
        info->refused = 1;
        break;
    case 6:   /* one entry poisoned, or at the limits */
        diagonal(r, m, info);
        b = read_byte(r);
        m[b % 12] = fuzz_poison[b / 12 % 8];
        info->exact = 0;
        break;
    default:   /* a huge or tiny scale */
        b = read_byte(r);
        similarity(r, m, (float)pow(10.0, b & 128 ? -(double)(b % 19) : (double)(b % 19)));
        break;
    }
    for (i = 0; i < 12; ++i)
        if (!(fabsf(m[i]) <= 1e18f)) info->refused = 1;
    if (info->refused) info->exact = 0;
}

/* Instance i from the input: its BVH (maybe one whose build failed), mask, map. */
static void read_instance(reader *r, scene_input *s, size_t i)
{
    unsigned pick = read_byte(r) % s->hair_count;
    hairobb_instance *inst = &s->instances[i];
    s->hair_of[i] = pick;
    inst->bvh = s->hairs[pick].bvh;
    inst->mask = read_mask(r);
    inst->user = &s->users[i];
    read_map(r, inst->transform, &s->maps[i]);
}

/* What a build or update of the instances must return: INVALID_ARGUMENT
   where one must be refused, OK where every one has an exact map (or
   the identity) and a BVH, else either. */
static int scene_result_allowed(hairobb_result result, const scene_input *s)
{
    int refused = 0, accepted = 1;
    size_t i;
    for (i = 0; i < s->count; ++i) {
        int none = s->instances[i].bvh == NULL;
        refused |= none || s->maps[i].refused;
        accepted &= !none && s->maps[i].exact;
    }
    if (result == HAIROBB_ERROR_INVALID_ARGUMENT) return !accepted;
    if (result == HAIROBB_OK) return !refused;
    return result == HAIROBB_ERROR_OUT_OF_MEMORY;
}

static void read_ray(reader *r, scene_ray *sr)
{
    hairobb_ray *ray = &sr->ray;
    unsigned b;
    int j;
    for (j = 0; j < 3; ++j) ray->org[j] = read_coordinate(r);
    for (j = 0; j < 3; ++j) ray->dir[j] = read_coordinate(r);
    ray->tnear = read_byte(r) < 200 ? 0.0f : read_coordinate(r);
    ray->tfar = read_byte(r) < 200 ? INFINITY : read_coordinate(r);
    ray->time = (float)read_byte(r) / 255.0f;   /* static BVHs ignore it */
    sr->mask = read_mask(r);
    sr->path = read_byte(r);
    sr->path |= read_byte(r) << 8;
    sr->path_flags = read_byte(r);
    for (b = 0; b < PATH_BOUNCES; ++b)
        if ((sr->path >> (2 * b) & 3) == 3)
            for (j = 0; j < 3; ++j) sr->given[b][j] = read_coordinate(r);
    sr->bounce_tfar = sr->path_flags & 1 ? read_coordinate(r) : INFINITY;
    sr->filter_choice = read_byte(r);
    sr->pattern = read_u32(r);
}

/* The ray in an instance with an exact inverse, as SCENES maps it: in
   double, rounded once. */
static void ray_to_object(const map_info *info, const hairobb_ray *ray, hairobb_ray *object)
{
    const float *m = info->inverse;
    int i;
    for (i = 0; i < 3; ++i) {
        object->org[i] = (float)((double)m[4 * i] * ray->org[0] + (double)m[4 * i + 1] * ray->org[1] +
                                 (double)m[4 * i + 2] * ray->org[2] + (double)m[4 * i + 3]);
        object->dir[i] = (float)((double)m[4 * i] * ray->dir[0] + (double)m[4 * i + 1] * ray->dir[1] + (double)m[4 * i + 2] * ray->dir[2]);
    }
    object->tnear = ray->tnear;
    object->tfar = ray->tfar;
    object->time = ray->time;
}

/* t, u, v and the segment to the bit, and the instance */
static int same_place(const hairobb_hit *a, const hairobb_hit *b)
{
    if (a->prim_id == HAIROBB_INVALID_ID || b->prim_id == HAIROBB_INVALID_ID) return a->prim_id == b->prim_id;
    return a->prim_id == b->prim_id && a->instance_id == b->instance_id && memcmp(&a->t, &b->t, sizeof a->t) == 0 &&
           memcmp(&a->u, &b->u, sizeof a->u) == 0 && memcmp(&a->v, &b->v, sizeof a->v) == 0;
}

/* A scene hit is sane: an instance the ray's mask lets through, a
   segment of its BVH, t and u in range; its user pointer given back. */
static void check_scene_hit(const hairobb_scene *scene, const scene_input *s, const hairobb_ray *ray, uint32_t mask,
                            const hairobb_hit *hit)
{
    if (hit->instance_id >= s->count) fuzz_fail("a scene hit of no instance");
    fuzz_check_hit(ray, hit, s->segments[hit->instance_id], hit->instance_id);
    if (!masks_meet(s->instances[hit->instance_id].mask, mask)) fuzz_fail("a hit of an instance the ray's mask leaves out");
    if (hairobb_scene_user(scene, hit->instance_id) != s->instances[hit->instance_id].user) fuzz_fail("another user pointer");
}

/* Where every instance the mask lets through has an exact inverse: the
   scene's hit is the nearest of their BVHs' own hits of the ray mapped
   (ties to the lower instance), its occlusion theirs; for hair and rays
   (world and object) of moderate size (moderate_hair: beyond it a hit may
   lie outside its segment's box, and a BVH traced with a shorter tfar
   miss it), and hits not on hair thinner than rounding (rounding_decided). */
static void check_exact(const scene_input *s, const hairobb_ray *ray, uint32_t mask, int got, const hairobb_hit *hit, int occluded)
{
    hairobb_hit best, h;
    int best_got = 0, any_occluded = 0;
    size_t i;
    if (!moderate_ray(ray)) return;
    for (i = 0; i < s->count; ++i) {
        const fuzz_hair *hair = &s->hairs[s->hair_of[i]];
        hairobb_ray object;
        if (!masks_meet(s->instances[i].mask, mask)) continue;
        if (!s->maps[i].exact || !moderate_hair(hair->vertices, hair->indices, hair->segments, hair->points)) return;
        ray_to_object(&s->maps[i], ray, &object);
        if (!moderate_ray(&object)) return;
    }
    best.prim_id = HAIROBB_INVALID_ID;
    for (i = 0; i < s->count; ++i) {
        hairobb_ray object;
        if (!masks_meet(s->instances[i].mask, mask)) continue;
        ray_to_object(&s->maps[i], ray, &object);
        any_occluded |= hairobb_occluded1(s->instances[i].bvh, &object);
        if (!hairobb_intersect1(s->instances[i].bvh, &object, &h)) continue;
        if (best_got && !(h.t < best.t)) continue;   /* ties: the lower instance, found first */
        best = h;
        best.instance_id = (uint32_t)i;
        best_got = 1;
    }
    for (i = 0; i < 2; ++i) {
        /* a hit on hair thinner than rounding: a box may keep it or not */
        const hairobb_hit *one = i ? hit : &best;
        hairobb_ray object;
        if (!(i ? got : best_got)) continue;
        ray_to_object(&s->maps[one->instance_id], ray, &object);
        if (rounding_decided(s->instances[one->instance_id].bvh, &object, one)) return;
    }
    if (best_got != got || !same_place(&best, hit)) fuzz_fail("a scene's hit is not the nearest of its instances' own");
    if (any_occluded != occluded) fuzz_fail("a scene's occlusion is not its instances' own");
}

/* The ray's path of bounces through the scene from its hit: each hit
   sane, occluded where intersect1 hits, `hit` == `from` the same. */
static void scene_path(const hairobb_scene *scene, const scene_input *s, const scene_ray *sr, const hairobb_context *context,
                       const hairobb_hit *first_hit)
{
    hairobb_ray ray = sr->ray;
    hairobb_hit from = *first_hit, hit;
    unsigned bounce;
    int j;
    for (bounce = 0; bounce < PATH_BOUNCES; ++bounce) {
        hairobb_ray next;
        unsigned kind = sr->path >> (2 * bounce) & 3;
        int got;
        for (j = 0; j < 3; ++j) next.org[j] = ray.org[j] + from.t * ray.dir[j];
        if (kind == 3) memcpy(next.dir, sr->given[bounce], sizeof next.dir);
        else bounce_direction(NULL, kind, ray.dir, &from, next.dir);
        next.tnear = 0.0f;
        next.tfar = sr->bounce_tfar;
        next.time = ray.time;
        got = hairobb_scene_intersect1(scene, context, &from, &next, &hit);
        if (sr->path_flags & 2) {
            hairobb_hit same = from;
            if (hairobb_scene_intersect1(scene, context, &same, &next, &same) != got || !same_hit(&same, &hit))
                fuzz_fail("scene_intersect1 with hit == from differs");
        }
        if (!got) {
            fuzz_check_miss(&hit);
            return;
        }
        check_scene_hit(scene, s, &next, context->mask, &hit);
        if (!hairobb_scene_occluded1(scene, context, &from, &next)) fuzz_fail("scene_intersect1 from a hit hits where occluded1 does not");
        from = hit;
        ray = next;
    }
}

/* The call's filter over the scene: shown only hits the mask lets
   through (fuzz_filter_fn checks), the hit returned one it took. */
static void scene_filter(const hairobb_scene *scene, scene_input *s, const scene_ray *sr, int got_plain, const hairobb_hit *plain,
                         int occluded_plain)
{
    fuzz_filter f;
    hairobb_context context;
    hairobb_hit hit;
    int got, occluded;
    memset(&f, 0, sizeof f);
    f.mode = sr->filter_choice % FILTER_MODES;
    f.pattern = sr->pattern;
    f.instance_masks = s->masks;
    f.instance_segments = s->segments;
    f.instance_count = s->count;
    f.ray_mask = sr->mask;
    context.filter = fuzz_filter_fn;
    context.user = &f;
    context.mask = sr->mask;
    got = hairobb_scene_intersect1(scene, &context, NULL, &sr->ray, &hit);
    if (got) {
        check_scene_hit(scene, s, &sr->ray, sr->mask, &hit);
        if (!fuzz_filter_took(&f, &hit)) fuzz_fail("scene_intersect1 returned a hit its filter did not take");
    } else {
        fuzz_check_miss(&hit);
    }
    if (f.taken && !got) fuzz_fail("scene_intersect1 missed where its filter took a hit");
    if (f.mode == FILTER_ALL && (got != got_plain || !same_hit(&hit, plain))) fuzz_fail("a filter taking every hit changed a scene's hit");
    if (f.mode == FILTER_NONE && got) fuzz_fail("a filter taking no hit, and a scene hit");
    fuzz_filter_reset(&f);
    occluded = hairobb_scene_occluded1(scene, &context, NULL, &sr->ray);
    if (occluded != (f.taken > 0)) fuzz_fail("scene_occluded1's answer is not whether its filter took a hit");
    if (f.mode == FILTER_ALL && occluded != occluded_plain) fuzz_fail("a filter taking every hit changed a scene's occlusion");
}

/* Every check of one ray through the scene. */
static void check_scene_ray(const hairobb_scene *scene, scene_input *s, const scene_ray *sr)
{
    hairobb_context context;
    hairobb_hit hit;
    int got, occluded;
    memset(&context, 0, sizeof context);
    context.mask = sr->mask;
    got = hairobb_scene_intersect1(scene, &context, NULL, &sr->ray, &hit);
    occluded = hairobb_scene_occluded1(scene, &context, NULL, &sr->ray);
    if (got) {
        check_scene_hit(scene, s, &sr->ray, sr->mask, &hit);
        if (!occluded) fuzz_fail("scene_intersect1 hits where scene_occluded1 does not");
        scene_path(scene, s, sr, &context, &hit);
    } else {
        fuzz_check_miss(&hit);
    }
    check_exact(s, &sr->ray, sr->mask, got, &hit, occluded);
    scene_filter(scene, s, sr, got, &hit, occluded);
}

/* Floats equal as numbers (a map by the identity turns -0 into +0). */
static int same_vector(const float *a, const float *b, float tolerance)
{
    int j;
    for (j = 0; j < 3; ++j)
        if (isfinite(a[j]) && isfinite(b[j]) && !(fabsf(a[j] - b[j]) <= tolerance)) return 0;
    return 1;
}

/* Scene (identity instance 0) against its BVH: the same hit but the
   instance and Ng, made unit again (SCENES), which may move its last
   bits. */
static void compare_identity(const hairobb_ray *ray, size_t segments, int round, int got_scene, const hairobb_hit *scene_hit, int got_bvh,
                             const hairobb_hit *bvh_hit)
{
    double length = sqrt((double)bvh_hit->Ng[0] * bvh_hit->Ng[0] + (double)bvh_hit->Ng[1] * bvh_hit->Ng[1] +
                         (double)bvh_hit->Ng[2] * bvh_hit->Ng[2]);
    float unit[3];
    int j;
    if (got_scene != got_bvh) fuzz_fail("a BVH under the identity map hits where the BVH alone does not, or misses");
    if (!got_bvh) return;
    fuzz_round = round;
    fuzz_check_hit(ray, bvh_hit, segments, HAIROBB_INVALID_ID);
    fuzz_round = 0;
    fuzz_check_hit(ray, scene_hit, segments, 0);
    for (j = 0; j < 3; ++j) unit[j] = (float)(bvh_hit->Ng[j] / length);
    if (scene_hit->instance_id != 0 || scene_hit->prim_id != bvh_hit->prim_id || memcmp(&scene_hit->t, &bvh_hit->t, sizeof scene_hit->t) ||
        memcmp(&scene_hit->u, &bvh_hit->u, sizeof scene_hit->u) || memcmp(&scene_hit->v, &bvh_hit->v, sizeof scene_hit->v) ||
        !same_vector(scene_hit->tangent, bvh_hit->tangent, 0.0f) || !same_vector(scene_hit->Ng, unit, 1e-6f))
        fuzz_fail("a BVH under the identity map gives another hit than the BVH alone");
}

/* Each built BVH alone under the identity map, against the BVH's own
   calls on the ray as the scene maps it (-0 becomes +0, a NaN or Inf
   anywhere every component NaN), and along the ray's path of bounces
   (directions from the BVH's hits; the scene's `from` the BVH's hit as
   instance 0's). */
static void check_identity(const fuzz_hair *h, const scene_ray *rays, unsigned ray_count)
{
    hairobb_instance one;
    hairobb_scene *scene = NULL;
    map_info identity;
    unsigned k, bounce;
    int j;
    if (!h->bvh) return;
    memset(&one, 0, sizeof one);
    memset(&identity, 0, sizeof identity);
    one.bvh = h->bvh;
    one.transform[0] = one.transform[5] = one.transform[10] = 1.0f;
    identity.inverse[0] = identity.inverse[5] = identity.inverse[10] = 1.0f;
    if (hairobb_scene_build(&one, 1, NULL, &scene) != HAIROBB_OK) fuzz_fail("a scene of one BVH under the identity");
    for (k = 0; k < ray_count; ++k) {
        const scene_ray *sr = &rays[k];
        hairobb_ray ray = sr->ray, object;
        hairobb_hit a, b, from;
        int got_a, got_b;
        ray_to_object(&identity, &ray, &object);
        got_a = hairobb_scene_intersect1(scene, NULL, NULL, &ray, &a);
        got_b = hairobb_intersect1(h->bvh, &object, &b);
        compare_identity(&ray, h->segments, h->round, got_a, &a, got_b, &b);
        if (hairobb_scene_occluded1(scene, NULL, NULL, &ray) != hairobb_occluded1(h->bvh, &object))
            fuzz_fail("a BVH under the identity map is occluded where the BVH alone is not, or not");
        for (bounce = 0; bounce < PATH_BOUNCES && got_b; ++bounce) {
            hairobb_ray next;
            unsigned kind = sr->path >> (2 * bounce) & 3;
            for (j = 0; j < 3; ++j) next.org[j] = ray.org[j] + b.t * ray.dir[j];
            if (kind == 3) memcpy(next.dir, sr->given[bounce], sizeof next.dir);
            else bounce_direction(NULL, kind, ray.dir, &b, next.dir);
            next.tnear = 0.0f;
            next.tfar = sr->bounce_tfar;
            next.time = ray.time;
            from = b;
            from.instance_id = 0;
            ray_to_object(&identity, &next, &object);
            got_a = hairobb_scene_intersect1(scene, NULL, &from, &next, &a);
            got_b = hairobb_intersect1_from(h->bvh, &b, &object, &b);
            compare_identity(&next, h->segments, h->round, got_a, &a, got_b, &b);
            ray = next;
        }
    }
    hairobb_scene_free(scene);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static scene_input s;
    scene_ray rays[MAX_RAYS];
    hairobb_scene *scene = NULL;
    hairobb_result result;
    reader r;
    unsigned k, ray_count;
    size_t i;
    r.data = data; r.size = size; r.at = 0;
    memset(&s, 0, sizeof s);
    s.hair_count = 1 + read_byte(&r) % MAX_HAIRS;
    for (k = 0; k < s.hair_count; ++k)
        if (!read_hair(&r, &s.hairs[k])) goto done;
    s.count = read_byte(&r) % (MAX_INSTANCES + 1);
    for (i = 0; i < s.count; ++i) read_instance(&r, &s, i);
    ray_count = 1 + read_byte(&r) % MAX_RAYS;
    for (k = 0; k < ray_count; ++k) read_ray(&r, &rays[k]);
    for (i = 0; i < s.count; ++i) {
        s.masks[i] = s.instances[i].mask;
        s.segments[i] = s.hairs[s.hair_of[i]].segments;
    }

    if (hairobb_scene_build(s.instances, s.count, NULL, NULL) != HAIROBB_ERROR_INVALID_ARGUMENT ||
        (s.count && (hairobb_scene_build(NULL, s.count, NULL, &scene) != HAIROBB_ERROR_INVALID_ARGUMENT || scene)))
        fuzz_fail("a scene build without instances or out");
    result = hairobb_scene_build(s.instances, s.count, NULL, &scene);
    if (!scene_result_allowed(result, &s)) fuzz_fail("a scene build's result is not one its instances allow");
    if ((result == HAIROBB_OK) != (scene != NULL)) fuzz_fail("a scene build's scene and its result disagree");
    if (scene && hairobb_scene_count(scene) != s.count) fuzz_fail("a scene's count is not its instances'");
    for (k = 0; k < s.hair_count; ++k) check_identity(&s.hairs[k], rays, ray_count);
    if (!scene) goto done;
    for (k = 0; k < ray_count; ++k) check_scene_ray(scene, &s, &rays[k]);

    /* an update from the input: as many instances (0 to 8: some added,
       some removed), each kept or with a new map, mask or BVH */
    {
        hairobb_hit before[MAX_RAYS], after;
        int got_before[MAX_RAYS];
        scene_input old;
        unsigned how = read_byte(&r);
        size_t count = how < 128 ? s.count : how % (MAX_INSTANCES + 1);
        for (k = 0; k < ray_count; ++k) got_before[k] = hairobb_scene_intersect1(scene, NULL, NULL, &rays[k].ray, &before[k]);
        if (hairobb_scene_update(NULL, s.instances, s.count) != HAIROBB_ERROR_INVALID_ARGUMENT ||
            hairobb_scene_update(scene, NULL, 1) != HAIROBB_ERROR_INVALID_ARGUMENT)
            fuzz_fail("an update without a scene or instances");
        memcpy(&old, &s, sizeof old);
        for (i = 0; i < count; ++i) {
            if (i >= s.count) {
                read_instance(&r, &s, i);
                continue;
            }
            how = read_byte(&r);
            if (how < 96) continue;
            if (how < 176) {
                read_map(&r, s.instances[i].transform, &s.maps[i]);
            } else if (how < 216) {
                s.instances[i].mask = read_mask(&r);
            } else {
                s.hair_of[i] = read_byte(&r) % s.hair_count;
                s.instances[i].bvh = s.hairs[s.hair_of[i]].bvh;
            }
        }
        s.count = count;
        result = hairobb_scene_update(scene, s.instances, s.count);
        if (!scene_result_allowed(result, &s)) fuzz_fail("a scene update's result is not one its instances allow");
        if (result != HAIROBB_OK) {
            /* refused: the scene as it was */
            memcpy(&s, &old, sizeof s);
            for (k = 0; k < ray_count; ++k)
                if (hairobb_scene_intersect1(scene, NULL, NULL, &rays[k].ray, &after) != got_before[k] || !same_hit(&after, &before[k]))
                    fuzz_fail("a refused update changed a scene's hit");
        }
        if (hairobb_scene_count(scene) != s.count) fuzz_fail("a scene's count is not its instances'");
        for (i = 0; i < s.count; ++i) {
            s.masks[i] = s.instances[i].mask;
            s.segments[i] = s.hairs[s.hair_of[i]].segments;
        }
        for (k = 0; k < ray_count; ++k) check_scene_ray(scene, &s, &rays[k]);
    }

done:
    hairobb_scene_free(scene);
    for (k = 0; k < MAX_HAIRS; ++k) free_hair(&s.hairs[k]);
    return 0;
}

#ifdef FUZZ_SCENE_WRITE_SEEDS
/* Seeds: 1 to 4 BVHs of two strands of three segments each (every basis,
   ribbons and tubes, caps and culling, a degenerate point), placed by maps
   of every kind with masks, and rays aimed at a strand of an instance
   (its point mapped to world space) with masks, paths, filters, then an
   update; each seed names its choices. */
#include <stdio.h>

typedef struct writer {
    uint8_t bytes[8192];
    size_t size;
} writer;

static void put_byte(writer *w, unsigned b) { w->bytes[w->size++] = (uint8_t)b; }

/* read_coordinate's inverse, for values in [-7, 7) on its 1/4096 grid */
static void put_coordinate(writer *w, float v)
{
    int kind = (int)floorf(v * 16.0f);
    int rest = (int)((v - (float)kind / 16.0f) * 4096.0f + 0.5f);
    put_byte(w, (unsigned)(kind + 112));
    put_byte(w, (unsigned)(rest > 255 ? 255 : rest));
}

enum { SEED_POINTS_PLAIN, SEED_ZERO_LENGTH, SEED_CUSP, SEED_ZERO_RADIUS, SEED_HUGE_RADIUS, SEED_POISON };

typedef struct hair_seed {
    unsigned shape, basis, degenerate;
} hair_seed;

/* A map seed: its kind (read_map) and the bytes after the kind byte. */
typedef struct map_seed {
    unsigned kind, parameters[24], count;
} map_seed;

typedef struct scene_seed {
    unsigned hairs;
    hair_seed hair[MAX_HAIRS];
    unsigned instances;
    unsigned mask[MAX_INSTANCES];   /* read_mask's byte */
    map_seed map[MAX_INSTANCES];
    unsigned ray_mask, filter, path, update, new_count;   /* new_count: 0 the same, else the count + 1 */
} scene_seed;

/* control point k of a seed's hair: strands along x, in the xy plane */
static void seed_point(const hair_seed *h, unsigned k, float p[4])
{
    unsigned stride = h->basis == HAIROBB_BASIS_BEZIER ? 10 : 6, s = k / stride, j = k % stride;
    unsigned used = h->basis == HAIROBB_BASIS_BEZIER ? 10 : h->basis == HAIROBB_BASIS_LINEAR || h->basis == HAIROBB_BASIS_HERMITE ? 4 : 6;
    p[0] = -1.0f + 2.0f * (float)j / (float)(used - 1);
    p[1] = -0.25f + 0.5f * (float)s;
    p[2] = 0.1f * p[0] * p[0];
    p[3] = 0.05f;
}

static void write_hair(writer *w, const hair_seed *h)
{
    const unsigned segments = 6, vertex_count = 4 * 6 + 3;
    unsigned k, i;
    put_byte(w, h->shape | 32);          /* chained strands */
    put_byte(w, h->basis + 5 * (h->shape & 3));   /* some node layouts */
    put_byte(w, 0);
    put_byte(w, segments);
    for (k = 0; k < vertex_count; ++k) {
        float p[4];
        seed_point(h, k, p);
        if (k == 1 && h->degenerate == SEED_CUSP) { put_byte(w, 216); continue; }   /* back to point -1: point 0 */
        if (k >= 4 && k <= 6 && h->degenerate == SEED_ZERO_LENGTH) { put_byte(w, 128); continue; }
        if (k == 2 && h->degenerate == SEED_POISON) { put_byte(w, 248); put_byte(w, 0); continue; }   /* x NaN */
        if (k % 2 && h->degenerate == SEED_ZERO_RADIUS) {
            put_byte(w, 232); put_coordinate(w, p[0]); put_coordinate(w, p[1]); put_coordinate(w, p[2]);
            continue;
        }
        if (k == 3 && h->degenerate == SEED_HUGE_RADIUS) { put_byte(w, 176); put_coordinate(w, 1.0f); put_byte(w, 20); continue; }
        put_byte(w, 0);
        put_coordinate(w, p[0]); put_coordinate(w, p[1]); put_coordinate(w, p[2]); put_coordinate(w, p[3] / 0.05f);
    }
    for (i = 0; i < segments; ++i) put_byte(w, i == 3 ? 200 : 0);   /* a new strand at segment 3 */
}

/* the map a map seed's bytes read as (read_map on them) */
static void seed_map(const map_seed *m, float out[12])
{
    uint8_t bytes[25];
    reader r;
    map_info info;
    unsigned i;
    bytes[0] = (uint8_t)m->kind;
    for (i = 0; i < m->count; ++i) bytes[1 + i] = (uint8_t)m->parameters[i];
    r.data = bytes; r.size = 1 + m->count; r.at = 0;
    read_map(&r, out, &info);
}

static void write_seed(writer *w, const scene_seed *seed)
{
    const unsigned rays = 16;
    unsigned i, k;
    w->size = 0;
    put_byte(w, seed->hairs - 1);
    for (k = 0; k < seed->hairs; ++k) write_hair(w, &seed->hair[k]);
    put_byte(w, seed->instances);
    for (i = 0; i < seed->instances; ++i) {
        put_byte(w, i % seed->hairs);
        put_byte(w, seed->mask[i]);
        if (seed->mask[i] >= 224) { put_byte(w, 0x0f); put_byte(w, 0); put_byte(w, 0); put_byte(w, 0x80); }   /* 4 bits and the top one */
        put_byte(w, seed->map[i].kind);
        for (k = 0; k < seed->map[i].count; ++k) put_byte(w, seed->map[i].parameters[k]);
    }
    put_byte(w, rays - 1);
    for (i = 0; i < rays; ++i) {
        /* at instance i's strand i % 2, a point along it, from 3 units away */
        static const float directions[4][3] = {{0, 0, 1}, {0.6f, -0.8f, 0}, {0.3f, 0.4f, -0.866f}, {0, 0.6f, 0.8f}};
        unsigned instance = seed->instances ? i % seed->instances : 0, j;
        float m[12], p[4], world[3];
        const float *d = directions[i % 4];
        seed_point(&seed->hair[instance % seed->hairs], (i % 2) * (seed->hair[instance % seed->hairs].basis ? 6 : 10) + 1 + i % 3, p);
        if (seed->instances) seed_map(&seed->map[instance], m);
        else memset(m, 0, sizeof m), m[0] = m[5] = m[10] = 1.0f;
        for (j = 0; j < 3; ++j) world[j] = m[4 * j] * p[0] + m[4 * j + 1] * p[1] + m[4 * j + 2] * p[2] + m[4 * j + 3];
        for (j = 0; j < 3; ++j) {
            float o = world[j] - 3.0f * d[j];
            put_coordinate(w, !(o > -6.9f) ? -6.9f : o > 6.9f ? 6.9f : o);   /* NaN: a map refused */
        }
        for (j = 0; j < 3; ++j) put_coordinate(w, d[j]);
        put_byte(w, 0); put_byte(w, 0);            /* tnear 0, tfar infinite */
        put_byte(w, 40);                           /* time */
        put_byte(w, i % 3 ? 0 : seed->ray_mask);   /* some rays masked */
        put_byte(w, seed->path & 255); put_byte(w, (seed->path >> 8) & 255); put_byte(w, i % 2 ? 2 : 0);
        for (j = 0; j < PATH_BOUNCES; ++j)
            if ((seed->path >> (2 * j) & 3) == 3) { put_coordinate(w, 0.0f); put_coordinate(w, 0.0f); put_coordinate(w, -1.0f); }
        put_byte(w, seed->filter);
        put_byte(w, 0x5a + i); put_byte(w, 0xc3); put_byte(w, 0x0f); put_byte(w, 0xf0);
    }
    /* the update: the count (kept, or new_count - 1), each instance's op
       (kept, a new map, mask or BVH), the added ones under the identity */
    put_byte(w, seed->new_count ? 128 + (seed->new_count - 1 + 7) % 9 : 0);   /* 128 + x: x + 128 = count (mod 9) */
    for (i = 0; i < seed->instances && (!seed->new_count || i + 1 < seed->new_count); ++i) {
        unsigned op = seed->update >> (2 * (i % 4)) & 3;
        if (op == 0) put_byte(w, 0);
        else if (op == 1) { put_byte(w, 100); put_byte(w, 1); put_byte(w, 8); put_byte(w, 8); put_byte(w, 9); put_coordinate(w, 0.5f); put_coordinate(w, -0.25f); put_coordinate(w, 1.0f); }
        else if (op == 2) { put_byte(w, 180); put_byte(w, 100 + i); }
        else { put_byte(w, 220); put_byte(w, i + 1); }
    }
    for (i = seed->instances; i + 1 < seed->new_count; ++i) { put_byte(w, i); put_byte(w, 0); put_byte(w, 0); }
}

/* map seeds: kind, then its bytes */
#define IDENTITY {0, {0}, 0}
#define DIAGONAL(sx, sy, sz, tx, ty, tz) {1, {sx, sy, sz, tx, 0, ty, 0, tz, 0}, 9}
#define SIMILARITY(scale) {2, {scale, 120, 10, 112, 0, 100, 0, 130, 0, 112, 0, 90, 0, 112, 0}, 15}

int main(int argc, char **argv)
{
    /* shape byte: 1 round, 2 caps on, 16 culled (back faces off); basis; degenerate */
    static const scene_seed seeds[] = {
        /* one BVH under the identity and a diagonal */
        {1, {{0, 0, 0}}, 2, {0, 0}, {IDENTITY, DIAGONAL(8, 8, 8, 144, 112, 112)}, 0, 0, 0x0000, 0, 0},
        {1, {{1, 0, 0}}, 2, {0, 0}, {IDENTITY, DIAGONAL(8, 8, 8, 144, 112, 112)}, 0, 1, 0x5555, 0x1, 0},
        {1, {{1 | 2, 0, 0}}, 3, {96, 97, 98}, {IDENTITY, DIAGONAL(9, 7, 8, 80, 100, 112), DIAGONAL(144, 8, 8, 112, 150, 112)}, 97, 2, 0xaaaa, 0x24, 0},
        {1, {{1 | 2 | 16, 1, 0}}, 2, {0, 0}, {IDENTITY, SIMILARITY(0x81)}, 0, 1, 0x1b1b, 0x6, 0},
        {2, {{0, 2, 0}, {1 | 2, 3, 0}}, 4, {96, 97, 0, 98}, {IDENTITY, DIAGONAL(8, 8, 8, 150, 112, 112), DIAGONAL(6, 6, 10, 80, 80, 112), SIMILARITY(0x80)}, 96, 1, 0x0000, 0x1b, 0},
        {2, {{1, 4, 0}, {0, 0, SEED_ZERO_LENGTH}}, 3, {0, 0, 0}, {IDENTITY, DIAGONAL(8, 8, 8, 112, 150, 112), DIAGONAL(10, 10, 10, 80, 112, 112)}, 0, 0, 0x4444, 0, 0},
        {2, {{1 | 2, 0, SEED_CUSP}, {1 | 2, 1, SEED_ZERO_LENGTH}}, 2, {0, 0}, {IDENTITY, DIAGONAL(8, 8, 8, 150, 112, 112)}, 0, 2, 0x8888, 0x5, 0},
        {1, {{1 | 2, 0, SEED_ZERO_RADIUS}}, 2, {0, 0}, {IDENTITY, IDENTITY}, 0, 1, 0x0000, 0, 0},
        {1, {{1 | 2, 4, SEED_HUGE_RADIUS}}, 2, {0, 0}, {IDENTITY, DIAGONAL(8, 8, 8, 150, 112, 112)}, 0, 1, 0x0000, 0x2, 0},
        {2, {{0, 0, SEED_POISON}, {1, 0, 0}}, 2, {0, 0}, {IDENTITY, IDENTITY}, 0, 0, 0x0000, 0, 0},   /* a BVH without a build: refused */
        /* maps: raw, nearly singular, singular, poisoned, at the limits, huge, tiny */
        {1, {{1, 0, 0}}, 2, {0, 0}, {IDENTITY, {3, {128, 0, 112, 0, 120, 0, 112, 0, 112, 0, 128, 0, 112, 0, 112, 0, 112, 0, 112, 0, 128, 0, 112, 0}, 24}}, 0, 0, 0x0000, 0, 0},
        {1, {{1, 0, 0}}, 2, {0, 0}, {IDENTITY, {4, {128, 0, 120, 0, 20, 120, 10, 112, 0, 100, 0, 130, 0, 112, 0, 90, 0, 112, 0}, 19}}, 0, 0, 0x0000, 0, 0},
        {1, {{1, 0, 0}}, 2, {0, 0}, {IDENTITY, {4, {128, 0, 120, 0, 45, 120, 10, 112, 0, 100, 0, 130, 0, 112, 0, 90, 0, 112, 0}, 19}}, 0, 0, 0x0000, 0, 0},
        {1, {{0, 0, 0}}, 2, {0, 0}, {IDENTITY, {5, {8, 8, 8, 112, 0, 112, 0, 112, 0, 0}, 10}}, 0, 0, 0x0000, 0, 0},   /* a zero row: refused */
        {1, {{0, 0, 0}}, 2, {0, 0}, {IDENTITY, {5, {8, 8, 8, 112, 0, 112, 0, 112, 0, 24}, 10}}, 0, 0, 0x0000, 0, 0},  /* a column twice another */
        {1, {{1, 0, 0}}, 2, {0, 0}, {IDENTITY, {6, {8, 8, 8, 112, 0, 112, 0, 112, 0, 3}, 10}}, 0, 0, 0x0000, 0, 0},   /* NaN: refused */
        {1, {{1, 0, 0}}, 2, {0, 0}, {IDENTITY, {6, {8, 8, 8, 112, 0, 112, 0, 112, 0, 12 * 3 + 7}, 10}}, 0, 0, 0x0000, 0, 0},   /* 1e18 translation */
        {1, {{1, 0, 0}}, 2, {0, 0}, {IDENTITY, {6, {8, 8, 8, 112, 0, 112, 0, 112, 0, 12 * 5 + 3}, 10}}, 0, 0, 0x0000, 0, 0},   /* 2e18: refused */
        {1, {{1, 0, 0}}, 2, {0, 0}, {IDENTITY, {7, {12, 120, 10, 112, 0, 100, 0, 130, 0, 112, 0, 90, 0, 112, 0}, 15}}, 0, 0, 0x0000, 0, 0},   /* 1e12 */
        {1, {{0, 0, 0}}, 2, {0, 0}, {IDENTITY, {7, {128 + 15, 120, 10, 112, 0, 100, 0, 130, 0, 112, 0, 90, 0, 112, 0}, 15}}, 0, 0, 0x0000, 0, 0},   /* 1e-15 */
        /* masks and many instances */
        {4, {{0, 0, 0}, {1, 1, 0}, {1 | 2, 2, 0}, {1 | 16, 3, 0}}, 8, {96, 97, 98, 99, 0, 96, 97, 255},
         {IDENTITY, DIAGONAL(8, 8, 8, 144, 112, 112), DIAGONAL(8, 8, 8, 80, 112, 112), DIAGONAL(8, 8, 8, 112, 144, 112),
          DIAGONAL(8, 8, 8, 112, 80, 112), DIAGONAL(7, 7, 7, 144, 144, 112), DIAGONAL(9, 9, 9, 80, 80, 112), DIAGONAL(8, 7, 9, 112, 112, 80)}, 98, 1, 0x0000, 0xe4e4, 0},
        {3, {{1 | 2, 0, 0}, {0, 4, 0}, {1, 2, SEED_CUSP}}, 6, {96, 96, 97, 97, 98, 98},
         {IDENTITY, IDENTITY, DIAGONAL(8, 8, 8, 112, 112, 120), DIAGONAL(8, 8, 8, 112, 112, 120), DIAGONAL(144, 8, 8, 112, 112, 112), IDENTITY}, 97, 3, 0x0000, 0x0, 3},   /* 4 removed */
        {1, {{1 | 2, 0, 0}}, 0, {0}, {IDENTITY}, 0, 0, 0x0000, 0, 3},   /* no instance, then 2 */
        {1, {{1 | 2, 3, 0}}, 1, {0}, {IDENTITY}, 0, 1, 0xffff, 0x1, 4},   /* paths from the input; 2 added */
    };
    size_t k;
    if (argc != 2) { fprintf(stderr, "usage: %s DIRECTORY\n", argv[0]); return 2; }
    for (k = 0; k < sizeof seeds / sizeof seeds[0]; ++k) {
        writer w;
        char path[4096];
        FILE *file;
        write_seed(&w, &seeds[k]);
        snprintf(path, sizeof path, "%s/scene%zu", argv[1], k);
        file = fopen(path, "wb");
        if (!file || fwrite(w.bytes, 1, w.size, file) != w.size || fclose(file) != 0) {
            fprintf(stderr, "%s: cannot write\n", path);
            return 1;
        }
        LLVMFuzzerTestOneInput(w.bytes, w.size);
        printf("%s: %zu bytes\n", path, w.size);
    }
    return 0;
}
#endif
