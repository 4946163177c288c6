/* fuzz_build.c - libFuzzer target: arbitrary bytes become build options
   (the curve basis and the shape too), control points (any float, NaN and
   Inf included, and degenerate ones: fuzz_input.h), segment indices (any
   value, past the end included) and rays.
   hairobb_build must return the code of one of the documented errors the
   input has, or succeed where it has none; on success traced hits must be
   sane: t finite and in [tnear, tfar], u in [0,1], prim_id a segment,
   instance_id unset, group_id 0, Ng unit (fuzz_checks.h), occluded1 true
   wherever intersect1 hits, a miss names nothing; a static BVH gives the
   same hit at any ray time.
   The input's tail, read from its end: the last byte is the basis; 'M'
   'B' before it asks for motion; two flag bytes and 'T' 'U' before those
   ask for the newer layout (so the seeds written before each keep their
   meaning: old ones read as ribbons of separate segments): shape ribbon
   or round, end_caps and back_faces AUTO, ON or OFF, round curves' pieces
   precision kept (INVALID_ARGUMENT) or made exact, strands that share
   their end points, the SSE2 path forced, bezier_copy; and control points
   read by read_point, which makes repeated, collinear, cusped, zero- and
   huge-radius and poisoned points easy to reach.
   Motion blur ('M' 'B'): time_steps 0..5, time_vertices NULL or one step
   NULL, one float of one step poisoned (NaN, Inf, beyond 1e18, a negative
   radius; or 1e18 and -0, which are allowed), `vertices` NULL or not. Rays
   of a motion-blurred BVH get times (in [0, 1], knots, raw floats, NaN,
   outside): outside [0, 1] or NaN they miss. Then hairobb_refit_motion: a
   NULL step (INVALID_ARGUMENT), a poisoned step (INVALID_GEOMETRY, the
   rays then traced to the same bits as before), or the steps in reverse
   order.
   Bytes after all of that (none in the old seeds: every read then gives
   0) drive, for each ray: a path of 8 bounces with
   hairobb_intersect1_from from each hit (reflected about Ng, along Ng,
   against it, or a direction from the input; `hit` the same as `from` or
   not, which must agree), each hit sane and occluded1_from true where
   intersect1_from hits; and hairobb_intersect1_context /
   occluded1_context with a filter (fuzz_input.h) taking every hit, none,
   by a pattern over the segments or over its calls: the hit returned is
   one it took and sane, occluded where it took one, taking every hit
   gives intersect1's hit and occluded1's answer, a pattern over the
   segments gives intersect1's hit where it takes that segment (away from
   the joints, where a crossing ignored is not shown again). Then a save
   and load round trip (other bezier_copy, verify_hair and SIMD path: the
   same bits; one byte short: INVALID_FILE), and a refit to points the
   input moves or replaces (maybe degenerate; Hermite with new tangents):
   refused with INVALID_GEOMETRY exactly where a point is bad, the BVH then
   tracing as before, else tracing as a fresh build on those points does,
   to the bit (exact precision; hair and rays of moderate size,
   moderate_hair; hits on hair thinner than rounding aside,
   rounding_decided). Build with clang
   -fsanitize=fuzzer,address,undefined (see `make fuzz`); leaks are
   LeakSanitizer's to find. Seeds: tests/fuzz/corpus/bvh_build (the
   motion and tube ones written by this file built with
   -DFUZZ_BUILD_WRITE_SEEDS). */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#define HAIROBB_IMPLEMENTATION
#include "../../hairobb.h"
#include "fuzz_checks.h"
#include "fuzz_input.h"

#define MAX_STEPS 5

/* The motion input: time_steps arrays (copies of the vertices, moved), one
   float of one step replaced, what the build is handed. */
typedef struct motion_input {
    int on;                   /* the input asked for motion options */
    unsigned time_steps;      /* 0..5 */
    float *steps[MAX_STEPS];
    const float *handed[MAX_STEPS];
    int steps_null, null_step;   /* time_vertices NULL; a step handed as NULL (>= time_steps: none) */
    int vertices_null;
} motion_input;

/* Values a poisoned float takes: the first five make the input invalid
   (-0.001 is put in a radius), the rest are allowed. */
static float poison_value(unsigned kind)
{
    switch (kind % 9) {
    case 0: return NAN;
    case 1: return INFINITY;
    case 2: return -INFINITY;
    case 3: return -2e18f;
    case 4: return -0.001f;
    case 5: return 1e18f;
    case 6: return -0.0f;
    case 7: return 1e-40f;
    default: return 3.0f;
    }
}

/* Steps k = 1.. move the vertices by k times a displacement scaled per
   control point (so segments bend as they move) and scale the radii. */
static int read_motion(reader *r, motion_input *m, const float *vertices, size_t vertex_count)
{
    unsigned k, poison_step, poison_kind;
    size_t poison_at, i;
    m->time_steps = read_byte(r) % (MAX_STEPS + 1);
    k = read_byte(r);
    m->steps_null = k == 255;
    m->null_step = (int)(k % 8);
    m->vertices_null = read_byte(r) & 1;
    poison_step = read_byte(r) % 8;
    poison_at = read_byte(r);
    poison_at |= (size_t)read_byte(r) << 8;
    poison_kind = read_byte(r);
    for (k = 0; k < m->time_steps; ++k) {
        float move[3], radius_scale = (float)read_byte(r) / 128.0f;
        int a;
        for (a = 0; a < 3; ++a) move[a] = read_coordinate(r);
        m->steps[k] = (float *)malloc(sizeof(float) * 4 * (vertex_count + 1));
        if (!m->steps[k]) return 1;
        for (i = 0; i < vertex_count; ++i) {
            float weight = (float)k * (float)(1 + i % 3) / 3.0f;
            for (a = 0; a < 3; ++a) m->steps[k][4 * i + a] = vertices[4 * i + a] + (k ? weight * move[a] : 0.0f);
            m->steps[k][4 * i + 3] = k ? vertices[4 * i + 3] * radius_scale : vertices[4 * i + 3];
        }
        if (poison_step == k && vertex_count) {
            size_t at = poison_at % (4 * vertex_count);
            if (poison_kind % 9 == 4) at |= 3;   /* a negative radius */
            m->steps[k][at] = poison_value(poison_kind);
        }
        m->handed[k] = (int)k == m->null_step ? NULL : m->steps[k];
    }
    return 0;
}

static void free_motion(motion_input *m)
{
    unsigned k;
    for (k = 0; k < MAX_STEPS; ++k) free(m->steps[k]);
}

