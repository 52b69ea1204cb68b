/*
 *  Missing data: NaN and infinite pixels of an input image are missing
 *  (docs/missing-data.md).  They never reach a result: the compensation
 *  fills them as it fills pixels with no source and marks them in the mask;
 *  an image with too many of them is refused.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_MISSING_DATA_H
#define LOCALSCAN_MISSING_DATA_H

#include <glib.h>

G_BEGIN_DECLS

/* More than this fraction of an image missing is refused: the fill value
 * and any drift measured from the rest would describe too little of it. */
#define MISSING_DATA_MAX_FRACTION 0.5

/* Finite values beyond this magnitude are refused: the mean, the
 * interpolation kernels and the registration's squares of such values
 * overflow (values near the largest double gave infinite result pixels).
 * No quantity an instrument records comes near it in SI units. */
#define MISSING_DATA_VALUE_MAX 1e150

#define MISSING_DATA_ERROR missing_data_error_quark()

typedef enum {
    MISSING_DATA_ERROR_TOO_MANY,   /* more than MISSING_DATA_MAX_FRACTION */
    MISSING_DATA_ERROR_RANGE,      /* a value beyond MISSING_DATA_VALUE_MAX */
} MissingDataError;

GQuark   missing_data_error_quark  (void);

/* The number of missing (non-finite) values among a[0..n-1]. */
gsize    missing_data_count        (const gdouble *a,
                                    gsize n);

/* Refuses (what names the image in the message) an image of xres x yres
 * with more than MISSING_DATA_MAX_FRACTION of its pixels missing, or with
 * a value beyond MISSING_DATA_VALUE_MAX (missing_data_check_range). */
gboolean missing_data_check        (const gdouble *a,
                                    gint xres,
                                    gint yres,
                                    const gchar *what,
                                    GError **error);

/* Refuses (what names the data) a finite value among a[0..n-1] beyond
 * MISSING_DATA_VALUE_MAX in magnitude. */
gboolean missing_data_check_range  (const gdouble *a,
                                    gsize n,
                                    const gchar *what,
                                    GError **error);

/* Least and greatest finite value (0 when none is finite). */
void     missing_data_finite_range (const gdouble *a,
                                    gsize n,
                                    gdouble *min,
                                    gdouble *max);

/* A newly allocated copy of a[0..n-1] with every missing value replaced by
 * value. */
gdouble* missing_data_filled_copy  (const gdouble *a,
                                    gsize n,
                                    gdouble value);

/* Every non-finite value of result[0..n-1] becomes fill_value, with 1.0 in
 * mask (may be NULL).  Returns how many were replaced. */
gsize    missing_data_fill_result  (gdouble *result,
                                    gdouble *mask,
                                    gsize n,
                                    gdouble fill_value);

G_END_DECLS

#endif
