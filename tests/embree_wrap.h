/* embree_wrap.h - Embree 3 as the reference for hairobb's tests and benchmarks.
 *
 * Header-only; every function is `static inline` (static, and inline only so
 * that a program using part of the header gets no -Wunused-function warning).
 * C99 and C++11. Link with -lembree3. Includes scenes.h (for its clock), so
 * the same rule applies: a C file must define _POSIX_C_SOURCE 200809L before
 * its first #include.
 *
 * One scene = one Embree device + one curve geometry that shares the
 * caller's buffers (hairobb's layout: float4 x, y, z, radius vertices,
 * 16-byte aligned with 16 bytes of padding; uint32 index of each segment's
 * first control point). The buffers must outlive the emb_scene.
 *
 * Embree drops curve hits with t <= 2*r/|dir| (its self-intersection rule),
 * so compare against it with rays that start away from hair.
 */
#ifndef HAIROBB_TESTS_EMBREE_WRAP_H
#define HAIROBB_TESTS_EMBREE_WRAP_H

#include <embree3/rtcore.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scenes.h" /* scene_now */

enum {
    EMB_FLAT_BEZIER = 0,  /* RTC_GEOMETRY_TYPE_FLAT_BEZIER_CURVE: ray-facing ribbon */
    EMB_ROUND_BEZIER = 1, /* RTC_GEOMETRY_TYPE_ROUND_BEZIER_CURVE: a swept circle (tests/ref_tube.h) */
    /* ray-facing ribbons in the other bases (emb_build_curves) */
    EMB_FLAT_BSPLINE = 2,
    EMB_FLAT_CATMULL_ROM = 3,
    EMB_FLAT_HERMITE = 4, /* needs tangents */
    EMB_FLAT_LINEAR = 5,
    EMB_ROUND_CATMULL_ROM = 6 /* a swept circle along Catmull-Rom segments (the bench's yeti scene) */
};

typedef struct emb_scene {
    RTCDevice device;
    RTCScene scene;
    /* Embree's running allocation total; updated by several build threads */
    int64_t allocated_bytes;
} emb_scene;

static inline void emb_error_callback(void *user, enum RTCError code, const char *message)
{
    (void)user;
    fprintf(stderr, "embree error %d: %s\n", (int)code, message ? message : "(no message)");
}

static inline bool emb_memory_callback(void *user, ssize_t bytes, bool post)
{
    /* bytes < 0 for frees; post calls only undo refused allocations, and we
       never refuse, so every call simply adds to the total */
    emb_scene *e = (emb_scene *)user;
    (void)post;
#if defined(__GNUC__) || defined(__clang__)
    __atomic_fetch_add(&e->allocated_bytes, (int64_t)bytes, __ATOMIC_RELAXED);
#else
    e->allocated_bytes += (int64_t)bytes; /* not thread safe: use threads=1 */
#endif
    return true;
}

static inline int64_t emb_allocated_bytes(emb_scene *e)
{
#if defined(__GNUC__) || defined(__clang__)
    return __atomic_load_n(&e->allocated_bytes, __ATOMIC_RELAXED);
#else
    return e->allocated_bytes;
#endif
}

static inline void emb_free(emb_scene *e)
{
    if (!e)
        return;
    /* release before free: releasing calls the memory monitor, which writes to e */
    if (e->scene)
        rtcReleaseScene(e->scene);
    if (e->device)
        rtcReleaseDevice(e->device);
    free(e);
}

/* Or'ed into scene_flags, not passed to Embree: the device limited to its
   AVX2 kernels ("isa=avx2"), to tell its AVX-512 from its design; or to
   its SSE4.2 or AVX kernels ("isa=sse4.2", "isa=avx"), what a CPU without
   AVX2 runs (the peers of hairobb's SSE2 path). */
#define EMB_FLAG_ISA_AVX2 (1u << 30)
#define EMB_FLAG_ISA_SSE42 (1u << 29)
#define EMB_FLAG_ISA_AVX (1u << 28)

