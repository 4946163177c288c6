/* fuzz_input.h - what fuzz_build.c and fuzz_scene.c read from their input:
   bytes, floats (small numbers mostly, raw bit patterns sometimes) and
   control points, often degenerate ones made from the points before them
   (repeated, collinear, folded back into a cusp, zero radius, a radius far
   larger than the segment, NaN, Inf, huge); and what both compare: hits to
   the bit, hits a filter was shown and took. Past the end every read gives
   0, so a short input still means something. */
#ifndef HAIROBB_TESTS_FUZZ_INPUT_H
#define HAIROBB_TESTS_FUZZ_INPUT_H

#include <math.h>
#include <stdint.h>
#include <string.h>

typedef struct reader {
    const uint8_t *data;
    size_t size, at;
} reader;

static unsigned read_byte(reader *r) { return r->at < r->size ? r->data[r->at++] : 0u; }

/* 4 bytes, little end first (one read after another: the operands of |
   are not sequenced) */
static uint32_t read_u32(reader *r)
{
    uint32_t bits = 0;
    int i;
    for (i = 0; i < 4; ++i) bits |= (uint32_t)read_byte(r) << (8 * i);
    return bits;
}

static float read_float(reader *r)
{
    uint32_t bits = read_u32(r);
    float f;
    memcpy(&f, &bits, sizeof f);
    return f;
}

/* Mostly small numbers (real scenes), sometimes raw bit patterns. */
static float read_coordinate(reader *r)
{
    unsigned kind = read_byte(r);
    if (kind < 224) return ((float)kind - 112.0f) / 16.0f + (float)read_byte(r) / 4096.0f;
    return read_float(r);
}

/* A radius: a coordinate, mostly made >= 0, scaled to hair. */
static float read_radius(reader *r)
{
    float v = read_coordinate(r);
    return (v < 0.0f && read_byte(r) < 240 ? -v : v) * 0.05f;
}

/* Floats a poisoned control point or map entry takes: the first three and
   the sixth are refused anywhere, the rest allowed (1e18 is the limit). */
static const float fuzz_poison[8] = {NAN, INFINITY, -INFINITY, 1e18f, -1e18f, 2e18f, -0.0f, 1e-40f};

/* Control point k of v (4 floats: x, y, z, radius) from the input, made
   from the points before it where the op byte says so: fresh (as
   read_coordinate reads them), the point before repeated (all of a
   segment's points repeated: zero length), point 0 again, the point
   before with a radius up to 50 times larger, collinear with the two
   before (1: a smooth joint's continuation, -1: back onto the one before
   that, a cusp), the point two before (a fold, a cusp), a zero radius, or
   the point before with one float poisoned. */
static void read_point(reader *r, float *v, size_t k)
{
    static const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    float *p = v + 4 * k;
    const float *a = k > 0 ? p - 4 : zero, *b = k > 1 ? p - 8 : a;
    unsigned op = read_byte(r), c;
    if (op < 128 || (k == 0 && op < 248)) {
        for (c = 0; c < 3; ++c) p[c] = read_coordinate(r);
        p[3] = read_radius(r);
    } else if (op < 160) {
        memcpy(p, a, 4 * sizeof(float));
    } else if (op < 176) {
        memcpy(p, v, 4 * sizeof(float));
    } else if (op < 192) {
        memcpy(p, a, 3 * sizeof(float));
        p[3] = fabsf(read_radius(r));
        p[3] *= (float)(1 + read_byte(r) % 50);
    } else if (op < 216) {
        float f = ((float)read_byte(r) - 128.0f) / 32.0f;   /* 0: a repeat; 1 and -1 above */
        if (op < 200) f = op < 196 ? 1.0f : -1.0f;
        for (c = 0; c < 3; ++c) p[c] = a[c] + f * (a[c] - b[c]);
        p[3] = read_radius(r);
    } else if (op < 232) {
        memcpy(p, b, 4 * sizeof(float));
    } else if (op < 248) {
        for (c = 0; c < 3; ++c) p[c] = read_coordinate(r);
        p[3] = op & 1 ? -0.0f : 0.0f;
    } else {
        unsigned which = read_byte(r);
        memcpy(p, a, 4 * sizeof(float));
        p[which % 4] = fuzz_poison[which / 4 % 8];
    }
}

/* A control point hairobb_build rejects: NaN, Inf, |value| > 1e18, radius < 0 (-0 is not). */
static int bad_point(const float *p)
{
    int c;
    for (c = 0; c < 4; ++c)
        if (!(fabsf(p[c]) <= 1e18f)) return 1;
    return p[3] < 0.0f;
}

