/*
 *  Stripes matched on the fringe of a feature beyond them: their lines
 *  show nothing of their own, the filters carry the fringe in, and the
 *  match holds the shift across the lines poorly (docs/registration.md).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_STRIPE_FRINGE_H
#define LOCALSCAN_STRIPE_FRINGE_H

#include <glib.h>
#include "frame-conditioning.h"
#include "stripe-registration.h"

G_BEGIN_DECLS

/* What each line of a levelled frame shows. */
typedef struct {
    gdouble *variance;      /* per line: the variance of its valid pixels
                               (NaN with fewer than 8, never judged) */
    gint yres;
    gdouble noise_var;      /* of the frame's white pixel noise */
} LineTextures;

/* From a frame levelled and not yet band-passed. */
void     line_textures_init     (LineTextures *textures,
                                 const ConditionedFrame *levelled);
void     line_textures_clear    (LineTextures *textures);

/* Un-accepts the accepted shifts of the n stripes whose lines, in the
 * image or under them in the reference, are on a fringe (reach: the
 * filters' reach in lines). */
void     stripe_fringe_reject   (const LineTextures *image,
                                 const LineTextures *reference,
                                 gint n, gint reach, StripeShift *shifts);

G_END_DECLS

#endif
