/*
 *  The median of a set of values, the mean of the two middle ones for an
 *  even count.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_MEDIAN_H
#define LOCALSCAN_MEDIAN_H

#include <glib.h>

G_BEGIN_DECLS

/* The median of n values, which it reorders; of an even count the mean of
 * the two middle ones (gwy_math_median takes one of them, which biases a
 * robust scale of few values); NaN when n is 0. */
gdouble      median_in_place      (gdouble *values,
                                   gint n);

G_END_DECLS

#endif
