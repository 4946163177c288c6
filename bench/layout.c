/* layout.c - the scene's arrays as a renderer hands them over: the order of
   its strands (--strand-order) and the memory its vertex and index arrays
   are in (--huge-pages).

   At millions of segments hairobb's leaves read the caller's vertices, so
   the caller's order and pages decide its speed (docs/benchmarking.md, "At
   scale"). A groom generator writes strands in no spatial order, into plain
   malloc memory: that is the default here for procedural scenes, whose
   generators (tests/scenes.h) emit them in an order that partly follows
   space. Files keep their own order unless --strand-order says otherwise.

   Strands are permuted whole: each strand's segments stay consecutive and
   joined, the vertices are copied in the new order and the indices
   rewritten. The scene keeps its bounds (so the camera and the rays stay
   the same); only segment numbers change. hair_scene holds no other
   per-segment array; moving scenes (--motion) make their steps from the
   arranged arrays. */
#include "bench/bench.h"

#if defined(__linux__)
#include <sys/mman.h>
#endif
#if defined(__linux__) && defined(MADV_HUGEPAGE)
#define BENCH_HUGE_PAGES 1
#else
#define BENCH_HUGE_PAGES 0
#endif

const char *const strand_order_names[STRAND_ORDER_COUNT] = {"generated", "groom", "space"};

enum { HUGE_PAGE_BYTES = 2 << 20 };
#define GROOM_SEED 2026 /* the shuffle's: every run hands over the same order */

int huge_pages_supported(void)
{
    return BENCH_HUGE_PAGES;
}

/* An array for the scene: plain memory (16-byte aligned, as scenes.h
   allocates vertices), or 2 MB-aligned and rounded up to 2 MB, advised
   MADV_HUGEPAGE, and emptied of any pages the allocator had touched there
   before (memory it reuses would stay on small pages), so that its first
   touch faults in huge pages. Either is released by free(), as scene_free
   does. */
static void *array_alloc(size_t bytes, int huge_pages)
{
    void *p = NULL;
    if (!huge_pages)
        return posix_memalign(&p, 16, bytes ? bytes : 1) == 0 ? p : NULL;
#if BENCH_HUGE_PAGES
    size_t rounded = (bytes + HUGE_PAGE_BYTES - 1) / HUGE_PAGE_BYTES * HUGE_PAGE_BYTES;
    if (posix_memalign(&p, HUGE_PAGE_BYTES, rounded ? rounded : HUGE_PAGE_BYTES) != 0)
        return NULL;
    /* [p, p + rounded) is the whole allocation: no allocator header lies inside it */
    if (madvise(p, rounded, MADV_HUGEPAGE) != 0 || madvise(p, rounded, MADV_DONTNEED) != 0)
        fprintf(stderr, "bench: madvise: %s (the arrays may stay on small pages)\n", strerror(errno));
#endif
    return p;
}

/* Bytes of [p, p + bytes) on huge pages: the AnonHugePages of each mapping
   of /proc/self/smaps that overlaps the range, at most the overlap. -1 when
   smaps cannot be read. */
static long long huge_page_bytes(const void *p, size_t bytes)
{
    FILE *f = fopen("/proc/self/smaps", "r");
    if (!f)
        return -1;
    uintptr_t begin = (uintptr_t)p, end = begin + bytes;
    unsigned long long overlap = 0, total = 0;
    char line[512];
    while (fgets(line, sizeof line, f)) {
        unsigned long long low, high, kb;
        if (sscanf(line, "%llx-%llx ", &low, &high) == 2) { /* a mapping's first line */
            unsigned long long from = low > begin ? low : begin, to = high < end ? high : end;
            overlap = to > from ? to - from : 0;
        } else if (sscanf(line, "AnonHugePages: %llu kB", &kb) == 1 && overlap) {
            total += kb * 1024 < overlap ? kb * 1024 : overlap;
        }
    }
    fclose(f);
    return (long long)total;
}

/* The system's transparent huge page mode: always, madvise or never. */
static const char *thp_mode(void)
{
    static char mode[32];
    char line[128];
    FILE *f = fopen("/sys/kernel/mm/transparent_hugepage/enabled", "r");
    snprintf(mode, sizeof mode, "unknown");
    if (f && fgets(line, sizeof line, f)) {
        const char *open = strchr(line, '['), *close = open ? strchr(open, ']') : NULL;
        if (open && close)
            snprintf(mode, sizeof mode, "%.*s", (int)(close - open - 1), open + 1);
    }
    if (f)
        fclose(f);
    return mode;
}

/* Whether segment i starts a strand: Catmull-Rom segments of a strand
   share their points (the next segment starts one point on), Bezier ones
   repeat or share the joint (tests/scenes.h's rule). */
