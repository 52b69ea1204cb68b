/*
 *  Seeded random numbers of the simulator.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include "sim-random.h"

/* PCG32 (O'Neill, XSH RR variant): small state, good statistics, and its
 * output is fixed by its definition, unlike GRand's floating point calls. */
#define PCG_MULTIPLIER G_GUINT64_CONSTANT(6364136223846793005)

/* Stream constant for the increment (any odd-making 64-bit value). */
#define STREAM_SALT G_GUINT64_CONSTANT(0xda3e39cb94b95bdb)

/* SplitMix64's finaliser: a bijection that spreads every input bit over
 * the whole word. */
static guint64
splitmix64(guint64 x)
{
    x += G_GUINT64_CONSTANT(0x9e3779b97f4a7c15);
    x = (x ^ (x >> 30))*G_GUINT64_CONSTANT(0xbf58476d1ce4e5b9);
    x = (x ^ (x >> 27))*G_GUINT64_CONSTANT(0x94d049bb133111eb);
    return x ^ (x >> 31);
}

/* PCG's own initialisation, but from mixed seed and stream: PCG32 seeded
 * directly with nearby small seeds (200 or 1000 apart) starts from nearby
 * states and gives nearly the same first draws. */
void
sim_random_init(SimRandom *rng, guint32 seed, guint32 stream)
{
    rng->state = 0;
    rng->increment = (splitmix64(stream ^ STREAM_SALT) << 1) | 1u;
    rng->have_spare = FALSE;
    rng->spare = 0.0;
    sim_random_uint32(rng);
    rng->state += splitmix64(((guint64)stream << 32) | seed);
    sim_random_uint32(rng);
}

guint32
sim_random_uint32(SimRandom *rng)
{
    guint64 old = rng->state;
    guint32 xorshifted, rot;

    rng->state = old*PCG_MULTIPLIER + rng->increment;
    xorshifted = (guint32)(((old >> 18u) ^ old) >> 27u);
    rot = (guint32)(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
}

gdouble
sim_random_uniform(SimRandom *rng)
{
    guint64 hi = sim_random_uint32(rng) >> 5, lo = sim_random_uint32(rng) >> 6;

    return (hi*67108864.0 + lo)/9007199254740992.0;
}

/* Marsaglia's polar method; the second deviate of each pair is kept. */
gdouble
sim_random_gaussian(SimRandom *rng)
{
    gdouble u, v, s, f;

    if (rng->have_spare) {
        rng->have_spare = FALSE;
        return rng->spare;
    }
    do {
        u = 2.0*sim_random_uniform(rng) - 1.0;
        v = 2.0*sim_random_uniform(rng) - 1.0;
        s = u*u + v*v;
    } while (s >= 1.0 || s == 0.0);
    f = sqrt(-2.0*log(s)/s);
    rng->spare = v*f;
    rng->have_spare = TRUE;
    return u*f;
}