/* emb_build_curves and emb_build_curves_motion: vertex buffer k (slot k)
   shares time_vertices[k], k < time_steps; time_steps >= 2 sets the
   geometry's time step count (motion blur), 1 builds static curves;
   scene_flags: RTC_SCENE_FLAG_* (0: none). */
static inline emb_scene *emb__build_curve_steps(const float *const *time_vertices, unsigned time_steps,
                                                size_t vertex_count, const uint32_t *indices, size_t segment_count,
                                                int type, const float *tangents, int tessellation_rate,
                                                unsigned scene_flags, int threads, size_t *memory_bytes,
                                                double *build_seconds)
{
    static const enum RTCGeometryType types[] = {
        RTC_GEOMETRY_TYPE_FLAT_BEZIER_CURVE, RTC_GEOMETRY_TYPE_ROUND_BEZIER_CURVE, RTC_GEOMETRY_TYPE_FLAT_BSPLINE_CURVE,
        RTC_GEOMETRY_TYPE_FLAT_CATMULL_ROM_CURVE, RTC_GEOMETRY_TYPE_FLAT_HERMITE_CURVE, RTC_GEOMETRY_TYPE_FLAT_LINEAR_CURVE,
        RTC_GEOMETRY_TYPE_ROUND_CATMULL_ROM_CURVE};
    if (memory_bytes)
        *memory_bytes = 0;
    if (build_seconds)
        *build_seconds = 0.0;
    if (type < 0 || type > EMB_ROUND_CATMULL_ROM || (type == EMB_FLAT_HERMITE) != (tangents != NULL)) {
        fprintf(stderr, "emb_build: unknown curve type %d (or tangents for the wrong type)\n", type);
        return NULL;
    }
    if (time_steps < 1 || (time_steps > 1 && tangents)) {
        fprintf(stderr, "emb_build: %u time steps (moving curves take no tangents)\n", time_steps);
        return NULL;
    }
    enum RTCGeometryType geometry_type = types[type];

    emb_scene *e = (emb_scene *)calloc(1, sizeof *e);
    if (!e)
        return NULL;
    char config[48] = "";
    if (threads > 0)
        snprintf(config, sizeof config, "threads=%d", threads);
    if (scene_flags & (EMB_FLAG_ISA_AVX2 | EMB_FLAG_ISA_SSE42 | EMB_FLAG_ISA_AVX)) {   /* not scene flags: the device's ISA */
        const char *isa = scene_flags & EMB_FLAG_ISA_AVX2 ? "isa=avx2" : scene_flags & EMB_FLAG_ISA_AVX ? "isa=avx" : "isa=sse4.2";
        if (config[0])
            strncat(config, ",", sizeof config - strlen(config) - 1);
        strncat(config, isa, sizeof config - strlen(config) - 1);
        scene_flags &= ~(EMB_FLAG_ISA_AVX2 | EMB_FLAG_ISA_SSE42 | EMB_FLAG_ISA_AVX);
    }
    e->device = rtcNewDevice(config[0] ? config : NULL);
    if (!e->device) {
        /* no device to call back yet: ask for the error directly */
        fprintf(stderr, "embree error %d: rtcNewDevice failed\n", (int)rtcGetDeviceError(NULL));
        emb_free(e);
        return NULL;
    }
    rtcSetDeviceErrorFunction(e->device, emb_error_callback, NULL);
    rtcSetDeviceMemoryMonitorFunction(e->device, emb_memory_callback, e);

    e->scene = rtcNewScene(e->device);
    RTCGeometry geometry = rtcNewGeometry(e->device, geometry_type);
    if (!e->scene || !geometry) {
        if (geometry)
            rtcReleaseGeometry(geometry);
        emb_free(e);
        return NULL;
    }
    if (time_steps > 1)
        rtcSetGeometryTimeStepCount(geometry, time_steps);
    /* Embree only reads shared buffers; its API is not const-qualified. */
    for (unsigned k = 0; k < time_steps; k++)
        rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, k, RTC_FORMAT_FLOAT4, (void *)time_vertices[k], 0,
                                   4 * sizeof(float), vertex_count);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, (void *)indices, 0,
                               sizeof(uint32_t), segment_count);
    if (tangents)
        rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_TANGENT, 0, RTC_FORMAT_FLOAT4, (void *)tangents, 0,
                                   4 * sizeof(float), vertex_count);
    if (tessellation_rate > 0)
        rtcSetGeometryTessellationRate(geometry, (float)tessellation_rate);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(e->scene, geometry);
    rtcReleaseGeometry(geometry); /* the scene holds its own reference */
    rtcSetSceneBuildQuality(e->scene, RTC_BUILD_QUALITY_MEDIUM);
    if (scene_flags)
        rtcSetSceneFlags(e->scene, (enum RTCSceneFlags)scene_flags);

    int64_t before = emb_allocated_bytes(e);
    double start = scene_now();
    rtcCommitScene(e->scene);
    double seconds = scene_now() - start;
    int64_t grown = emb_allocated_bytes(e) - before;
    if (rtcGetDeviceError(e->device) != RTC_ERROR_NONE) { /* message already printed */
        emb_free(e);
        return NULL;
    }
    if (memory_bytes)
        *memory_bytes = grown > 0 ? (size_t)grown : 0;
    if (build_seconds)
        *build_seconds = seconds;
    return e;
}

