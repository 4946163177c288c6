/* bench.h - what the parts of the bench share. bench/bench.c says what the
   bench measures and how; the Makefile's $(B)/bench rule compiles the parts
   together in one command line. Each part calls only parts listed before
   it, so that the parts can be read, and changed, from the top of the list
   down:

     progress.c        progress lines on stderr
     memory.c          the memory a build would take, and what each step took
     layout.c          the scene's arrays: the strands' order, plain or huge-page memory
     scenes.c          scenes and their ray sets (primary, incoherent, shadow)
     options.c         the command line: defaults, --help, parsing
     harness.c         hairobb's implementation, the tracers, the parallel loop, timing in rounds
     variants.c        the variants (hairobb options, Embree curves), their groups, building one
     accuracy.c        the reference's answers, and a tracer's errors against them
     report.c          the machine, the tables
     tsv_chart.c       the TSV, and the run time against error chart (bench/plot.gp)
     mode_scenes.c     the default mode and --profile: each scene's variants built, timed, checked
     mode_builds.c     --builds: build time against Embree, in rounds
     mode_motion.c     --motion: motion blur against Embree
     mode_animate.c    --animate N: refit against rebuild over an animation
     mode_save_load.c  --save-load: save and load against build
     mode_groups.c     --groups: one BVH against the same hair as a scene of 4-64 groups
     bench.c           main: the options, then one mode

   What the bench shares with the tests comes from tests/: the scenes
   (scenes.h, random.h), the references (reference.h, ref_tube.h), Embree
   (embree_wrap.h), the counting allocator (test_alloc.h) and the hit
   comparisons and percentiles (compare.h).

   Every part includes this header first: it sets the feature macros before
   any system header. */
#ifndef HAIROBB_BENCH_H
#define HAIROBB_BENCH_H

#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE   /* madvise(MADV_HUGEPAGE), as gnu C and C++ builds have it (HAIROBB_NO_HUGE_PAGES) */

/* --profile (bench/profile.sh): built with -DBENCH_COUNTS, the header counts
   each ray's nodes, leaves and segments (in harness.c, which holds the
   implementation); run under callgrind, each variant's pass over each ray
   set is dumped on its own (mode_scenes.c). */
#ifdef BENCH_COUNTS
typedef struct bench_counts {
    unsigned long long node, leaf, segment, segment_passed;
} bench_counts;
extern bench_counts bench_count;
#define HAIROBB__COUNT(what) (++bench_count.what)
#endif

/* hairobb's allocations go through the tests' counting allocator: the build's peak */
#include "tests/test_alloc.h"
#include "hairobb.h"
#include "tests/compare.h"
#include "tests/embree_wrap.h"
#include "tests/reference.h"
#include "tests/ref_tube.h"
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
/* Limits and options                                                       */
/* ======================================================================== */

enum {
    MAX_SCENES = 16,
    MAX_THREAD_COUNTS = 8,
    RAY_BLOCK = 64,            /* rays per work item; blocks interleave across threads */
    MAX_ROUNDS = 64,
    MAX_SAVE_LOAD = 8
};

typedef enum ray_kind { RAYS_PRIMARY, RAYS_INCOHERENT, RAYS_SHADOW, RAY_KIND_COUNT } ray_kind;
extern const char *const ray_kind_names[RAY_KIND_COUNT];

/* --strand-order: the order of the strands in the scene's arrays (layout.c) */
typedef enum strand_order {
    STRAND_ORDER_GENERATED, /* as tests/scenes.h makes them, or as a file holds them */
    STRAND_ORDER_GROOM,     /* shuffled with a fixed seed, as a groom generator writes them */
    STRAND_ORDER_SPACE,     /* sorted by the Morton code of their roots */
    STRAND_ORDER_COUNT,
    STRAND_ORDER_UNSET = -1 /* groom for procedural scenes, the file's order for files */
} strand_order;
extern const char *const strand_order_names[STRAND_ORDER_COUNT];

