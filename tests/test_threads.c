/* test_threads.c - threads, black-box: a build on several threads gives the
   tree of a build on one (same statistics, same memory, the same hits to the
   bit), so do builds through a user's parallel_for (the test's own task
   system on 3 threads, and one running the tasks backwards), and several
   threads tracing one BVH at once get exactly what one thread gets. `make
   test` also runs it under ThreadSanitizer. */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE   /* madvise(MADV_HUGEPAGE), as gnu C and C++ builds have it (HAIROBB_NO_HUGE_PAGES) */
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include "check.h"
#include "scenes.h"

enum { TRACERS = 4, SIDE = 96, RAYS = SIDE * SIDE };

typedef struct trace_job {
    const hairobb_bvh *bvh;
    const float *org, *dir;
    hairobb_hit hits[RAYS];
    int occluded[RAYS];
} trace_job;

static void trace_all(trace_job *job)
{
    int i;
    for (i = 0; i < RAYS; ++i) {
        hairobb_ray ray;
        memcpy(ray.org, job->org + 3 * i, sizeof ray.org);
        memcpy(ray.dir, job->dir + 3 * i, sizeof ray.dir);
        ray.tnear = 0.0f;
        ray.tfar = INFINITY;
        hairobb_intersect1(job->bvh, &ray, &job->hits[i]);
        job->occluded[i] = hairobb_occluded1(job->bvh, &ray);
    }
}

static void *tracer(void *job)
{
    trace_all((trace_job *)job);
    return NULL;
}

/* A user's task system: 3 threads take the next index under a lock. */
typedef struct task_pool {
    pthread_mutex_t lock;
    unsigned next, count;
    hairobb_task_fn run;
    void *context;
} task_pool;

static void *pool_thread(void *arg)
{
    task_pool *pool = (task_pool *)arg;
    for (;;) {
        unsigned index;
        pthread_mutex_lock(&pool->lock);
        index = pool->next < pool->count ? pool->next++ : pool->count;
        pthread_mutex_unlock(&pool->lock);
        if (index >= pool->count) return NULL;
        pool->run(pool->context, index);
    }
}

static unsigned last_task_count;    /* what the last parallel_for was asked for */

static void for_on_threads(void *user, unsigned count, hairobb_task_fn run, void *context)
{
    task_pool pool;
    pthread_t threads[3];
    int t, started = 0;
    (void)user;
    memset(&pool, 0, sizeof pool);
    pthread_mutex_init(&pool.lock, NULL);
    pool.count = count;
    pool.run = run;
    pool.context = context;
    for (t = 0; t < 3; ++t) started += pthread_create(&threads[t], NULL, pool_thread, &pool) == 0;
    if (started == 0) pool_thread(&pool);
    for (t = 0; t < started; ++t) pthread_join(threads[t], NULL);
    pthread_mutex_destroy(&pool.lock);
    last_task_count = count;
}

/* Every index on the calling thread, last first. */
static void for_backwards(void *user, unsigned count, hairobb_task_fn run, void *context)
{
    unsigned i;
    (void)user;
    for (i = count; i > 0; --i) run(context, i - 1);
    last_task_count = count;
}

/* Bitwise: identical trees and identical code must give identical floats. */
static int same_results(const trace_job *a, const trace_job *b)
{
    int i, differ = 0;
    for (i = 0; i < RAYS; ++i)
        differ += memcmp(&a->hits[i], &b->hits[i], sizeof a->hits[i]) != 0 || a->occluded[i] != b->occluded[i];
    return differ;
}

