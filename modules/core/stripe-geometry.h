/*
 *  Stripe geometry of the local-scan method (docs/paper-mode.md).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_STRIPE_GEOMETRY_H
#define LOCALSCAN_STRIPE_GEOMETRY_H

#include <glib.h>

G_BEGIN_DECLS

/* Stripe s of n over yres rows holds rows floor(s*yres/n) .. floor((s+1)*yres/n)-1.
 * All functions require 1 <= n <= yres. */
gint     stripe_first_row           (gint s, gint n, gint yres);
gint     stripe_end_row             (gint s, gint n, gint yres);   /* one past the last row */
gint     stripe_of_row              (gint row, gint n, gint yres);
gdouble  stripe_centre_row          (gint s, gint n, gint yres);   /* (first+last)/2 */

/* The nearest-stripe rule: every stripe with has_drift[s] == FALSE takes dx, dy
 * of the nearest stripe with has_drift TRUE (distance in stripe index, the lower
 * index on a tie).  Returns FALSE, changing nothing, when no stripe has drift. */
gboolean stripe_drift_fill_missing  (gint n,
                                     const gboolean *has_drift,
                                     gdouble *dx,
                                     gdouble *dy);

/* Index of the stripe whose value fills stripe s under the rule above, or -1. */
gint     stripe_drift_nearest_source(gint s, gint n, const gboolean *has_drift);

G_END_DECLS

#endif
