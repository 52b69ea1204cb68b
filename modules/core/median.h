/*
 *  The median of a set of values, the mean of the two middle ones for an
 *  even count, and any rank of them.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_MEDIAN_H
#define LOCALSCAN_MEDIAN_H

#include <glib.h>

G_BEGIN_DECLS

/* The median of n values (no NaN among them), which it reorders; of an
 * even count the mean of the two middle ones (gwy_math_median takes one
 * of them, which biases a robust scale of few values); NaN when n is 0.
 * Gwyddion's own is not used: see median.c. */
gdouble      median_in_place      (gdouble *values,
                                   gint n);

/* The k-th smallest (from 0) of n values (no NaN among them), which it
 * reorders. */
gdouble      median_kth_in_place  (gdouble *values,
                                   gint n,
                                   gint k);

G_END_DECLS

#endif
