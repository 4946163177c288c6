/*
 * reference.h - independent double-precision reference ray/hair intersector
 *               used by the hairobb test suite to judge hairobb.h.
 *
 * It is deliberately written WITHOUT looking at hairobb.h and shares no code
 * with it: it implements the surface definition below as literally as
 * possible, favouring obvious correctness over speed.
 *
 * Surface definition
 * ------------------
 * Segment i is a cubic Bezier with 4 consecutive control points starting at
 * vertex indices[i]; each vertex is 4 floats (x, y, z, radius) (Embree's
 * RTC_FORMAT_FLOAT4 layout). Position P(u) and radius r(u) are the cubic
 * Bezier of the control points / radii, u in [0,1].
 * Each segment is a ray-facing ribbon (Embree's FLAT curve). In ray space
 * (origin at the ray origin, z along d^ = dir/|dir|, x and y an orthonormal
 * pair with x cross y = z) let P(u) = (x, y, z)(u) and P2 = (x, y).
 * The ribbon is hit at every u in [0,1] where
 *     f(u) = dot(P2(u), P2'(u)) = 0   and   |P2(u)| <= r(u),
 * at distance t = z(u) / |dir| (so org + t*dir lies on the centre line's
 * depth). The first hit is the smallest t in [tnear, tfar] (inclusive) over
 * all roots of all segments.
 * Across-ribbon coordinate (frame independent): with T = P'(u), C = P(u),
 * X = org + t*dir, T_perp = T - dot(T,d^) d^,
 *     v = dot(cross(T, X - C), d^) / (|T_perp| * r(u)),   v = 0 if r(u) == 0
 *                                                          or |T_perp| == 0.
 *
 * Method
 * ------
 * All arithmetic is double on the float inputs (converted first).
 * f has degree 5. It is written in Bernstein form on [0,1] and its roots are
 * isolated by recursive de Casteljau halving: by the variation-diminishing
 * property a coefficient sequence with no sign change has no root in the
 * open interval, and one with exactly one sign change has exactly one, which
 * is then refined by bisection to ~1e-15 in u. Roots exactly at u = 0,
 * u = 1 and at a halving point are detected by exact zero coefficients.
 * Documented limitations (inherent to a floating-point reference):
 *  - double roots (f touches zero without changing sign) are ignored unless
 *    the rounded coefficients happen to show a sign change or an exact zero;
 *    after REF_MAX_DEPTH halvings, an interval with an even number of sign
 *    changes is dropped.
 *  - if f vanishes identically (e.g. a zero-length segment, or a segment
 *    whose projection is a single point), only u = 0 and u = 1 are tested.
 *  - a segment whose vertex index is out of range or whose data is not
 *    finite never hits (ref_build drops it; ref_intersect_segment trusts
 *    the caller on indices).
 * The scene acceleration is a binary object-median BVH over per-segment
 * boxes (control-point box dilated by the largest radius, padded outward),
 * traversed with a conservative, padded, inclusive slab test.
 */
#ifndef HAIROBB_TESTS_REFERENCE_H
#define HAIROBB_TESTS_REFERENCE_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

typedef struct ref_hit {
    double t, u, v;
    double r; /* r(u) at the hit */
    uint32_t prim_id;
} ref_hit;

#define REF_INVALID_ID 0xffffffffu
/* Halving depth for root isolation: 2^-50 ~ 9e-16 in u. */
#define REF_MAX_DEPTH 50
/* Relative pad applied to boxes and slab distances to absorb rounding. */
#define REF_REL_PAD 1e-12
#define REF_ABS_PAD 1e-300
#define REF_LEAF_SIZE 4

/* ------------------------------------------------------------------------ */
/* Ray set-up                                                               */
/* ------------------------------------------------------------------------ */

typedef struct ref__ray {
    double org[3], dir[3];
    double dir_len;
    double axis_x[3], axis_y[3], axis_z[3]; /* ray-space frame, z = d^ */
    double inv_dir[3];
    int dir_is_zero[3];
    int valid; /* 0 for a zero-length or non-finite direction */
} ref__ray;

