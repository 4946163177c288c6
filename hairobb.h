/* hairobb.h - v0.1.0 - ray tracing of hair and fur with a mixed AABB/OBB BVH
   single-file C library, public domain or MIT (see the end of the file)

   WHAT IT DOES
     Builds a 4-wide (or 8-wide) bounding volume hierarchy over cubic Bezier
     hair segments and intersects rays with them. Groups of neighbouring
     hairs point the same way, so boxes oriented along the hair ("hair space")
     bound them far more tightly than axis-aligned boxes; the builder decides
     per node, by the surface area heuristic, whether an axis-aligned (AABB)
     or an oriented (OBB) node pays (Woop, Benthin, Wald, Johnson, Tabellion,
     HPG 2014).

   HOW TO USE
     In exactly one C or C++ file:
         #define HAIROBB_IMPLEMENTATION
         #include "hairobb.h"
     Everywhere else just #include "hairobb.h".

     float    vertices[] = { x,y,z,radius, x,y,z,radius, ... };   // 4 per segment
     uint32_t indices[]  = { 0, 4, 8, ... };         // first control point of each segment
     hairobb_bvh *bvh;
     hairobb_result res = hairobb_build(vertices, vertex_count, indices, segment_count,
                                        NULL, &bvh);          // NULL: default options
     if (res != HAIROBB_OK) { puts(hairobb_result_string(res)); return 1; }
     hairobb_ray ray = { {0,0,-5}, 0.0f, {0,0,1}, INFINITY };
     hairobb_hit hit;
     if (hairobb_intersect1(bvh, &ray, &hit)) printf("segment %u at t=%g\n", hit.prim_id, hit.t);
     hairobb_free(bvh);

   INPUT
     The vertex and index layout is Embree's curve layout, so a renderer can hand
     the same buffers to either library: vertices are 4 floats per control point
     (x, y, z, radius), indices[i] is the first of the 4 consecutive control
     points of segment i. Position and radius are cubic Bezier curves in u.
     No alignment is required.

     MEMORY LIFETIME: the BVH keeps pointers to the caller's vertex and index
     arrays and reads them while tracing (it copies nothing the caller already
     holds). They must stay alive and unchanged until hairobb_free; to change
     the hair, build again.

   THE SURFACE
     Each segment is a ray-facing ribbon (Embree's "flat" curve). In ray space
     (origin at the ray origin, z along the normalised direction) let P(u) and
     r(u) be the segment's position and radius and P2 = (x, y) the projection.
     The ribbon is hit at u in [0,1] where dot(P2(u), P2'(u)) = 0 and
     |P2(u)| <= r(u); t = z(u)/|dir| (org + t*dir is on the curve's centre line).
     The first hit is the smallest t in [tnear, tfar] over all segments.
     v in [-1,1] is the signed position across the ribbon:
       v = dot(cross(T, X - C), dir/|dir|) / (|T_perp| r(u)),
     T = P'(u), C = P(u), X = org + t*dir, T_perp = T without its component
     along dir. The default intersector finds the roots of dot(P2, P2') with a
     bracketed Newton iteration after a conservative test against 8 linear
     pieces, so its hits agree with this definition up to float rounding.

   BUILD OPTIONS (hairobb_build_options; a zero-initialised struct = defaults)
     nodes                   HAIROBB_NODES_MIXED (default): AABB or OBB per node
                             by SAH; _AABB_ONLY and _OBB_ONLY for comparisons.
     obb_layout              HAIROBB_OBB_PER_CHILD (default): each child box has
                             its own hair space, an affine map onto the unit
                             cube; HAIROBB_OBB_SHARED_ROTATION: the ray is
                             rotated once per node into the node's hair space
                             (176 instead of 240 bytes per 4-wide node; on
                             combed fur, 8-wide: 32% less memory, 14% slower).
     max_leaf_size           segments per leaf at most, 0 = 4, at most 15.
     hair_space_candidates   rotations tried per node (main directions of
                             sampled segments), 0 = 4, at most 16.
     curve_pieces            linear pieces per segment in the intersector's
                             first test, 0 = 8, at most 16 (with the exact
                             precision it changes speed, not the hits).
     precision               HAIROBB_PRECISION_EXACT (default): roots refined to
                             the surface above. HAIROBB_PRECISION_PIECES: the
                             linear pieces alone, faster, less accurate.
     allocator_user          passed to HAIROBB_MALLOC/HAIROBB_FREE.

   HITS
     hairobb_hit: t, u, v as above; Ng the ribbon's unit normal facing the ray
     origin; tangent = P'(u) in world space; prim_id the segment index.
     Every hit with t in [tnear, tfar] counts, including the ribbon a
     secondary ray starts on (unlike Embree, nothing is dropped near t = 0):
     start such rays with tnear a few radii (over |dir|) past 0.

   THREAD SAFETY
     hairobb_intersect1/hairobb_occluded1 only read the BVH: any number of
     threads may trace one BVH at once. There is no global state.

   CONFIGURATION MACROS (define before including the implementation)
     HAIROBB_MALLOC(size, user), HAIROBB_FREE(ptr, user)   allocation; define
                             both or neither. user = options->allocator_user.
     HAIROBB_ASSERT(x)       internal checks, default assert().
     HAIROBB_STATIC          make every function static to the including file.
     HAIROBB_NO_SIMD         plain C everywhere (same answers as the SIMD paths).
     HAIROBB_NODE_WIDTH      children per node, 4 or 8; default 8 where the
                             compiler targets AVX, else 4.
     SSE is used on x86-64; AVX for the 8-wide curve evaluation when the
     compiler targets it (-mavx or -march=...).

   ERRORS
     hairobb_build returns a hairobb_result; hairobb_result_string names it.
     The library never prints and never exits.
*/
#ifndef HAIROBB_H
#define HAIROBB_H

#include <stddef.h>
#include <stdint.h>

#define HAIROBB_VERSION_MAJOR 0
#define HAIROBB_VERSION_MINOR 1
#define HAIROBB_VERSION_PATCH 0
#define HAIROBB_VERSION (HAIROBB_VERSION_MAJOR * 10000 + HAIROBB_VERSION_MINOR * 100 + HAIROBB_VERSION_PATCH)

#if defined(HAIROBB_STATIC) && (defined(__GNUC__) || defined(__clang__))
#define HAIROBB_DEF static __attribute__((unused)) /* a file need not call every function */
#elif defined(HAIROBB_STATIC)
#define HAIROBB_DEF static
#else
#define HAIROBB_DEF extern
#endif

#ifdef __cplusplus
extern "C" {
#endif

typedef enum hairobb_result {
    HAIROBB_OK = 0,
    HAIROBB_ERROR_INVALID_ARGUMENT,   /* NULL pointer, zero segments, bad option value */
    HAIROBB_ERROR_INDEX_OUT_OF_RANGE, /* indices[i] + 3 >= vertex_count */
    HAIROBB_ERROR_INVALID_GEOMETRY,   /* NaN/Inf or |coordinate| > 1e18, negative radius */
    HAIROBB_ERROR_OUT_OF_MEMORY,      /* HAIROBB_MALLOC returned NULL */
    HAIROBB_ERROR_TOO_LARGE           /* counts whose byte sizes overflow, > 2^32-1 segments */
} hairobb_result;

HAIROBB_DEF const char *hairobb_result_string(hairobb_result r);

typedef enum hairobb_node_policy {
    HAIROBB_NODES_MIXED = 0,
    HAIROBB_NODES_AABB_ONLY,
    HAIROBB_NODES_OBB_ONLY
} hairobb_node_policy;

typedef enum hairobb_precision {
    HAIROBB_PRECISION_EXACT = 0,  /* roots of dot(P2,P2') refined: the surface as defined */
    HAIROBB_PRECISION_PIECES      /* linear pieces only (like Embree's flat curves) */
} hairobb_precision;

/* How an OBB node stores its child boxes (sizes for 4-wide nodes). */
typedef enum hairobb_obb_layout {
    HAIROBB_OBB_PER_CHILD = 0,       /* an affine map per child (the paper's uncompressed node): 240 bytes */
    HAIROBB_OBB_SHARED_ROTATION      /* one rotation per node, the boxes in it: 176 bytes */
} hairobb_obb_layout;

typedef struct hairobb_build_options {
    hairobb_node_policy nodes;
    hairobb_obb_layout obb_layout;
    unsigned max_leaf_size;          /* 0 = 4; 1..15 */
    unsigned hair_space_candidates;  /* 0 = 4; 1..16 */
    unsigned curve_pieces;           /* 0 = 8; 1..16 */
    hairobb_precision precision;
    void *allocator_user;
} hairobb_build_options;

typedef struct hairobb_bvh hairobb_bvh;

/* Builds a BVH over segment_count segments. options may be NULL (defaults).
   The BVH keeps pointers to vertices and indices (see MEMORY LIFETIME).
   On failure *out is NULL and nothing is leaked. */
HAIROBB_DEF hairobb_result hairobb_build(const float *vertices, size_t vertex_count,
                                         const uint32_t *indices, size_t segment_count,
                                         const hairobb_build_options *options, hairobb_bvh **out);
HAIROBB_DEF void hairobb_free(hairobb_bvh *bvh);

/* Every byte the BVH allocated (the caller's arrays are not counted). */
HAIROBB_DEF size_t hairobb_memory_bytes(const hairobb_bvh *bvh);

typedef struct hairobb_stats {
    size_t aabb_nodes, obb_nodes, leaves;    /* obb_nodes: either layout */
    size_t leaf_references;   /* segment references in leaves */
    unsigned max_depth;       /* root = 0 */
    size_t node_bytes, leaf_bytes;
} hairobb_stats;
HAIROBB_DEF void hairobb_get_stats(const hairobb_bvh *bvh, hairobb_stats *stats);

/* Bounds of all ribbons, radius included. */
HAIROBB_DEF void hairobb_bounds(const hairobb_bvh *bvh, float lower[3], float upper[3]);

typedef struct hairobb_ray {
    float org[3]; float tnear;
    float dir[3]; float tfar;   /* dir need not be normalised; t is in units of |dir| */
} hairobb_ray;

#define HAIROBB_INVALID_ID 0xffffffffu

typedef struct hairobb_hit {
    float t, u, v;      /* distance, curve parameter, signed position across the ribbon */
    float Ng[3];        /* unit geometric normal of the ribbon, facing the ray origin */
    float tangent[3];   /* dP/du at u in world space, not normalised */
    uint32_t prim_id;   /* segment index, HAIROBB_INVALID_ID on a miss */
} hairobb_hit;

/* 1: nearest hit in [tnear, tfar] written to *hit; 0: miss, hit->prim_id = HAIROBB_INVALID_ID. */
HAIROBB_DEF int hairobb_intersect1(const hairobb_bvh *bvh, const hairobb_ray *ray, hairobb_hit *hit);
/* 1: some segment is hit in [tnear, tfar]; stops at the first one found. */
HAIROBB_DEF int hairobb_occluded1(const hairobb_bvh *bvh, const hairobb_ray *ray);

#ifdef __cplusplus
}
#endif
#endif /* HAIROBB_H */

/* ======================================================================== */
/*                              IMPLEMENTATION                              */
/* ======================================================================== */
#ifdef HAIROBB_IMPLEMENTATION
#ifndef HAIROBB_IMPLEMENTATION_DONE
#define HAIROBB_IMPLEMENTATION_DONE

#include <float.h>
#include <math.h>
#include <string.h>

#if defined(HAIROBB_MALLOC) != defined(HAIROBB_FREE)
#error "define both HAIROBB_MALLOC and HAIROBB_FREE, or neither"
#endif
#ifndef HAIROBB_MALLOC
#include <stdlib.h>
#define HAIROBB_MALLOC(size, user) ((void)(user), malloc(size))
#define HAIROBB_FREE(ptr, user) ((void)(user), free(ptr))
#endif
#ifndef HAIROBB_ASSERT
#include <assert.h>
#define HAIROBB_ASSERT(x) assert(x)
#endif

#if !defined(HAIROBB_NO_SIMD) && (defined(__SSE2__) || defined(_M_X64))
#define HAIROBB__SSE 1
#include <emmintrin.h>
#if defined(__AVX__)
#define HAIROBB__AVX 1
#include <immintrin.h>
#endif
#endif

#ifdef __cplusplus
#define HAIROBB__CAST(type, x) (static_cast<type>(x))
#else
#define HAIROBB__CAST(type, x) ((type)(x))
#endif

/* ------------------------------------------------------------------------ */
/* Limits and cost model                                                     */
/* ------------------------------------------------------------------------ */
#ifndef HAIROBB_NODE_WIDTH             /* children per node: 4 or 8 */
#if HAIROBB__AVX
#define HAIROBB_NODE_WIDTH 8            /* one AVX register per node test */
#else
#define HAIROBB_NODE_WIDTH 4
#endif
#endif
#define HAIROBB__W HAIROBB_NODE_WIDTH
/* A range a full node could not split further becomes a leaf, not a node of
   its own, up to this many segments: -35% memory at equal or better speed
   (combed, straight.hair, furBall_A). */