/* Builds an Embree scene over the caller's buffers (shared, not copied).
   type: EMB_*; tangents: for EMB_FLAT_HERMITE only; tessellation_rate: 0 = Embree's
   default, else rtcSetGeometryTessellationRate (flat curves); threads: 0 =
   all cores, else "threads=N". Build quality medium (Embree's default), no
   scene flags. memory_bytes (optional) = bytes Embree allocated during
   rtcCommitScene, net of what it freed; build_seconds (optional) = wall time
   of rtcCommitScene. Returns NULL on failure, after Embree's message has been
   printed to stderr. */
static inline emb_scene *emb_build_curves(const float *vertices, size_t vertex_count, const uint32_t *indices,
                                          size_t segment_count, int type, const float *tangents, int tessellation_rate,
                                          int threads, size_t *memory_bytes, double *build_seconds)
{
    return emb__build_curve_steps(&vertices, 1, vertex_count, indices, segment_count, type, tangents,
                                  tessellation_rate, 0, threads, memory_bytes, build_seconds);
}

/* emb_build_curves with scene flags (rtcSetSceneFlags, RTC_SCENE_FLAG_*
   or'ed; 0 = none): RTC_SCENE_FLAG_COMPACT for Embree's compact leaves and
   nodes, RTC_SCENE_FLAG_ROBUST for its robust traversal (Cycles sets it). */
static inline emb_scene *emb_build_curves_flags(const float *vertices, size_t vertex_count, const uint32_t *indices,
                                                size_t segment_count, int type, const float *tangents,
                                                int tessellation_rate, unsigned scene_flags, int threads,
                                                size_t *memory_bytes, double *build_seconds)
{
    return emb__build_curve_steps(&vertices, 1, vertex_count, indices, segment_count, type, tangents,
                                  tessellation_rate, scene_flags, threads, memory_bytes, build_seconds);
}

/* Moving curves (motion blur), as emb_build_curves without tangents: the
   hair at time_steps >= 2 times k / (time_steps - 1), step k in
   time_vertices[k] (vertex_count points each, the same indices), through
   rtcSetGeometryTimeStepCount and one shared vertex buffer per step; rays
   carry their time (emb_intersect_at_time, emb_occluded_at_time). */
