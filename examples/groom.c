/* groom.c - a groom of three hair groups in one BVH (hairobb_build_groups):
   a scalp's hair, flyaways over it and a fringe, each in arrays of its own
   with its own shader (the user pointer) and mask bits; the fringe, seen
   close up, as round tubes, the rest as flat ribbons (MIXED SHAPES). Camera rays see
   every group; shadow rays skip the flyaways (a renderer's "casts no
   shadow" flag, as a mask); then the flyaways move (hairobb_refit_group)
   and the picture is traced again. Prints what each group was hit by;
   exits 1 where a group is never seen. */
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

enum { SEGMENTS = 6, POINTS = 3 * SEGMENTS + 1 };   /* a strand: 6 Bezier segments sharing end points */
#define CAMERA 1u   /* mask bits: seen by camera rays, casts shadows */
#define SHADOW 2u

typedef struct shader {
    const char *name;
    float colour[3];
} shader;

/* strands strands rooted on a patch of the sphere of radius 1 (latitude
   from lat0 to lat1), each `length` long, leaning by `lean` and waving by
   `wave`; vertices and indices allocated here. */
static void make_group(size_t strands, float lat0, float lat1, float length, float lean, float wave, float radius, unsigned seed,
                       float **vertices, uint32_t **indices)
{
    size_t s, k;
    *vertices = (float *)malloc(sizeof(float) * 4 * POINTS * strands);
    *indices = (uint32_t *)malloc(sizeof(uint32_t) * SEGMENTS * strands);
    srand(seed);
    for (s = 0; s < strands; ++s) {
        float lat = lat0 + (lat1 - lat0) * (float)rand() / (float)RAND_MAX, lon = 6.2831853f * (float)rand() / (float)RAND_MAX;
        float root[3] = {cosf(lat) * cosf(lon), sinf(lat), cosf(lat) * sinf(lon)};
        for (k = 0; k < POINTS; ++k) {
            float a = (float)k / (float)(POINTS - 1), *p = *vertices + 4 * (POINTS * s + k);
            p[0] = root[0] * (1.0f + length * a) + wave * sinf(9.0f * a + lon) * a;
            p[1] = root[1] * (1.0f + length * a) - lean * a * a;
            p[2] = root[2] * (1.0f + length * a) + wave * cosf(7.0f * a + lat) * a;
            p[3] = radius * (1.0f - 0.8f * a);
        }
        for (k = 0; k < SEGMENTS; ++k) (*indices)[SEGMENTS * s + k] = (uint32_t)(POINTS * s + 3 * k);
    }
}

/* A 64 x 64 picture of camera rays; counts each group's hits, and how many
   of them a light straight above sees (shadow rays with the SHADOW mask). */
static int trace(const hairobb_bvh *bvh, const char *when)
{
    size_t hits[3] = {0, 0, 0}, lit[3] = {0, 0, 0};
    int x, y;
    uint32_t g;
    hairobb_context camera = {NULL, NULL, CAMERA}, shadow = {NULL, NULL, SHADOW};
    for (y = 0; y < 64; ++y)
        for (x = 0; x < 64; ++x) {
            hairobb_ray ray = {{0.0f, 0.3f, 6.0f}, 0.0f, {(x - 31.5f) / 96.0f, (31.5f - y) / 96.0f, -1.0f}, INFINITY, 0.0f};
            hairobb_hit hit;
            if (!hairobb_intersect1_context(bvh, &camera, NULL, &ray, &hit)) continue;
            ++hits[hit.group_id];
            {   /* to the light above: a shadow ray leaving the hit */
                hairobb_ray to_light = {{ray.org[0] + hit.t * ray.dir[0], ray.org[1] + hit.t * ray.dir[1], ray.org[2] + hit.t * ray.dir[2]},
                                        0.0f, {0.0f, 1.0f, 0.0f}, INFINITY, 0.0f};
                if (!hairobb_occluded1_context(bvh, &shadow, &hit, &to_light)) ++lit[hit.group_id];
            }
        }
    int seen = 1;
    printf("%s:\n", when);
    for (g = 0; g < hairobb_group_count(bvh); ++g) {
        seen &= hits[g] > 0;
        const shader *sh = (const shader *)hairobb_group_user(bvh, g);
        printf("  %-9s (%zu segments, colour %.1f %.1f %.1f): %4zu pixels, %4zu of them lit\n", sh->name, hairobb_group_segments(bvh, g),
               (double)sh->colour[0], (double)sh->colour[1], (double)sh->colour[2], hits[g], lit[g]);
    }
    return seen;
}