#define HAIROBB__FULL_NODE_LEAF (HAIROBB__W == 8 ? 3u : 2u)
#define HAIROBB__BINS 16
#define HAIROBB__MAX_PIECES 16
#define HAIROBB__MAX_LEAF 15
#define HAIROBB__MAX_CANDIDATES 16
#define HAIROBB__MAX_COORD 1e18f        /* beyond this, box areas overflow float */
#define HAIROBB__SAH_DEPTH 40           /* deeper nodes split at the median, so depth stays bounded */
#define HAIROBB__STACK ((HAIROBB__W - 1) * (HAIROBB__SAH_DEPTH + 32) + 1)  /* pushes per level x depth */
#define HAIROBB__SAMPLE 64              /* segments sampled to rank hair-space candidates */
/* Relative costs of testing one child box and intersecting one segment.
   An OBB child costs a 3x4 transform of the ray before its slab test. */
#ifndef HAIROBB__COST_AABB
#define HAIROBB__COST_AABB 1.0f
#endif
#ifndef HAIROBB__COST_OBB
#define HAIROBB__COST_OBB 2.0f
#endif
#ifndef HAIROBB__COST_SEGMENT
#define HAIROBB__COST_SEGMENT 4.0f
#endif

/* Node references: low 4 bits type; inner nodes: byte offset (32-aligned);
   leaves: first index into leaf_prims << 8 | count << 4. */
#define HAIROBB__REF_AABB 0u
#define HAIROBB__REF_OBB 1u
#define HAIROBB__REF_LEAF 2u
#define HAIROBB__REF_EMPTY 3u
#define HAIROBB__REF_ROTATED 4u
#define HAIROBB__REF_TYPE(ref) ((unsigned)((ref) & 15u))

/* ------------------------------------------------------------------------ */
/* Small vector helpers                                                      */
/* ------------------------------------------------------------------------ */
static float hairobb__minf(float a, float b) { return a < b ? a : b; }
static float hairobb__maxf(float a, float b) { return a > b ? a : b; }
static float hairobb__dot3(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Rows 0,1 span the plane orthogonal to n (unit), row 2 = n, right-handed
   (row0 x row1 = row2). Branch-free basis of Duff et al. 2017. */
static void hairobb__frame_from_direction(const float n[3], float frame[9])
{
    float sign = n[2] >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n[2]);
    float b = n[0] * n[1] * a;
    frame[0] = 1.0f + sign * n[0] * n[0] * a; frame[1] = sign * b; frame[2] = -sign * n[0];
    frame[3] = b; frame[4] = sign + n[1] * n[1] * a; frame[5] = -n[1];
    frame[6] = n[0]; frame[7] = n[1]; frame[8] = n[2];
}

static void hairobb__identity_frame(float frame[9])
{
    memset(frame, 0, 9 * sizeof(float));
    frame[0] = frame[4] = frame[8] = 1.0f;
}

/* Widens [lower, upper] by 2-4 float ulps of the largest magnitude involved:
   the rounding of the box's own computation. Rounding in the traversal
   scales with the distance from the ray origin to the box (OBBs are stored
   relative to a centre near them) and is covered by HAIROBB__FAR_SCALE. */
static void hairobb__pad_box(float lower[3], float upper[3])
{
    int k;
    for (k = 0; k < 3; ++k) {
        float mag = hairobb__maxf(hairobb__maxf(fabsf(lower[k]), fabsf(upper[k])), upper[k] - lower[k]);
        float pad = mag * (1.0f / 4194304.0f) + 1e-30f;  /* 2^-22 relative: 2-4 ulps */
        lower[k] -= pad;
        upper[k] += pad;
    }
}

static float hairobb__half_area(const float lower[3], const float upper[3])
{
    float dx = upper[0] - lower[0], dy = upper[1] - lower[1], dz = upper[2] - lower[2];
    return dx * dy + dy * dz + dz * dx;
}

static void hairobb__box_empty(float lower[3], float upper[3])
{
    int k;
    for (k = 0; k < 3; ++k) { lower[k] = FLT_MAX; upper[k] = -FLT_MAX; }
}

static void hairobb__box_grow(float lower[3], float upper[3], const float lo[3], const float hi[3])
{
    int k;
    for (k = 0; k < 3; ++k) {
        lower[k] = hairobb__minf(lower[k], lo[k]);
        upper[k] = hairobb__maxf(upper[k], hi[k]);
    }
}

/* Cubic Bezier value and first two derivatives at u. */
static float hairobb__bezier(const float c[4], float u, float *d1, float *d2)
{
    float s = 1.0f - u;
    float e0 = c[1] - c[0], e1 = c[2] - c[1], e2 = c[3] - c[2];
    if (d1) *d1 = 3.0f * (s * s * e0 + 2.0f * u * s * e1 + u * u * e2);
    if (d2) *d2 = 6.0f * (s * (e1 - e0) + u * (e2 - e1));
    return s * s * s * c[0] + 3.0f * u * s * s * c[1] + 3.0f * u * u * s * c[2] + u * u * u * c[3];
}

/* ------------------------------------------------------------------------ */
/* SIMD: 4 or 8 lanes for nodes, 8 for curve points (inline, as a build    */
/* uses only some). Each operation has a plain C twin with the same         */
/* rounding and NaN rule (min(a,b) is a < b ? a : b, as SSE's minps), so    */
/* every path gives the same answers.                                       */
/* ------------------------------------------------------------------------ */
#if HAIROBB__SSE
typedef __m128 hairobb__v4;
static inline hairobb__v4 hairobb__v4_load(const float *p) { return _mm_loadu_ps(p); }
static inline hairobb__v4 hairobb__v4_set1(float x) { return _mm_set1_ps(x); }
static inline hairobb__v4 hairobb__v4_add(hairobb__v4 a, hairobb__v4 b) { return _mm_add_ps(a, b); }
static inline hairobb__v4 hairobb__v4_sub(hairobb__v4 a, hairobb__v4 b) { return _mm_sub_ps(a, b); }
static inline hairobb__v4 hairobb__v4_mul(hairobb__v4 a, hairobb__v4 b) { return _mm_mul_ps(a, b); }
static inline hairobb__v4 hairobb__v4_div(hairobb__v4 a, hairobb__v4 b) { return _mm_div_ps(a, b); }
static inline hairobb__v4 hairobb__v4_min(hairobb__v4 a, hairobb__v4 b) { return _mm_min_ps(a, b); }
static inline hairobb__v4 hairobb__v4_max(hairobb__v4 a, hairobb__v4 b) { return _mm_max_ps(a, b); }
static inline int hairobb__v4_le_bits(hairobb__v4 a, hairobb__v4 b) { return _mm_movemask_ps(_mm_cmple_ps(a, b)); }
static inline void hairobb__v4_store(float *p, hairobb__v4 a) { _mm_storeu_ps(p, a); }
static inline hairobb__v4 hairobb__v4_abs(hairobb__v4 a) { return _mm_andnot_ps(_mm_set1_ps(-0.0f), a); }
/* Rows a..d become columns (moves only). */
static inline void hairobb__v4_transpose(hairobb__v4 *a, hairobb__v4 *b, hairobb__v4 *c, hairobb__v4 *d) { _MM_TRANSPOSE4_PS(*a, *b, *c, *d); }
/* max(max(a0, a2), max(a1, a3)) with max's NaN rule. */
static inline float hairobb__v4_hmax(hairobb__v4 a)
{
    __m128 t = _mm_max_ps(a, _mm_movehl_ps(a, a));
    return _mm_cvtss_f32(_mm_max_ss(t, _mm_shuffle_ps(t, t, 1)));
}
/* x, or +-tiny where |x| < tiny: keeps 1/x finite for directions parallel to a slab. */
static inline hairobb__v4 hairobb__v4_nonzero(hairobb__v4 x, float tiny)
{
    __m128 sign = _mm_and_ps(x, _mm_set1_ps(-0.0f));
    __m128 small = _mm_cmplt_ps(_mm_andnot_ps(_mm_set1_ps(-0.0f), x), _mm_set1_ps(tiny));
    __m128 replacement = _mm_or_ps(sign, _mm_set1_ps(tiny));
    return _mm_or_ps(_mm_and_ps(small, replacement), _mm_andnot_ps(small, x));
}
#else
typedef struct hairobb__v4 { float f[4]; } hairobb__v4;
#define HAIROBB__V4_MAP(expr) hairobb__v4 r; int i; for (i = 0; i < 4; ++i) r.f[i] = (expr); return r
static inline hairobb__v4 hairobb__v4_load(const float *p) { HAIROBB__V4_MAP(p[i]); }
static inline hairobb__v4 hairobb__v4_set1(float x) { HAIROBB__V4_MAP(x); }
static inline hairobb__v4 hairobb__v4_add(hairobb__v4 a, hairobb__v4 b) { HAIROBB__V4_MAP(a.f[i] + b.f[i]); }
static inline hairobb__v4 hairobb__v4_sub(hairobb__v4 a, hairobb__v4 b) { HAIROBB__V4_MAP(a.f[i] - b.f[i]); }
static inline hairobb__v4 hairobb__v4_mul(hairobb__v4 a, hairobb__v4 b) { HAIROBB__V4_MAP(a.f[i] * b.f[i]); }
static inline hairobb__v4 hairobb__v4_div(hairobb__v4 a, hairobb__v4 b) { HAIROBB__V4_MAP(a.f[i] / b.f[i]); }
static inline hairobb__v4 hairobb__v4_min(hairobb__v4 a, hairobb__v4 b) { HAIROBB__V4_MAP(a.f[i] < b.f[i] ? a.f[i] : b.f[i]); }
static inline hairobb__v4 hairobb__v4_max(hairobb__v4 a, hairobb__v4 b) { HAIROBB__V4_MAP(a.f[i] > b.f[i] ? a.f[i] : b.f[i]); }
static inline hairobb__v4 hairobb__v4_nonzero(hairobb__v4 x, float tiny)
{
    HAIROBB__V4_MAP(fabsf(x.f[i]) < tiny ? (signbit(x.f[i]) ? -tiny : tiny) : x.f[i]);
}
#undef HAIROBB__V4_MAP
static inline int hairobb__v4_le_bits(hairobb__v4 a, hairobb__v4 b)
{
    int i, bits = 0;
    for (i = 0; i < 4; ++i) bits |= (a.f[i] <= b.f[i]) << i;
    return bits;
}
static inline void hairobb__v4_store(float *p, hairobb__v4 a) { memcpy(p, a.f, sizeof a.f); }
static inline hairobb__v4 hairobb__v4_abs(hairobb__v4 a)
{
    hairobb__v4 r;
    int i;
    for (i = 0; i < 4; ++i) r.f[i] = fabsf(a.f[i]);
    return r;
}
static inline void hairobb__v4_transpose(hairobb__v4 *a, hairobb__v4 *b, hairobb__v4 *c, hairobb__v4 *d)
{
    hairobb__v4 *rows[4];
    float m[4][4];
    int i, j;
    rows[0] = a; rows[1] = b; rows[2] = c; rows[3] = d;
    for (i = 0; i < 4; ++i) for (j = 0; j < 4; ++j) m[i][j] = rows[j]->f[i];
    for (i = 0; i < 4; ++i) memcpy(rows[i]->f, m[i], sizeof m[i]);
}
static inline float hairobb__v4_hmax(hairobb__v4 a)
{
    float t0 = a.f[0] > a.f[2] ? a.f[0] : a.f[2], t1 = a.f[1] > a.f[3] ? a.f[1] : a.f[3];
    return t0 > t1 ? t0 : t1;
}
#endif