static inline double ref__dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline void ref__cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static inline void ref__ray_setup(ref__ray *ray, const float org[3], const float dir[3])
{
    int k;
    double len, s;
    const double *d = ray->axis_z;
    for (k = 0; k < 3; ++k) {
        ray->org[k] = (double)org[k];
        ray->dir[k] = (double)dir[k];
    }
    len = sqrt(ref__dot3(ray->dir, ray->dir));
    ray->dir_len = len;
    ray->valid = (len > 0.0) && (len < HUGE_VAL) &&
                 (ray->org[0] - ray->org[0] == 0.0) && (ray->org[1] - ray->org[1] == 0.0) &&
                 (ray->org[2] - ray->org[2] == 0.0);
    if (!ray->valid)
        return;
    for (k = 0; k < 3; ++k) {
        ray->axis_z[k] = ray->dir[k] / len;
        ray->dir_is_zero[k] = (ray->dir[k] == 0.0);
        ray->inv_dir[k] = ray->dir_is_zero[k] ? 0.0 : 1.0 / ray->dir[k];
    }
    /* x axis: perpendicular to d^, built from the two larger components so
     * the normalisation is well conditioned. */
    if (fabs(d[0]) > fabs(d[1])) {
        s = sqrt(d[0] * d[0] + d[2] * d[2]);
        ray->axis_x[0] = -d[2] / s;
        ray->axis_x[1] = 0.0;
        ray->axis_x[2] = d[0] / s;
    } else {
        s = sqrt(d[1] * d[1] + d[2] * d[2]);
        ray->axis_x[0] = 0.0;
        ray->axis_x[1] = d[2] / s;
        ray->axis_x[2] = -d[1] / s;
    }
    /* y = z cross x, which makes x cross y = z. */
    ref__cross3(ray->axis_z, ray->axis_x, ray->axis_y);
}

/* ------------------------------------------------------------------------ */
/* Polynomials                                                              */
/* ------------------------------------------------------------------------ */

/* The lerp form a + u(b - a) returns a exactly when a == b, so constant
 * coordinates (and the resulting t) are reproduced exactly. */
static inline double ref__lerp(double a, double b, double u)
{
    return a + u * (b - a);
}

/* Cubic Bezier value and derivative at u, by de Casteljau. */
static inline void ref__cubic_eval(const double c[4], double u, double *value, double *derivative)
{
    double a0 = ref__lerp(c[0], c[1], u);
    double a1 = ref__lerp(c[1], c[2], u);
    double a2 = ref__lerp(c[2], c[3], u);
    double b0 = ref__lerp(a0, a1, u);
    double b1 = ref__lerp(a1, a2, u);
    *value = ref__lerp(b0, b1, u);
    if (derivative)
        *derivative = 3.0 * (b1 - b0);
}

/* Degree-5 Bernstein polynomial value at u, by de Casteljau (stable). */
static inline double ref__quintic_eval(const double c[6], double u)
{
    double w[6];
    int i, level;
    for (i = 0; i < 6; ++i)
        w[i] = c[i];
    for (level = 5; level > 0; --level)
        for (i = 0; i < level; ++i)
            w[i] = ref__lerp(w[i], w[i + 1], u);
    return w[0];
}

/* Split a degree-5 Bernstein polynomial at the middle of its interval. */
static inline void ref__quintic_halve(const double c[6], double left[6], double right[6])
{
    double w[6];
    int i, level;
    for (i = 0; i < 6; ++i)
        w[i] = c[i];
    left[0] = w[0];
    right[5] = w[5];
    for (level = 5; level > 0; --level) {
        for (i = 0; i < level; ++i)
            w[i] = 0.5 * (w[i] + w[i + 1]);
        left[6 - level] = w[0];
        right[level - 1] = w[level - 1];
    }
}

static inline int ref__sign(double x)
{
    return (x > 0.0) - (x < 0.0);
}

#define REF_MAX_ROOTS 32

typedef struct ref__roots {
    const double *coef; /* f on [0,1], for evaluation during refinement */
    double u[REF_MAX_ROOTS];
    int count;
} ref__roots;

static inline void ref__add_root(ref__roots *roots, double u)
{
    if (roots->count < REF_MAX_ROOTS)
        roots->u[roots->count++] = u;
}

/* Bisection for the single root in the open interval (a, b); f has sign
 * sign_left just right of a and the opposite sign just left of b. */
static inline double ref__bisect(const double coef[6], double a, double b, int sign_left)
{
    int iter;
    for (iter = 0; iter < 200 && b - a > 1e-15; ++iter) {
        double m = 0.5 * (a + b);
        double fm;
        int s;
        if (m <= a || m >= b)
            break;
        fm = ref__quintic_eval(coef, m);
        s = ref__sign(fm);
        if (s == 0)
            return m;
        if (s == sign_left)
            a = m;
        else
            b = m;
    }
    return 0.5 * (a + b);
}

