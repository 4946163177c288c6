/* fuzz_build.c - libFuzzer target: arbitrary bytes become build options
   (the curve basis too), control points (any float, NaN and Inf included),
   segment indices (any value, past the end included) and rays.
   hairobb_build must return one of its codes and, on success, traced hits
   must be sane: t finite and in
   [tnear, tfar], u in [0,1], prim_id a segment, occluded1 true wherever
   intersect1 hits; a static BVH gives the same hit at any ray time.
   Motion blur, for inputs that end in the bytes 'M' 'B' before the basis
   (so the seeds written before it keep their meaning): time_steps 0..5,
   time_vertices NULL or one step NULL, one float of one step poisoned
   (NaN, Inf, beyond 1e18, a negative radius; or 1e18 and -0, which are
   allowed), `vertices` NULL or not; the build must return the code of one
   of the documented errors the input has (MOTION BLUR in hairobb.h), or
   succeed where it has none. Rays of a motion-blurred BVH get times (in
   [0, 1], knots, raw floats, NaN, outside): outside [0, 1] or NaN they
   miss. Then hairobb_refit_motion: a NULL step (INVALID_ARGUMENT), a
   poisoned step (INVALID_GEOMETRY, the rays then traced to the same bits
   as before), or the steps in reverse order. Build with clang
   -fsanitize=fuzzer,address,undefined (see `make fuzz`); leaks are
   LeakSanitizer's to find. Seeds: tests/fuzz/corpus/bvh_build (the
   motion ones written by this file built with -DFUZZ_BUILD_WRITE_SEEDS). */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#define HAIROBB_IMPLEMENTATION
#include "../../hairobb.h"
#include "fuzz_checks.h"

typedef struct reader {
    const uint8_t *data;
    size_t size, at;
} reader;

static unsigned read_byte(reader *r) { return r->at < r->size ? r->data[r->at++] : 0u; }

