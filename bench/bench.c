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
/* The parts: bench/bench.h lists them. */
#include "bench/bench.h"

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
    test_allocator_init_meter(&hairobb_meter, 0);

    print_machine(&o);
    if (o.animate_frames)
        return run_animation(&o, o.animate_frames);
    if (o.save_load_count)
        return run_save_load(&o);
    if (o.motion)
        return run_motion(&o);
    if (o.builds)
        return run_builds(&o);
    if (o.groups)
        return run_groups(&o);
    return run_scenes(&o, selected);
}
