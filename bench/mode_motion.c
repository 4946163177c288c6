/* mode_motion.c - --motion: motion blur against Embree. */
#include "bench/bench.h"

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

static void motion_print(const options *o, const hair_scene *s, const scene_layout *layout,
                         const ray_set rays[RAY_KIND_COUNT], size_t accuracy_rays, double reference_seconds,
                         motion_result results[MOTION_ROWS][MOTION_LIBRARIES])
{
    char c[5][48], memory[256];
    printf("\n=== motion blur: combed, %zu segments; hairobb defaults against Embree flat Bezier r%d "
           "(rtcSetGeometryTimeStepCount), the same buffers, both built on all cores\n",
           s->segment_count, all_variants[variant_index(BASELINE_KEY)].embree_rate);
    printf("strands: %zu, %s; arrays: %s (the steps: plain memory, in the same order)\n", layout->strands,
           layout_order_text(layout), layout_memory_text(layout, memory, sizeof memory));
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

int run_motion(const options *o)
{
    static motion_result results[MOTION_ROWS][MOTION_LIBRARIES];
    float *steps[MOTION_ROWS][MOTION_MAX_STEPS];
    hair_scene s;
    scene_layout layout;
    char why[TEST_DATA_WHY_SIZE];
    ray_set rays[RAY_KIND_COUNT];
    int failures = 0;
    memset(results, 0, sizeof results);
    memset(steps, 0, sizeof steps);
    memset(rays, 0, sizeof rays);
    if (load_scene(o, "combed", 0, &s, &layout, why) != 0) {
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
            r->has_accuracy = accuracy_measure(&r->accel.tracer, &a, 0, &r->accuracy) == 0;
        }
        accuracy_free(&a);
        progress("done");
    }
    if (!failures) {
        motion_print(o, &s, &layout, rays, accuracy_rays, reference_seconds, results);
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