/* --groups-shape: the surfaces --groups builds its rows as, a bit each in
   options.groups_shapes (options.c names them) */
typedef enum groups_shape {
    GROUPS_SHAPE_RIBBON,    /* hairobb's ribbons, Embree's flat Bezier curves */
    GROUPS_SHAPE_ROUND,     /* tubes: HAIROBB_SHAPE_ROUND, Embree's round Bezier curves */
    GROUPS_SHAPE_COUNT
} groups_shape;
extern const char *const groups_shape_names[GROUPS_SHAPE_COUNT];

typedef struct options {
    const char *scenes[MAX_SCENES];
    size_t scene_segments[MAX_SCENES]; /* NAME:N in --scene (and --scene scale); 0 = --segments */
    int scene_scale[MAX_SCENES];       /* from --scene scale: the scale group unless --variants */
    int scene_count;
    size_t segments;
    int strand_order;               /* --strand-order: STRAND_ORDER_*, or STRAND_ORDER_UNSET */
    int huge_pages;                 /* --huge-pages: the scene's arrays in memory advised MADV_HUGEPAGE */
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
    int groups;                     /* --groups: one BVH against the same hair in groups under a scene, alone */
    unsigned groups_shapes;         /* --groups-shape: bit 1 << GROUPS_SHAPE_* for each surface built (default ribbons) */
    int groups_shape_given;         /* --groups-shape on the command line (it needs --groups) */
} options;

/* A scene's arrays as the bench handed them over (layout.c) */
typedef struct scene_layout {
    strand_order order;        /* the order the strands are in */
    int from_file;             /* read from a file: STRAND_ORDER_GENERATED is the file's own order */
    size_t strands;
    int huge_pages;            /* the arrays are in 2 MB-aligned memory advised MADV_HUGEPAGE */
    size_t array_bytes;        /* of the vertices and indices */
    long long huge_page_bytes; /* of those, on huge pages (AnonHugePages, /proc/self/smaps); -1 unknown */
} scene_layout;

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
    /* Embree's round curves are a swept circle (a tube), not the reference's ribbon:
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
    unsigned embree_flags; /* Embree: RTC_SCENE_FLAG_* (compact, robust); 0 = none */
    hairobb_shape shape;   /* hairobb: ribbons, or tubes (round) */
} variant;

/* the rows of all_variants (variants.c checks the count); result arrays are this long */
enum { VARIANT_COUNT = 33 };
extern const variant all_variants[];

/* The baseline of every ratio */
#define BASELINE_KEY "embree-r4"
/* Rows timed against a peer of their own kind as well, the ratio taken
   within each round as the ratio to the baseline is: hairobb without the
   copy against Embree's compact mode (peers in memory), hairobb's round
   curves against Embree's, default and robust (peers in surface). */
typedef struct peer_pair {
    const char *row, *peer; /* variant keys */
} peer_pair;
enum { PEER_PAIR_COUNT = 5 };
extern const peer_pair peer_pairs[PEER_PAIR_COUNT];

/* ======================================================================== */
/* Memory                                                                   */
/* ======================================================================== */

/* Bytes a segment that a build adds to the process at its peak (its
   structure and its transient memory) or the accuracy reference takes, for
   memory_fits. Yeti at 10M segments (bench/results/yeti-10M-*.txt):
   hairobb without the copy 70 of peak RSS (BVH 36, transient 32 by its
   allocator), Embree 136 allocated (its memory monitor; 114 of RSS, no
   higher peak), the reference 259 of RSS with the Bezier form. The copy
   (bezier_copy, every basis, static hair) is written after the build, so
   a build with it peaks at the larger of the build's peak and the BVH
   with its copy: 100-104 at 2M-10M (bench/results/trace-scale-*), other
   bases 4 more (their indices), rounded up. */