int main(void)
{
    static shader shaders[3] = {{"scalp", {0.35f, 0.2f, 0.1f}}, {"flyaways", {0.5f, 0.3f, 0.15f}}, {"fringe", {0.3f, 0.15f, 0.08f}}};
    static const size_t strands[3] = {8000, 300, 1500};
    float *vertices[3], *moved;
    uint32_t *indices[3];
    hairobb_group groups[3];
    hairobb_bvh *bvh;
    hairobb_result result;
    size_t i;
    int g;
    make_group(strands[0], 0.2f, 1.5f, 0.35f, 0.4f, 0.02f, 0.008f, 1, &vertices[0], &indices[0]);
    make_group(strands[1], 0.3f, 1.5f, 0.6f, 0.1f, 0.15f, 0.004f, 2, &vertices[1], &indices[1]);
    make_group(strands[2], 0.9f, 1.3f, 0.25f, 0.9f, 0.01f, 0.008f, 3, &vertices[2], &indices[2]);
    for (g = 0; g < 3; ++g) {
        groups[g].vertices = vertices[g];
        groups[g].vertex_count = POINTS * strands[g];
        groups[g].indices = indices[g];
        groups[g].segment_count = SEGMENTS * strands[g];
        groups[g].tangents = NULL;
        groups[g].time_vertices = NULL;
        groups[g].mask = g == 1 ? CAMERA : CAMERA | SHADOW;   /* flyaways cast no shadow */
        groups[g].user = &shaders[g];
        groups[g].shape = g == 2 ? HAIROBB_GROUP_SHAPE_ROUND : HAIROBB_GROUP_SHAPE_OPTIONS;   /* options: ribbons */
    }
    result = hairobb_build_groups(groups, 3, NULL, &bvh);
    if (result != HAIROBB_OK) {
        fprintf(stderr, "hairobb_build_groups: %s\n", hairobb_result_string(result));
        return 1;
    }
    {
        hairobb_group_stats stats[3];
        uint32_t n = hairobb_get_group_stats(bvh, stats, 3), k;
        printf("one BVH over %u groups: %zu bytes\n", hairobb_group_count(bvh), hairobb_memory_bytes(bvh));
        for (k = 0; k < n; ++k)
            printf("  %-9s %s, %zu leaf references, %zu bytes\n", shaders[k].name,
                   stats[k].shape == HAIROBB_SHAPE_ROUND ? "tubes  " : "ribbons", stats[k].leaf_references, stats[k].bytes);
    }
    int seen = trace(bvh, "as built");
    /* wind on the flyaways: their new points, copied into the BVH, which refits */
    moved = (float *)malloc(sizeof(float) * 4 * groups[1].vertex_count);
    for (i = 0; i < 4 * groups[1].vertex_count; ++i) moved[i] = vertices[1][i] + ((i & 3) == 0 ? 0.15f * (float)((i / 4) % POINTS) / POINTS : 0.0f);
    result = hairobb_refit_group(bvh, 1, moved, NULL, NULL);
    if (result != HAIROBB_OK) {
        fprintf(stderr, "hairobb_refit_group: %s\n", hairobb_result_string(result));
        return 1;
    }
    seen &= trace(bvh, "the flyaways blown aside");
    hairobb_free(bvh);
    for (g = 0; g < 3; ++g) {
        free(vertices[g]);
        free(indices[g]);
    }
    free(moved);
    return seen ? 0 : 1;
}
