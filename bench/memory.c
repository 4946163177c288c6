/* memory.c - the memory a build or the reference would take, checked
   against what the machine can give before it runs (--memory-mb), and the
   process's resident memory over each step (the memory table). */
#include "bench/bench.h"

/* What a variant's build adds to the process at its peak (bench.h's bytes a segment). */
double estimated_build_bytes(const variant *v, const hair_scene *s)
{
    double per_segment = EMBREE_BUILD_PEAK_BYTES_PER_SEGMENT;
    if (v->lib == LIB_HAIROBB) {
        int copy = v->bezier_copy != HAIROBB_OFF;   /* the bench's scenes are static */
        per_segment = copy ? HAIROBB_WITH_COPY_BYTES_PER_SEGMENT : HAIROBB_BUILD_PEAK_BYTES_PER_SEGMENT;
    }
    return per_segment * (double)s->segment_count;
}

/* A field of /proc/self/status or /proc/meminfo in bytes (their kB lines);
   0 when absent. */
static size_t proc_field_bytes(const char *path, const char *field)
{
    char line[256];
    size_t length = strlen(field), kilobytes = 0;
    FILE *f = fopen(path, "r");
    if (!f)
        return 0;
    while (fgets(line, sizeof line, f))
        if (strncmp(line, field, length) == 0 && line[length] == ':') {
            kilobytes = (size_t)strtoull(line + length + 1, NULL, 10);
            break;
        }
    fclose(f);
    return kilobytes * 1024;
}

size_t memory_limit_bytes; /* --memory-mb, else 0 */

/* 1 if bytes fit in what the machine can still give (MemAvailable: other
   processes and what this one holds already are not in it; or --memory-mb
   less what this process holds), keeping a tenth of it free; else 0 and
   why says so. Unknown availability fits. */
int memory_fits(double bytes, const char *what, char *why, size_t size)
{
    size_t available = proc_field_bytes("/proc/meminfo", "MemAvailable");
    if (memory_limit_bytes) {
        size_t held = proc_field_bytes("/proc/self/status", "VmRSS");
        available = memory_limit_bytes > held ? memory_limit_bytes - held : 1;
    }
    if (available == 0 || bytes <= 0.9 * (double)available)
        return 1;
    snprintf(why, size, "%s needs about %.2f GB (estimated), %.2f GB available (%s)", what, bytes * 1e-9,
             (double)available * 1e-9, memory_limit_bytes ? "--memory-mb less this process's RSS" : "MemAvailable");
    return 0;
}

int rss_peak_reset_works = 1;

void rss_step_begin(rss_step *r)
{
    FILE *f = fopen("/proc/self/clear_refs", "w");
    rss_peak_reset_works = f && fputs("5", f) >= 0;
    if (f && fclose(f) != 0)
        rss_peak_reset_works = 0;
    r->before = proc_field_bytes("/proc/self/status", "VmRSS");
    r->after = r->peak = 0;
}

void rss_step_end(rss_step *r)
{
    r->after = proc_field_bytes("/proc/self/status", "VmRSS");
    r->peak = proc_field_bytes("/proc/self/status", "VmHWM");
}