#if HAIROBB__AVX
typedef __m256 hairobb__v8;
static inline hairobb__v8 hairobb__v8_load(const float *p) { return _mm256_loadu_ps(p); }
static inline hairobb__v8 hairobb__v8_set1(float x) { return _mm256_set1_ps(x); }
static inline hairobb__v8 hairobb__v8_add(hairobb__v8 a, hairobb__v8 b) { return _mm256_add_ps(a, b); }
static inline hairobb__v8 hairobb__v8_sub(hairobb__v8 a, hairobb__v8 b) { return _mm256_sub_ps(a, b); }
static inline hairobb__v8 hairobb__v8_mul(hairobb__v8 a, hairobb__v8 b) { return _mm256_mul_ps(a, b); }
static inline hairobb__v8 hairobb__v8_div(hairobb__v8 a, hairobb__v8 b) { return _mm256_div_ps(a, b); }
static inline hairobb__v8 hairobb__v8_min(hairobb__v8 a, hairobb__v8 b) { return _mm256_min_ps(a, b); }
static inline hairobb__v8 hairobb__v8_max(hairobb__v8 a, hairobb__v8 b) { return _mm256_max_ps(a, b); }
static inline int hairobb__v8_le_bits(hairobb__v8 a, hairobb__v8 b) { return _mm256_movemask_ps(_mm256_cmp_ps(a, b, _CMP_LE_OQ)); }
static inline void hairobb__v8_store(float *p, hairobb__v8 a) { _mm256_storeu_ps(p, a); }
static inline hairobb__v8 hairobb__v8_nonzero(hairobb__v8 x, float tiny)
{
    __m256 sign = _mm256_and_ps(x, _mm256_set1_ps(-0.0f));
    __m256 small = _mm256_cmp_ps(_mm256_andnot_ps(_mm256_set1_ps(-0.0f), x), _mm256_set1_ps(tiny), _CMP_LT_OQ);
    __m256 replacement = _mm256_or_ps(sign, _mm256_set1_ps(tiny));
    return _mm256_or_ps(_mm256_and_ps(small, replacement), _mm256_andnot_ps(small, x));
}
#else
/* Two 4-lane halves: SSE, or plain C through the 4-lane twin above. */
typedef struct hairobb__v8 { hairobb__v4 lo, hi; } hairobb__v8;
#define HAIROBB__V8_PAIR(op) hairobb__v8 r; r.lo = op(a.lo, b.lo); r.hi = op(a.hi, b.hi); return r
static inline hairobb__v8 hairobb__v8_load(const float *p) { hairobb__v8 r; r.lo = hairobb__v4_load(p); r.hi = hairobb__v4_load(p + 4); return r; }
static inline hairobb__v8 hairobb__v8_set1(float x) { hairobb__v8 r; r.lo = r.hi = hairobb__v4_set1(x); return r; }
static inline hairobb__v8 hairobb__v8_add(hairobb__v8 a, hairobb__v8 b) { HAIROBB__V8_PAIR(hairobb__v4_add); }
static inline hairobb__v8 hairobb__v8_sub(hairobb__v8 a, hairobb__v8 b) { HAIROBB__V8_PAIR(hairobb__v4_sub); }
static inline hairobb__v8 hairobb__v8_mul(hairobb__v8 a, hairobb__v8 b) { HAIROBB__V8_PAIR(hairobb__v4_mul); }
static inline hairobb__v8 hairobb__v8_div(hairobb__v8 a, hairobb__v8 b) { HAIROBB__V8_PAIR(hairobb__v4_div); }
static inline hairobb__v8 hairobb__v8_min(hairobb__v8 a, hairobb__v8 b) { HAIROBB__V8_PAIR(hairobb__v4_min); }
static inline hairobb__v8 hairobb__v8_max(hairobb__v8 a, hairobb__v8 b) { HAIROBB__V8_PAIR(hairobb__v4_max); }
#undef HAIROBB__V8_PAIR
static inline int hairobb__v8_le_bits(hairobb__v8 a, hairobb__v8 b) { return hairobb__v4_le_bits(a.lo, b.lo) | (hairobb__v4_le_bits(a.hi, b.hi) << 4); }
static inline void hairobb__v8_store(float *p, hairobb__v8 a) { hairobb__v4_store(p, a.lo); hairobb__v4_store(p + 4, a.hi); }
static inline hairobb__v8 hairobb__v8_nonzero(hairobb__v8 x, float tiny)
{
    hairobb__v8 r;
    r.lo = hairobb__v4_nonzero(x.lo, tiny);
    r.hi = hairobb__v4_nonzero(x.hi, tiny);
    return r;
}
#endif

/* Node-wide vectors: one lane per child. */
#if HAIROBB__W == 8
typedef hairobb__v8 hairobb__vn;
#define hairobb__vn_load hairobb__v8_load
#define hairobb__vn_set1 hairobb__v8_set1
#define hairobb__vn_add hairobb__v8_add
#define hairobb__vn_sub hairobb__v8_sub
#define hairobb__vn_mul hairobb__v8_mul
#define hairobb__vn_div hairobb__v8_div
#define hairobb__vn_min hairobb__v8_min
#define hairobb__vn_max hairobb__v8_max
#define hairobb__vn_le_bits hairobb__v8_le_bits
#define hairobb__vn_store hairobb__v8_store
#define hairobb__vn_nonzero hairobb__v8_nonzero
#elif HAIROBB__W == 4
typedef hairobb__v4 hairobb__vn;
#define hairobb__vn_load hairobb__v4_load
#define hairobb__vn_set1 hairobb__v4_set1
#define hairobb__vn_add hairobb__v4_add
#define hairobb__vn_sub hairobb__v4_sub
#define hairobb__vn_mul hairobb__v4_mul
#define hairobb__vn_div hairobb__v4_div
#define hairobb__vn_min hairobb__v4_min
#define hairobb__vn_max hairobb__v4_max
#define hairobb__vn_le_bits hairobb__v4_le_bits
#define hairobb__vn_store hairobb__v4_store
#define hairobb__vn_nonzero hairobb__v4_nonzero
#else
#error "HAIROBB_NODE_WIDTH must be 4 or 8"
#endif

static int hairobb__lowest_bit(unsigned bits)
{
#if defined(__GNUC__) || defined(__clang__)
    return __builtin_ctz(bits);
#else
    int i = 0;
    while (!(bits & 1u)) { bits >>= 1; ++i; }
    return i;
#endif
}

/* ------------------------------------------------------------------------ */
/* The BVH                                                                   */
/* ------------------------------------------------------------------------ */
/* Four axis-aligned child boxes, struct of arrays: 128 bytes. */
typedef struct hairobb__aabb_node {
    float lower[3][HAIROBB__W], upper[3][HAIROBB__W];   /* [axis][child] */
    uint64_t child[HAIROBB__W];
} hairobb__aabb_node;

/* Four oriented child boxes, each an affine map of world space onto the unit
   cube: unit = M * (p - centre) + m, with xfm[0..8] = M row-major and
   xfm[9..11] = m, each entry holding all children. Subtracting a centre
   near the node first keeps the transform's rounding proportional to the
   distance between ray origin and node, not to their distance from the
   world origin: 240 bytes. */
typedef struct hairobb__obb_node {
    float centre[4];                  /* xyz, w unused */
    float xfm[12][HAIROBB__W];
    uint64_t child[HAIROBB__W];
} hairobb__obb_node;

/* Four boxes in one rotated frame, the node's hair space, around a centre:
   the ray is moved and rotated once, then tested as in an AABB node: 176 bytes. */
typedef struct hairobb__rotated_node {
    float rotation[9], centre[3];     /* rows: the frame's axes */
    float lower[3][HAIROBB__W], upper[3][HAIROBB__W];   /* [axis][child], of R * (p - centre) */
    uint64_t child[HAIROBB__W];
} hairobb__rotated_node;

struct hairobb_bvh {
    const float *vertices;
    const uint32_t *indices;
    void *allocator_user;
    void *node_allocation;            /* what HAIROBB_MALLOC returned */
    unsigned char *nodes;             /* 64-byte aligned inside node_allocation */
    size_t node_bytes;
    uint32_t *leaf_prims;             /* segment ids, leaves index ranges of it */
    size_t leaf_prim_count;
    uint64_t root;
    float lower[3], upper[3];
    hairobb_precision precision;
    int pieces, piece_chunks;         /* linear pieces; 8-lane chunks of them */
    unsigned chunk_valid[2];          /* lanes holding real pieces */
    /* Bernstein weights of the pieces' start and end points: [chunk][start/end][basis][lane] */
    float piece_weights[2][2][4][8];
    hairobb_stats stats;
};

/* ------------------------------------------------------------------------ */
/* Input: validation and per-segment bounds                                  */
/* ------------------------------------------------------------------------ */
HAIROBB_DEF const char *hairobb_result_string(hairobb_result r)
{
    switch (r) {
    case HAIROBB_OK: return "ok";
    case HAIROBB_ERROR_INVALID_ARGUMENT: return "invalid argument (NULL pointer, zero segments or bad option)";
    case HAIROBB_ERROR_INDEX_OUT_OF_RANGE: return "segment index out of range (index + 3 >= vertex count)";
    case HAIROBB_ERROR_INVALID_GEOMETRY: return "invalid geometry (NaN, infinite or huge coordinate, or negative radius)";
    case HAIROBB_ERROR_OUT_OF_MEMORY: return "out of memory";
    case HAIROBB_ERROR_TOO_LARGE: return "input too large (size overflow or more than 2^32-1 segments)";
    }
    return "unknown hairobb_result";
}

static hairobb_result hairobb__validate(const float *vertices, size_t vertex_count,
                                        const uint32_t *indices, size_t segment_count)
{
    size_t i, k;
    if (segment_count > 0xffffffffu || vertex_count > (size_t)-1 / (4 * sizeof(float)))
        return HAIROBB_ERROR_TOO_LARGE;
    for (i = 0; i < segment_count; ++i) {
        if (vertex_count < 4 || indices[i] > vertex_count - 4) return HAIROBB_ERROR_INDEX_OUT_OF_RANGE;
    }
    for (i = 0; i < segment_count; ++i) {
        const float *cp = vertices + 4 * (size_t)indices[i];
        for (k = 0; k < 16; ++k) {
            /* the negated test also rejects NaN */
            if (!(fabsf(cp[k]) <= HAIROBB__MAX_COORD)) return HAIROBB_ERROR_INVALID_GEOMETRY;
        }
        for (k = 3; k < 16; k += 4) {
            if (cp[k] < 0.0f) return HAIROBB_ERROR_INVALID_GEOMETRY;
        }
    }
    return HAIROBB_OK;
}

/* Box of a segment in a rotated frame (rows of frame are the new axes).
   The ribbon lies in the convex hull of the control points dilated by the
   largest radius (r(u) is a convex combination of the 4 radii), so the box of
   the rotated control points grown by that radius bounds it. centre, if
   given, is subtracted first. Node boxes are padded for rounding once, when
   stored (hairobb__pad_box). */
static void hairobb__segment_box(const float *cp, const float frame[9], const float *centre, float lower[3], float upper[3])
{
    int i, k;
    float radius = hairobb__maxf(hairobb__maxf(cp[3], cp[7]), hairobb__maxf(cp[11], cp[15]));
    hairobb__box_empty(lower, upper);
    for (i = 0; i < 4; ++i) {
        float p[3];
        for (k = 0; k < 3; ++k) p[k] = centre ? cp[4 * i + k] - centre[k] : cp[4 * i + k];
        for (k = 0; k < 3; ++k) {
            float x = hairobb__dot3(frame + 3 * k, p);
            lower[k] = hairobb__minf(lower[k], x);
            upper[k] = hairobb__maxf(upper[k], x);
        }
    }
    for (k = 0; k < 3; ++k) { lower[k] -= radius; upper[k] += radius; }
}

/* ------------------------------------------------------------------------ */
/* Hair space                                                                */
/* ------------------------------------------------------------------------ */
typedef struct hairobb__builder {
    const float *vertices;
    const uint32_t *indices;
    float *world_boxes;               /* 6 per segment: lower, upper */
    float *frame_boxes;               /* 6 per position of ids: boxes in the frame being binned */
    uint32_t *ids;                    /* partitioned in place; becomes leaf_prims */
    unsigned char *node_allocation, *nodes;
    size_t node_bytes, node_capacity;
    void *user;
    hairobb_node_policy policy;
    hairobb_obb_layout obb_layout;
    unsigned max_leaf, candidates;
    hairobb_stats stats;
    int out_of_memory;
} hairobb__builder;

static const float *hairobb__control_points(const hairobb__builder *b, uint32_t id)
{
    return b->vertices + 4 * (size_t)b->indices[id];
}

static void hairobb__prim_box(const hairobb__builder *b, uint32_t id, const float *frame,
                              float lower[3], float upper[3])
{
    if (!frame) {
        memcpy(lower, b->world_boxes + 6 * (size_t)id, 3 * sizeof(float));
        memcpy(upper, b->world_boxes + 6 * (size_t)id + 3, 3 * sizeof(float));
    } else {
        hairobb__segment_box(hairobb__control_points(b, id), frame, NULL, lower, upper);
    }
}

/* Rotation whose z axis is the main direction (first to last control point)
   of segment id; 0 if the segment has no direction. */
static int hairobb__segment_frame(const hairobb__builder *b, uint32_t id, float frame[9])
{
    const float *cp = hairobb__control_points(b, id);
    float d[3];
    float len;
    d[0] = cp[12] - cp[0]; d[1] = cp[13] - cp[1]; d[2] = cp[14] - cp[2];
    len = sqrtf(hairobb__dot3(d, d));
    if (!(len > 0.0f) || !(len < FLT_MAX)) return 0;
    d[0] /= len; d[1] /= len; d[2] /= len;
    hairobb__frame_from_direction(d, frame);
    return 1;
}

/* Picks, among the main directions of evenly spaced segments of the range
   (and the world axes when allow_identity), the rotation with the smallest
   summed surface area of the sampled segments' boxes. Deterministic. */
