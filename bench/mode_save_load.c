/* mode_save_load.c - --save-load: save and load against build. */
#include "bench/bench.h"

/* --save-load: what a renderer saves by loading a saved BVH instead of
   building it. Per round: a build (default options, all cores), a save into
   memory, a load with the hair check and one without (both from memory,
   nothing of disks in the figures); the loaded BVH must trace as the built
   one (a 64 x 64 camera, compared to the bit). Medians and [min-max]. */
int run_save_load(const options *o)
{
    int failures = 0;
    printf("\nsave and load against build: combed (strands in %s order, arrays in %s), default options, all cores, "
           "%d rounds\n",
           strand_order_names[o->strand_order == STRAND_ORDER_UNSET ? STRAND_ORDER_GROOM : o->strand_order],
           o->huge_pages ? "memory advised MADV_HUGEPAGE" : "plain malloc memory", o->rounds);
    printf("%12s %10s %20s %20s %20s %20s %10s\n", "segments", "bytes/seg", "build s", "save s", "load s", "load unchecked s",
           "build/load");
    for (int c = 0; c < o->save_load_count; c++) {
        hair_scene s;
        scene_layout layout;
        char why[TEST_DATA_WHY_SIZE];
        double build_s[MAX_ROUNDS], save_s[MAX_ROUNDS], load_s[MAX_ROUNDS], unchecked_s[MAX_ROUNDS];
        size_t size = 0;
        int ok = 1;
        progress_start("save/load: combed %zu segments", o->save_load_segments[c]);
        if (load_scene(o, "combed", o->save_load_segments[c], &s, &layout, why) != 0) {
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
    return failures ? 1 : 0;
}