/* A Hermite tangent hairobb_build rejects (any sign of dr/du is taken). */
static int bad_tangent(const float *p)
{
    int c;
    for (c = 0; c < 4; ++c)
        if (!(fabsf(p[c]) <= 1e18f)) return 1;
    return 0;
}

/* Where two trees must give the same nearest hit to the bit (it does not
   depend on the tree): hair and rays of moderate size (every float a
   segment reads, and the ray's, at most 1024 in magnitude; a direction
   not tiny). Beyond that the intersector's rounding, relative to the
   largest coordinate (a control point at 4e13 moves the curve's points by
   millions), may place a hit outside a segment's box, which one tree's
   culling reaches and another's does not: float rounding, as THE SURFACE
   allows (tests/fuzz/findings/README.md; -DFUZZ_ANY_SIZE compares every
   size, and every thickness: rounding_decided). */
static int moderate_hair(const float *vertices, const uint32_t *indices, size_t segments, unsigned points)
{
    size_t i;
    unsigned j;
#ifdef FUZZ_ANY_SIZE
    return 1;
#endif
    for (i = 0; i < segments; ++i)
        for (j = 0; j < 4 * points; ++j)
            if (!(fabsf(vertices[4 * (size_t)indices[i] + j]) <= 1024.0f)) return 0;
    return 1;
}

static int moderate_ray(const hairobb_ray *ray)
{
    int j;
    float largest = 0.0f;
#ifdef FUZZ_ANY_SIZE
    return 1;
#endif
    for (j = 0; j < 3; ++j) {
        if (!(fabsf(ray->org[j]) <= 1024.0f && fabsf(ray->dir[j]) <= 1024.0f)) return 0;
        largest = fmaxf(largest, fabsf(ray->dir[j]));
    }
    return largest >= 1.0f / 1024.0f;
}

/* Whether a hit was decided by float rounding rather than by the surface:
   the ribbon or tube there (hairobb_interpolate's radius) thinner than
   2^-16 of the magnitudes involved, the ray's origin and the hit point
   (a ray along a zero-radius strand, a radius clamped to 0). Whether a
   tree's boxes keep such a segment for the ray is rounding too, so two
   trees may differ there (tests/fuzz/findings/README.md, 3). */
static int rounding_decided(const hairobb_bvh *bvh, const hairobb_ray *ray, const hairobb_hit *hit)
{
    float p[4], scale = 1.0f;
    int j;
#ifdef FUZZ_ANY_SIZE
    return 0;
#endif
    if (!hairobb_interpolate(bvh, hit->group_id, hit->prim_id, hit->u, ray->time, p, NULL, NULL)) return 0;
    for (j = 0; j < 3; ++j) scale += fabsf(p[j]) + fabsf(ray->org[j]);
    return !(p[3] > scale * (1.0f / 65536.0f));
}

/* Hermite tangents made from the points: differences of neighbours. */
static void difference_tangents(const float *vertices, size_t vertex_count, float *tangents)
{
    size_t i;
    for (i = 0; i < 4 * vertex_count; ++i) tangents[i] = vertices[(i + 4) % (4 * vertex_count)] - vertices[i];
}

/* Segment indices: 4 points of their own each (the first layout), or
   strands whose segments share their end points (chained: 3 apart for
   Bezier, 1 for the other bases), a new strand where the input says; a
   pick of 250 and up puts a segment at or past the end of the vertices. */
static void read_indices(reader *r, uint32_t *indices, size_t segments, size_t vertex_count, int chained, hairobb_basis basis)
{
    uint32_t next = 0, step = basis == HAIROBB_BASIS_BEZIER ? 3u : 1u;
    size_t i;
    for (i = 0; i < segments; ++i) {
        unsigned pick = read_byte(r);
        if (pick >= 250) {
            indices[i] = pick == 255 ? 0xfffffffeu : (uint32_t)(vertex_count - 3 + (pick - 250));
        } else if (!chained) {
            indices[i] = (uint32_t)(4 * i);
        } else {
            if (pick >= 200 && i > 0) next += 4 - step;   /* a new strand: no point shared */
            indices[i] = next;
            next += step;
        }
    }
}

/* The same hit to the bit (a miss writes nothing but prim_id). */
static int same_hit(const hairobb_hit *a, const hairobb_hit *b)
{
    if (a->prim_id == HAIROBB_INVALID_ID || b->prim_id == HAIROBB_INVALID_ID) return a->prim_id == b->prim_id;
    return a->prim_id == b->prim_id && memcmp(&a->t, &b->t, sizeof a->t) == 0 && memcmp(&a->u, &b->u, sizeof a->u) == 0 &&
           memcmp(&a->v, &b->v, sizeof a->v) == 0 && memcmp(a->Ng, b->Ng, sizeof a->Ng) == 0 &&
           memcmp(a->tangent, b->tangent, sizeof a->tangent) == 0 && a->instance_id == b->instance_id && a->group_id == b->group_id;
}

