/* tree_hash.c - proves builder changes keep the trees, and measures what a
   build allocates.

   build/tree_hash                 for each scene (combed, curly, crossing,
                                   random: 200k segments; straight.hair and
                                   furBall_A where found) x option set x
                                   build threads 1 and 2: a 64-bit hash of
                                   the tree (node bytes, leaf_prims, root,
                                   stats, bounds), one line each. Compare the
                                   output before and after a change (diff);
                                   bench/results/tree-hashes-*.txt.
   build/tree_hash --memory        the same builds' peak transient bytes a
                                   segment (tests/test_alloc.h: the peak of the
                                   library's allocations during the build
                                   minus the BVH's hairobb_memory_bytes) and
                                   the blocks live at that peak.
   --scenes a,b  --options a,b  --threads 1,2  --segments N (k/M suffixes)
                                   choose; `--scenes combed --options
                                   default --threads 1` is one build, what
                                   callgrind measures:
     valgrind --tool=callgrind --toggle-collect=hairobb_build build/tree_hash_cg \
         --scenes combed --options default --threads 1
   Build instructions a segment = the Ir callgrind reports / segments. */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE   /* madvise(MADV_HUGEPAGE), as gnu C and C++ builds have it (HAIROBB_NO_HUGE_PAGES) */
#include "tests/test_alloc.h"
#define HAIROBB_IMPLEMENTATION
#include "hairobb.h"
#include "tests/compare.h"
#include "tests/scenes.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct option_set {
    const char *name;
    void (*set)(hairobb_build_options *o);
    int time_steps;                   /* motion blur: the scene's steps from scene_motion_steps */
    scene_motion motion;
    double amount;
} option_set;

static void set_default(hairobb_build_options *o) { (void)o; }
static void set_per_child(hairobb_build_options *o) { o->obb_layout = HAIROBB_OBB_PER_CHILD; }
static void set_shared_rotation(hairobb_build_options *o) { o->obb_layout = HAIROBB_OBB_SHARED_ROTATION; }
static void set_compressed(hairobb_build_options *o) { o->obb_layout = HAIROBB_OBB_COMPRESSED; }
static void set_aabb_only(hairobb_build_options *o) { o->nodes = HAIROBB_NODES_AABB_ONLY; }
static void set_obb_only(hairobb_build_options *o) { o->nodes = HAIROBB_NODES_OBB_ONLY; }
static void set_spatial(hairobb_build_options *o) { o->spatial_splits = HAIROBB_ON; }
static void set_clustering(hairobb_build_options *o) { o->clustering = HAIROBB_ON; }
static void set_spatial_clustering(hairobb_build_options *o) { o->spatial_splits = o->clustering = HAIROBB_ON; }
static void set_leaf1(hairobb_build_options *o) { o->max_leaf_size = 1; }
static void set_leaf15(hairobb_build_options *o) { o->max_leaf_size = 15; }
static void set_candidates4(hairobb_build_options *o) { o->hair_space_candidates = 4; }
static void set_catmull_rom(hairobb_build_options *o) { o->basis = HAIROBB_BASIS_CATMULL_ROM; }
static void set_catmull_rom_no_copy(hairobb_build_options *o) { o->basis = HAIROBB_BASIS_CATMULL_ROM; o->bezier_copy = HAIROBB_OFF; }

