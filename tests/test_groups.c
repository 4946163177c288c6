/* test_groups.c - several hair groups in one BVH (hairobb_build_groups,
   GROUPS), each against one BVH (hairobb_build) over the same hair: the
   groups' arrays concatenated in group order, so that segment p of group g
   is segment group_first[g] + p there.

   - Strands dealt to 1, 4 and 16 groups in groom order (strand i to group
     i % k: every group spans the fur) and in space order, ribbons and
     tubes (caps on): camera rays and rays aimed at segments hit the same
     segments, bit for bit (t, u, v, Ng, tangent), the ids mapped; occluded1
     agrees; a secondary ray from each hit (_from) as the one BVH's.
   - Masks: each group's mask a bit of its own (group g: bit g % 32, one
     group 0 = every bit), rays with random masks: the one BVH with a filter
     that ignores the hits of groups the mask excludes gives the same hits.
   - Filters see each hit's group and its segment within the group.
   - hairobb_refit_group moves one group: the same hits as a one BVH built
     over the moved hair; a bad refit is refused and leaves the BVH as it
     was. Motion blur (2 steps): the same hits at ray times 0, 0.3, 1.
   - Instances: a scene over a multi-group BVH gives its hits with
     instance_id.
   - Mixed shapes: ribbon and tube groups in one BVH trace as the nearer
     of the same groups' ribbon BVH and tube BVH (each shown only its own
     groups' hits), bounces and save/load too; a load asking another
     shape is refused; an empty group's shape changes nothing.
   - Group stats: counts as given, leaf references and bytes adding up to
     the BVH's.
   - Bad input: no groups, NULL arrays, an index past its own group's
     points (INDEX_OUT_OF_RANGE even where the concatenation would reach
     the next group), NaN; an empty group is never hit; failed
     allocations leak nothing. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_alloc.h"
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "check.h"
#include "compare.h"
#include "scenes.h"

#define MAX_GROUPS 16

/* A scene's strands dealt to groups: each group's own arrays, and the
   concatenation in group order (one BVH's input). */
typedef struct grouped {
    size_t count;
    hairobb_group group[MAX_GROUPS];
    float *vertices[MAX_GROUPS];
    uint32_t *indices[MAX_GROUPS];
    float *all_vertices;        /* the concatenation */
    uint32_t *all_indices;
    size_t all_vertex_count, all_segment_count;
    uint32_t first[MAX_GROUPS + 1];   /* group g's segments in the concatenation */
} grouped;

/* Strand i (Bezier segments sharing end points, indices 3 apart) goes to
   group i % k (groom order) or to group i * k / strands (space order: the
   scenes generate strands by position). */
static void group_strands(grouped *out, const hair_scene *s, size_t k, int space_order)
{
    size_t i, strands = 0, g, strand = 0;
    size_t *first_segment = (size_t *)malloc(sizeof(size_t) * (s->segment_count + 1));
    memset(out, 0, sizeof *out);
    out->count = k;
    for (i = 0; i < s->segment_count; ++i)
        if (i == 0 || s->indices[i] != s->indices[i - 1] + 3) first_segment[strands++] = i;
    first_segment[strands] = s->segment_count;
    for (g = 0; g < k; ++g) {
        size_t points = 0, segments = 0;
        for (strand = 0; strand < strands; ++strand) {
            size_t owner = space_order ? strand * k / strands : strand % k;
            if (owner != g) continue;
            segments += first_segment[strand + 1] - first_segment[strand];
            points += 3 * (first_segment[strand + 1] - first_segment[strand]) + 1;
        }
        out->vertices[g] = (float *)malloc(16 * (points ? points : 1));
        out->indices[g] = (uint32_t *)malloc(4 * (segments ? segments : 1));
        points = segments = 0;
        for (strand = 0; strand < strands; ++strand) {
            size_t owner = space_order ? strand * k / strands : strand % k, a = first_segment[strand], b = first_segment[strand + 1], j;
            size_t n = 3 * (b - a) + 1;
            if (owner != g) continue;
            memcpy(out->vertices[g] + 4 * points, s->vertices + 4 * (size_t)s->indices[a], 16 * n);
            for (j = a; j < b; ++j) out->indices[g][segments++] = (uint32_t)(points + 3 * (j - a));
            points += n;
        }
        out->group[g].vertices = out->vertices[g];
        out->group[g].vertex_count = points;
        out->group[g].indices = out->indices[g];
        out->group[g].segment_count = segments;
        out->group[g].mask = g == 1 ? 0u : 1u << (g % 32);
        out->group[g].user = out;
        out->all_vertex_count += points;
        out->all_segment_count += segments;
    }
    out->all_vertices = (float *)malloc(16 * out->all_vertex_count);
    out->all_indices = (uint32_t *)malloc(4 * out->all_segment_count);
    {
        size_t vbase = 0, sbase = 0, j;
        for (g = 0; g < k; ++g) {
            memcpy(out->all_vertices + 4 * vbase, out->vertices[g], 16 * out->group[g].vertex_count);
            out->first[g] = (uint32_t)sbase;
            for (j = 0; j < out->group[g].segment_count; ++j) out->all_indices[sbase + j] = out->indices[g][j] + (uint32_t)vbase;
            vbase += out->group[g].vertex_count;
            sbase += out->group[g].segment_count;
        }
        out->first[k] = (uint32_t)sbase;
    }
    free(first_segment);
}

static void grouped_free(grouped *gr)
{
    size_t g;
    for (g = 0; g < gr->count; ++g) {
        free(gr->vertices[g]);
        free(gr->indices[g]);
    }
    free(gr->all_vertices);
    free(gr->all_indices);
}

/* The one BVH's hit with its ids as the multi-group BVH names them. */
static void map_ids(const grouped *gr, hairobb_hit *hit)
{
    uint32_t g = 0;
    while (g + 1 < gr->count && gr->first[g + 1] <= hit->prim_id) ++g;
    hit->prim_id -= gr->first[g];
    hit->group_id = g;
}

/* A filter on the one BVH: ignores the hits of the groups the ray's mask
   excludes (user: the grouped hair and the mask, in a mask_filter). */
typedef struct mask_filter {
    const grouped *gr;
    uint32_t mask;
} mask_filter;

static int mask_filter_fn(void *user, const hairobb_ray *ray, const hairobb_hit *hit)
{
    const mask_filter *m = (const mask_filter *)user;
    hairobb_hit mapped = *hit;
    uint32_t group_mask;
    (void)ray;
    map_ids(m->gr, &mapped);
    group_mask = m->gr->group[mapped.group_id].mask ? m->gr->group[mapped.group_id].mask : 0xffffffffu;
    return (group_mask & m->mask) != 0;
}

