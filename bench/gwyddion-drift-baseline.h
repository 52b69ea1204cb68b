/*
 *  Gwyddion's own "Compensate Drift" (process function drift) run headlessly
 *  on an image, as the baseline the benchmarks compare against.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_GWYDDION_DRIFT_BASELINE_H
#define LOCALSCAN_GWYDDION_DRIFT_BASELINE_H

#include <glib.h>

G_BEGIN_DECLS

/* Initialises Gwyddion without a GUI (single-threaded, so timings compare
 * with ours) and checks that drift exists.  Prints why on failure. */
gboolean  gwyddion_drift_init    (void);

/* Runs drift with GWY_RUN_IMMEDIATE on the image (1 px = 1 unit) with its
 * default settings (range 12 rows, B-spline), only plotting, and reads its
 * per-row x drift (px, sign of the drift table's dx, median zero) from the
 * graph it adds.  seconds gets the run's wall time. */
gboolean  gwyddion_drift_estimate(const gdouble *image,
                                  gint xres,
                                  gint yres,
                                  gdouble *row_drift,
                                  gdouble *seconds);

void      gwyddion_drift_finish  (void);

G_END_DECLS

#endif