/* Whether the result is one the documented errors of the input allow:
   each error it has may be the one reported (INVALID_ARGUMENT: no
   segments, round curves with the pieces precision, and for motion
   time_vertices or a step NULL, or Hermite (its tangents do not move);
   INDEX_OUT_OF_RANGE: an index past the vertices; INVALID_GEOMETRY: a bad
   control point, at any step, or a bad Hermite tangent; UNSUPPORTED: a
   SIMD path named); with none, the build succeeds (or runs out of
   memory). A static build without vertices is checked apart. */
static int build_result_allowed(hairobb_result result, const motion_input *m, const hairobb_build_options *options,
                                const float *vertices, size_t vertex_count, const uint32_t *indices, size_t segments)
{
    int moving = m->on && m->time_steps >= 2;
    int argument = segments == 0 || (options->shape == HAIROBB_SHAPE_ROUND && options->precision == HAIROBB_PRECISION_PIECES) ||
                   (moving && (m->steps_null || m->null_step < (int)m->time_steps || options->basis == HAIROBB_BASIS_HERMITE));
    unsigned points = options->basis == HAIROBB_BASIS_LINEAR || options->basis == HAIROBB_BASIS_HERMITE ? 2u : 4u;
    unsigned steps = moving ? m->time_steps : 1u, k, j;
    int index = 0, geometry = 0;
    size_t i;
    for (i = 0; i < segments; ++i) {
        if ((size_t)indices[i] + points > vertex_count) { index = 1; continue; }
        for (k = 0; k < steps; ++k) {
            const float *v = moving ? m->steps[k] : vertices;
            for (j = 0; j < points; ++j) {
                geometry |= bad_point(v + 4 * ((size_t)indices[i] + j));
                if (!moving && options->tangents) geometry |= bad_tangent(options->tangents + 4 * ((size_t)indices[i] + j));
            }
        }
    }
    if (result == HAIROBB_ERROR_INVALID_ARGUMENT) return argument;
    if (result == HAIROBB_ERROR_INDEX_OUT_OF_RANGE) return index;
    if (result == HAIROBB_ERROR_INVALID_GEOMETRY) return geometry;
    if (result == HAIROBB_ERROR_UNSUPPORTED) return options->simd != HAIROBB_SIMD_AUTO;
    if (result == HAIROBB_OK || result == HAIROBB_ERROR_OUT_OF_MEMORY) return !argument && !index && !geometry;
    return 0;
}

/* A ray time from the input: mostly in [0, 1] (0 and 1 included), knots
   k / (T - 1), raw bit patterns, and values just outside, NaN, -0. */
static float read_time(reader *r, unsigned time_steps)
{
    static const float special[8] = {-0.0f, NAN, -1e-30f, 1.0000001f, -1.0f, 2.0f, INFINITY, -INFINITY};
    unsigned kind = read_byte(r);
    if (kind < 192) return (float)kind / 191.0f;
    if (kind < 208) return (float)((kind - 192) % time_steps) / (float)(time_steps - 1);
    if (kind < 232) return read_float(r);
    return special[kind % 8];
}

/* A ray of a motion-blurred BVH: outside [0, 1] or NaN a miss, else sane. */
static void check_motion_ray(const hairobb_bvh *bvh, const hairobb_ray *ray, size_t segments)
{
    hairobb_hit hit;
    if (ray->time >= 0.0f && ray->time <= 1.0f) {
        fuzz_check_ray(bvh, ray, segments);
        return;
    }
    if (hairobb_intersect1(bvh, ray, &hit)) fuzz_fail("a ray at a time outside [0, 1] hit");
    fuzz_check_miss(&hit);
    if (hairobb_occluded1(bvh, ray)) fuzz_fail("a ray at a time outside [0, 1] is occluded");
}

/* Refit of a motion-blurred BVH with the input's steps: one of them NULL,
   one poisoned (either fails and leaves the BVH tracing as before), or
   all in reverse order. */
static void check_refit_motion(hairobb_bvh *bvh, motion_input *m, const float *vertices, const uint32_t *indices,
                               const hairobb_ray *rays, unsigned ray_count, size_t segments, unsigned mode)
{
    const float *steps[MAX_STEPS];
    hairobb_hit before[32], after;
    unsigned k, T = m->time_steps;
    float saved = 0.0f;
    hairobb_result result;
    for (k = 0; k < ray_count; ++k) hairobb_intersect1(bvh, &rays[k], &before[k]);
    if (hairobb_refit(bvh, vertices) != HAIROBB_ERROR_INVALID_ARGUMENT) fuzz_fail("hairobb_refit of a motion-blurred BVH");
    for (k = 0; k < T; ++k) steps[k] = m->steps[mode % 3 == 2 ? T - 1 - k : k];
    if (mode % 3 == 0) {
        steps[mode / 3 % T] = NULL;
        if (hairobb_refit_motion(bvh, steps) != HAIROBB_ERROR_INVALID_ARGUMENT) fuzz_fail("refit with a NULL step");
    } else if (mode % 3 == 1) {
        /* the radius of the first segment's first point, at one step */
        float *poisoned = m->steps[mode / 3 % T] + 4 * (size_t)indices[0] + 3;
        saved = *poisoned;
        *poisoned = -1.0f;
        result = hairobb_refit_motion(bvh, steps);
        *poisoned = saved;
        if (result != HAIROBB_ERROR_INVALID_GEOMETRY) fuzz_fail("refit with a negative radius");
    } else {
        if (hairobb_refit_motion(bvh, steps) != HAIROBB_OK) fuzz_fail("refit to valid steps");
        for (k = 0; k < ray_count; ++k) check_motion_ray(bvh, &rays[k], segments);
        return;
    }
    for (k = 0; k < ray_count; ++k) {
        hairobb_intersect1(bvh, &rays[k], &after);
        if (!same_hit(&before[k], &after)) fuzz_fail("a failed refit changed a hit");
    }
}

#define PATH_BOUNCES 8

/* A path of PATH_BOUNCES secondary rays from the hit `first_hit` of ray
   `first`: each starts at the hit point (tnear 0) in a direction the path
   bits pick (2 a bounce: bounce_direction), tfar infinite or from the
   input; each hit sane and occluded1_from true where intersect1_from
   hits; `hit` passed as `from` too where the flags say (a path tracer's
   loop), which must give the same hit. The directions from the input are
   read before any is traced, so the bytes a path takes do not depend on
   its hits. */