static float read_float(reader *r)
{
    uint32_t bits = 0;
    int i;
    float f;
    for (i = 0; i < 4; ++i) bits |= (uint32_t)read_byte(r) << (8 * i);
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
    poison_at = read_byte(r) | (size_t)read_byte(r) << 8;
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

/* A control point hairobb_build rejects: NaN, Inf, |value| > 1e18, radius < 0 (-0 is not). */
static int bad_point(const float *p)
{
    int c;
    for (c = 0; c < 4; ++c)
        if (!(fabsf(p[c]) <= 1e18f)) return 1;
    return p[3] < 0.0f;
}

/* Whether the result is one the documented errors of a motion build allow:
   each error the input has (time_vertices or a step NULL, Hermite (its
   tangents do not move), no segments: INVALID_ARGUMENT; an index past the vertices:
   INDEX_OUT_OF_RANGE; a bad control point at any step: INVALID_GEOMETRY)
   may be the one reported; with none, the build succeeds (or runs out of
   memory). */
static int motion_result_allowed(hairobb_result result, const motion_input *m, const hairobb_build_options *options,
                                 size_t vertex_count, const uint32_t *indices, size_t segments)
{
    int argument = segments == 0 || m->steps_null || m->null_step < (int)m->time_steps || options->basis == HAIROBB_BASIS_HERMITE;
    unsigned points = options->basis == HAIROBB_BASIS_LINEAR || options->basis == HAIROBB_BASIS_HERMITE ? 2u : 4u;
    int index = 0, geometry = 0;
    size_t i;
    unsigned k, j;
    for (i = 0; i < segments; ++i) {
        if ((size_t)indices[i] + points > vertex_count) { index = 1; continue; }
        for (k = 0; k < m->time_steps; ++k)
            for (j = 0; j < points; ++j) geometry |= bad_point(m->steps[k] + 4 * ((size_t)indices[i] + j));
    }
    if (result == HAIROBB_ERROR_INVALID_ARGUMENT) return argument;
    if (result == HAIROBB_ERROR_INDEX_OUT_OF_RANGE) return index;
    if (result == HAIROBB_ERROR_INVALID_GEOMETRY) return geometry;
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

/* the same hit to the bit (a miss writes nothing but prim_id) */
static int same_hit(const hairobb_hit *a, const hairobb_hit *b)
{
    if (a->prim_id == HAIROBB_INVALID_ID || b->prim_id == HAIROBB_INVALID_ID) return a->prim_id == b->prim_id;
    return a->prim_id == b->prim_id && memcmp(&a->t, &b->t, sizeof a->t) == 0 && memcmp(&a->u, &b->u, sizeof a->u) == 0 &&
           memcmp(&a->v, &b->v, sizeof a->v) == 0 && memcmp(a->Ng, b->Ng, sizeof a->Ng) == 0;
}

/* A ray of a motion-blurred BVH: outside [0, 1] or NaN a miss, else sane. */
static void check_motion_ray(const hairobb_bvh *bvh, const hairobb_ray *ray, size_t segments)
{
    hairobb_hit hit;
    if (ray->time >= 0.0f && ray->time <= 1.0f) {
        fuzz_check_ray(bvh, ray, segments);
        return;
    }
    if (hairobb_intersect1(bvh, ray, &hit) || hit.prim_id != HAIROBB_INVALID_ID) fuzz_fail("a ray at a time outside [0, 1] hit");
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

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    reader r;
    hairobb_build_options options;
    hairobb_bvh *bvh = NULL;
    hairobb_result result;
    size_t segments, vertex_count, i;
    float *vertices, *tangents = NULL;
    uint32_t *indices;
    unsigned rays, k;
    motion_input motion;

    memset(&motion, 0, sizeof motion);
    motion.on = size >= 3 && data[size - 3] == 'M' && data[size - 2] == 'B';
    r.data = data; r.size = motion.on ? size - 3 : size; r.at = 0;
    memset(&options, 0, sizeof options);
    options.nodes = (hairobb_node_policy)(read_byte(&r) % 3);
    options.obb_layout = (hairobb_obb_layout)(read_byte(&r) % 5);
    options.spatial_splits = (hairobb_switch)(read_byte(&r) % 3);
    options.clustering = (hairobb_switch)(read_byte(&r) % 3);
    options.max_leaf_size = read_byte(&r) % 16;
    options.precision = (hairobb_precision)(read_byte(&r) % 2);
    options.curve_pieces = read_byte(&r) % 17;
    options.threads = 1u + read_byte(&r) % 2;
    segments = read_byte(&r) % 48;
    vertex_count = 4 * segments + read_byte(&r) % 4;
    vertices = (float *)malloc(sizeof(float) * 4 * (vertex_count + 1));
    indices = (uint32_t *)malloc(sizeof(uint32_t) * (segments + 1));
    if (!vertices || !indices) { free(vertices); free(indices); return 0; }
    for (i = 0; i < 4 * vertex_count; ++i) {
        float v = read_coordinate(&r);
        vertices[i] = (i % 4 == 3) ? (v < 0.0f && read_byte(&r) < 240 ? -v : v) * 0.05f : v;   /* radii: mostly >= 0 */
    }
    for (i = 0; i < segments; ++i) {
        unsigned pick = read_byte(&r);
        indices[i] = pick < 250 ? (uint32_t)(4 * i) : (uint32_t)(pick == 255 ? 0xfffffffeu : vertex_count - 3 + (pick - 250));
    }
    /* the curve basis from the last byte (the stream's order stays as the
       seeds were written); Hermite tangents: differences of the vertices */
    options.basis = (hairobb_basis)(size > 0 ? data[size - 1] % 5 : 0);
    if (options.basis == HAIROBB_BASIS_HERMITE) {
        tangents = (float *)malloc(sizeof(float) * 4 * (vertex_count + 1));
        if (!tangents) { free(vertices); free(indices); return 0; }
        for (i = 0; i < 4 * vertex_count; ++i) tangents[i] = vertices[(i + 4) % (4 * vertex_count)] - vertices[i];
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
    if ((unsigned)result > HAIROBB_ERROR_CANCELLED) fuzz_fail("unknown result code");
    if (!strcmp(hairobb_result_string(result), "unknown hairobb_result")) fuzz_fail("result without a message");
    if (motion.on && motion.time_steps >= 2 && !motion_result_allowed(result, &motion, &options, vertex_count, indices, segments))
        fuzz_fail("a motion build's result is not one its input's errors allow");
    if (motion.on && motion.time_steps < 2 && motion.vertices_null && result != HAIROBB_ERROR_INVALID_ARGUMENT)
        fuzz_fail("a static build without vertices");
    if (result != HAIROBB_OK) {
        if (bvh) fuzz_fail("a failed build returned a BVH");
    } else {
        hairobb_ray ray_list[32];
        int moving = motion.on && motion.time_steps >= 2;
        if (!bvh) fuzz_fail("a successful build returned no BVH");
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
        if (moving) check_refit_motion(bvh, &motion, vertices, indices, ray_list, rays, segments, read_byte(&r));
        hairobb_free(bvh);
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
   the motion input's choices (the stream as LLVMFuzzerTestOneInput reads it). */
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
    size_t k;
    if (argc != 2) { fprintf(stderr, "usage: %s DIRECTORY\n", argv[0]); return 2; }
    for (k = 0; k < sizeof seeds / sizeof seeds[0]; ++k) {
        writer w;
        char path[4096];
        FILE *file;
        write_seed(&w, &seeds[k]);
        snprintf(path, sizeof path, "%s/motion%zu", argv[1], k);
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