static int starts_strand(const hair_scene *s, size_t i)
{
    if (s->basis == SCENE_BASIS_CATMULL_ROM)
        return i == 0 || s->indices[i] != s->indices[i - 1] + 1;
    return scene_bezier_starts_strand(s, i);
}

/* The first segment of each strand, and one past the last: strand k is
   segments [first[k], first[k + 1]). NULL when out of memory (the caller
   frees it; --groups splits a scene at these). */
size_t *find_strands(const hair_scene *s, size_t *strand_count)
{
    size_t count = 0;
    for (size_t i = 0; i < s->segment_count; i++)
        count += (size_t)starts_strand(s, i);
    size_t *first = (size_t *)malloc((count + 1) * sizeof(size_t));
    if (!first)
        return NULL;
    count = 0;
    for (size_t i = 0; i < s->segment_count; i++)
        if (starts_strand(s, i))
            first[count++] = i;
    first[count] = s->segment_count;
    *strand_count = count;
    return first;
}

/* 21 bits of each coordinate, interleaved: z y x from the top bit down. */
static uint64_t morton_spread(uint64_t x)
{
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffULL;
    x = (x | x << 16) & 0x1f0000ff0000ffULL;
    x = (x | x << 8) & 0x100f00f00f00f00fULL;
    x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
    x = (x | x << 2) & 0x1249249249249249ULL;
    return x;
}

typedef struct strand_key {
    uint64_t key;
    size_t strand;
} strand_key;

static int compare_strand_keys(const void *a, const void *b)
{
    const strand_key *x = (const strand_key *)a, *y = (const strand_key *)b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return x->strand < y->strand ? -1 : x->strand > y->strand;
}

/* order[k]: the strand that goes k-th. Groom: a Fisher-Yates shuffle with a
   fixed seed. Space: by the Morton code of the strand's root (its first
   segment's first Bezier point) in the scene's bounds, ties in the
   generated order. Returns 1 when out of memory. */
static int strand_permutation(const hair_scene *s, const size_t *first, size_t strands, strand_order order,
                              size_t *out)
{
    for (size_t k = 0; k < strands; k++)
        out[k] = k;
    if (order == STRAND_ORDER_GROOM) {
        scene_rng rng;
        scene_rng_seed(&rng, GROOM_SEED);
        for (size_t k = strands; k > 1; k--) {
            /* 64 random bits: strand counts pass 2^32 only in theory, but cost nothing here */
            uint64_t r = (uint64_t)scene_rng_u32(&rng) << 32 | scene_rng_u32(&rng);
            size_t j = (size_t)(r % k), kept = out[k - 1];
            out[k - 1] = out[j];
            out[j] = kept;
        }
        return 0;
    }
    if (order != STRAND_ORDER_SPACE)
        return 0;
    strand_key *keys = (strand_key *)malloc((strands ? strands : 1) * sizeof(strand_key));
    if (!keys)
        return 1;
    for (size_t k = 0; k < strands; k++) {
        float bezier[16];
        uint64_t code = 0;
        scene_segment_bezier(s, first[k], bezier);
        for (int axis = 0; axis < 3; axis++) {
            float extent = s->upper[axis] - s->lower[axis];
            float unit = extent > 0.0f ? (bezier[axis] - s->lower[axis]) / extent : 0.0f;
            unit = unit < 0.0f ? 0.0f : unit > 1.0f ? 1.0f : unit;
            code |= morton_spread((uint64_t)(unit * 2097151.0f)) << axis;
        }
        keys[k].key = code;
        keys[k].strand = k;
    }
    qsort(keys, strands, sizeof *keys, compare_strand_keys);
    for (size_t k = 0; k < strands; k++)
        out[k] = keys[k].strand;
    free(keys);
    return 0;
}

/* The scene's strands written in the permutation's order into new arrays:
   each point copied once, the first time a segment of the new order reads
   it, so the points a strand shares stay shared and each segment's four
   points stay consecutive (checked). Returns 1 when out of memory or when
   the scene shares points across strands in a way this cannot keep. */
