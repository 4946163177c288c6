/* mode_animate.c - --animate N: refit against rebuild over an animation. */
#include "bench/bench.h"

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
int run_animation(const options *o, int frames)
{
    hair_scene rest;
    scene_layout layout;
    char why[TEST_DATA_WHY_SIZE], memory[256];
    if (load_scene(o, "combed", 0, &rest, &layout, why) != 0) {
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
    printf("strands: %zu, %s; arrays: %s (the poses: plain malloc memory)\n", layout.strands,
           layout_order_text(&layout), layout_memory_text(&layout, memory, sizeof memory));
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