/* A filter on the multi-group BVH that checks what it is shown and takes
   every hit. */
typedef struct shown_ids {
    const grouped *gr;
    size_t shown, bad;
} shown_ids;

static int check_ids(void *user, const hairobb_ray *ray, const hairobb_hit *hit)
{
    shown_ids *s = (shown_ids *)user;
    (void)ray;
    ++s->shown;
    s->bad += hit->group_id >= s->gr->count || hit->prim_id >= s->gr->group[hit->group_id].segment_count ||
              hit->instance_id != HAIROBB_INVALID_ID;
    return 1;
}

static void make_rays(const grouped *gr, const hair_scene *s, size_t n, uint64_t seed, float *org, float *dir)
{
    size_t side = 64, i;
    scene_rng rng;
    scene_camera_rays(s, (int)side, (int)side, org, dir);
    scene_rng_seed(&rng, seed);
    for (i = side * side; i < n; ++i) {
        size_t prim = (size_t)(scene_rng_float(&rng) * (float)gr->all_segment_count) % gr->all_segment_count;
        scene_ray_near_segment(gr->all_vertices + 4 * (size_t)gr->all_indices[prim], &rng, org + 3 * i, dir + 3 * i);
    }
}

/* Ray i of the set, from org and dir, at `time`. */
static hairobb_ray ray_of(const float *org, const float *dir, size_t i, float time)
{
    hairobb_ray ray;
    memcpy(ray.org, org + 3 * i, sizeof ray.org);
    memcpy(ray.dir, dir + 3 * i, sizeof ray.dir);
    ray.tnear = 0.0f;
    ray.tfar = INFINITY;
    ray.time = time;
    return ray;
}

/* The rays traced by a and b; the count of rays whose hits differ (b's
   ids mapped to groups where gr is given), and a's hits in *hits. Ray i
   at times[i % 3] (NULL: 0). */
static size_t trace_differ(const hairobb_bvh *a, const hairobb_bvh *b, const grouped *gr, const float *org, const float *dir, size_t rays,
                           const float *times, size_t *hits)
{
    size_t i, differ = 0;
    *hits = 0;
    for (i = 0; a && b && i < rays; ++i) {
        hairobb_ray ray = ray_of(org, dir, i, times ? times[i % 3] : 0.0f);
        hairobb_hit ha, hb;
        int got_a = hairobb_intersect1(a, &ray, &ha), got_b = hairobb_intersect1(b, &ray, &hb);
        if (got_b && gr) map_ids(gr, &hb);
        *hits += (size_t)got_a;
        differ += !same_hit(got_a, &ha, got_b, &hb);
    }
    return differ;
}

/* The multi-group BVH against the one BVH: hits, occlusion, a bounce from
   each hit, ray masks, what filters are shown. */
static void compare_groups(const char *name, const grouped *gr, const hair_scene *s, const hairobb_build_options *options,
                           const float *org, const float *dir, size_t rays)
{
    hairobb_bvh *groups = NULL, *one = NULL;
    hairobb_build_options one_options = *options;
    size_t i, hits = 0, differ = 0, occluded_differ = 0, bounce_differ = 0, masked_differ = 0, mask_changed = 0;
    shown_ids shown;
    mask_filter mf;
    hairobb_context shown_context, mask_context;
    hairobb_result r = hairobb_build_groups(gr->group, gr->count, options, &groups);
    CHECK(r == HAIROBB_OK, "%s: hairobb_build_groups: %s", name, hairobb_result_string(r));
    CHECK(hairobb_build(gr->all_vertices, gr->all_vertex_count, gr->all_indices, gr->all_segment_count, &one_options, &one) == HAIROBB_OK,
          "%s: one BVH", name);
    if (!groups || !one) return;
    CHECK(hairobb_group_count(groups) == gr->count && hairobb_group_user(groups, 0) == gr &&
              hairobb_group_segments(groups, (uint32_t)gr->count - 1) == gr->group[gr->count - 1].segment_count &&
              hairobb_group_segments(groups, (uint32_t)gr->count) == 0 && hairobb_group_count(one) == 1,
          "%s: group count, users and segment counts", name);
    memset(&shown, 0, sizeof shown);
    shown.gr = gr;
    shown_context.filter = check_ids;
    shown_context.user = &shown;
    shown_context.mask = 0;
    mf.gr = gr;
    mask_context.filter = mask_filter_fn;
    mask_context.user = &mf;
    mask_context.mask = 0;
    for (i = 0; i < rays; ++i) {
        hairobb_ray ray = ray_of(org, dir, i, 0.0f);
        hairobb_hit a, b, shown_hit;
        int got_a, got_b;
        got_a = hairobb_intersect1(groups, &ray, &a);
        got_b = hairobb_intersect1(one, &ray, &b);
        if (got_b) map_ids(gr, &b);
        hits += (size_t)got_a;
        differ += !same_hit(got_a, &a, got_b, &b);
        occluded_differ += hairobb_occluded1(groups, &ray) != got_a;
        if (hairobb_intersect1_context(groups, &shown_context, NULL, &ray, &shown_hit) != got_a) ++differ;
        if (got_a && got_b) {   /* a bounce: reflected about Ng, from the hit */
            hairobb_ray bounce = ray;
            hairobb_hit from_b = b, next_a, next_b;
            float along = 2.0f * (ray.dir[0] * a.Ng[0] + ray.dir[1] * a.Ng[1] + ray.dir[2] * a.Ng[2]);
            int k, ga, gb;
            for (k = 0; k < 3; ++k) {
                bounce.org[k] = ray.org[k] + a.t * ray.dir[k];
                bounce.dir[k] = ray.dir[k] - along * a.Ng[k];
            }
            from_b.prim_id += gr->first[from_b.group_id];   /* the one BVH's own id */
            ga = hairobb_intersect1_from(groups, &a, &bounce, &next_a);
            gb = hairobb_intersect1_from(one, &from_b, &bounce, &next_b);
            if (gb) map_ids(gr, &next_b);
            bounce_differ += !same_hit(ga, &next_a, gb, &next_b);
        }
        {   /* a ray mask: the one BVH ignores the excluded groups' hits */
            hairobb_context masked;
            hairobb_hit ma, mb;
            int gm, gn;
            uint32_t mask = (uint32_t)(i * 2654435761u) | (i % 3 == 0 ? 0u : 1u << 31);
            if (i % 7 == 0) mask = 0;   /* every bit */
            masked.filter = NULL;
            masked.user = NULL;
            masked.mask = mask;
            mf.mask = mask ? mask : 0xffffffffu;
            gm = hairobb_intersect1_context(groups, &masked, NULL, &ray, &ma);
            gn = hairobb_intersect1_context(one, &mask_context, NULL, &ray, &mb);
            if (gn) map_ids(gr, &mb);
            masked_differ += !same_hit(gm, &ma, gn, &mb) || hairobb_occluded1_context(groups, &masked, NULL, &ray) != gm;
            mask_changed += !same_hit(gm, &ma, got_a, &a);
        }
    }
    printf("%s: %zu groups, %zu rays, %zu hits: %zu differ from one BVH over the same hair, occluded1 %zu, bounces %zu, "
           "ray masks %zu (the mask changed %zu hits); filters shown %zu hits, %zu with bad ids; memory %zu bytes (one BVH %zu)\n",
           name, gr->count, rays, hits, differ, occluded_differ, bounce_differ, masked_differ, mask_changed, shown.shown, shown.bad,
           hairobb_memory_bytes(groups), hairobb_memory_bytes(one));
    CHECK(hits > rays / 4, "%s: %zu hits", name, hits);
    CHECK(differ == 0 && occluded_differ == 0 && bounce_differ == 0 && masked_differ == 0,
          "%s: %zu hits, %zu occlusions, %zu bounces, %zu masked rays differ", name, differ, occluded_differ, bounce_differ, masked_differ);
    CHECK(gr->count == 1 || mask_changed > hits / 10, "%s: ray masks changed only %zu hits", name, mask_changed);
    CHECK(shown.shown >= hits && shown.bad == 0, "%s: filters shown %zu hits, %zu with bad ids", name, shown.shown, shown.bad);
    hairobb_free(groups);
    hairobb_free(one);
    (void)s;
}

