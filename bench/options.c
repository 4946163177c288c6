/* options.c - the bench's command line: the defaults, --help, and parsing
   into an options struct (bench.h). */
#include "bench/bench.h"

enum {
    DEFAULT_SEGMENTS = 200000,
    DEFAULT_RESOLUTION = 768, /* make bench within 2 minutes on 2 cores */
    DEFAULT_ROUNDS = 3,
    DEFAULT_ACCURACY_RAYS = 16384
};

#define DEFAULT_TSV_PATH "build/bench.tsv"
#define DEFAULT_PNG_PATH "build/bench_error.png"
#define DEFAULT_PLOT_SCRIPT "bench/plot.gp"

const char *const groups_shape_names[GROUPS_SHAPE_COUNT] = {"ribbon", "round"};

static void print_help(void)
{
    printf("usage: build/bench [options]   (run from the repository root)\n"
           "  --scene LIST        scenes, comma list or repeated (default combed):\n"
           "                      combed, curly, random, crossing (procedural), straight (--straight-path),\n"
           "                      furball (Embree's furBall_A, skipped if absent), or a PATH.hair file;\n"
           "                      NAME:N: a procedural scene of its own size (e.g. combed:2M,curly:500k);\n"
           "                      scale: combed:2M and combed:10M, run with the scale group unless --variants;\n"
           "                      yeti: Yeti-class fur on a capsule, Catmull-Rom strands of 16 segments\n"
           "                        holding 19 shared points (1.19 a segment), run by default with the yeti\n"
           "                        group (with --variants, every row reads its Catmull-Rom curves); builds\n"
           "                        and the reference that would not fit in MemAvailable are skipped, said so;\n"
           "                        the paper's size: --scene yeti --segments 153M --rays primary,incoherent\n"
           "  --segments N        segments of procedural scenes without a size of their own (default %d; k and M\n"
           "                      suffixes allowed)\n"
           "  --res N             primary rays: N x N pinhole camera framing the hair (default %d)\n"
           "  --rays LIST         ray sets: primary, incoherent, shadow (default all)\n"
           "  --threads LIST      thread counts, e.g. 1,8 (default 1 and the number of cores)\n"
           "  --variants LIST     variants or groups (default all):\n"
           "                      hairobb: default (= mixed), exact4, exact16, pieces4, pieces8, pieces16,\n"
           "                        aabb, obb, mixed-uncompressed, spatial, spatial-compressed,\n"
           "                        spatial-compressed-cluster, shared, compressed-shared,\n"
           "                        build-1t (defaults built on 1 thread), filter (a hit filter taking every hit),\n"
           "                        sse2 (the SSE2 kernels, where the build has them: not with -mavx2 or -march)\n"
           "                        round (round curves: tubes, HAIROBB_SHAPE_ROUND; the peer of embree-round),\n"
           "                        catmull-rom, catmull-rom-copy (Catmull-Rom basis, without and with the Bezier\n"
           "                        copy: on Bezier scenes other curves through the same points),\n"
           "                        b-spline, b-spline-copy (the same for the uniform B-spline basis)\n"
           "                      Embree: embree-r4 (flat, rate 4: Embree's default, the baseline of every ratio),\n"
           "                        embree-r8, embree-r16 (flat), embree-avx2, embree-sse42, embree-avx, and the\n"
           "                        peers embree-compact, embree-cycles, embree-round and embree-round-robust (below)\n"
           "                      groups: all, hairobb, embree, precision, ablation, bases, tubes (round, embree-round,\n"
           "                        embree-round-robust, default, embree-r4), scale (default, embree-r4,\n"
           "                        embree-compact), yeti (catmull-rom: hairobb C-R without the Bezier copy,\n"
           "                        embree-r4, embree-cycles, embree-round)\n",
           DEFAULT_SEGMENTS, DEFAULT_RESOLUTION);
    printf("  --rounds N          timing rounds, one pass of every variant each, after a warm-up pass;\n"
           "                      medians and [min-max] reported (default %d, 1..64; --passes: the same)\n"
           "  --accuracy-rays N   primary rays checked against the reference, 0 = none (default %d)\n"
           "  --memory-mb N       builds and the reference whose estimated memory exceeds 0.9 of what is\n"
           "                      available are skipped: N MB less this process's RSS (default MemAvailable)\n"
           "  --tsv FILE          every figure, one row per scene and variant, with each peer pair's ratios\n"
           "                      (columns KIND_per_PEER_Nt) on its row's row (default %s)\n"
           "  --png FILE          run time against error chart, drawn by gnuplot if present (default %s)\n"
           "  --plot-script FILE  gnuplot script (default %s)\n"
           "  --straight-path P   file of the 'straight' scene (default $" TEST_DATA_STRAIGHT_HAIR_VARIABLE ",\n"
           "                      else %s; skipped if absent)\n"
           "  --furball-path P    furBall_A.bin.gz (default %s)\n"
           "  --animate N         only an animation: combed fur (--segments) swaying over N frames, a BVH\n"
           "                      refitted frame to frame against one built afresh: refit and build s,\n"
           "                      primary Mrays/s of both (--res, --rounds, the first --threads), SAH ratios\n"
           "                      (TSV: --tsv, one row a frame)\n"
           "  --quiet             no progress on stderr (shown only when stderr is a terminal)\n"
           "  --profile           no timing: one pass of each variant over each ray set on 1 thread,\n"
           "                      a callgrind dump each (valgrind --collect-atstart=no), and a line\n"
           "                      'profile' with the work per ray (bench/profile.sh: make profile)\n"
           "  --save-load LIST    only this: combed scenes of these segment counts (e.g. 1M,10M), each\n"
           "                      built (all cores), saved and loaded in memory --rounds times: bytes per\n"
           "                      segment, build, save and load seconds (with the hair check, and without)\n",
           DEFAULT_ROUNDS, DEFAULT_ACCURACY_RAYS, DEFAULT_TSV_PATH,
           DEFAULT_PNG_PATH, DEFAULT_PLOT_SCRIPT, TEST_DATA_STRAIGHT_HAIR_DEFAULT, SCENE_FURBALL_DEFAULT_PATH);
    /* several strings: C99 compilers need support only 4095 characters in one */
    printf("  --builds            only build time: for each --scene, --rounds rounds of hairobb's defaults on all\n"
           "                      cores, on 1 thread, and Embree flat r4 on all cores (Catmull-Rom scenes: both\n"
           "                      read the Catmull-Rom curves), each freed before the next; medians [min-max] of\n"
           "                      the seconds and of the ratios to Embree within each round; TSV (--tsv, a row a\n"
           "                      scene and build)\n"
           "  --motion            only motion blur against Embree: combed fur (--segments) rotating about each\n"
           "                      root (0.5 rad) or translating (0.05, 0.2), at 2 and 4 time steps, and static;\n"
           "                      hairobb's defaults and Embree flat r4 (rtcSetGeometryTimeStepCount) on the same\n"
           "                      arrays: build s, bytes/segment, primary and incoherent Mrays/s at random ray\n"
           "                      times (--res, --rounds, --threads), accuracy at 8 times (--accuracy-rays),\n"
           "                      TSV (--tsv, one row a motion and library)\n");
    printf("  --groups            only several hair groups (SCENES): each --scene (default combed and combed:2M)\n"
           "                      traced as one BVH and as a hairobb_scene over its strands split in array order\n"
           "                      into 4, 16 and 64 groups (a BVH each, identity maps), plus one BVH under a\n"
           "                      scene alone and 16 translated instances of one group (other hair: its speed\n"
           "                      alone); in groom order (groups interleaved in space) and in space order\n"
           "                      (groups as patches) unless --strand-order picks one; build s, bytes/segment,\n"
           "                      instance boxes a primary ray crosses, Mrays/s and ratios to the one BVH\n"
           "                      within rounds (--rays, --threads, --rounds, --res), and each group scene's\n"
           "                      hits against the one BVH's on every ray; the same k groups as one BVH\n"
           "                      (hairobb_build_groups) and Embree's hair as k curve geometries of one scene;\n"
           "                      the one BVH and each k in 1 BVH built in turn, --rounds rounds on each\n"
           "                      --threads count: seconds, ratios within rounds, bytes a segment more\n"
           "  --groups-shape S    what --groups builds every row as: ribbon (hairobb's ribbons, Embree's flat\n"
           "                      Bezier curves; the default), round (tubes: HAIROBB_SHAPE_ROUND, Embree's round\n"
           "                      Bezier curves), or both (each scene and order as ribbons, then as tubes)\n");
    printf("  --strand-order O    the order of the strands in the scene's arrays: groom (shuffled whole with a\n"
           "                      fixed seed, as a groom generator writes them and a renderer hands them over; the\n"
           "                      default for procedural scenes), space (sorted by the Morton code of their roots),\n"
           "                      generated (as tests/scenes.h makes them, partly in space; files keep their own\n"
           "                      order unless this is given). Segment numbers change; the hair and the rays do not\n"
           "  --huge-pages        the scene's vertex and index arrays in 2 MB-aligned memory advised\n"
           "                      MADV_HUGEPAGE (Linux only), not in plain malloc memory (the default); the scene's\n"
           "                      header says which, and how much of them lies on huge pages\n"
           "                      (both: every mode, --builds, --motion, --animate and --save-load included)\n"
           "  --help              this text\n"
           "Embree's peers (in the groups all and embree; ratios stay against embree-r4, and each peer's row\n"
           "against it is a table of its own, the ratio taken within each round):\n"
           "  embree-compact      flat r4 with RTC_SCENE_FLAG_COMPACT: Embree's compact mode (40-66 bytes a segment),\n"
           "                      the peer of hairobb without the copy (no-copy)\n"
           "  embree-round        Embree's round curves (RTC_GEOMETRY_TYPE_ROUND_BEZIER_CURVE), the peer of round;\n"
           "  embree-round-robust the same with RTC_SCENE_FLAG_ROBUST. Round rows (*) are measured against the\n"
           "                      tube reference, and are on the chart as tubes\n"
           "  embree-cycles       Cycles' set-up: flat curves, RTC_SCENE_FLAG_ROBUST, tessellation rate 5; flat\n"
           "                      Catmull-Rom curves on a Catmull-Rom scene (yeti), as Cycles hands Embree its\n"
           "                      hair; on a Bezier scene, flat Bezier curves with the same flags and rate\n"
           "  embree-avx2         flat r4 on a device limited to Embree's AVX2 kernels (isa=avx2): where the CPU\n"
           "                      has AVX-512, what Embree's speed owes to it\n"
           "  embree-sse42,       flat r4 limited to Embree's SSE4.2 or AVX kernels (isa=sse4.2, isa=avx): what a\n"
           "  embree-avx          CPU without AVX2 runs, the peers of sse2 (hairobb's path there)\n");
}