/* c: Bernstein coefficients of f restricted to [a, b]. Finds the roots in
 * the open interval (a, b); an exact zero at a halving point is a root. */
static inline void ref__isolate(ref__roots *roots, const double c[6], double a, double b, int depth)
{
    int i, variations = 0, first_sign = 0, last_sign = 0;
    double left[6], right[6], m;
    for (i = 0; i < 6; ++i) {
        int s = ref__sign(c[i]);
        if (s == 0)
            continue;
        if (first_sign == 0)
            first_sign = s;
        else if (s != last_sign)
            ++variations;
        last_sign = s;
    }
    if (variations == 0)
        return; /* no root in (a, b) */
    if (variations == 1) {
        ref__add_root(roots, ref__bisect(roots->coef, a, b, first_sign));
        return;
    }
    if (depth >= REF_MAX_DEPTH) {
        /* Tiny interval with >= 2 sign changes: an odd count of roots is
         * certain when the end signs differ; an even count (typically a
         * double root) is dropped. */
        if (first_sign != last_sign)
            ref__add_root(roots, ref__bisect(roots->coef, a, b, first_sign));
        return;
    }
    ref__quintic_halve(c, left, right);
    m = 0.5 * (a + b);
    if (left[5] == 0.0)
        ref__add_root(roots, m);
    ref__isolate(roots, left, a, m, depth + 1);
    ref__isolate(roots, right, m, b, depth + 1);
}

/* ------------------------------------------------------------------------ */
/* One segment                                                              */
/* ------------------------------------------------------------------------ */

/* ctrl: the 16 floats of the 4 control points. Writes hit (without prim_id)
 * only when returning 1. Ties in t keep the smaller u. */
/* 1 if all four coordinates lie on one side of [-radius, radius], padded. */
static inline int ref__farther_than(const double p[4], double radius)
{
    double lo = p[0], hi = p[0], pad;
    int i;
    for (i = 1; i < 4; ++i) {
        lo = p[i] < lo ? p[i] : lo;
        hi = p[i] > hi ? p[i] : hi;
    }
    pad = radius + REF_REL_PAD * (radius + fabs(lo) + fabs(hi)) + REF_ABS_PAD;
    return lo > pad || hi < -pad;
}