static void check_scene(hair_scene *s, const hairobb_build_options *base, const char *what)
{
    static trace_job reference, jobs[TRACERS];
    float *org = (float *)malloc(sizeof(float) * 3 * RAYS), *dir = (float *)malloc(sizeof(float) * 3 * RAYS);
    hairobb_build_options options = *base;
    hairobb_bvh *serial = NULL, *parallel = NULL;
    hairobb_stats serial_stats, parallel_stats;
    pthread_t threads[TRACERS];
    int t, started = 0, hits = 0, i;
    scene_camera_rays(s, SIDE, SIDE, org, dir);

    options.threads = 1;
    CHECK(hairobb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, &options, &serial) == HAIROBB_OK,
          "%s %s: build on 1 thread", s->name, what);
    options.threads = 4;            /* more threads than this machine's cores: interleavings vary */
    CHECK(hairobb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, &options, &parallel) == HAIROBB_OK,
          "%s %s: build on 4 threads", s->name, what);
    if (!serial || !parallel) goto done;
    hairobb_get_stats(serial, &serial_stats);
    hairobb_get_stats(parallel, &parallel_stats);
    CHECK(memcmp(&serial_stats, &parallel_stats, sizeof serial_stats) == 0 &&
          hairobb_memory_bytes(serial) == hairobb_memory_bytes(parallel),
          "%s %s: 1 and 4 build threads give other trees (%zu / %zu nodes, %zu / %zu bytes)", s->name, what,
          serial_stats.aabb_nodes + serial_stats.obb_nodes, parallel_stats.aabb_nodes + parallel_stats.obb_nodes,
          hairobb_memory_bytes(serial), hairobb_memory_bytes(parallel));

    reference.bvh = serial; reference.org = org; reference.dir = dir;
    trace_all(&reference);
    for (i = 0; i < RAYS; ++i) hits += reference.hits[i].prim_id != HAIROBB_INVALID_ID;
    CHECK(hits > RAYS / 10, "%s %s: only %d of %d rays hit: the scene does not exercise the tree", s->name, what, hits, RAYS);

    /* the 4-thread build traced on 4 threads at once */
    for (t = 0; t < TRACERS; ++t) {
        jobs[t].bvh = parallel; jobs[t].org = org; jobs[t].dir = dir;
        if (pthread_create(&threads[t], NULL, tracer, &jobs[t]) == 0) ++started;
    }
    for (t = 0; t < started; ++t) pthread_join(threads[t], NULL);
    CHECK(started == TRACERS, "%s %s: %d of %d tracing threads started", s->name, what, started, TRACERS);
    for (t = 0; t < started; ++t) {
        int differ = same_results(&reference, &jobs[t]);
        CHECK(differ == 0, "%s %s: tracing thread %d differs from one thread on %d of %d rays", s->name, what, t,
              differ, RAYS);
    }
    /* a user's task system: the same tree */
    for (t = 0; t < 2; ++t) {
        static const char *systems[] = {"parallel_for on 3 threads", "parallel_for backwards"};
        hairobb_bvh *user_built = NULL;
        hairobb_stats stats;
        options.threads = 0;
        options.parallel_for = t == 0 ? for_on_threads : for_backwards;
        last_task_count = 0;
        CHECK(hairobb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, &options, &user_built) == HAIROBB_OK,
              "%s %s: build through %s", s->name, what, systems[t]);
        if (!user_built) continue;
        CHECK(last_task_count >= 16, "%s %s: %s ran %u tasks", s->name, what, systems[t], last_task_count);
        hairobb_get_stats(user_built, &stats);
        jobs[0].bvh = user_built; jobs[0].org = org; jobs[0].dir = dir;
        trace_all(&jobs[0]);
        i = same_results(&reference, &jobs[0]);
        CHECK(memcmp(&serial_stats, &stats, sizeof stats) == 0 && hairobb_memory_bytes(serial) == hairobb_memory_bytes(user_built) &&
              i == 0, "%s %s: %s gives another tree (%zu / %zu bytes, %d rays differ)", s->name, what, systems[t],
              hairobb_memory_bytes(serial), hairobb_memory_bytes(user_built), i);
        hairobb_free(user_built);
    }
    options.parallel_for = NULL;
    printf("%s, %s: %zu segments, %d of %d rays hit; 1- and 4-thread builds and both parallel_for builds (%u tasks) equal; "
           "%d threads traced alike\n", s->name, what, s->segment_count, hits, RAYS, last_task_count, started);
done:
    hairobb_free(serial);
    hairobb_free(parallel);
    free(org);
    free(dir);
}

int main(void)
{
    hair_scene s;
    hairobb_build_options options;
    memset(&options, 0, sizeof options);
    /* large enough for tens of build tasks: the top is built by the calling thread */
    CHECK(scene_combed(&s, 60000, 3) == 0, "combed scene");
    check_scene(&s, &options, "defaults");
    options.spatial_splits = HAIROBB_ON;
    options.clustering = HAIROBB_ON;
    options.obb_layout = HAIROBB_OBB_PER_CHILD;
    check_scene(&s, &options, "spatial splits, clustering, per-child OBBs");
    scene_free(&s);
    memset(&options, 0, sizeof options);
    CHECK(scene_crossed(&s, 20000, 7) == 0, "crossed scene");
    options.spatial_splits = HAIROBB_ON;
    check_scene(&s, &options, "spatial splits");
    scene_free(&s);
    return check_summary();
}
