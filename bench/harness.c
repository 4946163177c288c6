/* harness.c - the timing harness: every tracer, hairobb's and Embree's,
   is called through one function pointer per ray, on the same thread layout
   and the same ray buffers; passes are timed in rounds (bench/bench.c).

   hairobb's implementation is compiled here, with the tracers that call it,
   so that hairobb_intersect1 can be inlined into its tracer as a renderer
   calling it would have it (`make profile` counts the harness's
   instructions apart: bench/profile.awk names these functions). */
#define HAIROBB_IMPLEMENTATION
#include "bench/bench.h"

#ifdef BENCH_COUNTS
bench_counts bench_count;
#endif

/* ======================================================================== */
/* Tracers                                                                  */
/* ======================================================================== */

/* The harness's ray as hairobb takes it (every ray starts at tnear = 0). */
static void hairobb_tracer_ray(hairobb_ray *ray, const float org[3], const float dir[3], float tfar, float time)
{
    memcpy(ray->org, org, sizeof ray->org);
    memcpy(ray->dir, dir, sizeof ray->dir);
    ray->tnear = 0.0f;
    ray->tfar = tfar;
    ray->time = time;
}

static int hairobb_tracer_intersect(const void *accel, const float org[3], const float dir[3], float tfar, float time,
                                    hit_record *out)
{
    hairobb_ray ray;
    hairobb_hit hit;
    hairobb_tracer_ray(&ray, org, dir, tfar, time);
    if (!hairobb_intersect1((const hairobb_bvh *)accel, &ray, &hit)) {
        out->prim = NO_HIT;
        return 0;
    }
    out->t = hit.t;
    out->u = hit.u;
    memcpy(out->ng, hit.Ng, sizeof out->ng);
    out->prim = hit.prim_id;
    return 1;
}

static int hairobb_tracer_occluded(const void *accel, const float org[3], const float dir[3], float tfar, float time)
{
    hairobb_ray ray;
    hairobb_tracer_ray(&ray, org, dir, tfar, time);
    return hairobb_occluded1((const hairobb_bvh *)accel, &ray);
}

static int embree_tracer_intersect(const void *accel, const float org[3], const float dir[3], float tfar, float time,
                                   hit_record *out)
{
    if (!emb_intersect_at_time((const emb_scene *)accel, org, 0.0f, dir, tfar, time, &out->t, &out->u, NULL,
                               &out->prim)) {
        out->prim = NO_HIT;
        return 0;
    }
    out->ng[0] = out->ng[1] = out->ng[2] = 0.0f;
    return 1;
}

static int embree_tracer_occluded(const void *accel, const float org[3], const float dir[3], float tfar, float time)
{
    return emb_occluded_at_time((const emb_scene *)accel, org, 0.0f, dir, tfar, time);
}

tracer hairobb_tracer(const hairobb_bvh *bvh)
{
    tracer t = {bvh, hairobb_tracer_intersect, hairobb_tracer_occluded};
    return t;
}

tracer embree_tracer(const emb_scene *scene)
{
    tracer t = {scene, embree_tracer_intersect, embree_tracer_occluded};
    return t;
}

/* ======================================================================== */
/* Parallel loop and timing harness                                         */
/* ======================================================================== */

/* Runs work(context, begin, end) over [0, count) in blocks of RAY_BLOCK,
   block b on thread b % thread_count: interleaving spreads the expensive
   image regions (the hair) evenly, without any shared counter. */

typedef struct worker {
    block_work work;
    void *context;
    size_t count;
    unsigned index, thread_count;
} worker;

static void *worker_run(void *argument)
{
    const worker *w = (const worker *)argument;
    for (size_t begin = (size_t)w->index * RAY_BLOCK; begin < w->count;
         begin += (size_t)w->thread_count * RAY_BLOCK) {
        size_t end = begin + RAY_BLOCK < w->count ? begin + RAY_BLOCK : w->count;
        w->work(w->context, begin, end);
    }
    return NULL;
}

void parallel_for(size_t count, unsigned thread_count, block_work work, void *context)
{
    pthread_t threads[256];
    worker workers[256];
    if (thread_count < 1)
        thread_count = 1;
    if (thread_count > 256)
        thread_count = 256;
    unsigned started = 1;
    for (unsigned i = 0; i < thread_count; i++) {
        worker w = {work, context, count, i, thread_count};
        workers[i] = w;
    }
    /* the calling thread is worker 0; if a thread cannot start, the rays it
       would have traced are traced by a second round on this thread */
    for (unsigned i = 1; i < thread_count; i++, started++)
        if (pthread_create(&threads[i], NULL, worker_run, &workers[i]) != 0)
            break;
    worker_run(&workers[0]);
    for (unsigned i = 1; i < started; i++)
        pthread_join(threads[i], NULL);
    for (unsigned i = started; i < thread_count; i++)
        worker_run(&workers[i]);
}

typedef struct trace_context {
    const tracer *tracer;
    const ray_set *rays;
    hit_record *hits;
} trace_context;

