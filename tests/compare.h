/* compare.h - comparing answers, for the tests and the bench: two of
   hairobb's hits bit for bit (same_hit); traced answers against the
   reference's (an accuracy_tally: hit/miss disagreements, |t - t_ref| / r
   and |u - u_ref|, summed up in an accuracy_summary); nearest-rank
   percentiles of sorted values; and FNV-1a, the hash that compares trees
   and hits between builds and machines. Header-only, every function static
   inline; C99 and C++11. */
#ifndef HAIROBB_TESTS_COMPARE_H
#define HAIROBB_TESTS_COMPARE_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "../hairobb.h" /* hairobb_hit: the declarations, unless the implementation came first */

/* ------------------------------------------------------------------------ */
/* Sorted values */

/* For qsort: ascending. */
static inline int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Nearest rank: of n values sorted ascending, the one at rank
   round(p (n - 1)), so that p = 0.5 is the median (the upper middle of an
   even count) and p = 1 the largest; NaN where there are none. */
static inline double percentile(const double *sorted, size_t n, double p)
{
    return n ? sorted[(size_t)(p * (double)(n - 1) + 0.5)] : NAN;
}

/* ------------------------------------------------------------------------ */
/* Two traces */

/* The same answer: both miss, or both hit with the same bits in every
   field (t, u, v, Ng, tangent, prim_id, instance_id: 4-byte fields, no
   padding). A miss writes the two ids alone, so the rest of a missed hit is not
   compared. */
static inline int same_hit(int got_a, const hairobb_hit *a, int got_b, const hairobb_hit *b)
{
    return got_a == got_b && (!got_a || memcmp(a, b, sizeof *a) == 0);
}

/* FNV-1a, 64 bits: h is FNV1A_START, or the hash so far of what came
   before. */
#define FNV1A_START 14695981039346656037ULL
static inline uint64_t fnv1a(uint64_t h, const void *data, size_t size)
{
    const unsigned char *p = (const unsigned char *)data;
    size_t i;
    for (i = 0; i < size; ++i) h = (h ^ p[i]) * 1099511628211ULL;
    return h;
}

/* ------------------------------------------------------------------------ */
/* Answers against the reference's */

/* A tracer's figures against the reference's on the same rays. */
typedef struct accuracy_summary {
    size_t rays, disagreements, t_compared, u_compared;
    double t_median, t_p99, t_max; /* |t - t_ref| / r_ref where both hit; NaN where none did */
    double u_median, u_p99;        /* |u - u_ref| where both hit the same segment */
} accuracy_summary;

/* The answers so far, ray by ray (accuracy_tally_add), until
   accuracy_summarize sums them up. */
typedef struct accuracy_tally {
    size_t rays, disagreements, t_compared, u_compared;
    double *t_errors, *u_errors; /* room for every ray */
} accuracy_tally;

static inline void accuracy_tally_free(accuracy_tally *a)
{
    free(a->t_errors);
    free(a->u_errors);
    memset(a, 0, sizeof *a);
}

/* Room for `rays` answers; 1 if out of memory (then nothing is held). */
static inline int accuracy_tally_init(accuracy_tally *a, size_t rays)
{
    memset(a, 0, sizeof *a);
    a->t_errors = (double *)malloc((rays ? rays : 1) * sizeof(double));
    a->u_errors = (double *)malloc((rays ? rays : 1) * sizeof(double));
    if (a->t_errors && a->u_errors) return 0;
    accuracy_tally_free(a);
    return 1;
}

/* One ray: the reference's answer (whether it hit; where: t, u, the
   segment, the radius there) and the traced one. Where both hit, t is
   compared in radii (not at a radius of 0), and u on the same segment
   only: on another it is another curve's parameter. */
static inline void accuracy_tally_add(accuracy_tally *a, int ref_hit, double ref_t, double ref_u, uint32_t ref_prim, double ref_r,
                                      int hit, double t, double u, uint32_t prim)
{
    a->rays++;
    if (hit != ref_hit) {
        a->disagreements++;
        return;
    }
    if (!hit) return;
    if (ref_r > 0.0) a->t_errors[a->t_compared++] = fabs(t - ref_t) / ref_r;
    if (prim == ref_prim) a->u_errors[a->u_compared++] = fabs(u - ref_u);
}

/* The tally's figures (its errors sorted in place). */
static inline void accuracy_summarize(accuracy_tally *a, accuracy_summary *out)
{
    qsort(a->t_errors, a->t_compared, sizeof(double), compare_doubles);
    qsort(a->u_errors, a->u_compared, sizeof(double), compare_doubles);
    out->rays = a->rays;
    out->disagreements = a->disagreements;
    out->t_compared = a->t_compared;
    out->u_compared = a->u_compared;
    out->t_median = percentile(a->t_errors, a->t_compared, 0.5);
    out->t_p99 = percentile(a->t_errors, a->t_compared, 0.99);
    out->t_max = percentile(a->t_errors, a->t_compared, 1.0);
    out->u_median = percentile(a->u_errors, a->u_compared, 0.5);
    out->u_p99 = percentile(a->u_errors, a->u_compared, 0.99);
}

/* Hit/miss disagreements in percent of the rays; NaN for no rays. */
static inline double disagreement_percent(const accuracy_summary *a)
{
    return a->rays ? 100.0 * (double)a->disagreements / (double)a->rays : NAN;
}

#endif
