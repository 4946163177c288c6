/* ab.c - two versions of hairobb.h in one process, timed in alternating
   passes over the same rays: the way to decide a change to the traversal
   or the intersector on a shared, noisy machine (`make ab`, bench/ab.sh).
   A round times each ray set once with each copy, in alternating order
   (base first in even rounds); the ratio test speed / base speed is taken
   within the round, and its median, range and quartiles are reported.
   The copies must agree on every hit (a hash of every prim id and t, and
   every occlusion answer); a difference is reported.

   --builds times the builders instead: a round builds with each copy
   (each freed before the next) in alternating order, on all cores and on
   1 thread; the ratio test time / base time is taken within the round.
   The copies must build the same tree (a hash of its nodes and leaves, on
   either thread count); a difference is reported.

   usage: build/ab [--builds] [--scene LIST] [--rounds N] [--res N]
     --scene   combed, curly, crossing (procedural, generated order; NAME:N
               for a size, e.g. combed:2M), furball, straight (the tests'
               data files), default combed,combed:2M
     --rounds  rounds (default 15), --res  N x N primary rays (default 512)
   Rays: primary (a pinhole camera), secondary (a random direction from
   each primary hit, hairobb_intersect1_from) and shadow (from each hit
   toward a point light above the hair, hairobb_occluded1_from); 1 thread.
   Defaults only (no options; CFLAGS_AB=-DAB_ROUND: round curves): build
   both copies the same way. */
#define _POSIX_C_SOURCE 200809L
#include "ab.h"
#include "../tests/compare.h"   /* compare_doubles */
#include "../tests/test_data.h"
#include <stdio.h>
#include <stdlib.h>

static size_t parse_count(const char *text)
{
    char *end;
    double value = strtod(text, &end);
    if (*end == 'k' || *end == 'K') value *= 1e3;
    if (*end == 'M' || *end == 'm') value *= 1e6;
    return value > 0.0 ? (size_t)value : 0;
}

static int load(const char *name, hair_scene *s)
{
    const char *colon = strchr(name, ':'), *path;
    size_t segments = colon ? parse_count(colon + 1) : 200000, length = colon ? (size_t)(colon - name) : strlen(name);
    char why[TEST_DATA_WHY_SIZE];
    memset(s, 0, sizeof *s);
    if (length == 6 && !strncmp(name, "combed", 6)) return scene_combed(s, segments, 1);
    if (length == 5 && !strncmp(name, "curly", 5)) return scene_curly(s, segments, 2);
    if (length == 8 && !strncmp(name, "crossing", 8)) return scene_crossing(s, segments, 3);
    if (!strcmp(name, "straight")) {
        if (test_data_straight_hair(&path, why) != TEST_DATA_FOUND) { fprintf(stderr, "ab: %s\n", why); return -1; }
        return scene_load_hair(s, path);
    }
    if (!strcmp(name, "furball")) {
        if (test_data_furball(&path, why) != TEST_DATA_FOUND) { fprintf(stderr, "ab: %s\n", why); return -1; }
        return scene_load_furball(s, path);
    }
    fprintf(stderr, "ab: unknown scene %s\n", name);
    return -1;
}

/* seconds of one build with either copy (test or base), freed after */
static double time_build(const hair_scene *s, int test, unsigned threads, uint64_t *hash)
{
    double t0 = scene_now(), t1;
    void *bvh = test ? ab_test_build_threads(s, threads) : ab_base_build_threads(s, threads);
    t1 = scene_now();
    if (!bvh) {
        fprintf(stderr, "ab: a build failed\n");
        exit(1);
    }
    if (hash) *hash = test ? ab_test_tree_hash(bvh) : ab_base_tree_hash(bvh);
    if (test) ab_test_free(bvh); else ab_base_free(bvh);
    return t1 - t0;
}

