/* test_conservative.c - traversal conservativeness: a ray never misses a
   box it touches. The header is built instrumented (HAIROBB__LEAF_VISIT):
   each segment of each leaf a ray reaches is recorded and its intersection
   skipped, so no hit shortens the ray and the traversal goes wherever the
   node tests lead. Every segment the double-precision reference hits in
   [tnear, tfar] must have been reached, for every node policy and layout,
   with spatial splits (clipped segments), near the origin and far from it.
   Motion blur: the same on moving fur (each strand swept about its root, or
   translated by several strand spacings; 2, 3 and 4 time steps), rays at
   random times, at 0, 1 and every knot k / (T - 1) and the floats beside the
   inner knots, the reference at each ray's time; then each BVH refitted to
   the other motion (hairobb_refit_motion) and checked again.
   So that a traversal reaching everything cannot pass, it must also stay
   selective: reach under a quarter of the segments per ray (the crossed
   bundles, where every ray crosses the dense middle, reach 6-7%; moving
   fur, whose boxes hold every step, 0.1-0.3%). */
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <string.h>

/* the segments the current ray reached: a bitmap over segment ids */
static unsigned char *reached;
static size_t reached_count;
#define HAIROBB__LEAF_VISIT(rs, prim) (reached_count += !reached[prim], reached[prim] = 1, (void)(rs), 1)

#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "check.h"
#include "reference.h"
#include "scenes.h"

#define MAX_STEPS 4

/* Rays with the segments the reference hits on each: ray i's are
   hit_prims[first_hit[i] .. first_hit[i + 1]). */
typedef struct ray_batch {
    size_t count;
    hairobb_ray *rays;
    size_t *first_hit;
    uint32_t *hit_prims;
    size_t hit_count, hit_capacity;
} ray_batch;

static void batch_free(ray_batch *b)
{
    free(b->rays);
    free(b->first_hit);
    free(b->hit_prims);
    memset(b, 0, sizeof *b);
}

static void append_hit(void *user, uint32_t prim, const ref_hit *hit)
{
    ray_batch *b = (ray_batch *)user;
    (void)hit;
    if (b->hit_count == b->hit_capacity) {
        b->hit_capacity = b->hit_capacity ? 2 * b->hit_capacity : 4096;
        b->hit_prims = (uint32_t *)realloc(b->hit_prims, b->hit_capacity * sizeof *b->hit_prims);
        if (!b->hit_prims) { printf("out of memory\n"); exit(1); }
    }
    b->hit_prims[b->hit_count++] = prim;
}

/* Camera rays, random rays through the bounds (any direction, every third
   with a tnear/tfar window), and rays along the axes and the axis planes,
   where direction components are exactly 0 and so are the ray's direction
   components in frames of whole byte rows (1/d infinite); all at time 0.
   `bounds` frames them (its vertices are not read). */