static inline emb_scene *emb_build_curves_motion(const float *const *time_vertices, unsigned time_steps,
                                                 size_t vertex_count, const uint32_t *indices, size_t segment_count,
                                                 int type, int tessellation_rate, int threads, size_t *memory_bytes,
                                                 double *build_seconds)
{
    if (time_steps < 2) {
        fprintf(stderr, "emb_build_curves_motion: %u time steps (at least 2)\n", time_steps);
        return NULL;
    }
    return emb__build_curve_steps(time_vertices, time_steps, vertex_count, indices, segment_count, type, NULL,
                                  tessellation_rate, 0, threads, memory_bytes, build_seconds);
}

/* Bezier curves (flat or round): emb_build_curves without tangents. */
static inline emb_scene *emb_build(const float *vertices, size_t vertex_count, const uint32_t *indices,
                                   size_t segment_count, int type, int tessellation_rate, int threads,
                                   size_t *memory_bytes, double *build_seconds)
{
    if (type != EMB_FLAT_BEZIER && type != EMB_ROUND_BEZIER) {
        fprintf(stderr, "emb_build: unknown curve type %d\n", type);
        return NULL;
    }
    return emb_build_curves(vertices, vertex_count, indices, segment_count, type, NULL, tessellation_rate, threads,
                            memory_bytes, build_seconds);
}

/* Several hair groups as Embree holds them: one scene of `groups` curve
   geometries of `type` (flat or round Bezier), geometry g over the shared
   vertex buffer with its own index buffer (group_indices[g],
   group_counts[g] segments). Embree builds one tree over every geometry of
   a scene (its leaves hold one geometry each). As emb_build otherwise. */
static inline emb_scene *emb_build_groups(const float *vertices, size_t vertex_count, const uint32_t *const *group_indices,
                                          const size_t *group_counts, size_t groups, int type, int threads, size_t *memory_bytes,
                                          double *build_seconds)
{
    emb_scene *e;
    char config[32] = "";
    size_t g;
    if (memory_bytes)
        *memory_bytes = 0;
    if (build_seconds)
        *build_seconds = 0.0;
    if (type != EMB_FLAT_BEZIER && type != EMB_ROUND_BEZIER)
        return NULL;
    e = (emb_scene *)calloc(1, sizeof *e);
    if (!e)
        return NULL;
    if (threads > 0)
        snprintf(config, sizeof config, "threads=%d", threads);
    e->device = rtcNewDevice(config[0] ? config : NULL);
    if (!e->device) {
        free(e);
        return NULL;
    }
    rtcSetDeviceErrorFunction(e->device, emb_error_callback, NULL);
    rtcSetDeviceMemoryMonitorFunction(e->device, emb_memory_callback, e);
    e->scene = rtcNewScene(e->device);
    for (g = 0; e->scene && g < groups; g++) {
        RTCGeometry geometry = rtcNewGeometry(e->device, type == EMB_ROUND_BEZIER ? RTC_GEOMETRY_TYPE_ROUND_BEZIER_CURVE
                                                                                   : RTC_GEOMETRY_TYPE_FLAT_BEZIER_CURVE);
        if (!geometry) {
            emb_free(e);
            return NULL;
        }
        rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, (void *)vertices, 0, 4 * sizeof(float),
                                   vertex_count);
        rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, (void *)group_indices[g], 0, sizeof(uint32_t),
                                   group_counts[g]);
        rtcCommitGeometry(geometry);
        rtcAttachGeometryByID(e->scene, geometry, (unsigned)g);
        rtcReleaseGeometry(geometry);
    }
    if (!e->scene) {
        emb_free(e);
        return NULL;
    }
    rtcSetSceneBuildQuality(e->scene, RTC_BUILD_QUALITY_MEDIUM);
    {
        int64_t before = emb_allocated_bytes(e), grown;
        double start = scene_now();
        rtcCommitScene(e->scene);
        if (build_seconds)
            *build_seconds = scene_now() - start;
        grown = emb_allocated_bytes(e) - before;
        if (memory_bytes)
            *memory_bytes = grown > 0 ? (size_t)grown : 0;
    }
    if (rtcGetDeviceError(e->device) != RTC_ERROR_NONE) {
        emb_free(e);
        return NULL;
    }
    return e;
}

