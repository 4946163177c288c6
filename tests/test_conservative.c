/* test_conservative.c - traversal conservativeness: a ray never misses a
   box it touches. The header is built instrumented (HAIROBB__LEAF_VISIT):
   each segment of each leaf a ray reaches is recorded and its intersection
   skipped, so no hit shortens the ray and the traversal goes wherever the
   node tests lead. Every segment the double-precision reference hits in
   [tnear, tfar] must have been reached, for every node policy and layout,
   with spatial splits (clipped segments), near the origin and far from it.
   So that a traversal reaching everything cannot pass, it must also stay
   selective: reach under a quarter of the segments per ray (the crossed
   bundles, where every ray crosses the dense middle, reach 6-7%). */
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

typedef struct missed {
    const unsigned char *reached;
    size_t hits, missed;
} missed;

static void count_missed(void *user, uint32_t prim, const ref_hit *hit)
{
    missed *m = (missed *)user;
    (void)hit;
    ++m->hits;
    m->missed += !m->reached[prim];
}

/* Camera rays, random rays through the bounds (any direction, some with a
   tnear/tfar window), and rays along the axes and the axis planes, where
   direction components are exactly 0 and so are the ray's direction
   components in frames of whole byte rows (1/d infinite), against one BVH. */
static void check_bvh(const char *name, const hair_scene *s, const ref_scene *reference, const hairobb_build_options *options)
{
    hairobb_bvh *bvh = NULL;
    int side = 48, rays = side * side * 3, i;
    float *org = (float *)malloc(3 * sizeof(float) * (size_t)rays), *dir = (float *)malloc(3 * sizeof(float) * (size_t)rays);
    missed m = {NULL, 0, 0};
    size_t total_reached = 0, hits = 0;
    scene_rng rng;
    hairobb_result r = hairobb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, options, &bvh);
    CHECK(r == HAIROBB_OK, "%s: build: %s", name, hairobb_result_string(r));
    if (r != HAIROBB_OK) return;
    scene_camera_rays(s, side, side, org, dir);
    scene_rng_seed(&rng, 17);
    for (i = side * side; i < rays; ++i) {
        scene_vec3 d = scene_random_unit_vector(&rng);
        int k;
        if (i >= 2 * side * side) {
            /* one or two components zeroed, the rest +-1, normalised */
            int keep = i % 6;
            float c[3], length;
            for (k = 0; k < 3; ++k) c[k] = (keep < 3 ? k == keep : k != keep - 3) ? (scene_rng_float(&rng) < 0.5f ? -1.0f : 1.0f) : 0.0f;
            length = sqrtf(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
            d.x = c[0] / length; d.y = c[1] / length; d.z = c[2] / length;
        }
        for (k = 0; k < 3; ++k) {
            float extent = s->upper[k] - s->lower[k];
            org[3 * i + k] = s->lower[k] + extent * scene_rng_float(&rng);
        }
        org[3 * i] -= 2.0f * (s->upper[0] - s->lower[0]) * d.x;
        org[3 * i + 1] -= 2.0f * (s->upper[0] - s->lower[0]) * d.y;
        org[3 * i + 2] -= 2.0f * (s->upper[0] - s->lower[0]) * d.z;
        dir[3 * i] = d.x; dir[3 * i + 1] = d.y; dir[3 * i + 2] = d.z;
    }
    m.reached = reached;
    for (i = 0; i < rays; ++i) {
        hairobb_ray ray;
        hairobb_hit hit;
        float length = 4.0f * (s->upper[0] - s->lower[0]);
        memcpy(ray.org, org + 3 * i, sizeof ray.org);
        memcpy(ray.dir, dir + 3 * i, sizeof ray.dir);
        /* every third random ray sees only a window of its path */
        ray.tnear = (i >= side * side && i % 3 == 0) ? length * (0.3f + 0.2f * scene_rng_float(&rng)) : 0.0f;
        ray.tfar = (i >= side * side && i % 3 == 0) ? ray.tnear + 0.3f * length : INFINITY;
        memset(reached, 0, s->segment_count);
        reached_count = 0;
        hits += (size_t)hairobb_intersect1(bvh, &ray, &hit);
        total_reached += reached_count;
        ref_all_hits(reference, ray.org, ray.dir, ray.tnear, ray.tfar, count_missed, &m);
    }
    printf("%-38s %6d rays, %7zu reference hits, %zu segments not reached; %.1f segments reached per ray of %zu\n", name, rays,
           m.hits, m.missed, (double)total_reached / rays, s->segment_count);
    CHECK(m.hits > (size_t)rays / 10, "%s: %zu reference hits", name, m.hits);
    CHECK(m.missed == 0, "%s: %zu segments the reference hits were not reached", name, m.missed);
    CHECK(hits == 0, "%s: %zu instrumented rays hit (every intersection is skipped)", name, hits);
    CHECK((double)total_reached / rays < 0.25 * (double)s->segment_count, "%s: %.1f segments reached per ray: not selective", name,
          (double)total_reached / rays);
    hairobb_free(bvh);
    free(org);
    free(dir);
}

static void check_scene(const char *name, hair_scene *s, int variants)
{
    static const struct { const char *name; hairobb_node_policy nodes; hairobb_obb_layout layout; hairobb_switch spatial; } configs[] = {
        {"defaults", HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_AUTO},
        {"per-child affine", HAIROBB_NODES_MIXED, HAIROBB_OBB_PER_CHILD, HAIROBB_AUTO},
        {"shared rotation", HAIROBB_NODES_MIXED, HAIROBB_OBB_SHARED_ROTATION, HAIROBB_AUTO},
        {"compressed (paper)", HAIROBB_NODES_MIXED, HAIROBB_OBB_COMPRESSED, HAIROBB_AUTO},
        {"AABB only", HAIROBB_NODES_AABB_ONLY, HAIROBB_OBB_DEFAULT, HAIROBB_AUTO},
        {"OBB only", HAIROBB_NODES_OBB_ONLY, HAIROBB_OBB_DEFAULT, HAIROBB_AUTO},
        {"spatial splits", HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_ON},
    };
    ref_scene *reference = ref_build(s->vertices, s->vertex_count, s->indices, s->segment_count);
    int c;
    reached = (unsigned char *)calloc(s->segment_count, 1);
    CHECK(reference != NULL, "%s: reference", name);
    for (c = 0; reference && c < variants; ++c) {
        hairobb_build_options options;
        char label[96];
        memset(&options, 0, sizeof options);
        options.nodes = configs[c].nodes;
        options.obb_layout = configs[c].layout;
        options.spatial_splits = configs[c].spatial;
        snprintf(label, sizeof label, "%s, %s:", name, configs[c].name);
        check_bvh(label, s, reference, &options);
    }
    ref_free(reference);
    free(reached);
}

int main(void)
{
    hair_scene s;
    const float far[3] = {1e5f, 5e4f, -1e5f};
    CHECK(scene_combed(&s, 20000, 21) == 0, "combed");
    check_scene("combed 20k", &s, 7);
    scene_transform(&s, far, 1.0f);
    check_scene("combed 20k at 1e5", &s, 1);
    scene_free(&s);
    CHECK(scene_curly(&s, 20000, 22) == 0, "curly");
    check_scene("curly 20k", &s, 7);
    scene_free(&s);
    CHECK(scene_crossed(&s, 6000, 23) == 0, "crossed");
    check_scene("crossed bundles 6k", &s, 7);
    scene_free(&s);
    return check_summary();
}
