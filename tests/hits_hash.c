/* hits_hash.c - one hash of every hit, for comparing builds of the library
   on other platforms (tests/run_windows.sh: mingw-w64 under wine, against
   this machine's own build). Scenes come from a file that the native build
   writes, so that no platform's sin or cos enters the comparison; rays are
   made from the scene's bounds with + - * / and sqrt only, which IEEE
   rounds alike everywhere.
   usage: hits_hash --write FILE   combed fur and curly fur (scenes.h), raw
          hits_hash FILE           one line a scene and option set: the hash
                                   of its saved tree, and of its hits
   The option sets cover ribbons and round curves (tubes, with and without
   end caps). Each is built on all cores (the Windows build: Win32 threads),
   then traced: primary rays on a grid, a shadow ray from each, and a bounce
   leaving each hit (hairobb_intersect1_from). Every bit of every hit
   (prim_id, t, u, v, Ng, tangent) and every occlusion answer is hashed.
   Hits do not depend on the tree, so option sets that change only the
   tree hash alike. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "compare.h"   /* fnv1a */
#include "scenes.h"

enum { SIDE = 64 };

static void normalize(float v[3])
{
    float length = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    v[0] /= length; v[1] /= length; v[2] /= length;
}

static int write_scenes(const char *path)
{
    FILE *f = fopen(path, "wb");
    int k;
    if (!f) return 1;
    for (k = 0; k < 2; ++k) {
        hair_scene s;
        uint64_t counts[2];
        if (k == 0 ? scene_combed(&s, 40000, 7) : scene_curly(&s, 20000, 11)) { fclose(f); return 1; }
        counts[0] = s.vertex_count;
        counts[1] = s.segment_count;
        fwrite(counts, sizeof counts, 1, f);
        fwrite(s.vertices, 4 * sizeof(float), s.vertex_count, f);
        fwrite(s.indices, sizeof(uint32_t), s.segment_count, f);
        scene_free(&s);
    }
    return fclose(f) != 0;
}

/* The scene's hairs hashed under one set of options. */
static uint64_t hash_hits(const float *vertices, size_t vertex_count, const uint32_t *indices, size_t segment_count,
                          const hairobb_build_options *options, const float lower[3], const float upper[3], int *hit_count,
                          uint64_t *tree_hash)
{
    hairobb_bvh *bvh = NULL;
    uint64_t h = FNV1A_START;
    float centre[3], extent[3];
    size_t bytes;
    void *saved;
    int i, j, k;
    *hit_count = 0;
    *tree_hash = 0;
    if (hairobb_build(vertices, vertex_count, indices, segment_count, options, &bvh) != HAIROBB_OK) return 0;
    /* the tree: its saved bytes */
    bytes = hairobb_save_size(bvh);
    saved = malloc(bytes);
    if (saved && hairobb_save(bvh, saved, bytes) == HAIROBB_OK) *tree_hash = fnv1a(FNV1A_START, saved, bytes);
    free(saved);
    for (k = 0; k < 3; ++k) {
        centre[k] = 0.5f * (lower[k] + upper[k]);
        extent[k] = upper[k] - lower[k];
    }
    for (j = 0; j < SIDE; ++j)
        for (i = 0; i < SIDE; ++i) {
            hairobb_ray ray, shadow, bounce;
            hairobb_hit hit, next;
            int occluded;
            /* from in front of the hair towards a grid over its middle */
            ray.org[0] = centre[0] + 0.1f * extent[0];
            ray.org[1] = centre[1] + 0.2f * extent[1];
            ray.org[2] = upper[2] + extent[2];
            for (k = 0; k < 2; ++k)
                ray.dir[k] = lower[k] + extent[k] * ((float)((k ? j : i) + 0.5f) / (float)SIDE) - ray.org[k];
            ray.dir[2] = centre[2] - ray.org[2];
            ray.tnear = 0.0f;
            ray.tfar = INFINITY;
            ray.time = 0.0f;
            memset(&hit, 0, sizeof hit);   /* a miss writes prim_id alone */
            memset(&next, 0, sizeof next);
            hairobb_intersect1(bvh, &ray, &hit);
            h = fnv1a(h, &hit, sizeof hit);
            if (hit.prim_id == HAIROBB_INVALID_ID) continue;
            ++*hit_count;
            for (k = 0; k < 3; ++k) {
                shadow.org[k] = ray.org[k] + hit.t * ray.dir[k];
                shadow.dir[k] = (k == 1 ? 1.0f : 0.3f) - shadow.org[k] * 0.1f;
                bounce.dir[k] = hit.Ng[k] + (k == 0 ? 0.5f : -0.25f);
            }
            normalize(bounce.dir);
            memcpy(bounce.org, shadow.org, sizeof bounce.org);
            shadow.tnear = bounce.tnear = 0.0f;
            shadow.tfar = bounce.tfar = INFINITY;
            shadow.time = bounce.time = 0.0f;
            occluded = hairobb_occluded1_from(bvh, &hit, &shadow);
            h = fnv1a(h, &occluded, sizeof occluded);
            hairobb_intersect1_from(bvh, &hit, &bounce, &next);
            h = fnv1a(h, &next, sizeof next);
        }
    hairobb_free(bvh);
    return h;
}

