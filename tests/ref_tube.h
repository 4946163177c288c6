/*
 * ref_tube.h - double-precision reference for round curves (tubes), the
 *              second shape of the round-curve issue; written from the
 *              definition below, sharing only reference.h's ray frame.
 *
 * Surface definition (Embree's cubic round curves, a swept circle)
 * ------------------------------------------------------------------
 * Segment: a cubic Bezier centre line c(u) and radius r(u), u in [0, 1], from
 * 4 control points (x, y, z, radius), as in reference.h. At each u the tube
 * is the circle of radius r(u) about c(u) in the plane normal to c'(u); the
 * ends are open (no caps). A point X is on the tube at u when
 *     dot(X - c(u), c'(u)) = 0   and   |X - c(u)| = r(u).
 * (This is not a sweep of spheres: with taper a sphere sweep is fatter by
 * about r (dr/ds)^2 / 2.) Both sheets count: the ray's entry and its exit.
 *
 * Method
 * ------
 * In ray space (origin at the ray origin, z along d^ = dir/|dir|, as
 * reference.h builds it) let c(u) = (x, y, z)(u). The plane normal to c'(u)
 * through c(u) meets the ray z axis at depth
 *     s(u) = z + (x x' + y y') / z'          (z' != 0),
 * at squared distance x^2 + y^2 + (x x' + y y')^2 / z'^2 from c(u). So the
 * ray meets the circle at u where
 *     H(u) = (x^2 + y^2 - r^2) z'^2 + (x x' + y y')^2 = 0,
 * a polynomial of degree 10, written exactly in Bernstein form on [0, 1]
 * (products of Bernstein polynomials) and solved as reference.h solves its
 * quintic: de Casteljau halving isolates each root (variation diminishing),
 * bisection refines it to 2^-50 in u. Each root with z'(u) != 0 is a hit at
 * t = s(u) / |dir| (each root polished on its sheet's own, unsquared
 * function w + sheet z' S, S = sqrt(r^2 - |P2|^2): H's squares lose the
 * precision when the ray is nearly perpendicular to a long segment); the
 * first hit is the smallest t in [tnear, tfar]
 * (inclusive), ties keeping the smaller u. Hits are classified by the outward
 * normal, the gradient of |X - c(u(X))|^2 - r(u(X))^2:
 *     n ~ R - r r' c' / (|c'|^2 - R.c''),   R = X - c(u),
 * which includes the curvature term; an exit hit has dot(n, dir) > 0.
 * v, the signed offset across the fibre in [-1, 1] a hair BSDF takes, is
 * reference.h's formula at the tube's hit point:
 *     v = dot(cross(c', X - c), d^) / (|c'_perp| r(u)).
 * Where z' = 0 at a root of w (the circle's plane holds the ray: a ray
 * perpendicular to the fibre), H has a double root there, and the hits are
 * taken from w's roots instead, at depths z -/+ S.
 * Limitation, inherent to a floating-point reference: a ray tangent to the
 * tube (a double root) is found only where rounding shows a sign change.
 */
#ifndef HAIROBB_TESTS_REF_TUBE_H
#define HAIROBB_TESTS_REF_TUBE_H

#include "reference.h"

typedef struct ref_tube_hit {
    double t, u, v;
    double r;           /* r(u) */
    double normal[3];   /* unit, outward, world space */
    int exit;           /* 1: the ray leaves the tube here (dot(normal, dir) > 0) */
    uint32_t prim_id;
} ref_tube_hit;

#define REF_TUBE_DEGREE 10
#define REF_TUBE_MAX_ROOTS 32

static inline double ref_tube__binomial(int n, int k)
{
    double b = 1.0;
    int i;
    for (i = 1; i <= k; ++i) b = b * (double)(n - k + i) / (double)i;
    return b;
}

