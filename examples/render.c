/* render.c - a small hair renderer on hairobb: one .hair file (or a built-in
   fur ball), a pinhole camera framing its bounds, 2x2 samples per pixel,
   Kajiya-Kay shading under two directional lights with ray-traced shadows
   through translucent hair (a hit filter), a PNG out.

       render [file.hair] [-o out.png] [-w width] [-h height] [-z zoom] [--round]

   --round traces the hair as round curves (tubes, HAIROBB_SHAPE_ROUND)
   instead of ray-facing ribbons; -z narrows the field of view zoom times
   about the middle of the hair's box, for a close-up.

   Build: cc -std=c99 -O2 -I. examples/render.c -o render -lm -pthread
   (needs stb_image_write.h: Debian's libstb-dev). */
#define _POSIX_C_SOURCE 200809L   /* clock_gettime, sysconf under -std=c99 */
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define SS 2          /* SS x SS samples per pixel */
#define MAX_THREADS 64

/* What the shader needs, the same for a file and for the built-in fur:
   segment i runs from point segment_point[i] (u = 0) to the next (u = 1),
   colours are per point (or NULL: one colour). */
typedef struct {
    float *vertices; size_t vertex_count;
    uint32_t *indices; size_t segment_count;
    uint32_t *segment_point;
    float *colors; float color[3];
    float skin;       /* > 0: an opaque sphere of this radius at the origin (the fur ball's body) */
} scene;

