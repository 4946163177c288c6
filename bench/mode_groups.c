/* mode_groups.c - --groups: one BVH against the same hair as a scene of
   4-64 groups (SCENES in the header's manual; issue 34 §3). */
#include "bench/bench.h"

/* A renderer holding a groom as several hair systems builds a BVH for
   each and places them under a hairobb_scene. What does that cost against
   one BVH over all of the hair? For each --scene, the strands, in the
   arrays' order, are split into k groups of whole strands (contiguous,
   strand counts equal to one), each built into a BVH of its own (default
   options but the surface, below; all cores) over the scene's own arrays (its indices from the
   group's first segment on) and placed by an identity map. The rows:

     one BVH        hairobb_intersect1 / _occluded1 on one BVH over every
                    segment: the baseline of every ratio
     scene of 1     that BVH as a scene's only instance: the top level's own cost
     4, 16, 64      the groups, a BVH each under a scene
     k in 1 BVH     the same k groups as one BVH (hairobb_build_groups), the
                    groom as one tree
     Embree k geom  Embree's Bezier curves (flat; round for tubes) as k
                    geometries of one scene (one tree over all of them;
                    k = 1: all the hair in one);
                    the table of pairs gives k in 1 BVH / Embree k geometries
                    within each round
     16 instances   group 0 of the 16 placed 16 times, translated on a 4 x 4
                    grid in x and y, GRID_STEP of the scene's diagonal apart:
                    other hair, so its speed stands alone (no ratio)

   The strands' order decides what a group is. In groom order (strands
   shuffled, the bench's default) every group spans the whole fur: a ray
   crosses every group's box and the top level culls nothing, the worst
   case. In space order (strands by the Morton code of their roots) a
   group is a patch, as a groom's systems (scalp, brows, lashes) are.
   Without --strand-order both are run, each over its own arrays with its
   own one BVH.

   Every row is built as one surface, --groups-shape: ribbons (hairobb's
   default, Embree's flat Bezier curves), tubes (options.shape =
   HAIROBB_SHAPE_ROUND, Embree's round Bezier curves, as the round and
   embree-round variants build them), or both, each order's ribbons, then
   its tubes, each with its own one BVH and its own secondary rays. Each
   row's label ends in its shape's name (ribbon, round).

   The rays are the bench's: primary rays from the camera, and the diffuse
   bounce and shadow rays spawned from the one BVH's primary hits. Each
   group scene's hits are checked against the one BVH's on every ray
   first (hit or miss; the segment, mapped back by its group's first
   segment; t to the bit), then every row is timed as the bench times its
   variants: each ray set and thread count in rounds, one pass of every
   row a round after a warm-up pass each, the ratio to the one BVH taken
   within each round. Build time is the sum of the BVH builds and the
   scene's; memory the sum of hairobb_memory_bytes and the scene's own
   allocations (the bench's allocator meter, around hairobb_scene_build).

   Those builds are one each, on a noisy machine: the build time of k in 1
   BVH against the one BVH is measured apart, in rounds. After the traces,
   on each --threads count (options.threads), each of --rounds rounds
   builds the one BVH (hairobb_build) and then k in 1 BVH
   (hairobb_build_groups, over the groups' arrays made once beforehand, as
   a renderer holds them) for k = 4, 16, 64 in turn, A B A B A B, each
   freed before the next; the ratio k in 1 / one BVH is taken within each
   pair, and the medians and [min-max] of the seconds and the ratios are
   printed with the bytes a segment k in 1 BVH holds beyond the one BVH.

   The scene's tracer lives here rather than beside hairobb_tracer in
   harness.c: hairobb_scene_intersect1 is called through the file's
   boundary, one call a ray that hairobb_tracer inlines (a few ns against
   hundreds a ray). */

enum {
    GROUP_SETS = 4,                       /* the scene of 1 and the three group counts */
    ROW_ONE = 0,                          /* the one BVH */
    ROW_SCENES = 1,                       /* the first of the GROUP_SETS scene rows */
    ROW_ONE_TREE = ROW_SCENES + GROUP_SETS,   /* the three group counts as one multi-group BVH each */
    ROW_EMBREE = ROW_ONE_TREE + GROUP_SETS - 1,   /* Embree: the hair as 1, 4, 16, 64 curve geometries of one scene */
    ROW_INSTANCED = ROW_EMBREE + GROUP_SETS,
    ROWS,
    INSTANCES = 16,                       /* of the instanced row, on a 4 x 4 grid */
    INSTANCED_FROM = ROW_SCENES + 2       /* its BVH: group 0 of the 16 groups' row */
};
static const int group_counts[GROUP_SETS] = {1, 4, 16, 64};
#define GRID_STEP 0.02 /* the instances' translations, in the scene's diagonals */
#define LABEL_WIDTH 21 /* the rows' labels in the tables: "Embree 64 geom ribbon" */

/* What --groups-shape builds every row as (groups_shape_names: the labels' last word) */
typedef struct group_surface {
    hairobb_shape shape;   /* hairobb's rows */
    int embree_type;       /* Embree's: EMB_FLAT_BEZIER or EMB_ROUND_BEZIER */
    const char *text;      /* in the tables' header */
} group_surface;
static const group_surface group_surfaces[GROUPS_SHAPE_COUNT] = {
    {HAIROBB_SHAPE_RIBBON, EMB_FLAT_BEZIER, "ribbons (hairobb's default surface; Embree's flat Bezier curves)"},
    {HAIROBB_SHAPE_ROUND, EMB_ROUND_BEZIER, "tubes (HAIROBB_SHAPE_ROUND; Embree's round Bezier curves)"}};

/* A scene as its tracer sees it: each instance's first segment in the
   scene's arrays, so that a hit's prim is the segment's number there. */
typedef struct scene_accel {
    const hairobb_scene *scene;
    const hairobb_bvh *groups;   /* a multi-group BVH's row: its hits' group_id index first_segment */
    const emb_scene *embree;     /* an Embree row: its hits' geometry ids index first_segment */
    const uint32_t *first_segment;
} scene_accel;

