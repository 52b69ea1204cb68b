/*
 *  Paper-mode compensation: whole-pixel stripe shifts, bit-exact to
 *  docs/paper-mode.md.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_PAPER_COMPENSATE_H
#define LOCALSCAN_PAPER_COMPENSATE_H

#include <glib.h>

G_BEGIN_DECLS

/* Compensates image a (yres rows of xres, row-major, row 0 on top) cut into n
 * stripes with whole-pixel drift dx[s], dy[s] (any size, also larger than the
 * image).  Pixels with no source, and those whose source is missing (NaN or
 * infinite, docs/missing-data.md), get fill_value.  result gets the compensated
 * image; mask (may be NULL) gets 1.0 for filled pixels and 0.0 elsewhere.
 * result and mask must not alias a. */
void     paper_compensate         (const gdouble *a,
                                   gint xres,
                                   gint yres,
                                   gint n,
                                   const gint *dx,
                                   const gint *dy,
                                   gdouble fill_value,
                                   gdouble *result,
                                   gdouble *mask);

/* The paper's fill value d: the mean of all pixels of a, missing ones
 * (NaN, infinite) left out; 0 when every pixel is missing. */
gdouble  paper_image_mean         (const gdouble *a, gint xres, gint yres);

G_END_DECLS

#endif