static void batch_rays(ray_batch *b, const hair_scene *bounds, int side)
{
    int rays = side * side * 3, i;
    float *org = (float *)malloc(3 * sizeof(float) * (size_t)rays), *dir = (float *)malloc(3 * sizeof(float) * (size_t)rays);
    float length = 4.0f * (bounds->upper[0] - bounds->lower[0]);
    scene_rng rng;
    memset(b, 0, sizeof *b);
    b->count = (size_t)rays;
    b->rays = (hairobb_ray *)calloc((size_t)rays, sizeof *b->rays);
    b->first_hit = (size_t *)calloc((size_t)rays + 1, sizeof *b->first_hit);
    if (!org || !dir || !b->rays || !b->first_hit) { printf("out of memory\n"); exit(1); }
    scene_camera_rays(bounds, side, side, org, dir);
    scene_rng_seed(&rng, 17);
    for (i = side * side; i < rays; ++i) {
        scene_vec3 d = scene_random_unit_vector(&rng);
        int k;
        if (i >= 2 * side * side) {
            /* one or two components zeroed, the rest +-1, normalised */
            int keep = i % 6;
            float c[3], norm;
            for (k = 0; k < 3; ++k) c[k] = (keep < 3 ? k == keep : k != keep - 3) ? (scene_rng_float(&rng) < 0.5f ? -1.0f : 1.0f) : 0.0f;
            norm = sqrtf(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
            d.x = c[0] / norm; d.y = c[1] / norm; d.z = c[2] / norm;
        }
        for (k = 0; k < 3; ++k) {
            float extent = bounds->upper[k] - bounds->lower[k];
            org[3 * i + k] = bounds->lower[k] + extent * scene_rng_float(&rng);
        }
        org[3 * i] -= 2.0f * (bounds->upper[0] - bounds->lower[0]) * d.x;
        org[3 * i + 1] -= 2.0f * (bounds->upper[0] - bounds->lower[0]) * d.y;
        org[3 * i + 2] -= 2.0f * (bounds->upper[0] - bounds->lower[0]) * d.z;
        dir[3 * i] = d.x; dir[3 * i + 1] = d.y; dir[3 * i + 2] = d.z;
    }
    for (i = 0; i < rays; ++i) {
        hairobb_ray *ray = &b->rays[i];
        memcpy(ray->org, org + 3 * i, sizeof ray->org);
        memcpy(ray->dir, dir + 3 * i, sizeof ray->dir);
        ray->tnear = (i >= side * side && i % 3 == 0) ? length * (0.3f + 0.2f * scene_rng_float(&rng)) : 0.0f;
        ray->tfar = (i >= side * side && i % 3 == 0) ? ray->tnear + 0.3f * length : INFINITY;
        ray->time = 0.0f;
    }
    free(org);
    free(dir);
}

/* The reference's hits on every ray of the batch, at each ray's time
   (steps NULL: the scene as it is). A reference is built for each run of
   rays at one time, so the batch keeps rays of one time together. */
static void batch_reference(ray_batch *b, const hair_scene *s, float *const *steps, int time_steps)
{
    float *points = steps ? (float *)malloc(4 * sizeof(float) * s->vertex_count) : NULL;
    ref_scene *reference = NULL;
    float built_for = 0.0f;
    size_t i;
    b->hit_count = 0;
    for (i = 0; i < b->count; ++i) {
        const hairobb_ray *ray = &b->rays[i];
        if (!reference || ray->time != built_for) {
            ref_free(reference);
            if (steps) ref_motion_points((const float *const *)steps, time_steps, ray->time, 0, 4 * s->vertex_count, points);
            reference = ref_build(steps ? points : s->vertices, s->vertex_count, s->indices, s->segment_count);
            built_for = ray->time;
            if (!reference) { printf("out of memory\n"); exit(1); }
        }
        b->first_hit[i] = b->hit_count;
        ref_all_hits(reference, ray->org, ray->dir, ray->tnear, ray->tfar, append_hit, b);
    }
    b->first_hit[b->count] = b->hit_count;
    ref_free(reference);
    free(points);
}

/* Traces the batch through the instrumented BVH: every segment the
   reference hits reached, no ray hit (intersection is skipped), and the
   traversal selective. Returns the segments reached per ray. */
static double check_reached(const char *name, const hairobb_bvh *bvh, const ray_batch *b, size_t segment_count)
{
    size_t i, missed = 0, total_reached = 0, hits = 0;
    double per_ray;
    for (i = 0; i < b->count; ++i) {
        hairobb_hit hit;
        size_t h;
        memset(reached, 0, segment_count);
        reached_count = 0;
        hits += (size_t)hairobb_intersect1(bvh, &b->rays[i], &hit);
        total_reached += reached_count;
        for (h = b->first_hit[i]; h < b->first_hit[i + 1]; ++h) missed += !reached[b->hit_prims[h]];
    }
    per_ray = (double)total_reached / (double)b->count;
    printf("%-50s %5zu rays, %6zu reference hits, %zu segments not reached; %.1f segments reached per ray of %zu (%.2f%%)\n", name,
           b->count, b->hit_count, missed, per_ray, segment_count, 100.0 * per_ray / (double)segment_count);
    CHECK(b->hit_count > b->count / 10, "%s: %zu reference hits", name, b->hit_count);
    CHECK(missed == 0, "%s: %zu segments the reference hits were not reached", name, missed);
    CHECK(hits == 0, "%s: %zu instrumented rays hit (every intersection is skipped)", name, hits);
    CHECK(per_ray < 0.25 * (double)segment_count, "%s: %.1f segments reached per ray: not selective", name, per_ray);
    return per_ray;
}

static const struct { const char *name; hairobb_node_policy nodes; hairobb_obb_layout layout; hairobb_switch spatial; } configs[] = {
    {"defaults", HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_AUTO},
    {"per-child affine", HAIROBB_NODES_MIXED, HAIROBB_OBB_PER_CHILD, HAIROBB_AUTO},
    {"shared rotation", HAIROBB_NODES_MIXED, HAIROBB_OBB_SHARED_ROTATION, HAIROBB_AUTO},
    {"compressed (paper)", HAIROBB_NODES_MIXED, HAIROBB_OBB_COMPRESSED, HAIROBB_AUTO},
    {"AABB only", HAIROBB_NODES_AABB_ONLY, HAIROBB_OBB_DEFAULT, HAIROBB_AUTO},
    {"OBB only", HAIROBB_NODES_OBB_ONLY, HAIROBB_OBB_DEFAULT, HAIROBB_AUTO},
    {"spatial splits", HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_ON},
};
#define CONFIGS (int)(sizeof configs / sizeof configs[0])

static void config_options(int c, hairobb_build_options *options)
{
    memset(options, 0, sizeof *options);
    options->nodes = configs[c].nodes;
    options->obb_layout = configs[c].layout;
    options->spatial_splits = configs[c].spatial;
}

static void check_scene(const char *name, hair_scene *s, int variants)
{
    ray_batch batch;
    int c;
    reached = (unsigned char *)calloc(s->segment_count, 1);
    batch_rays(&batch, s, 48);
    batch_reference(&batch, s, NULL, 0);
    for (c = 0; c < variants; ++c) {
        hairobb_build_options options;
        hairobb_bvh *bvh = NULL;
        hairobb_result r;
        char label[96];
        config_options(c, &options);
        snprintf(label, sizeof label, "%s, %s:", name, configs[c].name);
        r = hairobb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, &options, &bvh);
        CHECK(r == HAIROBB_OK, "%s: build: %s", label, hairobb_result_string(r));
        if (r == HAIROBB_OK) check_reached(label, bvh, &batch, s->segment_count);
        hairobb_free(bvh);
    }
    batch_free(&batch);
    free(reached);
}