static inline int ref__segment_hit(const ref__ray *ray, const float *ctrl, double tnear, double tfar, ref_hit *hit)
{
    double rel[3][4];   /* control points relative to the origin, world axes */
    double radius[4];
    double px[4], py[4], pz[4]; /* control points in ray space */
    double dx[3], dy[3];        /* derivative control points / 3 */
    double coef[6];
    double max_radius, zmin, zmax, len = ray->dir_len;
    ref__roots roots;
    int i, k, found = 0;
    ref_hit best;

    if (!ray->valid)
        return 0;
    for (i = 0; i < 4; ++i) {
        double c[3];
        for (k = 0; k < 3; ++k) {
            rel[k][i] = (double)ctrl[4 * i + k] - ray->org[k];
            c[k] = rel[k][i];
        }
        radius[i] = (double)ctrl[4 * i + 3];
        px[i] = ref__dot3(c, ray->axis_x);
        py[i] = ref__dot3(c, ray->axis_y);
        pz[i] = ref__dot3(c, ray->axis_z);
    }
    max_radius = radius[0];
    for (i = 1; i < 4; ++i)
        max_radius = radius[i] > max_radius ? radius[i] : max_radius;
    if (!(max_radius >= 0.0))
        return 0; /* negative everywhere (or NaN): |P2| <= r impossible */

    /* Early-out: the projected curve lies in the hull of the projected
     * control points, so it is farther than max_radius from the ray if the
     * hull's 2D bounds are. Same for the depth range vs [tnear, tfar]. */
    if (ref__farther_than(px, max_radius) || ref__farther_than(py, max_radius))
        return 0;
    zmin = zmax = pz[0];
    for (i = 1; i < 4; ++i) {
        zmin = pz[i] < zmin ? pz[i] : zmin;
        zmax = pz[i] > zmax ? pz[i] : zmax;
    }
    zmin /= len;
    zmax /= len;
    if (zmax + REF_REL_PAD * fabs(zmax) + REF_ABS_PAD < tnear ||
        zmin - REF_REL_PAD * fabs(zmin) - REF_ABS_PAD > tfar)
        return 0;

    /* f = x x' + y y'. With x = sum x_i B3_i and x' = 3 sum (x_{j+1}-x_j) B2_j,
     * the product B3_i B2_j = C(3,i) C(2,j) / C(5,i+j) B5_{i+j}. The common
     * factor 3 is dropped (it does not move roots). */
    for (i = 0; i < 3; ++i) {
        dx[i] = px[i + 1] - px[i];
        dy[i] = py[i + 1] - py[i];
    }
#define REF_PD(i, j) (px[i] * dx[j] + py[i] * dy[j])
    coef[0] = REF_PD(0, 0);
    coef[1] = (2.0 * REF_PD(0, 1) + 3.0 * REF_PD(1, 0)) / 5.0;
    coef[2] = (REF_PD(0, 2) + 6.0 * REF_PD(1, 1) + 3.0 * REF_PD(2, 0)) / 10.0;
    coef[3] = (3.0 * REF_PD(1, 2) + 6.0 * REF_PD(2, 1) + REF_PD(3, 0)) / 10.0;
    coef[4] = (3.0 * REF_PD(2, 2) + 2.0 * REF_PD(3, 1)) / 5.0;
    coef[5] = REF_PD(3, 2);
#undef REF_PD

    roots.coef = coef;
    roots.count = 0;
    if (coef[0] == 0.0)
        ref__add_root(&roots, 0.0);
    if (coef[5] == 0.0)
        ref__add_root(&roots, 1.0);
    ref__isolate(&roots, coef, 0.0, 1.0, 0);

    best.t = best.u = best.v = best.r = 0.0;
    best.prim_id = REF_INVALID_ID;
    for (i = 0; i < roots.count; ++i) {
        double u = roots.u[i];
        double x, y, z, r, t;
        ref__cubic_eval(px, u, &x, NULL);
        ref__cubic_eval(py, u, &y, NULL);
        ref__cubic_eval(radius, u, &r, NULL);
        if (!(r >= 0.0) || !(x * x + y * y <= r * r))
            continue;
        ref__cubic_eval(pz, u, &z, NULL);
        t = z / len;
        if (!(t >= tnear && t <= tfar))
            continue;
        if (found && !(t < best.t || (t == best.t && u < best.u)))
            continue;
        found = 1;
        best.t = t;
        best.u = u;
        best.r = r;
    }
    if (!found)
        return 0;

    /* v, literally from the definition, in world axes relative to org. */
    {
        double tangent[3], centre[3], offset[3], tperp[3], cr[3];
        double along, tperp_len;
        for (k = 0; k < 3; ++k) {
            ref__cubic_eval(rel[k], best.u, &centre[k], &tangent[k]);
            offset[k] = best.t * ray->dir[k] - centre[k]; /* X - C */
        }
        ref__cross3(tangent, offset, cr);
        along = ref__dot3(tangent, ray->axis_z);
        for (k = 0; k < 3; ++k)
            tperp[k] = tangent[k] - along * ray->axis_z[k];
        tperp_len = sqrt(ref__dot3(tperp, tperp));
        if (best.r == 0.0 || tperp_len == 0.0)
            best.v = 0.0;
        else
            best.v = ref__dot3(cr, ray->axis_z) / (tperp_len * best.r);
    }
    *hit = best;
    return 1;
}

/* All roots of one segment against a ray; writes the smallest-t hit in
 * [tnear, tfar] and returns 1, or returns 0 and leaves *hit untouched. */
static inline int ref_intersect_segment(const float *vertices, const uint32_t *indices, uint32_t prim,
                                        const float org[3], const float dir[3], double tnear, double tfar,
                                        ref_hit *hit)
{
    ref__ray ray;
    ref_hit h;
    ref__ray_setup(&ray, org, dir);
    if (!ref__segment_hit(&ray, vertices + 4 * (size_t)indices[prim], tnear, tfar, &h))
        return 0;
    h.prim_id = prim;
    *hit = h;
    return 1;
}

/* ------------------------------------------------------------------------ */
/* BVH                                                                      */
/* ------------------------------------------------------------------------ */

