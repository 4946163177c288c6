/* embree_swap.c - the same hair buffers given to Embree 3 and to hairobb,
   the same rays traced with both: a renderer author's side-by-side.

       embree_swap [file.hair] [-r rate]
   Without a file: a built-in patch of wavy strands. rate: Embree's
   tessellation rate, the linear pieces per segment it approximates the
   ribbon by (default 4; at 16 it disagrees with hairobb's exact surface
   on 15-20x fewer rays, on the patch as on straight.hair).

   Build: cc -std=c99 -O2 -march=native -I. examples/embree_swap.c -o embree_swap -lembree3 -lm -pthread */
#define _POSIX_C_SOURCE 200809L   /* posix_memalign under -std=c99 */
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include <embree3/rtcore.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RES 256

/* Embree's memory monitor: called with +bytes / -bytes as it allocates and
   frees, from its build threads, so the total is updated atomically. */
static bool count_bytes(void *user, ssize_t bytes, bool post)
{
    (void)post;   /* only undoes allocations we refused; we never refuse */
    __atomic_fetch_add((long long *)user, (long long)bytes, __ATOMIC_RELAXED);
    return true;
}

/* 64 x 64 strands of 4 segments rising from the plane z = 0, each waving in
   its own phase. The buffer layout is the one both libraries read:
   x, y, z, radius per control point, segment i = control points
   indices[i] .. indices[i] + 3, consecutive segments sharing an end. */
static float *make_patch(size_t *vertex_count, uint32_t **indices, size_t *segment_count)
{
    const unsigned n = 64, segs = 4, per = 3 * segs + 1;
    float *v;
    unsigned s, j;
    *vertex_count = (size_t)n * n * per;
    *segment_count = (size_t)n * n * segs;
    /* Embree: 16-byte aligned vertices, and 16 bytes past the last one readable */
    if (posix_memalign((void **)&v, 16, (*vertex_count + 1) * 4 * sizeof(float))) return NULL;
    *indices = malloc(*segment_count * sizeof(uint32_t));
    for (s = 0; s < n * n; s++) {
        float x = (s % n) / (float)n, y = (s / n) / (float)n, phase = 0.37f * s;
        for (j = 0; j < per; j++) {   /* control points sampled along the wave: a smooth strand */
            float h = (float)j / (per - 1), *p = v + 4 * ((size_t)s * per + j);
            p[0] = x + 0.05f * sinf(6 * h + phase);
            p[1] = y + 0.05f * cosf(5 * h + phase);
            p[2] = 0.6f * h;
            p[3] = 0.003f * (1 - 0.5f * h);
        }
        for (j = 0; j < segs; j++) (*indices)[s * segs + j] = s * per + 3 * j;
    }
    for (j = 0; j < 4; j++) v[4 * *vertex_count + j] = 0;   /* the padding */
    return v;
}