/* ------------------------------------------------------------------------ */
/* Motion blur */

/* One motion of a scene: its steps and rays (framed by the hair at every
   step) at their times, with the reference's hits. */
typedef struct motion_case {
    const char *name;
    float *steps[MAX_STEPS];
    int time_steps;
    ray_batch batch;
} motion_case;

/* The batch's rays get times in runs (batch_reference builds a reference
   per time): the knots k / (T - 1) (0 and 1 among them), the floats either
   side of each inner knot, and random times for the rest. */
static void motion_times(ray_batch *b, int time_steps, int run_count, scene_rng *rng)
{
    float times[64];
    int t = 0, k;
    size_t i;
    for (k = 0; k < time_steps; ++k) times[t++] = (float)k / (float)(time_steps - 1);
    for (k = 1; k < time_steps - 1; ++k) {
        times[t++] = nextafterf(times[k], 0.0f);
        times[t++] = nextafterf(times[k], 1.0f);
    }
    while (t < run_count) times[t++] = scene_rng_float(rng);
    /* ray i gets run i % run_count, so every kind of ray is at every time;
       the batch is then reordered run by run */
    {
        hairobb_ray *sorted = (hairobb_ray *)malloc(b->count * sizeof *sorted);
        size_t j = 0;
        int run;
        if (!sorted) { printf("out of memory\n"); exit(1); }
        for (run = 0; run < run_count; ++run)
            for (i = (size_t)run; i < b->count; i += (size_t)run_count) {
                sorted[j] = b->rays[i];
                sorted[j++].time = times[run];
            }
        free(b->rays);
        b->rays = sorted;
    }
}

static int motion_case_make(motion_case *m, const char *name, const hair_scene *s, scene_motion motion, double amount,
                            int time_steps, uint64_t seed)
{
    hair_scene bounds = *s, step;
    scene_rng rng;
    int k, a;
    memset(m, 0, sizeof *m);
    m->name = name;
    m->time_steps = time_steps;
    if (scene_motion_steps(s, motion, amount, time_steps, m->steps) != 0) return 1;
    for (k = 1; k < time_steps; ++k) {
        step = *s;
        step.vertices = m->steps[k];
        scene_update_bounds(&step);
        for (a = 0; a < 3; ++a) {
            bounds.lower[a] = fminf(bounds.lower[a], step.lower[a]);
            bounds.upper[a] = fmaxf(bounds.upper[a], step.upper[a]);
        }
    }
    batch_rays(&m->batch, &bounds, 32);
    scene_rng_seed(&rng, seed);
    motion_times(&m->batch, time_steps, 48, &rng);
    batch_reference(&m->batch, s, m->steps, time_steps);
    return 0;
}

static void motion_case_free(motion_case *m)
{
    scene_motion_free(m->steps, m->time_steps);
    batch_free(&m->batch);
}