/* hairobb_refit_group against a one BVH built over the moved hair. */
static void test_refit_group(const grouped *gr_in, const float *org, const float *dir, size_t rays, hairobb_switch copy)
{
    hairobb_build_options o = hairobb_default_options();
    grouped gr = *gr_in;   /* shallow: group 1's vertices replaced below */
    hairobb_bvh *groups = NULL, *one = NULL;
    size_t n = gr.group[1].vertex_count, i, differ = 0, hits = 0;
    float *moved = (float *)malloc(16 * n), *all = (float *)malloc(16 * gr.all_vertex_count), *bad = (float *)malloc(16 * n);
    size_t vbase = gr.group[0].vertex_count;
    hairobb_result r;
    for (i = 0; i < 4 * n; ++i) moved[i] = gr.vertices[1][i] + ((i & 3) == 1 ? 0.05f : 0.0f);   /* up by 0.05 */
    memcpy(all, gr.all_vertices, 16 * gr.all_vertex_count);
    memcpy(all + 4 * vbase, moved, 16 * n);
    memcpy(bad, moved, 16 * n);
    bad[4 * (n / 2)] = NAN;
    o.bezier_copy = copy;   /* with the copy, the others' points are gathered from it */
    CHECK(hairobb_build_groups(gr.group, gr.count, &o, &groups) == HAIROBB_OK, "refit: builds");
    CHECK(hairobb_build(all, gr.all_vertex_count, gr.all_indices, gr.all_segment_count, &o, &one) == HAIROBB_OK, "refit: one BVH");
    if (!groups || !one) return;
    r = hairobb_refit_group(groups, 1, bad, NULL, NULL);
    CHECK(r == HAIROBB_ERROR_INVALID_GEOMETRY, "refit_group with a NaN: %s", hairobb_result_string(r));
    CHECK(hairobb_refit_group(groups, (uint32_t)gr.count, moved, NULL, NULL) == HAIROBB_ERROR_INVALID_ARGUMENT &&
              hairobb_refit(groups, gr.all_vertices) == HAIROBB_ERROR_INVALID_ARGUMENT,
          "refit of a group out of range, and hairobb_refit of a multi-group BVH, refused");
    r = hairobb_refit_group(groups, 1, moved, NULL, NULL);
    CHECK(r == HAIROBB_OK, "refit_group: %s", hairobb_result_string(r));
    memset(moved, 0, 16 * n);   /* the BVH keeps its own copy */
    differ = trace_differ(groups, one, &gr, org, dir, rays, NULL, &hits);
    printf("refit_group (group 1 of %zu moved, after a refused refit; copy %s): %zu rays, %zu hits, %zu differ from one BVH built "
           "moved; memory %zu bytes (one BVH %zu)\n", gr.count, copy == HAIROBB_OFF ? "off" : "on", rays, hits, differ,
           hairobb_memory_bytes(groups), hairobb_memory_bytes(one));
    CHECK(differ == 0 && hits > rays / 4, "refit_group: %zu differ, %zu hits", differ, hits);
    hairobb_free(groups);
    hairobb_free(one);
    free(moved);
    free(all);
    free(bad);
}

/* Motion blur: the groups' steps against one BVH over the concatenated steps. */
static void test_motion(const grouped *gr, const float *org, const float *dir, size_t rays)
{
    static const float times[3] = {0.0f, 0.3f, 1.0f};
    hairobb_group moving[MAX_GROUPS];
    const float *steps[MAX_GROUPS][2], *all_steps[2];
    float *later[MAX_GROUPS], *all_later = (float *)malloc(16 * gr->all_vertex_count);
    hairobb_build_options o = hairobb_default_options();
    hairobb_bvh *groups = NULL, *one = NULL;
    size_t g, differ = 0, hits = 0, vbase = 0;
    for (g = 0; g < gr->count; ++g) {
        size_t n = gr->group[g].vertex_count, j;
        later[g] = (float *)malloc(16 * (n ? n : 1));
        for (j = 0; j < 4 * n; ++j) later[g][j] = gr->vertices[g][j] + ((j & 3) == 0 ? 0.03f * (float)(g + 1) : 0.0f);
        memcpy(all_later + 4 * vbase, later[g], 16 * n);
        vbase += n;
        steps[g][0] = gr->vertices[g];
        steps[g][1] = later[g];
        moving[g] = gr->group[g];
        moving[g].vertices = NULL;
        moving[g].time_vertices = steps[g];
    }
    all_steps[0] = gr->all_vertices;
    all_steps[1] = all_later;
    o.time_steps = 2;
    CHECK(hairobb_build_groups(moving, gr->count, &o, &groups) == HAIROBB_OK, "motion: builds");
    o.time_vertices = all_steps;
    CHECK(hairobb_build(NULL, gr->all_vertex_count, gr->all_indices, gr->all_segment_count, &o, &one) == HAIROBB_OK, "motion: one BVH");
    differ = trace_differ(groups, one, gr, org, dir, rays, times, &hits);
    printf("motion (2 steps, rays at times 0, 0.3, 1): %zu rays, %zu hits, %zu differ from one BVH\n", rays, hits, differ);
    CHECK(differ == 0 && hits > rays / 4, "motion: %zu differ, %zu hits", differ, hits);
    hairobb_free(groups);
    hairobb_free(one);
    for (g = 0; g < gr->count; ++g) free(later[g]);
    free(all_later);
}

