/* check.h - the tests' tiny harness: CHECK prints failures, check_report
   every check (PASS or FAIL, for programs that list them all), check_skip a
   case that could not run, check_summary prints the closing line
   "N passed, M failed, K skipped" and gives the exit code. */
#ifndef HAIROBB_TESTS_CHECK_H
#define HAIROBB_TESTS_CHECK_H

#include <stdarg.h>
#include <stdio.h>

#include "test_data.h"

#if defined(__GNUC__) || defined(__clang__)
#define CHECK_PRINTF_LIKE(format_index) __attribute__((format(printf, format_index, format_index + 1)))
#else
#define CHECK_PRINTF_LIKE(format_index)
#endif

static int check_passed, check_failed, check_skipped;

#define CHECK(cond, ...)                                                  \
    do {                                                                  \
        if (cond) {                                                       \
            ++check_passed;                                               \
        } else {                                                          \
            ++check_failed;                                               \
            printf("FAIL %s:%d: %s: ", __FILE__, __LINE__, #cond);        \
            printf(__VA_ARGS__);                                          \
            printf("\n");                                                 \
        }                                                                 \
    } while (0)

/* One check's line, whatever its outcome: "PASS " or "FAIL " and the
   message. */
static inline void check_report(int ok, const char *format, ...) CHECK_PRINTF_LIKE(2);
static inline void check_report(int ok, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    printf("%s ", ok ? "PASS" : "FAIL");
    vprintf(format, args);
    printf("\n");
    va_end(args);
    if (ok)
        ++check_passed;
    else
        ++check_failed;
}

static inline void check_skip(const char *why)
{
    ++check_skipped;
    printf("SKIP %s\n", why);
}

/* The path of a data file the next cases need (found by a lookup of
   test_data.h), or NULL after reporting it: a skip, or a failure where it
   must be there (HAIROBB_REQUIRE_DATA=1, or HAIROBB_STRAIGHT_HAIR naming a
   file that is not). */
static inline const char *check_data(test_data_status (*lookup)(const char **path, char why[TEST_DATA_WHY_SIZE]))
{
    const char *path;
    char why[TEST_DATA_WHY_SIZE];
    test_data_status status = lookup(&path, why);
    if (status == TEST_DATA_FOUND) return path;
    if (status == TEST_DATA_ABSENT && !test_data_required()) {
        check_skip(why);
    } else {
        ++check_failed;
        printf("FAIL %s%s\n", why, status == TEST_DATA_ABSENT ? " (HAIROBB_REQUIRE_DATA is set)" : "");
    }
    return NULL;
}

static inline int check_summary(void)
{
    printf("%d passed, %d failed, %d skipped\n", check_passed, check_failed, check_skipped);
    return check_failed ? 1 : 0;
}

#endif
