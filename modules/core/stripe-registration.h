/*
 *  Drift measured from the data: each stripe of an image registered against
 *  a reference frame of the same area (FFT cross-correlation, FFTW).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_STRIPE_REGISTRATION_H
#define LOCALSCAN_STRIPE_REGISTRATION_H

#include <glib.h>
#include <libprocess/datafield.h>
#include "drift-table.h"

G_BEGIN_DECLS

#define STRIPE_REGISTRATION_ERROR stripe_registration_error_quark()

typedef enum {
    STRIPE_REGISTRATION_ERROR_SIZE,     /* image and reference differ, or too small */
    STRIPE_REGISTRATION_ERROR_STRIPES,  /* n outside 1..yres */
    STRIPE_REGISTRATION_ERROR_VALUE,    /* NaN or infinity in the data */
    STRIPE_REGISTRATION_ERROR_NO_MATCH, /* no stripe could be registered */
} StripeRegistrationError;

/* A min_score that rejects featureless and ambiguous (periodic) stripes but
 * keeps every well-textured one; what the tools use unless told otherwise. */
#define STRIPE_REGISTRATION_DEFAULT_MIN_SCORE 0.25

typedef struct {
    gdouble dx;        /* px: content of the reference at (r, c) appears in */
    gdouble dy;        /* the image at (r + dy, c + dx), the table convention;
                          at the stripe's centre row (the stripe's mean for a
                          drift changing linearly over its rows) */
    gdouble score;     /* confidence in [0, 1] */
    gboolean accepted; /* score >= min_score and consistent */
    /* Diagnostics. */
    gdouble peak;      /* normalised cross-correlation at the chosen peak */
    gdouble rival;     /* the highest competing peak (in the window used) */
    gboolean resolved; /* the stripe's own best peak disagreed with its
                          neighbours and was replaced by the best one near
                          their prediction */
} StripeShift;

GQuark       stripe_registration_error_quark(void);

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

/* The same, each stripe searched only within radius_px (in both axes) of
 * its predicted shift (px, table convention): for shifts known roughly
 * beforehand, such as those of a frame series registered against an older
 * frame, which may lie beyond any blind search.  The peaks that compete
 * for a stripe's score are those within its window. */
gboolean     stripe_registration_measure_around(const gdouble *image,
                                                const gdouble *reference,
                                                gint xres,
                                                gint yres,
                                                gint n,
                                                const gdouble *predicted_dx,
                                                const gdouble *predicted_dy,
                                                gdouble radius_px,
                                                gdouble min_score,
                                                StripeShift *shifts,
                                                GError **error);

/* The same for two channels; refuses (with a message giving both sizes)
 * fields of different pixel dimensions. */
gboolean     stripe_registration_measure_fields(GwyDataField *image,
                                                GwyDataField *reference,
                                                gint n,
                                                gdouble max_shift_px,
                                                gdouble min_score,
                                                StripeShift *shifts,
                                                GError **error);

/* A px table of the shifts: rejected stripes are blank (nearest-stripe rule),
 * with dx_exact, dy_exact and score columns. */
DriftTable*  stripe_registration_to_table(const StripeShift *shifts, gint n,
                                          gboolean whole_pixels);

/* What the tool and the module call: measures with the default min_score
 * and returns the table (see above), or NULL with an error when the sizes
 * differ, n is out of range, or no stripe is accepted. */
DriftTable*  stripe_registration_table_for_fields(GwyDataField *image,
                                                  GwyDataField *reference,
                                                  gint n,
                                                  gdouble max_shift_px,
                                                  gboolean whole_pixels,
                                                  GError **error);

/* How many stripes were accepted. */
gint         stripe_registration_count_accepted(const StripeShift *shifts,
                                                gint n);

G_END_DECLS

#endif