/* Saved and loaded (hairobb_load_groups): the same hits bit for bit;
   hairobb_load refuses the groups' bytes, other group sizes are refused,
   a one-group BVH's bytes load as one group. */
static void test_save_load(const grouped *gr, const float *org, const float *dir, size_t rays)
{
    hairobb_bvh *groups = NULL, *loaded = NULL, *other = NULL;
    hairobb_group shifted[MAX_GROUPS];
    size_t size, differ = 0, hits = 0;
    unsigned char *bytes;
    hairobb_result r;
    CHECK(hairobb_build_groups(gr->group, gr->count, NULL, &groups) == HAIROBB_OK, "save: builds");
    if (!groups) return;
    size = hairobb_save_size(groups);
    bytes = (unsigned char *)malloc(size);
    CHECK(bytes && hairobb_save(groups, bytes, size) == HAIROBB_OK, "save: saved (%zu bytes)", size);
    r = hairobb_load_groups(bytes, size, gr->group, gr->count, NULL, &loaded);
    CHECK(r == HAIROBB_OK && hairobb_group_count(loaded) == gr->count, "load_groups: %s", hairobb_result_string(r));
    r = hairobb_load(bytes, size, gr->all_vertices, gr->all_vertex_count, gr->all_indices, gr->all_segment_count, NULL, &other);
    CHECK(r == HAIROBB_ERROR_MISMATCH && !other, "hairobb_load of a multi-group BVH's bytes: %s", hairobb_result_string(r));
    memcpy(shifted, gr->group, gr->count * sizeof shifted[0]);
    shifted[0].segment_count -= 8;   /* a strand fewer in group 0: the same total count elsewhere would differ too */
    r = hairobb_load_groups(bytes, size, shifted, gr->count, NULL, &other);
    CHECK(r == HAIROBB_ERROR_MISMATCH && !other, "load_groups over other groups: %s", hairobb_result_string(r));
    r = hairobb_load_groups(bytes, size, gr->group, gr->count - 1, NULL, &other);
    CHECK(r == HAIROBB_ERROR_MISMATCH && !other, "load_groups over fewer groups: %s", hairobb_result_string(r));
    differ = trace_differ(groups, loaded, NULL, org, dir, rays, NULL, &hits);
    printf("save and load of %zu groups (%zu bytes): %zu rays, %zu hits, %zu differ\n", gr->count, size, rays, hits, differ);
    CHECK(differ == 0 && hits > rays / 4, "save and load: %zu differ", differ);
    hairobb_free(loaded);
    hairobb_free(groups);
    free(bytes);
    {   /* a one-group BVH's bytes, loaded as one group */
        hairobb_bvh *one = NULL;
        hairobb_group all;
        memset(&all, 0, sizeof all);
        all.vertices = gr->all_vertices;
        all.vertex_count = gr->all_vertex_count;
        all.indices = gr->all_indices;
        all.segment_count = gr->all_segment_count;
        CHECK(hairobb_build(all.vertices, all.vertex_count, all.indices, all.segment_count, NULL, &one) == HAIROBB_OK, "one BVH");
        size = hairobb_save_size(one);
        bytes = (unsigned char *)malloc(size);
        CHECK(hairobb_save(one, bytes, size) == HAIROBB_OK, "one BVH saved");
        r = hairobb_load_groups(bytes, size, &all, 1, NULL, &loaded);
        CHECK(r == HAIROBB_OK && hairobb_group_count(loaded) == 1, "a one-group BVH's bytes through load_groups: %s",
              hairobb_result_string(r));
        hairobb_free(loaded);
        hairobb_free(one);
        free(bytes);
    }
}

/* A filter on a one-shape BVH over the same groups: takes only the hits
   of the groups of that shape (user: a shape_filter). */
typedef struct shape_filter {
    const hairobb_group_shape *shapes;
    hairobb_group_shape shape;
} shape_filter;

static int shape_filter_fn(void *user, const hairobb_ray *ray, const hairobb_hit *hit)
{
    const shape_filter *f = (const shape_filter *)user;
    (void)ray;
    return f->shapes[hit->group_id] == f->shape;
}

/* The nearer of a ribbon BVH's and a tube BVH's hits (each filtered to
   its own groups): what a BVH mixing the two shapes must find. On a tie
   in t either is right: *either says so. */
static int nearer_of(int got_r, const hairobb_hit *hr, int got_t, const hairobb_hit *ht, hairobb_hit *out, int *either)
{
    *either = got_r && got_t && hr->t == ht->t;
    if (got_r && (!got_t || hr->t < ht->t)) { *out = *hr; return 1; }
    if (got_t) { *out = *ht; return 1; }
    return 0;
}

/* MIXED SHAPES: groups 0, 2 as ribbons and 1, 3 as tubes (caps on) in one
   BVH, against the same groups as one ribbon BVH and one tube BVH (each
   checked against one BVH by compare_groups; groups, not one BVH, so that
   joints and _from's skips end at groups as in the mixed BVH), each shown
   only its own groups' hits: the nearer of the two, bit for bit;
   occluded1; a bounce from each hit (_from); save and load (the shapes
   saved; a load asking another shape is MISMATCH); a bad shape and tubes
   in pieces precision refused; group stats name the shapes. */
