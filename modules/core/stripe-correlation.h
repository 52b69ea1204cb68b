/*
 *  The normalised cross-correlation of one stripe of an image with a
 *  reference frame, over a window of shifts around any centre.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_STRIPE_CORRELATION_H
#define LOCALSCAN_STRIPE_CORRELATION_H

#include <glib.h>
#include "frame-conditioning.h"

G_BEGIN_DECLS

/* Marks shifts that leave too little of the stripe on the reference. */
#define STRIPE_CORRELATION_NONE (-2.0)

/* Shifts dy in [cy - ry, cy + ry] by dx in [cx - rx, cx + rx], in the
 * table convention: reference content at (r, c) appears in the image at
 * (r + dy, c + dx). */
typedef struct {
    gint cy, cx;
    gint ry, rx;
    gdouble *values;     /* (2ry + 1) x (2rx + 1), by dy then dx */
} StripeCorrelationMap;

typedef struct _StripeCorrelation StripeCorrelation;

/* For stripes up to max_height rows and windows up to max_ry x max_rx;
 * image and reference (same size) must outlive the object.  Shifts that
 * keep less than min_overlap of a stripe's valid pixels on the reference
 * are not considered: a small overlap can correlate by chance. */
StripeCorrelation* stripe_correlation_new (const ConditionedFrame *image,
                                           const ConditionedFrame *reference,
                                           gint max_height,
                                           gint max_ry,
                                           gint max_rx,
                                           gdouble min_overlap);
void               stripe_correlation_free(StripeCorrelation *sc);

/* Fills map (its cy, cx, ry, rx set by the caller, values allocated for
 * them) for image rows first .. end - 1.  Shifts with too little overlap
 * are STRIPE_CORRELATION_NONE; a flat stripe or reference patch gives 0. */
void               stripe_correlation_map (StripeCorrelation *sc,
                                           gint first,
                                           gint end,
                                           StripeCorrelationMap *map);

/* The map's value at a shift (NONE outside the window). */
gdouble            stripe_correlation_map_at(const StripeCorrelationMap *map,
                                             gint dy,
                                             gint dx);

G_END_DECLS

#endif