static inline void emb_init_ray(struct RTCRay *ray, const float org[3], float tnear, const float dir[3], float tfar)
{
    ray->org_x = org[0]; ray->org_y = org[1]; ray->org_z = org[2];
    ray->dir_x = dir[0]; ray->dir_y = dir[1]; ray->dir_z = dir[2];
    ray->tnear = tnear;
    ray->tfar = tfar;
    ray->time = 0.0f;
    ray->mask = 0xFFFFFFFFu;
    ray->id = 0;
    ray->flags = 0;
}

/* Closest hit in [tnear, tfar] of a ray at `time` (in [0, 1]; read by
   moving curves only): returns 1 and fills t, u (curve parameter), v and
   prim (segment index), any of which may be NULL; 0 on a miss. */
static inline int emb_intersect_at_time(const emb_scene *e, const float org[3], float tnear, const float dir[3],
                                        float tfar, float time, float *t, float *u, float *v, uint32_t *prim)
{
    struct RTCRayHit ray_hit;
    emb_init_ray(&ray_hit.ray, org, tnear, dir, tfar);
    ray_hit.ray.time = time;
    ray_hit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    ray_hit.hit.primID = RTC_INVALID_GEOMETRY_ID;
    ray_hit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rtcIntersect1(e->scene, &context, &ray_hit);
    if (ray_hit.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return 0;
    if (t)
        *t = ray_hit.ray.tfar;
    if (u)
        *u = ray_hit.hit.u;
    if (v)
        *v = ray_hit.hit.v;
    if (prim)
        *prim = ray_hit.hit.primID;
    return 1;
}

/* emb_intersect_at_time that also names the geometry hit (emb_build_groups). */
static inline int emb_intersect_group(const emb_scene *e, const float org[3], const float dir[3], float tfar, float *t, float *u,
                                      uint32_t *geometry, uint32_t *prim)
{
    struct RTCRayHit ray_hit;
    struct RTCIntersectContext context;
    emb_init_ray(&ray_hit.ray, org, 0.0f, dir, tfar);
    ray_hit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    ray_hit.hit.primID = RTC_INVALID_GEOMETRY_ID;
    ray_hit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcInitIntersectContext(&context);
    rtcIntersect1(e->scene, &context, &ray_hit);
    if (ray_hit.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return 0;
    *t = ray_hit.ray.tfar;
    *u = ray_hit.hit.u;
    *geometry = ray_hit.hit.geomID;
    *prim = ray_hit.hit.primID;
    return 1;
}

/* emb_intersect_at_time at time 0. */
static inline int emb_intersect(const emb_scene *e, const float org[3], float tnear, const float dir[3], float tfar,
                                float *t, float *u, float *v, uint32_t *prim)
{
    return emb_intersect_at_time(e, org, tnear, dir, tfar, 0.0f, t, u, v, prim);
}

/* Any hit in [tnear, tfar] of a ray at `time`: 1 if occluded, else 0. */
static inline int emb_occluded_at_time(const emb_scene *e, const float org[3], float tnear, const float dir[3],
                                       float tfar, float time)
{
    struct RTCRay ray;
    emb_init_ray(&ray, org, tnear, dir, tfar);
    ray.time = time;
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rtcOccluded1(e->scene, &context, &ray);
    /* Embree marks an occluded ray by setting tfar to -inf */
    return ray.tfar < 0.0f;
}

/* emb_occluded_at_time at time 0. */
static inline int emb_occluded(const emb_scene *e, const float org[3], float tnear, const float dir[3], float tfar)
{
    return emb_occluded_at_time(e, org, tnear, dir, tfar, 0.0f);
}

#endif /* HAIROBB_TESTS_EMBREE_WRAP_H */