static void build_scene(const char *name, int rounds)
{
    static const unsigned threads[2] = {0, 1};
    static const char *thread_names[2] = {"all cores", "1 thread"};
    hair_scene s;
    double *ratio, seconds[2][2] = {{0, 0}, {0, 0}};
    int k, round;
    if (load(name, &s) != 0) return;
    ratio = (double *)malloc(sizeof *ratio * (size_t)rounds * 2);
    if (!ratio) { fprintf(stderr, "ab: out of memory\n"); exit(1); }
    for (k = 0; k < 2; ++k) {
        uint64_t base_hash, test_hash;
        time_build(&s, 0, threads[k], &base_hash);
        time_build(&s, 1, threads[k], &test_hash);
        if (base_hash != test_hash) printf("%s: the copies' trees DIFFER (%s)\n", name, thread_names[k]);
    }
    for (round = 0; round < rounds; ++round)
        for (k = 0; k < 2; ++k) {
            /* base first in even rounds */
            double first = time_build(&s, round & 1, threads[k], NULL), second = time_build(&s, !(round & 1), threads[k], NULL);
            double base_s = round & 1 ? second : first, test_s = round & 1 ? first : second;
            ratio[k * rounds + round] = test_s / base_s;
            seconds[k][0] += base_s;
            seconds[k][1] += test_s;
        }
    printf("%s: %zu segments, %d rounds of builds; test time / base time within rounds: median [min-max] (quartiles)\n", name,
           s.segment_count, rounds);
    for (k = 0; k < 2; ++k) {
        double *r = ratio + k * rounds;
        qsort(r, (size_t)rounds, sizeof *r, compare_doubles);
        printf("  %-9s %.3f [%.3f-%.3f] (%.3f-%.3f); base %.4f s, test %.4f s (means)\n", thread_names[k], r[rounds / 2], r[0],
               r[rounds - 1], r[rounds / 4], r[(3 * rounds) / 4], seconds[k][0] / rounds, seconds[k][1] / rounds);
    }
    fflush(stdout);
    free(ratio);
    scene_free(&s);
}