typedef struct group_row {
    char label[32];
    int instances;              /* under the scene; 0 for the one BVH */
    int bvh_count;              /* the BVHs it traces (the instanced row: 1, shared) */
    int owned;                  /* its BVHs were built for it (freed with it) */
    hairobb_bvh **bvh;          /* bvh_count of them */
    uint32_t *first_segment;    /* each instance's first segment in the scene's arrays */
    size_t segments;            /* segments traced (the instanced row: 16 times its group's) */
    hairobb_scene *scene;
    scene_accel accel;
    tracer tracer;
    double build_seconds;       /* its BVHs' builds and the scene's */
    double first_build_seconds; /* of its first BVH */
    double scene_seconds;
    size_t bvh_bytes, scene_bytes;
    double boxes_per_ray;       /* instance boxes a primary ray crosses, mean */
    int measured;
    spread mrays[RAY_KIND_COUNT][MAX_THREAD_COUNTS], ratio[RAY_KIND_COUNT][MAX_THREAD_COUNTS];
    spread pair[RAY_KIND_COUNT][MAX_THREAD_COUNTS];   /* k in 1 BVH rows: / Embree's k geometries, within rounds */
    emb_scene *embree;
    uint32_t **embree_indices;  /* an Embree row's index buffers, one a geometry */
    size_t *embree_counts;
    /* a k in 1 BVH row: its groups as hairobb_build_groups takes them (kept
       for the builds in rounds), each group's indices rebased to its vertices */
    hairobb_group *groups;
    uint32_t **rebased;
    int group_count;
    /* and its builds in rounds against the one BVH's, seconds and ratio (within each round) */
    int build_timed;
    spread build_one[MAX_THREAD_COUNTS], build_tree[MAX_THREAD_COUNTS], build_ratio[MAX_THREAD_COUNTS];
    /* against the one BVH, every ray of each set */
    int checked[RAY_KIND_COUNT];
    size_t hit_miss[RAY_KIND_COUNT], other_segment[RAY_KIND_COUNT], tie[RAY_KIND_COUNT], t_differs[RAY_KIND_COUNT];
    double t_max_relative[RAY_KIND_COUNT];
} group_row;

/* ======================================================================== */
/* The scene's tracer                                                       */
/* ======================================================================== */

static void group_ray(hairobb_ray *ray, const float org[3], const float dir[3], float tfar, float time)
{
    memcpy(ray->org, org, sizeof ray->org);
    memcpy(ray->dir, dir, sizeof ray->dir);
    ray->tnear = 0.0f;
    ray->tfar = tfar;
    ray->time = time;
}

static int scene_tracer_intersect(const void *accel, const float org[3], const float dir[3], float tfar, float time,
                                  hit_record *out)
{
    const scene_accel *a = (const scene_accel *)accel;
    hairobb_ray ray;
    hairobb_hit hit;
    group_ray(&ray, org, dir, tfar, time);
    if (!hairobb_scene_intersect1(a->scene, NULL, NULL, &ray, &hit)) {
        out->prim = NO_HIT;
        return 0;
    }
    out->t = hit.t;
    out->u = hit.u;
    memcpy(out->ng, hit.Ng, sizeof out->ng);
    out->prim = a->first_segment[hit.instance_id] + hit.prim_id;
    return 1;
}

static int scene_tracer_occluded(const void *accel, const float org[3], const float dir[3], float tfar, float time)
{
    hairobb_ray ray;
    group_ray(&ray, org, dir, tfar, time);
    return hairobb_scene_occluded1(((const scene_accel *)accel)->scene, NULL, NULL, &ray);
}

static int groups_tracer_intersect(const void *accel, const float org[3], const float dir[3], float tfar, float time,
                                   hit_record *out)
{
    const scene_accel *a = (const scene_accel *)accel;
    hairobb_ray ray;
    hairobb_hit hit;
    group_ray(&ray, org, dir, tfar, time);
    if (!hairobb_intersect1(a->groups, &ray, &hit)) {
        out->prim = NO_HIT;
        return 0;
    }
    out->t = hit.t;
    out->u = hit.u;
    memcpy(out->ng, hit.Ng, sizeof out->ng);
    out->prim = a->first_segment[hit.group_id] + hit.prim_id;
    return 1;
}

static int embree_groups_intersect(const void *accel, const float org[3], const float dir[3], float tfar, float time,
                                   hit_record *out)
{
    const scene_accel *a = (const scene_accel *)accel;
    uint32_t geometry, prim;
    (void)time;
    if (!emb_intersect_group(a->embree, org, dir, tfar, &out->t, &out->u, &geometry, &prim)) {
        out->prim = NO_HIT;
        return 0;
    }
    out->ng[0] = out->ng[1] = out->ng[2] = 0.0f;
    out->prim = a->first_segment[geometry] + prim;
    return 1;
}

static int embree_groups_occluded(const void *accel, const float org[3], const float dir[3], float tfar, float time)
{
    return emb_occluded_at_time(((const scene_accel *)accel)->embree, org, 0.0f, dir, tfar, time);
}

static int groups_tracer_occluded(const void *accel, const float org[3], const float dir[3], float tfar, float time)
{
    hairobb_ray ray;
    group_ray(&ray, org, dir, tfar, time);
    return hairobb_occluded1(((const scene_accel *)accel)->groups, &ray);
}

/* ======================================================================== */
/* Building the rows                                                        */
/* ======================================================================== */

/* The options of every hairobb build here: defaults, but the scene's
   basis, the shape, and threads (0: every core); the bench's allocator meter. */
static hairobb_build_options group_options(const hair_scene *s, hairobb_shape shape, unsigned threads)
{
    hairobb_build_options build_options;
    memset(&build_options, 0, sizeof build_options);
    build_options.basis = s->basis == SCENE_BASIS_CATMULL_ROM ? HAIROBB_BASIS_CATMULL_ROM : HAIROBB_BASIS_BEZIER;
    build_options.shape = shape;
    build_options.threads = threads;
    build_options.allocator_user = &hairobb_meter;
    return build_options;
}

/* Segments [begin, end) of the scene built (group_options), metered as
   every bench build is. */
