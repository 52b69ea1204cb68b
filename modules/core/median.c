/*
 *  The median of a set of values, and any rank of them.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdlib.h>
#include "median.h"

/*
 * Why not gwy_math_median() and gwy_math_kth_rank(): in Gwyddion 2.62 (the
 * Debian bookworm build) they return a wrong element for about one set in
 * sixteen of seven values or more, uniform random values included: of
 * 0.836 0.285 0.186 0.304 0.435 0.641 0.871 the median 0.304, and of the
 * 23 line costs of test-jump-votes seed 540000260 draw 9 the 4th smallest
 * for the 12th, which put a jump 5 lines late.  Every median of the
 * product (line offsets, robust scales, outlier cuts, votes) goes through
 * here instead.
 */

static inline void
swap_values(gdouble *a, gint i, gint j)
{
    gdouble t = a[i];

    a[i] = a[j];
    a[j] = t;
}

static gint
compare_values(gconstpointer a, gconstpointer b)
{
    gdouble x = *(const gdouble*)a, y = *(const gdouble*)b;

    return (x > y) - (x < y);
}

/* Hoare's selection with the median of three as pivot: on return values[k]
 * holds the k-th smallest, none before it is larger and none after it
 * smaller.  Input made to defeat the pivot would take it quadratic time
 * (0.35 ms for 2048 values against 4 us, 22 ms for 16384): after more
 * rounds than halving would need, what is left is sorted instead. */
gdouble
median_kth_in_place(gdouble *values, gint n, gint k)
{
    gint lo = 0, hi = n - 1, mid, i, j, rounds = 0, most_rounds = 8;
    gdouble pivot;

    g_return_val_if_fail(values && k >= 0 && k < n, NAN);
    for (i = n; i > 1; i /= 2)
        most_rounds += 2;
    while (hi > lo) {
        if (++rounds > most_rounds) {
            qsort(values + lo, hi - lo + 1, sizeof(gdouble), compare_values);
            break;
        }
        mid = lo + (hi - lo)/2;
        if (values[mid] < values[lo])
            swap_values(values, lo, mid);
        if (values[hi] < values[lo])
            swap_values(values, lo, hi);
        if (values[hi] < values[mid])
            swap_values(values, mid, hi);
        pivot = values[mid];
        i = lo;
        j = hi;
        while (i <= j) {
            while (values[i] < pivot)
                i++;
            while (values[j] > pivot)
                j--;
            if (i <= j)
                swap_values(values, i++, j--);
        }
        /* [lo, j] <= pivot <= [i, hi], and what lies between is the pivot. */
        if (k <= j)
            hi = j;
        else if (k >= i)
            lo = i;
        else
            break;
    }
    return values[k];
}

gdouble
median_in_place(gdouble *values, gint n)
{
    gdouble upper, lower;
    gint i;

    if (n <= 0)
        return NAN;
    upper = median_kth_in_place(values, n, n/2);
    if (n % 2)
        return upper;
    /* The lower middle is the largest of those the selection left below. */
    for (i = 1, lower = values[0]; i < n/2; i++)
        lower = MAX(lower, values[i]);
    return 0.5*(lower + upper);
}
