/* scenes.h - hair scenes for hairobb's tests and benchmarks.
 *
 * Header-only; every function is `static inline` (static, and inline only so
 * that a program using part of the header gets no -Wunused-function warning).
 * C99 and C++11. Uses POSIX (posix_memalign, popen, clock_gettime): a C file
 * must start with
 *     #define _POSIX_C_SOURCE 200809L
 * before its first #include.
 *
 * Geometry conventions, shared with hairobb.h and Embree:
 *   vertices  float[4 * vertex_count]: x, y, z, radius per control point
 *             (Embree's RTC_FORMAT_FLOAT4 curve vertex), 16-byte aligned and
 *             followed by 16 bytes of padding, as Embree requires;
 *   indices   uint32 per segment: the first of its 4 consecutive control
 *             points (Embree's curve index buffer);
 *   segment   a cubic Bezier curve in position and in radius; in scenes
 *             whose basis is SCENE_BASIS_CATMULL_ROM (scene_yeti) the
 *             Catmull-Rom segment through 4 points shared along a strand.
 *
 * Contents: Catmull-Rom conversion of polyline strands,
 * procedural scenes (Yeti-class Catmull-Rom fur among them), loaders for Cem Yuksel's .hair files and Embree's
 * furBall_A model, a camera that frames a scene, a transform for stress tests
 * and a monotonic clock. Its random numbers are random.h's scene_rng (PCG32),
 * included here.
 */
#ifndef HAIROBB_TESTS_SCENES_H
#define HAIROBB_TESTS_SCENES_H

/* Strict C modes hide POSIX declarations; fail early with the fix instead of
   warning about implicit declarations. */
#if !defined(__cplusplus) && defined(__STRICT_ANSI__) && \
    !defined(_POSIX_C_SOURCE) && !defined(_XOPEN_SOURCE) && !defined(_GNU_SOURCE)
#error "scenes.h needs POSIX: #define _POSIX_C_SOURCE 200809L before the first #include"
#endif

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "random.h"    /* scene_rng: the generators' random numbers */
#include "test_data.h" /* where furBall_A is installed */

/* How a scene's segments read their 4 control points from indices[i] on;
   zero (a memset scene) is Bezier. */
typedef enum scene_basis {
    SCENE_BASIS_BEZIER = 0,   /* the cubic Bezier of the 4 points */
    SCENE_BASIS_CATMULL_ROM   /* the uniform Catmull-Rom segment from the 2nd point to the 3rd,
                                 points shared along a strand (Embree's and hairobb's convention) */
} scene_basis;

typedef struct hair_scene {
    float *vertices;        /* 16-byte aligned float4 (x, y, z, radius) */
    size_t vertex_count;
    uint32_t *indices;      /* first control point of each segment */
    size_t segment_count;
    float lower[3], upper[3]; /* bounds of the segments' Bezier control points expanded by their radius */
    char name[64];
    scene_basis basis;
} hair_scene;

/* ------------------------------------------------------------------------ */
/* Small vector helpers for the generators. */

typedef struct scene_vec3 { float x, y, z; } scene_vec3;