static hairobb_bvh *build_group(const hair_scene *s, size_t begin, size_t end, hairobb_shape shape, unsigned threads,
                                double *seconds)
{
    hair_scene view = *s;
    hairobb_build_options build_options = group_options(s, shape, threads);
    size_t transient;
    view.indices = s->indices + begin;
    view.segment_count = end - begin;
    return build_metered(&view, s->vertices, &build_options, "group", seconds, &transient);
}

static int row_alloc(group_row *r, int instances, int bvh_count)
{
    r->instances = instances;
    r->bvh_count = bvh_count;
    r->bvh = (hairobb_bvh **)calloc((size_t)bvh_count, sizeof *r->bvh);
    r->first_segment = (uint32_t *)calloc((size_t)(instances ? instances : 1), sizeof *r->first_segment);
    return !r->bvh || !r->first_segment;
}

static void row_free(group_row *r)
{
    if (r->embree)
        emb_free(r->embree);
    for (int g = 0; r->embree_indices && g < r->bvh_count; g++)
        free(r->embree_indices[g]);
    free(r->embree_indices);
    free(r->embree_counts);
    for (int g = 0; r->rebased && g < r->group_count; g++)
        free(r->rebased[g]);
    free(r->rebased);
    free(r->groups);
    hairobb_scene_free(r->scene);
    for (int i = 0; r->owned && r->bvh && i < r->bvh_count; i++)
        hairobb_free(r->bvh[i]);
    free(r->bvh);
    free(r->first_segment);
    memset(r, 0, sizeof *r);
}

/* The row's scene over its BVHs (instance i: bvh[i % bvh_count], moved by
   offsets[i], or in place where offsets is NULL); its seconds and the
   bytes it allocated added to the row's. */
static int row_scene(group_row *r, const float (*offsets)[3])
{
    hairobb_instance *instances = (hairobb_instance *)calloc((size_t)r->instances, sizeof *instances);
    if (!instances)
        return 1;
    for (int i = 0; i < r->instances; i++) {
        float *m = instances[i].transform;
        instances[i].bvh = r->bvh[i % r->bvh_count];
        m[0] = m[5] = m[10] = 1.0f;
        if (offsets) {
            m[3] = offsets[i][0];
            m[7] = offsets[i][1];
            m[11] = offsets[i][2];
        }
    }
    size_t live_before = hairobb_meter.bytes;
    double start = scene_now();
    hairobb_result result = hairobb_scene_build(instances, (size_t)r->instances, &hairobb_meter, &r->scene);
    r->scene_seconds = scene_now() - start;
    r->scene_bytes = hairobb_meter.bytes - live_before;
    r->build_seconds += r->scene_seconds;
    free(instances);
    if (result != HAIROBB_OK) {
        fprintf(stderr, "bench: hairobb_scene_build (%s): %s\n", r->label, hairobb_result_string(result));
        return 1;
    }
    r->accel.scene = r->scene;
    r->accel.first_segment = r->first_segment;
    r->tracer.accel = &r->accel;
    r->tracer.intersect = scene_tracer_intersect;
    r->tracer.occluded = scene_tracer_occluded;
    return 0;
}

/* Whether the ray's line from its origin crosses the box (tfar: the ray's). */
static int ray_crosses_box(const float org[3], const float dir[3], float tfar, const float lower[3], const float upper[3])
{
    float t0 = 0.0f, t1 = tfar;
    for (int k = 0; k < 3; k++) {
        if (dir[k] == 0.0f) {
            if (org[k] < lower[k] || org[k] > upper[k])
                return 0;
            continue;
        }
        float inv = 1.0f / dir[k], a = (lower[k] - org[k]) * inv, b = (upper[k] - org[k]) * inv;
        t0 = a < b ? (a > t0 ? a : t0) : (b > t0 ? b : t0);
        t1 = a < b ? (b < t1 ? b : t1) : (a < t1 ? a : t1);
    }
    return t0 <= t1;
}

/* The mean over the primary rays of the instance boxes each crosses: what
   the top level cannot cull before a ray finds its first hit. */
static double boxes_per_ray(const group_row *r, const float (*offsets)[3], const ray_set *primary)
{
    enum { MOST = 256 };
    float lower[MOST][3], upper[MOST][3];
    int n = r->instances ? r->instances : 1;
    if (n > MOST || primary->count == 0)
        return NAN;
    for (int i = 0; i < n; i++) {
        hairobb_bounds(r->bvh[i % r->bvh_count], lower[i], upper[i]);
        for (int k = 0; offsets && k < 3; k++) {
            lower[i][k] += offsets[i][k];
            upper[i][k] += offsets[i][k];
        }
    }
    size_t crossed = 0;
    for (size_t j = 0; j < primary->count; j++)
        for (int i = 0; i < n; i++)
            crossed += (size_t)ray_crosses_box(primary->org + 3 * j, primary->dir + 3 * j, primary->tfar[j], lower[i],
                                               upper[i]);
    return (double)crossed / (double)primary->count;
}

/* The groups of one scene row: count groups of whole strands in the
   arrays' order (fewer where the scene has fewer strands). */
static int build_groups(const hair_scene *s, const size_t *first, size_t strands, int count, groups_shape shape,
                        group_row *r)
{
    if ((size_t)count > strands)
        count = (int)strands;
    snprintf(r->label, sizeof r->label, "%d groups %s", count, groups_shape_names[shape]);
    if (row_alloc(r, count, count) != 0)
        return 1;
    r->owned = 1;
    r->segments = s->segment_count;
    progress_start("  %s: builds", r->label);
    for (int g = 0; g < count; g++) {
        size_t begin = first[strands * (size_t)g / (size_t)count], end = first[strands * (size_t)(g + 1) / (size_t)count];
        double seconds = 0.0;
        r->bvh[g] = build_group(s, begin, end, group_surfaces[shape].shape, 0, &seconds);
        if (!r->bvh[g]) {
            progress("failed");
            return 1;
        }
        r->first_segment[g] = (uint32_t)begin;
        r->build_seconds += seconds;
        if (g == 0)
            r->first_build_seconds = seconds;
        r->bvh_bytes += hairobb_memory_bytes(r->bvh[g]);
    }
    progress("%.3f s", r->build_seconds);
    return 0;
}

