/* scenes.c - the scenes (procedural, or read from files) and the ray sets
   every variant traces: primary rays from a pinhole camera, then from their
   hits a diffuse bounce and a shadow ray each. */
#include "bench/bench.h"

const char *const ray_kind_names[RAY_KIND_COUNT] = {"primary", "incoherent", "shadow"};

/* The segments of --scene's index-th scene: its own (NAME:N, --scene scale)
   or --segments. */
size_t scene_segments(const options *o, int index)
{
    return index >= 0 && index < o->scene_count && o->scene_segments[index] ? o->scene_segments[index] : o->segments;
}

/* Makes or reads the scene. Returns 0 on success, -1 when a file-based
   scene is absent (skipped; why says what is missing and where to get it),
   1 on errors, 2 for an unknown name or a data path that cannot be read
   (reported here). */
static int make_scene(const options *o, const char *name, size_t segments, hair_scene *s, int *from_file,
                      char why[TEST_DATA_WHY_SIZE])
{
    const char *path = NULL;
    test_data_status found = TEST_DATA_FOUND;
    snprintf(why, TEST_DATA_WHY_SIZE, "%s: file not found", name);
    *from_file = 0;
    if (strcmp(name, "combed") == 0)
        return scene_combed(s, segments, 1);
    if (strcmp(name, "curly") == 0)
        return scene_curly(s, segments, 2);
    if (strcmp(name, "random") == 0)
        return scene_random(s, segments, 3);
    if (strcmp(name, "crossing") == 0)
        return scene_crossing(s, segments, 4);
    if (strcmp(name, "yeti") == 0)
        return scene_yeti(s, segments, 5);
    *from_file = 1;
    if (strcmp(name, "straight") == 0 || strcmp(name, "furball") == 0) {
        int straight = name[0] == 's';
        path = straight ? o->straight_path : o->furball_path; /* given on the command line */
        if (!path)
            found = straight ? test_data_straight_hair(&path, why) : test_data_furball(&path, why);
        if (found == TEST_DATA_BAD_PATH || (found == TEST_DATA_ABSENT && test_data_required())) {
            fprintf(stderr, "bench: %s%s\n", why, found == TEST_DATA_ABSENT ? " (HAIROBB_REQUIRE_DATA is set)" : "");
            return 2;
        }
        if (found == TEST_DATA_ABSENT)
            return -1;
        return straight ? scene_load_hair(s, path) : scene_load_furball(s, path);
    }
    if (!strchr(name, '/') && !strchr(name, '.')) {
        fprintf(stderr, "bench: unknown scene '%s' (see --help; a file needs a path or the .hair extension)\n", name);
        return 2;
    }
    return scene_load_hair(s, name);
}

/* The scene, procedural (of `segments` segments; 0: --segments) or read
   from a file, with its strands and arrays arranged as --strand-order and
   --huge-pages say (layout.c); returns as make_scene. */
int load_scene(const options *o, const char *name, size_t segments, hair_scene *s, scene_layout *layout,
               char why[TEST_DATA_WHY_SIZE])
{
    int from_file;
    int made = make_scene(o, name, segments ? segments : o->segments, s, &from_file, why);
    if (made != 0)
        return made;
    if (arrange_scene(o, s, from_file, layout) != 0) {
        scene_free(s);
        return 1;
    }
    return 0;
}

int ray_set_alloc(ray_set *r, ray_kind kind, size_t count)
{
    r->kind = kind;
    r->count = count;
    size_t n = count ? count : 1;
    r->org = (float *)malloc(3 * n * sizeof(float));
    r->dir = (float *)malloc(3 * n * sizeof(float));
    r->tfar = (float *)malloc(n * sizeof(float));
    r->time = NULL;
    return !r->org || !r->dir || !r->tfar;
}

/* Gives every ray a time, uniform in [0, 1) from a fixed seed. */
int ray_set_random_times(ray_set *r, uint64_t seed)
{
    scene_rng rng;
    free(r->time);
    r->time = (float *)malloc((r->count ? r->count : 1) * sizeof(float));
    if (!r->time)
        return 1;
    scene_rng_seed(&rng, seed);
    for (size_t i = 0; i < r->count; i++)
        r->time[i] = scene_rng_float(&rng);
    return 0;
}

void ray_set_free(ray_set *r)
{
    free(r->org);
    free(r->dir);
    free(r->tfar);
    free(r->time);
    memset(r, 0, sizeof *r);
}