static void test_mixed_shapes(const grouped *gr_in, const float *org, const float *dir, size_t rays)
{
    grouped gr = *gr_in, as_options;   /* shallow: only the shapes change */
    hairobb_group_shape shapes[MAX_GROUPS];
    hairobb_build_options o = hairobb_default_options(), round_options;
    hairobb_bvh *mixed = NULL, *ribbons = NULL, *tubes = NULL, *loaded = NULL, *other = NULL;
    shape_filter fr, ft;
    hairobb_context cr, ct;
    hairobb_group_stats stats[MAX_GROUPS + 1];
    size_t i, g, hits = 0, differ = 0, occluded_differ = 0, bounce_differ = 0, bounces = 0, tube_hits = 0, loaded_differ = 0;
    size_t size;
    unsigned char *bytes = NULL;
    hairobb_result r;
    for (g = 0; g < gr.count; ++g) {
        shapes[g] = g % 2 ? HAIROBB_GROUP_SHAPE_ROUND : HAIROBB_GROUP_SHAPE_RIBBON;
        gr.group[g].shape = shapes[g];
    }
    o.end_caps = HAIROBB_ON;
    round_options = o;
    round_options.shape = HAIROBB_SHAPE_ROUND;
    r = hairobb_build_groups(gr.group, gr.count, &o, &mixed);
    CHECK(r == HAIROBB_OK, "mixed shapes: builds: %s", hairobb_result_string(r));
    as_options = gr;   /* every group the options' shape: built as ribbons and as tubes */
    for (g = 0; g < gr.count; ++g) {
        as_options.group[g].shape = HAIROBB_GROUP_SHAPE_OPTIONS;
    }
    CHECK(hairobb_build_groups(as_options.group, gr.count, &o, &ribbons) == HAIROBB_OK &&
              hairobb_build_groups(as_options.group, gr.count, &round_options, &tubes) == HAIROBB_OK,
          "mixed shapes: the one-shape BVHs");
    if (!mixed || !ribbons || !tubes) return;
    fr.shapes = ft.shapes = shapes;
    fr.shape = HAIROBB_GROUP_SHAPE_RIBBON;
    ft.shape = HAIROBB_GROUP_SHAPE_ROUND;
    cr.filter = shape_filter_fn;
    cr.user = &fr;
    ct.filter = shape_filter_fn;
    ct.user = &ft;
    cr.mask = ct.mask = 0;
    size = hairobb_save_size(mixed);
    bytes = (unsigned char *)malloc(size);
    CHECK(bytes && hairobb_save(mixed, bytes, size) == HAIROBB_OK, "mixed shapes: saved");
    r = hairobb_load_groups(bytes, size, gr.group, gr.count, NULL, &loaded);
    CHECK(r == HAIROBB_OK, "mixed shapes: load_groups: %s", hairobb_result_string(r));
    for (i = 0; i < rays; ++i) {
        hairobb_ray ray = ray_of(org, dir, i, 0.0f);
        hairobb_hit hm, hr, ht, want, hl;
        int got_m = hairobb_intersect1(mixed, &ray, &hm), got_r = hairobb_intersect1_context(ribbons, &cr, NULL, &ray, &hr);
        int got_t = hairobb_intersect1_context(tubes, &ct, NULL, &ray, &ht), either, got_w, got_l;
        got_w = nearer_of(got_r, &hr, got_t, &ht, &want, &either);
        hits += (size_t)got_m;
        tube_hits += (size_t)(got_m && shapes[hm.group_id] == HAIROBB_GROUP_SHAPE_ROUND);
        differ += !(same_hit(got_m, &hm, got_w, &want) || (either && (same_hit(got_m, &hm, 1, &hr) || same_hit(got_m, &hm, 1, &ht))));
        occluded_differ += hairobb_occluded1(mixed, &ray) != (got_r || got_t);
        got_l = loaded ? hairobb_intersect1(loaded, &ray, &hl) : 0;
        loaded_differ += !same_hit(got_m, &hm, got_l, &hl);
        if (got_m && !either) {   /* a bounce from the hit, reflected about Ng */
            hairobb_ray bounce = ray;
            hairobb_hit next_m, next_r, next_t, next_w;
            float along = 2.0f * (ray.dir[0] * hm.Ng[0] + ray.dir[1] * hm.Ng[1] + ray.dir[2] * hm.Ng[2]);
            int k, gm, gr_, gt, gw, e;
            for (k = 0; k < 3; ++k) {
                bounce.org[k] = ray.org[k] + hm.t * ray.dir[k];
                bounce.dir[k] = ray.dir[k] - along * hm.Ng[k];
            }
            gm = hairobb_intersect1_from(mixed, &hm, &bounce, &next_m);
            gr_ = hairobb_intersect1_context(ribbons, &cr, &hm, &bounce, &next_r);
            gt = hairobb_intersect1_context(tubes, &ct, &hm, &bounce, &next_t);
            gw = nearer_of(gr_, &next_r, gt, &next_t, &next_w, &e);
            ++bounces;
            bounce_differ += !(same_hit(gm, &next_m, gw, &next_w) ||
                               (e && (same_hit(gm, &next_m, 1, &next_r) || same_hit(gm, &next_m, 1, &next_t))));
        }
    }
    printf("mixed shapes (%zu groups, even ribbons, odd tubes): %zu rays, %zu hits (%zu on tubes): %zu differ from the nearer of "
           "the same groups' ribbon and tube BVHs', occluded1 %zu, bounces %zu of %zu; saved and loaded: %zu differ\n",
           gr.count, rays, hits, tube_hits, differ, occluded_differ, bounce_differ, bounces, loaded_differ);
    CHECK(hits > rays / 4 && tube_hits > hits / 8 && hits - tube_hits > hits / 8, "mixed shapes: %zu hits, %zu on tubes", hits, tube_hits);
    CHECK(differ == 0 && occluded_differ == 0 && bounce_differ == 0 && loaded_differ == 0,
          "mixed shapes: %zu hits, %zu occlusions, %zu bounces, %zu loaded differ", differ, occluded_differ, bounce_differ, loaded_differ);
    CHECK(hairobb_get_group_stats(mixed, stats, MAX_GROUPS) == gr.count && stats[0].shape == HAIROBB_SHAPE_RIBBON &&
              stats[1].shape == HAIROBB_SHAPE_ROUND,
          "mixed shapes: group stats name the shapes");
    /* a load must not ask another shape than the saved one (OPTIONS takes it) */
    gr.group[1].shape = HAIROBB_GROUP_SHAPE_RIBBON;
    r = hairobb_load_groups(bytes, size, gr.group, gr.count, NULL, &other);
    CHECK(r == HAIROBB_ERROR_MISMATCH && !other, "mixed shapes: a load asking another shape: %s", hairobb_result_string(r));
    for (g = 0; g < gr.count; ++g) gr.group[g].shape = HAIROBB_GROUP_SHAPE_OPTIONS;
    r = hairobb_load_groups(bytes, size, gr.group, gr.count, NULL, &other);
    CHECK(r == HAIROBB_OK && hairobb_get_group_stats(other, stats, 2) == 2 && stats[1].shape == HAIROBB_SHAPE_ROUND &&
              stats[0].shape == HAIROBB_SHAPE_RIBBON,
          "mixed shapes: a load asking the options' shape takes the saved ones: %s", hairobb_result_string(r));
    hairobb_free(other);
    other = NULL;
    /* refused: a shape out of range; tubes in pieces precision */
    gr.group[1].shape = (hairobb_group_shape)7;
    CHECK(hairobb_build_groups(gr.group, gr.count, &o, &other) == HAIROBB_ERROR_INVALID_ARGUMENT && !other, "a group shape out of range");
    gr.group[1].shape = HAIROBB_GROUP_SHAPE_ROUND;
    o.precision = HAIROBB_PRECISION_PIECES;
    CHECK(hairobb_build_groups(gr.group, gr.count, &o, &other) == HAIROBB_ERROR_INVALID_ARGUMENT && !other, "a round group in pieces");
    gr.group[1].shape = HAIROBB_GROUP_SHAPE_OPTIONS;
    CHECK(hairobb_build_groups(gr.group, gr.count, &o, &other) == HAIROBB_OK && hairobb_get_group_stats(other, stats, 1) == 1 &&
              stats[0].shape == HAIROBB_SHAPE_RIBBON,
          "ribbon groups in pieces");
    hairobb_free(other);
    other = NULL;
    free(bytes);
    {   /* an empty group's shape is moot: ribbons with an empty round group
           build, save and load as ribbons, the empty group's shape kept */
        hairobb_group with_empty[MAX_GROUPS + 1], as_ribbon[MAX_GROUPS + 1];
        hairobb_bvh *plain = NULL;
        memcpy(with_empty, as_options.group, gr.count * sizeof with_empty[0]);
        with_empty[gr.count] = gr.group[0];
        with_empty[gr.count].segment_count = 0;
        with_empty[gr.count].shape = HAIROBB_GROUP_SHAPE_ROUND;
        memcpy(as_ribbon, with_empty, sizeof as_ribbon);
        as_ribbon[gr.count].shape = HAIROBB_GROUP_SHAPE_OPTIONS;
        o.precision = HAIROBB_PRECISION_EXACT;
        CHECK(hairobb_build_groups(with_empty, gr.count + 1, &o, &other) == HAIROBB_OK &&
                  hairobb_build_groups(as_ribbon, gr.count + 1, &o, &plain) == HAIROBB_OK,
              "an empty round group: builds");
        size = hairobb_save_size(other);
        bytes = (unsigned char *)malloc(size);
        CHECK(bytes && hairobb_save(other, bytes, size) == HAIROBB_OK && size == hairobb_save_size(plain) &&
                  hairobb_get_group_stats(other, stats, MAX_GROUPS + 1) == gr.count + 1 && stats[gr.count].shape == HAIROBB_SHAPE_ROUND &&
                  stats[0].shape == HAIROBB_SHAPE_RIBBON,
              "an empty round group: saved as ribbon groups' bytes");
        hairobb_free(other);
        other = NULL;
        r = hairobb_load_groups(bytes, size, with_empty, gr.count + 1, NULL, &other);
        CHECK(r == HAIROBB_OK && hairobb_get_group_stats(other, stats, MAX_GROUPS + 1) == gr.count + 1 &&
                  stats[gr.count].shape == HAIROBB_SHAPE_ROUND && stats[0].shape == HAIROBB_SHAPE_RIBBON,
              "an empty round group: loads: %s", hairobb_result_string(r));
        for (i = 0, differ = 0; other && plain && i < rays; i += 7) {
            hairobb_ray ray = ray_of(org, dir, i, 0.0f);
            hairobb_hit a, b;
            int got_a = hairobb_intersect1(other, &ray, &a), got_b = hairobb_intersect1(plain, &ray, &b);
            differ += !same_hit(got_a, &a, got_b, &b);
        }
        CHECK(differ == 0, "an empty round group: %zu rays differ from the ribbon groups alone", differ);
        hairobb_free(other);
        hairobb_free(plain);
        free(bytes);
    }
    hairobb_free(loaded);
    hairobb_free(mixed);
    hairobb_free(ribbons);
    hairobb_free(tubes);
}

