/*
 *  What the lines of a local scan tell: chords, their midpoints, and the
 *  stripe's drift.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include "local-scan-analysis.h"

void
local_scan_chord_midpoints(const gdouble *h, gint n, gdouble length,
                           gdouble thr, GArray *mids)
{
    gdouble step = length/(n - 1);
    gint i = 0, first, last;

    g_array_set_size(mids, 0);
    while (i < n) {
        gdouble left, right, m;

        if (h[i] <= thr) {
            i++;
            continue;
        }
        first = i;
        while (i < n && h[i] > thr)
            i++;
        last = i - 1;
        if (first == 0 || last == n-1)
            continue;
        left = (first - 1) + (thr - h[first-1])/(h[first] - h[first-1]);
        right = last + (h[last] - thr)/(h[last] - h[last+1]);
        m = -0.5*length + 0.5*(left + right)*step;
        g_array_append_val(mids, m);
    }
}

gboolean
local_scan_take_nearest_chord(GArray *mids, gdouble expect, gdouble limit,
                              gdouble *mid)
{
    gdouble best = G_MAXDOUBLE;
    guint i, best_i = 0;

    for (i = 0; i < mids->len; i++) {
        gdouble m = g_array_index(mids, gdouble, i);

        if (!isnan(m) && fabs(m) <= limit && fabs(m - expect) < best) {
            best = fabs(m - expect);
            best_i = i;
        }
    }
    if (best == G_MAXDOUBLE)
        return FALSE;
    *mid = g_array_index(mids, gdouble, best_i);
    g_array_index(mids, gdouble, best_i) = NAN;
    return TRUE;
}

void
local_scan_table_set_row(DriftTable *table, gint s, const LocalScanParticle *r)
{
    gboolean scanned = (r && r->lines > 0);
    gboolean found = (scanned && r->found);

    table->rows[s].stripe = s;
    table->rows[s].has_drift = found;
    /* + 0.0 turns round()'s -0 into 0, which the table writes as "0". */
    table->rows[s].dx = found ? round(r->dx) + 0.0 : 0.0;
    table->rows[s].dy = found ? round(r->dy) + 0.0 : 0.0;
    drift_table_set_extra(table, s, "dx_exact", found ? r->dx : NAN);
    drift_table_set_extra(table, s, "dy_exact", found ? r->dy : NAN);
    drift_table_set_extra(table, s, "t_image", scanned ? r->t_image : NAN);
    drift_table_set_extra(table, s, "t_local", found ? r->t_local : NAN);
    drift_table_set_extra(table, s, "x", scanned ? r->x_disp : NAN);
    drift_table_set_extra(table, s, "y", scanned ? r->y_disp : NAN);
    drift_table_set_extra(table, s, "lines", scanned ? r->lines : NAN);
}