static void hairobb__choose_hair_space(const hairobb__builder *b, size_t begin, size_t end,
                                       int allow_identity, float best_frame[9])
{
    size_t count = end - begin, step = count > HAIROBB__SAMPLE ? count / HAIROBB__SAMPLE : 1;
    unsigned c, candidates = b->candidates < count ? b->candidates : (unsigned)count;
    float best_area = FLT_MAX;
    hairobb__identity_frame(best_frame);
    for (c = 0; c < candidates + (allow_identity ? 1u : 0u); ++c) {
        float frame[9], area = 0.0f;
        size_t i;
        if (c == candidates) {
            hairobb__identity_frame(frame);
        } else {
            size_t pick = begin + (count * (2 * c + 1)) / (2 * candidates);
            if (!hairobb__segment_frame(b, b->ids[pick], frame)) continue;
        }
        for (i = begin; i < end && area < best_area; i += step) {
            float lower[3], upper[3];
            hairobb__prim_box(b, b->ids[i], c == candidates ? NULL : frame, lower, upper);   /* NULL: cached world box */
            area += hairobb__half_area(lower, upper);
        }
        if (area < best_area) { best_area = area; memcpy(best_frame, frame, sizeof frame); }
    }
}

/* ------------------------------------------------------------------------ */
/* Builder: binned SAH in world space and in hair space, filling W children */
/* ------------------------------------------------------------------------ */
typedef struct hairobb__split {
    float cost;                 /* FLT_MAX: no split found */
    int hair_space;             /* the split was made in frame, not world axes */
    float frame[9];
    int axis;
    float bin_origin, bin_scale;
    int last_left_bin;          /* bins 0..last_left_bin go left; -1: split at the median */
    float area_left, area_right;
    float parent_area;          /* world box of the range being split */
} hairobb__split;

static int hairobb__bin_of(float centroid, float origin, float scale)
{
    int bin = (int)((centroid - origin) * scale);
    return bin < 0 ? 0 : bin >= HAIROBB__BINS ? HAIROBB__BINS - 1 : bin;
}

/* Box of the segment at position i of ids: its world box, or (frame given)
   the box hairobb__bin_split computed in that frame. */
static void hairobb__box_at(const hairobb__builder *b, const float *frame, size_t i, float lower[3], float upper[3])
{
    const float *box = frame ? b->frame_boxes + 6 * i : b->world_boxes + 6 * (size_t)b->ids[i];
    memcpy(lower, box, 3 * sizeof(float));
    memcpy(upper, box + 3, 3 * sizeof(float));
}

/* Best SAH object split of ids[begin, end) binned by centroid along the axes
   of frame (NULL = world axes). Costs are SAH costs times the parent's area;
   box_cost is that of testing the two new child boxes. */
static void hairobb__bin_split(const hairobb__builder *b, size_t begin, size_t end,
                               const float *frame, float box_cost, hairobb__split *best)
{
    float cmin[3], cmax[3];
    size_t i;
    int axis;
    if (frame) {
        for (i = begin; i < end; ++i)
            hairobb__segment_box(hairobb__control_points(b, b->ids[i]), frame, NULL, b->frame_boxes + 6 * i, b->frame_boxes + 6 * i + 3);
    }
    hairobb__box_empty(cmin, cmax);
    for (i = begin; i < end; ++i) {
        float lower[3], upper[3], c[3];
        int k;
        hairobb__box_at(b, frame, i, lower, upper);
        for (k = 0; k < 3; ++k) c[k] = 0.5f * (lower[k] + upper[k]);
        hairobb__box_grow(cmin, cmax, c, c);
    }
    for (axis = 0; axis < 3; ++axis) {
        float bin_lower[HAIROBB__BINS][3], bin_upper[HAIROBB__BINS][3];
        float right_area[HAIROBB__BINS];
        size_t bin_count[HAIROBB__BINS], right_count[HAIROBB__BINS], left_count = 0;
        float extent = cmax[axis] - cmin[axis], scale, lo[3], hi[3];
        int bin;
        if (!(extent > 0.0f)) continue;
        scale = (float)HAIROBB__BINS * (1.0f - 1.0f / 1024.0f) / extent;
        for (bin = 0; bin < HAIROBB__BINS; ++bin) {
            hairobb__box_empty(bin_lower[bin], bin_upper[bin]);
            bin_count[bin] = 0;
        }
        for (i = begin; i < end; ++i) {
            float lower[3], upper[3];
            hairobb__box_at(b, frame, i, lower, upper);
            bin = hairobb__bin_of(0.5f * (lower[axis] + upper[axis]), cmin[axis], scale);
            hairobb__box_grow(bin_lower[bin], bin_upper[bin], lower, upper);
            bin_count[bin]++;
        }
        /* right-to-left sweep: box and count of bins [bin, BINS) */
        hairobb__box_empty(lo, hi);
        for (bin = HAIROBB__BINS - 1; bin > 0; --bin) {
            hairobb__box_grow(lo, hi, bin_lower[bin], bin_upper[bin]);
            right_count[bin] = bin_count[bin] + (bin + 1 < HAIROBB__BINS ? right_count[bin + 1] : 0);
            right_area[bin] = right_count[bin] ? hairobb__half_area(lo, hi) : 0.0f;
        }
        hairobb__box_empty(lo, hi);
        for (bin = 0; bin < HAIROBB__BINS - 1; ++bin) {
            float cost, left_area;
            hairobb__box_grow(lo, hi, bin_lower[bin], bin_upper[bin]);
            left_count += bin_count[bin];
            if (left_count == 0 || right_count[bin + 1] == 0) continue;
            left_area = hairobb__half_area(lo, hi);
            cost = box_cost + HAIROBB__COST_SEGMENT * (left_area * (float)left_count + right_area[bin + 1] * (float)right_count[bin + 1]);
            if (cost < best->cost) {
                best->cost = cost;
                best->hair_space = frame != NULL;
                if (frame) memcpy(best->frame, frame, sizeof best->frame);
                best->axis = axis;
                best->bin_origin = cmin[axis];
                best->bin_scale = scale;
                best->last_left_bin = bin;
                best->area_left = left_area;
                best->area_right = right_area[bin + 1];
            }
        }
    }
}

static void hairobb__range_box(const hairobb__builder *b, size_t begin, size_t end, const float *frame,
                               float lower[3], float upper[3])
{
    size_t i;
    hairobb__box_empty(lower, upper);
    for (i = begin; i < end; ++i) {
        float lo[3], hi[3];
        hairobb__prim_box(b, b->ids[i], frame, lo, hi);
        hairobb__box_grow(lower, upper, lo, hi);
    }
}

/* The padded box of ids[begin, end) in frame around centre: what a node stores. */
static void hairobb__node_box(const hairobb__builder *b, size_t begin, size_t end, const float frame[9],
                              const float centre[3], float lower[3], float upper[3])
{
    size_t i;
    hairobb__box_empty(lower, upper);
    for (i = begin; i < end; ++i) {
        float lo[3], hi[3];
        hairobb__segment_box(hairobb__control_points(b, b->ids[i]), frame, centre, lo, hi);
        hairobb__box_grow(lower, upper, lo, hi);
    }
    hairobb__pad_box(lower, upper);
}

/* A float point near the middle of the range's world box. */
static void hairobb__range_centre(const hairobb__builder *b, size_t begin, size_t end, float centre[3])
{
    float lower[3], upper[3];
    int k;
    hairobb__range_box(b, begin, end, NULL, lower, upper);
    for (k = 0; k < 3; ++k) centre[k] = 0.5f * lower[k] + 0.5f * upper[k];
}

/* The cheapest split the policy allows; a median split when binning finds
   none (all centroids equal) or below the SAH depth. */
static void hairobb__find_split(const hairobb__builder *b, size_t begin, size_t end, unsigned depth,
                                hairobb__split *best)
{
    float lower[3], upper[3], area;
    hairobb__range_box(b, begin, end, NULL, lower, upper);
    area = hairobb__half_area(lower, upper);
    best->cost = FLT_MAX;
    best->hair_space = 0;
    best->last_left_bin = -1;
    best->parent_area = area;
    if (depth < HAIROBB__SAH_DEPTH) {
        if (b->policy != HAIROBB_NODES_OBB_ONLY)
            hairobb__bin_split(b, begin, end, NULL, 2.0f * HAIROBB__COST_AABB * area, best);
        if (b->policy != HAIROBB_NODES_AABB_ONLY) {
            float frame[9];
            hairobb__choose_hair_space(b, begin, end, 0, frame);
            hairobb__bin_split(b, begin, end, frame, 2.0f * HAIROBB__COST_OBB * area, best);
        }
    }
    if (best->cost == FLT_MAX) {
        size_t half = (end - begin) / 2;
        hairobb__range_box(b, begin, begin + half, NULL, lower, upper);
        best->area_left = hairobb__half_area(lower, upper);
        hairobb__range_box(b, begin + half, end, NULL, lower, upper);
        best->area_right = hairobb__half_area(lower, upper);
    }
}

/* Reorders ids[begin, end) so the split's left side comes first; returns the
   first right index. */
static size_t hairobb__partition(hairobb__builder *b, size_t begin, size_t end, const hairobb__split *split)
{
    size_t left = begin, right = end;
    if (split->last_left_bin < 0) return begin + (end - begin) / 2;
    while (left < right) {
        float lower[3], upper[3];
        hairobb__prim_box(b, b->ids[left], split->hair_space ? split->frame : NULL, lower, upper);
        if (hairobb__bin_of(0.5f * (lower[split->axis] + upper[split->axis]), split->bin_origin, split->bin_scale)
            <= split->last_left_bin) {
            ++left;
        } else {
            uint32_t t = b->ids[left];
            b->ids[left] = b->ids[--right];
            b->ids[right] = t;
        }
    }
    HAIROBB_ASSERT(left > begin && left < end);
    return left;
}

/* Node memory grows by doubling; offsets, not pointers, survive a move. */
static size_t hairobb__alloc_node(hairobb__builder *b, size_t bytes)
{
    size_t offset = b->node_bytes;
    if (b->out_of_memory) return 0;
    if (offset + bytes > b->node_capacity) {
        size_t capacity = b->node_capacity ? 2 * b->node_capacity : 4096;
        unsigned char *allocation, *aligned;
        while (capacity < offset + bytes) capacity *= 2;
        allocation = HAIROBB__CAST(unsigned char *, HAIROBB_MALLOC(capacity + 64, b->user));
        if (!allocation) { b->out_of_memory = 1; return 0; }
        aligned = allocation + ((64 - ((uintptr_t)allocation & 63)) & 63);
        if (b->node_bytes) memcpy(aligned, b->nodes, b->node_bytes);
        if (b->node_allocation) HAIROBB_FREE(b->node_allocation, b->user);
        b->node_allocation = allocation;
        b->nodes = aligned;
        b->node_capacity = capacity;
    }
    b->node_bytes += bytes;
    return offset;
}

typedef struct hairobb__child {
    size_t begin, end;
    float area;
    int final_leaf;             /* SAH chose a leaf for it */
} hairobb__child;

static uint64_t hairobb__make_leaf(hairobb__builder *b, size_t begin, size_t end, unsigned depth)
{
    b->stats.leaves++;
    b->stats.leaf_references += end - begin;
    if (depth > b->stats.max_depth) b->stats.max_depth = depth;
    return ((uint64_t)begin << 8) | ((uint64_t)(end - begin) << 4) | HAIROBB__REF_LEAF;
}

/* Writes the affine map of box [lower, upper] in frame onto the unit cube
   into lane `lane` of an OBB node. */
static void hairobb__store_obb(hairobb__obb_node *node, int lane, const float frame[9],
                               const float lower[3], const float upper[3])
{
    int row, col;
    for (row = 0; row < 3; ++row) {
        /* a floor on the extent keeps the scale finite for flat boxes */
        float extent = hairobb__maxf(upper[row] - lower[row], 1e-30f);
        float scale = 1.0f / extent;
        for (col = 0; col < 3; ++col) node->xfm[3 * row + col][lane] = frame[3 * row + col] * scale;
        node->xfm[9 + row][lane] = -lower[row] * scale;
    }
}

static uint64_t hairobb__build_range(hairobb__builder *b, size_t begin, size_t end, unsigned depth);

/* SAH cost of a leaf, on the scale of hairobb__bin_split's costs */
static float hairobb__leaf_cost(size_t count, float area) { return HAIROBB__COST_SEGMENT * (float)count * area; }

/* Builds a node over ids[begin, end): split the child with the largest
   area until there are W; the node is OBB where a hair-space split won. */