/* out (degree m + n) = a (degree m) * b (degree n), all in Bernstein form */
static inline void ref_tube__multiply(const double *a, int m, const double *b, int n, double *out)
{
    int i, j;
    for (i = 0; i <= m + n; ++i) out[i] = 0.0;
    for (i = 0; i <= m; ++i)
        for (j = 0; j <= n; ++j)
            out[i + j] += ref_tube__binomial(m, i) * ref_tube__binomial(n, j) / ref_tube__binomial(m + n, i + j) * a[i] * b[j];
}

/* de Casteljau: the value at u, and (when left/right are given) the halves
   on [0, 1/2] and [1/2, 1] */
static inline double ref_tube__eval(const double *c, int n, double u)
{
    double w[REF_TUBE_DEGREE + 1];
    int i, k;
    for (i = 0; i <= n; ++i) w[i] = c[i];
    for (k = 1; k <= n; ++k)
        for (i = 0; i <= n - k; ++i) w[i] = w[i] + u * (w[i + 1] - w[i]);
    return w[0];
}

static inline void ref_tube__halve(const double *c, int n, double *left, double *right)
{
    double w[REF_TUBE_DEGREE + 1];
    int i, k;
    for (i = 0; i <= n; ++i) w[i] = c[i];
    left[0] = w[0];
    right[n] = w[n];
    for (k = 1; k <= n; ++k) {
        for (i = 0; i <= n - k; ++i) w[i] = 0.5 * (w[i] + w[i + 1]);
        left[k] = w[0];
        right[n - k] = w[n - k];
    }
}

typedef struct ref_tube__roots {
    const double *coef;
    int degree, count;
    double u[REF_TUBE_MAX_ROOTS];
} ref_tube__roots;

static inline void ref_tube__add(ref_tube__roots *roots, double u)
{
    if (roots->count < REF_TUBE_MAX_ROOTS) roots->u[roots->count++] = u;
}

static inline double ref_tube__bisect(const ref_tube__roots *roots, double a, double b, int sign_left)
{
    int iteration;
    for (iteration = 0; iteration < 200 && b - a > 0x1p-50; ++iteration) {
        double m = 0.5 * (a + b);
        int s = ref__sign(ref_tube__eval(roots->coef, roots->degree, m));
        if (m <= a || m >= b) break;
        if (s == 0) return m;
        if (s == sign_left) a = m; else b = m;
    }
    return 0.5 * (a + b);
}

static inline void ref_tube__isolate(ref_tube__roots *roots, const double *c, double a, double b, int depth)
{
    double left[REF_TUBE_DEGREE + 1], right[REF_TUBE_DEGREE + 1], m;
    int i, n = roots->degree, variations = 0, first_sign = 0, last_sign = 0;
    for (i = 0; i <= n; ++i) {
        int s = ref__sign(c[i]);
        if (s == 0) continue;
        if (first_sign == 0) first_sign = s;
        else if (s != last_sign) ++variations;
        last_sign = s;
    }
    if (variations == 0) return;
    if (variations == 1) {
        ref_tube__add(roots, ref_tube__bisect(roots, a, b, first_sign));
        return;
    }
    if (depth >= REF_MAX_DEPTH) {
        if (first_sign != last_sign) ref_tube__add(roots, ref_tube__bisect(roots, a, b, first_sign));
        return;
    }
    ref_tube__halve(c, n, left, right);
    m = 0.5 * (a + b);
    if (left[n] == 0.0) ref_tube__add(roots, m);
    ref_tube__isolate(roots, left, a, m, depth + 1);
    ref_tube__isolate(roots, right, m, b, depth + 1);
}

/* The value and first two derivatives of a cubic in Bernstein form at u. */
static inline void ref_tube__cubic(const double c[4], double u, double *value, double *d1, double *d2)
{
    double s = 1.0 - u;
    *value = s * s * s * c[0] + 3.0 * u * s * s * c[1] + 3.0 * u * u * s * c[2] + u * u * u * c[3];
    *d1 = 3.0 * (s * s * (c[1] - c[0]) + 2.0 * u * s * (c[2] - c[1]) + u * u * (c[3] - c[2]));
    *d2 = 6.0 * (s * (c[2] - 2.0 * c[1] + c[0]) + u * (c[3] - 2.0 * c[2] + c[1]));
}

