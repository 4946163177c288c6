/* mode_scenes.c - the default mode: for each --scene, its rays and the
   reference's answers, every selected variant built, timed in rounds and
   checked, the tables; then the TSV, the chart and the tables over all
   scenes. With --profile: each variant traced once, under callgrind. */
#include "bench/bench.h"

/* callgrind's client requests: --profile zeroes, collects and dumps each pass */
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

/* ======================================================================== */
/* Scene workload                                                           */
/* ======================================================================== */

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
        int tubes = 0;
        for (int i = 0; i < VARIANT_COUNT; i++)
            tubes |= selected[i] && variant_is_tube(&all_variants[i]);
        int failed = accuracy_prepare(&w->scene, &w->rays[RAYS_PRIMARY], o->accuracy_rays, max_threads(o), tubes, &w->accuracy);
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

/* The variants a scene runs: --variants; without it a Catmull-Rom scene
   runs the yeti group (the Bezier rows there would each hold a 72-byte
   copy a segment, the rest of "all" reads Bezier points), and the scenes of
   --scene scale the scale group (every row's BVH is held at once: at 10M
   segments "all" would take gigabytes, and minutes a round). */
static void scene_variants(const options *o, int index, const hair_scene *s, const int requested[VARIANT_COUNT],
                           scene_result *sr)
{
    sr->basis = s->basis;
    if (s->basis == SCENE_BASIS_CATMULL_ROM && !o->variants_given) {
        memset(sr->selected, 0, sizeof sr->selected);
        select_variants("yeti", sr->selected);
    } else if (o->scene_scale[index] && !o->variants_given) {
        memset(sr->selected, 0, sizeof sr->selected);
        select_variants("scale", sr->selected);
    } else {
        memcpy(sr->selected, requested, sizeof sr->selected);
    }
}

/* ======================================================================== */
/* A scene, and all of them                                                 */
/* ======================================================================== */

/* "combed" of 2,000,000 segments asked as combed:2M becomes "combed-2M" */
static void scene_name_with_size(hair_scene *s, size_t segments)
{
    char base[40];
    snprintf(base, sizeof base, "%.39s", s->name);
    if (segments % 1000000 == 0)
        snprintf(s->name, sizeof s->name, "%s-%zuM", base, segments / 1000000);
    else if (segments % 1000 == 0)
        snprintf(s->name, sizeof s->name, "%s-%zuk", base, segments / 1000);
    else
        snprintf(s->name, sizeof s->name, "%s-%zu", base, segments);
}

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

/* Loads, measures and prints --scene's index-th scene. Returns 0, or 1 on
   an error. requested: --variants (sr->selected: those this scene runs). */
static int run_scene(const options *o, int index, const int requested[VARIANT_COUNT], scene_result *sr)
{
    const char *name = o->scenes[index];
    workload w;
    memset(&w, 0, sizeof w);
    memset(sr, 0, sizeof *sr);
    snprintf(sr->name, sizeof sr->name, "%s", name);
    progress("%s: loading", name);
    double start = scene_now();
    char why[TEST_DATA_WHY_SIZE];
    rss_step_begin(&w.scene_rss);
    int loaded = load_scene(o, name, scene_segments(o, index), &w.scene, &w.layout, why);
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
    /* a scene of its own size (NAME:N, scale) is named by it: combed-2M and combed-10M stay apart in the TSV */
    if (o->scene_segments[index])
        scene_name_with_size(&w.scene, o->scene_segments[index]);
    snprintf(sr->name, sizeof sr->name, "%s", w.scene.name);
    sr->segment_count = w.scene.segment_count;
    sr->layout = w.layout;
    scene_variants(o, index, &w.scene, requested, sr);
    const int *selected = sr->selected;
    if (workload_prepare(o, selected, &w) != 0) {
        workload_free(&w);
        return 1;
    }
    sr->loaded = 1;
    for (int k = 0; k < RAY_KIND_COUNT; k++)
        sr->ray_counts[k] = w.rays[k].count;
    if (o->profile) {
        print_scene_line(&w);
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
    int peers[PEER_PAIR_COUNT][2];
    for (int p = 0; p < PEER_PAIR_COUNT; p++) {
        peers[p][0] = variant_index(peer_pairs[p].row);
        peers[p][1] = variant_index(peer_pairs[p].peer);
    }
    time_in_rounds(o, &w, accel, sr, variant_index(BASELINE_KEY), peers);
    rss_step_end(&w.trace_rss);
    for (int i = 0; i < VARIANT_COUNT; i++) {
        variant_result *r = &sr->variants[i];
        if (r->measured && w.has_accuracy) {
            progress_start("  %s: accuracy", all_variants[i].label);
            r->has_accuracy = accuracy_measure(&accel[i].tracer, &w.accuracy, variant_is_tube(&all_variants[i]), &r->accuracy) == 0;
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

/* The default mode, and --profile: every scene in turn, then (not with
   --profile) the TSV, the chart and the tables over all scenes. */
int run_scenes(const options *o, const int selected[VARIANT_COUNT])
{
    static scene_result results[MAX_SCENES];
    if (o->profile) {
        int failures = 0;
        for (int s = 0; s < o->scene_count; s++)
            failures += run_scene(o, s, selected, &results[s]);
        return failures ? 1 : 0;
    }
    FILE *tsv = tsv_open(o);
    int failures = 0;
    for (int s = 0; s < o->scene_count; s++) {
        failures += run_scene(o, s, selected, &results[s]);
        if (tsv && results[s].loaded)
            tsv_write_scene(tsv, o, &results[s], results[s].selected);
    }
    if (tsv)
        fclose(tsv);

    char note[512];
    /* the variants some scene ran (a Catmull-Rom scene may run fewer than --variants) */
    int ran[VARIANT_COUNT] = {0};
    for (int s = 0; s < o->scene_count; s++)
        for (int i = 0; i < VARIANT_COUNT; i++)
            ran[i] |= results[s].selected[i];
    const char *chart_note = tsv ? draw_chart(o, results, o->scene_count, ran, note, sizeof note) : "no TSV, no chart";
    print_ablation_table(o, results, o->scene_count, ran);
    print_tradeoff_table(o, results, o->scene_count, ran, chart_note);
    printf("\nTSV: %s; %s\n", tsv ? o->tsv_path : "not written", chart_note);
    return failures ? 1 : 0;
}
