/* check.h - the tests' tiny harness: CHECK prints failures, check_summary
   prints the closing line "N passed, M failed" and gives the exit code. */
#ifndef HAIROBB_TESTS_CHECK_H
#define HAIROBB_TESTS_CHECK_H

#include <stdio.h>

static int check_passed, check_failed;

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

static int check_summary(void)
{
    printf("%d passed, %d failed\n", check_passed, check_failed);
    return check_failed ? 1 : 0;
}

#endif