typedef struct ref__node {
    double lo[3], hi[3];
    uint32_t right_or_first; /* inner: right child index (left is next); leaf: first slot */
    uint32_t count;          /* 0 for inner nodes */
    int axis;                /* inner: split axis, for front-to-back order */
} ref__node;

typedef struct ref_scene ref_scene; /* the scene: owned input copies + BVH */

struct ref_scene {
    float *vertices; /* owned copies of the input */
    uint32_t *indices;
    size_t segment_count;
    ref__node *nodes;
    size_t node_count;
    uint32_t *prims; /* leaf slots -> segment ids */
    double *boxes;   /* build-time only: 6 per segment (lo, hi) */
    double *centroids; /* build-time only: 3 per segment */
};

/* Partial sort: afterwards every key in [first, k) <= key(k) <= every key in
 * (k, last). Three-way partition so equal keys cannot cause quadratic time. */
static inline void ref__select(uint32_t *ids, const double *centroids, int axis, size_t first, size_t last,
                               size_t k)
{
    while (last - first > 1) {
        double pivot = centroids[3 * (size_t)ids[first + (last - first) / 2] + (size_t)axis];
        size_t lt = first, i = first, gt = last;
        while (i < gt) {
            double key = centroids[3 * (size_t)ids[i] + (size_t)axis];
            uint32_t tmp;
            if (key < pivot) {
                tmp = ids[lt]; ids[lt] = ids[i]; ids[i] = tmp;
                ++lt;
                ++i;
            } else if (key > pivot) {
                --gt;
                tmp = ids[gt]; ids[gt] = ids[i]; ids[i] = tmp;
            } else {
                ++i;
            }
        }
        if (k < lt)
            last = lt;
        else if (k >= gt)
            first = gt;
        else
            return;
    }
}

/* Builds the subtree over prims[first, last); returns its node index.
 * The object-median split halves the count, so depth <= log2(n) + 1. */
static inline uint32_t ref__build_node(ref_scene *s, size_t first, size_t last)
{
    uint32_t index = (uint32_t)s->node_count++;
    ref__node *node = &s->nodes[index];
    double clo[3], chi[3];
    size_t i;
    int k, axis;
    for (k = 0; k < 3; ++k) {
        node->lo[k] = clo[k] = HUGE_VAL;
        node->hi[k] = chi[k] = -HUGE_VAL;
    }
    for (i = first; i < last; ++i) {
        const double *box = s->boxes + 6 * (size_t)s->prims[i];
        const double *cen = s->centroids + 3 * (size_t)s->prims[i];
        for (k = 0; k < 3; ++k) {
            node->lo[k] = box[k] < node->lo[k] ? box[k] : node->lo[k];
            node->hi[k] = box[3 + k] > node->hi[k] ? box[3 + k] : node->hi[k];
            clo[k] = cen[k] < clo[k] ? cen[k] : clo[k];
            chi[k] = cen[k] > chi[k] ? cen[k] : chi[k];
        }
    }
    node->axis = 0;
    if (last - first <= REF_LEAF_SIZE) {
        node->right_or_first = (uint32_t)first;
        node->count = (uint32_t)(last - first);
        return index;
    }
    axis = 0;
    for (k = 1; k < 3; ++k)
        if (chi[k] - clo[k] > chi[axis] - clo[axis])
            axis = k;
    {
        size_t mid = first + (last - first) / 2;
        uint32_t right;
        ref__select(s->prims, s->centroids, axis, first, last, mid);
        ref__build_node(s, first, mid);
        right = ref__build_node(s, mid, last);
        node = &s->nodes[index];
        node->right_or_first = right;
        node->count = 0;
        node->axis = axis;
    }
    return index;
}

static inline void ref_free(ref_scene *s)
{
    if (!s)
        return;
    free(s->vertices);
    free(s->indices);
    free(s->nodes);
    free(s->prims);
    free(s->boxes);
    free(s->centroids);
    free(s);
}

