/*
 *  What the tests of continuous compensation share: every interpolation
 *  kernel it offers, random images and tables of one constant drift.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_CONTINUOUS_FIXTURES_H
#define LOCALSCAN_CONTINUOUS_FIXTURES_H

#include <glib.h>
#include <libprocess/interpolation.h>
#include "drift-table.h"

static const GwyInterpolationType all_kernels[] = {
    GWY_INTERPOLATION_ROUND, GWY_INTERPOLATION_LINEAR, GWY_INTERPOLATION_KEY,
    GWY_INTERPOLATION_BSPLINE, GWY_INTERPOLATION_OMOMS, GWY_INTERPOLATION_NNA,
    GWY_INTERPOLATION_SCHAUM,
};

/* xres x yres values drawn uniformly from [lo, hi). */
static inline gdouble*
random_image(gint xres, gint yres, gdouble lo, gdouble hi, GRand *rng)
{
    gdouble *a = g_new(gdouble, xres*yres);
    gint k;

    for (k = 0; k < xres*yres; k++)
        a[k] = g_rand_double_range(rng, lo, hi);
    return a;
}

/* The same drift (px) in every one of n stripes; with rng, the stripes
 * have times too: stripe s imaged at 2s + 1 and scanned locally at a
 * random time from 200 to 203 (s). */
static inline DriftTable*
constant_table(gint n, gdouble dx, gdouble dy, GRand *rng)
{
    DriftTable *table = drift_table_new(n, DRIFT_UNIT_PX);
    gint s;

    for (s = 0; s < n; s++) {
        table->rows[s].has_drift = TRUE;
        table->rows[s].dx = dx;
        table->rows[s].dy = dy;
        if (rng) {
            drift_table_set_extra(table, s, "t_image", 2.0*s + 1.0);
            drift_table_set_extra(table, s, "t_local",
                                  200.0 + g_rand_double_range(rng, 0.0, 3.0));
        }
    }
    return table;
}

#endif
