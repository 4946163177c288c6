/* bench.c - hairobb's benchmark: speed, memory and accuracy of hairobb
   against Embree's curves on the same buffers and the same rays.

   `make bench` runs it with no arguments on the procedural combed-fur scene;
   `build/bench --help` lists the options. For each scene it measures, per
   variant (hairobb build options, Embree curve types and tessellation
   rates): build time, memory, Mrays/s on primary, incoherent (diffuse
   bounce) and shadow rays on 1 and all threads, and accuracy against the
   double-precision reference on a fixed random subset of the primary rays.
   Tables go to stdout, progress to stderr (terminals only), every figure to
   a TSV file, and run time against error to a gnuplot chart.

   Fairness rules: every tracer runs through the same timing harness (one
   function pointer call per ray, same thread layout, same ray buffers);
   secondary rays are spawned once per scene and shared by all variants.

   Drift: this runs on shared machines, whose speed drifts by more than the
   differences measured. So every variant is built first, then each ray set
   and thread count is timed in rounds: one pass of every variant per round,
   Embree included, after one warm-up pass each. A figure is the median over
   the rounds, with its min-max spread; a ratio to Embree is taken within
   each round (the variants of one round run seconds apart), then its
   median and spread. */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE   /* madvise(MADV_HUGEPAGE), as gnu C and C++ builds have it (HAIROBB_NO_HUGE_PAGES) */
#define HAIROBB_IMPLEMENTATION

/* --profile (bench/profile.sh): built with -DBENCH_COUNTS, the header counts
   each ray's nodes, leaves and segments; run under callgrind, each variant's
   pass over each ray set is dumped on its own. */
#ifdef BENCH_COUNTS
static struct { unsigned long long node, leaf, segment, segment_passed; } bench_count;
#define HAIROBB__COUNT(what) (++bench_count.what)
#endif
#if defined(__has_include)
#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#endif
#endif
#ifndef CALLGRIND_TOGGLE_COLLECT /* no valgrind headers: --profile still counts */
#define CALLGRIND_TOGGLE_COLLECT
#define CALLGRIND_ZERO_STATS
#define CALLGRIND_DUMP_STATS_AT(name) ((void)(name))
#endif

/* hairobb's allocations go through a counting allocator: the build's peak */
#include "bench/alloc_meter.h"
#include "hairobb.h"
#include "tests/embree_wrap.h"
#include "tests/reference.h"
#include "tests/scenes.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

/* ======================================================================== */
/* Configuration                                                            */
/* ======================================================================== */

enum {
    MAX_SCENES = 16,
    MAX_THREAD_COUNTS = 8,
    RAY_BLOCK = 64,            /* rays per work item; blocks interleave across threads */
    DEFAULT_SEGMENTS = 200000,
    DEFAULT_RESOLUTION = 768, /* make bench within 2 minutes on 2 cores */
    MAX_ROUNDS = 64,
    DEFAULT_ROUNDS = 3,
    DEFAULT_ACCURACY_RAYS = 16384,
    MAX_SAVE_LOAD = 8
};

#define DEFAULT_TSV_PATH "build/bench.tsv"
#define DEFAULT_PNG_PATH "build/bench_error.png"
#define DEFAULT_PLOT_SCRIPT "bench/plot.gp"

typedef enum ray_kind { RAYS_PRIMARY, RAYS_INCOHERENT, RAYS_SHADOW, RAY_KIND_COUNT } ray_kind;
static const char *const ray_kind_names[RAY_KIND_COUNT] = {"primary", "incoherent", "shadow"};

typedef struct options {
    const char *scenes[MAX_SCENES];
    int scene_count;
    size_t segments;
    int resolution;
    int ray_kind_enabled[RAY_KIND_COUNT];
    unsigned thread_counts[MAX_THREAD_COUNTS];
    int thread_count_count;
    const char *variant_list;
    int variants_given;             /* --variants on the command line (else Catmull-Rom scenes run the yeti group) */
    size_t memory_mb;               /* --memory-mb: what the memory checks take as available; 0 = MemAvailable */
    int rounds;
    size_t accuracy_rays;
    const char *tsv_path, *png_path, *plot_script;
    const char *straight_path, *furball_path;
    int quiet;
    int profile;
    int animate_frames;             /* --animate N: the animation alone */
    size_t save_load_segments[MAX_SAVE_LOAD];   /* --save-load: combed scenes of these sizes */
    int save_load_count;
    int motion;                     /* --motion: the motion blur study alone */
    int builds;                     /* --builds: the build-time study alone */
} options;

static int show_progress; /* stderr is a terminal and --quiet was not given */

/* Progress lines: progress() writes a line, or ends one that
   progress_start() began with what is about to run, so that a slow step
   shows what it is while it runs and its outcome after. */
static void progress_write(const char *format, va_list args, const char *end)
{
    vfprintf(stderr, format, args);
    fputs(end, stderr);
    fflush(stderr);
}

static void progress(const char *format, ...)
{
    if (!show_progress)
        return;
    va_list args;
    va_start(args, format);
    progress_write(format, args, "\n");
    va_end(args);
}

static void progress_start(const char *format, ...)
{
    if (!show_progress)
        return;
    va_list args;
    va_start(args, format);
    progress_write(format, args, "... ");
    va_end(args);
}

/* ======================================================================== */
/* Variants                                                                 */
/* ======================================================================== */

typedef enum library { LIB_HAIROBB, LIB_EMBREE } library;

typedef struct variant {
    const char *key;     /* name on the command line and in the TSV */
    const char *label;   /* name in the tables */
    library lib;
    hairobb_node_policy nodes;
    hairobb_obb_layout obb_layout;
    hairobb_precision precision;
    unsigned curve_pieces;
    hairobb_switch spatial_splits, clustering;
    int embree_type, embree_rate; /* rate 0 = Embree's default */
    /* Embree's round curves are swept spheres, not the reference's ribbon:
       their "errors" measure the difference of surfaces, not accuracy. */
    int accuracy_comparable;
    int on_chart;        /* a point of the run time against error chart */
    unsigned build_threads; /* hairobb: 0 = every core */
    int hit_filter;      /* hairobb: a hit filter that takes every hit (what a set filter costs) */
    hairobb_simd simd;   /* hairobb: the kernels' path (AUTO: the widest the CPU runs) */
    /* hairobb: the scene's control points read as Catmull-Rom points (another
       curve, not the reference's: for memory and speed), with or without the copy */
    hairobb_basis basis;
    hairobb_switch bezier_copy;
} variant;