int primary_rays(const hair_scene *s, int resolution, ray_set *rays)
{
    if (ray_set_alloc(rays, RAYS_PRIMARY, (size_t)resolution * (size_t)resolution) != 0)
        return 1;
    scene_camera_rays(s, resolution, resolution, rays->org, rays->dir);
    for (size_t i = 0; i < rays->count; i++)
        rays->tfar[i] = INFINITY;
    return 0;
}

static float scene_diagonal(const hair_scene *s)
{
    scene_vec3 extent = scene_v3(s->upper[0] - s->lower[0], s->upper[1] - s->lower[1], s->upper[2] - s->lower[2]);
    return scene_v3_length(extent);
}

/* Fixed point light above, right of and in front of the hair, outside its
   bounding sphere, so that shadow rays cross the hair volume. */
static scene_vec3 light_position(const hair_scene *s)
{
    scene_vec3 centre = scene_v3(0.5f * (s->lower[0] + s->upper[0]), 0.5f * (s->lower[1] + s->upper[1]),
                                 0.5f * (s->lower[2] + s->upper[2]));
    scene_vec3 toward = scene_v3_normalize(scene_v3(0.4f, 1.0f, 0.6f));
    return scene_v3_add(centre, scene_v3_scale(toward, scene_diagonal(s)));
}

/* Cosine-distributed direction about the unit normal n. */
static scene_vec3 cosine_direction(scene_vec3 n, scene_rng *rng)
{
    float phi = 6.28318531f * scene_rng_float(rng);
    float r2 = scene_rng_float(rng);
    float sin_theta = sqrtf(r2), cos_theta = sqrtf(1.0f - r2);
    scene_vec3 tangent = scene_v3_perpendicular(n);
    scene_vec3 bitangent = scene_v3_cross(n, tangent);
    return scene_v3_normalize(scene_v3_add(scene_v3_scale(n, cos_theta),
                                           scene_v3_add(scene_v3_scale(tangent, sin_theta * cosf(phi)),
                                                        scene_v3_scale(bitangent, sin_theta * sinf(phi)))));
}

/* From every primary hit: one diffuse bounce and one shadow ray. Both start
   at the hit point pushed off the ribbon along Ng by 1e-3 of the scene's
   diagonal (over the hair radius in the procedural scenes), so neither
   library finds the surface the ray left. */
int secondary_rays(const hair_scene *s, const ray_set *primary, const hit_record *hits, ray_set *incoherent,
                   ray_set *shadow)
{
    size_t count = 0;
    for (size_t i = 0; i < primary->count; i++)
        count += hits[i].prim != NO_HIT;
    if (ray_set_alloc(incoherent, RAYS_INCOHERENT, count) != 0 || ray_set_alloc(shadow, RAYS_SHADOW, count) != 0)
        return 1;
    float epsilon = 1e-3f * scene_diagonal(s);
    scene_vec3 light = light_position(s);
    scene_rng rng;
    scene_rng_seed(&rng, 12345);
    size_t k = 0;
    for (size_t i = 0; i < primary->count; i++) {
        const hit_record *h = &hits[i];
        if (h->prim == NO_HIT)
            continue;
        const float *o = primary->org + 3 * i, *d = primary->dir + 3 * i;
        scene_vec3 ng = scene_v3(h->ng[0], h->ng[1], h->ng[2]);
        scene_vec3 p = scene_v3(o[0] + h->t * d[0], o[1] + h->t * d[1], o[2] + h->t * d[2]);
        p = scene_v3_add(p, scene_v3_scale(ng, epsilon));

        scene_vec3 bounce = cosine_direction(ng, &rng);
        scene_vec3 to_light = scene_v3_sub(light, p);
        float distance = scene_v3_length(to_light);
        to_light = scene_v3_scale(to_light, 1.0f / distance);
        float origin[3] = {p.x, p.y, p.z};
        memcpy(incoherent->org + 3 * k, origin, sizeof origin);
        memcpy(shadow->org + 3 * k, origin, sizeof origin);
        float bounce_dir[3] = {bounce.x, bounce.y, bounce.z}, light_dir[3] = {to_light.x, to_light.y, to_light.z};
        memcpy(incoherent->dir + 3 * k, bounce_dir, sizeof bounce_dir);
        memcpy(shadow->dir + 3 * k, light_dir, sizeof light_dir);
        incoherent->tfar[k] = INFINITY;
        shadow->tfar[k] = distance;
        k++;
    }
    return 0;
}