static uint64_t hairobb__build_node(hairobb__builder *b, size_t begin, size_t end, unsigned depth,
                                    const hairobb__split *first_split)
{
    hairobb__child children[HAIROBB__W];
    int count = 1, use_obb = b->policy == HAIROBB_NODES_OBB_ONLY, i;
    unsigned node_type;
    size_t offset;
    uint64_t refs[HAIROBB__W];
    hairobb__split split = *first_split;
    children[0].begin = begin; children[0].end = end; children[0].area = FLT_MAX; children[0].final_leaf = 0;
    for (;;) {
        int pick = -1;
        size_t middle;
        for (i = 0; i < count; ++i) {
            if (children[i].final_leaf || children[i].end - children[i].begin < 2) continue;
            if (pick < 0 || children[i].area > children[pick].area) pick = i;
        }
        if (pick < 0 || count == HAIROBB__W) break;
        if (count > 1) {
            size_t n = children[pick].end - children[pick].begin;
            hairobb__find_split(b, children[pick].begin, children[pick].end, depth + 1, &split);
            if (n <= b->max_leaf && hairobb__leaf_cost(n, split.parent_area) <= split.cost) {
                children[pick].final_leaf = 1;
                continue;
            }
        }
        middle = hairobb__partition(b, children[pick].begin, children[pick].end, &split);
        if (split.hair_space) use_obb = 1;
        children[count].begin = middle;
        children[count].end = children[pick].end;
        children[count].area = split.area_right;
        children[count].final_leaf = 0;
        children[pick].end = middle;
        children[pick].area = split.area_left;
        ++count;
    }
    if (b->policy == HAIROBB_NODES_AABB_ONLY) use_obb = 0;

    if (use_obb && b->obb_layout == HAIROBB_OBB_PER_CHILD) node_type = HAIROBB__REF_OBB;
    else if (use_obb) node_type = HAIROBB__REF_ROTATED;
    else node_type = HAIROBB__REF_AABB;
    offset = hairobb__alloc_node(b, node_type == HAIROBB__REF_OBB ? sizeof(hairobb__obb_node)
                                    : node_type == HAIROBB__REF_ROTATED ? sizeof(hairobb__rotated_node)
                                    : sizeof(hairobb__aabb_node));
    if (use_obb) b->stats.obb_nodes++; else b->stats.aabb_nodes++;
    for (i = 0; i < count; ++i) {
        size_t n = children[i].end - children[i].begin;
        if (children[i].final_leaf || n == 1 || (count == HAIROBB__W && n <= HAIROBB__FULL_NODE_LEAF && n <= b->max_leaf))
            refs[i] = hairobb__make_leaf(b, children[i].begin, children[i].end, depth + 1);
        else
            refs[i] = hairobb__build_range(b, children[i].begin, children[i].end, depth + 1);
    }
    if (b->out_of_memory) return HAIROBB__REF_EMPTY;

    if (node_type == HAIROBB__REF_OBB) {
        hairobb__obb_node *node = HAIROBB__CAST(hairobb__obb_node *, (void *)(b->nodes + offset));
        hairobb__range_centre(b, begin, end, node->centre);
        node->centre[3] = 0.0f;
        for (i = 0; i < HAIROBB__W; ++i) {
            float frame[9], lower[3], upper[3];
            if (i < count) {
                hairobb__choose_hair_space(b, children[i].begin, children[i].end, 1, frame);
                hairobb__node_box(b, children[i].begin, children[i].end, frame, node->centre, lower, upper);
            } else {
                /* an empty child maps everything to (2,2,2): never inside the unit cube */
                memset(frame, 0, sizeof frame);
                lower[0] = lower[1] = lower[2] = -2.0f;
                upper[0] = upper[1] = upper[2] = -1.0f;
            }
            hairobb__store_obb(node, i, frame, lower, upper);
            node->child[i] = i < count ? refs[i] : HAIROBB__REF_EMPTY;
        }
    } else {
        /* AABB and rotated nodes: all boxes in one frame (world axes, no centre, for AABB) */
        float frame[9], (*lower)[HAIROBB__W], (*upper)[HAIROBB__W];
        const float *centre = NULL;
        uint64_t *child;
        if (node_type == HAIROBB__REF_ROTATED) {
            hairobb__rotated_node *node = HAIROBB__CAST(hairobb__rotated_node *, (void *)(b->nodes + offset));
            hairobb__choose_hair_space(b, begin, end, 1, frame);
            memcpy(node->rotation, frame, sizeof frame);
            hairobb__range_centre(b, begin, end, node->centre);
            centre = node->centre;
            lower = node->lower; upper = node->upper; child = node->child;
        } else {
            hairobb__aabb_node *node = HAIROBB__CAST(hairobb__aabb_node *, (void *)(b->nodes + offset));
            hairobb__identity_frame(frame);
            lower = node->lower; upper = node->upper; child = node->child;
        }
        for (i = 0; i < HAIROBB__W; ++i) {
            float lo[3], hi[3];
            int k;
            if (i < count) {
                hairobb__node_box(b, children[i].begin, children[i].end, frame, centre, lo, hi);
            } else { for (k = 0; k < 3; ++k) { lo[k] = INFINITY; hi[k] = -INFINITY; } }
            for (k = 0; k < 3; ++k) { lower[k][i] = lo[k]; upper[k][i] = hi[k]; }
            child[i] = i < count ? refs[i] : HAIROBB__REF_EMPTY;
        }
    }
    return (uint64_t)offset | node_type;
}

static uint64_t hairobb__build_range(hairobb__builder *b, size_t begin, size_t end, unsigned depth)
{
    hairobb__split split;
    size_t n = end - begin;
    if (n == 1) return hairobb__make_leaf(b, begin, end, depth);
    hairobb__find_split(b, begin, end, depth, &split);
    if (n <= b->max_leaf && hairobb__leaf_cost(n, split.parent_area) <= split.cost)
        return hairobb__make_leaf(b, begin, end, depth);
    return hairobb__build_node(b, begin, end, depth, &split);
}

static void hairobb__setup_pieces(hairobb_bvh *bvh, int pieces)
{
    int chunk, lane, end;
    bvh->pieces = pieces;
    bvh->piece_chunks = (pieces + 7) / 8;
    for (chunk = 0; chunk < 2; ++chunk) {
        int first = 8 * chunk;
        int real = pieces - first < 0 ? 0 : pieces - first > 8 ? 8 : pieces - first;
        bvh->chunk_valid[chunk] = (1u << real) - 1u;
        for (lane = 0; lane < 8; ++lane) {
            /* lanes past the last piece repeat it; they are masked out */
            int k = first + lane < pieces ? first + lane : pieces - 1;
            for (end = 0; end < 2; ++end) {
                float u = (float)(k + end) / (float)pieces, s = 1.0f - u;
                bvh->piece_weights[chunk][end][0][lane] = s * s * s;
                bvh->piece_weights[chunk][end][1][lane] = 3.0f * u * s * s;
                bvh->piece_weights[chunk][end][2][lane] = 3.0f * u * u * s;
                bvh->piece_weights[chunk][end][3][lane] = u * u * u;
            }
        }
    }
}

HAIROBB_DEF hairobb_result hairobb_build(const float *vertices, size_t vertex_count,
                             const uint32_t *indices, size_t segment_count,
                             const hairobb_build_options *options, hairobb_bvh **out)
{
    hairobb_build_options opt;
    hairobb__builder b;
    hairobb_bvh *bvh;
    hairobb_result result;
    size_t i;
    float identity[9];

    if (out) *out = NULL;
    if (!out || !vertices || !indices || segment_count == 0) return HAIROBB_ERROR_INVALID_ARGUMENT;
    if (options) opt = *options; else memset(&opt, 0, sizeof opt);
    if (opt.max_leaf_size == 0) opt.max_leaf_size = 4;
    if (opt.hair_space_candidates == 0) opt.hair_space_candidates = 4;
    if (opt.curve_pieces == 0) opt.curve_pieces = 8;
    if ((unsigned)opt.nodes > HAIROBB_NODES_OBB_ONLY || (unsigned)opt.precision > HAIROBB_PRECISION_PIECES ||
        (unsigned)opt.obb_layout > HAIROBB_OBB_SHARED_ROTATION ||
        opt.max_leaf_size > HAIROBB__MAX_LEAF || opt.hair_space_candidates > HAIROBB__MAX_CANDIDATES ||
        opt.curve_pieces > HAIROBB__MAX_PIECES)
        return HAIROBB_ERROR_INVALID_ARGUMENT;
    result = hairobb__validate(vertices, vertex_count, indices, segment_count);
    if (result != HAIROBB_OK) return result;
    if (segment_count > (size_t)-1 / (6 * sizeof(float))) return HAIROBB_ERROR_TOO_LARGE;

    memset(&b, 0, sizeof b);
    b.vertices = vertices;
    b.indices = indices;
    b.user = opt.allocator_user;
    b.policy = opt.nodes;
    b.obb_layout = opt.obb_layout;
    b.max_leaf = opt.max_leaf_size;
    b.candidates = opt.hair_space_candidates;
    bvh = HAIROBB__CAST(hairobb_bvh *, HAIROBB_MALLOC(sizeof *bvh, b.user));
    b.world_boxes = HAIROBB__CAST(float *, HAIROBB_MALLOC(6 * sizeof(float) * segment_count, b.user));
    b.frame_boxes = HAIROBB__CAST(float *, HAIROBB_MALLOC(6 * sizeof(float) * segment_count, b.user));
    b.ids = HAIROBB__CAST(uint32_t *, HAIROBB_MALLOC(sizeof(uint32_t) * segment_count, b.user));
    if (!bvh || !b.world_boxes || !b.frame_boxes || !b.ids) goto out_of_memory;
    memset(bvh, 0, sizeof *bvh);

    hairobb__identity_frame(identity);
    hairobb__box_empty(bvh->lower, bvh->upper);
    for (i = 0; i < segment_count; ++i) {
        float *box = b.world_boxes + 6 * i;
        hairobb__segment_box(vertices + 4 * (size_t)indices[i], identity, NULL, box, box + 3);
        hairobb__box_grow(bvh->lower, bvh->upper, box, box + 3);
        b.ids[i] = (uint32_t)i;
    }
    bvh->root = hairobb__build_range(&b, 0, segment_count, 0);
    if (b.out_of_memory) goto out_of_memory;

    /* shrink the node memory to its exact size: memory_bytes reports what stays */
    if (b.node_bytes) {
        unsigned char *allocation = HAIROBB__CAST(unsigned char *, HAIROBB_MALLOC(b.node_bytes + 64, b.user));
        if (!allocation) goto out_of_memory;
        bvh->node_allocation = allocation;
        bvh->nodes = allocation + ((64 - ((uintptr_t)allocation & 63)) & 63);
        memcpy(bvh->nodes, b.nodes, b.node_bytes);
        bvh->node_bytes = b.node_bytes;
        HAIROBB_FREE(b.node_allocation, b.user);
    }
    HAIROBB_FREE(b.world_boxes, b.user);
    HAIROBB_FREE(b.frame_boxes, b.user);
    hairobb__pad_box(bvh->lower, bvh->upper);
    bvh->vertices = vertices;
    bvh->indices = indices;
    bvh->allocator_user = b.user;
    bvh->leaf_prims = b.ids;
    bvh->leaf_prim_count = segment_count;
    bvh->precision = opt.precision;
    hairobb__setup_pieces(bvh, (int)opt.curve_pieces);
    bvh->stats = b.stats;
    bvh->stats.node_bytes = b.node_bytes;
    bvh->stats.leaf_bytes = sizeof(uint32_t) * segment_count;
    *out = bvh;
    return HAIROBB_OK;

out_of_memory:
    if (b.node_allocation) HAIROBB_FREE(b.node_allocation, b.user);
    if (b.world_boxes) HAIROBB_FREE(b.world_boxes, b.user);
    if (b.frame_boxes) HAIROBB_FREE(b.frame_boxes, b.user);
    if (b.ids) HAIROBB_FREE(b.ids, b.user);
    if (bvh) HAIROBB_FREE(bvh, b.user);
    return HAIROBB_ERROR_OUT_OF_MEMORY;
}

HAIROBB_DEF void hairobb_free(hairobb_bvh *bvh)
{
    void *user;
    if (!bvh) return;
    user = bvh->allocator_user;
    if (bvh->node_allocation) HAIROBB_FREE(bvh->node_allocation, user);
    if (bvh->leaf_prims) HAIROBB_FREE(bvh->leaf_prims, user);
    HAIROBB_FREE(bvh, user);
}

HAIROBB_DEF size_t hairobb_memory_bytes(const hairobb_bvh *bvh)
{
    if (!bvh) return 0;
    return sizeof *bvh + (bvh->node_allocation ? bvh->node_bytes + 64 : 0) + sizeof(uint32_t) * bvh->leaf_prim_count;
}

HAIROBB_DEF void hairobb_get_stats(const hairobb_bvh *bvh, hairobb_stats *stats)
{
    if (!stats) return;
    if (!bvh) { memset(stats, 0, sizeof *stats); return; }
    *stats = bvh->stats;
}

HAIROBB_DEF void hairobb_bounds(const hairobb_bvh *bvh, float lower[3], float upper[3])
{
    if (!bvh || !lower || !upper) return;
    memcpy(lower, bvh->lower, sizeof bvh->lower);
    memcpy(upper, bvh->upper, sizeof bvh->upper);
}

/* ------------------------------------------------------------------------ */
/* Traversal                                                                 */
/* ------------------------------------------------------------------------ */
#if defined(__GNUC__) || defined(__clang__)
#define HAIROBB__INLINE static inline __attribute__((always_inline))
#else
#define HAIROBB__INLINE static inline
#endif

/* A ray prepared for slab tests against boxes in one frame. */
typedef struct hairobb__slab_ray {
    float org[3];
    float rdir[3];              /* 1/dir, finite */
    /* floats from a node's lower[0] to the plane entered (near) and left
       (far) on each axis: the upper plane is entered where rdir < 0 */
    int near_plane[3], far_plane[3];
} hairobb__slab_ray;

