/* report.c - what the bench prints on stdout: the machine it ran on, and
   each scene's tables (build and memory, speed, accuracy, process memory),
   then the ablation and the run time against error over all scenes.
   (Progress lines on stderr: progress.c.) */
#include "bench/bench.h"

/* ======================================================================== */
/* Machine description                                                      */
/* ======================================================================== */

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

void print_machine(const options *o)
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
/* Tables                                                                   */
/* ======================================================================== */

/* The rows of the ablation table (the paper's three node policies, all
   with the default exact intersector). */
static const char *const ablation_keys[] = {"aabb", "obb", "mixed-uncompressed", "spatial", "spatial-compressed",
                                            "spatial-compressed-cluster", "shared", "compressed-shared", "default"};
static const char *const ablation_labels[] = {"AABB-only", "OBB-only", "mixed", "+ spatial", "+ compression",
                                              "+ clustering", "shared-R float", "shared-R bytes", "defaults"};
enum { ABLATION_ROWS = 9 };

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

/* The scene's line, and where its arrays lie: the first lines of its header
   (--profile prints these alone). */
void print_scene_line(const workload *w)
{
    const hair_scene *s = &w->scene;
    char memory[256];
    printf("\n=== scene %s: %zu segments in %zu strands, %s, bounds (%.3g %.3g %.3g)-(%.3g %.3g %.3g)\n", s->name,
           s->segment_count, w->layout.strands, layout_order_text(&w->layout), s->lower[0], s->lower[1], s->lower[2],
           s->upper[0], s->upper[1], s->upper[2]);
    printf("arrays: %s\n", layout_memory_text(&w->layout, memory, sizeof memory));
}

void print_scene_header(const options *o, const workload *w)
{
    const hair_scene *s = &w->scene;
    print_scene_line(w);
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

void print_build_table(const scene_result *sr, const int selected[VARIANT_COUNT])
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
void print_speed_table(const options *o, const scene_result *sr, const int selected[VARIANT_COUNT])
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
                    printf(" %-17s", spread_cell(cell, sizeof cell, table == 0 ? r->mrays[k][t] : r->ratio[k][t]));
                }
            printf("\n");
        }
    }
    /* each row against its peer (peer_pairs), within rounds */
    int width = 0;
    for (int p = 0; p < PEER_PAIR_COUNT; p++) {
        int row = variant_index(peer_pairs[p].row), peer = variant_index(peer_pairs[p].peer);
        int length = (int)(strlen(all_variants[row].label) + strlen(all_variants[peer].label) + 3);
        if (selected[row] && sr->variants[row].measured && selected[peer] && sr->variants[peer].measured)
            width = length > width ? length : width;
    }
    if (width == 0)
        return;
    printf("\nthis / its peer (no copy: in memory; round curves: in surface; SSE2 path: on a CPU without AVX2), the ratio taken within each round: "
           "median [min-max]\n");
    printf("%-*s", width, "variant / peer");
    for (int k = 0; k < RAY_KIND_COUNT; k++)
        for (int t = 0; t < o->thread_count_count && o->ray_kind_enabled[k]; t++) {
            snprintf(heading, sizeof heading, "%s %ut", ray_kind_names[k], o->thread_counts[t]);
            printf(" %-17s", heading);
        }
    printf("\n");
    for (int p = 0; p < PEER_PAIR_COUNT; p++) {
        int row = variant_index(peer_pairs[p].row), peer = variant_index(peer_pairs[p].peer);
        char pair[96];
        if (!selected[row] || !sr->variants[row].measured || !selected[peer] || !sr->variants[peer].measured)
            continue;
        snprintf(pair, sizeof pair, "%s / %s", all_variants[row].label, all_variants[peer].label);
        printf("%-*s", width, pair);
        for (int k = 0; k < RAY_KIND_COUNT; k++)
            for (int t = 0; t < o->thread_count_count && o->ray_kind_enabled[k]; t++)
                printf(" %-17s", spread_cell(cell, sizeof cell, sr->peer_ratio[p][k][t]));
        printf("\n");
    }
}

void print_accuracy_table(const workload *w, const scene_result *sr, const int selected[VARIANT_COUNT])
{
    int any_informative = 0;
    if (!w->has_accuracy)
        return;
    printf("\naccuracy on %zu primary rays against the double-precision reference ribbon (round curves' rows, *: the reference "
           "tube)\n", w->accuracy.rays.count);
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
        printf("* on this scene the round rows read its points as Bezier points of other curves: informative, not comparable\n");
    if (any_informative & 2)
        printf("* the C-R rows read this scene's Bezier points as Catmull-Rom points: other curves, not comparable\n");
}

/* Rows AABB-only, OBB-only, mixed per scene, as in the paper's results
   table (Woop et al. 2014): speed on primary and incoherent rays, memory
   and build time. */
void print_ablation_table(const options *o, const scene_result *results, int scene_count,
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

/* The chart's points as a table: precision variants, Embree rates and the
   round curves (tubes, each against the tube reference). */
void print_tradeoff_table(const options *o, const scene_result *results, int scene_count,
                          const int selected[VARIANT_COUNT], const char *chart_note)
{
    if (!o->ray_kind_enabled[RAYS_PRIMARY] || o->accuracy_rays == 0)
        return;
    printf("\n=== run time against error: primary rays, %u thread%s; *: round curves, against the tube reference (%s)\n",
           o->thread_counts[0], o->thread_counts[0] == 1 ? "" : "s", chart_note);
    printf("%-12s %-20s %-10s %-12s %-10s\n", "scene", "variant", "Mrays/s", "disagree %", "|dt|/r p99");
    for (int s = 0; s < scene_count; s++) {
        if (!results[s].loaded)
            continue;
        int first = 1;
        for (int i = 0; i < VARIANT_COUNT; i++) {
            const variant_result *r = &results[s].variants[i];
            if (!selected[i] || !variant_on_chart(&all_variants[i], results[s].basis) || !r->has_accuracy)
                continue;
            printf("%-12s %-20s %-10.2f %-12.4f %-10.2e\n", first ? results[s].name : "", all_variants[i].label,
                   r->mrays[RAYS_PRIMARY][0].median, disagreement_percent(&r->accuracy), r->accuracy.t_p99);
            first = 0;
        }
    }
}

/* What a Catmull-Rom scene holds and what each row reads from it. */
void print_curves_note(const workload *w)
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
void print_memory_table(const workload *w, const scene_result *sr)
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