static inline scene_vec3 scene_v3(float x, float y, float z)
{
    scene_vec3 v;
    v.x = x; v.y = y; v.z = z;
    return v;
}
static inline scene_vec3 scene_v3_add(scene_vec3 a, scene_vec3 b) { return scene_v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline scene_vec3 scene_v3_sub(scene_vec3 a, scene_vec3 b) { return scene_v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline scene_vec3 scene_v3_scale(scene_vec3 a, float s) { return scene_v3(a.x * s, a.y * s, a.z * s); }
static inline float scene_v3_dot(scene_vec3 a, scene_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline scene_vec3 scene_v3_cross(scene_vec3 a, scene_vec3 b)
{
    return scene_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline float scene_v3_length(scene_vec3 a) { return sqrtf(scene_v3_dot(a, a)); }
static inline scene_vec3 scene_v3_normalize(scene_vec3 a)
{
    float length = scene_v3_length(a);
    return length > 0.0f ? scene_v3_scale(a, 1.0f / length) : a;
}

/* Any unit vector perpendicular to the unit vector n. */
static inline scene_vec3 scene_v3_perpendicular(scene_vec3 n)
{
    scene_vec3 axis = fabsf(n.x) < 0.6f ? scene_v3(1, 0, 0) : scene_v3(0, 1, 0);
    return scene_v3_normalize(scene_v3_cross(n, axis));
}

static inline scene_vec3 scene_random_unit_vector(scene_rng *rng)
{
    float z = 2.0f * scene_rng_float(rng) - 1.0f;
    float phi = 6.28318531f * scene_rng_float(rng);
    float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    return scene_v3(r * cosf(phi), r * sinf(phi), z);
}

/* Root k of count on the unit sphere: a Fibonacci spiral spreads roots evenly
   (random roots leave bald patches and clumps); a jitter of about half the
   spacing, drawn from rng, hides the spiral pattern. */
static inline scene_vec3 scene_sphere_root(size_t k, size_t count, scene_rng *rng)
{
    const float golden_angle = 2.39996323f;
    float y = 1.0f - 2.0f * ((float)k + 0.5f) / (float)count;
    float ring = sqrtf(fmaxf(0.0f, 1.0f - y * y));
    float phi = golden_angle * (float)k;
    scene_vec3 p = scene_v3(ring * cosf(phi), y, ring * sinf(phi));
    float spacing = sqrtf(4.0f * 3.14159265f / (float)count);
    scene_vec3 jitter = scene_v3_scale(scene_random_unit_vector(rng), 0.5f * spacing);
    return scene_v3_normalize(scene_v3_add(p, jitter));
}

/* ------------------------------------------------------------------------ */
/* Allocation and bounds */

static inline void scene_free(hair_scene *s)
{
    free(s->vertices);
    free(s->indices);
    memset(s, 0, sizeof *s);
}

static inline void scene_set_name(hair_scene *s, const char *name)
{
    snprintf(s->name, sizeof s->name, "%s", name ? name : "");
}

/* Allocates segment_count independent segments (4 vertices each, indices[i] =
   4*i) with uninitialised vertices. */
static inline int scene_alloc(hair_scene *s, size_t segment_count, const char *name)
{
    memset(s, 0, sizeof *s);
    /* indices are uint32, so the last vertex index 4*segments-1 must fit */
    if (segment_count == 0 || segment_count > UINT32_MAX / 4)
        return 1;
    size_t vertex_count = 4 * segment_count;
    void *vertices = NULL;
    if (posix_memalign(&vertices, 16, vertex_count * 4 * sizeof(float) + 16) != 0)
        return 1;
    s->vertices = (float *)vertices;
    memset(s->vertices + 4 * vertex_count, 0, 16); /* defined padding: reads past the end stay harmless */
    s->indices = (uint32_t *)malloc(segment_count * sizeof(uint32_t));
    if (!s->indices) {
        scene_free(s);
        return 1;
    }
    for (size_t i = 0; i < segment_count; i++)
        s->indices[i] = (uint32_t)(4 * i);
    s->vertex_count = vertex_count;
    s->segment_count = segment_count;
    scene_set_name(s, name);
    return 0;
}

/* Bezier control points (x, y, z, r each) of the uniform Catmull-Rom
   segment from p1 to p2, p0 and p3 its neighbours: it interpolates p1 and p2
   with tangents (p2 - p0) / 2 and (p3 - p1) / 2, on all four components.
   Radii that overshoot below zero are clamped. */
static inline void scene_catmull_rom_bezier(const float *p0, const float *p1, const float *p2, const float *p3,
                                            float out[16])
{
    for (int c = 0; c < 4; c++) {
        out[c] = p1[c];
        out[4 + c] = p1[c] + (p2[c] - p0[c]) / 6.0f;
        out[8 + c] = p2[c] - (p3[c] - p1[c]) / 6.0f;
        out[12 + c] = p2[c];
    }
    for (int j = 0; j < 4; j++)
        out[4 * j + 3] = fmaxf(out[4 * j + 3], 0.0f);
}

/* Segment i's Bezier control points, whatever the scene's basis. */
static inline void scene_segment_bezier(const hair_scene *s, size_t i, float out[16])
{
    const float *p = s->vertices + 4 * (size_t)s->indices[i];
    if (s->basis == SCENE_BASIS_CATMULL_ROM)
        scene_catmull_rom_bezier(p, p + 4, p + 8, p + 12, out);
    else
        memcpy(out, p, 16 * sizeof(float));
}

static inline void scene_expand_bounds(hair_scene *s, const float *v)
{
    for (int axis = 0; axis < 3; axis++) {
        s->lower[axis] = fminf(s->lower[axis], v[axis] - v[3]);
        s->upper[axis] = fmaxf(s->upper[axis], v[axis] + v[3]);
    }
}

static inline void scene_update_bounds(hair_scene *s)
{
    for (int axis = 0; axis < 3; axis++) {
        s->lower[axis] = s->vertex_count ? INFINITY : 0.0f;
        s->upper[axis] = s->vertex_count ? -INFINITY : 0.0f;
    }
    /* A Bezier curve lies in the convex hull of its control points and its
       radius is a convex combination of theirs, so boxes around the control
       points enclose the swept tube. Catmull-Rom points are not such a hull
       (the Bezier points lie outside theirs where a strand bends), so those
       scenes bound each segment's Bezier form. */
    if (s->basis == SCENE_BASIS_CATMULL_ROM) {
        /* comparisons, not fminf/fmaxf calls: a third of the time of scene_yeti at 153M segments */
        float lower[3] = {INFINITY, INFINITY, INFINITY}, upper[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (size_t i = 0; i < s->segment_count; i++) {
            float bezier[16];
            scene_segment_bezier(s, i, bezier);
            for (int j = 0; j < 4; j++)
                for (int axis = 0; axis < 3; axis++) {
                    float low = bezier[4 * j + axis] - bezier[4 * j + 3], high = bezier[4 * j + axis] + bezier[4 * j + 3];
                    lower[axis] = low < lower[axis] ? low : lower[axis];
                    upper[axis] = high > upper[axis] ? high : upper[axis];
                }
        }
        for (int axis = 0; axis < 3; axis++) {
            s->lower[axis] = s->segment_count ? lower[axis] : 0.0f;
            s->upper[axis] = s->segment_count ? upper[axis] : 0.0f;
        }
        return;
    }
    for (size_t i = 0; i < s->vertex_count; i++)
        scene_expand_bounds(s, s->vertices + 4 * i);
}

/* dst = src's segments as independent Bezier segments (scene_alloc's
   layout, 64 bytes a segment): what the reference and other Bezier-only
   code read. Returns 0, or 1 when out of memory (dst then empty). */
static inline int scene_to_bezier(const hair_scene *src, hair_scene *dst)
{
    if (scene_alloc(dst, src->segment_count, src->name) != 0)
        return 1;
    for (size_t i = 0; i < src->segment_count; i++)
        scene_segment_bezier(src, i, dst->vertices + 16 * i);
    scene_update_bounds(dst);
    return 0;
}

/* ------------------------------------------------------------------------ */
/* Polylines to Bezier segments */

/* Uniform Catmull-Rom: each segment interpolates its two polyline points and
   the tangents match at joints (C1), on all four components. End points are
   repeated (p[-1] = p[0], p[n] = p[n-1]). Radii that overshoot below zero are
   clamped. Strands of fewer than 2 points give no segments. Returns nonzero
   for no segments at all, non-finite input or out of memory. */
static inline int scene_from_polylines(hair_scene *s, const float *points_xyzr,
                                       const uint32_t *points_per_strand, size_t strand_count,
                                       const char *name)
{
    memset(s, 0, sizeof *s);
    size_t segment_count = 0, point_count = 0;
    for (size_t k = 0; k < strand_count; k++) {
        point_count += points_per_strand[k];
        if (points_per_strand[k] >= 2)
            segment_count += points_per_strand[k] - 1;
    }
    for (size_t i = 0; i < 4 * point_count; i++)
        if (!isfinite(points_xyzr[i]))
            return 1;
    if (scene_alloc(s, segment_count, name) != 0)
        return 1;

    size_t segment = 0;
    const float *strand = points_xyzr;
    for (size_t k = 0; k < strand_count; k++) {
        size_t n = points_per_strand[k];
        for (size_t i = 0; i + 1 < n; i++) {
            const float *before = strand + 4 * (i > 0 ? i - 1 : 0);
            const float *start = strand + 4 * i;
            const float *end = strand + 4 * (i + 1);
            const float *after = strand + 4 * (i + 2 < n ? i + 2 : n - 1);
            scene_catmull_rom_bezier(before, start, end, after, s->vertices + 16 * segment);
            segment++;
        }
        strand += 4 * n;
    }
    scene_update_bounds(s);
    return 0;
}

static inline void scene_put_point(float *point, scene_vec3 p, float radius)
{
    point[0] = p.x; point[1] = p.y; point[2] = p.z; point[3] = radius;
}

/* Shared tail of the strand generators: strand_count strands of the same
   point count, filled by the caller, converted by Catmull-Rom. */
typedef struct scene_strands {
    float *points;
    uint32_t *counts;
    size_t strand_count, points_per_strand;
} scene_strands;

static inline int scene_strands_alloc(scene_strands *st, size_t strand_count, size_t points_per_strand)
{
    st->strand_count = strand_count;
    st->points_per_strand = points_per_strand;
    st->points = (float *)malloc(strand_count * points_per_strand * 4 * sizeof(float));
    st->counts = (uint32_t *)malloc(strand_count * sizeof(uint32_t));
    if (!st->points || !st->counts) {
        free(st->points);
        free(st->counts);
        return 1;
    }
    for (size_t k = 0; k < strand_count; k++)
        st->counts[k] = (uint32_t)points_per_strand;
    return 0;
}

static inline int scene_strands_finish(scene_strands *st, hair_scene *s, const char *name)
{
    int result = scene_from_polylines(s, st->points, st->counts, st->strand_count, name);
    free(st->points);
    free(st->counts);
    return result;
}

static inline size_t scene_strand_count_for(size_t target_segments, size_t segments_per_strand)
{
    size_t strands = (target_segments + segments_per_strand / 2) / segments_per_strand;
    return strands > 0 ? strands : 1;
}

/* ------------------------------------------------------------------------ */
/* Motion blur: a scene's control points at time_steps times tau = k / (time_steps - 1). */

typedef enum scene_motion {
    SCENE_MOTION_ROTATE,     /* each strand swept by amount * tau radians about the line through its root
                                along the direction from the scene's centre to the root (the sphere's normal) */
    SCENE_MOTION_TRANSLATE   /* every point moved by amount * tau along (1, 0.5, 0.25) normalised */
} scene_motion;

static inline void scene_motion_free(float **steps, int time_steps)
{
    for (int k = 0; k < time_steps; k++) {
        free(steps[k]);
        steps[k] = NULL;
    }
}

/* Whether Bezier segment i starts a strand: its first point is not the
   previous segment's last (independent Bezier segments of a polyline
   repeat the joint). */
static inline int scene_bezier_starts_strand(const hair_scene *s, size_t i)
{
    return i == 0 || memcmp(s->vertices + 4 * (size_t)s->indices[i], s->vertices + 4 * (size_t)s->indices[i - 1] + 12,
                            3 * sizeof(float)) != 0;
}

/* Fills steps[0..time_steps) with arrays of s->vertex_count points (16-byte
   aligned, with the scene's 16 bytes of defined padding): step 0 is the
   scene as it is, radii are kept. A strand starts where
   scene_bezier_starts_strand says. Rotations are done in double. Returns 0, or
   1 when out of memory (nothing left allocated). */
static inline int scene_motion_steps(const hair_scene *s, scene_motion motion, double amount, int time_steps, float **steps)
{
    double centre[3];
    for (int a = 0; a < 3; a++) centre[a] = 0.5 * ((double)s->lower[a] + (double)s->upper[a]);
    for (int k = 0; k < time_steps; k++) {
        void *p = NULL;
        steps[k] = NULL;
        if (posix_memalign(&p, 16, s->vertex_count * 4 * sizeof(float) + 16) != 0) {
            scene_motion_free(steps, k);
            return 1;
        }
        steps[k] = (float *)p;
        memcpy(steps[k], s->vertices, s->vertex_count * 4 * sizeof(float) + 16);
    }
    if (motion == SCENE_MOTION_TRANSLATE) {
        const double d[3] = {1.0 / 1.1456439237389600, 0.5 / 1.1456439237389600, 0.25 / 1.1456439237389600};
        for (int k = 1; k < time_steps; k++) {
            double tau = (double)k / (time_steps - 1);
            for (size_t i = 0; i < s->vertex_count; i++)
                for (int a = 0; a < 3; a++)
                    steps[k][4 * i + a] = (float)((double)s->vertices[4 * i + a] + amount * tau * d[a]);
        }
        return 0;
    }
    const float *root = NULL;
    for (size_t i = 0; i < s->segment_count; i++) {
        const float *first = s->vertices + 4 * (size_t)s->indices[i];
        if (scene_bezier_starts_strand(s, i)) root = first;
        double axis[3], length = 0.0;
        for (int a = 0; a < 3; a++) {
            axis[a] = (double)root[a] - centre[a];
            length += axis[a] * axis[a];
        }
        length = sqrt(length);
        for (int a = 0; a < 3; a++) axis[a] = length > 0.0 ? axis[a] / length : (a == 2);
        for (int k = 1; k < time_steps; k++) {
            double angle = amount * (double)k / (time_steps - 1), c = cos(angle), sn = sin(angle);
            for (int j = 0; j < 4; j++) {
                const float *v = first + 4 * j;
                float *out = steps[k] + 4 * (size_t)s->indices[i] + 4 * j;
                double q[3] = {(double)v[0] - root[0], (double)v[1] - root[1], (double)v[2] - root[2]};
                double along = axis[0] * q[0] + axis[1] * q[1] + axis[2] * q[2];
                double cross[3] = {axis[1] * q[2] - axis[2] * q[1], axis[2] * q[0] - axis[0] * q[2], axis[0] * q[1] - axis[1] * q[0]};
                /* Rodrigues: q c + (axis x q) s + axis (axis . q)(1 - c) */
                for (int a = 0; a < 3; a++)
                    out[a] = (float)((double)root[a] + q[a] * c + cross[a] * sn + axis[a] * along * (1.0 - c));
            }
        }
    }
    return 0;
}

/* ------------------------------------------------------------------------ */
/* Procedural scenes. Each has about target_segments segments and depends only
   on (target_segments, seed). Return 0 on success. */

/* The comb field at a root of the given normal: toward `toward` within the
   tangent plane plus half a swirl about swirl_axis (both terms shrink to
   zero at the poles, but their direction stays smooth; at the exact pole
   any tangent will do), then a random twist of up to 0.15 rad per strand. */
static inline scene_vec3 scene_comb_direction(scene_vec3 normal, scene_vec3 toward, scene_vec3 swirl_axis, scene_rng *rng)
{
    scene_vec3 along = scene_v3_sub(toward, scene_v3_scale(normal, scene_v3_dot(normal, toward)));
    scene_vec3 swirl = scene_v3_cross(swirl_axis, normal);
    scene_vec3 comb = scene_v3_add(along, scene_v3_scale(swirl, 0.5f));
    comb = scene_v3_length(comb) > 1e-6f ? scene_v3_normalize(comb) : scene_v3_perpendicular(normal);
    float twist = scene_rng_range(rng, -0.15f, 0.15f);
    scene_vec3 side = scene_v3_cross(normal, comb);
    return scene_v3_add(scene_v3_scale(comb, cosf(twist)), scene_v3_scale(side, sinf(twist)));
}

/* Combed fur on the unit sphere: 8 segments per strand, 0.3-0.5 long, leaving
   the surface 17-29 degrees off the normal and bending over, mostly near the
   root, to 77-86 degrees (nearly flat) toward a smooth comb field
   (down the meridians with a swirl around the y axis), so neighbours lie
   alike and strands run diagonally to the coordinate axes. Radius 0.004 at
   the root (+-15% per strand) tapering to 0.001 at the tip. */
static inline int scene_combed(hair_scene *s, size_t target_segments, uint64_t seed)
{
    enum { SEGMENTS = 8 };
    scene_rng rng;
    scene_rng_seed(&rng, seed);
    scene_strands st;
    size_t strand_count = scene_strand_count_for(target_segments, SEGMENTS);
    if (scene_strands_alloc(&st, strand_count, SEGMENTS + 1) != 0) {
        memset(s, 0, sizeof *s);
        return 1;
    }
    const scene_vec3 down = scene_v3(0, -1, 0), up = scene_v3(0, 1, 0);
    for (size_t k = 0; k < strand_count; k++) {
        scene_vec3 normal = scene_sphere_root(k, strand_count, &rng);
        scene_vec3 comb = scene_comb_direction(normal, down, up, &rng);

        float length = scene_rng_range(&rng, 0.3f, 0.5f);
        float bend_root = scene_rng_range(&rng, 0.3f, 0.5f);
        float bend_tip = scene_rng_range(&rng, 1.35f, 1.5f);
        float radius_root = 0.004f * scene_rng_range(&rng, 0.85f, 1.15f);
        const float radius_tip = 0.001f;
        float step = length / SEGMENTS;

        float *points = st.points + 4 * (SEGMENTS + 1) * k;
        scene_vec3 p = normal; /* root on the unit sphere */
        scene_put_point(points, p, radius_root);
        for (int i = 1; i <= SEGMENTS; i++) {
            /* Directions stay in the root's normal/comb plane: as the sphere
               curves away below that plane, the strand never dips inside it. */
            float along = ((float)i - 0.5f) / SEGMENTS;
            float bent = 1.0f - (1.0f - along) * (1.0f - along); /* most bending near the root */
            float angle = bend_root + (bend_tip - bend_root) * bent;
            scene_vec3 direction = scene_v3_add(scene_v3_scale(normal, cosf(angle)),
                                                scene_v3_scale(comb, sinf(angle)));
            p = scene_v3_add(p, scene_v3_scale(direction, step));
            float t = (float)i / SEGMENTS;
            scene_put_point(points + 4 * i, p, radius_root + (radius_tip - radius_root) * t);
        }
    }
    return scene_strands_finish(&st, s, "combed");
}

/* Curly hair on the unit sphere: helices around the (slightly drooping)
   normal, 24 segments for 3.5-4.5 turns (5-7 segments per turn), helix radius
   0.03-0.045 growing from zero over the first turn so strands leave their
   root, pitch 0.05-0.07, either handedness. Radius 0.003 tapering to 0.0012. */
static inline int scene_curly(hair_scene *s, size_t target_segments, uint64_t seed)
{
    enum { SEGMENTS = 24 };
    scene_rng rng;
    scene_rng_seed(&rng, seed);
    scene_strands st;
    size_t strand_count = scene_strand_count_for(target_segments, SEGMENTS);
    if (scene_strands_alloc(&st, strand_count, SEGMENTS + 1) != 0) {
        memset(s, 0, sizeof *s);
        return 1;
    }
    const scene_vec3 down = scene_v3(0, -1, 0);
    for (size_t k = 0; k < strand_count; k++) {
        scene_vec3 root = scene_sphere_root(k, strand_count, &rng);
        scene_vec3 meridian = scene_v3_sub(down, scene_v3_scale(root, scene_v3_dot(root, down)));
        scene_vec3 axis = scene_v3_normalize(scene_v3_add(root, scene_v3_scale(meridian, 0.3f)));
        scene_vec3 u = scene_v3_perpendicular(axis);
        scene_vec3 v = scene_v3_cross(axis, u);

        float turns = scene_rng_range(&rng, 3.5f, 4.5f);
        float pitch = scene_rng_range(&rng, 0.05f, 0.07f);
        float helix_radius = scene_rng_range(&rng, 0.03f, 0.045f);
        float phase = scene_rng_range(&rng, 0.0f, 6.28318531f);
        float handedness = scene_rng_float(&rng) < 0.5f ? -1.0f : 1.0f;
        const float radius_root = 0.003f, radius_tip = 0.0012f;

        float *points = st.points + 4 * (SEGMENTS + 1) * k;
        for (int i = 0; i <= SEGMENTS; i++) {
            float t = (float)i / SEGMENTS;
            float turn = turns * t;
            float ramp = turn < 1.0f ? turn : 1.0f;
            float angle = phase + handedness * 6.28318531f * turn;
            scene_vec3 centre = scene_v3_add(root, scene_v3_scale(axis, pitch * turn));
            scene_vec3 offset = scene_v3_add(scene_v3_scale(u, cosf(angle)), scene_v3_scale(v, sinf(angle)));
            scene_vec3 p = scene_v3_add(centre, scene_v3_scale(offset, helix_radius * ramp));
            scene_put_point(points + 4 * i, p, radius_root + (radius_tip - radius_root) * t);
        }
    }
    return scene_strands_finish(&st, s, "curly");
}

/* Three bundles of strongly bent segments (1 long, the middle bent out by
   0.05-0.2 in a random direction) along the x, y and z axes, all crossing
   one small region (centres within +-0.2): object splits cannot separate
   them, so spatial splits clip and clusters by orientation pay. Radius
   0.002 growing to 0.005 along each segment. */
static inline int scene_crossed(hair_scene *s, size_t n, uint64_t seed)
{
    scene_rng rng;
    size_t i;
    if (scene_alloc(s, n, "crossed") != 0) return 1;
    scene_rng_seed(&rng, seed);
    for (i = 0; i < n; ++i) {
        float *v = s->vertices + 16 * i, o[3], e[3], len;
        int axis = (int)(i % 3), k, j;
        float bend = scene_rng_range(&rng, 0.05f, 0.2f);
        for (k = 0; k < 3; ++k) {
            o[k] = scene_rng_range(&rng, -0.2f, 0.2f);
            e[k] = scene_rng_range(&rng, -1.0f, 1.0f);
        }
        e[axis] = 0.0f;
        len = sqrtf(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
        if (!(len > 1e-3f)) { e[(axis + 1) % 3] = 1.0f; len = 1.0f; }
        for (k = 0; k < 4; ++k) {
            float t = (float)k / 3.0f - 0.5f, w = (k == 1 || k == 2) ? bend / 0.75f : 0.0f;
            for (j = 0; j < 3; ++j) v[4 * k + j] = o[j] + (j == axis ? t : 0.0f) + w * e[j] / len;
            v[4 * k + 3] = 0.002f + 0.001f * (float)k;
        }
    }
    scene_update_bounds(s);
    return 0;
}

/* Unconnected short curved segments in the box [-0.5, 0.5]^3: random centre
   and direction, length 0.02-0.06, a bend of up to 35% of the length whose
   plane twists along the segment, radius 0.0005-0.0012 with one end up to 2x
   thinner. The density grows with target_segments (about 5 layers deep at
   100k), which makes this the stress test for overlapping boxes. */
static inline int scene_random(hair_scene *s, size_t target_segments, uint64_t seed)
{
    if (target_segments == 0)
        target_segments = 1;
    if (scene_alloc(s, target_segments, "random") != 0)
        return 1;
    scene_rng rng;
    scene_rng_seed(&rng, seed);
    const float margin = 0.06f; /* half the longest segment plus its bend */
    for (size_t i = 0; i < s->segment_count; i++) {
        scene_vec3 centre = scene_v3(scene_rng_range(&rng, -0.5f + margin, 0.5f - margin),
                                     scene_rng_range(&rng, -0.5f + margin, 0.5f - margin),
                                     scene_rng_range(&rng, -0.5f + margin, 0.5f - margin));
        scene_vec3 direction = scene_random_unit_vector(&rng);
        scene_vec3 u = scene_v3_perpendicular(direction);
        scene_vec3 v = scene_v3_cross(direction, u);
        float length = scene_rng_range(&rng, 0.02f, 0.06f);
        /* A Bezier curve's midpoint moves by 3/4 of a common offset of P1 and
           P2, so offset them by bend / 0.75. */
        float bend = length * scene_rng_range(&rng, 0.0f, 0.35f) / 0.75f;
        float angle1 = scene_rng_range(&rng, 0.0f, 6.28318531f);
        float angle2 = angle1 + scene_rng_range(&rng, -1.5f, 1.5f);
        scene_vec3 offset1 = scene_v3_add(scene_v3_scale(u, bend * cosf(angle1)), scene_v3_scale(v, bend * sinf(angle1)));
        scene_vec3 offset2 = scene_v3_add(scene_v3_scale(u, bend * cosf(angle2)), scene_v3_scale(v, bend * sinf(angle2)));
        scene_vec3 p0 = scene_v3_sub(centre, scene_v3_scale(direction, 0.5f * length));
        scene_vec3 p3 = scene_v3_add(centre, scene_v3_scale(direction, 0.5f * length));
        scene_vec3 p1 = scene_v3_add(scene_v3_add(p0, scene_v3_scale(direction, length / 3.0f)), offset1);
        scene_vec3 p2 = scene_v3_add(scene_v3_sub(p3, scene_v3_scale(direction, length / 3.0f)), offset2);
        float r0 = scene_rng_range(&rng, 0.0005f, 0.0012f);
        float r3 = r0 * scene_rng_range(&rng, 0.5f, 1.0f);
        float *control = s->vertices + 16 * i;
        scene_put_point(control + 0, p0, r0);
        scene_put_point(control + 4, p1, (2.0f * r0 + r3) / 3.0f);
        scene_put_point(control + 8, p2, (r0 + 2.0f * r3) / 3.0f);
        scene_put_point(control + 12, p3, r3);
    }
    scene_update_bounds(s);
    return 0;
}

/* Two layers of parallel strands crossing at 90 degrees, like a woven
   screen: strands 2 long run along (1,1,0) in the layer at z = +gap/2 and
   along (1,-1,0) at z = -gap/2, i.e. diagonal to the axes, where
   axis-aligned boxes fit worst. Each layer has n strands of m segments with
   n ~ 6m (segments ~10 diameters long); radius 0.3 x spacing (+-10%), so each
   layer covers ~60% of its area; gentle in-plane and out-of-plane waves
   (0.25 spacing, 0.8 radius) and a jitter of +-0.1 spacing keep them
   straight-ish without touching. */
static inline int scene_crossing(hair_scene *s, size_t target_segments, uint64_t seed)
{
    size_t segments = (size_t)(sqrt((double)target_segments / 12.0) + 0.5);
    if (segments < 2)
        segments = 2;
    size_t per_layer = scene_strand_count_for(target_segments, 2 * segments);
    scene_rng rng;
    scene_rng_seed(&rng, seed);
    scene_strands st;
    if (scene_strands_alloc(&st, 2 * per_layer, segments + 1) != 0) {
        memset(s, 0, sizeof *s);
        return 1;
    }
    const float half_length = 1.0f, half_width = 1.0f;
    const float spacing = 2.0f * half_width / (float)per_layer;
    const float radius = 0.3f * spacing;
    const float gap = 6.0f * radius;
    const float diagonal = 0.70710678f;
    for (size_t k = 0; k < 2 * per_layer; k++) {
        int layer = k < per_layer ? 0 : 1;
        size_t j = k % per_layer;
        scene_vec3 along = scene_v3(diagonal, layer ? -diagonal : diagonal, 0);
        scene_vec3 across = scene_v3(layer ? diagonal : -diagonal, diagonal, 0);
        float depth = layer ? -0.5f * gap : 0.5f * gap;
        float offset = -half_width + ((float)j + 0.5f) * spacing + scene_rng_range(&rng, -0.1f, 0.1f) * spacing;
        float strand_radius = radius * scene_rng_range(&rng, 0.9f, 1.1f);
        float waves = scene_rng_range(&rng, 0.5f, 1.5f);
        float wave_phase = scene_rng_range(&rng, 0.0f, 6.28318531f);
        float depth_phase = scene_rng_range(&rng, 0.0f, 6.28318531f);
        float *points = st.points + 4 * (segments + 1) * k;
        for (size_t i = 0; i <= segments; i++) {
            float t = (float)i / (float)segments;
            float wave = 6.28318531f * waves * t;
            float lateral = offset + 0.25f * spacing * sinf(wave + wave_phase);
            float z = depth + 0.8f * strand_radius * sinf(wave + depth_phase);
            scene_vec3 p = scene_v3_add(scene_v3_scale(along, (2.0f * t - 1.0f) * half_length),
                                        scene_v3_scale(across, lateral));
            p.z = z;
            scene_put_point(points + 4 * i, p, strand_radius);
        }
    }
    return scene_strands_finish(&st, s, "crossing");
}

/* Yeti-class fur, held as a renderer holds it: Catmull-Rom strands whose
   control points are shared along each strand (s->basis =
   SCENE_BASIS_CATMULL_ROM; no Bezier form is made: at 153M segments it
   would take 9.8 GB). SCENE_YETI_SEGMENTS = 16 segments a strand through 17
   points, plus a point extrapolated before the root and one after the tip
   (so the end segments keep their chord's direction): 19 points a strand,
   1.19 a segment; indices[i] is the first of segment i's 4 points.
   The body is a capsule (radius 0.5, a cylinder 1.5 long between two
   hemispheres) lying along the diagonal (0.8, 0.3, -0.5) normalised,
   rather than combed's ball: an animal's torso, whose long side the camera
   sees, and whose fur runs diagonally to the coordinate axes. Roots cover
   it evenly: a golden-angle spiral taken uniformly along the axis (by
   Archimedes' hat-box theorem a sphere's zone has the area of the cylinder
   of its height, so uniform heights are uniform area) with a jitter of
   half the spacing. Strands are combed like scene_combed's: 0.15-0.25 long,
   leaving the skin 17-29 degrees off its normal and bending over to 77-86
   degrees toward a comb field from head to tail (toward -axis) with a
   swirl about the axis, twisted +-0.15 rad per strand. The radius scales
   with the root spacing, so the fur covers the skin alike at every size:
   0.25 spacing at the root (+-15% per strand) tapering to 0.0625 at the tip.
   Memory: 16 bytes a point and 4 an index, nothing else. Point numbers must
   fit uint32 (up to 3.6G segments); sizes are size_t. Returns 0, or 1 when
   out of memory or too large. */
enum { SCENE_YETI_SEGMENTS = 16, SCENE_YETI_POINTS = SCENE_YETI_SEGMENTS + 3 };

static inline scene_vec3 scene_capsule_closest_axis_point(scene_vec3 p, scene_vec3 axis, float half_length)
{
    float along = scene_v3_dot(p, axis);
    along = along < -half_length ? -half_length : along > half_length ? half_length : along;
    return scene_v3_scale(axis, along);
}

static inline int scene_yeti(hair_scene *s, size_t target_segments, uint64_t seed)
{
    enum { SEGMENTS = SCENE_YETI_SEGMENTS, POINTS = SCENE_YETI_POINTS };
    const float body_radius = 0.5f, half_length = 0.75f;
    const double golden_turn = 0.38196601125010515; /* the golden angle in turns: 2 - golden ratio */
    memset(s, 0, sizeof *s);
    /* scene_strand_count_for's rounding, without its overflow near SIZE_MAX */
    size_t strand_count = target_segments / SEGMENTS + (target_segments % SEGMENTS >= SEGMENTS / 2);
    strand_count = strand_count > 0 ? strand_count : 1;
    if (strand_count > UINT32_MAX / POINTS || strand_count > SIZE_MAX / (POINTS * 16) - 1)
        return 1;
    size_t point_count = strand_count * POINTS, segment_count = strand_count * SEGMENTS;
    void *vertices = NULL;
    if (posix_memalign(&vertices, 16, point_count * 4 * sizeof(float) + 16) != 0)
        return 1;
    s->vertices = (float *)vertices;
    memset(s->vertices + 4 * point_count, 0, 16); /* defined padding: Embree reads 16 bytes past the end */
    s->indices = (uint32_t *)malloc(segment_count * sizeof(uint32_t));
    if (!s->indices) {
        scene_free(s);
        return 1;
    }
    s->vertex_count = point_count;
    s->segment_count = segment_count;
    s->basis = SCENE_BASIS_CATMULL_ROM;
    scene_set_name(s, "yeti");

    const scene_vec3 axis = scene_v3_normalize(scene_v3(0.8f, 0.3f, -0.5f));
    const scene_vec3 axis_u = scene_v3_perpendicular(axis), axis_v = scene_v3_cross(axis, axis_u);
    const scene_vec3 tail = scene_v3_scale(axis, -1.0f);
    const float extent = half_length + body_radius; /* roots' axial coordinates span [-extent, extent] */
    const float area = 2.0f * 3.14159265f * body_radius * (2.0f * extent);
    const float spacing = sqrtf(area / (float)strand_count);
    scene_rng rng;
    scene_rng_seed(&rng, seed);
    for (size_t k = 0; k < strand_count; k++) {
        /* the root: height and angle from the spiral, jittered, put back on the skin */
        /* in double: k reaches tens of millions, past float's integers and its angles' precision */
        float height = (float)(-extent + 2.0 * extent * ((double)k + 0.5) / (double)strand_count);
        double turns = (double)k * golden_turn;
        float phi = (float)(6.283185307179586 * (turns - floor(turns)));
        float cap = fabsf(height) - half_length;
        float ring = cap > 0.0f ? sqrtf(fmaxf(0.0f, body_radius * body_radius - cap * cap)) : body_radius;
        scene_vec3 around = scene_v3_add(scene_v3_scale(axis_u, cosf(phi)), scene_v3_scale(axis_v, sinf(phi)));
        scene_vec3 root = scene_v3_add(scene_v3_scale(axis, height), scene_v3_scale(around, ring));
        root = scene_v3_add(root, scene_v3_scale(scene_random_unit_vector(&rng), 0.5f * spacing));
        scene_vec3 centre = scene_capsule_closest_axis_point(root, axis, half_length);
        scene_vec3 normal = scene_v3_sub(root, centre);
        normal = scene_v3_length(normal) > 0.0f ? scene_v3_normalize(normal) : axis_u;
        root = scene_v3_add(centre, scene_v3_scale(normal, body_radius));

        scene_vec3 comb = scene_comb_direction(normal, tail, axis, &rng);

        float length = scene_rng_range(&rng, 0.15f, 0.25f);
        float bend_root = scene_rng_range(&rng, 0.3f, 0.5f);
        float bend_tip = scene_rng_range(&rng, 1.35f, 1.5f);
        float radius_root = 0.25f * spacing * scene_rng_range(&rng, 0.85f, 1.15f);
        const float radius_tip = 0.0625f * spacing;
        float step = length / SEGMENTS;

        /* points[1..SEGMENTS+1] are the strand, root first; points[0] and
           points[SEGMENTS+2] the extrapolated ends */
        float *points = s->vertices + 4 * (size_t)POINTS * k;
        scene_vec3 p = root;
        scene_put_point(points + 4, p, radius_root);
        for (int i = 1; i <= SEGMENTS; i++) {
            /* in the root's normal/comb plane, so the strand never dips into the body */
            float along = ((float)i - 0.5f) / SEGMENTS;
            float bent = 1.0f - (1.0f - along) * (1.0f - along); /* most bending near the root */
            float angle = bend_root + (bend_tip - bend_root) * bent;
            scene_vec3 direction = scene_v3_add(scene_v3_scale(normal, cosf(angle)), scene_v3_scale(comb, sinf(angle)));
            p = scene_v3_add(p, scene_v3_scale(direction, step));
            float t = (float)i / SEGMENTS;
            scene_put_point(points + 4 * (i + 1), p, radius_root + (radius_tip - radius_root) * t);
        }
        for (int c = 0; c < 4; c++) {
            points[c] = 2.0f * points[4 + c] - points[8 + c];
            points[4 * (POINTS - 1) + c] = 2.0f * points[4 * (POINTS - 2) + c] - points[4 * (POINTS - 3) + c];
        }
        uint32_t *indices = s->indices + (size_t)SEGMENTS * k;
        for (int i = 0; i < SEGMENTS; i++)
            indices[i] = (uint32_t)((size_t)POINTS * k + (size_t)i);
    }
    scene_update_bounds(s);
    return 0;
}

/* ------------------------------------------------------------------------ */
/* File loading */

/* Reads a whole stream into a malloc'd buffer (works for pipes, unlike
   fseek/ftell). Returns 0 on success. */
static inline int scene_read_stream(FILE *file, unsigned char **data, size_t *size)
{
    size_t capacity = 1 << 20, used = 0;
    unsigned char *buffer = (unsigned char *)malloc(capacity);
    if (!buffer)
        return 1;
    for (;;) {
        if (used == capacity) {
            unsigned char *bigger = (unsigned char *)realloc(buffer, 2 * capacity);
            if (!bigger) {
                free(buffer);
                return 1;
            }
            buffer = bigger;
            capacity *= 2;
        }
        size_t got = fread(buffer + used, 1, capacity - used, file);
        used += got;
        if (got == 0)
            break;
    }
    if (ferror(file)) {
        free(buffer);
        return 1;
    }
    *data = buffer;
    *size = used;
    return 0;
}

/* Returns 0 on success, -1 if the file does not exist, 1 on other errors. */
static inline int scene_read_file(const char *path, unsigned char **data, size_t *size)
{
    FILE *file = fopen(path, "rb");
    if (!file)
        return errno == ENOENT ? -1 : 1;
    int result = scene_read_stream(file, data, size);
    fclose(file);
    return result;
}

/* The file name without directories and extension, as a scene name. */
static inline void scene_name_from_path(char name[64], const char *path)
{
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    size_t length = strcspn(base, ".");
    if (length > 63)
        length = 63;
    memcpy(name, base, length);
    name[length] = '\0';
}

/* Little-endian decoding by bytes, so loading works on any host. */
static inline uint32_t scene_le_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static inline uint16_t scene_le_u16(const unsigned char *p)
{
    return (uint16_t)(p[0] | p[1] << 8);
}
static inline float scene_le_f32(const unsigned char *p)
{
    uint32_t bits = scene_le_u32(p);
    float value;
    memcpy(&value, &bits, sizeof value);
    return value;
}
/* and encoding, for the tests that write .hair files */
static inline void scene_put_le_u32(unsigned char *p, uint32_t value)
{
    p[0] = (unsigned char)value;
    p[1] = (unsigned char)(value >> 8);
    p[2] = (unsigned char)(value >> 16);
    p[3] = (unsigned char)(value >> 24);
}
static inline void scene_put_le_f32(unsigned char *p, float value)
{
    uint32_t bits;
    memcpy(&bits, &value, sizeof bits);
    scene_put_le_u32(p, bits);
}

/* Cem Yuksel's .hair format: 128-byte header ("HAIR", strand count, point
   count, array flags, default segments, default thickness, default
   transparency, default colour, 88 bytes of text), then the arrays whose
   flags are set: uint16 segments per strand, float3 points, float thickness,
   float transparency, float3 colours. Thickness is a diameter. The file size
   must match the header exactly: anything else means a truncated file or a
   misread header. Returns 0 on success, -1 if the file does not exist,
   1 for any other error. */
enum {
    SCENE_HAIR_HEADER_BYTES = 128,
    SCENE_HAIR_HAS_SEGMENTS = 1,
    SCENE_HAIR_HAS_POINTS = 2,
    SCENE_HAIR_HAS_THICKNESS = 4,
    SCENE_HAIR_HAS_TRANSPARENCY = 8,
    SCENE_HAIR_HAS_COLORS = 16
};

static inline int scene_parse_hair(hair_scene *s, const unsigned char *data, size_t size, const char *name)
{
    if (size < SCENE_HAIR_HEADER_BYTES || memcmp(data, "HAIR", 4) != 0)
        return 1;
    uint32_t strand_count = scene_le_u32(data + 4);
    uint32_t point_count = scene_le_u32(data + 8);
    uint32_t flags = scene_le_u32(data + 12);
    uint32_t default_segments = scene_le_u32(data + 16);
    float default_thickness = scene_le_f32(data + 20);
    if ((flags & ~31u) != 0 || !(flags & SCENE_HAIR_HAS_POINTS))
        return 1;

    /* array offsets, in 64 bits so that huge counts cannot wrap */
    uint64_t offset = SCENE_HAIR_HEADER_BYTES;
    uint64_t segments_at = offset;
    if (flags & SCENE_HAIR_HAS_SEGMENTS)
        offset += 2 * (uint64_t)strand_count;
    uint64_t points_at = offset;
    offset += 12 * (uint64_t)point_count;
    uint64_t thickness_at = offset;
    if (flags & SCENE_HAIR_HAS_THICKNESS)
        offset += 4 * (uint64_t)point_count;
    if (flags & SCENE_HAIR_HAS_TRANSPARENCY)
        offset += 4 * (uint64_t)point_count;
    if (flags & SCENE_HAIR_HAS_COLORS)
        offset += 12 * (uint64_t)point_count;
    if (offset != (uint64_t)size)
        return 1;

    uint32_t *counts = (uint32_t *)malloc((strand_count ? strand_count : 1) * sizeof(uint32_t));
    if (!counts)
        return 1;
    uint64_t points_in_strands = 0;
    for (uint32_t k = 0; k < strand_count; k++) {
        uint32_t segments = (flags & SCENE_HAIR_HAS_SEGMENTS) ? scene_le_u16(data + segments_at + 2 * (uint64_t)k)
                                                              : default_segments;
        counts[k] = segments + 1;
        points_in_strands += (uint64_t)segments + 1;
    }
    if (points_in_strands != point_count) {
        free(counts);
        return 1;
    }

    float *points = (float *)malloc(((size_t)point_count ? point_count : 1) * 4 * sizeof(float));
    if (!points) {
        free(counts);
        return 1;
    }
    for (size_t i = 0; i < point_count; i++) {
        for (int c = 0; c < 3; c++)
            points[4 * i + c] = scene_le_f32(data + points_at + 12 * i + 4 * (size_t)c);
        float thickness = (flags & SCENE_HAIR_HAS_THICKNESS) ? scene_le_f32(data + thickness_at + 4 * i)
                                                             : default_thickness;
        points[4 * i + 3] = 0.5f * thickness;
    }
    int result = scene_from_polylines(s, points, counts, strand_count, name);
    free(points);
    free(counts);
    return result;
}

static inline int scene_load_hair(hair_scene *s, const char *path)
{
    memset(s, 0, sizeof *s);
    unsigned char *data = NULL;
    size_t size = 0;
    int result = scene_read_file(path, &data, &size);
    if (result != 0)
        return result;
    char name[64];
    scene_name_from_path(name, path);
    result = scene_parse_hair(s, data, size, name);
    free(data);
    return result;
}

/* Embree's furBall_A model as Debian ships it in embree-tools (see
   furBall_A.xml): after gunzip, uint32 segment start indices at byte 0 and
   float4 vertices right after them; segments are linear, vertex i to i+1. */
#define SCENE_FURBALL_DEFAULT_PATH TEST_DATA_FURBALL_PATH
enum {
    SCENE_FURBALL_SEGMENTS = 455505,
    SCENE_FURBALL_VERTICES = 485872,
    SCENE_FURBALL_VERTICES_AT = 4 * SCENE_FURBALL_SEGMENTS /* byte 1,822,020 */
};

/* Runs "gzip -dc" on path: piping through gzip avoids a zlib link dependency. */
static inline int scene_gunzip(const char *path, unsigned char **data, size_t *size)
{
    /* single-quote the path for the shell; a quote inside becomes '\'' */
    size_t length = strlen(path);
    char *command = (char *)malloc(4 * length + 32);
    if (!command)
        return 1;
    char *out = command + sprintf(command, "gzip -dc -- '");
    for (size_t i = 0; i < length; i++) {
        if (path[i] == '\'') {
            memcpy(out, "'\\''", 4);
            out += 4;
        } else {
            *out++ = path[i];
        }
    }
    strcpy(out, "'");
    FILE *pipe = popen(command, "r");
    free(command);
    if (!pipe)
        return 1;
    int result = scene_read_stream(pipe, data, size);
    if (pclose(pipe) != 0 && result == 0) { /* gzip failed: corrupt or not gzip */
        free(*data);
        result = 1;
    }
    return result;
}

/* Strands are runs of consecutive segment indices; each becomes a polyline
   and is converted by Catmull-Rom like every other scene. Returns 0 on
   success, -1 if the file does not exist (callers skip), 1 on errors.
   path NULL = SCENE_FURBALL_DEFAULT_PATH. */
static inline int scene_load_furball(hair_scene *s, const char *path)
{
    memset(s, 0, sizeof *s);
    if (!path)
        path = SCENE_FURBALL_DEFAULT_PATH;
    FILE *probe = fopen(path, "rb"); /* tell "absent" from "broken" before running gzip */
    if (!probe)
        return errno == ENOENT ? -1 : 1;
    fclose(probe);

    unsigned char *data = NULL;
    size_t size = 0;
    if (scene_gunzip(path, &data, &size) != 0)
        return 1;
    const size_t segment_count = SCENE_FURBALL_SEGMENTS, vertex_count = SCENE_FURBALL_VERTICES;
    if (size != SCENE_FURBALL_VERTICES_AT + 16 * vertex_count) {
        free(data);
        return 1;
    }
    const unsigned char *vertices = data + SCENE_FURBALL_VERTICES_AT;

    /* first pass: validate, count strands */
    size_t strand_count = 0;
    for (size_t k = 0; k < segment_count; k++) {
        uint32_t first = scene_le_u32(data + 4 * k);
        if ((size_t)first + 1 >= vertex_count) {
            free(data);
            return 1;
        }
        if (k == 0 || first != scene_le_u32(data + 4 * (k - 1)) + 1)
            strand_count++;
    }
    size_t point_count = segment_count + strand_count;
    float *points = (float *)malloc(point_count * 4 * sizeof(float));
    uint32_t *counts = (uint32_t *)malloc(strand_count * sizeof(uint32_t));
    if (!points || !counts) {
        free(points);
        free(counts);
        free(data);
        return 1;
    }
    /* second pass: a strand's points are its first segment's start vertex,
       then the end vertex of each segment */
    size_t point = 0, strand = 0;
    for (size_t k = 0; k < segment_count; k++) {
        uint32_t first = scene_le_u32(data + 4 * k);
        int starts_strand = k == 0 || first != scene_le_u32(data + 4 * (k - 1)) + 1;
        for (uint32_t v = starts_strand ? first : first + 1; v <= first + 1; v++) {
            for (int c = 0; c < 4; c++)
                points[4 * point + c] = scene_le_f32(vertices + 16 * (size_t)v + 4 * (size_t)c);
            point++;
        }
        if (starts_strand)
            counts[strand++] = 1;
        counts[strand - 1]++;
    }
    free(data);
    int result = scene_from_polylines(s, points, counts, strand_count, "furBall_A");
    free(points);
    free(counts);
    return result;
}

/* ------------------------------------------------------------------------ */
/* Camera, transform, clock */


/* A ray aimed near a random point of the Bezier segment cp (4 control
   points x, y, z, r): u uniform, the target moved by up to 1.5 r(u) on each
   axis, the origin 0.05-1 before it, the direction random but at least 30
   degrees off the tangent there (100 tries). Draws from rng in this order,
   so a test's rays depend only on its seed. */
static inline void scene_ray_near_segment(const float *cp, scene_rng *rng, float org[3], float dir[3])
{
    float u = scene_rng_float(rng), w = 1.0f - u, distance = scene_rng_range(rng, 0.05f, 1.0f);
    float b[4], db[4], radius, tangent[3], length;
    scene_vec3 d;
    int k, tries;
    b[0] = w * w * w; b[1] = 3.0f * u * w * w; b[2] = 3.0f * u * u * w; b[3] = u * u * u;
    db[0] = -3.0f * w * w; db[1] = 3.0f * w * w - 6.0f * u * w; db[2] = 6.0f * u * w - 3.0f * u * u; db[3] = 3.0f * u * u;
    radius = b[0] * cp[3] + b[1] * cp[7] + b[2] * cp[11] + b[3] * cp[15];
    for (k = 0; k < 3; ++k) tangent[k] = db[0] * cp[k] + db[1] * cp[4 + k] + db[2] * cp[8 + k] + db[3] * cp[12 + k];
    length = sqrtf(tangent[0] * tangent[0] + tangent[1] * tangent[1] + tangent[2] * tangent[2]);
    for (tries = 0;; ++tries) {
        d = scene_random_unit_vector(rng);
        if (tries == 100 || !(length > 0.0f) || fabsf(d.x * tangent[0] + d.y * tangent[1] + d.z * tangent[2]) <= 0.866f * length)
            break;
    }
    dir[0] = d.x; dir[1] = d.y; dir[2] = d.z;
    for (k = 0; k < 3; ++k) {
        float target = b[0] * cp[k] + b[1] * cp[4 + k] + b[2] * cp[8 + k] + b[3] * cp[12 + k] +
                       1.5f * radius * scene_rng_range(rng, -1.0f, 1.0f);
        org[k] = target - distance * dir[k];
    }
}

/* Pinhole camera looking at the bounds' centre from +z and a little above
   (direction (0, 0.25, 1)), 2.5 bounding-sphere radii away; the field of view
   is fitted to the projected corners of the bounds (square pixels, 2%
   margin) so the scene fills the image at any scale. Writes width*height
   rays, row-major from the top-left pixel: org and dir 3 floats per ray,
   dir unit length, all origins at the eye. */
static inline void scene_camera_rays(const hair_scene *s, int width, int height, float *org, float *dir)
{
    scene_vec3 lower = scene_v3(s->lower[0], s->lower[1], s->lower[2]);
    scene_vec3 upper = scene_v3(s->upper[0], s->upper[1], s->upper[2]);
    scene_vec3 centre = scene_v3_scale(scene_v3_add(lower, upper), 0.5f);
    float sphere_radius = 0.5f * scene_v3_length(scene_v3_sub(upper, lower));
    if (!(sphere_radius > 0.0f))
        sphere_radius = 1.0f;
    scene_vec3 backward = scene_v3_normalize(scene_v3(0.0f, 0.25f, 1.0f));
    scene_vec3 eye = scene_v3_add(centre, scene_v3_scale(backward, 2.5f * sphere_radius));
    scene_vec3 forward = scene_v3_scale(backward, -1.0f);
    scene_vec3 right = scene_v3_normalize(scene_v3_cross(forward, scene_v3(0, 1, 0)));
    scene_vec3 up = scene_v3_cross(right, forward);

    /* widest angular extent of the 8 corners; all lie in front of the eye
       since it is outside the bounding sphere */
    float aspect = (float)width / (float)height;
    float tan_half_height = 0.0f;
    for (int corner = 0; corner < 8; corner++) {
        scene_vec3 p = scene_v3((corner & 1) ? upper.x : lower.x, (corner & 2) ? upper.y : lower.y,
                                (corner & 4) ? upper.z : lower.z);
        scene_vec3 d = scene_v3_sub(p, eye);
        float depth = scene_v3_dot(d, forward);
        tan_half_height = fmaxf(tan_half_height, fabsf(scene_v3_dot(d, up)) / depth);
        tan_half_height = fmaxf(tan_half_height, fabsf(scene_v3_dot(d, right)) / depth / aspect);
    }
    tan_half_height *= 1.02f;
    float tan_half_width = tan_half_height * aspect;

    for (int y = 0; y < height; y++) {
        for (int x = 0; x < width; x++) {
            float sx = (2.0f * ((float)x + 0.5f) / (float)width - 1.0f) * tan_half_width;
            float sy = (1.0f - 2.0f * ((float)y + 0.5f) / (float)height) * tan_half_height;
            scene_vec3 d = scene_v3_normalize(scene_v3_add(forward, scene_v3_add(scene_v3_scale(right, sx),
                                                                                  scene_v3_scale(up, sy))));
            size_t ray = (size_t)y * (size_t)width + (size_t)x;
            org[3 * ray + 0] = eye.x; org[3 * ray + 1] = eye.y; org[3 * ray + 2] = eye.z;
            dir[3 * ray + 0] = d.x; dir[3 * ray + 1] = d.y; dir[3 * ray + 2] = d.z;
        }
    }
}

/* For stress tests (far from the origin, tiny or huge): scales positions and
   radii by scale about the bounds' centre, then translates by offset.
   A negative scale mirrors the positions; radii use |scale|. */
static inline void scene_transform(hair_scene *s, const float offset[3], float scale)
{
    float centre[3];
    for (int axis = 0; axis < 3; axis++)
        centre[axis] = 0.5f * (s->lower[axis] + s->upper[axis]);
    for (size_t i = 0; i < s->vertex_count; i++) {
        float *v = s->vertices + 4 * i;
        for (int axis = 0; axis < 3; axis++)
            v[axis] = centre[axis] + (v[axis] - centre[axis]) * scale + offset[axis];
        v[3] *= fabsf(scale);
    }
    scene_update_bounds(s);
}

/* Monotonic time in seconds, for timing builds and traversal. */
static inline double scene_now(void)
{
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
}

#endif /* HAIROBB_TESTS_SCENES_H */