static hairobb_result build_motion(const hair_scene *s, const motion_case *m, const hairobb_build_options *base, hairobb_bvh **bvh)
{
    hairobb_build_options options = *base;
    options.time_steps = (unsigned)m->time_steps;
    options.time_vertices = (const float *const *)m->steps;
    return hairobb_build(NULL, s->vertex_count, s->indices, s->segment_count, &options, bvh);
}

/* Both motions of a scene at time_steps steps, every configuration; each
   BVH is then refitted to the other motion's steps and checked on its rays. */
static void check_motion(const char *scene_name, const hair_scene *s, double angle, double shift, int time_steps, int variants)
{
    motion_case cases[2];
    char names[2][64];
    double most[2] = {0.0, 0.0};
    int c, m;
    snprintf(names[0], sizeof names[0], "%s rotate %.2g T=%d", scene_name, angle, time_steps);
    snprintf(names[1], sizeof names[1], "%s translate %.2g T=%d", scene_name, shift, time_steps);
    CHECK(motion_case_make(&cases[0], names[0], s, SCENE_MOTION_ROTATE, angle, time_steps, 31u + (unsigned)time_steps) == 0 &&
          motion_case_make(&cases[1], names[1], s, SCENE_MOTION_TRANSLATE, shift, time_steps, 41u + (unsigned)time_steps) == 0,
          "%s: motion steps", scene_name);
    reached = (unsigned char *)calloc(s->segment_count, 1);
    for (m = 0; m < 2; ++m)
        for (c = 0; c < variants; ++c) {
            hairobb_build_options options;
            hairobb_bvh *bvh = NULL;
            hairobb_result r;
            char label[128];
            double per_ray;
            config_options(c, &options);
            snprintf(label, sizeof label, "%s, %s:", cases[m].name, configs[c].name);
            r = build_motion(s, &cases[m], &options, &bvh);
            CHECK(r == HAIROBB_OK, "%s: build: %s", label, hairobb_result_string(r));
            if (r != HAIROBB_OK) continue;
            per_ray = check_reached(label, bvh, &cases[m].batch, s->segment_count);
            most[0] = per_ray > most[0] ? per_ray : most[0];
            r = hairobb_refit_motion(bvh, (const float *const *)cases[1 - m].steps);
            snprintf(label, sizeof label, "%s, %s, refit to %s:", cases[m].name, configs[c].name, 1 - m ? "translate" : "rotate");
            CHECK(r == HAIROBB_OK, "%s: %s", label, hairobb_result_string(r));
            if (r == HAIROBB_OK) {
                per_ray = check_reached(label, bvh, &cases[1 - m].batch, s->segment_count);
                most[1] = per_ray > most[1] ? per_ray : most[1];
            }
            hairobb_free(bvh);
        }
    printf("%s T=%d: at most %.2f%% of the segments reached per ray as built, %.2f%% refitted\n", scene_name, time_steps,
           100.0 * most[0] / (double)s->segment_count, 100.0 * most[1] / (double)s->segment_count);
    free(reached);
    motion_case_free(&cases[0]);
    motion_case_free(&cases[1]);
}

int main(void)
{
    hair_scene s;
    const float far_away[3] = {1e5f, 5e4f, -1e5f};
    int time_steps;
    CHECK(scene_combed(&s, 20000, 21) == 0, "combed");
    check_scene("combed 20k", &s, CONFIGS);
    scene_transform(&s, far_away, 1.0f);
    check_scene("combed 20k at 1e5", &s, 1);
    scene_free(&s);
    CHECK(scene_curly(&s, 20000, 22) == 0, "curly");
    check_scene("curly 20k", &s, CONFIGS);
    scene_free(&s);
    CHECK(scene_crossed(&s, 6000, 23) == 0, "crossed");
    check_scene("crossed bundles 6k", &s, CONFIGS);
    scene_free(&s);
    /* moving combed fur: strands about 0.1 apart, 0.3-0.5 long; a
       translation of 0.5 crosses five strand spacings */
    CHECK(scene_combed(&s, 10000, 24) == 0, "combed");
    for (time_steps = 2; time_steps <= MAX_STEPS; ++time_steps) check_motion("combed 10k", &s, 0.8, 0.5, time_steps, CONFIGS);
    scene_transform(&s, far_away, 1.0f);
    check_motion("combed 10k at 1e5", &s, 0.8, 0.5, 3, 1);
    scene_free(&s);
    return check_summary();
}