/* A k in 1 BVH row's groups built as one BVH (group_options); *seconds:
   hairobb_build_groups's alone. */
static hairobb_result build_tree(const hair_scene *s, const group_row *r, hairobb_shape shape, unsigned threads,
                                 hairobb_bvh **out, double *seconds)
{
    hairobb_build_options build_options = group_options(s, shape, threads);
    double start = scene_now();
    hairobb_result result = hairobb_build_groups(r->groups, (size_t)r->group_count, &build_options, out);
    *seconds = scene_now() - start;
    return result;
}

/* The same k groups as one BVH (hairobb_build_groups): group g is the
   scene's segments [begin, end), its vertices the range they read, its
   indices rebased to it. The groups stay with the row: the builds in
   rounds build them again. */
static int build_one_tree(const hair_scene *s, const size_t *first, size_t strands, int count, groups_shape shape,
                          group_row *r)
{
    size_t points = 4;   /* Bezier and Catmull-Rom segments read 4 points */
    if ((size_t)count > strands)
        count = (int)strands;
    snprintf(r->label, sizeof r->label, "%d in 1 BVH %s", count, groups_shape_names[shape]);
    if (row_alloc(r, count, 1) != 0)
        return 1;
    r->instances = 0;
    r->owned = 1;
    r->segments = s->segment_count;
    r->groups = (hairobb_group *)calloc((size_t)count, sizeof *r->groups);
    r->rebased = (uint32_t **)calloc((size_t)count, sizeof *r->rebased);
    if (!r->groups || !r->rebased)
        return 1;
    r->group_count = count;
    for (int g = 0; g < count; g++) {
        size_t begin = first[strands * (size_t)g / (size_t)count], end = first[strands * (size_t)(g + 1) / (size_t)count], i;
        uint32_t lo = UINT32_MAX, hi = 0;
        for (i = begin; i < end; i++) {
            lo = s->indices[i] < lo ? s->indices[i] : lo;
            hi = s->indices[i] > hi ? s->indices[i] : hi;
        }
        r->rebased[g] = (uint32_t *)malloc((end - begin ? end - begin : 1) * sizeof(uint32_t));
        if (!r->rebased[g])
            return 1;
        for (i = begin; i < end; i++)
            r->rebased[g][i - begin] = s->indices[i] - lo;
        r->groups[g].vertices = s->vertices + 4 * (size_t)lo;
        r->groups[g].vertex_count = end > begin ? (size_t)(hi - lo) + points : 0;
        r->groups[g].indices = r->rebased[g];
        r->groups[g].segment_count = end - begin;
        r->first_segment[g] = (uint32_t)begin;
    }
    progress_start("  %s: build", r->label);
    hairobb_result result = build_tree(s, r, group_surfaces[shape].shape, 0, &r->bvh[0], &r->build_seconds);
    progress("%s %.3f s", result != HAIROBB_OK ? hairobb_result_string(result) : "done", r->build_seconds);
    if (result != HAIROBB_OK)
        return 1;
    r->bvh_bytes = hairobb_memory_bytes(r->bvh[0]);
    r->accel.groups = r->bvh[0];
    r->accel.first_segment = r->first_segment;
    r->tracer.accel = &r->accel;
    r->tracer.intersect = groups_tracer_intersect;
    r->tracer.occluded = groups_tracer_occluded;
    return 0;
}

/* Embree over the same hair as k curve geometries of one scene (flat or
   round Bezier curves, as the shape; the scene's arrays shared, an index
   buffer each). */
static int build_embree_groups(const hair_scene *s, const size_t *first, size_t strands, int count, groups_shape shape,
                               group_row *r)
{
    size_t memory = 0;
    if ((size_t)count > strands)
        count = (int)strands;
    snprintf(r->label, sizeof r->label, "Embree %d geom %s", count, groups_shape_names[shape]);
    if (row_alloc(r, count, count) != 0)
        return 1;
    r->instances = 0;
    r->segments = s->segment_count;
    r->embree_indices = (uint32_t **)calloc((size_t)count, sizeof *r->embree_indices);
    r->embree_counts = (size_t *)calloc((size_t)count, sizeof *r->embree_counts);
    if (!r->embree_indices || !r->embree_counts || s->basis != SCENE_BASIS_BEZIER)
        return 1;
    for (int g = 0; g < count; g++) {
        size_t begin = first[strands * (size_t)g / (size_t)count], end = first[strands * (size_t)(g + 1) / (size_t)count];
        r->embree_indices[g] = (uint32_t *)malloc((end - begin ? end - begin : 1) * sizeof(uint32_t));
        if (!r->embree_indices[g])
            return 1;
        memcpy(r->embree_indices[g], s->indices + begin, (end - begin) * sizeof(uint32_t));
        r->embree_counts[g] = end - begin;
        r->first_segment[g] = (uint32_t)begin;
    }
    progress_start("  %s: build", r->label);
    r->embree = emb_build_groups(s->vertices, s->vertex_count, (const uint32_t *const *)r->embree_indices, r->embree_counts,
                                 (size_t)count, group_surfaces[shape].embree_type, 0, &memory, &r->build_seconds);
    progress("%s %.3f s", r->embree ? "done" : "failed", r->build_seconds);
    if (!r->embree)
        return 1;
    r->bvh_bytes = memory;
    r->accel.embree = r->embree;
    r->accel.first_segment = r->first_segment;
    r->tracer.accel = &r->accel;
    r->tracer.intersect = embree_groups_intersect;
    r->tracer.occluded = embree_groups_occluded;
    return 0;
}

/* ======================================================================== */
/* Hits against the one BVH's, and timing in rounds                         */
/* ======================================================================== */

/* Each scene row of groups traced over the ray set and compared ray by ray
   with the one BVH: hit or miss (shadow rays: occluded or not), and where
   both hit, the segment and t. */