/* sheet * (w + sheet z' sqrt(-q)) at u, unsquared (sheet +1: the entry, at
   depth z - S; -1: the exit, at z + S), and that depth in *depth. */
static inline double ref_tube__sheet(const double p[3][4], const double r[4], double u, double sheet, double *depth)
{
    double c[3], d1[3], d2[3], radius, dr, d2r, q, S;
    int k;
    for (k = 0; k < 3; ++k) ref_tube__cubic(p[k], u, &c[k], &d1[k], &d2[k]);
    ref_tube__cubic(r, u, &radius, &dr, &d2r);
    q = c[0] * c[0] + c[1] * c[1] - radius * radius;
    S = q < 0.0 ? sqrt(-q) : 0.0;
    *depth = c[2] - sheet * S;
    return c[0] * d1[0] + c[1] * d1[1] + sheet * d1[2] * S;
}

/* A root u of H polished on its sheet's own function, which keeps the
   precision H's squares lose when the ray is nearly perpendicular to a long
   segment (H's terms cancel there below double's epsilon): the nearest
   sign change around u, bisected to 1e-16. Returns the depth; u updated. */
static inline double ref_tube__polish(const double p[3][4], const double r[4], double *u, double sheet)
{
    double h = 1e-9, depth, lo, hi, g_lo, g_hi;
    for (; h < 0.05; h *= 4.0) {
        lo = *u - h < 0.0 ? 0.0 : *u - h;
        hi = *u + h > 1.0 ? 1.0 : *u + h;
        g_lo = ref_tube__sheet(p, r, lo, sheet, &depth);
        g_hi = ref_tube__sheet(p, r, hi, sheet, &depth);
        if ((g_lo < 0.0) != (g_hi < 0.0)) {
            int iteration;
            for (iteration = 0; iteration < 200 && hi - lo > 1e-16; ++iteration) {
                double middle = 0.5 * (lo + hi), g = ref_tube__sheet(p, r, middle, sheet, &depth);
                if (middle <= lo || middle >= hi) break;
                if ((g < 0.0) == (g_lo < 0.0)) lo = middle; else hi = middle;
            }
            *u = 0.5 * (lo + hi);
            break;
        }
    }
    ref_tube__sheet(p, r, *u, sheet, &depth);
    return depth;
}

/* ctrl: the 16 floats of one segment. Writes *hit (without prim_id) only
   when returning 1. all (optional, up to REF_TUBE_MAX_ROOTS): every hit in
   [tnear, tfar], in root order, and their count in *all_count. */