static void trace_path(const hairobb_bvh *bvh, const hairobb_ray *first, const hairobb_hit *first_hit, size_t segments,
                       reader *r)
{
    unsigned path = read_byte(r), flags, bounce;
    float given[PATH_BOUNCES][3], tfar;
    hairobb_ray ray = *first;
    hairobb_hit from, hit;
    int j;
    path |= read_byte(r) << 8;
    flags = read_byte(r);
    for (bounce = 0; bounce < PATH_BOUNCES; ++bounce)
        if ((path >> (2 * bounce) & 3) == 3)
            for (j = 0; j < 3; ++j) given[bounce][j] = read_coordinate(r);
    tfar = flags & 1 ? read_coordinate(r) : INFINITY;
    if (!first_hit) return;
    from = *first_hit;
    for (bounce = 0; bounce < PATH_BOUNCES; ++bounce) {
        hairobb_ray next;
        unsigned kind = path >> (2 * bounce) & 3;
        int got, occluded;
        for (j = 0; j < 3; ++j) next.org[j] = ray.org[j] + from.t * ray.dir[j];
        if (kind == 3) memcpy(next.dir, given[bounce], sizeof next.dir);
        else bounce_direction(r, kind, ray.dir, &from, next.dir);
        next.tnear = 0.0f;
        next.tfar = tfar;
        next.time = ray.time;
        got = hairobb_intersect1_from(bvh, &from, &next, &hit);
        occluded = hairobb_occluded1_from(bvh, &from, &next);
        if (flags & 2) {
            /* `hit` and `from` one hit */
            hairobb_hit same = from;
            if (hairobb_intersect1_from(bvh, &same, &next, &same) != got || !same_hit(&same, &hit))
                fuzz_fail("intersect1_from with hit == from differs");
        }
        if (!got) {
            fuzz_check_miss(&hit);
            return;
        }
        fuzz_check_hit(&next, &hit, segments, HAIROBB_INVALID_ID);
        if (!occluded) fuzz_fail("intersect1_from hits where occluded1_from does not");
        from = hit;
        ray = next;
    }
}

/* intersect1_context / occluded1_context with the input's filter (and a
   mask: hairobb_build's one group has every bit), against intersect1_from /
   occluded1_from: the ray from no hit, or its first bounce (reflected)
   from its hit. */
static void check_filters(const hairobb_bvh *bvh, const hairobb_ray *primary, const hairobb_hit *primary_hit, size_t segments,
                          reader *r)
{
    fuzz_filter f;
    hairobb_context context;
    hairobb_ray ray = *primary;
    hairobb_hit plain, hit;
    const hairobb_hit *from = NULL;
    unsigned choice = read_byte(r);
    int got_plain, occluded_plain, got, occluded, j;
    memset(&f, 0, sizeof f);
    f.mode = choice % FILTER_MODES;
    f.pattern = read_u32(r);
    context.filter = fuzz_filter_fn;
    context.user = &f;
    context.mask = choice & 4 ? 0u : 1u << (choice >> 3);
    if ((choice & 128) && primary_hit) {
        from = primary_hit;
        for (j = 0; j < 3; ++j) ray.org[j] = primary->org[j] + primary_hit->t * primary->dir[j];
        bounce_direction(r, 0, primary->dir, primary_hit, ray.dir);
        ray.tnear = 0.0f;
    }
    got_plain = hairobb_intersect1_from(bvh, from, &ray, &plain);
    occluded_plain = hairobb_occluded1_from(bvh, from, &ray);
    got = hairobb_intersect1_context(bvh, &context, from, &ray, &hit);
    if (got) {
        fuzz_check_hit(&ray, &hit, segments, HAIROBB_INVALID_ID);
        if (!fuzz_filter_took(&f, &hit)) fuzz_fail("intersect1_context returned a hit its filter did not take");
    } else {
        fuzz_check_miss(&hit);
    }
    if (f.taken && !got) fuzz_fail("intersect1_context missed where its filter took a hit");
    if (f.mode == FILTER_ALL && (got != got_plain || !same_hit(&hit, &plain)))
        fuzz_fail("a filter taking every hit changed intersect1's hit");
    if (f.mode == FILTER_NONE && got) fuzz_fail("a filter taking no hit, and a hit");
    if (f.mode == FILTER_BY_PRIM && got_plain && (f.pattern >> (plain.prim_id % 32) & 1u) && plain.u > 1.0f / 1024.0f &&
        plain.u < 1.0f - 1.0f / 1024.0f && !same_hit(&hit, &plain))
        fuzz_fail("a filter taking the nearest hit's segment changed intersect1's hit");
    fuzz_filter_reset(&f);
    occluded = hairobb_occluded1_context(bvh, &context, from, &ray);
    if (occluded != (f.taken > 0)) fuzz_fail("occluded1_context's answer is not whether its filter took a hit");
    if (f.mode == FILTER_ALL && occluded != occluded_plain) fuzz_fail("a filter taking every hit changed occluded1's answer");
    if (f.mode == FILTER_BY_PRIM && got && hit.u > 1.0f / 1024.0f && hit.u < 1.0f - 1.0f / 1024.0f && !occluded)
        fuzz_fail("occluded1_context misses a hit intersect1_context's filter (by segment) took");
}

/* Saved, then loaded over the same hair with the input's bezier_copy,
   verify_hair and SIMD path (the other of the build's and SSE2): every
   ray traced to the same bits; one byte short, INVALID_FILE. */