/* hairobb_get_group_stats: segment and vertex counts as given, leaf
   references adding up to hairobb_get_stats', bytes to
   hairobb_memory_bytes; a group's bytes at least what it alone needs;
   a one-group BVH is one group of everything. */
static void test_group_stats(const grouped *gr)
{
    hairobb_group_stats stats[MAX_GROUPS + 1];
    hairobb_stats tree;
    hairobb_bvh *bvh = NULL;
    size_t g, references = 0, bytes = 0, bad = 0;
    hairobb_build_options o = hairobb_default_options();
    int copy;
    for (copy = 0; copy < 2; ++copy) {
        o.bezier_copy = copy ? HAIROBB_AUTO : HAIROBB_OFF;
        CHECK(hairobb_build_groups(gr->group, gr->count, &o, &bvh) == HAIROBB_OK, "group stats: builds");
        if (!bvh) return;
        hairobb_get_stats(bvh, &tree);
        CHECK(hairobb_get_group_stats(bvh, stats, MAX_GROUPS + 1) == gr->count && hairobb_get_group_stats(bvh, stats, 1) == 1 &&
                  hairobb_get_group_stats(NULL, stats, 1) == 0 && hairobb_get_group_stats(bvh, NULL, 1) == 0,
              "group stats: counts written");
        hairobb_get_group_stats(bvh, stats, MAX_GROUPS);
        references = bytes = bad = 0;
        for (g = 0; g < gr->count; ++g) {
            references += stats[g].leaf_references;
            bytes += stats[g].bytes;
            bad += stats[g].segment_count != gr->group[g].segment_count || stats[g].vertex_count != gr->group[g].vertex_count ||
                   stats[g].leaf_references < stats[g].segment_count || stats[g].bytes < 4 * stats[g].segment_count ||
                   stats[g].shape != HAIROBB_SHAPE_RIBBON;
        }
        printf("group stats (%s): %zu groups, %zu leaf references (tree %zu), %zu bytes (hairobb_memory_bytes %zu), group 0 %zu bytes\n",
               copy ? "copy" : "no copy", gr->count, references, tree.leaf_references, bytes, hairobb_memory_bytes(bvh), stats[0].bytes);
        CHECK(bad == 0 && references == tree.leaf_references && bytes == hairobb_memory_bytes(bvh),
              "group stats: %zu groups wrong; references %zu of %zu, bytes %zu of %zu", bad, references, tree.leaf_references, bytes,
              hairobb_memory_bytes(bvh));
        hairobb_free(bvh);
        bvh = NULL;
    }
    CHECK(hairobb_build(gr->all_vertices, gr->all_vertex_count, gr->all_indices, gr->all_segment_count, NULL, &bvh) == HAIROBB_OK,
          "group stats: one BVH");
    hairobb_get_stats(bvh, &tree);
    CHECK(hairobb_get_group_stats(bvh, stats, 4) == 1 && stats[0].segment_count == gr->all_segment_count &&
              stats[0].leaf_references == tree.leaf_references && stats[0].bytes == hairobb_memory_bytes(bvh),
          "group stats of a one-group BVH");
    hairobb_free(bvh);
}