#define HAIROBB_ROW(key, label, nodes, layout, spatial, cluster, precision, pieces, on_chart) \
    {key, label, LIB_HAIROBB, HAIROBB_NODES_##nodes, HAIROBB_##layout, HAIROBB_PRECISION_##precision, pieces, \
     HAIROBB_##spatial, HAIROBB_##cluster, 0, 0, 1, on_chart, 0, 0, HAIROBB_SIMD_AUTO, HAIROBB_BASIS_BEZIER, HAIROBB_AUTO}
/* the defaults built on one thread (the build's speed-up), with a filter, or
   traced by the SSE2 kernels (what CPUs without AVX2 get) */
#define HAIROBB_DEFAULTS_ROW(key, label, build_threads, hit_filter, simd) \
    {key, label, LIB_HAIROBB, HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_PRECISION_EXACT, 8, HAIROBB_AUTO, HAIROBB_AUTO, \
     0, 0, 1, 0, build_threads, hit_filter, HAIROBB_SIMD_##simd, HAIROBB_BASIS_BEZIER, HAIROBB_AUTO}
#define EMBREE_ROW(key, label, type, rate, comparable, on_chart) \
    {key, label, LIB_EMBREE, HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_PRECISION_EXACT, 0, HAIROBB_AUTO, HAIROBB_AUTO, \
     type, rate, comparable, on_chart, 0, 0, HAIROBB_SIMD_AUTO, HAIROBB_BASIS_BEZIER, HAIROBB_AUTO}
#define HAIROBB_BASIS_ROW(key, label, basis, copy) \
    {key, label, LIB_HAIROBB, HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_PRECISION_EXACT, 8, HAIROBB_AUTO, HAIROBB_AUTO, \
     0, 0, 0, 0, 0, 0, HAIROBB_SIMD_AUTO, HAIROBB_BASIS_##basis, HAIROBB_##copy}
static const variant all_variants[] = {
    /* precision points: exact and pieces-only intersectors, 4 to 16 pieces */
    HAIROBB_ROW("default", "hairobb default", MIXED, OBB_DEFAULT, AUTO, AUTO, EXACT, 8, 1),
    HAIROBB_ROW("exact4", "hairobb exact 4", MIXED, OBB_DEFAULT, AUTO, AUTO, EXACT, 4, 1),
    HAIROBB_ROW("exact16", "hairobb exact 16", MIXED, OBB_DEFAULT, AUTO, AUTO, EXACT, 16, 1),
    HAIROBB_ROW("pieces4", "hairobb pieces 4", MIXED, OBB_DEFAULT, AUTO, AUTO, PIECES, 4, 1),
    HAIROBB_ROW("pieces8", "hairobb pieces 8", MIXED, OBB_DEFAULT, AUTO, AUTO, PIECES, 8, 1),
    HAIROBB_ROW("pieces16", "hairobb pieces 16", MIXED, OBB_DEFAULT, AUTO, AUTO, PIECES, 16, 1),
    /* the paper's ablation: node policy, then each heuristic and the compression added */
    HAIROBB_ROW("aabb", "hairobb AABB-only", AABB_ONLY, OBB_PER_CHILD, OFF, OFF, EXACT, 8, 0),
    HAIROBB_ROW("obb", "hairobb OBB-only", OBB_ONLY, OBB_PER_CHILD, OFF, OFF, EXACT, 8, 0),
    HAIROBB_ROW("mixed-uncompressed", "hairobb mixed", MIXED, OBB_PER_CHILD, OFF, OFF, EXACT, 8, 0),
    HAIROBB_ROW("spatial", "hairobb +spatial", MIXED, OBB_PER_CHILD, ON, OFF, EXACT, 8, 0),
    HAIROBB_ROW("spatial-compressed", "hairobb +sp +compr", MIXED, OBB_COMPRESSED_PER_CHILD, ON, OFF, EXACT, 8, 0),
    HAIROBB_ROW("spatial-compressed-cluster", "hairobb +sp+co+cl", MIXED, OBB_COMPRESSED_PER_CHILD, ON, ON, EXACT, 8, 0),
    /* other node layouts: one float rotation per node, the paper's compressed node (one byte rotation) */
    HAIROBB_ROW("shared", "hairobb shared rot.", MIXED, OBB_SHARED_ROTATION, OFF, OFF, EXACT, 8, 0),
    HAIROBB_ROW("compressed-shared", "hairobb compr. shared", MIXED, OBB_COMPRESSED, OFF, OFF, EXACT, 8, 0),
    HAIROBB_DEFAULTS_ROW("build-1t", "hairobb built on 1t", 1, 0, AUTO),
    HAIROBB_DEFAULTS_ROW("filter", "hairobb + hit filter", 0, 1, AUTO),
    HAIROBB_DEFAULTS_ROW("sse2", "hairobb SSE2 path", 0, 0, SSE2),
    HAIROBB_BASIS_ROW("catmull-rom", "hairobb C-R no copy", CATMULL_ROM, OFF),
    HAIROBB_BASIS_ROW("catmull-rom-copy", "hairobb C-R + copy", CATMULL_ROM, ON),
    HAIROBB_BASIS_ROW("b-spline", "hairobb B-sp no copy", BSPLINE, OFF),
    HAIROBB_BASIS_ROW("b-spline-copy", "hairobb B-sp + copy", BSPLINE, ON),
    EMBREE_ROW("embree-r4", "Embree flat r4", EMB_FLAT_BEZIER, 4, 1, 1),
    EMBREE_ROW("embree-r8", "Embree flat r8", EMB_FLAT_BEZIER, 8, 1, 1),
    EMBREE_ROW("embree-r16", "Embree flat r16", EMB_FLAT_BEZIER, 16, 1, 1),
    EMBREE_ROW("embree-round", "Embree round *", EMB_ROUND_BEZIER, 0, 0, 0),
};
enum { VARIANT_COUNT = sizeof all_variants / sizeof all_variants[0] };

/* The baseline of every ratio, and the rows of the ablation table (the
   paper's three node policies, all with the default exact intersector). */
#define BASELINE_KEY "embree-r4"
static const char *const ablation_keys[] = {"aabb", "obb", "mixed-uncompressed", "spatial", "spatial-compressed",
                                            "spatial-compressed-cluster", "shared", "compressed-shared", "default"};
static const char *const ablation_labels[] = {"AABB-only", "OBB-only", "mixed", "+ spatial", "+ compression",
                                              "+ clustering", "shared-R float", "shared-R bytes", "defaults"};
enum { ABLATION_ROWS = 9 };

/* Named groups for --variants; "mixed" is the default variant by another name. */
static const struct { const char *name, *members; } variant_groups[] = {
    {"all", "default,exact4,exact16,pieces4,pieces8,pieces16,aabb,obb,mixed-uncompressed,spatial,spatial-compressed,"
            "spatial-compressed-cluster,shared,compressed-shared,build-1t,filter,sse2,embree-r4,embree-r8,embree-r16,embree-round"},
    {"hairobb", "default,exact4,exact16,pieces4,pieces8,pieces16,aabb,obb,mixed-uncompressed,spatial,spatial-compressed,"
                "spatial-compressed-cluster,shared,compressed-shared,build-1t,filter,sse2"},
    {"embree", "embree-r4,embree-r8,embree-r16,embree-round"},
    {"precision", "default,exact4,exact16,pieces4,pieces8,pieces16"},
    {"ablation", "aabb,obb,mixed-uncompressed,spatial,spatial-compressed,spatial-compressed-cluster,shared,compressed-shared,default"},
    {"mixed", "default"},
    {"bases", "default,catmull-rom,catmull-rom-copy,b-spline,b-spline-copy"},
    /* a Catmull-Rom scene (yeti) without --variants: hairobb without the copy, Embree on the same buffers */
    {"yeti", "catmull-rom,embree-r4,embree-round"},
};

static int variant_index(const char *key)
{
    for (int i = 0; i < VARIANT_COUNT; i++)
        if (strcmp(all_variants[i].key, key) == 0)
            return i;
    return -1;
}

/* Marks the variants named in a comma list (names or groups). Returns 0 on
   success, else prints the unknown name and returns 1. */
static int select_variants(const char *list, int selected[VARIANT_COUNT])
{
    char buffer[1024];
    snprintf(buffer, sizeof buffer, "%s", list);
    char *rest = NULL;
    /* strtok_r: the group expansion below recurses */
    for (char *name = strtok_r(buffer, ",", &rest); name; name = strtok_r(NULL, ",", &rest)) {
        int found = 0;
        for (size_t g = 0; g < sizeof variant_groups / sizeof variant_groups[0]; g++)
            if (strcmp(variant_groups[g].name, name) == 0) {
                found = 1;
                if (select_variants(variant_groups[g].members, selected) != 0)
                    return 1;
            }
        int index = variant_index(name);
        if (index >= 0) {
            selected[index] = 1;
            found = 1;
        }
        if (!found) {
            fprintf(stderr, "bench: unknown variant '%s' (see --help)\n", name);
            return 1;
        }
    }
    return 0;
}

/* ======================================================================== */
/* Catmull-Rom scenes (yeti) and the memory they need                       */
/* ======================================================================== */

/* On a Catmull-Rom scene every variant reads the scene's own curves from
   the same shared buffers: hairobb rows build with that basis (the Bezier
   rows with hairobb's default, the Bezier copy; "catmull-rom" without it),
   Embree rows use the Catmull-Rom curve of their type. */
static hairobb_basis variant_basis(const variant *v, const hair_scene *s)
{
    return s->basis == SCENE_BASIS_CATMULL_ROM && v->basis == HAIROBB_BASIS_BEZIER ? HAIROBB_BASIS_CATMULL_ROM : v->basis;
}

static int variant_embree_type(const variant *v, const hair_scene *s)
{
    if (s->basis != SCENE_BASIS_CATMULL_ROM)
        return v->embree_type;
    return v->embree_type == EMB_ROUND_BEZIER ? EMB_ROUND_CATMULL_ROM : EMB_FLAT_CATMULL_ROM;
}

/* Whether the reference judges a variant's surface: on a Catmull-Rom scene
   the reference reads the segments' Bezier form, the curves hairobb's
   Catmull-Rom and default rows trace; the B-spline rows, and on a Bezier
   scene every basis row, read other curves through the same points. */
static int variant_comparable(const variant *v, scene_basis basis)
{
    if (basis == SCENE_BASIS_CATMULL_ROM && v->lib == LIB_HAIROBB)   /* its own basis or the Bezier default (made C-R) */
        return v->basis == HAIROBB_BASIS_BEZIER || v->basis == HAIROBB_BASIS_CATMULL_ROM;
    return v->accuracy_comparable;
}

/* The hairobb variant whose BVH spawns the secondary rays (and is kept for
   its row): the defaults, or on a Catmull-Rom scene the row without the
   copy, whose 72 bytes a segment would be 11 GB at 153M segments. */
static int spawn_variant(const hair_scene *s)
{
    return variant_index(s->basis == SCENE_BASIS_CATMULL_ROM ? "catmull-rom" : "default");
}

/* Bytes a segment that a build adds to the process at its peak (its
   structure and its transient memory) or the accuracy reference takes, for
   the check below. Yeti at 10M segments (bench/results/yeti-10M-*.txt):
   hairobb without the copy 70 of peak RSS (BVH 36, transient 32 by its
   allocator), Embree 136 allocated (its memory monitor; 114 of RSS, no
   higher peak), the reference 259 of RSS with the Bezier form. */
#define HAIROBB_BUILD_PEAK_BYTES_PER_SEGMENT 80.0
#define HAIROBB_COPY_BYTES_PER_SEGMENT 72.0         /* the Bezier copy of another basis */
#define EMBREE_BUILD_PEAK_BYTES_PER_SEGMENT 150.0
#define REFERENCE_BYTES_PER_SEGMENT 272.0           /* tests/reference.h's allocations: copies, boxes, nodes */
#define BEZIER_FORM_BYTES_PER_SEGMENT 68.0          /* scene_to_bezier, for the reference of a Catmull-Rom scene */

static double estimated_build_bytes(const variant *v, const hair_scene *s)
{
    double per_segment = EMBREE_BUILD_PEAK_BYTES_PER_SEGMENT;
    if (v->lib == LIB_HAIROBB) {
        int copy = variant_basis(v, s) != HAIROBB_BASIS_BEZIER && v->bezier_copy != HAIROBB_OFF;
        per_segment = HAIROBB_BUILD_PEAK_BYTES_PER_SEGMENT + (copy ? HAIROBB_COPY_BYTES_PER_SEGMENT : 0.0);
    }
    return per_segment * (double)s->segment_count;
}

/* A field of /proc/self/status or /proc/meminfo in bytes (their kB lines);
   0 when absent. */
static size_t proc_field_bytes(const char *path, const char *field)
{
    char line[256];
    size_t length = strlen(field), kilobytes = 0;
    FILE *f = fopen(path, "r");
    if (!f)
        return 0;
    while (fgets(line, sizeof line, f))
        if (strncmp(line, field, length) == 0 && line[length] == ':') {
            kilobytes = (size_t)strtoull(line + length + 1, NULL, 10);
            break;
        }
    fclose(f);
    return kilobytes * 1024;
}

static size_t memory_limit_bytes; /* --memory-mb, else 0 */

/* 1 if bytes fit in what the machine can still give (MemAvailable: other
   processes and what this one holds already are not in it; or --memory-mb
   less what this process holds), keeping a tenth of it free; else 0 and
   why says so. Unknown availability fits. */
static int memory_fits(double bytes, const char *what, char *why, size_t size)
{
    size_t available = proc_field_bytes("/proc/meminfo", "MemAvailable");
    if (memory_limit_bytes) {
        size_t held = proc_field_bytes("/proc/self/status", "VmRSS");
        available = memory_limit_bytes > held ? memory_limit_bytes - held : 1;
    }
    if (available == 0 || bytes <= 0.9 * (double)available)
        return 1;
    snprintf(why, size, "%s needs about %.2f GB (estimated), %.2f GB available (%s)", what, bytes * 1e-9,
             (double)available * 1e-9, memory_limit_bytes ? "--memory-mb less this process's RSS" : "MemAvailable");
    return 0;
}

/* A step's resident memory: before, after, and its peak (VmHWM, reset at
   the step's start by writing 5 to /proc/self/clear_refs; where that is
   refused, the process's peak so far). */
typedef struct rss_step {
    size_t before, after, peak;
} rss_step;

static int rss_peak_reset_works = 1;

static void rss_step_begin(rss_step *r)
{
    FILE *f = fopen("/proc/self/clear_refs", "w");
    rss_peak_reset_works = f && fputs("5", f) >= 0;
    if (f && fclose(f) != 0)
        rss_peak_reset_works = 0;
    r->before = proc_field_bytes("/proc/self/status", "VmRSS");
    r->after = r->peak = 0;
}

static void rss_step_end(rss_step *r)
{
    r->after = proc_field_bytes("/proc/self/status", "VmRSS");
    r->peak = proc_field_bytes("/proc/self/status", "VmHWM");
}

/* ======================================================================== */
/* Rays, hits and tracers                                                   */
/* ======================================================================== */

/* Structure of arrays so that every tracer reads the very same floats. All
   rays start at tnear = 0: secondary rays are offset off the surface. */
typedef struct ray_set {
    ray_kind kind;
    size_t count;
    float *org, *dir; /* 3 floats per ray */
    float *tfar;
    float *time; /* each ray's time in [0, 1] (motion blur); NULL: time 0 */
} ray_set;

#define NO_HIT 0xffffffffu

typedef struct hit_record {
    float t, u;
    float ng[3];   /* only hairobb reports a normal; secondary rays need it */
    uint32_t prim; /* NO_HIT on a miss; any-hit queries write 0 when occluded */
} hit_record;

/* One acceleration structure behind two per-ray functions. One indirect
   call per ray costs a few ns against hundreds for the trace itself.
   time: the ray's (static scenes ignore it). */
typedef struct tracer {
    const void *accel;
    int (*intersect)(const void *accel, const float org[3], const float dir[3], float tfar, float time, hit_record *hit);
    int (*occluded)(const void *accel, const float org[3], const float dir[3], float tfar, float time);
} tracer;

static int hairobb_tracer_intersect(const void *accel, const float org[3], const float dir[3], float tfar, float time,
                                    hit_record *out)
{
    hairobb_ray ray;
    hairobb_hit hit;
    memcpy(ray.org, org, sizeof ray.org);
    memcpy(ray.dir, dir, sizeof ray.dir);
    ray.tnear = 0.0f;
    ray.tfar = tfar;
    ray.time = time;
    if (!hairobb_intersect1((const hairobb_bvh *)accel, &ray, &hit)) {
        out->prim = NO_HIT;
        return 0;
    }
    out->t = hit.t;
    out->u = hit.u;
    memcpy(out->ng, hit.Ng, sizeof out->ng);
    out->prim = hit.prim_id;
    return 1;
}

static int hairobb_tracer_occluded(const void *accel, const float org[3], const float dir[3], float tfar, float time)
{
    hairobb_ray ray;
    memcpy(ray.org, org, sizeof ray.org);
    memcpy(ray.dir, dir, sizeof ray.dir);
    ray.tnear = 0.0f;
    ray.tfar = tfar;
    ray.time = time;
    return hairobb_occluded1((const hairobb_bvh *)accel, &ray);
}

static int embree_tracer_intersect(const void *accel, const float org[3], const float dir[3], float tfar, float time,
                                   hit_record *out)
{
    if (!emb_intersect_at_time((const emb_scene *)accel, org, 0.0f, dir, tfar, time, &out->t, &out->u, NULL,
                               &out->prim)) {
        out->prim = NO_HIT;
        return 0;
    }
    out->ng[0] = out->ng[1] = out->ng[2] = 0.0f;
    return 1;
}

static int embree_tracer_occluded(const void *accel, const float org[3], const float dir[3], float tfar, float time)
{
    return emb_occluded_at_time((const emb_scene *)accel, org, 0.0f, dir, tfar, time);
}

static tracer hairobb_tracer(const hairobb_bvh *bvh)
{
    tracer t = {bvh, hairobb_tracer_intersect, hairobb_tracer_occluded};
    return t;
}

static tracer embree_tracer(const emb_scene *scene)
{
    tracer t = {scene, embree_tracer_intersect, embree_tracer_occluded};
    return t;
}

/* ======================================================================== */
/* Parallel loop and timing harness                                         */
/* ======================================================================== */

/* Runs work(context, begin, end) over [0, count) in blocks of RAY_BLOCK,
   block b on thread b % thread_count: interleaving spreads the expensive
   image regions (the hair) evenly, without any shared counter. */
typedef void (*block_work)(void *context, size_t begin, size_t end);

typedef struct worker {
    block_work work;
    void *context;
    size_t count;
    unsigned index, thread_count;
} worker;

static void *worker_run(void *argument)
{
    const worker *w = (const worker *)argument;
    for (size_t begin = (size_t)w->index * RAY_BLOCK; begin < w->count;
         begin += (size_t)w->thread_count * RAY_BLOCK) {
        size_t end = begin + RAY_BLOCK < w->count ? begin + RAY_BLOCK : w->count;
        w->work(w->context, begin, end);
    }
    return NULL;
}

static void parallel_for(size_t count, unsigned thread_count, block_work work, void *context)
{
    pthread_t threads[256];
    worker workers[256];
    if (thread_count < 1)
        thread_count = 1;
    if (thread_count > 256)
        thread_count = 256;
    unsigned started = 1;
    for (unsigned i = 0; i < thread_count; i++) {
        worker w = {work, context, count, i, thread_count};
        workers[i] = w;
    }
    /* the calling thread is worker 0; if a thread cannot start, the rays it
       would have traced are traced by a second round on this thread */
    for (unsigned i = 1; i < thread_count; i++, started++)
        if (pthread_create(&threads[i], NULL, worker_run, &workers[i]) != 0)
            break;
    worker_run(&workers[0]);
    for (unsigned i = 1; i < started; i++)
        pthread_join(threads[i], NULL);
    for (unsigned i = started; i < thread_count; i++)
        worker_run(&workers[i]);
}

typedef struct trace_context {
    const tracer *tracer;
    const ray_set *rays;
    hit_record *hits;
} trace_context;

static void trace_block(void *context, size_t begin, size_t end)
{
    const trace_context *c = (const trace_context *)context;
    const ray_set *r = c->rays;
    if (r->kind == RAYS_SHADOW) {
        for (size_t i = begin; i < end; i++)
            c->hits[i].prim = c->tracer->occluded(c->tracer->accel, r->org + 3 * i, r->dir + 3 * i, r->tfar[i],
                                                  r->time ? r->time[i] : 0.0f) ? 0 : NO_HIT;
    } else {
        for (size_t i = begin; i < end; i++)
            c->tracer->intersect(c->tracer->accel, r->org + 3 * i, r->dir + 3 * i, r->tfar[i],
                                 r->time ? r->time[i] : 0.0f, &c->hits[i]);
    }
}

/* Traces the whole ray set once; returns wall seconds. */
static double trace_pass(const tracer *t, const ray_set *rays, hit_record *hits, unsigned thread_count)
{
    trace_context context = {t, rays, hits};
    double start = scene_now();
    parallel_for(rays->count, thread_count, trace_block, &context);
    return scene_now() - start;
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Median, min and max of n <= MAX_ROUNDS values (left in their order: a
   round's figures pair with the baseline's of the same round); NaN for none. */
typedef struct spread {
    double median, min, max;
} spread;

static spread spread_of(const double *values, int n)
{
    spread out = {NAN, NAN, NAN};
    double sorted[MAX_ROUNDS];
    if (n <= 0 || n > MAX_ROUNDS)
        return out;
    memcpy(sorted, values, (size_t)n * sizeof sorted[0]);
    qsort(sorted, (size_t)n, sizeof sorted[0], compare_doubles);
    out.median = n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
    out.min = sorted[0];
    out.max = sorted[n - 1];
    return out;
}

/* ======================================================================== */
/* Scenes and ray sets                                                      */
/* ======================================================================== */

/* Returns 0 on success, -1 when a file-based scene is absent (skipped; why
   says what is missing and where to get it), 1 on errors, 2 for an unknown
   name or a data path that cannot be read (reported here). */
static int load_scene(const options *o, const char *name, hair_scene *s, char why[TEST_DATA_WHY_SIZE])
{
    const char *path = NULL;
    test_data_status found = TEST_DATA_FOUND;
    snprintf(why, TEST_DATA_WHY_SIZE, "%s: file not found", name);
    if (strcmp(name, "combed") == 0)
        return scene_combed(s, o->segments, 1);
    if (strcmp(name, "curly") == 0)
        return scene_curly(s, o->segments, 2);
    if (strcmp(name, "random") == 0)
        return scene_random(s, o->segments, 3);
    if (strcmp(name, "crossing") == 0)
        return scene_crossing(s, o->segments, 4);
    if (strcmp(name, "yeti") == 0)
        return scene_yeti(s, o->segments, 5);
    if (strcmp(name, "straight") == 0 || strcmp(name, "furball") == 0) {
        int straight = name[0] == 's';
        path = straight ? o->straight_path : o->furball_path; /* given on the command line */
        if (!path)
            found = straight ? test_data_straight_hair(&path, why) : test_data_furball(&path, why);
        if (found == TEST_DATA_BAD_PATH || (found == TEST_DATA_ABSENT && test_data_required())) {
            fprintf(stderr, "bench: %s%s\n", why, found == TEST_DATA_ABSENT ? " (HAIROBB_REQUIRE_DATA is set)" : "");
            return 2;
        }
        if (found == TEST_DATA_ABSENT)
            return -1;
        return straight ? scene_load_hair(s, path) : scene_load_furball(s, path);
    }
    if (!strchr(name, '/') && !strchr(name, '.')) {
        fprintf(stderr, "bench: unknown scene '%s' (see --help; a file needs a path or the .hair extension)\n", name);
        return 2;
    }
    return scene_load_hair(s, name);
}

static int ray_set_alloc(ray_set *r, ray_kind kind, size_t count)
{
    r->kind = kind;
    r->count = count;
    size_t n = count ? count : 1;
    r->org = (float *)malloc(3 * n * sizeof(float));
    r->dir = (float *)malloc(3 * n * sizeof(float));
    r->tfar = (float *)malloc(n * sizeof(float));
    r->time = NULL;
    return !r->org || !r->dir || !r->tfar;
}

/* Gives every ray a time, uniform in [0, 1) from a fixed seed. */
static int ray_set_random_times(ray_set *r, uint64_t seed)
{
    scene_rng rng;
    free(r->time);
    r->time = (float *)malloc((r->count ? r->count : 1) * sizeof(float));
    if (!r->time)
        return 1;
    scene_rng_seed(&rng, seed);
    for (size_t i = 0; i < r->count; i++)
        r->time[i] = scene_rng_float(&rng);
    return 0;
}

static void ray_set_free(ray_set *r)
{
    free(r->org);
    free(r->dir);
    free(r->tfar);
    free(r->time);
    memset(r, 0, sizeof *r);
}

static int primary_rays(const hair_scene *s, int resolution, ray_set *rays)
{
    if (ray_set_alloc(rays, RAYS_PRIMARY, (size_t)resolution * (size_t)resolution) != 0)
        return 1;
    scene_camera_rays(s, resolution, resolution, rays->org, rays->dir);
    for (size_t i = 0; i < rays->count; i++)
        rays->tfar[i] = INFINITY;
    return 0;
}

static float scene_diagonal(const hair_scene *s)
{
    scene_vec3 extent = scene_v3(s->upper[0] - s->lower[0], s->upper[1] - s->lower[1], s->upper[2] - s->lower[2]);
    return scene_v3_length(extent);
}

/* Fixed point light above, right of and in front of the hair, outside its
   bounding sphere, so that shadow rays cross the hair volume. */
static scene_vec3 light_position(const hair_scene *s)
{
    scene_vec3 centre = scene_v3(0.5f * (s->lower[0] + s->upper[0]), 0.5f * (s->lower[1] + s->upper[1]),
                                 0.5f * (s->lower[2] + s->upper[2]));
    scene_vec3 toward = scene_v3_normalize(scene_v3(0.4f, 1.0f, 0.6f));
    return scene_v3_add(centre, scene_v3_scale(toward, scene_diagonal(s)));
}

/* Cosine-distributed direction about the unit normal n. */
static scene_vec3 cosine_direction(scene_vec3 n, scene_rng *rng)
{
    float phi = 6.28318531f * scene_rng_float(rng);
    float r2 = scene_rng_float(rng);
    float sin_theta = sqrtf(r2), cos_theta = sqrtf(1.0f - r2);
    scene_vec3 tangent = scene_v3_perpendicular(n);
    scene_vec3 bitangent = scene_v3_cross(n, tangent);
    return scene_v3_normalize(scene_v3_add(scene_v3_scale(n, cos_theta),
                                           scene_v3_add(scene_v3_scale(tangent, sin_theta * cosf(phi)),
                                                        scene_v3_scale(bitangent, sin_theta * sinf(phi)))));
}

/* From every primary hit: one diffuse bounce and one shadow ray. Both start
   at the hit point pushed off the ribbon along Ng by 1e-3 of the scene's
   diagonal (over the hair radius in the procedural scenes), so neither
   library finds the surface the ray left. */
static int secondary_rays(const hair_scene *s, const ray_set *primary, const hit_record *hits, ray_set *incoherent,
                          ray_set *shadow)
{
    size_t count = 0;
    for (size_t i = 0; i < primary->count; i++)
        count += hits[i].prim != NO_HIT;
    if (ray_set_alloc(incoherent, RAYS_INCOHERENT, count) != 0 || ray_set_alloc(shadow, RAYS_SHADOW, count) != 0)
        return 1;
    float epsilon = 1e-3f * scene_diagonal(s);
    scene_vec3 light = light_position(s);
    scene_rng rng;
    scene_rng_seed(&rng, 12345);
    size_t k = 0;
    for (size_t i = 0; i < primary->count; i++) {
        const hit_record *h = &hits[i];
        if (h->prim == NO_HIT)
            continue;
        const float *o = primary->org + 3 * i, *d = primary->dir + 3 * i;
        scene_vec3 ng = scene_v3(h->ng[0], h->ng[1], h->ng[2]);
        scene_vec3 p = scene_v3(o[0] + h->t * d[0], o[1] + h->t * d[1], o[2] + h->t * d[2]);
        p = scene_v3_add(p, scene_v3_scale(ng, epsilon));

        scene_vec3 bounce = cosine_direction(ng, &rng);
        scene_vec3 to_light = scene_v3_sub(light, p);
        float distance = scene_v3_length(to_light);
        to_light = scene_v3_scale(to_light, 1.0f / distance);
        float origin[3] = {p.x, p.y, p.z};
        memcpy(incoherent->org + 3 * k, origin, sizeof origin);
        memcpy(shadow->org + 3 * k, origin, sizeof origin);
        float bounce_dir[3] = {bounce.x, bounce.y, bounce.z}, light_dir[3] = {to_light.x, to_light.y, to_light.z};
        memcpy(incoherent->dir + 3 * k, bounce_dir, sizeof bounce_dir);
        memcpy(shadow->dir + 3 * k, light_dir, sizeof light_dir);
        incoherent->tfar[k] = INFINITY;
        shadow->tfar[k] = distance;
        k++;
    }
    return 0;
}

/* ======================================================================== */
/* Accuracy                                                                 */
/* ======================================================================== */

/* The reference's answers on a fixed random subset of the primary rays. */
typedef struct accuracy_set {
    ray_set rays;      /* copies of the chosen primary rays */
    ref_hit *ref;
    int *ref_hits;
    double seconds;    /* reference build + trace */
} accuracy_set;

typedef struct accuracy_summary {
    size_t rays, disagreements, t_compared, u_compared;
    double t_median, t_p99, t_max; /* |t - t_ref| / r_ref where both hit */
    double u_median, u_p99;        /* |u - u_ref| where both hit the same segment */
} accuracy_summary;

typedef struct reference_context {
    const ref_scene *scene;
    accuracy_set *set;
    size_t first; /* of the rays traced */
} reference_context;

static void reference_block(void *context, size_t begin, size_t end)
{
    reference_context *c = (reference_context *)context;
    for (size_t i = c->first + begin; i < c->first + end; i++)
        c->set->ref_hits[i] = ref_intersect(c->scene, c->set->rays.org + 3 * i, c->set->rays.dir + 3 * i, 0.0,
                                            INFINITY, &c->set->ref[i]);
}

/* The reference's answers for the set's rays [first, end). */
static void reference_trace(const ref_scene *reference, accuracy_set *a, size_t first, size_t end,
                            unsigned thread_count)
{
    reference_context context = {reference, a, first};
    parallel_for(end - first, thread_count, reference_block, &context);
}

/* Picks `wanted` distinct primary rays with a fixed seed (partial
   Fisher-Yates) and copies them, without their times; the same rays on
   every call. */
static int accuracy_pick(const ray_set *primary, size_t wanted, accuracy_set *a)
{
    memset(a, 0, sizeof *a);
    size_t n = wanted < primary->count ? wanted : primary->count;
    uint32_t *order = (uint32_t *)malloc((primary->count ? primary->count : 1) * sizeof(uint32_t));
    a->ref = (ref_hit *)malloc((n ? n : 1) * sizeof(ref_hit));
    a->ref_hits = (int *)malloc((n ? n : 1) * sizeof(int));
    if (!order || !a->ref || !a->ref_hits || ray_set_alloc(&a->rays, RAYS_PRIMARY, n) != 0) {
        free(order);
        return 1;
    }
    for (size_t i = 0; i < primary->count; i++)
        order[i] = (uint32_t)i;
    scene_rng rng;
    scene_rng_seed(&rng, 777);
    for (size_t i = 0; i < n; i++) {
        size_t j = i + (size_t)(((uint64_t)scene_rng_u32(&rng) * (primary->count - i)) >> 32);
        uint32_t chosen = order[j];
        order[j] = order[i];
        order[i] = chosen;
        memcpy(a->rays.org + 3 * i, primary->org + 3 * (size_t)chosen, 3 * sizeof(float));
        memcpy(a->rays.dir + 3 * i, primary->dir + 3 * (size_t)chosen, 3 * sizeof(float));
        a->rays.tfar[i] = primary->tfar[chosen];
    }
    free(order);
    return 0;
}

/* accuracy_pick, and the picked rays traced with the reference only. */
static int accuracy_prepare(const hair_scene *s, const ray_set *primary, size_t wanted, unsigned thread_count,
                            accuracy_set *a)
{
    if (accuracy_pick(primary, wanted, a) != 0)
        return 1;
    double start = scene_now();
    /* the reference reads Bezier segments: a Catmull-Rom scene's are converted for it, then freed */
    hair_scene bezier;
    const hair_scene *input = s;
    if (s->basis != SCENE_BASIS_BEZIER) {
        if (scene_to_bezier(s, &bezier) != 0)
            return 1;
        input = &bezier;
    }
    ref_scene *reference = ref_build(input->vertices, input->vertex_count, input->indices, input->segment_count);
    if (input == &bezier)
        scene_free(&bezier);
    if (!reference)
        return 1;
    reference_trace(reference, a, 0, a->rays.count, thread_count);
    ref_free(reference);
    a->seconds = scene_now() - start;
    return 0;
}

static void accuracy_free(accuracy_set *a)
{
    ray_set_free(&a->rays);
    free(a->ref);
    free(a->ref_hits);
    memset(a, 0, sizeof *a);
}

/* Nearest-rank percentile of a sorted array. */
static double percentile(const double *sorted, size_t n, double p)
{
    return n ? sorted[(size_t)(p * (double)(n - 1) + 0.5)] : NAN;
}

static int accuracy_measure(const tracer *t, const accuracy_set *a, accuracy_summary *out)
{
    size_t n = a->rays.count;
    memset(out, 0, sizeof *out);
    hit_record *hits = (hit_record *)malloc((n ? n : 1) * sizeof(hit_record));
    double *t_errors = (double *)malloc((n ? n : 1) * sizeof(double));
    double *u_errors = (double *)malloc((n ? n : 1) * sizeof(double));
    if (!hits || !t_errors || !u_errors) {
        free(hits);
        free(t_errors);
        free(u_errors);
        return 1;
    }
    trace_pass(t, &a->rays, hits, 1);
    out->rays = n;
    for (size_t i = 0; i < n; i++) {
        int hit = hits[i].prim != NO_HIT;
        const ref_hit *ref = &a->ref[i];
        if (hit != a->ref_hits[i]) {
            out->disagreements++;
            continue;
        }
        if (!hit)
            continue;
        if (ref->r > 0.0)
            t_errors[out->t_compared++] = fabs((double)hits[i].t - ref->t) / ref->r;
        /* u on another segment is a different curve's parameter */
        if (hits[i].prim == ref->prim_id)
            u_errors[out->u_compared++] = fabs((double)hits[i].u - ref->u);
    }
    qsort(t_errors, out->t_compared, sizeof(double), compare_doubles);
    qsort(u_errors, out->u_compared, sizeof(double), compare_doubles);
    out->t_median = percentile(t_errors, out->t_compared, 0.5);
    out->t_p99 = percentile(t_errors, out->t_compared, 0.99);
    out->t_max = percentile(t_errors, out->t_compared, 1.0);
    out->u_median = percentile(u_errors, out->u_compared, 0.5);
    out->u_p99 = percentile(u_errors, out->u_compared, 0.99);
    free(hits);
    free(t_errors);
    free(u_errors);
    return 0;
}

static double disagreement_percent(const accuracy_summary *a)
{
    return a->rays ? 100.0 * (double)a->disagreements / (double)a->rays : NAN;
}

/* ======================================================================== */
/* Running one variant                                                      */
/* ======================================================================== */

typedef struct variant_result {
    int measured;
    double build_seconds;
    size_t memory_bytes;
    size_t build_transient_bytes; /* hairobb: peak allocations during the build beyond the BVH's memory_bytes */
    hairobb_stats stats;   /* hairobb only */
    /* Mrays/s over the rounds, and the ratio to Embree flat r4 taken within
       each round; NAN when not measured */
    spread mrays[RAY_KIND_COUNT][MAX_THREAD_COUNTS];
    spread ratio[RAY_KIND_COUNT][MAX_THREAD_COUNTS];
    int has_accuracy;
    accuracy_summary accuracy;
    rss_step build_rss;    /* the process's resident memory over the build */
    char skipped[192];     /* why it was not built (memory), or empty */
} variant_result;

typedef struct scene_result {
    char name[64];
    size_t segment_count;
    size_t ray_counts[RAY_KIND_COUNT];
    int loaded;
    variant_result variants[VARIANT_COUNT];
    scene_basis basis;
    int selected[VARIANT_COUNT]; /* the variants run on this scene */
} scene_result;

/* Everything a scene's variants share: the geometry and the rays. */
typedef struct workload {
    hair_scene scene;
    ray_set rays[RAY_KIND_COUNT];
    hit_record *hits;      /* output buffer, sized for the largest ray set */
    size_t primary_hits;
    int has_accuracy;
    accuracy_set accuracy;
    /* The default variant's BVH, built to spawn the secondary rays and kept
       for that variant's row: at tens of millions of segments a build takes
       minutes, too long to do twice. NULL once adopted. */
    hairobb_bvh *default_bvh;
    double default_build_seconds;
    size_t default_build_transient_bytes;
    rss_step default_build_rss;
    /* resident memory over the scene's generation, the reference and the timed tracing */
    rss_step scene_rss, reference_rss, trace_rss;
    double scene_seconds;       /* generating or loading the scene */
    char accuracy_skipped[192]; /* why the reference was not built (memory), or empty */
} workload;

/* An acceleration structure built for one variant. */
typedef struct built_accel {
    hairobb_bvh *bvh;
    emb_scene *embree;
    tracer tracer;
} built_accel;

/* Takes every hit: what calling a filter costs, without changing a hit. */
static int take_every_hit(void *user, const hairobb_ray *ray, const hairobb_hit *hit)
{
    (void)user; (void)ray; (void)hit;
    return 1;
}

/* The SIMD paths this build of hairobb has on this CPU, and the one its
   defaults pick (one segment built per path). */
static const char *simd_paths(void)
{
    static const float vertices[16] = {0, 0, 0, 0.1f, 0, 0, 1, 0.1f, 0, 0, 2, 0.1f, 0, 0, 3, 0.1f};
    static const uint32_t indices[1] = {0};
    static char text[128];
    hairobb_build_options build_options;
    text[0] = '\0';
    for (int k = HAIROBB_SIMD_AUTO; k <= HAIROBB_SIMD_AVX2; k++) {
        hairobb_bvh *bvh = NULL;
        memset(&build_options, 0, sizeof build_options);
        build_options.simd = (hairobb_simd)k;
        if (hairobb_build(vertices, 4, indices, 1, &build_options, &bvh) != HAIROBB_OK) continue;
        snprintf(text + strlen(text), sizeof text - strlen(text), k == HAIROBB_SIMD_AUTO ? "%s (paths:" : " %s",
                 hairobb_simd_string(hairobb_get_simd(bvh)));
        hairobb_free(bvh);
    }
    snprintf(text + strlen(text), sizeof text - strlen(text), ")");
    return text;
}

/* Every hairobb BVH allocates through this one meter (the allocator_user of
   every build; BVHs built earlier stay live in it): a build's peak transient
   bytes = the meter's peak during the build - what was live before it - the
   BVH's hairobb_memory_bytes. */
static alloc_meter hairobb_meter;

/* hairobb_build over the scene's segments (vertices NULL: a moving scene's
   build_options->time_vertices), metered: build seconds and peak transient
   bytes. allocator_user is set here; what: the build in an error message. */
static hairobb_bvh *build_metered(const hair_scene *s, const float *vertices, hairobb_build_options *build_options,
                                  const char *what, double *seconds, size_t *transient_bytes)
{
    build_options->allocator_user = &hairobb_meter;
    hairobb_bvh *bvh = NULL;
    alloc_meter_reset_peak(&hairobb_meter);
    size_t live_before = hairobb_meter.current; /* no other thread allocates between builds */
    double start = scene_now();
    hairobb_result result = hairobb_build(vertices, s->vertex_count, s->indices, s->segment_count, build_options, &bvh);
    *seconds = scene_now() - start;
    *transient_bytes = bvh ? hairobb_meter.peak - live_before - hairobb_memory_bytes(bvh) : 0;
    if (result != HAIROBB_OK)
        fprintf(stderr, "bench: %s: hairobb_build (%s): %s\n", s->name, what, hairobb_result_string(result));
    return bvh;
}

static hairobb_bvh *build_hairobb(const hair_scene *s, const variant *v, double *seconds, size_t *transient_bytes)
{
    hairobb_build_options build_options;
    memset(&build_options, 0, sizeof build_options);
    build_options.threads = v->build_threads;
    build_options.hit_filter = v->hit_filter ? take_every_hit : NULL;
    build_options.nodes = v->nodes;
    build_options.obb_layout = v->obb_layout;
    build_options.precision = v->precision;
    build_options.curve_pieces = v->curve_pieces;
    build_options.spatial_splits = v->spatial_splits;
    build_options.clustering = v->clustering;
    build_options.simd = v->simd;
    build_options.basis = variant_basis(v, s);
    build_options.bezier_copy = v->bezier_copy;
    return build_metered(s, s->vertices, &build_options, v->key, seconds, transient_bytes);
}

static int build_variant(workload *w, const variant *v, built_accel *b, variant_result *r)
{
    const hair_scene *s = &w->scene;
    memset(b, 0, sizeof *b);
    if (v->lib == LIB_HAIROBB) {
        if (w->default_bvh && v == &all_variants[spawn_variant(s)]) {
            b->bvh = w->default_bvh;
            r->build_seconds = w->default_build_seconds;
            r->build_transient_bytes = w->default_build_transient_bytes;
            r->build_rss = w->default_build_rss;
            w->default_bvh = NULL;
        } else {
            b->bvh = build_hairobb(s, v, &r->build_seconds, &r->build_transient_bytes);
        }
        if (!b->bvh)
            return 1;
        r->memory_bytes = hairobb_memory_bytes(b->bvh);
        hairobb_get_stats(b->bvh, &r->stats);
        b->tracer = hairobb_tracer(b->bvh);
    } else {
        /* threads 0: Embree builds on every core, as it would in a renderer */
        b->embree = emb_build_curves(s->vertices, s->vertex_count, s->indices, s->segment_count,
                                     variant_embree_type(v, s), NULL, v->embree_rate, 0, &r->memory_bytes,
                                     &r->build_seconds);
        if (!b->embree)
            return 1;
        b->tracer = embree_tracer(b->embree);
    }
    return 0;
}

static void free_variant(built_accel *b)
{
    hairobb_free(b->bvh);
    emb_free(b->embree);
    memset(b, 0, sizeof *b);
}

/* Builds a variant and records its build time, memory and tree; 1 if the
   build failed. */
static int build_and_record(workload *w, const variant *v, built_accel *accel, variant_result *r)
{
    for (int k = 0; k < RAY_KIND_COUNT; k++)
        for (int t = 0; t < MAX_THREAD_COUNTS; t++)
            r->mrays[k][t] = r->ratio[k][t] = (spread){NAN, NAN, NAN};
    progress_start("  %s: build", v->label);
    int adopted = w->default_bvh && v == &all_variants[spawn_variant(&w->scene)];
    if (!adopted && !memory_fits(estimated_build_bytes(v, &w->scene), "the build", r->skipped, sizeof r->skipped)) {
        progress("skipped: %s", r->skipped);
        return 1;
    }
    if (!adopted)
        rss_step_begin(&r->build_rss);
    int failed = build_variant(w, v, accel, r);
    if (!adopted)
        rss_step_end(&r->build_rss);
    if (failed) {
        progress("failed");
        return 1;
    }
    progress("%.2f s", r->build_seconds);
    r->measured = 1;
    return 0;
}

/* Times every built variant on each ray set and thread count, in rounds
   (see the top of the file); fills mrays and ratio. */
static void time_in_rounds(const options *o, workload *w, built_accel accel[VARIANT_COUNT], scene_result *sr)
{
    static double mrays[VARIANT_COUNT][MAX_ROUNDS];
    int base = variant_index(BASELINE_KEY);
    for (int k = 0; k < RAY_KIND_COUNT; k++) {
        const ray_set *rays = &w->rays[k];
        if (!o->ray_kind_enabled[k] || rays->count == 0)
            continue;
        for (int t = 0; t < o->thread_count_count; t++) {
            unsigned threads = o->thread_counts[t];
            progress_start("  %s rays, %u thread%s: warm-up", ray_kind_names[k], threads, threads == 1 ? "" : "s");
            for (int i = 0; i < VARIANT_COUNT; i++) /* caches, page faults, Embree's lazy set-up */
                if (sr->variants[i].measured)
                    trace_pass(&accel[i].tracer, rays, w->hits, threads);
            for (int round = 0; round < o->rounds; round++) {
                progress_start("  %s rays, %u thread%s: round %d of %d", ray_kind_names[k], threads,
                               threads == 1 ? "" : "s", round + 1, o->rounds);
                for (int i = 0; i < VARIANT_COUNT; i++)
                    if (sr->variants[i].measured)
                        mrays[i][round] = (double)rays->count / trace_pass(&accel[i].tracer, rays, w->hits, threads) * 1e-6;
            }
            progress("done");
            for (int i = 0; i < VARIANT_COUNT; i++) {
                variant_result *r = &sr->variants[i];
                double ratios[MAX_ROUNDS];
                if (!r->measured)
                    continue;
                for (int round = 0; round < o->rounds; round++)
                    ratios[round] = sr->variants[base].measured ? mrays[i][round] / mrays[base][round] : NAN;
                r->ratio[k][t] = spread_of(ratios, sr->variants[base].measured ? o->rounds : 0);
                r->mrays[k][t] = spread_of(mrays[i], o->rounds);
            }
        }
    }
}

/* ======================================================================== */
/* Scene workload                                                           */
/* ======================================================================== */

static unsigned max_threads(const options *o)
{
    unsigned most = 1;
    for (int t = 0; t < o->thread_count_count; t++)
        most = o->thread_counts[t] > most ? o->thread_counts[t] : most;
    return most;
}

/* Secondary rays start where the default hairobb BVH's primary rays hit:
   built and traced here once, so that every variant (Embree included)
   traces the very same secondary rays. The BVH is kept for the default
   variant if it is selected. */
static int spawn_secondary_rays(const options *o, workload *w, int keep_bvh)
{
    const variant *v = &all_variants[spawn_variant(&w->scene)];
    char why[192];
    if (!memory_fits(estimated_build_bytes(v, &w->scene), "the BVH that spawns the secondary rays", why, sizeof why)) {
        fprintf(stderr, "bench: %s: %s (--rays primary needs none)\n", w->scene.name, why);
        return 1;
    }
    rss_step_begin(&w->default_build_rss);
    hairobb_bvh *bvh = build_hairobb(&w->scene, v, &w->default_build_seconds, &w->default_build_transient_bytes);
    rss_step_end(&w->default_build_rss);
    if (!bvh)
        return 1;
    tracer t = hairobb_tracer(bvh);
    trace_pass(&t, &w->rays[RAYS_PRIMARY], w->hits, max_threads(o));
    if (keep_bvh)
        w->default_bvh = bvh;
    else
        hairobb_free(bvh);
    w->primary_hits = 0;
    for (size_t i = 0; i < w->rays[RAYS_PRIMARY].count; i++)
        w->primary_hits += w->hits[i].prim != NO_HIT;
    return secondary_rays(&w->scene, &w->rays[RAYS_PRIMARY], w->hits, &w->rays[RAYS_INCOHERENT],
                          &w->rays[RAYS_SHADOW]);
}

static void workload_free(workload *w)
{
    for (int k = 0; k < RAY_KIND_COUNT; k++)
        ray_set_free(&w->rays[k]);
    free(w->hits);
    hairobb_free(w->default_bvh);
    accuracy_free(&w->accuracy);
    scene_free(&w->scene);
}

/* Primary rays, the reference's answers on the accuracy subset, then the
   secondary rays (in that order: the reference, the largest allocation, is
   freed before the default BVH is built and kept). */
static int workload_prepare(const options *o, const int selected[VARIANT_COUNT], workload *w)
{
    progress("%s: primary rays (%dx%d)", w->scene.name, o->resolution, o->resolution);
    if (primary_rays(&w->scene, o->resolution, &w->rays[RAYS_PRIMARY]) != 0)
        return 1;
    /* secondary rays are at most one per primary ray */
    w->hits = (hit_record *)malloc((w->rays[RAYS_PRIMARY].count ? w->rays[RAYS_PRIMARY].count : 1) *
                                   sizeof(hit_record));
    if (!w->hits)
        return 1;
    double reference_bytes = (REFERENCE_BYTES_PER_SEGMENT +
                              (w->scene.basis != SCENE_BASIS_BEZIER ? BEZIER_FORM_BYTES_PER_SEGMENT : 0.0)) *
                             (double)w->scene.segment_count;
    if (o->accuracy_rays > 0 &&
        !memory_fits(reference_bytes, "the reference", w->accuracy_skipped, sizeof w->accuracy_skipped))
        progress("%s: accuracy skipped: %s", w->scene.name, w->accuracy_skipped);
    else if (o->accuracy_rays > 0) {
        progress_start("%s: reference on %zu primary rays", w->scene.name, o->accuracy_rays);
        rss_step_begin(&w->reference_rss);
        int failed = accuracy_prepare(&w->scene, &w->rays[RAYS_PRIMARY], o->accuracy_rays, max_threads(o), &w->accuracy);
        rss_step_end(&w->reference_rss);
        if (failed) {
            progress("failed");
            fprintf(stderr, "bench: %s: reference failed (out of memory?)\n", w->scene.name);
            return 1;
        }
        progress("%.2f s", w->accuracy.seconds);
        w->has_accuracy = 1;
    }
    if (o->ray_kind_enabled[RAYS_INCOHERENT] || o->ray_kind_enabled[RAYS_SHADOW]) {
        progress_start("%s: secondary rays from the default hairobb BVH's primary hits", w->scene.name);
        if (spawn_secondary_rays(o, w, selected[spawn_variant(&w->scene)]) != 0) {
            progress("failed");
            return 1;
        }
        progress("build %.2f s", w->default_build_seconds);
    }
    return 0;
}

/* ======================================================================== */
/* Tables                                                                   */
/* ======================================================================== */

/* "value (ratio x)" against the Embree flat r4 row; "-" when unmeasured. */
static const char *with_ratio(char *buffer, size_t size, const char *format, double value, double baseline)
{
    char number[32];
    if (!isfinite(value)) {
        snprintf(buffer, size, "-");
        return buffer;
    }
    snprintf(number, sizeof number, format, value);
    if (isfinite(baseline) && baseline > 0.0)
        snprintf(buffer, size, "%s (%.2fx)", number, value / baseline);
    else
        snprintf(buffer, size, "%s", number);
    return buffer;
}

static const variant_result *baseline_of(const scene_result *sr)
{
    const variant_result *b = &sr->variants[variant_index(BASELINE_KEY)];
    return b->measured ? b : NULL;
}

static void print_scene_header(const options *o, const workload *w)
{
    const hair_scene *s = &w->scene;
    printf("\n=== scene %s: %zu segments, bounds (%.3g %.3g %.3g)-(%.3g %.3g %.3g)\n", s->name, s->segment_count,
           s->lower[0], s->lower[1], s->lower[2], s->upper[0], s->upper[1], s->upper[2]);
    printf("rays: primary %zu (%dx%d pinhole)", w->rays[RAYS_PRIMARY].count, o->resolution, o->resolution);
    if (w->rays[RAYS_INCOHERENT].count || w->rays[RAYS_SHADOW].count)
        printf(", %.1f%% hit by %s; incoherent %zu (diffuse bounce), shadow %zu (point light)",
               100.0 * (double)w->primary_hits / (double)w->rays[RAYS_PRIMARY].count,
               s->basis == SCENE_BASIS_BEZIER ? "default hairobb" : all_variants[spawn_variant(s)].label,
               w->rays[RAYS_INCOHERENT].count, w->rays[RAYS_SHADOW].count);
    printf("\n");
    if (w->has_accuracy) {
        size_t ref_hits = 0;
        for (size_t i = 0; i < w->accuracy.rays.count; i++)
            ref_hits += (size_t)w->accuracy.ref_hits[i];
        printf("accuracy: %zu random primary rays, %zu hit the reference (reference build + trace %.2f s)\n",
               w->accuracy.rays.count, ref_hits, w->accuracy.seconds);
    }
}

static void print_build_table(const scene_result *sr, const int selected[VARIANT_COUNT])
{
    const variant_result *base = baseline_of(sr);
    char c1[48], c2[48], c3[48], c4[48];
    printf("\nbuild and memory (ratios: this / Embree flat r4; both build on all cores; transient: the library's\n"
           "peak allocations during the build beyond the BVH's memory, bytes/segment)\n");
    printf("%-20s %-18s %-18s %-18s %-10s %s\n", "variant", "build s", "MB", "bytes/segment", "transient",
           "AABB/OBB nodes, leaves, segments/leaf, depth");
    for (int i = 0; i < VARIANT_COUNT; i++) {
        const variant_result *r = &sr->variants[i];
        if (!selected[i] || !r->measured)
            continue;
        double bytes_per_segment = (double)r->memory_bytes / (double)sr->segment_count;
        printf("%-20s %-18s %-18s %-18s", all_variants[i].label,
               with_ratio(c1, sizeof c1, "%.3f", r->build_seconds, base ? base->build_seconds : NAN),
               with_ratio(c2, sizeof c2, "%.1f", (double)r->memory_bytes / 1048576.0,
                          base ? (double)base->memory_bytes / 1048576.0 : NAN),
               with_ratio(c3, sizeof c3, "%.1f", bytes_per_segment,
                          base ? (double)base->memory_bytes / (double)sr->segment_count : NAN));
        if (all_variants[i].lib == LIB_HAIROBB)
            snprintf(c4, sizeof c4, "%.1f", (double)r->build_transient_bytes / (double)sr->segment_count);
        else
            snprintf(c4, sizeof c4, "-");
        printf(" %-10s", c4);
        if (all_variants[i].lib == LIB_HAIROBB)
            printf(" %zu/%zu, %zu, %.2f, %u", r->stats.aabb_nodes, r->stats.obb_nodes, r->stats.leaves,
                   r->stats.leaves ? (double)r->stats.leaf_references / (double)r->stats.leaves : 0.0,
                   r->stats.max_depth);
        printf("\n");
    }
}

/* Two tables: Mrays/s, then the ratio to Embree flat r4, each as the
   median over the rounds and its [min-max] spread. */
static void print_speed_table(const options *o, const scene_result *sr, const int selected[VARIANT_COUNT])
{
    char cell[64], heading[48];
    for (int table = 0; table < 2; table++) {
        if (table == 0)
            printf("\nMrays/s: median of %d round%s [min-max]\n", o->rounds, o->rounds == 1 ? "" : "s");
        else if (baseline_of(sr))
            printf("\nthis / Embree flat r4, the ratio taken within each round: median [min-max]\n");
        else
            break;
        printf("%-21s", "variant");
        for (int k = 0; k < RAY_KIND_COUNT; k++)
            for (int t = 0; t < o->thread_count_count && o->ray_kind_enabled[k]; t++) {
                snprintf(heading, sizeof heading, "%s %ut", ray_kind_names[k], o->thread_counts[t]);
                printf(" %-17s", heading);
            }
        printf("\n");
        for (int i = 0; i < VARIANT_COUNT; i++) {
            const variant_result *r = &sr->variants[i];
            if (!selected[i] || !r->measured)
                continue;
            printf("%-21s", all_variants[i].label);
            for (int k = 0; k < RAY_KIND_COUNT; k++)
                for (int t = 0; t < o->thread_count_count && o->ray_kind_enabled[k]; t++) {
                    spread x = table == 0 ? r->mrays[k][t] : r->ratio[k][t];
                    if (isnan(x.median))
                        snprintf(cell, sizeof cell, "-");
                    else
                        snprintf(cell, sizeof cell, "%.2f [%.2f-%.2f]", x.median, x.min, x.max);
                    printf(" %-17s", cell);
                }
            printf("\n");
        }
    }
}

static void print_accuracy_table(const workload *w, const scene_result *sr, const int selected[VARIANT_COUNT])
{
    int any_informative = 0;
    if (!w->has_accuracy)
        return;
    printf("\naccuracy on %zu primary rays against the double-precision reference ribbon\n",
           w->accuracy.rays.count);
    printf("%-20s %-17s %-10s %-10s %-10s %-10s %-10s\n", "variant", "disagree", "|dt|/r med", "|dt|/r p99",
           "|dt|/r max", "|du| med", "|du| p99");
    for (int i = 0; i < VARIANT_COUNT; i++) {
        const variant_result *r = &sr->variants[i];
        if (!selected[i] || !r->has_accuracy)
            continue;
        const accuracy_summary *a = &r->accuracy;
        char disagree[32];
        snprintf(disagree, sizeof disagree, "%.3f%% (%zu)", disagreement_percent(a), a->disagreements);
        printf("%-20s %-17s %-10.2e %-10.2e %-10.2e %-10.2e %-10.2e\n", all_variants[i].label, disagree, a->t_median,
               a->t_p99, a->t_max, a->u_median, a->u_p99);
        if (!variant_comparable(&all_variants[i], sr->basis))
            any_informative |= all_variants[i].lib == LIB_EMBREE ? 1 : 2;
    }
    if (any_informative & 1)
        printf("* round curves are swept spheres, not the reference's flat ribbon: informative, not comparable\n");
    if (any_informative & 2)
        printf("* the C-R rows read this scene's Bezier points as Catmull-Rom points: other curves, not comparable\n");
}

/* Rows AABB-only, OBB-only, mixed per scene, as in the paper's results
   table (Woop et al. 2014): speed on primary and incoherent rays, memory
   and build time. */
static void print_ablation_table(const options *o, const scene_result *results, int scene_count,
                                 const int selected[VARIANT_COUNT])
{
    int any = 0;
    for (int a = 0; a < ABLATION_ROWS; a++)
        any |= selected[variant_index(ablation_keys[a])];
    if (!any)
        return;
    char heading[48];
    printf("\n=== ablation (exact intersector, 8 pieces): node policy, then spatial splits, compressed nodes and\n"
           "    clustering added in turn (the paper's table; compression: a byte rotation per child); then nodes with\n"
           "    one rotation shared by the children, in floats and in bytes (the paper's compressed node); defaults\n");
    printf("%-12s %-14s", "scene", "nodes");
    for (int k = RAYS_PRIMARY; k <= RAYS_INCOHERENT; k++)
        for (int t = 0; t < o->thread_count_count && o->ray_kind_enabled[k]; t++) {
            snprintf(heading, sizeof heading, "%s %ut", ray_kind_names[k], o->thread_counts[t]);
            printf(" %-13s", heading);
        }
    printf(" %-8s %-9s %-8s %s\n", "MB", "bytes/seg", "build s", "OBB nodes %");
    for (int s = 0; s < scene_count; s++) {
        if (!results[s].loaded)
            continue;
        int first = 1;
        for (int a = 0; a < ABLATION_ROWS; a++) {
            int i = variant_index(ablation_keys[a]);
            const variant_result *r = &results[s].variants[i];
            if (!selected[i] || !r->measured)
                continue;
            printf("%-12s %-14s", first ? results[s].name : "", ablation_labels[a]);
            first = 0;
            for (int k = RAYS_PRIMARY; k <= RAYS_INCOHERENT; k++)
                for (int t = 0; t < o->thread_count_count && o->ray_kind_enabled[k]; t++)
                    printf(" %-13.2f", r->mrays[k][t].median);
            size_t inner = r->stats.aabb_nodes + r->stats.obb_nodes;
            printf(" %-8.1f %-9.1f %-8.3f %.1f\n", (double)r->memory_bytes / 1048576.0,
                   (double)r->memory_bytes / (double)results[s].segment_count, r->build_seconds,
                   inner ? 100.0 * (double)r->stats.obb_nodes / (double)inner : 0.0);
        }
    }
}

/* The chart's points as a table: precision variants and Embree rates. */
static void print_tradeoff_table(const options *o, const scene_result *results, int scene_count,
                                 const int selected[VARIANT_COUNT], const char *chart_note)
{
    if (!o->ray_kind_enabled[RAYS_PRIMARY] || o->accuracy_rays == 0)
        return;
    printf("\n=== run time against error: primary rays, %u thread%s (%s)\n", o->thread_counts[0],
           o->thread_counts[0] == 1 ? "" : "s", chart_note);
    printf("%-12s %-20s %-10s %-12s %-10s\n", "scene", "variant", "Mrays/s", "disagree %", "|dt|/r p99");
    for (int s = 0; s < scene_count; s++) {
        if (!results[s].loaded)
            continue;
        int first = 1;
        for (int i = 0; i < VARIANT_COUNT; i++) {
            const variant_result *r = &results[s].variants[i];
            if (!selected[i] || !all_variants[i].on_chart || !r->has_accuracy)
                continue;
            printf("%-12s %-20s %-10.2f %-12.4f %-10.2e\n", first ? results[s].name : "", all_variants[i].label,
                   r->mrays[RAYS_PRIMARY][0].median, disagreement_percent(&r->accuracy), r->accuracy.t_p99);
            first = 0;
        }
    }
}

/* The variants a scene runs: --variants; without it a Catmull-Rom scene
   runs the yeti group (the Bezier rows there would each hold a 72-byte
   copy a segment, the rest of "all" reads Bezier points). */
static void scene_variants(const options *o, const hair_scene *s, const int requested[VARIANT_COUNT], scene_result *sr)
{
    sr->basis = s->basis;
    if (s->basis == SCENE_BASIS_CATMULL_ROM && !o->variants_given) {
        memset(sr->selected, 0, sizeof sr->selected);
        select_variants("yeti", sr->selected);
    } else {
        memcpy(sr->selected, requested, sizeof sr->selected);
    }
}

/* What a Catmull-Rom scene holds and what each row reads from it. */
static void print_curves_note(const workload *w)
{
    const hair_scene *s = &w->scene;
    if (s->basis != SCENE_BASIS_CATMULL_ROM)
        return;
    double bytes = (double)s->vertex_count * 16.0 + (double)s->segment_count * 4.0;
    printf("curves: Catmull-Rom, %zu control points shared along the strands (%.4f a segment), %.1f MB of points and "
           "indices (%.2f bytes a segment), generated in %.2f s; every row reads these buffers: hairobb with the basis "
           "set (the Bezier copy unless 'no copy'), Embree as Catmull-Rom curves of its type\n",
           s->vertex_count, (double)s->vertex_count / (double)s->segment_count, bytes / 1048576.0,
           bytes / (double)s->segment_count, w->scene_seconds);
}

static void print_rss_row(const char *step, const rss_step *r)
{
    printf("%-30s %-10.1f %-10.1f %-10.1f\n", step, (double)r->before / 1048576.0, (double)r->after / 1048576.0,
           (double)r->peak / 1048576.0);
}

/* The process's resident memory over each step of the scene, and the
   scene's peak: what a machine needs to run it. */
static void print_memory_table(const workload *w, const scene_result *sr)
{
    size_t peak = 0;
    const rss_step *steps[] = {&w->scene_rss, &w->reference_rss, &w->default_build_rss, &w->trace_rss};
    printf("\nprocess memory, MB (RSS before and after each step, and its peak: VmHWM, %s)\n",
           rss_peak_reset_works ? "reset at the step's start" : "not resettable here: the process's peak so far");
    printf("%-30s %-10s %-10s %-10s\n", "step", "before", "after", "peak");
    print_rss_row("scene generated/loaded", &w->scene_rss);
    if (w->has_accuracy)
        print_rss_row("accuracy reference", &w->reference_rss);
    for (int i = 0; i < VARIANT_COUNT; i++) {
        const variant_result *r = &sr->variants[i];
        char step[64];
        if (!sr->selected[i] || !r->measured)
            continue;
        snprintf(step, sizeof step, "build %s", all_variants[i].label);
        print_rss_row(step, &r->build_rss);
        peak = r->build_rss.peak > peak ? r->build_rss.peak : peak;
    }
    /* the BVH that spawned the secondary rays, when its row was not run */
    if (w->default_build_rss.peak && !sr->variants[spawn_variant(&w->scene)].measured)
        print_rss_row("build for secondary rays", &w->default_build_rss);
    print_rss_row("tracing (timed rounds)", &w->trace_rss);
    for (size_t k = 0; k < sizeof steps / sizeof steps[0]; k++)
        peak = steps[k]->peak > peak ? steps[k]->peak : peak;
    printf("peak over the scene: %.1f MB (%.1f bytes a segment)\n", (double)peak / 1048576.0,
           (double)peak / (double)sr->segment_count);
    for (int i = 0; i < VARIANT_COUNT; i++)
        if (sr->selected[i] && sr->variants[i].skipped[0])
            printf("%s: skipped, %s\n", all_variants[i].label, sr->variants[i].skipped);
    if (w->accuracy_skipped[0])
        printf("accuracy: skipped, %s\n", w->accuracy_skipped);
}

/* ======================================================================== */
/* TSV and chart                                                            */
/* ======================================================================== */

static void tsv_number(FILE *f, const char *format, double value)
{
    if (isfinite(value))
        fprintf(f, format, value);
    else
        fputs("\tNaN", f); /* gnuplot skips NaN */
}

/* The accuracy columns of a TSV row: rays, disagreements, their percentage,
   |dt| median, p99 and max, |du| median and p99 (NULL: not measured). */
static void tsv_accuracy(FILE *f, const accuracy_summary *a)
{
    if (!a) {
        fputs("\t0\t0\tNaN\tNaN\tNaN\tNaN\tNaN\tNaN", f);
        return;
    }
    fprintf(f, "\t%zu\t%zu", a->rays, a->disagreements);
    tsv_number(f, "\t%.6g", disagreement_percent(a));
    tsv_number(f, "\t%.6g", a->t_median);
    tsv_number(f, "\t%.6g", a->t_p99);
    tsv_number(f, "\t%.6g", a->t_max);
    tsv_number(f, "\t%.6g", a->u_median);
    tsv_number(f, "\t%.6g", a->u_p99);
}

static FILE *tsv_open(const options *o)
{
    FILE *f = fopen(o->tsv_path, "w");
    if (!f) {
        fprintf(stderr, "bench: cannot write %s: %s\n", o->tsv_path, strerror(errno));
        return NULL;
    }
    fputs("scene\tsegments\tvariant\tlabel\tlibrary\tnodes\tprecision\tcurve_pieces\tembree_rate"
          "\tbuild_s\tmemory_bytes\tbytes_per_segment\tbuild_transient_bytes\ttransient_bytes_per_segment\taabb_nodes\tobb_nodes\tleaves\tleaf_references\tmax_depth",
          f);
    for (int k = 0; k < RAY_KIND_COUNT; k++)
        fprintf(f, "\t%s_rays", ray_kind_names[k]);
    for (int k = 0; k < RAY_KIND_COUNT; k++)
        for (int t = 0; t < o->thread_count_count; t++)
            fprintf(f, "\t%s_mrays_%ut", ray_kind_names[k], o->thread_counts[t]);
    fputs("\taccuracy_rays\tdisagreements\tdisagree_pct\tdt_r_median\tdt_r_p99\tdt_r_max\tdu_median\tdu_p99"
          "\taccuracy_comparable\tchart_series",
          f);
    /* the spread over the rounds, and the within-round ratios to Embree flat r4 */
    for (int k = 0; k < RAY_KIND_COUNT; k++)
        for (int t = 0; t < o->thread_count_count; t++)
            fprintf(f, "\t%s_mrays_%ut_min\t%s_mrays_%ut_max\t%s_ratio_%ut\t%s_ratio_%ut_min\t%s_ratio_%ut_max",
                    ray_kind_names[k], o->thread_counts[t], ray_kind_names[k], o->thread_counts[t], ray_kind_names[k],
                    o->thread_counts[t], ray_kind_names[k], o->thread_counts[t], ray_kind_names[k], o->thread_counts[t]);
    fputs("\n", f);
    return f;
}

static void tsv_write_scene(FILE *f, const options *o, const scene_result *sr, const int selected[VARIANT_COUNT])
{
    static const char *const node_names[] = {"mixed", "aabb", "obb"};
    for (int i = 0; i < VARIANT_COUNT; i++) {
        const variant *v = &all_variants[i];
        const variant_result *r = &sr->variants[i];
        if (!selected[i] || !r->measured)
            continue;
        int hairobb = v->lib == LIB_HAIROBB;
        fprintf(f, "%s\t%zu\t%s\t%s\t%s\t%s\t%s\t%u\t%d", sr->name, sr->segment_count, v->key, v->label,
                hairobb ? "hairobb" : "embree", hairobb ? node_names[v->nodes] : "-",
                hairobb ? (v->precision == HAIROBB_PRECISION_EXACT ? "exact" : "pieces")
                        : (v->embree_type == EMB_FLAT_BEZIER ? "flat" : "round"),
                v->curve_pieces, v->embree_rate);
        fprintf(f, "\t%.6f\t%zu\t%.3f", r->build_seconds, r->memory_bytes, (double)r->memory_bytes / (double)sr->segment_count);
        if (hairobb)
            fprintf(f, "\t%zu\t%.3f", r->build_transient_bytes, (double)r->build_transient_bytes / (double)sr->segment_count);
        else
            fputs("\tNaN\tNaN", f);
        fprintf(f, "\t%zu\t%zu\t%zu\t%zu\t%u", r->stats.aabb_nodes, r->stats.obb_nodes,
                r->stats.leaves, r->stats.leaf_references, r->stats.max_depth);
        for (int k = 0; k < RAY_KIND_COUNT; k++)
            fprintf(f, "\t%zu", sr->ray_counts[k]);
        for (int k = 0; k < RAY_KIND_COUNT; k++)
            for (int t = 0; t < o->thread_count_count; t++)
                tsv_number(f, "\t%.4f", r->mrays[k][t].median);
        tsv_accuracy(f, r->has_accuracy ? &r->accuracy : NULL);
        fprintf(f, "\t%d\t%s", variant_comparable(v, sr->basis), v->on_chart ? (hairobb ? "hairobb" : "embree") : "-");
        for (int k = 0; k < RAY_KIND_COUNT; k++)
            for (int t = 0; t < o->thread_count_count; t++) {
                tsv_number(f, "\t%.4f", r->mrays[k][t].min);
                tsv_number(f, "\t%.4f", r->mrays[k][t].max);
                tsv_number(f, "\t%.4f", r->ratio[k][t].median);
                tsv_number(f, "\t%.4f", r->ratio[k][t].min);
                tsv_number(f, "\t%.4f", r->ratio[k][t].max);
            }
        fputs("\n", f);
    }
    fflush(f);
}

/* A scene gets a row of the chart if some variant of the chart has both a
   speed and an accuracy: the gnuplot script needs points to set its axes. */
static int has_chart_points(const scene_result *sr, const int selected[VARIANT_COUNT])
{
    for (int i = 0; i < VARIANT_COUNT; i++) {
        const variant_result *r = &sr->variants[i];
        if (sr->loaded && selected[i] && all_variants[i].on_chart && r->has_accuracy &&
            isfinite(r->mrays[RAYS_PRIMARY][0].median))
            return 1;
    }
    return 0;
}

/* Returns the path of an executable named `name` on PATH, in `found`. */
static int find_on_path(const char *name, char *found, size_t size)
{
    const char *path = getenv("PATH");
    while (path && *path) {
        size_t length = strcspn(path, ":");
        snprintf(found, size, "%.*s/%s", (int)length, path, name);
        if (length > 0 && access(found, X_OK) == 0)
            return 1;
        path += length + (path[length] == ':');
    }
    return 0;
}

/* Draws the chart with gnuplot (run directly, no shell, so paths need no
   quoting beyond gnuplot's own). Returns a note for the tables. */
static const char *draw_chart(const options *o, const scene_result *results, int scene_count,
                              const int selected[VARIANT_COUNT], char *note, size_t note_size)
{
    char gnuplot[4096], variables[4096], scenes[1024] = "";
    for (int s = 0; s < scene_count; s++)
        if (has_chart_points(&results[s], selected) && strlen(scenes) + strlen(results[s].name) + 2 < sizeof scenes)
            snprintf(scenes + strlen(scenes), sizeof scenes - strlen(scenes), "%s%s", *scenes ? " " : "",
                     results[s].name);
    if (!find_on_path("gnuplot", gnuplot, sizeof gnuplot)) {
        snprintf(note, note_size, "gnuplot not on PATH: no chart drawn");
        return note;
    }
    if (!*scenes) {
        snprintf(note, note_size, "no chart: it needs primary rays, accuracy rays and a precision or Embree flat "
                                  "variant");
        return note;
    }
    if (access(o->plot_script, R_OK) != 0) {
        snprintf(note, note_size, "no chart: cannot read %s (run from the repository root or pass --plot-script)",
                 o->plot_script);
        return note;
    }
    snprintf(variables, sizeof variables, "tsv='%s'; out='%s'; scenes='%s'; speed='primary_mrays_%ut'; threads=%u",
             o->tsv_path, o->png_path, scenes, o->thread_counts[0], o->thread_counts[0]);
    fflush(stdout);
    pid_t child = fork();
    if (child == 0) {
        execl(gnuplot, "gnuplot", "-e", variables, o->plot_script, (char *)NULL);
        _exit(127);
    }
    int status = 0;
    if (child < 0 || waitpid(child, &status, 0) < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
        snprintf(note, note_size, "gnuplot failed: no chart");
    else
        snprintf(note, note_size, "chart: %s", o->png_path);
    return note;
}

/* ======================================================================== */
/* Machine description                                                      */
/* ======================================================================== */

/* "model name (family F, model M), AVX-512: yes|no" from /proc/cpuinfo:
   the family tells Zen 3 (25) from Zen 5 (26); machines here differ. */
static void cpu_model(char *model, size_t size)
{
    static char line[16384]; /* the flags line is long */
    char name[256] = "unknown";
    int family = -1, number = -1, avx512 = -1;
    FILE *f = fopen("/proc/cpuinfo", "r");
    if (f) {
        while (fgets(line, sizeof line, f)) {
            const char *value = strchr(line, ':');
            if (!value)
                continue;
            value += 1 + strspn(value + 1, " \t");
            if (strncmp(line, "model name", 10) == 0)
                snprintf(name, sizeof name, "%.*s", (int)strcspn(value, "\n"), value);
            else if (strncmp(line, "cpu family", 10) == 0 && family < 0)
                family = atoi(value);
            else if (strncmp(line, "model", 5) == 0 && (line[5] == ' ' || line[5] == '\t') && number < 0)
                number = atoi(value);
            else if (strncmp(line, "flags", 5) == 0 && avx512 < 0) {
                avx512 = strstr(value, "avx512f") != NULL;
                break;
            }
        }
        fclose(f);
    }
    snprintf(model, size, "%s (family %d, model %d), AVX-512: %s", name, family, number,
             avx512 < 0 ? "unknown" : avx512 ? "yes" : "no");
}

static void print_machine(const options *o)
{
    char model[256], date[64], threads[64] = "";
    time_t now = time(NULL);
    struct tm local;
    cpu_model(model, sizeof model);
    strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S %Z", localtime_r(&now, &local));
    for (int t = 0; t < o->thread_count_count; t++)
        snprintf(threads + strlen(threads), sizeof threads - strlen(threads), "%s%u", t ? ", " : "",
                 o->thread_counts[t]);
    printf("hairobb benchmark, %s\n", date);
    printf("cpu: %s, %ld logical cores; threads measured: %s\n", model, sysconf(_SC_NPROCESSORS_ONLN), threads);
#if defined(__VERSION__) && defined(__GNUC__) && !defined(__clang__)
    printf("compiler: gcc %s", __VERSION__); /* gcc's __VERSION__ is the bare number */
#elif defined(__VERSION__)
    printf("compiler: %s", __VERSION__);
#else
    printf("compiler: unknown");
#endif
#ifdef BENCH_CFLAGS
    printf(", flags: %s", BENCH_CFLAGS);
#else
    printf(", flags: see Makefile (the $(B)/bench rule)");
#endif
    printf(", SIMD: %s\n", simd_paths());
    if (o->profile)
        printf("hairobb %d.%d.%d, Embree %s; profile: one untimed pass of each variant over each ray set, 1 thread\n",
               HAIROBB_VERSION_MAJOR, HAIROBB_VERSION_MINOR, HAIROBB_VERSION_PATCH, RTC_VERSION_STRING);
    else
        printf("hairobb %d.%d.%d, Embree %s; %d timing round%s (every variant one pass a round, after a warm-up pass); "
               "blocks of %d rays interleaved across threads\n",
               HAIROBB_VERSION_MAJOR, HAIROBB_VERSION_MINOR, HAIROBB_VERSION_PATCH, RTC_VERSION_STRING, o->rounds,
               o->rounds == 1 ? "" : "s", RAY_BLOCK);
    /* other work on the machine skews the figures, the threaded ones most */
    double load[3];
    FILE *f = fopen("/proc/loadavg", "r");
    if (f && fscanf(f, "%lf %lf %lf", &load[0], &load[1], &load[2]) == 3)
        printf("load average before the run: %.2f %.2f %.2f (1, 5, 15 min)\n", load[0], load[1], load[2]);
    if (f)
        fclose(f);
    /* the file scenes, for --scene straight,furball: found, or what to get */
    const char *path;
    char why[TEST_DATA_WHY_SIZE];
    if (o->straight_path || test_data_straight_hair(&path, why) == TEST_DATA_FOUND)
        printf("data: straight.hair at %s (--scene straight)\n", o->straight_path ? o->straight_path : path);
    else
        printf("data: --scene straight would be skipped: %s\n", why);
}

/* ======================================================================== */
/* Command line                                                             */
/* ======================================================================== */

static void print_help(void)
{
    printf("usage: build/bench [options]   (run from the repository root)\n"
           "  --scene LIST        scenes, comma list or repeated (default combed):\n"
           "                      combed, curly, random, crossing (procedural), straight (--straight-path),\n"
           "                      furball (Embree's furBall_A, skipped if absent), or a PATH.hair file;\n"
           "                      yeti: Yeti-class fur on a capsule, Catmull-Rom strands of 16 segments\n"
           "                        holding 19 shared points (1.19 a segment), run by default with the yeti\n"
           "                        group (with --variants, every row reads its Catmull-Rom curves); builds\n"
           "                        and the reference that would not fit in MemAvailable are skipped, said so;\n"
           "                        the paper's size: --scene yeti --segments 153M --rays primary,incoherent\n"
           "  --segments N        segments of procedural scenes (default %d; k and M suffixes allowed)\n"
           "  --res N             primary rays: N x N pinhole camera framing the hair (default %d)\n"
           "  --rays LIST         ray sets: primary, incoherent, shadow (default all)\n"
           "  --threads LIST      thread counts, e.g. 1,8 (default 1 and the number of cores)\n"
           "  --variants LIST     variants or groups (default all):\n"
           "                      hairobb: default (= mixed), exact4, exact16, pieces4, pieces8, pieces16,\n"
           "                        aabb, obb, mixed-uncompressed, spatial, spatial-compressed,\n"
           "                        spatial-compressed-cluster, shared, compressed-shared,\n"
           "                        build-1t (defaults built on 1 thread), filter (a hit filter taking every hit),\n"
           "                        sse2 (the SSE2 kernels, where the build has them: not with -mavx2 or -march)\n"
           "                        catmull-rom, catmull-rom-copy (Catmull-Rom basis, without and with the Bezier\n"
           "                        copy: on Bezier scenes other curves through the same points),\n"
           "                        b-spline, b-spline-copy (the same for the uniform B-spline basis)\n"
           "                      Embree: embree-r4, embree-r8, embree-r16 (flat), embree-round\n"
           "                      groups: all, hairobb, embree, precision, ablation, bases,\n"
           "                        yeti (catmull-rom: hairobb C-R without the Bezier copy, embree-r4, embree-round)\n"
           "  --rounds N          timing rounds, one pass of every variant each, after a warm-up pass;\n"
           "                      medians and [min-max] reported (default %d, 1..64; --passes: the same)\n"
           "  --accuracy-rays N   primary rays checked against the reference, 0 = none (default %d)\n"
           "  --memory-mb N       builds and the reference whose estimated memory exceeds 0.9 of what is\n"
           "                      available are skipped: N MB less this process's RSS (default MemAvailable)\n"
           "  --tsv FILE          every figure, one row per scene and variant (default %s)\n"
           "  --png FILE          run time against error chart, drawn by gnuplot if present (default %s)\n"
           "  --plot-script FILE  gnuplot script (default %s)\n"
           "  --straight-path P   file of the 'straight' scene (default $" TEST_DATA_STRAIGHT_HAIR_VARIABLE ",\n"
           "                      else %s; skipped if absent)\n"
           "  --furball-path P    furBall_A.bin.gz (default %s)\n"
           "  --animate N         only an animation: combed fur (--segments) swaying over N frames, a BVH\n"
           "                      refitted frame to frame against one built afresh: refit and build s,\n"
           "                      primary Mrays/s of both (--res, --rounds, the first --threads), SAH ratios\n"
           "                      (TSV: --tsv, one row a frame)\n"
           "  --quiet             no progress on stderr (shown only when stderr is a terminal)\n"
           "  --profile           no timing: one pass of each variant over each ray set on 1 thread,\n"
           "                      a callgrind dump each (valgrind --collect-atstart=no), and a line\n"
           "                      'profile' with the work per ray (bench/profile.sh: make profile)\n"
           "  --save-load LIST    only this: combed scenes of these segment counts (e.g. 1M,10M), each\n"
           "                      built (all cores), saved and loaded in memory --rounds times: bytes per\n"
           "                      segment, build, save and load seconds (with the hair check, and without)\n",
           DEFAULT_SEGMENTS, DEFAULT_RESOLUTION, DEFAULT_ROUNDS, DEFAULT_ACCURACY_RAYS, DEFAULT_TSV_PATH,
           DEFAULT_PNG_PATH, DEFAULT_PLOT_SCRIPT, TEST_DATA_STRAIGHT_HAIR_DEFAULT, SCENE_FURBALL_DEFAULT_PATH);
    /* two strings: C99 compilers need support only 4095 characters in one */
    printf("  --builds            only build time: for each --scene, --rounds rounds of hairobb's defaults on all\n"
           "                      cores, on 1 thread, and Embree flat r4 on all cores (Catmull-Rom scenes: both\n"
           "                      read the Catmull-Rom curves), each freed before the next; medians [min-max] of\n"
           "                      the seconds and of the ratios to Embree within each round\n"
           "  --motion            only motion blur against Embree: combed fur (--segments) rotating about each\n"
           "                      root (0.5 rad) or translating (0.05, 0.2), at 2 and 4 time steps, and static;\n"
           "                      hairobb's defaults and Embree flat r4 (rtcSetGeometryTimeStepCount) on the same\n"
           "                      arrays: build s, bytes/segment, primary and incoherent Mrays/s at random ray\n"
           "                      times (--res, --rounds, --threads), accuracy at 8 times (--accuracy-rays),\n"
           "                      TSV (--tsv, one row a motion and library)\n"
           "  --help              this text\n");
}

/* Parses a count with an optional k or M suffix; 0 on success. */
static int parse_count(const char *text, size_t *value)
{
    char *end;
    errno = 0;
    double number = strtod(text, &end);
    if (*end == 'k' || *end == 'K')
        number *= 1e3, end++;
    else if (*end == 'm' || *end == 'M')
        number *= 1e6, end++;
    if (errno || end == text || *end != '\0' || !(number >= 0.0) || number > 4e9)
        return 1;
    *value = (size_t)(number + 0.5);
    return 0;
}

static int add_scenes(options *o, const char *list)
{
    char *copy = (char *)malloc(strlen(list) + 1);
    if (!copy)
        return 1;
    strcpy(copy, list);
    /* names are kept for the whole run; the copy is never freed */
    char *rest = NULL;
    for (char *name = strtok_r(copy, ",", &rest); name; name = strtok_r(NULL, ",", &rest)) {
        if (o->scene_count == MAX_SCENES) {
            fprintf(stderr, "bench: at most %d scenes\n", MAX_SCENES);
            return 1;
        }
        o->scenes[o->scene_count++] = name;
    }
    return 0;
}

static int parse_ray_kinds(options *o, const char *list)
{
    char buffer[256];
    snprintf(buffer, sizeof buffer, "%s", list);
    memset(o->ray_kind_enabled, 0, sizeof o->ray_kind_enabled);
    char *rest = NULL;
    for (char *name = strtok_r(buffer, ",", &rest); name; name = strtok_r(NULL, ",", &rest)) {
        int found = 0;
        for (int k = 0; k < RAY_KIND_COUNT; k++)
            if (strcmp(name, ray_kind_names[k]) == 0)
                o->ray_kind_enabled[k] = found = 1;
        if (!found)
            return 1;
    }
    return 0;
}

static int parse_thread_counts(options *o, const char *list)
{
    char buffer[256];
    snprintf(buffer, sizeof buffer, "%s", list);
    o->thread_count_count = 0;
    char *rest = NULL;
    for (char *item = strtok_r(buffer, ",", &rest); item; item = strtok_r(NULL, ",", &rest)) {
        size_t count;
        if (parse_count(item, &count) != 0 || count < 1 || count > 256 || o->thread_count_count == MAX_THREAD_COUNTS)
            return 1;
        o->thread_counts[o->thread_count_count++] = (unsigned)count;
    }
    return o->thread_count_count == 0;
}

static void default_options(options *o)
{
    memset(o, 0, sizeof *o);
    o->segments = DEFAULT_SEGMENTS;
    o->resolution = DEFAULT_RESOLUTION;
    for (int k = 0; k < RAY_KIND_COUNT; k++)
        o->ray_kind_enabled[k] = 1;
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    o->thread_counts[o->thread_count_count++] = 1;
    if (cores > 1)
        o->thread_counts[o->thread_count_count++] = (unsigned)(cores < 256 ? cores : 256);
    o->variant_list = "all";
    o->rounds = DEFAULT_ROUNDS;
    o->accuracy_rays = DEFAULT_ACCURACY_RAYS;
    o->tsv_path = DEFAULT_TSV_PATH;
    o->png_path = DEFAULT_PNG_PATH;
    o->plot_script = DEFAULT_PLOT_SCRIPT;
    o->straight_path = NULL; /* tests/test_data.h's rule */
    o->furball_path = NULL;
}

/* Returns 0 to run, 1 on a usage error, 2 after --help. */
static int parse_options(int argc, char **argv, options *o)
{
    default_options(o);
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i], *value = NULL;
        char name[64];
        size_t length = strcspn(arg, "=");
        snprintf(name, sizeof name, "%.*s", (int)length, arg);
        if (arg[length] == '=')
            value = arg + length + 1;
        if (strcmp(name, "--help") == 0 || strcmp(name, "-h") == 0) {
            print_help();
            return 2;
        }
        if (strcmp(name, "--quiet") == 0) {
            o->quiet = 1;
            continue;
        }
        if (strcmp(name, "--profile") == 0) {
            o->profile = 1;
            continue;
        }
        if (strcmp(name, "--motion") == 0) {
            o->motion = 1;
            continue;
        }
        if (strcmp(name, "--builds") == 0) {
            o->builds = 1;
            continue;
        }
        if (!value) {
            if (i + 1 >= argc) {
                fprintf(stderr, "bench: %s needs a value (see --help)\n", name);
                return 1;
            }
            value = argv[++i];
        }
        size_t count = 0;
        int bad = 0;
        if (strcmp(name, "--scene") == 0)
            bad = add_scenes(o, value);
        else if (strcmp(name, "--segments") == 0)
            bad = parse_count(value, &o->segments) || o->segments == 0;
        else if (strcmp(name, "--res") == 0) {
            bad = parse_count(value, &count) || count < 1 || count > 16384;
            o->resolution = (int)count;
        } else if (strcmp(name, "--rays") == 0)
            bad = parse_ray_kinds(o, value);
        else if (strcmp(name, "--threads") == 0)
            bad = parse_thread_counts(o, value);
        else if (strcmp(name, "--variants") == 0) {
            o->variant_list = value;
            o->variants_given = 1;
        } else if (strcmp(name, "--rounds") == 0 || strcmp(name, "--passes") == 0) {
            bad = parse_count(value, &count) || count < 1 || count > MAX_ROUNDS;
            o->rounds = (int)count;
        } else if (strcmp(name, "--accuracy-rays") == 0)
            bad = parse_count(value, &o->accuracy_rays);
        else if (strcmp(name, "--memory-mb") == 0)
            bad = parse_count(value, &o->memory_mb) || o->memory_mb == 0;
        else if (strcmp(name, "--tsv") == 0)
            o->tsv_path = value;
        else if (strcmp(name, "--png") == 0)
            o->png_path = value;
        else if (strcmp(name, "--plot-script") == 0)
            o->plot_script = value;
        else if (strcmp(name, "--straight-path") == 0)
            o->straight_path = value;
        else if (strcmp(name, "--furball-path") == 0)
            o->furball_path = value;
        else if (strcmp(name, "--animate") == 0) {
            bad = parse_count(value, &count) || count < 1 || count > 100000;
            o->animate_frames = (int)count;
        } else if (strcmp(name, "--save-load") == 0) {
            char list[256], *item, *rest = NULL;
            snprintf(list, sizeof list, "%s", value);
            o->save_load_count = 0;
            for (item = strtok_r(list, ",", &rest); item && !bad; item = strtok_r(NULL, ",", &rest)) {
                bad = o->save_load_count == MAX_SAVE_LOAD || parse_count(item, &count) || count == 0;
                if (!bad)
                    o->save_load_segments[o->save_load_count++] = count;
            }
            bad = bad || o->save_load_count == 0;
        } else {
            fprintf(stderr, "bench: unknown option %s (see --help)\n", name);
            return 1;
        }
        if (bad) {
            fprintf(stderr, "bench: bad value '%s' for %s (see --help)\n", value, name);
            return 1;
        }
    }
    if (o->scene_count == 0)
        o->scenes[o->scene_count++] = "combed";
    return 0;
}

/* ======================================================================== */
/* --animate N: refit against rebuild over an animation                     */
/* ======================================================================== */

/* Frame f of n of the combed fur swaying about its roots: each control
   point turned about the y axis, and tilted about the x axis, by angles
   that grow from 0 at the root (radius 1) to the tip (about 1.5) and swing
   with the frame; the roots stay. */
static void sway_pose(const hair_scene *rest, int frame, int frames, float *out)
{
    float phase = 6.2831853f * (float)frame / (float)frames;
    float swing = 0.6f * sinf(phase), tilt = 0.25f * sinf(2.0f * phase);
    for (size_t i = 0; i < rest->vertex_count; i++) {
        const float *p = rest->vertices + 4 * i;
        float *q = out + 4 * i;
        float along = (sqrtf(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 1.0f) / 0.5f;
        float a = swing * along, b = tilt * along;
        float x = cosf(a) * p[0] + sinf(a) * p[2], z = -sinf(a) * p[0] + cosf(a) * p[2];
        q[0] = x;
        q[1] = cosf(b) * p[1] - sinf(b) * z;
        q[2] = sinf(b) * p[1] + cosf(b) * z;
        q[3] = p[3];
    }
}

/* Built on the rest pose, then for each frame: the BVH refitted from the
   frame before, against one built afresh on the frame; both on all cores
   (the build's default threads), traced on the first --threads count in
   rounds (refitted, fresh, refitted, ...). */
static int run_animation(const options *o, int frames)
{
    hair_scene rest;
    char why[TEST_DATA_WHY_SIZE];
    if (load_scene(o, "combed", &rest, why) != 0) {
        fprintf(stderr, "bench: the combed scene could not be made\n");
        return 1;
    }
    ray_set rays;
    float *pose = (float *)malloc(16 * rest.vertex_count);
    hit_record *hits = (hit_record *)malloc(sizeof(hit_record) * (size_t)o->resolution * (size_t)o->resolution);
    if (!pose || !hits || primary_rays(&rest, o->resolution, &rays) != 0) {
        fprintf(stderr, "bench: out of memory\n");
        return 1;
    }
    unsigned trace_threads = o->thread_counts[0];
    hairobb_build_options build_options;
    memset(&build_options, 0, sizeof build_options);
    build_options.allocator_user = &hairobb_meter;
    memcpy(pose, rest.vertices, 16 * rest.vertex_count);
    hairobb_bvh *refitted = NULL;
    if (hairobb_build(pose, rest.vertex_count, rest.indices, rest.segment_count, &build_options, &refitted) != HAIROBB_OK) {
        fprintf(stderr, "bench: build failed\n");
        return 1;
    }
    FILE *tsv = fopen(o->tsv_path, "w");
    if (tsv)
        fprintf(tsv, "frame\tsegments\trefit_s\tbuild_s\trefit_over_build\tmrays_refitted\tmrays_fresh\t"
                     "speed_refitted_over_fresh\tsah_refitted_over_as_built\tsah_refitted_over_fresh\n");
    printf("\n=== animation: combed, %zu segments, %d frames swaying about the roots; refit and build on all cores, "
           "%dx%d primary rays on %u thread%s, %d rounds\n",
           rest.segment_count, frames, o->resolution, o->resolution, trace_threads, trace_threads == 1 ? "" : "s", o->rounds);
    printf("frame  refit s    build s    refit/build  Mrays/s refitted  Mrays/s fresh  refitted/fresh  SAH/as built  SAH/fresh\n");
    double ratio_sum = 0.0;
    int failures = 0;
    for (int f = 1; f <= frames; f++) {
        sway_pose(&rest, f, frames, pose);
        double start = scene_now();
        hairobb_result refit_result = hairobb_refit(refitted, pose);
        double refit_seconds = scene_now() - start;
        hairobb_bvh *fresh = NULL;
        start = scene_now();
        hairobb_result build_result = hairobb_build(pose, rest.vertex_count, rest.indices, rest.segment_count, &build_options, &fresh);
        double build_seconds = scene_now() - start;
        if (refit_result != HAIROBB_OK || build_result != HAIROBB_OK) {
            fprintf(stderr, "bench: frame %d: refit %s, build %s\n", f, hairobb_result_string(refit_result),
                    hairobb_result_string(build_result));
            hairobb_free(fresh);
            failures++;
            break;
        }
        tracer t[2] = {hairobb_tracer(refitted), hairobb_tracer(fresh)};
        double mrays[2][MAX_ROUNDS], ratios[MAX_ROUNDS];
        for (int k = 0; k < 2; k++)
            trace_pass(&t[k], &rays, hits, trace_threads); /* warm-up */
        for (int r = 0; r < o->rounds; r++) {
            for (int k = 0; k < 2; k++)
                mrays[k][r] = (double)rays.count / trace_pass(&t[k], &rays, hits, trace_threads) * 1e-6;
            ratios[r] = mrays[0][r] / mrays[1][r];
        }
        spread refit_rate = spread_of(mrays[0], o->rounds), fresh_rate = spread_of(mrays[1], o->rounds);
        spread speed_ratio = spread_of(ratios, o->rounds);
        hairobb_stats refit_stats, fresh_stats;
        hairobb_get_stats(refitted, &refit_stats);
        hairobb_get_stats(fresh, &fresh_stats);
        double sah_as_built = refit_stats.sah_cost / refit_stats.build_sah_cost;
        double sah_fresh = refit_stats.sah_cost / fresh_stats.sah_cost;
        ratio_sum += refit_seconds / build_seconds;
        printf("%5d  %-9.4f  %-9.4f  %-11.3f  %-16.2f  %-13.2f  %-14.3f  %-12.3f  %.3f\n", f, refit_seconds, build_seconds,
               refit_seconds / build_seconds, refit_rate.median, fresh_rate.median, speed_ratio.median, sah_as_built, sah_fresh);
        if (tsv)
            fprintf(tsv, "%d\t%zu\t%.6f\t%.6f\t%.4f\t%.4f\t%.4f\t%.4f\t%.4f\t%.4f\n", f, rest.segment_count, refit_seconds,
                    build_seconds, refit_seconds / build_seconds, refit_rate.median, fresh_rate.median, speed_ratio.median,
                    sah_as_built, sah_fresh);
        hairobb_free(fresh);
    }
    printf("mean refit/build time over the frames: %.3f\n", ratio_sum / frames);
    if (tsv) {
        fclose(tsv);
        printf("TSV: %s\n", o->tsv_path);
    }
    hairobb_free(refitted);
    ray_set_free(&rays);
    free(hits);
    free(pose);
    scene_free(&rest);
    return failures ? 1 : 0;
}

/* ======================================================================== */
/* Save and load against build                                              */
/* ======================================================================== */

/* --save-load: what a renderer saves by loading a saved BVH instead of
   building it. Per round: a build (default options, all cores), a save into
   memory, a load with the hair check and one without (both from memory,
   nothing of disks in the figures); the loaded BVH must trace as the built
   one (a 64 x 64 camera, compared to the bit). Medians and [min-max]. */
static int save_load_bench(const options *o)
{
    int failures = 0;
    printf("\nsave and load against build: combed, default options, all cores, %d rounds\n", o->rounds);
    printf("%12s %10s %20s %20s %20s %20s %10s\n", "segments", "bytes/seg", "build s", "save s", "load s", "load unchecked s",
           "build/load");
    for (int c = 0; c < o->save_load_count; c++) {
        hair_scene s;
        double build_s[MAX_ROUNDS], save_s[MAX_ROUNDS], load_s[MAX_ROUNDS], unchecked_s[MAX_ROUNDS];
        size_t size = 0;
        int ok = 1;
        progress_start("save/load: combed %zu segments", o->save_load_segments[c]);
        if (scene_combed(&s, o->save_load_segments[c], 1) != 0) {
            progress("out of memory");
            ++failures;
            continue;
        }
        for (int r = 0; r < o->rounds && ok; r++) {
            hairobb_bvh *built = NULL, *loaded = NULL, *unchecked = NULL;
            hairobb_build_options skip;
            unsigned char *blob = NULL;
            double t0 = scene_now();
            ok = hairobb_build(s.vertices, s.vertex_count, s.indices, s.segment_count, NULL, &built) == HAIROBB_OK;
            double t1 = scene_now();
            size = hairobb_save_size(built);
            ok = ok && (blob = (unsigned char *)malloc(size)) != NULL;
            double t2 = scene_now();
            ok = ok && hairobb_save(built, blob, size) == HAIROBB_OK;
            double t3 = scene_now();
            ok = ok && hairobb_load(blob, size, s.vertices, s.vertex_count, s.indices, s.segment_count, NULL, &loaded) == HAIROBB_OK;
            double t4 = scene_now();
            memset(&skip, 0, sizeof skip);
            skip.verify_hair = HAIROBB_OFF;
            ok = ok && hairobb_load(blob, size, s.vertices, s.vertex_count, s.indices, s.segment_count, &skip, &unchecked) == HAIROBB_OK;
            double t5 = scene_now();
            build_s[r] = t1 - t0;
            save_s[r] = t3 - t2;
            load_s[r] = t4 - t3;
            unchecked_s[r] = t5 - t4;
            if (ok && r == 0) {
                enum { SIDE = 64 };
                static float org[3 * SIDE * SIDE], dir[3 * SIDE * SIDE];
                scene_camera_rays(&s, SIDE, SIDE, org, dir);
                for (int i = 0; i < SIDE * SIDE && ok; i++) {
                    hairobb_ray ray = {{org[3 * i], org[3 * i + 1], org[3 * i + 2]}, 0.0f,
                                       {dir[3 * i], dir[3 * i + 1], dir[3 * i + 2]}, INFINITY, 0.0f};
                    hairobb_hit a, b;
                    memset(&a, 0, sizeof a);
                    memset(&b, 0, sizeof b);
                    int ga = hairobb_intersect1(built, &ray, &a), gb = hairobb_intersect1(loaded, &ray, &b);
                    ok = ga == gb && memcmp(&a, &b, sizeof a) == 0;
                }
            }
            hairobb_free(unchecked);
            hairobb_free(loaded);
            free(blob);
            hairobb_free(built);
        }
        if (!ok) {
            progress("failed");
            printf("%12zu: build, save or load failed, or the loaded BVH traced otherwise\n", s.segment_count);
            ++failures;
        } else {
            spread b = spread_of(build_s, o->rounds), sv = spread_of(save_s, o->rounds), l = spread_of(load_s, o->rounds);
            spread u = spread_of(unchecked_s, o->rounds);
            char cell[4][32];
            const spread *cells[4] = {&b, &sv, &l, &u};
            for (int k = 0; k < 4; k++)
                snprintf(cell[k], sizeof cell[k], "%.4f [%.4f-%.4f]", cells[k]->median, cells[k]->min, cells[k]->max);
            progress("done");
            printf("%12zu %10.2f %20s %20s %20s %20s %9.1fx\n", s.segment_count, (double)size / (double)s.segment_count, cell[0],
                   cell[1], cell[2], cell[3], b.median / l.median);
        }
        scene_free(&s);
    }
    return failures;
}

/* ======================================================================== */
/* Motion blur against Embree                                               */
/* ======================================================================== */

/* --motion: combed fur (--segments) moving over the frame, given at T time
   steps by scene_motion_steps (rotate: each strand swept about its root's
   normal; translate: every point along (1, 0.5, 0.25)), traced by hairobb's
   defaults (options.time_steps, time_vertices) and by Embree's flat Bezier
   curves at the baseline's rate (rtcSetGeometryTimeStepCount, one shared
   vertex buffer a step: the same arrays), both built on all cores; the
   static scene is the row every moving one is compared with. Rays carry a
   random time each, the same for both libraries. */
typedef struct motion_row {
    const char *label;
    const char *key;     /* the TSV's motion column */
    scene_motion motion;
    double amount;       /* radians (rotate) or scene units (translate) at time 1 */
    int time_steps;      /* 1: the static scene */
} motion_row;

/* Root radii are 0.004 (+-15%) and strands 0.3-0.5 long, lying nearly flat:
   0.5 rad sweeps a tip by about 0.2, translations of 0.05 (12 root radii)
   and 0.2 (as far as the rotation's tips) */
static const motion_row motion_rows[] = {
    {"static", "static", SCENE_MOTION_ROTATE, 0.0, 1},
    {"rotate 0.5 rad", "rotate", SCENE_MOTION_ROTATE, 0.5, 2},
    {"rotate 0.5 rad", "rotate", SCENE_MOTION_ROTATE, 0.5, 4},
    {"translate 0.05", "translate", SCENE_MOTION_TRANSLATE, 0.05, 2},
    {"translate 0.05", "translate", SCENE_MOTION_TRANSLATE, 0.05, 4},
    {"translate 0.2", "translate", SCENE_MOTION_TRANSLATE, 0.2, 2},
    {"translate 0.2", "translate", SCENE_MOTION_TRANSLATE, 0.2, 4},
};
enum {
    MOTION_ROWS = sizeof motion_rows / sizeof motion_rows[0],
    MOTION_MAX_STEPS = 4,
    MOTION_LIBRARIES = 2,   /* hairobb, then Embree */
    MOTION_TIME_GROUPS = 8  /* accuracy rays at times j / 7 */
};
static const char *const motion_library_names[MOTION_LIBRARIES] = {"hairobb", "Embree"};

typedef struct motion_result {
    int measured;
    double build_seconds;
    size_t memory_bytes, build_transient_bytes; /* transient: hairobb only */
    built_accel accel;
    /* primary and incoherent rays; over_embree: hairobb's only */
    spread mrays[RAY_KIND_COUNT][MAX_THREAD_COUNTS], over_embree[RAY_KIND_COUNT][MAX_THREAD_COUNTS],
        over_static[RAY_KIND_COUNT][MAX_THREAD_COUNTS];
    int has_accuracy;
    accuracy_summary accuracy;
} motion_result;

static float motion_group_time(int group)
{
    return (float)group / (float)(MOTION_TIME_GROUPS - 1);
}

/* The accuracy rays (accuracy_pick's), in MOTION_TIME_GROUPS runs of
   consecutive rays, run j at motion_group_time(j), each traced by the
   reference built over the segments at that time (ref_motion_points:
   lerped in double, rounded to float). */
static int motion_accuracy_prepare(const hair_scene *s, float *const *steps, int time_steps, const ray_set *primary,
                                   size_t wanted, unsigned thread_count, accuracy_set *a)
{
    if (accuracy_pick(primary, wanted, a) != 0)
        return 1;
    size_t n = a->rays.count;
    a->rays.time = (float *)malloc((n ? n : 1) * sizeof(float));
    float *at_time = (float *)malloc(4 * s->vertex_count * sizeof(float));
    if (!a->rays.time || !at_time) {
        free(at_time);
        return 1;
    }
    double start = scene_now();
    ref_scene *reference = NULL;
    for (int j = 0; j < MOTION_TIME_GROUPS; j++) {
        size_t first = n * (size_t)j / MOTION_TIME_GROUPS, end = n * (size_t)(j + 1) / MOTION_TIME_GROUPS;
        for (size_t i = first; i < end; i++)
            a->rays.time[i] = motion_group_time(j);
        if (j == 0 || time_steps > 1) { /* a static scene is the same at every time */
            ref_free(reference);
            ref_motion_points((const float *const *)steps, time_steps, motion_group_time(j), 0, 4 * s->vertex_count,
                              at_time);
            reference = ref_build(at_time, s->vertex_count, s->indices, s->segment_count);
            if (!reference) {
                free(at_time);
                return 1;
            }
        }
        reference_trace(reference, a, first, end, thread_count);
    }
    ref_free(reference);
    free(at_time);
    a->seconds = scene_now() - start;
    return 0;
}

static int motion_build(const hair_scene *s, float *const *steps, int time_steps, int library, motion_result *r)
{
    built_accel *b = &r->accel;
    memset(b, 0, sizeof *b);
    if (library == 0) {
        hairobb_build_options build_options;
        memset(&build_options, 0, sizeof build_options);
        build_options.time_steps = (unsigned)time_steps;
        build_options.time_vertices = (const float *const *)steps;
        b->bvh = build_metered(s, time_steps > 1 ? NULL : s->vertices, &build_options, "motion", &r->build_seconds,
                               &r->build_transient_bytes);
        if (!b->bvh)
            return 1;
        r->memory_bytes = hairobb_memory_bytes(b->bvh);
        b->tracer = hairobb_tracer(b->bvh);
    } else {
        int rate = all_variants[variant_index(BASELINE_KEY)].embree_rate;
        if (time_steps > 1)
            b->embree = emb_build_curves_motion((const float *const *)steps, (unsigned)time_steps, s->vertex_count,
                                                s->indices, s->segment_count, EMB_FLAT_BEZIER, rate, 0,
                                                &r->memory_bytes, &r->build_seconds);
        else
            b->embree = emb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, EMB_FLAT_BEZIER, rate,
                                  0, &r->memory_bytes, &r->build_seconds);
        if (!b->embree)
            return 1;
        b->tracer = embree_tracer(b->embree);
    }
    r->measured = 1;
    return 0;
}

/* Every row and library one pass a round, after a warm-up pass each; the
   ratios (hairobb over Embree, a row over the static row of its library)
   taken within each round. */
static void motion_time_in_rounds(const options *o, const ray_set *rays, hit_record *hits,
                                  motion_result results[MOTION_ROWS][MOTION_LIBRARIES])
{
    static double mrays[MOTION_ROWS][MOTION_LIBRARIES][MAX_ROUNDS];
    int k = rays->kind;
    for (int t = 0; t < o->thread_count_count; t++) {
        unsigned threads = o->thread_counts[t];
        progress_start("motion: %s rays, %u thread%s: warm-up", ray_kind_names[k], threads, threads == 1 ? "" : "s");
        for (int row = 0; row < MOTION_ROWS; row++)
            for (int lib = 0; lib < MOTION_LIBRARIES; lib++)
                if (results[row][lib].measured)
                    trace_pass(&results[row][lib].accel.tracer, rays, hits, threads);
        for (int round = 0; round < o->rounds; round++) {
            progress_start("motion: %s rays, %u thread%s: round %d of %d", ray_kind_names[k], threads,
                           threads == 1 ? "" : "s", round + 1, o->rounds);
            for (int row = 0; row < MOTION_ROWS; row++)
                for (int lib = 0; lib < MOTION_LIBRARIES; lib++)
                    if (results[row][lib].measured)
                        mrays[row][lib][round] =
                            (double)rays->count / trace_pass(&results[row][lib].accel.tracer, rays, hits, threads) * 1e-6;
        }
        progress("done");
        for (int row = 0; row < MOTION_ROWS; row++)
            for (int lib = 0; lib < MOTION_LIBRARIES; lib++) {
                motion_result *r = &results[row][lib];
                double over_embree[MAX_ROUNDS], over_static[MAX_ROUNDS];
                int embree = lib == 0 && results[row][1].measured, statics = results[0][lib].measured;
                if (!r->measured)
                    continue;
                for (int round = 0; round < o->rounds; round++) {
                    over_embree[round] = embree ? mrays[row][0][round] / mrays[row][1][round] : NAN;
                    over_static[round] = statics ? mrays[row][lib][round] / mrays[0][lib][round] : NAN;
                }
                r->mrays[k][t] = spread_of(mrays[row][lib], o->rounds);
                r->over_embree[k][t] = spread_of(over_embree, embree ? o->rounds : 0);
                r->over_static[k][t] = spread_of(over_static, statics ? o->rounds : 0);
            }
    }
}

static const char *spread_cell(char *cell, size_t size, spread x)
{
    if (isnan(x.median))
        snprintf(cell, size, "-");
    else
        snprintf(cell, size, "%.2f [%.2f-%.2f]", x.median, x.min, x.max);
    return cell;
}

static void motion_print(const options *o, const hair_scene *s, const ray_set rays[RAY_KIND_COUNT],
                         size_t accuracy_rays, double reference_seconds,
                         motion_result results[MOTION_ROWS][MOTION_LIBRARIES])
{
    char c[5][48];
    printf("\n=== motion blur: combed, %zu segments; hairobb defaults against Embree flat Bezier r%d "
           "(rtcSetGeometryTimeStepCount), the same buffers, both built on all cores\n",
           s->segment_count, all_variants[variant_index(BASELINE_KEY)].embree_rate);
    printf("steps: scene_motion_steps at times k/(T-1); rotate: each strand swept about its root's normal; "
           "translate: along (1, 0.5, 0.25) (root radius 0.004)\n");
    printf("rays: primary %zu (%dx%d pinhole), incoherent %zu (diffuse bounce from the static hairobb's primary hits); "
           "each at a random time in [0, 1], the same for both libraries\n",
           rays[RAYS_PRIMARY].count, o->resolution, o->resolution, rays[RAYS_INCOHERENT].count);
    if (accuracy_rays)
        printf("accuracy: %zu primary rays in %d groups at times j/%d, against the double reference built at each "
               "group's time (reference build + trace %.2f s)\n",
               accuracy_rays, MOTION_TIME_GROUPS, MOTION_TIME_GROUPS - 1, reference_seconds);

    printf("\nbuild and memory (h/E: hairobb / Embree; transient: hairobb's peak beyond its BVH, bytes/segment)\n");
    printf("%-16s %2s %-10s %-10s %-7s %-12s %-12s %-7s %s\n", "motion", "T", "build s h", "build s E", "h/E",
           "bytes/seg h", "bytes/seg E", "h/E", "transient h");
    for (int row = 0; row < MOTION_ROWS; row++) {
        const motion_result *h = &results[row][0], *e = &results[row][1];
        double hb = h->measured ? (double)h->memory_bytes / (double)s->segment_count : NAN;
        double eb = e->measured ? (double)e->memory_bytes / (double)s->segment_count : NAN;
        printf("%-16s %2d %-10.4f %-10.4f %-7.2f %-12.1f %-12.1f %-7.2f %.1f\n", motion_rows[row].label,
               motion_rows[row].time_steps, h->measured ? h->build_seconds : NAN, e->measured ? e->build_seconds : NAN,
               h->build_seconds / e->build_seconds, hb, eb, hb / eb,
               h->measured ? (double)h->build_transient_bytes / (double)s->segment_count : NAN);
    }

    printf("\nMrays/s: median of %d round%s [min-max]; h/E and /static (a row over the static row, the same "
           "library) taken within each round\n", o->rounds, o->rounds == 1 ? "" : "s");
    printf("%-16s %2s %-10s %3s  %-20s %-20s %-18s %-18s %-18s\n", "motion", "T", "rays", "thr", "hairobb", "Embree",
           "h/E", "hairobb/static", "Embree/static");
    for (int k = RAYS_PRIMARY; k <= RAYS_INCOHERENT; k++) {
        if (!o->ray_kind_enabled[k] || rays[k].count == 0)
            continue;
        for (int t = 0; t < o->thread_count_count; t++)
            for (int row = 0; row < MOTION_ROWS; row++) {
                const motion_result *h = &results[row][0], *e = &results[row][1];
                printf("%-16s %2d %-10s %3u  %-20s %-20s %-18s %-18s %-18s\n", motion_rows[row].label,
                       motion_rows[row].time_steps, ray_kind_names[k], o->thread_counts[t],
                       spread_cell(c[0], sizeof c[0], h->mrays[k][t]), spread_cell(c[1], sizeof c[1], e->mrays[k][t]),
                       spread_cell(c[2], sizeof c[2], h->over_embree[k][t]),
                       row ? spread_cell(c[3], sizeof c[3], h->over_static[k][t]) : "",
                       row ? spread_cell(c[4], sizeof c[4], e->over_static[k][t]) : "");
            }
    }

    if (!accuracy_rays)
        return;
    printf("\naccuracy on %zu primary rays against the double-precision reference ribbon at each ray's time\n",
           accuracy_rays);
    printf("%-16s %2s %-8s %-17s %-10s %-10s %-10s %-10s %-10s\n", "motion", "T", "library", "disagree",
           "|dt|/r med", "|dt|/r p99", "|dt|/r max", "|du| med", "|du| p99");
    for (int row = 0; row < MOTION_ROWS; row++)
        for (int lib = 0; lib < MOTION_LIBRARIES; lib++) {
            const motion_result *r = &results[row][lib];
            if (!r->has_accuracy)
                continue;
            const accuracy_summary *a = &r->accuracy;
            snprintf(c[0], sizeof c[0], "%.3f%% (%zu)", disagreement_percent(a), a->disagreements);
            printf("%-16s %2d %-8s %-17s %-10.2e %-10.2e %-10.2e %-10.2e %-10.2e\n", motion_rows[row].label,
                   motion_rows[row].time_steps, motion_library_names[lib], c[0], a->t_median, a->t_p99, a->t_max,
                   a->u_median, a->u_p99);
        }
}

static void motion_tsv(const options *o, const hair_scene *s, motion_result results[MOTION_ROWS][MOTION_LIBRARIES])
{
    static const char *const spreads[] = {"mrays", "over_embree", "over_static"};
    FILE *f = fopen(o->tsv_path, "w");
    if (!f) {
        fprintf(stderr, "bench: cannot write %s: %s\n", o->tsv_path, strerror(errno));
        return;
    }
    fputs("motion\tamount\ttime_steps\tlibrary\tsegments\tbuild_s\tmemory_bytes\tbytes_per_segment\tbuild_transient_bytes",
          f);
    for (int k = RAYS_PRIMARY; k <= RAYS_INCOHERENT; k++)
        for (int t = 0; t < o->thread_count_count; t++)
            for (int x = 0; x < 3; x++)
                fprintf(f, "\t%s_%s_%ut\t%s_%s_%ut_min\t%s_%s_%ut_max", ray_kind_names[k], spreads[x], o->thread_counts[t],
                        ray_kind_names[k], spreads[x], o->thread_counts[t], ray_kind_names[k], spreads[x],
                        o->thread_counts[t]);
    fputs("\taccuracy_rays\tdisagreements\tdisagree_pct\tdt_r_median\tdt_r_p99\tdt_r_max\tdu_median\tdu_p99\n", f);
    for (int row = 0; row < MOTION_ROWS; row++)
        for (int lib = 0; lib < MOTION_LIBRARIES; lib++) {
            const motion_result *r = &results[row][lib];
            if (!r->measured)
                continue;
            fprintf(f, "%s\t%g\t%d\t%s\t%zu\t%.6f\t%zu\t%.3f", motion_rows[row].key, motion_rows[row].amount,
                    motion_rows[row].time_steps, lib ? "embree" : "hairobb", s->segment_count, r->build_seconds,
                    r->memory_bytes, (double)r->memory_bytes / (double)s->segment_count);
            if (lib == 0)
                fprintf(f, "\t%zu", r->build_transient_bytes);
            else
                fputs("\tNaN", f);
            for (int k = RAYS_PRIMARY; k <= RAYS_INCOHERENT; k++)
                for (int t = 0; t < o->thread_count_count; t++) {
                    const spread *x[3] = {&r->mrays[k][t], &r->over_embree[k][t], &r->over_static[k][t]};
                    for (int j = 0; j < 3; j++) {
                        tsv_number(f, "\t%.4f", x[j]->median);
                        tsv_number(f, "\t%.4f", x[j]->min);
                        tsv_number(f, "\t%.4f", x[j]->max);
                    }
                }
            tsv_accuracy(f, r->has_accuracy ? &r->accuracy : NULL);
            fputs("\n", f);
        }
    fclose(f);
    printf("TSV: %s\n", o->tsv_path);
}

static int run_motion(const options *o)
{
    static motion_result results[MOTION_ROWS][MOTION_LIBRARIES];
    float *steps[MOTION_ROWS][MOTION_MAX_STEPS];
    hair_scene s;
    char why[TEST_DATA_WHY_SIZE];
    ray_set rays[RAY_KIND_COUNT];
    int failures = 0;
    memset(results, 0, sizeof results);
    memset(steps, 0, sizeof steps);
    memset(rays, 0, sizeof rays);
    if (load_scene(o, "combed", &s, why) != 0) {
        fprintf(stderr, "bench: the combed scene could not be made\n");
        return 1;
    }
    hit_record *hits = (hit_record *)malloc(sizeof(hit_record) * (size_t)o->resolution * (size_t)o->resolution);
    if (!hits || primary_rays(&s, o->resolution, &rays[RAYS_PRIMARY]) != 0) {
        fprintf(stderr, "bench: out of memory\n");
        return 1;
    }
    for (int row = 0; row < MOTION_ROWS && !failures; row++) {
        const motion_row *m = &motion_rows[row];
        if (m->time_steps == 1)
            steps[row][0] = s.vertices;
        else if (scene_motion_steps(&s, m->motion, m->amount, m->time_steps, steps[row]) != 0)
            failures++;
        for (int lib = 0; lib < MOTION_LIBRARIES && !failures; lib++) {
            progress_start("motion: %s T=%d, %s build", m->label, m->time_steps, motion_library_names[lib]);
            failures += motion_build(&s, steps[row], m->time_steps, lib, &results[row][lib]);
            progress("%s", failures ? "failed" : "done");
        }
    }
    /* the incoherent rays leave the static scene's hits, for every row */
    if (!failures) {
        trace_pass(&results[0][0].accel.tracer, &rays[RAYS_PRIMARY], hits, max_threads(o));
        if (secondary_rays(&s, &rays[RAYS_PRIMARY], hits, &rays[RAYS_INCOHERENT], &rays[RAYS_SHADOW]) != 0 ||
            ray_set_random_times(&rays[RAYS_PRIMARY], 2024) != 0 || ray_set_random_times(&rays[RAYS_INCOHERENT], 2025) != 0)
            failures++;
    }
    if (failures)
        fprintf(stderr, "bench: --motion: out of memory, or a build failed\n");
    for (int k = RAYS_PRIMARY; k <= RAYS_INCOHERENT && !failures; k++)
        if (o->ray_kind_enabled[k] && rays[k].count)
            motion_time_in_rounds(o, &rays[k], hits, results);
    double reference_seconds = 0.0;
    size_t accuracy_rays = 0;
    for (int row = 0; row < MOTION_ROWS && !failures && o->accuracy_rays; row++) {
        accuracy_set a;
        progress_start("motion: %s T=%d, accuracy", motion_rows[row].label, motion_rows[row].time_steps);
        if (motion_accuracy_prepare(&s, steps[row], motion_rows[row].time_steps, &rays[RAYS_PRIMARY], o->accuracy_rays,
                                    max_threads(o), &a) != 0) {
            progress("out of memory");
            accuracy_free(&a);
            break;
        }
        reference_seconds += a.seconds;
        accuracy_rays = a.rays.count;
        for (int lib = 0; lib < MOTION_LIBRARIES; lib++) {
            motion_result *r = &results[row][lib];
            r->has_accuracy = accuracy_measure(&r->accel.tracer, &a, &r->accuracy) == 0;
        }
        accuracy_free(&a);
        progress("done");
    }
    if (!failures) {
        motion_print(o, &s, rays, accuracy_rays, reference_seconds, results);
        motion_tsv(o, &s, results);
    }
    for (int row = 0; row < MOTION_ROWS; row++) {
        for (int lib = 0; lib < MOTION_LIBRARIES; lib++)
            free_variant(&results[row][lib].accel);
        if (motion_rows[row].time_steps > 1)
            scene_motion_free(steps[row], motion_rows[row].time_steps);
    }
    for (int k = 0; k < RAY_KIND_COUNT; k++)
        ray_set_free(&rays[k]);
    free(hits);
    scene_free(&s);
    return failures ? 1 : 0;
}

/* ======================================================================== */
/* Main                                                                     */
/* ======================================================================== */

/* --profile: each variant built in turn and traced once over each ray set,
   on this thread, between callgrind's zeroing and its dump (named after the
   pass), then one tab-separated line:
   profile scene variant library rays nodes leaves segments passed
   (the counts are totals, from a -DBENCH_COUNTS build; 0 otherwise). */
static void profile_scene(const options *o, workload *w, const int selected[VARIANT_COUNT], scene_result *sr)
{
    for (int i = 0; i < VARIANT_COUNT; i++) {
        built_accel accel;
        const variant *v = &all_variants[i];
        if (!selected[i] || build_and_record(w, v, &accel, &sr->variants[i]) != 0)
            continue;
        for (int k = 0; k < RAY_KIND_COUNT; k++) {
            char name[160];
            const ray_set *rays = &w->rays[k];
            if (!o->ray_kind_enabled[k] || rays->count == 0)
                continue;
            snprintf(name, sizeof name, "%s %s %s", sr->name, v->key, ray_kind_names[k]);
#ifdef BENCH_COUNTS
            memset(&bench_count, 0, sizeof bench_count);
#endif
            CALLGRIND_ZERO_STATS;
            CALLGRIND_TOGGLE_COLLECT;
            trace_pass(&accel.tracer, rays, w->hits, 1);
            CALLGRIND_TOGGLE_COLLECT;
            CALLGRIND_DUMP_STATS_AT(name);
            printf("profile\t%s\t%s\t%s\t%s\t%zu", sr->name, v->key, ray_kind_names[k],
                   v->lib == LIB_HAIROBB ? "hairobb" : "embree", rays->count);
#ifdef BENCH_COUNTS
            printf("\t%llu\t%llu\t%llu\t%llu\n", bench_count.node, bench_count.leaf, bench_count.segment,
                   bench_count.segment_passed);
#else
            printf("\t0\t0\t0\t0\n");
#endif
        }
        free_variant(&accel);
    }
}

/* Loads, measures and prints one scene. Returns 0, or 1 on an error.
   requested: --variants (sr->selected: those this scene runs). */
static int run_scene(const options *o, const char *name, const int requested[VARIANT_COUNT], scene_result *sr)
{
    workload w;
    memset(&w, 0, sizeof w);
    memset(sr, 0, sizeof *sr);
    snprintf(sr->name, sizeof sr->name, "%s", name);
    progress("%s: loading", name);
    double start = scene_now();
    char why[TEST_DATA_WHY_SIZE];
    rss_step_begin(&w.scene_rss);
    int loaded = load_scene(o, name, &w.scene, why);
    rss_step_end(&w.scene_rss);
    w.scene_seconds = scene_now() - start;
    if (loaded == -1) {
        printf("\n=== scene %s skipped: %s\n", name, why);
        return 0;
    }
    if (loaded != 0) {
        if (loaded == 1)
            fprintf(stderr, "bench: cannot load scene %s (unreadable, malformed or out of memory)\n", name);
        return 1;
    }
    progress("%s: %zu segments in %.2f s", w.scene.name, w.scene.segment_count, scene_now() - start);
    snprintf(sr->name, sizeof sr->name, "%s", w.scene.name);
    sr->segment_count = w.scene.segment_count;
    scene_variants(o, &w.scene, requested, sr);
    const int *selected = sr->selected;
    if (workload_prepare(o, selected, &w) != 0) {
        workload_free(&w);
        return 1;
    }
    sr->loaded = 1;
    for (int k = 0; k < RAY_KIND_COUNT; k++)
        sr->ray_counts[k] = w.rays[k].count;
    if (o->profile) {
        profile_scene(o, &w, selected, sr);
        workload_free(&w);
        return 0;
    }
    /* every variant built at once, so that the rounds can alternate them */
    static built_accel accel[VARIANT_COUNT];
    memset(accel, 0, sizeof accel);
    for (int i = 0; i < VARIANT_COUNT; i++)
        if (selected[i])
            build_and_record(&w, &all_variants[i], &accel[i], &sr->variants[i]);
    rss_step_begin(&w.trace_rss);
    time_in_rounds(o, &w, accel, sr);
    rss_step_end(&w.trace_rss);
    for (int i = 0; i < VARIANT_COUNT; i++) {
        variant_result *r = &sr->variants[i];
        if (r->measured && w.has_accuracy) {
            progress_start("  %s: accuracy", all_variants[i].label);
            r->has_accuracy = accuracy_measure(&accel[i].tracer, &w.accuracy, &r->accuracy) == 0;
            progress("%s", r->has_accuracy ? "done" : "out of memory");
        }
        free_variant(&accel[i]);
    }
    print_scene_header(o, &w);
    print_curves_note(&w);
    print_build_table(sr, selected);
    print_speed_table(o, sr, selected);
    print_accuracy_table(&w, sr, selected);
    print_memory_table(&w, sr);
    fflush(stdout);
    workload_free(&w);
    return 0;
}

/* ======================================================================== */
/* Build time against Embree, in rounds                                     */
/* ======================================================================== */

/* --builds: per scene, --rounds rounds of three builds, each freed before
   the next: hairobb's defaults on all cores, the same on 1 thread, Embree
   flat r4 on all cores (a Catmull-Rom scene: both read its Catmull-Rom
   curves, hairobb without the copy). Medians [min-max] of the seconds, and
   of the ratios to Embree taken within each round; hairobb's transient
   bytes a segment (allocator meter). */
static int run_builds(const options *o)
{
    enum { ALL_CORES, ONE_THREAD, EMBREE, BUILDS };
    static const char *const names[BUILDS] = {"hairobb, all cores", "hairobb, 1 thread", "Embree flat r4, all cores"};
    int failures = 0;
    printf("\nbuild time in rounds (%d rounds; each round builds the three in turn, each freed before the next)\n", o->rounds);
    printf("%-12s %12s %-26s %-24s %-24s %-18s %s\n", "scene", "segments", "build", "seconds", "/ Embree (in round)",
           "bytes/segment", "transient b/seg");
    for (int c = 0; c < o->scene_count; c++) {
        hair_scene s;
        char why[TEST_DATA_WHY_SIZE];
        int loaded = load_scene(o, o->scenes[c], &s, why);
        if (loaded != 0) {
            printf("%-12s skipped: %s\n", o->scenes[c], loaded < 0 ? why : "could not be loaded");
            failures += loaded > 0;
            continue;
        }
        int catmull_rom = s.basis == SCENE_BASIS_CATMULL_ROM;
        double seconds[BUILDS][MAX_ROUNDS], ratios[BUILDS][MAX_ROUNDS];
        size_t memory[BUILDS] = {0, 0, 0}, transient = 0;
        int ok = 1, builds = BUILDS;
        char why_not[256];
        if (!memory_fits(HAIROBB_BUILD_PEAK_BYTES_PER_SEGMENT * (double)s.segment_count, "hairobb's build", why_not,
                         sizeof why_not)) {
            printf("%-12s skipped: %s\n", o->scenes[c], why_not);
            scene_free(&s);
            continue;
        }
        if (!memory_fits(EMBREE_BUILD_PEAK_BYTES_PER_SEGMENT * (double)s.segment_count, "Embree's build", why_not,
                         sizeof why_not)) {
            printf("%-12s Embree skipped: %s\n", o->scenes[c], why_not);
            builds = EMBREE;    /* hairobb's rows alone, without ratios */
        }
        progress_start("builds: %s, %zu segments, %d rounds", o->scenes[c], s.segment_count, o->rounds);
        for (int r = 0; r < o->rounds && ok; r++) {
            for (int k = 0; k < builds && ok; k++) {
                /* a pause first: threads the last build left spinning (TBB's, Embree's) stop before the next starts */
                struct timespec pause = {0, 200000000};
                nanosleep(&pause, NULL);
                if (k == EMBREE) {
                    emb_scene *e = emb_build_curves(s.vertices, s.vertex_count, s.indices, s.segment_count,
                                                    catmull_rom ? EMB_FLAT_CATMULL_ROM : EMB_FLAT_BEZIER, NULL, 4, 0,
                                                    &memory[k], &seconds[k][r]);
                    ok = e != NULL;
                    emb_free(e);
                } else {
                    hairobb_build_options build_options;
                    memset(&build_options, 0, sizeof build_options);
                    build_options.threads = k == ONE_THREAD ? 1 : 0;
                    build_options.basis = catmull_rom ? HAIROBB_BASIS_CATMULL_ROM : HAIROBB_BASIS_BEZIER;
                    build_options.bezier_copy = HAIROBB_OFF;
                    hairobb_bvh *bvh = build_metered(&s, s.vertices, &build_options, names[k], &seconds[k][r], &transient);
                    ok = bvh != NULL;
                    if (bvh)
                        memory[k] = hairobb_memory_bytes(bvh);
                    hairobb_free(bvh);
                }
            }
            for (int k = 0; k < builds && ok; k++)
                ratios[k][r] = builds == BUILDS ? seconds[k][r] / seconds[EMBREE][r] : NAN;
        }
        progress(ok ? "done" : "failed");
        if (!ok) {
            printf("%-12s a build failed\n", o->scenes[c]);
            ++failures;
        }
        for (int k = 0; k < builds && ok; k++) {
            spread t = spread_of(seconds[k], o->rounds), q = spread_of(ratios[k], o->rounds);
            char cell[2][48], transient_cell[32] = "-";
            snprintf(cell[0], sizeof cell[0], "%.4f [%.4f-%.4f]", t.median, t.min, t.max);
            if (builds == BUILDS)
                snprintf(cell[1], sizeof cell[1], "%.2f [%.2f-%.2f]", q.median, q.min, q.max);
            else
                snprintf(cell[1], sizeof cell[1], "-");
            if (k != EMBREE)
                snprintf(transient_cell, sizeof transient_cell, "%.1f", (double)transient / (double)s.segment_count);
            printf("%-12s %12zu %-26s %-24s %-24s %-18.1f %s\n", o->scenes[c], s.segment_count, names[k], cell[0], cell[1],
                   (double)memory[k] / (double)s.segment_count, transient_cell);
        }
        scene_free(&s);
    }
    return failures ? 1 : 0;
}

int main(int argc, char **argv)
{
    options o;
    int parsed = parse_options(argc, argv, &o);
    if (parsed)
        return parsed == 2 ? 0 : 2;
    int selected[VARIANT_COUNT] = {0};
    if (select_variants(o.variant_list, selected) != 0)
        return 2;
    show_progress = isatty(STDERR_FILENO) && !o.quiet;
    memory_limit_bytes = o.memory_mb * (size_t)1048576;
    alloc_meter_init(&hairobb_meter, 0);

    print_machine(&o);
    if (o.animate_frames)
        return run_animation(&o, o.animate_frames);
    if (o.save_load_count)
        return save_load_bench(&o) ? 1 : 0;
    if (o.motion)
        return run_motion(&o);
    if (o.builds)
        return run_builds(&o);
    static scene_result results[MAX_SCENES];
    if (o.profile) {
        int failures = 0;
        for (int s = 0; s < o.scene_count; s++)
            failures += run_scene(&o, o.scenes[s], selected, &results[s]);
        return failures ? 1 : 0;
    }
    FILE *tsv = tsv_open(&o);
    int failures = 0;
    for (int s = 0; s < o.scene_count; s++) {
        failures += run_scene(&o, o.scenes[s], selected, &results[s]);
        if (tsv && results[s].loaded)
            tsv_write_scene(tsv, &o, &results[s], results[s].selected);
    }
    if (tsv)
        fclose(tsv);

    char note[512];
    /* the variants some scene ran (a Catmull-Rom scene may run fewer than --variants) */
    int ran[VARIANT_COUNT] = {0};
    for (int s = 0; s < o.scene_count; s++)
        for (int i = 0; i < VARIANT_COUNT; i++)
            ran[i] |= results[s].selected[i];
    const char *chart_note = tsv ? draw_chart(&o, results, o.scene_count, ran, note, sizeof note) : "no TSV, no chart";
    print_ablation_table(&o, results, o.scene_count, ran);
    print_tradeoff_table(&o, results, o.scene_count, ran, chart_note);
    printf("\nTSV: %s; %s\n", tsv ? o.tsv_path : "not written", chart_note);
    return failures ? 1 : 0;
}