static void check_save_load(const hairobb_bvh *bvh, const hairobb_build_options *options, const float *vertices,
                            size_t vertex_count, const uint32_t *indices, size_t segments, const hairobb_ray *rays,
                            unsigned ray_count, reader *r)
{
    static const hairobb_switch switches[3] = {HAIROBB_AUTO, HAIROBB_ON, HAIROBB_OFF};
    hairobb_build_options load_options = *options;
    hairobb_bvh *loaded = NULL;
    unsigned choice = read_byte(r), k;
    size_t size = hairobb_save_size(bvh);
    unsigned char *bytes;
    hairobb_result result;
    if (size == 0) fuzz_fail("a BVH with no saved size");
    bytes = (unsigned char *)malloc(size);
    if (!bytes) return;
    if (hairobb_save(bvh, bytes, size - 1) != HAIROBB_ERROR_INVALID_ARGUMENT) fuzz_fail("hairobb_save into too small a buffer");
    if (hairobb_save(bvh, bytes, size) != HAIROBB_OK) fuzz_fail("hairobb_save");
    load_options.verify_hair = switches[choice % 3];
    load_options.bezier_copy = switches[choice / 3 % 3];
    if (choice / 9 % 2) load_options.simd = options->simd == HAIROBB_SIMD_AUTO ? HAIROBB_SIMD_SSE2 : HAIROBB_SIMD_AUTO;
    result = hairobb_load(bytes, size - 1, vertices, vertex_count, indices, segments, &load_options, &loaded);
    if (result != HAIROBB_ERROR_INVALID_FILE || loaded) fuzz_fail("a saved BVH one byte short loaded");
    result = hairobb_load(bytes, size, vertices, vertex_count, indices, segments, &load_options, &loaded);
    free(bytes);   /* nothing of the bytes is kept */
    if (result == HAIROBB_ERROR_UNSUPPORTED && load_options.simd != HAIROBB_SIMD_AUTO) return;   /* SSE2 is not this build's path */
    if (result == HAIROBB_ERROR_OUT_OF_MEMORY) return;
    if (result != HAIROBB_OK || !loaded) fuzz_fail("a saved BVH did not load over its own hair");
    for (k = 0; k < ray_count; ++k) {
        hairobb_hit a, b;
        int got_a = hairobb_intersect1(bvh, &rays[k], &a), got_b = hairobb_intersect1(loaded, &rays[k], &b);
        if (got_a != got_b || !same_hit(&a, &b) || hairobb_occluded1(bvh, &rays[k]) != hairobb_occluded1(loaded, &rays[k]))
            fuzz_fail("a loaded BVH traces other bits than the saved one");
    }
    hairobb_free(loaded);
}

/* hairobb_refit (hairobb_refit_tangents for Hermite, the tangents the
   new points' differences) to points from the input: each kept, moved a
   little (and its radius scaled) or replaced by read_point. A bad point
   (or tangent) any segment reads: INVALID_GEOMETRY, the BVH tracing as
   before; else the rays trace as through a fresh build on the new
   points, to the bit (exact precision: the nearest hit does not depend
   on the tree), where hair and ray are of moderate size (moderate_hair)
   and neither hit is on hair thinner than rounding (rounding_decided).
   The wrong refit call for the basis: INVALID_ARGUMENT. Frees the BVH
   (it keeps the new points' pointer). */