static void check_rows(const options *o, const ray_set *rays, hit_record *base, hit_record *other, group_row rows[ROWS])
{
    int k = rays->kind;
    trace_pass(&rows[ROW_ONE].tracer, rays, base, max_threads(o));
    for (int row = ROW_SCENES; row < ROW_EMBREE; row++) {   /* Embree's flat curves are another surface */
        group_row *r = &rows[row];
        if (!r->measured)
            continue;
        progress_start("  %s: %s hits against the one BVH's", r->label, ray_kind_names[k]);
        trace_pass(&r->tracer, rays, other, max_threads(o));
        for (size_t i = 0; i < rays->count; i++) {
            const hit_record *a = &base[i], *b = &other[i];
            if ((a->prim == NO_HIT) != (b->prim == NO_HIT)) {
                r->hit_miss[k]++;
                continue;
            }
            if (a->prim == NO_HIT || k == RAYS_SHADOW)
                continue;
            if (a->prim != b->prim) {
                r->other_segment[k]++;
                r->tie[k] += a->t == b->t;
            } else if (memcmp(&a->t, &b->t, sizeof a->t) != 0) {
                double relative = fabs((double)a->t - (double)b->t) / fabs((double)a->t);
                r->t_differs[k]++;
                r->t_max_relative[k] = relative > r->t_max_relative[k] ? relative : r->t_max_relative[k];
            }
        }
        r->checked[k] = 1;
        progress("%zu hit/miss, %zu other segment", r->hit_miss[k], r->other_segment[k]);
    }
}

/* Every row one pass a round, after a warm-up pass each; the ratio to the
   one BVH taken within each round (not for the instanced row: other hair). */
static void time_rows(const options *o, const ray_set *rays, hit_record *hits, group_row rows[ROWS])
{
    static double mrays[ROWS][MAX_ROUNDS];
    int k = rays->kind;
    for (int t = 0; t < o->thread_count_count; t++) {
        unsigned threads = o->thread_counts[t];
        progress_start("  %s rays, %u thread%s: warm-up", ray_kind_names[k], threads, threads == 1 ? "" : "s");
        for (int row = 0; row < ROWS; row++)
            if (rows[row].measured)
                trace_pass(&rows[row].tracer, rays, hits, threads);
        for (int round = 0; round < o->rounds; round++) {
            progress_start("  %s rays, %u thread%s: round %d of %d", ray_kind_names[k], threads, threads == 1 ? "" : "s",
                           round + 1, o->rounds);
            for (int row = 0; row < ROWS; row++)
                if (rows[row].measured)
                    mrays[row][round] = (double)rays->count / trace_pass(&rows[row].tracer, rays, hits, threads) * 1e-6;
        }
        progress("done");
        for (int row = 0; row < ROWS; row++) {
            group_row *r = &rows[row];
            double ratios[MAX_ROUNDS];
            int with_ratio = row != ROW_INSTANCED && rows[ROW_ONE].measured;
            if (!r->measured)
                continue;
            for (int round = 0; round < o->rounds; round++)
                ratios[round] = with_ratio ? mrays[row][round] / mrays[ROW_ONE][round] : NAN;
            r->mrays[k][t] = spread_of(mrays[row], o->rounds);
            r->ratio[k][t] = spread_of(ratios, with_ratio ? o->rounds : 0);
            if (row >= ROW_ONE_TREE && row < ROW_EMBREE && rows[row + GROUP_SETS].measured) {   /* against Embree's same k */
                for (int round = 0; round < o->rounds; round++)
                    ratios[round] = mrays[row][round] / mrays[row + GROUP_SETS][round];
                r->pair[k][t] = spread_of(ratios, o->rounds);
            }
        }
    }
}

/* The builds in rounds: on each --threads count, --rounds rounds of the
   one BVH, then k in 1 BVH, for each k in turn (A B A B A B), each freed
   before the next; the ratio k in 1 / one BVH taken within each pair.
   0, or 1 when a build failed. */
static int time_builds(const options *o, const hair_scene *s, groups_shape shape, group_row rows[ROWS])
{
    static double one[GROUP_SETS - 1][MAX_ROUNDS], tree[GROUP_SETS - 1][MAX_ROUNDS], ratio[GROUP_SETS - 1][MAX_ROUNDS];
    hairobb_shape surface = group_surfaces[shape].shape;
    for (int t = 0; t < o->thread_count_count; t++) {
        unsigned threads = o->thread_counts[t];
        /* a pause first, as --builds makes: threads Embree's builds left spinning stop */
        struct timespec pause = {0, 200000000};
        nanosleep(&pause, NULL);
        for (int round = 0; round < o->rounds; round++) {
            progress_start("  builds, %u thread%s: round %d of %d", threads, threads == 1 ? "" : "s", round + 1, o->rounds);
            for (int set = 0; set < GROUP_SETS - 1; set++) {
                group_row *r = &rows[ROW_ONE_TREE + set];
                hairobb_bvh *bvh = NULL;
                if (!r->measured)
                    continue;
                bvh = build_group(s, 0, s->segment_count, surface, threads, &one[set][round]);
                if (!bvh)
                    return 1;
                hairobb_free(bvh);
                bvh = NULL;
                hairobb_result result = build_tree(s, r, surface, threads, &bvh, &tree[set][round]);
                hairobb_free(bvh);
                if (result != HAIROBB_OK) {
                    fprintf(stderr, "bench: hairobb_build_groups (%s): %s\n", r->label, hairobb_result_string(result));
                    return 1;
                }
                ratio[set][round] = tree[set][round] / one[set][round];
            }
        }
        progress("done");
        for (int set = 0; set < GROUP_SETS - 1; set++) {
            group_row *r = &rows[ROW_ONE_TREE + set];
            if (!r->measured)
                continue;
            r->build_one[t] = spread_of(one[set], o->rounds);
            r->build_tree[t] = spread_of(tree[set], o->rounds);
            r->build_ratio[t] = spread_of(ratio[set], o->rounds);
            r->build_timed = 1;
        }
    }
    return 0;
}

/* ======================================================================== */
/* Tables                                                                   */
/* ======================================================================== */

/* "median [min-max]" to 3 decimals (the group rows run at a tenth of the
   one BVH's speed and below), or "-" */
static const char *cell3(char *cell, size_t size, spread x)
{
    if (isnan(x.median))
        snprintf(cell, size, "-");
    else
        snprintf(cell, size, "%.3f [%.3f-%.3f]", x.median, x.min, x.max);
    return cell;
}