/* Parses a count with an optional k or M suffix; 0 on success. */
static int parse_count(const char *text, size_t *value)
{
    char *end;
    errno = 0;
    double number = strtod(text, &end);
    if (*end == 'k' || *end == 'K')
        number *= 1e3, end++;
    else if (*end == 'm' || *end == 'M')
        number *= 1e6, end++;
    if (errno || end == text || *end != '\0' || !(number >= 0.0) || number > 4e9)
        return 1;
    *value = (size_t)(number + 0.5);
    return 0;
}

/* The sizes --scene scale runs combed fur at */
static const char *const scale_sizes[] = {"2M", "10M"};

static int add_scene(options *o, const char *name, size_t segments, int scale)
{
    if (o->scene_count == MAX_SCENES) {
        fprintf(stderr, "bench: at most %d scenes\n", MAX_SCENES);
        return 1;
    }
    o->scenes[o->scene_count] = name;
    o->scene_segments[o->scene_count] = segments;
    o->scene_scale[o->scene_count++] = scale;
    return 0;
}

/* --scene: names, NAME:N (a procedural scene of its own size), or scale */
static int add_scenes(options *o, const char *list)
{
    char *copy = (char *)malloc(strlen(list) + 1);
    if (!copy)
        return 1;
    strcpy(copy, list);
    /* names are kept for the whole run; the copy is never freed */
    char *rest = NULL;
    for (char *name = strtok_r(copy, ",", &rest); name; name = strtok_r(NULL, ",", &rest)) {
        char *size = strchr(name, ':');
        size_t segments = 0;
        if (strcmp(name, "scale") == 0) {
            for (size_t k = 0; k < sizeof scale_sizes / sizeof scale_sizes[0]; k++)
                if (parse_count(scale_sizes[k], &segments) != 0 || add_scene(o, "combed", segments, 1) != 0)
                    return 1;
            continue;
        }
        /* a size only after a procedural scene's name: paths may hold colons */
        if (size && !strchr(name, '/') && !strchr(name, '.')) {
            *size++ = '\0';
            if (parse_count(size, &segments) != 0 || segments == 0) {
                fprintf(stderr, "bench: bad size '%s' for scene %s (see --help)\n", size, name);
                return 1;
            }
        }
        if (add_scene(o, name, segments, 0) != 0)
            return 1;
    }
    return 0;
}

