/* ab_copy.c - one copy of hairobb for bench/ab.c, compiled twice: once
   from the version under test and once from the base version
   (-DAB_HEADER, -DAB_NAME(x) gives each copy's names). HAIROBB_STATIC
   keeps the two implementations apart in one program (and lets ab.c's
   build mode hash the tree's internals). -DAB_ROUND builds
   both with round curves (CFLAGS_AB=-DAB_ROUND). */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE   /* madvise(MADV_HUGEPAGE), as gnu C and C++ builds and the bench have it (HAIROBB_NO_HUGE_PAGES) */
#define HAIROBB_STATIC
#define HAIROBB_IMPLEMENTATION
#include AB_HEADER
#include "ab.h"

/* threads: the build's (0: one per core) */
void *AB_NAME(build_threads)(const hair_scene *s, unsigned threads)
{
    hairobb_bvh *bvh = NULL;
    hairobb_build_options options;
    memset(&options, 0, sizeof options);
    options.threads = threads;
#ifdef AB_ROUND
    options.shape = HAIROBB_SHAPE_ROUND;
#endif
    return hairobb_build(s->vertices, s->vertex_count, s->indices, s->segment_count, &options, &bvh) == HAIROBB_OK ? bvh : NULL;
}

void *AB_NAME(build)(const hair_scene *s) { return AB_NAME(build_threads)(s, 0); }

/* A hash of what the tree is (the copy's own hairobb__hash): its nodes'
   bytes, the leaves' segment ids and the root; the two copies must build
   the same tree (--builds) */
uint64_t AB_NAME(tree_hash)(const void *tree)
{
    const hairobb_bvh *bvh = (const hairobb_bvh *)tree;
    uint64_t h = hairobb__hash(0, bvh->nodes, bvh->node_bytes);
    h = hairobb__hash(h, bvh->leaf_prims, sizeof(uint32_t) * bvh->leaf_prim_count);
    return hairobb__hash(h, &bvh->root, sizeof bvh->root);
}

void AB_NAME(free)(void *bvh) { hairobb_free((hairobb_bvh *)bvh); }

uint64_t AB_NAME(trace)(void *bvh, const ab_rays *r, ab_hit *hits)
{
    uint64_t sum = 0;
    size_t i;
    for (i = 0; i < r->count; ++i) {
        hairobb_ray ray;
        hairobb_hit hit, from;
        int got;
        memcpy(ray.org, r->org + 3 * i, sizeof ray.org);
        memcpy(ray.dir, r->dir + 3 * i, sizeof ray.dir);
        ray.tnear = 0.0f;
        ray.tfar = INFINITY;
        ray.time = 0.0f;
        if (r->kind == AB_PRIMARY) {
            got = hairobb_intersect1((hairobb_bvh *)bvh, &ray, &hit);
            if (hits) {   /* the secondary rays leave these hits: the two copies find the same ones */
                hits[i].prim_id = hit.prim_id;
                hits[i].t = hit.t;
                memcpy(hits[i].Ng, hit.Ng, sizeof hits[i].Ng);
            }
        } else {
            from.prim_id = hits[i].prim_id;   /* prim_id is read of `from`, and Ng for round curves */
            from.t = hits[i].t;
            memcpy(from.Ng, hits[i].Ng, sizeof from.Ng);
            got = r->kind == AB_SHADOW ? hairobb_occluded1_from((hairobb_bvh *)bvh, &from, &ray)
                                       : hairobb_intersect1_from((hairobb_bvh *)bvh, &from, &ray, &hit);
        }
        /* every bit of the answer enters the sum, so that copies that
           disagree on any hit are caught */
        if (got && r->kind != AB_SHADOW) {
            uint32_t bits;
            memcpy(&bits, &hit.t, sizeof bits);
            sum = sum * 1099511628211ull + hit.prim_id * 31ull + bits;
        } else {
            sum = sum * 1099511628211ull + (uint64_t)got;
        }
    }
    return sum;
}
