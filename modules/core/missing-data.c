/*
 *  Missing data: NaN and infinite pixels of an input image are missing
 *  (docs/missing-data.md).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include "missing-data.h"
#include "localscan-intl.h"

GQuark
missing_data_error_quark(void)
{
    return g_quark_from_static_string("missing-data-error-quark");
}

gsize
missing_data_count(const gdouble *a, gsize n)
{
    gsize i, count = 0;

    for (i = 0; i < n; i++)
        count += !isfinite(a[i]);
    return count;
}

gboolean
missing_data_check_range(const gdouble *a, gsize n, const gchar *what, GError **error)
{
    gsize i;

    for (i = 0; i < n; i++) {
        if (isfinite(a[i]) && fabs(a[i]) > MISSING_DATA_VALUE_MAX) {
            g_set_error(error, MISSING_DATA_ERROR, MISSING_DATA_ERROR_RANGE,
                        _("%s holds the value %g, beyond %g in magnitude: no arithmetic on such values "
                          "stays finite"),
                        what, a[i], MISSING_DATA_VALUE_MAX);
            return FALSE;
        }
    }
    return TRUE;
}

gboolean
missing_data_check(const gdouble *a, gint xres, gint yres, const gchar *what, GError **error)
{
    gsize n = (gsize)xres*yres, missing = missing_data_count(a, n);

    if (!missing_data_check_range(a, n, what, error))
        return FALSE;
    if (missing <= MISSING_DATA_MAX_FRACTION*n)
        return TRUE;
    g_set_error(error, MISSING_DATA_ERROR, MISSING_DATA_ERROR_TOO_MANY,
                _("%s: %" G_GSIZE_FORMAT " of its %" G_GSIZE_FORMAT " pixels are missing "
                  "(NaN or infinite), more than %g%%: too little of the image is left "
                  "to work with"),
                what, missing, n, 100.0*MISSING_DATA_MAX_FRACTION);
    return FALSE;
}

void
missing_data_finite_range(const gdouble *a, gsize n, gdouble *min, gdouble *max)
{
    gdouble lo = HUGE_VAL, hi = -HUGE_VAL;
    gsize i;

    for (i = 0; i < n; i++) {
        if (isfinite(a[i])) {
            lo = MIN(lo, a[i]);
            hi = MAX(hi, a[i]);
        }
    }
    *min = (lo <= hi) ? lo : 0.0;
    *max = (lo <= hi) ? hi : 0.0;
}

gdouble*
missing_data_filled_copy(const gdouble *a, gsize n, gdouble value)
{
    gdouble *copy = g_new(gdouble, MAX(n, 1));
    gsize i;

    for (i = 0; i < n; i++)
        copy[i] = isfinite(a[i]) ? a[i] : value;
    return copy;
}

gsize
missing_data_fill_result(gdouble *result, gdouble *mask, gsize n, gdouble fill_value)
{
    gsize i, count = 0;

    for (i = 0; i < n; i++) {
        if (G_UNLIKELY(!isfinite(result[i]))) {
            result[i] = fill_value;
            if (mask)
                mask[i] = 1.0;
            count++;
        }
    }
    return count;
}
