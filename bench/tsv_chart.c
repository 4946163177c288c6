/* tsv_chart.c - every figure to a TSV file, one row per scene and variant,
   and the run time against error chart drawn from it by gnuplot
   (bench/plot.gp). */
#include "bench/bench.h"

void tsv_number(FILE *f, const char *format, double value)
{
    if (isfinite(value))
        fprintf(f, format, value);
    else
        fputs("\tNaN", f); /* gnuplot skips NaN */
}

/* The accuracy columns of a TSV row: rays, disagreements, their percentage,
   |dt| median, p99 and max, |du| median and p99 (NULL: not measured). */
void tsv_accuracy(FILE *f, const accuracy_summary *a)
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

FILE *tsv_open(const options *o)
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
    /* the scene's arrays (layout.c): the strands' order, and the memory they are in */
    fputs("\tstrand_order\tarray_memory\tarray_huge_page_bytes", f);
    /* each peer pair's ratio within rounds (peer_pairs: ROW / PEER), on ROW's row; NaN on the others */
    for (int p = 0; p < PEER_PAIR_COUNT; p++)
        for (int k = 0; k < RAY_KIND_COUNT; k++)
            for (int t = 0; t < o->thread_count_count; t++)
                fprintf(f, "\t%s_per_%s_%ut\t%s_per_%s_%ut_min\t%s_per_%s_%ut_max", ray_kind_names[k],
                        peer_pairs[p].peer, o->thread_counts[t], ray_kind_names[k], peer_pairs[p].peer,
                        o->thread_counts[t], ray_kind_names[k], peer_pairs[p].peer, o->thread_counts[t]);
    fputc('\n', f);
    return f;
}

void tsv_write_scene(FILE *f, const options *o, const scene_result *sr, const int selected[VARIANT_COUNT])
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
        /* the chart's series: ribbons, and tubes against the tube reference apart */
        const char *series = !variant_on_chart(v, sr->basis) ? "-"
                             : variant_is_tube(v) ? (hairobb ? "hairobb-round" : "embree-round")
                                                  : (hairobb ? "hairobb" : "embree");
        fprintf(f, "\t%d\t%s", variant_comparable(v, sr->basis), series);
        for (int k = 0; k < RAY_KIND_COUNT; k++)
            for (int t = 0; t < o->thread_count_count; t++) {
                tsv_number(f, "\t%.4f", r->mrays[k][t].min);
                tsv_number(f, "\t%.4f", r->mrays[k][t].max);
                tsv_number(f, "\t%.4f", r->ratio[k][t].median);
                tsv_number(f, "\t%.4f", r->ratio[k][t].min);
                tsv_number(f, "\t%.4f", r->ratio[k][t].max);
            }
        fprintf(f, "\t%s\t%s\t%lld", sr->layout.order == STRAND_ORDER_GENERATED && sr->layout.from_file
                                              ? "file" : strand_order_names[sr->layout.order],
                sr->layout.huge_pages ? "madvise-hugepage" : "malloc", sr->layout.huge_page_bytes);
        for (int p = 0; p < PEER_PAIR_COUNT; p++) {
            int own = strcmp(v->key, peer_pairs[p].row) == 0;
            for (int k = 0; k < RAY_KIND_COUNT; k++)
                for (int t = 0; t < o->thread_count_count; t++) {
                    spread x = own ? sr->peer_ratio[p][k][t] : (spread){NAN, NAN, NAN};
                    tsv_number(f, "\t%.4f", x.median);
                    tsv_number(f, "\t%.4f", x.min);
                    tsv_number(f, "\t%.4f", x.max);
                }
        }
        fputc('\n', f);
    }
    fflush(f);
}

/* A scene gets a row of the chart if some variant of the chart has both a
   speed and an accuracy: the gnuplot script needs points to set its axes. */
static int has_chart_points(const scene_result *sr, const int selected[VARIANT_COUNT])
{
    for (int i = 0; i < VARIANT_COUNT; i++) {
        const variant_result *r = &sr->variants[i];
        if (sr->loaded && selected[i] && variant_on_chart(&all_variants[i], sr->basis) && r->has_accuracy &&
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
const char *draw_chart(const options *o, const scene_result *results, int scene_count,
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
        snprintf(note, note_size, "no chart: it needs primary rays, accuracy rays and a precision, Embree flat or "
                                  "round variant");
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
