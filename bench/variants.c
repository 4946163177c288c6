/* variants.c - what the bench compares: hairobb build options and Embree
   curve types and rates, the groups --variants names, the curves each reads
   on a Catmull-Rom scene, and building one (hairobb's builds metered). */
#include "bench/bench.h"

/* ======================================================================== */
/* The variants                                                             */
/* ======================================================================== */

#define HAIROBB_ROW(key, label, nodes, layout, spatial, cluster, precision, pieces, on_chart) \
    {key, label, LIB_HAIROBB, HAIROBB_NODES_##nodes, HAIROBB_##layout, HAIROBB_PRECISION_##precision, pieces, \
     HAIROBB_##spatial, HAIROBB_##cluster, 0, 0, 1, on_chart, 0, 0, HAIROBB_SIMD_AUTO, HAIROBB_BASIS_BEZIER, HAIROBB_AUTO, 0, HAIROBB_SHAPE_RIBBON}
/* the defaults built on one thread (the build's speed-up), with a filter, or
   traced by the SSE2 kernels (what CPUs without AVX2 get) */
#define HAIROBB_DEFAULTS_ROW(key, label, build_threads, hit_filter, simd) \
    {key, label, LIB_HAIROBB, HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_PRECISION_EXACT, 8, HAIROBB_AUTO, HAIROBB_AUTO, \
     0, 0, 1, 0, build_threads, hit_filter, HAIROBB_SIMD_##simd, HAIROBB_BASIS_BEZIER, HAIROBB_AUTO, 0, HAIROBB_SHAPE_RIBBON}
/* Embree's curves: type, tessellation rate, scene flags */
#define EMBREE_ROW(key, label, type, rate, flags, comparable, on_chart) \
    {key, label, LIB_EMBREE, HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_PRECISION_EXACT, 0, HAIROBB_AUTO, HAIROBB_AUTO, \
     type, rate, comparable, on_chart, 0, 0, HAIROBB_SIMD_AUTO, HAIROBB_BASIS_BEZIER, HAIROBB_AUTO, flags, HAIROBB_SHAPE_RIBBON}
#define HAIROBB_BASIS_ROW(key, label, basis, copy) \
    {key, label, LIB_HAIROBB, HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_PRECISION_EXACT, 8, HAIROBB_AUTO, HAIROBB_AUTO, \
     0, 0, 0, 0, 0, 0, HAIROBB_SIMD_AUTO, HAIROBB_BASIS_##basis, HAIROBB_##copy, 0, HAIROBB_SHAPE_RIBBON}
const variant all_variants[] = {
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
    /* the defaults without the copy (bezier_copy OFF): the caller's arrays read where they are */
    {"no-copy", "hairobb no copy", LIB_HAIROBB, HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_PRECISION_EXACT, 8, HAIROBB_AUTO,
     HAIROBB_AUTO, 0, 0, 1, 0, 0, 0, HAIROBB_SIMD_AUTO, HAIROBB_BASIS_BEZIER, HAIROBB_OFF, 0, HAIROBB_SHAPE_RIBBON},
    /* round curves (tubes): the peer of embree-round, not of the ribbon
       reference; on the chart against the tube reference */
    {"round", "hairobb round *", LIB_HAIROBB, HAIROBB_NODES_MIXED, HAIROBB_OBB_DEFAULT, HAIROBB_PRECISION_EXACT, 8, HAIROBB_AUTO,
     HAIROBB_AUTO, 0, 0, 0, 1, 0, 0, HAIROBB_SIMD_AUTO, HAIROBB_BASIS_BEZIER, HAIROBB_AUTO, 0, HAIROBB_SHAPE_ROUND},
    HAIROBB_BASIS_ROW("catmull-rom", "hairobb C-R no copy", CATMULL_ROM, OFF),
    HAIROBB_BASIS_ROW("catmull-rom-copy", "hairobb C-R + copy", CATMULL_ROM, ON),
    HAIROBB_BASIS_ROW("b-spline", "hairobb B-sp no copy", BSPLINE, OFF),
    HAIROBB_BASIS_ROW("b-spline-copy", "hairobb B-sp + copy", BSPLINE, ON),
    /* Embree's default curves (flat, rate 4: the baseline of every ratio) and finer tessellations */
    EMBREE_ROW("embree-r4", "Embree flat r4", EMB_FLAT_BEZIER, 4, 0, 1, 1),
    EMBREE_ROW("embree-r8", "Embree flat r8", EMB_FLAT_BEZIER, 8, 0, 1, 1),
    EMBREE_ROW("embree-r16", "Embree flat r16", EMB_FLAT_BEZIER, 16, 0, 1, 1),
    /* the peers: Embree's compact mode (40-66 bytes a segment: the peer of
       hairobb without the copy, no-copy), and
       Cycles' set-up (robust traversal, rate 5; Cycles hands Embree
       Catmull-Rom curves, which these rows read on a Catmull-Rom scene, and
       flat Bezier curves on a Bezier scene) */
    EMBREE_ROW("embree-compact", "Embree compact r4", EMB_FLAT_BEZIER, 4, RTC_SCENE_FLAG_COMPACT, 1, 0),
    EMBREE_ROW("embree-cycles", "Embree Cycles r5", EMB_FLAT_BEZIER, 5, RTC_SCENE_FLAG_ROBUST, 1, 0),
    /* Embree's round curves, the peers of round: its default mode (on the
       chart) and its robust traversal */
    EMBREE_ROW("embree-round", "Embree round *", EMB_ROUND_BEZIER, 0, 0, 0, 1),
    EMBREE_ROW("embree-round-robust", "Embree round rob. *", EMB_ROUND_BEZIER, 0, RTC_SCENE_FLAG_ROBUST, 0, 0),
    /* Embree's default limited to its AVX2 kernels (where the CPU has AVX-512) */
    EMBREE_ROW("embree-avx2", "Embree r4 AVX2 only", EMB_FLAT_BEZIER, 4, EMB_FLAG_ISA_AVX2, 1, 0),
    /* limited to its SSE4.2 or AVX kernels: what a CPU without AVX2 gets, the peers of sse2 */
    EMBREE_ROW("embree-sse42", "Embree r4 SSE4.2 only", EMB_FLAT_BEZIER, 4, EMB_FLAG_ISA_SSE42, 1, 0),
    EMBREE_ROW("embree-avx", "Embree r4 AVX only", EMB_FLAT_BEZIER, 4, EMB_FLAG_ISA_AVX, 1, 0),
};

/* VARIANT_COUNT (bench.h) sizes the result arrays: a row added above raises it */
typedef char variant_table_has_VARIANT_COUNT_rows[sizeof all_variants / sizeof all_variants[0] == VARIANT_COUNT ? 1 : -1];

/* Named groups for --variants; "mixed" is the default variant by another name. */
static const struct { const char *name, *members; } variant_groups[] = {
    {"all", "default,exact4,exact16,pieces4,pieces8,pieces16,aabb,obb,mixed-uncompressed,spatial,spatial-compressed,"
            "spatial-compressed-cluster,shared,compressed-shared,build-1t,filter,sse2,no-copy,round,embree-r4,embree-r8,embree-r16,"
            "embree-compact,embree-cycles,embree-round,embree-round-robust,embree-avx2,embree-sse42,embree-avx"},
    {"hairobb", "default,exact4,exact16,pieces4,pieces8,pieces16,aabb,obb,mixed-uncompressed,spatial,spatial-compressed,"
                "spatial-compressed-cluster,shared,compressed-shared,build-1t,filter,sse2,no-copy,round"},
    {"embree", "embree-r4,embree-r8,embree-r16,embree-compact,embree-cycles,embree-round,embree-round-robust,embree-avx2,"
               "embree-sse42,embree-avx"},
    {"precision", "default,exact4,exact16,pieces4,pieces8,pieces16"},
    {"ablation", "aabb,obb,mixed-uncompressed,spatial,spatial-compressed,spatial-compressed-cluster,shared,compressed-shared,default"},
    {"mixed", "default"},
    /* round curves: hairobb's tubes and Embree's, and the ribbons of both */
    {"tubes", "round,embree-round,embree-round-robust,default,embree-r4"},
    {"bases", "default,catmull-rom,catmull-rom-copy,b-spline,b-spline-copy"},
    /* a Catmull-Rom scene (yeti) without --variants: hairobb without the copy, Embree on the same buffers
       (embree-cycles: Cycles' own curves there, flat Catmull-Rom) */
    {"yeti", "catmull-rom,embree-r4,embree-cycles,embree-round"},
    /* --scene scale without --variants: the defaults (the copy, and without it) against Embree's
       default and its compact mode */
    {"scale", "default,no-copy,embree-r4,embree-compact"},
};

const peer_pair peer_pairs[PEER_PAIR_COUNT] = {
    {"no-copy", "embree-compact"},
    {"round", "embree-round"},
    {"round", "embree-round-robust"},
    {"sse2", "embree-sse42"},
    {"sse2", "embree-avx"},
};

int variant_index(const char *key)
{
    for (int i = 0; i < VARIANT_COUNT; i++)
        if (strcmp(all_variants[i].key, key) == 0)
            return i;
    return -1;
}

/* Marks the variants named in a comma list (names or groups). Returns 0 on
   success, else prints the unknown name and returns 1. */
int select_variants(const char *list, int selected[VARIANT_COUNT])
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
/* Catmull-Rom scenes (yeti)                                                */
/* ======================================================================== */

/* On a Catmull-Rom scene every variant reads the scene's own curves from
   the same shared buffers: hairobb rows build with that basis (the Bezier
   rows with hairobb's default, the Bezier copy; "catmull-rom" without it),
   Embree rows use the Catmull-Rom curve of their type. */
hairobb_basis variant_basis(const variant *v, const hair_scene *s)
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
int variant_is_tube(const variant *v)
{
    return v->lib == LIB_HAIROBB ? v->shape == HAIROBB_SHAPE_ROUND : v->embree_type == EMB_ROUND_BEZIER;
}

int variant_comparable(const variant *v, scene_basis basis)
{
    if (variant_is_tube(v)) return basis == SCENE_BASIS_BEZIER;   /* against the tube reference */
    if (basis == SCENE_BASIS_CATMULL_ROM && v->lib == LIB_HAIROBB)   /* its own basis or the Bezier default (made C-R) */
        return v->basis == HAIROBB_BASIS_BEZIER || v->basis == HAIROBB_BASIS_CATMULL_ROM;
    return v->accuracy_comparable;
}

/* A point of the run time against error chart on this scene: a chart row
   whose errors measure its accuracy (not a round row on a Catmull-Rom scene). */
int variant_on_chart(const variant *v, scene_basis basis)
{
    return v->on_chart && variant_comparable(v, basis);
}

/* The hairobb variant whose BVH spawns the secondary rays (and is kept for
   its row): the defaults, or on a Catmull-Rom scene the row without the
   copy, whose 68-72 bytes a segment would be 11 GB at 153M segments. */
int spawn_variant(const hair_scene *s)
{
    return variant_index(s->basis == SCENE_BASIS_CATMULL_ROM ? "catmull-rom" : "default");
}

/* ======================================================================== */
/* Building a variant                                                       */
/* ======================================================================== */

/* Takes every hit: what calling a filter costs, without changing a hit. */
static int take_every_hit(void *user, const hairobb_ray *ray, const hairobb_hit *hit)
{
    (void)user; (void)ray; (void)hit;
    return 1;
}

/* Every hairobb BVH allocates through this one meter (the allocator_user of
   every build; BVHs built earlier stay live in it): a build's peak transient
   bytes = the meter's peak during the build - what was live before it - the
   BVH's hairobb_memory_bytes. */
test_allocator hairobb_meter;

/* hairobb_build over the scene's segments (vertices NULL: a moving scene's
   build_options->time_vertices), metered: build seconds and peak transient
   bytes. allocator_user is set here; what: the build in an error message. */
hairobb_bvh *build_metered(const hair_scene *s, const float *vertices, hairobb_build_options *build_options,
                           const char *what, double *seconds, size_t *transient_bytes)
{
    build_options->allocator_user = &hairobb_meter;
    hairobb_bvh *bvh = NULL;
    test_allocator_reset_peak(&hairobb_meter);
    size_t live_before = hairobb_meter.bytes; /* no other thread allocates between builds */
    double start = scene_now();
    hairobb_result result = hairobb_build(vertices, s->vertex_count, s->indices, s->segment_count, build_options, &bvh);
    *seconds = scene_now() - start;
    *transient_bytes = bvh ? hairobb_meter.peak_bytes - live_before - hairobb_memory_bytes(bvh) : 0;
    if (result != HAIROBB_OK)
        fprintf(stderr, "bench: %s: hairobb_build (%s): %s\n", s->name, what, hairobb_result_string(result));
    return bvh;
}

hairobb_bvh *build_hairobb(const hair_scene *s, const variant *v, double *seconds, size_t *transient_bytes)
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
    build_options.shape = v->shape;
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
        b->embree = emb_build_curves_flags(s->vertices, s->vertex_count, s->indices, s->segment_count,
                                           variant_embree_type(v, s), NULL, v->embree_rate, v->embree_flags, 0,
                                           &r->memory_bytes, &r->build_seconds);
        if (!b->embree)
            return 1;
        b->tracer = embree_tracer(b->embree);
    }
    return 0;
}

void free_variant(built_accel *b)
{
    hairobb_free(b->bvh);
    emb_free(b->embree);
    memset(b, 0, sizeof *b);
}

/* Builds a variant and records its build time, memory and tree; 1 if the
   build failed. */
int build_and_record(workload *w, const variant *v, built_accel *accel, variant_result *r)
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