static void check_refit_and_free(hairobb_bvh *bvh, const hairobb_build_options *options, const float *vertices,
                                 size_t vertex_count, const uint32_t *indices, size_t segments, const hairobb_ray *rays,
                                 unsigned ray_count, reader *r)
{
    hairobb_build_options fresh_options = *options;
    hairobb_bvh *fresh = NULL;
    hairobb_hit before[32];
    int got_before[32], occluded_before[32], hermite = options->basis == HAIROBB_BASIS_HERMITE, bad = 0, compare;
    unsigned points = options->basis == HAIROBB_BASIS_LINEAR || hermite ? 2u : 4u, k, j;
    float *moved = (float *)malloc(sizeof(float) * 4 * (vertex_count + 1)), *tangents = NULL;
    hairobb_result result;
    size_t i;
    if (!moved || (hermite && !(tangents = (float *)malloc(sizeof(float) * 4 * (vertex_count + 1))))) goto done;
    for (i = 0; i < vertex_count; ++i) {
        unsigned how = read_byte(r);
        if (how < 128) {
            memcpy(moved + 4 * i, vertices + 4 * i, 4 * sizeof(float));
        } else if (how < 192) {
            for (j = 0; j < 3; ++j) moved[4 * i + j] = vertices[4 * i + j] + ((float)read_byte(r) - 128.0f) / 256.0f;
            moved[4 * i + 3] = vertices[4 * i + 3] * (float)read_byte(r) / 128.0f;
        } else {
            read_point(r, moved, i);
        }
    }
    if (hermite) difference_tangents(moved, vertex_count, tangents);
    for (i = 0; i < segments; ++i)
        for (j = 0; j < points; ++j) {
            bad |= bad_point(moved + 4 * ((size_t)indices[i] + j));
            if (hermite) bad |= bad_tangent(tangents + 4 * ((size_t)indices[i] + j));
        }
    for (k = 0; k < ray_count; ++k) {
        got_before[k] = hairobb_intersect1(bvh, &rays[k], &before[k]);
        occluded_before[k] = hairobb_occluded1(bvh, &rays[k]);
    }
    if ((hermite ? hairobb_refit(bvh, moved) : hairobb_refit_tangents(bvh, moved, moved)) != HAIROBB_ERROR_INVALID_ARGUMENT)
        fuzz_fail("a refit with tangents for the wrong basis");
    result = hermite ? hairobb_refit_tangents(bvh, moved, tangents) : hairobb_refit(bvh, moved);
    if (result != (bad ? HAIROBB_ERROR_INVALID_GEOMETRY : HAIROBB_OK)) fuzz_fail("a refit's result is not its input's");
    if (bad) {
        for (k = 0; k < ray_count; ++k) {
            hairobb_hit after;
            if (hairobb_intersect1(bvh, &rays[k], &after) != got_before[k] || !same_hit(&before[k], &after) ||
                hairobb_occluded1(bvh, &rays[k]) != occluded_before[k])
                fuzz_fail("a refused refit changed a hit");
        }
        goto done;
    }
    fresh_options.tangents = tangents;
    result = hairobb_build(moved, vertex_count, indices, segments, &fresh_options, &fresh);
    if (result == HAIROBB_ERROR_OUT_OF_MEMORY) goto done;
    if (result != HAIROBB_OK) fuzz_fail("a fresh build refused the points a refit took");
    compare = options->precision == HAIROBB_PRECISION_EXACT && moderate_hair(moved, indices, segments, points) &&
              (!hermite || moderate_hair(tangents, indices, segments, points));
    for (k = 0; k < ray_count; ++k) {
        hairobb_hit a, b;
        int got_a, got_b;
        fuzz_check_ray(bvh, &rays[k], segments);
        if (!compare || !moderate_ray(&rays[k])) continue;
        got_a = hairobb_intersect1(bvh, &rays[k], &a);
        got_b = hairobb_intersect1(fresh, &rays[k], &b);
        if ((got_a != got_b || !same_hit(&a, &b) || hairobb_occluded1(bvh, &rays[k]) != hairobb_occluded1(fresh, &rays[k])) &&
            !(got_a && rounding_decided(bvh, &rays[k], &a)) && !(got_b && rounding_decided(fresh, &rays[k], &b)))
            fuzz_fail("a refitted BVH traces other bits than a fresh build");
    }
done:
    hairobb_free(fresh);
    hairobb_free(bvh);
    free(moved);
    free(tangents);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* a switch from 2 bits: AUTO, ON, OFF, and the setting that differs from the default again */
    static const hairobb_switch then_on[4] = {HAIROBB_AUTO, HAIROBB_ON, HAIROBB_OFF, HAIROBB_ON};
    static const hairobb_switch then_off[4] = {HAIROBB_AUTO, HAIROBB_ON, HAIROBB_OFF, HAIROBB_OFF};
    reader r;
    hairobb_build_options options;
    hairobb_bvh *bvh = NULL;
    hairobb_result result;
    size_t segments, vertex_count, i, end;
    float *vertices, *tangents = NULL;
    uint32_t *indices;
    unsigned rays, k, flags = 0, flags2 = 0;
    int newer, chained = 0;
    motion_input motion;

    /* the tail: basis, then 'M' 'B', then flags, flags2, 'T' 'U' (each optional) */
    memset(&motion, 0, sizeof motion);
    motion.on = size >= 3 && data[size - 3] == 'M' && data[size - 2] == 'B';
    end = motion.on ? size - 3 : size ? size - 1 : 0;
    newer = end >= 4 && data[end - 2] == 'T' && data[end - 1] == 'U';
    if (newer) {
        flags = data[end - 4];
        flags2 = data[end - 3];
        end -= 4;
    }
    /* the old seeds' stream: all but the motion tail (the basis byte too) */
    r.data = data; r.size = motion.on || newer ? end : size; r.at = 0;
    memset(&options, 0, sizeof options);
    options.nodes = (hairobb_node_policy)(read_byte(&r) % 3);
    options.obb_layout = (hairobb_obb_layout)(read_byte(&r) % 5);
    options.spatial_splits = (hairobb_switch)(read_byte(&r) % 3);
    options.clustering = (hairobb_switch)(read_byte(&r) % 3);
    options.max_leaf_size = read_byte(&r) % 16;
    options.precision = (hairobb_precision)(read_byte(&r) % 2);
    options.curve_pieces = read_byte(&r) % 17;
    options.threads = 1u + read_byte(&r) % 2;
    if (newer) {
        options.shape = flags & 1 ? HAIROBB_SHAPE_ROUND : HAIROBB_SHAPE_RIBBON;
        options.end_caps = then_on[flags >> 1 & 3];
        options.back_faces = then_off[flags >> 3 & 3];
        /* round curves are exact only: the pieces precision kept where the flag asks (INVALID_ARGUMENT) */
        if (options.shape == HAIROBB_SHAPE_ROUND && !(flags & 32)) options.precision = HAIROBB_PRECISION_EXACT;
        chained = flags >> 6 & 1;
        options.simd = flags & 128 ? HAIROBB_SIMD_SSE2 : HAIROBB_SIMD_AUTO;
        options.bezier_copy = then_off[flags2 & 3];
    }
    segments = read_byte(&r) % 48;
    vertex_count = 4 * segments + read_byte(&r) % 4;
    vertices = (float *)malloc(sizeof(float) * 4 * (vertex_count + 1));
    indices = (uint32_t *)malloc(sizeof(uint32_t) * (segments + 1));
    if (!vertices || !indices) { free(vertices); free(indices); return 0; }
    if (newer) {
        for (i = 0; i < vertex_count; ++i) read_point(&r, vertices, i);
    } else {
        for (i = 0; i < 4 * vertex_count; ++i) {
            float v = read_coordinate(&r);
            vertices[i] = (i % 4 == 3) ? (v < 0.0f && read_byte(&r) < 240 ? -v : v) * 0.05f : v;   /* radii: mostly >= 0 */
        }
    }
    /* the curve basis from the last byte (the stream's order stays as the
       seeds were written); Hermite tangents: differences of the vertices */
    options.basis = (hairobb_basis)(size > 0 ? data[size - 1] % 5 : 0);
    read_indices(&r, indices, segments, vertex_count, chained, options.basis);
    if (options.basis == HAIROBB_BASIS_HERMITE) {
        tangents = (float *)malloc(sizeof(float) * 4 * (vertex_count + 1));
        if (!tangents) { free(vertices); free(indices); return 0; }
        difference_tangents(vertices, vertex_count, tangents);
        options.tangents = tangents;
    }

    if (motion.on) {
        if (read_motion(&r, &motion, vertices, vertex_count) != 0) {
            free_motion(&motion); free(vertices); free(tangents); free(indices);
            return 0;
        }
        options.time_steps = motion.time_steps;
        options.time_vertices = motion.steps_null ? NULL : motion.handed;
    }
    result = hairobb_build(motion.on && motion.vertices_null ? NULL : vertices, vertex_count, indices, segments, &options, &bvh);
    if ((unsigned)result > HAIROBB_ERROR_MISMATCH) fuzz_fail("unknown result code");
    if (!strcmp(hairobb_result_string(result), "unknown hairobb_result")) fuzz_fail("result without a message");
    if (motion.on && motion.time_steps < 2 && motion.vertices_null) {
        if (result != HAIROBB_ERROR_INVALID_ARGUMENT) fuzz_fail("a static build without vertices");
    } else if (!build_result_allowed(result, &motion, &options, vertices, vertex_count, indices, segments)) {
        fuzz_fail("a build's result is not one its input's errors allow");
    }
    if ((hairobb_check_options(&options) != NULL) !=
        ((options.shape == HAIROBB_SHAPE_ROUND && options.precision == HAIROBB_PRECISION_PIECES) ||
         (motion.on && motion.time_steps >= 2 &&
          (motion.steps_null || motion.null_step < (int)motion.time_steps || options.basis == HAIROBB_BASIS_HERMITE))))
        fuzz_fail("hairobb_check_options disagrees with the options' errors");
    if (result != HAIROBB_OK) {
        if (bvh) fuzz_fail("a failed build returned a BVH");
    } else {
        hairobb_ray ray_list[32];
        hairobb_hit hits[32];
        int moving = motion.on && motion.time_steps >= 2, got[32];
        unsigned refit_mode = 0;
        if (!bvh) fuzz_fail("a successful build returned no BVH");
        fuzz_round = options.shape == HAIROBB_SHAPE_ROUND;
        if (moving) fuzz_check_rays_through_bounds(bvh, segments, 0.5f);
        else fuzz_check_rays_through_bounds(bvh, segments, 0.0f);
        rays = 1 + read_byte(&r) % 32;
        for (k = 0; k < rays; ++k) {
            hairobb_ray *ray = &ray_list[k];
            int j;
            for (j = 0; j < 3; ++j) ray->org[j] = read_coordinate(&r);
            for (j = 0; j < 3; ++j) ray->dir[j] = read_coordinate(&r);
            ray->tnear = read_byte(&r) < 200 ? 0.0f : read_coordinate(&r);
            ray->tfar = read_byte(&r) < 200 ? INFINITY : read_coordinate(&r);
            ray->time = moving ? read_time(&r, motion.time_steps) : 0.0f;
            if (moving) {
                check_motion_ray(bvh, ray, segments);
            } else {
                /* static BVHs ignore the time */
                hairobb_ray at_nan = *ray;
                hairobb_hit a, b;
                fuzz_check_ray(bvh, ray, segments);
                at_nan.time = NAN;
                if (hairobb_intersect1(bvh, ray, &a) != hairobb_intersect1(bvh, &at_nan, &b) || !same_hit(&a, &b) ||
                    hairobb_occluded1(bvh, ray) != hairobb_occluded1(bvh, &at_nan))
                    fuzz_fail("a static BVH's hit depends on the ray's time");
            }
        }
        if (moving) refit_mode = read_byte(&r);
        /* the rest of the input: paths, filters, save and load, refit */
        for (k = 0; k < rays; ++k) {
            got[k] = hairobb_intersect1(bvh, &ray_list[k], &hits[k]);
            trace_path(bvh, &ray_list[k], got[k] ? &hits[k] : NULL, segments, &r);
            check_filters(bvh, &ray_list[k], got[k] ? &hits[k] : NULL, segments, &r);
        }
        check_save_load(bvh, &options, motion.on && motion.vertices_null ? NULL : vertices, vertex_count, indices, segments,
                        ray_list, rays, &r);
        if (moving) {
            check_refit_motion(bvh, &motion, vertices, indices, ray_list, rays, segments, refit_mode);
            hairobb_free(bvh);
        } else {
            check_refit_and_free(bvh, &options, vertices, vertex_count, indices, segments, ray_list, rays, &r);
        }
    }
    free_motion(&motion);
    free(vertices);
    free(tangents);
    free(indices);
    return 0;
}

