/*
 *  Drift measured from the data: each stripe of an image registered against
 *  a reference frame of the same area (FFT cross-correlation, FFTW).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_STRIPE_REGISTRATION_H
#define LOCALSCAN_STRIPE_REGISTRATION_H

#include <glib.h>
#include "drift-table.h"

G_BEGIN_DECLS

typedef struct {
    gdouble dx;        /* px: content of the reference at (r, c) appears in */
    gdouble dy;        /* the image at (r + dy, c + dx), the table convention */
    gdouble score;     /* confidence in [0, 1] */
    gboolean accepted; /* score >= min_score and consistent */
} StripeShift;

/* Measures n stripes of image against reference (same xres, yres).
 * max_shift_px limits the search (<= 0: a quarter of the smaller side). */
gboolean     stripe_registration_measure (const gdouble *image,
                                          const gdouble *reference,
                                          gint xres,
                                          gint yres,
                                          gint n,
                                          gdouble max_shift_px,
                                          gdouble min_score,
                                          StripeShift *shifts,
                                          GError **error);

/* A px table of the shifts: rejected stripes are blank (nearest-stripe rule),
 * with dx_exact, dy_exact and score columns. */
DriftTable*  stripe_registration_to_table(const StripeShift *shifts, gint n,
                                          gboolean whole_pixels);

G_END_DECLS

#endif
