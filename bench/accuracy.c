/* accuracy.c - the reference's answers (tests/reference.h, in double
   precision; for round curves tests/ref_tube.h's tube) on a fixed random
   subset of the primary rays, and a tracer's errors against them: hit/miss
   disagreements, |t - t_ref| / r, |u - u_ref|. */
#include "bench/bench.h"

typedef struct reference_context {
    const ref_scene *scene;
    accuracy_set *set;
    size_t first; /* of the rays traced */
} reference_context;

static void reference_block(void *context, size_t begin, size_t end)
{
    reference_context *c = (reference_context *)context;
    for (size_t i = c->first + begin; i < c->first + end; i++)
        c->set->ref_hits[i] = ref_intersect(c->scene, c->set->rays.org + 3 * i, c->set->rays.dir + 3 * i, 0.0,
                                            INFINITY, &c->set->ref[i]);
}

static void tube_reference_block(void *context, size_t begin, size_t end)
{
    reference_context *c = (reference_context *)context;
    for (size_t i = c->first + begin; i < c->first + end; i++)
        c->set->tube_hits[i] = ref_tube_intersect_scene(c->scene, c->set->rays.org + 3 * i, c->set->rays.dir + 3 * i, 0.0,
                                                        INFINITY, &c->set->tube[i]);
}

/* The reference's answers for the set's rays [first, end). */
void reference_trace(const ref_scene *reference, accuracy_set *a, size_t first, size_t end,
                     unsigned thread_count)
{
    reference_context context = {reference, a, first};
    parallel_for(end - first, thread_count, reference_block, &context);
}

/* Picks `wanted` distinct primary rays with a fixed seed (partial
   Fisher-Yates) and copies them, without their times; the same rays on
   every call. */
int accuracy_pick(const ray_set *primary, size_t wanted, accuracy_set *a)
{
    memset(a, 0, sizeof *a);
    size_t n = wanted < primary->count ? wanted : primary->count;
    uint32_t *order = (uint32_t *)malloc((primary->count ? primary->count : 1) * sizeof(uint32_t));
    a->ref = (ref_hit *)malloc((n ? n : 1) * sizeof(ref_hit));
    a->ref_hits = (int *)malloc((n ? n : 1) * sizeof(int));
    if (!order || !a->ref || !a->ref_hits || ray_set_alloc(&a->rays, RAYS_PRIMARY, n) != 0) {
        free(order);
        return 1;
    }
    for (size_t i = 0; i < primary->count; i++)
        order[i] = (uint32_t)i;
    scene_rng rng;
    scene_rng_seed(&rng, 777);
    for (size_t i = 0; i < n; i++) {
        size_t j = i + scene_rng_below(&rng, (uint32_t)(primary->count - i));
        uint32_t chosen = order[j];
        order[j] = order[i];
        order[i] = chosen;
        memcpy(a->rays.org + 3 * i, primary->org + 3 * (size_t)chosen, 3 * sizeof(float));
        memcpy(a->rays.dir + 3 * i, primary->dir + 3 * (size_t)chosen, 3 * sizeof(float));
        a->rays.tfar[i] = primary->tfar[chosen];
    }
    free(order);
    return 0;
}

/* accuracy_pick, and the picked rays traced with the reference only (and
   the tube reference where tubes is set). */
int accuracy_prepare(const hair_scene *s, const ray_set *primary, size_t wanted, unsigned thread_count, int tubes,
                     accuracy_set *a)
{
    if (accuracy_pick(primary, wanted, a) != 0)
        return 1;
    double start = scene_now();
    /* the reference reads Bezier segments: a Catmull-Rom scene's are converted for it, then freed */
    hair_scene bezier;
    const hair_scene *input = s;
    if (s->basis != SCENE_BASIS_BEZIER) {
        if (scene_to_bezier(s, &bezier) != 0)
            return 1;
        input = &bezier;
    }
    ref_scene *reference = ref_build(input->vertices, input->vertex_count, input->indices, input->segment_count);
    if (input == &bezier)
        scene_free(&bezier);
    if (!reference)
        return 1;
    reference_trace(reference, a, 0, a->rays.count, thread_count);
    if (tubes) {
        size_t n = a->rays.count;
        a->tube = (ref_tube_hit *)malloc((n ? n : 1) * sizeof(ref_tube_hit));
        a->tube_hits = (int *)malloc((n ? n : 1) * sizeof(int));
        if (!a->tube || !a->tube_hits) {
            ref_free(reference);
            return 1;
        }
        reference_context context = {reference, a, 0};
        parallel_for(n, thread_count, tube_reference_block, &context);
    }
    ref_free(reference);
    a->seconds = scene_now() - start;
    return 0;
}

void accuracy_free(accuracy_set *a)
{
    ray_set_free(&a->rays);
    free(a->ref);
    free(a->ref_hits);
    free(a->tube);
    free(a->tube_hits);
    memset(a, 0, sizeof *a);
}

/* The tracer's answers on the set's rays against the reference's (the
   tube reference's where tube is set): tests/compare.h's tally. */
int accuracy_measure(const tracer *t, const accuracy_set *a, int tube, accuracy_summary *out)
{
    size_t n = a->rays.count;
    accuracy_tally tally;
    memset(out, 0, sizeof *out);
    if (tube && !a->tube)
        return 1;
    hit_record *hits = (hit_record *)malloc((n ? n : 1) * sizeof(hit_record));
    if (!hits || accuracy_tally_init(&tally, n) != 0) {
        free(hits);
        return 1;
    }
    trace_pass(t, &a->rays, hits, 1);
    for (size_t i = 0; i < n; i++) {
        const hit_record *h = &hits[i];
        if (tube)
            accuracy_tally_add(&tally, a->tube_hits[i], a->tube[i].t, a->tube[i].u, a->tube[i].prim_id, a->tube[i].r,
                               h->prim != NO_HIT, h->t, h->u, h->prim);
        else
            accuracy_tally_add(&tally, a->ref_hits[i], a->ref[i].t, a->ref[i].u, a->ref[i].prim_id, a->ref[i].r,
                               h->prim != NO_HIT, h->t, h->u, h->prim);
    }
    accuracy_summarize(&tally, out);
    accuracy_tally_free(&tally);
    free(hits);
    return 0;
}