static inline ref_scene *ref_build(const float *vertices, size_t vertex_count, const uint32_t *indices,
                                   size_t segment_count)
{
    ref_scene *s = (ref_scene *)calloc(1, sizeof(ref_scene));
    size_t i, valid = 0;
    if (!s)
        return NULL;
    /* +1 so a zero count never turns into a NULL from malloc(0). */
    s->vertices = (float *)malloc((4 * vertex_count + 1) * sizeof(float));
    s->indices = (uint32_t *)malloc((segment_count + 1) * sizeof(uint32_t));
    s->prims = (uint32_t *)malloc((segment_count + 1) * sizeof(uint32_t));
    s->boxes = (double *)malloc((6 * segment_count + 1) * sizeof(double));
    s->centroids = (double *)malloc((3 * segment_count + 1) * sizeof(double));
    s->nodes = (ref__node *)malloc((2 * segment_count + 1) * sizeof(ref__node));
    if (!s->vertices || !s->indices || !s->prims || !s->boxes || !s->centroids || !s->nodes ||
        segment_count >= REF_INVALID_ID) {
        ref_free(s);
        return NULL;
    }
    for (i = 0; i < 4 * vertex_count; ++i)
        s->vertices[i] = vertices[i];
    for (i = 0; i < segment_count; ++i)
        s->indices[i] = indices[i];
    s->segment_count = segment_count;

    for (i = 0; i < segment_count; ++i) {
        double *box = s->boxes + 6 * i;
        const float *ctrl;
        double max_radius;
        int j, k, finite = 1;
        if ((size_t)indices[i] + 4 > vertex_count)
            continue; /* out of range: never hits */
        ctrl = s->vertices + 4 * (size_t)indices[i];
        max_radius = 0.0;
        for (k = 0; k < 3; ++k) {
            box[k] = HUGE_VAL;
            box[3 + k] = -HUGE_VAL;
        }
        for (j = 0; j < 4; ++j) {
            double r = (double)ctrl[4 * j + 3];
            for (k = 0; k < 3; ++k) {
                double c = (double)ctrl[4 * j + k];
                finite &= (c - c == 0.0);
                box[k] = c < box[k] ? c : box[k];
                box[3 + k] = c > box[3 + k] ? c : box[3 + k];
            }
            finite &= (r - r == 0.0);
            max_radius = r > max_radius ? r : max_radius;
        }
        if (!finite)
            continue; /* NaN/inf data: never hits */
        /* Any hit point X lies within r(u) <= max_radius of P(u), which lies
         * in the control-point hull; pad outward for rounding. */
        for (k = 0; k < 3; ++k) {
            double lo = box[k] - max_radius, hi = box[3 + k] + max_radius;
            double pad = REF_REL_PAD * (fabs(lo) + fabs(hi) + max_radius) + REF_ABS_PAD;
            box[k] = lo - pad;
            box[3 + k] = hi + pad;
            s->centroids[3 * i + (size_t)k] = 0.5 * (box[k] + box[3 + k]);
        }
        s->prims[valid++] = (uint32_t)i;
    }
    if (valid > 0)
        ref__build_node(s, 0, valid);
    free(s->boxes);
    free(s->centroids);
    s->boxes = NULL;
    s->centroids = NULL;
    return s;
}

/* Conservative, inclusive slab test: is some t in [tnear, tfar] inside the
 * box (up to a relative pad on the slab distances)? */
static inline int ref__box_hit(const ref__ray *ray, const double lo[3], const double hi[3], double tnear, double tfar)
{
    int k;
    for (k = 0; k < 3; ++k) {
        double t0, t1;
        if (ray->dir_is_zero[k]) {
            if (ray->org[k] < lo[k] || ray->org[k] > hi[k])
                return 0;
            continue;
        }
        t0 = (lo[k] - ray->org[k]) * ray->inv_dir[k];
        t1 = (hi[k] - ray->org[k]) * ray->inv_dir[k];
        if (t0 > t1) {
            double tmp = t0;
            t0 = t1;
            t1 = tmp;
        }
        t0 -= REF_REL_PAD * fabs(t0) + REF_ABS_PAD;
        t1 += REF_REL_PAD * fabs(t1) + REF_ABS_PAD;
        tnear = t0 > tnear ? t0 : tnear;
        tfar = t1 < tfar ? t1 : tfar;
        if (tnear > tfar)
            return 0;
    }
    return 1;
}

#define REF_STACK_SIZE 128 /* tree depth <= log2(2^32) + 2, two pushes per level */

/* Nearest hit over all segments in [tnear, tfar]; ties in t go to the
 * smaller prim id. Returns 1 on a hit; on a miss returns 0 and writes
 * t = tfar, u = v = r = 0, prim_id = REF_INVALID_ID (0xffffffff). */