static inline int ref_tube_segment_hit(const ref__ray *ray, const float *ctrl, double tnear, double tfar, ref_tube_hit *hit,
                                       ref_tube_hit *all, int *all_count)
{
    double p[3][4], r[4], dp[3][3], square[3][7], a[7], dz2[5], w[6], wx[6], h[11], hz[11];
    ref_tube__roots roots;
    int i, k, found = 0;
    if (all_count) *all_count = 0;
    if (!ray->valid) return 0;
    for (i = 0; i < 4; ++i) {
        double q[3];
        for (k = 0; k < 3; ++k) q[k] = (double)ctrl[4 * i + k] - ray->org[k];
        p[0][i] = ref__dot3(q, ray->axis_x);
        p[1][i] = ref__dot3(q, ray->axis_y);
        p[2][i] = ref__dot3(q, ray->axis_z);
        r[i] = (double)ctrl[4 * i + 3];
    }
    for (k = 0; k < 3; ++k)
        for (i = 0; i < 3; ++i) dp[k][i] = 3.0 * (p[k][i + 1] - p[k][i]);
    ref_tube__multiply(p[0], 3, p[0], 3, square[0]);
    ref_tube__multiply(p[1], 3, p[1], 3, square[1]);
    ref_tube__multiply(r, 3, r, 3, square[2]);
    for (i = 0; i <= 6; ++i) a[i] = square[0][i] + square[1][i] - square[2][i];
    ref_tube__multiply(dp[2], 2, dp[2], 2, dz2);
    ref_tube__multiply(p[0], 3, dp[0], 2, w);
    ref_tube__multiply(p[1], 3, dp[1], 2, wx);
    for (i = 0; i <= 5; ++i) w[i] += wx[i];
    ref_tube__multiply(a, 6, dz2, 4, h);
    ref_tube__multiply(w, 5, w, 5, hz);
    for (i = 0; i <= REF_TUBE_DEGREE; ++i) h[i] += hz[i];
    roots.coef = h;
    roots.degree = REF_TUBE_DEGREE;
    roots.count = 0;
    if (h[0] == 0.0) ref_tube__add(&roots, 0.0);
    ref_tube__isolate(&roots, h, 0.0, 1.0, 0);
    if (h[REF_TUBE_DEGREE] == 0.0) ref_tube__add(&roots, 1.0);
    {
        /* Where the circle's plane holds the ray (z' = 0 there: a ray
           perpendicular to the fibre), H = w^2 has only double roots; the
           ray meets the circle at depths z -/+ S at the roots of w. Each such
           root enters twice (plane_sheet -1 and +1) after H's roots. */
        ref_tube__roots plane;
        int j, first_plane = roots.count;
        plane.coef = w;
        plane.degree = 5;
        plane.count = 0;
        if (w[0] == 0.0) ref_tube__add(&plane, 0.0);
        ref_tube__isolate(&plane, w, 0.0, 1.0, 0);
        if (w[5] == 0.0) ref_tube__add(&plane, 1.0);
        for (j = 0; j < plane.count && roots.count + 1 < REF_TUBE_MAX_ROOTS; ++j) {
            double c[3], d1[3], d2[3];
            for (k = 0; k < 3; ++k) ref_tube__cubic(p[k], plane.u[j], &c[k], &d1[k], &d2[k]);
            /* (no circle where the tangent vanishes: a repeated end point) */
            if (fabs(d1[2]) > 1e-12 * sqrt(d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2]) ||
                !(d1[0] * d1[0] + d1[1] * d1[1] > 0.0))
                continue;
            roots.u[roots.count++] = plane.u[j];
            roots.u[roots.count++] = plane.u[j];
        }
        for (i = 0; i < roots.count; ++i) {
            double u = roots.u[i], c[3], d1[3], d2[3], radius, dr, s, t, X[3], C[3], T[3], T2[3], R[3], n[3], rc, denominator;
            double cross[3], tperp[3], along, len;
            ref_tube_hit candidate;
            for (k = 0; k < 3; ++k) ref_tube__cubic(p[k], u, &c[k], &d1[k], &d2[k]);
            ref_tube__cubic(r, u, &radius, &dr, &len);
            if (i < first_plane) {
                if (d1[2] == 0.0) continue;
                s = c[2] + (c[0] * d1[0] + c[1] * d1[1]) / d1[2];
                /* the sheet s lies on, then the root polished on it */
                s = ref_tube__polish((const double (*)[4])p, r, &u, s <= c[2] ? 1.0 : -1.0);
                for (k = 0; k < 3; ++k) ref_tube__cubic(p[k], u, &c[k], &d1[k], &d2[k]);
                ref_tube__cubic(r, u, &radius, &dr, &len);
            } else {
                double q = c[0] * c[0] + c[1] * c[1] - radius * radius;
                if (q > 0.0) continue;
                s = c[2] + ((i - first_plane) % 2 == 0 ? -1.0 : 1.0) * sqrt(-q);
            }
            t = s / ray->dir_len;
            if (!(t >= tnear && t <= tfar)) continue;
        /* world space: the hit point, the centre, c' and c'' */
        for (k = 0; k < 3; ++k) {
            X[k] = ray->org[k] + t * ray->dir[k];
            C[k] = ray->org[k] + c[0] * ray->axis_x[k] + c[1] * ray->axis_y[k] + c[2] * ray->axis_z[k];
            T[k] = d1[0] * ray->axis_x[k] + d1[1] * ray->axis_y[k] + d1[2] * ray->axis_z[k];
            T2[k] = d2[0] * ray->axis_x[k] + d2[1] * ray->axis_y[k] + d2[2] * ray->axis_z[k];
            R[k] = X[k] - C[k];
        }
        {
            /* Where c' vanishes (a cusp, a collinear curve turning back,
               repeated control points) H has a root for any ray, whose
               depth s = z + w / z' is a ratio of vanishing terms: a hit
               only where X is on that u's circle, within the rounding of
               the polished root (1e-6 r, and 1e-12 of the coordinates) */
            double tolerance = 1e-6 * radius + 1e-12 * (sqrt(ref__dot3(C, C)) + sqrt(ref__dot3(X, X))), tangent = sqrt(ref__dot3(T, T));
            if (!(tangent > 0.0) || !(fabs(sqrt(ref__dot3(R, R)) - radius) <= tolerance) ||
                !(fabs(ref__dot3(R, T)) <= tolerance * tangent))
                continue;
        }
        denominator = ref__dot3(T, T) - ref__dot3(R, T2);
        rc = denominator != 0.0 ? radius * dr / denominator : 0.0;
        for (k = 0; k < 3; ++k) n[k] = R[k] - rc * T[k];
        len = sqrt(ref__dot3(n, n));
        if (len > 0.0)
            for (k = 0; k < 3; ++k) n[k] /= len;
        candidate.t = t;
        candidate.u = u;
        candidate.r = radius;
        for (k = 0; k < 3; ++k) candidate.normal[k] = n[k];
        candidate.exit = ref__dot3(n, ray->dir) > 0.0;
        along = ref__dot3(T, ray->axis_z);
        for (k = 0; k < 3; ++k) tperp[k] = T[k] - along * ray->axis_z[k];
        ref__cross3(T, R, cross);
        len = sqrt(ref__dot3(tperp, tperp));
        candidate.v = radius > 0.0 && len > 0.0 ? ref__dot3(cross, ray->axis_z) / (len * radius) : 0.0;
        candidate.v = candidate.v < -1.0 ? -1.0 : candidate.v > 1.0 ? 1.0 : candidate.v;
        candidate.prim_id = REF_INVALID_ID;
        if (all && all_count && *all_count < REF_TUBE_MAX_ROOTS) all[(*all_count)++] = candidate;
        if (!found || t < hit->t || (t == hit->t && u < hit->u)) {
            *hit = candidate;
            found = 1;
        }
        }
    }
    return found;
}

