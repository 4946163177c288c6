/* scratch.h - where a test writes its files: a directory of the run's own,
   made on first use (mkdtemp) under build/ when the tests run from the
   repository root, else under $TMPDIR or /tmp, so that two runs at once
   never share a file. scratch_path names a file in it. The directory is
   removed at exit; the tests remove their files, and one left behind keeps
   the directory, where it shows. Header-only, static, C99/C++ with POSIX:
   #define _POSIX_C_SOURCE 200809L before the first #include. */
#ifndef HAIROBB_TESTS_SCRATCH_H
#define HAIROBB_TESTS_SCRATCH_H

#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#define SCRATCH_PATH_SIZE 1280   /* the directory (1024) and a file name */

static char scratch__dir[1024];

static inline void scratch__remove(void)
{
    rmdir(scratch__dir);
}

/* The run's directory, made on the first call; NULL if none can be made. */
static inline const char *scratch_dir(void)
{
    if (!scratch__dir[0]) {
        const char *tmp = getenv("TMPDIR");
        snprintf(scratch__dir, sizeof scratch__dir, "build/scratch-XXXXXX");
        if (!mkdtemp(scratch__dir)) {
            snprintf(scratch__dir, sizeof scratch__dir, "%s/hairobb-tests-XXXXXX", tmp && *tmp ? tmp : "/tmp");
            if (!mkdtemp(scratch__dir)) {
                printf("scratch.h: no directory for the test's files (%s)\n", scratch__dir);
                scratch__dir[0] = '\0';
                return NULL;
            }
        }
        atexit(scratch__remove);
    }
    return scratch__dir;
}

/* path = the scratch directory / name; "" if there is no directory (a
   file that cannot be opened: the test that writes it fails). */
static inline const char *scratch_path(char *path, size_t size, const char *name)
{
    const char *dir = scratch_dir();
    if (dir)
        snprintf(path, size, "%s/%s", dir, name);
    else if (size > 0)
        path[0] = '\0';
    return path;
}

#endif