/* Everything one ray needs, computed once per ray. */
typedef struct hairobb__ray_state {
    float org[3], dir[3];
    float tnear, tfar;          /* tfar shrinks to the nearest hit so far */
    hairobb__slab_ray world;    /* for AABB nodes */
    float frame[9];             /* rows x, y, z of ray space; z = dir/|dir| */
    float dir_length, inv_dir_length;
    uint32_t hit_prim;
    float hit_u;
} hairobb__ray_state;

#define HAIROBB__TINY_DIR 1e-18f
/* Slab distances carry rounding from the ray transform; widening the far end
   by a few ulps keeps the test conservative (after Ize 2013). */
#define HAIROBB__FAR_SCALE (1.0f + 4.0f * FLT_EPSILON)

/* org and dir given in the slab frame; zero direction components become
   +-tiny, so 1/dir stays finite for rays parallel to a slab. */
static void hairobb__slab_setup(hairobb__slab_ray *slab, const float org[3], const float dir[3])
{
    int k;
    for (k = 0; k < 3; ++k) {
        float d = fabsf(dir[k]) < HAIROBB__TINY_DIR ? (signbit(dir[k]) ? -HAIROBB__TINY_DIR : HAIROBB__TINY_DIR) : dir[k];
        int upper_first = 0;
        slab->org[k] = org[k];
        slab->rdir[k] = 1.0f / d;
        upper_first = slab->rdir[k] < 0.0f;
        slab->near_plane[k] = (upper_first ? 3 * HAIROBB__W : 0) + k * HAIROBB__W;
        slab->far_plane[k] = (upper_first ? 0 : 3 * HAIROBB__W) + k * HAIROBB__W;
    }
}

static int hairobb__ray_setup(hairobb__ray_state *rs, const hairobb_ray *ray)
{
    int k;
    float unit[3];
    memcpy(rs->org, ray->org, sizeof rs->org);
    memcpy(rs->dir, ray->dir, sizeof rs->dir);
    hairobb__slab_setup(&rs->world, ray->org, ray->dir);
    rs->tnear = ray->tnear;
    rs->tfar = ray->tfar;
    rs->hit_prim = HAIROBB_INVALID_ID;
    rs->hit_u = 0.0f;
    rs->dir_length = sqrtf(hairobb__dot3(ray->dir, ray->dir));
    if (!(rs->dir_length > 0.0f) || !(rs->dir_length < INFINITY) || !(rs->tnear <= rs->tfar)) return 0;
    rs->inv_dir_length = 1.0f / rs->dir_length;
    for (k = 0; k < 3; ++k) unit[k] = ray->dir[k] * rs->inv_dir_length;
    hairobb__frame_from_direction(unit, rs->frame);
    return 1;
}

HAIROBB__INLINE hairobb__vn hairobb__far_scale(hairobb__vn tfar)
{
    return hairobb__vn_mul(tfar, hairobb__vn_set1(HAIROBB__FAR_SCALE));
}

/* Slab test of a node's boxes in the slab ray's frame; planes points at
   lower[3][W], followed by upper[3][W] ([axis][child] arrays). */
HAIROBB__INLINE int hairobb__intersect_boxes(const float *planes, const hairobb__slab_ray *slab,
                                             const hairobb__ray_state *rs, float dist[HAIROBB__W])
{
    hairobb__vn tn = hairobb__vn_set1(rs->tnear), tf = hairobb__vn_set1(rs->tfar);
    int k;
    for (k = 0; k < 3; ++k) {
        hairobb__vn o = hairobb__vn_set1(slab->org[k]), r = hairobb__vn_set1(slab->rdir[k]);
        tn = hairobb__vn_max(hairobb__vn_mul(hairobb__vn_sub(hairobb__vn_load(planes + slab->near_plane[k]), o), r), tn);
        tf = hairobb__vn_min(hairobb__vn_mul(hairobb__vn_sub(hairobb__vn_load(planes + slab->far_plane[k]), o), r), tf);
    }
    hairobb__vn_store(dist, tn);
    return hairobb__vn_le_bits(tn, hairobb__far_scale(tf));
}

/* The ray rotated once into the node's frame; rotation preserves t. */
static int hairobb__intersect_rotated_node(const hairobb__rotated_node *node, const hairobb__ray_state *rs, float dist[HAIROBB__W])
{
    hairobb__slab_ray slab;
    float org[3], dir[3], moved[3];
    int k;
    for (k = 0; k < 3; ++k) moved[k] = rs->org[k] - node->centre[k];
    for (k = 0; k < 3; ++k) {
        org[k] = hairobb__dot3(node->rotation + 3 * k, moved);
        dir[k] = hairobb__dot3(node->rotation + 3 * k, rs->dir);
    }
    hairobb__slab_setup(&slab, org, dir);
    return hairobb__intersect_boxes(node->lower[0], &slab, rs, dist);
}

/* Each child's slab pair along a row of its map is [0, 1] in unit space.
   1/d is clamped to +-1/tiny, which is 1/d with d replaced by +-tiny where
   |d| < tiny (as hairobb__slab_setup does), in two operations. */
HAIROBB__INLINE int hairobb__intersect_obb_node(const hairobb__obb_node *node, const hairobb__ray_state *rs, float dist[HAIROBB__W])
{
    hairobb__vn tn = hairobb__vn_set1(rs->tnear), tf = hairobb__vn_set1(rs->tfar);
    hairobb__vn one = hairobb__vn_set1(1.0f), zero = hairobb__vn_set1(0.0f);
    hairobb__vn big = hairobb__vn_set1(1.0f / HAIROBB__TINY_DIR), neg_big = hairobb__vn_set1(-(1.0f / HAIROBB__TINY_DIR));
    hairobb__vn ox = hairobb__vn_set1(rs->org[0] - node->centre[0]), oy = hairobb__vn_set1(rs->org[1] - node->centre[1]);
    hairobb__vn oz = hairobb__vn_set1(rs->org[2] - node->centre[2]);
    hairobb__vn dx = hairobb__vn_set1(rs->dir[0]), dy = hairobb__vn_set1(rs->dir[1]), dz = hairobb__vn_set1(rs->dir[2]);
#define HAIROBB__OBB_ROW(row) do { \
        hairobb__vn m0 = hairobb__vn_load(node->xfm[3 * (row)]), m1 = hairobb__vn_load(node->xfm[3 * (row) + 1]); \
        hairobb__vn m2 = hairobb__vn_load(node->xfm[3 * (row) + 2]), m3 = hairobb__vn_load(node->xfm[9 + (row)]); \
        hairobb__vn o = hairobb__vn_add(hairobb__vn_add(hairobb__vn_add(hairobb__vn_mul(m0, ox), hairobb__vn_mul(m1, oy)), hairobb__vn_mul(m2, oz)), m3); \
        hairobb__vn d = hairobb__vn_add(hairobb__vn_add(hairobb__vn_mul(m0, dx), hairobb__vn_mul(m1, dy)), hairobb__vn_mul(m2, dz)); \
        hairobb__vn r = hairobb__vn_min(hairobb__vn_max(hairobb__vn_div(one, d), neg_big), big); \
        hairobb__vn t0 = hairobb__vn_mul(hairobb__vn_sub(zero, o), r); \
        hairobb__vn t1 = hairobb__vn_mul(hairobb__vn_sub(one, o), r); \
        tn = hairobb__vn_max(hairobb__vn_min(t0, t1), tn); \
        tf = hairobb__vn_min(hairobb__vn_max(t0, t1), tf); \
    } while (0)
    HAIROBB__OBB_ROW(0);
    HAIROBB__OBB_ROW(1);
    HAIROBB__OBB_ROW(2);
#undef HAIROBB__OBB_ROW
    hairobb__vn_store(dist, tn);
    return hairobb__vn_le_bits(tn, hairobb__far_scale(tf));
}

static int hairobb__intersect_leaf(const hairobb_bvh *bvh, hairobb__ray_state *rs, uint64_t ref, int any_hit);

/* Nearest-first traversal; any_hit stops at the first hit. A node with
   several hit children pushes them all, sorted so that the nearest is on
   top, and goes on with that one. */
static int hairobb__traverse(const hairobb_bvh *bvh, hairobb__ray_state *rs, int any_hit)
{
    uint64_t stack_ref[HAIROBB__STACK];
    float stack_dist[HAIROBB__STACK];
    int sp = 0, found = 0;
    uint64_t ref = bvh->root;
    for (;;) {
        unsigned type = HAIROBB__REF_TYPE(ref);
        if (type != HAIROBB__REF_LEAF && type != HAIROBB__REF_EMPTY) {
            const void *node = bvh->nodes + (ref & ~(uint64_t)15);
            const uint64_t *child;
            float dist[HAIROBB__W];
            int bits, i;
            if (type == HAIROBB__REF_AABB) {
                const hairobb__aabb_node *aabb = HAIROBB__CAST(const hairobb__aabb_node *, node);
                bits = hairobb__intersect_boxes(aabb->lower[0], &rs->world, rs, dist);
                child = aabb->child;
            } else if (type == HAIROBB__REF_ROTATED) {
                bits = hairobb__intersect_rotated_node(HAIROBB__CAST(const hairobb__rotated_node *, node), rs, dist);
                child = HAIROBB__CAST(const hairobb__rotated_node *, node)->child;
            } else {
                bits = hairobb__intersect_obb_node(HAIROBB__CAST(const hairobb__obb_node *, node), rs, dist);
                child = HAIROBB__CAST(const hairobb__obb_node *, node)->child;
            }
            if (bits) {
                int base = sp;
                i = hairobb__lowest_bit((unsigned)bits);
                bits &= bits - 1;
                if (!bits) { ref = child[i]; continue; }   /* one hit: the common case */
                if (!(bits & (bits - 1))) {                 /* two: the farther one waits */
                    int j = hairobb__lowest_bit((unsigned)bits);
                    int i_first = dist[i] < dist[j];        /* as the sort below orders them */
                    stack_ref[sp] = i_first ? child[j] : child[i];
                    stack_dist[sp] = i_first ? dist[j] : dist[i];
                    ++sp;
                    ref = i_first ? child[i] : child[j];
                    continue;
                }
                /* insertion sort onto the stack, nearest on top; equal
                   distances keep child order */
                stack_ref[sp] = child[i];
                stack_dist[sp] = dist[i];
                ++sp;
                do {
                    int j = hairobb__lowest_bit((unsigned)bits);
                    float d = dist[j];
                    bits &= bits - 1;
                    for (i = sp; i > base && stack_dist[i - 1] < d; --i) {
                        stack_ref[i] = stack_ref[i - 1];
                        stack_dist[i] = stack_dist[i - 1];
                    }
                    stack_ref[i] = child[j];
                    stack_dist[i] = d;
                    ++sp;
                } while (bits);
                ref = stack_ref[--sp];
                continue;
            }
        } else if (type == HAIROBB__REF_LEAF) {
            if (hairobb__intersect_leaf(bvh, rs, ref, any_hit)) {
                found = 1;
                if (any_hit) return 1;
            }
        }
        do {
            if (sp == 0) return found;
            --sp;
        } while (stack_dist[sp] > rs->tfar);
        ref = stack_ref[sp];
    }
}

/* ------------------------------------------------------------------------ */
/* Ray / curve intersection                                                  */
/* ------------------------------------------------------------------------ */
/* A segment's control points in ray space: x, y across the ray, z along it. */
typedef struct hairobb__ray_curve {
    float x[4], y[4], z[4], r[4];
} hairobb__ray_curve;

/* Also returns x, y, z, r as vectors, lane i = control point i. */
HAIROBB__INLINE void hairobb__to_ray_space_v4(const hairobb__ray_state *rs, const float *cp, hairobb__ray_curve *c,
                                              hairobb__v4 *x, hairobb__v4 *y, hairobb__v4 *z, hairobb__v4 *r)
{
    hairobb__v4 p0 = hairobb__v4_load(cp), p1 = hairobb__v4_load(cp + 4);
    hairobb__v4 p2 = hairobb__v4_load(cp + 8), p3 = hairobb__v4_load(cp + 12);
    hairobb__v4 qx, qy, qz;
    hairobb__v4_transpose(&p0, &p1, &p2, &p3);
    qx = hairobb__v4_sub(p0, hairobb__v4_set1(rs->org[0]));
    qy = hairobb__v4_sub(p1, hairobb__v4_set1(rs->org[1]));
    qz = hairobb__v4_sub(p2, hairobb__v4_set1(rs->org[2]));
#define HAIROBB__ROW(f) hairobb__v4_add(hairobb__v4_add(hairobb__v4_mul(hairobb__v4_set1((f)[0]), qx), \
        hairobb__v4_mul(hairobb__v4_set1((f)[1]), qy)), hairobb__v4_mul(hairobb__v4_set1((f)[2]), qz))
    *x = HAIROBB__ROW(rs->frame);
    *y = HAIROBB__ROW(rs->frame + 3);
    *z = HAIROBB__ROW(rs->frame + 6);