#define STILL(name, set) {name, set, 0, SCENE_MOTION_ROTATE, 0.0}
static const option_set option_sets[] = {
    STILL("default", set_default),
    STILL("per-child", set_per_child),
    STILL("shared-rotation", set_shared_rotation),
    STILL("compressed", set_compressed),
    STILL("aabb-only", set_aabb_only),
    STILL("obb-only", set_obb_only),
    STILL("spatial", set_spatial),
    STILL("clustering", set_clustering),
    STILL("spatial+clustering", set_spatial_clustering),
    STILL("max-leaf-1", set_leaf1),
    STILL("max-leaf-15", set_leaf15),
    STILL("candidates-4", set_candidates4),
    STILL("catmull-rom", set_catmull_rom),
    STILL("catmull-rom-no-copy", set_catmull_rom_no_copy),
    {"motion-rotate-2", set_default, 2, SCENE_MOTION_ROTATE, 0.5},
    {"motion-translate-4", set_default, 4, SCENE_MOTION_TRANSLATE, 0.05},
    {"motion-rotate-3-spatial", set_spatial, 3, SCENE_MOTION_ROTATE, 0.5},
    {"motion-compressed", set_compressed, 2, SCENE_MOTION_ROTATE, 0.5},
};
enum { OPTION_SETS = sizeof option_sets / sizeof option_sets[0] };

static const char *const scene_names[] = {"combed", "curly", "crossing", "random", "straight", "furball"};
enum { SCENES = sizeof scene_names / sizeof scene_names[0] };

static uint64_t hash_size(uint64_t h, size_t x)
{
    uint64_t v = (uint64_t)x;
    return fnv1a(h, &v, sizeof v);
}

static uint64_t tree_hash(const hairobb_bvh *bvh)
{
    uint64_t h = FNV1A_START;
    const hairobb_stats *s = &bvh->stats;
    h = hash_size(h, bvh->node_bytes);
    if (bvh->node_bytes) h = fnv1a(h, bvh->nodes, bvh->node_bytes);
    h = hash_size(h, bvh->leaf_prim_count);
    h = fnv1a(h, bvh->leaf_prims, bvh->leaf_prim_count * sizeof *bvh->leaf_prims);
    h = fnv1a(h, &bvh->root, sizeof bvh->root);
    h = hash_size(h, s->aabb_nodes);
    h = hash_size(h, s->obb_nodes);
    h = hash_size(h, s->leaves);
    h = hash_size(h, s->leaf_references);
    h = hash_size(h, s->max_depth);
    h = hash_size(h, s->node_bytes);
    h = hash_size(h, s->leaf_bytes);
    h = fnv1a(h, bvh->lower, sizeof bvh->lower);
    h = fnv1a(h, bvh->upper, sizeof bvh->upper);
    return h;
}

/* 0 loaded, -1 absent file, 1 error */
static int load(const char *name, size_t segments, hair_scene *s)
{
    const char *path;
    if (strcmp(name, "combed") == 0) return scene_combed(s, segments, 1);
    if (strcmp(name, "curly") == 0) return scene_curly(s, segments, 2);
    if (strcmp(name, "crossing") == 0) return scene_crossing(s, segments, 4);
    if (strcmp(name, "random") == 0) return scene_random(s, segments, 3);
    if (strcmp(name, "straight") == 0) {
        if (test_data_straight_hair(&path, NULL) != TEST_DATA_FOUND) return -1;
        return scene_load_hair(s, path);
    }
    if (strcmp(name, "furball") == 0) return scene_load_furball(s, NULL);
    fprintf(stderr, "tree_hash: unknown scene %s\n", name);
    return 1;
}

/* name in the comma-separated list (NULL: every name) */
static int listed(const char *list, const char *name)
{
    size_t n = strlen(name);
    const char *p = list;
    if (!list) return 1;
    while (*p) {
        const char *end = strchr(p, ',');
        size_t len = end ? (size_t)(end - p) : strlen(p);
        if (len == n && strncmp(p, name, n) == 0) return 1;
        if (!end) break;
        p = end + 1;
    }
    return 0;
}

static size_t parse_count(const char *text)
{
    char *end;
    double v = strtod(text, &end);
    if (*end == 'k' || *end == 'K') v *= 1e3;
    if (*end == 'M' || *end == 'm') v *= 1e6;
    return (size_t)v;
}