/* A flat end cap (end_caps): the disk of radius r(end) centred on the
   segment's end point (end 0 or 1), in the plane normal to c' there. A hit
   in [tnear, tfar] has u exactly end and the outward normal -c'(0) / c'(1)
   over its length; exit and v as for the sheets. */
static inline int ref_tube_cap_hit(const ref__ray *ray, const float *ctrl, int end, double tnear, double tfar, ref_tube_hit *hit)
{
    double C[3], T[3], X[3], R[3], cross[3], tperp[3], radius = (double)ctrl[12 * end + 3], along, t, d2 = 0.0, len;
    int k;
    if (!ray->valid) return 0;
    for (k = 0; k < 3; ++k) {
        C[k] = (double)ctrl[12 * end + k];
        T[k] = end ? 3.0 * ((double)ctrl[12 + k] - (double)ctrl[8 + k]) : 3.0 * ((double)ctrl[4 + k] - (double)ctrl[k]);
    }
    along = ref__dot3(T, ray->dir);
    if (along == 0.0 || !(radius > 0.0)) return 0;
    for (k = 0; k < 3; ++k) X[k] = C[k] - ray->org[k];
    t = ref__dot3(X, T) / along;
    if (!(t >= tnear && t <= tfar)) return 0;
    for (k = 0; k < 3; ++k) {
        X[k] = ray->org[k] + t * ray->dir[k];
        R[k] = X[k] - C[k];
        d2 += R[k] * R[k];
    }
    if (!(d2 <= radius * radius)) return 0;
    len = sqrt(ref__dot3(T, T));
    hit->t = t;
    hit->u = end;
    hit->r = radius;
    for (k = 0; k < 3; ++k) hit->normal[k] = (end ? T[k] : -T[k]) / len;
    hit->exit = ref__dot3(hit->normal, ray->dir) > 0.0;
    along = ref__dot3(T, ray->axis_z);
    for (k = 0; k < 3; ++k) tperp[k] = T[k] - along * ray->axis_z[k];
    ref__cross3(T, R, cross);
    len = sqrt(ref__dot3(tperp, tperp));
    hit->v = len > 0.0 ? ref__dot3(cross, ray->axis_z) / (len * radius) : 0.0;
    hit->v = hit->v < -1.0 ? -1.0 : hit->v > 1.0 ? 1.0 : hit->v;
    hit->prim_id = REF_INVALID_ID;
    return 1;
}