#define HAIROBB_BUILD_PEAK_BYTES_PER_SEGMENT 80.0
#define HAIROBB_WITH_COPY_BYTES_PER_SEGMENT 112.0
#define EMBREE_BUILD_PEAK_BYTES_PER_SEGMENT 150.0
#define REFERENCE_BYTES_PER_SEGMENT 272.0           /* tests/reference.h's allocations: copies, boxes, nodes */
#define BEZIER_FORM_BYTES_PER_SEGMENT 68.0          /* scene_to_bezier, for the reference of a Catmull-Rom scene */

/* A step's resident memory: before, after, and its peak (VmHWM, reset at
   the step's start by writing 5 to /proc/self/clear_refs; where that is
   refused, the process's peak so far). */
typedef struct rss_step {
    size_t before, after, peak;
} rss_step;

/* ======================================================================== */
/* Rays, hits, tracers and spreads                                          */
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

/* Median, min and max of n <= MAX_ROUNDS values (left in their order: a
   round's figures pair with the baseline's of the same round); NaN for none. */
typedef struct spread {
    double median, min, max;
} spread;

/* ======================================================================== */
/* Accuracy                                                                 */
/* ======================================================================== */

/* The reference's answers on a fixed random subset of the primary rays (a
   tracer's figures against them: tests/compare.h's accuracy_summary). */
typedef struct accuracy_set {
    ray_set rays;      /* copies of the chosen primary rays */
    ref_hit *ref;
    int *ref_hits;
    ref_tube_hit *tube;  /* the tube reference's answers (round curves' rows), or NULL */
    int *tube_hits;
    double seconds;    /* reference build + trace */
} accuracy_set;

/* ======================================================================== */
/* A scene's workload and results                                           */
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
    /* row / peer of each of peer_pairs, within rounds; NAN when either was not measured */
    spread peer_ratio[PEER_PAIR_COUNT][RAY_KIND_COUNT][MAX_THREAD_COUNTS];
    scene_layout layout;
} scene_result;

