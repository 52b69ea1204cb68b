/*
 *  Resampling of scanned rows in x: each row moved back by its x drift,
 *  with the shear within the line (the source column is affine in the
 *  output column).  Internal to the core.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_ROW_RESAMPLE_H
#define LOCALSCAN_ROW_RESAMPLE_H

#include <glib.h>
#include <libprocess/gwyprocessenums.h>
#include "spline-prefilter.h"

G_BEGIN_DECLS

/* Makes the x-corrected rows of image a: output column c of row i comes
 * from source column x_start[i] + x_step[i] c of the same row.  For
 * B-spline and o-MOMS it keeps the x coefficients of the last batch of
 * rows. */
typedef struct {
    const gdouble *a;
    gint xres;
    gint yres;
    const gdouble *x_start;
    const gdouble *x_step;
    GwyInterpolationType interpolation;
    gboolean prefilter_x;
    SplinePrefilter x_prefilter;
    gdouble *lanes;        /* scratch of spline_prefilter_batch() */
    gdouble *coeffs;       /* x coefficients of rows batch_first .. */
    gsize coeff_stride;
    gint batch_first;
    gint batch_count;
} RowResampler;

void     row_resampler_init        (RowResampler *resampler,
                                    const gdouble *a,
                                    gint xres,
                                    gint yres,
                                    const gdouble *x_start,
                                    const gdouble *x_step,
                                    GwyInterpolationType interpolation);
void     row_resampler_clear       (RowResampler *resampler);
/* Source row i corrected in x into dest, minus q times prev unless prev is
 * NULL (the y prefilter's forward elimination, fused while the values are
 * at hand).  Rows are best asked for in ascending order. */
void     row_resampler_correct_row (RowResampler *resampler,
                                    gint i,
                                    const gdouble *restrict prev,
                                    gdouble q,
                                    gdouble *restrict dest);

/* Columns c (first .. last) whose source x_start + x_step c lies within
 * the row's extent [-0.5, n-0.5]. */
void     row_resample_valid_range  (gdouble x_start,
                                    gdouble x_step,
                                    gint n,
                                    gint *first,
                                    gint *last);

G_END_DECLS

#endif