static void trace_block(void *context, size_t begin, size_t end)
{
    const trace_context *c = (const trace_context *)context;
    const ray_set *r = c->rays;
    if (r->kind == RAYS_SHADOW) {
        for (size_t i = begin; i < end; i++)
            c->hits[i].prim = c->tracer->occluded(c->tracer->accel, r->org + 3 * i, r->dir + 3 * i, r->tfar[i],
                                                  r->time ? r->time[i] : 0.0f) ? 0 : NO_HIT;
    } else {
        for (size_t i = begin; i < end; i++)
            c->tracer->intersect(c->tracer->accel, r->org + 3 * i, r->dir + 3 * i, r->tfar[i],
                                 r->time ? r->time[i] : 0.0f, &c->hits[i]);
    }
}

/* Traces the whole ray set once; returns wall seconds. */
double trace_pass(const tracer *t, const ray_set *rays, hit_record *hits, unsigned thread_count)
{
    trace_context context = {t, rays, hits};
    double start = scene_now();
    parallel_for(rays->count, thread_count, trace_block, &context);
    return scene_now() - start;
}

unsigned max_threads(const options *o)
{
    unsigned most = 1;
    for (int t = 0; t < o->thread_count_count; t++)
        most = o->thread_counts[t] > most ? o->thread_counts[t] : most;
    return most;
}

spread spread_of(const double *values, int n)
{
    spread out = {NAN, NAN, NAN};
    double sorted[MAX_ROUNDS];
    if (n <= 0 || n > MAX_ROUNDS)
        return out;
    memcpy(sorted, values, (size_t)n * sizeof sorted[0]);
    qsort(sorted, (size_t)n, sizeof sorted[0], compare_doubles);
    out.median = n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
    out.min = sorted[0];
    out.max = sorted[n - 1];
    return out;
}

/* "median [min-max]", or "-" when not measured. */
const char *spread_cell(char *cell, size_t size, spread x)
{
    if (isnan(x.median))
        snprintf(cell, size, "-");
    else
        snprintf(cell, size, "%.2f [%.2f-%.2f]", x.median, x.min, x.max);
    return cell;
}

/* Times every built variant on each ray set and thread count, in rounds
   (bench/bench.c says why); fills mrays, ratio (to variant base, within
   each round) and the scene's peer_ratio (row peers[p][0] to peers[p][1],
   within each round). The caller looks them up (variant_index): the
   harness knows no variant by name. */
void time_in_rounds(const options *o, workload *w, built_accel accel[VARIANT_COUNT], scene_result *sr, int base,
                    int peers[PEER_PAIR_COUNT][2])
{
    static double mrays[VARIANT_COUNT][MAX_ROUNDS];
    for (int p = 0; p < PEER_PAIR_COUNT; p++)
        for (int k = 0; k < RAY_KIND_COUNT; k++)
            for (int t = 0; t < MAX_THREAD_COUNTS; t++)
                sr->peer_ratio[p][k][t] = (spread){NAN, NAN, NAN};
    for (int k = 0; k < RAY_KIND_COUNT; k++) {
        const ray_set *rays = &w->rays[k];
        if (!o->ray_kind_enabled[k] || rays->count == 0)
            continue;
        for (int t = 0; t < o->thread_count_count; t++) {
            unsigned threads = o->thread_counts[t];
            progress_start("  %s rays, %u thread%s: warm-up", ray_kind_names[k], threads, threads == 1 ? "" : "s");
            for (int i = 0; i < VARIANT_COUNT; i++) /* caches, page faults, Embree's lazy set-up */
                if (sr->variants[i].measured)
                    trace_pass(&accel[i].tracer, rays, w->hits, threads);
            for (int round = 0; round < o->rounds; round++) {
                progress_start("  %s rays, %u thread%s: round %d of %d", ray_kind_names[k], threads,
                               threads == 1 ? "" : "s", round + 1, o->rounds);
                for (int i = 0; i < VARIANT_COUNT; i++)
                    if (sr->variants[i].measured)
                        mrays[i][round] = (double)rays->count / trace_pass(&accel[i].tracer, rays, w->hits, threads) * 1e-6;
            }
            progress("done");
            for (int i = 0; i < VARIANT_COUNT; i++) {
                variant_result *r = &sr->variants[i];
                double ratios[MAX_ROUNDS];
                if (!r->measured)
                    continue;
                for (int round = 0; round < o->rounds; round++)
                    ratios[round] = sr->variants[base].measured ? mrays[i][round] / mrays[base][round] : NAN;
                r->ratio[k][t] = spread_of(ratios, sr->variants[base].measured ? o->rounds : 0);
                r->mrays[k][t] = spread_of(mrays[i], o->rounds);
            }
            for (int p = 0; p < PEER_PAIR_COUNT; p++) {
                int row = peers[p][0], peer = peers[p][1];
                double ratios[MAX_ROUNDS];
                if (row < 0 || peer < 0 || !sr->variants[row].measured || !sr->variants[peer].measured)
                    continue;
                for (int round = 0; round < o->rounds; round++)
                    ratios[round] = mrays[row][round] / mrays[peer][round];
                sr->peer_ratio[p][k][t] = spread_of(ratios, o->rounds);
            }
        }
    }
}