static double now(void) { struct timespec ts; clock_gettime(CLOCK_MONOTONIC, &ts); return ts.tv_sec + 1e-9 * ts.tv_nsec; }
static float dot3(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void norm3(float a[3]) { float l = sqrtf(dot3(a, a)); if (l > 0) { a[0] /= l; a[1] /= l; a[2] /= l; } }
static void cross3(const float a[3], const float b[3], float c[3])
{ c[0] = a[1] * b[2] - a[2] * b[1]; c[1] = a[2] * b[0] - a[0] * b[2]; c[2] = a[0] * b[1] - a[1] * b[0]; }

static uint32_t rng = 12345u;   /* xorshift: the fur must be the same every run */
static float rnd(void) { rng ^= rng << 13; rng ^= rng >> 17; rng ^= rng << 5; return (rng >> 8) * (1.0f / 16777216.0f); }

/* The built-in fur ball: strands rooted uniformly on a unit sphere, each a
   smooth curve c(s) = root + L (s d + s^2 b) (d leaning off the normal, b a
   droop towards -z plus a random bend), cut into cubic Bezier segments by
   Hermite interpolation so the strand is C1 at its joints. Consecutive
   segments share their end control point, as Embree's buffers allow. */
static void make_fur(scene *sc, unsigned strands, unsigned segs)
{
    unsigned s, j, k, pts = segs + 1;
    sc->segment_count = (size_t)strands * segs;
    sc->vertex_count = (size_t)strands * (3 * segs + 1);
    sc->vertices = malloc(sc->vertex_count * 4 * sizeof(float));
    sc->indices = malloc(sc->segment_count * sizeof(uint32_t));
    sc->segment_point = malloc(sc->segment_count * sizeof(uint32_t));
    sc->colors = malloc((size_t)strands * pts * 3 * sizeof(float));
    sc->skin = 1.0f;
    for (s = 0; s < strands; s++) {
        float z = 1 - 2 * rnd(), phi = 6.2831853f * rnd(), rxy = sqrtf(1 - z * z);
        float n[3] = {rxy * cosf(phi), rxy * sinf(phi), z}, t[3], d[3], b[3];
        float L = 0.3f + 0.2f * rnd(), lean = 0.8f + 0.4f * rnd(), shade = 0.8f + 0.4f * rnd();
        float *v = sc->vertices + (size_t)s * (3 * segs + 1) * 4;
        for (k = 0; k < 3; k++) t[k] = n[k] * z - (k == 2);   /* combed from the top down the meridians: */
        norm3(t);                                            /* a crown on top, the fur lying on the sides */
        for (k = 0; k < 3; k++) {
            d[k] = n[k] + lean * t[k];
            b[k] = 0.4f * (rnd() - 0.5f) - (k == 2 ? 0.3f : 0.0f);
        }
        norm3(d);
        for (j = 0; j <= 3 * segs; j++) {    /* control point j: Bezier points at thirds of each segment */
            float u = (float)(j / 3) / segs, h = 1.0f / segs, *p = v + 4 * j;
            int e = j % 3;                  /* 0: curve point, 1: + tangent/3, 2: next point - tangent/3 */
            if (e == 2) u += h;
            for (k = 0; k < 3; k++) {
                float c = n[k] + L * (u * d[k] + u * u * b[k]), dc = L * (d[k] + 2 * u * b[k]) * h / 3;
                p[k] = c + (e == 1 ? dc : e == 2 ? -dc : 0.0f);
            }
            p[3] = 0.004f * (1 - 0.8f * u);  /* tapering towards the tip */
        }
        for (j = 0; j < segs; j++) {
            sc->indices[s * segs + j] = (uint32_t)(s * (3 * segs + 1) + 3 * j);
            sc->segment_point[s * segs + j] = s * pts + j;
        }
        for (j = 0; j < pts; j++) {         /* darker roots, lighter tips, each strand its own tint */
            float f = shade * (0.45f + 0.55f * j / segs), *c = sc->colors + 3 * (s * pts + j);
            c[0] = 0.55f * f; c[1] = 0.33f * f; c[2] = 0.17f * f;
        }
    }
}

/* The camera and what every row worker reads. */
static struct {
    const hairobb_bvh *bvh; const scene *sc;
    int w, h; float eye[3], fwd[3], right[3], up[3], fov;   /* fov: half the image's height at distance 1 */
    float light[2][3], light_color[2][3];
    unsigned char *pixels;
    pthread_mutex_t lock; int next_row, rows_done; long rays, hits;
} R;

/* Shadow rays pass through hair: each strand crossed lets this share of the
   light through (a crude stand-in for the scattering that keeps light hair
   bright inside). The hit filter sees every strand a ray crosses, with the
   ray the tracer was given, so the ray carries its own tally. */
#define STRAND_TRANSMITTANCE 0.55f
typedef struct {
    hairobb_ray ray;      /* first: the filter gets &ray back */
    int is_shadow;
    float transmitted;    /* shadow rays: the share of light left */
} traced_ray;

static int through_hair(void *user, const hairobb_ray *ray, const hairobb_hit *hit)
{
    traced_ray *r = (traced_ray *)(void *)ray;
    (void)user; (void)hit;
    if (!r->is_shadow) return 1;                 /* camera rays: the nearest hit */
    r->transmitted *= STRAND_TRANSMITTANCE;
    return r->transmitted < 0.01f;               /* nearly dark: take it and stop */
}

/* Distance along the ray to the fur ball's body, or INFINITY. */
static float skin_hit(const float o[3], const float d[3], float tmax)
{
    float b = dot3(o, d), c = dot3(o, o) - R.sc->skin * R.sc->skin, disc = b * b - c, t;
    if (R.sc->skin <= 0 || disc < 0) return INFINITY;
    t = -b - sqrtf(disc);
    return t > 1e-4f && t < tmax ? t : INFINITY;
}

/* Radiance of one camera ray; *rays counts the rays traced. */
static void shade(const float dir[3], float out[3], long *rays, int *hit_any)
{
    traced_ray camera = {{{R.eye[0], R.eye[1], R.eye[2]}, 0.0f, {dir[0], dir[1], dir[2]}, INFINITY, 0.0f}, 0, 1.0f};
    hairobb_hit hit;
    int is_hair = hairobb_intersect1(R.bvh, &camera.ray, &hit), l, k;
    float ts = skin_hit(R.eye, dir, is_hair ? hit.t : INFINITY), V[3] = {-dir[0], -dir[1], -dir[2]};
    float base[3], T[3], P[3];
    ++*rays;
    if (!is_hair && ts == INFINITY) {   /* background: a dim vertical gradient */
        float g = 0.10f + 0.06f * dir[2];
        out[0] = out[1] = g; out[2] = g * 1.15f;
        return;
    }
    *hit_any = 1;
    if (ts < INFINITY) {                /* the body: dark skin, lit diffusely, shadowed by the hair */
        for (k = 0; k < 3; k++) P[k] = R.eye[k] + ts * dir[k];
        for (k = 0; k < 3; k++) out[k] = 0.02f;
        for (l = 0; l < 2; l++) {
            traced_ray sh = {{{P[0], P[1], P[2]}, 1e-4f, {R.light[l][0], R.light[l][1], R.light[l][2]}, INFINITY, 0.0f}, 1, 1.0f};
            float ndl = dot3(P, R.light[l]) / R.sc->skin;
            if (ndl <= 0) continue;
            ++*rays;
            if (hairobb_occluded1(R.bvh, &sh.ray)) sh.transmitted = 0.0f;
            for (k = 0; k < 3; k++) out[k] += 0.15f * ndl * sh.transmitted * R.light_color[l][k];
        }
        return;
    }
    /* Hair: the file's colour at the hit, the two point colours blended by u. */
    if (R.sc->colors) {
        const float *c0 = R.sc->colors + 3 * (size_t)R.sc->segment_point[hit.prim_id], *c1 = c0 + 3;
        for (k = 0; k < 3; k++) base[k] = c0[k] + hit.u * (c1[k] - c0[k]);
    } else
        memcpy(base, R.sc->color, sizeof base);
    memcpy(T, hit.tangent, sizeof T); norm3(T);
    for (k = 0; k < 3; k++) { P[k] = R.eye[k] + hit.t * dir[k]; out[k] = 0.06f * base[k]; }   /* ambient */
    for (l = 0; l < 2; l++) {
        const float *L = R.light[l];
        /* Kajiya-Kay: diffuse ~ sin(T, L); specular peaks where the eye lies on
           the cone of mirror directions around the tangent, cos(theta_L + theta_V). */
        float cl = dot3(T, L), cv = dot3(T, V), sl = sqrtf(fmaxf(0, 1 - cl * cl)), sv = sqrtf(fmaxf(0, 1 - cv * cv));
        float spec = powf(fmaxf(0, sl * sv - cl * cv), 80.0f), lit;
        /* The shadow ray starts at the hit and names it, so the ribbon it
           leaves is skipped while touching hairs still shadow it; the
           filter dims it by each strand it crosses. */
        traced_ray sh = {{{P[0], P[1], P[2]}, 0.0f, {L[0], L[1], L[2]}, INFINITY, 0.0f}, 1, 1.0f};
        if (skin_hit(P, L, INFINITY) < INFINITY) lit = 0.0f;
        else { ++*rays; lit = hairobb_occluded1_from(R.bvh, &hit, &sh.ray) ? 0.0f : sh.transmitted; }
        for (k = 0; k < 3; k++)
            out[k] += lit * R.light_color[l][k] * (0.7f * base[k] * sl + 0.6f * spec * (0.4f + 0.6f * base[k]));
    }
    /* v runs across the ribbon: darkening its edges makes each strand read
       as round and keeps neighbouring strands apart. */
    for (k = 0; k < 3; k++) out[k] *= 0.6f + 0.4f * sqrtf(fmaxf(0, 1 - hit.v * hit.v));
}

static unsigned char to_srgb(float x)   /* Reinhard-ish roll-off, then gamma 2.2 */
{
    x = x / (1 + 0.3f * x);
    return (unsigned char)(255.0f * powf(fminf(fmaxf(x, 0), 1), 1 / 2.2f) + 0.5f);
}

/* A worker takes the next free row until none is left (rows differ in cost). */
static void *worker(void *arg)
{
    long rays = 0, hits = 0;
    (void)arg;
    for (;;) {
        int x, y, i, j, k, pct;
        pthread_mutex_lock(&R.lock);
        y = R.next_row++;
        pthread_mutex_unlock(&R.lock);
        if (y >= R.h) break;
        for (x = 0; x < R.w; x++) {
            float sum[3] = {0, 0, 0}, c[3], d[3];
            int hit_any = 0;
            for (j = 0; j < SS; j++)
                for (i = 0; i < SS; i++) {
                    float sx = ((x + (i + 0.5f) / SS) / R.w * 2 - 1) * R.w / R.h, sy = 1 - (y + (j + 0.5f) / SS) / R.h * 2;
                    for (k = 0; k < 3; k++) d[k] = R.fwd[k] + R.fov * (sx * R.right[k] + sy * R.up[k]);
                    norm3(d);
                    shade(d, c, &rays, &hit_any);
                    for (k = 0; k < 3; k++) sum[k] += c[k] / (SS * SS);
                }
            hits += hit_any;
            for (k = 0; k < 3; k++) R.pixels[3 * ((size_t)y * R.w + x) + k] = to_srgb(sum[k]);
        }
        pthread_mutex_lock(&R.lock);
        pct = 100 * ++R.rows_done / R.h;
        if (pct != 100 * (R.rows_done - 1) / R.h) fprintf(stderr, "\rtracing: %3d%%", pct);
        pthread_mutex_unlock(&R.lock);
    }
    pthread_mutex_lock(&R.lock);
    R.rays += rays; R.hits += hits;
    pthread_mutex_unlock(&R.lock);
    return NULL;
}

int main(int argc, char **argv)
{
    const char *in = NULL, *out = "out.png";
    hairobb_hair hair;
    scene sc;
    hairobb_bvh *bvh;
    hairobb_build_options options;
    hairobb_result res;
    pthread_t th[MAX_THREADS];
    float lo[3], hi[3], center[3], radius, dist, world_up[3] = {0, 0, 1};
    static const float light_color[2][3] = {{1.5f, 1.4f, 1.2f}, {0.5f, 0.6f, 0.8f}};
    float view[3] = {0.5f, -1.0f, 0.3f};   /* camera at -y (behind straight.hair's head), to the side, above */
    double t0, t_build, t_trace;
    int a, k, t, threads = (int)sysconf(_SC_NPROCESSORS_ONLN), round = 0;

    memset(&R, 0, sizeof R); memset(&sc, 0, sizeof sc); memset(&hair, 0, sizeof hair);
    R.w = R.h = 800;
    R.fov = 0.45f;   /* ~48 deg field of view */
    for (a = 1; a < argc; a++) {
        if (!strcmp(argv[a], "-o") && a + 1 < argc) out = argv[++a];
        else if (!strcmp(argv[a], "-w") && a + 1 < argc) R.w = atoi(argv[++a]);
        else if (!strcmp(argv[a], "-h") && a + 1 < argc) R.h = atoi(argv[++a]);
        else if (!strcmp(argv[a], "-z") && a + 1 < argc) R.fov = 0.45f / (float)atof(argv[++a]);
        else if (!strcmp(argv[a], "--round")) round = 1;
        else if (argv[a][0] != '-' && !in) in = argv[a];
        else { fprintf(stderr, "usage: %s [file.hair] [-o out.png] [-w width] [-h height] [-z zoom] [--round]\n", argv[0]); return 2; }
    }
    if (R.w <= 0 || R.h <= 0 || R.w > 16384 || R.h > 16384) { fprintf(stderr, "bad image size\n"); return 2; }
    if (!(R.fov > 0 && R.fov <= 0.45f)) { fprintf(stderr, "bad zoom (1 or more)\n"); return 2; }

    if (in) {   /* the file's Bezier segments and colours are ready to use as they are */
        if ((res = hairobb_hair_load(in, NULL, &hair)) != HAIROBB_OK) {
            fprintf(stderr, "%s: %s\n", in, hairobb_result_string(res));
            return 1;
        }
        sc.vertices = hair.vertices; sc.vertex_count = hair.vertex_count;
        sc.indices = hair.indices; sc.segment_count = hair.segment_count;
        sc.segment_point = hair.segment_point; sc.colors = hair.colors;
        memcpy(sc.color, hair.default_color, sizeof sc.color);
        fprintf(stderr, "%s: %u strands, %zu segments\n", in, hair.strand_count, sc.segment_count);
    } else {
        make_fur(&sc, 60000, 4);
        fprintf(stderr, "built-in fur ball: 60000 strands, %zu segments\n", sc.segment_count);
    }

    t0 = now();
    memset(&options, 0, sizeof options);
    options.hit_filter = through_hair;
    options.shape = round ? HAIROBB_SHAPE_ROUND : HAIROBB_SHAPE_RIBBON;
    res = hairobb_build(sc.vertices, sc.vertex_count, sc.indices, sc.segment_count, &options, &bvh);
    t_build = now() - t0;
    if (res != HAIROBB_OK) { fprintf(stderr, "hairobb_build: %s\n", hairobb_result_string(res)); return 1; }

    /* Frame the hair's box: a sphere of half its largest side in the field of
       view (the box's own bounding sphere leaves hair small: it is rarely a cube). */
    hairobb_bounds(bvh, lo, hi);
    for (radius = 0, k = 0; k < 3; k++) {
        center[k] = 0.5f * (lo[k] + hi[k]);
        radius = fmaxf(radius, 0.5f * (hi[k] - lo[k]));
    }
    dist = 1.3f * radius / 0.42f * (R.w < R.h ? (float)R.h / R.w : 1.0f);
    norm3(view);
    for (k = 0; k < 3; k++) { R.eye[k] = center[k] + dist * view[k]; R.fwd[k] = -view[k]; }
    cross3(R.fwd, world_up, R.right); norm3(R.right);
    cross3(R.right, R.fwd, R.up);
    for (k = 0; k < 3; k++) {   /* placed around the camera: a warm key from the upper left, a cool rim light from behind on the right */
        R.light[0][k] = -0.8f * R.right[k] + 0.6f * R.up[k] + 0.5f * view[k];
        R.light[1][k] = 0.7f * R.right[k] + 0.3f * R.up[k] - 0.5f * view[k];
    }
    norm3(R.light[0]); norm3(R.light[1]);
    memcpy(R.light_color, light_color, sizeof light_color);

    R.bvh = bvh; R.sc = &sc;
    R.pixels = malloc((size_t)R.w * R.h * 3);
    pthread_mutex_init(&R.lock, NULL);
    t0 = now();
    threads = threads < 1 ? 1 : threads > MAX_THREADS ? MAX_THREADS : threads;   /* one per core */
    for (t = 0; t < threads; t++) pthread_create(&th[t], NULL, worker, NULL);
    for (t = 0; t < threads; t++) pthread_join(th[t], NULL);
    t_trace = now() - t0;
    fprintf(stderr, "\rbuild %.3f s, trace %.3f s (%s, %d threads), %.2f Mrays/s (%ld rays), %.1f%% of pixels hit\n",
            t_build, t_trace, hairobb_simd_string(hairobb_get_simd(bvh)), threads, R.rays / t_trace * 1e-6, R.rays,
            100.0 * R.hits / ((double)R.w * R.h));

    if (!stbi_write_png(out, R.w, R.h, 3, R.pixels, R.w * 3)) { fprintf(stderr, "cannot write %s\n", out); return 1; }
    fprintf(stderr, "wrote %s (%dx%d)\n", out, R.w, R.h);
    hairobb_free(bvh);   /* before the buffers it points into */
    if (in) hairobb_hair_free(&hair);
    else { free(sc.vertices); free(sc.indices); free(sc.segment_point); free(sc.colors); }
    free(R.pixels);
    return 0;
}
