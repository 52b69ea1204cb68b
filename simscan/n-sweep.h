/*
 *  `simscan sweep`: the particle-centre error after compensation against
 *  the number of stripes N, on one simulated image, with the drift during
 *  the (longer, for more stripes) local scans included.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_N_SWEEP_H
#define SIMSCAN_N_SWEEP_H

#include <glib.h>
#include "centre-error.h"

G_BEGIN_DECLS

typedef struct {
    gint n;                    /* stripes */
    gint measured;             /* stripes whose particle was found */
    gint lines;                /* local-scan lines */
    gdouble local_time;        /* s the local scans took */
    CentreError before;
    CentreError after;
} SweepPoint;

int  simscan_sweep_main  (int argc, char **argv);

G_END_DECLS

#endif
