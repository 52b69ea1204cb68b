/*
 *  How far particle centres found in an image sit from where they should
 *  be: the simulator's figure of merit before and after compensation.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_CENTRE_ERROR_H
#define SIMSCAN_CENTRE_ERROR_H

#include <glib.h>

G_BEGIN_DECLS

typedef struct {
    gint n_expected;       /* particles considered (clear of the border) */
    gint n_matched;        /* of them, found near where expected */
    gdouble rms_px, max_px;
    gdouble rms_nm, max_nm;
} CentreError;

/* For each of n particles: look for the detected particle (a GArray of
 * DetectedParticle) nearest to search[2i], search[2i+1] (px) within
 * match_radius px, and measure its distance from truth[2i], truth[2i+1]
 * (px; pixel sizes dx_m, dy_m give nm).  Particles whose truth lies within
 * margin px of the border of an xres x yres image are left out. */
void  centre_error_measure  (const GArray *detected,
                             const gdouble *search,
                             const gdouble *truth,
                             gint n,
                             gint xres,
                             gint yres,
                             gdouble margin,
                             gdouble match_radius,
                             gdouble dx_m,
                             gdouble dy_m,
                             CentreError *error);

G_END_DECLS

#endif