static int parse_ray_kinds(options *o, const char *list)
{
    char buffer[256];
    snprintf(buffer, sizeof buffer, "%s", list);
    memset(o->ray_kind_enabled, 0, sizeof o->ray_kind_enabled);
    char *rest = NULL;
    for (char *name = strtok_r(buffer, ",", &rest); name; name = strtok_r(NULL, ",", &rest)) {
        int found = 0;
        for (int k = 0; k < RAY_KIND_COUNT; k++)
            if (strcmp(name, ray_kind_names[k]) == 0)
                o->ray_kind_enabled[k] = found = 1;
        if (!found)
            return 1;
    }
    return 0;
}

static int parse_thread_counts(options *o, const char *list)
{
    char buffer[256];
    snprintf(buffer, sizeof buffer, "%s", list);
    o->thread_count_count = 0;
    char *rest = NULL;
    for (char *item = strtok_r(buffer, ",", &rest); item; item = strtok_r(NULL, ",", &rest)) {
        size_t count;
        if (parse_count(item, &count) != 0 || count < 1 || count > 256 || o->thread_count_count == MAX_THREAD_COUNTS)
            return 1;
        o->thread_counts[o->thread_count_count++] = (unsigned)count;
    }
    return o->thread_count_count == 0;
}

static void default_options(options *o)
{
    memset(o, 0, sizeof *o);
    o->segments = DEFAULT_SEGMENTS;
    o->resolution = DEFAULT_RESOLUTION;
    for (int k = 0; k < RAY_KIND_COUNT; k++)
        o->ray_kind_enabled[k] = 1;
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    o->thread_counts[o->thread_count_count++] = 1;
    if (cores > 1)
        o->thread_counts[o->thread_count_count++] = (unsigned)(cores < 256 ? cores : 256);
    o->variant_list = "all";
    o->strand_order = STRAND_ORDER_UNSET;
    o->groups_shapes = 1u << GROUPS_SHAPE_RIBBON;
    o->rounds = DEFAULT_ROUNDS;
    o->accuracy_rays = DEFAULT_ACCURACY_RAYS;
    o->tsv_path = DEFAULT_TSV_PATH;
    o->png_path = DEFAULT_PNG_PATH;
    o->plot_script = DEFAULT_PLOT_SCRIPT;
    o->straight_path = NULL; /* tests/test_data.h's rule */
    o->furball_path = NULL;
}