int main(int argc, char **argv)
{
    FILE *f;
    int scene;
    if (argc == 3 && strcmp(argv[1], "--write") == 0) return write_scenes(argv[2]);
    if (argc != 2 || !(f = fopen(argv[1], "rb"))) {
        fprintf(stderr, "usage: hits_hash --write FILE | hits_hash FILE\n");
        return 2;
    }
    for (scene = 0; scene < 2; ++scene) {
        uint64_t counts[2];
        float *vertices, lower[3] = {INFINITY, INFINITY, INFINITY}, upper[3] = {-INFINITY, -INFINITY, -INFINITY};
        uint32_t *indices;
        size_t v, k;
        int set;
        if (fread(counts, sizeof counts, 1, f) != 1 || counts[0] > 100000000u || counts[1] > 100000000u) return 2;
        vertices = (float *)malloc(16 * (size_t)counts[0] + 16);
        indices = (uint32_t *)malloc(4 * (size_t)counts[1]);
        if (!vertices || !indices || fread(vertices, 16, (size_t)counts[0], f) != (size_t)counts[0] ||
            fread(indices, 4, (size_t)counts[1], f) != (size_t)counts[1])
            return 2;
        for (v = 0; v < counts[0]; ++v)
            for (k = 0; k < 3; ++k) {
                if (vertices[4 * v + k] < lower[k]) lower[k] = vertices[4 * v + k];
                if (vertices[4 * v + k] > upper[k]) upper[k] = vertices[4 * v + k];
            }
        for (set = 0; set < 6; ++set) {
            static const char *names[6] = {"defaults", "spatial splits, clustering", "no copy", "Catmull-Rom", "round curves",
                                           "round curves, end caps, Catmull-Rom"};
            hairobb_build_options options;
            int hits;
            uint64_t h, tree;
            memset(&options, 0, sizeof options);
            if (set == 1) { options.spatial_splits = HAIROBB_ON; options.clustering = HAIROBB_ON; }
            if (set == 2) options.bezier_copy = HAIROBB_OFF;
            if (set == 3 || set == 5) options.basis = HAIROBB_BASIS_CATMULL_ROM;
            if (set >= 4) options.shape = HAIROBB_SHAPE_ROUND;
            if (set == 5) options.end_caps = HAIROBB_ON;
            h = hash_hits(vertices, (size_t)counts[0], indices, (size_t)counts[1], &options, lower, upper, &hits, &tree);
            printf("%s, %s: tree %016llx, %d of %d rays hit, hits %016llx\n", scene ? "curly" : "combed", names[set],
                   (unsigned long long)tree, hits, SIDE * SIDE, (unsigned long long)h);
        }
        free(vertices);
        free(indices);
    }
    fclose(f);
    return 0;
}