static void print_rows(const options *o, const hair_scene *s, const scene_layout *layout, groups_shape shape,
                       const ray_set rays[RAY_KIND_COUNT], size_t primary_hits, const group_row rows[ROWS])
{
    char arrays[256], cell[48];
    int space = layout->order == STRAND_ORDER_SPACE;
    printf("\n=== groups: %s, %zu segments in %zu strands, %s (%s), %s\n", s->name, s->segment_count, layout->strands,
           layout_order_text(layout),
           space                                     ? "a group is a patch of the fur"
           : layout->order == STRAND_ORDER_GENERATED ? "groups as the arrays hold the strands"
                                                     : "every group spans the whole fur",
           groups_shape_names[shape]);
    printf("surface: every row %s\n", group_surfaces[shape].text);
    printf("arrays: %s\n", layout_memory_text(layout, arrays, sizeof arrays));
    printf("rays: primary %zu (%dx%d pinhole), %.1f%% hit by the one BVH; incoherent %zu (diffuse bounce), shadow %zu "
           "(point light)\n",
           rays[RAYS_PRIMARY].count, o->resolution, o->resolution,
           rays[RAYS_PRIMARY].count ? 100.0 * (double)primary_hits / (double)rays[RAYS_PRIMARY].count : 0.0,
           rays[RAYS_INCOHERENT].count, rays[RAYS_SHADOW].count);
    printf("rows: the one BVH (hairobb_intersect1/_occluded1); it alone under a scene; the strands in array order split "
           "into\nk groups, a BVH each (default options but the surface, all cores), identity maps; the same k groups as "
           "one BVH\n(hairobb_build_groups: \"k in 1 BVH\"); Embree's hair as k curve geometries of one scene; group 0 of "
           "the 16\nplaced %d times, translated on a 4x4 grid %.2f of the scene's diagonal apart (other hair: speed alone)\n",
           INSTANCES, GRID_STEP);

    printf("\nbuild and memory (build: the BVHs' builds, one each, and the scene's; bytes: hairobb_memory_bytes of "
           "the BVHs\nand the scene's allocations; boxes: instance boxes a primary ray crosses, mean)\n");
    printf("%-*s %9s %5s %12s %10s %10s %9s %10s %10s %8s\n", LABEL_WIDTH, "row", "instances", "BVHs", "segments/BVH",
           "build s", "scene ms", "MB", "bytes/seg", "scene KB", "boxes");
    for (int row = 0; row < ROWS; row++) {
        const group_row *r = &rows[row];
        if (!r->measured) {
            printf("%-*s not built\n", LABEL_WIDTH, r->label);
            continue;
        }
        size_t bytes = r->bvh_bytes + r->scene_bytes;
        double per_bvh = (row == ROW_INSTANCED ? (double)r->segments / INSTANCES : (double)r->segments) /
                         (double)(r->embree ? 1 : r->bvh_count);
        char instances[16] = "-", scene_ms[16] = "-", scene_kb[16] = "-";
        if (r->instances) {
            snprintf(instances, sizeof instances, "%d", r->instances);
            snprintf(scene_ms, sizeof scene_ms, "%.3f", r->scene_seconds * 1e3);
            snprintf(scene_kb, sizeof scene_kb, "%.1f", (double)r->scene_bytes / 1024.0);
        }
        char boxes[16] = "-";
        if (r->boxes_per_ray == r->boxes_per_ray)
            snprintf(boxes, sizeof boxes, "%.2f", r->boxes_per_ray);
        printf("%-*s %9s %5d %12.0f %10.3f %10s %9.1f %10.1f %10s %8s\n", LABEL_WIDTH, r->label, instances,
               r->embree ? 1 : r->bvh_count, per_bvh, r->build_seconds, scene_ms, (double)bytes / 1048576.0,
               (double)bytes / (double)r->segments, scene_kb, boxes);
    }

    printf("\nbuild in rounds: %d round%s on each thread count, each the one BVH (hairobb_build) and then k in 1 BVH\n"
           "(hairobb_build_groups over its groups' arrays, made beforehand) for each k in turn, each freed before the\n"
           "next; seconds, and k in 1 / one BVH within each pair: median [min-max]; +bytes/seg: k in 1 BVH's\n"
           "hairobb_memory_bytes less the one BVH's, a segment\n",
           o->rounds, o->rounds == 1 ? "" : "s");
    printf("%-*s %7s %-26s %-26s %-24s %10s\n", LABEL_WIDTH, "row", "threads", "one BVH s", "k in 1 BVH s",
           "k in 1 / one BVH", "+bytes/seg");
    for (int row = ROW_ONE_TREE; row < ROW_EMBREE; row++) {
        const group_row *r = &rows[row];
        if (!r->build_timed)
            continue;
        for (int t = 0; t < o->thread_count_count; t++) {
            char seconds[2][48];
            snprintf(seconds[0], sizeof seconds[0], "%.4f [%.4f-%.4f]", r->build_one[t].median, r->build_one[t].min,
                     r->build_one[t].max);
            snprintf(seconds[1], sizeof seconds[1], "%.4f [%.4f-%.4f]", r->build_tree[t].median, r->build_tree[t].min,
                     r->build_tree[t].max);
            printf("%-*s %7u %-26s %-26s %-24s %10.2f\n", LABEL_WIDTH, r->label, o->thread_counts[t], seconds[0], seconds[1],
                   cell3(cell, sizeof cell, r->build_ratio[t]),
                   ((double)r->bvh_bytes - (double)rows[ROW_ONE].bvh_bytes) / (double)r->segments);
        }
    }

    for (int table = 0; table < 2; table++) {
        printf(table == 0 ? "\nMrays/s: median of %d round%s [min-max]\n"
                          : "\nthis / the one BVH, the ratio taken within each round: median of %d round%s [min-max]\n",
               o->rounds, o->rounds == 1 ? "" : "s");
        printf("%-*s", LABEL_WIDTH, "row");
        for (int k = 0; k < RAY_KIND_COUNT; k++)
            for (int t = 0; t < o->thread_count_count; t++)
                if (o->ray_kind_enabled[k] && rays[k].count) {
                    char head[32];
                    snprintf(head, sizeof head, "%s %ut", ray_kind_names[k], o->thread_counts[t]);
                    printf(" %-22s", head);
                }
        printf("\n");
        for (int row = 0; row < ROWS; row++) {
            const group_row *r = &rows[row];
            if (!r->measured || (table == 1 && row == ROW_INSTANCED))
                continue;
            printf("%-*s", LABEL_WIDTH, r->label);
            for (int k = 0; k < RAY_KIND_COUNT; k++)
                for (int t = 0; t < o->thread_count_count; t++)
                    if (o->ray_kind_enabled[k] && rays[k].count)
                        printf(" %-22s", cell3(cell, sizeof cell, table == 0 ? r->mrays[k][t] : r->ratio[k][t]));
            printf("\n");
        }
    }

    printf("\nk groups in one hairobb BVH / Embree's k curve geometries in one scene, the ratio taken within each round: median "
           "of %d round%s [min-max]\n", o->rounds, o->rounds == 1 ? "" : "s");
    for (int row = ROW_ONE_TREE; row < ROW_EMBREE; row++) {
        const group_row *r = &rows[row];
        if (!r->measured || !rows[row + GROUP_SETS].measured)
            continue;
        printf("%-*s", LABEL_WIDTH, r->label);
        for (int k = 0; k < RAY_KIND_COUNT; k++)
            for (int t = 0; t < o->thread_count_count; t++)
                if (o->ray_kind_enabled[k] && rays[k].count)
                    printf(" %-22s", cell3(cell, sizeof cell, r->pair[k][t]));
        printf("\n");
    }

    printf("\nhits against the one BVH's, every ray: hit or miss (shadow: occluded or not) differs; both hit, another "
           "segment\n(of them at the same t: ties), the same segment at another t (max |dt|/t)\n");
    printf("%-*s %-11s %9s %10s %6s %10s %12s\n", LABEL_WIDTH, "row", "ray set", "rays", "hit/miss", "other", "ties", "t differs");
    for (int row = ROW_SCENES; row < ROW_INSTANCED; row++)
        for (int k = 0; k < RAY_KIND_COUNT; k++) {
            const group_row *r = &rows[row];
            if (!r->checked[k])
                continue;
            if (k == RAYS_SHADOW)
                printf("%-*s %-11s %9zu %10zu %6s %10s %12s\n", LABEL_WIDTH, r->label, ray_kind_names[k], rays[k].count, r->hit_miss[k],
                       "-", "-", "-");
            else {
                char differs[48];
                snprintf(differs, sizeof differs, "%zu (%.1e)", r->t_differs[k], r->t_max_relative[k]);
                printf("%-*s %-11s %9zu %10zu %6zu %10zu %12s\n", LABEL_WIDTH, r->label, ray_kind_names[k], rays[k].count,
                       r->hit_miss[k], r->other_segment[k], r->tie[k], differs);
            }
        }
    fflush(stdout);
}