#ifdef FUZZ_BUILD_WRITE_SEEDS
/* Motion seeds: three strands of four Bezier segments along x, moving in y
   and z, and rays up the z axis across them at many times; each seed names
   the motion input's choices (the stream as LLVMFuzzerTestOneInput reads it).
   Tube seeds (the newer layout): three strands of four segments sharing
   their end points, in each basis, ribbons and tubes with caps and
   culling, one kind of degenerate point each; rays across them, along
   them into the tips' caps and from inside them; the tail's paths,
   filters, load options and refit. */
#include <stdio.h>

typedef struct writer {
    uint8_t bytes[4096];
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

typedef struct motion_seed {
    unsigned nodes, layout, spatial, leaf;
    unsigned time_steps, null_choice, vertices_null, poison_step, poison_kind, refit_mode, basis;
} motion_seed;

static void write_seed(writer *w, const motion_seed *seed)
{
    const unsigned segments = 12, rays = 24;
    unsigned i, j, k;
    w->size = 0;
    put_byte(w, seed->nodes); put_byte(w, seed->layout); put_byte(w, seed->spatial); put_byte(w, 0);
    put_byte(w, seed->leaf); put_byte(w, 0); put_byte(w, 0); put_byte(w, 0);
    put_byte(w, segments); put_byte(w, 0);
    for (i = 0; i < segments; ++i)          /* strand i / 4, its segment i % 4 */
        for (j = 0; j < 4; ++j) {
            float x = -1.0f + 0.5f * (float)(i % 4) + (float)j / 6.0f;
            put_coordinate(w, x);
            put_coordinate(w, -0.5f + 0.5f * (float)(i / 4) + 0.03f * x * x);
            put_coordinate(w, 0.1f * x);
            put_coordinate(w, 1.2f - 0.1f * (float)j);   /* radius 0.06 - 0.005 j */
        }
    for (i = 0; i < segments; ++i) put_byte(w, 0);
    put_byte(w, seed->time_steps);
    put_byte(w, seed->null_choice);
    put_byte(w, seed->vertices_null);
    put_byte(w, seed->poison_step);
    put_byte(w, 37); put_byte(w, 0);        /* the float poisoned: 37 (point 9's y) */
    put_byte(w, seed->poison_kind);
    for (k = 0; k < seed->time_steps; ++k) {
        put_byte(w, 128 - 8 * k);          /* radii shrink a little */
        put_coordinate(w, 0.05f);
        put_coordinate(w, 0.04f);
        put_coordinate(w, -0.1f);
    }
    put_byte(w, rays - 1);
    for (i = 0; i < rays; ++i) {
        put_coordinate(w, -1.2f + 0.11f * (float)i);
        put_coordinate(w, -0.5f + 0.5f * (float)(i % 3) + 0.01f * (float)(i % 5));
        put_coordinate(w, -3.0f);
        put_coordinate(w, 0.0f); put_coordinate(w, 0.0f); put_coordinate(w, 1.0f);
        put_byte(w, i % 7 == 6 ? 200 : 0);
        if (i % 7 == 6) put_coordinate(w, 1.0f);
        put_byte(w, 0);
        put_byte(w, (unsigned[]){0, 191, 95, 192, 193, 194, 210, 232, 233, 236, 40, 150}[i % 12]);
        if (i % 12 == 6) { put_byte(w, 0); put_byte(w, 0); put_byte(w, 0); put_byte(w, 0x3f); }   /* raw 0.5 */
    }
    put_byte(w, seed->refit_mode);
    put_byte(w, 'M'); put_byte(w, 'B'); put_byte(w, seed->basis);
}

/* The tube seeds: the flags of the tail, the basis, a degenerate point,
   the filter's choice byte, the paths' two bits a bounce, the load's
   choice, the refit (0 kept, 1 moved, 2 a point replaced, 3 poisoned). */
enum { D_NONE, D_ZERO_LENGTH, D_REPEAT, D_SAME_AS_0, D_COLLINEAR, D_CUSP, D_ZERO_RADIUS, D_HUGE_RADIUS, D_POISON, D_KINDS };
typedef struct tube_seed {
    unsigned flags, flags2, basis, degenerate, filter, path, load, refit;
} tube_seed;

/* a fresh control point (read_point's op 0) */
static void put_point(writer *w, float x, float y, float z, float radius)
{
    put_byte(w, 0);
    put_coordinate(w, x); put_coordinate(w, y); put_coordinate(w, z);
    put_coordinate(w, radius / 0.05f);
}

static void write_tube_seed(writer *w, const tube_seed *seed)
{
    const unsigned segments = 12, rays = 24, vertex_count = 4 * 12;
    /* chained strands as read_indices lays them out: 13 points apart (Bezier), 7 (the others) */
    unsigned stride = seed->basis == HAIROBB_BASIS_BEZIER ? 13 : 7, used = seed->basis == HAIROBB_BASIS_BEZIER ? 13
                      : seed->basis == HAIROBB_BASIS_LINEAR || seed->basis == HAIROBB_BASIS_HERMITE ? 5 : 7;
    unsigned i, k;
    w->size = 0;
    put_byte(w, 0); put_byte(w, seed->flags & 1 ? 4 : 0); put_byte(w, 0); put_byte(w, 0);
    put_byte(w, 0); put_byte(w, seed->flags & 32 ? 1 : 0); put_byte(w, 0); put_byte(w, 0);   /* pieces where kept */
    put_byte(w, segments); put_byte(w, 0);
    for (k = 0; k < vertex_count; ++k) {
        unsigned s = k / stride, j = k % stride;
        float x = -1.0f + 2.0f * (float)j / (float)(used - 1);
        if (k == 1 && seed->degenerate == D_REPEAT) { put_byte(w, 128); continue; }
        if (k >= 4 && k <= 6 && seed->degenerate == D_ZERO_LENGTH) { put_byte(w, 128); continue; }   /* segment 1 (Bezier) or 4.. */
        if (k == 9 && seed->degenerate == D_SAME_AS_0) { put_byte(w, 160); continue; }
        if (j >= 2 && s == 1 && seed->degenerate == D_COLLINEAR) { put_byte(w, 192); put_coordinate(w, 1.2f); continue; }
        if (k == 2 && seed->degenerate == D_CUSP) { put_byte(w, 216); continue; }
        if (k % 3 == 0 && k && seed->degenerate == D_ZERO_RADIUS) {
            put_byte(w, 232); put_coordinate(w, x); put_coordinate(w, -0.5f + 0.5f * (float)s + 0.03f * x * x);
            put_coordinate(w, 0.1f * x);
            continue;
        }
        if (k == 5 && seed->degenerate == D_HUGE_RADIUS) { put_byte(w, 176); put_coordinate(w, 1.2f); put_byte(w, 40); continue; }
        if (k == 3 && seed->degenerate == D_POISON) { put_byte(w, 248); put_byte(w, 1); continue; }   /* y NaN */
        put_point(w, x, -0.5f + 0.5f * (float)s + 0.03f * x * x, 0.1f * x, 0.06f);
    }
    for (i = 0; i < segments; ++i) put_byte(w, i % 4 == 0 && i ? 200 : 0);   /* three strands */
    put_byte(w, rays - 1);
    for (i = 0; i < rays; ++i) {
        float y = -0.5f + 0.5f * (float)(i % 3), x = -0.9f + 0.08f * (float)i;
        switch (i % 4) {
        case 0:   /* across, up the z axis */
            put_coordinate(w, x); put_coordinate(w, y + 0.03f * x * x + 0.01f * (float)(i % 5)); put_coordinate(w, -3.0f);
            put_coordinate(w, 0.0f); put_coordinate(w, 0.0f); put_coordinate(w, 1.0f);
            break;
        case 1:   /* along the strand into its tip (x = -1): the cap */
            put_coordinate(w, -3.0f); put_coordinate(w, y + 0.03f + 0.004f * (float)(i % 7)); put_coordinate(w, -0.1f);
            put_coordinate(w, 1.0f); put_coordinate(w, 0.0f); put_coordinate(w, 0.0f);
            break;
        case 2:   /* oblique */
            put_coordinate(w, x - 0.6f); put_coordinate(w, y + 0.8f); put_coordinate(w, 0.1f * x);
            put_coordinate(w, 0.6f); put_coordinate(w, -0.8f); put_coordinate(w, 0.0f);
            break;
        default:   /* from inside the fibre, on its centre line */
            put_coordinate(w, x); put_coordinate(w, y + 0.03f * x * x); put_coordinate(w, 0.1f * x);
            put_coordinate(w, 0.0f); put_coordinate(w, 1.0f); put_coordinate(w, 0.25f);
            break;
        }
        put_byte(w, 0); put_byte(w, 0);   /* tnear 0, tfar infinite */
    }
    for (i = 0; i < rays; ++i) {   /* paths, then filters */
        unsigned path = seed->path >> (i % 3) | (i % 5 == 4 ? 0xc000u : 0u);   /* the last bounce from the input, some rays */
        put_byte(w, path & 255); put_byte(w, path >> 8); put_byte(w, i % 2 ? 2 : 0);
        if ((path >> 14 & 3) == 3) { put_coordinate(w, 0.0f); put_coordinate(w, 0.0f); put_coordinate(w, -1.0f); }
        put_byte(w, seed->filter + (i % 4 == 3 ? 128 : 0));
        put_byte(w, 0x5a + i); put_byte(w, 0xc3); put_byte(w, 0x0f); put_byte(w, 0xf0);
    }
    put_byte(w, seed->load);
    for (k = 0; k < vertex_count && seed->refit; ++k) {
        if (seed->refit == 1) { put_byte(w, 128); put_byte(w, 140); put_byte(w, 120); put_byte(w, 128 + k % 5); put_byte(w, 150); }
        else if (k == 6 && seed->refit == 2) { put_byte(w, 192); put_byte(w, 128); }   /* the point before repeated */
        else if (k == 7 && seed->refit == 3) { put_byte(w, 192); put_byte(w, 248); put_byte(w, 3 + 4 * 1); }   /* radius Inf */
        else put_byte(w, 0);
    }
    put_byte(w, seed->flags); put_byte(w, seed->flags2); put_byte(w, 'T'); put_byte(w, 'U'); put_byte(w, seed->basis);
}

static int write_file(const char *directory, const char *name, size_t k, const writer *w)
{
    char path[4096];
    FILE *file;
    snprintf(path, sizeof path, "%s/%s%zu", directory, name, k);
    file = fopen(path, "wb");
    if (!file || fwrite(w->bytes, 1, w->size, file) != w->size || fclose(file) != 0) {
        fprintf(stderr, "%s: cannot write\n", path);
        return 1;
    }
    LLVMFuzzerTestOneInput(w->bytes, w->size);
    printf("%s: %zu bytes\n", path, w->size);
    return 0;
}

int main(int argc, char **argv)
{
    static const motion_seed seeds[] = {
        /* nodes layout spatial leaf | T null vertices_null poison_step poison_kind refit basis */
        {0, 0, 0, 0, 2, 7, 0, 7, 0, 2, 0},   /* valid; refit to the steps reversed */
        {0, 1, 0, 1, 3, 7, 1, 7, 0, 0, 0},   /* valid, vertices NULL; refit with a NULL step */
        {0, 3, 1, 0, 4, 7, 0, 7, 0, 1, 0},   /* compressed, spatial splits; refit with a poisoned step */
        {1, 0, 0, 1, 5, 7, 0, 7, 0, 5, 0},   /* AABB only, leaf size 1 */
        {2, 4, 0, 0, 3, 7, 0, 7, 0, 4, 0},   /* OBB only, compressed per child */
        {0, 0, 0, 0, 2, 255, 0, 7, 0, 2, 0}, /* time_vertices NULL */
        {0, 0, 0, 0, 3, 1, 0, 7, 0, 2, 0},   /* step 1 NULL */
        {0, 0, 0, 0, 4, 7, 0, 2, 0, 2, 0},   /* NaN at step 2 */
        {0, 0, 0, 0, 2, 7, 0, 1, 4, 2, 0},   /* a negative radius at step 1 */
        {0, 0, 0, 0, 3, 7, 0, 0, 5, 2, 0},   /* 1e18 at step 0: allowed */
        {0, 0, 0, 0, 5, 7, 0, 4, 3, 2, 0},   /* -2e18 at the last step */
        {0, 0, 0, 0, 0, 7, 1, 7, 0, 2, 0},   /* static, vertices NULL */
        {0, 0, 0, 0, 1, 7, 0, 7, 0, 2, 0},   /* T = 1: static */
        {0, 0, 0, 0, 3, 7, 0, 7, 0, 2, 2},   /* Catmull-Rom with motion */
        {0, 2, 0, 0, 2, 7, 1, 1, 1, 1, 0},   /* Inf at step 1 */
        {0, 0, 0, 3, 3, 7, 0, 2, 6, 0, 0},   /* -0 at step 2: allowed */
    };
    /* flags: 1 round, 2 caps on, 16 back faces off, 32 pieces kept, 64 chained, 128 SSE2;
       flags2: bezier_copy (1 on, 2 off) */
    static const tube_seed tubes[] = {
        /* flags flags2 basis degenerate | filter path load refit */
        {64 | 1, 0, HAIROBB_BASIS_BEZIER, D_NONE, 0, 0x0000, 0, 0},            /* tubes, open, both sheets */
        {64 | 1 | 2, 0, HAIROBB_BASIS_BEZIER, D_NONE, 1, 0x5555, 1, 1},        /* caps; paths along Ng */
        {64 | 1 | 16, 0, HAIROBB_BASIS_BEZIER, D_NONE, 2, 0xaaaa, 2, 0},       /* culled; paths into the fibre */
        {64 | 1 | 2 | 16, 2, HAIROBB_BASIS_BEZIER, D_NONE, 3, 0x1b1b, 9, 1},   /* caps and culling, no copy */
        {64 | 1 | 2, 0, HAIROBB_BASIS_BSPLINE, D_NONE, 1, 0x0000, 3, 1},
        {64 | 1 | 2, 0, HAIROBB_BASIS_CATMULL_ROM, D_NONE, 2, 0x2222, 4, 2},
        {64 | 1 | 2, 0, HAIROBB_BASIS_HERMITE, D_NONE, 1, 0x9999, 5, 1},
        {64 | 1 | 2 | 16, 0, HAIROBB_BASIS_LINEAR, D_NONE, 1, 0x0000, 10, 1},
        {64 | 1 | 2, 0, HAIROBB_BASIS_BEZIER, D_ZERO_LENGTH, 1, 0x0000, 0, 0},
        {64 | 1 | 2, 0, HAIROBB_BASIS_BSPLINE, D_ZERO_LENGTH, 0, 0x0000, 0, 2},
        {64 | 1 | 2, 0, HAIROBB_BASIS_BEZIER, D_REPEAT, 1, 0x4444, 0, 0},
        {64 | 1, 0, HAIROBB_BASIS_BEZIER, D_SAME_AS_0, 2, 0x0000, 0, 0},
        {64 | 1 | 2, 0, HAIROBB_BASIS_BEZIER, D_COLLINEAR, 1, 0x0000, 11, 1},
        {64 | 1 | 2, 0, HAIROBB_BASIS_CATMULL_ROM, D_CUSP, 1, 0x8888, 0, 0},
        {64 | 1 | 2 | 16, 0, HAIROBB_BASIS_BEZIER, D_ZERO_RADIUS, 1, 0x0000, 0, 2},
        {64 | 1 | 2, 0, HAIROBB_BASIS_LINEAR, D_HUGE_RADIUS, 1, 0x0000, 0, 0},
        {64 | 1, 0, HAIROBB_BASIS_BEZIER, D_POISON, 0, 0x0000, 0, 0},          /* INVALID_GEOMETRY */
        {64 | 1 | 32, 0, HAIROBB_BASIS_BEZIER, D_NONE, 0, 0x0000, 0, 0},       /* pieces kept: INVALID_ARGUMENT */
        {64 | 1 | 2 | 128, 0, HAIROBB_BASIS_BEZIER, D_NONE, 1, 0x0000, 9, 3},  /* SSE2, loaded as AVX2; a refused refit */
        {1 | 2, 1, HAIROBB_BASIS_BEZIER, D_NONE, 1, 0x0000, 0, 1},             /* separate segments: caps at every end */
        {64, 0, HAIROBB_BASIS_BEZIER, D_NONE, 1, 0x5555, 0, 1},                /* ribbons in the newer layout */
        {64 | 2 | 16, 0, HAIROBB_BASIS_BSPLINE, D_ZERO_LENGTH, 2, 0x0000, 9, 2},  /* ribbons ignore caps and culling */
        {64, 0, HAIROBB_BASIS_HERMITE, D_CUSP, 1, 0xaaaa, 0, 3},
        {64 | 128, 2, HAIROBB_BASIS_CATMULL_ROM, D_REPEAT, 3, 0x0000, 13, 1},
    };
    size_t k;
    if (argc != 2) { fprintf(stderr, "usage: %s DIRECTORY\n", argv[0]); return 2; }
    for (k = 0; k < sizeof seeds / sizeof seeds[0]; ++k) {
        writer w;
        write_seed(&w, &seeds[k]);
        if (write_file(argv[1], "motion", k, &w)) return 1;
    }
    for (k = 0; k < sizeof tubes / sizeof tubes[0]; ++k) {
        writer w;
        write_tube_seed(&w, &tubes[k]);
        if (write_file(argv[1], "tube", k, &w)) return 1;
    }
    return 0;
}
#endif