#undef HAIROBB__ROW
    *r = p3;
    hairobb__v4_store(c->x, *x);
    hairobb__v4_store(c->y, *y);
    hairobb__v4_store(c->z, *z);
    hairobb__v4_store(c->r, *r);
}

/* The same curve in power form, a[0] + a[1] u + a[2] u^2 + a[3] u^3: the
   root finder evaluates it many times, Horner's rule makes that cheap. */
typedef struct hairobb__ray_poly {
    float x[4], y[4], z[4], r[4];
} hairobb__ray_poly;

static void hairobb__power_form(const float c[4], float a[4])
{
    a[0] = c[0];
    a[1] = 3.0f * (c[1] - c[0]);
    a[2] = 3.0f * (c[2] - 2.0f * c[1] + c[0]);
    a[3] = c[3] - 3.0f * c[2] + 3.0f * c[1] - c[0];
}

static void hairobb__to_power_form(const hairobb__ray_curve *c, hairobb__ray_poly *p)
{
    hairobb__power_form(c->x, p->x);
    hairobb__power_form(c->y, p->y);
    hairobb__power_form(c->z, p->z);
    hairobb__power_form(c->r, p->r);
}

static float hairobb__horner(const float a[4], float u, float *d1, float *d2)
{
    if (d1) *d1 = (3.0f * a[3] * u + 2.0f * a[2]) * u + a[1];
    if (d2) *d2 = 6.0f * a[3] * u + 2.0f * a[2];
    return ((a[3] * u + a[2]) * u + a[1]) * u + a[0];
}

/* f(u) = dot(P2, P2') vanishes where the ribbon faces the ray; f'(u) too. */
static float hairobb__ribbon_f(const hairobb__ray_poly *c, float u, float *derivative)
{
    float dx, dy, ddx, ddy;
    float x = hairobb__horner(c->x, u, &dx, &ddx);
    float y = hairobb__horner(c->y, u, &dy, &ddy);
    if (derivative) *derivative = dx * dx + dy * dy + x * ddx + y * ddy;
    return x * dx + y * dy;
}

/* Records the hit if the ribbon point (x, y) covers the ray axis within
   radius r and t is in [tnear, tfar]: the nearest hit so far. */
static int hairobb__accept(hairobb__ray_state *rs, uint32_t prim, float u, float t, float x, float y, float r)
{
    if (!(x * x + y * y <= r * r) || !(t >= rs->tnear) || !(t <= rs->tfar)) return 0;
    rs->tfar = t;
    rs->hit_prim = prim;
    rs->hit_u = u;
    return 1;
}

static int hairobb__try_hit(hairobb__ray_state *rs, const hairobb__ray_poly *c, uint32_t prim, float u)
{
    return hairobb__accept(rs, prim, u, hairobb__horner(c->z, u, NULL, NULL) * rs->inv_dir_length,
                           hairobb__horner(c->x, u, NULL, NULL), hairobb__horner(c->y, u, NULL, NULL),
                           hairobb__maxf(hairobb__horner(c->r, u, NULL, NULL), 0.0f));
}

/* Root of f in [lo, hi] where f changes sign: Newton steps, bisection when a
   step leaves the bracket. A Newton step of 1e-7 or less ends the search
   before the bracket test: u has converged, and a step that rounds onto the
   bracket end just set to u must not restart bisection from the far end. */
static float hairobb__solve_bracketed(const hairobb__ray_poly *c, float lo, float hi, float f_lo, float f_hi)
{
    float u = f_lo == f_hi ? 0.5f * (lo + hi) : lo + (hi - lo) * (f_lo / (f_lo - f_hi));
    int iteration;
    if (!(u >= lo && u <= hi)) u = 0.5f * (lo + hi);
    for (iteration = 0; iteration < 24; ++iteration) {
        float derivative, f = hairobb__ribbon_f(c, u, &derivative), next;
        if (f == 0.0f) break;
        if ((f < 0.0f) == (f_lo < 0.0f)) { lo = u; f_lo = f; } else { hi = u; }
        next = u - f / derivative;
        if (fabsf(next - u) <= 1e-7f) {
            if (next >= lo && next <= hi) u = next;
            break;
        }
        if (!(next > lo && next < hi)) next = 0.5f * (lo + hi);
        if (fabsf(next - u) <= 1e-7f) { u = next; break; }
        u = next;
    }
    return u;
}

static int hairobb__sign_change(float fa, float fb)
{
    return (fa <= 0.0f && fb >= 0.0f) || (fa >= 0.0f && fb <= 0.0f);
}

/* Roots of f in [a, b], each tried as a hit. A sign change brackets one.
   Without one, two roots can hide where f dips through zero; halving the
   interval `depth` times exposes such dips down to a quarter of a piece,
   below that they are looked for around the extremum where f' changes sign. */
static int hairobb__refine_range(hairobb__ray_state *rs, const hairobb__ray_poly *c, uint32_t prim,
                                 float a, float b, float fa, float fb, float da, float db, int depth)
{
    float lo = a, hi = b, middle, f_middle, d_middle;
    int found = 0, iteration;
    if (hairobb__sign_change(fa, fb))
        return hairobb__try_hit(rs, c, prim, hairobb__solve_bracketed(c, a, b, fa, fb));
    if (depth > 0) {
        middle = 0.5f * (a + b);
        f_middle = hairobb__ribbon_f(c, middle, &d_middle);
        found |= hairobb__refine_range(rs, c, prim, a, middle, fa, f_middle, da, d_middle, depth - 1);
        found |= hairobb__refine_range(rs, c, prim, middle, b, f_middle, fb, d_middle, db, depth - 1);
        return found;
    }
    if ((da < 0.0f) == (db < 0.0f)) return 0;
    for (iteration = 0; iteration < 20; ++iteration) {
        middle = 0.5f * (lo + hi);
        hairobb__ribbon_f(c, middle, &d_middle);
        if ((d_middle < 0.0f) == (da < 0.0f)) lo = middle; else hi = middle;
    }
    middle = 0.5f * (lo + hi);
    f_middle = hairobb__ribbon_f(c, middle, NULL);
    if ((f_middle < 0.0f) == (fa < 0.0f) && f_middle != 0.0f) return 0;
    found |= hairobb__try_hit(rs, c, prim, hairobb__solve_bracketed(c, a, middle, fa, f_middle));
    found |= hairobb__try_hit(rs, c, prim, hairobb__solve_bracketed(c, middle, b, f_middle, fb));
    return found;
}

/* hairobb__ribbon_f and its derivative at 8 parameters at once, rounded as
   it rounds. */
static void hairobb__ribbon_f_v8(const hairobb__ray_poly *c, const float u_lanes[8], float f[8], float derivative[8])
{
    hairobb__v8 u = hairobb__v8_load(u_lanes), x, y, dx, dy, ddx, ddy;
#define HAIROBB__HORNER(a, value, d1, d2) \
    value = hairobb__v8_add(hairobb__v8_mul(hairobb__v8_add(hairobb__v8_mul(hairobb__v8_add(hairobb__v8_mul( \
        hairobb__v8_set1(a[3]), u), hairobb__v8_set1(a[2])), u), hairobb__v8_set1(a[1])), u), hairobb__v8_set1(a[0])); \
    d1 = hairobb__v8_add(hairobb__v8_mul(hairobb__v8_add(hairobb__v8_mul(hairobb__v8_set1(3.0f * a[3]), u), \
        hairobb__v8_set1(2.0f * a[2])), u), hairobb__v8_set1(a[1])); \
    d2 = hairobb__v8_add(hairobb__v8_mul(hairobb__v8_set1(6.0f * a[3]), u), hairobb__v8_set1(2.0f * a[2]))
    HAIROBB__HORNER(c->x, x, dx, ddx);
    HAIROBB__HORNER(c->y, y, dy, ddy);
#undef HAIROBB__HORNER
    hairobb__v8_store(derivative, hairobb__v8_add(hairobb__v8_add(hairobb__v8_add(hairobb__v8_mul(dx, dx), hairobb__v8_mul(dy, dy)),
                                                                  hairobb__v8_mul(x, ddx)), hairobb__v8_mul(y, ddy)));
    hairobb__v8_store(f, hairobb__v8_add(hairobb__v8_mul(x, dx), hairobb__v8_mul(y, dy)));
}

/* hairobb__refine_range(a, b, ..., depth 2), with f and f' at the ends,
   the middle and the quarters evaluated at once up front. */
static int hairobb__refine_piece(hairobb__ray_state *rs, const hairobb__ray_poly *c, uint32_t prim, float a, float b)
{
    float u[8], f[8], d[8];
    int found = 0, half, k;
    u[0] = a;
    u[4] = b;
    u[2] = 0.5f * (a + b);
    u[1] = 0.5f * (a + u[2]);
    u[3] = 0.5f * (u[2] + b);
    u[5] = u[6] = u[7] = b;
    hairobb__ribbon_f_v8(c, u, f, d);
    if (hairobb__sign_change(f[0], f[4]))
        return hairobb__try_hit(rs, c, prim, hairobb__solve_bracketed(c, a, b, f[0], f[4]));
    for (half = 0; half < 4; half += 2) {
        if (hairobb__sign_change(f[half], f[half + 2])) {
            found |= hairobb__try_hit(rs, c, prim, hairobb__solve_bracketed(c, u[half], u[half + 2], f[half], f[half + 2]));
            continue;
        }
        /* the quarters: depth 0, which finds nothing without a sign change
           of f or of f' */
        for (k = half; k < half + 2; ++k) {
            if (hairobb__sign_change(f[k], f[k + 1]) || (d[k] < 0.0f) != (d[k + 1] < 0.0f))
                found |= hairobb__refine_range(rs, c, prim, u[k], u[k + 1], f[k], f[k + 1], d[k], d[k + 1], 0);
        }
    }
    return found;
}

/* The linear piece alone (HAIROBB_PRECISION_PIECES): hit where the closest
   point of the chord to the ray axis lies within the interpolated radius. */
static int hairobb__piece_hit(hairobb__ray_state *rs, const hairobb__ray_curve *c, uint32_t prim,
                              float a, float b, float s)
{
    float xa = hairobb__bezier(c->x, a, NULL, NULL), xb = hairobb__bezier(c->x, b, NULL, NULL);
    float ya = hairobb__bezier(c->y, a, NULL, NULL), yb = hairobb__bezier(c->y, b, NULL, NULL);
    float za = hairobb__bezier(c->z, a, NULL, NULL), zb = hairobb__bezier(c->z, b, NULL, NULL);
    float ra = hairobb__bezier(c->r, a, NULL, NULL), rb = hairobb__bezier(c->r, b, NULL, NULL);
    return hairobb__accept(rs, prim, a + s * (b - a), (za + s * (zb - za)) * rs->inv_dir_length,
                           xa + s * (xb - xa), ya + s * (yb - ya), ra + s * (rb - ra));
}

/* The pieces stage of one segment that survived the cull, c in ray space. */
/* A piece of parameter length h strays from its chord by at most
   h^2/8 max|P''| and |P''| <= 6 max|second difference|: widening the chord
   test by that (and the same for r), plus rounding of the evaluated points,
   misses no root of the ribbon. */
static float hairobb__chord_pad(const hairobb__ray_curve *c, int pieces, float magnitude)
{
    float bend = 0.0f, bend_r = 0.0f;
    int i;
    for (i = 0; i < 2; ++i) {
        float ddx = c->x[i] - 2.0f * c->x[i + 1] + c->x[i + 2], ddy = c->y[i] - 2.0f * c->y[i + 1] + c->y[i + 2];
        bend = hairobb__maxf(bend, sqrtf(ddx * ddx + ddy * ddy));
        bend_r = hairobb__maxf(bend_r, fabsf(c->r[i] - 2.0f * c->r[i + 1] + c->r[i + 2]));
    }
    return (bend + bend_r) * (0.75f / (float)(pieces * pieces)) + magnitude * (8.0f * FLT_EPSILON);
}

/* magnitude: the largest |x|, |y| of the control points */
static int hairobb__intersect_curve(const hairobb_bvh *bvh, hairobb__ray_state *rs, const hairobb__ray_curve *c,
                                    float magnitude, uint32_t prim, int any_hit)
{
    hairobb__ray_poly poly;
    int have_poly = 0, chunk, found = 0;
    float pad = bvh->precision == HAIROBB_PRECISION_PIECES ? 0.0f : hairobb__chord_pad(c, bvh->pieces, magnitude);

    for (chunk = 0; chunk < bvh->piece_chunks; ++chunk) {
        const float (*w)[4][8] = bvh->piece_weights[chunk];
        hairobb__v8 end_x[2], end_y[2], end_r[2];
        hairobb__v8 dx, dy, len2, s, px, py, reach;
        unsigned bits, inside;
        float s_lanes[8];
        int e;
        for (e = 0; e < 2; ++e) {
            hairobb__v8 w0 = hairobb__v8_load(w[e][0]), w1 = hairobb__v8_load(w[e][1]);
            hairobb__v8 w2 = hairobb__v8_load(w[e][2]), w3 = hairobb__v8_load(w[e][3]);
#define HAIROBB__EVAL(v) hairobb__v8_add(hairobb__v8_add(hairobb__v8_add(hairobb__v8_mul(w0, hairobb__v8_set1(v[0])), \
        hairobb__v8_mul(w1, hairobb__v8_set1(v[1]))), hairobb__v8_mul(w2, hairobb__v8_set1(v[2]))), hairobb__v8_mul(w3, hairobb__v8_set1(v[3])))
            end_x[e] = HAIROBB__EVAL(c->x);
            end_y[e] = HAIROBB__EVAL(c->y);
            end_r[e] = HAIROBB__EVAL(c->r);