/* ======================================================================== */
/* A scene in one strand order, and the mode                                */
/* ======================================================================== */

/* The rows of one scene in one order and one surface: built, their hits
   checked against the one BVH's, traced and built in rounds, printed.
   primary: the scene's primary rays; first: its strands' first segments.
   0, or 1 on an error. */
static int run_group_shape(const options *o, const hair_scene *s, const scene_layout *layout, const size_t *first,
                           size_t strands, const ray_set *primary, groups_shape shape)
{
    static group_row rows[ROWS];
    ray_set rays[RAY_KIND_COUNT];
    hit_record *hits = NULL, *other = NULL;
    size_t primary_hits = 0;
    float offsets[INSTANCES][3];
    hairobb_shape surface = group_surfaces[shape].shape;
    int failed = 0;
    memset(rows, 0, sizeof rows);
    memset(rays, 0, sizeof rays);
    rays[RAYS_PRIMARY] = *primary;   /* shared with the other surface: not freed here */
    hits = (hit_record *)malloc((primary->count ? primary->count : 1) * sizeof *hits);
    other = (hit_record *)malloc((primary->count ? primary->count : 1) * sizeof *other);
    failed = !hits || !other;
    progress("groups: %s, %s order, %s", s->name, strand_order_names[layout->order], groups_shape_names[shape]);

    /* the one BVH, and the secondary rays from its primary hits */
    group_row *one = &rows[ROW_ONE];
    snprintf(one->label, sizeof one->label, "one BVH %s", groups_shape_names[shape]);
    if (!failed && !(failed = row_alloc(one, 0, 1))) {
        progress_start("  %s: build", one->label);
        one->owned = 1;
        one->segments = s->segment_count;
        one->bvh[0] = build_group(s, 0, s->segment_count, surface, 0, &one->build_seconds);
        failed = !one->bvh[0];
        progress("%s %.3f s", failed ? "failed" : "done", one->build_seconds);
    }
    if (!failed) {
        one->bvh_bytes = hairobb_memory_bytes(one->bvh[0]);
        one->tracer = hairobb_tracer(one->bvh[0]);
        one->measured = 1;
        trace_pass(&one->tracer, &rays[RAYS_PRIMARY], hits, max_threads(o));
        for (size_t i = 0; i < rays[RAYS_PRIMARY].count; i++)
            primary_hits += hits[i].prim != NO_HIT;
        failed = secondary_rays(s, &rays[RAYS_PRIMARY], hits, &rays[RAYS_INCOHERENT], &rays[RAYS_SHADOW]);
        one->boxes_per_ray = boxes_per_ray(one, NULL, &rays[RAYS_PRIMARY]);
    }

    /* the one BVH under a scene, then the groups */
    for (int set = 0; set < GROUP_SETS && !failed; set++) {
        group_row *r = &rows[ROW_SCENES + set];
        if (group_counts[set] == 1) {
            snprintf(r->label, sizeof r->label, "scene of 1 %s", groups_shape_names[shape]);
            failed = row_alloc(r, 1, 1);
            if (failed)
                break;
            r->bvh[0] = one->bvh[0];
            r->segments = s->segment_count;
            r->build_seconds = one->build_seconds;
            r->bvh_bytes = one->bvh_bytes;
        } else if (build_groups(s, first, strands, group_counts[set], shape, r) != 0) {
            failed = 1;
            break;
        }
        failed = row_scene(r, NULL);
        if (!failed) {
            r->boxes_per_ray = boxes_per_ray(r, NULL, &rays[RAYS_PRIMARY]);
            r->measured = 1;
        }
    }

    /* the groups as one BVH each */
    for (int set = 1; set < GROUP_SETS && !failed; set++) {
        group_row *r = &rows[ROW_ONE_TREE + set - 1];
        failed = build_one_tree(s, first, strands, group_counts[set], shape, r);
        if (!failed) {
            r->boxes_per_ray = one->boxes_per_ray;
            r->measured = 1;
        }
    }

    /* Embree: the hair as 1, 4, 16, 64 geometries of one scene (Bezier scenes) */
    for (int set = 0; set < GROUP_SETS && !failed && s->basis == SCENE_BASIS_BEZIER; set++) {
        group_row *r = &rows[ROW_EMBREE + set];
        failed = build_embree_groups(s, first, strands, group_counts[set], shape, r);
        if (!failed) {
            r->boxes_per_ray = NAN;
            r->measured = 1;
        }
    }

    /* group 0 of the 16, placed 16 times */
    group_row *placed = &rows[ROW_INSTANCED], *from = &rows[INSTANCED_FROM];
    snprintf(placed->label, sizeof placed->label, "%d instances %s", INSTANCES, groups_shape_names[shape]);
    if (!failed && !(failed = row_alloc(placed, INSTANCES, 1))) {
        scene_vec3 extent = scene_v3(s->upper[0] - s->lower[0], s->upper[1] - s->lower[1], s->upper[2] - s->lower[2]);
        float step = (float)GRID_STEP * scene_v3_length(extent);
        size_t group_segments = (from->bvh_count > 1 ? from->first_segment[1] : s->segment_count) - from->first_segment[0];
        for (int i = 0; i < INSTANCES; i++) {
            offsets[i][0] = step * ((float)(i % 4) - 1.5f);
            offsets[i][1] = step * ((float)(i / 4) - 1.5f);
            offsets[i][2] = 0.0f;
            placed->first_segment[i] = from->first_segment[0];
        }
        placed->bvh[0] = from->bvh[0];
        placed->segments = INSTANCES * group_segments;
        placed->bvh_bytes = hairobb_memory_bytes(from->bvh[0]);
        placed->build_seconds = from->first_build_seconds; /* its one BVH's build, then its scene's */
        failed = row_scene(placed, (const float(*)[3])offsets);
        if (!failed) {
            placed->boxes_per_ray = boxes_per_ray(placed, (const float(*)[3])offsets, &rays[RAYS_PRIMARY]);
            placed->measured = 1;
        }
    }

    for (int k = 0; k < RAY_KIND_COUNT && !failed; k++)
        if (o->ray_kind_enabled[k] && rays[k].count)
            check_rows(o, &rays[k], hits, other, rows);
    for (int k = 0; k < RAY_KIND_COUNT && !failed; k++)
        if (o->ray_kind_enabled[k] && rays[k].count)
            time_rows(o, &rays[k], hits, rows);
    if (!failed)
        failed = time_builds(o, s, shape, rows);
    if (failed)
        fprintf(stderr, "bench: --groups: %s (%s): out of memory, or a build failed\n", s->name, groups_shape_names[shape]);
    else
        print_rows(o, s, layout, shape, rays, primary_hits, rows);

    for (int row = ROWS - 1; row >= 0; row--)
        row_free(&rows[row]);
    ray_set_free(&rays[RAYS_INCOHERENT]);
    ray_set_free(&rays[RAYS_SHADOW]);
    free(hits);
    free(other);
    return failed;
}