/* hairobb_interpolate at hits: the tangent is the hit's, the point within
   r of the hit's (ribbons: across the ray at the hit's depth; tubes: on
   the tube); hairobb_basis_weights on the caller's points, in every
   basis, gives hairobb_interpolate's point and tangent. */
static void test_interpolate(const grouped *gr, const float *org, const float *dir, size_t rays)
{
    static const hairobb_basis bases[5] = {HAIROBB_BASIS_BEZIER, HAIROBB_BASIS_BSPLINE, HAIROBB_BASIS_CATMULL_ROM, HAIROBB_BASIS_HERMITE,
                                           HAIROBB_BASIS_LINEAR};
    hairobb_bvh *groups = NULL;
    size_t i, hits = 0, bad = 0, weights_bad = 0, tried = 0;
    int shape, b;
    for (shape = 0; shape < 2; ++shape) {
        hairobb_build_options o = hairobb_default_options();
        o.shape = shape ? HAIROBB_SHAPE_ROUND : HAIROBB_SHAPE_RIBBON;
        CHECK(hairobb_build_groups(gr->group, gr->count, &o, &groups) == HAIROBB_OK, "interpolate: builds");
        for (i = 0; groups && i < rays; ++i) {
            hairobb_ray ray;
            hairobb_hit hit;
            float p[4], d1[4], d2[4], X[3];
            double off = 0.0, along = 0.0, t2 = 0.0, dd = 0.0, tangent_error = 0.0, length;
            int k;
            memcpy(ray.org, org + 3 * i, sizeof ray.org);
            memcpy(ray.dir, dir + 3 * i, sizeof ray.dir);
            ray.tnear = 0.0f;
            ray.tfar = INFINITY;
            ray.time = 0.0f;
            if (!hairobb_intersect1(groups, &ray, &hit)) continue;
            ++hits;
            if (!hairobb_interpolate(groups, hit.group_id, hit.prim_id, hit.u, 0.0f, p, d1, d2)) {
                ++bad;
                continue;
            }
            for (k = 0; k < 3; ++k) {
                X[k] = ray.org[k] + hit.t * ray.dir[k];
                tangent_error += fabs((double)d1[k] - hit.tangent[k]);
                t2 += (double)hit.tangent[k] * hit.tangent[k];
                dd += (double)ray.dir[k] * ray.dir[k];
            }
            length = sqrt(dd);
            for (k = 0; k < 3; ++k) along += ((double)X[k] - p[k]) * ray.dir[k] / length;
            for (k = 0; k < 3; ++k) {
                double across = (double)X[k] - p[k] - (shape ? 0.0 : along * ray.dir[k] / length);
                off += across * across;
            }
            off = sqrt(off);
            /* a ribbon's point lies across the ray within r of the hit's; a tube's at r */
            bad += tangent_error > 1e-5 * sqrt(t2) + 1e-6 || !(shape ? fabs(off - p[3]) <= 2e-3 * p[3] + 1e-5 : off <= 1.002 * p[3] + 1e-5);
        }
        hairobb_free(groups);
        groups = NULL;
    }
    /* every basis: the weights on the caller's points (group 0's) against the curve as traced */
    for (b = 0; b < 5; ++b) {
        const hairobb_group *g0 = &gr->group[0];
        size_t points = bases[b] == HAIROBB_BASIS_HERMITE || bases[b] == HAIROBB_BASIS_LINEAR ? 2 : 4, n = g0->vertex_count - points + 1;
        uint32_t *idx = (uint32_t *)malloc(sizeof(uint32_t) * n);
        float *tangents = (float *)malloc(16 * g0->vertex_count);
        hairobb_group one = *g0;
        hairobb_build_options o = hairobb_default_options();
        for (i = 0; i < n; ++i) idx[i] = (uint32_t)i;
        for (i = 0; i < 4 * g0->vertex_count; ++i) tangents[i] = (i & 3) == 3 ? 0.0f : 0.1f * (float)((i * 7) % 5) - 0.2f;
        one.indices = idx;
        one.segment_count = n;
        one.tangents = bases[b] == HAIROBB_BASIS_HERMITE ? tangents : NULL;
        o.basis = bases[b];
        CHECK(hairobb_build_groups(&one, 1, &o, &groups) == HAIROBB_OK, "basis %d: builds", b);
        for (i = 0; groups && i < 2000; ++i) {
            uint32_t prim = (uint32_t)((i * 2654435761u) % n);
            float u = (float)(i % 17) / 16.0f, w[4], dw[4], p[4], d1[4], want[4] = {0, 0, 0, 0}, want_d[4] = {0, 0, 0, 0};
            const float *v = g0->vertices + 4 * (size_t)prim, *t = tangents + 4 * (size_t)prim;
            int k, j;
            hairobb_basis_weights(bases[b], u, w, dw);
            for (k = 0; k < 4; ++k)
                for (j = 0; j < 4; ++j) {
                    /* Hermite: w[2], w[3] weigh the tangents; linear: two points */
                    float a = bases[b] == HAIROBB_BASIS_HERMITE ? (j < 2 ? v[4 * j + k] : t[4 * (j - 2) + k])
                                                                 : (j < (int)points ? v[4 * j + k] : 0.0f);
                    want[k] += w[j] * a;
                    want_d[k] += dw[j] * a;
                }
            ++tried;
            if (!hairobb_interpolate(groups, 0, prim, u, 0.0f, p, d1, NULL)) {
                ++weights_bad;
                continue;
            }
            for (k = 0; k < 4; ++k)
                weights_bad += fabsf(p[k] - want[k]) > 1e-5f * (1.0f + fabsf(want[k])) || fabsf(d1[k] - want_d[k]) > 1e-4f * (1.0f + fabsf(want_d[k]));
        }
        hairobb_free(groups);
        groups = NULL;
        free(idx);
        free(tangents);
    }
    printf("interpolate: %zu hits (ribbons and tubes), %zu off the hit; basis weights on the caller's points, 5 bases: %zu of %zu "
           "differ from the curve as traced\n", hits, bad, weights_bad, tried);
    CHECK(hits > rays / 4 && bad == 0 && weights_bad == 0, "interpolate: %zu bad of %zu hits, %zu weights", bad, hits, weights_bad);
    CHECK(!hairobb_interpolate(NULL, 0, 0, 0.5f, 0.0f, NULL, NULL, NULL), "interpolate: NULL");
}

/* A scene placing a multi-group BVH twice (identity, and moved): its hits
   in the first instance are the BVH's own, with instance_id. */
