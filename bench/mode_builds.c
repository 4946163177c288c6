/* mode_builds.c - --builds: build time against Embree, in rounds. */
#include "bench/bench.h"

/* --builds: per scene, --rounds rounds of three builds, each freed before
   the next: hairobb's defaults (the Bezier copy included) on all cores, the
   same on 1 thread, Embree flat r4 on all cores (a Catmull-Rom scene: both
   read its Catmull-Rom curves). Medians [min-max] of the seconds, and of the
   ratios to Embree taken within each round; bytes a segment and hairobb's
   transient bytes a segment (allocator meter). On stdout, and a row a scene
   and build in the TSV (--tsv). */
int run_builds(const options *o)
{
    enum { ALL_CORES, ONE_THREAD, EMBREE, BUILDS };
    static const char *const names[BUILDS] = {"hairobb, all cores", "hairobb, 1 thread", "Embree flat r4, all cores"};
    int failures = 0;
    static const char *const keys[BUILDS] = {"hairobb", "hairobb-1t", "embree-r4"};
    FILE *tsv = fopen(o->tsv_path, "w");
    if (!tsv)
        fprintf(stderr, "bench: cannot write %s: %s\n", o->tsv_path, strerror(errno));
    else
        fputs("scene\tsegments\tbuild\tlabel\tseconds\tseconds_min\tseconds_max\tratio\tratio_min\tratio_max"
              "\tbytes_per_segment\ttransient_bytes_per_segment\trounds\n", tsv);
    printf("\nbuild time in rounds (%d rounds; each round builds the three in turn, each freed before the next)\n", o->rounds);
    printf("%-12s %12s %-26s %-24s %-24s %-18s %s\n", "scene", "segments", "build", "seconds", "/ Embree (in round)",
           "bytes/segment", "transient b/seg");
    for (int c = 0; c < o->scene_count; c++) {
        hair_scene s;
        scene_layout layout;
        char why[TEST_DATA_WHY_SIZE], arrays[256];
        int loaded = load_scene(o, o->scenes[c], scene_segments(o, c), &s, &layout, why);
        if (loaded != 0) {
            printf("%-12s skipped: %s\n", o->scenes[c], loaded < 0 ? why : "could not be loaded");
            failures += loaded > 0;
            continue;
        }
        printf("%-12s %12zu strands: %zu, %s; arrays: %s\n", o->scenes[c], s.segment_count, layout.strands,
               layout_order_text(&layout), layout_memory_text(&layout, arrays, sizeof arrays));
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
            if (tsv) {
                fprintf(tsv, "%s\t%zu\t%s\t%s", s.name, s.segment_count, keys[k], names[k]);
                tsv_number(tsv, "\t%.6f", t.median);
                tsv_number(tsv, "\t%.6f", t.min);
                tsv_number(tsv, "\t%.6f", t.max);
                tsv_number(tsv, "\t%.4f", builds == BUILDS ? q.median : NAN);
                tsv_number(tsv, "\t%.4f", builds == BUILDS ? q.min : NAN);
                tsv_number(tsv, "\t%.4f", builds == BUILDS ? q.max : NAN);
                tsv_number(tsv, "\t%.3f", (double)memory[k] / (double)s.segment_count);
                tsv_number(tsv, "\t%.3f", k != EMBREE ? (double)transient / (double)s.segment_count : NAN);
                fprintf(tsv, "\t%d\n", o->rounds);
            }
        }
        scene_free(&s);
    }
    if (tsv) {
        fclose(tsv);
        printf("TSV: %s\n", o->tsv_path);
    }
    return failures ? 1 : 0;
}
