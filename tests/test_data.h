/* test_data.h - the one rule by which the tests and the bench find the data
   files they do not generate themselves.

   straight.hair (Cem Yuksel's model; the clone does not carry it):
     1. $HAIROBB_STRAIGHT_HAIR when set; a path there that cannot be read is
        an error, never a skip (the user asked for that file);
     2. else ../shared/data/straight.hair, the development layout (the
        project's shared folder beside the clone; tests run from the
        repository root);
     3. else absent: the cases that need it are skipped, with a line naming
        the file, where to download it and which variable to set.
   furBall_A: the path of Debian's embree-tools package (scenes.h).

   HAIROBB_REQUIRE_DATA=1 (CI sets it) turns an absent file into a failure,
   so that a lost data path cannot hide behind a skip.

   No harness here: tests/check.h reports through it (check_data),
   the bench uses the lookup alone. Header-only, static inline, C99/C++. */
#ifndef HAIROBB_TESTS_TEST_DATA_H
#define HAIROBB_TESTS_TEST_DATA_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TEST_DATA_STRAIGHT_HAIR_VARIABLE "HAIROBB_STRAIGHT_HAIR"
#define TEST_DATA_STRAIGHT_HAIR_DEFAULT "../shared/data/straight.hair"
#define TEST_DATA_STRAIGHT_HAIR_URL "www.cemyuksel.com/research/hairmodels"
#define TEST_DATA_FURBALL_PATH "/usr/share/doc/embree3/models/furBall_A.bin.gz"
#define TEST_DATA_WHY_SIZE 512

typedef enum test_data_status {
    TEST_DATA_FOUND = 0,
    TEST_DATA_ABSENT = 1,   /* not there: skip the cases, unless required */
    TEST_DATA_BAD_PATH = 2  /* the variable names a file that cannot be read: fail */
} test_data_status;

static inline int test_data_readable(const char *path)
{
    FILE *file = fopen(path, "rb");
    if (file) fclose(file);
    return file != NULL;
}

/* HAIROBB_REQUIRE_DATA set to anything but "" or "0" */
static inline int test_data_required(void)
{
    const char *value = getenv("HAIROBB_REQUIRE_DATA");
    return value && value[0] && strcmp(value, "0") != 0;
}

/* *path gets straight.hair's path when found, else NULL; why (when not
   NULL) gets a one-line reason for the other outcomes. */
static inline test_data_status test_data_straight_hair(const char **path, char why[TEST_DATA_WHY_SIZE])
{
    const char *chosen = getenv(TEST_DATA_STRAIGHT_HAIR_VARIABLE);
    *path = NULL;
    if (chosen && chosen[0]) {
        if (test_data_readable(chosen)) {
            *path = chosen;
            return TEST_DATA_FOUND;
        }
        if (why)
            snprintf(why, TEST_DATA_WHY_SIZE, "straight.hair: %s=%s cannot be read", TEST_DATA_STRAIGHT_HAIR_VARIABLE,
                     chosen);
        return TEST_DATA_BAD_PATH;
    }
    if (test_data_readable(TEST_DATA_STRAIGHT_HAIR_DEFAULT)) {
        *path = TEST_DATA_STRAIGHT_HAIR_DEFAULT;
        return TEST_DATA_FOUND;
    }
    if (why)
        snprintf(why, TEST_DATA_WHY_SIZE,
                 "straight.hair: not found at %s; download it from %s and set %s to its path",
                 TEST_DATA_STRAIGHT_HAIR_DEFAULT, TEST_DATA_STRAIGHT_HAIR_URL, TEST_DATA_STRAIGHT_HAIR_VARIABLE);
    return TEST_DATA_ABSENT;
}

static inline test_data_status test_data_furball(const char **path, char why[TEST_DATA_WHY_SIZE])
{
    *path = NULL;
    if (test_data_readable(TEST_DATA_FURBALL_PATH)) {
        *path = TEST_DATA_FURBALL_PATH;
        return TEST_DATA_FOUND;
    }
    if (why)
        snprintf(why, TEST_DATA_WHY_SIZE, "furBall_A: not found at %s; install Debian's embree-tools",
                 TEST_DATA_FURBALL_PATH);
    return TEST_DATA_ABSENT;
}

#endif
