/*
 *  Seeded random numbers of the simulator (PCG32 with Gaussian deviates):
 *  the same seed gives the same sequence on every machine and GLib version.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_SIM_RANDOM_H
#define LOCALSCAN_SIM_RANDOM_H

#include <glib.h>

G_BEGIN_DECLS

typedef struct {
    guint64 state;
    guint64 increment;
    gboolean have_spare;
    gdouble spare;
} SimRandom;

/* stream separates independent sequences drawn from one user seed. */
void     sim_random_init     (SimRandom *rng, guint32 seed, guint32 stream);
guint32  sim_random_uint32   (SimRandom *rng);
/* Uniform in [0, 1), 53 bits. */
gdouble  sim_random_uniform  (SimRandom *rng);
/* Standard normal deviate. */
gdouble  sim_random_gaussian (SimRandom *rng);

G_END_DECLS

#endif
