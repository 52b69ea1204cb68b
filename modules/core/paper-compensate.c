/*
 *  Paper-mode compensation: whole-pixel stripe shifts, bit-exact to
 *  docs/paper-mode.md.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <string.h>
#include "paper-compensate.h"
#include "stripe-geometry.h"
#include "missing-data.h"

static void
fill_doubles(gdouble *dest, gint64 count, gdouble value)
{
    gint64 i;

    for (i = 0; i < count; i++)
        dest[i] = value;
}

/* Rules 1 and 2 combined for one output row: C[r] = B[src], and B[src] is
 * A[src] shifted by the x drift of src's own stripe, so the row is one
 * contiguous copy from A[src] between two filled margins.  Shifts are 64-bit
 * because drift may exceed the image (or even gint) when added to c. */
static void
compensate_row(const gdouble *a_row, gint xres, gint64 shift,
               gdouble fill_value, gdouble *result_row, gdouble *mask_row)
{
    gint64 lo = MAX(0, -shift), hi = MIN((gint64)xres, (gint64)xres - shift);

    if (hi <= lo) {
        fill_doubles(result_row, xres, fill_value);
        if (mask_row)
            fill_doubles(mask_row, xres, 1.0);
        return;
    }
    fill_doubles(result_row, lo, fill_value);
    memcpy(result_row + lo, a_row + lo + shift, (hi - lo)*sizeof(gdouble));
    fill_doubles(result_row + hi, xres - hi, fill_value);
    if (mask_row) {
        fill_doubles(mask_row, lo, 1.0);
        /* All-zero bytes are 0.0 in IEEE 754. */
        memset(mask_row + lo, 0, (hi - lo)*sizeof(gdouble));
        fill_doubles(mask_row + hi, xres - hi, 1.0);
    }
}

void
paper_compensate(const gdouble *a, gint xres, gint yres, gint n,
                 const gint *dx, const gint *dy, gdouble fill_value,
                 gdouble *result, gdouble *mask)
{
    gint s, r, first, end;
    gint64 src;

    g_return_if_fail(a && result && dx && dy);
    g_return_if_fail(xres >= 1 && yres >= 1);
    g_return_if_fail(n >= 1 && n <= yres);

    for (s = 0; s < n; s++) {
        first = stripe_first_row(s, n, yres);
        end = stripe_end_row(s, n, yres);
        for (r = first; r < end; r++) {
            gdouble *result_row = result + (gsize)r*xres;
            gdouble *mask_row = mask ? mask + (gsize)r*xres : NULL;

            src = (gint64)r + dy[s];
            if (src < 0 || src >= yres) {
                fill_doubles(result_row, xres, fill_value);
                if (mask_row)
                    fill_doubles(mask_row, xres, 1.0);
                continue;
            }
            compensate_row(a + (gsize)src*xres, xres,
                           dx[stripe_of_row((gint)src, n, yres)],
                           fill_value, result_row, mask_row);
        }
    }
    /* Missing input pixels (docs/missing-data.md) were copied like any
     * other; finite images are left exactly as the rules made them. */
    missing_data_fill_result(result, mask, (gsize)xres*yres, fill_value);
}

/* Neumaier's compensated summation: the error stays at a few ulp of the sum
 * however many pixels there are and whatever their range, and unlike long
 * double it is equally accurate on every architecture. */
gdouble
paper_image_mean(const gdouble *a, gint xres, gint yres)
{
    gsize i, n, count;
    gdouble sum = 0.0, compensation = 0.0, t;

    g_return_val_if_fail(a, 0.0);
    g_return_val_if_fail(xres >= 1 && yres >= 1, 0.0);

    /* Missing pixels (docs/missing-data.md) are left out; with none the
     * sum is the plain one. */
    n = (gsize)xres*yres;
    count = 0;
    for (i = 0; i < n; i++) {
        if (G_UNLIKELY(!isfinite(a[i])))
            continue;
        count++;
        t = sum + a[i];
        if (fabs(sum) >= fabs(a[i]))
            compensation += (sum - t) + a[i];
        else
            compensation += (a[i] - t) + sum;
        sum = t;
    }
    return count ? (sum + compensation)/count : 0.0;
}