/* Everything a scene's variants share: the geometry and the rays. */
typedef struct workload {
    hair_scene scene;
    scene_layout layout;   /* its strands' order and its arrays' memory */
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

/* ======================================================================== */
/* Functions, by the part that defines them                                 */
/* ======================================================================== */

/* In the order of the list above: each part calls only those before it. */

/* progress.c */
extern int show_progress; /* stderr is a terminal and --quiet was not given */
void progress(const char *format, ...);
void progress_start(const char *format, ...);

/* memory.c */
extern size_t memory_limit_bytes; /* --memory-mb, else 0 */
extern int rss_peak_reset_works;
double estimated_build_bytes(const variant *v, const hair_scene *s);
int memory_fits(double bytes, const char *what, char *why, size_t size);
void rss_step_begin(rss_step *r);
void rss_step_end(rss_step *r);

/* layout.c */
int huge_pages_supported(void);
int arrange_scene(const options *o, hair_scene *s, int from_file, scene_layout *layout);
size_t *find_strands(const hair_scene *s, size_t *strand_count);
const char *layout_order_text(const scene_layout *l);
const char *layout_memory_text(const scene_layout *l, char *text, size_t size);

/* scenes.c */
size_t scene_segments(const options *o, int index);
int load_scene(const options *o, const char *name, size_t segments, hair_scene *s, scene_layout *layout,
               char why[TEST_DATA_WHY_SIZE]);
int ray_set_alloc(ray_set *r, ray_kind kind, size_t count);
int ray_set_random_times(ray_set *r, uint64_t seed);
void ray_set_free(ray_set *r);
int primary_rays(const hair_scene *s, int resolution, ray_set *rays);
int secondary_rays(const hair_scene *s, const ray_set *primary, const hit_record *hits, ray_set *incoherent,
                   ray_set *shadow);

/* options.c: returns 0 to run, 1 on a usage error, 2 after --help */
int parse_options(int argc, char **argv, options *o);

/* harness.c */
tracer hairobb_tracer(const hairobb_bvh *bvh);
tracer embree_tracer(const emb_scene *scene);
typedef void (*block_work)(void *context, size_t begin, size_t end);
void parallel_for(size_t count, unsigned thread_count, block_work work, void *context);
unsigned max_threads(const options *o);
double trace_pass(const tracer *t, const ray_set *rays, hit_record *hits, unsigned thread_count);
spread spread_of(const double *values, int n);
const char *spread_cell(char *cell, size_t size, spread x);
void time_in_rounds(const options *o, workload *w, built_accel accel[VARIANT_COUNT], scene_result *sr, int base,
                    int peers[PEER_PAIR_COUNT][2]);

/* variants.c */
extern test_allocator hairobb_meter;
int variant_index(const char *key);
int select_variants(const char *list, int selected[VARIANT_COUNT]);
hairobb_basis variant_basis(const variant *v, const hair_scene *s);
int variant_comparable(const variant *v, scene_basis basis);
int variant_on_chart(const variant *v, scene_basis basis);
/* round curves (hairobb's or Embree's): measured against the tube reference */
int variant_is_tube(const variant *v);
int spawn_variant(const hair_scene *s);
hairobb_bvh *build_metered(const hair_scene *s, const float *vertices, hairobb_build_options *build_options,
                           const char *what, double *seconds, size_t *transient_bytes);
hairobb_bvh *build_hairobb(const hair_scene *s, const variant *v, double *seconds, size_t *transient_bytes);
int build_and_record(workload *w, const variant *v, built_accel *accel, variant_result *r);
void free_variant(built_accel *b);

/* accuracy.c */
void reference_trace(const ref_scene *reference, accuracy_set *a, size_t first, size_t end, unsigned thread_count);
int accuracy_pick(const ray_set *primary, size_t wanted, accuracy_set *a);
int accuracy_prepare(const hair_scene *s, const ray_set *primary, size_t wanted, unsigned thread_count, int tubes,
                     accuracy_set *a);
void accuracy_free(accuracy_set *a);
int accuracy_measure(const tracer *t, const accuracy_set *a, int tube, accuracy_summary *out);

/* report.c */
void print_machine(const options *o);
void print_scene_line(const workload *w);
void print_scene_header(const options *o, const workload *w);
void print_curves_note(const workload *w);
void print_build_table(const scene_result *sr, const int selected[VARIANT_COUNT]);
void print_speed_table(const options *o, const scene_result *sr, const int selected[VARIANT_COUNT]);
void print_accuracy_table(const workload *w, const scene_result *sr, const int selected[VARIANT_COUNT]);
void print_memory_table(const workload *w, const scene_result *sr);
void print_ablation_table(const options *o, const scene_result *results, int scene_count,
                          const int selected[VARIANT_COUNT]);
void print_tradeoff_table(const options *o, const scene_result *results, int scene_count,
                          const int selected[VARIANT_COUNT], const char *chart_note);

/* tsv_chart.c */
void tsv_number(FILE *f, const char *format, double value);
void tsv_accuracy(FILE *f, const accuracy_summary *a);
FILE *tsv_open(const options *o);
void tsv_write_scene(FILE *f, const options *o, const scene_result *sr, const int selected[VARIANT_COUNT]);
const char *draw_chart(const options *o, const scene_result *results, int scene_count,
                       const int selected[VARIANT_COUNT], char *note, size_t note_size);

/* the modes: each returns the process's exit status */
int run_scenes(const options *o, const int selected[VARIANT_COUNT]); /* mode_scenes.c */
int run_builds(const options *o);                                    /* mode_builds.c */
int run_motion(const options *o);                                    /* mode_motion.c */
int run_animation(const options *o, int frames);                     /* mode_animate.c */
int run_save_load(const options *o);                                 /* mode_save_load.c */
int run_groups(const options *o);                                    /* mode_groups.c */

#endif /* HAIROBB_BENCH_H */