static int permute_strands(hair_scene *s, const size_t *first, const size_t *order, size_t strands,
                           int huge_pages)
{
    const uint32_t unmapped = 0xffffffffu;
    uint32_t *map = (uint32_t *)malloc((s->vertex_count ? s->vertex_count : 1) * sizeof(uint32_t));
    float *vertices = (float *)array_alloc(s->vertex_count * 4 * sizeof(float) + 16, huge_pages);
    uint32_t *indices = (uint32_t *)array_alloc(s->segment_count * sizeof(uint32_t), huge_pages);
    int failed = !map || !vertices || !indices;
    size_t next_vertex = 0, next_segment = 0;
    if (!failed)
        memset(map, 0xff, s->vertex_count * sizeof(uint32_t));
    for (size_t k = 0; k < strands && !failed; k++)
        for (size_t i = first[order[k]]; i < first[order[k] + 1] && !failed; i++) {
            size_t v = s->indices[i];
            for (size_t j = 0; j < 4; j++)
                if (map[v + j] == unmapped) {
                    memcpy(vertices + 4 * next_vertex, s->vertices + 4 * (v + j), 4 * sizeof(float));
                    map[v + j] = (uint32_t)next_vertex++;
                }
            for (size_t j = 1; j < 4; j++)
                failed |= map[v + j] != map[v] + j;
            indices[next_segment++] = map[v];
        }
    free(map);
    if (failed) {
        free(vertices);
        free(indices);
        return 1;
    }
    memset(vertices + 4 * next_vertex, 0, 16); /* scenes.h's defined padding: Embree reads 16 bytes past the end */
    free(s->vertices);
    free(s->indices);
    s->vertices = vertices;
    s->indices = indices;
    s->vertex_count = next_vertex; /* points no segment reads are left out (no scene here has any) */
    return 0;
}

/* The arrays copied as they are, into memory advised for huge pages. */
static int copy_arrays(hair_scene *s)
{
    size_t vertex_bytes = s->vertex_count * 4 * sizeof(float) + 16;
    float *vertices = (float *)array_alloc(vertex_bytes, 1);
    uint32_t *indices = (uint32_t *)array_alloc(s->segment_count * sizeof(uint32_t), 1);
    if (!vertices || !indices) {
        free(vertices);
        free(indices);
        return 1;
    }
    memcpy(vertices, s->vertices, vertex_bytes);
    memcpy(indices, s->indices, s->segment_count * sizeof(uint32_t));
    free(s->vertices);
    free(s->indices);
    s->vertices = vertices;
    s->indices = indices;
    return 0;
}

/* Puts a freshly made or loaded scene's strands in --strand-order's order
   (unset: groom for procedural scenes, the file's order for files) and its
   arrays in the memory --huge-pages asks for; fills layout. Returns 0, or 1
   when out of memory (said on stderr; the scene is left as it was). */
int arrange_scene(const options *o, hair_scene *s, int from_file, scene_layout *layout)
{
    memset(layout, 0, sizeof *layout);
    layout->from_file = from_file;
    layout->order = o->strand_order != STRAND_ORDER_UNSET ? (strand_order)o->strand_order
                    : from_file                           ? STRAND_ORDER_GENERATED
                                                          : STRAND_ORDER_GROOM;
    layout->huge_pages = o->huge_pages;
    size_t strands = 0;
    size_t *first = find_strands(s, &strands);
    size_t *order = first ? (size_t *)malloc((strands ? strands : 1) * sizeof(size_t)) : NULL;
    int failed = !first || !order;
    layout->strands = strands;
    if (!failed && layout->order != STRAND_ORDER_GENERATED) {
        progress_start("%s: %s order", s->name, strand_order_names[layout->order]);
        failed = strand_permutation(s, first, strands, layout->order, order) ||
                 permute_strands(s, first, order, strands, o->huge_pages);
        progress(failed ? "failed" : "done");
    } else if (!failed && o->huge_pages) {
        failed = copy_arrays(s);
    }
    free(first);
    free(order);
    if (failed) {
        fprintf(stderr, "bench: %s: the strands could not be put in %s order (out of memory?)\n", s->name,
                strand_order_names[layout->order]);
        return 1;
    }
    layout->array_bytes = s->vertex_count * 4 * sizeof(float) + s->segment_count * sizeof(uint32_t);
    long long on_vertices = huge_page_bytes(s->vertices, s->vertex_count * 4 * sizeof(float));
    long long on_indices = huge_page_bytes(s->indices, s->segment_count * sizeof(uint32_t));
    layout->huge_page_bytes = on_vertices < 0 || on_indices < 0 ? -1 : on_vertices + on_indices;
    return 0;
}

/* "groom order", "space order", "generated order" or "file order". */
const char *layout_order_text(const scene_layout *l)
{
    static const char *const texts[STRAND_ORDER_COUNT] = {"generated order", "groom order", "space order"};
    return l->order == STRAND_ORDER_GENERATED && l->from_file ? "file order" : texts[l->order];
}

/* What the arrays are and where they lie, for the headers. */
const char *layout_memory_text(const scene_layout *l, char *text, size_t size)
{
    char huge[64] = "";
    if (l->huge_page_bytes >= 0)
        snprintf(huge, sizeof huge, ", %.1f MB of them on huge pages", (double)l->huge_page_bytes / 1048576.0);
    snprintf(text, size, "%.1f MB of vertices and indices in %s (transparent huge pages: %s%s)",
             (double)l->array_bytes / 1048576.0,
             l->huge_pages ? "2 MB-aligned memory advised MADV_HUGEPAGE" : "plain malloc memory", thp_mode(), huge);
    return text;
}