static void run_scene(const char *name, int rounds, int side)
{
    static const char *kind_names[3] = {"primary", "secondary", "shadow"};
    hair_scene s;
    size_t n = (size_t)side * side, i;
    ab_rays rays[3];
    ab_hit *hits;
    void *base, *test;
    scene_rng rng;
    float light[3];
    double *ratio, seconds[3][2] = {{0, 0}, {0, 0}, {0, 0}};
    int k, round;
    if (load(name, &s) != 0) return;
    hits = (ab_hit *)malloc(sizeof *hits * n);
    ratio = (double *)malloc(sizeof *ratio * (size_t)rounds * 3);
    for (k = 0; k < 3; ++k) {
        rays[k].kind = (ab_kind)k;
        rays[k].count = n;
        rays[k].org = (float *)malloc(3 * sizeof(float) * n);
        rays[k].dir = (float *)malloc(3 * sizeof(float) * n);
    }
    base = ab_base_build(&s);
    test = ab_test_build(&s);
    if (!hits || !ratio || !rays[2].dir || !rays[2].org || !rays[1].dir || !rays[1].org || !rays[0].dir || !rays[0].org || !base ||
        !test) {
        fprintf(stderr, "ab: %s: out of memory or a build failed\n", name);
        exit(1);
    }
    scene_camera_rays(&s, side, side, rays[0].org, rays[0].dir);
    if (ab_base_trace(base, &rays[0], hits) != ab_test_trace(test, &rays[0], NULL))
        printf("%s: the copies' primary hits DIFFER\n", name);
    for (k = 0; k < 3; ++k) light[k] = s.upper[k] + (k == 1 ? 2.0f : 1.0f) * (s.upper[k] - s.lower[k]);
    scene_rng_seed(&rng, 7);
    for (i = 0; i < n; ++i) {
        scene_vec3 d = scene_random_unit_vector(&rng);
        int hit = hits[i].prim_id != UINT32_MAX;   /* HAIROBB_INVALID_ID */
        for (k = 0; k < 3; ++k) {
            float at = rays[0].org[3 * i + k] + (hit ? hits[i].t * rays[0].dir[3 * i + k] : 0.0f);
            rays[1].org[3 * i + k] = rays[2].org[3 * i + k] = at;
            rays[2].dir[3 * i + k] = light[k] - at;
        }
        rays[1].dir[3 * i] = d.x; rays[1].dir[3 * i + 1] = d.y; rays[1].dir[3 * i + 2] = d.z;
    }
    for (k = 1; k < 3; ++k)
        if (ab_base_trace(base, &rays[k], hits) != ab_test_trace(test, &rays[k], hits))
            printf("%s: the copies' %s answers DIFFER\n", name, kind_names[k]);
    for (round = 0; round < rounds; ++round)
        for (k = 0; k < 3; ++k) {
            double t0, t1, t2, base_s, test_s;
            t0 = scene_now();
            if (round & 1) ab_test_trace(test, &rays[k], hits); else ab_base_trace(base, &rays[k], hits);
            t1 = scene_now();
            if (round & 1) ab_base_trace(base, &rays[k], hits); else ab_test_trace(test, &rays[k], hits);
            t2 = scene_now();
            base_s = round & 1 ? t2 - t1 : t1 - t0;
            test_s = round & 1 ? t1 - t0 : t2 - t1;
            ratio[k * rounds + round] = base_s / test_s;
            seconds[k][0] += base_s;
            seconds[k][1] += test_s;
        }
    printf("%s: %zu segments, %zu rays a set, %d rounds; test speed / base speed within rounds: median [min-max] (quartiles)\n", name,
           s.segment_count, n, rounds);
    for (k = 0; k < 3; ++k) {
        double *r = ratio + k * rounds;
        qsort(r, (size_t)rounds, sizeof *r, compare_doubles);
        printf("  %-9s %.3f [%.3f-%.3f] (%.3f-%.3f); base %.2f, test %.2f Mrays/s\n", kind_names[k], r[rounds / 2], r[0],
               r[rounds - 1], r[rounds / 4], r[(3 * rounds) / 4], 1e-6 * (double)n * rounds / seconds[k][0],
               1e-6 * (double)n * rounds / seconds[k][1]);
    }
    fflush(stdout);
    ab_base_free(base);
    ab_test_free(test);
    for (k = 0; k < 3; ++k) { free(rays[k].org); free(rays[k].dir); }
    free(hits);
    free(ratio);
    scene_free(&s);
}

int main(int argc, char **argv)
{
    const char *scenes = "combed,combed:2M";
    int rounds = 15, side = 512, builds = 0, a;
    char list[1024], *name, *save = NULL;
    for (a = 1; a < argc; ++a) {
        if (!strcmp(argv[a], "--builds")) builds = 1;
        else if (!strcmp(argv[a], "--scene") && a + 1 < argc) scenes = argv[++a];
        else if (!strcmp(argv[a], "--rounds") && a + 1 < argc) rounds = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--res") && a + 1 < argc) side = atoi(argv[++a]);
        else {
            fprintf(stderr, "usage: %s [--builds] [--scene LIST] [--rounds N] [--res N] (see bench/ab.c)\n", argv[0]);
            return 2;
        }
    }
    if (rounds < 1 || rounds > 1000 || side < 1 || side > 8192 || strlen(scenes) >= sizeof list) {
        fprintf(stderr, "ab: --rounds 1..1000, --res 1..8192\n");
        return 2;
    }
    strcpy(list, scenes);
    for (name = strtok_r(list, ",", &save); name; name = strtok_r(NULL, ",", &save)) {
        if (builds) build_scene(name, rounds);
        else run_scene(name, rounds, side);
    }
    return 0;
}