int main(int argc, char **argv)
{
    const char *scenes = NULL, *options = NULL, *threads = "1,2";
    size_t segments = 200000;
    int memory = 0, i, failures = 0;
    for (i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--memory") == 0) memory = 1;
        else if (i + 1 < argc && strcmp(argv[i], "--scenes") == 0) scenes = argv[++i];
        else if (i + 1 < argc && strcmp(argv[i], "--options") == 0) options = argv[++i];
        else if (i + 1 < argc && strcmp(argv[i], "--threads") == 0) threads = argv[++i];
        else if (i + 1 < argc && strcmp(argv[i], "--segments") == 0) segments = parse_count(argv[++i]);
        else {
            fprintf(stderr, "usage: %s [--memory] [--scenes a,b] [--options a,b] [--threads 1,2] [--segments N]\n", argv[0]);
            return 2;
        }
    }
    if (memory) printf("scene\tsegments\toptions\tthreads\tpeak_transient_B_per_segment\tbvh_B_per_segment\tblocks live at the peak (bytes)\n");
    for (i = 0; i < SCENES; ++i) {
        hair_scene s;
        int o, loaded;
        if (!listed(scenes, scene_names[i])) continue;
        loaded = load(scene_names[i], segments, &s);
        if (loaded < 0) {
            printf("%s\tabsent\n", scene_names[i]);
            continue;
        }
        if (loaded > 0) {
            printf("%s\tcannot be loaded\n", scene_names[i]);
            ++failures;
            continue;
        }
        for (o = 0; o < OPTION_SETS; ++o) {
            float *steps[4];
            int time_steps = option_sets[o].time_steps;
            unsigned t;
            if (!listed(options, option_sets[o].name)) continue;
            if (time_steps && scene_motion_steps(&s, option_sets[o].motion, option_sets[o].amount, time_steps, steps) != 0) {
                printf("%s\t%s\tout of memory for the steps\n", s.name, option_sets[o].name);
                ++failures;
                continue;
            }
            for (t = 1; t <= 16; ++t) {
                char name[4];
                hairobb_build_options opt;
                hairobb_bvh *bvh = NULL;
                hairobb_result r;
                test_allocator meter;
                snprintf(name, sizeof name, "%u", t);
                if (!listed(threads, name)) continue;
                test_allocator_init_meter(&meter, memory);
                memset(&opt, 0, sizeof opt);
                option_sets[o].set(&opt);
                opt.threads = t;
                opt.allocator_user = &meter;
                opt.time_steps = (unsigned)time_steps;
                opt.time_vertices = (const float *const *)steps;
                r = hairobb_build(time_steps ? NULL : s.vertices, s.vertex_count, s.indices, s.segment_count, &opt, &bvh);
                if (r != HAIROBB_OK) {
                    printf("%s\t%s\t%u\tfailed: %s\n", s.name, option_sets[o].name, t, hairobb_result_string(r));
                    ++failures;
                } else if (memory) {
                    size_t k, bytes = hairobb_memory_bytes(bvh);
                    printf("%s\t%zu\t%s\t%u\t%.2f\t%.2f\t", s.name, s.segment_count, option_sets[o].name, t,
                           (double)(meter.peak_bytes - bytes) / (double)s.segment_count, (double)bytes / (double)s.segment_count);
                    for (k = 0; k < meter.peak_blocks; ++k) printf("%s%zu", k ? " " : "", meter.peak_sizes[k]);
                    printf("\n");
                } else {
                    printf("%s\t%s\t%u\t%016llx\n", s.name, option_sets[o].name, t, (unsigned long long)tree_hash(bvh));
                }
                fflush(stdout);
                hairobb_free(bvh);
                if (meter.bytes != 0) {
                    printf("%s\t%s\t%u\t%zu bytes still allocated after hairobb_free\n", s.name, option_sets[o].name, t,
                           meter.bytes);
                    ++failures;
                }
            }
            scene_motion_free(steps, time_steps);
        }
        scene_free(&s);
    }
    return failures != 0;
}