#undef HAIROBB__EVAL
        }
        /* closest point of each chord to the ray axis (Nakamaru and Ohno) */
        dx = hairobb__v8_sub(end_x[1], end_x[0]);
        dy = hairobb__v8_sub(end_y[1], end_y[0]);
        len2 = hairobb__v8_max(hairobb__v8_add(hairobb__v8_mul(dx, dx), hairobb__v8_mul(dy, dy)), hairobb__v8_set1(FLT_MIN));
        s = hairobb__v8_div(hairobb__v8_sub(hairobb__v8_set1(0.0f), hairobb__v8_add(hairobb__v8_mul(end_x[0], dx), hairobb__v8_mul(end_y[0], dy))), len2);
        /* a flat ribbon has no end caps: the pieces alone are hit only between
           their ends; the exact test clamps, to find every candidate piece */
        inside = (unsigned)(hairobb__v8_le_bits(hairobb__v8_set1(0.0f), s) & hairobb__v8_le_bits(s, hairobb__v8_set1(1.0f)));
        s = hairobb__v8_max(hairobb__v8_min(s, hairobb__v8_set1(1.0f)), hairobb__v8_set1(0.0f));
        px = hairobb__v8_add(end_x[0], hairobb__v8_mul(s, dx));
        py = hairobb__v8_add(end_y[0], hairobb__v8_mul(s, dy));
        if (bvh->precision == HAIROBB_PRECISION_PIECES)
            reach = hairobb__v8_add(end_r[0], hairobb__v8_mul(s, hairobb__v8_sub(end_r[1], end_r[0])));
        else
            reach = hairobb__v8_add(hairobb__v8_max(end_r[0], end_r[1]), hairobb__v8_set1(pad));
        bits = (unsigned)hairobb__v8_le_bits(hairobb__v8_add(hairobb__v8_mul(px, px), hairobb__v8_mul(py, py)),
                                             hairobb__v8_mul(reach, reach)) & bvh->chunk_valid[chunk];
        if (bvh->precision == HAIROBB_PRECISION_PIECES) {
            bits &= inside;
            if (bits) hairobb__v8_store(s_lanes, s);
        }
        while (bits) {
            int lane = hairobb__lowest_bit(bits), k = 8 * chunk + lane;
            float a = (float)k / (float)bvh->pieces, b = (float)(k + 1) / (float)bvh->pieces;
            bits &= bits - 1;
            if (bvh->precision == HAIROBB_PRECISION_PIECES) {
                found |= hairobb__piece_hit(rs, c, prim, a, b, s_lanes[lane]);
            } else {
                if (!have_poly) { hairobb__to_power_form(c, &poly); have_poly = 1; }
                found |= hairobb__refine_piece(rs, &poly, prim, a, b);
            }
            if (found && any_hit) return 1;
        }
    }
    return found;
}

/* One segment: moved into ray space and culled by its control polygon (the
   ribbon lies in its hull dilated by the largest radius), then the pieces.
   (Culling 4 segments at once with SIMD measured 10% slower: leaves hold
   about one segment.) */
static int hairobb__intersect_segment(const hairobb_bvh *bvh, hairobb__ray_state *rs, uint32_t prim, int any_hit)
{
    hairobb__ray_curve c;
    hairobb__v4 x, y, z, r, reach, neg_reach;
    float max_r, magnitude;
    int inside;
    hairobb__to_ray_space_v4(rs, bvh->vertices + 4 * (size_t)bvh->indices[prim], &c, &x, &y, &z, &r);
    max_r = hairobb__v4_hmax(r);
    reach = hairobb__v4_set1(max_r);
    neg_reach = hairobb__v4_set1(-max_r);
    /* some control point on the near side of each of the four lines
       x, y = +-max_r, and of the planes z = tnear, tfar (times |dir|): each
       4-bit mask is nonzero, that is, has bit 4 set once 15 is added */
    inside = (hairobb__v4_le_bits(x, reach) + 15) & (hairobb__v4_le_bits(neg_reach, x) + 15) &
             (hairobb__v4_le_bits(y, reach) + 15) & (hairobb__v4_le_bits(neg_reach, y) + 15) &
             (hairobb__v4_le_bits(hairobb__v4_set1(rs->tnear * rs->dir_length), z) + 15) &
             (hairobb__v4_le_bits(z, hairobb__v4_set1(rs->tfar * rs->dir_length)) + 15) & 16;
    /* The same for the two lines parallel to the chord P0 P3 at distance
       max_r, widened by the rounding of the curve's points as the exact test
       evaluates them: |n.P2(u)| <= |n| |P2(u)| <= |n| r(u) on the ribbon,
       and n.P2(u) lies between the extreme n.Pi. */
    {
        float nx = c.y[0] - c.y[3], ny = c.x[3] - c.x[0], limit;
        hairobb__v4 d;
        magnitude = hairobb__v4_hmax(hairobb__v4_max(hairobb__v4_abs(x), hairobb__v4_abs(y)));
        limit = sqrtf(nx * nx + ny * ny) * (max_r + magnitude * (16.0f * FLT_EPSILON));
        d = hairobb__v4_add(hairobb__v4_mul(hairobb__v4_set1(nx), x), hairobb__v4_mul(hairobb__v4_set1(ny), y));
        inside &= (hairobb__v4_le_bits(d, hairobb__v4_set1(limit)) + 15) & (hairobb__v4_le_bits(hairobb__v4_set1(-limit), d) + 15);
        if (!inside) return 0;   /* both tests, one branch */
    }
    return hairobb__intersect_curve(bvh, rs, &c, magnitude, prim, any_hit);
}

static int hairobb__intersect_leaf(const hairobb_bvh *bvh, hairobb__ray_state *rs, uint64_t ref, int any_hit)
{
    size_t first = (size_t)(ref >> 8), count = (size_t)((ref >> 4) & 15u), i;
    int found = 0;
    for (i = 0; i < count; ++i) {
        if (hairobb__intersect_segment(bvh, rs, bvh->leaf_prims[first + i], any_hit)) {
            found = 1;
            if (any_hit) return 1;
        }
    }
    return found;
}

/* hairobb__bezier's value and first derivative for 4 curves at once, one
   per lane, rounded as it rounds: rows p0..p3 hold the control points. */
static void hairobb__bezier_v4(hairobb__v4 p0, hairobb__v4 p1, hairobb__v4 p2, hairobb__v4 p3, float u,
                               hairobb__v4 *value, hairobb__v4 *d1)
{
    float s = 1.0f - u;
    hairobb__v4 e0 = hairobb__v4_sub(p1, p0), e1 = hairobb__v4_sub(p2, p1), e2 = hairobb__v4_sub(p3, p2);
    *d1 = hairobb__v4_mul(hairobb__v4_set1(3.0f),
                          hairobb__v4_add(hairobb__v4_add(hairobb__v4_mul(hairobb__v4_set1(s * s), e0),
                                                          hairobb__v4_mul(hairobb__v4_set1(2.0f * u * s), e1)),
                                          hairobb__v4_mul(hairobb__v4_set1(u * u), e2)));
    *value = hairobb__v4_add(hairobb__v4_add(hairobb__v4_add(hairobb__v4_mul(hairobb__v4_set1(s * s * s), p0),
                                                             hairobb__v4_mul(hairobb__v4_set1(3.0f * u * s * s), p1)),
                                             hairobb__v4_mul(hairobb__v4_set1(3.0f * u * u * s), p2)),
                             hairobb__v4_mul(hairobb__v4_set1(u * u * u), p3));
}

/* Hit attributes, computed once for the final hit only. */
static void hairobb__fill_hit(const hairobb_bvh *bvh, const hairobb__ray_state *rs, hairobb_hit *hit)
{
    const float *cp = bvh->vertices + 4 * (size_t)bvh->indices[rs->hit_prim];
    hairobb__ray_curve c;
    hairobb__v4 x4, y4, z4, r4, value, d1;
    float u = rs->hit_u, at[4], tangent_at[4], tangent_xy[2], x, y, r, tlen2, along, n[3], nlen;
    const float *unit_dir = rs->frame + 6;
    int k;
    hairobb__bezier_v4(hairobb__v4_load(cp), hairobb__v4_load(cp + 4), hairobb__v4_load(cp + 8), hairobb__v4_load(cp + 12),
                       u, &value, &d1);
    hairobb__v4_store(tangent_at, d1);
    for (k = 0; k < 3; ++k) hit->tangent[k] = tangent_at[k];
    hairobb__to_ray_space_v4(rs, cp, &c, &x4, &y4, &z4, &r4);
    hairobb__v4_transpose(&x4, &y4, &z4, &r4);     /* rows: control points (x, y, z, r) */
    hairobb__bezier_v4(x4, y4, z4, r4, u, &value, &d1);
    hairobb__v4_store(at, value);
    hairobb__v4_store(tangent_at, d1);
    x = at[0]; y = at[1]; r = at[3];
    tangent_xy[0] = tangent_at[0]; tangent_xy[1] = tangent_at[1];
    tlen2 = tangent_xy[0] * tangent_xy[0] + tangent_xy[1] * tangent_xy[1];
    hit->v = 0.0f;
    if (r > 0.0f && tlen2 > 0.0f) {
        hit->v = (tangent_xy[1] * x - tangent_xy[0] * y) / (sqrtf(tlen2) * r);
        hit->v = hairobb__maxf(-1.0f, hairobb__minf(1.0f, hit->v));
    }
    /* the ribbon's normal: -dir without its component along the tangent */
    along = hairobb__dot3(unit_dir, hit->tangent);
    tlen2 = hairobb__dot3(hit->tangent, hit->tangent);
    for (k = 0; k < 3; ++k) n[k] = -unit_dir[k] + (tlen2 > 0.0f ? along * hit->tangent[k] / tlen2 : 0.0f);
    nlen = sqrtf(hairobb__dot3(n, n));
    for (k = 0; k < 3; ++k) hit->Ng[k] = nlen > 0.0f ? n[k] / nlen : -unit_dir[k];
    hit->t = rs->tfar;
    hit->u = u;
    hit->prim_id = rs->hit_prim;
}

HAIROBB_DEF int hairobb_intersect1(const hairobb_bvh *bvh, const hairobb_ray *ray, hairobb_hit *hit)
{
    hairobb__ray_state rs;
    if (!hit) return 0;
    hit->prim_id = HAIROBB_INVALID_ID;
    if (!bvh || !ray || !hairobb__ray_setup(&rs, ray)) return 0;
    if (!hairobb__traverse(bvh, &rs, 0)) return 0;
    hairobb__fill_hit(bvh, &rs, hit);
    return 1;
}

HAIROBB_DEF int hairobb_occluded1(const hairobb_bvh *bvh, const hairobb_ray *ray)
{
    hairobb__ray_state rs;
    if (!bvh || !ray || !hairobb__ray_setup(&rs, ray)) return 0;
    return hairobb__traverse(bvh, &rs, 1);
}

#endif /* HAIROBB_IMPLEMENTATION_DONE */
#endif /* HAIROBB_IMPLEMENTATION */

/*
------------------------------------------------------------------------------
This software is available under 2 licenses -- choose whichever you prefer.
------------------------------------------------------------------------------
ALTERNATIVE A - MIT License
Copyright (c) 2026 the hairobb authors
Permission is hereby granted, free of charge, to any person obtaining a copy of
this software and associated documentation files (the "Software"), to deal in
the Software without restriction, including without limitation the rights to
use, copy, modify, merge, publish, distribute, sublicense, and/or sell copies
of the Software, and to permit persons to whom the Software is furnished to do
so, subject to the following conditions:
The above copyright notice and this permission notice shall be included in all
copies or substantial portions of the Software.
THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER
LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE
SOFTWARE.
------------------------------------------------------------------------------
ALTERNATIVE B - Public Domain (www.unlicense.org)
This is free and unencumbered software released into the public domain.
Anyone is free to copy, modify, publish, use, compile, sell, or distribute this
software, either in source code form or as a compiled binary, for any purpose,
commercial or non-commercial, and by any means.
In jurisdictions that recognize copyright laws, the author or authors of this
software dedicate any and all copyright interest in the software to the public
domain. We make this dedication in the interest of the public and to the benefit
of the public at large and to the detriment of our heirs and successors. We
intend this dedication to be an overt act of relinquishment in perpetuity of
all present and future rights to this software under copyright law.
THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER
LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE
SOFTWARE.
------------------------------------------------------------------------------
*/