/* A per-call filter (hairobb_context) driven by the input: it takes or
   ignores each hit it is shown by a 32-bit pattern, indexed by the
   segment (a pure function of the hit), by the call's count (not one), or
   takes all or none; it counts its calls and keeps the hits it took, so
   that the hit a call returns can be found among them. */
enum { FILTER_ALL, FILTER_BY_PRIM, FILTER_BY_CALL, FILTER_NONE, FILTER_MODES };
#define FILTER_KEPT 64

typedef struct fuzz_filter {
    unsigned mode;
    uint32_t pattern;
    size_t calls, taken;
    hairobb_hit took[FILTER_KEPT];   /* the first FILTER_KEPT it took */
    /* scenes: each instance's mask and segment count, the ray's mask */
    const uint32_t *instance_masks;
    const size_t *instance_segments;
    size_t instance_count;
    uint32_t ray_mask;
} fuzz_filter;

static void fuzz_fail(const char *what);

static int fuzz_filter_fn(void *user, const hairobb_ray *ray, const hairobb_hit *hit)
{
    fuzz_filter *f = (fuzz_filter *)user;
    int take;
    (void)ray;
    if (!(hit->t >= ray->tnear && hit->t <= ray->tfar) || !(hit->u >= 0.0f && hit->u <= 1.0f))
        fuzz_fail("a filter was shown a hit outside [tnear, tfar] or u outside [0, 1]");
    if (f->instance_masks) {
        uint32_t mask;
        if (hit->instance_id >= f->instance_count) fuzz_fail("a filter was shown a hit of no instance");
        mask = f->instance_masks[hit->instance_id];
        if (!((mask ? mask : 0xffffffffu) & (f->ray_mask ? f->ray_mask : 0xffffffffu)))
            fuzz_fail("a filter was shown a hit of an instance the ray's mask leaves out");
        if (hit->prim_id >= f->instance_segments[hit->instance_id]) fuzz_fail("a filter was shown a segment past its BVH's");
    } else if (hit->instance_id != HAIROBB_INVALID_ID) {
        fuzz_fail("a BVH's own call showed its filter an instance");
    }
    switch (f->mode) {
    case FILTER_ALL: take = 1; break;
    case FILTER_BY_PRIM: take = (int)(f->pattern >> (hit->prim_id % 32) & 1u); break;
    case FILTER_BY_CALL: take = (int)(f->pattern >> (f->calls % 32) & 1u); break;
    default: take = 0; break;
    }
    ++f->calls;
    if (take) {
        if (f->taken < FILTER_KEPT) f->took[f->taken] = *hit;
        ++f->taken;
    }
    return take;
}

static void fuzz_filter_reset(fuzz_filter *f)
{
    f->calls = f->taken = 0;
}

/* Whether the filter took this hit: the same segment, instance, t and u
   (those it was shown are the hits a call returns, filters off or on). */
static int fuzz_filter_took(const fuzz_filter *f, const hairobb_hit *hit)
{
    size_t i, kept = f->taken < FILTER_KEPT ? f->taken : FILTER_KEPT;
    if (f->taken > FILTER_KEPT) return 1;   /* some not kept: cannot tell */
    for (i = 0; i < kept; ++i) {
        const hairobb_hit *h = &f->took[i];
        if (h->prim_id == hit->prim_id && h->instance_id == hit->instance_id && memcmp(&h->t, &hit->t, sizeof h->t) == 0 &&
            memcmp(&h->u, &hit->u, sizeof h->u) == 0)
            return 1;
    }
    return 0;
}

/* A bounce's direction leaving a hit: the ray reflected about Ng, along
   Ng, against it (into a tube), or one from the input. */
static void bounce_direction(reader *r, unsigned kind, const float dir[3], const hairobb_hit *hit, float out[3])
{
    float d = dir[0] * hit->Ng[0] + dir[1] * hit->Ng[1] + dir[2] * hit->Ng[2];
    int j;
    for (j = 0; j < 3; ++j) {
        switch (kind % 4) {
        case 0: out[j] = dir[j] - 2.0f * d * hit->Ng[j]; break;
        case 1: out[j] = hit->Ng[j]; break;
        case 2: out[j] = -hit->Ng[j]; break;
        default: out[j] = read_coordinate(r); break;
        }
    }
}

#endif