int main(int argc, char **argv)
{
    hairobb_hair hair;
    const char *file = NULL;
    float rate = 0;   /* 0: Embree's default */
    float *vertices, lo[3], hi[3], eye[3];
    uint32_t *indices;
    size_t vertex_count, segment_count;
    long long embree_bytes = 0;
    long hits_h = 0, hits_e = 0, disagree = 0, other_segment = 0;
    int x, y, k, a;
    hairobb_bvh *bvh;
    hairobb_result res;
    RTCDevice device;
    RTCScene scene;
    RTCGeometry geom;

    for (a = 1; a < argc; a++) {
        if (!strcmp(argv[a], "-r") && a + 1 < argc) rate = (float)atof(argv[++a]);
        else if (argv[a][0] != '-' && !file) file = argv[a];
        else { fprintf(stderr, "usage: %s [file.hair] [-r tessellation_rate]\n", argv[0]); return 2; }
    }
    if (file) {   /* hairobb's .hair reader pads its vertices as Embree wants */
        if ((res = hairobb_hair_load(file, NULL, &hair)) != HAIROBB_OK) {
            fprintf(stderr, "%s: %s\n", file, hairobb_result_string(res));
            return 1;
        }
        vertices = hair.vertices; vertex_count = hair.vertex_count;
        indices = hair.indices; segment_count = hair.segment_count;
    } else if (!(vertices = make_patch(&vertex_count, &indices, &segment_count))) return 1;

    /* hairobb: one call; the BVH points into the buffers. */
    if ((res = hairobb_build(vertices, vertex_count, indices, segment_count, NULL, &bvh)) != HAIROBB_OK) {
        fprintf(stderr, "hairobb_build: %s\n", hairobb_result_string(res));
        return 1;
    }

    /* Embree: device, scene, a flat (ray-facing) Bezier geometry sharing the
       same two buffers (Embree's API is not const: it only reads them). */
    device = rtcNewDevice(NULL);
    rtcSetDeviceMemoryMonitorFunction(device, count_bytes, &embree_bytes);
    scene = rtcNewScene(device);
    geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_FLAT_BEZIER_CURVE);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, vertices, 0, 4 * sizeof(float), vertex_count);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, indices, 0, sizeof(uint32_t), segment_count);
    if (rate > 0) rtcSetGeometryTessellationRate(geom, rate);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene, geom);
    rtcReleaseGeometry(geom);   /* the scene keeps it */
    rtcCommitScene(scene);
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE) { fprintf(stderr, "embree: build failed\n"); return 1; }

    /* A pinhole camera in front of and above the hair's bounds, looking at their centre. */
    hairobb_bounds(bvh, lo, hi);
    for (k = 0; k < 3; k++) eye[k] = 0.5f * (lo[k] + hi[k]);
    eye[1] -= 2.0f * (hi[2] - lo[2] > hi[0] - lo[0] ? hi[2] - lo[2] : hi[0] - lo[0]);
    eye[2] += 0.5f * (hi[2] - lo[2]);
    for (y = 0; y < RES; y++)
        for (x = 0; x < RES; x++) {
            float c[3], d[3];
            hairobb_ray ray;
            hairobb_hit hit;
            struct RTCRayHit rh;
            struct RTCIntersectContext ctx;
            int h, e;
            for (k = 0; k < 3; k++) c[k] = 0.5f * (lo[k] + hi[k]);
            d[0] = c[0] - eye[0] + 1.3f * (hi[0] - lo[0]) * (x + 0.5f - RES / 2) / RES;
            d[1] = c[1] - eye[1];
            d[2] = c[2] - eye[2] - 1.3f * (hi[2] - lo[2]) * (y + 0.5f - RES / 2) / RES;

            ray.org[0] = eye[0]; ray.org[1] = eye[1]; ray.org[2] = eye[2]; ray.tnear = 0;
            ray.dir[0] = d[0]; ray.dir[1] = d[1]; ray.dir[2] = d[2]; ray.tfar = INFINITY;
            h = hairobb_intersect1(bvh, &ray, &hit);

            /* Embree's ray: the same fields plus time, mask, id, flags, and
               the hit's IDs, which must start out invalid */
            rh.ray.org_x = eye[0]; rh.ray.org_y = eye[1]; rh.ray.org_z = eye[2]; rh.ray.tnear = 0;
            rh.ray.dir_x = d[0]; rh.ray.dir_y = d[1]; rh.ray.dir_z = d[2]; rh.ray.tfar = INFINITY;
            rh.ray.time = 0; rh.ray.mask = 0xffffffffu; rh.ray.id = 0; rh.ray.flags = 0;
            rh.hit.geomID = rh.hit.primID = rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcInitIntersectContext(&ctx);
            rtcIntersect1(scene, &ctx, &rh);
            e = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;

            /* both give t (rh.ray.tfar), u, v and the segment (rh.hit.primID);
               Embree's v is 0..1 across the ribbon (hairobb's is -1..1) */
            hits_h += h; hits_e += e;
            disagree += h != e;
            other_segment += h && e && hit.prim_id != rh.hit.primID;
        }

    printf("%zu segments, %d x %d rays, Embree tessellation rate %g\n", segment_count, RES, RES, rate > 0 ? rate : 4.0);
    printf("hits: hairobb %ld, Embree %ld; hit/miss disagreements %ld, hit other segments %ld\n",
           hits_h, hits_e, disagree, other_segment);
    printf("memory: hairobb %zu bytes (%.1f per segment), Embree %lld bytes (%.1f per segment)\n",
           hairobb_memory_bytes(bvh), (double)hairobb_memory_bytes(bvh) / segment_count,
           embree_bytes, (double)embree_bytes / segment_count);

    hairobb_free(bvh);
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);   /* both before the buffers they read */
    if (file) hairobb_hair_free(&hair);
    else { free(vertices); free(indices); }
    /* Embree approximates the ribbon by linear pieces: near-misses and rays
       grazing the tips differ (0.8% of the hits on the patch at rate 4) */
    return hits_h > 0 && disagree * 50 <= hits_h ? 0 : 1;
}
