/*
 *  Particle-centre error of an image against the true positions.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include "particle-detect.h"
#include "centre-error.h"

static gint
nearest_detected(const GArray *detected, gdouble x, gdouble y,
                 gdouble radius)
{
    gdouble best = radius*radius;
    gint found = -1;
    guint k;

    for (k = 0; k < detected->len; k++) {
        const DetectedParticle *p = &g_array_index(detected,
                                                   DetectedParticle, k);
        gdouble d2 = (p->x - x)*(p->x - x) + (p->y - y)*(p->y - y);

        if (!p->on_edge && d2 <= best) {
            best = d2;
            found = (gint)k;
        }
    }
    return found;
}

void
centre_error_measure(const GArray *detected, const gdouble *search,
                     const gdouble *truth, gint n, gint xres, gint yres,
                     gdouble margin, gdouble match_radius,
                     gdouble dx_m, gdouble dy_m, CentreError *error)
{
    gdouble s2_px = 0.0, s2_nm = 0.0;
    gint i, k;

    error->n_expected = error->n_matched = 0;
    error->rms_px = error->max_px = error->rms_nm = error->max_nm = 0.0;
    for (i = 0; i < n; i++) {
        const DetectedParticle *p;
        gdouble tx = truth[2*i], ty = truth[2*i + 1], ex, ey, e_px, e_nm;

        if (tx < margin || ty < margin
            || tx > xres-1 - margin || ty > yres-1 - margin)
            continue;
        error->n_expected++;
        k = nearest_detected(detected, search[2*i], search[2*i + 1],
                             match_radius);
        if (k < 0)
            continue;
        p = &g_array_index(detected, DetectedParticle, k);
        ex = p->x - tx;
        ey = p->y - ty;
        e_px = sqrt(ex*ex + ey*ey);
        e_nm = 1e9*sqrt(ex*dx_m*ex*dx_m + ey*dy_m*ey*dy_m);
        error->n_matched++;
        s2_px += e_px*e_px;
        s2_nm += e_nm*e_nm;
        error->max_px = fmax(error->max_px, e_px);
        error->max_nm = fmax(error->max_nm, e_nm);
    }
    if (error->n_matched) {
        error->rms_px = sqrt(s2_px/error->n_matched);
        error->rms_nm = sqrt(s2_nm/error->n_matched);
    }
}
