/* progress.c - progress lines on stderr, for every part of the bench: a
   slow step shows what it is while it runs and its outcome after. It calls
   no other part, so that any part may call it. */
#include "bench/bench.h"

int show_progress; /* stderr is a terminal and --quiet was not given */

/* progress() writes a line, or ends one that progress_start() began with
   what is about to run. */
static void progress_write(const char *format, va_list args, const char *end)
{
    vfprintf(stderr, format, args);
    fputs(end, stderr);
    fflush(stderr);
}

void progress(const char *format, ...)
{
    if (!show_progress)
        return;
    va_list args;
    va_start(args, format);
    progress_write(format, args, "\n");
    va_end(args);
}

void progress_start(const char *format, ...)
{
    if (!show_progress)
        return;
    va_list args;
    va_start(args, format);
    progress_write(format, args, "... ");
    va_end(args);
}