/* Loads --scene's index-th scene in the given order and runs its rows as
   each surface of --groups-shape in turn. 0, or 1 on an error. */
static int run_group_scene(const options *given, int index, int order)
{
    options o = *given;
    hair_scene s;
    scene_layout layout;
    char why[TEST_DATA_WHY_SIZE], why_not[256];
    ray_set primary;
    size_t *first = NULL, strands = 0;
    int failed = 0;
    o.strand_order = order;
    memset(&primary, 0, sizeof primary);
    progress("groups: %s, loading", o.scenes[index]);
    int loaded = load_scene(&o, o.scenes[index], scene_segments(&o, index), &s, &layout, why);
    if (loaded != 0) {
        printf("\n=== groups: %s skipped: %s\n", o.scenes[index], loaded < 0 ? why : "could not be loaded");
        return loaded > 0;
    }
    /* the one BVH and the six rows of groups each hold the whole hair, and
       Embree's four; the builds in rounds one more build at a time */
    if (!memory_fits((3.0 * GROUP_SETS) * HAIROBB_WITH_COPY_BYTES_PER_SEGMENT * (double)s.segment_count +
                         HAIROBB_BUILD_PEAK_BYTES_PER_SEGMENT * (double)s.segment_count,
                     "the BVHs", why_not, sizeof why_not)) {
        printf("\n=== groups: %s skipped: %s\n", s.name, why_not);
        scene_free(&s);
        return 0;
    }
    first = find_strands(&s, &strands);
    failed = !first || primary_rays(&s, o.resolution, &primary) != 0;
    for (int shape = 0; shape < GROUPS_SHAPE_COUNT && !failed; shape++)
        if (o.groups_shapes & (1u << shape))
            failed = run_group_shape(&o, &s, &layout, first, strands, &primary, (groups_shape)shape);
    if (failed && !first)
        fprintf(stderr, "bench: --groups: %s: out of memory\n", s.name);
    ray_set_free(&primary);
    free(first);
    scene_free(&s);
    return failed;
}

int run_groups(const options *o)
{
    int failures = 0;
    for (int c = 0; c < o->scene_count; c++) {
        if (o->strand_order != STRAND_ORDER_UNSET)
            failures += run_group_scene(o, c, o->strand_order);
        else {
            failures += run_group_scene(o, c, STRAND_ORDER_UNSET); /* groom (procedural) or the file's order */
            failures += run_group_scene(o, c, STRAND_ORDER_SPACE);
        }
    }
    return failures ? 1 : 0;
}