/* Returns 0 to run, 1 on a usage error, 2 after --help. */
int parse_options(int argc, char **argv, options *o)
{
    /* the options that take no value */
    const struct { const char *name; int *set; } switches[] = {
        {"--quiet", &o->quiet}, {"--profile", &o->profile}, {"--motion", &o->motion}, {"--builds", &o->builds},
        {"--huge-pages", &o->huge_pages}, {"--groups", &o->groups}};
    default_options(o);
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i], *value = NULL;
        char name[64];
        size_t length = strcspn(arg, "=");
        snprintf(name, sizeof name, "%.*s", (int)length, arg);
        if (arg[length] == '=')
            value = arg + length + 1;
        if (strcmp(name, "--help") == 0 || strcmp(name, "-h") == 0) {
            print_help();
            return 2;
        }
        int switched = 0;
        for (size_t s = 0; s < sizeof switches / sizeof switches[0]; s++)
            if (strcmp(name, switches[s].name) == 0)
                *switches[s].set = switched = 1;
        if (switched)
            continue;
        if (!value) {
            if (i + 1 >= argc) {
                fprintf(stderr, "bench: %s needs a value (see --help)\n", name);
                return 1;
            }
            value = argv[++i];
        }
        size_t count = 0;
        int bad = 0;
        if (strcmp(name, "--scene") == 0)
            bad = add_scenes(o, value);
        else if (strcmp(name, "--segments") == 0)
            bad = parse_count(value, &o->segments) || o->segments == 0;
        else if (strcmp(name, "--strand-order") == 0) {
            o->strand_order = STRAND_ORDER_UNSET;
            for (int k = 0; k < STRAND_ORDER_COUNT; k++)
                if (strcmp(value, strand_order_names[k]) == 0)
                    o->strand_order = k;
            bad = o->strand_order == STRAND_ORDER_UNSET;
        }
        else if (strcmp(name, "--groups-shape") == 0) {
            o->groups_shapes = strcmp(value, "both") == 0 ? (1u << GROUPS_SHAPE_COUNT) - 1 : 0;
            for (int k = 0; k < GROUPS_SHAPE_COUNT; k++)
                if (strcmp(value, groups_shape_names[k]) == 0)
                    o->groups_shapes = 1u << k;
            bad = o->groups_shapes == 0;
            o->groups_shape_given = 1;
        }
        else if (strcmp(name, "--res") == 0) {
            bad = parse_count(value, &count) || count < 1 || count > 16384;
            o->resolution = (int)count;
        } else if (strcmp(name, "--rays") == 0)
            bad = parse_ray_kinds(o, value);
        else if (strcmp(name, "--threads") == 0)
            bad = parse_thread_counts(o, value);
        else if (strcmp(name, "--variants") == 0) {
            o->variant_list = value;
            o->variants_given = 1;
        } else if (strcmp(name, "--rounds") == 0 || strcmp(name, "--passes") == 0) {
            bad = parse_count(value, &count) || count < 1 || count > MAX_ROUNDS;
            o->rounds = (int)count;
        } else if (strcmp(name, "--accuracy-rays") == 0)
            bad = parse_count(value, &o->accuracy_rays);
        else if (strcmp(name, "--memory-mb") == 0)
            bad = parse_count(value, &o->memory_mb) || o->memory_mb == 0;
        else if (strcmp(name, "--tsv") == 0)
            o->tsv_path = value;
        else if (strcmp(name, "--png") == 0)
            o->png_path = value;
        else if (strcmp(name, "--plot-script") == 0)
            o->plot_script = value;
        else if (strcmp(name, "--straight-path") == 0)
            o->straight_path = value;
        else if (strcmp(name, "--furball-path") == 0)
            o->furball_path = value;
        else if (strcmp(name, "--animate") == 0) {
            bad = parse_count(value, &count) || count < 1 || count > 100000;
            o->animate_frames = (int)count;
        } else if (strcmp(name, "--save-load") == 0) {
            char list[256], *item, *rest = NULL;
            snprintf(list, sizeof list, "%s", value);
            o->save_load_count = 0;
            for (item = strtok_r(list, ",", &rest); item && !bad; item = strtok_r(NULL, ",", &rest)) {
                bad = o->save_load_count == MAX_SAVE_LOAD || parse_count(item, &count) || count == 0;
                if (!bad)
                    o->save_load_segments[o->save_load_count++] = count;
            }
            bad = bad || o->save_load_count == 0;
        } else {
            fprintf(stderr, "bench: unknown option %s (see --help)\n", name);
            return 1;
        }
        if (bad) {
            fprintf(stderr, "bench: bad value '%s' for %s (see --help)\n", value, name);
            return 1;
        }
    }
    if (o->huge_pages && !huge_pages_supported()) {
        fprintf(stderr, "bench: --huge-pages needs Linux's madvise(MADV_HUGEPAGE), which this system lacks\n");
        return 1;
    }
    if (o->groups_shape_given && !o->groups) {
        fprintf(stderr, "bench: --groups-shape is an option of --groups (see --help)\n");
        return 1;
    }
    if (o->scene_count == 0 && o->groups) { /* --groups: combed at --segments and at 2M */
        add_scene(o, "combed", 0, 0);
        add_scene(o, "combed", 2000000, 0);
    }
    if (o->scene_count == 0)
        add_scene(o, "combed", 0, 0);
    return 0;
}
