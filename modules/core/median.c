/*
 *  The median of a set of values.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <libgwyddion/gwymath.h>
#include "median.h"

gdouble
median_in_place(gdouble *values, gint n)
{
    guint k[2];
    gdouble middle[2];

    if (n <= 0)
        return NAN;
    if (n % 2)
        return gwy_math_kth_rank(n, values, n/2);
    k[0] = n/2 - 1;
    k[1] = n/2;
    gwy_math_kth_ranks(n, values, 2, k, middle);
    return 0.5*(middle[0] + middle[1]);
}
