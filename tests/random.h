/* random.h - every random number the tests and the bench draw, from one
   place. A seed fixes its sequence on every platform and compiler: a
   scene's strands, a test's rays and the bench's picks never change.

     scene_rng   PCG32 (O'Neill): the scenes, most tests' rays, the bench
     lcg64       the 64-bit LCG under PCG32, its state's high bits used as
                 they are: test_round's stress rays, test_filter
     lcg32       Numerical Recipes' 32-bit LCG: test_motion, test_bases
     xorshift64  Marsaglia's (13, 7, 17): test_unit, test_reference

   The last three are older tests' own generators, kept so that their rays
   stay what they were; new code draws from a scene_rng. Header-only, every
   function static inline; C99 and C++11. */
#ifndef HAIROBB_TESTS_RANDOM_H
#define HAIROBB_TESTS_RANDOM_H

#include <stdint.h>

/* 2^-24 and 2^-53: 24 random bits make every float of [0, 1) on a grid
   exactly, 53 every double */
#define RANDOM_FLOAT_ULP (1.0f / 16777216.0f)
#define RANDOM_DOUBLE_ULP (1.0 / 9007199254740992.0)

/* ------------------------------------------------------------------------ */
/* The 64-bit LCG (Knuth's MMIX constants) */

/* The next state, which is also what the caller may read bits of. */
static inline uint64_t lcg64_next(uint64_t *state)
{
    *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
    return *state;
}

/* Uniform in [0, 1): the next state's 53 high bits. */
static inline double lcg64_double(uint64_t *state)
{
    return (double)(lcg64_next(state) >> 11) * RANDOM_DOUBLE_ULP;
}

/* ------------------------------------------------------------------------ */
/* PCG32: the LCG's state, permuted. The stream increment is fixed to keep
   the state one word. */

typedef struct scene_rng { uint64_t state; } scene_rng;

static inline uint32_t scene_rng_u32(scene_rng *rng)
{
    uint64_t old = rng->state;
    lcg64_next(&rng->state);
    uint32_t xorshifted = (uint32_t)(((old >> 18) ^ old) >> 27);
    uint32_t rotation = (uint32_t)(old >> 59);
    return (xorshifted >> rotation) | (xorshifted << ((32u - rotation) & 31u));
}

static inline void scene_rng_seed(scene_rng *rng, uint64_t seed)
{
    /* PCG's reference seeding: mixes the seed so that nearby seeds diverge. */
    rng->state = 0;
    scene_rng_u32(rng);
    rng->state += seed;
    scene_rng_u32(rng);
}

/* Uniform in [0, 1): 24 random bits, exactly representable as float. */
static inline float scene_rng_float(scene_rng *rng)
{
    return (float)(scene_rng_u32(rng) >> 8) * RANDOM_FLOAT_ULP;
}

static inline float scene_rng_range(scene_rng *rng, float lo, float hi)
{
    return lo + (hi - lo) * scene_rng_float(rng);
}

/* Uniform in [0, n): the high word of a 32 x 32-bit product (Lemire's
   multiply-shift, without the rejection step: a bias of n / 2^32 at most). */
static inline uint32_t scene_rng_below(scene_rng *rng, uint32_t n)
{
    return (uint32_t)(((uint64_t)scene_rng_u32(rng) * n) >> 32);
}

/* ------------------------------------------------------------------------ */
/* The 32-bit LCG */

/* Uniform in [0, 1): the next state's 24 high bits. */
static inline float lcg32_float(uint32_t *state)
{
    *state = *state * 1664525u + 1013904223u;
    return (float)(*state >> 8) * RANDOM_FLOAT_ULP;
}

/* ------------------------------------------------------------------------ */
/* xorshift64 (the state must not be 0) */

static inline uint64_t xorshift64_next(uint64_t *state)
{
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    return *state;
}

/* Uniform in [0, 1): the next state's 24 high bits. */
static inline float xorshift64_float(uint64_t *state)
{
    return (float)(xorshift64_next(state) >> 40) * RANDOM_FLOAT_ULP;
}

/* Uniform in [0, 1): the next state's 53 high bits. */
static inline double xorshift64_double(uint64_t *state)
{
    return (double)(xorshift64_next(state) >> 11) * RANDOM_DOUBLE_ULP;
}

#endif