static void test_instances(const grouped *gr, const float *org, const float *dir, size_t rays)
{
    hairobb_bvh *groups = NULL;
    hairobb_scene *scene = NULL;
    hairobb_instance inst[2];
    size_t i, differ = 0, hits = 0;
    int k;
    CHECK(hairobb_build_groups(gr->group, gr->count, NULL, &groups) == HAIROBB_OK, "instances: builds");
    memset(inst, 0, sizeof inst);
    for (k = 0; k < 2; ++k) {
        inst[k].bvh = groups;
        inst[k].transform[0] = inst[k].transform[5] = inst[k].transform[10] = 1.0f;
    }
    inst[1].transform[3] = 1000.0f;   /* far off: never in the way */
    CHECK(groups && hairobb_scene_build(inst, 2, NULL, &scene) == HAIROBB_OK, "instances: the scene builds");
    for (i = 0; scene && i < rays; ++i) {
        hairobb_ray ray = ray_of(org, dir, i, 0.0f);
        hairobb_hit a, b;
        int got_a, got_b;
        got_a = hairobb_scene_intersect1(scene, NULL, NULL, &ray, &a);
        got_b = hairobb_intersect1(groups, &ray, &b);
        hits += (size_t)got_a;
        differ += got_a != got_b || (got_a && (a.instance_id != 0 || a.group_id != b.group_id || a.prim_id != b.prim_id || a.t != b.t));
    }
    printf("a scene over a multi-group BVH: %zu rays, %zu hits, %zu differ from the BVH's own\n", rays, hits, differ);
    CHECK(differ == 0 && hits > rays / 4, "instances: %zu differ, %zu hits", differ, hits);
    hairobb_scene_free(scene);
    hairobb_free(groups);
}

static void test_bad_input(const grouped *gr)
{
    hairobb_group g[3];
    hairobb_bvh *bvh = (hairobb_bvh *)(void *)g;
    uint32_t past[1];
    float nan_points[16];
    hairobb_result r;
    test_allocator a;
    long fail;
    int k;
    memcpy(g, gr->group, 2 * sizeof g[0]);
    CHECK(hairobb_build_groups(NULL, 2, NULL, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT && bvh == NULL, "NULL groups");
    CHECK(hairobb_build_groups(g, 0, NULL, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT && bvh == NULL, "no groups");
    CHECK(hairobb_build_groups(g, 2, NULL, NULL) == HAIROBB_ERROR_INVALID_ARGUMENT, "no out");
    g[1].indices = NULL;
    CHECK(hairobb_build_groups(g, 2, NULL, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT, "a group's NULL indices");
    g[1] = gr->group[1];
    /* the last point a segment would read is past its own group's points,
       though group 2's follow in the concatenation */
    past[0] = (uint32_t)g[1].vertex_count - 3;
    g[1].indices = past;
    g[1].segment_count = 1;
    g[2] = gr->group[0];
    r = hairobb_build_groups(g, 3, NULL, &bvh);
    CHECK(r == HAIROBB_ERROR_INDEX_OUT_OF_RANGE && bvh == NULL, "an index past its group's points: %s", hairobb_result_string(r));
    g[1] = gr->group[1];
    for (k = 0; k < 16; ++k) nan_points[k] = (float)k;
    nan_points[5] = NAN;
    past[0] = 0;
    g[2].vertices = nan_points;
    g[2].vertex_count = 4;
    g[2].indices = past;
    g[2].segment_count = 1;
    r = hairobb_build_groups(g, 3, NULL, &bvh);
    CHECK(r == HAIROBB_ERROR_INVALID_GEOMETRY && bvh == NULL, "a NaN in a group: %s", hairobb_result_string(r));
    /* an empty group (no arrays) among others: built, never hit */
    g[2].vertices = NULL;
    g[2].indices = NULL;
    g[2].vertex_count = 0;
    g[2].segment_count = 0;
    r = hairobb_build_groups(g, 3, NULL, &bvh);
    CHECK(r == HAIROBB_OK && hairobb_group_count(bvh) == 3 && hairobb_group_segments(bvh, 2) == 0, "an empty group: %s",
          hairobb_result_string(r));
    hairobb_free(bvh);
    CHECK(hairobb_build_groups(g + 2, 1, NULL, &bvh) == HAIROBB_ERROR_INVALID_ARGUMENT, "only empty groups");
    /* every allocation failing in turn: an error, nothing leaked */
    for (fail = 0;; ++fail) {
        hairobb_build_options o = hairobb_default_options();
        test_allocator_init(&a, fail);
        o.allocator_user = &a;
        o.threads = 1;
        r = hairobb_build_groups(gr->group, gr->count, &o, &bvh);
        hairobb_free(r == HAIROBB_OK ? bvh : NULL);
        CHECK((a.failed ? r == HAIROBB_ERROR_OUT_OF_MEMORY : r == HAIROBB_OK) && a.live == 0 && a.bad_frees == 0,
              "allocation %ld failing: %s, %ld blocks live", fail, hairobb_result_string(r), (long)a.live);
        if (!a.failed || fail > 200) break;
    }
}

int main(void)
{
    hair_scene s;
    grouped gr;
    size_t rays = 12000, k;
    float *org = (float *)malloc(12 * rays), *dir = (float *)malloc(12 * rays);
    static const size_t counts[3] = {1, 4, 16};
    CHECK(scene_combed(&s, 40000, 5) == 0, "combed");
    for (k = 0; k < 3; ++k) {
        int order;
        for (order = 0; order < 2; ++order) {
            hairobb_build_options o = hairobb_default_options();
            char name[96];
            group_strands(&gr, &s, counts[k], order);
            make_rays(&gr, &s, rays, 7 + k, org, dir);
            snprintf(name, sizeof name, "combed 40k, %zu groups in %s order, ribbons", counts[k], order ? "space" : "groom");
            compare_groups(name, &gr, &s, &o, org, dir, rays);
            o.shape = HAIROBB_SHAPE_ROUND;
            o.end_caps = HAIROBB_ON;
            snprintf(name, sizeof name, "combed 40k, %zu groups in %s order, tubes", counts[k], order ? "space" : "groom");
            compare_groups(name, &gr, &s, &o, org, dir, rays / 2);
            if (counts[k] == 16 && order == 1) test_mixed_shapes(&gr, org, dir, rays / 2);
            if (counts[k] == 4 && order == 0) {
                test_refit_group(&gr, org, dir, rays, HAIROBB_AUTO);
                test_refit_group(&gr, org, dir, rays, HAIROBB_OFF);
                test_motion(&gr, org, dir, rays);
                test_instances(&gr, org, dir, rays);
                test_save_load(&gr, org, dir, rays);
                test_interpolate(&gr, org, dir, rays);
                test_bad_input(&gr);
                test_group_stats(&gr);
                test_mixed_shapes(&gr, org, dir, rays);
            }
            grouped_free(&gr);
        }
    }
    scene_free(&s);
    free(org);
    free(dir);
    return check_summary();
}
