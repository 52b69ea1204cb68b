/*
 *  Stripe geometry of the local-scan method.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include "stripe-geometry.h"

/* 64-bit products: s*yres overflows gint for large images cut finely. */
gint
stripe_first_row(gint s, gint n, gint yres)
{
    g_return_val_if_fail(n >= 1 && n <= yres, 0);
    return (gint)(((gint64)s*yres)/n);
}

gint
stripe_end_row(gint s, gint n, gint yres)
{
    return stripe_first_row(s + 1, n, yres);
}

/* floor(s*yres/n) <= row  <=>  s*yres < (row+1)*n, so the stripe is the
 * largest such s, floor(((row+1)*n - 1)/yres). */
gint
stripe_of_row(gint row, gint n, gint yres)
{
    g_return_val_if_fail(n >= 1 && n <= yres, 0);
    g_return_val_if_fail(row >= 0 && row < yres, 0);
    return (gint)((((gint64)row + 1)*n - 1)/yres);
}

gdouble
stripe_centre_row(gint s, gint n, gint yres)
{
    return 0.5*(stripe_first_row(s, n, yres) + stripe_end_row(s, n, yres) - 1);
}

gint
stripe_drift_nearest_source(gint s, gint n, const gboolean *has_drift)
{
    gint dist;

    if (has_drift[s])
        return s;
    /* Looking below before above at each distance gives the lower index on
     * a tie, as the paper-mode rules require. */
    for (dist = 1; dist < n; dist++) {
        if (s - dist >= 0 && has_drift[s - dist])
            return s - dist;
        if (s + dist < n && has_drift[s + dist])
            return s + dist;
    }
    return -1;
}

/* Two sweeps keep the fill linear in the stripe count: the nearest source
 * at or below each stripe, then the nearest at or above, the lower winning
 * a tie as stripe_drift_nearest_source() does.  Sources are stripes that
 * had drift originally, so one filled value never chains into another. */
gboolean
stripe_drift_fill_missing(gint n, const gboolean *has_drift,
                          gdouble *dx, gdouble *dy)
{
    gint *below = g_new(gint, MAX(n, 1));
    gint s, src, above = -1;
    gboolean any = FALSE;

    for (s = 0; s < n; s++) {
        below[s] = has_drift[s] ? s : (s ? below[s-1] : -1);
        any = any || has_drift[s];
    }
    for (s = n-1; any && s >= 0; s--) {
        if (has_drift[s]) {
            above = s;
            continue;
        }
        src = below[s];
        if (src < 0 || (above >= 0 && above - s < s - src))
            src = above;
        dx[s] = dx[src];
        dy[s] = dy[src];
    }
    g_free(below);
    return any;
}