/* The first tube hit of a ray over segments [0, segment_count), by brute
   force (the tests' scenes for tubes are small). */
static inline int ref_tube_intersect(const float *vertices, const uint32_t *indices, size_t segment_count, const float org[3],
                                     const float dir[3], double tnear, double tfar, ref_tube_hit *hit)
{
    ref__ray ray;
    size_t i;
    int found = 0;
    ref__ray_setup(&ray, org, dir);
    for (i = 0; i < segment_count; ++i) {
        ref_tube_hit h;
        if (!ref_tube_segment_hit(&ray, vertices + 4 * (size_t)indices[i], tnear, found ? hit->t : tfar, &h, NULL, NULL)) continue;
        if (found && h.t == hit->t && (uint32_t)i > hit->prim_id) continue;
        *hit = h;
        hit->prim_id = (uint32_t)i;
        found = 1;
    }
    return found;
}

/* The first tube hit over a scene built by ref_build (reference.h): its
   boxes (control points dilated by the largest radius) hold the tubes as
   they hold the ribbons. Ties in t go to the smaller prim id. */
static inline int ref_tube_intersect_scene(const ref_scene *s, const float org[3], const float dir[3], double tnear, double tfar,
                                           ref_tube_hit *hit)
{
    ref__ray ray;
    uint32_t stack[REF_STACK_SIZE];
    int sp = 0, found = 0;
    ref__ray_setup(&ray, org, dir);
    hit->prim_id = REF_INVALID_ID;
    if (s && s->node_count > 0 && ray.valid) stack[sp++] = 0;
    while (sp > 0) {
        const ref__node *node = &s->nodes[stack[--sp]];
        if (!ref__box_hit(&ray, node->lo, node->hi, tnear, found ? hit->t : tfar)) continue;
        if (node->count > 0) {
            uint32_t i;
            for (i = 0; i < node->count; ++i) {
                uint32_t prim = s->prims[node->right_or_first + i];
                ref_tube_hit h;
                if (!ref_tube_segment_hit(&ray, s->vertices + 4 * (size_t)s->indices[prim], tnear, found ? hit->t : tfar, &h, NULL, NULL))
                    continue;
                if (found && !(h.t < hit->t || (h.t == hit->t && prim < hit->prim_id))) continue;
                *hit = h;
                hit->prim_id = prim;
                found = 1;
            }
        } else {
            uint32_t left = (uint32_t)(node - s->nodes) + 1, right = node->right_or_first;
            if (ray.dir[node->axis] >= 0.0) {
                stack[sp++] = right;
                stack[sp++] = left;
            } else {
                stack[sp++] = left;
                stack[sp++] = right;
            }
        }
    }
    return found;
}

#endif