static inline int ref_intersect(const ref_scene *s, const float org[3], const float dir[3], double tnear,
                                double tfar, ref_hit *hit)
{
    ref__ray ray;
    uint32_t stack[REF_STACK_SIZE];
    int sp = 0, found = 0;
    ref_hit best;
    best.t = tfar;
    best.u = best.v = best.r = 0.0;
    best.prim_id = REF_INVALID_ID;
    ref__ray_setup(&ray, org, dir);
    if (s && s->node_count > 0 && ray.valid)
        stack[sp++] = 0;
    while (sp > 0) {
        const ref__node *node = &s->nodes[stack[--sp]];
        double limit = found ? best.t : tfar;
        if (!ref__box_hit(&ray, node->lo, node->hi, tnear, limit))
            continue;
        if (node->count > 0) {
            uint32_t i;
            for (i = 0; i < node->count; ++i) {
                uint32_t prim = s->prims[node->right_or_first + i];
                ref_hit h;
                limit = found ? best.t : tfar;
                if (!ref__segment_hit(&ray, s->vertices + 4 * (size_t)s->indices[prim], tnear, limit, &h))
                    continue;
                if (found && !(h.t < best.t || (h.t == best.t && prim < best.prim_id)))
                    continue;
                found = 1;
                best = h;
                best.prim_id = prim;
            }
        } else {
            uint32_t left = (uint32_t)(node - s->nodes) + 1, right = node->right_or_first;
            /* Push the far child first so the near one is popped first. */
            if (ray.dir[node->axis] >= 0.0) {
                stack[sp++] = right;
                stack[sp++] = left;
            } else {
                stack[sp++] = left;
                stack[sp++] = right;
            }
        }
    }
    *hit = best;
    return found;
}

/* Calls fn(user, prim, &hit) for every segment with a hit in [tnear, tfar]
 * (hit = that segment's nearest), in traversal order; returns the count.
 * fn may be NULL to only count. */
static inline size_t ref_all_hits(const ref_scene *s, const float org[3], const float dir[3], double tnear,
                                  double tfar, void (*fn)(void *user, uint32_t prim, const ref_hit *hit),
                                  void *user)
{
    ref__ray ray;
    uint32_t stack[REF_STACK_SIZE];
    int sp = 0;
    size_t count = 0;
    ref__ray_setup(&ray, org, dir);
    if (s && s->node_count > 0 && ray.valid)
        stack[sp++] = 0;
    while (sp > 0) {
        const ref__node *node = &s->nodes[stack[--sp]];
        if (!ref__box_hit(&ray, node->lo, node->hi, tnear, tfar))
            continue;
        if (node->count > 0) {
            uint32_t i;
            for (i = 0; i < node->count; ++i) {
                uint32_t prim = s->prims[node->right_or_first + i];
                ref_hit h;
                if (!ref__segment_hit(&ray, s->vertices + 4 * (size_t)s->indices[prim], tnear, tfar, &h))
                    continue;
                h.prim_id = prim;
                ++count;
                if (fn)
                    fn(user, prim, &h);
            }
        } else {
            stack[sp++] = node->right_or_first;
            stack[sp++] = (uint32_t)(node - s->nodes) + 1;
        }
    }
    return count;
}

/* ------------------------------------------------------------------------ */
/* Motion blur                                                              */
/* ------------------------------------------------------------------------ */

/* Moving hair given at time_steps >= 1 times k / (time_steps - 1), every
 * step the same layout: floats [first, first + count) of it at `time` in
 * [0, 1], lerped in double between the two steps around time and rounded
 * to float into out (the float control points the reference then reads).
 * The pair and the weight come from time * (time_steps - 1) rounded to
 * float, as a float ray time scales; time_steps 1: a copy. */
static inline void ref_motion_points(const float *const *steps, int time_steps, float time, size_t first,
                                     size_t count, float *out)
{
    double f, w;
    int k;
    size_t j;
    if (time_steps < 2) {
        for (j = 0; j < count; ++j)
            out[j] = steps[0][first + j];
        return;
    }
    f = time * (float)(time_steps - 1);
    k = (int)f;
    if (k > time_steps - 2)
        k = time_steps - 2;
    w = f - k;
    for (j = 0; j < count; ++j)
        out[j] = (float)((1.0 - w) * (double)steps[k][first + j] + w * (double)steps[k + 1][first + j]);
}

#endif /* HAIROBB_TESTS_REFERENCE_H */
